"""The generated imitation experiment: structure, determinism, geometry, truth."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.arm import BODY_TO_SHOULDER
from visprim.datasets import (
    POSTURES_DEG,
    STIMULI,
    VOCABULARY,
    Measurement,
    imitation_experiment,
)
from visprim.datasets.stimuli import random_stimulus
from visprim.trial import Trial

CLEAN = dict(noise=False, skin_offsets=False, drift=False)


@pytest.fixture(scope="module")
def experiment() -> list[Trial]:
    return imitation_experiment()


@pytest.fixture(scope="module")
def clean() -> list[Trial]:
    return imitation_experiment(4, 20, **CLEAN)


def test_default_experiment_shape(experiment: list[Trial]) -> None:
    assert len(experiment) == 11 * 20
    names = [t.name for t in experiment]
    assert names[0] == "s00_m00" and names[-1] == "s10_m19"
    assert len(set(names)) == len(names)
    for t in experiment:
        assert isinstance(t, Trial) and t.truth is not None
        assert t.markers.shape == (t.n_frames, 4, 3)
        assert t.truth.angles.shape == (t.n_frames, 4)
        assert t.name == f"s{t.subject:02d}_m{t.stimulus:02d}"
        assert t.repetitions == t.truth.repetitions == STIMULI[t.stimulus].repetitions
        assert t.truth.labels.tolist() == list(STIMULI[t.stimulus].strokes)
        assert t.truth.boundaries.shape == (t.truth.labels.size + 1,)
        assert np.all(np.diff(t.truth.boundaries) > 0)
        # the stroke sequence lies inside the recording, with stillness before and after
        assert t.times[0] < t.truth.boundaries[0] - 0.2
        assert t.truth.boundaries[-1] < t.times[-1] - 0.2


def test_sampling_every_34_ms_with_small_jitter(experiment: list[Trial]) -> None:
    steps = np.concatenate([np.diff(t.times) for t in experiment])
    assert abs(np.median(steps) - 0.034) < 2e-4
    assert np.all(np.abs(steps - 0.034) < 2e-3)
    assert np.std(steps) > 1e-4  # jitter is there
    assert all(t.times[0] == 0.0 for t in experiment)


def test_vocabulary_and_stimuli_follow_the_spec() -> None:
    assert len(VOCABULARY) >= 8
    assert len(STIMULI) == 20
    for stim in STIMULI:
        stim.validate()
        assert 2 <= len(stim.strokes) <= 6
        assert 3.0 <= stim.nominal_duration <= 5.0
    assert sum(s.repetitions > 1 for s in STIMULI) >= 6
    for p in VOCABULARY:
        assert 0.3 <= p.duration <= 1.5
    for name, (_g, beta, _a, elbow) in POSTURES_DEG.items():
        assert beta >= 30.0 and elbow >= 20.0, name


def test_extra_stimuli_are_valid_random_chains() -> None:
    for m in range(20, 40):
        stim = random_stimulus(np.random.default_rng(m), m)
        stim.validate()
        assert 3.0 <= stim.nominal_duration <= 5.0
    trials = imitation_experiment(1, 23, **CLEAN)
    assert [t.stimulus for t in trials] == list(range(23))


def test_stroke_durations_and_pauses(experiment: list[Trial]) -> None:
    spans = np.concatenate([np.diff(t.truth.boundaries) for t in experiment])
    # stroke 0.3-1.5 s, plus at most half a pause (<= 0.125 s) on each side
    assert spans.min() >= 0.3 - 1e-9
    assert spans.max() <= 1.5 + 0.25 + 1e-9
    assert 2.0 < min(t.duration for t in experiment)
    assert max(t.duration for t in experiment) < 7.5


def test_determinism() -> None:
    a = imitation_experiment(2, 3, seed=5)
    b = imitation_experiment(2, 3, seed=5)
    c = imitation_experiment(2, 3, seed=6)
    for x, y, z in zip(a, b, c, strict=True):
        assert np.array_equal(x.times, y.times)
        assert np.array_equal(x.markers, y.markers)
        assert np.array_equal(x.truth.angles, y.truth.angles)
        assert np.array_equal(x.truth.boundaries, y.truth.boundaries)
        assert x.times.shape != z.times.shape or not np.array_equal(x.markers, z.markers)
        assert not np.allclose(
            x.truth.angles[: min(x.n_frames, z.n_frames)],
            z.truth.angles[: min(x.n_frames, z.n_frames)],
        )


def test_a_trial_does_not_depend_on_the_experiment_size(experiment: list[Trial]) -> None:
    small = imitation_experiment(3, 5)
    by_name = {t.name: t for t in experiment}
    for t in small:
        assert np.array_equal(t.markers, by_name[t.name].markers)


def test_subjects_differ(experiment: list[Trial]) -> None:
    heights = {t.subject: t.meta["height_m"] for t in experiment}
    assert len(set(heights.values())) == 11
    assert all(1.5 <= h <= 2.0 for h in heights.values())
    # the same stimulus is performed with different timing by different subjects
    first_onsets = [t.truth.boundaries[0] for t in experiment if t.stimulus == 0]
    lengths = [
        t.truth.boundaries[-1] - t.truth.boundaries[0] for t in experiment if t.stimulus == 0
    ]
    assert np.ptp(first_onsets) > 0.1 and np.ptp(lengths) > 0.2


@pytest.mark.parametrize("bad", [0, -1, 2.5, "3", True])
def test_bad_counts_raise(bad: object) -> None:
    with pytest.raises(ValueError, match="n_subjects"):
        imitation_experiment(n_subjects=bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="n_stimuli"):
        imitation_experiment(n_stimuli=bad)  # type: ignore[arg-type]


def test_bad_seed_raises() -> None:
    with pytest.raises(ValueError, match="seed"):
        imitation_experiment(1, 1, seed=-3)


# --- geometry ------------------------------------------------------------------------


def _implied_joints(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What inverse kinematics assumes: wrist = m3, elbow = 2 m2 - m3, shoulder = 2 m1 - e."""
    wrist = markers[:, 2]
    elbow = 2 * markers[:, 1] - wrist
    shoulder = 2 * markers[:, 0] - elbow
    return shoulder, elbow, wrist


def test_clean_markers_are_exactly_on_the_implied_points(clean: list[Trial]) -> None:
    for t in clean:
        shoulder, elbow, wrist = _implied_joints(t.markers)
        true = t.meta["true_joints"]
        np.testing.assert_allclose(shoulder, true[:, 0], atol=1e-12)
        np.testing.assert_allclose(elbow, true[:, 1], atol=1e-12)
        np.testing.assert_allclose(wrist, true[:, 2], atol=1e-12)


def test_clean_geometry_matches_segment_lengths_and_angles(clean: list[Trial]) -> None:
    for t in clean:
        lengths = t.meta["segment_lengths_m"]
        shoulder, elbow, wrist = _implied_joints(t.markers)
        finger = t.markers[:, 3]
        upper, fore, hand = elbow - shoulder, wrist - elbow, finger - wrist
        np.testing.assert_allclose(np.linalg.norm(upper, axis=1), lengths["upper_arm"], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(fore, axis=1), lengths["forearm"], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(hand, axis=1), lengths["hand_marker"], atol=1e-9)
        # elbow flexion = angle between upper arm and forearm; hand continues the forearm
        cos_elbow = (
            np.sum(upper * fore, axis=1)
            / np.linalg.norm(upper, axis=1)
            / np.linalg.norm(fore, axis=1)
        )
        np.testing.assert_allclose(
            np.arccos(np.clip(cos_elbow, -1, 1)), t.truth.angles[:, 3], atol=1e-6
        )
        np.testing.assert_allclose(np.cross(fore, hand), 0.0, atol=1e-9)
        # elevation β = angle between the upper arm and straight down (-z)
        beta = np.arccos(-upper[:, 2] / np.linalg.norm(upper, axis=1))
        np.testing.assert_allclose(beta, t.truth.angles[:, 1], atol=1e-6)
        # plane of elevation γ: azimuth of the upper arm in the shoulder frame (y_S = right)
        u_s = upper @ BODY_TO_SHOULDER.T
        gamma = np.arctan2(u_s[:, 1], u_s[:, 0])
        diff = np.angle(np.exp(1j * (gamma - t.truth.angles[:, 0])))
        np.testing.assert_allclose(diff, 0.0, atol=1e-6)


def test_noisy_marker_distances_follow_segment_lengths(experiment: list[Trial]) -> None:
    no_offsets = imitation_experiment(3, 20, skin_offsets=False)
    for trials, max_dev, rms_dev in ((no_offsets, 0.012, 0.004), (experiment, 0.035, 0.02)):
        devs = []
        for t in trials:
            lengths = t.meta["segment_lengths_m"]
            m = t.markers
            devs.append(np.linalg.norm(m[:, 2] - m[:, 1], axis=1) - lengths["forearm"] / 2)
            devs.append(np.linalg.norm(m[:, 3] - m[:, 2], axis=1) - lengths["hand_marker"])
        dev = np.concatenate(devs)
        assert np.abs(dev).max() < max_dev
        assert np.sqrt(np.mean(dev**2)) < rms_dev
    # the upper-arm sensor sits halfway down the upper arm, so |m1 - m2| is about half the
    # upper arm plus half the forearm at most (triangle inequality), with noise
    for t in no_offsets:
        lengths = t.meta["segment_lengths_m"]
        d12 = np.linalg.norm(t.markers[:, 1] - t.markers[:, 0], axis=1)
        assert np.all(d12 <= (lengths["upper_arm"] + lengths["forearm"]) / 2 + 0.01)


def test_singularity_and_straight_arm_are_avoided(experiment: list[Trial]) -> None:
    angles = np.concatenate([t.truth.angles for t in experiment])
    assert np.degrees(angles[:, 1]).min() >= 18.0 - 1e-9
    assert np.degrees(angles[:, 3]).min() >= 12.0 - 1e-9
    assert np.mean(np.degrees(angles[:, 1]) < 30.0) < 0.02


# --- measurement effects -----------------------------------------------------------------


def _power_fraction(x: np.ndarray, dt: float, above: float) -> float:
    """Fraction of the power of the mean-removed signal (axis 0) above ``above`` Hz."""
    x = x - x.mean(axis=0)
    freqs = np.fft.rfftfreq(x.shape[0], dt)
    power = np.abs(np.fft.rfft(x, axis=0)) ** 2
    return float(power[freqs > above].sum() / power.sum())


CUTOFF_HZ = 0.25 * 0.5 / 0.034  # Butterworth cutoff 0.25 of Nyquist at 34 ms: 3.68 Hz


def test_drift_is_a_slow_common_translation() -> None:
    kw = dict(noise=False, skin_offsets=True, timing_jitter=False)
    with_drift = imitation_experiment(2, 20, drift=True, **kw)
    without = imitation_experiment(2, 20, drift=False, **kw)
    rms = []
    for a, b in zip(with_drift, without, strict=True):
        d = a.markers - b.markers
        np.testing.assert_allclose(d, np.broadcast_to(d[:, :1], d.shape), atol=1e-12)
        rms.append(np.sqrt(np.mean(d[:, 0] ** 2, axis=0)))
    rms = np.array(rms)
    assert 0.001 < np.median(rms[:, 0]) < 0.015 and np.median(rms[:, 2]) < np.median(rms[:, 0])
    # spectrum on a long stretch: below 0.5 Hz
    from visprim.datasets.measurement import shoulder_drift

    t = np.arange(6000) * 0.034
    for seed in range(5):
        drift = shoulder_drift(t, np.random.default_rng(seed), Measurement())
        assert _power_fraction(drift, 0.034, 0.5) < 0.01


def test_vibration_is_above_the_filter_cutoff() -> None:
    from visprim.datasets.measurement import vibration

    m = Measurement()
    t = np.arange(6000) * 0.034
    speed = np.abs(np.sin(2 * np.pi * 0.4 * t))[:, None] * np.ones(4)  # moving, stopping
    for seed in range(5):
        vib = vibration(t, speed, np.random.default_rng(seed), m)
        assert _power_fraction(vib, 0.034, CUTOFF_HZ) > 0.99
        assert 0.3e-3 < np.sqrt(np.mean(vib**2)) * np.sqrt(3) < 3e-3
    # in the experiment: (noise on) - (noise off) with only vibration enabled
    only_vib = Measurement(noise_sd_m=0.0, distortion_rms_m=0.0)
    a = imitation_experiment(2, 20, measurement=only_vib)
    b = imitation_experiment(2, 20, noise=False)
    fractions = [
        _power_fraction((x.markers - y.markers).reshape(x.n_frames, 12), 0.034, CUTOFF_HZ)
        for x, y in zip(a, b, strict=True)
    ]
    assert np.median(fractions) > 0.9


def test_sensor_error_is_about_2_mm() -> None:
    no_vib = Measurement(vibration_amplitude_m=0.0)
    a = imitation_experiment(3, 20, measurement=no_vib)
    b = imitation_experiment(3, 20, noise=False)
    err = np.concatenate([x.markers - y.markers for x, y in zip(a, b, strict=True)])
    rms_3d = np.sqrt(np.mean(np.sum(err**2, axis=-1)))
    assert 1.5e-3 < rms_3d < 2.6e-3
    # the sample-to-sample (white) part is the smaller one: first differences of a white
    # error have sqrt(2) x its SD; the field distortion changes slowly
    jumps = np.concatenate(
        [np.diff(x.markers - y.markers, axis=0) for x, y in zip(a, b, strict=True)]
    )
    assert np.std(jumps) / np.sqrt(2) < 0.6e-3


# --- ground truth --------------------------------------------------------------------------


def test_boundaries_are_at_velocity_minima_of_the_true_angles() -> None:
    fine = Measurement(frame_period_s=0.002)
    trials = imitation_experiment(3, 20, measurement=fine, timing_jitter=False, **CLEAN)
    for t in trials:
        speed = np.linalg.norm(np.gradient(t.truth.angles, t.times, axis=0), axis=1)
        b = t.truth.boundaries
        peak = speed.max()
        for k, tb in enumerate(b):
            i = int(np.argmin(np.abs(t.times - tb)))
            assert speed[i] < 0.01 * peak, (t.name, k)
            window = np.abs(t.times - tb) < 0.08
            assert speed[i] <= speed[window].min() + 0.01 * peak
        # strokes do not stop inside: between two boundaries the arm moves during one
        # contiguous stretch of >= 0.3 s (the rest is a pause) with a single speed peak
        for k in range(b.size - 1):
            span = (t.times > b[k]) & (t.times < b[k + 1])
            moving = np.flatnonzero(span & (speed > 1e-3 * peak))
            assert moving.size and np.all(np.diff(moving) == 1), (t.name, k)
            assert t.times[moving[-1]] - t.times[moving[0]] >= 0.3 - 0.01
            run = speed[moving]
            top = int(np.argmax(run))
            assert np.all(np.diff(run[: top + 1]) > -1e-9 * peak), (t.name, k)
            assert np.all(np.diff(run[top:]) < 1e-9 * peak), (t.name, k)
        # still before the first and after the last stroke
        assert speed[t.times < b[0] - 0.002].max(initial=0.0) < 1e-9
        assert speed[t.times > b[-1] + 0.002].max(initial=0.0) < 1e-9


def test_repeated_strokes_are_similar_but_not_identical(clean: list[Trial]) -> None:
    for t in clean:
        stim = STIMULI[t.stimulus]
        if stim.repetitions < 2:
            continue
        n_pre, n_rep = len(stim.prefix), len(stim.repeat)
        b = t.truth.boundaries
        ends = []
        for r in range(stim.repetitions):
            j = n_pre + (r + 1) * n_rep
            i = int(np.argmin(np.abs(t.times - b[j])))
            ends.append(t.truth.angles[i])
        spread = np.degrees(np.ptp(np.array(ends), axis=0))
        assert np.all(spread < 20.0) and np.any(spread > 0.1), t.name
