//! Causal resampling of a stream onto a uniform clock: a stream's frames at their own times
//! in, the frames every `period` seconds from its first frame out.
//!
//! Grid frame `n` is at `t₀ + n · period` (`t₀` the stream's first time; a product, not a
//! running sum, so the clock does not drift, as `visprim.io.resample_trial`'s). It is
//! emitted as soon as a frame at or after it has arrived: the input frame itself (its time
//! and values) when one falls on it (within a millionth of the period), else the linear interpolation of the two
//! input frames around it. Linear interpolation needs no later frame, so a grid frame waits
//! at most one input period, and the output does not depend on how the stream is cut into
//! chunks.
//!
//! Columns from `rotations_from` on are 3×3 matrices (row-major), rotations: an interpolated
//! one is brought back to the nearest rotation (its polar factor, by Newton's iteration
//! `X ← (X + X⁻ᵀ) / 2`), which for the small steps of a stream is the spherical interpolation
//! to third order in the step's angle.
//!
//! An input frame with a NaN or infinite value (an occluded marker) is left out and
//! counted: the grid frames around it are interpolated across the gap. A gap longer than
//! `max_gap` seconds between two kept frames (a long occlusion, a stalled stream) is not
//! bridged: the clock starts again at the frame after it, as a new stream, and the grid
//! frame index where it does is reported (`breaks`), so that the frames after it are
//! segmented afresh.
//!
//! Memory: the previous frame (`width` values); the output grows with the chunk.

use crate::buffer::{elements, try_filled};
use crate::{Error, Result};

/// Newton steps of the polar factor (an interpolated rotation is orthogonal to ~1e-3 at
/// most, and each step squares the error).
const POLAR_STEPS: usize = 6;

/// Grid frames out of [`StreamResampler::push`].
#[derive(Debug, Clone, Default)]
pub struct Resampled {
    /// Their times, seconds.
    pub times: Vec<f64>,
    /// The time of the input frame that completed each, seconds (≥ its time).
    pub arrivals: Vec<f64>,
    /// Their values, `(m, width)` row-major.
    pub rows: Vec<f64>,
    /// Input frames left out for a NaN or infinite value.
    pub dropped: usize,
    /// Whether the grid frames are the input frames, one for one (every input frame on
    /// the clock, none left out).
    pub unchanged: bool,
    /// Indices into `times` of the grid frames that start the clock again after a gap
    /// longer than `max_gap` (the input frame after the gap, at its own time).
    pub breaks: Vec<usize>,
}

/// The resampler's state (module docstring).
#[derive(Debug, Clone)]
pub struct StreamResampler {
    period: f64,
    width: usize,
    rotations_from: usize,
    /// Longest gap between kept frames that is interpolated across, seconds.
    max_gap: f64,
    /// The stream's first time (NaN before the first frame).
    origin: f64,
    /// Index of the next grid frame to emit.
    next: u64,
    prev_t: f64,
    prev: Vec<f64>,
}

impl StreamResampler {
    /// A resampler onto a clock of `period` seconds for frames of `width` values; columns
    /// from `rotations_from` (if any) to the end are 3×3 rotation matrices; gaps longer
    /// than `max_gap` seconds (infinite: none) start the clock again (module docstring).
    ///
    /// Errors: a period that is not positive and finite, a `max_gap` that is not positive,
    /// a width of 0, or rotation columns that are not whole 3×3 matrices (InvalidArgument).
    pub fn new(
        period: f64,
        width: usize,
        rotations_from: Option<usize>,
        max_gap: f64,
    ) -> Result<Self> {
        if !(period.is_finite() && period > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "period must be a positive number of seconds, got {period}"
            )));
        }
        if max_gap.is_nan() || max_gap <= 0.0 {
            return Err(Error::InvalidArgument(format!(
                "max_gap must be a positive number of seconds (or infinite), got {max_gap}"
            )));
        }
        if width == 0 {
            return Err(Error::InvalidArgument("width must be at least 1".into()));
        }
        let from = rotations_from.unwrap_or(width);
        if from > width || !(width - from).is_multiple_of(9) {
            return Err(Error::InvalidArgument(format!(
                "rotation columns {from}..{width} are not whole 3x3 matrices"
            )));
        }
        Ok(Self {
            period,
            width,
            rotations_from: from,
            max_gap,
            origin: f64::NAN,
            next: 0,
            prev_t: f64::NAN,
            prev: try_filled(width, 0.0, "previous frame")?,
        })
    }

    /// Values per frame.
    pub fn width(&self) -> usize {
        self.width
    }

    /// The clock's period, seconds.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Grid frames emitted so far.
    pub fn emitted(&self) -> u64 {
        self.next
    }

    /// Bytes held by the state.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.prev.capacity() * std::mem::size_of::<f64>()
    }

    /// Forget the stream.
    pub fn reset(&mut self) {
        self.origin = f64::NAN;
        self.next = 0;
        self.prev_t = f64::NAN;
    }

    /// The grid frames that the chunk `times` (k,) s, `rows` (k, width) completes: their
    /// times in `out.times`, the time of the input frame that completed each (its arrival)
    /// in `out.arrivals`, their values in `out.rows` (all cleared first).
    ///
    /// Errors (nothing changes): rows not `k · width` values (Shape); a time that is NaN or
    /// infinite (NonFinite); times that do not increase, within the chunk or from the
    /// previous chunk (InvalidArgument); output too large to allocate (Memory).
    pub fn push(&mut self, times: &[f64], rows: &[f64], out: &mut Resampled) -> Result<()> {
        out.times.clear();
        out.arrivals.clear();
        out.rows.clear();
        out.dropped = 0;
        out.unchanged = true;
        out.breaks.clear();
        let k = times.len();
        let want = elements::<f64>(&[k, self.width], "rows")?;
        if rows.len() != want {
            return Err(Error::Shape(format!(
                "rows: {} values where {k} frames of {} need {want}",
                rows.len(),
                self.width
            )));
        }
        if let Some(i) = times.iter().position(|t| !t.is_finite()) {
            return Err(Error::NonFinite(format!(
                "timestamps must be finite (frame {i} of the chunk is {})",
                times[i]
            )));
        }
        let mut last = self.prev_t;
        for (i, &t) in times.iter().enumerate() {
            if t <= last {
                return Err(Error::InvalidArgument(format!(
                    "timestamps must increase: {t} s (frame {i} of the chunk) follows {last} s"
                )));
            }
            last = t;
        }
        if k == 0 {
            return Ok(());
        }
        // Grid frames up to the chunk's last time, a bound for the allocation.
        let w = self.width;
        let complete = |i: &usize| rows[i * w..(i + 1) * w].iter().all(|v| v.is_finite());
        let Some(first) = (0..k).find(complete) else {
            out.dropped = k;
            out.unchanged = false;
            return Ok(());
        };
        let origin = if self.origin.is_nan() {
            times[first]
        } else {
            self.origin
        };
        let span = (times[k - 1] - origin) / self.period;
        let upto = (span + 1e-6).floor() as u64 + 1;
        // A restart after a gap emits no more grid frames up to the chunk's end than the
        // old grid would, plus the restarting frame itself: at most k more.
        let m = usize::try_from(upto.saturating_sub(self.next))
            .ok()
            .and_then(|m| m.checked_add(k))
            .ok_or_else(|| Error::Memory("too many grid frames".into()))?;
        let rows_len = elements::<f64>(&[m, self.width], "resampled frames")?;
        for v in [&mut out.times, &mut out.arrivals] {
            v.try_reserve(m)
                .map_err(|_| Error::Memory(format!("cannot allocate {m} times")))?;
        }
        out.rows
            .try_reserve(rows_len)
            .map_err(|_| Error::Memory(format!("cannot allocate {rows_len} values")))?;
        // Checked: from here on the state changes.
        self.origin = origin;
        let eps = 1e-6 * self.period;
        for (i, &t) in times.iter().enumerate() {
            let row = &rows[i * w..(i + 1) * w];
            if !row.iter().all(|v| v.is_finite()) {
                out.dropped += 1;
                out.unchanged = false;
                continue;
            }
            let before = out.times.len();
            if t - self.prev_t > self.max_gap {
                // Too long a gap to bridge: the clock starts again here (module docstring).
                self.origin = t;
                self.next = 0;
                self.prev_t = f64::NAN;
                out.breaks.push(before);
            }
            loop {
                let g = self.origin + self.next as f64 * self.period;
                if g > t + eps {
                    break;
                }
                let on_it = (g - t).abs() <= eps || self.prev_t.is_nan();
                if on_it {
                    out.rows.extend_from_slice(row);
                } else {
                    let a = (g - self.prev_t) / (t - self.prev_t);
                    let start = out.rows.len();
                    out.rows
                        .extend(self.prev.iter().zip(row).map(|(p, x)| p + a * (x - p)));
                    for r in out.rows[start + self.rotations_from..start + w].chunks_exact_mut(9) {
                        nearest_rotation(r);
                    }
                }
                out.unchanged &= on_it && out.times.len() == before;
                out.times.push(if on_it { t } else { g });
                out.arrivals.push(t);
                self.next += 1;
            }
            out.unchanged &= out.times.len() == before + 1;
            self.prev.copy_from_slice(row);
            self.prev_t = t;
        }
        Ok(())
    }
}

/// `m` (3×3, row-major) replaced by its polar factor, the nearest orthogonal matrix (left
/// as it is when it is singular).
fn nearest_rotation(m: &mut [f64]) {
    for _ in 0..POLAR_STEPS {
        let [a, b, c, d, e, f, g, h, i] = [m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]];
        // Cofactors: X⁻ᵀ = cof(X) / det(X).
        let cof = [
            e * i - f * h,
            f * g - d * i,
            d * h - e * g,
            c * h - b * i,
            a * i - c * g,
            b * g - a * h,
            b * f - c * e,
            c * d - a * f,
            a * e - b * d,
        ];
        let det = a * cof[0] + b * cof[1] + c * cof[2];
        if det.abs() < 1e-12 || !det.is_finite() {
            return;
        }
        for (x, y) in m.iter_mut().zip(cof) {
            *x = 0.5 * (*x + y / det);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(r: &mut StreamResampler, times: &[f64], rows: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut out = Resampled::default();
        r.push(times, rows, &mut out).unwrap();
        for (g, a) in out.times.iter().zip(&out.arrivals) {
            assert!(*a >= g - 1e-9 && times.contains(a));
        }
        (out.times, out.rows)
    }

    #[test]
    fn a_stream_on_the_clock_comes_out_unchanged() {
        let times: Vec<f64> = (0..10).map(|n| 0.5 + n as f64 * 0.034).collect();
        let rows: Vec<f64> = (0..20).map(|v| (v as f64).sin()).collect();
        let mut r = StreamResampler::new(0.034, 2, None, f64::INFINITY).unwrap();
        let (t, x) = run(&mut r, &times, &rows);
        assert_eq!((t, x), (times, rows));
    }

    #[test]
    fn linear_motion_is_sampled_exactly_and_chunks_do_not_matter() {
        // 60 Hz input of x = 2 t + 1 onto a 34 ms clock.
        let times: Vec<f64> = (0..61).map(|n| n as f64 / 60.0).collect();
        let rows: Vec<f64> = times.iter().map(|t| 2.0 * t + 1.0).collect();
        let mut r = StreamResampler::new(0.034, 1, None, f64::INFINITY).unwrap();
        let (t, x) = run(&mut r, &times, &rows);
        assert_eq!(t.len(), 30); // 0, 0.034, ..., 0.986 ≤ 1 s
        for (g, v) in t.iter().zip(&x) {
            assert!((v - (2.0 * g + 1.0)).abs() < 1e-12);
        }
        for cut in [1usize, 2, 7, 60] {
            let mut r = StreamResampler::new(0.034, 1, None, f64::INFINITY).unwrap();
            let (mut tt, mut xx) = (Vec::new(), Vec::new());
            for a in (0..times.len()).step_by(cut) {
                let b = (a + cut).min(times.len());
                let (t1, x1) = run(&mut r, &times[a..b], &rows[a..b]);
                tt.extend(t1);
                xx.extend(x1);
            }
            assert_eq!(tt, t);
            assert_eq!(xx, x);
        }
        assert_eq!(r.emitted(), 30);
    }

    #[test]
    fn an_interpolated_rotation_is_a_rotation_between_the_two() {
        let rot = |th: f64| {
            let (s, c) = th.sin_cos();
            vec![c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]
        };
        let mut rows = vec![7.0];
        rows.extend(rot(0.0));
        rows.push(9.0);
        rows.extend(rot(0.2));
        let mut r = StreamResampler::new(0.5, 10, Some(1), f64::INFINITY).unwrap();
        let (t, x) = run(&mut r, &[0.0, 1.0], &rows);
        assert_eq!(t, vec![0.0, 0.5, 1.0]);
        let mid = &x[10..20];
        assert!((mid[0] - 8.0).abs() < 1e-12);
        let want = rot(0.1); // the polar factor of the mean of two rotations about one axis
        for (a, b) in mid[1..].iter().zip(&want) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
    }

    #[test]
    fn frames_with_missing_values_are_left_out_and_interpolated_across() {
        let mut r = StreamResampler::new(0.1, 2, None, f64::INFINITY).unwrap();
        let mut out = Resampled::default();
        let rows = [0.0, 0.0, f64::NAN, 1.0, 2.0, 2.0, 3.0, 3.0];
        r.push(&[0.0, 0.1, 0.2, 0.3], &rows, &mut out).unwrap();
        assert_eq!((out.dropped, out.unchanged), (1, false));
        assert_eq!(out.times.len(), 4);
        assert!((out.rows[2] - 1.0).abs() < 1e-12 && (out.rows[3] - 1.0).abs() < 1e-12);
        assert_eq!(out.arrivals[1], 0.2);
        r.push(&[0.4, 0.5], &[4.0, 4.0, 5.0, 5.0], &mut out)
            .unwrap();
        assert_eq!((out.dropped, out.unchanged), (0, true));
        let mut fresh = StreamResampler::new(0.1, 1, None, f64::INFINITY).unwrap();
        fresh
            .push(&[0.0, 0.05], &[f64::NAN, 1.0], &mut out)
            .unwrap();
        assert_eq!((out.dropped, out.times.clone()), (1, vec![0.05]));
        fresh.push(&[0.1], &[f64::INFINITY], &mut out).unwrap();
        assert_eq!((out.dropped, out.times.len()), (1, 0));
    }

    #[test]
    fn a_gap_longer_than_max_gap_starts_the_clock_again() {
        // 0.1 s frames, a stall of 0.5 s (and a NaN frame that makes a 0.3 s gap): the clock
        // restarts at the frame after each gap longer than 0.25 s, at its own time.
        let times = [0.0, 0.1, 0.2, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2];
        let rows = [0.0, 1.0, 2.0, 7.0, 8.0, f64::NAN, f64::NAN, 11.0, 12.0];
        let want_t = vec![0.0, 0.1, 0.2, 0.7, 0.8, 1.1, 1.2];
        let mut r = StreamResampler::new(0.1, 1, None, 0.25).unwrap();
        let mut out = Resampled::default();
        r.push(&times, &rows, &mut out).unwrap();
        assert_eq!(out.breaks, vec![3, 5]);
        assert_eq!(out.dropped, 2);
        for (a, b) in out.times.iter().zip(&want_t) {
            assert!((a - b).abs() < 1e-12, "{a} {b}");
        }
        assert_eq!(out.rows, vec![0.0, 1.0, 2.0, 7.0, 8.0, 11.0, 12.0]);
        // Frame by frame: the same frames, the breaks where those frames are.
        let mut r = StreamResampler::new(0.1, 1, None, 0.25).unwrap();
        let (mut tt, mut breaks): (Vec<f64>, Vec<usize>) = (Vec::new(), Vec::new());
        for i in 0..times.len() {
            r.push(&times[i..=i], &rows[i..=i], &mut out).unwrap();
            breaks.extend(out.breaks.iter().map(|b| b + tt.len()));
            tt.extend(&out.times);
        }
        assert_eq!((tt.len(), breaks), (7, vec![3, 5]));
        // Without a limit the gap is interpolated across, on the first clock.
        let mut r = StreamResampler::new(0.1, 1, None, f64::INFINITY).unwrap();
        r.push(&times, &rows, &mut out).unwrap();
        assert!(out.breaks.is_empty());
        assert_eq!(out.times.len(), 13); // 0.0, 0.1, ..., 1.2
    }

    #[test]
    fn bad_input_is_refused_and_changes_nothing() {
        let mut r = StreamResampler::new(0.1, 1, None, f64::INFINITY).unwrap();
        run(&mut r, &[0.0, 0.1], &[1.0, 2.0]);
        let mut out = Resampled::default();
        assert!(matches!(
            r.push(&[0.1], &[3.0], &mut out),
            Err(Error::InvalidArgument(_))
        ));
        assert!(matches!(
            r.push(&[f64::NAN], &[1.0], &mut out),
            Err(Error::NonFinite(_))
        ));
        assert!(matches!(
            r.push(&[0.2, 0.3], &[1.0], &mut out),
            Err(Error::Shape(_))
        ));
        let (t2, x2) = run(&mut r, &[0.2], &[3.0]);
        assert_eq!((t2.len(), x2), (1, vec![3.0]));
        assert!(StreamResampler::new(0.0, 1, None, f64::INFINITY).is_err());
        assert!(StreamResampler::new(0.1, 0, None, f64::INFINITY).is_err());
        assert!(StreamResampler::new(0.1, 10, Some(2), f64::INFINITY).is_err());
        assert!(StreamResampler::new(0.1, 1, None, 0.0).is_err());
        assert!(StreamResampler::new(0.1, 1, None, f64::NAN).is_err());
    }
}
