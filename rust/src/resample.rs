//! Resampling of segments of a multichannel signal to a fixed number of samples.
//!
//! Segment `s` spans the fractional frame indices `[starts[s], ends[s]]` of `values`
//! `(frames, channels)`; it is sampled at `n` equally spaced points from start to end inclusive
//! (`numpy.linspace(start, end, n)`), each channel linearly interpolated between frames
//! (`numpy.interp(points, arange(frames), values[:, c])`). The output row of a segment is
//! channel-major: the `n` samples of channel 0, then of channel 1, ...

use rayon::prelude::*;

use crate::buffer;
use crate::checks::first_non_finite;
use crate::simd::Level;
use crate::{Error, Result};

/// Segments per parallel task.
const SEGMENTS_PER_TASK: usize = 256;

fn check(values: &[f64], channels: usize, starts: &[f64], ends: &[f64], n: usize) -> Result<()> {
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

/// Length `channels * n` of one output row, checked: it must not overflow and a row must fit
/// in memory (also when there are no segments, so that the output shape is representable).
pub fn output_row(channels: usize, n: usize) -> Result<usize> {
    buffer::elements::<f64>(&[channels, n], "one resampled segment")
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
    let level = crate::simd::level()?;
    check(values, channels, starts, ends, n)?;
    let row = output_row(channels, n)?;
    let len = buffer::elements::<f64>(&[starts.len(), channels, n], "the resampled segments")?;
    let mut out = buffer::try_zeroed_f64(len, "the resampled segments")?;
    if out.is_empty() {
        return Ok(out);
    }
    let kernel = pick_kernel(level, channels);
    out.par_chunks_mut(row.saturating_mul(SEGMENTS_PER_TASK))
        .enumerate()
        .for_each(|(k, chunk)| {
            let first = k * SEGMENTS_PER_TASK;
            let count = chunk.len() / row;
            kernel(
                values,
                channels,
                &starts[first..first + count],
                &ends[first..first + count],
                n,
                chunk,
            );
        });
    Ok(out)
}

/// Point `k` of a segment is `numpy.linspace(start, end, n)[k]` (`k * step + start`, the
/// last exactly `end`); on the frame grid 0, 1, ..., frames - 1 it falls in `[j, j + 1]`, `j =
/// min(floor(x), frames - 2)`. Returns `(j, x - j)`; the fraction is exactly 1 only for a point
/// on the last frame. Requires `0 <= start < end <= frames - 1` (checked by `check`).
#[inline(always)]
fn locate(k: usize, n: usize, start: f64, step: f64, end: f64, frames: usize) -> (usize, f64) {
    // Signed conversions: one instruction each (`n`, `frames` are far below 2^53).
    let x = if k == n - 1 {
        end
    } else {
        let x = k as i64 as f64 * step + start;
        // Never past `end` (rounding); never below `start >= 0`.
        if x > end {
            end
        } else {
            x
        }
    };
    // SAFETY: `0 <= x <= frames - 1`, finite and far inside the range of i64.
    let j = unsafe { x.to_int_unchecked::<i64>() }.min(frames as i64 - 2);
    (j as usize, x - j as f64)
}

/// Resamples segments into consecutive rows of `dst` (`C * n` each) for `C` channels known at
/// compile time: each point interpolates the `C` channels of two frames together into a
/// point-major scratch block, transposed to the channel-major row at the end. Each channel gets
/// numpy.interp's `(fp[j + 1] - fp[j]) * frac + fp[j]`; a point on the last frame takes that
/// frame's value exactly.
#[inline(always)]
fn resample_rows<const C: usize>(
    values: &[f64],
    starts: &[f64],
    ends: &[f64],
    n: usize,
    dst: &mut [f64],
) {
    let frames = values.len() / C;
    assert!(C >= 1 && n >= 2 && frames >= 2 && values.len() == frames * C);
    assert!(dst.len() == starts.len() * C * n && starts.len() == ends.len());
    // SAFETY: `[f64; C]` has the layout of `C` consecutive `f64` (same alignment), and
    // `values` holds exactly `frames * C` of them.
    let rows: &[[f64; C]] =
        unsafe { std::slice::from_raw_parts(values.as_ptr().cast::<[f64; C]>(), frames) };
    // Point-major scratch, padded to a multiple of 4 points for the transposition.
    let n4 = n.div_ceil(4) * 4;
    let mut tmp = vec![[0.0f64; C]; n4];
    for ((&start, &end), out) in starts.iter().zip(ends).zip(dst.chunks_exact_mut(C * n)) {
        let step = (end - start) / (n - 1) as f64;
        for (k, r) in tmp[..n].iter_mut().enumerate() {
            let (j, frac) = locate(k, n, start, step, end, frames);
            // SAFETY: `j <= frames - 2` (`locate`), so `j + 1 < frames`.
            let (lo, hi) = unsafe { (rows.get_unchecked(j), rows.get_unchecked(j + 1)) };
            let v: [f64; C] = std::array::from_fn(|c| (hi[c] - lo[c]) * frac + lo[c]);
            *r = if frac == 1.0 { *hi } else { v };
        }
        // Transpose 4 points at a time: `out[c * n + k] = tmp[k][c]`.
        for (kb, block) in tmp.chunks_exact(4).enumerate() {
            let k0 = kb * 4;
            let width = (n - k0).min(4);
            for c in 0..C {
                let col = [block[0][c], block[1][c], block[2][c], block[3][c]];
                if width == 4 {
                    let o: &mut [f64; 4] = (&mut out[c * n + k0..c * n + k0 + 4])
                        .try_into()
                        .expect("4 points");
                    *o = col;
                } else {
                    for (i, &v) in col[..width].iter().enumerate() {
                        out[c * n + k0 + i] = v;
                    }
                }
            }
        }
    }
}

/// [`resample_rows`] for any number of channels.
fn resample_rows_any(
    values: &[f64],
    channels: usize,
    starts: &[f64],
    ends: &[f64],
    n: usize,
    dst: &mut [f64],
) {
    let ch = channels;
    let frames = values.len() / ch;
    assert!(ch >= 1 && n >= 2 && frames >= 2 && dst.len() == starts.len() * ch * n);
    for ((&start, &end), out) in starts.iter().zip(ends).zip(dst.chunks_exact_mut(ch * n)) {
        let step = (end - start) / (n - 1) as f64;
        for k in 0..n {
            let (j, frac) = locate(k, n, start, step, end, frames);
            let lo = &values[j * ch..j * ch + ch];
            let hi = &values[j * ch + ch..j * ch + 2 * ch];
            for c in 0..ch {
                out[c * n + k] = if frac == 1.0 {
                    hi[c]
                } else {
                    (hi[c] - lo[c]) * frac + lo[c]
                };
            }
        }
    }
}

/// [`resample_rows`] for 4 channels with AVX2: the 4 channels of a point are interpolated in
/// one vector, and 4 points at a time are transposed in registers into the 4 channel rows.
/// Same arithmetic (`(hi - lo) * frac + lo`, no fused multiply-add).
///
/// SAFETY (caller): the CPU has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn resample4_avx2(values: &[f64], starts: &[f64], ends: &[f64], n: usize, dst: &mut [f64]) {
    use std::arch::x86_64::*;
    const C: usize = 4;
    let frames = values.len() / C;
    assert!(n >= 2 && frames >= 2 && values.len() == frames * C);
    assert!(dst.len() == starts.len() * C * n && starts.len() == ends.len());
    let base = values.as_ptr();
    for ((&start, &end), out) in starts.iter().zip(ends).zip(dst.chunks_exact_mut(C * n)) {
        let step = (end - start) / (n - 1) as f64;
        let point = |k: usize| {
            let (j, frac) = locate(k, n, start, step, end, frames);
            // SAFETY: `j + 1 < frames` (`locate`): rows j and j + 1 are inside `values`.
            unsafe {
                let lo = _mm256_loadu_pd(base.add(j * C));
                let hi = _mm256_loadu_pd(base.add(j * C + C));
                if frac == 1.0 {
                    hi
                } else {
                    let d = _mm256_sub_pd(hi, lo);
                    _mm256_add_pd(_mm256_mul_pd(d, _mm256_set1_pd(frac)), lo)
                }
            }
        };
        let optr = out.as_mut_ptr();
        let mut k = 0;
        while k + 4 <= n {
            let (r0, r1, r2, r3) = (point(k), point(k + 1), point(k + 2), point(k + 3));
            // SAFETY: `c * n + k + 3 < C * n = out.len()` for every channel c.
            unsafe {
                let t0 = _mm256_unpacklo_pd(r0, r1);
                let t1 = _mm256_unpackhi_pd(r0, r1);
                let t2 = _mm256_unpacklo_pd(r2, r3);
                let t3 = _mm256_unpackhi_pd(r2, r3);
                _mm256_storeu_pd(optr.add(k), _mm256_permute2f128_pd(t0, t2, 0x20));
                _mm256_storeu_pd(optr.add(n + k), _mm256_permute2f128_pd(t1, t3, 0x20));
                _mm256_storeu_pd(optr.add(2 * n + k), _mm256_permute2f128_pd(t0, t2, 0x31));
                _mm256_storeu_pd(optr.add(3 * n + k), _mm256_permute2f128_pd(t1, t3, 0x31));
            }
            k += 4;
        }
        while k < n {
            let mut v = [0.0f64; 4];
            // SAFETY: 4 values into a 4-array.
            unsafe { _mm256_storeu_pd(v.as_mut_ptr(), point(k)) };
            for (c, &x) in v.iter().enumerate() {
                out[c * n + k] = x;
            }
            k += 1;
        }
    }
}

type Kernel = fn(&[f64], usize, &[f64], &[f64], usize, &mut [f64]);

macro_rules! kernels {
    ($name:ident, $($feature:literal)?) => {
        /// [`resample_rows`] for 1, 2, 3, 4, 6, 8 or any number of channels.
        $(#[target_feature(enable = $feature)])?
        fn $name(
            values: &[f64],
            channels: usize,
            starts: &[f64],
            ends: &[f64],
            n: usize,
            dst: &mut [f64],
        ) {
            match channels {
                1 => resample_rows::<1>(values, starts, ends, n, dst),
                2 => resample_rows::<2>(values, starts, ends, n, dst),
                3 => resample_rows::<3>(values, starts, ends, n, dst),
                4 => resample_rows::<4>(values, starts, ends, n, dst),
                6 => resample_rows::<6>(values, starts, ends, n, dst),
                8 => resample_rows::<8>(values, starts, ends, n, dst),
                _ => resample_rows_any(values, channels, starts, ends, n, dst),
            }
        }
    };
}

kernels!(rows_portable,);
#[cfg(target_arch = "x86_64")]
kernels!(rows_avx2, "avx2,fma");
#[cfg(target_arch = "x86_64")]
kernels!(rows_avx512, "avx512f,avx512vl,avx2,fma");

/// The kernel for `channels` at `level` (one this CPU runs). The arithmetic is identical in
/// all: `x * y + z` is never contracted to a fused multiply-add by Rust, so every level gives
/// the same bits.
fn pick_kernel(level: Level, channels: usize) -> Kernel {
    assert!(crate::simd::cpu_runs(level), "{level:?} not available");
    match level {
        // SAFETY (all three): the CPU has the features the functions were compiled for.
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma | Level::Avx512 if channels == 4 => {
            |v, _, s, e, n, d| unsafe { resample4_avx2(v, s, e, n, d) }
        }
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => |v, c, s, e, n, d| unsafe { rows_avx512(v, c, s, e, n, d) },
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => |v, c, s, e, n, d| unsafe { rows_avx2(v, c, s, e, n, d) },
        _ => rows_portable,
    }
}

/// What the resampler runs at `level`, as `instruction_sets()` reports it.
pub fn instruction_set(level: Level) -> &'static str {
    match level {
        Level::Avx512 => "avx512f (4 channels: avx2)",
        Level::Avx2Fma => "avx2+fma",
        Level::Portable => "portable",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_signal_is_resampled_exactly() {
        // channel 0: 2 t, channel 1: 10 - t over 6 frames.
        let values: Vec<f64> = (0..6)
            .flat_map(|t| [2.0 * t as f64, 10.0 - t as f64])
            .collect();
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
    fn every_kernel_matches_the_plain_formula_bit_for_bit() {
        // Pseudo-random values, 1..=9 channels, segments ending on the last frame, odd n.
        let mut state = 99u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for channels in 1..=9 {
            let frames = 37;
            let values: Vec<f64> = (0..frames * channels).map(|_| next() * 4.0 - 2.0).collect();
            let last = (frames - 1) as f64;
            let mut starts = vec![0.0, 3.25, 10.0];
            let mut ends = vec![last, last, 10.5];
            for _ in 0..20 {
                let a = next() * last;
                let b = a + (last - a) * next().max(1e-3);
                starts.push(a);
                ends.push(b);
            }
            for n in [2usize, 5, 100, 101] {
                let mut want = vec![0.0; starts.len() * channels * n];
                resample_rows_any(&values, channels, &starts, &ends, n, &mut want);
                let got = resample_segments(&values, channels, &starts, &ends, n).unwrap();
                assert_eq!(got, want, "channels {channels} n {n}");
                for level in crate::simd::levels() {
                    let mut at = vec![0.0; want.len()];
                    pick_kernel(level, channels)(&values, channels, &starts, &ends, n, &mut at);
                    assert_eq!(at, want, "{level:?}, channels {channels} n {n}");
                }
                // The last point of a segment ending on the last frame is that frame.
                for c in 0..channels {
                    assert_eq!(want[c * n + n - 1], values[(frames - 1) * channels + c]);
                }
            }
        }
    }

    #[test]
    fn sizes_that_overflow_or_exceed_memory_are_refused() {
        let values = vec![0.0; 40];
        let huge = [
            (1usize << 62) + 1,
            1 << 62,
            (1 << 61) + 1,
            1 << 61,
            usize::MAX,
            1_000_000_000_000,
        ];
        for n in huge {
            for segments in [0usize, 1, 3] {
                let s = vec![0.0; segments];
                let e = vec![5.0; segments];
                let err = resample_segments(&values, 4, &s, &e, n).unwrap_err();
                assert!(matches!(err, Error::Memory(_)), "n {n}: {err:?}");
            }
            assert!(matches!(output_row(4, n), Err(Error::Memory(_))));
        }
        // Just representable: the check passes, the numbers are the product.
        assert_eq!(output_row(4, 1000).unwrap(), 4000);
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
