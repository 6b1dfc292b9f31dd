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

use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// The DTW rows of one growing query against a set of references.
#[derive(Debug, Clone)]
pub struct OnlineDtw {
    references: Vec<f64>,
    dim: usize,
    bounds: Vec<(usize, usize)>,
    /// Row `n − 1` of every reference's table, concatenated like the references' frames.
    rows: Vec<f64>,
    n: usize,
}

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
        let mut values = Vec::new();
        values
            .try_reserve_exact(references.len())
            .map_err(|_| Error::Memory("cannot copy the references".into()))?;
        values.extend_from_slice(references);
        Ok(Self {
            references: values,
            dim,
            bounds,
            rows: try_filled(frames, f64::INFINITY, "the DTW rows")?,
            n: 0,
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

    /// Bytes held (references and rows): fixed at construction.
    pub fn memory_bytes(&self) -> usize {
        (self.references.len() + self.rows.len()) * std::mem::size_of::<f64>()
            + self.bounds.len() * std::mem::size_of::<(usize, usize)>()
    }

    /// Forget the query: the next frame pushed is its first.
    pub fn reset(&mut self) {
        self.rows.fill(f64::INFINITY);
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
        for a in frames.chunks_exact(dim) {
            let first = self.n == 0;
            for &(s, e) in &self.bounds {
                let row = &mut self.rows[s..e];
                let refs = &self.references[s * dim..e * dim];
                advance(row, refs, a, dim, first);
            }
            self.n += 1;
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

/// Row `i` of one reference's table from row `i − 1` (in place); `first`: `i = 0`.
#[inline]
fn advance(row: &mut [f64], reference: &[f64], a: &[f64], dim: usize, first: bool) {
    // `diag` is D(i − 1, j − 1); the padded table's corner (−1, −1) is 0, its border infinite.
    let mut diag = if first { 0.0 } else { f64::INFINITY };
    let mut left = f64::INFINITY;
    for (cell, b) in row.iter_mut().zip(reference.chunks_exact(dim)) {
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt();
        let up = *cell;
        // Same order of the minimum as the offline kernel: D(i−1, j−1), D(i−1, j), D(i, j−1).
        let best = diag.min(up).min(left);
        diag = up;
        left = d + best;
        *cell = left;
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
        let refs: Vec<f64> = lengths
            .iter()
            .flat_map(|&m| random(m, dim, &mut seed))
            .collect();
        let mut offsets = vec![0i64];
        for &m in &lengths[..lengths.len() - 1] {
            offsets.push(offsets.last().unwrap() + m as i64);
        }
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
