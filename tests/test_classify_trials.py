"""Trial-level classification from primitive histograms: fold logic, errors, and the
leave-one-style-out accuracy separating Bandai-Namco "wave" from "raise" trials."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError
from visprim.classify import (
    PrimitiveHistogramClassifier,
    bandai_wave_vs_raise,
    leave_one_group_out,
)
from visprim.io import read_many
from visprim.trial import Trial


def _trial(name: str, **meta: Any) -> Trial:
    t = np.arange(3) * 0.1
    return Trial(times=t, markers=np.zeros((3, 4, 3)), name=name, meta=meta)


class _Recorder:
    """A stand-in classifier: predicts the majority training label, remembers what it saw."""

    seen: list[set[str]] = []

    def fit(self, trials: list[Trial], y: np.ndarray) -> _Recorder:
        _Recorder.seen.append({t.name for t in trials})
        values, counts = np.unique(y, return_counts=True)
        self.label = values[np.argmax(counts)]
        return self

    def predict(self, trials: list[Trial]) -> np.ndarray:
        return np.array([self.label] * len(trials))


def test_leave_one_group_out_never_trains_on_the_held_out_group() -> None:
    trials = [_trial(f"t{i}") for i in range(6)]
    labels = ["a", "a", "b", "b", "b", "a"]
    groups = ["g1", "g1", "g2", "g2", "g3", "g3"]
    _Recorder.seen = []
    res = leave_one_group_out(_Recorder, trials, labels, groups)  # type: ignore[arg-type]
    assert _Recorder.seen == [
        {"t2", "t3", "t4", "t5"},
        {"t0", "t1", "t4", "t5"},
        {"t0", "t1", "t2", "t3"},
    ]
    # Majority of the other groups: g1 → b (3 of 4), g2 → a (3 of 4), g3 → tie a/b → "a".
    assert res.predictions.tolist() == ["b", "b", "a", "a", "a", "a"]
    assert res.accuracy == pytest.approx(1 / 6)
    assert res.per_group == {"g1": 0.0, "g2": 0.0, "g3": 0.5}
    assert "1/6 trials" in str(res)
    with pytest.raises(ValueError, match="must match"):
        leave_one_group_out(_Recorder, trials, labels[:-1], groups)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="two groups"):
        leave_one_group_out(_Recorder, trials, labels, ["g"] * 6)  # type: ignore[arg-type]


def test_bandai_labels_and_classifier_argument_errors() -> None:
    trials = [
        _trial("w", content="wave-right-hand", style="active"),
        _trial("r", content="raise-up-both-hands", style="normal"),
        _trial("x", content="walk", style="normal"),
        _trial("y"),
    ]
    kept, labels, styles = bandai_wave_vs_raise(trials)
    assert [t.name for t in kept] == ["w", "r"]
    assert labels == ["wave", "raise"] and styles == ["active", "normal"]
    with pytest.raises(ValueError, match="no Bandai"):
        bandai_wave_vs_raise(trials[2:])
    with pytest.raises(NotFittedError):
        PrimitiveHistogramClassifier().predict(trials[:1])
    with pytest.raises(ValueError, match="method must be"):
        PrimitiveHistogramClassifier(method="svm").fit(kept, labels)
    with pytest.raises(ValueError, match="two different labels"):
        PrimitiveHistogramClassifier().fit(kept, ["wave", "wave"])


def test_wave_vs_raise_leave_one_style_out(shared_data: Path) -> None:
    trials = read_many(shared_data / "bandai_namco_ds2", resample=0.034)
    kept, labels, styles = bandai_wave_vs_raise(trials)
    assert len(kept) == 34 and labels.count("wave") == 17 and len(set(styles)) == 7

    def make() -> PrimitiveHistogramClassifier:
        return PrimitiveHistogramClassifier(
            {"n_clusters": 10, "n_components": 10}, method="centroid", features="counts"
        )

    res = leave_one_group_out(make, kept, labels, styles)
    print(res)
    # Chance is 0.5 (17 wave, 17 raise). Measured with the Rust kernels: 0.794 (27/34) at
    # seed 0, 0.765-0.794 over k-means seeds 0-7 (features="frequencies": 0.706-0.853, less
    # stable, hence counts). All 7 errors are waves taken for raises (active, elderly,
    # exhausted, feminine styles), whose few slow strokes look like a raise; the number of
    # segments alone already scores 0.765 (26/34). The threshold keeps a 3-trial margin.
    assert res.accuracy >= 0.70
    # Deterministic for the model's seed.
    again = leave_one_group_out(make, kept, labels, styles)
    np.testing.assert_array_equal(again.predictions, res.predictions)
