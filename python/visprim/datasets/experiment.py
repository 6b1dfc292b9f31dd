"""The generated imitation experiment: subjects × stimuli trials with ground truth.

Two presets share the measurement model (:mod:`visprim.datasets.measurement`):

* ``"paper"`` (default): 20 composite gestures (:mod:`visprim.datasets.gestures`) imitated
  with coarticulation, personal style and a hanging arm
  (:mod:`visprim.datasets.imitation`) — calibrated so that the demo's error tables are
  as large as the paper's;
* ``"strokes"``: 15 minimum-jerk strokes between 8 key postures, every stroke ending at
  rest (:mod:`visprim.datasets.vocabulary`, :mod:`visprim.datasets.stimuli`,
  :mod:`visprim.datasets.subjects`) — easy, fast data for tests of the method's
  mechanics.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from visprim.datasets.gestures import GESTURES, Gesture, jittered_gesture
from visprim.datasets.imitation import Performer, sample_performer
from visprim.datasets.imitation import perform as perform_gesture
from visprim.datasets.measurement import (
    Measurement,
    place_sensors,
    sample_distortion,
    sample_times,
    sensor_noise,
    shoulder_drift,
    vibration,
)
from visprim.datasets.stimuli import STIMULI, Stimulus, random_stimulus
from visprim.datasets.subjects import Subject, perform, sample_subject
from visprim.trial import Trial, Truth

#: The generator presets (see the module docstring); the first is the default.
PRESETS: tuple[str, ...] = ("paper", "strokes")

# Independent random streams: SeedSequence(seed, spawn_key=(domain, ...)). Subject s and
# trial (s, m) get the same numbers whatever n_subjects / n_stimuli are.
_SUBJECT, _TRIAL, _STIMULUS, _SESSION = 0, 1, 2, 3
_MOTION, _TIMES, _DRIFT, _SENSORS = 0, 1, 2, 3


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def _check_count(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _check_preset(preset: str) -> str:
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; known: {', '.join(PRESETS)}")
    return preset


def stimuli(n_stimuli: int = 20, seed: int = 0, preset: str = "paper") -> list[Any]:
    """The first ``n_stimuli`` stimuli of ``preset``: the 20 fixed ones (:data:`GESTURES`
    for "paper", :data:`STIMULI` for "strokes"), then random ones."""
    n_stimuli = _check_count("n_stimuli", n_stimuli)
    if _check_preset(preset) == "paper":
        out: list[Any] = list(GESTURES[:n_stimuli])
        for m in range(len(out), n_stimuli):
            base = GESTURES[m % len(GESTURES)]
            out.append(jittered_gesture(base, _rng(seed, _STIMULUS, m), f"{base.name} ({m})"))
        return out
    out = list(STIMULI[:n_stimuli])
    for m in range(len(out), n_stimuli):
        out.append(random_stimulus(_rng(seed, _STIMULUS, m), m))
    return out


def subjects(n_subjects: int = 11, seed: int = 0, preset: str = "paper") -> list[Any]:
    """The first ``n_subjects`` subjects of ``preset`` for ``seed``."""
    n_subjects = _check_count("n_subjects", n_subjects)
    if _check_preset(preset) == "paper":
        return [sample_performer(s, _rng(seed, _SUBJECT, s)) for s in range(n_subjects)]
    return [sample_subject(s, _rng(seed, _SUBJECT, s)) for s in range(n_subjects)]


def generate_trial(
    subject: Subject | Performer,
    stimulus: Stimulus | Gesture,
    stimulus_index: int,
    seed: int = 0,
    *,
    noise: bool = True,
    skin_offsets: bool = True,
    drift: bool = True,
    timing_jitter: bool = True,
    measurement: Measurement | None = None,
) -> Trial:
    """One subject's imitation of one stimulus, measured (see :func:`imitation_experiment`)."""
    m = measurement or Measurement()
    key = (_TRIAL, subject.index, stimulus_index)
    rng = _rng(seed, *key, _MOTION)
    if isinstance(stimulus, Gesture) and isinstance(subject, Performer):
        motion: Any = perform_gesture(stimulus, subject, rng)
    elif isinstance(stimulus, Stimulus) and isinstance(subject, Subject):
        motion = perform(stimulus, subject, rng)
    else:
        raise TypeError("generate_trial: subject and stimulus must come from the same preset")
    times = sample_times(motion.duration, _rng(seed, *key, _TIMES) if timing_jitter else None, m)
    angles = motion.angles(times)
    body = subject.body
    offsets = subject.skin_offsets if skin_offsets else None
    sensors, joints = place_sensors(angles, body.lengths, offsets)
    origin = np.broadcast_to(np.asarray(body.shoulder), (times.size, 3)).copy()
    if drift:
        origin += shoulder_drift(times, _rng(seed, *key, _DRIFT), m)
    markers = sensors + origin[:, None, :]
    true_joints = joints[:, :3] + origin[:, None, :]
    if noise:
        rng = _rng(seed, *key, _SENSORS)
        speed = np.linalg.norm(np.gradient(sensors, times, axis=0), axis=2)
        field = sample_distortion(_rng(seed, _SESSION, subject.index), m)
        markers = markers + field(markers)
        markers = markers + vibration(times, speed, rng, m)
        markers = markers + sensor_noise(markers.shape, rng, m)
    truth = Truth(
        angles=angles,
        boundaries=motion.boundaries,
        labels=motion.labels,
        repetitions=stimulus.repetitions,
    )
    lengths = body.lengths
    return Trial(
        times=times,
        markers=markers,
        name=f"s{subject.index:02d}_m{stimulus_index:02d}",
        subject=subject.index,
        stimulus=stimulus_index,
        repetitions=stimulus.repetitions,
        truth=truth,
        meta={
            "generator": "visprim.datasets",
            "seed": seed,
            "frame_period_s": m.frame_period_s,
            "rate_hz": 1.0 / m.frame_period_s,
            "stimulus_name": stimulus.name,
            "preset": "paper" if isinstance(stimulus, Gesture) else "strokes",
            "height_m": body.height,
            "segment_lengths_m": {
                "upper_arm": lengths.upper_arm,
                "forearm": lengths.forearm,
                "hand": lengths.hand,
                "hand_marker": lengths.hand_marker,
            },
            "noise": noise,
            "skin_offsets": skin_offsets,
            "drift": drift,
            "true_joints": true_joints,
        },
    )


def imitation_experiment(
    n_subjects: int = 11,
    n_stimuli: int = 20,
    seed: int = 0,
    *,
    noise: bool = True,
    skin_offsets: bool = True,
    drift: bool = True,
    timing_jitter: bool = True,
    measurement: Measurement | None = None,
    preset: str = "paper",
) -> list[Trial]:
    """Generate the imitation experiment: every subject imitating every stimulus.

    Parameters
    ----------
    n_subjects, n_stimuli : int
        Subjects (default 11) and stimuli (default 20; beyond the 20 fixed ones, random
        variants are added).
    seed : int
        Non-negative seed. Every (subject, stimulus) trial has its own random streams, so
        subject ``s`` imitating stimulus ``m`` is the same trial for any ``n_subjects > s``
        and ``n_stimuli > m``.
    noise : bool
        Add the tracker's error (smooth field distortion plus white jitter, ≈2 mm 3-D RMS
        together) and sensor vibration (7–12 Hz). With
        ``noise=False`` and ``skin_offsets=False`` the markers lie exactly on the points
        inverse kinematics assumes (relative to the shoulder).
    skin_offsets : bool
        Place the sensors off the bone axis as skin-mounted sensors are.
    drift : bool
        Add the slow shoulder drift (a common translation of all four markers).
    timing_jitter : bool
        Jitter the 34 ms sample instants (SD 0.3 ms).
    measurement : Measurement, optional
        Override the measurement parameters.
    preset : {"paper", "strokes"}
        "paper" (default): the 20 composite gestures of
        :mod:`~visprim.datasets.gestures` with coarticulation and a hanging arm, as hard as
        the paper's data. "strokes": 15 minimum-jerk strokes between key postures, every
        stroke ending at rest (easy; for tests of the method's mechanics).

    Returns
    -------
    list of Trial
        Ordered by subject, then stimulus; ``name`` ``"sSS_mMM"`` (0-based ids), integer
        ``subject`` and ``stimulus``, ``repetitions``, ``truth`` and ``meta`` (frame
        period, segment lengths in m, the noise-free joint centres ``true_joints``
        (T, 3, 3) in m, ...). ``truth.angles`` (T, 4) rad are the true angles at the sample
        instants; ``truth.boundaries`` (s) are the start of the first stroke, the instant
        between consecutive strokes (the middle of the pause when the subject paused) and
        the end of the last stroke (with coarticulation, the middle of the overlap of two
        strokes); ``truth.labels`` index
        :data:`~visprim.datasets.gestures.STROKE_KINDS` ("paper") or
        :data:`~visprim.datasets.vocabulary.VOCABULARY` ("strokes"). ``trial.joints`` is None: like
        the original sensors, the generator reports markers only.
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    seed = int(seed)
    subs = subjects(n_subjects, seed, preset)
    stims = stimuli(n_stimuli, seed, preset)
    return [
        generate_trial(
            subject,
            stim,
            m,
            seed,
            noise=noise,
            skin_offsets=skin_offsets,
            drift=drift,
            timing_jitter=timing_jitter,
            measurement=measurement,
        )
        for subject in subs
        for m, stim in enumerate(stims)
    ]


def export_experiment(
    out_dir: str | Path,
    n_subjects: int = 11,
    n_stimuli: int = 20,
    seed: int = 0,
    preset: str = "paper",
) -> list[Path]:
    """Write the experiment as marker CSV files (one per trial) with truth sidecars.

    Writes ``out_dir/<name>.csv`` (see :mod:`visprim.io.markers_csv`) and
    ``out_dir/<name>.truth.json`` per trial; returns the CSV paths in trial order.
    """
    from visprim.io.markers_csv import write_marker_csv

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    trials = imitation_experiment(n_subjects, n_stimuli, seed, preset=preset)
    return [write_marker_csv(out / f"{t.name}.csv", t) for t in trials]
