"""Principal component analysis of segment vectors (paper §4: the eigenvectors of K).

``K = (1/N) Σ (s − s̄)(s − s̄)ᵀ`` is computed by the Rust kernel
:func:`visprim.kernels.covariance` (divisor N, as the paper) and decomposed by
:func:`visprim.kernels.eigh` (eigenvalues in descending order, eigenvectors as columns with
the kernel's fixed sign convention). Keeping the first ``f`` eigenvectors ``E_f`` gives the
projections ``p = E_fᵀ (s − s̄)`` and the reconstructions ``s ≈ E_f p + s̄``.

With divisor N, the mean squared reconstruction error over the training vectors equals the
sum of the dropped eigenvalues ``Σ_{i > f} λ_i`` exactly (the projection error of Table 1).

Fewer vectors than dimensions (N ≤ d, common with two-arm 1200-D vectors of a few hundred
segments): K has rank r < N and a null space of dimension d − r, a huge repeated eigenvalue
0 that a d × d eigensolver handles slowly and whose eigenvectors the data do not determine.
:func:`fit_pca` then decomposes the N × N Gram matrix ``G = (1/N) X̃ X̃ᵀ`` instead (same
non-zero eigenvalues; eigenvectors ``X̃ᵀ u / √(N λ)``) and keeps the r eigenvectors of the
non-zero eigenvalues; the eigenvalues are still all d (zeros after r). Where more
eigenvectors are asked for (:meth:`PCABasis.components`), the null space is spanned by the
coordinate axes farthest from the kept eigenvectors, orthonormalised (deterministic).
"""

from __future__ import annotations

import functools
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_triangular

from visprim import kernels


@dataclass(frozen=True)
class PCABasis:
    """Mean and eigen-decomposition of the covariance of a set of vectors.

    Attributes
    ----------
    mean : (d,) array
        ``s̄`` (units of the vectors: radians for segment vectors).
    eigenvalues : (d,) array, descending
        Eigenvalues of K (squared units).
    eigenvectors : (d, m) array
        Unit eigenvectors as columns, in the order of ``eigenvalues``: all d, or (fitted
        from N ≤ d vectors) at least those of the non-zero eigenvalues (module docstring).
    n_vectors : int
        Number of vectors N the basis was computed from.
    """

    mean: NDArray[np.float64]
    eigenvalues: NDArray[np.float64]
    eigenvectors: NDArray[np.float64]
    n_vectors: int

    @property
    def dim(self) -> int:
        """Dimension d of the vectors."""
        return int(self.mean.shape[0])

    def _check_f(self, f: int) -> int:
        f = int(f)
        if not 1 <= f <= self.dim:
            raise ValueError(f"number of eigenvectors f must be in [1, {self.dim}], got {f}")
        return f

    def components(self, f: int) -> NDArray[np.float64]:
        """``E_f``: the first ``f`` eigenvectors, shape (d, f) (beyond the stored ones, an
        orthonormal basis of the null space: see the module docstring)."""
        f = self._check_f(f)
        return _with_null_space(self.eigenvectors, f)

    def project(self, vectors: ArrayLike, f: int) -> NDArray[np.float64]:
        """``p = E_fᵀ (s − s̄)`` for each row of ``vectors`` (N, d) → (N, f)."""
        x = _as_rows(vectors, self.dim, "vectors")
        e = np.ascontiguousarray(self.components(f))
        # X E - s̄ E: no centred copy of X (same result to rounding, ~1e-14 rad).
        return one_thread_product(x, e) - self.mean @ e

    def reconstruct(self, projections: ArrayLike) -> NDArray[np.float64]:
        """``s = E_f p + s̄`` for each row of ``projections`` (N, f) → (N, d)."""
        p = np.asarray(projections, dtype=np.float64)
        single = p.ndim == 1
        p = np.atleast_2d(p)
        out = one_thread_product(p, self.components(p.shape[1]).T) + self.mean
        return out[0] if single else out

    def dropped_variance(self, f: int) -> float:
        """Sum of the eigenvalues beyond the first ``f`` (the projection error, Table 1)."""
        if not 0 <= int(f) <= self.eigenvalues.shape[0]:
            raise ValueError(f"f must be in [0, {self.eigenvalues.shape[0]}], got {f}")
        return float(np.sum(self.eigenvalues[int(f) :]))

    def explained_fraction(self, f: int) -> float:
        """Fraction of the total variance kept by the first ``f`` eigenvectors."""
        total = float(np.sum(self.eigenvalues))
        if total <= 0:
            return 1.0
        return 1.0 - self.dropped_variance(f) / total


@functools.cache
def _blas_controller() -> Any:
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def one_thread_product(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a @ b`` on one BLAS thread. OpenBLAS's matrix product changes its summation order
    with its thread count (results one ulp apart between ``OPENBLAS_NUM_THREADS=1`` and
    ``2``), which would make a model's bits depend on the machine; the products here are
    thin (f ≤ a few dozen columns), so one thread costs little."""
    with _blas_controller().limit(limits=1, user_api="blas"):
        return np.asarray(a @ b)


def _as_rows(x: ArrayLike, d: int, name: str) -> NDArray[np.float64]:
    a = np.asarray(x, dtype=np.float64)
    a = np.atleast_2d(a)
    if a.ndim != 2 or a.shape[1] != d:
        raise ValueError(f"{name} must have shape (N, {d}), got {np.asarray(x).shape}")
    return a


def fit_pca(vectors: ArrayLike, n_keep: int = 0) -> PCABasis:
    """Mean, covariance (divisor N) and its eigen-decomposition, all in the Rust kernels.

    Parameters
    ----------
    vectors : (N, d) array
        One vector per row (N ≥ 2).
    n_keep : int
        Eigenvectors to keep at least when N ≤ d (module docstring); all d otherwise.
    """
    x = np.ascontiguousarray(vectors, dtype=np.float64)
    if x.ndim != 2:
        raise ValueError(f"vectors must be a 2-D array (N, d), got shape {x.shape}")
    if x.shape[0] < 2:
        raise ValueError(f"PCA needs at least 2 vectors, got {x.shape[0]}")
    if x.shape[0] <= x.shape[1]:
        return _fit_pca_gram(x, int(n_keep))
    mean, cov = kernels.covariance(x)
    values, vecs = kernels.eigh(cov)
    return PCABasis(
        mean=np.asarray(mean),
        eigenvalues=np.asarray(values),
        eigenvectors=np.asarray(vecs),
        n_vectors=int(x.shape[0]),
    )


def _fit_pca_gram(x: NDArray[np.float64], n_keep: int) -> PCABasis:
    """:func:`fit_pca` through the N × N Gram matrix, for N ≤ d (see the module docstring).

    Its products and factorisations are small (N ≤ d, a few hundred to a few thousand) and
    follow Rust kernels that use every core: they run on one BLAS thread, since waking
    OpenBLAS's threads on cores that are busy costs more than the work itself.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return _gram_basis(x, n_keep)


def _gram_basis(x: NDArray[np.float64], n_keep: int) -> PCABasis:
    n, d = x.shape
    mean = x.mean(axis=0)
    xc = x - mean
    gram = (xc @ xc.T) / n
    gram = 0.5 * (gram + gram.T)  # exactly symmetric for the kernel's check
    g_values, u = kernels.eigh(gram)
    g_values = np.asarray(g_values)
    # Eigenvalues at rounding level of the largest are the null space (the centred rows
    # sum to zero, so r ≤ N − 1).
    tol = max(n, d) * np.finfo(np.float64).eps * max(float(g_values[0]), 0.0)
    r = int(np.count_nonzero(g_values > tol))
    vecs = xc.T @ np.asarray(u)[:, :r]
    vecs /= np.linalg.norm(vecs, axis=0)  # = / √(N λ) up to rounding
    # Orthonormal up to rounding that grows as λ shrinks: two Cholesky-QR passes restore
    # it to machine precision (cheaper than Householder QR for d ≫ r). When the smallest
    # kept eigenvalues sit just above rounding level (repeated rows: a recording looped
    # back and forth), their vectors are nearly dependent and Cholesky fails: Householder
    # QR then orthonormalises them and drops the directions that are only rounding.
    for _ in range(2):
        try:
            chol = np.linalg.cholesky(vecs.T @ vecs)
        except np.linalg.LinAlgError:
            vecs = _householder_basis(vecs)
            r = vecs.shape[1]
            break
        vecs = solve_triangular(chol, vecs.T, lower=True).T
    # The kernel's sign convention: each column's component of largest |value| positive.
    top = vecs[np.argmax(np.abs(vecs), axis=0), np.arange(r)]
    vecs *= np.where(top < 0, -1.0, 1.0)
    values = np.zeros(d)
    values[:r] = g_values[:r]
    vecs = _with_null_space(vecs, min(d, max(r, n_keep)))
    return PCABasis(mean=mean, eigenvalues=values, eigenvectors=vecs, n_vectors=int(n))


def _householder_basis(vecs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Orthonormal columns spanning the leading columns of ``vecs`` (d, r; unit columns,
    in decreasing eigenvalue order) by Householder QR, cut before the first column whose
    new direction is below √ε of its length (a direction made of rounding only)."""
    q, rr = np.linalg.qr(vecs)
    small = np.abs(np.diag(rr)) < np.sqrt(np.finfo(np.float64).eps)
    keep = int(np.argmax(small)) if small.any() else vecs.shape[1]
    q = q[:, :keep]
    # Householder's signs are arbitrary: keep each column's direction that of ``vecs``.
    q *= np.where(np.sum(q * vecs[:, :keep], axis=0) < 0, -1.0, 1.0)
    return np.ascontiguousarray(q)


def _with_null_space(vecs: NDArray[np.float64], m: int) -> NDArray[np.float64]:
    """The first ``m`` columns of the orthonormal ``vecs`` (d, r), completed when ``m > r``
    by the coordinate axes farthest from their span, one at a time, orthonormalised."""
    d, r = vecs.shape
    if m <= r:
        return vecs[:, :m]
    out = np.zeros((d, m))
    out[:, :r] = vecs
    residual = 1.0 - np.sum(vecs**2, axis=1)  # squared distance of each axis to the span
    for j in range(r, m):
        axis = int(np.argmax(residual))
        w = -out[axis, :j].copy()  # e_axis − Q Qᵀ e_axis, twice for rounding
        w = out[:, :j] @ w
        w[axis] += 1.0
        w -= out[:, :j] @ (out[:, :j].T @ w)
        out[:, j] = w / np.linalg.norm(w)
        residual -= out[:, j] ** 2
        residual[axis] = -1.0
    return out


def fit_pca_chunks(chunks: Iterable[ArrayLike]) -> PCABasis:
    """:func:`fit_pca` over a corpus given in chunks of rows (mergeable accumulator)."""
    acc = kernels.CovarianceAccumulator()
    n = 0
    for chunk in chunks:
        c = np.ascontiguousarray(chunk, dtype=np.float64)
        if c.shape[0] == 0:
            continue
        acc.update(c)
        n += int(c.shape[0])
    if n < 2:
        raise ValueError(f"PCA needs at least 2 vectors, got {n}")
    values, vecs = kernels.eigh(np.asarray(acc.covariance()))
    return PCABasis(
        mean=np.asarray(acc.mean),
        eigenvalues=np.asarray(values),
        eigenvectors=np.asarray(vecs),
        n_vectors=n,
    )
