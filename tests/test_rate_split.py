"""The DCT code of ``eigen/dct-splitD`` and ``eigen/dct-fitD`` (visprim.rate.descriptions):
the splits of the coefficients over the channels the index chooses from, the encoder's
choice among them, and the coefficients fitted to the bone directions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.fft import dct, idct
from visprim.features import from_angles
from visprim.rate.descriptions import (
    best_dct_split,
    dct_rebuild_counts,
    dct_splits,
    eigen_describe,
    eigen_numbers,
    fit_dct_coefficients,
    fit_eigen_movements,
)
from visprim.rate.measures import bone_rms_deg


def _movement(seed: int, frames: int = 70) -> tuple[np.ndarray, np.ndarray]:
    """Smooth random arm angles ``(T, 4)`` (away from the shoulder's singular posture)
    and their bone directions."""
    rng = np.random.default_rng(seed)
    u = np.linspace(0.0, 1.0, frames)[:, None]
    wave = np.sin(2 * np.pi * rng.uniform(0.3, 2.5, size=4) * u + rng.uniform(0, 6, size=4))
    angles = np.array([0.3, 1.2, -0.4, 1.0]) + 0.5 * wave
    return angles, from_angles(angles, "directions")


@pytest.mark.parametrize(("n", "spread"), [(12, 1), (13, 2), (22, 2), (21, 3), (5, 2)])
def test_dct_splits_are_every_split_near_the_even_share(n: int, spread: int) -> None:
    """Against a brute-force enumeration of all splits of n over 4 channels."""
    brute = sorted(
        s
        for s in itertools.product(range(1, n + 1), repeat=4)
        if sum(s) == n and all(abs(k - n / 4) <= spread for k in s)
    )
    got = dct_splits(n, 4, spread, 1000)
    assert [tuple(int(k) for k in row) for row in got] == brute
    assert len(got) > 0


def test_dct_splits_respect_the_frames() -> None:
    assert dct_splits(40, 4, 2, 9).shape[0] == 0  # no channel can hold more than 9
    assert np.all(dct_splits(34, 4, 2, 9) <= 9)


def test_best_dct_split_is_the_closest_split() -> None:
    """The chosen split is the one whose truncated DCT rebuilds the bone directions
    closest, checked split by split with the plain functions."""
    angles, directions = _movement(0)
    n, spread = 14, 2
    index, rebuilt, err = best_dct_split(angles, directions, n, spread)
    errors = [
        bone_rms_deg(from_angles(dct_rebuild_counts(angles, s), "directions"), directions)
        for s in dct_splits(n, 4, spread, angles.shape[0])
    ]
    assert index == int(np.argmin(errors))
    assert err == pytest.approx(min(errors), abs=1e-9)
    np.testing.assert_allclose(
        rebuilt, dct_rebuild_counts(angles, dct_splits(n, 4, spread, angles.shape[0])[index])
    )


def test_fitted_coefficients_are_decodable_and_closer() -> None:
    """The fitted angles are still the first counts[j] DCT coefficients of each channel
    (the decoder is unchanged), and rebuild the bones no worse than the truncated DCT."""
    angles, directions = _movement(1)
    counts = np.array([3, 4, 2, 3])
    rebuilt, err = fit_dct_coefficients(angles, directions, counts)
    coef = dct(rebuilt, type=2, norm="ortho", axis=0)
    rows = np.arange(coef.shape[0])[:, None]
    assert np.max(np.abs(coef[rows >= counts[None, :]])) < 1e-9
    truncated = bone_rms_deg(
        from_angles(dct_rebuild_counts(angles, counts), "directions"), directions
    )
    assert err == pytest.approx(bone_rms_deg(from_angles(rebuilt, "directions"), directions))
    assert err < truncated


def test_fit_finds_a_band_limited_movement_from_a_poor_start() -> None:
    """Bone directions made from angles with only counts[j] DCT coefficients are
    representable exactly: fitted from angles off by a smooth error, the rebuild comes
    back close."""
    rng = np.random.default_rng(3)
    t, counts = 60, np.array([3, 3, 2, 2])
    coef = np.zeros((t, 4))
    coef[0] = [0.3 * np.sqrt(t), 1.2 * np.sqrt(t), -0.4 * np.sqrt(t), 1.0 * np.sqrt(t)]
    for j, k in enumerate(counts):
        coef[1:k, j] = rng.normal(scale=0.8, size=k - 1)
    exact = idct(coef, type=2, norm="ortho", axis=0)
    directions = from_angles(exact, "directions")
    start = exact + 0.15 * np.sin(np.linspace(0, 3, t))[:, None]
    before = bone_rms_deg(from_angles(dct_rebuild_counts(start, counts), "directions"), directions)
    _, err = fit_dct_coefficients(start, directions, counts, iterations=10)
    assert before > 3.0
    assert err < 0.05 * before


def test_split_and_fit_families_count_as_eigen_dct_and_improve_on_it() -> None:
    angles, directions = [], []
    for seed in range(12):
        a, d = _movement(seed + 10, frames=40 + 3 * seed)
        angles.append(a)
        directions.append(d)
    seconds = [0.034 * (a.shape[0] - 1) for a in angles]
    book = fit_eigen_movements(directions[:-1], angles[:-1], seconds[:-1], (12.0,))
    a, d, s = angles[-1], directions[-1], seconds[-1]
    errs = {}
    for family in ("eigen/dct", "eigen/dct-split2", "eigen/dct-fit2"):
        code, rebuilt, numbers = eigen_describe(book, family, 12.0, s, d, a)
        assert numbers == eigen_numbers(12.0, s)
        errs[family] = bone_rms_deg(
            rebuilt if code == "eigen" else from_angles(rebuilt, "directions"), d
        )
    # The split search includes the even split eigen/dct uses only when it is within
    # the spread, which an even split always is; the fit starts from the chosen split.
    assert errs["eigen/dct-split2"] <= errs["eigen/dct"] + 1e-9
    assert errs["eigen/dct-fit2"] <= errs["eigen/dct-split2"] + 1e-9


def test_whole_movement_rows_are_shared_across_segment_settings() -> None:
    """The nested search scores every segment setting on one fold; the whole-movement
    rows (which ignore those settings) are computed once and are the same rows as a fold
    computed afresh."""
    from pathlib import Path

    from _motion_data import movements
    from visprim.evaluate import Recording, make_benchmarks
    from visprim.rate.benchmark import _fold
    from visprim.trial import split_arms

    data, labels = movements(3, seed=0)
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    bench = make_benchmarks(recs, data)[0][0]
    groups = [str(g) for g in bench.groups]
    train = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g != "g2"])
    test = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g == "g2"])
    small = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}

    def run(settings: list[tuple[str, float | None]], prepared: dict) -> list[list[dict]]:
        out = []
        for posture, stroke in settings:
            rows: list[dict] = []
            _fold(
                train,
                test,
                "g2",
                small,
                ("eigen/dct-fit1",),
                centres="projection",
                max_stroke=stroke,
                rows=rows,
                posture_mode=posture,
                prepared=prepared,
                joint=False,
            )
            out.append(rows)
        return out

    shared = run([("mean", None), ("unit", 0.8)], {})
    fresh = run([("unit", 0.8)], {})
    assert shared[0] == shared[1] == fresh[0]
    assert shared[0] and {r["family"] for r in shared[0]} == {"eigen/dct-fit1"}
    assert all(r["numbers"] <= r["param"] * r["seconds"] + 1e-9 for r in shared[0])


def test_a_whole_movement_within_a_budget_uses_the_fitted_code_by_default() -> None:
    from visprim.rate.budget import describe_movement

    angles, directions = [], []
    for seed in range(12):
        a, d = _movement(seed + 30, frames=50 + 2 * seed)
        angles.append(a)
        directions.append(d)
    seconds = [0.034 * (a.shape[0] - 1) for a in angles]
    book = fit_eigen_movements(directions[:-1], angles[:-1], seconds[:-1], (12.0,))
    a, d, s = angles[-1], directions[-1], seconds[-1]
    values, desc = describe_movement(book, d, a, s, 12.0)
    code, rebuilt, numbers = eigen_describe(book, "eigen/dct-fit3", 12.0, s, d, a)
    expected = rebuilt if code == "eigen" else from_angles(rebuilt, "directions")
    np.testing.assert_allclose(values, expected)
    assert desc.numbers == numbers == eigen_numbers(12.0, s)
    with pytest.raises(ValueError, match="not 'eigen'"):
        describe_movement(book, d, a, s, 12.0, code_family="eigen")


def test_fitted_dct_baseline_stores_the_same_numbers_and_rebuilds_closer() -> None:
    from visprim.rate.benchmark import HeldOut, _baseline

    angles, directions = _movement(5, frames=80)
    times = 0.034 * np.arange(angles.shape[0])
    mv = HeldOut(
        "m",
        "g",
        times,
        directions,
        angles,
        np.array([[times[0], times[-1]]]),
        np.array([0]),
    )
    rows: list[dict] = []
    for family in ("dct-angles", "dct-angles-fit"):
        _baseline(rows, mv, family, 12.0)
    plain, fitted = rows
    assert plain["numbers"] == fitted["numbers"]
    assert fitted["bone_deg"] < plain["bone_deg"]
