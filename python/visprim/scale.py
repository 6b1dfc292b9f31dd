"""Learning from corpora larger than memory: streaming on one machine, Dask on many.

:meth:`visprim.model.PrimitiveModel.fit` hands a lazy corpus
(:class:`visprim.io.Corpus`, :class:`visprim.io.corpus.GeneratedCorpus`) or a Dask
``client`` to :func:`fit_corpus`. The result is the in-memory fit of the same trials:

1. **SEG-2's constant** ``c`` is tuned on the sample the in-memory fit tunes on (the
   :data:`~visprim.segment.seg2` limit of 2000 trials spread evenly over the corpus; every
   trial when there are fewer), so the segments are the same.
2. **Pass 1**, per chunk of items (map): read → IK → low-pass → segment → vectors with the
   model's own :meth:`~visprim.model.PrimitiveModel.prepare` and
   :meth:`~visprim.model.PrimitiveModel.vectorize`, merged into a
   :class:`visprim.kernels.CovarianceAccumulator` (reduce: accumulators merge exactly up to
   rounding, in any order); then the eigendecomposition.
3. **Pass 2**: the projections ``p = E_fᵀ (s − s̄)`` (N × f), then k-means on them with
   :func:`visprim.clustering.kmeans_projections`, the in-memory fit's procedure (above
   50,000 segments its k-means++ seedings run on a deterministic sample of the rows).

What stays in memory is what the model keeps: the projections (8 f bytes per segment), the
segments' trial, start and end, and the trial names; never the N × 4n vectors (the model's
``training_vectors_`` is ``None``, so :meth:`~visprim.model.PrimitiveModel.error_table`
needs an in-memory fit).

Streaming (:func:`fit_streaming`) writes each chunk's vectors to a temporary folder in pass 1
and reads them back in pass 2 (so the corpus is read once), then runs the in-memory fit's
k-means on the projections: identical clusters up to rounding.

Dask (:func:`fit_dask`, the only code that imports ``dask.distributed``; install
``visprim[dask]``): items are split in partitions spread over the workers. A partition task
computes its vectors (kept on the worker); its covariance accumulator is returned and the
accumulators are merged in a binary tree; projections are computed where the vectors are and
stay there. k-means follows :mod:`visprim.clustering` step by step, so the clusters are the
in-memory fit's up to rounding: up to its sample size the projections are gathered and
clustered as in memory; above it the sample rows are gathered, the ``n_init`` candidate
centre sets computed from them, scored on every row by the workers (with the column
variances that scale ``tol``), and the best one starts Lloyd's iterations as map (per-worker
sums, counts and farthest rows, for empty clusters) / reduce (the kernel's update rule) until
the kernel's stopping rule holds. A lost worker's tasks are re-run by Dask from the corpus
(their inputs); a task that keeps killing workers ends the fit with a :class:`RuntimeError`.
"""

from __future__ import annotations

import contextlib
import math
import shutil
import signal
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.base import clone
from tqdm.auto import tqdm

from visprim import kernels
from visprim.clustering import kmeans_projections, sample_candidates, sample_rows, sample_size
from visprim.io.corpus import LazyCorpus, sample_items, trial_names
from visprim.pca import PCABasis
from visprim.progress import _disable
from visprim.provenance import Provenance
from visprim.segment.seg2 import _MAX_TRIALS
from visprim.trial import Trial

__all__ = [
    "TrialList",
    "fit_corpus",
    "fit_dask",
    "fit_streaming",
    "local_client",
    "tune_threshold",
]


class TrialList(LazyCorpus):
    """Trials already in memory as a lazy corpus (one item per trial), e.g. to fit a list
    of trials on a Dask cluster."""

    def __init__(self, trials: Sequence[Trial]) -> None:
        self.trials = list(trials)

    def __len__(self) -> int:
        return len(self.trials)

    def read_item(self, index: int) -> list[Trial]:
        return [self.trials[self._index(index)]]

    def subset(self, indices: Sequence[int]) -> TrialList:
        return TrialList([self.trials[self._index(i)] for i in indices])

    @property
    def provenance(self) -> Provenance:
        return Provenance.trials(self.trials)


# ---------------------------------------------------------------------------- map steps


@dataclass
class Block:
    """The segments of a chunk of items: vectors (n, d) radians and where they came from
    (``trial`` indices local to the chunk, ``starts``/``ends`` seconds), the chunk's trial
    names, its arms (None without trials), how many of its trials have no segment and how
    many are shorter than the filter's padding."""

    vectors: NDArray[np.float64]
    trial: NDArray[np.int64]
    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    names: list[str]
    arms: tuple[str, ...] | None = None
    n_without: int = 0
    n_short: int = 0

    @property
    def n_trials(self) -> int:
        return len(self.names)

    def __len__(self) -> int:
        return int(self.vectors.shape[0])


def _settings(model: Any, threshold: float | None) -> Any:
    """An unfitted copy of ``model`` (same parameters) that cuts with SEG-2 constant
    ``threshold``: ``prepare`` / ``vectorize`` on it are the in-memory fit's."""
    m = clone(model)
    m.seg2_threshold_ = threshold
    return m


def tune_threshold(
    model: Any, corpus: LazyCorpus, *, max_trials: int = _MAX_TRIALS
) -> float | None:
    """SEG-2's constant for ``corpus`` as the in-memory fit tunes it (None for SEG-1).

    Tuned on at most ``max_trials`` (the tuning's own limit, 2000) items spread evenly over
    the corpus (every item when there are fewer): the trials the in-memory fit tunes on
    when every item is one trial.
    """
    if model.segmentation != "seg2":
        return None
    if model.seg2_threshold is not None:
        return float(model.seg2_threshold)
    trials = corpus.read(sample_items(len(corpus), max_trials))
    if not trials:
        raise ValueError("fit: the corpus yielded no trials")
    prepared = _settings(model, None).prepare(trials, tune_seg2=True)
    return prepared.seg2_threshold


def chunk_block(settings: Any, corpus: LazyCorpus, items: Sequence[int], first: int) -> Block:
    """Map step of pass 1: the segment vectors of the corpus items ``items``.

    ``settings`` is a model from :func:`_settings`; ``first`` numbers unnamed trials.
    """
    trials = corpus.read(items)
    names = trial_names(trials, first)
    if not trials:
        return Block(np.zeros((0, 0)), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), [])
    prepared = settings.prepare(trials, tune_seg2=False)
    arms = tuple(prepared.arms)
    n_without = int(np.sum(prepared.segmentation.counts() == 0))
    n_short = int(prepared.n_short)
    if prepared.segmentation.n_segments == 0:
        empty = np.zeros(0)
        no_trial = np.zeros(0, dtype=np.int64)
        return Block(np.zeros((0, 0)), no_trial, empty, empty, names, arms, n_without, n_short)
    sv = settings.vectorize(prepared)
    return Block(sv.vectors, sv.trial, sv.starts, sv.ends, names, arms, n_without, n_short)


def _accumulate(block: Block, n_threads: int | None = None) -> Any:
    acc = kernels.CovarianceAccumulator()
    if len(block):
        acc.update(block.vectors, n_threads=n_threads)
    return acc


def _basis(acc: Any, n_segments: int) -> PCABasis:
    values, vectors = kernels.eigh(np.asarray(acc.covariance()))
    return PCABasis(
        mean=np.asarray(acc.mean),
        eigenvalues=np.asarray(values),
        eigenvectors=np.asarray(vectors),
        n_vectors=n_segments,
    )


def _check_count(model: Any, n: int) -> None:
    if n < 2:
        raise ValueError(f"fit: the corpus yielded {n} segment(s); PCA needs at least 2")
    if int(model.n_clusters) > n:
        raise ValueError(
            f"fit: n_clusters={model.n_clusters} exceeds the number of segments found ({n}); "
            "lower n_clusters or give more trials"
        )


@dataclass
class _Segments:
    """Per-segment bookkeeping gathered from the blocks, in corpus order."""

    trial: list[NDArray[np.int64]]
    starts: list[NDArray[np.float64]]
    ends: list[NDArray[np.float64]]
    names: list[str]
    arms: set[tuple[str, ...]]
    n_without: int = 0
    n_short: int = 0

    @classmethod
    def empty(cls) -> _Segments:
        return cls([], [], [], [], set())

    def add(self, block: Block) -> None:
        self.trial.append(block.trial + len(self.names))
        self.starts.append(block.starts)
        self.ends.append(block.ends)
        self.names.extend(block.names)
        if block.arms is not None:
            self.arms.add(block.arms)
        self.n_without += block.n_without
        self.n_short += block.n_short

    def arrays(self) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        def cat(parts: list[NDArray[Any]], dtype: Any) -> NDArray[Any]:
            return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)

        return cat(self.trial, np.int64), cat(self.starts, np.float64), cat(self.ends, np.float64)


def _finish(
    model: Any,
    basis: PCABasis,
    projections: NDArray[np.float64] | None,
    segs: _Segments,
    threshold: float | None,
    source: Any,
    clusters: tuple[NDArray[np.float64], NDArray[np.int64], float, int] | None = None,
) -> Any:
    trial, starts, ends = segs.arrays()
    if len(segs.arms) > 1:
        raise ValueError(
            f"fit: the corpus mixes trials of arms {sorted(list(a) for a in segs.arms)}; "
            "read them with the same arm= option"
        )
    return model._set_fitted(
        basis,
        projections,
        trial=trial,
        starts=starts,
        ends=ends,
        seg2_threshold=threshold,
        trial_names=segs.names,
        arms=segs.arms.pop() if segs.arms else ("right",),
        n_without_segments=segs.n_without,
        n_short=segs.n_short,
        vectors=None,
        source=source,
        clusters=clusters,
    )


# ---------------------------------------------------------------------------- streaming


def fit_streaming(
    model: Any,
    corpus: LazyCorpus,
    *,
    chunk_size: int | None = None,
    spill_dir: str | Path | None = None,
    source: Provenance | None = None,
) -> Any:
    """Fit ``model`` on a lazy corpus in bounded memory (see the module docstring).

    Parameters
    ----------
    chunk_size : items read at a time (default :data:`visprim.io.corpus.DEFAULT_CHUNK`).
    spill_dir : folder for the temporary vector files of pass 1 (default: the system's
        temporary folder); needs 8 × 4 n_samples bytes per segment (3.2 kB at n = 100),
        removed when the fit ends.
    source : recorded as ``provenance_`` (default: the corpus's own record).
    """
    threshold = tune_threshold(model, corpus)
    settings = _settings(model, threshold)
    segs = _Segments.empty()
    acc = kernels.CovarianceAccumulator()
    tmp = Path(tempfile.mkdtemp(prefix="visprim-fit-", dir=spill_dir))
    bar = tqdm(total=len(corpus), desc="learn", unit="item", disable=_disable(), leave=False)
    try:
        files = []
        for j, items in enumerate(corpus.chunk_ranges(chunk_size)):
            block = chunk_block(settings, corpus, items, len(segs.names))
            segs.add(block)
            if len(block):
                acc.update(block.vectors)
                files.append(tmp / f"{j:08d}.npy")
                np.save(files[-1], block.vectors)
            bar.update(len(items))
        n = int(acc.count)
        _check_count(model, n)
        basis = _basis(acc, n)
        f = int(model.n_components)
        projections = np.empty((n, f))
        row = 0
        for path in files:
            p = basis.project(np.load(path), f)
            projections[row : row + p.shape[0]] = p
            row += p.shape[0]
            path.unlink()
    finally:
        bar.close()
        shutil.rmtree(tmp, ignore_errors=True)
    return _finish(model, basis, projections, segs, threshold, source or corpus.provenance)


def fit_corpus(
    model: Any,
    data: Any,
    *,
    client: Any = None,
    source: Provenance | None = None,
    chunk_size: int | None = None,
) -> Any:
    """:meth:`PrimitiveModel.fit` on a lazy corpus, or on a Dask cluster (``client``: a
    ``distributed.Client``, a scheduler address, or ``True`` for a local cluster)."""
    model._validate_params()
    for attr in [a for a in vars(model) if a.endswith("_") and not a.startswith("_")]:
        delattr(model, attr)
    corpus = data if isinstance(data, LazyCorpus) else TrialList(_trials(data))
    if len(corpus) == 0:
        raise ValueError("fit: the corpus is empty")
    if client is None:
        return fit_streaming(model, corpus, chunk_size=chunk_size, source=source)
    return fit_dask(model, corpus, client, chunk_size=chunk_size, source=source)


def _trials(data: Any) -> list[Trial]:
    out = [data] if isinstance(data, Trial) else list(data)
    for i, t in enumerate(out):
        if not isinstance(t, Trial):
            raise TypeError(f"item {i} is a {type(t).__name__}, expected visprim.Trial")
    return out


# ---------------------------------------------------------------------------- Dask


def local_client(n_workers: int | None = None, *, threads_per_worker: int = 1) -> Any:
    """A ``distributed.Client`` on a new ``LocalCluster`` of worker processes (one thread
    each, and one thread for the Rust kernels in each). Close it with ``client.close()``
    and ``client.cluster.close()``.

    The workers start without Dask's default ``MALLOC_TRIM_THRESHOLD_``: setting it also
    freezes glibc's mmap threshold at 128 kB, so that every array of a partition (vectors,
    angles) is mapped, page-faulted and unmapped afresh, which costs pass 1 a large share of
    its time (``benches/bench_scale.py --modes stream,dask,dask-default`` measures it), nor
    the statistical profiler (it samples the task thread every 10 ms for the dashboard,
    which is off). Workers started otherwise (``dask worker``) can do the same in their Dask
    configuration: ``MALLOC_TRIM_THRESHOLD_: null`` under
    ``distributed.nanny.pre-spawn-environ``, ``distributed.worker.profile.enabled: false``."""
    import dask
    from distributed import Client, LocalCluster

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    settings = {
        "distributed.nanny.pre-spawn-environ": environ,
        # The statistical profiler feeds the dashboard (off here) and wakes every 10 ms.
        "distributed.worker.profile.enabled": False,
    }
    # A Ctrl-C while the cluster starts would leave it half-made (and distributed prints a
    # long traceback when it closes it at exit): the interruption waits until it has
    # started, then closes it and is raised.
    with dask.config.set(settings), _interrupt_deferred() as interrupted:
        cluster = LocalCluster(
            n_workers=n_workers,
            threads_per_worker=threads_per_worker,
            processes=True,
            dashboard_address=None,
            env={"RAYON_NUM_THREADS": str(threads_per_worker)},
        )
    if interrupted:
        cluster.close()
        raise KeyboardInterrupt
    return Client(cluster)


@contextlib.contextmanager
def _interrupt_deferred() -> Iterator[list[int]]:
    """Within the block, SIGINT is recorded in the yielded list instead of raised (main
    thread only; elsewhere signals are left alone)."""
    seen: list[int] = []
    try:
        previous = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    except ValueError:  # not the main thread
        yield seen
        return
    try:
        yield seen
    finally:
        signal.signal(signal.SIGINT, previous)


def _block_task(settings: Any, part: LazyCorpus) -> Block:
    return chunk_block(settings, part, range(len(part)), 0)


def _acc_task(block: Block) -> Any:
    return _accumulate(block, n_threads=1)


def _merge_task(a: Any, b: Any) -> Any:
    a.merge(b)
    return a


def _meta_task(block: Block) -> Block:
    return Block(
        np.zeros((0, 0)),
        block.trial,
        block.starts,
        block.ends,
        block.names,
        block.arms,
        block.n_without,
        block.n_short,
    )


def _project_task(block: Block, mean_e: NDArray[np.float64], e: NDArray[np.float64]) -> Any:
    if len(block) == 0:
        return np.zeros((0, e.shape[1]))
    return block.vectors @ e - mean_e


def _take_task(p: NDArray[np.float64], rows: NDArray[np.int64]) -> NDArray[np.float64]:
    return p[rows]


def _stats_task(
    p: NDArray[np.float64], candidates: NDArray[np.float64]
) -> tuple[NDArray[np.float64], int, NDArray[np.float64], NDArray[np.float64]]:
    """The inertia of the rows for each of several centre sets ``(R, k, f)`` → ``(R,)``, and
    the rows' count, column means and sums of squared deviations (for the variance)."""
    f = candidates.shape[2]
    if p.shape[0] == 0:
        return np.zeros(candidates.shape[0]), 0, np.zeros(f), np.zeros(f)
    out = np.zeros(candidates.shape[0])
    for r, c in enumerate(candidates):
        dist = kernels.kmeans_predict(p, c, n_threads=1)[1]
        out[r] = float(np.dot(dist, dist))
    mean = p.mean(axis=0)
    return out, int(p.shape[0]), mean, np.sum((p - mean) ** 2, axis=0)


@dataclass
class _LloydPart:
    """One worker's share of a Lloyd iteration: per-cluster sums ``(k, f)`` and counts
    ``(k,)`` of the rows nearest each centre, and its ``k`` rows farthest from their centre
    (distance, global row index, label, values), for re-seeding empty clusters."""

    sums: NDArray[np.float64]
    counts: NDArray[np.int64]
    far_dist: NDArray[np.float64]
    far_row: NDArray[np.int64]
    far_label: NDArray[np.int64]
    far_values: NDArray[np.float64]


def _global_rows(local: NDArray[np.int64], spans: list[tuple[int, int]]) -> NDArray[np.int64]:
    """Global row numbers of positions in the concatenation of the row ranges ``spans``."""
    sizes = np.array([b - a for a, b in spans], dtype=np.int64)
    ends = np.cumsum(sizes)
    which = np.searchsorted(ends, local, side="right")
    starts = np.array([a for a, _ in spans], dtype=np.int64)
    return starts[which] + local - (ends[which] - sizes[which])


def _lloyd_task(
    p: NDArray[np.float64], centers: NDArray[np.float64], spans: list[tuple[int, int]]
) -> _LloydPart:
    """Map step of one Lloyd iteration (the assignment, and the sums of the update)."""
    k, f = centers.shape
    if p.shape[0] == 0:
        none = np.zeros(0, dtype=np.int64)
        return _LloydPart(np.zeros((k, f)), np.zeros(k, np.int64), np.zeros(0), none, none, p)
    labels, dist = kernels.kmeans_predict(p, centers, n_threads=1)
    counts = np.bincount(labels, minlength=k)
    sums = np.stack([np.bincount(labels, weights=p[:, j], minlength=k) for j in range(f)], 1)
    m = min(k, p.shape[0])
    # The m largest distances, ties by row (all rows tied with the m-th are candidates).
    cut = np.partition(dist, p.shape[0] - m)[p.shape[0] - m]
    cand = np.flatnonzero(dist >= cut)
    rows = _global_rows(cand, spans)
    order = np.lexsort((rows, -dist[cand]))[:m]
    far = cand[order]
    return _LloydPart(
        sums.astype(np.float64),
        counts.astype(np.int64),
        dist[far],
        rows[order],
        np.asarray(labels, dtype=np.int64)[far],
        p[far],
    )


def _assign_task(
    p: NDArray[np.float64], centers: NDArray[np.float64]
) -> tuple[NDArray[np.int64], float]:
    if p.shape[0] == 0:
        return np.zeros(0, dtype=np.int64), 0.0
    labels, dist = kernels.kmeans_predict(p, centers, n_threads=1)
    return np.asarray(labels, dtype=np.int64), float(np.dot(dist, dist))


def _lloyd_update(
    parts: list[_LloydPart], centers: NDArray[np.float64]
) -> tuple[NDArray[np.float64], float]:
    """Reduce step: the new centres and the total squared shift, with
    :func:`visprim.kernels.kmeans`'s rules (an empty cluster takes the row farthest from its
    own centre, the i-th empty one the i-th farthest row, ties by row; that row's cluster
    loses it; a cluster still empty keeps its centre)."""
    totals = np.sum([q.sums for q in parts], axis=0)
    counts = np.sum([q.counts for q in parts], axis=0)
    empty = np.flatnonzero(counts == 0)
    dist = np.concatenate([q.far_dist for q in parts])
    if empty.size and dist.size and float(np.max(dist)) > 0.0:
        rows = np.concatenate([q.far_row for q in parts])
        labels = np.concatenate([q.far_label for q in parts])
        values = np.concatenate([q.far_values for q in parts])
        order = np.lexsort((rows, -dist))
        for j, far in zip(empty, order, strict=False):
            old = int(labels[far])
            totals[old] -= values[far]
            totals[j] = values[far]
            counts[old] -= 1
            counts[j] = 1
    new = centers.copy()
    filled = counts > 0
    new[filled] = totals[filled] * (1.0 / counts[filled])[:, None]
    return new, float(np.sum((new[filled] - centers[filled]) ** 2))


def _tree_merge(client: Any, futures: list[Any]) -> Any:
    while len(futures) > 1:
        merged = [
            client.submit(_merge_task, futures[i], futures[i + 1], pure=False)
            for i in range(0, len(futures) - 1, 2)
        ]
        if len(futures) % 2:
            merged.append(futures[-1])
        futures = merged
    return futures[0].result()


def _partitions(n_items: int, n_workers: int, chunk_size: int | None) -> list[range]:
    """Item ranges: chunks of ``chunk_size`` items, or enough for 4 partitions a worker."""
    if chunk_size is None:
        per = max(1, min(1024, math.ceil(n_items / (4 * max(1, n_workers)))))
    else:
        per = int(chunk_size)
    return [range(a, min(a + per, n_items)) for a in range(0, n_items, per)]


def fit_dask(
    model: Any,
    corpus: LazyCorpus,
    client: Any,
    *,
    chunk_size: int | None = None,
    source: Provenance | None = None,
) -> Any:
    """Fit ``model`` on a Dask cluster (see the module docstring).

    ``client``: a ``distributed.Client``, a scheduler address (``"tcp://host:8786"``), or
    ``True`` for a new local cluster (closed afterwards). ``chunk_size``: items per
    partition (default: 4 partitions per worker, at most 1024 items each).
    """
    try:
        from distributed import CancelledError, Client, KilledWorker
    except ImportError:
        raise ImportError(
            "fitting on a Dask cluster needs dask.distributed: pip install 'visprim[dask]'"
        ) from None
    own = None
    if client is True:
        own = client = local_client()
    elif isinstance(client, str):
        own = client = Client(client)
    try:
        return _fit_dask(model, corpus, client, chunk_size, source)
    except (KilledWorker, CancelledError) as exc:
        raise RuntimeError(
            f"Dask: a task kept killing workers and was abandoned ({exc}); "
            "a recording may exhaust a worker's memory"
        ) from None
    finally:
        if own is not None:
            cluster = own.cluster
            own.close()
            if cluster is not None:
                cluster.close()


def _fit_dask(
    model: Any,
    corpus: LazyCorpus,
    client: Any,
    chunk_size: int | None,
    source: Provenance | None,
) -> Any:
    n_workers = max(1, len(client.scheduler_info().get("workers", {})))
    threshold = client.submit(tune_threshold, model, corpus, pure=False).result()
    settings = _settings(model, threshold)
    parts = _partitions(len(corpus), n_workers, chunk_size)
    # Each task carries its own items (no scattered data to lose with a worker).
    blocks = [client.submit(_block_task, settings, corpus.subset(r), pure=False) for r in parts]
    acc = _tree_merge(client, [client.submit(_acc_task, b, pure=False) for b in blocks])
    n = int(acc.count)
    _check_count(model, n)
    basis = _basis(acc, n)
    f = int(model.n_components)
    e = np.ascontiguousarray(basis.eigenvectors[:, :f])
    mean_e = basis.mean @ e
    projs = [client.submit(_project_task, b, mean_e, e, pure=False) for b in blocks]
    metas = client.gather([client.submit(_meta_task, b, pure=False) for b in blocks])
    del blocks
    segs = _Segments.empty()
    rows = [0]
    for meta in metas:
        segs.add(meta)
        rows.append(rows[-1] + meta.trial.size)
    clusters = _kmeans_dask(client, model, projs, rows)
    return _finish(
        model,
        basis,
        None,
        segs,
        threshold,
        source or corpus.provenance,
        clusters=clusters,
    )


def _kmeans_dask(
    client: Any, model: Any, projs: list[Any], rows: list[int]
) -> tuple[NDArray[np.float64], NDArray[np.int64], float, int]:
    """:func:`visprim.clustering.kmeans_projections` of the projections held by the workers
    (partition ``i`` holds rows ``rows[i]:rows[i + 1]``)."""
    n, k = rows[-1], int(model.n_clusters)
    opts: dict[str, Any] = dict(
        n_init=int(model.n_init), max_iter=int(model.max_iter), tol=float(model.tol)
    )
    seed = int(model.seed)
    if n <= sample_size(k):  # few rows: every row in one place, as in memory
        return kmeans_projections(np.concatenate(client.gather(projs)), k, seed=seed, **opts)
    pick = sample_rows(n, k, seed)
    takes = []
    for i, p in enumerate(projs):
        a, b = np.searchsorted(pick, [rows[i], rows[i + 1]])
        if b > a:
            takes.append(client.submit(_take_task, p, pick[a:b] - rows[i], pure=False))
    sample = np.concatenate(client.gather(takes))
    groups, members = _group_by_worker(client, projs)  # concatenated while the client seeds
    del projs, takes
    candidates = sample_candidates(sample, k, seed=seed, **opts)
    spans = [[(rows[i], rows[i + 1]) for i in idx] for idx in members]
    stats = client.gather([client.submit(_stats_task, g, candidates, pure=False) for g in groups])
    centers = candidates[int(np.argmin(np.sum([s[0] for s in stats], axis=0)))]
    tol = float(model.tol) * _mean_variance([s[1:] for s in stats])
    n_iter = 0
    for n_iter in range(1, int(model.max_iter) + 1):  # noqa: B007 (reported after the loop)
        tasks = [
            client.submit(_lloyd_task, g, centers, sp, pure=False)
            for g, sp in zip(groups, spans, strict=True)
        ]
        centers, shift = _lloyd_update(client.gather(tasks), centers)
        if shift <= tol:
            break
    final = client.gather([client.submit(_assign_task, g, centers, pure=False) for g in groups])
    labels = np.empty(n, dtype=np.int64)
    for (lab, _), idx in zip(final, members, strict=True):
        sizes = [rows[i + 1] - rows[i] for i in idx]
        for i, part in zip(idx, np.split(lab, np.cumsum(sizes)[:-1]), strict=True):
            labels[rows[i] : rows[i + 1]] = part
    inertia = float(sum(i for _, i in final))
    return centers, labels, inertia, n_iter


def _mean_variance(
    parts: list[tuple[int, NDArray[np.float64], NDArray[np.float64]]],
) -> float:
    """``mean(var(X, axis=0))`` from per-part counts, means and squared deviations (merged
    with Chan et al.'s pairwise update)."""
    n, mean, m2 = 0, np.zeros_like(parts[0][1]), np.zeros_like(parts[0][2])
    for nb, mb, m2b in parts:
        if nb == 0:
            continue
        total = n + nb
        delta = mb - mean
        mean = mean + delta * (nb / total)
        m2 = m2 + m2b + delta**2 * (n * nb / total)
        n = total
    return float(np.mean(m2 / max(n, 1)))


def _concat_task(*parts: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.concatenate(parts)


def _group_by_worker(client: Any, projs: list[Any]) -> tuple[list[Any], list[list[int]]]:
    """One array of projections per worker (concatenated where they are), so that each
    Lloyd iteration is one task per worker; returns the futures and the partitions (in
    corpus order) each one holds."""
    from distributed import wait

    wait(projs)
    where = client.who_has(projs)
    by_worker: dict[str, list[int]] = {}
    for i, fut in enumerate(projs):
        holders = sorted(where.get(fut.key, ())) or [""]
        by_worker.setdefault(holders[0], []).append(i)
    groups, members = [], []
    for worker, idx in by_worker.items():
        groups.append(
            client.submit(
                _concat_task,
                *[projs[i] for i in idx],
                pure=False,
                workers=[worker] if worker else None,
                allow_other_workers=True,
            )
        )
        members.append(idx)
    return groups, members
