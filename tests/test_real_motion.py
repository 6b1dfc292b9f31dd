"""Segmentation and vectors that hold on real motion: bone-direction features, robust SEG-2
tuning, coverage, SEG-1 on fast cyclic motion, short clips and two-arm trials."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.arm import forward_kinematics
from visprim.features import from_angles, periodic_channels, to_angles
from visprim.ik import arm_angles, arm_angles_corpus
from visprim.segment import seg1
from visprim.segment.coverage import segment_coverage
from visprim.segment.seg2 import robust_seg2_thresholds, speed_squared
from visprim.trial import Trial, TrialError

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
BANDAI = DATA / "bandai_namco_ds2"
needs_data = pytest.mark.skipif(not BANDAI.is_dir(), reason="../shared/data not present")


def _trial_from_angles(times, angles, name="t"):
    """A trial whose joint centres follow ``angles`` exactly (FK, body frame = world)."""
    pts = forward_kinematics(angles)
    markers = np.stack(
        [
            (pts[:, 0] + pts[:, 1]) / 2,
            (pts[:, 1] + pts[:, 2]) / 2,
            pts[:, 2],
            pts[:, 3],
        ],
        axis=1,
    )
    return Trial(times=times, markers=markers, joints=pts[:, :3], name=name)


@pytest.fixture(scope="module")
def bandai() -> list[Trial]:
    from visprim.io import read_many

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_many([BANDAI], resample=0.034)


# ---------------------------------------------------------------------------- features


def test_direction_features_round_trip_and_units() -> None:
    rng = np.random.default_rng(0)
    t = np.arange(200) * 0.034
    a = np.stack(
        [
            0.5 + 0.3 * np.sin(t),
            1.0 + 0.4 * np.sin(1.3 * t),
            0.2 * np.cos(t),
            1.0 + 0.3 * np.sin(0.7 * t),
        ],
        axis=1,
    ) + rng.normal(0, 1e-3, (200, 4))
    v = from_angles(a, "directions")
    assert v.shape == (200, 6)
    np.testing.assert_allclose(np.linalg.norm(v[:, :3], axis=1), 1.0)
    np.testing.assert_allclose(np.linalg.norm(v[:, 3:], axis=1), 1.0)
    np.testing.assert_allclose(to_angles(v, "directions", t), a, atol=1e-9)
    assert periodic_channels("directions", 2) == ()
    assert periodic_channels("zyz", 2) == (0, 2, 4, 6)


def test_direction_speed_stays_small_through_the_singularity() -> None:
    """Arm hanging, upper arm swaying 2° around the vertical: the Euler speed blows up
    (γ and α swing in opposite directions), the bone-direction speed does not."""
    t = np.arange(300) * 0.01
    upper = np.stack(
        [
            np.sin(np.deg2rad(2)) * np.cos(2 * t),
            np.sin(np.deg2rad(2)) * np.sin(2 * t),
            -np.ones_like(t),
        ],
        axis=1,
    )
    upper /= np.linalg.norm(upper, axis=1, keepdims=True)
    fore = upper + np.array([0.3, 0.0, 0.0])
    shoulder = np.zeros_like(upper)
    elbow = 0.3 * upper
    wrist = elbow + 0.25 * fore / np.linalg.norm(fore, axis=1, keepdims=True)
    joints = np.stack([shoulder, elbow, wrist], axis=1)
    markers = np.stack([elbow / 2, (elbow + wrist) / 2, wrist, wrist + 0.1 * upper], axis=1)
    trial = Trial(times=t, markers=markers, joints=joints, name="sway")
    angles = arm_angles(trial)
    z_euler = speed_squared(t, angles)
    z_dir = speed_squared(t, from_angles(angles, "directions"))
    # The upper arm's tip moves at 2 rad/s × sin 2° ≈ 0.07 rad/s; the forearm likewise.
    assert np.max(z_dir[5:-5]) < 0.1
    assert np.max(z_euler[5:-5]) > 10 * np.max(z_dir[5:-5])


# ---------------------------------------------------------------------------- SEG-2 tuning


def test_robust_threshold_ignores_static_trials_and_scales_slow_ones() -> None:
    z = np.concatenate([np.full(100, 4.0), np.full(100, 5.0), np.full(100, 0.04), np.zeros(100)])
    off = np.array([0, 100, 200, 300])
    c, per = robust_seg2_thresholds(z, off, fraction=0.02, slowest=100.0)
    assert c == pytest.approx(0.02 * 4.0)  # median of the moving trials' speeds (4, 5, 0.04)
    assert per[0] == pytest.approx(c) and per[1] == pytest.approx(c)
    assert per[2] == pytest.approx(0.02 * 0.04)  # the slow trial: its own, lower threshold
    assert per[3] == pytest.approx(c / 100.0)  # the static trial: the floor
    c2, _ = robust_seg2_thresholds(np.concatenate([z, np.zeros(50)]), np.append(off, 400))
    assert c2 == c


@needs_data
def test_seg2_on_real_recordings_is_stable_and_covers_the_movement(bandai) -> None:
    model = PrimitiveModel()
    corpus = model.prepare(bandai, tune_seg2=True)
    c = corpus.seg2_threshold
    first = bandai[0]
    jitter = np.random.default_rng(0).normal(0, 0.002, first.joints.shape)  # 2 mm, like a tracker
    frozen = dataclasses.replace(
        first,
        markers=np.broadcast_to(first.markers[:1], first.markers.shape).copy(),
        joints=np.broadcast_to(first.joints[:1], first.joints.shape) + jitter,
        name="near-static",
    )
    c_static = model.prepare([*bandai, frozen], tune_seg2=True).seg2_threshold
    c_fewer = model.prepare(bandai[3:], tune_seg2=True).seg2_threshold
    for other in (c_static, c_fewer):
        assert 0.5 < other / c < 2.0
    cov = segment_coverage(bandai, corpus.segments)
    assert np.nanmedian(cov) >= 0.95
    assert np.nanmin(cov) >= 0.7


@needs_data
def test_slow_movement_keeps_its_return_stroke(bandai) -> None:
    """The elderly raise-up (slow) is covered nearly whole, with several segments."""
    model = PrimitiveModel()
    corpus = model.prepare(bandai, tune_seg2=True)
    i = next(i for i, t in enumerate(bandai) if "raise-up-right-hand_elderly" in t.name)
    segs = corpus.segments[i]
    assert len(segs) >= 2
    assert segment_coverage([bandai[i]], [segs])[0] >= 0.9


# ---------------------------------------------------------------------------- SEG-1


def test_seg1_cuts_fast_cyclic_motion_at_half_cycles() -> None:
    t = np.arange(0, 4, 0.034)
    f = 2.5  # Hz: half-cycles of 0.2 s, shorter than the 300 ms window
    a = np.stack(
        [
            0.5 + 0.4 * np.sin(2 * np.pi * f * t),
            1.2 + 0.3 * np.sin(2 * np.pi * f * t),
            0.3 * np.ones_like(t),
            1.0 + 0.5 * np.sin(2 * np.pi * f * t),
        ],
        axis=1,
    )
    assert len(seg1(t, a, adaptive=False)) == 0  # the paper's rule chains everything
    segs = seg1(t, a)
    assert len(segs) >= 2 * f * 4 * 0.7  # most half-cycles
    np.testing.assert_allclose(np.median(np.diff(segs, axis=1)), 0.5 / f, rtol=0.15)


# ---------------------------------------------------------------------------- short clips


def test_short_clips_do_not_fail_a_corpus() -> None:
    from visprim.datasets import imitation_experiment

    trials = imitation_experiment(n_subjects=2, n_stimuli=4, seed=1)
    short = dataclasses.replace(
        trials[0],
        times=trials[0].times[:20],
        markers=trials[0].markers[:20],
        joints=None,
        truth=None,
        name="short",
    )
    tiny = dataclasses.replace(short, times=short.times[:3], markers=short.markers[:3], name="tiny")
    model = PrimitiveModel(n_components=8, n_clusters=4, n_init=2).fit([*trials, short, tiny])
    assert model.n_short_trials_ == 2
    assert model.n_trials_without_segments_ >= 1  # the 3-frame clip cannot hold a segment


# ---------------------------------------------------------------------------- two arms


def test_two_arm_trial_mirrors_the_left_arm() -> None:
    t = np.arange(100) * 0.034
    a = np.stack(
        [0.4 + 0.2 * np.sin(t), 1.0 + 0.3 * np.cos(t), 0.1 * t, 0.8 + 0.2 * np.sin(2 * t)], 1
    )
    right = _trial_from_angles(t, a)
    mirror = np.array([1.0, -1.0, 1.0])
    both = Trial(
        times=t,
        markers=np.concatenate([right.markers, right.markers * mirror], axis=1),
        joints=np.concatenate([right.joints, right.joints * mirror], axis=1),
        arms=("right", "left"),
        name="both",
    )
    angles = arm_angles_corpus([both])[0]
    assert angles.shape == (100, 8)
    np.testing.assert_allclose(angles[:, :4], a, atol=1e-9)
    np.testing.assert_allclose(angles[:, 4:], a, atol=1e-9)  # the mirror image: same angles
    with pytest.raises(TrialError, match="markers must have shape"):
        Trial(times=t, markers=right.markers, arms=("right", "left"))
    with pytest.raises(ValueError, match="same arm"):
        arm_angles_corpus([both, right])


@needs_data
def test_read_both_arms_and_fit_a_two_arm_model() -> None:
    from visprim.io import read

    files = sorted(BANDAI.glob("dataset-2_wave-both-hands_*.bvh"))[:4]
    trials = [read(f, "both", resample=0.034) for f in files]
    assert trials[0].markers.shape[1:] == (8, 3) and trials[0].arms == ("right", "left")
    model = PrimitiveModel(n_components=10, n_clusters=3, n_init=2).fit(trials)
    assert model.dim == 12 * 100
    assert model.primitive_angles(0).shape == (100, 8)
    times, rec, orig = model.reconstruct_movement(trials[0], return_original=True)
    assert rec.shape == orig.shape and rec.shape[1] == 8
    assert np.degrees(np.sqrt(np.mean((rec - orig) ** 2))) < 15.0
    with pytest.raises(ValueError, match="arms"):
        model.transform([read(files[0], resample=0.034)])
