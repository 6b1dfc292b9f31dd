//! Open-end dynamic time warping of a growing query against fixed references, row by row.
//!
//! The DTW of [`crate::dtw`] fills a table `D(i, j)` (query frame `i`, reference frame `j`)
//! one query row at a time, and row `i` needs only row `i − 1`. [`OnlineDtw`] keeps that one
//! row per reference (`m` values for a reference of `m` frames) and advances it with every
//! query frame pushed, so a stream costs `O(Σ m)` memory whatever its length and `O(Σ m · dim)`
//! work per frame. The recursion, the local cost (Euclidean distance between frames) and the
//! summation order are those of [`crate::dtw`], so after the whole query has been pushed
//! [`OnlineDtw::closed_end_costs`] equals [`crate::dtw::dtw_cross`] with `normalize` (no band)
//! bit for bit.
//!
//! * **Closed end**: `D(n − 1, m − 1) / (n + m)`, the query so far against the whole reference.
//! * **Open end**: `min_j D(n − 1, j) / (n + j + 1)`, the query so far against the best-matching
//!   *prefix* of the reference (the movement in progress against how each reference began);
//!   the `j` reached is [`OnlineDtw::open_end`]'s position.
//! * **Running class**: [`OnlineDtw::running`] gives the reference of the smallest open-end
//!   cost and a confidence `1 − d₁ / d₂` against the best reference of another label, in one
//!   pass over the rows (no per-reference array handed back).
//!
//! **Layout.** Each reference's frames are stored channel-major (value `c` of frame `j` of a
//! reference of `m` frames at `c·m + j` within its block), so the local distances of a query
//! frame to every frame of a reference are computed across `j` in SIMD lanes, each lane
//! summing its channels in the offline kernel's order (`Σ_c (a_c − b_c)²`, channel 0 first,
//! then the square root): the same bits as [`crate::dtw`]. The recursion then runs along the
//! row, for four references at a time in lockstep (references grouped by length at
//! construction), so that four independent chains of `D(i, j − 1) → D(i, j)` overlap in the
//! processor. The open-end costs of the last frame of a push are taken afterwards, over each
//! row in SIMD lanes (the divisions `D(n − 1, j) / (n + j + 1)` were the recursion's slowest
//! step when taken along it, one frame per push). Vector widths are chosen by
//! [`crate::simd`]; every level gives the same bits (no fused multiply-add; the minima are
//! exact selections, values being never NaN).

use crate::ragged::trial_bounds;
use crate::simd::Level;
use crate::{Error, Result};

/// The DTW rows of one growing query against a set of references.
#[derive(Debug, Clone)]
pub struct OnlineDtw {
    /// The references, channel-major within each reference's block (module docstring).
    references: Vec<f64>,
    dim: usize,
    bounds: Vec<(usize, usize)>,
    /// Row `n − 1` of every reference's table, concatenated like the references' frames.
    rows: Vec<f64>,
    /// Local distances of the current query frame to every reference frame (scratch).
    local: Vec<f64>,
    /// References by groups of four in the recursion's lockstep, shortest first.
    groups: Vec<Vec<usize>>,
    /// Open-end cost of each reference after `open_at` query frames.
    open: Vec<f64>,
    open_at: usize,
    n: usize,
    distances: Distances,
    open_min: OpenMin,
}

/// The local distances of one query frame to one reference's frames (module docstring).
type Distances = fn(&[f64], &[f64], &mut [f64]);

/// `min_j row[j] / (n + j + 1)`: the open-end cost of one reference's row after `n` query
/// frames (module docstring).
type OpenMin = fn(&[f64], usize) -> f64;

/// References in one lockstep group of the recursion.
const LOCKSTEP: usize = 4;

fn try_filled(len: usize, value: f64, what: &str) -> Result<Vec<f64>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| Error::Memory(format!("cannot allocate {len} values for {what}")))?;
    v.resize(len, value);
    Ok(v)
}

impl OnlineDtw {
    /// References: row-major `(frames, dim)` values and the first frame of each reference.
    pub fn new(references: &[f64], offsets: &[i64], dim: usize) -> Result<Self> {
        if dim == 0 {
            return Err(Error::Shape(
                "references: frames need at least one channel (dim = 0)".into(),
            ));
        }
        if !references.len().is_multiple_of(dim) {
            return Err(Error::Shape(format!(
                "references: {} values do not split into frames of {dim} channels",
                references.len()
            )));
        }
        if references.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite(
                "references contain NaN or infinity".into(),
            ));
        }
        let frames = references.len() / dim;
        let bounds = trial_bounds(offsets, frames).map_err(|e| match e {
            Error::Shape(m) | Error::InvalidArgument(m) => {
                Error::Shape(format!("reference offsets: {m}"))
            }
            other => other,
        })?;
        let level = crate::simd::level()?;
        let mut values = try_filled(references.len(), 0.0, "the references")?;
        for &(s, e) in &bounds {
            let m = e - s;
            let block = &mut values[s * dim..e * dim];
            for (j, frame) in references[s * dim..e * dim].chunks_exact(dim).enumerate() {
                for (c, &v) in frame.iter().enumerate() {
                    block[c * m + j] = v;
                }
            }
        }
        let mut order: Vec<usize> = (0..bounds.len()).collect();
        order.sort_by_key(|&r| (bounds[r].1 - bounds[r].0, r));
        let groups = order.chunks(LOCKSTEP).map(|g| g.to_vec()).collect();
        Ok(Self {
            references: values,
            dim,
            rows: try_filled(frames, f64::INFINITY, "the DTW rows")?,
            local: try_filled(frames, 0.0, "the local distances")?,
            groups,
            open: try_filled(bounds.len(), f64::INFINITY, "the open-end costs")?,
            open_at: 0,
            bounds,
            n: 0,
            distances: pick(level),
            open_min: pick_open_min(level),
        })
    }

    /// Number of references.
    pub fn n_references(&self) -> usize {
        self.bounds.len()
    }

    /// Channels per frame.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Query frames pushed since the start or the last [`reset`](Self::reset).
    pub fn n_frames(&self) -> usize {
        self.n
    }

    /// Bytes held (references, rows, scratch, groups): fixed at construction.
    pub fn memory_bytes(&self) -> usize {
        let values = self.references.len() + self.rows.len() + self.local.len() + self.open.len();
        values * std::mem::size_of::<f64>()
            + self.bounds.len()
                * (std::mem::size_of::<(usize, usize)>() + std::mem::size_of::<usize>())
            + self.groups.len() * std::mem::size_of::<Vec<usize>>()
    }

    /// Forget the query: the next frame pushed is its first.
    pub fn reset(&mut self) {
        self.rows.fill(f64::INFINITY);
        self.open.fill(f64::INFINITY);
        self.open_at = 0;
        self.n = 0;
    }

    /// Advance every reference's row by the query frames `frames` (row-major `(k, dim)`,
    /// `k ≥ 0`). Refused without any change when a value is not finite.
    pub fn push(&mut self, frames: &[f64]) -> Result<()> {
        let dim = self.dim;
        if !frames.len().is_multiple_of(dim) {
            return Err(Error::Shape(format!(
                "{} values do not split into frames of {dim} channels",
                frames.len()
            )));
        }
        if frames.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite(
                "query frames contain NaN or infinity".into(),
            ));
        }
        let k = frames.len() / dim;
        for a in frames.chunks_exact(dim) {
            let first = self.n == 0;
            for &(s, e) in &self.bounds {
                let refs = &self.references[s * dim..e * dim];
                (self.distances)(refs, a, &mut self.local[s..e]);
            }
            recurrences(
                &mut self.rows,
                &self.local,
                &self.bounds,
                &self.groups,
                first,
            );
            self.n += 1;
        }
        if k > 0 {
            // The open-end costs of the push's last frame, in SIMD lanes over each row.
            for (o, &(s, e)) in self.open.iter_mut().zip(&self.bounds) {
                *o = (self.open_min)(&self.rows[s..e], self.n);
            }
            self.open_at = self.n;
        }
        Ok(())
    }

    /// `D(n − 1, m − 1) / (n + m)` per reference into `out` (infinite before any frame).
    pub fn closed_end_costs(&self, out: &mut [f64]) -> Result<()> {
        self.check_out(out.len())?;
        for (o, &(s, e)) in out.iter_mut().zip(&self.bounds) {
            *o = self.rows[e - 1] / (self.n + (e - s)) as f64;
        }
        Ok(())
    }

    /// `min_j D(n − 1, j) / (n + j + 1)` per reference into `costs`, and the `j` reaching it
    /// into `positions` (the first on ties; infinite costs and position 0 before any frame).
    pub fn open_end(&self, costs: &mut [f64], positions: &mut [usize]) -> Result<()> {
        self.check_out(costs.len())?;
        self.check_out(positions.len())?;
        for ((c, p), &(s, e)) in costs.iter_mut().zip(positions.iter_mut()).zip(&self.bounds) {
            let mut best = f64::INFINITY;
            let mut at = 0;
            for (j, &d) in self.rows[s..e].iter().enumerate() {
                let v = d / (self.n + j + 1) as f64;
                if v < best {
                    best = v;
                    at = j;
                }
            }
            *c = best;
            *p = at;
        }
        Ok(())
    }

    /// The running class: `(best, confidence, cost)` with `best` the first reference of the
    /// smallest open-end cost `d₁ = cost` (as [`open_end`](Self::open_end)), and the
    /// confidence `max(0, 1 − d₁ / d₂)`, `d₂` the smallest open-end cost of a reference whose
    /// `codes` entry (its label) differs from `best`'s: 1 when every reference has the same
    /// label, 0 when `d₁` is infinite (before any frame) or `d₂` is not positive. `costs`
    /// (one per reference) receives every open-end cost.
    pub fn running(&self, codes: &[i64], costs: &mut [f64]) -> Result<(usize, f64, f64)> {
        self.check_out(codes.len())?;
        self.check_out(costs.len())?;
        let n = self.n;
        let mut best = (0usize, f64::INFINITY);
        for (r, (c, &(s, e))) in costs.iter_mut().zip(&self.bounds).enumerate() {
            let cost = if self.open_at == n {
                self.open[r]
            } else {
                (self.open_min)(&self.rows[s..e], n)
            };
            *c = cost;
            // The first of the smallest (numpy's argmin).
            if r == 0 || cost < best.1 {
                best = (r, cost);
            }
        }
        let (best, d1) = best;
        let label = codes[best];
        let d2 = codes
            .iter()
            .zip(costs.iter())
            .filter(|(&code, _)| code != label)
            .map(|(_, &c)| c)
            .reduce(f64::min);
        let confidence = match d2 {
            None => 1.0,
            Some(d2) if !d1.is_finite() || d2.is_nan() || d2 <= 0.0 => 0.0,
            Some(d2) => (1.0 - d1 / d2).max(0.0),
        };
        Ok((best, confidence, d1))
    }

    fn check_out(&self, len: usize) -> Result<()> {
        if len != self.bounds.len() {
            return Err(Error::Shape(format!(
                "output of {len} values for {} references",
                self.bounds.len()
            )));
        }
        Ok(())
    }
}

/// The state of one reference's recursion along its row.
#[derive(Clone, Copy)]
struct Chain {
    /// D(i − 1, j − 1).
    diag: f64,
    /// D(i, j − 1).
    left: f64,
}

impl Chain {
    fn new(first: bool) -> Self {
        // The padded table's corner (−1, −1) is 0, its border infinite.
        let diag = if first { 0.0 } else { f64::INFINITY };
        Self {
            diag,
            left: f64::INFINITY,
        }
    }

    /// `D(i, j) = d + min(D(i−1, j−1), D(i−1, j), D(i, j−1))` in place of `D(i − 1, j)`
    /// (the offline kernel's order of the minimum; `x < y` selections equal `f64::min` since
    /// no value is NaN and none is −0).
    #[inline(always)]
    fn step(&mut self, cell: &mut f64, d: f64) {
        let up = *cell;
        let m = if up < self.diag { up } else { self.diag };
        let best = if self.left < m { self.left } else { m };
        self.diag = up;
        self.left = d + best;
        *cell = self.left;
    }
}

/// Row `n − 1` of every reference's table from row `n − 2` and the local distances, the
/// references of a group in lockstep up to the shortest's length (module docstring).
fn recurrences(
    rows: &mut [f64],
    local: &[f64],
    bounds: &[(usize, usize)],
    groups: &[Vec<usize>],
    first: bool,
) {
    for group in groups {
        let mut chains = [Chain::new(first); LOCKSTEP];
        let mut done = 0;
        if group.len() == LOCKSTEP {
            let s: [usize; LOCKSTEP] = std::array::from_fn(|l| bounds[group[l]].0);
            // Grouped shortest first: the first is the shortest.
            let short = bounds[group[0]].1 - bounds[group[0]].0;
            for j in 0..short {
                for (chain, &start) in chains.iter_mut().zip(&s) {
                    let at = start + j;
                    chain.step(&mut rows[at], local[at]);
                }
            }
            done = short;
        }
        for (chain, &r) in chains.iter_mut().zip(group) {
            let (s, e) = bounds[r];
            for j in done..e - s {
                chain.step(&mut rows[s + j], local[s + j]);
            }
        }
    }
}

/// Lanes of the open-end kernels (`open_min_*`).
const OPEN_LANES: usize = 8;

macro_rules! open_min_kernel {
    ($name:ident, $($feature:literal)?) => {
        /// `min_j row[j] / (n + j + 1)` (infinite for an empty row), the divisions in
        /// `OPEN_LANES` lanes: each quotient is the correctly rounded one of the scalar
        /// loop, and a minimum of values that are never NaN is exact in any order, so every
        /// level gives the scalar loop's bits (the denominators, integers below 2⁵³, are
        /// exact in f64).
        $(#[target_feature(enable = $feature)])?
        fn $name(row: &[f64], n: usize) -> f64 {
            let mut best = [f64::INFINITY; OPEN_LANES];
            let mut denom = [0.0f64; OPEN_LANES];
            for (l, d) in denom.iter_mut().enumerate() {
                *d = (n + 1 + l) as f64;
            }
            let mut blocks = row.chunks_exact(OPEN_LANES);
            for block in &mut blocks {
                for ((b, d), &x) in best.iter_mut().zip(denom.iter_mut()).zip(block) {
                    let v = x / *d;
                    *b = if v < *b { v } else { *b };
                    *d += OPEN_LANES as f64;
                }
            }
            for ((b, d), &x) in best.iter_mut().zip(&denom).zip(blocks.remainder()) {
                let v = x / *d;
                *b = if v < *b { v } else { *b };
            }
            best.iter().fold(f64::INFINITY, |m, &v| if v < m { v } else { m })
        }
    };
}

open_min_kernel!(open_min_portable,);
#[cfg(target_arch = "x86_64")]
open_min_kernel!(open_min_avx2, "avx2,fma");
#[cfg(target_arch = "x86_64")]
open_min_kernel!(open_min_avx512, "avx512f,avx512vl,avx2,fma");

/// The open-end kernel at `level` (one this CPU runs).
fn pick_open_min(level: Level) -> OpenMin {
    assert!(crate::simd::cpu_runs(level), "{level:?} not available");
    match level {
        // SAFETY (both): the CPU has the features the functions were compiled for.
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => |r, n| unsafe { open_min_avx512(r, n) },
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => |r, n| unsafe { open_min_avx2(r, n) },
        _ => open_min_portable,
    }
}

macro_rules! distance_kernel {
    ($name:ident, $($feature:literal)?) => {
        /// The local distances `local` (`m` values) of the query frame `a` to a reference's
        /// `m` frames (channel-major `reference`), across `j`, each summed over the channels
        /// in order, then the square root.
        $(#[target_feature(enable = $feature)])?
        fn $name(reference: &[f64], a: &[f64], local: &mut [f64]) {
            let m = local.len();
            let mut columns = reference.chunks_exact(m).zip(a);
            if let Some((column, &x)) = columns.next() {
                // 0 + t² = t² exactly (t² ≥ +0): the offline sum's first term.
                for (d, &y) in local.iter_mut().zip(column) {
                    let t = x - y;
                    *d = t * t;
                }
            }
            for (column, &x) in columns {
                for (d, &y) in local.iter_mut().zip(column) {
                    let t = x - y;
                    *d += t * t;
                }
            }
            for d in local.iter_mut() {
                *d = d.sqrt();
            }
        }
    };
}

distance_kernel!(distances_portable,);
#[cfg(target_arch = "x86_64")]
distance_kernel!(distances_avx2, "avx2,fma");
#[cfg(target_arch = "x86_64")]
distance_kernel!(distances_avx512, "avx512f,avx512vl,avx2,fma");

/// The distance kernel at `level` (one this CPU runs). `x * y + z` is never contracted to a
/// fused multiply-add by Rust, so every level gives the same bits.
fn pick(level: Level) -> Distances {
    assert!(crate::simd::cpu_runs(level), "{level:?} not available");
    match level {
        // SAFETY (both): the CPU has the features the functions were compiled for.
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => |b, a, l| unsafe { distances_avx512(b, a, l) },
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => |b, a, l| unsafe { distances_avx2(b, a, l) },
        _ => distances_portable,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dtw::{dtw_cross, DtwOptions};

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    }

    fn random(frames: usize, dim: usize, seed: &mut u64) -> Vec<f64> {
        (0..frames * dim).map(|_| lcg(seed)).collect()
    }

    /// Random references of `lengths` frames one after the other, and their offsets.
    fn references(lengths: &[usize], dim: usize, seed: &mut u64) -> (Vec<f64>, Vec<i64>) {
        let refs = lengths.iter().flat_map(|&m| random(m, dim, seed)).collect();
        let mut offsets = vec![0i64];
        for &m in &lengths[..lengths.len() - 1] {
            offsets.push(offsets.last().unwrap() + m as i64);
        }
        (refs, offsets)
    }

    /// Open-end cost from a full table, for comparison.
    #[allow(clippy::needless_range_loop)]
    fn open_end_by_table(a: &[f64], b: &[f64], dim: usize) -> (f64, usize) {
        let (n, m) = (a.len() / dim, b.len() / dim);
        let mut t = vec![vec![f64::INFINITY; m + 1]; n + 1];
        t[0][0] = 0.0;
        for i in 1..=n {
            for j in 1..=m {
                let d: f64 = (0..dim)
                    .map(|k| (a[(i - 1) * dim + k] - b[(j - 1) * dim + k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                t[i][j] = d + t[i - 1][j - 1].min(t[i - 1][j]).min(t[i][j - 1]);
            }
        }
        let mut best = (f64::INFINITY, 0);
        for j in 1..=m {
            let v = t[n][j] / (n + j) as f64;
            if v < best.0 {
                best = (v, j - 1);
            }
        }
        best
    }

    #[test]
    fn closed_end_equals_the_offline_kernel_whatever_the_chunks() {
        let mut seed = 7;
        let dim = 3;
        let lengths = [5usize, 1, 12, 30];
        let (refs, offsets) = references(&lengths, dim, &mut seed);
        let query = random(23, dim, &mut seed);
        let offline =
            dtw_cross(&query, &[0], &refs, &offsets, dim, &DtwOptions::default()).unwrap();
        for chunk in [1usize, 4, 23] {
            let mut online = OnlineDtw::new(&refs, &offsets, dim).unwrap();
            for part in query.chunks(chunk * dim) {
                online.push(part).unwrap();
            }
            let mut out = vec![0.0; lengths.len()];
            online.closed_end_costs(&mut out).unwrap();
            assert_eq!(out, offline, "chunks of {chunk} frames");
        }
    }

    #[test]
    fn open_end_matches_the_full_table_at_every_frame() {
        let mut seed = 11;
        let dim = 2;
        let b = random(17, dim, &mut seed);
        let a = random(25, dim, &mut seed);
        let mut online = OnlineDtw::new(&b, &[0], dim).unwrap();
        for i in 1..=25 {
            online.push(&a[(i - 1) * dim..i * dim]).unwrap();
            let (mut c, mut p) = ([0.0], [0usize]);
            online.open_end(&mut c, &mut p).unwrap();
            let (want, at) = open_end_by_table(&a[..i * dim], &b, dim);
            approx::assert_relative_eq!(c[0], want, max_relative = 1e-12);
            assert_eq!(p[0], at);
        }
    }

    #[test]
    fn a_prefix_of_the_reference_matches_at_zero_cost_near_its_end() {
        let mut seed = 3;
        let dim = 4;
        let b = random(40, dim, &mut seed);
        let mut online = OnlineDtw::new(&b, &[0], dim).unwrap();
        online.push(&b[..15 * dim]).unwrap();
        let (mut c, mut p) = ([0.0], [0usize]);
        online.open_end(&mut c, &mut p).unwrap();
        assert_eq!(c[0], 0.0);
        assert_eq!(p[0], 14);
        let mut closed = [0.0];
        online.closed_end_costs(&mut closed).unwrap();
        assert!(closed[0] > 0.0);
    }

    #[test]
    fn reset_forgets_the_query_and_memory_stays_fixed() {
        let mut seed = 5;
        let dim = 2;
        let b = random(10, dim, &mut seed);
        let a = random(8, dim, &mut seed);
        let mut online = OnlineDtw::new(&b, &[0], dim).unwrap();
        let bytes = online.memory_bytes();
        for _ in 0..1000 {
            online.push(&random(3, dim, &mut seed)).unwrap();
        }
        assert_eq!(online.memory_bytes(), bytes);
        online.reset();
        assert_eq!(online.n_frames(), 0);
        online.push(&a).unwrap();
        let mut fresh = OnlineDtw::new(&b, &[0], dim).unwrap();
        fresh.push(&a).unwrap();
        let (mut x, mut y) = ([0.0], [0.0]);
        online.closed_end_costs(&mut x).unwrap();
        fresh.closed_end_costs(&mut y).unwrap();
        assert_eq!(x, y);
    }

    #[test]
    fn every_simd_level_gives_the_offline_kernel_bits() {
        let mut seed = 19;
        for dim in [1usize, 2, 5, 12, 13] {
            let lengths = [1usize, 3, 7, 64, 33, 2, 50, 5, 17, 1, 90];
            let (refs, offsets) = references(&lengths, dim, &mut seed);
            let query = random(21, dim, &mut seed);
            let offline =
                dtw_cross(&query, &[0], &refs, &offsets, dim, &DtwOptions::default()).unwrap();
            for level in crate::simd::levels() {
                let mut online = OnlineDtw::new(&refs, &offsets, dim).unwrap();
                online.distances = pick(level);
                online.push(&query).unwrap();
                let mut out = vec![0.0; lengths.len()];
                online.closed_end_costs(&mut out).unwrap();
                assert_eq!(out, offline, "dim {dim}, {level:?}");
            }
        }
    }

    /// The running class from the open-end costs, written out separately.
    fn running_by_costs(costs: &[f64], codes: &[i64]) -> (usize, f64, f64) {
        let mut best = 0;
        for (r, &c) in costs.iter().enumerate() {
            if c < costs[best] {
                best = r;
            }
        }
        let d1 = costs[best];
        let others: Vec<f64> = (0..costs.len())
            .filter(|&r| codes[r] != codes[best])
            .map(|r| costs[r])
            .collect();
        if others.is_empty() {
            return (best, 1.0, d1);
        }
        let d2 = others.iter().cloned().fold(f64::INFINITY, f64::min);
        if !d1.is_finite() || d2 <= 0.0 {
            return (best, 0.0, d1);
        }
        (best, f64::max(0.0, 1.0 - d1 / d2), d1)
    }

    #[test]
    fn running_is_the_best_open_end_match_and_its_margin() {
        let mut seed = 23;
        let dim = 3;
        let lengths = [6usize, 9, 4, 11, 8];
        let (refs, offsets) = references(&lengths, dim, &mut seed);
        let mut online = OnlineDtw::new(&refs, &offsets, dim).unwrap();
        let mut costs = vec![0.0; 5];
        // Before any frame: every cost infinite, the first reference, confidence 0.
        let got = online.running(&[0, 1, 0, 2, 1], &mut costs).unwrap();
        assert_eq!(got, (0, 0.0, f64::INFINITY));
        for i in 0..12 {
            online.push(&random(1, dim, &mut seed)).unwrap();
            let (mut want, mut at) = (vec![0.0; 5], vec![0usize; 5]);
            online.open_end(&mut want, &mut at).unwrap();
            for codes in [[0i64, 1, 0, 2, 1], [4, 4, 4, 4, 4], [0, 1, 2, 3, 4]] {
                let got = online.running(&codes, &mut costs).unwrap();
                assert_eq!(costs, want, "frame {i}");
                assert_eq!(got, running_by_costs(&want, &codes), "frame {i} {codes:?}");
            }
        }
        // A chunk of frames: the costs of its last frame.
        online.push(&random(3, dim, &mut seed)).unwrap();
        let (mut want, mut at) = (vec![0.0; 5], vec![0usize; 5]);
        online.open_end(&mut want, &mut at).unwrap();
        let got = online.running(&[0, 1, 0, 2, 1], &mut costs).unwrap();
        assert_eq!(costs, want);
        assert_eq!(got, running_by_costs(&want, &[0, 1, 0, 2, 1]));
        // One label: confidence 1.
        assert_eq!(online.running(&[7; 5], &mut costs).unwrap().1, 1.0);
        // After a reset: as before any frame.
        online.reset();
        assert_eq!(
            online.running(&[0, 1, 0, 2, 1], &mut costs).unwrap(),
            (0, 0.0, f64::INFINITY)
        );
        assert!(online.running(&[0; 4], &mut costs).is_err());
    }

    #[test]
    fn the_open_end_lanes_give_the_scalar_loops_bits() {
        let mut seed = 29;
        for len in [0usize, 1, 7, 8, 9, 31, 64, 101] {
            let mut row: Vec<f64> = (0..len).map(|_| 10.0 * (lcg(&mut seed) + 0.5)).collect();
            if len > 3 {
                row[2] = f64::INFINITY;
            }
            for n in [1usize, 2, 17, 1000] {
                let mut want = f64::INFINITY;
                for (j, &d) in row.iter().enumerate() {
                    let v = d / (n + j + 1) as f64;
                    if v < want {
                        want = v;
                    }
                }
                for level in crate::simd::levels() {
                    let got = pick_open_min(level)(&row, n);
                    assert_eq!(got.to_bits(), want.to_bits(), "len {len}, n {n}, {level:?}");
                }
            }
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        assert!(OnlineDtw::new(&[1.0, 2.0, 3.0], &[0], 2).is_err());
        assert!(OnlineDtw::new(&[1.0, 2.0], &[0], 0).is_err());
        assert!(OnlineDtw::new(&[1.0, f64::NAN], &[0], 2).is_err());
        assert!(OnlineDtw::new(&[1.0, 2.0], &[1], 2).is_err());
        let mut o = OnlineDtw::new(&[1.0, 2.0, 3.0, 4.0], &[0], 2).unwrap();
        assert!(o.push(&[1.0]).is_err());
        assert!(o.push(&[1.0, f64::INFINITY]).is_err());
        assert_eq!(o.n_frames(), 0);
        let mut out = [0.0; 2];
        assert!(o.closed_end_costs(&mut out).is_err());
    }
}
