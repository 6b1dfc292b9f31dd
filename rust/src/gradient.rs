//! Time derivative of a ragged multichannel signal on its own (non-uniform) timestamps.
//!
//! Per trial and channel this is `numpy.gradient(values, times, axis=0)` (its default
//! `edge_order=1`): with steps `h0 = t[i] - t[i-1]` and `h1 = t[i+1] - t[i]`, the interior
//! frames get the second-order weights for uneven steps,
//!
//! ```text
//! v[i] = -h1/(h0 (h0+h1)) x[i-1] + (h1-h0)/(h0 h1) x[i] + h0/(h1 (h0+h1)) x[i+1]
//! ```
//!
//! and the first and last frames one-sided differences `(x[1]-x[0])/h` and
//! `(x[n-1]-x[n-2])/h`. The operations (and their order) are numpy's, without fused
//! multiply-adds, so the results are bit-identical to `numpy.gradient`. Values are not checked
//! (NaN or infinity propagates, as in numpy); timestamps must be finite and strictly increasing
//! within each trial, and every trial needs at least two frames.

use rayon::prelude::*;

use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// Trials per parallel task.
const TRIALS_PER_TASK: usize = 64;

/// One parallel task: its first trial's index, the trials' frame ranges, their output rows.
type Task<'a> = (usize, &'a [(usize, usize)], &'a mut [f64]);

/// The error for the first non-finite or non-increasing timestamp of a trial, if any.
fn check_times(t: &[f64], trial: usize, first: usize) -> Result<()> {
    // Branch-free scan (vectorised); the exact location only when something is wrong.
    let ok = t[0].is_finite()
        & t.windows(2).fold(true, |ok, w| {
            ok & ((w[1] - w[0]) > 0.0) & (w[1] - w[0]).is_finite()
        });
    if ok {
        return Ok(());
    }
    if !t[0].is_finite() {
        return Err(Error::NonFinite(format!(
            "times contain NaN or infinity (trial {trial}, frame {first})"
        )));
    }
    for (j, w) in t.windows(2).enumerate() {
        let h = w[1] - w[0];
        if !(h > 0.0 && h.is_finite()) {
            let what = if w[1].is_finite() {
                "must be strictly increasing within a trial"
            } else {
                "contain NaN or infinity"
            };
            return Err(Error::InvalidArgument(format!(
                "times {what}: trial {trial}, frame {} (t = {} after {})",
                first + j + 1,
                w[1],
                w[0]
            )));
        }
    }
    Ok(())
}

/// Interior weights of one trial (reused buffers): `w[i] = (a, b, c)` for frame `i + 1`.
#[derive(Default)]
pub(crate) struct Weights {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
}

/// `numpy.gradient` of one trial: `t` (n,), `x` and `out` (n, channels) row-major, n >= 2.
fn gradient_trial(t: &[f64], x: &[f64], channels: usize, w: &mut Weights, out: &mut [f64]) {
    let c_n = channels;
    let n = t.len();
    let h_first = t[1] - t[0];
    for c in 0..c_n {
        out[c] = (x[c_n + c] - x[c]) / h_first;
    }
    // The weights first, in a loop without dependencies (vectorised divisions).
    let m = n - 2;
    w.a.resize(m, 0.0);
    w.b.resize(m, 0.0);
    w.c.resize(m, 0.0);
    let (t0, t1, t2) = (&t[..m], &t[1..m + 1], &t[2..m + 2]);
    let (wa, wb, wc) = (&mut w.a[..m], &mut w.b[..m], &mut w.c[..m]);
    for i in 0..m {
        let h0 = t1[i] - t0[i];
        let h1 = t2[i] - t1[i];
        wa[i] = -h1 / (h0 * (h0 + h1));
        wb[i] = (h1 - h0) / (h0 * h1);
        wc[i] = h0 / (h1 * (h0 + h1));
    }
    for i in 1..n - 1 {
        let (a, b, cc) = (wa[i - 1], wb[i - 1], wc[i - 1]);
        let prev = &x[(i - 1) * c_n..i * c_n];
        let here = &x[i * c_n..(i + 1) * c_n];
        let next = &x[(i + 1) * c_n..(i + 2) * c_n];
        let o = &mut out[i * c_n..(i + 1) * c_n];
        for c in 0..c_n {
            o[c] = a * prev[c] + b * here[c] + cc * next[c];
        }
    }
    let h_last = t[n - 1] - t[n - 2];
    for c in 0..c_n {
        out[(n - 1) * c_n + c] = (x[(n - 1) * c_n + c] - x[(n - 2) * c_n + c]) / h_last;
    }
}

/// Checks a ragged corpus for [`gradient_ragged`] (shapes, offsets, at least two frames per
/// trial) and returns each trial's frame range.
pub(crate) fn check_corpus(
    times: &[f64],
    values: &[f64],
    channels: usize,
    offsets: &[i64],
) -> Result<Vec<(usize, usize)>> {
    if channels == 0 || values.is_empty() {
        return Err(Error::Shape(
            "values is empty: need at least two frames and one channel".into(),
        ));
    }
    if !values.len().is_multiple_of(channels) {
        return Err(Error::Shape(format!(
            "values has {} entries, not a multiple of {channels} channels",
            values.len()
        )));
    }
    let frames = values.len() / channels;
    if times.len() != frames {
        return Err(Error::Shape(format!(
            "times must have one value per frame ({frames}), got {}",
            times.len()
        )));
    }
    let bounds = trial_bounds(offsets, frames)?;
    if let Some(k) = bounds.iter().position(|&(s, e)| e - s < 2) {
        return Err(Error::InvalidArgument(format!(
            "trial {k} has fewer than 2 frames (offsets[{k}] = {}): a derivative needs two",
            bounds[k].0
        )));
    }
    Ok(bounds)
}

/// The derivative of one trial into `out` after checking its timestamps (`trial` and `first`,
/// its index and first frame, name it in the error).
pub(crate) fn trial_gradient(
    t: &[f64],
    x: &[f64],
    channels: usize,
    (trial, first): (usize, usize),
    w: &mut Weights,
    out: &mut [f64],
) -> Result<()> {
    check_times(t, trial, first)?;
    gradient_trial(t, x, channels, w, out);
    Ok(())
}

/// Time derivative of every trial of a ragged corpus: `times` `(total_frames,)` seconds (each
/// trial's clock, strictly increasing within a trial), `values` `(total_frames, channels)`
/// row-major, `offsets` the first frame of each trial. Returns `(total_frames, channels)`
/// row-major, per trial equal to `numpy.gradient(values_i, times_i, axis=0)`.
pub fn gradient_ragged(
    times: &[f64],
    values: &[f64],
    channels: usize,
    offsets: &[i64],
) -> Result<Vec<f64>> {
    let bounds = check_corpus(times, values, channels, offsets)?;
    let mut out = crate::buffer::zeroed_f64(values.len());
    // Disjoint output slices, one per task of TRIALS_PER_TASK consecutive trials.
    let mut tasks: Vec<Task<'_>> = Vec::new();
    let mut rest: &mut [f64] = &mut out;
    for (k, chunk) in bounds.chunks(TRIALS_PER_TASK).enumerate() {
        let len = (chunk[chunk.len() - 1].1 - chunk[0].0) * channels;
        let (head, tail) = rest.split_at_mut(len);
        tasks.push((k * TRIALS_PER_TASK, chunk, head));
        rest = tail;
    }
    let results: Vec<Result<()>> = tasks
        .into_par_iter()
        .map(|(first_trial, chunk, out)| {
            let base = chunk[0].0;
            let mut w = Weights::default();
            for (j, &(s, e)) in chunk.iter().enumerate() {
                let t = &times[s..e];
                trial_gradient(
                    t,
                    &values[s * channels..e * channels],
                    channels,
                    (first_trial + j, s),
                    &mut w,
                    &mut out[(s - base) * channels..(e - base) * channels],
                )?;
            }
            Ok(())
        })
        .collect();
    // The first failing task in trial order reports (the same error whatever the threads).
    results.into_iter().collect::<Result<()>>()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quadratic_is_exact_on_uneven_steps() {
        // x = t^2: the uneven central difference is exact for a quadratic (2 t inside), the
        // one-sided ends give the slopes of the end intervals.
        let t = [0.0, 0.5, 2.0, 2.25, 4.0];
        let x: Vec<f64> = t.iter().map(|&s| s * s).collect();
        let v = gradient_ragged(&t, &x, 1, &[0]).unwrap();
        assert!((v[0] - 0.5).abs() < 1e-12); // (0.25 - 0) / 0.5
        for i in 1..4 {
            assert!((v[i] - 2.0 * t[i]).abs() < 1e-12, "frame {i}: {}", v[i]);
        }
        assert!((v[4] - (16.0 - 5.0625) / 1.75).abs() < 1e-12);
    }

    #[test]
    fn channels_and_trials_are_independent() {
        // Two channels (x = 3t and x = -t), trials of 2 and 3 frames: every slope exact, and
        // the jump between the trials does not leak.
        let t = [0.0, 0.1, 5.0, 5.2, 5.5];
        let x: Vec<f64> = t
            .iter()
            .enumerate()
            .flat_map(|(i, &s)| {
                let jump = if i >= 2 { 100.0 } else { 0.0 };
                [3.0 * s + jump, -s]
            })
            .collect();
        let v = gradient_ragged(&t, &x, 2, &[0, 2]).unwrap();
        for (i, pair) in v.chunks_exact(2).enumerate() {
            assert!((pair[0] - 3.0).abs() < 1e-9, "frame {i}: {pair:?}");
            assert!((pair[1] + 1.0).abs() < 1e-9, "frame {i}: {pair:?}");
        }
    }

    #[test]
    fn many_trials_over_several_tasks() {
        // More trials than one task holds; x = sin(t) per trial on jittered clocks.
        let lengths: Vec<usize> = (0..3 * TRIALS_PER_TASK + 5).map(|k| 2 + k % 9).collect();
        let mut times = Vec::new();
        let mut offsets = Vec::new();
        for &n in &lengths {
            offsets.push(times.len() as i64);
            times.extend((0..n).map(|i| i as f64 * 0.01 + (i % 3) as f64 * 1e-3));
        }
        let x: Vec<f64> = times.iter().map(|s| s.sin()).collect();
        let v = gradient_ragged(&times, &x, 1, &offsets).unwrap();
        for (k, &n) in lengths.iter().enumerate() {
            let s = offsets[k] as usize;
            let one = gradient_ragged(&times[s..s + n], &x[s..s + n], 1, &[0]).unwrap();
            assert_eq!(&v[s..s + n], &one[..], "trial {k}");
        }
    }

    #[test]
    fn invalid_input_is_refused() {
        let ok = [0.0, 1.0, 2.0];
        assert!(matches!(
            gradient_ragged(&ok, &[], 1, &[0]),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            gradient_ragged(&ok[..2], &ok, 1, &[0]),
            Err(Error::Shape(_))
        ));
        let err = gradient_ragged(&ok, &ok, 1, &[0, 2]).unwrap_err();
        assert!(err.to_string().contains("trial 1 has fewer than 2 frames"));
        let err = gradient_ragged(&[0.0, 1.0, 1.0], &ok, 1, &[0]).unwrap_err();
        assert!(err.to_string().contains("strictly increasing"), "{err}");
        let err = gradient_ragged(&[0.0, 1.0, f64::NAN], &ok, 1, &[0]).unwrap_err();
        assert!(err.to_string().contains("NaN"), "{err}");
        assert!(matches!(
            gradient_ragged(&[f64::INFINITY, 1.0, 2.0], &ok, 1, &[0]),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            gradient_ragged(&ok, &ok, 1, &[0, 3]),
            Err(Error::InvalidArgument(_))
        ));
    }
}
