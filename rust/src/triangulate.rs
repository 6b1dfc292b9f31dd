//! Weighted DLT triangulation of points seen by several calibrated cameras.
//!
//! For a point seen at `(u, v)` by a camera with projection matrix `P` (3 × 4, rows `p1, p2,
//! p3`), the homogeneous point `X` satisfies `u p3·X − p1·X = 0` and `v p3·X − p2·X = 0`.
//! Every view `i` with weight `w_i > 0` and finite coordinates adds these two rows, times
//! `w_i`, to a system `A X = 0`; `X` is the unit vector minimising `|A X|`, the eigenvector of
//! the 4 × 4 normal matrix `AᵀA` with the smallest eigenvalue (found by cyclic Jacobi
//! rotations), and the point is `X[0..3] / X[3]`.
//!
//! Coordinates: any consistent choice; with `P = [R | t]` and undistorted *normalised* image
//! coordinates (pixels through `K⁻¹`) the system is well scaled. A point seen by fewer than
//! `min_views` usable views, or whose solution lies at infinity, comes out NaN.

use rayon::prelude::*;

use crate::buffer;
use crate::{Error, Result};

/// Jacobi sweeps before giving up (a 4 × 4 matrix converges in 5–8).
const MAX_SWEEPS: usize = 60;

/// Eigenvector of the smallest eigenvalue of the symmetric 4 × 4 matrix `m` (row-major).
fn smallest_eigenvector(mut m: [f64; 16]) -> [f64; 4] {
    let mut v = [0.0f64; 16];
    for i in 0..4 {
        v[i * 4 + i] = 1.0;
    }
    let scale: f64 = m.iter().map(|x| x * x).sum::<f64>().sqrt();
    if scale == 0.0 {
        return [f64::NAN; 4];
    }
    for _ in 0..MAX_SWEEPS {
        let off: f64 = (0..4)
            .flat_map(|i| (0..4).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| m[i * 4 + j] * m[i * 4 + j])
            .sum::<f64>()
            .sqrt();
        if off <= 1e-15 * scale {
            break;
        }
        for p in 0..3 {
            for q in (p + 1)..4 {
                let apq = m[p * 4 + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (m[q * 4 + q] - m[p * 4 + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let mkp = m[k * 4 + p];
                    let mkq = m[k * 4 + q];
                    m[k * 4 + p] = c * mkp - s * mkq;
                    m[k * 4 + q] = s * mkp + c * mkq;
                }
                for k in 0..4 {
                    let mpk = m[p * 4 + k];
                    let mqk = m[q * 4 + k];
                    m[p * 4 + k] = c * mpk - s * mqk;
                    m[q * 4 + k] = s * mpk + c * mqk;
                }
                for k in 0..4 {
                    let vkp = v[k * 4 + p];
                    let vkq = v[k * 4 + q];
                    v[k * 4 + p] = c * vkp - s * vkq;
                    v[k * 4 + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let mut best = 0;
    for i in 1..4 {
        if m[i * 4 + i] < m[best * 4 + best] {
            best = i;
        }
    }
    [v[best], v[4 + best], v[8 + best], v[12 + best]]
}

/// One point from its views: `proj` (views × 12), `uv` (views × 2), `w` (views).
fn triangulate_one(proj: &[f64], uv: &[f64], w: &[f64], min_views: usize) -> [f64; 3] {
    let mut m = [0.0f64; 16];
    let mut used = 0usize;
    for (i, &wi) in w.iter().enumerate() {
        let (u, v) = (uv[2 * i], uv[2 * i + 1]);
        if wi <= 0.0 || !u.is_finite() || !v.is_finite() {
            continue;
        }
        used += 1;
        let p = &proj[12 * i..12 * i + 12];
        for (coord, row) in [(u, 0usize), (v, 1usize)] {
            let mut r = [0.0f64; 4];
            for (k, rk) in r.iter_mut().enumerate() {
                *rk = wi * (coord * p[8 + k] - p[4 * row + k]);
            }
            for a in 0..4 {
                for b in 0..4 {
                    m[a * 4 + b] += r[a] * r[b];
                }
            }
        }
    }
    if used < min_views {
        return [f64::NAN; 3];
    }
    let x = smallest_eigenvector(m);
    let norm = x.iter().map(|a| a * a).sum::<f64>().sqrt();
    // NaN-safe: a NaN solution also lands here.
    if x[3].is_nan() || x[3].abs() <= 1e-12 * norm {
        return [f64::NAN; 3];
    }
    [x[0] / x[3], x[1] / x[3], x[2] / x[3]]
}

/// Triangulate `n` points seen by `views` cameras.
///
/// * `proj`: `views × 3 × 4` projection matrices, row-major, finite;
/// * `uv`: `n × views × 2` image coordinates (NaN: not seen);
/// * `weights`: `n × views`, finite and ≥ 0 (0: not used; e.g. the detector's confidence);
/// * `min_views` ≥ 2.
///
/// Returns `n × 3` points (NaN where fewer than `min_views` views were usable).
/// Errors: lengths that do not fit (Shape), non-finite projections (NonFinite), negative or
/// NaN weights or `min_views` < 2 (InvalidArgument), an output too large (Memory).
pub fn triangulate(
    proj: &[f64],
    uv: &[f64],
    weights: &[f64],
    views: usize,
    min_views: usize,
) -> Result<Vec<f64>> {
    if views == 0 {
        return Err(Error::Shape("no views".into()));
    }
    if min_views < 2 {
        return Err(Error::InvalidArgument(format!(
            "min_views must be ≥ 2, got {min_views}"
        )));
    }
    let per_proj = buffer::elements::<f64>(&[views, 12], "projections")?;
    if proj.len() != per_proj {
        return Err(Error::Shape(format!(
            "projections must hold {views} × 3 × 4 = {per_proj} values, got {}",
            proj.len()
        )));
    }
    if let Some(i) = crate::checks::first_non_finite(proj) {
        return Err(Error::NonFinite(format!(
            "projections contain NaN or infinity (camera {})",
            i / 12
        )));
    }
    if !weights.len().is_multiple_of(views) {
        return Err(Error::Shape(format!(
            "weights hold {} values, not a multiple of {views} views",
            weights.len()
        )));
    }
    let n = weights.len() / views;
    let per_uv = buffer::elements::<f64>(&[n, views, 2], "points")?;
    if uv.len() != per_uv {
        return Err(Error::Shape(format!(
            "points must hold {n} × {views} × 2 = {per_uv} values, got {}",
            uv.len()
        )));
    }
    if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w >= 0.0)) {
        return Err(Error::InvalidArgument(format!(
            "weights must be finite and ≥ 0; point {}, view {} has {}",
            i / views,
            i % views,
            weights[i]
        )));
    }
    let mut out = buffer::try_zeroed_f64(buffer::elements::<f64>(&[n, 3], "output")?, "output")?;
    out.par_chunks_mut(3)
        .zip(uv.par_chunks(2 * views))
        .zip(weights.par_chunks(views))
        .for_each(|((o, p), w)| {
            o.copy_from_slice(&triangulate_one(proj, p, w, min_views));
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Camera looking at the origin from `centre` (world z up), `P = [R | −R c]`.
    fn camera(centre: [f64; 3]) -> [f64; 12] {
        let f = {
            let n = centre.iter().map(|x| x * x).sum::<f64>().sqrt();
            [-centre[0] / n, -centre[1] / n, -centre[2] / n]
        };
        let up = [0.0, 0.0, 1.0];
        let mut x = [
            f[1] * up[2] - f[2] * up[1],
            f[2] * up[0] - f[0] * up[2],
            f[0] * up[1] - f[1] * up[0],
        ];
        let nx = x.iter().map(|a| a * a).sum::<f64>().sqrt();
        x.iter_mut().for_each(|a| *a /= nx);
        let y = [
            f[1] * x[2] - f[2] * x[1],
            f[2] * x[0] - f[0] * x[2],
            f[0] * x[1] - f[1] * x[0],
        ];
        let r = [x, y, f];
        let mut p = [0.0; 12];
        for i in 0..3 {
            for k in 0..3 {
                p[4 * i + k] = r[i][k];
            }
            p[4 * i + 3] = -(0..3).map(|k| r[i][k] * centre[k]).sum::<f64>();
        }
        p
    }

    fn project(p: &[f64; 12], x: [f64; 3]) -> [f64; 2] {
        let h =
            |r: usize| p[4 * r] * x[0] + p[4 * r + 1] * x[1] + p[4 * r + 2] * x[2] + p[4 * r + 3];
        [h(0) / h(2), h(1) / h(2)]
    }

    fn rig() -> Vec<f64> {
        [
            [3.0, 0.5, 1.5],
            [-0.4, 3.1, 1.2],
            [-2.8, -1.0, 2.0],
            [0.3, -3.0, 1.0],
        ]
        .iter()
        .flat_map(|c| camera(*c))
        .collect()
    }

    #[test]
    fn exact_views_give_the_point_back() {
        let proj = rig();
        let pts = [[0.1, -0.2, 1.3], [0.0, 0.0, 0.0], [-0.5, 0.4, 0.9]];
        let mut uv = Vec::new();
        for x in pts {
            for v in 0..4 {
                let p: [f64; 12] = proj[12 * v..12 * v + 12].try_into().unwrap();
                uv.extend(project(&p, x));
            }
        }
        let out = triangulate(&proj, &uv, &[1.0; 12], 4, 2).unwrap();
        for (i, x) in pts.iter().enumerate() {
            for k in 0..3 {
                assert!((out[3 * i + k] - x[k]).abs() < 1e-9, "{out:?}");
            }
        }
    }

    #[test]
    fn zero_weights_and_nan_views_are_skipped() {
        let proj = rig();
        let x = [0.2, 0.1, 1.0];
        let mut uv = Vec::new();
        for v in 0..4 {
            let p: [f64; 12] = proj[12 * v..12 * v + 12].try_into().unwrap();
            uv.extend(project(&p, x));
        }
        // A wild observation in view 0 with weight 0, NaN in view 1: views 2 and 3 decide.
        uv[0] += 5.0;
        uv[2] = f64::NAN;
        let out = triangulate(&proj, &uv, &[0.0, 1.0, 0.7, 0.3], 4, 2).unwrap();
        for k in 0..3 {
            assert!((out[k] - x[k]).abs() < 1e-9);
        }
        // Only two usable views but three required: NaN.
        let out = triangulate(&proj, &uv, &[0.0, 1.0, 0.7, 0.3], 4, 3).unwrap();
        assert!(out.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn a_low_weight_outlier_moves_the_point_less() {
        let proj = rig();
        let x = [0.0, 0.0, 1.0];
        let mut uv = Vec::new();
        for v in 0..4 {
            let p: [f64; 12] = proj[12 * v..12 * v + 12].try_into().unwrap();
            uv.extend(project(&p, x));
        }
        uv[0] += 0.05;
        let err = |w0: f64| {
            let o = triangulate(&proj, &uv, &[w0, 1.0, 1.0, 1.0], 4, 2).unwrap();
            ((o[0] - x[0]).powi(2) + (o[1] - x[1]).powi(2) + (o[2] - x[2]).powi(2)).sqrt()
        };
        assert!(err(0.1) < 0.2 * err(1.0), "{} {}", err(0.1), err(1.0));
        assert!(err(1.0) > 1e-3);
    }

    #[test]
    fn bad_arguments_are_refused() {
        let proj = rig();
        assert!(matches!(
            triangulate(&proj, &[0.0; 8], &[1.0; 4], 4, 1),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            triangulate(&proj[..12], &[0.0; 8], &[1.0; 4], 4, 2),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            triangulate(&proj, &[0.0; 6], &[1.0; 4], 4, 2),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            triangulate(&proj, &[0.0; 8], &[1.0, -1.0, 1.0, 1.0], 4, 2),
            Err(Error::InvalidArgument(_))
        ));
        let mut bad = proj.clone();
        bad[13] = f64::NAN;
        assert!(matches!(
            triangulate(&bad, &[0.0; 8], &[1.0; 4], 4, 2),
            Err(Error::NonFinite(_))
        ));
        assert_eq!(
            triangulate(&proj, &[], &[], 4, 2).unwrap(),
            Vec::<f64>::new()
        );
    }
}
