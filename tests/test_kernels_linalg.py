"""Parity, property and error tests of the covariance and eigh kernels (vs numpy)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from visprim import _visprim as V
from visprim import kernels as K


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    """Largest absolute difference relative to the largest magnitude of the reference."""
    scale = max(float(np.abs(b).max()), 1e-300)
    return float(np.abs(a - b).max()) / scale


def numpy_cov(x: np.ndarray) -> np.ndarray:
    return np.atleast_2d(np.cov(x, rowvar=False, bias=True))


# --- covariance ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("n", "d"), [(1, 1), (2, 3), (50, 7), (3000, 40), (20_000, 5), (5000, 260)]
)
def test_covariance_matches_numpy(n: int, d: int) -> None:
    rng = np.random.default_rng(n * 7 + d)
    x = rng.standard_normal((n, d)) @ rng.standard_normal((d, d)) + rng.uniform(-3, 3, d)
    mean, cov = K.covariance(x)
    assert mean.shape == (d,) and cov.shape == (d, d)
    assert rel_err(mean, x.mean(axis=0)) < 1e-12
    assert rel_err(cov, numpy_cov(x)) < 1e-9
    np.testing.assert_array_equal(cov, cov.T)


def test_covariance_keeps_precision_far_from_the_origin() -> None:
    # Positions ~1e6 m with millimetre spread: XᵀX - N·μμᵀ would lose every digit here.
    rng = np.random.default_rng(1)
    base = rng.standard_normal((4000, 3)) * 1e-3
    mean, cov = K.covariance(base + 1.0e6)
    assert rel_err(cov, numpy_cov(base)) < 1e-7
    assert np.allclose(mean, 1.0e6, rtol=0, atol=1e-3)


def test_covariance_non_contiguous_and_threads() -> None:
    rng = np.random.default_rng(2)
    x = rng.standard_normal((9000, 12))
    ref = K.covariance(np.ascontiguousarray(x[:, ::2]))
    for view in (x[:, ::2], np.asfortranarray(x[:, ::2])):
        got = K.covariance(view)
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[1], ref[1])
    one = K.covariance(x, n_threads=1)
    three = K.covariance(x, n_threads=3)
    np.testing.assert_array_equal(one[1], three[1])


def test_covariance_accepts_lists() -> None:
    mean, cov = K.covariance([[0.0, 0.0], [2.0, 4.0]])
    np.testing.assert_array_equal(mean, [1.0, 2.0])
    np.testing.assert_array_equal(cov, [[1.0, 2.0], [2.0, 4.0]])


@settings(max_examples=60, deadline=None)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(1, 40), st.integers(1, 6)),
        elements=st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False),
    )
)
def test_covariance_property(x: np.ndarray) -> None:
    mean, cov = K.covariance(x)
    ref = numpy_cov(x)
    # Spread of the data, floored at the rounding level of its magnitude (numpy's own error).
    scale = max(float(np.abs(x - x.mean(0)).max()), 1e-8 * float(np.abs(x).max()), 1e-150) ** 2
    assert np.abs(cov - ref).max() <= 1e-10 * scale
    assert np.abs(mean - x.mean(0)).max() <= 1e-12 * max(float(np.abs(x).max()), 1.0)
    assert np.all(np.diag(cov) >= 0.0)


# --- accumulator --------------------------------------------------------------------------


def test_accumulator_chunks_and_merges_equal_one_shot() -> None:
    rng = np.random.default_rng(3)
    x = rng.standard_normal((10_001, 9)) * [1, 2, 3, 4, 5, 6, 7, 8, 9] + 100.0
    mean, cov = K.covariance(x)
    seq = K.CovarianceAccumulator()
    for chunk in np.array_split(x, 13):
        seq.update(chunk)
    seq.update(np.empty((0, 9)))
    # A tree of merges in another grouping.
    parts = []
    for chunk in np.array_split(x, 4):
        acc = K.CovarianceAccumulator(9)
        acc.update(chunk)
        parts.append(acc)
    parts[0].merge(parts[1])
    parts[2].merge(parts[3])
    parts[2].merge(parts[0])
    for acc in (seq, parts[2]):
        assert acc.count == 10_001 and acc.dim == 9
        assert rel_err(acc.mean, mean) < 1e-12
        assert rel_err(acc.covariance(), cov) < 1e-9
        assert rel_err(acc.scatter, cov * 10_001) < 1e-9


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(
        np.float64,
        st.tuples(st.integers(2, 30), st.integers(1, 4)),
        elements=st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False),
    ),
    st.data(),
)
def test_accumulator_property(x: np.ndarray, data: st.DataObject) -> None:
    cut = data.draw(st.integers(0, x.shape[0]))
    a, b = K.CovarianceAccumulator(), K.CovarianceAccumulator()
    a.update(x[:cut])
    b.update(x[cut:])
    a.merge(b)
    scale = max(float(np.abs(x - x.mean(0)).max()), 1e-8 * float(np.abs(x).max()), 1e-150) ** 2
    assert np.abs(a.covariance() - numpy_cov(x)).max() <= 1e-9 * scale


def test_accumulator_pickles_and_reprs() -> None:
    acc = K.CovarianceAccumulator()
    assert acc.count == 0 and acc.dim is None
    assert "count=0" in repr(acc)
    assert pickle.loads(pickle.dumps(acc)).dim is None
    acc.update(np.arange(12.0).reshape(4, 3) ** 2)
    back = pickle.loads(pickle.dumps(acc))
    assert back.count == 4 and back.dim == 3
    np.testing.assert_array_equal(back.covariance(), acc.covariance())
    np.testing.assert_array_equal(back.mean, acc.mean)


def test_accumulator_errors() -> None:
    acc = K.CovarianceAccumulator(3)
    with pytest.raises(ValueError, match="no rows yet"):
        acc.covariance()
    with pytest.raises(ValueError, match="no rows yet"):
        _ = acc.mean
    with pytest.raises(ValueError, match="4 columns.*dimension 3"):
        acc.update(np.zeros((2, 4)))
    other = K.CovarianceAccumulator()
    other.update(np.ones((2, 2)))
    with pytest.raises(ValueError, match="dimension 3"):
        acc.merge(other)
    with pytest.raises(ValueError, match="NaN or infinity"):
        acc.update(np.array([[1.0, np.nan, 0.0]]))
    with pytest.raises(TypeError, match="float64"):
        acc.update(np.zeros((2, 3), dtype=np.complex128))
    with pytest.raises(ValueError, match="2-D"):
        acc.update(np.zeros(3))
    with pytest.raises(ValueError, match=r"dim \(the dimension of the rows\) must be"):
        K.CovarianceAccumulator(0)
    with pytest.raises(ValueError, match="at least one column"):
        K.CovarianceAccumulator().update(np.zeros((3, 0)))


def test_covariance_errors() -> None:
    # The compiled function is strict; visprim.kernels converts real dtypes on purpose.
    with pytest.raises(TypeError, match="dtype float64, got float32"):
        V.covariance(np.zeros((3, 2), dtype=np.float32))
    with pytest.raises(TypeError, match="real numbers, got dtype complex128"):
        K.covariance(np.zeros((3, 2), dtype=np.complex128))
    with pytest.raises(ValueError, match="2-D"):
        K.covariance(np.zeros(5))
    with pytest.raises(ValueError, match="empty"):
        K.covariance(np.zeros((0, 3)))
    with pytest.raises(ValueError, match="empty"):
        K.covariance(np.zeros((3, 0)))
    with pytest.raises(ValueError, match=r"NaN or infinity \(row 1, column 0\)"):
        K.covariance(np.array([[0.0, 1.0], [np.inf, 2.0]]))
    with pytest.raises(ValueError, match="n_threads"):
        K.covariance(np.zeros((3, 2)), n_threads=0)


# --- eigh ---------------------------------------------------------------------------------


def random_spd(d: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((3 * d, d))
    return numpy_cov(a @ np.diag(np.linspace(1.0, 4.0, d)))


@pytest.mark.parametrize("d", [1, 2, 5, 40, 200])
def test_eigh_matches_numpy(d: int) -> None:
    a = random_spd(d, d)
    w, v = K.eigh(a)
    w0, v0 = np.linalg.eigh(a)
    w0, v0 = w0[::-1], v0[:, ::-1]
    assert np.all(np.diff(w) <= 0.0)
    assert np.abs(w - w0).max() <= 1e-9 * np.abs(w0).max()
    # Well separated eigenvalues here: each vector equals numpy's up to sign.
    gaps = np.abs(np.diff(w0))
    assert d == 1 or gaps.min() > 1e-6 * w0[0]
    signs = np.sign(np.sum(v * v0, axis=0))
    assert np.abs(v - v0 * signs).max() < 1e-9
    # The documented sign convention.
    pivot = np.argmax(np.abs(v), axis=0)
    assert np.all(v[pivot, np.arange(d)] > 0)
    np.testing.assert_allclose(v.T @ v, np.eye(d), atol=1e-12)


def test_eigh_repeated_eigenvalues_same_subspace() -> None:
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.standard_normal((8, 8)))
    lam = np.array([5.0, 5.0, 5.0, 2.0, 2.0, 1.0, 0.5, 0.0])
    a = (q * lam) @ q.T
    a = (a + a.T) / 2
    w, v = K.eigh(a)
    np.testing.assert_allclose(w, lam, atol=1e-12)
    for block in (slice(0, 3), slice(3, 5), slice(5, 6), slice(6, 7), slice(7, 8)):
        p = v[:, block] @ v[:, block].T
        p0 = q[:, block] @ q[:, block].T
        assert np.abs(p - p0).max() < 1e-9


def test_eigh_leading_k_and_known_answer() -> None:
    a = np.diag([2.0, -1.0, 5.0])
    w, v = K.eigh(a)
    np.testing.assert_array_equal(w, [5.0, 2.0, -1.0])
    np.testing.assert_array_equal(v, [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    b = random_spd(30, 1)
    w_all, v_all = K.eigh(b)
    w3, v3 = K.eigh(b, k=3)
    np.testing.assert_array_equal(w3, w_all[:3])
    np.testing.assert_array_equal(v3, v_all[:, :3])


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 10).flatmap(
        lambda d: hnp.arrays(np.float64, (d, d), elements=st.floats(-100, 100, allow_nan=False))
    )
)
@example(m=np.array([[0.0, 4.0168353e-159, 0.0], [0.0, 0.0, 3.0], [0.0, 0.0, 0.0]]))
def test_eigh_property(m: np.ndarray) -> None:
    a = (m + m.T) / 2
    w, v = K.eigh(a)
    norm = max(float(np.abs(a).max()), 1e-300)
    assert np.all(np.diff(w) <= 0.0)
    # The reference on the matrix eigh solves: entries below sqrt(f64 min) of the largest
    # flushed to zero (documented). LAPACK itself loses accuracy on them: for
    # [[0, 2e-159, 0], [2e-159, 0, 1.5], [0, 1.5, 0]] eigvalsh gives ±1.50000069, not ±1.5.
    flushed = np.where(np.abs(a) < np.sqrt(np.finfo(float).tiny) * norm, 0.0, a)
    assert np.abs(w - np.linalg.eigvalsh(flushed)[::-1]).max() <= 1e-9 * norm * a.shape[0]
    assert np.abs(a @ v - v * w).max() <= 1e-9 * norm * a.shape[0]
    np.testing.assert_allclose(v.T @ v, np.eye(a.shape[0]), atol=1e-10)


def test_eigh_errors() -> None:
    with pytest.raises(ValueError, match="square"):
        K.eigh(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="not symmetric"):
        K.eigh(np.array([[1.0, 2.0], [2.5, 1.0]]))
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.eigh(np.array([[1.0, np.nan], [np.nan, 1.0]]))
    with pytest.raises(ValueError, match="empty"):
        K.eigh(np.zeros((0, 0)))
    with pytest.raises(ValueError, match="2-D"):
        K.eigh(np.ones(4))
    with pytest.raises(TypeError, match="float64"):
        V.eigh(np.eye(3, dtype=np.float32))
    with pytest.raises(
        ValueError, match=r"k \(leading eigenpairs to return\) must be an integer >= 1"
    ):
        K.eigh(np.eye(3), k=0)
    with pytest.raises(ValueError, match="k must be between 1 and"):
        K.eigh(np.eye(3), k=4)
