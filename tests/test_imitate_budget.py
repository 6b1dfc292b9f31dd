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
    from _motion_data import two_arm_strokes

    model, _ = data
    both = two_arm_strokes()
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
        imitate(model, both, play=False, budget=0.5 * d["numbers_per_s"])


def test_a_budget_uses_the_rate_benchmark_settings(data) -> None:
    """With a budget: the RATE_OPTIONS defaults (unit posture, strokes cut), counted and
    stated; without: the model's own storage."""
    from visprim.params import RATE_OPTIONS

    model, trial = data
    plain = imitate(model, trial, play=False)
    d0 = plain.metrics["description"]
    assert d0["posture"] == "mean" and d0["max_stroke_s"] is None
    cut = {"max_stroke": RATE_OPTIONS["max_stroke"].default}
    result = imitate(model, trial, play=False, budget=1e4, budget_options=cut)
    d = result.metrics["description"]
    assert d["posture"] == RATE_OPTIONS["posture"].default
    assert d["max_stroke_s"] == RATE_OPTIONS["max_stroke"].default
    assert "encoder_choice" not in d
    assert "strokes cut at" in result.summary() and "uncut" in plain.summary()
    # No stroke longer than max_stroke, and the cuts tile the uncut segments.
    durations = result.segments[:, 1] - result.segments[:, 0]
    assert durations.max() <= d["max_stroke_s"] + 1e-9
    assert result.segments[0, 0] == pytest.approx(plain.segments[0, 0])
    assert result.segments[-1, 1] == pytest.approx(plain.segments[-1, 1])
    assert durations.sum() == pytest.approx(np.sum(plain.segments[:, 1] - plain.segments[:, 0]))
    # The cheapest description under these settings: start time, and per (cut) segment the
    # id, the duration and 4 posture numbers (two unit bone directions).
    n = result.metrics["n_segments"]
    assert n > plain.metrics["n_segments"]
    least = (1 + 6 * n) / d["seconds"]
    cheapest = imitate(model, trial, play=False, budget=least + 1e-9, budget_options=cut)
    c = cheapest.metrics["description"]
    assert c["numbers"] == 1 + 6 * n and c["description"] == "nearest primitive"
    assert c["numbers_per_s"] <= least + 1e-9
    with pytest.raises(ValueError, match="below the smallest description"):
        imitate(model, trial, play=False, budget=0.99 * least, budget_options=cut)
    # The model's own storage within a budget, when asked for.
    old = imitate(model, trial, play=False, budget=1e4, budget_options={"max_stroke": None})
    assert old.metrics["n_segments"] == plain.metrics["n_segments"]
    with pytest.raises(ValueError, match="only with a budget"):
        imitate(model, trial, play=False, budget_options={"posture": "unit"})


def test_unit_posture_keeps_the_mean_bone_directions(data) -> None:
    """A segment rebuilt with the unit posture points each bone, on average, where the
    segment's mean bone direction points."""
    from visprim.rate.budget import (
        budget_settings,
        cut_vectors,
        describe_segments,
        rebuilt_postures,
    )
    from visprim.vectors import to_curves

    model, trial = data
    settings = budget_settings()
    sv = cut_vectors(model, model.prepare([trial]), settings.max_stroke)
    seconds = float(sv.ends.max() - sv.starts.min())
    rebuilt, d = describe_segments(
        model, sv.vectors, seconds, budget=1e4, settings=settings, postures=sv.offsets
    )
    assert d.settings.posture == "unit"
    curves = (
        to_curves(rebuilt, model.n_channels)
        + rebuilt_postures(model, d.settings, sv.offsets, rebuilt)[:, None, :]
    )
    mean = curves.mean(axis=1).reshape(len(curves), -1, 3)
    own = sv.offsets.reshape(len(curves), -1, 3)
    unit = lambda v: v / np.linalg.norm(v, axis=-1, keepdims=True)  # noqa: E731
    assert np.allclose(unit(mean), unit(own), atol=1e-9)
    # Each bone's mean squared length is one, as for the unit bones of a movement.
    length2 = np.sum(curves.reshape(len(curves), curves.shape[1], -1, 3) ** 2, axis=3)
    assert np.allclose(length2.mean(axis=1), 1.0, atol=1e-9)


@pytest.mark.parametrize("budget", [12.0, 40.0])
def test_the_encoder_chooses_to_cut_strokes_or_not(data, budget) -> None:
    """Without a stroke cut given, the encoder describes the movement cut and uncut, each
    within the budget less one number (the flag that says which), and keeps the one whose
    rebuilt frames lie closer to the movement's; the choice is counted and stated."""
    from visprim.params import RATE_OPTIONS

    model, trial = data
    span = imitate(model, trial, play=False).metrics["description"]["seconds"]
    result = imitate(model, trial, play=False, budget=budget)
    d = result.metrics["description"]
    choice = d["encoder_choice"]
    assert choice["numbers"] == 1 and choice["cut_at_s"] == RATE_OPTIONS["max_stroke"].default
    assert d["numbers_per_s"] <= budget * (1 + 1e-12)
    # Each alternative forced, within the same numbers: none lies closer than the choice.
    forced = {
        key: imitate(
            model,
            trial,
            play=False,
            budget=budget - 1 / span,
            budget_options={"max_stroke": cut_at},
        )
        for key, cut_at in (("cut", choice["cut_at_s"]), ("uncut", None))
    }
    for key, f in forced.items():
        assert _err(f) == pytest.approx(choice["frames_rms_deg"][key], rel=1e-9)
        assert _err(result) <= _err(f) + 1e-9
    # The chosen one is what was kept, and its flag is counted.
    kept = forced[choice["chosen"]].metrics["description"]
    assert d["numbers"] == kept["numbers"] + 1 and d["max_stroke_s"] == kept["max_stroke_s"]
    assert "encoder's choice" in result.summary() and "1 number" in d["counted"]
