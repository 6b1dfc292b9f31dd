//! Seconds and fractional frame indices on a ragged corpus's own timestamps.
//!
//! * [`times_to_frames`]: a time `t` of trial `k` (on that trial's clock) is clamped to the
//!   trial's first and last timestamps and located by linear interpolation between the two
//!   frames around it: the result is `i + (t - times[i]) / (times[i+1] - times[i])`, relative to
//!   the trial's first frame, in `[0, n_k - 1]`.
//! * [`frames_to_times`], the converse: a fractional frame `f` of trial `k` is
//!   `times[i] + (f - i) · (times[i+1] - times[i])` with `i = ⌊f⌋` kept inside the trial's
//!   frames (linear extrapolation from its first or last interval beyond them).

use rayon::prelude::*;

use crate::ragged::trial_bounds;
use crate::{Error, Result};

/// Queries per parallel task.
const QUERIES_PER_TASK: usize = 4096;

/// Checks the trials named in `trial`: indices in range, at least two frames each and, when
/// `increasing`, strictly increasing timestamps. Each queried trial is checked once, in
/// parallel; the error names the first bad query (a trial index) or the lowest bad trial.
fn check_trials(
    times: &[f64],
    bounds: &[(usize, usize)],
    trial: &[i64],
    increasing: bool,
) -> Result<()> {
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
    let mut queried = vec![false; bounds.len()];
    for &k in trial {
        queried[k as usize] = true;
    }
    let ids: Vec<usize> = (0..bounds.len()).filter(|&k| queried[k]).collect();
    let bad = ids.par_iter().find_first(|&&k| {
        let (s, e) = bounds[k];
        e - s < 2 || (increasing && !times[s..e].windows(2).all(|w| w[1] > w[0]))
    });
    let Some(&k) = bad else {
        return Ok(());
    };
    let (s, e) = bounds[k];
    if e - s < 2 {
        return Err(Error::InvalidArgument(format!(
            "trial {k} has fewer than 2 frames"
        )));
    }
    let j = times[s..e]
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        .unwrap_or(0);
    Err(Error::InvalidArgument(format!(
        "times must be strictly increasing within a trial: trial {k}, frame {}",
        s + j + 1
    )))
}

/// Seconds of the fractional frames `frame` (relative to each trial's first frame) of trials
/// `trial`, by linear interpolation of the corpus timestamps `times` split by `offsets`; frames
/// outside `[0, n_k - 1]` are extrapolated from the trial's first or last interval. Each
/// queried trial needs at least two frames.
pub fn frames_to_times(
    times: &[f64],
    offsets: &[i64],
    trial: &[i64],
    frame: &[f64],
) -> Result<Vec<f64>> {
    let bounds = check_queries(times, offsets, trial, frame, "frame", false)?;
    per_query(trial, frame, |k, f| {
        let (s, e) = bounds[k];
        // The same operations as numpy on the global frame index `s + f`.
        let g = s as f64 + f;
        let i = (g.floor().max(s as f64) as usize).min(e - 2);
        times[i] + (g - i as f64) * (times[i + 1] - times[i])
    })
}

/// The checks shared by both conversions: `trial` and the query values `q` (called `name`)
/// of equal length, `offsets` valid for `times`, finite queries, and the queried trials (see
/// [`check_trials`]). Returns each trial's frame range.
fn check_queries(
    times: &[f64],
    offsets: &[i64],
    trial: &[i64],
    q: &[f64],
    name: &str,
    increasing: bool,
) -> Result<Vec<(usize, usize)>> {
    if trial.len() != q.len() {
        return Err(Error::Shape(format!(
            "trial and {name} must have the same length, got {} and {}",
            trial.len(),
            q.len()
        )));
    }
    let bounds = trial_bounds(offsets, times.len())?;
    if let Some(i) = q.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite(format!(
            "{name} contains NaN or infinity (query {i})"
        )));
    }
    check_trials(times, &bounds, trial, increasing)?;
    Ok(bounds)
}

/// `f(trial[i], q[i])` for every query, in parallel chunks (`trial` already checked).
fn per_query(trial: &[i64], q: &[f64], f: impl Fn(usize, f64) -> f64 + Sync) -> Result<Vec<f64>> {
    let mut out = crate::buffer::try_zeroed_f64(q.len(), "the converted queries")?;
    out.par_chunks_mut(QUERIES_PER_TASK)
        .zip(trial.par_chunks(QUERIES_PER_TASK))
        .zip(q.par_chunks(QUERIES_PER_TASK))
        .for_each(|((out, trial), q)| {
            for ((o, &k), &x) in out.iter_mut().zip(trial).zip(q) {
                *o = f(k as usize, x);
            }
        });
    Ok(out)
}

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
    let bounds = check_queries(times, offsets, trial, t, "t", true)?;
    per_query(trial, t, |k, x| {
        let (s, e) = bounds[k];
        frame_of(&times[s..e], x)
    })
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
    fn frames_to_times_interpolates_and_extrapolates_per_trial() {
        // Trial 0: 0, 1, 3 s; trial 1: 10, 10.5 s.
        let times = [0.0, 1.0, 3.0, 10.0, 10.5];
        let got = frames_to_times(
            &times,
            &[0, 3],
            &[0, 0, 0, 0, 0, 1, 1, 1],
            &[0.0, 0.5, 1.5, 2.0, 2.5, -1.0, 0.5, 1.0],
        )
        .unwrap();
        // Beyond the last frame of trial 0: the last interval's slope (2 s per frame).
        assert_eq!(got, vec![0.0, 0.5, 2.0, 3.0, 4.0, 9.5, 10.25, 10.5]);
        // The converse of times_to_frames inside the trials.
        let t = [0.25, 2.5, 10.1];
        let f = times_to_frames(&times, &[0, 3], &[0, 0, 1], &t).unwrap();
        let back = frames_to_times(&times, &[0, 3], &[0, 0, 1], &f).unwrap();
        for (a, b) in back.iter().zip(t) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        let err = frames_to_times(&times, &[0, 3], &[0], &[f64::NAN]).unwrap_err();
        assert!(matches!(err, Error::NonFinite(_)), "{err}");
        let err = frames_to_times(&times, &[0, 4], &[1], &[0.0]).unwrap_err();
        assert!(err.to_string().contains("fewer than 2 frames"), "{err}");
        let err = frames_to_times(&times, &[0, 3], &[2], &[0.0]).unwrap_err();
        assert!(err.to_string().contains("not a trial index"), "{err}");
        let err = frames_to_times(&times, &[0, 3], &[0, 1], &[0.0]).unwrap_err();
        assert!(matches!(err, Error::Shape(_)), "{err}");
    }

    #[test]
    fn the_lowest_bad_trial_is_named() {
        // Trials 1 and 3 repeat a timestamp; the error names trial 1 whatever the query order.
        let mut times: Vec<f64> = (0..400).map(|i| (i % 100) as f64).collect();
        times[150] = times[149];
        times[350] = times[349];
        let offsets = [0, 100, 200, 300];
        let err = times_to_frames(&times, &offsets, &[3, 0, 1], &[1.0, 1.0, 1.0]).unwrap_err();
        assert!(err.to_string().contains("trial 1, frame 150"), "{err}");
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
