"""The leave-one-group-out rate–distortion benchmark: held-out movements, their segments,
every description scored (:func:`evaluate_rate`, :func:`rate_benchmark`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.params import RATE_OPTIONS
from visprim.rate.descriptions import (
    BASELINE_RATES,
    EIGEN_FAMILIES,
    FAMILIES,
    POSTURES,
    RATE_K,
    RATE_M,
    RATE_Q,
    RESIDUAL_K,
    Codebook,
    bridge_lines,
    eigen_describe,
    eigen_rates,
    fit_codebook,
    fit_eigen_movements,
    movement_numbers,
    rebuild_segments,
    unit_bones,
    unit_posture,
)
from visprim.rate.measures import bone_rms_deg, dct_rebuild, joint_rms_deg, keyframe_rebuild
from visprim.trial import Trial, split_arms

# ---------------------------------------------------------------------------- movements


@dataclass
class HeldOut:
    """One held-out one-arm movement over the span its segments cover.

    ``times`` (T,) s, ``directions`` (T, 6) and ``angles`` (T, 4) rad: the low-passed
    movement; ``segments`` (N, 2) s; ``rows``: its segments' rows in the fold's vectors."""

    name: str
    group: str
    times: NDArray[np.float64]
    directions: NDArray[np.float64]
    angles: NDArray[np.float64]
    segments: NDArray[np.float64]
    rows: NDArray[np.int64]
    rotations: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        from visprim.arm import shoulder_rotation

        self.rotations = shoulder_rotation(self.angles)

    @property
    def seconds(self) -> float:
        return float(self.segments[-1, 1] - self.segments[0, 0])


def on_clock(
    curves: NDArray[np.float64], segments: NDArray[np.float64], times: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Segment curves ``(N, n, C)`` stretched onto their segments ``(N, 2)`` s and read at
    ``times`` (T,) s; frames between segments are interpolated linearly."""
    from visprim.vectors import stretch

    out = np.full((times.size, curves.shape[2]), np.nan)
    for (start, end), curve in zip(segments, curves, strict=True):
        rows = (times >= start - 1e-9) & (times <= end + 1e-9)
        if rows.any():
            out[rows] = stretch(curve, start, end, np.clip(times[rows], start, end))
    gap = np.isnan(out[:, 0])
    if gap.any() and not gap.all():
        for j in range(out.shape[1]):
            out[gap, j] = np.interp(times[gap], times[~gap], out[~gap, j])
    return out


def split_long(segments: NDArray[np.float64], max_stroke: float | None) -> NDArray[np.float64]:
    """Segments ``(N, 2)`` s with every one longer than ``max_stroke`` seconds cut into the
    fewest equal parts no longer than that (unchanged for ``None``)."""
    if max_stroke is None or segments.shape[0] == 0:
        return segments
    out: list[tuple[float, float]] = []
    for start, end in segments:
        parts = max(1, int(np.ceil((end - start) / max_stroke - 1e-9)))
        edges = np.linspace(start, end, parts + 1)
        out.extend(zip(edges[:-1], edges[1:], strict=True))
    return np.asarray(out, dtype=np.float64)


def _corpus_vectors(
    corpus: Any, n_samples: int, max_stroke: float | None
) -> tuple[Any, list[NDArray[np.float64]]]:
    """Posture-relative segment vectors (:class:`visprim.vectors.SegmentVectors`, the
    postures in ``offsets``) of a prepared corpus with its long segments cut
    (:func:`split_long`), and the segments of each trial (None when there is none)."""
    from visprim.features import periodic_channels
    from visprim.vectors import time_to_frame, vectors_from_frames

    segs = [split_long(s, max_stroke) for s in corpus.segments]
    keep = [i for i, s in enumerate(segs) if s.shape[0]]
    if not keep:
        return None, segs
    frames = [time_to_frame(corpus.times[i], segs[i]) + corpus.offsets[i] for i in keep]
    f = np.concatenate(frames)
    sv = vectors_from_frames(
        corpus.values,
        f[:, 0],
        f[:, 1],
        trial=np.concatenate([np.full(segs[i].shape[0], i) for i in keep]),
        starts=np.concatenate([segs[i][:, 0] for i in keep]),
        ends=np.concatenate([segs[i][:, 1] for i in keep]),
        n_samples=n_samples,
        periodic_channels=periodic_channels(corpus.features, len(corpus.arms)),
        offsets="mean",
    )
    return sv, segs


# ---------------------------------------------------------------------------- benchmark


@dataclass
class RateResult:
    """Per held-out movement and description: numbers, seconds and errors (``rows``)."""

    benchmark: str
    group_by: str
    groups: list[str]
    rows: list[dict[str, Any]] = field(default_factory=list)
    options: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> list[dict[str, Any]]:
        """One row per description: the rate (all numbers over all seconds), the median
        over held-out movements of the bone-direction and joint-space RMS (degrees), and the
        lowest and highest per-group median of the bone-direction RMS."""
        keys = list(dict.fromkeys((r["family"], r["param"]) for r in self.rows))
        out = []
        for fam, param in keys:
            rs = [r for r in self.rows if r["family"] == fam and r["param"] == param]
            head = {"benchmark": self.benchmark, "family": fam, "param": param}
            out.append({**head, **summarise_rows(rs, self.groups)})
        return out


def summarise_rows(rows: Sequence[dict[str, Any]], groups: Sequence[Any]) -> dict[str, Any]:
    """Of the scored movements ``rows`` of one description: the rate (all numbers over all
    seconds), the median bone-direction and joint-space RMS (degrees), the lowest and
    highest per-group median of the bone-direction RMS, and how many movements."""
    per_group = [
        float(np.median([r["bone_deg"] for r in rows if r["group"] == g]))
        for g in groups
        if any(r["group"] == g for r in rows)
    ]
    return {
        "numbers_per_s": sum(r["numbers"] for r in rows) / sum(r["seconds"] for r in rows),
        "bone_deg_median": float(np.median([r["bone_deg"] for r in rows])),
        "bone_deg_group_min": min(per_group),
        "bone_deg_group_max": max(per_group),
        "joint_deg_median": float(np.median([r["joint_deg"] for r in rows])),
        "movements": len(rows),
    }


def _score(
    rows: list[dict[str, Any]],
    mv: HeldOut,
    family: str,
    param: Any,
    numbers: int,
    directions: NDArray[np.float64] | None = None,
    angles: NDArray[np.float64] | None = None,
    joint: bool = True,
) -> None:
    from visprim.features import from_angles, to_angles

    if directions is None:
        assert angles is not None
        directions = from_angles(angles, "directions")
    if angles is None and joint:
        angles = to_angles(directions, "directions", mv.times)
    rows.append(
        {
            "group": mv.group,
            "movement": mv.name,
            "family": family,
            "param": param,
            "numbers": int(numbers),
            "seconds": mv.seconds,
            "bone_deg": bone_rms_deg(directions, mv.directions),
            "joint_deg": (
                joint_rms_deg(angles, mv.angles, mv.rotations) if angles is not None else np.nan
            ),
        }
    )


def _prepare(
    train: Sequence[Trial], test: Sequence[Trial], params: dict[str, Any]
) -> tuple[Any, Any, Any]:
    """The segmenting model, the training corpus (SEG-2 constant tuned on it) and the
    held-out corpus (segmented with that constant) of one fold."""
    from visprim.model import PrimitiveModel

    params = {**params, "offsets": "mean", "features": "directions"}
    seg_model = PrimitiveModel(**params)
    train_corpus = seg_model.prepare(list(train), tune_seg2=True, segmentation="seg2")
    test_model = PrimitiveModel(**{**params, "seg2_threshold": train_corpus.seg2_threshold})
    corpus = test_model.prepare(list(test), tune_seg2=False, segmentation="seg2")
    return seg_model, train_corpus, corpus


def held_out_movements(
    corpus: Any, group: str, segs: Sequence[NDArray[np.float64]]
) -> list[HeldOut]:
    """The held-out movements of a prepared ``corpus`` over the span their segments
    ``segs`` (one ``(N, 2)`` array per trial) cover; trials without a segment are left out,
    and each movement's ``rows`` index its segments in the order of ``segs``."""
    per_trial = np.split(corpus.values, corpus.offsets[1:])
    movements: list[HeldOut] = []
    row = 0
    for i, s in enumerate(segs):
        if s.shape[0] == 0:
            continue
        t = corpus.times[i]
        span = (t >= s[0, 0] - 1e-9) & (t <= s[-1, 1] + 1e-9)
        movements.append(
            HeldOut(
                corpus.names[i],
                group,
                t[span],
                per_trial[i][span],
                corpus.angles[i][span],
                s,
                np.arange(row, row + s.shape[0]),
            )
        )
        row += s.shape[0]
    return movements


def _fold(
    train: Sequence[Trial],
    test: Sequence[Trial],
    group: str,
    params: dict[str, Any],
    families: Sequence[str],
    *,
    centres: str,
    max_stroke: float | None,
    rows: list[dict[str, Any]],
    posture_mode: str = "mean",
    prepared: dict[str, Any] | None = None,
    joint: bool = True,
) -> None:
    """Score ``families`` on the held-out ``test`` trials of ``group`` with everything
    learned from ``train``, appending to ``rows``. ``prepared`` (a dict kept by the caller)
    caches the SEG-2-segmented corpora of this fold under ``group``: the settings tried on
    one fold (posture, max stroke) share them. ``joint=False`` leaves the joint-space error
    out (NaN) of the primitive descriptions' rows: the nested search scores only bone
    directions."""
    from visprim.vectors import to_curves, to_vectors

    cached = None if prepared is None else prepared.get(group)
    if cached is None:
        cached = _prepare(train, test, params)
        if prepared is not None:
            prepared[group] = cached
    seg_model, train_corpus, corpus = cached
    n = int(seg_model.n_samples)
    train_sv, _ = _corpus_vectors(train_corpus, n, max_stroke)
    if train_sv is None:
        raise ValueError(f"held-out group {group!r}: no SEG-2 segment in the training groups")
    sv, segs = _corpus_vectors(corpus, n, max_stroke)
    if sv is None:
        return
    x, posture = sv.vectors, sv.offsets
    ks = sorted(set(RATE_K) | {RESIDUAL_K})
    book = fit_codebook(
        train_sv.vectors,
        ks,
        n_components=int(seg_model.n_components),
        centres=centres,
        n_init=3,
        seed=int(seg_model.seed),
    )
    c = posture.shape[1]
    movements = held_out_movements(corpus, group, segs)
    # Bridges: each segment's shape less the line between its end postures (unit bone
    # directions, what is stored), rebuilt from primitives of such shapes.
    absolute = to_curves(x, c) + posture[:, None, :]
    lines = bridge_lines(absolute, (unit_bones(absolute[:, 0, :]), unit_bones(absolute[:, -1, :])))
    bridge: tuple[Codebook, NDArray[np.float64]] | None = None
    for family in families:
        if bridge is None and family.startswith("bridge"):
            bridge = (
                _bridge_codebook(train_sv, c, ks, seg_model, centres),
                to_vectors(absolute - lines),
            )
        if family.startswith(("keyframes", "dct")):
            for rate in BASELINE_RATES:
                for mv in movements:
                    _baseline(rows, mv, family, float(rate))
            continue
        if family in EIGEN_FAMILIES:
            key = f"{group}|eigen-movements"
            eigen = None if prepared is None else prepared.get(key)
            if eigen is None:
                eigen = _eigen_book(train_corpus)
                if prepared is not None:
                    prepared[key] = eigen
            # The whole-movement codes do not depend on the segment settings (posture,
            # max stroke): the settings tried on one fold share their rows.
            rows_key = f"{group}|rows|{family}"
            cached_rows = None if prepared is None else prepared.get(rows_key)
            if cached_rows is None:
                cached_rows = []
                for rate in eigen_rates(family):
                    for mv in movements:
                        _eigen_row(cached_rows, mv, eigen, family, float(rate), joint)
                if prepared is not None:
                    prepared[rows_key] = cached_rows
            rows.extend(dict(r) for r in cached_rows)
            continue
        # m up to f, and f itself: the per-segment projection.
        m_values = tuple(sorted({m for m in RATE_M if m < book.n_components} | {book.n_components}))
        params_of = {
            "nearest": RATE_K,
            "nearest+gain": RATE_K,
            "warp": RATE_K,
            "residual": m_values,
            "nearest+dct": RATE_Q,
            "projection": m_values,
            "bridge": RATE_K,
            "bridge+gain": RATE_K,
            "bridge+residual": m_values,
        }[family]
        bridged = family.startswith("bridge")
        if family in ("residual", "nearest+dct") and not book.centers:
            continue  # fewer training segments than the fewest primitives
        centers = bridge[0].centers if bridged and bridge is not None else book.centers
        for p in params_of:
            if (
                family not in ("residual", "projection", "bridge+residual", "nearest+dct")
                and p not in centers
            ):
                continue
            inner = _BRIDGE_INNER.get(family, family)
            if bridged and bridge is not None:
                rebuilt = rebuild_segments(bridge[0], bridge[1], c, inner, p)
                curves = to_curves(rebuilt, c) + lines
            else:
                rebuilt = rebuild_segments(book, x, c, family, p)
                shapes = to_curves(rebuilt, c)
                curves = shapes + (
                    posture[:, None, :]
                    if posture_mode == "mean"
                    else unit_posture(unit_bones(posture), shapes)[:, None, :]
                )
            for mv in movements:
                values = on_clock(curves[mv.rows], mv.segments, mv.times)
                n_post = c if bridged or posture_mode == "mean" else c // 3 * 2
                numbers = (
                    movement_numbers(family, mv.segments.shape[0], n_post, q=p)
                    if family == "nearest+dct"
                    else movement_numbers(family, mv.segments.shape[0], n_post, p)
                )
                _score(rows, mv, family, p, numbers, directions=values, joint=joint)


#: The primitive description that rebuilds a bridge's shape.
_BRIDGE_INNER = {"bridge": "nearest", "bridge+gain": "nearest+gain", "bridge+residual": "residual"}


def _bridge_codebook(
    train_sv: Any, c: int, ks: Sequence[int], seg_model: Any, centres: str
) -> Codebook:
    """The codebook of the training segments' shapes less their end-to-end lines."""
    from visprim.vectors import to_curves, to_vectors

    absolute = to_curves(train_sv.vectors, c) + train_sv.offsets[:, None, :]
    return fit_codebook(
        to_vectors(absolute - bridge_lines(absolute, None)),
        ks,
        n_components=int(seg_model.n_components),
        centres=centres,
        n_init=3,
        seed=int(seg_model.seed),
    )


def _eigen_book(train_corpus: Any) -> Any:
    """The eigen-movements of a fold's training movements, over the spans their segments
    cover (as the held-out movements are), with the DCT channel order at every baseline
    rate."""
    train = held_out_movements(train_corpus, "train", list(train_corpus.segments))
    return fit_eigen_movements(
        [mv.directions for mv in train],
        [mv.angles for mv in train],
        [mv.seconds for mv in train],
        BASELINE_RATES,
    )


def _eigen_row(
    rows: list[dict[str, Any]], mv: HeldOut, book: Any, family: str, rate: float, joint: bool
) -> None:
    """Score one held-out movement described whole by an eigen-movement ``family`` within
    ``rate`` numbers per second (:func:`~visprim.rate.descriptions.eigen_describe`); the
    row's ``code`` says which code the encoder used."""
    code, rebuilt, numbers = eigen_describe(
        book, family, rate, mv.seconds, mv.directions, mv.angles
    )
    if code == "dct":
        _score(rows, mv, family, rate, numbers, angles=rebuilt)
    else:
        _score(rows, mv, family, rate, numbers, directions=rebuilt, joint=joint)
    rows[-1]["code"] = code


def _baseline(rows: list[dict[str, Any]], mv: HeldOut, family: str, rate: float) -> None:
    """Score one baseline ``family`` (``keyframes-…``, ``dct-…``, ``dct-angles-fit``) on
    one held-out movement at ``rate``: its count per channel rounded from the rate."""
    from visprim.rate.descriptions import fit_dct_coefficients

    kind, channels, *fit = family.split("-")
    signal = mv.angles if channels == "angles" else mv.directions
    c = signal.shape[1]
    count = max(2, int(round((rate * mv.seconds - 2.0) / c)))
    count = min(count, signal.shape[0])
    if fit:
        counts = np.full(c, count, dtype=np.int64)
        rebuilt, _ = fit_dct_coefficients(signal, mv.directions, counts)
    elif kind == "keyframes":
        rebuilt = keyframe_rebuild(signal, count)
    else:
        rebuilt = dct_rebuild(signal, count)
    numbers = 2 + c * count
    if channels == "angles":
        _score(rows, mv, family, rate, numbers, angles=rebuilt)
    else:
        _score(rows, mv, family, rate, numbers, directions=rebuilt)


def evaluate_rate(
    bench: Any,
    *,
    families: Sequence[str] = FAMILIES,
    centres: str = RATE_OPTIONS["centres"].default,
    max_stroke: float | None = RATE_OPTIONS["max_stroke"].default,
    posture: str = RATE_OPTIONS["posture"].default,
    model_params: dict[str, Any] | None = None,
    on_fold: Callable[[str], None] | None = None,
) -> RateResult:
    """Leave-one-group-out rate–distortion of one :class:`visprim.evaluate.Benchmark`
    (module docstring). ``model_params`` are :class:`~visprim.model.PrimitiveModel`
    parameters (filtering, segmentation, n_samples, n_components, seed; the vectors are
    always posture-relative bone directions)."""
    if posture not in POSTURES:
        raise ValueError(f"posture must be one of {list(POSTURES)}, got {posture!r}")
    bad = [f for f in families if f not in FAMILIES]
    if bad:
        raise ValueError(f"unknown description(s) {bad}; choose from {list(FAMILIES)}")
    groups = bench.groups
    order = list(dict.fromkeys(groups.tolist()))
    result = RateResult(
        bench.name,
        bench.group_by,
        order,
        options={"centres": centres, "max_stroke": max_stroke, "posture": posture},
    )
    for group in order:
        if on_fold:
            on_fold(f"{bench.name}: {bench.group_by} {group or '-'}")
        train = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g != group])
        test = split_arms([m for m, g in zip(bench.movements, groups, strict=True) if g == group])
        _fold(
            train,
            test,
            str(group),
            dict(model_params or {}),
            families,
            centres=centres,
            max_stroke=max_stroke,
            rows=result.rows,
            posture_mode=posture,
        )
    return result


def read_benchmarks(
    sources: Iterable[str | os.PathLike[str]],
    labels: str | os.PathLike[str] | None,
    group_by: str | None,
    period: float,
    jobs: int | None,
    disable: bool,
) -> list[Any]:
    """The :class:`visprim.evaluate.Benchmark` s found under ``sources`` (as ``visprim
    evaluate`` finds them, :func:`visprim.evaluate.find_recordings`), read with a progress
    bar unless ``disable``."""
    from tqdm.auto import tqdm

    from visprim.evaluate import find_recordings, make_benchmarks, read_movements

    recordings, _ = find_recordings(sources, labels)
    if not recordings:
        raise ValueError("no labelled recordings found (labels.tsv beside the data, or --labels)")
    with tqdm(total=len(recordings), desc="reading", unit="file", disable=disable) as bar:
        read_out, _ = read_movements(recordings, period=period, jobs=jobs, on_progress=bar.update)
    recordings = [r for r, t in zip(recordings, read_out, strict=True) if t is not None]
    movements = [t for t in read_out if t is not None]
    benches, _ = make_benchmarks(recordings, movements, group_by=group_by)
    return list(benches)


def rate_benchmark(
    sources: Iterable[str | os.PathLike[str]],
    *,
    labels: str | os.PathLike[str] | None = None,
    group_by: str | None = None,
    period: float = 0.034,
    families: Sequence[str] = FAMILIES,
    centres: str = RATE_OPTIONS["centres"].default,
    max_stroke: float | None = RATE_OPTIONS["max_stroke"].default,
    posture: str = RATE_OPTIONS["posture"].default,
    jobs: int | None = None,
    progress: bool | None = None,
) -> list[RateResult]:
    """:func:`evaluate_rate` on every benchmark found under ``sources`` (as
    ``visprim evaluate`` finds them, :func:`visprim.evaluate.find_recordings`)."""
    from tqdm.auto import tqdm

    from visprim.progress import _disable

    disable = bool(_disable()) if progress is None else not progress
    benches = read_benchmarks(sources, labels, group_by, period, jobs, disable)
    n_folds = sum(len(set(b.groups.tolist())) for b in benches)
    out = []
    with tqdm(total=n_folds, desc="rate-distortion", unit="fold", disable=disable) as bar:

        def step(name: str) -> None:
            bar.set_postfix_str(name)
            bar.update(1)

        for b in benches:
            out.append(
                evaluate_rate(
                    b,
                    families=families,
                    centres=centres,
                    max_stroke=max_stroke,
                    posture=posture,
                    on_fold=step,
                )
            )
    return out
