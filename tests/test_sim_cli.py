"""`visprim simulate` and demo_primitives, with a stand-in model and with a learned one."""

from __future__ import annotations

import csv

import numpy as np
import pytest
import visprim.cli.simulate as simulate_cli
import visprim.sim.showcase as sim_cli
from PIL import Image
from visprim.cli import main
from visprim.sim.trajectories import minimum_jerk


class FakeModel:
    """Duck-typed PrimitiveModel: three minimum-jerk strokes as 'primitives'."""

    def __init__(self) -> None:
        ends = np.array(
            [
                [[0.0, 0.4, 0.0, 0.4], [0.3, 1.3, 0.4, 1.2]],
                [[1.2, 1.0, -0.2, 0.3], [1.5, 0.6, 0.2, 1.4]],
                [[0.5, 0.8, 0.5, 1.5], [0.1, 1.8, 0.0, 0.5]],
            ]
        )
        self.primitive_durations_ = np.array([0.5, 0.4, 0.6])
        self.labels_ = np.array([2, 2, 1, 2, 0, 1])
        self._angles = []
        for pair, d in zip(ends, self.primitive_durations_, strict=True):
            t, a = minimum_jerk(pair, [d], rate=(100 - 1) / d)
            self._angles.append(a[:100])

    @property
    def n_primitives(self) -> int:
        return 3

    def primitive_angles(self, k: int) -> np.ndarray:
        return self._angles[k]


def test_primitive_trajectory_spans_the_duration() -> None:
    times, angles = sim_cli.primitive_trajectory(FakeModel(), 1)
    assert times[0] == 0.0 and times[-1] == pytest.approx(0.4)
    assert angles.shape == (100, 4)
    with pytest.raises(ValueError, match="out of range"):
        sim_cli.primitive_trajectory(FakeModel(), 3)


def test_demo_primitives_writes_gifs_and_metrics(tmp_path, caplog) -> None:
    with caplog.at_level("INFO", logger="visprim"):
        paths = sim_cli.demo_primitives(FakeModel(), tmp_path / "demo", n=2)
    # Only primitives 1 and 2 hold two segments or more (labels_).
    assert [p.name for p in paths] == ["adonis_primitive_01.gif", "adonis_primitive_02.gif"]
    for p in paths:
        with Image.open(p) as im:
            assert im.n_frames > 5
    with open(tmp_path / "demo" / "adonis_metrics.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(r["primitive"]) for r in rows] == [0, 1, 2]
    for r in rows:
        assert float(r["rms_error_deg"]) <= 5.0
        assert float(r["time_ratio"]) <= 1.5
        assert r["via_reached"] == r["via_points"]
    assert "all 3 primitives" in caplog.text and "adonis_primitive_02.gif" in caplog.text


def test_demo_plays_the_primitives_that_move_most() -> None:
    """Not the most used: a still primitive holding most segments is passed over. The
    motion is the bones' path length, recomputed from forward kinematics."""
    from visprim.arm import forward_kinematics

    model = FakeModel()
    model._angles.append(np.tile(model._angles[0][:1], (100, 1)))  # primitive 3: still
    a0 = model._angles[0]
    model._angles.append(a0[:1] + 0.5 * (a0 - a0[:1]))  # primitive 4: half of 0
    model.primitive_durations_ = np.array([0.5, 0.4, 0.6, 0.5, 0.4])
    model.labels_ = np.array([3, 3, 3, 3, 3, 0, 0, 1, 1, 2, 2, 4, 4])
    type(model).n_primitives = property(lambda self: 5)  # type: ignore[assignment]

    def path(angles: np.ndarray) -> float:
        pts = forward_kinematics(angles)
        bones = np.stack([pts[:, 1] - pts[:, 0], pts[:, 2] - pts[:, 1]], axis=1)
        bones /= np.linalg.norm(bones, axis=2, keepdims=True)
        cos = np.clip(np.sum(bones[1:] * bones[:-1], axis=2), -1, 1)
        return float(np.degrees(np.arccos(cos).sum()))

    moves = [path(model.primitive_angles(k)) for k in range(5)]
    assert moves[3] < 0.01  # arccos of 1 - rounding
    for k in range(5):
        assert sim_cli.motion_deg(model.primitive_angles(k)) == pytest.approx(moves[k], abs=0.01)
    want = sorted(int(i) for i in np.argsort(moves)[::-1][:3])
    assert 3 not in want
    assert sim_cli._default_indices(model, 3) == want


def test_simulate_command_with_stand_in_model(tmp_path, monkeypatch, capsys) -> None:
    model_file = tmp_path / "model.npz"
    model_file.write_bytes(b"stand-in")
    monkeypatch.setattr(simulate_cli, "_load_model", lambda path: FakeModel())
    out = tmp_path / "clip.gif"
    assert main(["simulate", str(model_file), "--primitive", "2", "--out", str(out)]) == 0
    with Image.open(out) as im:
        assert im.n_frames == 16  # 0.6 s at 25 Hz, t = 0 included
    assert "primitive 2: RMS" in capsys.readouterr().out
    argv = ["simulate", str(model_file), "--primitive", "7", "--out", str(out), "--force"]
    assert main(argv) == 2
    assert "out of range" in capsys.readouterr().err
    assert main(["simulate", str(model_file), "--out", str(out)]) == 2
    assert main(["simulate", str(tmp_path / "missing.npz"), "--primitive", "0"]) == 2
    assert "not found" in capsys.readouterr().err


def test_simulate_learned_model_primitives_and_movement(tmp_path, capsys) -> None:
    """End to end on a small generated corpus: learn, save, then play every primitive
    (the simulation targets), render one primitive, and imitate a recording through the
    primitives (the chain of `visprim imitate`, not the near-copy projection)."""
    datasets = pytest.importorskip("visprim.datasets")
    from visprim import PrimitiveModel
    from visprim.imitate import imitate
    from visprim.io.markers_csv import write_marker_csv

    trials = datasets.imitation_experiment(n_subjects=2, n_stimuli=4, seed=0)
    model = PrimitiveModel(n_components=8, n_clusters=5, n_init=2).fit(trials[1:])
    path = tmp_path / "model.vpm"
    model.save(path)
    loaded = PrimitiveModel.load(path)
    for k, pb in sim_cli.play_primitives(loaded).items():
        assert np.all(np.isfinite(pb.q_actual)), k
        assert pb.rms_error_deg <= 5.0, (k, pb.summary())
        assert pb.completion_time <= 1.5 * pb.movement_duration, (k, pb.summary())
    gif = tmp_path / "p0.gif"
    assert main(["simulate", str(path), "--primitive", "0", "--out", str(gif)]) == 0
    assert gif.is_file()
    capsys.readouterr()
    trial_file = tmp_path / f"{trials[0].name}.csv"
    write_marker_csv(trial_file, trials[0])
    gif2 = tmp_path / "movement.gif"
    assert main(["simulate", str(path), "--movement", str(trial_file), "--out", str(gif2)]) == 0
    with Image.open(gif2) as im:
        assert im.n_frames > 25  # a whole 3-5 s movement
    printed = capsys.readouterr().out
    # The figures printed are those of the imitation through primitives of that recording,
    # measured against the human, with the uncovered parts listed.
    ref = imitate(loaded, str(trial_file), play=False).metrics
    assert "NEAR-COPY" not in printed and "uncovered" in printed
    seq = " ".join(str(k) for k in ref["primitive_sequence"])
    assert f"primitives {seq}" in printed
    assert f"overall {ref['rebuild_vs_human_rms_deg']['overall']:.2f}" in printed
    assert "Adonis vs human" in printed
    near = imitate(loaded, str(trial_file), source="projection", play=False).metrics
    assert near["rebuild_vs_human_rms_deg"]["overall"] != pytest.approx(
        ref["rebuild_vs_human_rms_deg"]["overall"], abs=0.01
    )
    png = tmp_path / "near.png"
    argv = ["simulate", str(path), "--movement", str(trial_file), "--out", str(png)]
    assert main([*argv, "--source", "projection"]) == 0
    printed = capsys.readouterr().out
    assert "NEAR-COPY" in printed
    assert f"overall {near['rebuild_vs_human_rms_deg']['overall']:.2f}" in printed
    assert png.is_file()


def test_simulate_source_needs_a_movement(tmp_path, monkeypatch, capsys) -> None:
    model_file = tmp_path / "model.npz"
    model_file.write_bytes(b"stand-in")
    monkeypatch.setattr(simulate_cli, "_load_model", lambda path: FakeModel())
    argv = ["simulate", str(model_file), "--primitive", "0", "--source", "projection"]
    assert main([*argv, "--out", str(tmp_path / "x.gif")]) == 2
    assert "--source applies to --movement only" in capsys.readouterr().err
    assert not (tmp_path / "x.gif").exists()
    argv = ["simulate", str(model_file), "--movement", str(tmp_path / "none.bvh")]
    assert main([*argv, "--out", str(tmp_path / "x.gif")]) == 2
    assert "recording" in capsys.readouterr().err
    assert not (tmp_path / "x.gif").exists()


def test_posture_relative_primitives_are_played_where_their_segments_were() -> None:
    """A primitive of posture-relative vectors placed at its segments' mean posture has
    their mean elevation and is closer to them (bone directions) than the bare shape
    around the zero posture (members come from several postures: the primitive is one)."""
    from visprim import PrimitiveModel
    from visprim.datasets import imitation_experiment
    from visprim.features import direction_rms_deg

    trials = imitation_experiment(2, 4, seed=0)
    model = PrimitiveModel.paper(offsets="mean", n_components=8, n_clusters=4, n_init=2)
    model.fit(trials)
    postures = sim_cli.primitive_postures(model, trials)
    assert postures.shape == (4, 4)
    sv = model.vectorize(model.prepare(trials))
    curves = sv.to_trial_angles(sv.vectors)  # each segment on the trial's own angles
    k = int(np.argmax(np.bincount(model.labels_)))
    members = curves[model.labels_ == k]
    _, posed = sim_cli.primitive_trajectory(model, k, postures[k])
    _, bare = sim_cli.primitive_trajectory(model, k)
    # The arm's mean elevation β is the members' (not the hanging arm's) ...
    beta = np.degrees(members[:, :, 1].mean())
    assert abs(np.degrees(posed[:, 1].mean()) - beta) < 2.0
    assert abs(np.degrees(bare[:, 1].mean()) - beta) > 10.0
    # ... and the bones are nearer the members' throughout.
    err_posed = np.mean([direction_rms_deg(posed, m) for m in members])
    err_bare = np.mean([direction_rms_deg(bare, m) for m in members])
    assert err_posed < err_bare, (err_posed, err_bare)
