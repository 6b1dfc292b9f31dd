"""The generated imitation experiment (default data of visprim), with ground truth.

Reproduces the setting of Fod, Matarić & Jenkins: 11 subjects imitate 20 short (3–6 s)
demonstrations of arm movements while four position sensors on the right arm (mid upper
arm, mid forearm, just above the wrist, middle finger) are read every 34 ms with ≈2 mm
accuracy. Two presets (``imitation_experiment(preset=...)``):

* ``"paper"`` (default) — composite gestures, coarticulated, with the arm hanging near the
  Z-Y-Z singularity; calibrated so that the demo's error tables match the paper's:

  * :mod:`~visprim.datasets.gestures` — the 20 gestures (stroke chains, repetitions);
  * :mod:`~visprim.datasets.imitation` — subjects' style, tempo, coarticulation;

* ``"strokes"`` — minimum-jerk strokes between 8 key postures, each ending at rest (easy;
  for tests of the method's mechanics):

  * :mod:`~visprim.datasets.vocabulary` — key postures and the 15 stroke primitives;
  * :mod:`~visprim.datasets.stimuli` — the 20 stimuli (stroke chains, repetitions);
  * :mod:`~visprim.datasets.subjects` — human variability in imitating a stimulus;
  * :mod:`~visprim.datasets.motion` — the continuous joint-space motion (minimum jerk);

Shared by both:

* :mod:`~visprim.datasets.anthropometry` — segment lengths from height (Winter 2009);
* :mod:`~visprim.datasets.measurement` — sensors, drift, vibration, noise, sampling;
* :mod:`~visprim.datasets.experiment` — :func:`imitation_experiment`,
  :func:`export_experiment`.
"""

from __future__ import annotations

from visprim.datasets.experiment import (
    PRESETS,
    export_experiment,
    generate_trial,
    imitation_experiment,
    stimuli,
    subjects,
)
from visprim.datasets.gestures import GESTURES, STROKE_KINDS, Gesture, Stroke
from visprim.datasets.imitation import Performer
from visprim.datasets.measurement import Measurement
from visprim.datasets.stimuli import STIMULI, Stimulus
from visprim.datasets.vocabulary import POSTURES_DEG, PRIMITIVE_NAMES, VOCABULARY, Primitive

__all__ = [
    "GESTURES",
    "PRESETS",
    "STROKE_KINDS",
    "Gesture",
    "Performer",
    "Stroke",
    "POSTURES_DEG",
    "PRIMITIVE_NAMES",
    "STIMULI",
    "VOCABULARY",
    "Measurement",
    "Primitive",
    "Stimulus",
    "export_experiment",
    "generate_trial",
    "imitation_experiment",
    "stimuli",
    "subjects",
]
