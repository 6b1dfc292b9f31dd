"""Parity, quality, property, determinism and error tests of the k-means kernels (vs
scikit-learn)."""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.cluster import KMeans
from sklearn.datasets import make_blobs
from visprim import _visprim as V
from visprim import kernels as K


def sklearn_lloyd(x: np.ndarray, init: np.ndarray, **kw: float) -> KMeans:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ConvergenceWarning when max_iter is tiny
        return KMeans(n_clusters=init.shape[0], init=init, n_init=1, algorithm="lloyd", **kw).fit(x)


def segment_projections(n_segments: int, seed: int) -> np.ndarray:
    """PCA projections (10 components) of resampled segments of smooth random 4-channel
    signals: the shape of data the pipeline clusters."""
    rng = np.random.default_rng(seed)
    frames = 40 * n_segments
    t = np.arange(frames)
    # Smooth signals: sums of random low-frequency sines, like joint angles in radians.
    signal = np.zeros((frames, 4))
    for c in range(4):
        for _ in range(6):
            f = rng.uniform(0.002, 0.05)
            signal[:, c] += rng.uniform(0.1, 0.5) * np.sin(2 * np.pi * f * t + rng.uniform(0, 6))
    cuts = np.sort(rng.choice(np.arange(10, frames - 10), n_segments - 1, replace=False))
    bounds = np.concatenate([[0], cuts, [frames - 1]])
    grid = np.linspace(0.0, 1.0, 50)
    rows = []
    for s, e in zip(bounds[:-1], bounds[1:], strict=True):
        ts = s + grid * (e - s)
        rows.append(np.concatenate([np.interp(ts, t, signal[:, c]) for c in range(4)]))
    seg = np.array(rows)
    mean, cov = K.covariance(seg)
    _, vecs = K.eigh(cov, k=10)
    return (seg - mean) @ vecs


@pytest.mark.parametrize(
    ("n", "d", "k", "kw"),
    [
        (2000, 2, 5, {}),
        (3000, 8, 20, {}),
        (3000, 8, 20, {"tol": 0.0}),
        (2500, 30, 60, {}),
        (2000, 5, 12, {"max_iter": 3}),
        (1500, 3, 1, {}),
    ],
)
def test_same_init_matches_sklearn_lloyd(n: int, d: int, k: int, kw: dict) -> None:
    x, _ = make_blobs(n_samples=n, n_features=d, centers=max(k // 2, 1), random_state=n + k)
    rng = np.random.default_rng(k)
    init = x[rng.choice(n, k, replace=False)]
    ref = sklearn_lloyd(x, init, **kw)
    ours = K.kmeans(x, k, init=init, **kw)
    np.testing.assert_array_equal(ours.labels, ref.labels_)
    scale = np.abs(x).max()
    assert np.abs(ours.centers - ref.cluster_centers_).max() <= 1e-9 * scale
    assert ours.n_iter == ref.n_iter_
    assert ours.inertia == pytest.approx(ref.inertia_, rel=1e-9)
    assert ours.labels.dtype == np.int64 and ours.centers.shape == (k, d)


def test_same_init_matches_sklearn_on_segment_projections() -> None:
    x = segment_projections(1500, seed=4)
    init = x[:25].copy()
    ref = sklearn_lloyd(x, init)
    ours = K.kmeans(x, 25, init=init)
    np.testing.assert_array_equal(ours.labels, ref.labels_)
    assert np.abs(ours.centers - ref.cluster_centers_).max() <= 1e-9 * np.abs(x).max()


def test_empty_cluster_reseeded_like_sklearn() -> None:
    # The third initial centre is far from every row: it gets no row in the first E-step and
    # both implementations move it to the row farthest from its centre.
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(0, 1, (100, 2)), rng.normal(8, 1, (100, 2))])
    init = np.array([[0.0, 0.0], [8.0, 8.0], [100.0, 100.0]])
    ref = sklearn_lloyd(x, init)
    ours = K.kmeans(x, 3, init=init)
    np.testing.assert_array_equal(ours.labels, ref.labels_)
    np.testing.assert_allclose(ours.centers, ref.cluster_centers_, rtol=0, atol=1e-9 * 100)
    assert np.bincount(ours.labels, minlength=3).min() > 0


@pytest.mark.parametrize("data", ["blobs", "segments"])
def test_own_seeding_within_one_percent_of_sklearn_best_of_10(data: str) -> None:
    if data == "blobs":
        x, _ = make_blobs(n_samples=4000, n_features=6, centers=15, random_state=1)
        k = 15
    else:
        x, k = segment_projections(2000, seed=2), 20
    ref = KMeans(k, n_init=10, algorithm="lloyd", random_state=0).fit(x)
    ours = K.kmeans(x, k, n_init=10, seed=0)
    assert ours.inertia <= 1.01 * ref.inertia_
    # And a single run stays reasonable too.
    assert K.kmeans(x, k, seed=1).inertia <= 1.05 * ref.inertia_


def test_best_of_n_init_never_worse_than_first_run() -> None:
    x = segment_projections(1200, seed=7)
    single = K.kmeans(x, 30, seed=5)
    multi = K.kmeans(x, 30, seed=5, n_init=4)
    assert multi.inertia <= single.inertia


def test_result_is_consistent() -> None:
    x, _ = make_blobs(n_samples=3000, n_features=4, centers=6, random_state=3)
    r = K.kmeans(x, 8, seed=2, tol=0.0)
    d2 = ((x[:, None, :] - r.centers[None, :, :]) ** 2).sum(-1)
    np.testing.assert_array_equal(r.labels, d2.argmin(1))
    assert r.inertia == pytest.approx(d2.min(1).sum(), rel=1e-12)
    # Converged (tol=0: until no label changes): every centre is the mean of its rows.
    for j in range(8):
        np.testing.assert_allclose(r.centers[j], x[r.labels == j].mean(0), atol=1e-12)
    assert 1 <= r.n_iter <= 300
    assert "KMeansResult(k=8, d=4" in repr(r)


def test_same_seed_same_result_and_seeds_differ() -> None:
    x = segment_projections(800, seed=1)
    a, b = K.kmeans(x, 10, seed=9), K.kmeans(x, 10, seed=9)
    np.testing.assert_array_equal(a.labels, b.labels)
    np.testing.assert_array_equal(a.centers, b.centers)
    c, ic = K.kmeans_plusplus(x, 10, seed=9)
    c2, ic2 = K.kmeans_plusplus(x, 10, seed=10)
    assert not np.array_equal(ic, ic2)
    np.testing.assert_array_equal(c, x[ic])
    assert len(set(ic.tolist())) == 10
    # kmeans(n_init=1) starts from kmeans_plusplus with the same seed.
    np.testing.assert_array_equal(K.kmeans(x, 10, init=c).labels, a.labels)


_THREAD_SCRIPT = """
import hashlib, numpy as np
from sklearn.datasets import make_blobs
from visprim import _visprim as V
from visprim import kernels as K
x, _ = make_blobs(n_samples=30000, n_features=12, centers=40, random_state=5)
r = K.kmeans(x, 50, seed=3, n_init=2)
m, c = K.covariance(x)
w = np.random.default_rng(1).standard_normal((6000, 300))  # wide rows: parallel product
mw, cw = K.covariance(w)
h = hashlib.sha256()
for a in (r.centers, r.labels, np.array([r.inertia, r.n_iter]), m, c, mw, cw):
    h.update(np.ascontiguousarray(a).tobytes())
print(h.hexdigest())
"""


def test_identical_for_any_thread_count() -> None:
    digests = set()
    for threads in ("1", "2", "3"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        out = subprocess.run(
            [sys.executable, "-c", _THREAD_SCRIPT], env=env, capture_output=True, text=True
        )
        assert out.returncode == 0, out.stderr
        digests.add(out.stdout.strip())
    assert len(digests) == 1


def test_n_threads_option_gives_identical_results() -> None:
    x, _ = make_blobs(n_samples=20000, n_features=8, centers=30, random_state=6)
    runs = [K.kmeans(x, 40, seed=1, n_threads=t) for t in (1, 2, 4)]
    for r in runs[1:]:
        np.testing.assert_array_equal(r.labels, runs[0].labels)
        np.testing.assert_array_equal(r.centers, runs[0].centers)
        assert r.inertia == runs[0].inertia


def test_predict_matches_brute_force() -> None:
    rng = np.random.default_rng(8)
    x = rng.standard_normal((5000, 7))
    centers = rng.standard_normal((23, 7))
    labels, dist = K.kmeans_predict(x, centers)
    d2 = ((x[:, None, :] - centers[None, :, :]) ** 2).sum(-1)
    np.testing.assert_array_equal(labels, d2.argmin(1))
    np.testing.assert_allclose(dist, np.sqrt(d2.min(1)), rtol=1e-12)
    assert labels.dtype == np.int64
    # Ties go to the lowest index.
    lab, dd = K.kmeans_predict(np.array([[1.0, 0.0]]), np.array([[0.0, 0.0], [2.0, 0.0]]))
    assert lab[0] == 0 and dd[0] == 1.0


@settings(max_examples=50, deadline=None)
@given(st.integers(1, 60), st.integers(1, 4), st.data())
def test_kmeans_property(n: int, d: int, data: st.DataObject) -> None:
    seed = data.draw(st.integers(0, 2**64 - 1))
    k = data.draw(st.integers(1, n))
    x = np.random.default_rng(seed % 1000).uniform(-5, 5, (n, d))
    r = K.kmeans(x, k, seed=seed, max_iter=data.draw(st.integers(1, 50)))
    assert r.labels.shape == (n,) and r.centers.shape == (k, d)
    assert r.labels.min() >= 0 and r.labels.max() < k
    d2 = ((x[:, None, :] - r.centers[None, :, :]) ** 2).sum(-1)
    # Every row is labelled with (one of) its nearest centres, and the inertia adds up.
    chosen = d2[np.arange(n), r.labels]
    assert np.all(chosen <= d2.min(1) * (1 + 1e-12) + 1e-12)
    assert r.inertia == pytest.approx(chosen.sum(), rel=1e-9, abs=1e-12)
    if k == n:
        assert r.inertia == pytest.approx(0.0, abs=1e-20)


def test_kmeans_errors() -> None:
    x = np.random.default_rng(0).standard_normal((10, 2))
    with pytest.raises(TypeError, match="float64, got float32"):
        V.kmeans(x.astype(np.float32), 2)
    with pytest.raises(TypeError, match="numpy.ndarray"):
        K.kmeans_predict(x, "centres")
    with pytest.raises(ValueError, match="2-D"):
        K.kmeans(x[:, 0], 2)
    with pytest.raises(ValueError, match="empty"):
        K.kmeans(np.zeros((0, 2)), 1)
    with pytest.raises(ValueError, match=r"k must be between 1 and the number of rows of X \(10\)"):
        K.kmeans(x, 11)
    with pytest.raises(ValueError, match=r"k \(the number of clusters\) must be an integer >= 1"):
        K.kmeans(x, 0)
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.kmeans(np.where(np.arange(20).reshape(10, 2) == 7, np.nan, x), 2)
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.kmeans(x, 2, init=np.array([[0.0, 0.0], [np.inf, 0.0]]))
    with pytest.raises(ValueError, match=r"init must have shape \(k, d\) = \(2, 2\)"):
        K.kmeans(x, 2, init=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="n_init must be 1 when initial centres are given"):
        K.kmeans(x, 2, init=x[:2], n_init=3)
    with pytest.raises(ValueError, match="n_init"):
        K.kmeans(x, 2, n_init=0)
    with pytest.raises(ValueError, match="max_iter"):
        K.kmeans(x, 2, max_iter=0)
    with pytest.raises(ValueError, match="tol"):
        K.kmeans(x, 2, tol=-1.0)
    with pytest.raises(ValueError, match="n_local_trials"):
        K.kmeans(x, 2, n_local_trials=0)
    with pytest.raises(ValueError, match="n_local_trials"):
        K.kmeans_plusplus(x, 2, n_local_trials=65)
    with pytest.raises(ValueError, match="n_threads"):
        K.kmeans(x, 2, n_threads=0)
    with pytest.raises(ValueError, match="seed"):
        K.kmeans(x, 2, seed=-1)
    with pytest.raises(ValueError, match="X has 2 columns but centers has 3"):
        K.kmeans_predict(x, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="empty"):
        K.kmeans_predict(x, np.zeros((0, 2)))
    with pytest.raises(ValueError, match="k must be between 1"):
        K.kmeans_plusplus(x, 11)
