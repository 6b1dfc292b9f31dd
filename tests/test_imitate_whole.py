"""The eigen-movements in the model file and `imitate(..., budget=N)` describing a recording
whole through them (visprim.rate.budget.learn_eigen_movements, visprim.imitate)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate
from visprim.modelfile import ModelFileError
from visprim.rate.budget import learn_eigen_movements


@pytest.fixture(scope="module")
def data():
    trials = imitation_experiment(2, 4, seed=3, preset="strokes")
    model = PrimitiveModel(n_clusters=6, n_components=8, n_init=2, seed=0).fit(trials[:-1])
    model.eigen_movements_ = learn_eigen_movements(model, trials[:-1])
    return model, trials


@pytest.fixture(scope="module")
def saved(data, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("model") / "eigen.npz"
    data[0].save(path)
    return path


def _err(result) -> float:
    return result.metrics["rebuild_vs_human_direction_rms_deg"]


def _without_book(model: PrimitiveModel) -> PrimitiveModel:
    import copy

    old = copy.copy(model)
    old.eigen_movements_ = None
    return old


# ---------------------------------------------------------------------------- the model file


def test_the_book_is_learned_from_every_training_movement(data) -> None:
    model, trials = data
    book = model.eigen_movements_
    # One movement per training trial (one arm each): fewer components than movements
    # (their mean is taken out), and a mean of averaged unit bone directions.
    assert 1 <= book.n_components <= len(trials) - 2
    assert book.mean.shape == (book.n_samples * 6,)
    assert np.all(np.linalg.norm(book.mean.reshape(-1, 3), axis=1) <= 1 + 1e-9)


def test_eigen_movements_round_trip(data, saved) -> None:
    model, _ = data
    loaded = PrimitiveModel.load(saved)
    a, b = model.eigen_movements_, loaded.eigen_movements_
    assert b is not None and b.n_samples == a.n_samples
    np.testing.assert_array_equal(b.mean, a.mean)
    np.testing.assert_array_equal(b.components, a.components)


def test_files_without_eigen_movements_load_as_before(data, tmp_path) -> None:
    path = tmp_path / "old.npz"
    _without_book(data[0]).save(path)
    with np.load(path) as npz:
        assert not any(name.startswith("eigen_movements") for name in npz.files)
    assert PrimitiveModel.load(path).eigen_movements_ is None


def _forge(src: Path, dst: Path, change) -> None:
    """Copy ``src`` to ``dst`` with ``change(arrays)`` applied and the header resealed
    (array specs and checksums recomputed, as a deliberate forger would), so that the
    checks of the values themselves are reached."""
    with np.load(src) as npz:
        arrays = {k: npz[k].copy() for k in npz.files}
    header = json.loads(arrays.pop("header").tobytes().decode())
    change(arrays)
    header["arrays"] = {
        name: {
            "shape": list(a.shape),
            "dtype": a.dtype.str,
            "sha256": hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest(),
        }
        for name, a in arrays.items()
    }
    body = {k: v for k, v in header.items() if k != "header_sha256"}
    canonical = json.dumps(body, sort_keys=True, separators=(",", ":")).encode()
    header["header_sha256"] = hashlib.sha256(canonical).hexdigest()
    np.savez(dst, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays)


def _set(name: str, value) -> object:
    def change(arrays: dict) -> None:
        arrays[name] = value(arrays[name])

    return change


def _nan(a: np.ndarray) -> np.ndarray:
    a = a.copy()
    a.flat[3] = np.nan
    return a


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_set("eigen_movements_mean", _nan), "NaN or infinity"),
        (_set("eigen_movements_components", _nan), "NaN or infinity"),
        (_set("eigen_movements_mean", lambda a: a[:-1]), "mean has shape"),
        (_set("eigen_movements_mean", lambda a: a[:-6]), "components have shape"),
        (_set("eigen_movements_components", lambda a: a[:-6]), "components have shape"),
        (_set("eigen_movements_mean", lambda a: a.reshape(-1, 6)), "mean has shape"),
        (_set("eigen_movements_mean", lambda a: 3.0 * a), "not bone directions"),
        (_set("eigen_movements_components", lambda a: 2.0 * a), "not orthonormal"),
        (lambda arrays: arrays.pop("eigen_movements_components"), "without its companion"),
    ],
)
def test_tampered_eigen_movements_are_refused(saved, tmp_path, change, message) -> None:
    bad = tmp_path / "tampered.npz"
    _forge(saved, bad, change)
    with pytest.raises(ModelFileError, match=message):
        PrimitiveModel.load(bad)


def test_an_untouched_forgery_still_loads(saved, tmp_path) -> None:
    """The forger of the test above, changing nothing: the refusals come from the values."""
    same = tmp_path / "same.npz"
    _forge(saved, same, lambda arrays: None)
    assert PrimitiveModel.load(same).eigen_movements_ is not None


# ---------------------------------------------------------------------------- imitate


def test_without_a_budget_nothing_changes(data) -> None:
    model, trials = data
    new = imitate(model, trials[-1], play=False)
    old = imitate(_without_book(model), trials[-1], play=False)
    assert new.metrics == old.metrics
    assert "encoder_choice" not in new.metrics["description"]


def test_a_training_movement_is_described_whole(data) -> None:
    """A training movement lies in the span of the eigen-movements: with enough numbers
    for every component its whole rebuild is exact up to resampling, closer than any
    segment description, and the encoder says it took the whole movement."""
    model, trials = data
    book = model.eigen_movements_
    seconds = imitate(model, trials[0], play=False).metrics["description"]["seconds"]
    # Start, duration, the code number, every component, and the choice flag.
    budget = (3 + book.n_components + 1) / seconds + 1.0
    result = imitate(model, trials[0], play=False, budget=budget)
    d = result.metrics["description"]
    choice = d["encoder_choice"]
    assert choice["alternatives"] == ["cut", "uncut", "whole"]
    assert choice["chosen"] == "whole" and d["whole_movement"]
    assert "whole movement" in d["description"] and d["posture"] is None
    assert choice["frames_rms_deg"]["whole"] < 1.0
    assert _err(result) < 1.0
    assert d["numbers"] <= budget * d["seconds"] + 1e-9
    assert result.metrics["n_segments"] == 1 and result.metrics["primitive_sequence"] == [-1]
    summary = result.summary()
    assert "whole movement" in summary and "whole " in summary.split("encoder's choice")[1]


@pytest.mark.parametrize("budget", [12.0, 30.0])
def test_a_held_out_movement_takes_the_closest_alternative_within_the_budget(data, budget) -> None:
    model, trials = data
    result = imitate(model, trials[-1], play=False, budget=budget)
    d = result.metrics["description"]
    choice = d["encoder_choice"]
    assert set(choice["frames_rms_deg"]) == {"cut", "uncut", "whole"}
    assert d["numbers_per_s"] <= budget * (1 + 1e-12)
    assert d["numbers"] <= budget * d["seconds"] + 1e-9
    # The movement described whole alone, without the flag: the alternative's error, and
    # what the choice keeps is no worse than it nor than the segments without a book.
    segments = imitate(_without_book(model), trials[-1], play=False, budget=budget)
    assert _err(result) <= _err(segments) + 1e-9
    assert _err(result) <= choice["frames_rms_deg"]["whole"] + 1e-9
    # Forcing the stroke cut forces segments: no whole movement, no choice.
    forced = imitate(
        model, trials[-1], play=False, budget=budget, budget_options={"max_stroke": None}
    )
    assert "encoder_choice" not in forced.metrics["description"]
    assert not forced.metrics["description"]["whole_movement"]


def test_two_arms_share_the_budget_when_described_whole(data) -> None:
    """A one-arm model on a two-arm recording: each arm described whole takes its share,
    and both together fit the budget."""
    from _motion_data import two_arm_strokes

    model, _ = data
    both = two_arm_strokes()
    budget = 30.0
    result = imitate(model, both, play=False, budget=budget)
    d = result.metrics["description"]
    assert "whole" in d["encoder_choice"]["frames_rms_deg"]
    assert d["numbers"] <= budget * d["seconds"] + 1e-9
    assert d["numbers"] == sum(a["numbers"] for a in d["arms"].values()) + 1


def test_learn_stores_the_book_and_imitate_budget_reports_the_choice(tmp_path, capsys) -> None:
    """From the command line: ``visprim learn`` writes the eigen-movements into the model
    file; ``imitate --budget`` weighs the whole movement, and imitation.json and the printed
    report say what it used, within the budget."""
    from visprim.cli.main import main
    from visprim.io.markers_csv import write_marker_csv

    trials = imitation_experiment(2, 4, seed=3, preset="strokes")
    takes = [write_marker_csv(tmp_path / f"take{i}.csv", t) for i, t in enumerate(trials)]
    model = tmp_path / "model.npz"
    assert main(["learn", *map(str, takes[:-1]), "--clusters", "5", "--out", str(model)]) == 0
    assert "eigen-movements:" in capsys.readouterr().out
    assert PrimitiveModel.load(model).eigen_movements_ is not None
    out = tmp_path / "out"
    argv = ["imitate", str(model), str(takes[-1]), "--out", str(out), "--no-video"]
    assert main([*argv, "--budget", "12"]) == 0
    printed = capsys.readouterr().out
    d = json.loads((out / "imitation.json").read_text())["description"]
    choice = d["encoder_choice"]
    assert set(choice["frames_rms_deg"]) == {"cut", "uncut", "whole"}
    assert d["whole_movement"] == (choice["chosen"] == "whole")
    assert d["numbers"] <= 12 * d["seconds"] + 1e-9
    assert f"{d['numbers']} numbers in" in printed and "whole" in printed


def test_a_movement_too_long_to_describe_whole_is_refused_and_said(data, monkeypatch) -> None:
    import visprim.imitate as imitation

    model, trials = data
    monkeypatch.setattr(imitation, "MAX_WHOLE_FRAMES", 10)
    result = imitate(model, trials[-1], play=False, budget=30.0)
    choice = result.metrics["description"]["encoder_choice"]
    assert set(choice["frames_rms_deg"]) == {"cut", "uncut"} and choice["chosen"] != "whole"
    assert "MAX_WHOLE_FRAMES" in choice["refused"]["whole"]


def test_a_two_arm_model_describes_both_arms_whole_within_the_budget() -> None:
    """A two-arm model: its eigen-movements are one-arm (both arms of every training
    trial, the left mirrored), and a recording described whole codes each arm."""
    from _motion_data import movements

    trials, _ = movements(3, seed=1)
    model = PrimitiveModel(n_clusters=4, n_components=6, n_init=1).fit(trials[:-1])
    assert model.arms_ == ("right", "left")
    model.eigen_movements_ = learn_eigen_movements(model, trials[:-1])
    # Two one-arm movements per training trial: fewer components than that.
    assert model.eigen_movements_.n_components <= 2 * len(trials[:-1]) - 1
    budget = 40.0
    result = imitate(model, trials[-1], play=False, budget=budget)
    d = result.metrics["description"]
    errors = d["encoder_choice"]["frames_rms_deg"]
    assert set(errors) == {"cut", "uncut", "whole"} and np.isfinite(errors["whole"])
    assert d["numbers"] <= budget * d["seconds"] + 1e-9
    assert _err(result) <= min(errors.values()) + 1e-9
    assert result.human.shape[1] == 8
    assert np.all(np.isfinite(result.rebuild_angles[result.covered]))
