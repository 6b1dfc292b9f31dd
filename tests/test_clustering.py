"""k-means of the projections (visprim.clustering) and the map / reduce steps of the Dask
Lloyd iterations (visprim.scale), run here in one process: the same clusters as the kernel."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import clustering, kernels
from visprim.scale import _assign_task, _lloyd_task, _lloyd_update, _mean_variance, _stats_task


def blobs(n: int, k: int, f: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    centres = rng.normal(scale=4.0, size=(k, f))
    return centres[rng.integers(0, k, size=n)] + rng.normal(size=(n, f))


def split_lloyd(
    x: np.ndarray, init: np.ndarray, cuts: list[int], max_iter: int, tol: float
) -> tuple[np.ndarray, np.ndarray, float, int]:
    """Lloyd's iterations as the Dask fit runs them, the rows split into parts at ``cuts``
    (each part one worker holding two partitions)."""
    bounds = [0, *cuts, x.shape[0]]
    parts = [x[a:b] for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
    spans = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        mid = (a + b) // 2
        spans.append([(a, mid), (mid, b)])
    stats = [_stats_task(p, init[None]) for p in parts]
    tol_abs = tol * _mean_variance([s[1:] for s in stats])
    centers, n_iter = init.copy(), 0
    for n_iter in range(1, max_iter + 1):  # noqa: B007
        maps = [_lloyd_task(p, centers, sp) for p, sp in zip(parts, spans, strict=True)]
        centers, shift = _lloyd_update(maps, centers)
        if shift <= tol_abs:
            break
    final = [_assign_task(p, centers) for p in parts]
    labels = np.concatenate([lab for lab, _ in final])
    return centers, labels, float(sum(i for _, i in final)), n_iter


@pytest.mark.parametrize("tol", [1e-4, 0.0])
def test_split_lloyd_equals_the_kernel_from_the_same_start(tol):
    x = blobs(3000, 6, 5, seed=0)
    init = x[[0, 1, 2, 3, 4, 5]].copy()
    km = kernels.kmeans(x, 6, init=init, tol=tol)
    centers, labels, inertia, n_iter = split_lloyd(x, init, [700, 1900], 300, tol)
    np.testing.assert_array_equal(labels, km.labels)
    np.testing.assert_allclose(centers, km.centers, rtol=1e-12, atol=1e-12)
    assert inertia == pytest.approx(km.inertia, rel=1e-12)
    assert n_iter == km.n_iter


def test_split_lloyd_reseeds_empty_clusters_as_the_kernel():
    # Two centres far from every row: both are empty after the first assignment and take
    # the farthest rows, which here sit in different parts.
    x = blobs(1200, 4, 3, seed=1)
    x[100] += 40.0
    x[1000] -= 35.0
    init = np.vstack([x[[5, 6]], np.full((2, 3), 500.0)])
    km = kernels.kmeans(x, 4, init=init, tol=1e-4)
    centers, labels, inertia, n_iter = split_lloyd(x, init, [600], 300, 1e-4)
    np.testing.assert_array_equal(labels, km.labels)
    np.testing.assert_allclose(centers, km.centers, rtol=1e-12, atol=1e-12)
    assert inertia == pytest.approx(km.inertia, rel=1e-12)
    assert n_iter == km.n_iter
    # The far rows seeded the empty clusters: each ends as a cluster of its own.
    assert np.sum(labels == labels[100]) == 1 and np.sum(labels == labels[1000]) == 1


def test_mean_variance_of_parts_is_numpys():
    x = blobs(500, 3, 4, seed=2) + 100.0
    parts = [_stats_task(p, np.zeros((1, 1, 4)))[1:] for p in (x[:10], x[10:10], x[10:])]
    assert _mean_variance(parts) == pytest.approx(float(np.mean(x.var(axis=0))), rel=1e-12)


def test_up_to_the_sample_size_kmeans_is_the_kernels(monkeypatch):
    x = blobs(400, 5, 4, seed=3)
    monkeypatch.setattr(clustering, "SAMPLE_SIZE", 400)
    c, lab, inertia, n_iter = clustering.kmeans_projections(
        x, 5, n_init=3, max_iter=300, tol=1e-4, seed=7
    )
    km = kernels.kmeans(x, 5, n_init=3, seed=7)
    np.testing.assert_array_equal(lab, km.labels)
    assert inertia == km.inertia and n_iter == km.n_iter


def test_above_the_sample_size_seeding_runs_on_a_deterministic_sample(monkeypatch):
    x = blobs(2000, 5, 4, seed=4)
    monkeypatch.setattr(clustering, "SAMPLE_SIZE", 300)
    rows = clustering.sample_rows(2000, 5, seed=7)
    assert rows.shape == (300,) and np.all(np.diff(rows) > 0)
    np.testing.assert_array_equal(rows, clustering.sample_rows(2000, 5, seed=7))
    c, lab, inertia, _ = clustering.kmeans_projections(
        x, 5, n_init=3, max_iter=300, tol=1e-4, seed=7
    )
    # The result is Lloyd (the kernel's) from the best of the sample's candidates.
    cands = clustering.sample_candidates(x[rows], 5, n_init=3, max_iter=300, tol=1e-4, seed=7)
    scores = [np.sum(kernels.kmeans_predict(x, cc)[1] ** 2) for cc in cands]
    km = kernels.kmeans(x, 5, init=cands[int(np.argmin(scores))])
    np.testing.assert_array_equal(lab, km.labels)
    assert inertia == km.inertia
    # Labels are the nearest centres; the inertia is their squared distances summed.
    d2 = ((x[:, None, :] - c[None]) ** 2).sum(-1)
    np.testing.assert_array_equal(lab, d2.argmin(1))
    assert inertia == pytest.approx(d2.min(1).sum(), rel=1e-9)
    # Twenty rows a cluster at least.
    assert clustering.sample_size(10_000) == 200_000
