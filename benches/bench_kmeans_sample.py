"""k-means on many segments: ten k-means++ seedings on every row vs on a sample.

Not part of ``make test``. ``python benches/bench_kmeans_sample.py`` fits the scale
benchmark's corpus (``bench_scale.py``'s pool of generated trials, ``--segments`` of them,
streaming) once, then clusters its projections (f = k = 30, n_init = 10) for each seed in
``--seeds`` in two ways:

* ``all rows``: :func:`visprim.kernels.kmeans` with ``n_init=10`` on every row (the in-memory
  fit's k-means before :mod:`visprim.clustering` sampled its seedings);
* ``sampled``: :func:`visprim.clustering.kmeans_projections` (seedings on
  :data:`~visprim.clustering.SAMPLE_SIZE` rows, the best on every row, Lloyd on every row),
  the procedure of the in-memory, streaming and Dask fits.

It prints each seed's inertia and time for both, and the ratios' median and range: how far
apart the local optima of different seedings lie, and what the sample costs in inertia.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import PARAMS, pool_corpus, write_pool  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--segments", type=int, default=1_000_000)
    ap.add_argument("--pool", type=int, default=2000, help="distinct trials on disk")
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--data", type=Path, default=None, help="pool folder (kept if given)")
    args = ap.parse_args()

    from visprim import kernels
    from visprim.clustering import kmeans_projections
    from visprim.model import PrimitiveModel

    tmp = None
    folder = args.data
    if folder is None:
        tmp = tempfile.TemporaryDirectory(prefix="visprim-bench-kmeans-")
        folder = Path(tmp.name)
    write_pool(folder, args.pool)
    probe = PrimitiveModel.paper(**PARAMS).fit(pool_corpus(folder, args.pool))
    items = round(args.segments * args.pool / probe.n_training_segments_)
    model = PrimitiveModel.paper(**PARAMS).fit(pool_corpus(folder, items))
    p = model.training_projections_
    assert p is not None
    k, n_init = int(PARAMS["n_clusters"]), int(PARAMS["n_init"])
    print(f"{p.shape[0]:,} projections ({p.shape[1]}-D), k = {k}, n_init = {n_init}")
    print("| seed | all rows: inertia, s | sampled: inertia, s | sampled / all rows |")
    print("|---:|---:|---:|---:|")
    ratios, speed = [], []
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        full = kernels.kmeans(p, k, n_init=n_init, seed=seed)
        t1 = time.perf_counter()
        sampled = kmeans_projections(p, k, n_init=n_init, max_iter=300, tol=1e-4, seed=seed)
        t2 = time.perf_counter()
        ratios.append(sampled[2] / full.inertia)
        speed.append((t1 - t0) / (t2 - t1))
        print(
            f"| {seed} | {full.inertia:,.0f}, {t1 - t0:.1f} | {sampled[2]:,.0f}, {t2 - t1:.1f} "
            f"| {ratios[-1]:.4f} |",
            flush=True,
        )
    print(
        f"inertia sampled / all rows: median {statistics.median(ratios):.4f} "
        f"({min(ratios):.4f}–{max(ratios):.4f}); time all rows / sampled: median "
        f"{statistics.median(speed):.1f}x ({min(speed):.1f}–{max(speed):.1f}x)"
    )
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
