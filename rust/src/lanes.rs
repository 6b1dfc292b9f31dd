//! Lockstep engine of `sosfiltfilt`: many equal-length signals filtered at once.
//!
//! The biquad recursion of ONE signal is latency-bound (each output needs the previous state,
//! two dependent multiply-adds per sample and section). Here up to 32 signals (see
//! [`lanes_at`]) of equal length are copied into a lane-major block (`buf[t][lane]`, odd
//! extension included), and the recursion runs over the block with the lanes innermost, so the
//! inner loop is plain element-wise SIMD over lanes and the lanes' dependency chains overlap.
//! With AVX-512 each sweep over the block runs two consecutive sections (half the memory
//! traffic); sections with numerator `[1, 2, 1]` (all low-pass Butterworth sections but the
//! first) replace their multiplications by 1 and 2 with additions. Blocks are distributed over
//! threads with rayon; the channels of one trial of a `(frames, channels)` corpus are gathered
//! and scattered together as short contiguous runs.
//!
//! The arithmetic per lane is scipy's `sosfilt` (direct form II transposed); the SIMD builds use
//! fused multiply-adds, which changes results only in the last bits (the portable build is
//! bit-identical to scipy's recursion). The instruction set is chosen at run time (AVX-512F,
//! AVX2+FMA, or portable code), not at build time.

use rayon::prelude::*;

/// Signals per block for the remainder of a group (at most this many signals left), and the
/// block width of the portable build.
const SMALL_LANES: usize = 8;

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

pub use crate::simd::Level;

/// One biquad step of one lane (direct form II transposed, scipy's `sosfilt`): returns the
/// output and updates the two state variables.
///
/// * `FMA = false`: scipy's expression order, bit for bit.
/// * `FMA = true`: the same recursion with fused multiply-adds.
/// * `UNIT = true` (only with FMA): a section with numerator exactly `[1, 2, 1]` (a double zero
///   at -1: every low-pass Butterworth section but the first). The multiplications by 1 and 2
///   become additions (`2 x + z1 = (x + x) + z1`, `x + x` being exact), which changes no bit of
///   the result but moves work from the FMA units to the adders.
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
            *z0 = (-s.a1).mul_add(y, (x + x) + *z1);
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
    s.b0 == 1.0 && s.b1 == 2.0 && s.b2 == 1.0
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
    assert!(
        crate::simd::cpu_runs(level),
        "level {level:?} is not supported by this CPU"
    );
    match level {
        Level::Portable => block_portable::<W, FUSE>(sections, buf),
        // SAFETY: the CPU runs the level (asserted above).
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => unsafe { block_avx2::<W, FUSE>(sections, buf) },
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => unsafe { block_avx512::<W, FUSE>(sections, buf) },
        #[cfg(not(target_arch = "x86_64"))]
        _ => block_portable::<W, FUSE>(sections, buf),
    }
}

/// A raw output pointer shared by the worker threads; every block writes only the samples of
/// its own signals, and signals do not overlap.
#[derive(Clone, Copy)]
struct OutPtr(*mut f64);
// SAFETY: see above; blocks write disjoint index sets.
unsafe impl Send for OutPtr {}
unsafe impl Sync for OutPtr {}

/// The signals of one block: signal `j` is `src[bases[j] + t * stride]`, `t < len`, and goes to
/// the same positions of `out`. Built only by [`Job::new`], which checks the bounds.
#[derive(Clone, Copy)]
struct Job<'a> {
    src: &'a [f64],
    out: OutPtr,
    bases: &'a [usize],
    stride: usize,
    len: usize,
    edge: usize,
}

impl<'a> Job<'a> {
    fn new(
        src: &'a [f64],
        out: OutPtr,
        out_len: usize,
        bases: &'a [usize],
        stride: usize,
        len: usize,
        edge: usize,
    ) -> Self {
        assert!(len > edge && src.len() == out_len);
        for &b in bases {
            assert!(b + (len - 1) * stride < src.len());
        }
        Job {
            src,
            out,
            bases,
            stride,
            len,
            edge,
        }
    }
}

/// If the block's signals come in runs of adjacent positions (the channels of one trial in a
/// `(frames, channels)` corpus), the run length; else 1.
fn run_length(bases: &[usize]) -> usize {
    let r = bases
        .windows(2)
        .position(|w| w[1] != w[0] + 1)
        .map_or(bases.len(), |p| p + 1);
    let uniform = bases.len().is_multiple_of(r)
        && bases
            .chunks_exact(r)
            .all(|c| c.windows(2).all(|w| w[1] == w[0] + 1));
    if uniform {
        r
    } else {
        1
    }
}

/// Gathers runs of `R` adjacent values per time step into `body` (`len` rows).
#[inline(always)]
fn gather_runs<const W: usize, const R: usize>(body: &mut [[f64; W]], job: &Job) {
    debug_assert!(job.bases.len() <= W && job.bases.len().is_multiple_of(R));
    for (t, row) in body.iter_mut().enumerate() {
        let off = t * job.stride;
        for (j, run) in job.bases.chunks_exact(R).enumerate() {
            // SAFETY: `run[0] + off + R - 1 = run[R - 1] + off`, a base checked by `Job::new`
            // (runs are adjacent positions); `j * R + R <= bases.len() <= W`.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    job.src.as_ptr().add(run[0] + off),
                    row.as_mut_ptr().add(j * R),
                    R,
                )
            };
        }
    }
}

/// Scatters runs of `R` adjacent values per time step from `body` to the output.
///
/// SAFETY (caller): no other thread writes these signals' positions.
#[inline(always)]
unsafe fn scatter_runs<const W: usize, const R: usize>(body: &[[f64; W]], job: &Job) {
    for (t, row) in body.iter().enumerate() {
        let off = t * job.stride;
        for (j, run) in job.bases.chunks_exact(R).enumerate() {
            // SAFETY: in bounds as in `gather_runs` (`out` has the length of `src`); exclusive
            // by the caller's contract.
            unsafe {
                std::ptr::copy_nonoverlapping(
                    row.as_ptr().add(j * R),
                    job.out.0.add(run[0] + off),
                    R,
                )
            };
        }
    }
}

/// Gathers lane by lane (contiguous reads when `stride == 1`, i.e. one signal per row).
#[inline(always)]
fn gather_lanes<const W: usize>(body: &mut [[f64; W]], job: &Job) {
    for (l, &b) in job.bases.iter().enumerate() {
        if job.stride == 1 {
            for (row, &v) in body.iter_mut().zip(&job.src[b..b + job.len]) {
                row[l] = v;
            }
        } else {
            for (t, row) in body.iter_mut().enumerate() {
                row[l] = job.src[b + t * job.stride];
            }
        }
    }
}

/// Scatters lane by lane. SAFETY (caller): as [`scatter_runs`].
#[inline(always)]
unsafe fn scatter_lanes<const W: usize>(body: &[[f64; W]], job: &Job) {
    for (l, &b) in job.bases.iter().enumerate() {
        for (t, row) in body.iter().enumerate() {
            // SAFETY: `b + t * stride` is in bounds (`Job::new`); exclusive by contract.
            unsafe { *job.out.0.add(b + t * job.stride) = row[l] };
        }
    }
}

/// One block: gather the signals into `buf` (lane-major, odd extension of `edge` samples at
/// both ends, unused lanes zero), filter, scatter. Returns false if an input value was NaN or
/// infinite (the output is then meaningless and the caller reports an error).
///
/// SAFETY (caller): no other thread writes the block's signals.
#[inline(always)]
unsafe fn block_job<const W: usize, const FMA: bool, const FUSE: bool>(
    sections: &[Section],
    job: &Job,
    buf: &mut Vec<[f64; W]>,
) -> bool {
    let (k, len, edge) = (job.bases.len(), job.len, job.edge);
    assert!(k <= W);
    if buf.len() != len + 2 * edge {
        buf.clear();
        buf.resize(len + 2 * edge, [0.0; W]);
    }
    if k < W {
        for row in buf.iter_mut() {
            row[k..].fill(0.0);
        }
    }
    let run = run_length(job.bases);
    let body = &mut buf[edge..edge + len];
    match run {
        2 => gather_runs::<W, 2>(body, job),
        3 => gather_runs::<W, 3>(body, job),
        4 => gather_runs::<W, 4>(body, job),
        6 => gather_runs::<W, 6>(body, job),
        8 => gather_runs::<W, 8>(body, job),
        _ => gather_lanes::<W>(body, job),
    }
    let mut bad = false;
    for row in body.iter() {
        for v in row {
            bad |= !v.is_finite();
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
    filtfilt_block::<W, FMA, FUSE>(sections, buf);
    let body = &buf[edge..edge + len];
    // SAFETY: exclusive by this function's contract.
    unsafe {
        match run {
            2 => scatter_runs::<W, 2>(body, job),
            3 => scatter_runs::<W, 3>(body, job),
            4 => scatter_runs::<W, 4>(body, job),
            6 => scatter_runs::<W, 6>(body, job),
            8 => scatter_runs::<W, 8>(body, job),
            _ => scatter_lanes::<W>(body, job),
        }
    }
    !bad
}

unsafe fn job_portable<const W: usize>(s: &[Section], job: &Job, buf: &mut Vec<[f64; W]>) -> bool {
    // SAFETY: forwarded contract.
    unsafe { block_job::<W, false, true>(s, job, buf) }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn job_avx2<const W: usize>(s: &[Section], job: &Job, buf: &mut Vec<[f64; W]>) -> bool {
    // SAFETY: forwarded contract.
    unsafe { block_job::<W, true, false>(s, job, buf) }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
unsafe fn job_avx512<const W: usize>(s: &[Section], job: &Job, buf: &mut Vec<[f64; W]>) -> bool {
    // SAFETY: forwarded contract.
    unsafe { block_job::<W, true, true>(s, job, buf) }
}

/// SAFETY (caller): `level` is available and no other thread writes the block's signals.
unsafe fn run_job<const W: usize>(
    level: Level,
    s: &[Section],
    job: &Job,
    buf: &mut Vec<[f64; W]>,
) -> bool {
    // SAFETY: forwarded contract (the CPU features checked by `filtfilt_groups_at`).
    unsafe {
        match level {
            Level::Portable => job_portable::<W>(s, job, buf),
            #[cfg(target_arch = "x86_64")]
            Level::Avx2Fma => job_avx2::<W>(s, job, buf),
            #[cfg(target_arch = "x86_64")]
            Level::Avx512 => job_avx512::<W>(s, job, buf),
            #[cfg(not(target_arch = "x86_64"))]
            _ => job_portable::<W>(s, job, buf),
        }
    }
}

/// Filters every signal of every group (forward-backward, odd extension of `edge` samples,
/// `sosfilt_zi` initial conditions) from `src` into the same positions of `dst`. Returns false
/// if any input value was NaN or infinite (`dst` is then meaningless). Runs at
/// [`crate::simd::active`].
pub fn filtfilt_groups(
    sections: &[Section],
    src: &[f64],
    dst: &mut [f64],
    groups: &[SignalGroup],
    edge: usize,
) -> bool {
    filtfilt_groups_at(crate::simd::active(), sections, src, dst, groups, edge)
}

/// [`filtfilt_groups`] at a given level (one this CPU runs).
pub fn filtfilt_groups_at(
    level: Level,
    sections: &[Section],
    src: &[f64],
    dst: &mut [f64],
    groups: &[SignalGroup],
    edge: usize,
) -> bool {
    assert!(src.len() == dst.len());
    assert!(
        crate::simd::cpu_runs(level),
        "level {level:?} is not supported by this CPU"
    );
    match level {
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => run_groups::<32>(level, sections, src, dst, groups, edge),
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => run_groups::<16>(level, sections, src, dst, groups, edge),
        _ => run_groups::<SMALL_LANES>(Level::Portable, sections, src, dst, groups, edge),
    }
}

/// Block width of the widest kernel at each level: enough independent lanes to keep the FMA
/// units busy without spilling the lane states out of the vector registers. With AVX-512 the
/// sweeps fuse two sections (32 registers hold both states); with AVX2 and portable code, one
/// (measured with `cargo bench --bench signal -- block`).
pub fn lanes_at(level: Level) -> usize {
    match level {
        #[cfg(target_arch = "x86_64")]
        Level::Avx512 => 32,
        #[cfg(target_arch = "x86_64")]
        Level::Avx2Fma => 16,
        _ => SMALL_LANES,
    }
}

/// What the filter runs at `level`, as `instruction_sets()` reports it.
pub fn instruction_set(level: Level) -> &'static str {
    match level {
        Level::Avx512 => "avx512f (32 signals in lockstep, two sections per sweep)",
        Level::Avx2Fma => "avx2+fma (16 signals in lockstep)",
        Level::Portable => "portable (8 signals in lockstep, scipy's arithmetic bit for bit)",
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
) -> bool {
    // Blocks: (group, first signal, number of signals).
    let mut blocks: Vec<(usize, usize, usize)> = Vec::new();
    for (g, group) in groups.iter().enumerate() {
        let n = group.bases.len();
        // Keep the channels of one trial (`stride` adjacent signals) in one block.
        let chunk = if group.stride > 1 && group.stride <= W {
            W / group.stride * group.stride
        } else {
            W
        };
        let mut j = 0;
        while j < n {
            let k = (n - j).min(chunk);
            blocks.push((g, j, k));
            j += k;
        }
    }
    // Signals must not overlap (each position is written by one block only).
    debug_assert!({
        let mut all: Vec<usize> = groups
            .iter()
            .flat_map(|g| {
                g.bases
                    .iter()
                    .flat_map(move |&b| (0..g.len).map(move |t| b + t * g.stride))
            })
            .collect();
        all.sort_unstable();
        all.windows(2).all(|w| w[0] != w[1])
    });
    let out = OutPtr(dst.as_mut_ptr());
    let out_len = dst.len();
    blocks
        .par_iter()
        .map_init(
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
                let job = Job::new(src, out, out_len, bases, group.stride, group.len, edge);
                // SAFETY: `level` was checked above; blocks hold disjoint signals.
                unsafe {
                    if k == 1 {
                        run_job::<1>(level, sections, &job, one)
                    } else if k <= SMALL_LANES {
                        run_job::<SMALL_LANES>(level, sections, &job, small)
                    } else {
                        run_job::<W>(level, sections, &job, big)
                    }
                }
            },
        )
        .reduce(|| true, |a, b| a && b)
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
                for level in crate::simd::levels() {
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
