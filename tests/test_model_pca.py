"""PCA of segment vectors (visprim.pca) against numpy."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.pca import fit_pca, fit_pca_chunks


def _data(n=300, d=40, seed=0):
    rng = np.random.default_rng(seed)
    # Correlated data with a decaying spectrum.
    basis = np.linalg.qr(rng.normal(size=(d, d)))[0]
    scales = np.exp(-np.arange(d) / 5.0)
    return rng.normal(size=(n, d)) * scales @ basis.T + rng.normal(size=d)


def test_mean_eigenvalues_and_subspaces_match_numpy():
    x = _data()
    b = fit_pca(x)
    ref_cov = np.cov(x, rowvar=False, bias=True)
    ref_w, ref_v = np.linalg.eigh(ref_cov)
    ref_w, ref_v = ref_w[::-1], ref_v[:, ::-1]
    np.testing.assert_allclose(b.mean, x.mean(axis=0), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(b.eigenvalues, ref_w, rtol=1e-9, atol=1e-12)
    assert np.all(np.diff(b.eigenvalues) <= 1e-12)
    for f in (1, 5, 20):
        p_ours = b.components(f) @ b.components(f).T
        p_ref = ref_v[:, :f] @ ref_v[:, :f].T
        np.testing.assert_allclose(p_ours, p_ref, atol=1e-8)
    np.testing.assert_allclose(b.eigenvectors.T @ b.eigenvectors, np.eye(40), atol=1e-10)


def test_projection_round_trip_and_dropped_variance():
    x = _data()
    b = fit_pca(x)
    full = b.reconstruct(b.project(x, b.dim))
    np.testing.assert_allclose(full, x, atol=1e-10)
    for f in (3, 10):
        resid = x - b.reconstruct(b.project(x, f))
        mse = np.mean(np.sum(resid**2, axis=1))
        np.testing.assert_allclose(b.dropped_variance(f), mse, rtol=1e-9)
    assert b.explained_fraction(b.dim) == pytest.approx(1.0)
    # One vector in, one vector out.
    assert b.reconstruct(b.project(x[0], 5)[0]).shape == (40,)


def test_chunked_equals_one_shot():
    x = _data(n=257)
    one = fit_pca(x)
    chunked = fit_pca_chunks([x[:100], x[100:101], x[101:]])
    np.testing.assert_allclose(chunked.mean, one.mean, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(chunked.eigenvalues, one.eigenvalues, rtol=1e-9, atol=1e-12)
    assert chunked.n_vectors == 257


def test_errors():
    with pytest.raises(ValueError, match="at least 2"):
        fit_pca(np.zeros((1, 4)))
    with pytest.raises(ValueError, match="2-D"):
        fit_pca(np.zeros(4))
    b = fit_pca(_data(n=50, d=6))
    with pytest.raises(ValueError, match=r"f must be in \[1, 6\]"):
        b.components(7)
    with pytest.raises(ValueError, match=r"shape \(N, 6\)"):
        b.project(np.zeros((2, 5)), 2)


@pytest.mark.parametrize(("n", "d", "keep"), [(40, 300, 10), (40, 300, 60), (12, 12, 0)])
def test_fewer_vectors_than_dimensions_match_the_covariance(n, d, keep):
    """N ≤ d goes through the Gram matrix: the same eigenvalues and leading eigenvectors as
    numpy's eigh of the covariance, at least ``keep`` orthonormal eigenvectors, and a
    null space completed on demand, orthogonal to the data's span."""
    rng = np.random.default_rng(n + d + keep)
    x = rng.standard_normal((n, d)) * np.linspace(3.0, 0.1, d) + 2.0
    basis = fit_pca(x, n_keep=keep)
    cov = np.cov(x.T, bias=True)
    w, v = np.linalg.eigh(cov)
    w, v = w[::-1], v[:, ::-1]
    np.testing.assert_allclose(basis.eigenvalues, np.clip(w, 0.0, None), atol=1e-10)
    m = basis.eigenvectors.shape[1]
    assert min(d, max(n - 1, keep)) <= m <= d
    top = basis.eigenvectors[:, :5]
    np.testing.assert_allclose(np.abs(top.T @ v[:, :5]), np.eye(5), atol=1e-8)
    e = basis.components(d)
    np.testing.assert_allclose(e.T @ e, np.eye(d), atol=1e-10)
    centred = x - x.mean(axis=0)
    np.testing.assert_allclose(centred @ e[:, n - 1 :], 0.0, atol=1e-9)


@pytest.mark.parametrize("seed", range(8))
def test_pca_of_repeated_rows_with_a_decaying_spectrum(seed):
    """Rows repeated forward and back (a recording looped to and fro) whose singular values
    decay through rounding level: Cholesky-QR of the Gram vectors fails on such data."""
    rng = np.random.default_rng(seed)
    m, d = 60, 400
    u = np.linalg.qr(rng.normal(size=(m, m)))[0]
    v = np.linalg.qr(rng.normal(size=(d, m)))[0]
    base = (u * 10.0 ** (-np.arange(m) / 3.0)) @ v.T
    x = np.concatenate([base, base[::-1]] * 3)
    basis = fit_pca(x, 10)
    w = basis.eigenvectors
    assert w.shape[0] == d and w.shape[1] >= 10
    np.testing.assert_allclose(w.T @ w, np.eye(w.shape[1]), atol=1e-12)
    xc = x - basis.mean
    np.testing.assert_allclose(xc @ w @ w.T, xc, atol=1e-6)  # the span, to rounding level
    values = basis.eigenvalues
    assert np.all(np.diff(values) <= 1e-18) and values[-1] >= 0.0
    expected = np.linalg.svd(xc, compute_uv=False) ** 2 / x.shape[0]
    np.testing.assert_allclose(values[:10], expected[:10], rtol=1e-9)
