"""Benchmark section: covariance + eigh and k-means, visprim against numpy / scikit-learn.

Workloads: a ``100,000 x 400`` covariance + eigendecomposition (references:
``numpy.cov`` + ``numpy.linalg.eigh``, and scikit-learn ``PCA(svd_solver="covariance_eigh")``
which does the same work), and k-means on ``100,000 x 30`` float64 rows for k in
{10, 30, 100, 170} (reference: scikit-learn ``KMeans(algorithm="lloyd")`` with the same
``n_init=1`` / ``max_iter=300`` / ``tol=1e-4``; both timings include the k-means++ seeding).
Each k-means run uses the next seed, and the mean inertia over 16 seeds (the timed runs and a
few more) is printed for both, so that speed is compared at equal clustering quality.

The covariance's rate is printed beside the rate of a square ``numpy`` matrix product (OpenBLAS
DGEMM, every core) measured in the same run: the practical peak of the machine's floating-point
units, against which a kernel's efficiency is read (it doubles with AVX-512).

Run through ``benches/compare.py`` (``make bench``); ``--quick`` shrinks every workload.
"""

from __future__ import annotations

import itertools
import statistics
from collections.abc import Callable
from typing import Any

import numpy as np
from _harness import Table, median_time
from visprim import kernels as K

KS = (10, 30, 100, 170)
#: Seeds over which the mean inertias are compared (the timed runs plus untimed ones): the
#: inertia of one k-means++ run varies by about a percent from seed to seed.
QUALITY_SEEDS = 16


def _kmeans_data(n: int, d: int) -> np.ndarray:
    """Gaussian blobs (50 centres, unit box ±10, std 2) in d dimensions, float64."""
    from sklearn.datasets import make_blobs

    x, _ = make_blobs(n_samples=n, n_features=d, centers=50, cluster_std=2.0, random_state=0)
    return np.ascontiguousarray(x, dtype=np.float64)


def _seeded(fit: Callable[[int], float]) -> tuple[Callable[[], None], list[float]]:
    """A no-argument callable running ``fit(seed)`` with seeds 0, 1, 2, ... and the list
    collecting the inertias it returns."""
    seeds = itertools.count()
    inertias: list[float] = []

    def run() -> None:
        inertias.append(fit(next(seeds)))

    return run, inertias


def dgemm_rate(quick: bool) -> float:
    """GFLOP/s of a square float64 ``numpy`` matrix product (median of 3 runs)."""
    m = 500 if quick else 3000
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal((m, m)), rng.standard_normal((m, m))
    return 2 * m**3 / median_time(lambda: a @ b, repeat=3) / 1e9


def bench_covariance_eigh(table: Table, quick: bool) -> None:
    n, d = (10_000, 100) if quick else (100_000, 400)
    peak = dgemm_rate(quick)
    rng = np.random.default_rng(0)
    x = rng.standard_normal((n, d)) + rng.uniform(-1, 1, d)
    workload = f"covariance+eigh {n}x{d}"
    repeat = 3 if quick else 7

    def ours() -> Any:
        _, c = K.covariance(x)
        return K.eigh(c)

    def numpy_ref() -> Any:
        c = np.cov(x, rowvar=False, bias=True)
        return np.linalg.eigh(c)

    from sklearn.decomposition import PCA

    def sklearn_ref() -> Any:
        return PCA(svd_solver="covariance_eigh").fit(x)

    # Same numbers first (whichever tile this CPU runs): covariance and eigenvalues.
    _, c_ours = K.covariance(x)
    c_ref = np.cov(x, rowvar=False, bias=True)
    err = float(np.abs(c_ours - c_ref).max() / np.abs(c_ref).max())
    assert err < 1e-12, f"covariance differs from numpy by {err:.1e} (relative)"
    w_ours, w_ref = K.eigh(c_ours)[0], np.linalg.eigvalsh(c_ref)[::-1]
    assert np.allclose(w_ours, w_ref, rtol=0, atol=1e-12 * w_ref[0]), "eigenvalues differ"
    t_ours = median_time(ours, repeat=repeat)
    t_np = median_time(numpy_ref, repeat=repeat)
    t_sk = median_time(sklearn_ref, repeat=repeat)
    flops = n * d * d  # nominal: the lower half of XᵀX is n·d²/2 multiply-adds
    rate = flops / t_ours / 1e9
    table.add(
        workload,
        "visprim covariance + eigh",
        t_ours,
        f"{rate:.1f} GFLOP/s",
        f"{rate / peak:.0%} of numpy DGEMM's {peak:.0f} GFLOP/s ({K.instruction_set()})",
    )
    table.add(workload, "numpy cov + eigh", t_np, f"{flops / t_np / 1e9:.1f} GFLOP/s")
    table.add(workload, "sklearn PCA covariance_eigh", t_sk, f"{flops / t_sk / 1e9:.1f} GFLOP/s")
    table.ratio(workload, "numpy cov + eigh", t_np, t_ours)
    table.ratio(workload, "sklearn PCA covariance_eigh", t_sk, t_ours)


def bench_kmeans(table: Table, quick: bool) -> None:
    from sklearn.cluster import KMeans

    n, d = (10_000, 30) if quick else (100_000, 30)
    x = _kmeans_data(n, d)
    repeat = 2 if quick else 5
    for k in KS:
        workload = f"kmeans {n}x{d} k={k}"

        def ours_fit(seed: int, k: int = k) -> float:
            return K.kmeans(x, k, n_init=1, max_iter=300, tol=1e-4, seed=seed).inertia

        def sk_fit(seed: int, k: int = k) -> float:
            km = KMeans(k, n_init=1, max_iter=300, tol=1e-4, algorithm="lloyd", random_state=seed)
            return float(km.fit(x).inertia_)

        ours, ours_inertia = _seeded(ours_fit)
        ref, ref_inertia = _seeded(sk_fit)
        t_ours = median_time(ours, repeat=repeat)
        t_ref = median_time(ref, repeat=repeat)
        while len(ours_inertia) < (4 if quick else QUALITY_SEEDS):
            ours()
            ref()
        mi_ours = statistics.fmean(ours_inertia)
        mi_ref = statistics.fmean(ref_inertia)
        runs = len(ours_inertia)
        # Standard error of the ratio of the two means (seed-to-seed spread of one run).
        se = (
            statistics.stdev(ours_inertia) ** 2 / runs + statistics.stdev(ref_inertia) ** 2 / runs
        ) ** 0.5 / mi_ref
        table.add(
            workload,
            "visprim kmeans (k-means++ + Lloyd)",
            t_ours,
            f"mean inertia {mi_ours:.6g}",
            f"{runs} seeds",
        )
        table.add(
            workload,
            "sklearn KMeans lloyd",
            t_ref,
            f"mean inertia {mi_ref:.6g}",
            f"inertia ratio {mi_ours / mi_ref:.4f} ± {se:.4f}",
        )
        table.ratio(workload, "sklearn KMeans lloyd", t_ref, t_ours)


def run(table: Table, quick: bool = False) -> None:
    """Run the linalg section into ``table``."""
    print("linalg kernels:", flush=True)
    bench_covariance_eigh(table, quick)
    bench_kmeans(table, quick)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small workloads (smoke test)")
    parser.add_argument("--covariance-only", action="store_true", help="skip the k-means rows")
    args = parser.parse_args()
    tab = Table()
    bench_covariance_eigh(tab, args.quick)
    if not args.covariance_only:
        bench_kmeans(tab, args.quick)
    tab.print()
