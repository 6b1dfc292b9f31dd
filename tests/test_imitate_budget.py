"""The size of an imitation's description and `imitate(..., budget=N)`."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate


@pytest.fixture(scope="module")
def data():
    trials = imitation_experiment(2, 4, seed=3, preset="strokes")
    model = PrimitiveModel(n_clusters=6, n_components=8, n_init=2, seed=0).fit(trials[:-1])
    return model, trials[-1]


def _err(result) -> float:
    return result.metrics["rebuild_vs_human_direction_rms_deg"]


def test_the_description_states_its_size(data) -> None:
    model, trial = data
    result = imitate(model, trial, play=False)
    d = result.metrics["description"]
    n = result.metrics["n_segments"]
    # Start time, then per segment: primitive id, duration, 6 posture numbers.
    assert d["numbers"] == 1 + 8 * n and d["budget_numbers_per_s"] is None
    span = result.segments[-1, 1] - result.segments[0, 0]
    assert d["seconds"] == pytest.approx(span)
    assert d["numbers_per_s"] == pytest.approx(d["numbers"] / span)
    assert d["description"] == "nearest primitive"
    assert "numbers/s" in result.summary()
    near_copy = imitate(model, trial, play=False, source="projection")
    # The projection: 8 coefficients, the duration and the posture per segment.
    assert near_copy.metrics["description"]["numbers"] == 1 + 15 * n


def test_a_budget_picks_the_best_description_that_fits(data) -> None:
    model, trial = data
    plain = imitate(model, trial, play=False)
    rate = plain.metrics["description"]["numbers_per_s"]
    seconds = plain.metrics["description"]["seconds"]
    n = plain.metrics["n_segments"]
    # Room for three residual coefficients per segment: more than the primitive alone.
    budget = (1 + 11 * n) / seconds + 1e-6
    mid = imitate(model, trial, play=False, budget=budget)
    d = mid.metrics["description"]
    assert d["numbers_per_s"] <= budget and d["budget_numbers_per_s"] == budget
    assert d["numbers"] > plain.metrics["description"]["numbers"]
    assert _err(mid) < _err(plain)
    # An ample budget affords the richest description, the primitive with residual and
    # DCT coefficients: at least as close as each segment's own projection.
    ample = imitate(model, trial, play=False, budget=1e4)
    assert "DCT coefficient" in ample.metrics["description"]["description"]
    projection = imitate(model, trial, play=False, source="projection")
    assert _err(ample) <= _err(projection) + 1e-9
    assert _err(ample) <= _err(mid)
    with pytest.raises(ValueError, match="below the smallest description"):
        imitate(model, trial, play=False, budget=0.5 * rate)
    with pytest.raises(ValueError, match="budget picks the description"):
        imitate(model, trial, play=False, budget=100.0, source="projection")


def test_two_arms_share_the_budget(data) -> None:
    """Arms imitated one by one share one budget: the best combination that fits."""
    from _motion_data import _two_arms

    model, _ = data
    s = np.linspace(0.0, 1.0, 90)
    right = np.stack(
        [0.4 + 0.8 * s, 0.5 + np.sin(np.pi * s), 0.2 * s, 0.4 + 0.6 * np.sin(2 * np.pi * s)], 1
    )
    left = np.stack([0.3 + 0 * s, 0.4 + 0.9 * np.sin(2 * np.pi * s) ** 2, 0 * s, 1.0 - 0.5 * s], 1)
    both = _two_arms(right, left, "both")
    plain = imitate(model, both, play=False)
    d = plain.metrics["description"]
    assert set(d["arms"]) == {"right", "left"}
    assert d["numbers"] == sum(a["numbers"] for a in d["arms"].values())
    budget = 1.5 * d["numbers_per_s"]
    shared = imitate(model, both, play=False, budget=budget)
    sh = shared.metrics["description"]
    assert sh["numbers_per_s"] <= budget * (1 + 1e-9) and sh["numbers"] > d["numbers"]
    assert _err(shared) < _err(plain)
    with pytest.raises(ValueError, match="below the smallest description"):
        imitate(model, both, play=False, budget=0.9 * d["numbers_per_s"])
