//! Low-pass Butterworth design as second-order sections, and zero-phase filtering.
//!
//! * [`butter_sos`] reproduces `scipy.signal.butter(order, cutoff, output="sos")`: the analog
//!   prototype (`buttap`), the pre-warped low-pass transform (`lp2lp_zpk`), the bilinear
//!   transform (`bilinear_zpk`) and scipy's `zpk2sos` with `pairing="nearest"` (same section
//!   order, the overall gain folded into the first section).
//! * [`sosfiltfilt_rows`] and [`sosfiltfilt_ragged`] reproduce `scipy.signal.sosfiltfilt`
//!   (odd extension of `padlen` samples at both ends, `sosfilt_zi` initial conditions scaled by
//!   the first sample, a forward then a backward pass), for many signals at once: equal-length
//!   signals are filtered in lockstep by [`crate::lanes`], so the latency-bound recursion of one
//!   signal is overlapped with that of 15 others.
//!
//! An `sos` array is a list of sections `[b0, b1, b2, a0, a1, a2]` with `a0 == 1` (as scipy
//! requires); the normalised cutoff is a fraction of the Nyquist frequency (1 = Nyquist).

use nalgebra::Complex;

use crate::checks::first_non_finite;
use crate::lanes::{self, Section, SignalGroup};
use crate::ragged::trial_bounds;
use crate::{Error, Result};

type C64 = Complex<f64>;

/// One second-order section `[b0, b1, b2, a0, a1, a2]`.
pub type Sos = [f64; 6];

/// Largest Butterworth order accepted by [`butter_sos`].
pub const MAX_ORDER: usize = 64;

/// Low-pass Butterworth filter of `order` with normalised `cutoff` (a fraction of Nyquist, in
/// (0, 1)) as `(order + 1) / 2` second-order sections, equal to
/// `scipy.signal.butter(order, cutoff, output="sos")`.
pub fn butter_sos(order: usize, cutoff: f64) -> Result<Vec<Sos>> {
    if !(1..=MAX_ORDER).contains(&order) {
        return Err(Error::InvalidArgument(format!(
            "order must be an integer in [1, {MAX_ORDER}], got {order}"
        )));
    }
    if !(cutoff > 0.0 && cutoff < 1.0) {
        return Err(Error::InvalidArgument(format!(
            "cutoff must be in the open interval (0, 1) (a fraction of the Nyquist frequency), \
             got {cutoff}"
        )));
    }
    // buttap: poles -exp(i*pi*m/(2N)), m = -N+1, -N+3, ..., N-1; no zeros; gain 1.
    let n = order as f64;
    let poles: Vec<C64> = (0..order)
        .map(|j| {
            let m = -(n - 1.0) + 2.0 * j as f64;
            let theta = std::f64::consts::PI * m / (2.0 * n);
            -C64::new(theta.cos(), theta.sin())
        })
        .collect();
    // Pre-warp (fs = 2) and lp2lp_zpk: scale the poles, gain wo^N.
    let fs = 2.0;
    let warped = 2.0 * fs * (std::f64::consts::PI * cutoff / fs).tan();
    let poles: Vec<C64> = poles.iter().map(|p| p * warped).collect();
    let k = warped.powi(order as i32);
    // bilinear_zpk with fs = 2: p -> (4 + p) / (4 - p); the N zeros at infinity go to -1.
    let fs2 = C64::new(2.0 * fs, 0.0);
    let zp: Vec<C64> = poles.iter().map(|p| (fs2 + p) / (fs2 - p)).collect();
    let zz = vec![C64::new(-1.0, 0.0); order];
    let prod = poles
        .iter()
        .fold(C64::new(1.0, 0.0), |acc, p| acc * (fs2 - p));
    let kz = k * (C64::new(1.0, 0.0) / prod).re;
    Ok(zpk2sos_nearest(&zz, &zp, kz))
}

/// Splits roots into complex pairs (one member, positive imaginary part, sorted by real part)
/// and reals (sorted), as scipy's `_cplxreal`.
fn cplxreal(z: &[C64]) -> Vec<C64> {
    let tol = 100.0 * f64::EPSILON;
    let is_real = |c: &C64| c.im.abs() <= tol * c.norm();
    let key = |a: &C64, b: &C64| {
        a.re.partial_cmp(&b.re)
            .unwrap()
            .then(a.im.abs().partial_cmp(&b.im.abs()).unwrap())
    };
    let mut reals: Vec<f64> = z.iter().filter(|c| is_real(c)).map(|c| c.re).collect();
    reals.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let mut pos: Vec<C64> = z
        .iter()
        .filter(|c| !is_real(c) && c.im > 0.0)
        .copied()
        .collect();
    let mut neg: Vec<C64> = z
        .iter()
        .filter(|c| !is_real(c) && c.im < 0.0)
        .copied()
        .collect();
    pos.sort_by(key);
    neg.sort_by(key);
    debug_assert_eq!(pos.len(), neg.len());
    let mut out: Vec<C64> = pos
        .iter()
        .zip(&neg)
        .map(|(p, q)| (p + q.conj()) / 2.0)
        .collect();
    out.extend(reals.iter().map(|&r| C64::new(r, 0.0)));
    out
}

/// Index of the pole closest to the unit circle (first one on ties, as `np.argmin`).
fn idx_worst(p: &[C64]) -> usize {
    let mut best = 0;
    let mut best_d = f64::INFINITY;
    for (i, c) in p.iter().enumerate() {
        let d = (1.0 - c.norm()).abs();
        if d < best_d {
            best_d = d;
            best = i;
        }
    }
    best
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// scipy's `_nearest_real_complex_idx`: the element of `fro` nearest to `to` of the given kind.
fn nearest_idx(fro: &[C64], to: C64, which: Which) -> usize {
    let mut order: Vec<usize> = (0..fro.len()).collect();
    order.sort_by(|&a, &b| {
        (fro[a] - to)
            .norm()
            .partial_cmp(&(fro[b] - to).norm())
            .unwrap()
    });
    *order
        .iter()
        .find(|&&i| match which {
            Which::Any => true,
            Which::Real => fro[i].im == 0.0,
            Which::Complex => fro[i].im != 0.0,
        })
        .expect("zpk2sos: no root of the requested kind is left")
}

/// Real coefficients of the monic polynomial with the given (at most two) roots, highest power
/// first (`np.poly`).
fn poly(roots: &[C64]) -> Vec<f64> {
    let mut a = vec![C64::new(1.0, 0.0)];
    for r in roots {
        let mut next = vec![C64::new(0.0, 0.0); a.len() + 1];
        for (i, c) in a.iter().enumerate() {
            next[i] += c;
            next[i + 1] += c * (-r);
        }
        a = next;
    }
    a.iter().map(|c| c.re).collect()
}

/// scipy's `_single_zpksos(z, p, 1)`.
fn single_zpksos(z: &[C64], p: &[C64]) -> Sos {
    let mut sos = [0.0; 6];
    let b = poly(z);
    let a = poly(p);
    sos[3 - b.len()..3].copy_from_slice(&b);
    sos[6 - a.len()..6].copy_from_slice(&a);
    sos
}

/// scipy's `zpk2sos(z, p, k, pairing="nearest")` for a digital filter.
fn zpk2sos_nearest(z: &[C64], p: &[C64], k: f64) -> Vec<Sos> {
    let mut z = z.to_vec();
    let mut p = p.to_vec();
    let n_pad = z.len().max(p.len());
    z.resize(n_pad, C64::new(0.0, 0.0));
    p.resize(n_pad, C64::new(0.0, 0.0));
    let n_sections = n_pad.div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(C64::new(0.0, 0.0));
        z.push(C64::new(0.0, 0.0));
    }
    let mut z = cplxreal(&z);
    let mut p = cplxreal(&p);
    let is_real = |c: &C64| c.im == 0.0;
    let mut sos = vec![[0.0; 6]; n_sections];
    for si in (0..n_sections).rev() {
        let p1 = p.remove(idx_worst(&p));
        let n_real_p = p.iter().filter(|c| is_real(c)).count();
        let n_real_z = z.iter().filter(|c| is_real(c)).count();
        if is_real(&p1) && n_real_p == 0 {
            // Special case (1): the last remaining real pole.
            let z1 = z.remove(nearest_idx(&z, p1, Which::Real));
            sos[si] = single_zpksos(&[z1, C64::new(0.0, 0.0)], &[p1, C64::new(0.0, 0.0)]);
        } else if p.len() + 1 == z.len() && !is_real(&p1) && n_real_p == 1 && n_real_z == 1 {
            // Special case (2): one real pole and one real zero left: pair with a complex zero.
            let z1 = z.remove(nearest_idx(&z, p1, Which::Complex));
            sos[si] = single_zpksos(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if is_real(&p1) {
                let real_idx: Vec<usize> = (0..p.len()).filter(|&i| is_real(&p[i])).collect();
                let reals: Vec<C64> = real_idx.iter().map(|&i| p[i]).collect();
                p.remove(real_idx[idx_worst(&reals)])
            } else {
                p1.conj()
            };
            if z.is_empty() {
                sos[si] = single_zpksos(&[], &[p1, p2]);
            } else {
                let z1 = z.remove(nearest_idx(&z, p1, Which::Any));
                if !is_real(&z1) {
                    sos[si] = single_zpksos(&[z1, z1.conj()], &[p1, p2]);
                } else if !z.is_empty() {
                    let z2 = z.remove(nearest_idx(&z, p1, Which::Real));
                    sos[si] = single_zpksos(&[z1, z2], &[p1, p2]);
                } else {
                    sos[si] = single_zpksos(&[z1], &[p1, p2]);
                }
            }
        }
    }
    debug_assert!(p.is_empty() && z.is_empty());
    for c in &mut sos[0][..3] {
        *c *= k;
    }
    sos
}

/// Checks that `sos` is a usable filter: at least one section, finite coefficients, `a0 == 1`.
pub fn validate_sos(sos: &[Sos]) -> Result<()> {
    if sos.is_empty() {
        return Err(Error::Shape(
            "sos must have at least one section (shape (n_sections, 6))".into(),
        ));
    }
    for (i, s) in sos.iter().enumerate() {
        if s.iter().any(|c| !c.is_finite()) {
            return Err(Error::NonFinite(format!(
                "sos[{i}] contains NaN or infinity: {s:?}"
            )));
        }
        if s[3] != 1.0 {
            return Err(Error::InvalidArgument(format!(
                "sos[{i}, 3] (a0) must be 1 as in scipy.signal.sosfilt, got {}",
                s[3]
            )));
        }
    }
    Ok(())
}

/// scipy's default `padlen` for `sosfiltfilt`: `3 * (2 * n_sections + 1 - min(#{b2 == 0},
/// #{a2 == 0}))`.
pub fn default_padlen(sos: &[Sos]) -> usize {
    let zb = sos.iter().filter(|s| s[2] == 0.0).count();
    let za = sos.iter().filter(|s| s[5] == 0.0).count();
    // (Sections are 48 bytes each: the count is far below usize::MAX / 6.)
    3 * (2 * sos.len() + 1 - zb.min(za))
}

/// `scipy.signal.sosfilt_zi(sos)`: per section, the steady state of the step response
/// (`lfilter_zi`, solved by Gaussian elimination with partial pivoting), scaled by the DC gain
/// of the preceding sections.
pub fn sosfilt_zi(sos: &[Sos]) -> Vec<[f64; 2]> {
    let mut scale = 1.0;
    sos.iter()
        .map(|s| {
            let (b0, b1, b2, a1, a2) = (s[0], s[1], s[2], s[4], s[5]);
            // (I - A^T) zi = B with I - A^T = [[1 + a1, -1], [a2, 1]], solved as LAPACK's
            // getrf/getrs do (partial pivoting, the multiplier scaled by the pivot's
            // reciprocal): this reproduces numpy.linalg.solve, hence scipy, bit for bit on
            // Butterworth sections, which matters for very low cutoffs where the system is
            // ill-conditioned.
            let rhs0 = b1 - a1 * b0;
            let rhs1 = b2 - a2 * b0;
            let m00 = 1.0 + a1;
            let (z0, z1) = if m00.abs() >= a2.abs() {
                let l = a2 * (1.0 / m00);
                let z1 = (rhs1 - l * rhs0) / (1.0 + l);
                ((rhs0 + z1) / m00, z1)
            } else {
                let l = m00 * (1.0 / a2);
                let z1 = (rhs0 - l * rhs1) / (-1.0 - l);
                ((rhs1 - z1) / a2, z1)
            };
            let zi = [scale * z0, scale * z1];
            scale *= (b0 + b1 + b2) / (s[3] + a1 + a2);
            zi
        })
        .collect()
}

/// The sections with their `sosfilt_zi` initial states, as the lockstep engine takes them.
pub fn sections(sos: &[Sos]) -> Vec<Section> {
    sos.iter()
        .zip(sosfilt_zi(sos))
        .map(|(s, zi)| Section {
            b0: s[0],
            b1: s[1],
            b2: s[2],
            a1: s[4],
            a2: s[5],
            zi0: zi[0],
            zi1: zi[1],
        })
        .collect()
}

fn resolve_padlen(sos: &[Sos], padlen: Option<usize>) -> usize {
    padlen.unwrap_or_else(|| default_padlen(sos))
}

/// Zero-phase filtering of `n_rows` signals of `n` samples each, stored row-major in `x`
/// (`x[r * n + t]`), as `scipy.signal.sosfiltfilt(sos, x, axis=-1, padlen=padlen)`; `padlen`
/// `None` is scipy's default ([`default_padlen`]). Returns a new array of the same layout.
pub fn sosfiltfilt_rows(
    sos: &[Sos],
    x: &[f64],
    n_rows: usize,
    n: usize,
    padlen: Option<usize>,
) -> Result<Vec<f64>> {
    let level = crate::simd::level()?;
    validate_sos(sos)?;
    if Some(x.len()) != n_rows.checked_mul(n) {
        return Err(Error::Shape(format!(
            "x has {} values, expected {n_rows} x {n}",
            x.len()
        )));
    }
    if n_rows == 0 || n == 0 {
        return Err(Error::Shape(format!(
            "x is empty (shape ({n_rows}, {n})); nothing to filter"
        )));
    }
    let edge = resolve_padlen(sos, padlen);
    if n <= edge {
        return Err(Error::Shape(format!(
            "the signal has {n} samples, which must be greater than padlen = {edge} \
             (the odd extension at each end); use a shorter padlen or a lower order"
        )));
    }
    let bases: Vec<usize> = (0..n_rows).map(|r| r * n).collect();
    let mut out = crate::buffer::zeroed_f64(x.len());
    let finite = lanes::filtfilt_groups_at(
        level,
        &sections(sos),
        x,
        &mut out,
        &[SignalGroup {
            bases: &bases,
            stride: 1,
            len: n,
        }],
        edge,
    );
    if !finite {
        let i = first_non_finite(x).expect("a non-finite value was seen");
        return Err(Error::NonFinite(format!(
            "x contains NaN or infinity (row {}, sample {})",
            i / n,
            i % n
        )));
    }
    Ok(out)
}

/// Zero-phase filtering of a ragged corpus: `values` is `(total_frames, channels)` row-major,
/// trial `i` spans frames `offsets[i]..offsets[i + 1]` (the last one runs to the end), and
/// every channel of every trial is filtered along time independently, as `sosfiltfilt` of that
/// trial alone. Returns a new `(total_frames, channels)` array.
pub fn sosfiltfilt_ragged(
    sos: &[Sos],
    values: &[f64],
    channels: usize,
    offsets: &[i64],
    padlen: Option<usize>,
) -> Result<Vec<f64>> {
    let level = crate::simd::level()?;
    validate_sos(sos)?;
    if channels == 0 || values.is_empty() {
        return Err(Error::Shape(format!(
            "values is empty (shape ({}, {channels})); nothing to filter",
            values.len().checked_div(channels).unwrap_or(0)
        )));
    }
    if !values.len().is_multiple_of(channels) {
        return Err(Error::Shape(format!(
            "values has {} entries, not a multiple of {channels} channels",
            values.len()
        )));
    }
    let total = values.len() / channels;
    let bounds = trial_bounds(offsets, total)?;
    let edge = resolve_padlen(sos, padlen);
    if let Some((i, (s, e))) = bounds.iter().enumerate().find(|(_, (s, e))| e - s <= edge) {
        return Err(Error::Shape(format!(
            "trial {i} (frames {s}..{e}) has {} frames, which must be greater than padlen = \
             {edge} (the odd extension at each end); drop or merge short trials, or pass a \
             shorter padlen",
            e - s
        )));
    }
    // Group the trials by length: signals of one length are filtered in lockstep.
    let mut by_len: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for &(s, e) in &bounds {
        let bases = by_len.entry(e - s).or_default();
        bases.extend((0..channels).map(|c| s * channels + c));
    }
    let groups: Vec<SignalGroup> = by_len
        .iter()
        .map(|(&len, bases)| SignalGroup {
            bases,
            stride: channels,
            len,
        })
        .collect();
    let mut out = crate::buffer::zeroed_f64(values.len());
    // Non-finite values are detected while the blocks are gathered (no extra pass over the
    // corpus); located only if there is one.
    if !lanes::filtfilt_groups_at(level, &sections(sos), values, &mut out, &groups, edge) {
        let i = first_non_finite(values).expect("a non-finite value was seen");
        return Err(Error::NonFinite(format!(
            "values contains NaN or infinity (frame {}, channel {})",
            i / channels,
            i % channels
        )));
    }
    Ok(out)
}

/// Plain one-signal `sosfilt` with initial state `zi * x[0]` (the scipy recursion, direct form
/// II transposed), in place. Reference for tests and for single signals.
pub fn sosfilt_scalar(sos: &[Sos], zi: &[[f64; 2]], x: &mut [f64], init: f64) {
    let mut state: Vec<[f64; 2]> = zi.iter().map(|z| [z[0] * init, z[1] * init]).collect();
    for v in x.iter_mut() {
        let mut cur = *v;
        for (s, z) in sos.iter().zip(state.iter_mut()) {
            let new = s[0] * cur + z[0];
            z[0] = s[1] * cur - s[4] * new + z[1];
            z[1] = s[2] * cur - s[5] * new;
            cur = new;
        }
        *v = cur;
    }
}

/// One-signal `sosfiltfilt` with plain scalar code (odd extension, forward, backward). Used as
/// the reference of the lockstep engine in tests.
pub fn sosfiltfilt_scalar(sos: &[Sos], x: &[f64], edge: usize) -> Vec<f64> {
    let n = x.len();
    assert!(n > edge);
    let mut ext = Vec::with_capacity(n + 2 * edge);
    ext.extend((0..edge).map(|i| 2.0 * x[0] - x[edge - i]));
    ext.extend_from_slice(x);
    ext.extend((0..edge).map(|j| 2.0 * x[n - 1] - x[n - 2 - j]));
    let zi = sosfilt_zi(sos);
    let x0 = ext[0];
    sosfilt_scalar(sos, &zi, &mut ext, x0);
    ext.reverse();
    let y0 = ext[0];
    sosfilt_scalar(sos, &zi, &mut ext, y0);
    ext.reverse();
    ext[edge..edge + n].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn butter_order2_known_answer() {
        // scipy.signal.butter(2, 0.5, output="sos"): b = [0.29289322, 0.58578644, 0.29289322],
        // a = [1, 0, 0.17157288] (the textbook half-band design).
        let sos = butter_sos(2, 0.5).unwrap();
        assert_eq!(sos.len(), 1);
        let expect = [
            0.292_893_218_813_452_4,
            0.585_786_437_626_904_9,
            0.292_893_218_813_452_4,
            1.0,
            0.0,
            0.171_572_875_253_809_9,
        ];
        for (a, b) in sos[0].iter().zip(expect) {
            assert_relative_eq!(*a, b, epsilon = 1e-14);
        }
    }

    #[test]
    fn butter_order3_pairs_the_origin_zero_like_scipy() {
        // scipy.signal.butter(3, 0.1, output="sos") (scipy 1.17):
        // [[0.00289819463372143, 0.00579638926744286, 0.00289819463372143, 1,
        //   -0.726542528005361, 0], [1, 1, 0, 1, -1.647552215703991, 0.7323389172728038]]
        let sos = butter_sos(3, 0.1).unwrap();
        assert_eq!(sos.len(), 2);
        assert_eq!(sos[0][5], 0.0);
        assert_relative_eq!(sos[0][4], -0.726_542_528_005_361, epsilon = 1e-12);
        assert_eq!(&sos[1][..3], &[1.0, 1.0, 0.0]);
        assert_relative_eq!(sos[1][4], -1.647_552_215_703_991, epsilon = 1e-12);
        assert_relative_eq!(sos[1][5], 0.732_338_917_272_803_8, epsilon = 1e-12);
        assert_relative_eq!(sos[0][0], 0.002_898_194_633_721_43, epsilon = 1e-15);
    }

    #[test]
    fn butter_has_unit_dc_gain_and_zero_nyquist_gain() {
        for order in 1..=12 {
            for &wc in &[0.01, 0.1, 0.25, 0.5, 0.9, 0.99] {
                let sos = butter_sos(order, wc).unwrap();
                assert_eq!(sos.len(), order.div_ceil(2));
                let dc: f64 = sos
                    .iter()
                    .map(|s| (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5]))
                    .product();
                assert_relative_eq!(dc, 1.0, epsilon = 1e-8);
                let nyq: f64 = sos.iter().map(|s| (s[0] - s[1] + s[2]).abs()).product();
                assert!(nyq < 1e-12, "order {order} cutoff {wc}: |H(-1)| = {nyq}");
            }
        }
    }

    #[test]
    fn butter_rejects_bad_arguments() {
        assert!(matches!(butter_sos(0, 0.5), Err(Error::InvalidArgument(_))));
        assert!(matches!(butter_sos(4, 0.0), Err(Error::InvalidArgument(_))));
        assert!(matches!(butter_sos(4, 1.0), Err(Error::InvalidArgument(_))));
        assert!(matches!(
            butter_sos(4, f64::NAN),
            Err(Error::InvalidArgument(_))
        ));
    }

    #[test]
    fn zi_is_the_step_response_steady_state() {
        // Filtering a constant from its steady state leaves it unchanged.
        let sos = butter_sos(6, 0.2).unwrap();
        let zi = sosfilt_zi(&sos);
        let mut x = vec![3.5; 50];
        sosfilt_scalar(&sos, &zi, &mut x, 3.5);
        for v in x {
            assert_relative_eq!(v, 3.5, epsilon = 1e-12);
        }
    }

    #[test]
    fn default_padlen_matches_scipy_rule() {
        assert_eq!(default_padlen(&butter_sos(10, 0.25).unwrap()), 33);
        // order 3: the first section has b2 == a2 == 0 -> ntaps 4 -> padlen 12.
        assert_eq!(default_padlen(&butter_sos(3, 0.1).unwrap()), 12);
    }

    #[test]
    fn filtfilt_keeps_constants_and_slow_sines() {
        // A constant is its own odd extension and the filter starts from its steady state.
        let sos = butter_sos(4, 0.3).unwrap();
        let y = sosfiltfilt_rows(&sos, &[-2.5; 80], 1, 80, None).unwrap();
        for v in y {
            assert_relative_eq!(v, -2.5, epsilon = 1e-12);
        }
        // A sine at 1% of Nyquist passes a cutoff of 30% with gain |H|^2 = 1 - O(1e-16) and
        // no phase shift: unchanged away from the ends.
        let x: Vec<f64> = (0..400)
            .map(|t| (std::f64::consts::PI * 0.01 * t as f64).sin())
            .collect();
        let y = sosfiltfilt_rows(&sos, &x, 1, 400, None).unwrap();
        for t in 100..300 {
            assert_relative_eq!(x[t], y[t], epsilon = 1e-6);
        }
    }

    #[test]
    fn rows_match_scalar_reference() {
        let sos = butter_sos(10, 0.25).unwrap();
        let n = 150;
        let rows = 37; // two full blocks of 16 and a remainder
        let x: Vec<f64> = (0..rows * n)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.5)
            .collect();
        let y = sosfiltfilt_rows(&sos, &x, rows, n, None).unwrap();
        for r in 0..rows {
            let want = sosfiltfilt_scalar(&sos, &x[r * n..(r + 1) * n], 33);
            for (a, b) in y[r * n..(r + 1) * n].iter().zip(&want) {
                assert_relative_eq!(*a, *b, epsilon = 1e-12);
            }
        }
    }

    #[test]
    fn ragged_matches_per_trial() {
        let sos = butter_sos(4, 0.2).unwrap();
        let channels = 3;
        let lens = [40usize, 55, 40, 31, 40, 90, 55];
        let offsets: Vec<i64> = lens
            .iter()
            .scan(0i64, |acc, &l| {
                let o = *acc;
                *acc += l as i64;
                Some(o)
            })
            .collect();
        let total: usize = lens.iter().sum();
        let values: Vec<f64> = (0..total * channels)
            .map(|i| ((i * 104_729) % 997) as f64 / 997.0)
            .collect();
        let y = sosfiltfilt_ragged(&sos, &values, channels, &offsets, None).unwrap();
        let edge = default_padlen(&sos);
        for (k, &len) in lens.iter().enumerate() {
            let s = offsets[k] as usize;
            for c in 0..channels {
                let sig: Vec<f64> = (0..len).map(|t| values[(s + t) * channels + c]).collect();
                let want = sosfiltfilt_scalar(&sos, &sig, edge);
                for t in 0..len {
                    assert_relative_eq!(y[(s + t) * channels + c], want[t], epsilon = 1e-12);
                }
            }
        }
    }

    #[test]
    fn too_short_signals_are_refused_naming_both_lengths() {
        let sos = butter_sos(10, 0.25).unwrap();
        let err = sosfiltfilt_rows(&sos, &[0.0; 33], 1, 33, None).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("33 samples") && msg.contains("padlen = 33"),
            "{msg}"
        );
        let err = sosfiltfilt_ragged(&sos, &[0.0; 100], 1, &[0, 70], None).unwrap_err();
        assert!(err.to_string().contains("trial 1"), "{err}");
        // padlen = 0 filters without extension.
        assert!(sosfiltfilt_rows(&sos, &[1.0; 5], 1, 5, Some(0)).is_ok());
    }

    #[test]
    fn non_finite_input_is_refused() {
        let sos = butter_sos(2, 0.25).unwrap();
        let mut x = vec![0.0; 40];
        x[23] = f64::NAN;
        let err = sosfiltfilt_rows(&sos, &x, 2, 20, None).unwrap_err();
        assert!(matches!(err, Error::NonFinite(_)));
        assert!(err.to_string().contains("row 1, sample 3"), "{err}");
        let err = sosfiltfilt_ragged(&sos, &x, 2, &[0], None).unwrap_err();
        assert!(err.to_string().contains("frame 11, channel 1"), "{err}");
    }

    #[test]
    fn invalid_sos_is_refused() {
        let mut sos = butter_sos(2, 0.3).unwrap();
        sos[0][3] = 2.0;
        assert!(matches!(validate_sos(&sos), Err(Error::InvalidArgument(_))));
        sos[0][3] = 1.0;
        sos[0][1] = f64::NAN;
        assert!(matches!(validate_sos(&sos), Err(Error::NonFinite(_))));
        assert!(matches!(validate_sos(&[]), Err(Error::Shape(_))));
    }
}
