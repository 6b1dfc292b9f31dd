//! Mean and covariance (divisor N) of the rows of a matrix, and a mergeable accumulator.
//!
//! The paper (Fod, Matarić, Jenkins) builds the covariance `K` of all resampled segments with
//! divisor N. A corpus may not fit in one array, so [`Moments`] holds the sufficient statistics
//! `(count, mean, scatter)` of a set of rows and can be updated with more rows or merged with
//! another accumulator (Chan, Golub & LeVeque's pairwise update), giving the one-shot result up
//! to rounding.
//!
//! The scatter matrix `Σ (x - mean)(x - mean)ᵀ` of a block of rows is computed on rows
//! centred by a *shift* (the mean of the first rows of the block), forming only the lower half
//! of `YᵀY`: with the packed kernel of [`crate::gram`] at the AVX2+FMA and AVX-512 levels
//! ([`crate::simd`]) where rows have at least 16 values, else with faer's triangular matrix
//! product on small sub-blocks (faer chooses its own instructions at run time). The
//! final correction `- n m mᵀ` (with `m` the mean of the shifted rows) is then tiny compared to
//! the scatter, so data far from the origin (e.g. positions in metres around an offset) keeps
//! its precision, unlike the textbook `XᵀX - n μμᵀ`.
//!
//! Parallelism: the rows are cut into a number of parts that depends only on `n` (never on the
//! thread count), each part's scatter is computed sequentially and the parts are added in order
//! (the pairwise update below). Without the packed kernel, wide rows (d ≥ 128) are instead one
//! part through faer's product parallel over output blocks, whose per-element summation order
//! does not depend on the split. Results are bit-identical for any number of rayon threads
//! (tested).

use faer::linalg::matmul::triangular::{matmul, BlockStructure};
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::simd::{self, Level};
use crate::{buffer, gram};
use crate::{Error, Result};

/// Rows per centred sub-block fed to the matrix product (the block stays in L2 for d ≈ 400).
const SUB_BLOCK_ROWS: usize = 512;
/// Row width from which faer's product itself is parallel (instead of splitting the rows),
/// when the packed kernel is not used.
const WIDE: usize = 128;
/// Minimum rows per parallel part, and the maximum number of parts.
const MIN_PART_ROWS: usize = 2048;
const MAX_PARTS: usize = 16;
/// Row width from which the packed Gram kernel ([`gram`]) is used where the CPU has it.
const GRAM_MIN_DIM: usize = 16;
/// Rows averaged to form the shift.
const SHIFT_ROWS: usize = 64;

/// Sufficient statistics of a set of `count` rows of dimension `dim`: their mean and their
/// scatter matrix `Σ (x - mean)(x - mean)ᵀ` (row-major, `dim × dim`, symmetric).
#[derive(Clone, Debug, PartialEq)]
pub struct Moments {
    dim: usize,
    count: u64,
    mean: Vec<f64>,
    scatter: Vec<f64>,
}

impl Moments {
    /// An empty accumulator for rows of dimension `dim`.
    ///
    /// Errors: a `dim × dim` scatter matrix that cannot be allocated (Memory).
    pub fn new(dim: usize) -> Result<Self> {
        Ok(Self {
            dim,
            count: 0,
            mean: buffer::try_zeroed_f64(dim, "the mean")?,
            scatter: buffer::try_zeroed_f64(scatter_len(dim)?, "the scatter matrix")?,
        })
    }

    /// The statistics of the `n` rows of the row-major `n × dim` matrix `x`.
    ///
    /// Errors: `x.len() != n * dim` (Shape), a non-finite value (NonFinite). `n == 0` gives an
    /// empty accumulator.
    pub fn from_rows(x: &[f64], n: usize, dim: usize) -> Result<Self> {
        // With the packed Gram kernel, non-finite values are noticed while the rows are packed
        // (and located afterwards); otherwise by a pass of their own.
        let level = simd::level()?;
        let packed = (dim >= GRAM_MIN_DIM && gram::available(level)).then_some(level);
        if packed.is_some() {
            check_len(x, n, dim, "X")?;
        } else {
            check_rows(x, n, dim, "X")?;
        }
        if n == 0 {
            return Self::new(dim);
        }
        scatter_len(dim)?;
        // Wide rows without the packed kernel: one part, faer's matrix product parallel over
        // the output (its split never changes the summation order). Otherwise: independent
        // parts in parallel, their number set by `n` alone.
        let (parts, par) = if dim >= WIDE && packed.is_none() {
            (1, Par::rayon(0))
        } else {
            (n.div_ceil(MIN_PART_ROWS).clamp(1, MAX_PARTS), Par::Seq)
        };
        let part_rows = n.div_ceil(parts);
        let partials: Vec<(Moments, bool)> = (0..parts)
            .into_par_iter()
            .map(|p| {
                let start = p * part_rows;
                let end = ((p + 1) * part_rows).min(n);
                block_moments(&x[start * dim..end * dim], end - start, dim, packed, par)
            })
            .collect::<Result<_>>()?;
        if partials.iter().any(|(_, finite)| !finite) {
            // A NaN or infinity (named by the check), or finite values whose products overflow
            // (kept, as the textbook sums would).
            check_rows(x, n, dim, "X")?;
        }
        // The parts hold lower triangles only: merge those, mirror once.
        let mut iter = partials.into_iter().map(|(m, _)| m);
        let mut acc = iter.next().expect("at least one part");
        for part in iter {
            acc.merge_lower(&part);
        }
        symmetrize_from_lower(&mut acc.scatter, dim);
        Ok(acc)
    }

    /// A copy; a failed allocation is an error (Memory), not an abort.
    pub fn try_clone(&self) -> Result<Self> {
        Ok(Self {
            dim: self.dim,
            count: self.count,
            mean: buffer::try_copy(&self.mean, "the mean")?,
            scatter: buffer::try_copy(&self.scatter, "the scatter matrix")?,
        })
    }

    /// Dimension of the rows.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of rows seen.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Mean of the rows seen (zeros when empty).
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Scatter matrix `Σ (x - mean)(x - mean)ᵀ`, row-major `dim × dim` (zeros when empty).
    pub fn scatter(&self) -> &[f64] {
        &self.scatter
    }

    /// Rebuild an accumulator from stored statistics (e.g. unpickling).
    ///
    /// Errors: lengths that do not match `dim`, non-finite values, or a scatter matrix that is
    /// not symmetric.
    pub fn from_parts(dim: usize, count: u64, mean: Vec<f64>, scatter: Vec<f64>) -> Result<Self> {
        if mean.len() != dim || Some(scatter.len()) != dim.checked_mul(dim) {
            return Err(Error::Shape(format!(
                "moments of dimension {dim} need a mean of length {dim} and a {dim}x{dim} \
                 scatter matrix, got lengths {} and {}",
                mean.len(),
                scatter.len()
            )));
        }
        if mean.iter().chain(scatter.iter()).any(|v| !v.is_finite()) {
            return Err(Error::NonFinite("moments contain NaN or infinity".into()));
        }
        for i in 0..dim {
            for j in 0..i {
                if scatter[i * dim + j] != scatter[j * dim + i] {
                    return Err(Error::InvalidArgument(format!(
                        "scatter matrix is not symmetric at ({i}, {j})"
                    )));
                }
            }
        }
        Ok(Self {
            dim,
            count,
            mean,
            scatter,
        })
    }

    /// Add the rows of the row-major `n × dim` matrix `x`.
    pub fn update(&mut self, x: &[f64], n: usize) -> Result<()> {
        let block = Self::from_rows(x, n, self.dim)?;
        self.merge(&block)
    }

    /// Add the statistics of another accumulator (pairwise update of Chan et al.).
    pub fn merge(&mut self, other: &Moments) -> Result<()> {
        if other.dim != self.dim {
            return Err(Error::Shape(format!(
                "cannot merge moments of dimension {} into moments of dimension {}",
                other.dim, self.dim
            )));
        }
        self.merge_lower(other);
        // The update adds wi·δj at (i, j) and wj·δi at (j, i): equal in exact arithmetic but
        // not always in floating point; mirror the lower triangle to stay exactly symmetric.
        symmetrize_from_lower(&mut self.scatter, self.dim);
        Ok(())
    }

    /// [`Moments::merge`] on the lower triangle of the scatter only (same dimension assumed).
    fn merge_lower(&mut self, other: &Moments) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            // Same dimension: copy into the buffers already held (no allocation).
            self.mean.copy_from_slice(&other.mean);
            self.scatter.copy_from_slice(&other.scatter);
            self.count = other.count;
            return;
        }
        let d = self.dim;
        let na = self.count as f64;
        let nb = other.count as f64;
        let n = na + nb;
        let delta: Vec<f64> = (0..d).map(|i| other.mean[i] - self.mean[i]).collect();
        let w = na * nb / n;
        for (i, &di) in delta.iter().enumerate() {
            let wi = w * di;
            let srow = &mut self.scatter[i * d..i * d + i + 1];
            let orow = &other.scatter[i * d..i * d + i + 1];
            for ((s, o), dj) in srow.iter_mut().zip(orow).zip(&delta) {
                *s += o + wi * dj;
            }
        }
        let fb = nb / n;
        for (m, dl) in self.mean.iter_mut().zip(&delta) {
            *m += dl * fb;
        }
        self.count += other.count;
    }

    /// Covariance with divisor N (`scatter / count`), row-major `dim × dim`.
    ///
    /// Errors: no rows seen yet.
    pub fn covariance(&self) -> Result<Vec<f64>> {
        if self.count == 0 {
            return Err(Error::Shape("covariance of zero rows is undefined".into()));
        }
        let mut cov = buffer::try_copy(&self.scatter, "the covariance matrix")?;
        let inv = 1.0 / self.count as f64;
        cov.iter_mut().for_each(|s| *s *= inv);
        Ok(cov)
    }

    /// [`Moments::covariance`] in the scatter matrix's own buffer, with the mean.
    fn into_mean_covariance(mut self) -> Result<(Vec<f64>, Vec<f64>)> {
        if self.count == 0 {
            return Err(Error::Shape("covariance of zero rows is undefined".into()));
        }
        let inv = 1.0 / self.count as f64;
        self.scatter.iter_mut().for_each(|s| *s *= inv);
        Ok((self.mean, self.scatter))
    }
}

/// Length `dim²` of a scatter matrix, checked (overflow, machine memory).
fn scatter_len(dim: usize) -> Result<usize> {
    buffer::elements::<f64>(&[dim, dim], "the scatter matrix")
}

/// Mean `(d,)` and covariance `(d, d)` with divisor N of the rows of the row-major `n × d`
/// matrix `x`.
///
/// Errors: `n == 0` or `d == 0` (Shape), a length mismatch (Shape), NaN/inf (NonFinite).
pub fn covariance(x: &[f64], n: usize, d: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    if n == 0 || d == 0 {
        return Err(Error::Shape(format!(
            "X is empty (shape {n}x{d}); need at least one row and one column"
        )));
    }
    Moments::from_rows(x, n, d)?.into_mean_covariance()
}

/// What the covariance (and [`Moments`]) runs at `level`, as `instruction_sets()` reports it.
pub fn instruction_set(level: Level) -> &'static str {
    match level {
        Level::Avx512 if gram::available(level) => {
            "avx512f (rows of 16 values or more; faer's product below)"
        }
        Level::Avx2Fma if gram::available(level) => {
            "avx2+fma (rows of 16 values or more; faer's product below)"
        }
        _ => "faer's product (faer chooses its instructions itself)",
    }
}

fn check_len(x: &[f64], n: usize, dim: usize, name: &str) -> Result<()> {
    if Some(x.len()) != n.checked_mul(dim) {
        return Err(Error::Shape(format!(
            "{name} has {} values, expected {n} rows x {dim} columns",
            x.len()
        )));
    }
    Ok(())
}

fn check_rows(x: &[f64], n: usize, dim: usize, name: &str) -> Result<()> {
    check_len(x, n, dim, name)?;
    if let Some(pos) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite(format!(
            "{name} contains NaN or infinity (row {}, column {})",
            pos / dim.max(1),
            pos % dim.max(1)
        )));
    }
    Ok(())
}

/// Copy the lower triangle of a row-major `d × d` matrix onto its upper triangle.
fn symmetrize_from_lower(a: &mut [f64], d: usize) {
    mirror::<true>(a, d);
}

/// Copy the lower (`FROM_LOWER`) or upper triangle of a row-major `d × d` matrix onto the
/// other one.
fn mirror<const FROM_LOWER: bool>(a: &mut [f64], d: usize) {
    // In 32 × 32 tiles, so that the strided writes stay in cache.
    const T: usize = 32;
    for i0 in (0..d).step_by(T) {
        for j0 in (0..=i0).step_by(T) {
            for i in i0..(i0 + T).min(d) {
                for j in j0..(j0 + T).min(i) {
                    if FROM_LOWER {
                        a[j * d + i] = a[i * d + j];
                    } else {
                        a[i * d + j] = a[j * d + i];
                    }
                }
            }
        }
    }
}

/// Sequential statistics of one block of rows (`n ≥ 1`), with the packed Gram kernel at
/// level `packed` or, if `None`, faer's triangular product, and whether its sums are finite
/// (always true for faer's path, whose input was checked).
///
/// Errors: the `d × d` matrix cannot be allocated (Memory).
fn block_moments(
    x: &[f64],
    n: usize,
    d: usize,
    packed: Option<Level>,
    par: Par,
) -> Result<(Moments, bool)> {
    // Shift: mean of the first rows, close to the block mean for any reasonable data.
    let ns = n.min(SHIFT_ROWS);
    let mut shift = vec![0.0; d];
    for row in x[..ns * d].chunks_exact(d) {
        for (s, v) in shift.iter_mut().zip(row) {
            *s += v;
        }
    }
    for s in &mut shift {
        *s /= ns as f64;
    }

    // Lower half of Σ yyᵀ (column-major d × d; symmetric, so row-major is the transpose) and
    // Σ y over the shifted rows y = x - shift.
    let mut gram = buffer::try_zeroed_f64(scatter_len(d)?, "the scatter matrix")?;
    let mut colsum = vec![0.0; d];
    let mut finite = true;
    if let Some(level) = packed {
        finite = gram::shifted_gram_lower(level, x, n, d, &shift, &mut gram, &mut colsum)?;
    } else {
        faer_gram_lower(x, n, d, &shift, &mut gram, &mut colsum, par)?;
    }

    // gram is column-major lower: element (i, j), i ≥ j, at j * d + i, which is the row-major
    // upper triangle of the symmetric result. Subtract n m mᵀ with m = colsum / n in place,
    // then mirror onto the lower triangle.
    let nf = n as f64;
    let m: Vec<f64> = colsum.iter().map(|c| c / nf).collect();
    for j in 0..d {
        let row = &mut gram[j * d..(j + 1) * d];
        for i in j..d {
            row[i] -= nf * m[i] * m[j];
        }
    }
    mirror::<false>(&mut gram, d);
    let mean = shift.iter().zip(&m).map(|(s, mi)| s + mi).collect();
    let moments = Moments {
        dim: d,
        count: n as u64,
        mean,
        scatter: gram,
    };
    Ok((moments, finite))
}

/// Lower half of `Σ yyᵀ` (into `gram`, column-major) and `Σ y` (into `colsum`) over the
/// shifted rows `y = x - shift`, by faer's triangular product on sub-blocks of centred rows.
fn faer_gram_lower(
    x: &[f64],
    n: usize,
    d: usize,
    shift: &[f64],
    gram: &mut [f64],
    colsum: &mut [f64],
    par: Par,
) -> Result<()> {
    let mut buf = buffer::try_zeroed_f64(SUB_BLOCK_ROWS.min(n) * d, "a block of centred rows")?;
    for (b, rows) in x.chunks(SUB_BLOCK_ROWS * d).enumerate() {
        let nb = rows.len() / d;
        let y = &mut buf[..rows.len()];
        for (yrow, xrow) in y.chunks_exact_mut(d).zip(rows.chunks_exact(d)) {
            for ((yv, xv), (s, c)) in yrow
                .iter_mut()
                .zip(xrow)
                .zip(shift.iter().zip(colsum.iter_mut()))
            {
                *yv = xv - s;
                *c += *yv;
            }
        }
        let yr = MatRef::from_row_major_slice(&*y, nb, d);
        let g = MatMut::from_column_major_slice_mut(gram, d, d);
        matmul(
            g,
            BlockStructure::TriangularLower,
            if b == 0 { Accum::Replace } else { Accum::Add },
            yr.transpose(),
            BlockStructure::Rectangular,
            yr,
            BlockStructure::Rectangular,
            1.0,
            par,
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic pseudo-random values in [-0.5, 0.5) (SplitMix64).
    fn values(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = s;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    /// Two-pass textbook reference.
    fn naive(x: &[f64], n: usize, d: usize) -> (Vec<f64>, Vec<f64>) {
        let mut mean = vec![0.0; d];
        for r in x.chunks_exact(d) {
            for j in 0..d {
                mean[j] += r[j];
            }
        }
        mean.iter_mut().for_each(|m| *m /= n as f64);
        let mut cov = vec![0.0; d * d];
        for r in x.chunks_exact(d) {
            for i in 0..d {
                for j in 0..d {
                    cov[i * d + j] += (r[i] - mean[i]) * (r[j] - mean[j]);
                }
            }
        }
        cov.iter_mut().for_each(|c| *c /= n as f64);
        (mean, cov)
    }

    fn assert_close(a: &[f64], b: &[f64], tol: f64) {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= tol * scale, "{x} vs {y}");
        }
    }

    #[test]
    fn known_answer_two_points() {
        // Rows (0, 0) and (2, 4): mean (1, 2), covariance [[1, 2], [2, 4]] with divisor 2.
        let (mean, cov) = covariance(&[0.0, 0.0, 2.0, 4.0], 2, 2).unwrap();
        assert_eq!(mean, vec![1.0, 2.0]);
        assert_eq!(cov, vec![1.0, 2.0, 2.0, 4.0]);
    }

    #[test]
    fn single_row_has_zero_covariance() {
        let (mean, cov) = covariance(&[3.0, -1.0, 7.0], 1, 3).unwrap();
        assert_eq!(mean, vec![3.0, -1.0, 7.0]);
        assert!(cov.iter().all(|&c| c == 0.0));
    }

    #[test]
    fn matches_naive_across_part_boundaries() {
        for &(n, d) in &[(1usize, 1usize), (5, 3), (257, 7), (5000, 13), (40_000, 4)] {
            let x = values(n * d, (n * 31 + d) as u64);
            let (m, c) = covariance(&x, n, d).unwrap();
            let (m0, c0) = naive(&x, n, d);
            assert_close(&m, &m0, 1e-12);
            assert_close(&c, &c0, 1e-12);
            for i in 0..d {
                for j in 0..d {
                    assert_eq!(c[i * d + j], c[j * d + i]);
                }
            }
        }
    }

    #[test]
    fn large_offset_keeps_precision() {
        let (n, d) = (3000, 3);
        let mut x = values(n * d, 7);
        let base = x.clone();
        x.iter_mut().for_each(|v| *v += 1.0e6);
        let (m, c) = covariance(&x, n, d).unwrap();
        let (_, c0) = naive(&base, n, d);
        assert!((m[0] - 1.0e6).abs() < 1.0);
        // Offset 1e6 on values of spread ~0.3: the textbook XᵀX formula loses everything here.
        assert_close(&c, &c0, 1e-8);
    }

    #[test]
    fn chunked_updates_and_merges_equal_one_shot() {
        let (n, d) = (3001, 6);
        let x = values(n * d, 3);
        let whole = Moments::from_rows(&x, n, d).unwrap();
        let mut acc = Moments::new(d).unwrap();
        let mut other = Moments::new(d).unwrap();
        acc.update(&x[..1000 * d], 1000).unwrap();
        acc.update(&x[1000 * d..1000 * d], 0).unwrap();
        other.update(&x[1000 * d..2500 * d], 1500).unwrap();
        other.update(&x[2500 * d..], 501).unwrap();
        acc.merge(&other).unwrap();
        assert_eq!(acc.count(), n as u64);
        assert_close(acc.mean(), whole.mean(), 1e-13);
        assert_close(
            &acc.covariance().unwrap(),
            &whole.covariance().unwrap(),
            1e-12,
        );
    }

    #[test]
    fn thread_count_does_not_change_bits() {
        // Narrow rows (parallel parts) and wide rows (parallel product).
        for &(n, d) in &[(20_000usize, 9usize), (3000, 300)] {
            let x = values(n * d, 11);
            let run = |t: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .unwrap();
                pool.install(|| covariance(&x, n, d).unwrap())
            };
            let one = run(1);
            assert_eq!(one, run(2));
            assert_eq!(one, run(3));
        }
    }

    #[test]
    fn packed_kernel_and_faer_agree() {
        for level in simd::levels().into_iter().filter(|&l| gram::available(l)) {
            for &(n, d) in &[(1usize, 16usize), (700, 16), (3000, 41), (1000, 400)] {
                let mut x = values(n * d, (n + d) as u64);
                x.iter_mut().for_each(|v| *v += 3.0);
                let (packed, ok) = block_moments(&x, n, d, Some(level), Par::Seq).unwrap();
                let (plain, _) = block_moments(&x, n, d, None, Par::Seq).unwrap();
                assert!(ok);
                assert_close(packed.mean(), plain.mean(), 1e-14);
                assert_close(packed.scatter(), plain.scatter(), 1e-13);
            }
        }
    }

    #[test]
    fn the_tiles_of_every_level_give_the_same_bits() {
        let levels: Vec<Level> = simd::levels()
            .into_iter()
            .filter(|&l| gram::available(l))
            .collect();
        let (n, d) = (3000, 41);
        let x = values(n * d, 8);
        let mut first: Option<Moments> = None;
        for &level in &levels {
            let (m, ok) = block_moments(&x, n, d, Some(level), Par::Seq).unwrap();
            assert!(ok);
            match &first {
                None => first = Some(m),
                Some(want) => assert_eq!(want, &m, "{level:?}"),
            }
        }
    }

    #[test]
    fn non_finite_values_are_located_on_every_path() {
        for d in [3usize, 16, 40] {
            let n = 5000;
            let mut x = values(n * d, 5);
            x[4321 * d + 2] = f64::INFINITY;
            let err = covariance(&x, n, d).unwrap_err();
            assert!(matches!(err, Error::NonFinite(_)), "{err}");
            assert!(err.to_string().contains("row 4321, column 2"), "{err}");
        }
    }

    #[test]
    fn impossible_sizes_are_memory_errors() {
        // A d × d scatter matrix beyond memory or beyond usize: refused before any work.
        for dim in [10_000_000usize, 1 << 30, 1 << 32, usize::MAX] {
            assert!(matches!(Moments::new(dim), Err(Error::Memory(_))), "{dim}");
        }
        let d = 3_000_000;
        let x = vec![0.0; d];
        assert!(matches!(covariance(&x, 1, d), Err(Error::Memory(_))));
        assert!(matches!(
            Moments::from_rows(&x, 1, d),
            Err(Error::Memory(_))
        ));
        // Stored moments whose dimension squared overflows.
        assert!(matches!(
            Moments::from_parts(1 << 32, 1, vec![], vec![]),
            Err(Error::Shape(_))
        ));
        // A row count times dimension that overflows is a shape mismatch, not a panic.
        assert!(matches!(
            covariance(&[1.0], 1 << 33, 1 << 33),
            Err(Error::Shape(_))
        ));
    }

    #[test]
    fn errors() {
        assert!(matches!(covariance(&[], 0, 3), Err(Error::Shape(_))));
        assert!(matches!(
            covariance(&[1.0, 2.0, 3.0], 2, 2),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            covariance(&[1.0, f64::NAN], 1, 2),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            Moments::new(2).unwrap().covariance(),
            Err(Error::Shape(_))
        ));
        let mut a = Moments::new(2).unwrap();
        assert!(matches!(
            a.merge(&Moments::new(3).unwrap()),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            Moments::from_parts(2, 1, vec![0.0; 2], vec![1.0, 2.0, 3.0, 4.0]),
            Err(Error::InvalidArgument(_))
        ));
    }
}
