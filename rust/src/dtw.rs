//! Dynamic time warping (DTW) distances between ragged sets of multichannel sequences.
//!
//! A set of sequences is one row-major `(total_frames, dim)` array plus `offsets`, the first
//! frame of each sequence (as in [`crate::ragged`]). For sequences `a` (`n` frames) and `b`
//! (`m` frames) the DTW cost is the smallest sum of local costs `‖a_i − b_j‖₂` (Euclidean
//! distance between frames) along a warping path from `(0, 0)` to `(n − 1, m − 1)` with
//! steps `(1, 0)`, `(0, 1)` and `(1, 1)`.
//!
//! * **Band** (Sakoe–Chiba, on normalised time): with `band = Some(r)`, cell `(i, j)` is
//!   allowed only when `|i / (n − 1) − j / (m − 1)| ≤ ρ`, with
//!   `ρ = max(r, (1 / (n − 1) + 1 / (m − 1)) / 2)` (the lower bound keeps a path possible
//!   whatever the lengths). The band is symmetric in the two sequences. A sequence of one
//!   frame has no band. `None`: no band.
//! * **Normalisation**: with `normalize`, the cost is divided by `n + m`, so sequences of
//!   different lengths compare on the scale of one frame's distance.
//!
//! Every pair is computed independently (two rows of `m + 1` values per worker), in parallel
//! over query sequences with rayon; results do not depend on the number of threads.

use rayon::prelude::*;

use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// Options of the DTW distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DtwOptions {
    /// Sakoe–Chiba band half-width as a fraction of the longer length, in `[0, 1]`.
    pub band: Option<f64>,
    /// Divide each cost by the sum of the two lengths.
    pub normalize: bool,
}

impl Default for DtwOptions {
    fn default() -> Self {
        Self {
            band: None,
            normalize: true,
        }
    }
}

/// A checked ragged set: values, dimension and each sequence's `(start, end)` frames.
struct Set<'a> {
    values: &'a [f64],
    dim: usize,
    bounds: Vec<(usize, usize)>,
}

impl<'a> Set<'a> {
    fn new(values: &'a [f64], offsets: &[i64], dim: usize, name: &str) -> Result<Self> {
        if dim == 0 {
            return Err(Error::Shape(format!(
                "{name}: frames need at least one channel (dim = 0)"
            )));
        }
        if !values.len().is_multiple_of(dim) {
            return Err(Error::Shape(format!(
                "{name}: {} values do not split into frames of {dim} channels",
                values.len()
            )));
        }
        let frames = values.len() / dim;
        if frames == 0 {
            return Err(Error::Shape(format!("{name}: no frames given")));
        }
        let bounds =
            trial_bounds(offsets, frames).map_err(|e| prefix_error(e, &format!("{name}: ")))?;
        if let Some(i) = crate::checks::first_non_finite(values) {
            return Err(Error::NonFinite(format!(
                "{name}: NaN or infinity at frame {}, channel {}",
                i / dim,
                i % dim
            )));
        }
        Ok(Self {
            values,
            dim,
            bounds,
        })
    }

    fn seq(&self, k: usize) -> &'a [f64] {
        let (s, e) = self.bounds[k];
        &self.values[s * self.dim..e * self.dim]
    }

    fn longest(&self) -> usize {
        self.bounds.iter().map(|(s, e)| e - s).max().unwrap_or(0)
    }
}

fn prefix_error(err: Error, prefix: &str) -> Error {
    match err {
        Error::InvalidArgument(m) => Error::InvalidArgument(format!("{prefix}{m}")),
        Error::Shape(m) => Error::Shape(format!("{prefix}{m}")),
        Error::NonFinite(m) => Error::NonFinite(format!("{prefix}{m}")),
        Error::Numerical(m) => Error::Numerical(format!("{prefix}{m}")),
        Error::Memory(m) => Error::Memory(format!("{prefix}{m}")),
    }
}

fn check_options(options: &DtwOptions) -> Result<()> {
    if let Some(r) = options.band {
        if !(0.0..=1.0).contains(&r) {
            return Err(Error::InvalidArgument(format!(
                "band must be a fraction of the length in [0, 1] (or None for no band), got {r}"
            )));
        }
    }
    Ok(())
}

/// A zeroed `f64` vector of `len` values, or an error instead of an aborting allocation.
fn try_zeroed(len: usize, what: &str) -> Result<Vec<f64>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| Error::InvalidArgument(format!("cannot allocate {len} values for {what}")))?;
    v.resize(len, 0.0);
    Ok(v)
}

/// The band of a pair of lengths: `(n − 1, m − 1, W)` such that cell `(i, j)` is allowed
/// when `|i (m − 1) − j (n − 1)| ≤ W`; `None` when every cell is allowed.
fn band_limits(band: Option<f64>, n: usize, m: usize) -> Option<(f64, f64, f64)> {
    let r = band?;
    if n < 2 || m < 2 {
        return None;
    }
    let (a, b) = ((n - 1) as f64, (m - 1) as f64);
    let rho = r.max((1.0 / a + 1.0 / b) / 2.0);
    Some((a, b, rho * (a * b)))
}

/// Columns `[lo, hi]` (inclusive) of row `i` allowed by the band.
#[inline]
fn band_range(i: usize, m: usize, limits: Option<(f64, f64, f64)>) -> (usize, usize) {
    let Some((a, b, w)) = limits else {
        return (0, m - 1);
    };
    let x = i as f64 * b;
    let allowed = |j: usize| (x - j as f64 * a).abs() <= w;
    // Estimate, then settle on the exact (symmetric) criterion.
    let mut lo = ((x - w) / a).ceil().clamp(0.0, (m - 1) as f64) as usize;
    while lo > 0 && allowed(lo - 1) {
        lo -= 1;
    }
    while lo < m - 1 && !allowed(lo) {
        lo += 1;
    }
    let mut hi = ((x + w) / a).floor().clamp(lo as f64, (m - 1) as f64) as usize;
    while hi < m - 1 && allowed(hi + 1) {
        hi += 1;
    }
    while hi > lo && !allowed(hi) {
        hi -= 1;
    }
    (lo, hi)
}

/// DTW cost of one pair; `prev` and `cur` hold at least `m + 1` values (scratch).
fn pair_cost(
    a: &[f64],
    b: &[f64],
    dim: usize,
    options: &DtwOptions,
    prev: &mut [f64],
    cur: &mut [f64],
) -> f64 {
    let n = a.len() / dim;
    let m = b.len() / dim;
    let limits = band_limits(options.band, n, m);
    // Column 0 of the padded table is the "before the first frame" boundary.
    prev[..=m].fill(f64::INFINITY);
    prev[0] = 0.0;
    let (mut prev, mut cur) = (prev, cur);
    for i in 0..n {
        let ai = &a[i * dim..(i + 1) * dim];
        let (lo, hi) = band_range(i, m, limits);
        cur[..=m].fill(f64::INFINITY);
        for j in lo..=hi {
            let bj = &b[j * dim..(j + 1) * dim];
            let d = ai
                .iter()
                .zip(bj)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt();
            let best = prev[j].min(prev[j + 1]).min(cur[j]);
            cur[j + 1] = d + best;
        }
        // The boundary column stays infinite in every later row: only (0, 0) starts a path.
        std::mem::swap(&mut prev, &mut cur);
    }
    let total = prev[m];
    if options.normalize {
        total / (n + m) as f64
    } else {
        total
    }
}

/// Fill `out` (one row per query, `n_refs` columns) with DTW costs, rows in parallel.
/// `skip_lower`: only compute columns `j > i` (self distances; the rest is mirrored later).
fn fill_rows(
    queries: &Set<'_>,
    refs: &Set<'_>,
    options: &DtwOptions,
    out: &mut [f64],
    skip_lower: bool,
) -> Result<()> {
    let n_refs = refs.bounds.len();
    let scratch = refs
        .longest()
        .checked_add(1)
        .ok_or_else(|| Error::Shape("reference sequences are too long".into()))?;
    let dim = queries.dim;
    out.par_chunks_mut(n_refs)
        .enumerate()
        .try_for_each(|(i, row)| -> Result<()> {
            let mut prev = try_zeroed(scratch, "the DTW table")?;
            let mut cur = try_zeroed(scratch, "the DTW table")?;
            let a = queries.seq(i);
            let first = if skip_lower { i + 1 } else { 0 };
            for (j, cell) in row.iter_mut().enumerate().skip(first) {
                *cell = pair_cost(a, refs.seq(j), dim, options, &mut prev, &mut cur);
            }
            Ok(())
        })
}

/// DTW costs between every query sequence and every reference sequence.
///
/// `queries` / `references` are row-major `(frames, dim)` values with `offsets` (first frame
/// of each sequence). Returns a row-major `(n_queries, n_references)` matrix.
pub fn dtw_cross(
    queries: &[f64],
    query_offsets: &[i64],
    references: &[f64],
    reference_offsets: &[i64],
    dim: usize,
    options: &DtwOptions,
) -> Result<Vec<f64>> {
    check_options(options)?;
    let q = Set::new(queries, query_offsets, dim, "queries")?;
    let r = Set::new(references, reference_offsets, dim, "references")?;
    let len = q
        .bounds
        .len()
        .checked_mul(r.bounds.len())
        .ok_or_else(|| Error::Shape("the distance matrix is too large".into()))?;
    let mut out = try_zeroed(len, "the distance matrix")?;
    fill_rows(&q, &r, options, &mut out, false)?;
    Ok(out)
}

/// DTW costs between every pair of sequences of one set: a symmetric `(n, n)` row-major
/// matrix with zeros on the diagonal. Each pair is computed once (`i < j`) and mirrored.
pub fn dtw_pairwise(
    values: &[f64],
    offsets: &[i64],
    dim: usize,
    options: &DtwOptions,
) -> Result<Vec<f64>> {
    check_options(options)?;
    let s = Set::new(values, offsets, dim, "sequences")?;
    let n = s.bounds.len();
    let len = n
        .checked_mul(n)
        .ok_or_else(|| Error::Shape("the distance matrix is too large".into()))?;
    let mut out = try_zeroed(len, "the distance matrix")?;
    fill_rows(&s, &s, options, &mut out, true)?;
    for i in 0..n {
        for j in 0..i {
            out[i * n + j] = out[j * n + i];
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Textbook DTW on a full (n + 1) × (m + 1) table, for comparison.
    fn reference(a: &[f64], b: &[f64], dim: usize, band: Option<f64>) -> f64 {
        let (n, m) = (a.len() / dim, b.len() / dim);
        let mut t = vec![vec![f64::INFINITY; m + 1]; n + 1];
        t[0][0] = 0.0;
        let limits = band_limits(band, n, m);
        for i in 1..=n {
            for j in 1..=m {
                if let Some((a, b, w)) = limits {
                    if ((i - 1) as f64 * b - (j - 1) as f64 * a).abs() > w {
                        continue;
                    }
                }
                let d: f64 = (0..dim)
                    .map(|k| (a[(i - 1) * dim + k] - b[(j - 1) * dim + k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                t[i][j] = d + t[i - 1][j].min(t[i][j - 1]).min(t[i - 1][j - 1]);
            }
        }
        t[n][m]
    }

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    fn random_set(lengths: &[usize], dim: usize, seed: &mut u64) -> (Vec<f64>, Vec<i64>) {
        let mut values = Vec::new();
        let mut offsets = Vec::new();
        for &len in lengths {
            offsets.push((values.len() / dim) as i64);
            for _ in 0..len * dim {
                values.push(lcg(seed));
            }
        }
        (values, offsets)
    }

    #[test]
    fn matches_the_textbook_table() {
        let mut seed = 7;
        let dim = 3;
        let (q, qo) = random_set(&[1, 5, 17, 9], dim, &mut seed);
        let (r, ro) = random_set(&[4, 1, 23], dim, &mut seed);
        for band in [None, Some(0.0), Some(0.1), Some(0.5), Some(1.0)] {
            let options = DtwOptions {
                band,
                normalize: false,
            };
            let out = dtw_cross(&q, &qo, &r, &ro, dim, &options).unwrap();
            let qs = Set::new(&q, &qo, dim, "q").unwrap();
            let rs = Set::new(&r, &ro, dim, "r").unwrap();
            for i in 0..4 {
                for j in 0..3 {
                    let want = reference(qs.seq(i), rs.seq(j), dim, band);
                    assert!(want.is_finite(), "band {band:?} leaves no path");
                    assert_relative_eq!(out[i * 3 + j], want, max_relative = 1e-12);
                }
            }
        }
    }

    #[test]
    fn warping_absorbs_repeated_frames() {
        // b repeats every frame of a twice: zero cost with warping.
        let a = [0.0, 10.0, 30.0, 20.0];
        let b = [0.0, 0.0, 10.0, 10.0, 30.0, 30.0, 20.0, 20.0];
        let out = dtw_cross(&a, &[0], &b, &[0], 1, &DtwOptions::default()).unwrap();
        assert_eq!(out, vec![0.0]);
        // Shifted by 1: every frame is 1 from its own copies and ≥ 9 from any other, and a
        // path has at least 8 cells, so the cost is 8, normalised by 4 + 8 frames.
        let shifted = [1.0, 11.0, 31.0, 21.0];
        let out = dtw_cross(&shifted, &[0], &b, &[0], 1, &DtwOptions::default()).unwrap();
        assert_relative_eq!(out[0], 8.0 / 12.0, max_relative = 1e-12);
    }

    #[test]
    fn pairwise_is_symmetric_and_equals_cross() {
        let mut seed = 3;
        let dim = 2;
        let (x, o) = random_set(&[6, 11, 3, 8, 8], dim, &mut seed);
        let options = DtwOptions {
            band: Some(0.2),
            normalize: true,
        };
        let p = dtw_pairwise(&x, &o, dim, &options).unwrap();
        let c = dtw_cross(&x, &o, &x, &o, dim, &options).unwrap();
        for i in 0..5 {
            assert_eq!(p[i * 5 + i], 0.0);
            assert_relative_eq!(c[i * 5 + i], 0.0, epsilon = 1e-12);
            for j in 0..5 {
                assert_eq!(p[i * 5 + j], p[j * 5 + i]);
                if i != j {
                    assert_relative_eq!(p[i * 5 + j], c[i * 5 + j], max_relative = 1e-12);
                }
            }
        }
    }

    #[test]
    fn results_do_not_depend_on_threads() {
        let mut seed = 11;
        let (x, o) = random_set(&[30, 25, 40, 12, 33, 18, 27], 4, &mut seed);
        let options = DtwOptions::default();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| dtw_pairwise(&x, &o, 4, &options).unwrap());
        let many = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap()
            .install(|| dtw_pairwise(&x, &o, 4, &options).unwrap());
        assert_eq!(one, many);
    }

    #[test]
    fn bad_inputs_are_refused() {
        let opts = DtwOptions::default();
        let x = [0.0; 6];
        assert!(matches!(
            dtw_cross(&x, &[0], &x, &[0], 0, &opts),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            dtw_cross(&x, &[0], &x[..5], &[0], 2, &opts),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            dtw_cross(&[], &[0], &x, &[0], 2, &opts),
            Err(Error::Shape(_))
        ));
        let err = dtw_cross(&x, &[0, 3], &x, &[0], 2, &opts).unwrap_err();
        assert!(err.to_string().starts_with("queries: "));
        let mut y = x;
        y[3] = f64::NAN;
        let err = dtw_cross(&x, &[0], &y, &[0], 2, &opts).unwrap_err();
        assert_eq!(
            err,
            Error::NonFinite("references: NaN or infinity at frame 1, channel 1".into())
        );
        for band in [-0.1, 1.5, f64::NAN] {
            let o = DtwOptions {
                band: Some(band),
                normalize: true,
            };
            assert!(matches!(
                dtw_pairwise(&x, &[0, 1], 2, &o),
                Err(Error::InvalidArgument(_))
            ));
        }
    }
}
