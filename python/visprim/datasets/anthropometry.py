"""Subject-specific arm segment lengths from body height (anthropometric ratios).

Segment lengths are fractions of standing height H from Winter, *Biomechanics and Motor
Control of Human Movement*, 4th ed. (Wiley, 2009), Fig. 4.1 / Table 4.1, which reproduces
the segment-length ratios of Drillis & Contini (1966):

========================================  ==========
segment                                    length / H
========================================  ==========
upper arm (shoulder to elbow joint)        0.186
forearm (elbow to wrist joint)             0.146
hand (wrist joint to middle fingertip)     0.108
shoulder joint height above the floor      0.818
========================================  ==========

Two quantities are not in those tables and are our estimates, documented here:

* the finger sensor sits on the proximal phalanx of the middle finger, taken at 0.55 of the
  hand length from the wrist joint centre (the third metacarpal is a bit under half of the
  hand length and the sensor sits near the middle of the proximal phalanx);
* the right shoulder joint centre lies 0.105 H to the right of the body's midline (about
  0.18 m for H = 1.72 m; a little less than half of the 0.259 H shoulder breadth of Winter's
  figure, because the joint centre is medial to the deltoid's surface).

Heights are drawn from a normal distribution (mean 1.72 m, SD 0.09 m, a mixed adult
population, truncated to 1.52–1.95 m) and each ratio gets an independent ±3 % (SD)
individual deviation, so two subjects of the same height still differ slightly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from visprim.arm import ArmLengths

#: Segment length / body height (Winter 2009 after Drillis & Contini 1966).
UPPER_ARM_RATIO = 0.186
FOREARM_RATIO = 0.146
HAND_RATIO = 0.108
SHOULDER_HEIGHT_RATIO = 0.818
#: Our estimates (see the module docstring).
FINGER_SENSOR_FRACTION = 0.55
SHOULDER_LATERAL_RATIO = 0.105

HEIGHT_MEAN_M = 1.72
HEIGHT_SD_M = 0.09
HEIGHT_RANGE_M = (1.52, 1.95)
RATIO_SD = 0.03


@dataclass(frozen=True)
class Body:
    """One subject's body dimensions.

    Attributes
    ----------
    height : float, metres
        Standing height H.
    lengths : ArmLengths
        Right-arm segment lengths, metres.
    shoulder : (3,) tuple, metres
        Right shoulder joint centre in the world frame (+x forward, +y left, +z up, origin
        on the floor between the feet) when the subject stands still.
    """

    height: float
    lengths: ArmLengths
    shoulder: tuple[float, float, float]


def body_from_height(height: float, deviations: np.ndarray | None = None) -> Body:
    """Arm segment lengths and shoulder position for a standing height in metres.

    ``deviations`` (4,) are relative deviations of the upper-arm, forearm, hand and
    shoulder-height ratios (0 = the table values).
    """
    if not np.isfinite(height) or height <= 0:
        raise ValueError(f"height must be a positive number of metres, got {height!r}")
    d = np.zeros(4) if deviations is None else np.asarray(deviations, dtype=np.float64)
    hand = HAND_RATIO * height * (1 + d[2])
    lengths = ArmLengths(
        upper_arm=float(UPPER_ARM_RATIO * height * (1 + d[0])),
        forearm=float(FOREARM_RATIO * height * (1 + d[1])),
        hand=float(hand),
        hand_marker=float(FINGER_SENSOR_FRACTION * hand),
    )
    shoulder = (
        0.0,
        float(-SHOULDER_LATERAL_RATIO * height),
        float(SHOULDER_HEIGHT_RATIO * height * (1 + d[3])),
    )
    return Body(height=float(height), lengths=lengths, shoulder=shoulder)


def sample_body(rng: np.random.Generator) -> Body:
    """Draw one subject's body (height and individual ratio deviations) from ``rng``."""
    lo, hi = HEIGHT_RANGE_M
    height = float(np.clip(rng.normal(HEIGHT_MEAN_M, HEIGHT_SD_M), lo, hi))
    deviations = np.clip(rng.normal(0.0, RATIO_SD, size=4), -2.5 * RATIO_SD, 2.5 * RATIO_SD)
    return body_from_height(height, deviations)
