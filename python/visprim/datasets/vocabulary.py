"""The ground-truth vocabulary: key postures and the stroke primitives between them.

Every posture and primitive is in the angle convention of :mod:`visprim.arm` (γ, β, α,
elbow); tables below are in **degrees** for readability, the API returns radians.

Design constraints (they keep the ground truth recoverable by the method):

* Every posture has shoulder elevation β ≥ 35°, away from the Z-Y-Z singularity at β = 0
  (arm hanging straight down, where γ and α are not separable and sensor noise is
  amplified by 1/sin β). Strokes interpolate between postures, so β stays ≥ 35° along
  them too (subjects' offsets and scaling may lower it; :mod:`visprim.datasets.subjects`
  clips it at 18°). The ready posture ("rest") therefore has the upper arm 35° forward of
  the body and the elbow bent 45°, rather than hanging.
* Elbow flexion is ≥ 25° in every posture (clipped at 12° after subject offsets): humeral
  rotation α is undefined for a straight arm and its noise grows like 1/sin(elbow).
* A stroke is a joint-space movement whose progress follows the minimum-jerk profile
  φ(s) = 10 s³ − 15 s⁴ + 6 s⁵ (Flash & Hogan 1985), so the velocity of **every** angle is
  exactly zero at both ends. Most strokes are straight lines in joint space; the circle
  adds a closed loop in (γ, β) on top of its (zero) net displacement.
* Nominal durations are 0.45–1.3 s; subjects' tempo changes them within 0.3–1.5 s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: Key postures, degrees (γ, β, α, elbow).
POSTURES_DEG: dict[str, tuple[float, float, float, float]] = {
    # ready posture: upper arm slightly forward of the body, hand in front of the thigh
    "rest": (10.0, 35.0, 0.0, 45.0),
    # reach forward at shoulder height, hand pointing ahead
    "front": (0.0, 80.0, -20.0, 30.0),
    # sideways abduction to shoulder height
    "side": (90.0, 80.0, 0.0, 30.0),
    # arm raised above shoulder level in front
    "up": (10.0, 145.0, -10.0, 25.0),
    # elbow flexed in front, hand towards the face
    "flex": (0.0, 70.0, -45.0, 105.0),
    # hand across the body in front of the chest
    "cross": (-45.0, 75.0, -20.0, 40.0),
    # waving: arm abducted, forearm up, rotated inwards / outwards
    "wave_in": (80.0, 75.0, -25.0, 95.0),
    "wave_out": (75.0, 75.0, 30.0, 90.0),
}


@dataclass(frozen=True)
class Primitive:
    """One stroke primitive of the ground-truth vocabulary.

    Attributes
    ----------
    name : str
        Human-readable name.
    start, end : str
        Key postures (names in :data:`POSTURES_DEG`) the stroke moves between.
    duration : float, seconds
        Nominal duration.
    loop_deg : (float, float)
        For a loop stroke, the half-axes (γ, β) in degrees of the closed loop traced on
        top of the start→end line; (0, 0) for a straight joint-space stroke.
    """

    name: str
    start: str
    end: str
    duration: float
    loop_deg: tuple[float, float] = (0.0, 0.0)


#: The vocabulary; a stroke's ground-truth label is its index here.
VOCABULARY: tuple[Primitive, ...] = (
    Primitive("reach_forward", "rest", "front", 0.9),
    Primitive("return_from_front", "front", "rest", 0.9),
    Primitive("reach_side", "rest", "side", 1.0),
    Primitive("return_from_side", "side", "rest", 1.0),
    Primitive("raise_up", "front", "up", 0.8),
    Primitive("lower_from_up", "up", "front", 0.8),
    Primitive("elbow_flex", "front", "flex", 0.6),
    Primitive("elbow_extend", "flex", "front", 0.6),
    Primitive("sweep_across", "front", "cross", 0.7),
    Primitive("sweep_back", "cross", "front", 0.7),
    Primitive("raise_forearm", "side", "wave_in", 0.6),
    Primitive("lower_forearm", "wave_in", "side", 0.6),
    Primitive("wave_out", "wave_in", "wave_out", 0.45),
    Primitive("wave_in", "wave_out", "wave_in", 0.45),
    Primitive("circle", "front", "front", 1.3, loop_deg=(22.0, 16.0)),
)

PRIMITIVE_NAMES: tuple[str, ...] = tuple(p.name for p in VOCABULARY)


def posture(name: str) -> NDArray[np.float64]:
    """A key posture in radians, shape (4,)."""
    try:
        return np.radians(np.asarray(POSTURES_DEG[name], dtype=np.float64))
    except KeyError:
        raise ValueError(f"unknown posture {name!r}; known: {', '.join(POSTURES_DEG)}") from None


def minimum_jerk(s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Minimum-jerk progress φ(s) = 10s³ − 15s⁴ + 6s⁵ for normalised time s in [0, 1]
    (clipped outside); φ, φ' and φ'' vanish at s = 0 and s = 1 except φ(1) = 1."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def primitive_index(name: str) -> int:
    """Label of the primitive called ``name``."""
    try:
        return PRIMITIVE_NAMES.index(name)
    except ValueError:
        raise ValueError(
            f"unknown primitive {name!r}; known: {', '.join(PRIMITIVE_NAMES)}"
        ) from None
