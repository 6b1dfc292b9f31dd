"""Eigen-movements (visprim.rate.descriptions): a whole movement as a superposition of a
basis learned from training movements, its counting, and that the held-out movements never
enter the basis."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from _motion_data import movements
from visprim.evaluate import Recording, make_benchmarks
from visprim.features import from_angles
from visprim.rate.benchmark import _fold
from visprim.rate.descriptions import (
    EIGEN_SAMPLES,
    dct_counts,
    dct_rebuild_counts,
    eigen_describe,
    eigen_numbers,
    fit_eigen_movements,
)
from visprim.rate.measures import bone_rms_deg, dct_rebuild
from visprim.trial import split_arms

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def _span_movements(k: int, n: int, seed: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """``n`` movements of EIGEN_SAMPLES frames (so resampling is the identity), each a
    fixed posture plus a random superposition of the same ``k`` smooth random curves of
    the 6 bone-direction channels; and those curves."""
    rng = np.random.default_rng(seed)
    u = np.linspace(0.0, 1.0, EIGEN_SAMPLES)[:, None, None]
    freq = rng.uniform(0.5, 3.0, size=(1, k, 6))
    phase = rng.uniform(0.0, 2 * np.pi, size=(1, k, 6))
    basis = np.sin(2 * np.pi * freq * u + phase)  # (T, k, 6)
    posture = np.array([0.2, 0.1, -0.9, 0.5, 0.3, -0.7])
    out = [posture + np.einsum("tkc,k->tc", basis, rng.normal(size=k)) for _ in range(n)]
    return basis, out


def test_a_movement_in_the_span_of_k_eigen_movements_needs_k_coefficients() -> None:
    k = 5
    _, train = _span_movements(k, 40, seed=0)
    book = fit_eigen_movements(train)
    assert book.n_components == k  # the training movements span k directions, no more
    _, unseen = _span_movements(k, 43, seed=0)  # same curves; the last 3 are new weights
    unseen = unseen[40:]
    for mv in unseen:
        np.testing.assert_allclose(book.rebuild(mv, k), mv, atol=1e-9)
        assert np.max(np.abs(book.rebuild(mv, k - 1) - mv)) > 1e-3


def test_eigen_numbers_never_exceed_the_rate() -> None:
    assert eigen_numbers(10, 2.0) == 20
    assert eigen_numbers(12, 1.25) == 15  # floor(15.0)
    assert eigen_numbers(10, 1.99) == 19
    assert eigen_numbers(10, 0.1) == 4  # start, duration, flag and one coefficient
    for rate in (8.0, 12.0, 16.0):
        for seconds in (0.7, 1.3, 2.2, 5.1):
            assert eigen_numbers(rate, seconds) <= rate * seconds + 1e-9


def test_dct_counts_split_evenly_and_in_order() -> None:
    np.testing.assert_array_equal(dct_counts(10, 4, (3, 1, 0, 2)), [2, 3, 2, 3])
    assert int(dct_counts(17, 4, (0, 1, 2, 3)).sum()) == 17
    rng = np.random.default_rng(1)
    v = rng.normal(size=(30, 4))
    np.testing.assert_allclose(dct_rebuild_counts(v, np.full(4, 30)), v, atol=1e-12)
    np.testing.assert_allclose(dct_rebuild_counts(v, np.full(4, 5)), dct_rebuild(v, 5))


def test_eigen_descriptions_count_and_choose() -> None:
    """``eigen`` stores numbers − 2 coefficients; ``eigen/dct`` also one flag, and keeps
    the closer of the eigen-movements and the DCT of the angles at that size."""
    rng = np.random.default_rng(2)
    angles = []
    for _ in range(12):
        u = np.linspace(0.0, 1.0, int(rng.integers(40, 80)))[:, None]
        wave = np.sin(2 * np.pi * rng.uniform(0.3, 2.0, size=4) * u + rng.uniform(0, 6, size=4))
        angles.append(np.array([0.3, 1.2, -0.4, 1.0]) + 0.4 * wave)
    directions = [from_angles(a, "directions") for a in angles]
    seconds = [0.034 * (a.shape[0] - 1) for a in angles]
    book = fit_eigen_movements(directions[:-1], angles[:-1], seconds[:-1], (12.0,))
    a, d, s = angles[-1], directions[-1], seconds[-1]
    code, rebuilt, numbers = eigen_describe(book, "eigen", 12.0, s, d, a)
    assert code == "eigen" and numbers == eigen_numbers(12.0, s)
    np.testing.assert_allclose(rebuilt, book.rebuild(d, numbers - 2))
    code, rebuilt, numbers = eigen_describe(book, "eigen/dct", 12.0, s, d, a)
    n = numbers - 3
    eigen_err = bone_rms_deg(book.rebuild(d, n), d)
    dct = dct_rebuild_counts(a, dct_counts(n, 4, book.dct_order[12.0]))
    dct_err = bone_rms_deg(from_angles(dct, "directions"), d)
    err = bone_rms_deg(rebuilt if code == "eigen" else from_angles(rebuilt, "directions"), d)
    assert err == min(eigen_err, dct_err)
    assert code == ("dct" if dct_err < eigen_err else "eigen")


def _bench(other_last: int | None = None):
    data, labels = movements(3, seed=0)
    if other_last is not None:
        data[6:] = movements(3, seed=other_last)[0][6:]  # the held-out group g2 only
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    return make_benchmarks(recs, data)[0][0]


def _held_out_fold(bench):
    """The fold that holds out g2: its eigen-movements and its rows."""
    groups = [str(g) for g in bench.groups]
    train = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g != "g2"])
    test = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g == "g2"])
    prepared: dict = {}
    rows: list = []
    _fold(
        train,
        test,
        "g2",
        SMALL_MODEL,
        ("eigen", "eigen/dct"),
        centres="projection",
        max_stroke=None,
        rows=rows,
        prepared=prepared,
        joint=False,
    )
    return prepared["g2|eigen-movements"], rows


def test_the_held_out_movements_never_enter_the_basis() -> None:
    book, rows = _held_out_fold(_bench())
    book_changed, rows_changed = _held_out_fold(_bench(other_last=7))
    np.testing.assert_array_equal(book.mean, book_changed.mean)
    np.testing.assert_array_equal(book.components, book_changed.components)
    assert book.dct_order == book_changed.dct_order
    # ... while the held-out movements, and so their scores, did change.
    assert [r["bone_deg"] for r in rows] != [r["bone_deg"] for r in rows_changed]
    assert {r["family"] for r in rows} == {"eigen", "eigen/dct"}
    assert all(r["numbers"] <= r["param"] * r["seconds"] + 1e-9 for r in rows)


def test_a_whole_movement_within_a_budget_states_its_description() -> None:
    from visprim.rate.budget import describe_movement

    # Bone directions from angles, so that the DCT alternative has angles to code.
    rng = np.random.default_rng(4)
    u = np.linspace(0.0, 1.0, EIGEN_SAMPLES)[:, None]
    angles = [
        np.array([0.3, 1.2, -0.4, 1.0]) + 0.3 * np.sin(2 * np.pi * rng.uniform(0.3, 1.5) * u + p)
        for p in rng.uniform(0.0, 6.0, size=(31, 4))
    ]
    directions = [from_angles(a, "directions") for a in angles]
    seconds = [0.034 * (EIGEN_SAMPLES - 1)] * len(angles)
    book = fit_eigen_movements(directions[:-1], angles[:-1], seconds[:-1], (12.0,))
    values, d = describe_movement(
        book, directions[-1], angles[-1], seconds[-1], 12.0, code_family="eigen/dct"
    )
    assert d.numbers_per_s <= 12.0 and d.numbers == eigen_numbers(12.0, seconds[-1])
    assert d.m == d.numbers - 3 and d.family in ("eigen", "eigen/dct")
    assert ("eigen-movement" if d.family == "eigen" else "DCT") in d.label
    code, rebuilt, _ = eigen_describe(
        book, "eigen/dct", 12.0, seconds[-1], directions[-1], angles[-1]
    )
    expected = rebuilt if code == "eigen" else from_angles(rebuilt, "directions")
    np.testing.assert_allclose(values, expected)
    assert values.shape == directions[-1].shape
