//! SEG-1 events: the zero-velocity crossings (ZVCs) of all channels of a trial merged along
//! time.
//!
//! Within each trial the crossings are taken in time order (ties keep their input order) and
//! grouped by single linkage: a crossing less than `window` seconds after the previous one
//! joins its event, otherwise it starts a new event (`t[i] - t[i-1] >= window`). Each event has
//! the **median** time of its crossings (the mean of the two middle ones for an even count)
//! and the number of distinct channels among them. Events never span two trials.

use rayon::prelude::*;

use crate::{buffer, Error, Result};

/// Events of a corpus, sorted by trial then time.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Events {
    /// Trial index of each event.
    pub trial: Vec<i64>,
    /// Median time of the event's crossings (seconds).
    pub time: Vec<f64>,
    /// Number of distinct channels with a crossing in the event.
    pub n_channels: Vec<i64>,
}

/// Trials per parallel task.
const TRIALS_PER_TASK: usize = 256;

/// Reusable per-task buffers.
#[derive(Default)]
struct Scratch {
    /// `(time, channel)` of the current trial, sorted by time.
    items: Vec<(f64, i64)>,
    /// Distinct channels of the current event (when some channel is >= 64).
    seen: Vec<i64>,
}

/// Distinct channels among `items`.
fn distinct_channels(items: &[(f64, i64)], seen: &mut Vec<i64>) -> i64 {
    if items.iter().all(|&(_, c)| c < 64) {
        let mask = items.iter().fold(0u64, |m, &(_, c)| m | (1u64 << c));
        return i64::from(mask.count_ones());
    }
    seen.clear();
    seen.extend(items.iter().map(|&(_, c)| c));
    seen.sort_unstable();
    seen.dedup();
    seen.len() as i64
}

/// Appends the events of one trial (crossings `time`, `channel`) to `out`.
fn trial_events(
    trial: i64,
    time: &[f64],
    channel: &[i64],
    window: f64,
    scratch: &mut Scratch,
    out: &mut Events,
) {
    let items = &mut scratch.items;
    items.clear();
    items.extend(time.iter().copied().zip(channel.iter().copied()));
    // Stable: crossings at equal times keep their input order. Times are finite (checked).
    items.sort_by(|a, b| a.0.partial_cmp(&b.0).expect("finite times"));
    let mut first = 0;
    for i in 1..=items.len() {
        if i < items.len() && items[i].0 - items[i - 1].0 < window {
            continue;
        }
        let ev = &items[first..i];
        let count = ev.len();
        out.trial.push(trial);
        out.time
            .push(0.5 * (ev[(count - 1) / 2].0 + ev[count / 2].0));
        out.n_channels
            .push(distinct_channels(ev, &mut scratch.seen));
        first = i;
    }
}

/// Groups the crossings of a corpus into events (see the module documentation). `trial`,
/// `channel` and `time` (seconds) describe one crossing each; `trial` must be non-decreasing
/// (crossings grouped by trial, in any order within a trial), `channel` >= 0, `time` finite,
/// `window` > 0 seconds.
pub fn seg1_events(trial: &[i64], channel: &[i64], time: &[f64], window: f64) -> Result<Events> {
    if channel.len() != trial.len() || time.len() != trial.len() {
        return Err(Error::Shape(format!(
            "trial, channel and time must have the same length, got {}, {} and {}",
            trial.len(),
            channel.len(),
            time.len()
        )));
    }
    if !(window.is_finite() && window > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "window must be a positive number of seconds, got {window}"
        )));
    }
    if let Some(i) = time.iter().position(|t| !t.is_finite()) {
        return Err(Error::NonFinite(format!(
            "time contains NaN or infinity (crossing {i})"
        )));
    }
    if let Some(i) = channel.iter().position(|&c| c < 0) {
        return Err(Error::InvalidArgument(format!(
            "channel must be >= 0, got {} (crossing {i})",
            channel[i]
        )));
    }
    if let Some(i) = trial.windows(2).position(|w| w[1] < w[0]) {
        return Err(Error::InvalidArgument(format!(
            "trial must be non-decreasing (crossings grouped by trial): trial[{}] = {} \
             follows trial[{i}] = {}",
            i + 1,
            trial[i + 1],
            trial[i]
        )));
    }
    // Runs of equal trial: (start, end) into the crossings.
    let mut runs = Vec::new();
    let mut s = 0;
    for i in 1..=trial.len() {
        if i == trial.len() || trial[i] != trial[s] {
            runs.push((s, i));
            s = i;
        }
    }
    let parts: Vec<Events> = runs
        .par_chunks(TRIALS_PER_TASK)
        .map(|chunk| {
            let mut out = Events::default();
            let mut scratch = Scratch::default();
            for &(s, e) in chunk {
                trial_events(
                    trial[s],
                    &time[s..e],
                    &channel[s..e],
                    window,
                    &mut scratch,
                    &mut out,
                );
            }
            out
        })
        .collect();
    let n: usize = parts.iter().map(|p| p.trial.len()).sum();
    let what = "the SEG-1 events";
    let mut all = Events {
        trial: buffer::try_with_capacity(n, what)?,
        time: buffer::try_with_capacity(n, what)?,
        n_channels: buffer::try_with_capacity(n, what)?,
    };
    for p in parts {
        all.trial.extend(p.trial);
        all.time.extend(p.time);
        all.n_channels.extend(p.n_channels);
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_by_window_with_median_times() {
        // One trial, crossings given by channel then time (as the ZVC kernel returns them):
        // channel 0 at 1.0 and 3.0, channel 1 at 1.1 and 2.0, channel 2 at 1.25.
        let trial = [0, 0, 0, 0, 0];
        let channel = [0, 0, 1, 1, 2];
        let time = [1.0, 3.0, 1.1, 2.0, 1.25];
        let ev = seg1_events(&trial, &channel, &time, 0.3).unwrap();
        // In time order: 1.0, 1.1, 1.25 (one event: gaps 0.1, 0.15), 2.0, 3.0.
        assert_eq!(ev.trial, vec![0, 0, 0]);
        assert_eq!(ev.time, vec![1.1, 2.0, 3.0]);
        assert_eq!(ev.n_channels, vec![3, 1, 1]);
        // A gap equal to the window starts a new event; an even count averages the middle.
        let ev = seg1_events(&[0, 0, 0], &[0, 1, 1], &[0.0, 0.25, 0.5], 0.25).unwrap();
        assert_eq!(ev.time, vec![0.0, 0.25, 0.5]);
        let ev = seg1_events(&[0, 0], &[0, 0], &[0.0, 0.2], 0.25).unwrap();
        assert_eq!((ev.time, ev.n_channels), (vec![0.1], vec![1]));
    }

    #[test]
    fn trials_do_not_merge_and_many_channels_count() {
        // Trial 0 ends at 1.0, trial 3 starts at 1.05 (each trial has its own clock).
        let ev = seg1_events(&[0, 3, 3], &[70, 70, 100], &[1.0, 1.05, 1.1], 0.3).unwrap();
        assert_eq!(ev.trial, vec![0, 3]);
        assert_eq!(ev.n_channels, vec![1, 2]);
        // Many trials over several tasks: one event of two channels each.
        let n = 3 * TRIALS_PER_TASK + 7;
        let trial: Vec<i64> = (0..n as i64).flat_map(|k| [k, k]).collect();
        let channel: Vec<i64> = (0..n).flat_map(|_| [0, 1]).collect();
        let time: Vec<f64> = (0..n).flat_map(|k| [k as f64, k as f64 + 0.1]).collect();
        let ev = seg1_events(&trial, &channel, &time, 0.3).unwrap();
        assert_eq!(ev.trial, (0..n as i64).collect::<Vec<_>>());
        assert!(ev.n_channels.iter().all(|&c| c == 2));
        assert!(ev
            .time
            .iter()
            .enumerate()
            .all(|(k, &t)| t == 0.5 * (k as f64 + (k as f64 + 0.1))));
        assert_eq!(seg1_events(&[], &[], &[], 0.3).unwrap(), Events::default());
    }

    #[test]
    fn invalid_input_is_refused() {
        assert!(matches!(
            seg1_events(&[0], &[0, 1], &[0.0], 0.3),
            Err(Error::Shape(_))
        ));
        assert!(matches!(
            seg1_events(&[0], &[0], &[0.0], 0.0),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            seg1_events(&[0], &[0], &[f64::NAN], 0.3),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            seg1_events(&[0], &[-1], &[0.0], 0.3),
            Err(Error::InvalidArgument(_))
        ));
        let err = seg1_events(&[1, 0], &[0, 0], &[0.0, 1.0], 0.3).unwrap_err();
        assert!(err.to_string().contains("non-decreasing"), "{err}");
    }
}
