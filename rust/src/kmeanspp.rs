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

use crate::sqdist::{sq_dists, Panel};

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

/// Choose `k` seeds among the rows of the row-major `n × d` matrix `x` (`1 ≤ k ≤ n`, finite
/// values, checked by the caller). Returns the row-major `k × d` centres and their row indices.
pub fn kmeans_plusplus(
    x: &[f64],
    n: usize,
    d: usize,
    k: usize,
    n_local_trials: usize,
    rng: &mut Rng,
) -> (Vec<f64>, Vec<usize>) {
    assert!(k >= 1 && k <= n && x.len() == n * d && n_local_trials >= 1);
    let trials = n_local_trials;
    let mut indices = Vec::with_capacity(k);
    indices.push(rng.below(n));

    // closest[i]: squared distance of row i to its nearest centre so far.
    let mut closest = vec![0.0; n];
    let first = Panel::from_rows(x, d, &indices);
    let mut chunk_pot: Vec<f64> = closest
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(b, dst)| {
            let mut buf = vec![0.0; GROUP * first.kpad()];
            let kp = first.kpad();
            for (g, dg) in dst.chunks_mut(GROUP).enumerate() {
                let start = b * CHUNK + g * GROUP;
                let rows: Vec<&[f64]> =
                    (start..start + dg.len()).map(|i| &x[i * d..(i + 1) * d]).collect();
                sq_dists(&rows, &first, &mut buf);
                for (r, v) in dg.iter_mut().enumerate() {
                    *v = buf[r * kp];
                }
            }
            dst.iter().sum()
        })
        .collect();

    // mins[i * trials + t] = min(closest[i], ‖x_i - candidate t‖²)
    let mut mins = vec![0.0; n * trials];
    let mut candidates = vec![0usize; trials];
    for _ in 1..k {
        let pot: f64 = chunk_pot.iter().sum();
        for c in candidates.iter_mut() {
            *c = if pot > 0.0 {
                sample(&closest, &chunk_pot, rng.uniform() * pot)
            } else {
                // Every row coincides with a centre: any row is as good as another.
                rng.below(n)
            };
        }
        let panel = Panel::from_rows(x, d, &candidates);
        let kp = panel.kpad();
        let partial: Vec<Vec<f64>> = mins
            .par_chunks_mut(CHUNK * trials)
            .zip(closest.par_chunks(CHUNK))
            .enumerate()
            .map(|(b, (m, cl))| {
                let mut pots = vec![0.0; trials];
                let mut buf = vec![0.0; GROUP * kp];
                for (g, clg) in cl.chunks(GROUP).enumerate() {
                    let start = b * CHUNK + g * GROUP;
                    let rows: Vec<&[f64]> =
                        (start..start + clg.len()).map(|i| &x[i * d..(i + 1) * d]).collect();
                    sq_dists(&rows, &panel, &mut buf);
                    for (r, &c) in clg.iter().enumerate() {
                        let mrow = &mut m[(g * GROUP + r) * trials..(g * GROUP + r + 1) * trials];
                        for t in 0..trials {
                            let v = buf[r * kp + t].min(c);
                            mrow[t] = v;
                            pots[t] += v;
                        }
                    }
                }
                pots
            })
            .collect();
        let mut best = 0;
        let mut best_pot = f64::INFINITY;
        for t in 0..trials {
            let p: f64 = partial.iter().map(|v| v[t]).sum();
            if p < best_pot {
                best_pot = p;
                best = t;
            }
        }
        indices.push(candidates[best]);
        chunk_pot = closest
            .par_chunks_mut(CHUNK)
            .zip(mins.par_chunks(CHUNK * trials))
            .map(|(cl, m)| {
                let mut s = 0.0;
                for (i, v) in cl.iter_mut().enumerate() {
                    *v = m[i * trials + best];
                    s += *v;
                }
                s
            })
            .collect();
    }
    let mut centers = Vec::with_capacity(k * d);
    for &i in &indices {
        centers.extend_from_slice(&x[i * d..(i + 1) * d]);
    }
    (centers, indices)
}

/// Row where the running sum of `weights` first exceeds `r` (`0 ≤ r < Σ weights`), using the
/// per-chunk sums to skip whole chunks.
fn sample(weights: &[f64], chunk_sums: &[f64], r: f64) -> usize {
    let mut acc = 0.0;
    for (b, &s) in chunk_sums.iter().enumerate() {
        if acc + s > r {
            let start = b * CHUNK;
            for (i, &w) in weights[start..(start + CHUNK).min(weights.len())].iter().enumerate() {
                acc += w;
                if acc > r {
                    return start + i;
                }
            }
            // Rounding: fall back to the chunk's last row with a positive weight.
            return (start..(start + CHUNK).min(weights.len()))
                .rev()
                .find(|&i| weights[i] > 0.0)
                .unwrap_or(start);
        }
        acc += s;
    }
    weights.iter().rposition(|&w| w > 0.0).unwrap_or(0)
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
        let w = vec![0.0, 1.0, 0.0, 3.0];
        let sums = vec![4.0];
        assert_eq!(sample(&w, &sums, 0.0), 1);
        assert_eq!(sample(&w, &sums, 0.999), 1);
        assert_eq!(sample(&w, &sums, 1.0), 3);
        assert_eq!(sample(&w, &sums, 3.999), 3);
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
