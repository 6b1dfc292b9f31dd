"""Segmentation of joint-angle trajectories (stage 3 of the method).

* :func:`zvc` — zero-velocity crossings per DOF with a significant-movement threshold;
* :func:`seg1` — SEG-1: cut where several DOFs have a ZVC within 300 ms (not a partition);
* :func:`seg2` — SEG-2: cut where ``z = Σ θ̇ᵢ²`` dips below a tuned threshold (a partition);
  :func:`tune_seg2_threshold` tunes one threshold for a corpus, :func:`seg2_trace` exposes
  z(t) and c;
* :func:`segment_corpus` / :func:`segment_concatenated` — either method on a whole corpus at
  once (vectorised; ZVCs in one Rust kernel call);
* :func:`boundary_scores` — precision / recall / F1 of boundaries against ground truth.

Velocities come from the real timestamps (:func:`angular_velocity`). Units: seconds,
radians (rad/s, (rad/s)² for z); the ZVC threshold is given in degrees.
"""

from __future__ import annotations

from visprim.segment.corpus import CorpusSegmentation, segment_concatenated, segment_corpus
from visprim.segment.scores import (
    BoundaryScores,
    boundary_matches,
    boundary_scores,
    corpus_boundary_scores,
    segment_boundaries,
    truth_pause_halfwidths,
)
from visprim.segment.seg1 import DEFAULT_WINDOW, Seg1Events, seg1, seg1_events
from visprim.segment.seg2 import (
    DEFAULT_MIN_TRAVEL_DEG,
    Seg2Trace,
    seg2,
    seg2_trace,
    speed_squared,
    tune_seg2_threshold,
)
from visprim.segment.velocity import angular_velocity, velocity_concatenated
from visprim.segment.zvc import (
    DEFAULT_MIN_CHANGE_DEG,
    CorpusCrossings,
    Crossings,
    zvc,
    zvc_concatenated,
)

__all__ = [
    "DEFAULT_MIN_CHANGE_DEG",
    "DEFAULT_MIN_TRAVEL_DEG",
    "DEFAULT_WINDOW",
    "BoundaryScores",
    "CorpusCrossings",
    "CorpusSegmentation",
    "Crossings",
    "Seg1Events",
    "Seg2Trace",
    "angular_velocity",
    "boundary_matches",
    "boundary_scores",
    "corpus_boundary_scores",
    "segment_boundaries",
    "seg1",
    "seg1_events",
    "seg2",
    "seg2_trace",
    "segment_concatenated",
    "segment_corpus",
    "speed_squared",
    "truth_pause_halfwidths",
    "tune_seg2_threshold",
    "velocity_concatenated",
    "zvc",
    "zvc_concatenated",
]
