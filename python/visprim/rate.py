"""Rate–distortion of movement descriptions (``visprim evaluate --rate``).

How well is a movement that the primitives have never seen rebuilt, and how many numbers
does its description need? Every description below is measured on held-out groups (leave
one group out: each group, e.g. an HDM05 actor, is held out in turn and everything is
learned from the others) by

* its **rate**: the numbers it stores per second of movement, counted honestly: per
  segment a primitive id, a duration and the segment's mean posture (one number per channel,
  6 for one arm's two bone directions), plus whatever the description adds (a gain, residual
  or projection coefficients, warp numbers); per movement its start time. Baselines store
  their samples or coefficients per channel plus the movement's start and duration;
* its **distortion**: the RMS angle, degrees, between the bone directions (upper arm and
  forearm) of the whole held-out movement and of its rebuilding (:func:`bone_rms_deg`), and
  the joint-space RMS (shoulder geodesic angle and elbow, as ``visprim imitate`` reports);
  the median over held-out movements, with the spread of the per-group medians.

Two-arm recordings are cut into one-arm movements (:func:`visprim.trial.split_arms`, the left
arm mirrored) and the one-arm primitives are learned from both arms of the training groups.
Each movement is segmented with SEG-2 (the constant tuned on the training groups) and every
segment is rebuilt by a description (:data:`FAMILIES`):

``nearest``
    the nearest of k primitives, placed at the segment's mean posture and stretched to its
    duration (k in :data:`RATE_K`); ``nearest+gain`` also scales it by its least-squares
    amplitude (:func:`visprim.vectors.amplitude_gains`, one more number).
``residual``
    the nearest primitive plus the segment's first m coefficients along the eigen-primitives,
    taken relative to the centre (m numbers more): with m = f this *is* the projection.
``projection``
    the segment's own first m PCA coefficients (no primitive id).
``warp``
    the nearest primitive with its gain and a monotone time warp inside the segment,
    ``u → u + w u (1 − u)``, ``|w| < 1``, one number (:func:`warp_curves`), the primitive and
    warp chosen together among the nearest few primitives.
``keyframes``, ``dct``
    baselines on the same movements: each channel (the 4 arm angles, or the 6 bone-direction
    coordinates) sampled at equally spaced instants and joined by a cubic spline, or its
    first DCT-II coefficients, at the rates :data:`BASELINE_RATES`.

Primitive centres are either the k-means centres in the f-D projection space (the paper
and :class:`~visprim.model.PrimitiveModel`, ``centres="projection"``, the default) or the
means of the members' full segment vectors (``centres="members"``, which keep what the f
eigenvectors drop); on HDM05 (leave one actor out) both rebuild within 0.2° of each other at
every k, so the default stays the model's own. A segment's posture is stored as each
channel's mean (``posture="mean"``, 6 numbers per arm) or as the two unit bone directions
of that mean (``posture="unit"``, 4 numbers, :func:`unit_posture`).
``max_stroke`` (seconds, default none) cuts every segment longer than that into equal parts,
in training and held-out movements alike.

Everything here is plain NumPy on a few hundred segments; the fits take well under a second
per fold.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim.trial import Trial, split_arms

__all__ = [
    "BASELINE_RATES",
    "FAMILIES",
    "RATE_K",
    "RATE_M",
    "Codebook",
    "RateResult",
    "bone_rms_deg",
    "dct_rebuild",
    "evaluate_rate",
    "keyframe_rebuild",
    "rate_benchmark",
    "rate_markdown",
    "segment_numbers",
    "warp_curves",
    "write_rate_report",
]

#: Primitive counts k of the ``nearest`` descriptions.
RATE_K: tuple[int, ...] = (10, 20, 30, 50, 100, 200, 300)
#: Coefficient counts m of the ``residual`` and ``projection`` descriptions (capped at f).
RATE_M: tuple[int, ...] = (1, 2, 3, 4, 6, 8, 12, 16, 20, 30)
#: Rates (numbers per second of movement) of the keyframe and DCT baselines.
BASELINE_RATES: tuple[float, ...] = (4, 6, 8, 10, 12, 16, 20, 30, 40, 60)
#: The descriptions measured (module docstring).
FAMILIES: tuple[str, ...] = (
    "nearest",
    "nearest+gain",
    "residual",
    "projection",
    "warp",
    "bridge",
    "bridge+gain",
    "bridge+residual",
    "keyframes-angles",
    "keyframes-directions",
    "dct-angles",
    "dct-directions",
)
#: Where primitive centres live: the k-means centres in the projection space (the paper),
#: or the means of the members' whole segment vectors.
CENTRES: tuple[str, ...] = ("projection", "members")
#: How a segment's posture is stored: each channel's mean (6 numbers per arm), or the two
#: bone directions of that mean as unit vectors (4 numbers; :func:`unit_posture`).
POSTURES: tuple[str, ...] = ("mean", "unit")
#: Warp values tried per segment (``u → u + w u (1 − u)``).
WARP_GRID: NDArray[np.float64] = np.linspace(-0.8, 0.8, 9)
#: Nearest primitives among which the warped primitive is chosen.
WARP_CANDIDATES = 5
#: k of the residual descriptions (the model's default number of primitives).
RESIDUAL_K = 30


# ---------------------------------------------------------------------------- counting


def segment_numbers(family: str, n_channels: int, m: int = 0) -> int:
    """Numbers stored per segment by a primitive description of ``family``: the primitive
    id, the duration and ``n_channels`` posture numbers, plus a gain (``nearest+gain``),
    ``m`` coefficients (``residual``), or a gain and one warp number (``warp``);
    ``projection`` stores ``m`` coefficients, the duration and the posture (no id).
    ``bridge`` descriptions store no posture per segment (their boundary postures are
    counted by :func:`movement_numbers`): the id and duration, plus a gain or ``m``
    coefficients."""
    base = 2 + int(n_channels)
    if family == "nearest":
        return base
    if family == "nearest+gain":
        return base + 1
    if family == "residual":
        return base + int(m)
    if family == "warp":
        return base + 2
    if family == "projection":
        return 1 + int(n_channels) + int(m)
    if family == "bridge":
        return 2
    if family == "bridge+gain":
        return 3
    if family == "bridge+residual":
        return 2 + int(m)
    raise ValueError(f"segment_numbers: unknown family {family!r}")


#: Numbers of one boundary posture of the bridge descriptions: two unit bone directions.
BOUNDARY_NUMBERS = 4


def movement_numbers(family: str, n_segments: int, n_channels: int, m: int = 0) -> int:
    """All the numbers of one movement of ``n_segments`` consecutive segments: its start
    time, each segment's numbers (:func:`segment_numbers`) and, for the ``bridge``
    descriptions, the posture at each of the ``n_segments + 1`` boundaries (two unit bone
    directions, :data:`BOUNDARY_NUMBERS`)."""
    total = 1 + int(n_segments) * segment_numbers(family, n_channels, m)
    if family.startswith("bridge"):
        total += BOUNDARY_NUMBERS * (int(n_segments) + 1)
    return total


def bridge_lines(
    curves: NDArray[np.float64], ends: tuple[NDArray[np.float64], NDArray[np.float64]] | None
) -> NDArray[np.float64]:
    """Straight lines ``(N, n, C)`` from each segment's first to its last posture: those of
    ``curves`` ``(N, n, C)``, or the given ``ends`` ``((N, C), (N, C))``."""
    first, last = (curves[:, 0, :], curves[:, -1, :]) if ends is None else ends
    u = np.linspace(0.0, 1.0, curves.shape[1])[None, :, None]
    return np.asarray(first[:, None, :] * (1.0 - u) + last[:, None, :] * u)


def unit_posture(
    directions: NDArray[np.float64], shapes: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Posture offsets ``(N, C)`` rebuilt from the unit bone directions ``(N, C)`` of each
    segment's mean posture and its rebuilt zero-mean shape ``(N, n, C)``: each bone's
    direction scaled by ``sqrt(1 − mean |shape|²)``, the length that makes the mean squared
    length of ``offset + shape`` one, as it is for the unit bones of a movement."""
    n, _, c = shapes.shape
    sq = np.mean(np.sum(shapes.reshape(n, -1, c // 3, 3) ** 2, axis=3), axis=1)  # (N, bones)
    scale = np.sqrt(np.clip(1.0 - sq, 0.0, 1.0))
    return np.asarray((directions.reshape(n, -1, 3) * scale[:, :, None]).reshape(n, c))


def unit_bones(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(..., 6 n_arms)`` bone directions scaled to unit length per bone."""
    v = values.reshape(*values.shape[:-1], -1, 3)
    return np.asarray(v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)).reshape(
        values.shape
    )


# ---------------------------------------------------------------------------- errors


def bone_rms_deg(values: ArrayLike, reference: ArrayLike) -> float:
    """RMS angle in degrees between the bones of two ``(T, 6 n_arms)`` bone-direction
    arrays (upper arm then forearm per arm; rows need not be unit vectors), over every frame
    and bone."""
    a = np.asarray(values, dtype=np.float64).reshape(len(values), -1, 3)  # type: ignore[arg-type]
    b = np.asarray(reference, dtype=np.float64).reshape(a.shape)
    na = np.linalg.norm(a, axis=2)
    nb = np.linalg.norm(b, axis=2)
    cos = np.sum(a * b, axis=2) / np.maximum(na * nb, 1e-12)
    return float(np.degrees(np.sqrt(np.mean(np.arccos(np.clip(cos, -1.0, 1.0)) ** 2))))


def joint_rms_deg(
    angles: NDArray[np.float64],
    reference: NDArray[np.float64],
    reference_rotations: NDArray[np.float64] | None = None,
) -> float:
    """Joint-space RMS, degrees, over the shoulder's geodesic angles and the elbow
    differences of two ``(T, 4)`` one-arm angle arrays (what ``visprim imitate`` reports);
    ``reference_rotations`` (T, 3, 3) are ``shoulder_rotation(reference)`` if known."""
    from visprim.arm import shoulder_rotation

    ra = shoulder_rotation(angles)
    rb = shoulder_rotation(reference) if reference_rotations is None else reference_rotations
    # The rotation between two orientations turns by arccos((tr(Raᵀ Rb) − 1) / 2).
    cos = (np.einsum("tij,tij->t", ra, rb) - 1.0) / 2.0
    shoulder = np.arccos(np.clip(cos, -1.0, 1.0))
    elbow = angles[:, 3] - reference[:, 3]
    return float(np.degrees(np.sqrt(np.mean(np.concatenate([shoulder, elbow]) ** 2))))


# ---------------------------------------------------------------------------- baselines


def keyframe_rebuild(values: ArrayLike, n_keys: int) -> NDArray[np.float64]:
    """Each channel of ``values`` ``(T, C)`` sampled at ``n_keys`` equally spaced instants
    (from the first frame to the last, linear interpolation between frames) and joined
    again by a cubic interpolating spline (not-a-knot; a line for two keys, a parabola
    for three)."""
    from scipy.interpolate import make_interp_spline

    v = np.asarray(values, dtype=np.float64)
    t = np.arange(v.shape[0], dtype=np.float64)
    n = int(np.clip(n_keys, 2, v.shape[0]))
    keys_t = np.linspace(0.0, t[-1], n)
    keys = np.stack([np.interp(keys_t, t, v[:, j]) for j in range(v.shape[1])], axis=1)
    degree = min(3, n - 1) if n != 3 else 2
    return np.asarray(make_interp_spline(keys_t, keys, k=degree, axis=0)(t), dtype=np.float64)


def dct_rebuild(values: ArrayLike, n_coefficients: int) -> NDArray[np.float64]:
    """Each channel of ``values`` ``(T, C)`` rebuilt from its first ``n_coefficients``
    orthonormal DCT-II coefficients (all T give the input back)."""
    from scipy.fft import dct, idct

    v = np.asarray(values, dtype=np.float64)
    c = dct(v, type=2, norm="ortho", axis=0)
    c[int(max(n_coefficients, 1)) :] = 0.0
    return np.asarray(idct(c, type=2, norm="ortho", axis=0), dtype=np.float64)


# ---------------------------------------------------------------------------- codebook


@dataclass
class Codebook:
    """PCA basis and primitive centres learned from training segment vectors.

    ``mean`` (d,) and ``components`` (d, f) are the PCA; ``centers[k]`` the (k, d) centres
    of k primitives as full segment vectors (rad, posture-relative shapes).
    """

    mean: NDArray[np.float64]
    components: NDArray[np.float64]
    centers: dict[int, NDArray[np.float64]]

    @property
    def n_components(self) -> int:
        return int(self.components.shape[1])

    def project(self, vectors: NDArray[np.float64]) -> NDArray[np.float64]:
        """Coefficients ``(N, f)`` of segment vectors along the eigen-primitives."""
        return np.asarray((vectors - self.mean) @ self.components)

    def nearest(self, vectors: NDArray[np.float64], k: int, n: int = 1) -> NDArray[np.int64]:
        """Indices ``(N, n)`` of the ``n`` centres of ``k`` nearest each vector (full
        segment-vector distance)."""
        c = self.centers[k]
        d2 = (
            np.einsum("ij,ij->i", vectors, vectors)[:, None]
            - 2.0 * vectors @ c.T
            + np.einsum("ij,ij->i", c, c)[None, :]
        )
        return np.argsort(d2, axis=1, kind="stable")[:, :n].astype(np.int64)


def fit_codebook(
    vectors: NDArray[np.float64],
    ks: Iterable[int],
    *,
    n_components: int = 30,
    centres: str = "projection",
    n_init: int = 3,
    seed: int = 0,
) -> Codebook:
    """PCA of training ``vectors`` (N, d), then k-means of their f-D projections for each
    k of ``ks`` (k ≤ N). ``centres`` (:data:`CENTRES`): the centres as vectors rebuilt from
    the k-means centres (``"projection"``, the paper) or the means of the members' own
    vectors (``"members"``)."""
    from visprim import kernels
    from visprim.pca import fit_pca

    if centres not in CENTRES:
        raise ValueError(f"centres must be one of {list(CENTRES)}, got {centres!r}")
    f = int(min(n_components, vectors.shape[0] - 1, vectors.shape[1]))
    basis = fit_pca(vectors, n_keep=f)
    comps = np.ascontiguousarray(basis.eigenvectors[:, :f])
    proj = np.ascontiguousarray((vectors - basis.mean) @ comps)
    out: dict[int, NDArray[np.float64]] = {}
    for k in ks:
        if k > vectors.shape[0]:
            continue
        km = kernels.kmeans(proj, int(k), n_init=n_init, seed=seed)
        c_proj = np.asarray(km.centers)
        full = c_proj @ comps.T + basis.mean
        if centres == "members":
            labels = np.asarray(km.labels)
            for j in range(int(k)):
                members = labels == j
                if members.any():
                    full[j] = vectors[members].mean(axis=0)
        out[int(k)] = np.ascontiguousarray(full)
    return Codebook(np.asarray(basis.mean), comps, out)


def warp_curves(curves: NDArray[np.float64], w: float) -> NDArray[np.float64]:
    """Curves ``(..., n, C)`` on ``n`` equally spaced instants of ``u ∈ [0, 1]``, evaluated
    at ``u + w u (1 − u)`` (linear interpolation): a monotone warp for ``|w| < 1`` that keeps
    both ends (``w > 0`` runs the start faster, ``w < 0`` slower)."""
    n = curves.shape[-2]
    u = np.linspace(0.0, 1.0, n)
    x = (u + w * u * (1.0 - u)) * (n - 1)
    i0 = np.clip(np.floor(x).astype(np.int64), 0, n - 2)
    frac = (x - i0)[:, None]
    return curves[..., i0, :] * (1.0 - frac) + curves[..., i0 + 1, :] * frac


def rebuild_segments(
    book: Codebook,
    vectors: NDArray[np.float64],
    n_channels: int,
    family: str,
    param: int,
) -> NDArray[np.float64]:
    """Posture-relative segment vectors ``(N, d)`` rebuilt by one primitive description
    (``param``: k for ``nearest``/``nearest+gain``/``warp``, m for ``residual`` and
    ``projection``; module docstring)."""
    from visprim.vectors import amplitude_gains, to_curves, to_vectors

    if family == "projection":
        m = min(int(param), book.n_components)
        p = book.project(vectors)[:, :m]
        return np.asarray(p @ book.components[:, :m].T + book.mean)
    if family == "residual":
        k = RESIDUAL_K if RESIDUAL_K in book.centers else max(book.centers)
        centre = book.centers[k][book.nearest(vectors, k)[:, 0]]
        m = min(int(param), book.n_components)
        e = book.components[:, :m]
        return np.asarray(centre + ((vectors - centre) @ e) @ e.T)
    k = int(param)
    if family in ("nearest", "nearest+gain"):
        rebuilt = book.centers[k][book.nearest(vectors, k)[:, 0]].copy()
        if family == "nearest+gain":
            rebuilt *= amplitude_gains(vectors, rebuilt)[:, None]
        return rebuilt
    if family != "warp":
        raise ValueError(f"rebuild_segments: unknown family {family!r}")
    cand = book.nearest(vectors, k, min(WARP_CANDIDATES, k))
    best = np.full(vectors.shape[0], np.inf)
    out = np.empty_like(vectors)
    for w in WARP_GRID:
        warped = to_vectors(warp_curves(to_curves(book.centers[k], n_channels), float(w)))
        for j in range(cand.shape[1]):
            r = warped[cand[:, j]]
            r = r * amplitude_gains(vectors, r)[:, None]
            err = np.einsum("ij,ij->i", vectors - r, vectors - r)
            better = err < best
            best[better] = err[better]
            out[better] = r[better]
    return out


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
            per_group = [
                float(np.median([r["bone_deg"] for r in rs if r["group"] == g]))
                for g in self.groups
                if any(r["group"] == g for r in rs)
            ]
            out.append(
                {
                    "benchmark": self.benchmark,
                    "family": fam,
                    "param": param,
                    "numbers_per_s": sum(r["numbers"] for r in rs) / sum(r["seconds"] for r in rs),
                    "bone_deg_median": float(np.median([r["bone_deg"] for r in rs])),
                    "bone_deg_group_min": min(per_group),
                    "bone_deg_group_max": max(per_group),
                    "joint_deg_median": float(np.median([r["joint_deg"] for r in rs])),
                    "movements": len(rs),
                }
            )
        return out


def _score(
    rows: list[dict[str, Any]],
    mv: HeldOut,
    family: str,
    param: Any,
    numbers: int,
    directions: NDArray[np.float64] | None = None,
    angles: NDArray[np.float64] | None = None,
) -> None:
    from visprim.features import from_angles, to_angles

    if directions is None:
        assert angles is not None
        directions = from_angles(angles, "directions")
    if angles is None:
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
            "joint_deg": joint_rms_deg(angles, mv.angles, mv.rotations),
        }
    )


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
) -> None:
    from visprim.model import PrimitiveModel
    from visprim.vectors import to_curves, to_vectors

    params = {**params, "offsets": "mean", "features": "directions"}
    seg_model = PrimitiveModel(**params)
    train_corpus = seg_model.prepare(list(train), tune_seg2=True, segmentation="seg2")
    n = int(seg_model.n_samples)
    train_sv, _ = _corpus_vectors(train_corpus, n, max_stroke)
    if train_sv is None:
        raise ValueError(f"held-out group {group!r}: no SEG-2 segment in the training groups")
    test_model = PrimitiveModel(**{**params, "seg2_threshold": train_corpus.seg2_threshold})
    corpus = test_model.prepare(list(test), tune_seg2=False, segmentation="seg2")
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
        # m up to f, and f itself: the per-segment projection.
        m_values = tuple(sorted({m for m in RATE_M if m < book.n_components} | {book.n_components}))
        params_of = {
            "nearest": RATE_K,
            "nearest+gain": RATE_K,
            "warp": RATE_K,
            "residual": m_values,
            "projection": m_values,
            "bridge": RATE_K,
            "bridge+gain": RATE_K,
            "bridge+residual": m_values,
        }[family]
        bridged = family.startswith("bridge")
        centers = bridge[0].centers if bridged and bridge is not None else book.centers
        for p in params_of:
            if family not in ("residual", "projection", "bridge+residual") and p not in centers:
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
                numbers = movement_numbers(family, mv.segments.shape[0], n_post, p)
                _score(rows, mv, family, p, numbers, directions=values)


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


def _baseline(rows: list[dict[str, Any]], mv: HeldOut, family: str, rate: float) -> None:
    kind, channels = family.split("-")
    signal = mv.angles if channels == "angles" else mv.directions
    c = signal.shape[1]
    count = max(2, int(round((rate * mv.seconds - 2.0) / c)))
    count = min(count, signal.shape[0])
    rebuilt = keyframe_rebuild(signal, count) if kind == "keyframes" else dct_rebuild(signal, count)
    numbers = 2 + c * count
    if channels == "angles":
        _score(rows, mv, family, rate, numbers, angles=rebuilt)
    else:
        _score(rows, mv, family, rate, numbers, directions=rebuilt)


def evaluate_rate(
    bench: Any,
    *,
    families: Sequence[str] = FAMILIES,
    centres: str = "projection",
    max_stroke: float | None = None,
    posture: str = "mean",
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


def rate_benchmark(
    sources: Iterable[str | os.PathLike[str]],
    *,
    labels: str | os.PathLike[str] | None = None,
    group_by: str | None = None,
    period: float = 0.034,
    families: Sequence[str] = FAMILIES,
    centres: str = "projection",
    max_stroke: float | None = None,
    posture: str = "mean",
    jobs: int | None = None,
    progress: bool | None = None,
) -> list[RateResult]:
    """:func:`evaluate_rate` on every benchmark found under ``sources`` (as
    ``visprim evaluate`` finds them, :func:`visprim.evaluate.find_recordings`)."""
    from tqdm.auto import tqdm

    from visprim.evaluate import find_recordings, make_benchmarks, read_movements
    from visprim.progress import _disable

    disable = _disable() if progress is None else not progress
    recordings, _ = find_recordings(sources, labels)
    if not recordings:
        raise ValueError("no labelled recordings found (labels.tsv beside the data, or --labels)")
    with tqdm(total=len(recordings), desc="reading", unit="file", disable=disable) as bar:
        read_out, _ = read_movements(recordings, period=period, jobs=jobs, on_progress=bar.update)
    recordings = [r for r, t in zip(recordings, read_out, strict=True) if t is not None]
    movements = [t for t in read_out if t is not None]
    benches, _ = make_benchmarks(recordings, movements, group_by=group_by)
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


# ---------------------------------------------------------------------------- reports


#: Rates (numbers per second) of the "best within" table of :func:`rate_markdown`.
FRONTIER_RATES: tuple[float, ...] = (8, 10, 12, 16, 20)


def best_within(
    summary: Sequence[dict[str, Any]], rate: float, kinds: str
) -> dict[str, Any] | None:
    """The description of ``summary`` rows with the lowest median bone-direction error
    among those of at most ``rate`` numbers per second: of the primitives (``kinds``
    ``"visprim"``), the keyframes or the DCT baselines."""

    def kind(fam: str) -> str:
        return fam.split("-")[0] if fam.startswith(("keyframes", "dct")) else "visprim"

    rows = [s for s in summary if kind(s["family"]) == kinds and s["numbers_per_s"] <= rate]
    return min(rows, key=lambda s: s["bone_deg_median"]) if rows else None


def rate_markdown(results: Sequence[RateResult]) -> str:
    """The rate–distortion tables as markdown, one per benchmark: the best description of
    each kind within a few rates, then every description by rate."""
    out = ["# Rate–distortion (held-out groups)", ""]
    for r in results:
        opts = ", ".join(f"{k}={v}" for k, v in r.options.items())
        summary = r.summary()
        out += [
            f"## {r.benchmark} (leave one {r.group_by} out; {opts})",
            "",
            "| at most numbers / s | best primitive description | best keyframes | best DCT |",
            "|---:|---|---|---|",
        ]
        for rate in FRONTIER_RATES:
            cells = []
            for kinds in ("visprim", "keyframes", "dct"):
                b = best_within(summary, rate, kinds)
                cells.append(
                    "-"
                    if b is None
                    else f"{b['bone_deg_median']:.1f}° ({b['family']} {b['param']}, "
                    f"{b['numbers_per_s']:.1f}/s)"
                )
            out.append(f"| {rate:g} | " + " | ".join(cells) + " |")
        out += [
            "",
            "| description | parameter | numbers / s | bone-direction RMS median "
            "(group medians) | joint-space RMS median | movements |",
            "|---|---:|---:|---:|---:|---:|",
        ]
        for s in sorted(summary, key=lambda s: (s["family"], s["numbers_per_s"])):
            out.append(
                f"| {s['family']} | {s['param']} | {s['numbers_per_s']:.1f} | "
                f"{s['bone_deg_median']:.1f}° ({s['bone_deg_group_min']:.1f}–"
                f"{s['bone_deg_group_max']:.1f}°) | {s['joint_deg_median']:.1f}° | "
                f"{s['movements']} |"
            )
        out.append("")
    out.append(
        "numbers / s: everything a description stores (ids, durations, postures, gains, "
        "coefficients, start times) over the seconds of movement it covers. Bone-direction "
        "RMS: angle between the rebuilt and the held-out upper-arm and forearm directions; "
        "median over held-out one-arm movements (in brackets the lowest and highest median "
        "of one held-out group). Parameter: k primitives (nearest, warp), m coefficients "
        "(residual, projection), target numbers / s (keyframes, dct)."
    )
    return "\n".join(out) + "\n"


def _csv(results: Sequence[RateResult]) -> str:
    from visprim.csvfile import csv_text

    rows = [s for r in results for s in r.summary()]
    if not rows:
        return ""
    header = list(rows[0])
    cells = (
        [round(v, 4) if isinstance(v, float) else v for v in (s[k] for k in header)] for s in rows
    )
    return csv_text(header, cells)


def _plot(results: Sequence[RateResult], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(7 * len(results), 5), squeeze=False)
    for ax, r in zip(axes[0], results, strict=True):
        summary = r.summary()
        colours = plt.get_cmap("tab20")(np.arange(20))
        for i, fam in enumerate(dict.fromkeys(s["family"] for s in summary)):
            pts = sorted(
                (s["numbers_per_s"], s["bone_deg_median"]) for s in summary if s["family"] == fam
            )
            baseline = fam.startswith(("keyframes", "dct"))
            ax.plot(
                *zip(*pts, strict=True),
                "--" if baseline else "-",
                marker="s" if baseline else "o",
                ms=3,
                color=colours[(2 * i) % 20 + (2 * i) // 20],
                label=fam,
            )
        ax.set_xscale("log")
        ax.set_xlabel("numbers per second of movement")
        ax.set_ylabel("bone-direction RMS, degrees (median, held-out)")
        ax.set_title(f"{r.benchmark}: leave one {r.group_by} out")
        ax.set_ylim(bottom=0)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_rate_report(results: Sequence[RateResult], out_dir: str | os.PathLike[str]) -> dict:
    """Write ``rate.md``, ``rate.csv`` and ``rate.png`` into ``out_dir`` (each atomically).
    Returns the paths by kind."""
    from visprim.atomic import atomic_file, write_text

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "rate_markdown": out / "rate.md",
        "rate_csv": out / "rate.csv",
        "rate_plot": out / "rate.png",
    }
    write_text(paths["rate_markdown"], rate_markdown(results), newline="")
    write_text(paths["rate_csv"], _csv(results), newline="")
    with atomic_file(paths["rate_plot"]) as tmp:
        _plot(results, tmp)
    return paths


# ---------------------------------------------------------------------------- one movement


@dataclass(frozen=True)
class Description:
    """The description chosen for one movement's segments: ``family`` (:data:`FAMILIES`),
    its ``m`` coefficients, the ``numbers`` it stores and the ``seconds`` it covers."""

    family: str
    m: int
    numbers: int
    seconds: float

    @property
    def numbers_per_s(self) -> float:
        return self.numbers / self.seconds if self.seconds > 0 else float("inf")

    @property
    def label(self) -> str:
        if self.family == "residual":
            return f"nearest primitive + {self.m} residual coefficient(s)"
        if self.family == "projection":
            return f"own projection ({self.m} coefficients)"
        return {"nearest": "nearest primitive", "nearest+gain": "nearest primitive × gain"}[
            self.family
        ]

    def to_dict(self) -> dict[str, Any]:
        return {
            "description": self.label,
            "family": self.family,
            "coefficients": self.m,
            "numbers": self.numbers,
            "seconds": self.seconds,
            "numbers_per_s": self.numbers_per_s,
        }


def _candidates(
    model: Any, vectors: NDArray[np.float64], seconds: float
) -> tuple[list[tuple[Description, float]], Callable[[Description], NDArray[np.float64]]]:
    """Every description :func:`describe_segments` chooses from, with the squared error of
    its rebuild, and the function that rebuilds the segments by one of them."""
    from visprim.vectors import amplitude_gains

    x = np.asarray(vectors, dtype=np.float64)
    n_seg = x.shape[0]
    f = int(model.n_components)
    posture = int(model.n_channels) if model.offsets == "mean" else 0
    p = model.transform(x)
    labels, _ = model.assign(p)
    centre = model.cluster_centers_[labels]

    def rebuild(d: Description) -> NDArray[np.float64]:
        if d.family == "projection":
            return np.asarray(p @ model.components_.T + model.mean_)
        coef = centre.copy()
        coef[:, : d.m] = p[:, : d.m]
        out = np.asarray(coef @ model.components_.T + model.mean_)
        if d.family == "nearest+gain":
            out = out * amplitude_gains(x, out)[:, None]
        return out

    options = [("nearest", 0)] + ([("nearest+gain", 0)] if model.offsets == "mean" else [])
    options += [("residual", m) for m in range(1, f)] + [("projection", f)]
    out = []
    for fam, m in options:
        d = Description(fam, m, movement_numbers(fam, n_seg, posture, m), float(seconds))
        out.append((d, float(np.sum((x - rebuild(d)) ** 2))))
    return out, rebuild


def describe_segments(
    model: Any,
    vectors: NDArray[np.float64],
    seconds: float,
    *,
    family: str | None = None,
    budget: float | None = None,
) -> tuple[NDArray[np.float64], Description]:
    """One movement's segment vectors ``(N, d)`` (``seconds`` long) rebuilt through a fitted
    :class:`~visprim.model.PrimitiveModel`, and the description used.

    Without ``budget``: ``family`` (default the model's own, the nearest primitive, scaled
    by its gain if ``model.amplitude``; or ``"projection"``). With ``budget`` (numbers per
    second of movement): of the nearest primitive, with its gain, with m = 1 … f − 1
    residual coefficients and the own projection (m = f), the one whose rebuild lies
    closest to the segments (squared error of the segment vectors) among those that fit
    the budget. Posture numbers are counted for posture-relative models
    (``offsets="mean"``); a model of absolute curves stores none.
    """
    candidates, rebuild = _candidates(model, vectors, seconds)
    if budget is None:
        fam = family or ("nearest+gain" if model.amplitude else "nearest")
        if fam not in ("nearest", "nearest+gain", "projection"):
            raise ValueError(f"family must be nearest, nearest+gain or projection, got {fam!r}")
        d = next(d for d, _ in candidates if d.family == fam)
        return rebuild(d), d
    fitting = [(err, d.numbers, i) for i, (d, err) in enumerate(candidates)]
    fitting = [c for c in fitting if candidates[c[2]][0].numbers_per_s <= budget * (1 + 1e-12)]
    if not fitting:
        least = candidates[0][0]
        raise ValueError(
            f"budget {budget:g} numbers/s is below the smallest description of this movement "
            f"({least.numbers_per_s:.1f} numbers/s: nearest primitive, "
            f"{vectors.shape[0]} segment(s) in {seconds:.2f} s)"
        )
    d = candidates[min(fitting)[2]][0]
    return rebuild(d), d


def share_budget(
    model: Any,
    parts: Sequence[tuple[NDArray[np.float64], float]],
    span: float,
    budget: float,
) -> list[float]:
    """Per-part budgets (numbers per second of each part) that share ``budget`` numbers per
    second of a ``span``-second recording between its parts (its arms imitated one by one,
    each ``(segment vectors, seconds)``): the combination of descriptions (one per part,
    :func:`describe_segments`) with the least summed squared error whose numbers together
    fit ``budget × span``."""
    options = [_candidates(model, x, sec)[0] for x, sec in parts]
    total = budget * span * (1 + 1e-12)
    best: tuple[float, tuple[int, ...]] | None = None
    # Two arms of at most f + 2 descriptions each: every combination is cheap to try.
    for combo in np.ndindex(*(len(o) for o in options)):
        numbers = sum(o[j][0].numbers for o, j in zip(options, combo, strict=True))
        if numbers > total:
            continue
        err = sum(o[j][1] for o, j in zip(options, combo, strict=True))
        if best is None or err < best[0]:
            best = (err, tuple(combo))
    if best is None:
        least = sum(o[0][0].numbers for o in options) / span
        raise ValueError(
            f"budget {budget:g} numbers/s is below the smallest description of this movement "
            f"({least:.1f} numbers/s: the nearest primitive for each of its {len(parts)} parts)"
        )
    return [o[j][0].numbers_per_s for o, j in zip(options, best[1], strict=True)]
