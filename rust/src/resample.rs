//! Resampling of segments of a multichannel signal to a fixed number of samples.
//!
//! Segment `s` spans the fractional frame indices `[starts[s], ends[s]]` of `values`
//! `(frames, channels)`; it is sampled at `n` equally spaced points from start to end inclusive
//! (`numpy.linspace(start, end, n)`), each channel linearly interpolated between frames
//! (`numpy.interp(points, arange(frames), values[:, c])`). The output row of a segment is
//! channel-major: the `n` samples of channel 0, then of channel 1, ...

use rayon::prelude::*;

use crate::checks::first_non_finite;
use crate::{Error, Result};

/// Segments per parallel task.
const SEGMENTS_PER_TASK: usize = 256;

fn check(values: &[f64], channels: usize, starts: &[f64], ends: &[f64], n: usize) -> Result<()> {
    if channels == 0 || values.is_empty() {
        return Err(Error::Shape(
            "values is empty: need at least two frames and one channel".into(),
        ));
    }
    if values.len() % channels != 0 {
        return Err(Error::Shape(format!(
            "values has {} entries, not a multiple of {channels} channels",
            values.len()
        )));
    }
    let frames = values.len() / channels;
    if starts.len() != ends.len() {
        return Err(Error::Shape(format!(
            "starts and ends must have the same length, got {} and {}",
            starts.len(),
            ends.len()
        )));
    }
    if n < 2 {
        return Err(Error::InvalidArgument(format!(
            "n (samples per channel) must be at least 2, got {n}"
        )));
    }
    if let Some(i) = first_non_finite(values) {
        return Err(Error::NonFinite(format!(
            "values contains NaN or infinity (frame {}, channel {})",
            i / channels,
            i % channels
        )));
    }
    let last = (frames - 1) as f64;
    for (i, (&s, &e)) in starts.iter().zip(ends).enumerate() {
        if !(s.is_finite() && e.is_finite()) {
            return Err(Error::NonFinite(format!(
                "segment {i}: start {s} / end {e} is not finite"
            )));
        }
        if !(0.0 <= s && s < e && e <= last) {
            return Err(Error::InvalidArgument(format!(
                "segment {i}: need 0 <= start < end <= frames - 1 = {last}, got start {s}, \
                 end {e} (fractional frame indices)"
            )));
        }
    }
    Ok(())
}

/// Resamples each segment to `n` samples per channel. `values` is `(frames, channels)`
/// row-major; returns `(n_segments, channels * n)` row-major, channel-major within a row. No
/// segments gives an empty result.
pub fn resample_segments(
    values: &[f64],
    channels: usize,
    starts: &[f64],
    ends: &[f64],
    n: usize,
) -> Result<Vec<f64>> {
    check(values, channels, starts, ends, n)?;
    let frames = values.len() / channels;
    let row = channels * n;
    let mut out = crate::buffer::zeroed_f64(starts.len() * row);
    out.par_chunks_mut(row * SEGMENTS_PER_TASK)
        .enumerate()
        .for_each(|(k, chunk)| {
            for (j, dst) in chunk.chunks_exact_mut(row).enumerate() {
                let s = k * SEGMENTS_PER_TASK + j;
                resample_one(values, channels, frames, starts[s], ends[s], n, dst);
            }
        });
    Ok(out)
}

/// One segment into `dst` (`channels * n`).
#[inline]
fn resample_one(
    values: &[f64],
    channels: usize,
    frames: usize,
    start: f64,
    end: f64,
    n: usize,
    dst: &mut [f64],
) {
    let step = (end - start) / (n - 1) as f64;
    for k in 0..n {
        // numpy.linspace: k * step + start, the last point exactly `end`.
        let x = if k == n - 1 {
            end
        } else {
            k as f64 * step + start
        };
        // numpy.interp on the grid 0, 1, ..., frames - 1: j = floor(x),
        // value = (fp[j + 1] - fp[j]) * (x - j) + fp[j]; x == frames - 1 gives fp[last].
        let j = (x as usize).min(frames - 1);
        let row = &values[j * channels..(j + 1) * channels];
        if j == frames - 1 {
            for (c, &v) in row.iter().enumerate() {
                dst[c * n + k] = v;
            }
        } else {
            let frac = x - j as f64;
            let next = &values[(j + 1) * channels..(j + 2) * channels];
            for c in 0..channels {
                dst[c * n + k] = (next[c] - row[c]) * frac + row[c];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_signal_is_resampled_exactly() {
        // channel 0: 2 t, channel 1: 10 - t over 6 frames.
        let values: Vec<f64> = (0..6).flat_map(|t| [2.0 * t as f64, 10.0 - t as f64]).collect();
        let out = resample_segments(&values, 2, &[0.5, 0.0], &[4.5, 5.0], 5).unwrap();
        assert_eq!(out.len(), 2 * 10);
        // segment 0 points 0.5, 1.5, 2.5, 3.5, 4.5
        assert_eq!(&out[..5], &[1.0, 3.0, 5.0, 7.0, 9.0]);
        assert_eq!(&out[5..10], &[9.5, 8.5, 7.5, 6.5, 5.5]);
        // segment 1 points 0, 1.25, 2.5, 3.75, 5 (the last frame exactly)
        assert_eq!(&out[10..15], &[0.0, 2.5, 5.0, 7.5, 10.0]);
        assert_eq!(&out[15..20], &[10.0, 8.75, 7.5, 6.25, 5.0]);
    }

    #[test]
    fn endpoints_are_the_interpolated_boundaries() {
        let values = [0.0, 1.0, 4.0, 9.0];
        let out = resample_segments(&values, 1, &[0.25], &[3.0], 2).unwrap();
        assert_eq!(out, vec![0.25, 9.0]);
    }

    #[test]
    fn no_segments_is_empty() {
        assert!(resample_segments(&[0.0, 1.0], 1, &[], &[], 10)
            .unwrap()
            .is_empty());
    }

    #[test]
    fn invalid_segments_are_refused() {
        let v = [0.0, 1.0, 2.0];
        for (s, e) in [(1.0, 1.0), (-0.5, 1.0), (0.0, 2.5), (2.0, 1.0)] {
            assert!(
                matches!(
                    resample_segments(&v, 1, &[s], &[e], 4),
                    Err(Error::InvalidArgument(_))
                ),
                "{s} {e}"
            );
        }
        assert!(matches!(
            resample_segments(&v, 1, &[f64::NAN], &[1.0], 4),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            resample_segments(&v, 1, &[0.0], &[1.0, 2.0], 4),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            resample_segments(&v, 1, &[0.0], &[1.0], 1),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            resample_segments(&[], 1, &[], &[], 4),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            resample_segments(&[0.0, f64::INFINITY], 1, &[0.0], &[1.0], 4),
            Err(Error::NonFinite(_))
        ));
    }
}
