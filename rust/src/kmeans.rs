//! k-means: greedy k-means++ seeding, Lloyd iterations, best of `n_init` runs.
//!
//! Semantics follow scikit-learn's `KMeans(algorithm="lloyd")` so that, from the same initial
//! centres, both give the same labels and centres (up to rounding):
//! - one iteration = assign every row to its nearest centre (E-step), then move each centre to
//!   the mean of its rows (M-step); `n_iter` counts these;
//! - stop when no label changed between two E-steps ("strict convergence"), or when the total
//!   squared centre shift `Σ_j ‖c_j,new - c_j,old‖²` is `≤ tol × mean(var(X, axis=0))`, or
//!   after `max_iter` iterations; in the last two cases one more E-step relabels the rows with
//!   the final centres;
//! - a cluster left empty by an E-step is re-seeded with the row farthest from its own centre
//!   (the i-th empty cluster, in index order, gets the i-th farthest row; ties by row index);
//!   the row keeps its label for that iteration and its old cluster's mean loses it, as in
//!   scikit-learn. If every row sits exactly on its centre (fewer distinct rows than `k`),
//!   the empty cluster keeps its previous centre;
//! - ties between equally near centres go to the lowest centre index.
//!
//! Seeding ([`crate::kmeanspp`]): scikit-learn's greedy k-means++ (`2 + ⌊ln k⌋` candidates per
//! step, the one leaving the lowest potential wins), with distances computed in single
//! precision on rows shifted by the first row and exact triangle-inequality pruning.
//!
//! Speed without changing the result ([`crate::lloyd`]): distances are computed directly
//! (`Σ (x_j - c_j)²`, see [`crate::sqdist`]), and bounds on the distances (anchored Hamerly
//! bounds, plus Elkan's per-centre bounds when `k ≤ 32` on CPUs with AVX-512) let most rows skip the distance
//! computations once centres settle. A row is only skipped when the bounds prove, with a safety
//! margin far above rounding (`1e-11 ×` the data diameter), that its nearest centre is
//! unchanged; the labels are therefore those of plain Lloyd except for rows whose two nearest
//! centres are tied within that margin.
//!
//! Determinism: rows are processed in fixed chunks (size set by `n`, `k`, `d` only), sums are
//! formed in a fixed order, so the result for a given seed is bit-identical whatever the number
//! of threads.

use rayon::prelude::*;

use crate::kmeanspp::{default_local_trials, seed, Rng, SeedData, MAX_LOCAL_TRIALS};
use crate::lloyd::lloyd;
use crate::simd::Level;
use crate::sqdist::{sq_dists, two_nearest, Panel};
use crate::{Error, Result};

/// Rows per distance-kernel call.
const GROUP: usize = 64;
/// Runs of `n_init` computed at the same time (each holds its own bounds and labels).
const PARALLEL_RUNS: usize = 2;

/// What [`kmeans`] and [`predict`] run at `level`, as `instruction_sets()` reports it.
pub fn instruction_set(level: Level) -> &'static str {
    match level {
        Level::Avx512 => "avx512f (k-means++ seeding: avx2+fma)",
        Level::Avx2Fma => "avx2+fma",
        Level::Portable => "portable",
    }
}

/// Parameters of [`kmeans`].
#[derive(Clone, Debug, PartialEq)]
pub struct KMeansParams {
    /// Number of clusters (`1 ≤ k ≤ n`).
    pub k: usize,
    /// Independent runs from different k-means++ seedings; the lowest inertia wins.
    pub n_init: usize,
    /// Maximum number of Lloyd iterations per run (`≥ 1`).
    pub max_iter: usize,
    /// Relative tolerance on the squared centre shift (scaled by the mean column variance).
    pub tol: f64,
    /// Seed of the k-means++ draws (run `r` uses a generator derived from `seed` and `r`).
    pub seed: u64,
    /// Candidates per k-means++ step; `None`: `2 + ⌊ln k⌋`.
    pub n_local_trials: Option<usize>,
}

impl KMeansParams {
    /// Defaults of scikit-learn's `KMeans` for `k` clusters (one k-means++ run).
    pub fn new(k: usize) -> Self {
        Self {
            k,
            n_init: 1,
            max_iter: 300,
            tol: 1e-4,
            seed: 0,
            n_local_trials: None,
        }
    }
}

/// A fitted clustering.
#[derive(Clone, Debug, PartialEq)]
pub struct KMeansResult {
    /// Row-major `k × d` centres.
    pub centers: Vec<f64>,
    /// Cluster of each row.
    pub labels: Vec<u32>,
    /// Sum of squared distances of the rows to their centre.
    pub inertia: f64,
    /// Lloyd iterations of the winning run.
    pub n_iter: usize,
    /// Number of clusters.
    pub k: usize,
    /// Dimension.
    pub dim: usize,
}

/// Cluster the rows of the row-major `n × d` matrix `x`.
///
/// `init`: row-major `k × d` initial centres (then `n_init` must be 1); `None`: k-means++.
///
/// Errors: empty or mis-sized input (Shape), NaN/inf (NonFinite), `k` outside `1..=n`,
/// `n_init < 1`, `max_iter < 1`, negative or non-finite `tol`, `n_local_trials < 1`, `init`
/// with `n_init > 1` (InvalidArgument).
pub fn kmeans(
    x: &[f64],
    n: usize,
    d: usize,
    params: &KMeansParams,
    init: Option<&[f64]>,
) -> Result<KMeansResult> {
    crate::simd::level()?;
    let stats = data_stats(x, n, d, "X")?;
    let k = params.k;
    if params.n_init < 1 {
        return Err(Error::InvalidArgument(format!(
            "n_init must be ≥ 1, got {}",
            params.n_init
        )));
    }
    if params.max_iter < 1 {
        return Err(Error::InvalidArgument(format!(
            "max_iter must be ≥ 1, got {}",
            params.max_iter
        )));
    }
    if !(params.tol >= 0.0 && params.tol.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "tol must be a finite number ≥ 0, got {}",
            params.tol
        )));
    }
    let trials = params
        .n_local_trials
        .unwrap_or_else(|| default_local_trials(k));
    check_k_and_trials(k, n, trials)?;
    let tol_abs = params.tol * stats.mean_variance;
    let diameter = stats.diameter;

    if let Some(init) = init {
        if params.n_init != 1 {
            return Err(Error::InvalidArgument(format!(
                "n_init must be 1 when initial centres are given, got {}",
                params.n_init
            )));
        }
        if Some(init.len()) != k.checked_mul(d) {
            return Err(Error::Shape(format!(
                "init has {} values, expected k={k} rows x {d} columns",
                init.len()
            )));
        }
        check_data(init, k, d, "init")?;
        return Ok(run(x, n, d, init, k, params.max_iter, tol_abs, diameter));
    }

    let seed_data = SeedData::new(x, n, d);
    let one = |r: usize| {
        let mut rng = Rng::new(run_seed(params.seed, r as u64));
        let (centers, _) = seed(x, &seed_data, n, k, trials, &mut rng);
        run(x, n, d, &centers, k, params.max_iter, tol_abs, diameter)
    };
    // Runs are independent: a few at a time in parallel (each also parallel inside), which
    // keeps both cores busy through the sequential parts of a run. The winner is chosen in run
    // order as before (first lowest inertia), so the result does not change.
    let mut best: Option<KMeansResult> = None;
    let mut r = 0;
    while r < params.n_init {
        let batch = (params.n_init - r).min(PARALLEL_RUNS);
        let results: Vec<KMeansResult> = (r..r + batch).into_par_iter().map(one).collect();
        for res in results {
            if best.as_ref().is_none_or(|b| res.inertia < b.inertia) {
                best = Some(res);
            }
        }
        r += batch;
    }
    Ok(best.expect("n_init ≥ 1"))
}

#[allow(clippy::too_many_arguments)]
fn run(
    x: &[f64],
    n: usize,
    d: usize,
    init: &[f64],
    k: usize,
    max_iter: usize,
    tol_abs: f64,
    diameter: f64,
) -> KMeansResult {
    let r = lloyd(x, n, d, init, k, max_iter, tol_abs, diameter, None);
    KMeansResult {
        centers: r.centers,
        labels: r.labels,
        inertia: r.inertia,
        n_iter: r.n_iter,
        k,
        dim: d,
    }
}

/// Nearest centre (lowest index on ties) and squared distance of every row of the row-major
/// `n × d` matrix `x` to the row-major `k × d` `centers`.
///
/// Errors: empty or mis-sized inputs (Shape), NaN/inf (NonFinite).
pub fn predict(
    x: &[f64],
    n: usize,
    d: usize,
    centers: &[f64],
    k: usize,
) -> Result<(Vec<u32>, Vec<f64>)> {
    crate::simd::level()?;
    check_data(x, n, d, "X")?;
    if k == 0 || Some(centers.len()) != k.checked_mul(d) {
        return Err(Error::Shape(format!(
            "centers must be a non-empty k x {d} matrix, got {} values for k={k}",
            centers.len()
        )));
    }
    check_data(centers, k, d, "centers")?;
    if k > MAX_ROWS {
        return Err(Error::Memory(format!(
            "centers has {k} rows; at most {MAX_ROWS} centres are supported"
        )));
    }
    let panel = Panel::from_centers(centers, k, d);
    let ch = crate::kmeanspp::CHUNK;
    let mut labels = vec![0u32; n];
    let mut dist = vec![0.0; n];
    labels
        .par_chunks_mut(ch)
        .zip(dist.par_chunks_mut(ch))
        .enumerate()
        .for_each(|(b, (lab, dst))| {
            let mut buf = vec![0.0; GROUP * panel.kpad()];
            let kp = panel.kpad();
            for g in 0..lab.len().div_ceil(GROUP) {
                let lo = g * GROUP;
                let hi = (lo + GROUP).min(lab.len());
                let rows: Vec<&[f64]> = (b * ch + lo..b * ch + hi)
                    .map(|i| &x[i * d..(i + 1) * d])
                    .collect();
                sq_dists(&rows, &panel, &mut buf);
                for r in 0..hi - lo {
                    let (best, bd, _) = two_nearest(&buf[r * kp..r * kp + k]);
                    lab[lo + r] = best as u32;
                    dst[lo + r] = bd;
                }
            }
        });
    Ok((labels, dist))
}

/// Largest number of rows (labels are 32-bit).
pub const MAX_ROWS: usize = u32::MAX as usize;

/// Check `1 ≤ k ≤ n ≤ MAX_ROWS` and `1 ≤ n_local_trials ≤ 64`.
pub fn check_k_and_trials(k: usize, n: usize, trials: usize) -> Result<()> {
    if n > MAX_ROWS {
        return Err(Error::Memory(format!(
            "X has {n} rows; k-means handles at most {MAX_ROWS} rows"
        )));
    }
    if k < 1 || k > n {
        return Err(Error::InvalidArgument(format!(
            "k must be between 1 and the number of rows of X ({n}), got {k}"
        )));
    }
    if !(1..=MAX_LOCAL_TRIALS).contains(&trials) {
        return Err(Error::InvalidArgument(format!(
            "n_local_trials must be between 1 and {MAX_LOCAL_TRIALS}, got {trials}"
        )));
    }
    Ok(())
}

/// Column statistics gathered in one pass over the data.
#[derive(Clone, Debug, PartialEq)]
pub struct DataStats {
    /// `mean(var(X, axis=0))` (scikit-learn scales `tol` by it).
    pub mean_variance: f64,
    /// Bound on the distances involved (data bounding box and distance from the origin).
    pub diameter: f64,
}

/// Check `x` (finite, `n × d`, non-empty) and compute its [`DataStats`] in one parallel pass
/// (per-chunk shifted sums combined in chunk order).
pub fn data_stats(x: &[f64], n: usize, d: usize, name: &str) -> Result<DataStats> {
    if n == 0 || d == 0 {
        return Err(Error::Shape(format!(
            "{name} is empty (shape {n}x{d}); need at least one row and one column"
        )));
    }
    if Some(x.len()) != n.checked_mul(d) {
        return Err(Error::Shape(format!(
            "{name} has {} values, expected {n} rows x {d} columns",
            x.len()
        )));
    }
    let shift = &x[..d];
    let ch = crate::kmeanspp::CHUNK;
    // Per chunk: first non-finite position, Σ (x - shift), Σ (x - shift)², min, max.
    type Part = (Option<usize>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);
    let parts: Vec<Part> = x
        .par_chunks(ch * d)
        .enumerate()
        .map(|(b, c)| {
            let mut s1 = vec![0.0; d];
            let mut s2 = vec![0.0; d];
            let mut lo = vec![f64::INFINITY; d];
            let mut hi = vec![f64::NEG_INFINITY; d];
            // v·0 is ±0 for finite values and NaN otherwise: a vectorizable finiteness test.
            let mut nan = 0.0;
            for row in c.chunks_exact(d) {
                for j in 0..d {
                    let v = row[j];
                    nan += v * 0.0;
                    let t = v - shift[j];
                    s1[j] += t;
                    s2[j] += t * t;
                    lo[j] = if v < lo[j] { v } else { lo[j] };
                    hi[j] = if v > hi[j] { v } else { hi[j] };
                }
            }
            let bad = if nan == 0.0 {
                None
            } else {
                c.iter()
                    .position(|v| !v.is_finite())
                    .map(|p| b * ch * d + p)
            };
            (bad, s1, s2, lo, hi)
        })
        .collect();
    if let Some(pos) = parts.iter().find_map(|p| p.0) {
        return Err(Error::NonFinite(format!(
            "{name} contains NaN or infinity (row {}, column {})",
            pos / d,
            pos % d
        )));
    }
    let mut s1 = vec![0.0; d];
    let mut s2 = vec![0.0; d];
    let mut lo = vec![f64::INFINITY; d];
    let mut hi = vec![f64::NEG_INFINITY; d];
    for (_, a1, a2, l, h) in &parts {
        for j in 0..d {
            s1[j] += a1[j];
            s2[j] += a2[j];
            lo[j] = lo[j].min(l[j]);
            hi[j] = hi[j].max(h[j]);
        }
    }
    let nf = n as f64;
    let var_sum: f64 = (0..d)
        .map(|j| (s2[j] / nf - (s1[j] / nf).powi(2)).max(0.0))
        .sum();
    // Half the diagonal of the bounding box plus its farthest corner's distance from the
    // origin (coordinate rounding scales with magnitude): covers every distance computed.
    let half: f64 = lo
        .iter()
        .zip(&hi)
        .map(|(a, b)| (b - a) * (b - a))
        .sum::<f64>()
        .sqrt()
        / 2.0;
    let far: f64 = lo
        .iter()
        .zip(&hi)
        .map(|(a, b)| a.abs().max(b.abs()).powi(2))
        .sum::<f64>()
        .sqrt();
    Ok(DataStats {
        mean_variance: var_sum / d as f64,
        diameter: 2.0 * (half + far),
    })
}

fn run_seed(seed: u64, run: u64) -> u64 {
    seed ^ run.wrapping_mul(0xD1B5_4A32_D192_ED03).rotate_left(17)
}

fn check_data(x: &[f64], n: usize, d: usize, name: &str) -> Result<()> {
    if n == 0 || d == 0 {
        return Err(Error::Shape(format!(
            "{name} is empty (shape {n}x{d}); need at least one row and one column"
        )));
    }
    if Some(x.len()) != n.checked_mul(d) {
        return Err(Error::Shape(format!(
            "{name} has {} values, expected {n} rows x {d} columns",
            x.len()
        )));
    }
    if let Some(pos) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite(format!(
            "{name} contains NaN or infinity (row {}, column {})",
            pos / d,
            pos % d
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blobs(n_per: usize, centres: &[[f64; 2]], spread: f64, seed: u64) -> Vec<f64> {
        let mut rng = Rng::new(seed);
        let mut x = Vec::new();
        for c in centres {
            for _ in 0..n_per {
                x.push(c[0] + spread * (rng.uniform() - 0.5));
                x.push(c[1] + spread * (rng.uniform() - 0.5));
            }
        }
        x
    }

    /// Plain Lloyd (brute force, direct distances) with the same stopping rules.
    fn reference(
        x: &[f64],
        n: usize,
        d: usize,
        init: &[f64],
        k: usize,
        max_iter: usize,
        tol: f64,
    ) -> (Vec<f64>, Vec<u32>, usize) {
        let assign = |c: &[f64]| -> Vec<u32> {
            (0..n)
                .map(|i| {
                    let dists: Vec<f64> = (0..k)
                        .map(|j| {
                            let mut acc = 0.0f64;
                            for t in 0..d {
                                let v = x[i * d + t] - c[j * d + t];
                                acc = v.mul_add(v, acc);
                            }
                            acc
                        })
                        .collect();
                    two_nearest(&dists).0 as u32
                })
                .collect()
        };
        let tol_abs = tol * data_stats(x, n, d, "X").unwrap().mean_variance;
        let mut c = init.to_vec();
        let mut old: Option<Vec<u32>> = None;
        let mut labels = Vec::new();
        let mut it = 0;
        let mut strict = false;
        while it < max_iter {
            it += 1;
            labels = assign(&c);
            let mut sums = vec![0.0; k * d];
            let mut cnt = vec![0usize; k];
            for i in 0..n {
                let l = labels[i] as usize;
                cnt[l] += 1;
                for t in 0..d {
                    sums[l * d + t] += x[i * d + t];
                }
            }
            let mut shift = 0.0;
            for j in 0..k {
                if cnt[j] > 0 {
                    for t in 0..d {
                        let v = sums[j * d + t] * (1.0 / cnt[j] as f64);
                        shift += (v - c[j * d + t]).powi(2);
                        c[j * d + t] = v;
                    }
                }
            }
            if old.as_ref() == Some(&labels) {
                strict = true;
                break;
            }
            if shift <= tol_abs {
                break;
            }
            old = Some(labels.clone());
        }
        if !strict {
            labels = assign(&c);
        }
        (c, labels, it)
    }

    #[test]
    fn finds_separated_blobs() {
        let centres = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]];
        let x = blobs(100, &centres, 1.0, 1);
        let res = kmeans(
            &x,
            300,
            2,
            &KMeansParams {
                n_init: 3,
                ..KMeansParams::new(3)
            },
            None,
        )
        .unwrap();
        for (i, want) in centres.iter().enumerate() {
            // All rows of one blob share a label, and the blobs have different labels.
            let l = res.labels[i * 100];
            assert!(res.labels[i * 100..(i + 1) * 100].iter().all(|&v| v == l));
            let c = &res.centers[l as usize * 2..l as usize * 2 + 2];
            assert!((c[0] - want[0]).abs() < 0.2 && (c[1] - want[1]).abs() < 0.2);
        }
        // Variance of U(-0.5, 0.5) is 1/12 per coordinate: inertia ≈ 300 · 2 / 12.
        assert!((res.inertia - 50.0).abs() < 10.0, "{}", res.inertia);
    }

    #[test]
    fn matches_plain_lloyd_from_the_same_start() {
        let mut rng = Rng::new(3);
        for &(n, d, k) in &[
            (500usize, 3usize, 7usize),
            (2500, 5, 20),
            (3000, 2, 1),
            (1200, 30, 40),
        ] {
            let x: Vec<f64> = (0..n * d).map(|_| rng.uniform() * 10.0).collect();
            let init: Vec<f64> = x[..k * d].to_vec();
            for &(max_iter, tol) in &[(300usize, 0.0), (300, 1e-4), (3, 1e-4)] {
                let p = KMeansParams {
                    max_iter,
                    tol,
                    ..KMeansParams::new(k)
                };
                let res = kmeans(&x, n, d, &p, Some(&init)).unwrap();
                let (c, l, it) = reference(&x, n, d, &init, k, max_iter, tol);
                assert_eq!(res.labels, l, "n={n} k={k} max_iter={max_iter} tol={tol}");
                assert_eq!(res.n_iter, it);
                for (a, b) in res.centers.iter().zip(&c) {
                    assert!((a - b).abs() <= 1e-12 * 10.0);
                }
            }
        }
    }

    #[test]
    fn both_scan_modes_match_plain_lloyd_over_many_iterations() {
        let mut rng = Rng::new(21);
        let mut longest = 0;
        for &(n, d, k) in &[(3000usize, 2usize, 40usize), (2000, 6, 12), (2500, 3, 70)] {
            let x: Vec<f64> = (0..n * d).map(|_| rng.uniform() * 4.0 - 2.0).collect();
            let init: Vec<f64> = x[(n - k) * d..].to_vec();
            let stats = data_stats(&x, n, d, "X").unwrap();
            let (c, l, it) = reference(&x, n, d, &init, k, 500, 0.0);
            longest = longest.max(it);
            use crate::lloyd::Scan;
            for scan in [Scan::Restricted, Scan::Direct, Scan::DirectElkan] {
                let r =
                    crate::lloyd::lloyd(&x, n, d, &init, k, 500, 0.0, stats.diameter, Some(scan));
                assert_eq!(r.labels, l, "n={n} k={k} scan={scan:?}");
                assert_eq!(r.n_iter, it);
                for (a, b) in r.centers.iter().zip(&c) {
                    assert!((a - b).abs() <= 1e-12);
                }
            }
        }
        // The bounds are re-anchored after 24 iterations: make sure that path ran.
        assert!(longest > 30, "longest run {longest}");
    }

    #[test]
    fn empty_cluster_is_reseeded_with_the_farthest_row() {
        // Two far-apart centres start on the same side; the second gets no row at first.
        let x = vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 20.0, 0.0];
        let init = vec![0.5, 0.5, 100.0, 100.0];
        let res = kmeans(&x, 4, 2, &KMeansParams::new(2), Some(&init)).unwrap();
        // Row 3 (20, 0) is farthest from the first centre: it becomes the second cluster.
        assert_eq!(res.labels, vec![0, 0, 0, 1]);
        assert_eq!(&res.centers[2..], &[20.0, 0.0]);
        assert!((res.centers[0] - 1.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn duplicate_rows_fewer_than_k() {
        let x = vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let res = kmeans(&x, 3, 2, &KMeansParams::new(2), None).unwrap();
        assert_eq!(res.inertia, 0.0);
    }

    #[test]
    fn identical_results_for_any_thread_count_and_best_of_n_init() {
        let mut rng = Rng::new(9);
        let (n, d) = (5000, 4);
        let x: Vec<f64> = (0..n * d).map(|_| rng.uniform()).collect();
        let p = KMeansParams {
            n_init: 3,
            seed: 11,
            ..KMeansParams::new(25)
        };
        let run = |t: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap();
            pool.install(|| kmeans(&x, n, d, &p, None).unwrap())
        };
        let one = run(1);
        assert_eq!(one, run(3));
        let single: Vec<f64> = (0..3)
            .map(|r| {
                let q = KMeansParams {
                    n_init: 1,
                    seed: 11,
                    ..p.clone()
                };
                let mut rng = Rng::new(run_seed(q.seed, r));
                let (c, _) = crate::kmeanspp::kmeans_plusplus(
                    &x,
                    n,
                    d,
                    25,
                    default_local_trials(25),
                    &mut rng,
                );
                kmeans(&x, n, d, &q, Some(&c)).unwrap().inertia
            })
            .collect();
        assert_eq!(
            one.inertia,
            single.iter().cloned().fold(f64::INFINITY, f64::min)
        );
    }

    #[test]
    fn predict_nearest_and_ties() {
        let centers = vec![0.0, 0.0, 2.0, 0.0];
        let x = vec![0.1, 0.0, 1.0, 0.0, 3.0, 1.0];
        let (l, dist) = predict(&x, 3, 2, &centers, 2).unwrap();
        assert_eq!(l, vec![0, 0, 1]);
        assert!((dist[0] - 0.01).abs() < 1e-15 && dist[1] == 1.0 && dist[2] == 2.0);
    }

    #[test]
    fn errors() {
        let x = vec![0.0; 10];
        let p = KMeansParams::new(2);
        assert!(matches!(kmeans(&[], 0, 2, &p, None), Err(Error::Shape(_))));
        assert!(matches!(
            kmeans(&x, 5, 2, &KMeansParams::new(6), None),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(&x, 5, 2, &KMeansParams::new(0), None),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(
                &x,
                5,
                2,
                &KMeansParams {
                    n_init: 0,
                    ..p.clone()
                },
                None
            ),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(
                &x,
                5,
                2,
                &KMeansParams {
                    max_iter: 0,
                    ..p.clone()
                },
                None
            ),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(
                &x,
                5,
                2,
                &KMeansParams {
                    tol: -1.0,
                    ..p.clone()
                },
                None
            ),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(
                &x,
                5,
                2,
                &KMeansParams {
                    n_local_trials: Some(0),
                    ..p.clone()
                },
                None
            ),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            kmeans(&x, 5, 2, &p, Some(&[0.0; 3])),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            kmeans(
                &x,
                5,
                2,
                &KMeansParams {
                    n_init: 2,
                    ..p.clone()
                },
                Some(&[0.0; 4])
            ),
            Err(Error::InvalidArgument(_))
        ));
        let mut bad = x.clone();
        bad[3] = f64::NAN;
        assert!(matches!(
            kmeans(&bad, 5, 2, &p, None),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            kmeans(&x, 5, 2, &p, Some(&[0.0, 0.0, f64::INFINITY, 0.0])),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(predict(&x, 5, 2, &[], 0), Err(Error::Shape(_))));
        assert!(matches!(
            predict(&x, 5, 2, &[0.0; 3], 2),
            Err(Error::Shape(_))
        ));
    }
}
