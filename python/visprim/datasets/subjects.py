"""Subjects and how they imitate a stimulus (human variability).

A subject (:class:`Subject`) has a body (:mod:`~visprim.datasets.anthropometry`), a
personal style and sensor placement. Imitating a stimulus (:func:`perform`) produces a
:class:`~visprim.datasets.motion.Motion` with these variations (SD = standard deviation):

* **posture offsets**: every key posture shifted by a per-subject offset (SD 4° for γ, α
  and elbow, 3° for β) and scaled about a central posture by a per-subject amplitude
  factor (SD 0.07, within 0.85–1.15); each visit of a posture in a trial gets a further
  SD 2° jitter per angle, so repetitions are not identical;
* **speed**: a per-subject tempo factor (log-normal, SD 0.1, within 0.8–1.25) and per-stroke
  duration jitter (SD 7 %); stroke durations stay within 0.3–1.5 s;
* **timing**: a reaction delay of 0.25–0.6 s before the first stroke and a 0.3–0.6 s hold
  after the last; between strokes, with a per-subject probability of 5–25 %, a short pause
  of 0.08–0.25 s (the ground-truth boundary is then the middle of the pause);
* loop strokes (the circle) scale with the amplitude factor and ±10 % per trial.

Angles are clipped to β ≥ 18° (away from the Z-Y-Z singularity) and elbow ≥ 12°.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from visprim.datasets.anthropometry import Body, sample_body
from visprim.datasets.motion import Motion
from visprim.datasets.stimuli import Stimulus
from visprim.datasets.vocabulary import POSTURES_DEG, VOCABULARY, posture

#: Posture about which a subject's amplitude factor scales, degrees (γ, β, α, elbow).
CENTRAL_POSTURE_DEG = (20.0, 75.0, -10.0, 50.0)
MIN_BETA = np.radians(18.0)
MIN_ELBOW = np.radians(12.0)
STROKE_DURATION_RANGE_S = (0.3, 1.5)


@dataclass(frozen=True)
class Subject:
    """One subject of the experiment.

    Attributes
    ----------
    index : int
        Subject id (0-based).
    body : Body
        Height, segment lengths (m) and shoulder position (m).
    tempo : float
        Duration factor of all strokes (> 1 = slower).
    amplitude : float
        Scale of postures about :data:`CENTRAL_POSTURE_DEG`.
    posture_offset : (4,) float array, radians
        Added to every key posture.
    pause_probability : float
        Chance of a short pause between two strokes.
    skin_offsets : (4, 3) float array, metres
        Sensor offsets from the implied points in segment coordinates (see
        :mod:`visprim.datasets.measurement`).
    """

    index: int
    body: Body
    tempo: float
    amplitude: float
    posture_offset: NDArray[np.float64]
    pause_probability: float
    skin_offsets: NDArray[np.float64]


def sample_subject(index: int, rng: np.random.Generator) -> Subject:
    """Draw subject ``index`` from ``rng`` (always the same number of draws)."""
    from visprim.datasets.measurement import sample_skin_offsets

    body = sample_body(rng)
    tempo = float(np.clip(np.exp(rng.normal(0.0, 0.1)), 0.8, 1.25))
    amplitude = float(np.clip(rng.normal(1.0, 0.07), 0.85, 1.15))
    offset = np.radians(rng.normal(0.0, [4.0, 3.0, 4.0, 4.0]))
    pause_probability = float(rng.uniform(0.05, 0.25))
    skin = sample_skin_offsets(rng)
    return Subject(index, body, tempo, amplitude, offset, pause_probability, skin)


def subject_posture(subject: Subject, name: str) -> NDArray[np.float64]:
    """A key posture as this subject performs it, radians (4,) (before per-visit jitter)."""
    centre = np.radians(np.asarray(CENTRAL_POSTURE_DEG))
    p = centre + subject.amplitude * (posture(name) - centre) + subject.posture_offset
    return _clip(p)


def _clip(p: NDArray[np.float64]) -> NDArray[np.float64]:
    p = p.copy()
    p[..., 1] = np.maximum(p[..., 1], MIN_BETA)
    p[..., 3] = np.maximum(p[..., 3], MIN_ELBOW)
    return p


def perform(stimulus: Stimulus, subject: Subject, rng: np.random.Generator) -> Motion:
    """The subject's imitation of ``stimulus`` as a continuous :class:`Motion`."""
    strokes = stimulus.strokes
    postures = {name: subject_posture(subject, name) for name in POSTURES_DEG}
    lo, hi = STROKE_DURATION_RANGE_S

    # the chain of visited postures, each visit jittered
    names = [VOCABULARY[strokes[0]].start] + [VOCABULARY[k].end for k in strokes]
    visits = np.stack([postures[n] for n in names])
    visits = _clip(visits + np.radians(rng.normal(0.0, 2.0, size=visits.shape)))
    durations = np.array([VOCABULARY[k].duration for k in strokes])
    durations = durations * stimulus.tempo * subject.tempo
    durations = np.clip(durations * (1.0 + rng.normal(0.0, 0.07, size=len(strokes))), lo, hi)
    pauses = np.where(
        rng.random(len(strokes) - 1) < subject.pause_probability,
        rng.uniform(0.08, 0.25, size=len(strokes) - 1),
        0.0,
    )
    lead = float(rng.uniform(0.25, 0.6))
    tail = float(rng.uniform(0.3, 0.6))
    loop_scale = subject.amplitude * rng.uniform(0.9, 1.1, size=len(strokes))

    piece_start: list[float] = []
    piece_duration: list[float] = []
    start: list[NDArray[np.float64]] = []
    delta: list[NDArray[np.float64]] = []
    loop: list[NDArray[np.float64]] = []
    zero4, zero2 = np.zeros(4), np.zeros(2)

    def hold(t: float, d: float, at: NDArray[np.float64]) -> float:
        piece_start.append(t)
        piece_duration.append(d)
        start.append(at)
        delta.append(zero4)
        loop.append(zero2)
        return t + d

    t = hold(0.0, lead, visits[0])
    boundaries = [t]
    for i, k in enumerate(strokes):
        piece_start.append(t)
        piece_duration.append(float(durations[i]))
        start.append(visits[i])
        delta.append(visits[i + 1] - visits[i])
        loop.append(np.radians(np.asarray(VOCABULARY[k].loop_deg)) * loop_scale[i])
        t += float(durations[i])
        if i < len(strokes) - 1 and pauses[i] > 0:
            boundaries.append(t + 0.5 * float(pauses[i]))
            t = hold(t, float(pauses[i]), visits[i + 1])
        else:
            boundaries.append(t)
    hold(t, tail, visits[-1])
    return Motion(
        piece_start=np.asarray(piece_start),
        piece_duration=np.asarray(piece_duration),
        start=np.stack(start),
        delta=np.stack(delta),
        loop=np.stack(loop),
        boundaries=np.asarray(boundaries),
        labels=np.asarray(strokes, dtype=np.int64),
    )
