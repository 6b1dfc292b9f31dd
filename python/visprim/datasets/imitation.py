"""How the subjects of the paper preset imitate a gesture: style, tempo and coarticulation.

The gestures of :mod:`visprim.datasets.gestures` are performed by subjects who differ as
people do. SD = standard deviation. Each value has a reason; the *calibrated* ones were
set so that ``visprim demo`` reproduces the paper's error tables (Table 3 within a factor
1.3 at the rows the paper reports, SEG-2 needing more eigenvectors than SEG-1, SEG-2
boundary F1 ≥ 0.8 at ±100 ms); the method was never tuned.

* **Posture** (:attr:`Performer.posture_offset`): every target shifted by a per-subject
  offset, SD 7° (γ), 5° (β), 10° (α), 7° (θ): people hold "the same" posture with the
  upper arm a few degrees apart and differ most in humeral rotation, which a video barely
  shows. Each visit of a target gets a further jitter, SD 13° (γ), 11° (β), 16° (α),
  12° (θ) (*calibrated*: the paper's subjects imitated each video from memory, so their
  endpoints scatter widely; this scatter sets the error at many clusters, k = 100–170).
* **Amplitude** (:attr:`Performer.amplitude`): displacements from the hanging arm scaled by
  a per-subject factor (SD 0.12, within 0.75–1.25) and per stroke by SD 0.12: some people
  wave big, others small, and nobody repeats an amplitude exactly.
* **Hanging arm** (:attr:`Performer.hang`): the relaxed arm hangs 8–15° off vertical, close
  to the Z-Y-Z singularity at β = 0, in a direction γ that differs per subject (uniform
  over ±150°) and per visit (SD 90°, α turning the other way so the forearm keeps its
  heading; *calibrated*): near β = 0 the direction of a slight tilt is arbitrary. The
  elbow hangs flexed 15–30° and humeral rotation differs per subject (SD 15°). (Nearer the
  axis, or with a straighter elbow, the skin-mounted sensors' bias and 2 mm noise make the
  inverse kinematics' γ and α swing by tens of degrees at rest, which SEG-2 cuts into
  spurious segments; 8° and 15° keep the SEG-2 boundary F1 above 0.8.)
* **Paths near the hanging arm**: strokes from and to the hanging arm are straight in
  swing-twist coordinates (:func:`to_swing`: the upper arm's swing away from vertical as a
  2-D vector, and the twist γ + α), as a relaxed arm lifts its elbow straight towards the
  target; the Euler angle γ then turns to the target's azimuth while the arm is still close
  to vertical, a fast, subject- and visit-dependent sweep of γ and α (*calibrated*: this
  is what makes SEG-2, whose partition includes the first and last stroke of every
  movement, need more eigenvectors than SEG-1, which never keeps them). All other
  strokes are straight in the Euler angles.
* **Style and imperfect paths** (:attr:`Performer.style`): every stroke bends by a
  per-subject detour (SD 0.12) plus a per-stroke one (SD 0.10), in units of the angle's
  "reach" ``0.5·|Δθ_j| + 0.1·Σ|Δθ|`` (a path bends mostly in the angles that move);
  circles and figure-eights scale by a per-subject 0.7–1.3 and per trial 0.85–1.15.
* **Tempo**: imitations take 1.25 × the demonstration's stroke durations (*calibrated*:
  people imitating from memory move more slowly than a demonstrator; faster strokes make
  SEG-1's 300 ms window chain neighbouring zero-velocity crossings), times a per-subject
  factor (log-normal SD 0.15, within 0.7–1.4) and a per-stroke jitter (SD 12 %); strokes
  last 0.25–2.2 s.
* **Coarticulation**: consecutive strokes overlap by a per-subject fraction 0.05–0.25 of
  the shorter one (± 0.08 per boundary, never below 0), so the arm does not stop between
  them; each angle starts its part of a stroke with its own lag (per subject SD 10–30 ms)
  and lasts ± 6 %, so the four angles do not reach zero velocity together. The ground-truth
  boundary between blended strokes is the *handover*: the instant in their overlap where
  the next stroke's own joint speed overtakes the current one's.
* **Pauses**: with a per-subject probability 0.05–0.25, a stop of 0.08–0.3 s between two
  strokes instead of an overlap, and 0.15–0.3 s after every pointing stroke (the boundary
  is then the middle of the pause; longer holds put it more than the ±100 ms of the
  boundary scores from any instant a segmentation can single out inside the rest).
* **Timing**: a reaction delay of 0.3–0.7 s before the first stroke and a hold of
  0.3–0.7 s after the last (the paper's videos began and ended at rest).

Angles are clipped to 1° ≤ β ≤ 175° and 5° ≤ θ ≤ 150° (anatomy; the generator never
crosses the β = 0 axis itself, the hanging arm approaches it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.datasets.anthropometry import Body, sample_body
from visprim.datasets.gestures import HANG_DEG, Gesture
from visprim.datasets.vocabulary import minimum_jerk

MIN_BETA = np.radians(1.0)
MAX_BETA = np.radians(175.0)
ELBOW_RANGE = (np.radians(5.0), np.radians(150.0))
STROKE_DURATION_RANGE_S = (0.25, 2.2)
#: Imitations are slower than the demonstrations (see the module docstring).
IMITATION_TEMPO = 1.25

#: Per-subject posture offset SD, degrees (γ, β, α, θ).
POSTURE_SD_DEG = (7.0, 5.0, 10.0, 7.0)
#: Per-visit target jitter SD, degrees (γ, β, α, θ).
VISIT_SD_DEG = (13.0, 11.0, 16.0, 12.0)
AMPLITUDE_SD = 0.12
AMPLITUDE_RANGE = (0.75, 1.25)
STROKE_AMPLITUDE_SD = 0.12
STYLE_SD = 0.12
TEMPO_LOG_SD = 0.15
TEMPO_RANGE = (0.7, 1.4)
DURATION_JITTER_SD = 0.12
OVERLAP_RANGE = (0.05, 0.25)
OVERLAP_JITTER_SD = 0.08
LAG_SD_RANGE_S = (0.01, 0.03)
PAUSE_PROBABILITY_RANGE = (0.05, 0.25)
PAUSE_RANGE_S = (0.08, 0.3)
POINT_HOLD_RANGE_S = (0.15, 0.3)
LEAD_RANGE_S = (0.3, 0.7)
TAIL_RANGE_S = (0.3, 0.7)
HANG_BETA_RANGE_DEG = (8.0, 15.0)
PATH_NOISE_SD = 0.10
HANG_VISIT_GAMMA_SD_DEG = 90.0


@dataclass(frozen=True)
class Performer:
    """One subject of the paper preset (angles in radians, times in seconds).

    Attributes
    ----------
    index : int
    body : Body
        Height, segment lengths (m) and shoulder position (m).
    skin_offsets : (4, 3) metres
        Sensor offsets in segment coordinates (:mod:`visprim.datasets.measurement`).
    tempo, amplitude : float
        Duration factor (> 1 = slower) and displacement scale.
    posture_offset : (4,) rad
        Added to every target.
    hang : (4,) rad
        This subject's hanging arm.
    style : (4,) rad per rad
        Detour per unit of stroke travel.
    loop_scale : float
        Scale of circles and figure-eights.
    overlap : float
        Mean coarticulation overlap, fraction of the shorter stroke.
    lag_sd : float, seconds
        SD of each angle's onset lag within a stroke.
    pause_probability : float
    """

    index: int
    body: Body
    skin_offsets: NDArray[np.float64]
    tempo: float
    amplitude: float
    posture_offset: NDArray[np.float64]
    hang: NDArray[np.float64]
    style: NDArray[np.float64]
    loop_scale: float
    overlap: float
    lag_sd: float
    pause_probability: float


def sample_performer(index: int, rng: np.random.Generator) -> Performer:
    """Draw subject ``index`` of the paper preset from ``rng`` (fixed number of draws)."""
    from visprim.datasets.measurement import sample_skin_offsets

    body = sample_body(rng)
    skin = sample_skin_offsets(rng)
    tempo = float(np.clip(np.exp(rng.normal(0.0, TEMPO_LOG_SD)), *TEMPO_RANGE))
    amplitude = float(np.clip(rng.normal(1.0, AMPLITUDE_SD), *AMPLITUDE_RANGE))
    offset = np.radians(rng.normal(0.0, POSTURE_SD_DEG))
    hang = np.radians(
        [
            rng.uniform(-150.0, 150.0),
            rng.uniform(*HANG_BETA_RANGE_DEG),
            HANG_DEG[2] + rng.normal(0.0, 15.0),
            rng.uniform(15.0, 30.0),
        ]
    )
    style = rng.normal(0.0, STYLE_SD, size=4)
    loop_scale = float(rng.uniform(0.7, 1.3))
    overlap = float(rng.uniform(*OVERLAP_RANGE))
    lag_sd = float(rng.uniform(*LAG_SD_RANGE_S))
    pause = float(rng.uniform(*PAUSE_PROBABILITY_RANGE))
    return Performer(
        index=index,
        body=body,
        skin_offsets=skin,
        tempo=tempo,
        amplitude=amplitude,
        posture_offset=offset,
        hang=hang,
        style=style,
        loop_scale=loop_scale,
        overlap=overlap,
        lag_sd=lag_sd,
        pause_probability=pause,
    )


def _clip(p: NDArray[np.float64]) -> NDArray[np.float64]:
    p = p.copy()
    p[..., 1] = np.clip(p[..., 1], MIN_BETA, MAX_BETA)
    p[..., 3] = np.clip(p[..., 3], *ELBOW_RANGE)
    return p


_HANG = np.radians(np.asarray(HANG_DEG))


def _is_hang(target: NDArray[np.float64]) -> bool:
    return bool(np.allclose(target, _HANG))


@dataclass(frozen=True)
class BlendedMotion:
    """Overlapping minimum-jerk strokes, each angle on its own clock (coarticulation).

    A stroke with ``chart[k]`` moves in swing-twist coordinates (:func:`to_swing`) from
    ``euler_start[k]``; it contributes the change of the Euler angles along that path.
    The others move in the Euler angles directly, as below.

    ``θ_j(t) = start_j + Σ_k [Δ_kj φ(s_kj) + bend_kj 4φ(s_k)(1 − φ(s_k))] + loops`` with
    ``s_kj = (t − onset_kj) / duration_kj`` clipped to [0, 1] and ``s_k`` the stroke's own
    normalised time. Loops (n turns): "circle" ``γ += A sin 2πnφ, β += B (1 − cos 2πnφ)``,
    "figure8" ``γ += A sin 2πnφ, β += B sin 4πnφ``.

    Attributes (radians, seconds)
    -----------------------------
    start : (4,) ; onset, duration : (K, 4) ; stroke_onset, stroke_duration : (K,) ;
    delta, bend : (K, 4) ; loop : (K, 2) ; loop_kind : (K,) int (0 none, 1 circle,
    2 figure-eight) ; loop_turns : (K,) ; boundaries : (K + 1,) ; labels : (K,) ; end_time : float.
    """

    start: NDArray[np.float64]
    onset: NDArray[np.float64]
    duration_: NDArray[np.float64]
    stroke_onset: NDArray[np.float64]
    stroke_duration: NDArray[np.float64]
    delta: NDArray[np.float64]
    bend: NDArray[np.float64]
    loop: NDArray[np.float64]
    loop_kind: NDArray[np.int64]
    loop_turns: NDArray[np.float64]
    chart: NDArray[np.bool_]
    euler_start: NDArray[np.float64]
    boundaries: NDArray[np.float64]
    labels: NDArray[np.int64]
    end_time: float

    @property
    def duration(self) -> float:
        """Total length in seconds."""
        return self.end_time

    def angles(self, times: ArrayLike) -> NDArray[np.float64]:
        """Angles (T, 4) in radians at ``times`` (s)."""
        t = np.asarray(times, dtype=np.float64)
        s = np.clip((t[:, None, None] - self.onset[None]) / self.duration_[None], 0.0, 1.0)
        sk = np.clip((t[:, None] - self.stroke_onset[None]) / self.stroke_duration[None], 0, 1)
        phi = minimum_jerk(sk)
        part = (
            minimum_jerk(s) * self.delta[None]
            + (4.0 * phi * (1.0 - phi))[..., None] * (self.bend[None])
        )
        out = self.start[None] + part[:, ~self.chart].sum(axis=1)
        order = np.argsort(t, kind="stable")
        for k in np.flatnonzero(self.chart):
            e0 = self.euler_start[k]
            c = to_swing(e0)[None] + part[order, k]
            e = np.empty_like(c)
            e[order] = from_swing(c, reference_gamma=float(e0[0]))
            out += e - e0[None]
        two_pi = 2.0 * np.pi * phi * self.loop_turns[None]
        circle = self.loop_kind == 1
        eight = self.loop_kind == 2
        out[:, 0] += np.sin(two_pi) @ (self.loop[:, 0] * (circle | eight))
        out[:, 1] += (1.0 - np.cos(two_pi)) @ (self.loop[:, 1] * circle)
        out[:, 1] += np.sin(2.0 * two_pi) @ (self.loop[:, 1] * eight)
        out[:, 1] = np.clip(out[:, 1], MIN_BETA, MAX_BETA)
        out[:, 3] = np.clip(out[:, 3], *ELBOW_RANGE)
        return out


def to_swing(angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """Euler angles (..., 4) → swing-twist coordinates (β cos γ, β sin γ, γ + α, θ).

    The arm moves along straight lines in these coordinates: the upper arm's *swing* away
    from hanging as a 2-D vector (no singularity at β = 0, where a reach starts by turning
    γ at once to the target's azimuth) and the *twist* γ + α that stays defined there."""
    a = np.asarray(angles, dtype=np.float64)
    g, b = a[..., 0], a[..., 1]
    return np.stack([b * np.cos(g), b * np.sin(g), g + a[..., 2], a[..., 3]], axis=-1)


def from_swing(c: NDArray[np.float64], reference_gamma: float = 0.0) -> NDArray[np.float64]:
    """Inverse of :func:`to_swing` for rows in time order: γ is unwrapped in time, its
    first value on the turn nearest ``reference_gamma``."""
    g = np.unwrap(np.arctan2(c[:, 1], c[:, 0]))
    if g.size:
        g += 2 * np.pi * np.round((reference_gamma - g[0]) / (2 * np.pi))
    b = np.hypot(c[:, 0], c[:, 1])
    return np.stack([g, b, c[:, 2] - g, c[:, 3]], axis=1)


def perform(gesture: Gesture, who: Performer, rng: np.random.Generator) -> BlendedMotion:
    """The subject's imitation of ``gesture`` as a continuous :class:`BlendedMotion`."""
    strokes = gesture.strokes
    k = len(strokes)
    lo, hi = STROKE_DURATION_RANGE_S
    hang_nominal = _HANG

    def personal(target_deg: tuple[float, float, float, float]) -> NDArray[np.float64]:
        target = np.radians(np.asarray(target_deg, dtype=np.float64))
        if _is_hang(target):
            # The hanging arm tilts a little differently each time (a new direction γ; α
            # takes the opposite turn so the forearm keeps its heading).
            turn = np.radians(rng.normal(0.0, HANG_VISIT_GAMMA_SD_DEG))
            return who.hang + np.array([turn, 0.0, -turn, 0.0])
        scale = who.amplitude * (1.0 + rng.normal(0.0, STROKE_AMPLITUDE_SD))
        p = hang_nominal + scale * (target - hang_nominal) + who.posture_offset
        return _clip(p + np.radians(rng.normal(0.0, VISIT_SD_DEG)))

    start_euler = personal(gesture.start)
    targets_euler = np.stack([personal(s.target) for s in strokes])
    # γ and α of each target on the turn nearest the previous one (no 2π jumps).
    chain = np.vstack([start_euler, targets_euler])
    chain[:, 0] = np.unwrap(chain[:, 0])
    chain[:, 2] = np.unwrap(chain[:, 2])
    cs = to_swing(chain)
    # Strokes from and to the hanging arm are straight in swing-twist coordinates (see
    # to_swing); the others are straight in the Euler angles.
    names = [gesture.start] + [s.target for s in strokes]
    hang = np.array([n == HANG_DEG for n in names])
    chart = hang[:-1] | hang[1:]
    delta = np.where(chart[:, None], cs[1:] - cs[:-1], chain[1:] - chain[:-1])
    travel = np.abs(delta)
    # Detours given in Euler degrees (γ, β, α, θ); for a swing-twist stroke mapped to those
    # coordinates at the stroke's middle (first order).
    mid = 0.5 * (chain[:-1] + chain[1:])
    bend_e = np.radians(np.asarray([s.bend for s in strokes], dtype=np.float64)) * who.amplitude
    cg, sg, bm = np.cos(mid[:, 0]), np.sin(mid[:, 0]), mid[:, 1]
    bend_c = np.stack(
        [
            cg * bend_e[:, 1] - bm * sg * bend_e[:, 0],
            sg * bend_e[:, 1] + bm * cg * bend_e[:, 0],
            bend_e[:, 0] + bend_e[:, 2],
            bend_e[:, 3],
        ],
        axis=1,
    )
    bend = np.where(chart[:, None], bend_c, bend_e)
    # Detours scale with how far each angle moves (plus a little of the whole stroke's
    # travel): the angles that move are the ones whose path bends.
    reach = 0.5 * travel + 0.1 * travel.sum(axis=1, keepdims=True)
    bend = bend + who.style[None] * reach
    bend = bend + rng.normal(0.0, PATH_NOISE_SD, size=(k, 4)) * reach
    loop = np.radians(np.asarray([s.loop for s in strokes], dtype=np.float64))
    loop = loop * who.loop_scale * rng.uniform(0.85, 1.15, size=(k, 1))
    turns = np.array([float(s.turns) for s in strokes])
    kind = np.array([{"circle": 1, "figure8": 2}.get(s.kind, 0) for s in strokes], dtype=np.int64)

    dur = np.array([s.duration for s in strokes]) * who.tempo * IMITATION_TEMPO
    dur = np.clip(dur * (1.0 + rng.normal(0.0, DURATION_JITTER_SD, size=k)), lo, hi)
    overlap = np.clip(who.overlap + rng.normal(0.0, OVERLAP_JITTER_SD, size=k - 1), 0.0, 0.45)
    pause = rng.random(k - 1) < who.pause_probability
    pause_len = rng.uniform(*PAUSE_RANGE_S, size=k - 1)
    pointing = np.array([s.kind == "point" for s in strokes[:-1]], dtype=bool)
    pause |= pointing
    pause_len = np.where(pointing, rng.uniform(*POINT_HOLD_RANGE_S, size=k - 1), pause_len)
    lead = float(rng.uniform(*LEAD_RANGE_S))
    tail = float(rng.uniform(*TAIL_RANGE_S))

    onset = np.empty(k)
    boundaries = np.empty(k + 1)
    t = lead
    boundaries[0] = t
    for i in range(k):
        onset[i] = t
        end = t + dur[i]
        if i == k - 1:
            boundaries[k] = end
            break
        if pause[i]:
            boundaries[i + 1] = end + 0.5 * pause_len[i]
            t = end + pause_len[i]
        else:
            ov = overlap[i] * min(dur[i], dur[i + 1])
            t = end - ov
            boundaries[i + 1] = end - 0.5 * ov
    # Each angle's own onset lag and duration change (coarticulation across the angles);
    # the lag never moves an angle's part before the trial's start.
    lag = rng.normal(0.0, who.lag_sd, size=(k, 4))
    stretch = 1.0 + rng.normal(0.0, 0.06, size=(k, 4))
    a_onset = np.maximum(onset[:, None] + lag, 0.05)
    a_dur = np.maximum(dur[:, None] * stretch, 0.15)
    end_time = float(max(boundaries[k], (a_onset + a_dur).max()) + tail)
    motion = BlendedMotion(
        start=chain[0],
        onset=a_onset,
        duration_=a_dur,
        stroke_onset=onset,
        stroke_duration=dur,
        delta=delta,
        bend=bend,
        loop=loop,
        loop_kind=kind,
        loop_turns=turns,
        chart=chart,
        euler_start=chain[:-1],
        boundaries=boundaries,
        labels=np.asarray([s.label for s in strokes], dtype=np.int64),
        end_time=end_time,
    )
    blended = np.flatnonzero(~pause)
    if blended.size:
        motion.boundaries[blended + 1] = [_handover(motion, int(i)) for i in blended]
    return motion


def _stroke_speed(m: BlendedMotion, k: int, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Joint-space speed (rad/s) of stroke ``k``'s own contribution at times ``t`` (the
    exact derivative of its terms in :meth:`BlendedMotion.angles`, before clipping)."""
    s = np.clip((t[:, None] - m.onset[k]) / m.duration_[k], 0.0, 1.0)
    v = m.delta[k] * (30.0 * s * s * (1.0 - s) ** 2) / m.duration_[k]
    sk = np.clip((t - m.stroke_onset[k]) / m.stroke_duration[k], 0.0, 1.0)
    phi = minimum_jerk(sk)
    dphi = 30.0 * sk * sk * (1.0 - sk) ** 2 / m.stroke_duration[k]
    v = v + np.outer(4.0 * (1.0 - 2.0 * phi) * dphi, m.bend[k])
    if m.loop_kind[k]:
        w = 2.0 * np.pi * m.loop_turns[k]
        v[:, 0] += m.loop[k, 0] * w * np.cos(w * phi) * dphi
        if m.loop_kind[k] == 1:
            v[:, 1] += m.loop[k, 1] * w * np.sin(w * phi) * dphi
        else:
            v[:, 1] += m.loop[k, 1] * 2.0 * w * np.cos(2.0 * w * phi) * dphi
    return np.linalg.norm(v, axis=1)


def _handover(m: BlendedMotion, i: int) -> float:
    """The boundary between blended strokes ``i`` and ``i + 1``: the instant in their
    overlap where the next stroke's own speed overtakes the current one's (the middle of
    the overlap if the speeds never cross there)."""
    lo = float(min(m.onset[i + 1].min(), m.stroke_onset[i + 1]))
    hi = float(max((m.onset[i] + m.duration_[i]).max(), m.stroke_onset[i] + m.stroke_duration[i]))
    mid = 0.5 * (m.stroke_onset[i + 1] + m.stroke_onset[i] + m.stroke_duration[i])
    if not hi > lo:
        return float(mid)
    t = np.linspace(lo, hi, 100)
    ahead = _stroke_speed(m, i + 1, t) > _stroke_speed(m, i, t)
    return float(t[int(np.argmax(ahead))]) if np.any(ahead) else float(mid)
