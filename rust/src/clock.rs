//! Seconds to fractional frame indices on a ragged corpus's own timestamps.
//!
//! A time `t` of trial `k` (on that trial's clock) is clamped to the trial's first and last
//! timestamps and located by linear interpolation between the two frames around it: the result
//! is `i + (t - times[i]) / (times[i+1] - times[i])`, relative to the trial's first frame, in
//! `[0, n_k - 1]`.

use rayon::prelude::*;

use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// Queries per parallel task.
const QUERIES_PER_TASK: usize = 4096;

/// Fractional frame of `t` in one trial's strictly increasing timestamps `tt` (len >= 2).
#[inline]
fn frame_of(tt: &[f64], t: f64) -> f64 {
    let n = tt.len();
    let q = t.clamp(tt[0], tt[n - 1]);
    let i = (tt.partition_point(|&x| x <= q) - 1).min(n - 2);
    let frac = (q - tt[i]) / (tt[i + 1] - tt[i]);
    i as f64 + frac.clamp(0.0, 1.0)
}

/// Fractional frame indices (relative to each trial's first frame) of the times `t` (seconds)
/// of trials `trial`, on the corpus timestamps `times` split by `offsets`. Each trial needs at
/// least two frames and strictly increasing timestamps (checked for the trials queried).
pub fn times_to_frames(
    times: &[f64],
    offsets: &[i64],
    trial: &[i64],
    t: &[f64],
) -> Result<Vec<f64>> {
    if trial.len() != t.len() {
        return Err(Error::Shape(format!(
            "trial and t must have the same length, got {} and {}",
            trial.len(),
            t.len()
        )));
    }
    let bounds = trial_bounds(offsets, times.len())?;
    if let Some(i) = t.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite(format!(
            "t contains NaN or infinity (query {i})"
        )));
    }
    if let Some(i) = trial
        .iter()
        .position(|&k| k < 0 || k as usize >= bounds.len())
    {
        return Err(Error::InvalidArgument(format!(
            "trial[{i}] = {} is not a trial index in [0, {})",
            trial[i],
            bounds.len()
        )));
    }
    // Check each queried trial once.
    let mut checked = vec![false; bounds.len()];
    for &k in trial {
        let k = k as usize;
        if std::mem::replace(&mut checked[k], true) {
            continue;
        }
        let (s, e) = bounds[k];
        if e - s < 2 {
            return Err(Error::InvalidArgument(format!(
                "trial {k} has fewer than 2 frames"
            )));
        }
        if let Some(j) = times[s..e]
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return Err(Error::InvalidArgument(format!(
                "times must be strictly increasing within a trial: trial {k}, frame {}",
                s + j + 1
            )));
        }
    }
    let mut out = vec![0.0; t.len()];
    out.par_chunks_mut(QUERIES_PER_TASK)
        .zip(trial.par_chunks(QUERIES_PER_TASK))
        .zip(t.par_chunks(QUERIES_PER_TASK))
        .for_each(|((out, trial), t)| {
            for ((o, &k), &x) in out.iter_mut().zip(trial).zip(t) {
                let (s, e) = bounds[k as usize];
                *o = frame_of(&times[s..e], x);
            }
        });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_clamps_per_trial() {
        // Trial 0: 0, 1, 3 s; trial 1: 0, 0.5 s.
        let times = [0.0, 1.0, 3.0, 0.0, 0.5];
        let f = times_to_frames(
            &times,
            &[0, 3],
            &[0, 0, 0, 0, 0, 1, 1],
            &[-1.0, 0.0, 0.5, 2.0, 9.0, 0.25, 0.5],
        )
        .unwrap();
        assert_eq!(f, vec![0.0, 0.0, 0.5, 1.5, 2.0, 0.5, 1.0]);
        assert!(times_to_frames(&times, &[0, 3], &[], &[])
            .unwrap()
            .is_empty());
    }

    #[test]
    fn invalid_input_is_refused() {
        let times = [0.0, 1.0, 1.0, 2.0];
        assert!(matches!(
            times_to_frames(&times, &[0], &[0], &[]),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            times_to_frames(&times, &[0], &[0], &[f64::NAN]),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            times_to_frames(&times, &[0], &[1], &[0.0]),
            Err(Error::InvalidArgument(_))
        ));
        let err = times_to_frames(&times, &[0], &[0], &[0.5]).unwrap_err();
        assert!(err.to_string().contains("strictly increasing"), "{err}");
        let err = times_to_frames(&times, &[0, 3], &[1], &[0.5]).unwrap_err();
        assert!(err.to_string().contains("fewer than 2 frames"), "{err}");
    }
}
