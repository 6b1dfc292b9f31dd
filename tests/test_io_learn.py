"""End to end on the real recordings: ``visprim learn`` on a small folder and on the five
original folders of ../shared/data together (every format: BVH, ASF/AMC, C3D), Tables 1-3
printed and checked against a numpy recomputation from the saved model."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.cli import main
from visprim.io import read_many

# Trials per folder, from the SOURCE.md tables (one trial per recording; no long gaps).
FOLDER_TRIALS = {
    "bandai_namco_ds2": 34,
    "cmu_asfamc": 6,
    "cmu_iclone_bvh": 2,
    "kineticstoolkit_c3d": 2,
    "pyomeca_c3d": 1,
}


def test_learn_small_folder_then_classify_the_same_frames(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = shared_data / "kineticstoolkit_c3d"
    model_path = tmp_path / "m.npz"
    assert main(["learn", str(folder), "--out", str(model_path), "--clusters", "8"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("2 trials -> ")
    assert out.count("**Table") == 3
    m = PrimitiveModel.load(model_path)
    assert m.n_primitives == 8
    assert sorted(m.trial_names_) == ["kinematics_racing_full", "kinematics_tennis_serve"]
    assert m.frame_period_ == pytest.approx(0.034)

    # classify resamples DATA to the model's period, so the same recordings are cut into
    # exactly the training segments (at the files' 50/70 Hz they would not be).
    seg_csv = tmp_path / "segments.csv"
    assert main(["classify", str(model_path), str(folder), "--out", str(seg_csv)]) == 0
    with seg_csv.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == m.n_training_segments_
    by_trial = {name: i for i, name in enumerate(m.trial_names_)}
    got = sorted((by_trial[r["trial"]], float(r["start_s"]), float(r["end_s"])) for r in rows)
    want = sorted(
        zip(
            m.segment_trial_.tolist(),
            m.segment_starts_.tolist(),
            m.segment_ends_.tolist(),
            strict=True,
        )
    )
    np.testing.assert_allclose(np.array(got), np.array(want), atol=1e-6)
    labels = np.array([int(r["primitive"]) for r in rows])
    assert np.bincount(labels, minlength=8).sum() == len(rows)


def test_learn_each_arm_learns_one_arm_primitives_from_both(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--arm each``: every recording gives its right arm and its mirrored left arm as two
    one-arm trials; the report re-reads them the same way from the recorded source."""
    files = sorted((shared_data / "bandai_namco_ds2").glob("*.bvh"))[:3]
    model_path = tmp_path / "m.npz"
    args = ["learn", *map(str, files), "--out", str(model_path), "--clusters", "8"]
    assert main([*args, "--arm", "each"]) == 0
    assert capsys.readouterr().out.startswith("6 trials -> ")
    m = PrimitiveModel.load(model_path)
    assert m.arms_ == ("right",)
    assert m.trial_names_ == [f"{f.stem}_{side}" for f in files for side in ("right", "left")]
    assert main(["report", str(model_path), "--out", str(tmp_path / "rep")]) == 0
    # Streaming reads file by file and splits each file's arms the same way.
    streamed = tmp_path / "s.npz"
    stream = ["learn", *map(str, files), "--out", str(streamed), "--clusters", "8", "--stream"]
    assert main([*stream, "--arm", "each"]) == 0
    s = PrimitiveModel.load(streamed)
    assert s.trial_names_ == m.trial_names_ and s.n_training_segments_ == m.n_training_segments_
    np.testing.assert_allclose(s.eigenvalues_[:30], m.eigenvalues_[:30], rtol=1e-9, atol=1e-12)


def test_learn_with_fewer_segments_than_clusters_is_a_clear_error(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # One box lift (pyomeca) yields 4 SEG-2 segments: 30 primitives cannot be learned.
    model_path = tmp_path / "m.npz"
    assert main(["learn", str(shared_data / "pyomeca_c3d"), "--out", str(model_path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert re.search(r"--clusters 30 exceeds .*\(4\).*lower --clusters", err[0])
    assert not model_path.exists()


def test_learn_the_original_recordings_gives_tables_1_to_3(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model_path = tmp_path / "all.npz"
    folders = [str(shared_data / f) for f in FOLDER_TRIALS]
    assert main(["learn", *folders, "--out", str(model_path)]) == 0
    out = capsys.readouterr().out
    n_trials = sum(FOLDER_TRIALS.values())
    assert out.startswith(f"{n_trials} trials -> ")
    for title in ("**Table 1: projection", "**Table 2: clustering", "**Table 3: total"):
        assert out.count(title) == 1

    m = PrimitiveModel.load(model_path)
    assert (m.n_primitives, m.n_components) == (30, 30)
    # Every folder (every format) contributes trials and segments.
    trials = read_many([shared_data / f for f in FOLDER_TRIALS], resample=0.034)
    folders = [Path(t.source or "").parent.name for t in trials]
    assert {f: folders.count(f) for f in FOLDER_TRIALS} == FOLDER_TRIALS
    assert [t.name for t in trials] == m.trial_names_
    seg_folders = {folders[i] for i in m.segment_trial_.tolist()}
    assert seg_folders == set(FOLDER_TRIALS)

    # Recompute the f = 30 / k = 30 rows with numpy from the saved model and fresh segments.
    vectors = m.vectorize(m.prepare(trials)).vectors
    assert vectors.shape == (m.n_training_segments_, m.dim)
    e = m.components_
    p = (vectors - m.mean_) @ e
    projection_mse = float(np.mean(np.sum((vectors - (p @ e.T + m.mean_)) ** 2, axis=1)))
    d2 = ((p[:, None, :] - m.cluster_centers_[None, :, :]) ** 2).sum(axis=2)
    clustering_mse = float(np.mean(d2.min(axis=1)))
    tables = m.error_tables_
    assert tables is not None
    t1, t2, t3 = tables.projection, tables.clustering, tables.total
    f_rows = list(t1.column("eigenvectors f"))
    k_rows = list(t2.column("clusters k"))
    assert f_rows == [10, 20, 30, 40, 50, 60, 80, 100]
    assert k_rows == [10, 20, 30, 100, 170]  # N > 170 segments: no row clipped
    row1 = t1.column("measured projection MSE (rad^2)")[f_rows.index(30)]
    row2 = t2.column("clustering MSE (rad^2)")[k_rows.index(30)]
    row3 = t3.column("measured total MSE (rad^2)")[k_rows.index(30)]
    assert row1 == pytest.approx(projection_mse, rel=1e-6)
    assert row2 == pytest.approx(clustering_mse, rel=1e-6)
    assert row3 == pytest.approx(projection_mse + clustering_mse, rel=1e-6)
    # More eigenvectors never increase the projection error; more clusters (k-means,
    # best of 10 restarts) lower the clustering error on this corpus.
    assert np.all(np.diff(t1.column("measured projection MSE (rad^2)")) <= 1e-12)
    assert np.all(np.diff(t2.column("clustering MSE (rad^2)")) < 0)
