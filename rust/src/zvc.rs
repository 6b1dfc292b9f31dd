//! Zero-velocity crossings (ZVCs) with the "significant movement" test.
//!
//! Definitions (per channel, frames in time order, velocity `v`, position `p`):
//!
//! * **Crossing.** The velocity changes sign between two frames. Exact zeros carry no sign:
//!   between consecutive NON-ZERO samples `v[a]` and `v[b]` (`a < b`, everything strictly
//!   between is exactly `0.0`) of opposite signs there is one crossing. If `b == a + 1` its
//!   position is the linear-interpolation root `a + v[a] / (v[a] - v[b])` (a fractional frame
//!   index in `[a, b]`); otherwise it is the middle of the run of zeros, `(a + b) / 2` (which is
//!   the zero frame itself for a single zero). A velocity that touches zero and returns to the
//!   same sign, or zeros at the start or end of the signal, give no crossing.
//! * **Significant movement.** The position at a crossing is `p` linearly interpolated at its
//!   fractional frame. Walking the channel's crossings in time order, a crossing is KEPT when
//!   `|p(crossing) - p(reference)| > min_change`, where the reference is the last kept crossing
//!   of that channel, or frame 0 of the trial before any was kept. `min_change = 0` keeps every
//!   crossing (no test). Dropped crossings do not move the reference.
//! * **Positions.** `p` is given (e.g. the joint angle whose derivative is `v`), or defaults to
//!   the running sum of the velocity, `p[t] = v[0] + ... + v[t]` (`numpy.cumsum`), i.e. the
//!   velocity taken in position units per frame.

use rayon::prelude::*;

use crate::checks::first_non_finite;
use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// Crossings of a ragged corpus, sorted by trial, then channel, then frame.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Crossings {
    /// Trial index of each crossing.
    pub trial: Vec<i64>,
    /// Channel index of each crossing.
    pub channel: Vec<i64>,
    /// Fractional frame index, relative to the trial's first frame.
    pub frame: Vec<f64>,
}

/// Interpolated value of a channel at fractional frame `i0 + frac` (`frac` in `[0, 1]`).
#[inline]
fn interp(p: impl Fn(usize) -> f64, i0: usize, frac: f64) -> f64 {
    if frac == 0.0 {
        p(i0)
    } else {
        let a = p(i0);
        a + frac * (p(i0 + 1) - a)
    }
}

/// Crossings of one channel of one trial (`vel(t)`, `pos(t)` for `t in 0..len`), appended to
/// `out` as fractional frames.
fn scan_channel(
    len: usize,
    vel: impl Fn(usize) -> f64,
    pos: impl Fn(usize) -> f64,
    min_change: f64,
    out: &mut Vec<f64>,
) {
    let mut reference = pos(0);
    let mut last: Option<(usize, f64)> = None;
    for t in 0..len {
        let v = vel(t);
        if v == 0.0 {
            continue;
        }
        if let Some((a, va)) = last {
            if (va > 0.0) != (v > 0.0) {
                let (i0, frac) = if t == a + 1 {
                    (a, va / (va - v))
                } else {
                    ((a + t) / 2, if (a + t) % 2 == 1 { 0.5 } else { 0.0 })
                };
                let at = interp(&pos, i0, frac);
                if min_change == 0.0 || (at - reference).abs() > min_change {
                    out.push(i0 as f64 + frac);
                    reference = at;
                }
            }
        }
        last = Some((t, v));
    }
}

/// Crossings of every channel of one trial spanning frames `s..e` of a corpus with `channels`
/// columns.
#[allow(clippy::too_many_arguments)]
fn scan_trial(
    velocity: &[f64],
    positions: Option<&[f64]>,
    channels: usize,
    s: usize,
    e: usize,
    min_change: f64,
    trial: i64,
    cum: &mut Vec<f64>,
    out: &mut Crossings,
) {
    let len = e - s;
    for c in 0..channels {
        let vel = |t: usize| velocity[(s + t) * channels + c];
        let before = out.frame.len();
        match positions {
            Some(p) => scan_channel(
                len,
                vel,
                |t| p[(s + t) * channels + c],
                min_change,
                &mut out.frame,
            ),
            None => {
                cum.clear();
                let mut acc = 0.0;
                cum.extend((0..len).map(|t| {
                    acc += vel(t);
                    acc
                }));
                let cum: &[f64] = cum;
                scan_channel(len, vel, |t| cum[t], min_change, &mut out.frame);
            }
        }
        let added = out.frame.len() - before;
        out.channel.extend(std::iter::repeat_n(c as i64, added));
        out.trial.extend(std::iter::repeat_n(trial, added));
    }
}

fn check_inputs(
    velocity: &[f64],
    channels: usize,
    min_change: f64,
    positions: Option<&[f64]>,
) -> Result<usize> {
    if channels == 0 || velocity.is_empty() {
        return Err(Error::Shape(
            "velocity is empty: need at least one frame and one channel".into(),
        ));
    }
    if velocity.len() % channels != 0 {
        return Err(Error::Shape(format!(
            "velocity has {} values, not a multiple of {channels} channels",
            velocity.len()
        )));
    }
    if !(min_change.is_finite() && min_change >= 0.0) {
        return Err(Error::InvalidArgument(format!(
            "min_change must be a finite number >= 0, got {min_change}"
        )));
    }
    if let Some(i) = first_non_finite(velocity) {
        return Err(Error::NonFinite(format!(
            "velocity contains NaN or infinity (frame {}, channel {})",
            i / channels,
            i % channels
        )));
    }
    if let Some(p) = positions {
        if p.len() != velocity.len() {
            return Err(Error::Shape(format!(
                "positions must have the shape of velocity ({} frames x {channels} channels), \
                 got {} values",
                velocity.len() / channels,
                p.len()
            )));
        }
        if let Some(i) = first_non_finite(p) {
            return Err(Error::NonFinite(format!(
                "positions contains NaN or infinity (frame {}, channel {})",
                i / channels,
                i % channels
            )));
        }
    }
    Ok(velocity.len() / channels)
}

/// Zero-velocity crossings of a `(frames, channels)` signal (row-major). Returns the fractional
/// frames and the channel of each crossing, sorted by channel then frame. See the module
/// documentation for the exact rules.
pub fn zero_velocity_crossings(
    velocity: &[f64],
    channels: usize,
    min_change: f64,
    positions: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<i64>)> {
    let frames = check_inputs(velocity, channels, min_change, positions)?;
    let mut out = Crossings::default();
    let mut cum = Vec::new();
    scan_trial(
        velocity, positions, channels, 0, frames, min_change, 0, &mut cum, &mut out,
    );
    Ok((out.frame, out.channel))
}

/// Trials per parallel task.
const TRIALS_PER_TASK: usize = 64;

/// Zero-velocity crossings of every trial of a ragged corpus (`velocity` `(total_frames,
/// channels)` row-major, `offsets` the first frame of each trial). Frames are relative to each
/// trial's first frame; the reference position of the significant-movement test restarts at
/// each trial's frame 0.
pub fn zero_velocity_crossings_ragged(
    velocity: &[f64],
    channels: usize,
    offsets: &[i64],
    min_change: f64,
    positions: Option<&[f64]>,
) -> Result<Crossings> {
    let frames = check_inputs(velocity, channels, min_change, positions)?;
    let bounds = trial_bounds(offsets, frames)?;
    let parts: Vec<Crossings> = bounds
        .par_chunks(TRIALS_PER_TASK)
        .enumerate()
        .map(|(k, chunk)| {
            let mut out = Crossings::default();
            let mut cum = Vec::new();
            for (j, &(s, e)) in chunk.iter().enumerate() {
                let trial = (k * TRIALS_PER_TASK + j) as i64;
                scan_trial(
                    velocity, positions, channels, s, e, min_change, trial, &mut cum, &mut out,
                );
            }
            out
        })
        .collect();
    let n: usize = parts.iter().map(|p| p.frame.len()).sum();
    let mut all = Crossings {
        trial: Vec::with_capacity(n),
        channel: Vec::with_capacity(n),
        frame: Vec::with_capacity(n),
    };
    for p in parts {
        all.trial.extend(p.trial);
        all.channel.extend(p.channel);
        all.frame.extend(p.frame);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(v: &[f64], min_change: f64, p: Option<&[f64]>) -> Vec<f64> {
        zero_velocity_crossings(v, 1, min_change, p).unwrap().0
    }

    #[test]
    fn interpolated_root_between_frames() {
        // v goes 1 -> -3 between frames 1 and 2: root at 1 + 1/4.
        assert_eq!(one(&[2.0, 1.0, -3.0, -1.0], 0.0, None), vec![1.25]);
        // and back up between frames 3 and 4: -1 -> 1, root at 3.5.
        assert_eq!(one(&[2.0, 1.0, -3.0, -1.0, 1.0], 0.0, None), vec![1.25, 3.5]);
    }

    #[test]
    fn exact_zeros() {
        // A single zero between opposite signs: the crossing is that frame.
        assert_eq!(one(&[1.0, 0.0, -1.0], 0.0, None), vec![1.0]);
        // A run of zeros: its middle.
        assert_eq!(one(&[1.0, 0.0, 0.0, -1.0], 0.0, None), vec![1.5]);
        assert_eq!(one(&[1.0, 0.0, 0.0, 0.0, -1.0], 0.0, None), vec![2.0]);
        // Touching zero and returning, and zeros at the ends: nothing.
        assert!(one(&[1.0, 0.0, 2.0], 0.0, None).is_empty());
        assert!(one(&[0.0, 0.0, 1.0, 2.0, 0.0], 0.0, None).is_empty());
        assert!(one(&[0.0; 4], 0.0, None).is_empty());
    }

    #[test]
    fn significant_movement_threshold_uses_last_kept_crossing() {
        // positions: 0, 10, 9, 9.5, 0 ; velocity signs: +, -, +, - around them.
        let p = [0.0, 10.0, 9.0, 9.5, 0.0];
        let v = [1.0, 1.0, -1.0, 1.0, -1.0];
        // Crossings at 1.5 (p 9.5), 2.5 (p 9.25), 3.5 (p 4.75) without a threshold.
        assert_eq!(one(&v, 0.0, Some(&p)), vec![1.5, 2.5, 3.5]);
        // min_change 2: 1.5 kept (|9.5 - 0| > 2), 2.5 dropped (|9.25 - 9.5|), 3.5 kept (|4.75 -
        // 9.5| > 2).
        assert_eq!(one(&v, 2.0, Some(&p)), vec![1.5, 3.5]);
        // min_change 5: 3.5 is 4.75 away from 9.5: dropped.
        assert_eq!(one(&v, 5.0, Some(&p)), vec![1.5]);
        // min_change 9.5: |9.5 - 0| is not > 9.5.
        assert!(one(&v, 9.5, Some(&p)).is_empty());
    }

    #[test]
    fn default_positions_are_the_running_sum() {
        // cumsum: 3, 4, 2, 1.5 ; crossing between frames 1 and 2 at 1 + 1/3 -> p = 4 - 2/3.
        let v = [3.0, 1.0, -2.0, -0.5];
        assert_eq!(one(&v, 0.0, None), vec![1.0 + 1.0 / 3.0]);
        // |p - p[0]| = |3.333 - 3| = 0.333: kept at 0.3, dropped at 0.34.
        assert_eq!(one(&v, 0.3, None).len(), 1);
        assert!(one(&v, 0.34, None).is_empty());
    }

    #[test]
    fn channels_and_ragged_trials() {
        // Two channels, trials of 3 and 4 frames.
        #[rustfmt::skip]
        let v = [
            1.0, -1.0,
            -1.0, -1.0,
            -1.0, 1.0,
            // trial 1 starts: a sign change across the trial boundary does not count.
            1.0, 1.0,
            1.0, 1.0,
            -1.0, 1.0,
            -1.0, -3.0,
        ];
        let (frames, channels) = zero_velocity_crossings(&v, 2, 0.0, None).unwrap();
        assert_eq!(channels, vec![0, 0, 0, 1, 1]);
        assert_eq!(frames, vec![0.5, 2.5, 4.5, 1.5, 5.25]);
        let r = zero_velocity_crossings_ragged(&v, 2, &[0, 3], 0.0, None).unwrap();
        assert_eq!(r.trial, vec![0, 0, 1, 1]);
        assert_eq!(r.channel, vec![0, 1, 0, 1]);
        assert_eq!(r.frame, vec![0.5, 1.5, 1.5, 2.25]);
    }

    #[test]
    fn invalid_input_is_refused() {
        assert!(matches!(
            zero_velocity_crossings(&[], 1, 0.0, None),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            zero_velocity_crossings(&[1.0, f64::NAN], 1, 0.0, None),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            zero_velocity_crossings(&[1.0, -1.0], 1, -1.0, None),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            zero_velocity_crossings(&[1.0, -1.0], 1, 0.0, Some(&[0.0])),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            zero_velocity_crossings_ragged(&[1.0, -1.0], 1, &[0, 2], 0.0, None),
            Err(Error::InvalidArgument(_))
        ));
    }
}
