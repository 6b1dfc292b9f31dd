"""Nested leave-one-group-out choice of the rate settings (visprim.rate.nested), and the
primitive corrected by DCT coefficients of its residual."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _motion_data import movements
from visprim.evaluate import Recording, make_benchmarks
from visprim.rate import segment_numbers
from visprim.rate.descriptions import dct_residual
from visprim.rate.nested import nested_markdown, nested_rate, write_nested_report
from visprim.vectors import to_vectors

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}
SEARCH = (("mean", None), ("unit", 0.8))
FAMILIES = ("nearest", "residual", "nearest+dct")


def _bench(seed: int = 0, other_last: int | None = None):
    data, labels = movements(3, seed=seed)
    if other_last is not None:
        # Other movements (of the same kinds) in the last group only (g2: the last three).
        data[6:] = movements(3, seed=other_last)[0][6:]
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    return make_benchmarks(recs, data)[0][0]


def _run(bench):
    return nested_rate(
        bench, budgets=(12, 40), search=SEARCH, families=FAMILIES, model_params=SMALL_MODEL
    )


def test_dct_residual_adds_what_the_prediction_misses() -> None:
    rng = np.random.default_rng(0)
    n, c = 16, 6
    u = np.linspace(0.0, 1.0, n)
    # A slow cosine on every channel: the first non-constant DCT term holds it all.
    wave = np.cos(np.pi * (np.arange(n) + 0.5) / n)[:, None] * rng.normal(size=(1, c))
    x = to_vectors(wave[None])
    zero = np.zeros_like(x)
    np.testing.assert_allclose(dct_residual(x, zero, c, 1), x, atol=1e-12)
    # The constant term is left out: the posture stores a segment's mean.
    shifted = x + 0.3
    np.testing.assert_allclose(dct_residual(shifted, zero, c, 1), x, atol=1e-12)
    # With skip_constant=False (absolute curves) the constant is the first term.
    const = np.full((1, n * c), 0.3)
    np.testing.assert_allclose(dct_residual(const, zero, c, 1, skip_constant=False), const)
    # More coefficients never move the rebuild further from the segment.
    y = to_vectors((u[:, None] ** 3 * rng.normal(size=(1, c)))[None])
    errs = [np.sum((y - dct_residual(y, zero, c, q)) ** 2) for q in range(1, 6)]
    assert all(b <= a + 1e-12 for a, b in zip(errs, errs[1:], strict=False))
    # Counting: id, duration, posture, then q numbers for each of the 6 shape channels.
    assert segment_numbers("nearest+dct", 4, q=2) == 2 + 4 + 12
    assert segment_numbers("residual+dct", 6, m=3, q=1) == 2 + 6 + 3 + 6


def test_the_outer_group_never_steers_its_own_choice(tmp_path: Path) -> None:
    """The choice for an outer group is made on the other groups only: changing the
    outer group's movements changes its score, never its choice."""
    plain = _run(_bench())
    changed = _run(_bench(other_last=7))
    outer = [c for c in plain.choices if c["group"] == "g2"]
    outer_changed = [c for c in changed.choices if c["group"] == "g2"]
    assert outer and outer == outer_changed
    scores = [[r["bone_deg"] for r in res.rows if r["group"] == "g2"] for res in (plain, changed)]
    assert scores[0] != scores[1]
    # Every choice fits its budget on the inner folds that made it.
    assert all(c["inner_numbers_per_s"] <= c["budget"] for c in plain.choices)
    kinds = {s["kind"] for s in plain.summary()}
    assert {"visprim", "dct-angles", "keyframes-angles"} <= kinds
    text = nested_markdown([plain])
    assert "nested leave-one-group-out" in text and "| 12 |" in text
    paths = write_nested_report([plain], tmp_path)
    assert paths["rate_nested_csv"].read_text().startswith("benchmark,budget,kind")


def test_nested_needs_three_groups() -> None:
    data, labels = movements(2, seed=1)
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    bench = make_benchmarks(recs, data)[0][0]
    with pytest.raises(ValueError, match="at least 3 groups"):
        nested_rate(bench, search=SEARCH, families=FAMILIES, model_params=SMALL_MODEL)


def test_the_command_line_reads_the_declared_rate_settings() -> None:
    import argparse

    from visprim.cli.evaluate import _stroke, register
    from visprim.params import RATE_OPTIONS

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["evaluate", "data"])
    assert args.rate_posture == RATE_OPTIONS["posture"].default
    assert args.max_stroke == RATE_OPTIONS["max_stroke"].default
    assert args.rate_centres == RATE_OPTIONS["centres"].default and not args.rate_nested
    assert parser.parse_args(["evaluate", "d", "--max-stroke", "none"]).max_stroke is None
    assert _stroke("1.5") == 1.5
    for bad in ("-1", "soon"):
        with pytest.raises(argparse.ArgumentTypeError):
            _stroke(bad)
