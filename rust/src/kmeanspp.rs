//! Greedy k-means++ seeding (Arthur & Vassilvitskii, with local trials as in scikit-learn)
//! and the small random generator it uses.
//!
//! The first centre is a uniformly random row. Each next centre: draw `n_local_trials`
//! candidate rows with probability proportional to `D(x)²` (squared distance to the nearest
//! centre chosen so far), and keep the candidate that leaves the smallest potential
//! `Σ min(D(x)², ‖x - candidate‖²)`. Default `n_local_trials = 2 + ⌊ln k⌋` (scikit-learn's).
//!
//! Work is split into fixed chunks of rows whatever the thread count; every sum is formed per
//! chunk in row order and the chunk sums are added in chunk order, so the chosen centres
//! depend only on the data and the seed.

use rayon::prelude::*;

use crate::sqdist::{seed_block32, sq_dists32, Panel32};

/// Rows per parallel task.
pub(crate) const CHUNK: usize = 1024;
/// Rows per call of the distance kernel.
const GROUP: usize = 64;

/// xoshiro256** seeded through SplitMix64: small, fast, and reproducible everywhere.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
}

impl Rng {
    /// Generator for a 64-bit seed.
    pub fn new(seed: u64) -> Self {
        let mut z = seed;
        let s = std::array::from_fn(|_| {
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut v = z;
            v = (v ^ (v >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            v = (v ^ (v >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            v ^ (v >> 31)
        });
        Self { s }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let result = self.s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = self.s[1] << 17;
        self.s[2] ^= self.s[0];
        self.s[3] ^= self.s[1];
        self.s[1] ^= self.s[2];
        self.s[0] ^= self.s[3];
        self.s[2] ^= t;
        self.s[3] = self.s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in [0, n) (`n ≥ 1`; Lemire's multiply-shift, bias < n / 2⁶⁴).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }
}

/// Default number of local trials: `2 + ⌊ln k⌋`.
pub fn default_local_trials(k: usize) -> usize {
    2 + (k as f64).ln().floor() as usize
}

/// Largest supported number of local trials (candidates are tracked in a 64-bit mask).
pub const MAX_LOCAL_TRIALS: usize = 64;

/// Rows of one cluster of the partition "nearest centre so far".
#[derive(Clone, Debug, Default)]
struct Cluster {
    /// Row indices, ascending.
    members: Vec<u32>,
    /// `D(x)²` of each member (same order): kept here, not in a global array, so that the
    /// passes over a cluster read it sequentially.
    dist: Vec<f64>,
    /// `Σ D(x)²` over the members, summed in member order.
    pot: f64,
    /// `max D(x)²` over the members.
    radius2: f64,
}

impl Cluster {
    fn from_members(members: Vec<u32>, closest: &[f64]) -> Self {
        let mut c = Self::default();
        for i in members {
            c.push(i, closest[i as usize]);
        }
        c
    }

    #[inline]
    fn push(&mut self, i: u32, v: f64) {
        self.members.push(i);
        self.dist.push(v);
        self.pot += v;
        self.radius2 = self.radius2.max(v);
    }
}

/// The data in single precision for the seeding: rows shifted by the first row (so that
/// the f32 rounding is relative to the spread of the data, not to its offset).
pub struct SeedData {
    d: usize,
    xf: Vec<f32>,
}

impl SeedData {
    /// Single-precision copy of the row-major `n × d` matrix `x` (`n ≥ 1`).
    pub fn new(x: &[f64], n: usize, d: usize) -> Self {
        assert!(n >= 1 && x.len() == n * d);
        let shift = &x[..d];
        let mut xf = vec![0.0f32; n * d];
        xf.par_chunks_mut(CHUNK * d)
            .zip(x.par_chunks(CHUNK * d))
            .for_each(|(dst, src)| {
                for (drow, srow) in dst.chunks_exact_mut(d).zip(src.chunks_exact(d)) {
                    for ((o, &v), &s) in drow.iter_mut().zip(srow).zip(shift) {
                        *o = (v - s) as f32;
                    }
                }
            });
        Self { d, xf }
    }
}

/// What [`kmeans_plusplus`] runs at `level`, as `instruction_sets()` reports it (there is no
/// AVX-512 kernel: at that level the single-precision distances run with AVX2 and FMA).
pub fn instruction_set(level: crate::simd::Level) -> &'static str {
    match level {
        crate::simd::Level::Portable => "portable",
        _ => "avx2+fma",
    }
}

/// Choose `k` seeds among the rows of the row-major `n × d` matrix `x` (`1 ≤ k ≤ n`, finite
/// values, `1 ≤ n_local_trials ≤ 64`, checked by the caller). Returns the row-major `k × d`
/// centres (rows of `x`) and their row indices.
///
/// Distances are computed in single precision on rows shifted by the first row (relative
/// error ~1e-7, enough to draw and compare candidates; half the memory traffic of f64).
/// Exact pruning (Raff, "Exact acceleration of k-means++", 2021): rows are grouped by their
/// nearest centre `c`; a candidate `t` cannot bring a row closer when `‖c - t‖ ≥ 2·D(x)`
/// (triangle inequality), so such rows, and whole groups, are skipped.
pub fn kmeans_plusplus(
    x: &[f64],
    n: usize,
    d: usize,
    k: usize,
    n_local_trials: usize,
    rng: &mut Rng,
) -> (Vec<f64>, Vec<usize>) {
    let data = SeedData::new(x, n, d);
    seed(x, &data, n, k, n_local_trials, rng)
}

/// [`kmeans_plusplus`] with a prepared single-precision copy.
pub fn seed(
    x: &[f64],
    data: &SeedData,
    n: usize,
    k: usize,
    n_local_trials: usize,
    rng: &mut Rng,
) -> (Vec<f64>, Vec<usize>) {
    let d = data.d;
    assert!(k >= 1 && k <= n && x.len() == n * d && data.xf.len() == n * d);
    assert!((1..=MAX_LOCAL_TRIALS).contains(&n_local_trials));
    let trials = n_local_trials;
    let xf = &data.xf;
    let row = |i: usize| &xf[i * d..(i + 1) * d];
    let mut indices = Vec::with_capacity(k);
    indices.push(rng.below(n));

    // closest[i]: squared distance of row i to its nearest centre so far.
    let mut closest = vec![0.0; n];
    let first = Panel32::from_rows(xf, d, &indices);
    closest
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(b, dst)| {
            let kp = first.kpad();
            let mut buf = vec![0.0; GROUP * kp];
            for (g, dg) in dst.chunks_mut(GROUP).enumerate() {
                let start = b * CHUNK + g * GROUP;
                let rows: Vec<&[f32]> = (start..start + dg.len()).map(row).collect();
                sq_dists32(&rows, &first, &mut buf);
                for (r, v) in dg.iter_mut().enumerate() {
                    *v = buf[r * kp];
                }
            }
        });
    let mut clusters = vec![Cluster::from_members((0..n as u32).collect(), &closest)];
    drop(closest);

    let mut candidates = vec![0usize; trials];
    for c in 1..k {
        let pot: f64 = clusters.iter().map(|cl| cl.pot).sum();
        for cand in candidates.iter_mut() {
            *cand = if pot > 0.0 {
                sample(&clusters, rng.uniform() * pot)
            } else {
                // Every row coincides with a centre: any row is as good as another.
                rng.below(n)
            };
        }
        let panel = Panel32::from_rows(xf, d, &candidates);
        let kp = panel.kpad();

        // Which candidates may improve which clusters.
        let crow: Vec<&[f32]> = indices.iter().map(|&i| row(i)).collect();
        let mut cc = vec![0.0; c * kp];
        sq_dists32(&crow, &panel, &mut cc);
        let masks: Vec<u64> = (0..c)
            .map(|j| {
                let lim = 4.0 * clusters[j].radius2;
                (0..trials)
                    .filter(|&t| cc[j * kp + t] < lim)
                    .fold(0u64, |m, t| m | (1 << t))
            })
            .collect();

        // Distances of the rows of every concerned cluster to the candidates, in blocks.
        let mut items: Vec<(usize, usize, usize)> = Vec::new();
        for j in 0..c {
            if masks[j] != 0 {
                let len = clusters[j].members.len();
                for s in (0..len).step_by(CHUNK) {
                    items.push((j, s, (s + CHUNK).min(len)));
                }
            }
        }
        // Per item: the rows whose distances were computed (position in the item, distances
        // to the candidates), and Σ min(D, d_t) per candidate. A row is only compared with
        // candidate t when ‖c - t‖² < 4·D(x)² (otherwise t cannot be closer than its centre).
        let results: Vec<(Vec<u32>, Vec<f64>, Vec<f64>)> = items
            .par_iter()
            .map(|&(j, s, e)| {
                let members = &clusters[j].members[s..e];
                let ccj = &cc[j * kp..j * kp + trials];
                let reach = ccj.iter().fold(f64::INFINITY, |m, &v| m.min(v)) / 4.0;
                // Rows out of reach of every candidate keep D(x)²: one sum serves them all.
                let mut skipped = 0.0;
                let mut positions: Vec<u32> = Vec::with_capacity(members.len());
                let mut near: Vec<f64> = Vec::with_capacity(members.len());
                let dists = &clusters[j].dist[s..e];
                for (r, &di) in dists.iter().enumerate() {
                    if di > reach {
                        positions.push(r as u32);
                        near.push(di);
                    } else {
                        skipped += di;
                    }
                }
                let mut pots = vec![skipped; trials];
                // Distances to the candidates (kp per row) and, per candidate, the potential
                // Σ min(D, d_t) over the rows it may bring closer (4·D(x)² > ‖c - t‖²).
                let mut dist = vec![0.0; positions.len() * kp];
                let mut lim = vec![f64::INFINITY; kp];
                lim[..trials].copy_from_slice(ccj);
                let mut rows: Vec<&[f32]> = Vec::with_capacity(GROUP);
                if kp == 8 {
                    let lim8: [f64; 8] = lim[..8].try_into().expect("8 values");
                    let mut acc = [0.0; 8];
                    for (g, grp) in positions.chunks(GROUP).enumerate() {
                        rows.clear();
                        rows.extend(grp.iter().map(|&r| row(members[r as usize] as usize)));
                        let (start, len) = (g * GROUP, grp.len());
                        let out = &mut dist[start * 8..(start + len) * 8];
                        seed_block32(
                            &rows,
                            &near[start..start + len],
                            &panel,
                            &lim8,
                            out,
                            &mut acc,
                        );
                    }
                    for (p, a) in pots.iter_mut().zip(&acc) {
                        *p += a;
                    }
                } else {
                    let mut acc = vec![0.0; kp];
                    for (g, grp) in positions.chunks(GROUP).enumerate() {
                        rows.clear();
                        rows.extend(grp.iter().map(|&r| row(members[r as usize] as usize)));
                        let start = g * GROUP * kp;
                        sq_dists32(&rows, &panel, &mut dist[start..start + grp.len() * kp]);
                    }
                    for (r, &di) in near.iter().enumerate() {
                        let drow = &dist[r * kp..(r + 1) * kp];
                        for ((a, &v), &l) in acc.iter_mut().zip(drow).zip(&lim) {
                            let m = if v < di { v } else { di };
                            *a += if 4.0 * di > l { m } else { di };
                        }
                    }
                    for (p, a) in pots.iter_mut().zip(&acc) {
                        *p += a;
                    }
                }
                (positions, dist, pots)
            })
            .collect();

        // Potential left by each candidate; keep the smallest (first on ties).
        let mut best = 0;
        let mut best_pot = f64::INFINITY;
        for t in 0..trials {
            let mut p = 0.0;
            let mut it = 0;
            for j in 0..c {
                if masks[j] == 0 {
                    p += clusters[j].pot;
                    continue;
                }
                let mut pj = 0.0;
                while it < items.len() && items[it].0 == j {
                    pj += results[it].2[t];
                    it += 1;
                }
                p += pj;
            }
            if p < best_pot {
                best_pot = p;
                best = t;
            }
        }
        indices.push(candidates[best]);

        // Move the rows that the new centre brings closer.
        let mut first_item = vec![usize::MAX; c];
        for (it, &(j, _, _)) in items.iter().enumerate().rev() {
            first_item[j] = it;
        }
        let touched: Vec<usize> = (0..c).filter(|&j| masks[j] >> best & 1 == 1).collect();
        // Per touched cluster: what it keeps (when it loses rows) and the (row, distance)
        // pairs it loses, in member order.
        type Moved = (Option<Cluster>, Vec<(u32, f64)>);
        let moved: Vec<Moved> = touched
            .par_iter()
            .map(|&j| {
                let mut movers = Vec::new();
                let mut keep = Cluster::default();
                let mut it = first_item[j];
                let (members, dists) = (&clusters[j].members, &clusters[j].dist);
                while it < items.len() && items[it].0 == j {
                    let (_, s, e) = items[it];
                    let (positions, dist) = (&results[it].0, &results[it].1);
                    let mut next = 0;
                    for (r, (&i, &di)) in members[s..e].iter().zip(&dists[s..e]).enumerate() {
                        if next < positions.len() && positions[next] as usize == r {
                            let v = dist[next * kp + best];
                            next += 1;
                            if 4.0 * di > cc[j * kp + best] && v < di {
                                movers.push((i, v));
                                continue;
                            }
                        }
                        keep.push(i, di);
                    }
                    it += 1;
                }
                (if movers.is_empty() { None } else { Some(keep) }, movers)
            })
            .collect();
        // The new cluster: the rows lost by the touched clusters, in cluster then member order.
        let mut gained: Vec<(u32, f64)> = Vec::new();
        for (&j, (keep, movers)) in touched.iter().zip(moved) {
            gained.extend_from_slice(&movers);
            if let Some(keep) = keep {
                clusters[j] = keep;
            }
        }
        // Ascending row order keeps the later passes over this cluster close to streaming.
        gained.sort_unstable_by_key(|&(i, _)| i);
        let mut fresh = Cluster::default();
        for (i, v) in gained {
            fresh.push(i, v);
        }
        clusters.push(fresh);
    }
    let mut centers = Vec::with_capacity(k * d);
    for &i in &indices {
        centers.extend_from_slice(&x[i * d..(i + 1) * d]);
    }
    (centers, indices)
}

/// Row where the running sum of `D(x)²`, cluster by cluster and in member order, first
/// exceeds `r` (`0 ≤ r < Σ D(x)²`).
fn sample(clusters: &[Cluster], r: f64) -> usize {
    let mut acc = 0.0;
    for cl in clusters {
        if acc + cl.pot > r {
            for (&i, &v) in cl.members.iter().zip(&cl.dist) {
                acc += v;
                if acc > r {
                    return i as usize;
                }
            }
            // Rounding: fall back to the cluster's last row with a positive weight.
            if let Some(p) = cl.dist.iter().rposition(|&v| v > 0.0) {
                return cl.members[p] as usize;
            }
        }
        acc += cl.pot;
    }
    // Rounding at the very end: the last row with a positive weight.
    clusters
        .iter()
        .rev()
        .find_map(|cl| {
            cl.dist
                .iter()
                .rposition(|&v| v > 0.0)
                .map(|p| cl.members[p] as usize)
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_reproducible_and_uniform() {
        let mut a = Rng::new(42);
        let mut b = Rng::new(42);
        let va: Vec<u64> = (0..100).map(|_| a.next_u64()).collect();
        let vb: Vec<u64> = (0..100).map(|_| b.next_u64()).collect();
        assert_eq!(va, vb);
        assert_ne!(Rng::new(43).next_u64(), va[0]);
        let mut r = Rng::new(1);
        let m: f64 = (0..100_000).map(|_| r.uniform()).sum::<f64>() / 100_000.0;
        assert!((m - 0.5).abs() < 0.01);
        let mut counts = [0usize; 5];
        for _ in 0..50_000 {
            counts[r.below(5)] += 1;
        }
        assert!(counts.iter().all(|&c| (9_000..11_000).contains(&c)));
    }

    #[test]
    fn sample_respects_weights() {
        let w = vec![0.0, 1.0, 0.0, 3.0, 2.0];
        let clusters = vec![
            Cluster::from_members(vec![0, 1, 3], &w),
            Cluster::from_members(vec![2, 4], &w),
        ];
        assert_eq!(sample(&clusters, 0.0), 1);
        assert_eq!(sample(&clusters, 0.999), 1);
        assert_eq!(sample(&clusters, 1.0), 3);
        assert_eq!(sample(&clusters, 3.999), 3);
        assert_eq!(sample(&clusters, 4.0), 4);
        assert_eq!(sample(&clusters, 5.999), 4);
    }

    /// Plain greedy k-means++ (no pruning) with the same random draws.
    fn brute(x: &[f64], n: usize, d: usize, k: usize, trials: usize, seed: u64) -> Vec<usize> {
        let mut rng = Rng::new(seed);
        // The same single-precision distances as the kernels (rows shifted by the first).
        let xf: Vec<f32> = (0..n * d).map(|p| (x[p] - x[p % d]) as f32).collect();
        let dist = |i: usize, j: usize| -> f64 {
            let mut acc = 0.0f32;
            for t in 0..d {
                let v = xf[i * d + t] - xf[j * d + t];
                acc = v.mul_add(v, acc);
            }
            acc as f64
        };
        let mut idx = vec![rng.below(n)];
        let mut closest: Vec<f64> = (0..n).map(|i| dist(i, idx[0])).collect();
        let mut members: Vec<Vec<u32>> = vec![(0..n as u32).collect()];
        for _ in 1..k {
            let clusters: Vec<Cluster> = members
                .iter()
                .map(|m| Cluster::from_members(m.clone(), &closest))
                .collect();
            let pot: f64 = clusters.iter().map(|cl| cl.pot).sum();
            let cands: Vec<usize> = (0..trials)
                .map(|_| {
                    if pot > 0.0 {
                        sample(&clusters, rng.uniform() * pot)
                    } else {
                        rng.below(n)
                    }
                })
                .collect();
            let pots: Vec<f64> = cands
                .iter()
                .map(|&t| (0..n).map(|i| closest[i].min(dist(i, t))).sum())
                .collect();
            let best = (0..trials).fold(0, |b, t| if pots[t] < pots[b] { t } else { b });
            let t = cands[best];
            idx.push(t);
            // Rows move to the new cluster, which lists them in ascending order.
            let mut fresh = Vec::new();
            for m in members.iter_mut() {
                m.retain(|&i| {
                    let v = dist(i as usize, t);
                    if v < closest[i as usize] {
                        closest[i as usize] = v;
                        fresh.push(i);
                        false
                    } else {
                        true
                    }
                });
            }
            fresh.sort_unstable();
            members.push(fresh);
        }
        idx
    }

    #[test]
    fn pruning_keeps_the_brute_force_choices() {
        // Clustered data, so that pruning actually skips groups.
        let mut rng = Rng::new(8);
        let (n, d) = (3000, 3);
        let mut x = Vec::with_capacity(n * d);
        for i in 0..n {
            let blob = (i % 12) as f64;
            for t in 0..d {
                x.push(blob * 10.0 * (t as f64 + 1.0) + rng.uniform());
            }
        }
        for seed in 0..4 {
            let (_, idx) = kmeans_plusplus(&x, n, d, 30, 3, &mut Rng::new(seed));
            assert_eq!(idx, brute(&x, n, d, 30, 3, seed), "seed {seed}");
        }
    }

    #[test]
    fn seeds_are_distinct_rows_one_per_blob() {
        // Four tight, far-apart blobs of 50 points: k-means++ must pick one row in each.
        let mut x = Vec::new();
        let mut rng = Rng::new(5);
        let centres = [[0.0, 0.0], [100.0, 0.0], [0.0, 100.0], [100.0, 100.0]];
        for c in &centres {
            for _ in 0..50 {
                x.push(c[0] + rng.uniform());
                x.push(c[1] + rng.uniform());
            }
        }
        for seed in 0..20 {
            let (centers, idx) = kmeans_plusplus(&x, 200, 2, 4, 3, &mut Rng::new(seed));
            let mut blobs: Vec<usize> = idx.iter().map(|i| i / 50).collect();
            blobs.sort();
            assert_eq!(blobs, vec![0, 1, 2, 3], "seed {seed}");
            for (c, &i) in idx.iter().enumerate() {
                assert_eq!(&centers[c * 2..c * 2 + 2], &x[i * 2..i * 2 + 2]);
            }
        }
    }

    #[test]
    fn all_identical_rows() {
        let x = vec![1.0; 30];
        let (centers, idx) = kmeans_plusplus(&x, 10, 3, 4, 2, &mut Rng::new(0));
        assert_eq!(idx.len(), 4);
        assert!(centers.iter().all(|&v| v == 1.0));
    }
}
