"""The paper-like stimuli: 20 composite arm gestures (the default experiment).

Fod, Matarić & Jenkins showed their 11 subjects 20 short videos of "arm movements": not
point-to-point strokes between a handful of postures but whole gestures — reaches in many
directions, curved paths, circles and figure-eights, waving, throwing, pointing, most
starting and ending with the arm hanging at the side. This module describes such gestures
as chains of **strokes**; :mod:`visprim.datasets.imitation` turns a chain into the
continuous, coarticulated movement of one subject.

Angles are in the convention of :mod:`visprim.arm` (γ azimuth, β elevation from hanging,
α humeral rotation, θ elbow flexion); the tables below are in **degrees** for readability,
the API returns radians.

A stroke (:class:`Stroke`) goes from where the previous one ended to ``target`` in
``duration`` seconds along a minimum-jerk profile φ(s), with an optional shape on top:

* ``bend`` (4 angles, deg): a bell-shaped detour ``bend · 4 φ (1 − φ)`` — curved joint
  paths (scooping, sweeping, arcs over the head);
* ``loop`` (γ, β half-axes, deg) with ``kind`` "circle" (``γ += A sin 2πnφ``,
  ``β += B (1 − cos 2πnφ)``) or "figure8" (``γ += A sin 2πnφ``, ``β += B sin 4πnφ``),
  ``n = turns`` loops in one stroke.

Every shape vanishes with its velocity at both ends of the stroke, so the ground truth
boundary between strokes is well defined.

Design choices (why these 20):

* **Hanging arm.** 19 of the 20 gestures start and end with the arm hanging (β of a few
  degrees: the Z-Y-Z singularity, where γ and α are ill-defined and sensor noise is
  amplified by 1/sin β); the paper's subjects stood with their arms at their sides
  between gestures. Within a gesture the arm stays away from hanging (β ≥ 25° between
  repetitions).
* **Many directions.** Reach and point targets are spread over azimuths −60° … 120° and
  elevations 40° … 165°, so strokes of one kind differ in direction, as people's do.
* **Several cycles.** Waves, swings, hammering and wiping repeat 2–4 times
  (``repetitions``, which SEG-2 uses to tune its threshold).
* **Length.** 3–6 s at the nominal tempo, like the paper's videos (a subject's tempo and
  reaction time change it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: Stroke kinds of the paper preset; a stroke's ground-truth label is its index here.
STROKE_KINDS: tuple[str, ...] = (
    "reach",  # 0: straight joint-space move away from the hanging arm
    "return",  # 1: back to the hanging arm
    "curved_reach",  # 2: reach with a bent joint path
    "move",  # 3: posture to posture with the arm raised (no hanging end)
    "circle",  # 4: closed loop in (γ, β)
    "figure8",  # 5: figure-eight in (γ, β)
    "wave",  # 6: one half-cycle of waving (humeral rotation + elbow)
    "windup",  # 7: cocking the arm back before a throw
    "throw",  # 8: fast release forward
    "point",  # 9: reach to a target with a nearly straight arm
    "swing",  # 10: pendulum swing of the whole arm across the body
    "curl",  # 11: elbow flexion / extension
)

#: The hanging arm (degrees): upper arm 6° off vertical, slightly forward, elbow a little
#: bent, as a relaxed arm hangs. Subjects shift it (see :mod:`visprim.datasets.imitation`).
HANG_DEG: tuple[float, float, float, float] = (0.0, 6.0, 0.0, 12.0)


@dataclass(frozen=True)
class Stroke:
    """One stroke of a gesture (angles in degrees, see the module docstring).

    Attributes
    ----------
    kind : str
        One of :data:`STROKE_KINDS` (the ground-truth label).
    target : (γ, β, α, θ) degrees
        Posture at the end of the stroke.
    duration : float, seconds
        Nominal duration.
    bend : (4,) degrees
        Peak of the bell-shaped detour (0 for a straight joint path).
    loop : (A_γ, A_β) degrees
        Loop half-axes for "circle" / "figure8" strokes.
    turns : int
        Number of loops drawn in one stroke (without stopping).
    """

    kind: str
    target: tuple[float, float, float, float]
    duration: float
    bend: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    loop: tuple[float, float] = (0.0, 0.0)
    turns: int = 1

    @property
    def label(self) -> int:
        """Index of ``kind`` in :data:`STROKE_KINDS`."""
        return STROKE_KINDS.index(self.kind)


@dataclass(frozen=True)
class Gesture:
    """One stimulus of the paper preset.

    Attributes
    ----------
    name : str
    start : (γ, β, α, θ) degrees
        Posture before the first stroke.
    prefix, repeat, suffix : tuple of Stroke
        The strokes are ``prefix + repeat * repetitions + suffix``.
    repetitions : int
        Repetitions of ``repeat`` (1 when nothing repeats).
    """

    name: str
    start: tuple[float, float, float, float]
    prefix: tuple[Stroke, ...]
    repeat: tuple[Stroke, ...] = ()
    repetitions: int = 1
    suffix: tuple[Stroke, ...] = ()

    @property
    def strokes(self) -> tuple[Stroke, ...]:
        """Strokes in order."""
        return self.prefix + self.repeat * self.repetitions + self.suffix

    @property
    def nominal_duration(self) -> float:
        """Sum of the nominal stroke durations, seconds."""
        return float(sum(s.duration for s in self.strokes))

    def start_rad(self) -> NDArray[np.float64]:
        """The starting posture in radians, shape (4,)."""
        return np.radians(np.asarray(self.start, dtype=np.float64))


def _reach(target: tuple[float, float, float, float], d: float = 0.9) -> Stroke:
    return Stroke("reach", target, d)


def _ret(d: float = 0.9, bend: tuple[float, float, float, float] = (0, 0, 0, 0)) -> Stroke:
    return Stroke("return", HANG_DEG, d, bend)


H = HANG_DEG

#: The 20 gestures of the default experiment.
GESTURES: tuple[Gesture, ...] = (
    Gesture(
        "reach forward and up, return",
        H,
        (_reach((10, 110, -20, 25), 1.0), _ret(1.0)),
    ),
    Gesture(
        "raise sideways, two circles, lower",
        H,
        (
            _reach((85, 95, 10, 15), 1.0),
            Stroke("circle", (85, 95, 10, 15), 2.0, loop=(25, 20), turns=2),
            _ret(1.0),
        ),
    ),
    Gesture(
        "scoop across the body",
        H,
        (
            Stroke("curved_reach", (-45, 85, -35, 60), 1.1, bend=(25, 30, 0, 25)),
            _ret(1.0, bend=(-20, 15, 10, 0)),
        ),
    ),
    Gesture(
        "point at three targets",
        H,
        (
            Stroke("point", (20, 90, -10, 12), 0.8),
            Stroke("point", (70, 100, 0, 12), 0.6),
            Stroke("point", (-30, 80, -20, 15), 0.7),
            _ret(0.9),
        ),
    ),
    Gesture(
        "circle in front",
        H,
        (
            _reach((5, 80, -20, 40), 0.9),
            Stroke("circle", (5, 80, -20, 40), 1.4, loop=(30, 25)),
            _ret(0.9),
        ),
    ),
    Gesture(
        "two circles to the side",
        H,
        (_reach((60, 85, 0, 30), 0.9),),
        (Stroke("circle", (60, 85, 0, 30), 1.1, loop=(25, 20)),),
        2,
        (_ret(0.9),),
    ),
    Gesture(
        "figure-eight",
        H,
        (
            _reach((15, 85, -15, 35), 0.9),
            Stroke("figure8", (15, 85, -15, 35), 2.2, loop=(35, 20)),
            _ret(0.9),
        ),
    ),
    Gesture(
        "wave three times",
        H,
        (Stroke("curved_reach", (80, 80, -25, 100), 1.0, bend=(0, 10, -10, 20)),),
        (Stroke("wave", (75, 80, 30, 85), 0.5), Stroke("wave", (80, 80, -25, 100), 0.5)),
        3,
        (_ret(0.9),),
    ),
    Gesture(
        "circle overhead",
        H,
        (
            Stroke("curved_reach", (20, 135, -10, 30), 1.1, bend=(20, 0, 0, 15)),
            Stroke("circle", (20, 135, -10, 30), 1.6, loop=(30, 18)),
            _ret(1.1, bend=(25, 0, 0, 0)),
        ),
    ),
    Gesture(
        "overhand throw",
        H,
        (
            Stroke("windup", (75, 115, 70, 110), 0.9, bend=(-20, 10, 20, 0)),
            Stroke("throw", (-5, 70, -30, 25), 0.35),
            _ret(1.0),
        ),
    ),
    Gesture(
        "two underhand throws",
        H,
        (),
        (
            Stroke("windup", (120, 35, 0, 25), 0.7),
            Stroke("throw", (0, 75, -10, 20), 0.4),
            Stroke("move", (10, 30, -10, 30), 0.7),
        ),
        2,
        (_ret(0.7),),
    ),
    Gesture(
        "reach up three times",
        H,
        (_reach((15, 160, -10, 20), 0.9),),
        (Stroke("move", (10, 40, -10, 30), 0.8), Stroke("move", (15, 160, -10, 20), 0.8)),
        2,
        (_ret(0.9),),
    ),
    Gesture(
        "reach in four directions",
        (10, 45, -10, 60),
        (
            Stroke("move", (0, 95, -20, 20), 0.7),
            Stroke("move", (90, 90, 10, 20), 0.8, bend=(0, 15, 0, 0)),
            Stroke("move", (20, 160, -10, 15), 0.8),
            Stroke("move", (-50, 80, -35, 45), 0.9, bend=(0, 20, 0, 0)),
            _ret(0.9),
        ),
    ),
    Gesture(
        "three curls, arm at the side",
        H,
        (Stroke("move", (10, 25, -10, 30), 0.6),),
        (Stroke("curl", (10, 28, -20, 130), 0.6), Stroke("curl", (10, 25, -10, 30), 0.6)),
        3,
        (_ret(0.6),),
    ),
    Gesture(
        "hammer three times",
        H,
        (_reach((0, 60, -30, 95), 0.8),),
        (
            Stroke("curl", (0, 72, -30, 125), 0.5),
            Stroke("curl", (0, 55, -30, 75), 0.45),
        ),
        3,
        (_ret(0.8),),
    ),
    Gesture(
        "wipe a table three times",
        H,
        (_reach((-20, 70, -40, 40), 0.9),),
        (
            Stroke("move", (60, 75, -10, 35), 0.65, bend=(0, -10, 0, 10)),
            Stroke("move", (-20, 70, -40, 40), 0.65, bend=(0, -10, 0, 10)),
        ),
        3,
        (_ret(0.8),),
    ),
    Gesture(
        "swing the arm across three times",
        H,
        (),
        (
            Stroke("swing", (60, 45, 0, 15), 0.6, bend=(0, -8, 0, 0)),
            Stroke("swing", (-40, 40, -20, 20), 0.6, bend=(0, -8, 0, 0)),
        ),
        3,
        (_ret(0.6),),
    ),
    Gesture(
        "point, then circle",
        H,
        (
            Stroke("point", (40, 95, -5, 10), 0.9),
            Stroke("circle", (40, 95, -5, 10), 1.2, loop=(20, 20)),
            _ret(1.0),
        ),
    ),
    Gesture(
        "arc over the head",
        H,
        (
            Stroke("curved_reach", (95, 100, 10, 20), 1.0, bend=(-10, -15, 0, 10)),
            Stroke("move", (-30, 120, -30, 30), 1.2, bend=(0, 45, 0, 0)),
            _ret(1.1, bend=(10, 10, 0, 10)),
        ),
    ),
    Gesture(
        "reach low forward and to the back",
        H,
        (
            _reach((-10, 45, -30, 30), 0.8),
            Stroke("move", (150, 40, 60, 20), 1.1, bend=(0, 25, 0, 0)),
            _ret(0.8),
        ),
    ),
)


def jittered_gesture(gesture: Gesture, rng: np.random.Generator, name: str) -> Gesture:
    """A variant of ``gesture`` with every non-hanging target moved by SD 15° per angle
    (the extra stimuli beyond the 20 of :data:`GESTURES`)."""

    def move(s: Stroke) -> Stroke:
        if s.target == HANG_DEG:
            return s
        t = tuple(float(v) for v in np.asarray(s.target) + rng.normal(0.0, 15.0, size=4))
        t = (t[0], max(t[1], 10.0), t[2], float(np.clip(t[3], 10.0, 140.0)))
        return Stroke(s.kind, t, s.duration, s.bend, s.loop, s.turns)

    return Gesture(
        name,
        gesture.start,
        tuple(move(s) for s in gesture.prefix),
        tuple(move(s) for s in gesture.repeat),
        gesture.repetitions,
        tuple(move(s) for s in gesture.suffix),
    )


def stroke_targets_rad(gesture: Gesture) -> NDArray[np.float64]:
    """Targets of the strokes in radians, shape (n_strokes, 4)."""
    return np.radians(np.asarray([s.target for s in gesture.strokes], dtype=np.float64))
