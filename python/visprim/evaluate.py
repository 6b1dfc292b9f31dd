"""The benchmark of the method on labelled real recordings (``visprim evaluate``).

Labels
------
Each recording needs a label and a group. They come from a ``labels.tsv`` beside the data
(tab-separated, columns ``file, label, style, subject, take, group, description``; only
``file`` and ``label`` are required) or from a file given with ``labels=``. Bandai-Namco
file names (``dataset-2_<label>_<style>_<take>.bvh``) carry their own labels, so folders of
such files need no table. Recordings without a label are left out (and counted).

Benchmarks
----------
Recordings are grouped into benchmarks by folder; a folder ``X_extra`` joins ``X`` (more
takes of the same corpus). In each benchmark:

* **Groups** for leave-one-group-out: the ``group_by`` column (``subject``, ``style`` or
  ``take``); by default the first of ``subject``, ``style``, ``take`` with at least two
  distinct values. Classes present in fewer than two groups are left out (a class whose
  every example is held out can never be recognised); ``classes=`` restricts the labels.
* **Classification**: :class:`~visprim.classify.MotionClassifier` (primitives learned from
  the training groups only) and, in the same run, the DTW 1-NN baseline
  (:class:`~visprim.classify.DTWClassifier`) on the same arms; accuracy, per-group accuracy
  and confusion matrices.
* **Segmentation** of the held-out trials with each fold's fitted SEG-2 constant: segments
  per trial, trials without a segment, the tuned ``c`` per fold, and coverage of moving
  time (fraction of the frames where the wrist moves faster than
  :data:`MOVING_SPEED` relative to the shoulder that lie inside a segment).
* **Reconstruction** of the held-out segments: the paper's total error (each segment
  rebuilt from its primitive's centre) as an RMS angle error in degrees (per bone
  direction for direction features, per angle sample for Z-Y-Z angles), at k = 30 and
  k = 100 primitives; and the whole-movement RMS angle between the bone directions of each
  movement and of its rebuilding from consecutive segments' primitives (k = 30). Two-arm
  movements are rebuilt arm by arm from one-arm primitives learned from both arms of the
  training groups (:func:`~visprim.trial.split_arms`; the left arm mirrored), as the
  paper's primitives are one arm's: each arm is segmented on its own and a segment is one
  arm's stroke. ``reconstruction="joint"`` uses the classifier's two-arm primitives
  instead.

Every number is computed on held-out groups: nothing is tuned on the group being scored.
"""

from __future__ import annotations

import csv
import io
import os
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim import csvfile, kernels
from visprim.accuracy import angular_error_deg
from visprim.atomic import atomic_file, write_text
from visprim.classify import MotionClassifier, arm_directions, dtw_matrix, group_folds
from visprim.features import direction_rms_deg
from visprim.io import BANDAI_NAME, FORMATS
from visprim.params import DEG2_PER_RAD2, STUDY_FRAME_PERIOD_S
from visprim.segment.coverage import DEFAULT_MOVING_SPEED, segment_coverage
from visprim.trial import Trial, split_arms

__all__ = [
    "GROUP_COLUMNS",
    "MOVING_SPEED",
    "Benchmark",
    "BenchmarkResult",
    "Recording",
    "evaluate",
    "find_recordings",
    "read_movements",
    "write_report",
]

#: Columns usable as leave-one-group-out groups.
GROUP_COLUMNS: tuple[str, ...] = ("subject", "style", "take")
#: Wrist speed relative to the shoulder (m/s) above which a frame counts as moving, for the
#: segmentation coverage (:mod:`visprim.segment.coverage`).
MOVING_SPEED: float = DEFAULT_MOVING_SPEED
#: Primitive counts of the reconstruction table.
RECONSTRUCTION_K: tuple[int, ...] = (30, 100)
#: Which primitives rebuild two-arm movements (:func:`evaluate_benchmark`).
RECONSTRUCTIONS: tuple[str, ...] = ("each-arm", "joint")
#: Frame period every recording is resampled to (s), as in the method (34 ms).
DEFAULT_PERIOD: float = STUDY_FRAME_PERIOD_S

#: Extensions of the recordings searched for in folders: every reader's.
_EXTENSIONS = tuple(FORMATS)
#: How :func:`find_recordings` names the Bandai-Namco file-name rule as a label source.
BANDAI_RULE = "Bandai-Namco file names (dataset-N_<label>_<style>_<take>)"


@dataclass(frozen=True)
class Recording:
    """One labelled recording: its file, label, groups and benchmark name."""

    path: Path
    label: str
    style: str = ""
    subject: str = ""
    take: str = ""
    benchmark: str = ""
    #: Where the label came from: the labels table's path, or the file-name rule.
    label_source: str = field(default="", compare=False)

    def group(self, column: str) -> str:
        return str(getattr(self, column))


def _read_table(path: Path) -> list[dict[str, str]]:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the labels ({exc.strerror})") from None
    rows = list(csv.DictReader(io.StringIO(text), delimiter="\t"))
    if not rows:
        raise ValueError(f"{path}: no labelled rows")
    missing = {"file", "label"} - set(rows[0])
    if missing:
        raise ValueError(
            f"{path}: missing column(s) {', '.join(sorted(missing))} (need a tab-separated "
            "table with at least 'file' and 'label')"
        )
    return rows


def _benchmark_name(folder: Path) -> str:
    name = folder.name
    return name[: -len("_extra")] if name.endswith("_extra") else name


def find_recordings(
    sources: Iterable[str | os.PathLike[str]], labels: str | os.PathLike[str] | None = None
) -> tuple[list[Recording], list[Path]]:
    """Labelled recordings under ``sources`` (files or folders, searched recursively).

    Returns ``(recordings, unlabelled files)``. Labels come from ``labels`` when given, else
    from the ``labels.tsv`` in each file's folder, else from a Bandai-Namco file name.
    """
    files: list[Path] = []
    for src in sources:
        p = Path(src)
        if p.is_dir():
            files.extend(
                sorted(f for f in p.rglob("*") if f.is_file() and f.suffix.lower() in _EXTENSIONS)
            )
        elif p.is_file():
            files.append(p)
        else:
            raise ValueError(f"{p}: no such file or folder")
    given = None if labels is None else {r["file"]: r for r in _read_table(Path(labels))}
    tables: dict[Path, dict[str, dict[str, str]] | None] = {}
    found, unlabelled = [], []
    seen: set[Path] = set()
    for f in files:
        if f.resolve() in seen:
            continue
        seen.add(f.resolve())
        row: Mapping[str, str] | None = None
        source = ""
        if given is not None:
            row = given.get(f.name) or given.get(str(f))
            source = str(labels)
        else:
            folder = f.parent
            if folder not in tables:
                table = folder / "labels.tsv"
                tables[folder] = (
                    {r["file"]: r for r in _read_table(table)} if table.is_file() else None
                )
            rows = tables[folder]
            if rows is not None:
                row = rows.get(f.name)
                source = str(folder / "labels.tsv")
        if row is None:
            m = BANDAI_NAME.match(f.stem)
            if m is not None and given is None:
                row = {"label": m["content"], "style": m["style"], "take": m["take"], "subject": ""}
                source = BANDAI_RULE
        if row is None or not (row.get("label") or "").strip():
            unlabelled.append(f)
            continue
        found.append(
            Recording(
                path=f,
                label=row["label"].strip(),
                style=(row.get("style") or "").strip(),
                subject=(row.get("subject") or "").strip(),
                take=(row.get("take") or "").strip(),
                benchmark=_benchmark_name(f.parent),
                label_source=source,
            )
        )
    return found, unlabelled


def _read_one(path: Path, period: float, arm: str = "both") -> tuple[Trial | str, list[str]]:
    """The recording as a trial, or the one-line reason it cannot be read, with the
    warnings the reader gave (a worker process hands them back to be shown here)."""
    from visprim.io import read

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            if path.suffix.lower() == ".csv":  # the marker CSV holds one (right) arm
                result: Trial | str = read(path, "right", resample=period)
            else:
                result = read(path, arm, resample=period)
        except ValueError as exc:  # ReadError and bad content: skip the file, say why
            result = str(exc).splitlines()[0] if str(exc) else f"{path}: unreadable"
    return result, [str(w.message) for w in caught]


def read_movements(
    recordings: Sequence[Recording],
    *,
    period: float = DEFAULT_PERIOD,
    arm: str = "both",
    jobs: int | None = None,
    on_progress: Callable[[int], object] | None = None,
) -> tuple[list[Trial | None], list[str]]:
    """Each recording as a trial of ``arm`` (``"both"`` by default, ``"right"`` or
    ``"left"``; marker CSV files hold the right arm only), read by
    :func:`visprim.io.read` and resampled to ``period`` seconds; ``jobs`` worker
    processes (default: the number of cores). Returns ``(trials, errors)``: ``None`` in
    place of a recording that cannot be read, and one line per such recording."""
    paths = [r.path for r in recordings]
    jobs = max(1, jobs if jobs is not None else (os.cpu_count() or 1))
    results: list[tuple[Trial | str, list[str]]] = []
    if jobs == 1 or len(paths) < 4:
        for p in paths:
            results.append(_read_one(p, period, arm))
            if on_progress:
                on_progress(1)
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        # "spawn": a forked child inherits locks held by this process's other threads
        # (Rust thread pools, progress bars) and can hang on them.
        spawn = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=spawn) as pool:
            n = len(paths)
            for m in pool.map(_read_one, paths, [period] * n, [arm] * n, chunksize=4):
                results.append(m)
                if on_progress:
                    on_progress(1)
    for _, said in results:
        for message in said:
            warnings.warn(message, stacklevel=2)
    trials = [r if isinstance(r, Trial) else None for r, _ in results]
    errors = [f"skipped {r}" for r, _ in results if isinstance(r, str)]
    return trials, errors


@dataclass
class Benchmark:
    """The recordings of one benchmark with their movements, labels and groups."""

    name: str
    recordings: list[Recording]
    movements: list[Trial]
    group_by: str
    left_out_classes: list[str] = field(default_factory=list)

    @property
    def labels(self) -> NDArray[Any]:
        return np.array([r.label for r in self.recordings])

    @property
    def groups(self) -> NDArray[Any]:
        return np.array([r.group(self.group_by) for r in self.recordings])


@dataclass
class BenchmarkResult:
    """Everything :func:`evaluate` measured on one benchmark (see the module docstring)."""

    name: str
    group_by: str
    n_trials: int
    classes: list[str]
    left_out_classes: list[str]
    groups: list[str]
    accuracy: float
    baseline_accuracy: float
    per_group: dict[str, tuple[float, float, int]]
    confusion: NDArray[np.int64]
    baseline_confusion: NDArray[np.int64]
    segments_per_trial: float
    trials_without_segments: int
    n_arm_trials: int
    coverage_median: float
    coverage_min: float
    seg2_thresholds: dict[str, float]
    reconstruction_deg: dict[int, float]
    #: Total error with each segment's primitive scaled by its least-squares amplitude
    #: (``PrimitiveModel(amplitude=True)``; posture-relative vectors only).
    amplitude_deg: dict[int, float]
    movement_rms_deg: float
    seconds: dict[str, float]
    predictions: NDArray[Any]
    baseline_predictions: NDArray[Any]
    labels: NDArray[Any]
    group_values: NDArray[Any]
    names: list[str]
    #: How held-out segments were rebuilt: ``"one arm"`` (one-arm movements), ``"each arm"``
    #: or ``"joint"`` (two-arm movements, see :func:`evaluate_benchmark`).
    reconstruction: str = "one arm"
    #: Where the labels came from (:attr:`Recording.label_source`) → number of recordings.
    label_sources: dict[str, int] = field(default_factory=dict)


def _choose_group(recordings: Sequence[Recording], group_by: str | None) -> str:
    if group_by is not None:
        if group_by not in GROUP_COLUMNS:
            raise ValueError(f"group must be one of {', '.join(GROUP_COLUMNS)}, got {group_by!r}")
        return group_by
    for col in GROUP_COLUMNS:
        if len({r.group(col) for r in recordings if r.group(col)}) >= 2:
            return col
    return "take"


def _confusion(classes: list[str], truth: NDArray[Any], pred: NDArray[Any]) -> NDArray[np.int64]:
    from sklearn.metrics import confusion_matrix

    return np.asarray(confusion_matrix(truth, pred, labels=classes), dtype=np.int64)


def _total_error_sq(
    model: Any, vectors: NDArray[np.float64], centers: NDArray[np.float64], amplitude: bool
) -> float:
    """Summed squared error of rebuilding ``vectors`` from their nearest of ``centers``,
    scaled by their amplitude when ``amplitude``."""
    from visprim.model import rebuild_from_centers

    rebuilt = rebuild_from_centers(model, vectors, centers, amplitude=amplitude)
    diff = vectors - rebuilt
    return float(np.einsum("ij,ij->", diff, diff))


def evaluate_benchmark(
    bench: Benchmark,
    *,
    classifier: MotionClassifier | None = None,
    on_fold: Callable[[str], None] | None = None,
    reconstruction: str = "each-arm",
) -> BenchmarkResult:
    """Leave-one-group-out classification, segmentation and reconstruction of one
    benchmark (see the module docstring).

    ``reconstruction`` is which primitives rebuild the held-out segments of two-arm
    movements: ``"each-arm"`` (default), one-arm primitives learned from both arms
    (:func:`~visprim.trial.split_arms`), each arm segmented and rebuilt on its own; or
    ``"joint"``, the classifier's two-arm primitives, both arms cut at the same times.
    """
    if reconstruction not in RECONSTRUCTIONS:
        raise ValueError(
            f"reconstruction must be one of {', '.join(RECONSTRUCTIONS)}, got {reconstruction!r}"
        )
    from sklearn.base import clone

    from visprim.model import PrimitiveModel

    y = bench.labels
    g = bench.groups
    classes = sorted(set(y.tolist()))
    order = list(dict.fromkeys(g.tolist()))
    if len(order) < 2:
        raise ValueError(
            f"benchmark {bench.name}: leave-one-group-out needs at least two {bench.group_by} "
            "groups"
        )
    template = classifier if classifier is not None else MotionClassifier()
    per_arm = reconstruction == "each-arm" and bench.movements[0].n_arms > 1
    seconds = {"classifier": 0.0, "baseline": 0.0, "segmentation": 0.0, "reconstruction": 0.0}

    t0 = time.perf_counter()
    d_all = dtw_matrix([arm_directions(t) for t in bench.movements], band=template.band)
    seconds["baseline"] += time.perf_counter() - t0

    pred = np.empty_like(y)
    base_pred = np.empty_like(y)
    seg_counts: list[int] = []
    coverage: list[float] = []
    thresholds: dict[str, float] = {}
    sq = {k: 0.0 for k in RECONSTRUCTION_K}
    sq_amp = {k: 0.0 for k in RECONSTRUCTION_K}
    n_amp = {k: 0 for k in RECONSTRUCTION_K}
    n_vec = {k: 0 for k in RECONSTRUCTION_K}
    rms: list[float] = []
    dims = [0]
    for group, train, test in group_folds(g):
        if on_fold:
            on_fold(f"{bench.name}: {bench.group_by} {group or '-'}")
        t0 = time.perf_counter()
        base_pred[test] = y[train][np.argmin(d_all[np.ix_(test, train)], axis=1)]
        seconds["baseline"] += time.perf_counter() - t0

        t0 = time.perf_counter()
        clf = clone(template).fit([bench.movements[i] for i in train], y[train], groups=g[train])
        pred[test] = clf.predict([bench.movements[i] for i in test])
        seconds["classifier"] += time.perf_counter() - t0

        model = clf.model_
        thresholds[group] = float(getattr(model, "seg2_threshold_", None) or float("nan"))
        t0 = time.perf_counter()
        held_out = [bench.movements[i] for i in test]
        corpus = model.prepare(held_out, tune_seg2=False)
        seg_counts.extend(int(segs.shape[0]) for segs in corpus.segments)
        coverage.extend(segment_coverage(held_out, corpus.segments).tolist())
        seconds["segmentation"] += time.perf_counter() - t0

        t0 = time.perf_counter()
        if per_arm:
            # One-arm primitives learned from both arms of the training groups.
            model = PrimitiveModel(**model.get_params()).fit(
                split_arms([bench.movements[i] for i in train])
            )
            held_out = split_arms(held_out)
            corpus = model.prepare(held_out, tune_seg2=False)
        if corpus.segmentation.n_segments:
            vectors = model.vectorize(corpus).vectors
            # Directions: 3 channels per bone, so the RMS angle of a bone direction is
            # sqrt(MSE / (d / 3)); angles: the RMS of one angle sample, sqrt(MSE / d).
            per = 3 if getattr(model, "features", "zyz") == "directions" else 1
            dims[0] = int(vectors.shape[1]) // per
            train_p = np.ascontiguousarray(model.training_projections_)
            for k in RECONSTRUCTION_K:
                if k == model.n_primitives:
                    centers = model.cluster_centers_
                elif k <= train_p.shape[0]:
                    centers = np.asarray(
                        kernels.kmeans(train_p, k, n_init=1, seed=int(model.seed)).centers
                    )
                else:
                    continue
                sq[k] += _total_error_sq(model, vectors, centers, bool(model.amplitude))
                n_vec[k] += vectors.shape[0]
                if model.offsets == "mean":
                    sq_amp[k] += _total_error_sq(model, vectors, centers, True)
                    n_amp[k] += vectors.shape[0]
        for t, segs in zip(held_out, corpus.segments, strict=True):
            if segs.shape[0] == 0:
                continue
            try:
                _, rec, orig = model.reconstruct_movement(t, source="cluster", return_original=True)
            except ValueError:
                continue
            rms.append(direction_rms_deg(rec, orig))
        seconds["reconstruction"] += time.perf_counter() - t0

    per_group = {}
    for grp in order:
        m = g == grp
        per_group[grp] = (
            float(np.mean(pred[m] == y[m])),
            float(np.mean(base_pred[m] == y[m])),
            int(m.sum()),
        )
    cov = np.array([c for c in coverage if np.isfinite(c)])
    return BenchmarkResult(
        name=bench.name,
        group_by=bench.group_by,
        n_trials=len(y),
        classes=classes,
        left_out_classes=bench.left_out_classes,
        groups=order,
        accuracy=float(np.mean(pred == y)),
        baseline_accuracy=float(np.mean(base_pred == y)),
        per_group=per_group,
        confusion=_confusion(classes, y, pred),
        baseline_confusion=_confusion(classes, y, base_pred),
        segments_per_trial=float(np.mean(seg_counts)) if seg_counts else float("nan"),
        trials_without_segments=int(sum(c == 0 for c in seg_counts)),
        n_arm_trials=len(seg_counts),
        coverage_median=float(np.median(cov)) if cov.size else float("nan"),
        coverage_min=float(np.min(cov)) if cov.size else float("nan"),
        seg2_thresholds=thresholds,
        reconstruction_deg={
            k: angular_error_deg(sq[k] / n_vec[k], dims[0]) for k in RECONSTRUCTION_K if n_vec[k]
        },
        amplitude_deg={
            k: angular_error_deg(sq_amp[k] / n_amp[k], dims[0])
            for k in RECONSTRUCTION_K
            if n_amp[k]
        },
        movement_rms_deg=float(np.median(rms)) if rms else float("nan"),
        seconds=seconds,
        predictions=pred,
        baseline_predictions=base_pred,
        labels=y,
        group_values=g,
        names=[r.path.name for r in bench.recordings],
        reconstruction=(
            "one arm" if bench.movements[0].n_arms == 1 else reconstruction.replace("-", " ")
        ),
        label_sources=dict(Counter(r.label_source or "not recorded" for r in bench.recordings)),
    )


def make_benchmarks(
    recordings: Sequence[Recording],
    movements: Sequence[Trial],
    *,
    group_by: str | None = None,
    classes: Sequence[str] | None = None,
) -> tuple[list[Benchmark], list[str]]:
    """Benchmarks of labelled recordings (see the module docstring) and notes on what was
    left out."""
    notes: list[str] = []
    by_name: dict[str, list[int]] = {}
    for i, r in enumerate(recordings):
        by_name.setdefault(r.benchmark, []).append(i)
    benches = []
    for name, idx in by_name.items():
        recs = [recordings[i] for i in idx]
        if classes is not None:
            keep = [j for j, r in enumerate(recs) if r.label in set(classes)]
            idx = [idx[j] for j in keep]
            recs = [recs[j] for j in keep]
            if not recs:
                continue
        col = _choose_group(recs, group_by)
        groups_of: dict[str, set[str]] = {}
        for r in recs:
            groups_of.setdefault(r.label, set()).add(r.group(col))
        dropped = sorted(c for c, gs in groups_of.items() if len(gs) < 2)
        keep = [j for j, r in enumerate(recs) if r.label not in dropped]
        recs = [recs[j] for j in keep]
        idx = [idx[j] for j in keep]
        if dropped:
            notes.append(f"{name}: left out {', '.join(dropped)} (in fewer than two {col} groups)")
        labels = {r.label for r in recs}
        groups = {r.group(col) for r in recs}
        if len(labels) < 2 or len(groups) < 2:
            notes.append(
                f"{name}: skipped ({len(recs)} recordings, {len(labels)} class(es), "
                f"{len(groups)} {col} group(s): nothing to cross-validate)"
            )
            continue
        benches.append(Benchmark(name, recs, [movements[i] for i in idx], col, dropped))
    return benches, notes


def evaluate(
    sources: Iterable[str | os.PathLike[str]],
    *,
    labels: str | os.PathLike[str] | None = None,
    group_by: str | None = None,
    classes: Sequence[str] | None = None,
    classifier: MotionClassifier | None = None,
    period: float = DEFAULT_PERIOD,
    arm: str = "both",
    reconstruction: str = "each-arm",
    jobs: int | None = None,
    progress: bool | None = None,
) -> tuple[list[BenchmarkResult], list[str]]:
    """Run the benchmark on the labelled recordings under ``sources`` (module docstring).

    ``arm`` is the arm(s) read from each recording (:func:`read_movements`);
    ``reconstruction`` the primitives that rebuild two-arm movements
    (:func:`evaluate_benchmark`). Returns
    ``(one result per benchmark, notes)``; the notes say what was left out.
    """
    from tqdm.auto import tqdm

    from visprim.progress import _disable

    if reconstruction not in RECONSTRUCTIONS:
        raise ValueError(
            f"reconstruction must be one of {', '.join(RECONSTRUCTIONS)}, got {reconstruction!r}"
        )
    disable = _disable() if progress is None else not progress
    recordings, unlabelled = find_recordings(sources, labels)
    notes = []
    if unlabelled:
        notes.append(f"{len(unlabelled)} recording(s) without a label left out")
    if not recordings:
        raise ValueError("no labelled recordings found (labels.tsv beside the data, or --labels)")
    if classes is not None:
        recordings = [r for r in recordings if r.label in set(classes)]
        if not recordings:
            raise ValueError(f"no recording has one of the labels {', '.join(classes)}")
    with tqdm(total=len(recordings), desc="reading", unit="file", disable=disable) as bar:
        read_out, errors = read_movements(
            recordings, period=period, arm=arm, jobs=jobs, on_progress=bar.update
        )
    notes.extend(errors)
    recordings = [r for r, t in zip(recordings, read_out, strict=True) if t is not None]
    movements = [t for t in read_out if t is not None]
    benches, more = make_benchmarks(recordings, movements, group_by=group_by, classes=classes)
    notes.extend(more)
    n_folds = sum(len(set(b.groups.tolist())) for b in benches)
    results = []
    with tqdm(total=n_folds, desc="evaluating", unit="fold", disable=disable) as bar:

        def step(name: str) -> None:
            bar.set_postfix_str(name)

        for b in benches:
            results.append(
                evaluate_benchmark(
                    b, classifier=classifier, on_fold=step, reconstruction=reconstruction
                )
            )
            bar.update(len(set(b.groups.tolist())))
    return results, notes


# ------------------------------------------------------------------ reports


def _pct(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{100 * v:.1f} %"


def _deg(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{v:.1f}°"


def summary_rows(results: Sequence[BenchmarkResult]) -> list[dict[str, Any]]:
    """One row per benchmark: the figures of the markdown table (for the CSV)."""
    rows = []
    for r in results:
        c = [v * DEG2_PER_RAD2 for v in r.seg2_thresholds.values()]  # (deg/s)²
        rows.append(
            {
                "benchmark": r.name,
                "group_by": r.group_by,
                "trials": r.n_trials,
                "classes": len(r.classes),
                "groups": len(r.groups),
                "accuracy": round(r.accuracy, 4),
                "dtw_baseline_accuracy": round(r.baseline_accuracy, 4),
                "segments_per_arm_trial": round(r.segments_per_trial, 3),
                "arm_trials_without_segments": r.trials_without_segments,
                "arm_trials": r.n_arm_trials,
                "coverage_median": round(r.coverage_median, 4),
                "coverage_min": round(r.coverage_min, 4),
                "seg2_c_min_deg2_s2": round(float(np.nanmin(c)), 1) if c else "",
                "seg2_c_max_deg2_s2": round(float(np.nanmax(c)), 1) if c else "",
                **{
                    f"total_error_deg_k{k}": round(r.reconstruction_deg.get(k, float("nan")), 2)
                    for k in RECONSTRUCTION_K
                },
                **{
                    f"amplitude_error_deg_k{k}": round(r.amplitude_deg.get(k, float("nan")), 2)
                    for k in RECONSTRUCTION_K
                },
                "movement_rms_deg": round(r.movement_rms_deg, 2),
                "reconstruction": r.reconstruction,
                "seconds": round(sum(r.seconds.values()), 2),
            }
        )
    return rows


def to_markdown(results: Sequence[BenchmarkResult], notes: Sequence[str] = ()) -> str:
    """The report as markdown: a summary table, then per benchmark the folds and the
    confusion matrix."""
    out = ["# visprim evaluate", ""]
    out.append(
        "| benchmark | groups | trials | classes | MotionClassifier | DTW 1-NN baseline | "
        "segments / trial | no segment | coverage median (min) | SEG-2 c per fold | "
        + " | ".join(f"total error k={k}" for k in RECONSTRUCTION_K)
        + " | "
        + " | ".join(f"× amplitude k={k}" for k in RECONSTRUCTION_K)
        + " | movement RMS |"
    )
    out.append("|" + "---|" * (10 + 2 * len(RECONSTRUCTION_K) + 1))
    for r in results:
        cs = ", ".join(f"{v * DEG2_PER_RAD2:.4g}" for v in r.seg2_thresholds.values())
        out.append(
            f"| {r.name} | {len(r.groups)} {r.group_by} | {r.n_trials} | {len(r.classes)} | "
            f"**{r.accuracy:.3f}** | {r.baseline_accuracy:.3f} | {r.segments_per_trial:.2f} | "
            f"{r.trials_without_segments}/{r.n_arm_trials} | {_pct(r.coverage_median)} "
            f"({_pct(r.coverage_min)}) | {cs} (deg/s)² | "
            + " | ".join(_deg(r.reconstruction_deg.get(k, float("nan"))) for k in RECONSTRUCTION_K)
            + " | "
            + " | ".join(_deg(r.amplitude_deg.get(k, float("nan"))) for k in RECONSTRUCTION_K)
            + f" | {_deg(r.movement_rms_deg)} |"
        )
    out.append("")
    out.append(
        "Leave-one-group-out: each group is held out in turn; primitives, SEG-2 constant and "
        "classifier are learned from the other groups only. Accuracy: fraction of held-out "
        "trials labelled right. Coverage: fraction of moving frames (wrist faster than "
        f"{MOVING_SPEED} m/s relative to the shoulder) inside a segment. Total error: RMS "
        "angle error of each held-out segment rebuilt from its nearest primitive (per bone "
        "direction for direction features, per angle sample for Z-Y-Z angles); × amplitude: "
        "the same with each primitive scaled by the segment's least-squares gain (one more "
        "number per segment, PrimitiveModel(amplitude=True)); movement "
        "RMS: median over held-out trials of the RMS angle between the bone directions of "
        "the movement and of its rebuilding from its segments' primitives (k = 30)."
        + (
            " Two-arm movements: each arm segmented and rebuilt from one-arm primitives "
            "learned from both arms of the training groups (the left arm mirrored)."
            if any(r.reconstruction == "each arm" for r in results)
            else ""
        )
    )
    for r in results:
        out += ["", f"## {r.name}", ""]
        if r.label_sources:
            out.append(
                "Labels from "
                + "; ".join(f"{src} ({n} recordings)" for src, n in r.label_sources.items())
                + "."
            )
            out.append("")
        out.append(f"| {r.group_by} | trials | MotionClassifier | DTW baseline |")
        out.append("|---|---|---|---|")
        for grp, (a, b, n) in r.per_group.items():
            out.append(f"| {grp or '-'} | {n} | {a:.2f} | {b:.2f} |")
        out += [
            "",
            "Confusion matrix of the MotionClassifier (rows: truth, columns: predicted):",
            "",
        ]
        short = [f"c{i}" for i in range(len(r.classes))]
        out.append("| truth \\ predicted | " + " | ".join(short) + " |")
        out.append("|---|" + "---|" * len(short))
        for i, c in enumerate(r.classes):
            out.append(f"| c{i} {c} | " + " | ".join(str(int(v)) for v in r.confusion[i]) + " |")
        if r.left_out_classes:
            out.append("")
            out.append(f"Left out (in fewer than two groups): {', '.join(r.left_out_classes)}")
    if notes:
        out += ["", "## Notes", ""] + [f"- {n}" for n in notes]
    return "\n".join(out) + "\n"


def to_html(markdown: str, figures: Mapping[str, Sequence[tuple[str, str]]] | None = None) -> str:
    """A self-contained HTML page of the markdown report (:func:`visprim.report.html.
    markdown_to_html`), styled like the ``visprim report`` page; wide tables scroll
    sideways. ``figures`` maps a benchmark's name to ``(image src, caption)`` pairs shown at
    the end of its section."""
    from visprim.report.html import CSS, figure, markdown_to_html

    figures = figures or {}
    body: list[str] = []
    section: str | None = None
    lines: list[str] = []

    def close_section() -> None:
        body.append(markdown_to_html("\n".join(lines)))
        lines.clear()
        for src, caption in figures.get(section or "", ()):
            body.append(figure(src, caption))

    for line in markdown.splitlines():
        if line.startswith("## "):
            close_section()
            section = line[3:].strip()
        lines.append(line)
    close_section()
    return (
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        "<title>visprim evaluate</title>"
        f"<style>{CSS}</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n"
    )


def write_report(
    results: Sequence[BenchmarkResult], notes: Sequence[str], out_dir: str | os.PathLike[str]
) -> dict[str, Path]:
    """Write ``evaluate.md``, ``summary.csv``, ``predictions.csv`` and ``evaluate.html``
    into ``out_dir``, each atomically. Returns the paths by kind."""
    out = Path(out_dir)
    md = to_markdown(results, notes)
    rows = summary_rows(results)
    buf = io.StringIO()
    if rows:
        w = csvfile.writer(buf)
        w.writerow(list(rows[0]))
        w.writerows([row.get(k, "") for k in rows[0]] for row in rows)
    pbuf = io.StringIO()
    pw = csvfile.writer(pbuf)
    pw.writerow(["benchmark", "file", "label", "group", "predicted", "dtw_baseline_predicted"])
    for r in results:
        for name, lab, grp, p, b in zip(
            r.names, r.labels, r.group_values, r.predictions, r.baseline_predictions, strict=True
        ):
            pw.writerow([r.name, name, lab, grp, p, b])
    paths = {
        "markdown": out / "evaluate.md",
        "summary": out / "summary.csv",
        "predictions": out / "predictions.csv",
        "html": out / "evaluate.html",
    }
    write_text(paths["markdown"], md, newline="")
    write_text(paths["summary"], buf.getvalue(), newline="")
    write_text(paths["predictions"], pbuf.getvalue(), newline="")
    shown: dict[str, list[tuple[str, str]]] = {}
    for bench, kind, path, caption in _write_figures(results, out):
        paths[f"{kind} {bench}"] = path
        shown.setdefault(bench, []).append((path.name, caption))
    write_text(paths["html"], to_html(md, shown), newline="")
    return paths


def _write_figures(
    results: Sequence[BenchmarkResult], out: Path
) -> list[tuple[str, str, Path, str]]:
    """Per benchmark, the confusion matrix and the per-group accuracy as PNGs (each written
    atomically): ``(benchmark, kind, path, caption)``."""
    from visprim.report import figures
    from visprim.report.html import slug

    drawn: list[tuple[str, str, Path, str]] = []
    for r in results:
        name = slug(r.name)
        cm = figures.confusion_figure(
            r.classes,
            r.confusion,
            f"{r.name}: MotionClassifier, held-out {r.group_by} "
            f"(accuracy {r.accuracy:.3f}, {r.n_trials} trials)",
        )
        groups = figures.group_accuracy_figure(
            r.per_group, r.group_by, f"{r.name}: accuracy on each held-out {r.group_by}"
        )
        for kind, fig, caption in (
            (
                "confusion",
                cm,
                "Confusion matrix of the MotionClassifier on the held-out groups (rows: true "
                "class, columns: predicted; counts, shaded by the fraction of the true class).",
            ),
            (
                "groups",
                groups,
                f"Accuracy on each held-out {r.group_by}, MotionClassifier beside the DTW "
                "1-NN baseline (trials per group under the names).",
            ),
        ):
            path = out / f"{kind}_{name}.png"
            with atomic_file(path) as tmp:
                figures.save_figure(fig, tmp)
            drawn.append((r.name, kind, path, caption))
    return drawn
