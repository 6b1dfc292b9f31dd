"""Imitation end to end on generated movements: primitives, rebuild, coverage, Adonis, files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import human_arm_points, imitate, write_imitation
from visprim.io import resample_trial
from visprim.trial import Trial


@pytest.fixture(scope="module")
def data():
    trials = imitation_experiment(2, 4, seed=3, preset="strokes")  # the mechanics, on easy data
    model = PrimitiveModel(n_clusters=6, n_init=2, seed=0).fit(trials[:-1])
    return model, trials[-1]


@pytest.fixture(scope="module")
def result(data):
    model, trial = data
    return imitate(model, trial)


def test_primitive_sequence_is_the_models_prediction(data, result) -> None:
    model, _ = data
    m = result.metrics
    assert m["primitive_sequence"] == list(model.predict(result.trial))
    assert m["n_segments"] == len(m["segments"]) == result.segments.shape[0] >= 2
    assert m["source"] == "primitives" and "primitives" in m["source_label"]


def test_coverage_lists_every_uncovered_second(result) -> None:
    cov = result.metrics["coverage"]
    duration = result.metrics["human_duration_s"]
    listed = sum(u["duration_s"] for u in cov["uncovered"])
    assert listed == pytest.approx(cov["uncovered_s"])
    assert cov["covered_s"] + cov["uncovered_s"] == pytest.approx(duration)
    assert cov["uncovered_percent"] == pytest.approx(100 * cov["uncovered_s"] / duration)
    # Frames inside an uncovered interval belong to no segment, and vice versa.
    t = result.times
    for u in cov["uncovered"]:
        inside = (t > u["start_s"] + 1e-9) & (t < u["end_s"] - 1e-9)
        assert np.all(result.segment_of_frame[inside] == -1)
    assert np.all(
        result.segment_of_frame[(t > result.segments[0, 0]) & (t < result.segments[-1, 1])] >= 0
    )


def test_rebuild_is_continuous_in_angle_and_velocity_at_boundaries(data, result) -> None:
    model, _ = data
    h, eps = 1e-5, 1e-6
    for b in result.segments[1:, 0]:
        t = np.array([b - eps - h, b - eps, b + eps, b + eps + h])
        a, _ = result.rebuild(t)
        assert np.abs(a[2] - a[1]).max() < 1e-4
        assert np.abs((a[3] - a[2]) / h - (a[1] - a[0]) / h).max() < 1e-2
    # The primitives' curves on their own do not meet: joining is what removes the steps.
    curves = model.reconstruct(result.trial, source="cluster")
    steps = [np.abs(c1[-1] - c2[0]).max() for c1, c2 in zip(curves[:-1], curves[1:], strict=True)]
    assert max(steps) > 1e-3


def test_errors_are_reported_and_projection_is_the_near_copy(data, result) -> None:
    model, trial = data
    cov = result.covered
    diff = result.rebuild_angles[cov] - result.human[cov]
    diff[:, [0, 2]] = (diff[:, [0, 2]] + np.pi) % (2 * np.pi) - np.pi  # whole turns of γ, α
    rms = np.degrees(np.sqrt(np.mean(diff**2, axis=0)))
    per = result.metrics["rebuild_vs_human_rms_deg"]
    np.testing.assert_allclose([per[a] for a in ("gamma", "beta", "alpha", "elbow")], rms)
    near = imitate(model, trial, source="projection", play=False)
    assert near.metrics["rebuild_vs_human_rms_deg"]["overall"] < per["overall"]
    assert "NEAR-COPY" in near.metrics["source_label"]
    assert near.playback is None and "adonis" not in near.metrics


def test_adonis_adds_at_most_two_degrees_to_the_rebuild_error(result) -> None:
    a = result.metrics["adonis"]
    rebuild = result.metrics["rebuild_vs_human_joint_rms_deg"]["overall"]
    assert a["vs_human_joint_rms_deg"]["overall"] <= rebuild + 2.0
    assert a["vs_rebuild_joint_rms_deg"]["overall"] < 2.0
    assert a["time_ratio"] == pytest.approx(1.0, abs=0.05)
    assert a["frames_compared"] == int(result.covered.sum())


def test_recording_is_resampled_to_the_models_period(data) -> None:
    model, trial = data
    fast = resample_trial(trial, 1 / 120)
    res = imitate(model, fast, play=False)
    assert np.diff(res.times) == pytest.approx(0.034)
    assert res.metrics["frame_period_s"] == pytest.approx(0.034)


def test_human_arm_points_follow_the_ik_angles(result) -> None:
    from visprim.arm import forward_kinematics
    from visprim.ik import arm_angles

    pts = human_arm_points(result.trial)
    assert np.abs(pts[:, 0]).max() == 0.0  # shoulder at the origin
    fk = forward_kinematics(arm_angles(result.trial))
    for i, j in ((0, 1), (1, 2)):  # upper arm and forearm directions
        u = pts[:, j] - pts[:, i]
        v = fk[:, j] - fk[:, i]
        cos = np.sum(u * v, axis=1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        assert np.all(cos > np.cos(np.radians(1.0)))


def test_files_are_written_and_bad_video_is_refused_first(result, tmp_path) -> None:
    paths = write_imitation(result, tmp_path / "out", video="v.gif", size=(120, 120))
    doc = json.loads(paths["json"].read_text())
    assert doc["primitive_sequence"] == result.metrics["primitive_sequence"]
    assert doc["files"]["video"] == "v.gif" and paths["video"].stat().st_size > 0
    rows = paths["csv"].read_text().splitlines()
    assert len(rows) == result.times.size + 1 and rows[0].startswith("time_s,segment,primitive")
    traj = json.loads(paths["trajectory_json"].read_text())
    assert len(traj["joint_names"]) == 20 and len(traj["points"]) == int(
        np.isfinite(result.rebuild_angles[:, 0]).sum()
    )
    with pytest.raises(ValueError, match="unsupported video format"):
        write_imitation(result, tmp_path / "other", video="v.avi")
    assert not (tmp_path / "other").exists()


def test_a_still_recording_has_nothing_to_imitate(data) -> None:
    model, trial = data
    still = Trial(trial.times, np.repeat(trial.markers[:1], trial.n_frames, axis=0), name="still")
    with pytest.raises(ValueError, match="no segment"):
        imitate(model, still)


def test_bad_options_are_refused(data) -> None:
    model, trial = data
    with pytest.raises(ValueError, match="source"):
        imitate(model, trial, source="cluster")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="servo"):
        imitate(model, trial, servo="pid")  # type: ignore[arg-type]


def test_a_failing_video_leaves_no_file(result, tmp_path, monkeypatch) -> None:
    import visprim.sim.sidebyside as sidebyside

    def broken(*args, **kwargs):
        raise RuntimeError("encoder failed")

    monkeypatch.setattr(sidebyside, "render_imitation", broken)
    with pytest.raises(RuntimeError, match="encoder failed"):
        write_imitation(result, tmp_path / "out", video="v.gif")
    assert list((tmp_path / "out").iterdir()) == []


def test_amplitude_scaled_primitives_rebuild_closer(data) -> None:
    """With ``amplitude=True`` each primitive is scaled to its segment: the rebuild moves
    closer to the human than the primitives as they are (same segments and sequence)."""
    model, trial = data
    plain = imitate(model, trial, play=False)
    scaled_model = PrimitiveModel(**{**model.get_params(), "amplitude": True}).fit(
        imitation_experiment(2, 4, seed=3, preset="strokes")[:-1]
    )
    scaled = imitate(scaled_model, trial, play=False)
    assert scaled.metrics["primitive_sequence"] == plain.metrics["primitive_sequence"]
    err = [r.metrics["rebuild_vs_human_rms_deg"]["overall"] for r in (scaled, plain)]
    assert err[0] < err[1]


def test_bone_direction_errors_are_reported(result) -> None:
    """The bone-direction RMS is the angle between the arm's bones, recomputed here from
    forward kinematics of the angles (independent of visprim.features)."""
    from visprim.arm import forward_kinematics

    m = result.metrics
    cov = result.covered

    def bones(angles: np.ndarray) -> np.ndarray:
        pts = forward_kinematics(angles)  # shoulder, elbow, wrist, hand
        b = np.stack([pts[:, 1] - pts[:, 0], pts[:, 2] - pts[:, 1]], axis=1)
        return b / np.linalg.norm(b, axis=2, keepdims=True)

    cos = np.clip(np.sum(bones(result.rebuild_angles[cov]) * bones(result.human[cov]), 2), -1, 1)
    want = np.degrees(np.sqrt(np.mean(np.arccos(cos) ** 2)))
    assert m["rebuild_vs_human_direction_rms_deg"] == pytest.approx(want, rel=1e-9)
    assert 0.0 < m["adonis"]["vs_human_direction_rms_deg"] < 90.0
    assert "bone-direction RMS" in result.summary()


def test_headline_is_the_bone_direction_rms_beside_holding_still(result) -> None:
    """One headline figure (Adonis vs human, bone directions) and the still-posture
    baseline, recomputed here from forward kinematics."""
    from visprim.arm import forward_kinematics

    head = result.metrics["headline"]
    assert head["compares"] == "Adonis vs human"
    assert head["rms_deg"] == result.metrics["adonis"]["vs_human_direction_rms_deg"]
    human = result.human[result.covered]
    pts = forward_kinematics(human)
    bones = np.stack([pts[:, 1] - pts[:, 0], pts[:, 2] - pts[:, 1]], axis=1)
    bones /= np.linalg.norm(bones, axis=2, keepdims=True)
    mean = bones.mean(axis=0)
    mean /= np.linalg.norm(mean, axis=1, keepdims=True)
    cos = np.clip(np.sum(bones * mean, axis=2), -1, 1)
    want = np.degrees(np.sqrt(np.mean(np.arccos(cos) ** 2)))
    assert head["still_posture_rms_deg"] == pytest.approx(want, rel=1e-9)
    assert head["ratio_to_still"] == pytest.approx(head["rms_deg"] / want)
    text = result.summary()
    first = text.splitlines()[2]
    assert first.startswith("  headline: Adonis vs human bone-direction RMS")
    assert f"{head['still_posture_rms_deg']:.2f}" in first
    assert "details" in text


def test_headline_notes_one_primitive_and_near_still() -> None:
    from visprim.imitate import headline

    metrics = {"rebuild_vs_human_direction_rms_deg": 4.7}
    head = headline(metrics, [0, 0, 0], still_deg=5.0)
    assert head["compares"] == "rebuild vs human"
    assert len(head["notes"]) == 2
    assert "primitive 0" in head["notes"][0] and "holding" in head["notes"][1]
    assert headline(metrics, [0, 1, 0], still_deg=20.0)["notes"] == []
