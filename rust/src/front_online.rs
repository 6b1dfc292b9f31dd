//! The online segmenter's front end, frame by frame, its state kept between chunks.
//!
//! Stages 1–3 of `visprim.online.segmenter` (and its adaptive threshold), on row-major
//! chunks of frames:
//!
//! 1. **Inverse kinematics** of every frame (`visprim.ik.arm_angles_corpus` on the chunk): the
//!    joint centres (the recording's, else those the four markers imply), the bones in the
//!    torso's axes (`body_frame`), a left arm mirrored, the shoulder frame, then
//!    `β = acos u_z`, `θ = acos(u·f)`, `γ = atan2(u_y, u_x)` and α from the forearm's plane.
//!    γ and α are unwrapped within the chunk; on frames inside the singular cones
//!    (`singular_angle`, radians; 0 for bone-direction models) they are interpolated in time
//!    within the chunk (held at its ends, 0 when no frame of the chunk is well defined), as
//!    offline. Across chunks they are continued by whole turns.
//! 2. **Causal low-pass** of the angles ([`CausalSos`]).
//! 3. The model's **per-frame channels** (the angles, or the unit bone directions of
//!    `Rz(γ) Ry(β) Rz(α)`) and **`z = Σ ẋ²`** with `numpy.gradient`'s differences on the
//!    timestamps: the velocity of frame `k` needs frame `k + 1`, so a push yields `z` of the
//!    frames before its last one (and [`OnlineFrontEnd::finish`] the last by a backward
//!    difference).
//!
//! With it, per frame `f` whose `z` is known, the SEG-2 threshold: the fitted `c`, or (adaptive)
//! every `every` frames `min(max(fraction · q, c / slowest), c)` with `q` the `quantile`
//! (numpy's linear rule) of `z` over the last `window` frames, `window` = `speed_window`
//! seconds at the median frame period of the first chunk. The window is a sorted ring (binary
//! insertion and removal, O(window) per frame by a memory move of at most a few kB).
//!
//! Memory is fixed once the first chunk has set the window, apart from scratch buffers that
//! grow to the largest chunk pushed. Sizes are checked and every buffer is allocated
//! fallibly.

use std::f64::consts::{PI, TAU};

use crate::buffer::{elements, try_filled, try_with_capacity};
use crate::filter::Sos;
use crate::sosfilt_online::CausalSos;
use crate::{Error, Result};

/// Shortest bone (metres) inverse kinematics accepts, as `visprim.ik`.
pub const MIN_BONE_LENGTH: f64 = 1e-9;
/// Frame period assumed when the first chunk has a single frame (seconds), as the segmenter.
pub const DEFAULT_PERIOD: f64 = 1.0 / 30.0;
/// Fewest frames in the rolling window.
pub const MIN_WINDOW: usize = 8;

/// What the per-frame channels are (`visprim.features`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Features {
    /// γ, β, α, elbow flexion per arm (4 channels, radians).
    Zyz,
    /// Unit upper-arm and forearm directions in the shoulder frame per arm (6 channels).
    Directions,
}

impl Features {
    pub(crate) fn per_arm(self) -> usize {
        match self {
            Features::Zyz => 4,
            Features::Directions => 6,
        }
    }
}

/// The SEG-2 threshold per frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Threshold {
    /// The fitted constant `c`, (rad/s)²; > 0.
    pub c: f64,
    /// Adaptive (`true`): lowered for slow movers from the rolling quantile; else `c`.
    pub adaptive: bool,
    /// The quantile of `z` over the window, in [0, 1] (0.95).
    pub quantile: f64,
    /// `c` follows `fraction · quantile` (0.02) ...
    pub fraction: f64,
    /// ... but not below `c / slowest` (100).
    pub slowest: f64,
    /// Recomputed on frames whose index is a multiple of `every` (8).
    pub every: usize,
    /// Window, seconds of stream (10).
    pub speed_window: f64,
}

/// Everything the front end is built from.
#[derive(Debug, Clone)]
pub struct Config {
    /// One entry per arm: `true` for a left arm (mirrored), `false` for a right arm.
    pub left: Vec<bool>,
    pub features: Features,
    /// Half-angle of the singular cones, radians, in [0, π/4).
    pub singular_angle: f64,
    /// The causal low-pass' sections.
    pub sos: Vec<Sos>,
    pub threshold: Threshold,
}

/// Per processed frame: `z`, its time, the time of the frame that decided it (its
/// successor, or the last frame at the end of the stream) and the threshold.
pub const SPEED_COLUMNS: usize = 4;

/// What one push yields (row-major, `k` frames pushed, `m` frames whose `z` became known).
#[derive(Debug, Default, Clone)]
pub struct Output {
    /// `(k, 4 n_arms)` raw arm angles, radians (empty for [`OnlineFrontEnd::push_values`]).
    pub angles: Vec<f64>,
    /// `(k, channels)` causally low-passed channels (empty for `push_values`).
    pub values: Vec<f64>,
    /// `(k, 6 n_arms)` unit bone directions in the torso's axes, upper arm then forearm per
    /// arm, unmirrored (`visprim.classify.arm_directions`; empty for `push_values`).
    pub directions: Vec<f64>,
    /// `(m, SPEED_COLUMNS)`: z (rad/s)², t s, decided-at s, threshold (rad/s)².
    pub speeds: Vec<f64>,
}

/// The last `capacity` values and the same values sorted, for order statistics.
#[derive(Debug, Clone)]
struct RollingWindow {
    ring: Vec<f64>,
    head: usize,
    sorted: Vec<f64>,
}

impl RollingWindow {
    fn new(capacity: usize) -> Result<Self> {
        Ok(Self {
            ring: try_filled(capacity, 0.0, "rolling window")?,
            head: 0,
            sorted: try_with_capacity(capacity, "rolling window")?,
        })
    }

    fn clear(&mut self) {
        self.head = 0;
        self.sorted.clear();
    }

    fn push(&mut self, v: f64) {
        let cap = self.ring.len();
        if self.sorted.len() == cap {
            let old = self.ring[self.head];
            // total_cmp finds the very value (same bits) that leaves.
            if let Ok(i) = self.sorted.binary_search_by(|x| x.total_cmp(&old)) {
                self.sorted.remove(i);
            }
        }
        self.ring[self.head] = v;
        self.head = (self.head + 1) % cap;
        let at = self.sorted.partition_point(|x| x.total_cmp(&v).is_lt());
        self.sorted.insert(at, v);
    }

    /// numpy's `quantile(values, q)` (method "linear"); NaN when empty.
    fn quantile(&self, q: f64) -> f64 {
        let n = self.sorted.len();
        if n == 0 {
            return f64::NAN;
        }
        let virtual_index = (n - 1) as f64 * q;
        let below = (virtual_index.floor() as usize).min(n - 1);
        let above = (below + 1).min(n - 1);
        let gamma = virtual_index - below as f64;
        let (a, b) = (self.sorted[below], self.sorted[above]);
        let diff = b - a;
        if gamma >= 0.5 {
            b - diff * (1.0 - gamma)
        } else {
            a + diff * gamma
        }
    }

    fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.ring.as_slice())
            + self.sorted.capacity() * std::mem::size_of::<f64>()
    }
}

/// Python's `max(a, b)` / `min(a, b)` (the first argument unless the second is strictly
/// larger / smaller), so a NaN goes through as it does there.
fn py_max(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

fn py_min(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// numpy's `mod` (the sign of the divisor).
fn py_mod(a: f64, b: f64) -> f64 {
    let m = a % b;
    if m != 0.0 && ((m < 0.0) != (b < 0.0)) {
        m + b
    } else {
        m
    }
}

/// `numpy.unwrap` of `x` in place (visprim.ik's ragged form: the correction summed in order).
fn unwrap(x: &mut [f64]) {
    let mut cum = 0.0;
    let mut prev = match x.first() {
        Some(&v) => v,
        None => return,
    };
    for v in x.iter_mut().skip(1) {
        let raw = *v;
        let d = raw - prev;
        if d.abs() >= PI {
            cum += py_mod(d + PI, TAU) - PI - d;
        }
        prev = raw;
        *v = raw + cum;
    }
}

/// `numpy.interp(x, xp, fp)` for increasing `xp` (held at the ends).
fn interp(x: f64, xp: &[f64], fp: &[f64]) -> f64 {
    let last = xp.len() - 1;
    if x < xp[0] {
        return fp[0];
    }
    if x > xp[last] {
        return fp[last];
    }
    let j = xp.partition_point(|&v| v <= x) - 1;
    if j == last || xp[j] == x {
        return fp[j];
    }
    let slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]);
    let y = slope * (x - xp[j]) + fp[j];
    if y.is_nan() {
        let y2 = slope * (x - xp[j + 1]) + fp[j + 1];
        if y2.is_nan() && fp[j] == fp[j + 1] {
            return fp[j];
        }
        return y2;
    }
    y
}

/// Scratch of the continuity step (reused from push to push).
#[derive(Debug, Default, Clone)]
struct Continuity {
    good_t: Vec<f64>,
    good_v: Vec<f64>,
}

impl Continuity {
    /// `visprim.ik._continuous` of one chunk: `raw` unwrapped over the frames `ok`, the
    /// others interpolated in time `t` (held at the ends; 0 when none is ok). In place.
    fn apply(&mut self, raw: &mut [f64], ok: &[bool], t: &[f64]) -> Result<()> {
        if ok.iter().all(|&g| g) {
            unwrap(raw);
            return Ok(());
        }
        self.good_t.clear();
        self.good_v.clear();
        let n_good = ok.iter().filter(|&&g| g).count();
        self.good_t
            .try_reserve(n_good)
            .and_then(|_| self.good_v.try_reserve(n_good))
            .map_err(|_| Error::Memory(format!("cannot allocate {n_good} frames of scratch")))?;
        for ((&v, &g), &ti) in raw.iter().zip(ok).zip(t) {
            if g {
                self.good_t.push(ti);
                self.good_v.push(v);
            }
        }
        if n_good == 0 {
            raw.fill(0.0);
            return Ok(());
        }
        unwrap(&mut self.good_v);
        let mut k = 0;
        for ((v, &g), &ti) in raw.iter_mut().zip(ok).zip(t) {
            if g {
                *v = self.good_v[k];
                k += 1;
            } else {
                *v = interp(ti, &self.good_t, &self.good_v);
            }
        }
        Ok(())
    }
}

/// The model's per-frame channels of arm angles `(k, 4 n_arms)` (γ, β, α, elbow per arm,
/// radians), appended to `out`: the angles themselves (`Zyz`), or per arm the unit upper-arm
/// direction (the rotation's third column) and the forearm's (`R · (sin θ, 0, cos θ)`) in
/// the shoulder frame (`Directions`), as `visprim.features.from_angles` (within 1 ulp per
/// product: numpy's matrix product may use its BLAS's fused multiply-adds).
pub fn channels_of_angles(features: Features, angles: &[f64], out: &mut Vec<f64>) {
    match features {
        Features::Zyz => out.extend_from_slice(angles),
        Features::Directions => {
            for q in angles.chunks_exact(4) {
                let r = shoulder_rotation(q[0], q[1], q[2]);
                let (st, ct) = q[3].sin_cos();
                out.extend_from_slice(&[r[0][2], r[1][2], r[2][2]]);
                for ri in &r {
                    out.push(ri[0] * st + ri[1] * 0.0 + ri[2] * ct);
                }
            }
        }
    }
}

/// `Rz(γ) Ry(β) Rz(α)` (row-major), as `visprim.arm.shoulder_rotation` multiplies them.
fn shoulder_rotation(g: f64, b: f64, a: f64) -> [[f64; 3]; 3] {
    let (sg, cg) = g.sin_cos();
    let (sb, cb) = b.sin_cos();
    let (sa, ca) = a.sin_cos();
    let rz_g = [[cg, -sg, 0.0], [sg, cg, 0.0], [0.0, 0.0, 1.0]];
    let ry_b = [[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]];
    let rz_a = [[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]];
    matmul(&matmul(&rz_g, &ry_b), &rz_a)
}

fn matmul(x: &[[f64; 3]; 3], y: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = x[i][0] * y[0][j] + x[i][1] * y[1][j] + x[i][2] * y[2][j];
        }
    }
    out
}

/// Per-arm scratch of the inverse kinematics of a chunk.
#[derive(Debug, Default, Clone)]
struct ArmScratch {
    u: Vec<[f64; 3]>,
    f: Vec<[f64; 3]>,
    beta: Vec<f64>,
    elbow: Vec<f64>,
    gamma: Vec<f64>,
    alpha: Vec<f64>,
    ok: Vec<bool>,
}

impl ArmScratch {
    fn resize(&mut self, k: usize) -> Result<()> {
        let fail = |_| Error::Memory(format!("cannot allocate {k} frames of scratch"));
        for v in [&mut self.u, &mut self.f] {
            v.clear();
            v.try_reserve(k).map_err(fail)?;
            v.resize(k, [0.0; 3]);
        }
        for v in [
            &mut self.beta,
            &mut self.elbow,
            &mut self.gamma,
            &mut self.alpha,
        ] {
            v.clear();
            v.try_reserve(k).map_err(fail)?;
            v.resize(k, 0.0);
        }
        self.ok.clear();
        self.ok.try_reserve(k).map_err(fail)?;
        self.ok.resize(k, false);
        Ok(())
    }
}

/// A chunk of frames (row-major slices; `k` frames).
#[derive(Debug, Clone, Copy)]
pub struct Chunk<'a> {
    /// `(k,)` seconds, strictly increasing and after the previous chunk's last frame.
    pub times: &'a [f64],
    /// `(k, 4 n_arms, 3)` metres: upper-arm, forearm, wrist and finger markers per arm.
    pub markers: &'a [f64],
    /// `(k, 3 n_arms, 3)` metres: shoulder, elbow and wrist centres per arm, optional.
    pub joints: Option<&'a [f64]>,
    /// `(k, 3, 3)` torso axes as columns in the recording frame, optional.
    pub body_frame: Option<&'a [f64]>,
}

/// The front end of one stream (module docstring).
#[derive(Debug, Clone)]
pub struct OnlineFrontEnd {
    cfg: Config,
    n_arms: usize,
    channels: usize,
    filter: CausalSos,
    /// The last pushed frame's raw angles (continuity by whole turns), once a frame came.
    last_angles: Vec<f64>,
    has_last: bool,
    /// Frames received and the next frame whose z is to be computed.
    n_frames: usize,
    next: usize,
    /// Times and channels of the frames `[max(0, next − 1), n_frames)` (at most 2).
    tail_times: Vec<f64>,
    tail_values: Vec<f64>,
    /// Frame period (seconds) and window (frames), set by the first chunk.
    period: Option<f64>,
    window: Option<RollingWindow>,
    current: f64,
    arms: Vec<ArmScratch>,
    continuity: Continuity,
    work_times: Vec<f64>,
    work_values: Vec<f64>,
}

impl OnlineFrontEnd {
    /// Errors: no arm, a singular angle outside [0, π/4), a threshold that is not positive
    /// and finite, a quantile outside [0, 1], `every` 0, a window that is not a positive
    /// number of seconds (InvalidArgument); bad sections (as [`CausalSos::new`]).
    pub fn new(cfg: Config) -> Result<Self> {
        let n_arms = cfg.left.len();
        if n_arms == 0 {
            return Err(Error::InvalidArgument("need at least one arm".into()));
        }
        if !(0.0..PI / 4.0).contains(&cfg.singular_angle) {
            return Err(Error::InvalidArgument(format!(
                "singular_angle must be in [0, π/4) radians, got {}",
                cfg.singular_angle
            )));
        }
        let th = &cfg.threshold;
        for (name, v) in [
            ("c", th.c),
            ("fraction", th.fraction),
            ("slowest", th.slowest),
            ("speed_window", th.speed_window),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidArgument(format!(
                    "{name} must be positive and finite, got {v}"
                )));
            }
        }
        if !(0.0..=1.0).contains(&th.quantile) {
            return Err(Error::InvalidArgument(format!(
                "quantile must be in [0, 1], got {}",
                th.quantile
            )));
        }
        if th.every == 0 {
            return Err(Error::InvalidArgument("every must be at least 1".into()));
        }
        let angle_channels = elements::<f64>(&[n_arms, 4], "angles per frame")?;
        let channels = elements::<f64>(&[n_arms, cfg.features.per_arm()], "channels")?;
        let filter = CausalSos::new(&cfg.sos, angle_channels)?;
        let mut arms = Vec::new();
        arms.try_reserve_exact(n_arms)
            .map_err(|_| Error::Memory("cannot allocate the arms' scratch".into()))?;
        arms.resize_with(n_arms, ArmScratch::default);
        let current = th.c;
        Ok(Self {
            n_arms,
            channels,
            filter,
            last_angles: try_filled(angle_channels, 0.0, "last angles")?,
            has_last: false,
            n_frames: 0,
            next: 0,
            tail_times: try_with_capacity(2, "tail")?,
            tail_values: try_with_capacity(2 * channels, "tail")?,
            period: None,
            window: None,
            current,
            arms,
            continuity: Continuity::default(),
            work_times: Vec::new(),
            work_values: Vec::new(),
            cfg,
        })
    }

    /// Channels per frame of the model's description.
    pub fn channels(&self) -> usize {
        self.channels
    }

    pub fn n_arms(&self) -> usize {
        self.n_arms
    }

    /// Frames received since the start (or the last [`reset`](Self::reset)).
    pub fn n_frames(&self) -> usize {
        self.n_frames
    }

    /// The frame period the first chunk set (median step; [`DEFAULT_PERIOD`] for a single
    /// frame), seconds; `None` before the first frame.
    pub fn period(&self) -> Option<f64> {
        self.period
    }

    /// Frames of the rolling window (`None` before the first frame, or with a fixed
    /// threshold).
    pub fn window_frames(&self) -> Option<usize> {
        self.window.as_ref().map(|w| w.ring.len())
    }

    /// Bytes held by the state (filter, window, tail, scratch).
    pub fn memory_bytes(&self) -> usize {
        let f = std::mem::size_of::<f64>();
        let scratch: usize = self
            .arms
            .iter()
            .map(|a| {
                (a.u.capacity() + a.f.capacity()) * 3 * f
                    + (a.beta.capacity()
                        + a.elbow.capacity()
                        + a.gamma.capacity()
                        + a.alpha.capacity())
                        * f
                    + a.ok.capacity()
            })
            .sum();
        self.filter.memory_bytes()
            + self.window.as_ref().map_or(0, RollingWindow::memory_bytes)
            + (self.last_angles.capacity()
                + self.tail_times.capacity()
                + self.tail_values.capacity()
                + self.continuity.good_t.capacity()
                + self.continuity.good_v.capacity()
                + self.work_times.capacity()
                + self.work_values.capacity())
                * f
            + scratch
    }

    /// Forget the stream (the period and window the first chunk set are kept).
    pub fn reset(&mut self) {
        self.filter.reset();
        self.has_last = false;
        self.n_frames = 0;
        self.next = 0;
        self.tail_times.clear();
        self.tail_values.clear();
        if let Some(w) = &mut self.window {
            w.clear();
        }
        self.current = self.cfg.threshold.c;
    }

    /// Stages 1–3 of a chunk of raw frames (module docstring) into `out`.
    ///
    /// Errors (nothing is changed then): lengths that do not match the arms (Shape), NaN or
    /// infinity (NonFinite), timestamps that do not increase (InvalidArgument), a bone of
    /// zero length (InvalidArgument).
    pub fn push(&mut self, chunk: Chunk<'_>, out: &mut Output) -> Result<()> {
        let k = chunk.times.len();
        let n_arms = self.n_arms;
        let a4 = 4 * n_arms;
        check_len(chunk.markers.len(), &[k, n_arms, 4, 3], "markers")?;
        if let Some(j) = chunk.joints {
            check_len(j.len(), &[k, n_arms, 3, 3], "joints")?;
        }
        if let Some(b) = chunk.body_frame {
            check_len(b.len(), &[k, 3, 3], "body_frame")?;
        }
        self.check_times(chunk.times)?;
        check_finite(chunk.markers, "markers")?;
        if let Some(j) = chunk.joints {
            check_finite(j, "joints")?;
        }
        if let Some(b) = chunk.body_frame {
            check_finite(b, "body_frame")?;
        }
        out.angles.clear();
        out.values.clear();
        out.directions.clear();
        out.speeds.clear();
        if k == 0 {
            return Ok(());
        }
        let angles_len = elements::<f64>(&[k, a4], "angles")?;
        reserve(&mut out.angles, angles_len)?;
        out.angles.resize(angles_len, 0.0);
        reserve(
            &mut out.directions,
            elements::<f64>(&[k, n_arms, 6], "directions")?,
        )?;
        out.directions.resize(k * n_arms * 6, 0.0);
        for arm in &mut self.arms {
            arm.resize(k)?;
        }
        self.inverse_kinematics(chunk, out)?;
        self.set_period(chunk.times)?;
        // Stage 1 done without error: from here on the state changes.
        if self.has_last {
            for p in (0..n_arms).flat_map(|a| [4 * a, 4 * a + 2]) {
                let turns = ((self.last_angles[p] - out.angles[p]) / TAU).round_ties_even();
                if turns != 0.0 {
                    let shift = TAU * turns;
                    for row in out.angles.chunks_exact_mut(a4) {
                        row[p] += shift;
                    }
                }
            }
        }
        self.last_angles
            .copy_from_slice(&out.angles[(k - 1) * a4..k * a4]);
        self.has_last = true;
        // Stage 2: the causal low-pass of the angles.
        let mut filtered = std::mem::take(&mut self.work_values);
        filtered.clear();
        reserve(&mut filtered, angles_len)?;
        filtered.extend_from_slice(&out.angles);
        self.filter.filter(&mut filtered)?;
        // Stage 3: the channels.
        let values_len = elements::<f64>(&[k, self.channels], "values")?;
        reserve(&mut out.values, values_len)?;
        channels_of_angles(self.cfg.features, &filtered, &mut out.values);
        self.work_values = filtered;
        self.speeds(chunk.times, &out.values, &mut out.speeds)
    }

    /// Stage 3's `z` of already filtered channels `(k, channels)` with their times, into
    /// `out.speeds` (the other outputs stay empty). Errors as [`push`](Self::push).
    pub fn push_values(&mut self, times: &[f64], values: &[f64], out: &mut Output) -> Result<()> {
        check_len(values.len(), &[times.len(), self.channels], "values")?;
        self.check_times(times)?;
        check_finite(values, "values")?;
        if !times.is_empty() {
            self.set_period(times)?;
        }
        out.angles.clear();
        out.values.clear();
        out.directions.clear();
        out.speeds.clear();
        if times.is_empty() {
            return Ok(());
        }
        self.speeds(times, values, &mut out.speeds)
    }

    /// The end of the stream: `z` of the frames still waiting (the last frame by a backward
    /// difference) into `out.speeds`.
    pub fn finish(&mut self, out: &mut Output) -> Result<()> {
        out.angles.clear();
        out.values.clear();
        out.directions.clear();
        out.speeds.clear();
        self.advance(&[], &[], self.n_frames, &mut out.speeds)
    }

    fn check_times(&self, times: &[f64]) -> Result<()> {
        if let Some(i) = times.iter().position(|t| !t.is_finite()) {
            return Err(Error::NonFinite(format!(
                "timestamps within a chunk must be finite and increasing (frame {i} is {})",
                times[i]
            )));
        }
        if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::InvalidArgument(format!(
                "timestamps within a chunk must be finite and increasing (frame {} at {} s \
                 follows {} s)",
                i + 1,
                times[i + 1],
                times[i]
            )));
        }
        if let (Some(&first), Some(&last)) = (times.first(), self.tail_times.last()) {
            if self.n_frames > 0 && first <= last {
                return Err(Error::InvalidArgument(format!(
                    "timestamps must increase: {first} s follows {last} s"
                )));
            }
        }
        Ok(())
    }

    fn inverse_kinematics(&mut self, chunk: Chunk<'_>, out: &mut Output) -> Result<()> {
        let k = chunk.times.len();
        let n_arms = self.n_arms;
        let s = self.cfg.singular_angle;
        for a in 0..n_arms {
            let mirror = if self.cfg.left[a] { -1.0 } else { 1.0 };
            // Body axes -> shoulder frame (visprim.arm.BODY_TO_SHOULDER), after the mirror.
            let signs = [1.0, -mirror, -1.0];
            let arm = &mut self.arms[a];
            for t in 0..k {
                let centres: [[f64; 3]; 3] = match chunk.joints {
                    Some(j) => {
                        let at = (t * 3 * n_arms + 3 * a) * 3;
                        let p = |i: usize| [j[at + 3 * i], j[at + 3 * i + 1], j[at + 3 * i + 2]];
                        [p(0), p(1), p(2)]
                    }
                    None => {
                        let at = (t * 4 * n_arms + 4 * a) * 3;
                        let m = |i: usize, c: usize| chunk.markers[at + 3 * i + c];
                        let wrist = [m(2, 0), m(2, 1), m(2, 2)];
                        let elbow: [f64; 3] = std::array::from_fn(|c| 2.0 * m(1, c) - wrist[c]);
                        let shoulder: [f64; 3] = std::array::from_fn(|c| 2.0 * m(0, c) - elbow[c]);
                        [shoulder, elbow, wrist]
                    }
                };
                let mut upper: [f64; 3] = std::array::from_fn(|c| centres[1][c] - centres[0][c]);
                let mut fore: [f64; 3] = std::array::from_fn(|c| centres[2][c] - centres[1][c]);
                if let Some(b) = chunk.body_frame {
                    let fr = &b[9 * t..9 * t + 9];
                    let to_body = |v: [f64; 3]| -> [f64; 3] {
                        std::array::from_fn(|i| fr[i] * v[0] + fr[3 + i] * v[1] + fr[6 + i] * v[2])
                    };
                    upper = to_body(upper);
                    fore = to_body(fore);
                }
                let dir = &mut out.directions[(t * n_arms + a) * 6..(t * n_arms + a) * 6 + 6];
                for (b, (v, what)) in [
                    (upper, "upper arm (shoulder→elbow)"),
                    (fore, "forearm (elbow→wrist)"),
                ]
                .into_iter()
                .enumerate()
                {
                    let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    if norm < MIN_BONE_LENGTH {
                        return Err(Error::InvalidArgument(format!(
                            "the {} {what} has zero length at frame {t} of the chunk \
                             (coincident joint centres); cannot compute arm angles",
                            if self.cfg.left[a] { "left" } else { "right" }
                        )));
                    }
                    let unit: [f64; 3] = std::array::from_fn(|c| v[c] / norm);
                    dir[3 * b..3 * b + 3].copy_from_slice(&unit);
                    let shoulder: [f64; 3] = std::array::from_fn(|c| signs[c] * unit[c]);
                    if b == 0 {
                        arm.u[t] = shoulder;
                    } else {
                        arm.f[t] = shoulder;
                    }
                }
                let (u, f) = (arm.u[t], arm.f[t]);
                arm.beta[t] = u[2].clamp(-1.0, 1.0).acos();
                arm.elbow[t] = (u[0] * f[0] + u[1] * f[1] + u[2] * f[2])
                    .clamp(-1.0, 1.0)
                    .acos();
                arm.gamma[t] = u[1].atan2(u[0]);
                arm.ok[t] = arm.beta[t] > s && arm.beta[t] < PI - s;
            }
            self.continuity
                .apply(&mut arm.gamma, &arm.ok, chunk.times)?;
            for t in 0..k {
                let (g, b, f) = (arm.gamma[t], arm.beta[t], arm.f[t]);
                let (sg, cg) = (g.sin(), g.cos());
                let (sb, cb) = (b.sin(), b.cos());
                let x1 = cg * f[0] + sg * f[1];
                let y1 = -sg * f[0] + cg * f[1];
                let vx = cb * x1 - sb * f[2];
                arm.alpha[t] = y1.atan2(vx);
                arm.ok[t] = arm.elbow[t] > s && arm.elbow[t] < PI - s;
            }
            self.continuity
                .apply(&mut arm.alpha, &arm.ok, chunk.times)?;
            for t in 0..k {
                let row = &mut out.angles[(t * n_arms + a) * 4..(t * n_arms + a) * 4 + 4];
                row.copy_from_slice(&[arm.gamma[t], arm.beta[t], arm.alpha[t], arm.elbow[t]]);
            }
        }
        Ok(())
    }

    /// The first chunk sets the period and the window.
    fn set_period(&mut self, times: &[f64]) -> Result<()> {
        if self.period.is_some() {
            return Ok(());
        }
        let mut steps: Vec<f64> = try_with_capacity(times.len().saturating_sub(1), "steps")?;
        steps.extend(times.windows(2).map(|w| w[1] - w[0]));
        let median = if steps.is_empty() {
            DEFAULT_PERIOD
        } else {
            steps.sort_by(f64::total_cmp);
            let n = steps.len();
            if n % 2 == 1 {
                steps[n / 2]
            } else {
                (steps[n / 2 - 1] + steps[n / 2]) / 2.0
            }
        };
        let period = if median > 0.0 { median } else { DEFAULT_PERIOD };
        if self.cfg.threshold.adaptive {
            let frames = (self.cfg.threshold.speed_window / period).ceil();
            let frames = if frames.is_finite() && frames < (1u64 << 40) as f64 {
                (frames as usize).max(MIN_WINDOW)
            } else {
                return Err(Error::InvalidArgument(format!(
                    "a window of {} s at {period} s frames is too long",
                    self.cfg.threshold.speed_window
                )));
            };
            self.window = Some(RollingWindow::new(frames)?);
        }
        self.period = Some(period);
        Ok(())
    }

    fn speeds(&mut self, times: &[f64], values: &[f64], speeds: &mut Vec<f64>) -> Result<()> {
        self.set_period(times)?;
        let stop = self.n_frames + times.len() - 1; // the newest frame waits for its successor
        self.advance(times, values, stop, speeds)
    }

    /// Appends the new frames, then `z` of frames `[next, stop)`.
    fn advance(
        &mut self,
        times: &[f64],
        values: &[f64],
        stop: usize,
        speeds: &mut Vec<f64>,
    ) -> Result<()> {
        let c = self.channels;
        let lo = self.next.saturating_sub(1);
        let mut wt = std::mem::take(&mut self.work_times);
        let mut wv = std::mem::take(&mut self.work_values);
        wt.clear();
        wv.clear();
        reserve(&mut wt, self.tail_times.len() + times.len())?;
        reserve(&mut wv, self.tail_values.len() + values.len())?;
        wt.extend_from_slice(&self.tail_times);
        wt.extend_from_slice(times);
        wv.extend_from_slice(&self.tail_values);
        wv.extend_from_slice(values);
        let n = wt.len(); // frames [lo, lo + n)
        let n_total = self.n_frames + times.len();
        let m = stop.saturating_sub(self.next);
        reserve(speeds, elements::<f64>(&[m, SPEED_COLUMNS], "speeds")?)?;
        let th = self.cfg.threshold;
        for f in self.next..stop {
            let i = f - lo;
            let x = |r: usize| &wv[r * c..(r + 1) * c];
            let mut z = 0.0;
            if f > 0 && i + 1 < n {
                let hs = wt[i] - wt[i - 1];
                let hd = wt[i + 1] - wt[i];
                let (hs2, hd2) = (hs * hs, hd * hd);
                let den = hs * hd * (hd + hs);
                for ((&a, &b), &p) in x(i - 1).iter().zip(x(i)).zip(x(i + 1)) {
                    let v = (hs2 * p - hd2 * a + (hd2 - hs2) * b) / den;
                    z += v * v;
                }
            } else if f == 0 {
                if n > 1 {
                    let h = wt[1] - wt[0];
                    for (&a, &b) in x(0).iter().zip(x(1)) {
                        let v = (b - a) / h;
                        z += v * v;
                    }
                }
            } else {
                let h = wt[i] - wt[i - 1];
                for (&a, &b) in x(i - 1).iter().zip(x(i)) {
                    let v = (b - a) / h;
                    z += v * v;
                }
            }
            let decided = if i + 1 < n { wt[i + 1] } else { wt[n - 1] };
            let threshold = if th.adaptive {
                if let Some(w) = &mut self.window {
                    w.push(z);
                    if f % th.every == 0 {
                        let q = w.quantile(th.quantile);
                        self.current = py_min(py_max(th.fraction * q, th.c / th.slowest), th.c);
                    }
                }
                self.current
            } else {
                th.c
            };
            speeds.extend_from_slice(&[z, wt[i], decided, threshold]);
        }
        self.n_frames = n_total;
        self.next = self.next.max(stop);
        // Keep frames [max(0, next - 1), n_total).
        let keep_from = self.next.saturating_sub(1).max(lo) - lo;
        self.tail_times.clear();
        self.tail_values.clear();
        self.tail_times.extend_from_slice(&wt[keep_from..]);
        self.tail_values.extend_from_slice(&wv[keep_from * c..]);
        self.work_times = wt;
        self.work_values = wv;
        Ok(())
    }
}

fn reserve(v: &mut Vec<f64>, len: usize) -> Result<()> {
    let more = len.saturating_sub(v.len());
    v.try_reserve(more)
        .map_err(|_| Error::Memory(format!("cannot allocate {len} values")))
}

fn check_len(len: usize, dims: &[usize], what: &str) -> Result<()> {
    let want = elements::<f64>(dims, what)?;
    if len != want {
        return Err(Error::Shape(format!(
            "{what}: {len} values where {dims:?} needs {want}"
        )));
    }
    Ok(())
}

fn check_finite(x: &[f64], what: &str) -> Result<()> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Error::NonFinite(format!(
            "{what} contain NaN or infinity (value {i} of the chunk)"
        ))),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::butter_sos;

    fn config(features: Features, adaptive: bool, singular: f64) -> Config {
        Config {
            left: vec![false, true],
            features,
            singular_angle: singular,
            sos: butter_sos(2, 0.25).unwrap(),
            threshold: Threshold {
                c: 0.5,
                adaptive,
                quantile: 0.95,
                fraction: 0.02,
                slowest: 100.0,
                every: 8,
                speed_window: 1.0,
            },
        }
    }

    /// Two arms swinging, markers (n, 8, 3) and times (n,).
    fn stream(n: usize) -> (Vec<f64>, Vec<f64>) {
        let times: Vec<f64> = (0..n).map(|i| 0.034 * i as f64).collect();
        let mut markers = Vec::new();
        for (i, &t) in times.iter().enumerate() {
            for arm in 0..2 {
                let side = if arm == 0 { -1.0 } else { 1.0 };
                let a = 0.9 * (1.3 * t).sin() + 0.2 * arm as f64;
                let e = 0.6 + 0.4 * (0.7 * t + i as f64 * 1e-3).cos();
                let shoulder = [0.0, 0.2 * side, 1.4];
                let elbow = [
                    shoulder[0] + 0.3 * a.sin(),
                    shoulder[1] + 0.05 * side,
                    shoulder[2] - 0.3 * a.cos(),
                ];
                let wrist = [
                    elbow[0] + 0.26 * (a + e).sin(),
                    elbow[1] + 0.02,
                    elbow[2] - 0.26 * (a + e).cos(),
                ];
                let mid = |p: [f64; 3], q: [f64; 3]| -> [f64; 3] {
                    std::array::from_fn(|c| 0.5 * (p[c] + q[c]))
                };
                for p in [mid(shoulder, elbow), mid(elbow, wrist), wrist, wrist] {
                    markers.extend_from_slice(&p);
                }
            }
        }
        (times, markers)
    }

    fn run(cfg: &Config, n: usize, chunk: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let (times, markers) = stream(n);
        let mut fe = OnlineFrontEnd::new(cfg.clone()).unwrap();
        let (mut angles, mut values, mut speeds) = (vec![], vec![], vec![]);
        let mut out = Output::default();
        for a in (0..n).step_by(chunk) {
            let b = (a + chunk).min(n);
            let c = Chunk {
                times: &times[a..b],
                markers: &markers[a * 24..b * 24],
                joints: None,
                body_frame: None,
            };
            fe.push(c, &mut out).unwrap();
            angles.extend_from_slice(&out.angles);
            values.extend_from_slice(&out.values);
            speeds.extend_from_slice(&out.speeds);
        }
        fe.finish(&mut out).unwrap();
        speeds.extend_from_slice(&out.speeds);
        (angles, values, speeds)
    }

    #[test]
    fn one_z_per_frame_and_the_same_for_any_chunking_of_a_direction_model() {
        let cfg = config(Features::Directions, true, 0.0);
        let (a1, v1, s1) = run(&cfg, 90, 1);
        assert_eq!(a1.len(), 90 * 8);
        assert_eq!(v1.len(), 90 * 12);
        assert_eq!(s1.len(), 90 * SPEED_COLUMNS);
        for chunk in [7, 64, 90] {
            let (a, v, s) = run(&cfg, 90, chunk);
            for (x, y) in a.iter().zip(&a1).chain(v.iter().zip(&v1)) {
                assert!((x - y).abs() < 1e-12, "chunk {chunk}: {x} vs {y}");
            }
            for (x, y) in s.iter().zip(&s1) {
                assert!((x - y).abs() <= 1e-9 * y.abs().max(1.0), "chunk {chunk}");
            }
        }
        // Unit bone directions, times in order, the decided-at time is the next frame's.
        for row in v1.chunks_exact(3) {
            let n = (row[0] * row[0] + row[1] * row[1] + row[2] * row[2]).sqrt();
            assert!((n - 1.0).abs() < 1e-12);
        }
        for (i, row) in s1.chunks_exact(SPEED_COLUMNS).enumerate() {
            assert!((row[1] - 0.034 * i as f64).abs() < 1e-12);
            let next = 0.034 * (i + 1).min(89) as f64;
            assert!((row[2] - next).abs() < 1e-12);
            assert!(row[0] >= 0.0 && row[3] <= 0.5 && row[3] >= 0.5 / 100.0);
        }
    }

    #[test]
    fn z_is_the_summed_squared_gradient_of_the_channels() {
        let cfg = config(Features::Zyz, false, 5f64.to_radians());
        let (_, v, s) = run(&cfg, 40, 3);
        let c = 8;
        let t = |i: usize| 0.034 * i as f64;
        for f in 0..40 {
            let d: Vec<f64> = (0..c)
                .map(|ch| {
                    let x = |i: usize| v[i * c + ch];
                    if f == 0 {
                        (x(1) - x(0)) / (t(1) - t(0))
                    } else if f == 39 {
                        (x(39) - x(38)) / (t(39) - t(38))
                    } else {
                        (x(f + 1) - x(f - 1)) / (t(f + 1) - t(f - 1)) // uniform steps
                    }
                })
                .collect();
            let z: f64 = d.iter().map(|v| v * v).sum();
            let got = s[f * SPEED_COLUMNS];
            assert!(
                (got - z).abs() <= 1e-8 * z.max(1.0),
                "frame {f}: {got} vs {z}"
            );
            assert_eq!(s[f * SPEED_COLUMNS + 3], 0.5); // fixed threshold
        }
    }

    #[test]
    fn the_rolling_quantile_is_numpys_over_the_window() {
        let mut w = RollingWindow::new(5).unwrap();
        let xs = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0, 5.0, 3.0];
        for (i, &x) in xs.iter().enumerate() {
            w.push(x);
            let mut held: Vec<f64> = xs[i.saturating_sub(4)..=i].to_vec();
            held.sort_by(f64::total_cmp);
            assert_eq!(w.sorted, held);
            // numpy.quantile(held, 0.5) and (.., 1.0): the median and the maximum.
            let n = held.len();
            let median = if n % 2 == 1 {
                held[n / 2]
            } else {
                0.5 * (held[n / 2 - 1] + held[n / 2])
            };
            assert!((w.quantile(0.5) - median).abs() < 1e-12);
            assert_eq!(w.quantile(1.0), held[n - 1]);
            assert_eq!(w.quantile(0.0), held[0]);
        }
        // numpy.quantile([1, 2, 3, 4, 5], 0.95) = 4.8
        let mut w = RollingWindow::new(8).unwrap();
        for x in [5.0, 1.0, 4.0, 2.0, 3.0] {
            w.push(x);
        }
        assert!((w.quantile(0.95) - 4.8).abs() < 1e-12);
    }

    #[test]
    fn unwrap_and_interp_follow_numpy() {
        let mut x = vec![3.0, -3.0, 3.1, -3.1];
        unwrap(&mut x);
        let want = [3.0, TAU - 3.0, 3.1, TAU - 3.1];
        for (a, b) in x.iter().zip(want) {
            assert!((a - b).abs() < 1e-12);
        }
        let (xp, fp) = ([0.0, 1.0, 3.0], [1.0, 3.0, 7.0]);
        assert_eq!(interp(-1.0, &xp, &fp), 1.0);
        assert_eq!(interp(4.0, &xp, &fp), 7.0);
        assert_eq!(interp(1.0, &xp, &fp), 3.0);
        assert!((interp(2.0, &xp, &fp) - 5.0).abs() < 1e-12);
        // Singular frames: interpolated in time between the well-defined ones, 0 if none.
        let mut c = Continuity::default();
        let mut g = vec![0.5, 9.0, 1.5];
        c.apply(&mut g, &[true, false, true], &[0.0, 1.0, 2.0])
            .unwrap();
        assert!((g[1] - 1.0).abs() < 1e-12);
        let mut g = vec![0.5, 9.0];
        c.apply(&mut g, &[false, false], &[0.0, 1.0]).unwrap();
        assert_eq!(g, [0.0, 0.0]);
    }

    #[test]
    fn refuses_bad_input_and_changes_nothing() {
        let cfg = config(Features::Directions, true, 0.0);
        let mut fe = OnlineFrontEnd::new(cfg.clone()).unwrap();
        let (times, markers) = stream(4);
        let mut out = Output::default();
        let chunk = |a: usize, b: usize| Chunk {
            times: &times[a..b],
            markers: &markers[a * 24..b * 24],
            joints: None,
            body_frame: None,
        };
        fe.push(chunk(0, 2), &mut out).unwrap();
        let bad_len = Chunk {
            markers: &markers[..23],
            ..chunk(2, 3)
        };
        assert!(matches!(fe.push(bad_len, &mut out), Err(Error::Shape(_))));
        assert!(matches!(
            fe.push(chunk(1, 2), &mut out),
            Err(Error::InvalidArgument(_))
        ));
        let mut nan = markers[48..72].to_vec();
        nan[5] = f64::NAN;
        let bad = Chunk {
            markers: &nan,
            ..chunk(2, 3)
        };
        assert!(matches!(fe.push(bad, &mut out), Err(Error::NonFinite(_))));
        let zero = vec![0.0; 24];
        let bad = Chunk {
            markers: &zero,
            ..chunk(2, 3)
        };
        assert!(matches!(
            fe.push(bad, &mut out),
            Err(Error::InvalidArgument(_))
        ));
        assert_eq!(fe.n_frames(), 2);
        fe.push(chunk(2, 4), &mut out).unwrap();
        let (_, v, _) = run(&cfg, 4, 2);
        let whole = {
            let mut f = OnlineFrontEnd::new(cfg.clone()).unwrap();
            f.push(chunk(0, 2), &mut out).unwrap();
            f.push(chunk(2, 4), &mut out).unwrap();
            out.values.clone()
        };
        assert_eq!(whole, v[2 * 12..]);
        let mut bad_cfg = cfg.clone();
        bad_cfg.threshold.c = 0.0;
        assert!(OnlineFrontEnd::new(bad_cfg).is_err());
        let mut bad_cfg = cfg;
        bad_cfg.left.clear();
        assert!(OnlineFrontEnd::new(bad_cfg).is_err());
    }

    #[test]
    fn reset_starts_again_and_memory_stays_flat() {
        let cfg = config(Features::Zyz, true, 5f64.to_radians());
        let (times, markers) = stream(300);
        let mut fe = OnlineFrontEnd::new(cfg).unwrap();
        let mut out = Output::default();
        let mut first = vec![];
        let mut sizes = vec![];
        for round in 0..2 {
            let mut speeds = vec![];
            for a in (0..300).step_by(10) {
                let c = Chunk {
                    times: &times[a..a + 10],
                    markers: &markers[a * 24..(a + 10) * 24],
                    joints: None,
                    body_frame: None,
                };
                fe.push(c, &mut out).unwrap();
                speeds.extend_from_slice(&out.speeds);
                sizes.push(fe.memory_bytes());
            }
            if round == 0 {
                first = speeds;
                fe.reset();
            } else {
                assert_eq!(speeds, first);
            }
        }
        assert_eq!(fe.window_frames(), Some(30)); // 1 s at 34 ms
        assert!(sizes[1..].iter().all(|&s| s == sizes[1]));
    }
}
