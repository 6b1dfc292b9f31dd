//! Lockstep engine of `sosfiltfilt`: many equal-length signals filtered at once.
//!
//! The biquad recursion of ONE signal is latency-bound (each output needs the previous state,
//! two dependent multiply-adds per sample and section). Here up to 32 signals (see [`lanes_at`]) of equal
//! length are copied into a lane-major block (`buf[t][lane]`, odd extension included), and the
//! recursion runs section by section over the block with the lanes innermost, so the inner loop
//! is plain element-wise SIMD over lanes and the lanes' dependency chains overlap. Blocks are
//! distributed over threads with rayon.
//!
//! The arithmetic per lane is scipy's `sosfilt` (direct form II transposed); the SIMD builds use
//! fused multiply-adds, which changes results only in the last bits. The instruction set is
//! chosen at run time (AVX-512F, AVX2+FMA, or portable code), not at build time.

use rayon::prelude::*;

/// Signals per block for the remainder of a group (at most this many signals left), and the
/// block width of the portable build.
const SMALL_LANES: usize = 8;
/// Whether sweeps fuse two sections (see [`run_block`]).
const FUSED: bool = true;

/// One second-order section with its `sosfilt_zi` initial state (per unit input).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    pub b0: f64,
    pub b1: f64,
    pub b2: f64,
    pub a1: f64,
    pub a2: f64,
    pub zi0: f64,
    pub zi1: f64,
}

/// Signals of equal length `len` inside a flat array: signal `j` is
/// `x[bases[j] + t * stride]` for `t in 0..len`. Signals must not overlap.
pub struct SignalGroup<'a> {
    pub bases: &'a [usize],
    pub stride: usize,
    pub len: usize,
}

/// The instruction set a kernel is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Portable,
    #[cfg(target_arch = "x86_64")]
    Avx2,
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Level {
    /// The best level this CPU supports.
    pub fn detect() -> Level {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Level::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Level::Avx2;
            }
        }
        Level::Portable
    }

    /// Every level this CPU can run (for tests and benchmarks).
    pub fn available() -> Vec<Level> {
        let mut v = vec![Level::Portable];
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                v.push(Level::Avx2);
            }
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("fma")
            {
                v.push(Level::Avx512);
            }
        }
        v
    }
}

/// One biquad step of one lane (direct form II transposed, scipy's `sosfilt`): returns the
/// output and updates the two state variables.
///
/// * `FMA = false`: scipy's expression order, bit for bit.
/// * `FMA = true`: the same recursion with fused multiply-adds.
/// * `UNIT = true` (only with FMA): a section with `b0 == 1` and `b2 == 1` (every Butterworth
///   section but the first); multiplying by those exact ones is skipped, which changes no bit of
///   the result but frees the FMA units for other lanes.
#[inline(always)]
fn biquad<const FMA: bool, const UNIT: bool>(
    s: &Section,
    x: f64,
    z0: &mut f64,
    z1: &mut f64,
) -> f64 {
    if FMA {
        if UNIT {
            let y = x + *z0;
            *z0 = (-s.a1).mul_add(y, s.b1.mul_add(x, *z1));
            *z1 = (-s.a2).mul_add(y, x);
            y
        } else {
            let y = s.b0.mul_add(x, *z0);
            *z0 = (-s.a1).mul_add(y, s.b1.mul_add(x, *z1));
            *z1 = (-s.a2).mul_add(y, s.b2 * x);
            y
        }
    } else {
        let y = s.b0 * x + *z0;
        *z0 = s.b1 * x - s.a1 * y + *z1;
        *z1 = s.b2 * x - s.a2 * y;
        y
    }
}

/// Lane states `zi * init` of one section.
#[inline(always)]
fn start_state<const W: usize>(s: &Section, init: &[f64; W]) -> ([f64; W], [f64; W]) {
    let mut z0 = [0.0; W];
    let mut z1 = [0.0; W];
    for l in 0..W {
        z0[l] = s.zi0 * init[l];
        z1[l] = s.zi1 * init[l];
    }
    (z0, z1)
}

/// One section over the whole block, forward or backward in time, from the state `zi * init`
/// per lane; outputs overwrite the inputs.
#[inline(always)]
fn pass1<const W: usize, const FMA: bool, const FORWARD: bool, const U: bool>(
    s: &Section,
    buf: &mut [[f64; W]],
    init: &[f64; W],
) {
    let (mut z0, mut z1) = start_state(s, init);
    let n = buf.len();
    let mut i = 0;
    while i < n {
        let t = if FORWARD { i } else { n - 1 - i };
        let row = &mut buf[t];
        for l in 0..W {
            row[l] = biquad::<FMA, U>(s, row[l], &mut z0[l], &mut z1[l]);
        }
        i += 1;
    }
}

/// Two consecutive sections fused in one sweep over the block (half the memory traffic of two
/// [`pass1`]); identical arithmetic.
#[inline(always)]
fn pass2<const W: usize, const FMA: bool, const FORWARD: bool, const U0: bool, const U1: bool>(
    s0: &Section,
    s1: &Section,
    buf: &mut [[f64; W]],
    init: &[f64; W],
) {
    let (mut p0, mut p1) = start_state(s0, init);
    let (mut q0, mut q1) = start_state(s1, init);
    let n = buf.len();
    let mut i = 0;
    while i < n {
        let t = if FORWARD { i } else { n - 1 - i };
        let row = &mut buf[t];
        for l in 0..W {
            let y = biquad::<FMA, U0>(s0, row[l], &mut p0[l], &mut p1[l]);
            row[l] = biquad::<FMA, U1>(s1, y, &mut q0[l], &mut q1[l]);
        }
        i += 1;
    }
}

/// Whether a section may take the `UNIT` path.
#[inline(always)]
fn unit(s: &Section) -> bool {
    s.b0 == 1.0 && s.b2 == 1.0
}

/// All sections over the block in one direction, two at a time.
#[inline(always)]
fn sweep<const W: usize, const FMA: bool, const FORWARD: bool, const FUSE: bool>(
    sections: &[Section],
    buf: &mut [[f64; W]],
    init: &[f64; W],
) {
    let mut k = 0;
    while FUSE && k + 1 < sections.len() {
        let (s0, s1) = (&sections[k], &sections[k + 1]);
        match (FMA && unit(s0), FMA && unit(s1)) {
            (false, false) => pass2::<W, FMA, FORWARD, false, false>(s0, s1, buf, init),
            (false, true) => pass2::<W, FMA, FORWARD, false, true>(s0, s1, buf, init),
            (true, false) => pass2::<W, FMA, FORWARD, true, false>(s0, s1, buf, init),
            (true, true) => pass2::<W, FMA, FORWARD, true, true>(s0, s1, buf, init),
        }
        k += 2;
    }
    while k < sections.len() {
        let s = &sections[k];
        if FMA && unit(s) {
            pass1::<W, FMA, FORWARD, true>(s, buf, init);
        } else {
            pass1::<W, FMA, FORWARD, false>(s, buf, init);
        }
        k += 1;
    }
}

/// Forward-backward filtering of a lane-major block holding the odd-extended signals: every
/// section starts from `zi * x[0]` forward, then from `zi * y[last]` backward (scipy).
#[inline(always)]
fn filtfilt_block<const W: usize, const FMA: bool, const FUSE: bool>(
    sections: &[Section],
    buf: &mut [[f64; W]],
) {
    let x0 = buf[0];
    sweep::<W, FMA, true, FUSE>(sections, buf, &x0);
    let y0 = buf[buf.len() - 1];
    sweep::<W, FMA, false, FUSE>(sections, buf, &y0);
}

fn block_portable<const W: usize, const FUSE: bool>(sections: &[Section], buf: &mut [[f64; W]]) {
    filtfilt_block::<W, false, FUSE>(sections, buf)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn block_avx2<const W: usize, const FUSE: bool>(sections: &[Section], buf: &mut [[f64; W]]) {
    filtfilt_block::<W, true, FUSE>(sections, buf)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
fn block_avx512<const W: usize, const FUSE: bool>(sections: &[Section], buf: &mut [[f64; W]]) {
    filtfilt_block::<W, true, FUSE>(sections, buf)
}

/// Forward-backward filtering of one lane-major block `buf[t][lane]` (already extended) at a
/// given level, with two sections fused per sweep over the block (`FUSE`) or one. Exposed for
/// benchmarks; [`filtfilt_groups`] is the API.
#[doc(hidden)]
pub fn run_block<const W: usize, const FUSE: bool>(
    level: Level,
    sections: &[Section],
    buf: &mut [[f64; W]],
) {
    match level {
        Level::Portable => block_portable::<W, FUSE>(sections, buf),
        // SAFETY: `Level::Avx2` / `Level::Avx512` are only produced by `detect`/`available`
        // after checking that the CPU has these features.
        #[cfg(target_arch = "x86_64")]
        Level::Avx2 => unsafe { block_avx2::<W, FUSE>(sections, buf) },
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => unsafe { block_avx512::<W, FUSE>(sections, buf) },
    }
}

/// A raw output pointer shared by the worker threads; every block writes only the samples of
/// its own signals, and signals do not overlap.
#[derive(Clone, Copy)]
struct OutPtr(*mut f64);
// SAFETY: see above; blocks write disjoint index sets.
unsafe impl Send for OutPtr {}
unsafe impl Sync for OutPtr {}

/// Copies the block's signals into `buf` (lane-major, odd extension of `edge` samples at both
/// ends; unused lanes zero), filters, and writes the filtered signals to `out`.
#[allow(clippy::too_many_arguments)]
fn do_block<const W: usize>(
    level: Level,
    sections: &[Section],
    src: &[f64],
    out: OutPtr,
    out_len: usize,
    bases: &[usize],
    stride: usize,
    len: usize,
    edge: usize,
    buf: &mut Vec<[f64; W]>,
) {
    debug_assert!(bases.len() <= W && len > edge);
    buf.clear();
    buf.resize(len + 2 * edge, [0.0; W]);
    for t in 0..len {
        let row = &mut buf[edge + t];
        for (l, &b) in bases.iter().enumerate() {
            row[l] = src[b + t * stride];
        }
    }
    for i in 0..edge {
        let (first, mirror) = (buf[edge], buf[2 * edge - i]);
        for l in 0..W {
            buf[i][l] = 2.0 * first[l] - mirror[l];
        }
        let (last, mirror) = (buf[edge + len - 1], buf[edge + len - 2 - i]);
        for l in 0..W {
            buf[edge + len + i][l] = 2.0 * last[l] - mirror[l];
        }
    }
    run_block::<W, FUSED>(level, sections, buf);
    for (l, &b) in bases.iter().enumerate() {
        assert!(b + (len - 1) * stride < out_len);
        for t in 0..len {
            // SAFETY: in bounds (checked above); no other block writes this signal's samples.
            unsafe { *out.0.add(b + t * stride) = buf[edge + t][l] };
        }
    }
}

/// Filters every signal of every group (forward-backward, odd extension of `edge` samples,
/// `sosfilt_zi` initial conditions) from `src` into the same positions of `dst`.
pub fn filtfilt_groups(
    sections: &[Section],
    src: &[f64],
    dst: &mut [f64],
    groups: &[SignalGroup],
    edge: usize,
) {
    filtfilt_groups_at(Level::detect(), sections, src, dst, groups, edge)
}

/// [`filtfilt_groups`] with a given instruction-set level (which must be available).
pub fn filtfilt_groups_at(
    level: Level,
    sections: &[Section],
    src: &[f64],
    dst: &mut [f64],
    groups: &[SignalGroup],
    edge: usize,
) {
    assert!(src.len() == dst.len());
    assert!(
        Level::available().contains(&level),
        "level {level:?} is not supported by this CPU"
    );
    match level {
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => run_groups::<32>(level, sections, src, dst, groups, edge),
        #[cfg(target_arch = "x86_64")]
        Level::Avx2 => run_groups::<16>(level, sections, src, dst, groups, edge),
        Level::Portable => run_groups::<SMALL_LANES>(level, sections, src, dst, groups, edge),
    }
}

/// Block width of the widest kernel at each level: enough independent lanes to keep the FMA
/// units busy without spilling the lane states out of the vector registers (measured with
/// `cargo bench --bench signal -- block`).
pub fn lanes_at(level: Level) -> usize {
    match level {
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => 32,
        #[cfg(target_arch = "x86_64")]
        Level::Avx2 => 16,
        Level::Portable => SMALL_LANES,
    }
}

/// [`filtfilt_groups_at`] with full blocks of `W` signals; a group's remainder goes to one
/// block of `W` (more than [`SMALL_LANES`] signals left), of [`SMALL_LANES`], or a single lane.
fn run_groups<const W: usize>(
    level: Level,
    sections: &[Section],
    src: &[f64],
    dst: &mut [f64],
    groups: &[SignalGroup],
    edge: usize,
) {
    // Blocks: (group, first signal, number of signals).
    let mut blocks: Vec<(usize, usize, usize)> = Vec::new();
    for (g, group) in groups.iter().enumerate() {
        assert!(group.len > edge && group.len >= 1);
        for b in group.bases {
            assert!(b + (group.len - 1) * group.stride < src.len());
        }
        let n = group.bases.len();
        let mut j = 0;
        while j < n {
            let k = (n - j).min(W);
            blocks.push((g, j, k));
            j += k;
        }
    }
    let out = OutPtr(dst.as_mut_ptr());
    let out_len = dst.len();
    blocks.par_iter().for_each_init(
        || {
            (
                Vec::<[f64; W]>::new(),
                Vec::<[f64; SMALL_LANES]>::new(),
                Vec::<[f64; 1]>::new(),
            )
        },
        |(big, small, one), &(g, j, k)| {
            let group = &groups[g];
            let bases = &group.bases[j..j + k];
            let (stride, len) = (group.stride, group.len);
            if k == 1 {
                do_block::<1>(level, sections, src, out, out_len, bases, stride, len, edge, one);
            } else if k <= SMALL_LANES {
                do_block::<SMALL_LANES>(
                    level, sections, src, out, out_len, bases, stride, len, edge, small,
                );
            } else {
                do_block::<W>(level, sections, src, out, out_len, bases, stride, len, edge, big);
            }
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::{butter_sos, sosfilt_zi, sosfiltfilt_scalar};

    fn sections_of(order: usize, wc: f64) -> (Vec<crate::filter::Sos>, Vec<Section>) {
        let sos = butter_sos(order, wc).unwrap();
        let secs = sos
            .iter()
            .zip(sosfilt_zi(&sos))
            .map(|(s, zi)| Section {
                b0: s[0],
                b1: s[1],
                b2: s[2],
                a1: s[4],
                a2: s[5],
                zi0: zi[0],
                zi1: zi[1],
            })
            .collect();
        (sos, secs)
    }

    #[test]
    fn every_level_and_width_matches_the_scalar_reference() {
        // Odd order (a first-order section, no unit sections fused with it), even order (two
        // fused pairs and a single section, unit sections), one section.
        for &(order, wc) in &[(7usize, 0.3), (10, 0.25), (2, 0.6)] {
            let (sos, secs) = sections_of(order, wc);
            let edge = crate::filter::default_padlen(&sos);
            let len = 70;
            // Full blocks of 32/16/8 with remainders > 8, <= 8 and 1.
            for &count in &[73usize, 37, 33, 41, 21, 17, 3, 1] {
                let src: Vec<f64> = (0..count * len)
                    .map(|i| ((i * 2_654_435_761usize) % 10_007) as f64 / 10_007.0 - 0.5)
                    .collect();
                let bases: Vec<usize> = (0..count).map(|r| r * len).collect();
                for level in Level::available() {
                    let mut dst = vec![f64::NAN; src.len()];
                    let group = SignalGroup {
                        bases: &bases,
                        stride: 1,
                        len,
                    };
                    filtfilt_groups_at(level, &secs, &src, &mut dst, &[group], edge);
                    for r in 0..count {
                        let want = sosfiltfilt_scalar(&sos, &src[r * len..(r + 1) * len], edge);
                        for t in 0..len {
                            let got = dst[r * len + t];
                            assert!(
                                (got - want[t]).abs() < 1e-12,
                                "{level:?} order {order} count {count} signal {r} t {t}: \
                                 {got} vs {}",
                                want[t]
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn portable_level_is_bit_identical_to_scipy_recursion() {
        let (sos, secs) = sections_of(4, 0.2);
        let edge = 27;
        let len = 50;
        let src: Vec<f64> = (0..len).map(|t| (t as f64 * 0.37).sin()).collect();
        let mut dst = vec![0.0; len];
        let group = SignalGroup {
            bases: &[0],
            stride: 1,
            len,
        };
        filtfilt_groups_at(Level::Portable, &secs, &src, &mut dst, &[group], edge);
        assert_eq!(dst, sosfiltfilt_scalar(&sos, &src, edge));
    }

    #[test]
    fn strided_signals_leave_other_samples_untouched() {
        let (sos, secs) = sections_of(2, 0.4);
        let edge = 9;
        let (len, stride) = (20, 3);
        let src: Vec<f64> = (0..len * stride).map(|i| i as f64).collect();
        let mut dst = vec![-7.0; src.len()];
        // Only channel 1 of 3.
        let group = SignalGroup {
            bases: &[1],
            stride,
            len,
        };
        filtfilt_groups(&secs, &src, &mut dst, &[group], edge);
        for (i, v) in dst.iter().enumerate() {
            if i % stride != 1 {
                assert_eq!(*v, -7.0);
            }
        }
        let sig: Vec<f64> = (0..len).map(|t| src[1 + t * stride]).collect();
        let want = sosfiltfilt_scalar(&sos, &sig, edge);
        for t in 0..len {
            assert!((dst[1 + t * stride] - want[t]).abs() < 1e-12);
        }
    }
}
