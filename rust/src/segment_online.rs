//! The values a closed online segment is described by: the model's zero-phase low-pass of
//! the raw arm angles buffered around it, then the model's channels of the segment's frames.
//!
//! `visprim.online.segmenter` used to take them in numpy (`visprim.filtering.lowpass` with
//! `short="reduce"`, then `visprim.features.from_angles`), a dozen array calls per segment;
//! [`segment_channels`] does both in one call. The filter is
//! [`crate::filter::sosfiltfilt_ragged`] of the window as one trial, with scipy's default
//! padding, or `n − 1` frames for a window not longer than it (`lowpass`'s `"reduce"`): the
//! same bits as the Python path. The channels are
//! [`crate::front_online::channels_of_angles`], within an ulp of numpy's.

use crate::buffer::{elements, try_with_capacity};
use crate::filter::{default_padlen, sosfiltfilt_ragged, Sos};
use crate::front_online::{channels_of_angles, Features};
use crate::{Error, Result};

/// Channels `(stop − start, channels)` row-major of frames `start..stop` of the window `raw`
/// (`(n, width)` row-major arm angles, radians, `width = 4 n_arms`), after the zero-phase
/// filter `sos` of the whole window (module docstring).
///
/// Errors: `width` not a positive multiple of 4, `raw` not whole frames or empty, or not
/// `start < stop ≤ n` (Shape); a non-finite angle (NonFinite); an invalid `sos` (from the
/// filter).
pub fn segment_channels(
    sos: &[Sos],
    raw: &[f64],
    width: usize,
    start: usize,
    stop: usize,
    features: Features,
) -> Result<Vec<f64>> {
    if width == 0 || !width.is_multiple_of(4) {
        return Err(Error::Shape(format!(
            "raw angles need 4 channels per arm, got {width}"
        )));
    }
    if raw.is_empty() || !raw.len().is_multiple_of(width) {
        return Err(Error::Shape(format!(
            "raw angles: {} values are not whole frames of {width} channels (at least one)",
            raw.len()
        )));
    }
    let n = raw.len() / width;
    if !(start < stop && stop <= n) {
        return Err(Error::Shape(format!(
            "frames {start}..{stop} are not a non-empty part of the window's {n} frames"
        )));
    }
    let pad = default_padlen(sos);
    let padlen = if n > pad { pad } else { n - 1 };
    let smooth = sosfiltfilt_ragged(sos, raw, width, &[0], Some(padlen))?;
    let channels = width / 4 * features.per_arm();
    let mut out = try_with_capacity(
        elements::<f64>(&[stop - start, channels], "channels")?,
        "channels",
    )?;
    channels_of_angles(features, &smooth[start * width..stop * width], &mut out);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::butter_sos;

    fn window(n: usize, width: usize) -> Vec<f64> {
        (0..n * width)
            .map(|i| (0.37 * i as f64).sin() + 0.01 * i as f64)
            .collect()
    }

    #[test]
    fn the_filter_is_sosfiltfilt_of_the_window_and_the_channels_the_front_ends() {
        let sos = butter_sos(10, 0.2).unwrap();
        let pad = default_padlen(&sos);
        for n in [1usize, 5, pad, pad + 1, 90] {
            let raw = window(n, 8);
            let padlen = if n > pad { pad } else { n - 1 };
            let smooth = sosfiltfilt_ragged(&sos, &raw, 8, &[0], Some(padlen)).unwrap();
            let (a, b) = (n / 3, n);
            for features in [Features::Zyz, Features::Directions] {
                let got = segment_channels(&sos, &raw, 8, a, b, features).unwrap();
                let mut want = Vec::new();
                channels_of_angles(features, &smooth[a * 8..b * 8], &mut want);
                assert_eq!(got, want, "n {n}, {features:?}");
                assert_eq!(got.len(), (b - a) * 2 * features.per_arm());
            }
        }
    }

    #[test]
    fn directions_are_unit_bones_of_the_angles() {
        let sos = butter_sos(2, 0.3).unwrap();
        // A constant posture passes the low-pass unchanged (within rounding).
        let q = [0.3, 1.1, -0.4, 0.9];
        let raw: Vec<f64> = (0..40).flat_map(|_| q).collect();
        let got = segment_channels(&sos, &raw, 4, 10, 12, Features::Directions).unwrap();
        let (sg, cg) = q[0].sin_cos();
        let (sb, cb) = q[1].sin_cos();
        // The upper arm: the third column of Rz(γ) Ry(β) Rz(α) = (cγ sβ, sγ sβ, cβ).
        let upper = [cg * sb, sg * sb, cb];
        for row in got.chunks_exact(6) {
            for (x, y) in row[..3].iter().zip(upper) {
                assert!((x - y).abs() < 1e-12, "{x} vs {y}");
            }
            let norm: f64 = row[3..].iter().map(|v| v * v).sum();
            assert!((norm - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let sos = butter_sos(2, 0.3).unwrap();
        let raw = window(10, 4);
        assert!(segment_channels(&sos, &raw, 3, 0, 1, Features::Zyz).is_err());
        assert!(segment_channels(&sos, &raw[..7], 4, 0, 1, Features::Zyz).is_err());
        assert!(segment_channels(&sos, &[], 4, 0, 1, Features::Zyz).is_err());
        assert!(segment_channels(&sos, &raw, 4, 3, 3, Features::Zyz).is_err());
        assert!(segment_channels(&sos, &raw, 4, 0, 11, Features::Zyz).is_err());
        let mut bad = raw.clone();
        bad[5] = f64::NAN;
        assert!(segment_channels(&sos, &bad, 4, 0, 10, Features::Zyz).is_err());
    }
}
