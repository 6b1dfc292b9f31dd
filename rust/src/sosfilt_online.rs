//! Causal second-order-section filtering of a multichannel stream, state kept between chunks.
//!
//! The online segmenter low-passes the arm angles once, forward, as frames arrive:
//! `scipy.signal.sosfilt` along time with its state carried from chunk to chunk, started in the
//! steady state of the first frame (`sosfilt_zi · x[0]`, per channel). [`CausalSos`] holds the
//! sections and the state (`n_sections × 2` values per channel) and filters row-major
//! `(frames, channels)` chunks in place with the recursion of [`crate::filter::sosfilt_scalar`]
//! (direct form II transposed, same operation order), so the output of a stream is the same
//! bit for bit however it is cut into chunks. Memory is fixed at construction.

use crate::filter::{sosfilt_zi, validate_sos, Sos};
use crate::{Error, Result};

/// A causal SOS filter of `channels` signals and its running state.
#[derive(Debug, Clone)]
pub struct CausalSos {
    sos: Vec<Sos>,
    zi: Vec<[f64; 2]>,
    channels: usize,
    /// `(channel, section)` states, channel-major; meaningful once `started`.
    state: Vec<[f64; 2]>,
    started: bool,
}

impl CausalSos {
    /// Sections (checked as `sosfilt` requires: finite, `a0 == 1`) for `channels` signals.
    pub fn new(sos: &[Sos], channels: usize) -> Result<Self> {
        validate_sos(sos)?;
        if channels == 0 {
            return Err(Error::Shape("channels must be at least 1".into()));
        }
        let len = channels
            .checked_mul(sos.len())
            .ok_or_else(|| Error::Memory("channels × sections overflows".into()))?;
        let mut state = Vec::new();
        state
            .try_reserve_exact(len)
            .map_err(|_| Error::Memory(format!("cannot allocate {len} filter states")))?;
        state.resize(len, [0.0; 2]);
        Ok(Self {
            sos: sos.to_vec(),
            zi: sosfilt_zi(sos),
            channels,
            state,
            started: false,
        })
    }

    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Bytes held by the sections and the state.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.sos.as_slice())
            + std::mem::size_of_val(self.zi.as_slice())
            + std::mem::size_of_val(self.state.as_slice())
    }

    /// Forget the stream: the next frame starts the steady state again.
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// Filter row-major `(frames, channels)` values in place (any number of frames).
    ///
    /// Errors: a length that is not a whole number of frames (Shape), NaN or infinity
    /// (NonFinite; nothing is changed then).
    pub fn filter(&mut self, x: &mut [f64]) -> Result<()> {
        let c = self.channels;
        if !x.len().is_multiple_of(c) {
            return Err(Error::Shape(format!(
                "{} values do not split into frames of {c} channels",
                x.len()
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite(format!(
                "frame {} channel {} is NaN or infinity",
                i / c,
                i % c
            )));
        }
        if x.is_empty() {
            return Ok(());
        }
        let n_sec = self.sos.len();
        if !self.started {
            for (states, &init) in self.state.chunks_exact_mut(n_sec).zip(&x[..c]) {
                for (z, zi) in states.iter_mut().zip(&self.zi) {
                    *z = [zi[0] * init, zi[1] * init];
                }
            }
            self.started = true;
        }
        for frame in x.chunks_exact_mut(c) {
            for (ch, v) in frame.iter_mut().enumerate() {
                let states = &mut self.state[ch * n_sec..(ch + 1) * n_sec];
                let mut cur = *v;
                for (s, z) in self.sos.iter().zip(states.iter_mut()) {
                    let new = s[0] * cur + z[0];
                    z[0] = s[1] * cur - s[4] * new + z[1];
                    z[1] = s[2] * cur - s[5] * new;
                    cur = new;
                }
                *v = cur;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::{butter_sos, sosfilt_scalar};

    fn signal(n: usize, channels: usize) -> Vec<f64> {
        (0..n * channels)
            .map(|i| {
                let (t, ch) = ((i / channels) as f64, (i % channels) as f64);
                (0.13 * t + ch).sin() + 0.3 * (0.71 * t * (ch + 1.0)).cos() + ch
            })
            .collect()
    }

    #[test]
    fn equals_the_scalar_sosfilt_per_channel_for_any_chunking() {
        let sos = butter_sos(4, 0.25).unwrap();
        let zi = sosfilt_zi(&sos);
        let (n, c) = (97, 3);
        let x = signal(n, c);
        let mut want = vec![0.0; n * c];
        for ch in 0..c {
            let mut col: Vec<f64> = (0..n).map(|t| x[t * c + ch]).collect();
            let init = col[0];
            sosfilt_scalar(&sos, &zi, &mut col, init);
            for t in 0..n {
                want[t * c + ch] = col[t];
            }
        }
        for chunk in [1usize, 7, 50, 97] {
            let mut f = CausalSos::new(&sos, c).unwrap();
            let mut got = x.clone();
            for part in got.chunks_mut(chunk * c) {
                f.filter(part).unwrap();
            }
            assert_eq!(got, want, "chunk {chunk}");
        }
    }

    #[test]
    fn starts_in_the_steady_state_and_reset_starts_again() {
        let sos = butter_sos(2, 0.25).unwrap();
        let mut f = CausalSos::new(&sos, 2).unwrap();
        let mut x = vec![1.5, -2.0, 1.5, -2.0, 1.5, -2.0];
        f.filter(&mut x).unwrap();
        for (got, want) in x.iter().zip([1.5, -2.0, 1.5, -2.0, 1.5, -2.0]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        f.reset();
        let mut y = vec![4.0, 4.0];
        f.filter(&mut y).unwrap();
        assert!((y[0] - 4.0).abs() < 1e-12 && (y[1] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn refuses_bad_input_and_changes_nothing() {
        let sos = butter_sos(2, 0.25).unwrap();
        assert!(CausalSos::new(&sos, 0).is_err());
        assert!(CausalSos::new(&[], 1).is_err());
        let mut f = CausalSos::new(&sos, 2).unwrap();
        assert!(matches!(
            f.filter(&mut [1.0, 2.0, 3.0]),
            Err(Error::Shape(_))
        ));
        let mut bad = [1.0, f64::NAN];
        assert!(matches!(f.filter(&mut bad), Err(Error::NonFinite(_))));
        assert!(bad[0] == 1.0);
        let mut ok = [3.0, 3.0];
        f.filter(&mut ok).unwrap(); // the failed calls did not start the stream
        assert!((ok[0] - 3.0).abs() < 1e-12);
    }
}
