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
use crate::{buffer, Error, Result};

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

impl Crossings {
    /// The crossings of `parts`, one after the other.
    ///
    /// Errors: the joined arrays cannot be allocated (Memory).
    fn concat(parts: Vec<Crossings>) -> Result<Self> {
        let n: usize = parts.iter().map(|p| p.frame.len()).sum();
        let what = "the zero-velocity crossings";
        let mut all = Crossings {
            trial: buffer::try_with_capacity(n, what)?,
            channel: buffer::try_with_capacity(n, what)?,
            frame: buffer::try_with_capacity(n, what)?,
        };
        for p in parts {
            all.trial.extend(p.trial);
            all.channel.extend(p.channel);
            all.frame.extend(p.frame);
        }
        Ok(all)
    }
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

/// Whether every value is finite. Eight independent accumulators of `v * 0` (NaN for NaN or
/// infinity, else 0) keep the loop branch-free and vectorised.
fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let mut chunks = x.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            acc[k] += c[k] * 0.0;
        }
    }
    let tail = chunks.remainder().iter().fold(0.0, |a, v| a + v * 0.0);
    acc.iter().sum::<f64>() + tail == 0.0
}

/// Whether consecutive samples need the exact rules: not both non-zero of one sign (a sign
/// change, a zero, or a product that underflows to zero).
#[inline(always)]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // the negation also flags NaN; clearer than partial_cmp
fn flagged(cur: f64, prev: f64) -> bool {
    !(cur * prev > 0.0)
}

/// Per-channel state of the scan of one trial.
#[derive(Clone, Copy, Default)]
struct ChannelState {
    /// Last non-zero sample `(frame, value)` before the current run of zeros.
    last_nonzero: Option<(usize, f64)>,
    /// Position of the significant-movement reference (frame 0, then the last kept crossing).
    reference: f64,
}

/// Reusable per-task buffers.
#[derive(Default)]
struct Scratch {
    cum: Vec<f64>,
    state: Vec<ChannelState>,
    per_channel: Vec<Vec<f64>>,
}

/// Crossings of every channel of one trial: `vel` and `pos` are the trial's `(len, channels)`
/// rows. Crossings are appended to `out` channel by channel. Returns false (and appends
/// nothing) if `vel` or `pos` holds NaN or infinity.
///
/// Most consecutive samples have the same sign; a vectorisable pass flags the others
/// (`!(v[t - 1] * v[t] > 0)`: a sign change, a zero, or an underflowing product) and only the
/// flagged samples run the exact rules.
fn scan_trial(
    vel: &[f64],
    pos: Option<&[f64]>,
    channels: usize,
    min_change: f64,
    trial: i64,
    scratch: &mut Scratch,
    out: &mut Crossings,
) -> bool {
    let c_n = channels;
    if !all_finite(vel) || !pos.is_none_or(all_finite) {
        return false;
    }
    let pos: &[f64] = match pos {
        Some(p) => p,
        None => {
            // Running sum per channel, restarting at the trial's first frame.
            let cum = &mut scratch.cum;
            cum.clear();
            cum.resize(vel.len(), 0.0);
            if c_n <= 8 {
                // Sums kept in registers: one add per value, the channels in parallel.
                let mut acc = [0.0f64; 8];
                for (row, out) in vel.chunks_exact(c_n).zip(cum.chunks_exact_mut(c_n)) {
                    for ((a, &v), o) in acc.iter_mut().zip(row).zip(out.iter_mut()) {
                        *a += v;
                        *o = *a;
                    }
                }
            } else {
                cum[..c_n].copy_from_slice(&vel[..c_n]);
                for i in c_n..vel.len() {
                    cum[i] = cum[i - c_n] + vel[i];
                }
            }
            &scratch.cum
        }
    };
    scratch.state.clear();
    scratch.state.extend((0..c_n).map(|c| ChannelState {
        last_nonzero: None,
        reference: pos[c],
    }));
    scratch.per_channel.resize_with(c_n, Vec::new);
    for list in &mut scratch.per_channel {
        list.clear();
    }
    let state = &mut scratch.state;
    let lists = &mut scratch.per_channel;
    let mut handle = |i: usize| {
        let (t, c) = (i / c_n, i % c_n);
        let (p, q) = (vel[i - c_n], vel[i]);
        let st = &mut state[c];
        let (i0, frac) = if q == 0.0 {
            if p != 0.0 {
                st.last_nonzero = Some((t - 1, p));
            }
            return;
        } else if p != 0.0 {
            if (p > 0.0) == (q > 0.0) {
                return; // same sign: the product underflowed
            }
            (t - 1, p / (p - q))
        } else {
            // The end of a run of zeros.
            match st.last_nonzero {
                Some((a, va)) if (va > 0.0) != (q > 0.0) => {
                    ((a + t) / 2, if (a + t) % 2 == 1 { 0.5 } else { 0.0 })
                }
                _ => return,
            }
        };
        let at = interp(|f| pos[f * c_n + c], i0, frac);
        if min_change == 0.0 || (at - st.reference).abs() > min_change {
            lists[c].push(i0 as f64 + frac);
            st.reference = at;
        }
    };
    const CHUNK: usize = 8;
    let n = vel.len();
    let mut i = c_n;
    while i + CHUNK <= n {
        let cur: &[f64; CHUNK] = vel[i..i + CHUNK].try_into().expect("chunk");
        let prev: &[f64; CHUNK] = vel[i - c_n..i - c_n + CHUNK].try_into().expect("chunk");
        let mut mask = 0u32;
        for k in 0..CHUNK {
            mask |= (flagged(cur[k], prev[k]) as u32) << k;
        }
        while mask != 0 {
            handle(i + mask.trailing_zeros() as usize);
            mask &= mask - 1;
        }
        i += CHUNK;
    }
    while i < n {
        if flagged(vel[i], vel[i - c_n]) {
            handle(i);
        }
        i += 1;
    }
    for (c, list) in scratch.per_channel.iter().enumerate() {
        out.frame.extend_from_slice(list);
        out.channel
            .extend(std::iter::repeat_n(c as i64, list.len()));
        out.trial.extend(std::iter::repeat_n(trial, list.len()));
    }
    true
}

/// The significant-movement threshold must be a finite number >= 0.
fn check_min_change(min_change: f64) -> Result<()> {
    if min_change.is_finite() && min_change >= 0.0 {
        return Ok(());
    }
    Err(Error::InvalidArgument(format!(
        "min_change must be a finite number >= 0, got {min_change}"
    )))
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
    if !velocity.len().is_multiple_of(channels) {
        return Err(Error::Shape(format!(
            "velocity has {} values, not a multiple of {channels} channels",
            velocity.len()
        )));
    }
    check_min_change(min_change)?;
    if let Some(p) = positions {
        if p.len() != velocity.len() {
            return Err(Error::Shape(format!(
                "positions must have the shape of velocity ({} frames x {channels} channels), \
                 got {} values",
                velocity.len() / channels,
                p.len()
            )));
        }
    }
    Ok(velocity.len() / channels)
}

/// The error for the first NaN or infinity of `velocity`, else of `positions`.
fn non_finite_error(velocity: &[f64], positions: Option<&[f64]>, channels: usize) -> Error {
    let (name, i) = match first_non_finite(velocity) {
        Some(i) => ("velocity", i),
        None => (
            "positions",
            positions
                .and_then(first_non_finite)
                .expect("a non-finite value was seen"),
        ),
    };
    Error::NonFinite(format!(
        "{name} contains NaN or infinity (frame {}, channel {})",
        i / channels,
        i % channels
    ))
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
    let c = zero_velocity_crossings_ragged(velocity, channels, &[0], min_change, positions)?;
    Ok((c.frame, c.channel))
}

/// Trials per parallel task.
const TRIALS_PER_TASK: usize = 64;

/// Zero-velocity crossings of every trial of a ragged corpus (`velocity` `(total_frames,
/// channels)` row-major, `offsets` the first frame of each trial). Frames are relative to each
/// trial's first frame; the reference position of the significant-movement test restarts at
/// each trial's frame 0, and so does the default running-sum position.
pub fn zero_velocity_crossings_ragged(
    velocity: &[f64],
    channels: usize,
    offsets: &[i64],
    min_change: f64,
    positions: Option<&[f64]>,
) -> Result<Crossings> {
    let frames = check_inputs(velocity, channels, min_change, positions)?;
    let bounds = trial_bounds(offsets, frames)?;
    let parts: Vec<Option<Crossings>> = bounds
        .par_chunks(TRIALS_PER_TASK)
        .enumerate()
        .map(|(k, chunk)| {
            let mut out = Crossings::default();
            let mut scratch = Scratch::default();
            for (j, &(s, e)) in chunk.iter().enumerate() {
                let trial = (k * TRIALS_PER_TASK + j) as i64;
                let (a, b) = (s * channels, e * channels);
                let pos = positions.map(|p| &p[a..b]);
                if !scan_trial(
                    &velocity[a..b],
                    pos,
                    channels,
                    min_change,
                    trial,
                    &mut scratch,
                    &mut out,
                ) {
                    return None;
                }
            }
            Some(out)
        })
        .collect();
    if parts.iter().any(Option::is_none) {
        return Err(non_finite_error(velocity, positions, channels));
    }
    Crossings::concat(parts.into_iter().flatten().collect())
}

/// [`zero_velocity_crossings_ragged`] of the velocity of `positions`: each trial's velocity is
/// [`crate::gradient`]'s (`numpy.gradient` on the trial's own `times`, seconds), computed
/// trial by trial into a small buffer instead of a corpus-sized array, and its crossings are
/// interpolated on `positions`. The result is identical to `gradient_ragged` followed by
/// `zero_velocity_crossings_ragged(velocity, ..., Some(positions))`.
pub fn zero_velocity_crossings_of_positions(
    times: &[f64],
    positions: &[f64],
    channels: usize,
    offsets: &[i64],
    min_change: f64,
) -> Result<Crossings> {
    let bounds = crate::gradient::check_corpus(times, positions, channels, offsets)?;
    check_min_change(min_change)?;
    let parts: Vec<Result<Crossings>> = bounds
        .par_chunks(TRIALS_PER_TASK)
        .enumerate()
        .map(|(k, chunk)| {
            let mut out = Crossings::default();
            let mut scratch = Scratch::default();
            let mut weights = Default::default();
            let mut vel = Vec::new();
            for (j, &(s, e)) in chunk.iter().enumerate() {
                let trial = k * TRIALS_PER_TASK + j;
                let (a, b) = (s * channels, e * channels);
                vel.clear();
                vel.resize(b - a, 0.0);
                let pos = &positions[a..b];
                crate::gradient::trial_gradient(
                    &times[s..e],
                    pos,
                    channels,
                    (trial, s),
                    &mut weights,
                    &mut vel,
                )?;
                let (pos, vel) = (Some(pos), &vel[..]);
                if !scan_trial(
                    vel,
                    pos,
                    channels,
                    min_change,
                    trial as i64,
                    &mut scratch,
                    &mut out,
                ) {
                    let (name, i) = match first_non_finite(&positions[a..b]) {
                        Some(i) => ("positions", i),
                        None => (
                            "the velocity of positions",
                            first_non_finite(vel).unwrap_or(0),
                        ),
                    };
                    return Err(Error::NonFinite(format!(
                        "{name} contains NaN or infinity (frame {}, channel {})",
                        s + i / channels,
                        i % channels
                    )));
                }
            }
            Ok(out)
        })
        .collect();
    Crossings::concat(parts.into_iter().collect::<Result<_>>()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules of the module documentation, one channel at a time, written plainly: the
    /// reference of the flagged scan.
    fn reference(
        v: &[f64],
        channels: usize,
        min_change: f64,
        p: Option<&[f64]>,
    ) -> Vec<(i64, f64)> {
        let frames = v.len() / channels;
        let mut out = Vec::new();
        for c in 0..channels {
            let vel = |t: usize| v[t * channels + c];
            let cum: Vec<f64> = (0..frames)
                .scan(0.0, |acc, t| {
                    *acc += vel(t);
                    Some(*acc)
                })
                .collect();
            let pos = |t: usize| p.map_or(cum[t], |p| p[t * channels + c]);
            let mut reference = pos(0);
            let mut last: Option<(usize, f64)> = None;
            for t in 0..frames {
                let x = vel(t);
                if x == 0.0 {
                    continue;
                }
                if let Some((a, va)) = last {
                    if (va > 0.0) != (x > 0.0) {
                        let (i0, frac) = if t == a + 1 {
                            (a, va / (va - x))
                        } else {
                            ((a + t) / 2, if (a + t) % 2 == 1 { 0.5 } else { 0.0 })
                        };
                        let at = interp(pos, i0, frac);
                        if min_change == 0.0 || (at - reference).abs() > min_change {
                            out.push((c as i64, i0 as f64 + frac));
                            reference = at;
                        }
                    }
                }
                last = Some((t, x));
            }
        }
        out
    }

    #[test]
    fn flagged_scan_matches_the_plain_rules() {
        // Pseudo-random velocities with many exact zeros, tiny values whose products
        // underflow, and sign changes; 1 to 5 channels; with and without positions.
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 33) as f64 / (1u64 << 31) as f64
        };
        for case in 0..300 {
            let channels = 1 + case % 5;
            let frames = 1 + (case * 7) % 40;
            let v: Vec<f64> = (0..frames * channels)
                .map(|_| {
                    let r = next();
                    if r < 0.25 {
                        0.0
                    } else if r < 0.35 {
                        (next() - 0.5) * 1e-200
                    } else {
                        next() - 0.5
                    }
                })
                .collect();
            let p: Vec<f64> = (0..frames * channels).map(|_| next() * 3.0).collect();
            for &min_change in &[0.0, 0.05, 0.5] {
                for pos in [None, Some(&p[..])] {
                    let (frames_got, chans_got) =
                        zero_velocity_crossings(&v, channels, min_change, pos).unwrap();
                    let got: Vec<(i64, f64)> = chans_got.into_iter().zip(frames_got).collect();
                    assert_eq!(got, reference(&v, channels, min_change, pos), "case {case}");
                }
            }
        }
    }

    fn one(v: &[f64], min_change: f64, p: Option<&[f64]>) -> Vec<f64> {
        zero_velocity_crossings(v, 1, min_change, p).unwrap().0
    }

    #[test]
    fn interpolated_root_between_frames() {
        // v goes 1 -> -3 between frames 1 and 2: root at 1 + 1/4.
        assert_eq!(one(&[2.0, 1.0, -3.0, -1.0], 0.0, None), vec![1.25]);
        // and back up between frames 3 and 4: -1 -> 1, root at 3.5.
        assert_eq!(
            one(&[2.0, 1.0, -3.0, -1.0, 1.0], 0.0, None),
            vec![1.25, 3.5]
        );
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
    fn from_positions_equals_gradient_then_crossings() {
        // Three trials of two channels on jittered clocks, with exact zeros and plateaus.
        let lengths = [40usize, 2, 57];
        let mut times = Vec::new();
        let mut pos = Vec::new();
        let mut offsets = Vec::new();
        let mut t = 0.0;
        for (k, &n) in lengths.iter().enumerate() {
            offsets.push(times.len() as i64);
            for f in 0..n {
                t += 0.03 + 0.01 * ((f * 7 + k) % 5) as f64;
                times.push(t);
                let x = f as f64 * 0.2;
                pos.push((x + k as f64).sin());
                pos.push(if (10..14).contains(&f) {
                    0.5
                } else {
                    (0.7 * x).cos()
                });
            }
        }
        let vel = crate::gradient::gradient_ragged(&times, &pos, 2, &offsets).unwrap();
        for min_change in [0.0, 0.05] {
            let want =
                zero_velocity_crossings_ragged(&vel, 2, &offsets, min_change, Some(&pos)).unwrap();
            let got = zero_velocity_crossings_of_positions(&times, &pos, 2, &offsets, min_change)
                .unwrap();
            assert!(!want.frame.is_empty());
            assert_eq!(got.trial, want.trial);
            assert_eq!(got.channel, want.channel);
            assert_eq!(got.frame, want.frame);
        }
        let mut bad = pos.clone();
        bad[2 * 45 + 1] = f64::NAN;
        let err = zero_velocity_crossings_of_positions(&times, &bad, 2, &offsets, 0.0).unwrap_err();
        assert!(
            err.to_string()
                .contains("positions contains NaN or infinity (frame 45, channel 1)"),
            "{err}"
        );
        let mut clock = times.clone();
        clock[50] = clock[49];
        let err = zero_velocity_crossings_of_positions(&clock, &pos, 2, &offsets, 0.0).unwrap_err();
        assert!(err.to_string().contains("strictly increasing"), "{err}");
        let err =
            zero_velocity_crossings_of_positions(&times, &pos, 2, &offsets, -1.0).unwrap_err();
        assert!(matches!(err, Error::InvalidArgument(_)), "{err}");
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
