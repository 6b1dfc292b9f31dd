"""k-means of the PCA projections: one procedure for the in-memory, streaming and Dask fits.

Up to :func:`sample_size` rows (50,000 for up to 2,500 clusters), :func:`visprim.kernels.kmeans`
on every row: ``n_init`` greedy k-means++ seedings, Lloyd's iterations, the lowest inertia
(scikit-learn's ``KMeans`` semantics).

On more rows the seeding runs on a deterministic sample, then Lloyd's iterations on every row:

1. the sample: :func:`sample_rows`, ``sample_size`` rows drawn without replacement by
   ``numpy.random.default_rng(seed)``, in row order;
2. :func:`sample_candidates`: ``n_init`` k-means runs on the sample (run ``r`` seeded with
   ``seed + r``), one candidate centre set each;
3. the candidate with the lowest inertia on every row (the first on ties) starts Lloyd's
   iterations on every row, with :func:`visprim.kernels.kmeans`'s rules (``tol`` scaled by
   the mean column variance of the rows, stop when no label changes, an empty cluster takes
   the row farthest from its centre).

The Dask fit (:mod:`visprim.scale`) runs the same steps with the rows spread over its
workers (the sample gathered, Lloyd's iterations as per-worker sums and counts), so the three
fits give the same clusters up to rounding. The sample is what makes that possible: the local
optima k-means reaches on a large corpus differ in inertia by more than a percent from one
seeding to another, so two fits agree within a fraction of a percent only when they seed
alike, and a k-means++ seeding on every row needs k sequential passes over all of them
(``n_init`` times), which a cluster cannot do cheaply. ``benches/bench_kmeans_sample.py``
compares the inertia and time of the sampled procedure with ten seedings on every row.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from visprim import kernels

__all__ = ["SAMPLE_SIZE", "kmeans_projections", "sample_candidates", "sample_rows", "sample_size"]

#: Rows on which the k-means++ seedings run (at least 20 per cluster, see :func:`sample_size`).
SAMPLE_SIZE = 50_000


def sample_size(k: int) -> int:
    """Rows of the seeding sample for ``k`` clusters: ``max(SAMPLE_SIZE, 20 k)``; fits on
    at most that many rows use every row."""
    return max(SAMPLE_SIZE, 20 * int(k))


def sample_rows(n: int, k: int, seed: int) -> NDArray[np.int64]:
    """Indices (ascending) of the seeding sample among ``n`` rows (all of them when
    ``n <= sample_size(k)``)."""
    m = sample_size(k)
    if n <= m:
        return np.arange(n, dtype=np.int64)
    rng = np.random.default_rng(int(seed))
    return np.sort(rng.choice(n, size=m, replace=False)).astype(np.int64)


def sample_candidates(
    sample: NDArray[np.float64], k: int, *, n_init: int, max_iter: int, tol: float, seed: int
) -> NDArray[np.float64]:
    """``(n_init, k, f)`` centre sets: one k-means run (k-means++ and Lloyd) on the sample per
    candidate, run ``r`` seeded with ``seed + r``."""
    x = np.ascontiguousarray(sample, dtype=np.float64)
    return np.stack(
        [
            kernels.kmeans(x, k, max_iter=max_iter, tol=tol, seed=int(seed) + r).centers
            for r in range(int(n_init))
        ]
    )


def kmeans_projections(
    p: NDArray[np.float64], k: int, *, n_init: int, max_iter: int, tol: float, seed: int
) -> tuple[NDArray[np.float64], NDArray[np.int64], float, int]:
    """k-means of the ``(N, f)`` rows ``p`` (see the module docstring): centres ``(k, f)``,
    labels ``(N,)``, inertia (sum of squared distances, units of ``p`` squared) and the
    Lloyd iterations of the kept run."""
    x = np.ascontiguousarray(p, dtype=np.float64)
    n = x.shape[0]
    if n <= sample_size(k):
        km = kernels.kmeans(x, k, n_init=n_init, max_iter=max_iter, tol=tol, seed=seed)
    else:
        candidates = sample_candidates(
            x[sample_rows(n, k, seed)], k, n_init=n_init, max_iter=max_iter, tol=tol, seed=seed
        )
        scores = [_inertia(x, c) for c in candidates]
        best = candidates[int(np.argmin(scores))]
        km = kernels.kmeans(x, k, max_iter=max_iter, tol=tol, init=best)
    return km.centers, km.labels, float(km.inertia), int(km.n_iter)


def _inertia(x: NDArray[np.float64], centers: NDArray[np.float64]) -> float:
    dist = kernels.kmeans_predict(x, centers)[1]
    return float(np.dot(dist, dist))
