"""Misuse refused up front, in one line: bad option values, missing labels."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.classify import MotionClassifier
from visprim.cli import main
from visprim.datasets import imitation_experiment


def run(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


@pytest.mark.parametrize(
    "option", [["--resample", "0"], ["--resample", "-1"], ["--resample", "nan"],
               ["--resample", "1e9"], ["--jobs", "0"], ["--jobs", "-5"]],
)  # fmt: skip
def test_evaluate_checks_resample_and_jobs_first(option, tmp_path, capsys):
    assert run(["evaluate", str(tmp_path), "--out", str(tmp_path / "r"), *option]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and option[0] in err[0], err


@pytest.fixture(scope="module")
def movements():
    trials = imitation_experiment(2, 3, seed=1)
    return trials, np.array([t.stimulus for t in trials])


def test_motion_classifier_needs_labels(movements):
    trials, _ = movements
    with pytest.raises(ValueError, match="y must be one label per training movement"):
        MotionClassifier().fit(trials, None)
    with pytest.raises(ValueError, match="y must be one label per training"):
        MotionClassifier(method="histogram").fit(trials, None)


@pytest.mark.parametrize("window", [np.inf, np.nan, 0.0, -1.0])
def test_motion_classifier_window_must_be_finite(movements, window):
    trials, labels = movements
    with pytest.raises(ValueError, match=r"window=.*must be a finite number > 0"):
        MotionClassifier(window=window).fit(trials, labels)


def test_a_diverging_simulation_is_one_clear_line(tmp_path, capsys):
    from visprim import PrimitiveModel
    from visprim.io.markers_csv import write_marker_csv

    trials = imitation_experiment(2, 4, seed=4)
    PrimitiveModel(n_clusters=5, n_init=2).fit(trials[:-1]).save(tmp_path / "m.npz")
    rec = write_marker_csv(tmp_path / "take.csv", trials[-1])
    argv = ["imitate", str(tmp_path / "m.npz"), str(rec), "--out", str(tmp_path / "o")]
    assert run([*argv, "--servo", "paper", "--dt", "0.002", "--no-video"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "diverged" in err[0] and "--dt" in err[0], err
    assert "internal error" not in err[0] and "a bug" not in err[0]
    assert not (tmp_path / "o").exists()


def test_ctrl_c_while_a_local_cluster_starts_is_deferred():
    import os
    import signal

    from visprim.scale import _interrupt_deferred

    with _interrupt_deferred() as interrupted:
        os.kill(os.getpid(), signal.SIGINT)  # recorded, not raised inside the block
    assert interrupted == [signal.SIGINT]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
