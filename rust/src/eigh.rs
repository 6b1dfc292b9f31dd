//! Symmetric eigendecomposition (faer), eigenvalues in descending order.
//!
//! Sign convention: every returned eigenvector has its component of largest absolute value
//! positive (the first such component when several tie). Eigenvectors of a repeated eigenvalue
//! span the right subspace but their basis inside it is whatever the solver returns.
//!
//! Like `numpy.linalg.eigh` (`UPLO='L'`) only the lower triangle `a[i, j], i ≥ j` is read once
//! the matrix has been checked to be symmetric. The matrix is scaled by a power of two and
//! entries below 1.5e-154 of the largest are flushed to zero before the solver runs (see
//! [`eigh`]).

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{Mat, MatRef, Par};

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

/// Eigenvalues (descending) and eigenvectors (columns) of the symmetric row-major `d × d`
/// matrix `a`; only the leading `k` pairs when `k` is given (`1 ≤ k ≤ d`).
///
/// Errors: wrong length or `d == 0` (Shape), NaN/inf (NonFinite), asymmetry beyond
/// [`SYMMETRY_TOL`] or `k` out of range (InvalidArgument), solver failure (Numerical).
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
    let par = if d >= 128 { Par::rayon(0) } else { Par::Seq };
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
    let scaled: Vec<f64> = a
        .iter()
        .map(|&v| {
            let w = v * scale;
            if w.abs() < tiny {
                0.0
            } else {
                w
            }
        })
        .collect();
    let mat = MatRef::from_row_major_slice(&scaled, d, d);
    let mut u = Mat::<f64>::zeros(d, d);
    let mut s = Diag::<f64>::zeros(d);
    let params = Default::default();
    let mut mem = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        d,
        ComputeEigenvectors::Yes,
        par,
        params,
    ));
    evd::self_adjoint_evd(
        mat,
        s.as_mut(),
        Some(u.as_mut()),
        par,
        MemStack::new(&mut mem),
        params,
    )
    .map_err(|e| Error::Numerical(format!("symmetric eigensolver failed: {e:?}")))?;

    // faer returns ascending eigenvalues: take the last k, reversed.
    let mut values = Vec::with_capacity(k);
    let mut vectors = vec![0.0; d * k];
    for c in 0..k {
        let src = d - 1 - c;
        values.push(s[src] / scale);
        let col = u.col(src);
        let mut pivot = 0;
        for i in 1..d {
            if col[i].abs() > col[pivot].abs() {
                pivot = i;
            }
        }
        let sign = if col[pivot] < 0.0 { -1.0 } else { 1.0 };
        for i in 0..d {
            vectors[i * k + c] = sign * col[i];
        }
    }
    Ok(Eigh {
        dim: d,
        values,
        vectors,
    })
}

/// Check that `a` is a finite, square (`d × d`, `d ≥ 1`), symmetric matrix.
pub fn check_symmetric(a: &[f64], d: usize) -> Result<()> {
    if d == 0 {
        return Err(Error::Shape(
            "K is empty (0x0); need a square matrix of size ≥ 1".into(),
        ));
    }
    if a.len() != d * d {
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
