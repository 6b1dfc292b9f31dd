//! Symmetric eigendecomposition (faer), eigenvalues in descending order.
//!
//! Sign convention: every returned eigenvector has its component of largest absolute value
//! positive (the first such component when several tie). Eigenvectors of a repeated eigenvalue
//! (equal to rounding) are returned in a canonical basis of its eigenspace ([`canonical_basis`]),
//! so they do not depend on the solver's rounding inside the eigenspace. The solver's parallel
//! split is fixed: results are bit-identical for any number of threads.
//!
//! Like `numpy.linalg.eigh` (`UPLO='L'`) only the lower triangle `a[i, j], i ≥ j` is read once
//! the matrix has been checked to be symmetric. The matrix is scaled by a power of two and
//! entries below 1.5e-154 of the largest are flushed to zero before the solver runs (see
//! [`eigh`]).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{ColMut, MatMut, MatRef, Par};

use crate::buffer;
use crate::{Error, Result};

/// Relative asymmetry `|a_ij - a_ji| / max|a|` above which a matrix is refused.
pub const SYMMETRY_TOL: f64 = 1e-10;

/// Leading eigenpairs of a symmetric matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Eigh {
    /// Number of rows (and columns) of the input.
    pub dim: usize,
    /// Eigenvalues, descending, length `k`.
    pub values: Vec<f64>,
    /// Eigenvectors as the columns of a row-major `dim × k` matrix.
    pub vectors: Vec<f64>,
}

/// Parallel split of the solver for `d ≥ 128`. Fixed, never the pool size: faer's parallel
/// tridiagonalisation adds per-split partial sums, so its rounding depends on the number of
/// splits, and a fixed number makes the result bit-identical for any number of threads.
const PAR_SPLITS: usize = 8;

/// Eigenvalues closer than this many `d · ε · max|λ|` are treated as one repeated eigenvalue
/// (their eigenvectors are not determined individually at that precision).
const CLUSTER_ULPS: f64 = 16.0;

/// Eigenvalues (descending) and eigenvectors (columns) of the symmetric row-major `d × d`
/// matrix `a`; only the leading `k` pairs when `k` is given (`1 ≤ k ≤ d`).
///
/// Eigenvectors of a repeated eigenvalue (a cluster of eigenvalues within
/// `16 · d · ε · max|λ|` of each other) are returned in a canonical basis of their eigenspace,
/// which depends only on the eigenspace: see [`canonical_basis`].
///
/// Errors: wrong length or `d == 0` (Shape), NaN/inf (NonFinite), asymmetry beyond
/// [`SYMMETRY_TOL`] or `k` out of range (InvalidArgument), a matrix too large for the
/// solver's workspace (Memory), solver failure (Numerical).
pub fn eigh(a: &[f64], d: usize, k: Option<usize>) -> Result<Eigh> {
    check_symmetric(a, d)?;
    let k = match k {
        None => d,
        Some(k) if (1..=d).contains(&k) => k,
        Some(k) => {
            return Err(Error::InvalidArgument(format!(
                "k must be between 1 and the matrix size {d}, got {k}"
            )))
        }
    };
    let par = if d >= 128 {
        Par::rayon(PAR_SPLITS)
    } else {
        Par::Seq
    };
    let params = Default::default();
    let scratch = evd::self_adjoint_evd_scratch::<f64>(d, ComputeEigenvectors::Yes, par, params);
    // Workspace: the scaled copy and the eigenvectors (d × d each), the solver's scratch, the
    // output (d × k); refused up front if it cannot fit in memory.
    let dd = buffer::elements::<f64>(&[d, d], "the eigenvector matrix")?;
    let total = dd
        .checked_mul(16)
        .and_then(|b| b.checked_add(scratch.size_bytes()))
        .and_then(|b| b.checked_add(d.checked_mul(k)?.checked_mul(8)?));
    buffer::check_total_bytes(
        total,
        &format!("the eigendecomposition of a {d}x{d} matrix"),
    )?;
    // Scale by a power of two (exact) so the largest entry is about 1, and flush entries
    // below √(f64::MIN_POSITIVE) ≈ 1.5e-154 of it to zero: their squares underflow inside the
    // solver (which then fails to converge), and dropping them moves the eigenvalues by at
    // most d·1.5e-154·max|a|, far below rounding.
    let amax = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // (The exponent is clamped so that the factor itself stays finite for subnormal input.)
    let scale = if amax > 0.0 {
        (-amax.log2().round()).clamp(-1020.0, 1020.0).exp2()
    } else {
        1.0
    };
    let tiny = f64::MIN_POSITIVE.sqrt();
    let mut scaled = buffer::try_with_capacity(dd, "a scaled copy of K")?;
    scaled.extend(a.iter().map(|&v| {
        let w = v * scale;
        if w.abs() < tiny {
            0.0
        } else {
            w
        }
    }));
    let mat = MatRef::from_row_major_slice(&scaled, d, d);
    let mut u_buf = buffer::try_zeroed_f64(dd, "the eigenvector matrix")?;
    let mut s_buf = vec![0.0; d];
    let mut mem = MemBuffer::try_new(scratch).map_err(|_| {
        Error::Memory(format!(
            "cannot allocate the eigensolver's workspace ({} bytes)",
            scratch.size_bytes()
        ))
    })?;
    let u = MatMut::from_column_major_slice_mut(&mut u_buf, d, d);
    let s = ColMut::from_slice_mut(&mut s_buf).as_diagonal_mut();
    evd::self_adjoint_evd(mat, s, Some(u), par, MemStack::new(&mut mem), params)
        .map_err(|e| Error::Numerical(format!("symmetric eigensolver failed: {e:?}")))?;
    drop(mem);
    drop(scaled);

    // faer returns ascending eigenvalues in column-major `u`: reverse both, so that column c
    // of `u_buf` (d values from c * d) is the eigenvector of `s_buf[c]`, descending.
    s_buf.reverse();
    for c in 0..d / 2 {
        let (left, right) = u_buf.split_at_mut((d - 1 - c) * d);
        left[c * d..(c + 1) * d].swap_with_slice(&mut right[..d]);
    }
    canonicalize_clusters(&s_buf, &mut u_buf, d);

    let values: Vec<f64> = s_buf[..k].iter().map(|v| v / scale).collect();
    let mut vectors = buffer::try_zeroed_f64(d * k, "the eigenvectors")?;
    for (c, col) in u_buf.chunks_exact(d).take(k).enumerate() {
        for (i, &v) in col.iter().enumerate() {
            vectors[i * k + c] = v;
        }
    }
    Ok(Eigh {
        dim: d,
        values,
        vectors,
    })
}

/// Puts the eigenvectors (columns of the column-major `d × d` matrix `u`, eigenvalues
/// `values` descending) in their canonical basis, cluster by cluster: eigenvalues closer than
/// `CLUSTER_ULPS · d · ε · max|λ|` to their neighbour form one cluster (single linkage).
fn canonicalize_clusters(values: &[f64], u: &mut [f64], d: usize) {
    let max_abs = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let tol = CLUSTER_ULPS * d as f64 * f64::EPSILON * max_abs;
    let mut start = 0;
    for end in 1..=d {
        if end == d || values[end - 1] - values[end] > tol {
            canonical_basis(&mut u[start * d..end * d], d);
            start = end;
        }
    }
}

/// Replaces the `m` orthonormal columns of the column-major `d × m` matrix `v` by the
/// canonical orthonormal basis of their span: pivoted Gram–Schmidt on the rows of `v`.
///
/// Pivot `p_1` is the row of largest norm (the coordinate axis closest to the subspace; the
/// first on exact ties), `w_1` the normalised projection of that axis onto the subspace; each
/// next pivot is the row of largest norm once the previous directions are projected out. The
/// result depends only on the subspace: `w_j[p_i] = 0` for `j > i` and `w_i[p_i] > 0`. For
/// `m = 1` this is the sign convention "the component of largest magnitude is positive".
pub fn canonical_basis(v: &mut [f64], d: usize) {
    let m = v.len() / d;
    if m == 0 {
        return;
    }
    // Rows of v (d × m, row-major copy): r_p = (v[p, 0], ..., v[p, m-1]).
    let mut rows = vec![0.0; d * m];
    for (j, col) in v.chunks_exact(d).enumerate() {
        for (p, &x) in col.iter().enumerate() {
            rows[p * m + j] = x;
        }
    }
    let mut norms: Vec<f64> = rows
        .chunks_exact(m)
        .map(|r| r.iter().map(|x| x * x).sum())
        .collect();
    let mut q = vec![0.0; m * m]; // q_i in q[i * m..(i + 1) * m]
    let mut used = vec![false; d];
    for i in 0..m {
        let mut p = usize::MAX;
        for (r, &nr) in norms.iter().enumerate() {
            if !used[r] && (p == usize::MAX || nr > norms[p]) {
                p = r;
            }
        }
        used[p] = true;
        let (done, rest) = q.split_at_mut(i * m);
        let qi = &mut rest[..m];
        qi.copy_from_slice(&rows[p * m..(p + 1) * m]);
        // Re-orthogonalise against the previous directions (twice is enough), normalise.
        for _ in 0..2 {
            for qj in done.chunks_exact(m) {
                let dot: f64 = qi.iter().zip(qj).map(|(a, b)| a * b).sum();
                qi.iter_mut().zip(qj).for_each(|(a, b)| *a -= dot * b);
            }
        }
        let norm = qi.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 0.0 {
            qi.iter_mut().for_each(|x| *x /= norm);
        }
        // Deflate every row by q_i.
        for (r, row) in rows.chunks_exact_mut(m).enumerate() {
            let dot: f64 = row.iter().zip(qi.iter()).map(|(a, b)| a * b).sum();
            row.iter_mut()
                .zip(qi.iter())
                .for_each(|(a, b)| *a -= dot * b);
            norms[r] = row.iter().map(|x| x * x).sum();
        }
    }
    // w_i = V q_i, from the original columns.
    let orig = v.to_vec();
    for (i, w) in v.chunks_exact_mut(d).enumerate() {
        let qi = &q[i * m..(i + 1) * m];
        for (p, wp) in w.iter_mut().enumerate() {
            *wp = (0..m).map(|j| orig[j * d + p] * qi[j]).sum();
        }
    }
}

/// Check that `a` is a finite, square (`d × d`, `d ≥ 1`), symmetric matrix.
pub fn check_symmetric(a: &[f64], d: usize) -> Result<()> {
    if d == 0 {
        return Err(Error::Shape(
            "K is empty (0x0); need a square matrix of size ≥ 1".into(),
        ));
    }
    if Some(a.len()) != d.checked_mul(d) {
        return Err(Error::Shape(format!(
            "K has {} values, expected a square {d}x{d} matrix",
            a.len()
        )));
    }
    if let Some(pos) = a.iter().position(|v| !v.is_finite()) {
        return Err(Error::NonFinite(format!(
            "K contains NaN or infinity at ({}, {})",
            pos / d,
            pos % d
        )));
    }
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..d {
        for j in 0..i {
            let diff = (a[i * d + j] - a[j * d + i]).abs();
            if diff > SYMMETRY_TOL * scale {
                return Err(Error::InvalidArgument(format!(
                    "K is not symmetric: K[{i}, {j}] = {} but K[{j}, {i}] = {}",
                    a[i * d + j],
                    a[j * d + i]
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matvec(a: &[f64], d: usize, v: &[f64]) -> Vec<f64> {
        (0..d)
            .map(|i| (0..d).map(|j| a[i * d + j] * v[j]).sum())
            .collect()
    }

    #[test]
    fn diagonal_known_answer() {
        let a = [2.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 5.0];
        let e = eigh(&a, 3, None).unwrap();
        assert_eq!(e.values, vec![5.0, 2.0, -1.0]);
        // Columns: e3, e1, e2 with the positive sign convention.
        let expected = [0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0];
        for (x, y) in e.vectors.iter().zip(expected) {
            assert!((x - y).abs() < 1e-15);
        }
    }

    #[test]
    fn two_by_two_known_answer() {
        // [[2, 1], [1, 2]]: eigenvalues 3 and 1, vectors (1, 1)/√2 and (1, -1)/√2 up to sign.
        let e = eigh(&[2.0, 1.0, 1.0, 2.0], 2, None).unwrap();
        assert!((e.values[0] - 3.0).abs() < 1e-14 && (e.values[1] - 1.0).abs() < 1e-14);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((e.vectors[0] - h).abs() < 1e-14 && (e.vectors[2] - h).abs() < 1e-14);
        // Second vector: components ±1/√2 tie in magnitude, the first one is made positive.
        assert!((e.vectors[1] - h).abs() < 1e-14 && (e.vectors[3] + h).abs() < 1e-14);
    }

    #[test]
    fn residual_orthonormality_and_leading_k() {
        let d = 150;
        let mut a = vec![0.0; d * d];
        for i in 0..d {
            for j in 0..=i {
                let v =
                    ((i * 7 + j * 13) % 17) as f64 / 17.0 - 0.5 + if i == j { 3.0 } else { 0.0 };
                a[i * d + j] = v;
                a[j * d + i] = v;
            }
        }
        let e = eigh(&a, d, None).unwrap();
        assert!(e.values.windows(2).all(|w| w[0] >= w[1]));
        for c in 0..d {
            let v: Vec<f64> = (0..d).map(|i| e.vectors[i * d + c]).collect();
            let av = matvec(&a, d, &v);
            for i in 0..d {
                assert!((av[i] - e.values[c] * v[i]).abs() < 1e-11);
            }
            let big = v
                .iter()
                .fold(0.0f64, |m, x| if x.abs() > m.abs() { *x } else { m });
            assert!(big > 0.0);
            for c2 in 0..=c {
                let dot: f64 = (0..d).map(|i| e.vectors[i * d + c2] * v[i]).sum();
                let want = if c2 == c { 1.0 } else { 0.0 };
                assert!((dot - want).abs() < 1e-12);
            }
        }
        let lead = eigh(&a, d, Some(5)).unwrap();
        assert_eq!(lead.values, e.values[..5].to_vec());
        for i in 0..d {
            assert_eq!(lead.vectors[i * 5..i * 5 + 5], e.vectors[i * d..i * d + 5]);
        }
    }

    #[test]
    fn tiny_entries_next_to_large_ones() {
        // Found by a property test: an entry of 2.5e-275 next to 1.0 made the solver fail.
        let d = 7;
        let mut a = vec![0.0; d * d];
        a[3] = 1.25e-275;
        a[3 * d] = 1.25e-275;
        a[2 * d + 5] = 0.5;
        a[5 * d + 2] = 0.5;
        let e = eigh(&a, d, None).unwrap();
        assert!((e.values[0] - 0.5).abs() < 1e-15 && (e.values[d - 1] + 0.5).abs() < 1e-15);
        // Huge entries: scaling keeps the solver away from overflow.
        let big = [1e300, 2e299, 2e299, 1e300];
        let e = eigh(&big, 2, None).unwrap();
        assert!((e.values[0] / 1.2e300 - 1.0).abs() < 1e-14);
        assert!((e.values[1] / 0.8e300 - 1.0).abs() < 1e-14);
        // Subnormal input.
        let e = eigh(&[2.225e-313], 1, None).unwrap();
        assert_eq!(e.values, vec![2.225e-313]);
    }

    #[test]
    fn errors() {
        assert!(matches!(eigh(&[], 0, None), Err(Error::Shape(_))));
        assert!(matches!(
            eigh(&[1.0, 2.0, 3.0], 2, None),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            eigh(&[1.0, 2.0, 2.5, 1.0], 2, None),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            eigh(&[f64::INFINITY], 1, None),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            eigh(&[1.0], 1, Some(0)),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            eigh(&[1.0], 1, Some(2)),
            Err(Error::InvalidArgument(_))
        ));
    }
}
