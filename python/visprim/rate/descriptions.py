"""Primitive descriptions of segments: what each stores (numbers) and how it rebuilds a
segment (codebooks of primitive centres, residual coefficients, warps)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

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
    "nearest+dct",
    "bridge",
    "bridge+gain",
    "bridge+residual",
    "eigen",
    "eigen/dct",
    "eigen/dct-split2",
    "eigen/dct-fit2",
    "keyframes-angles",
    "keyframes-directions",
    "dct-angles",
    "dct-directions",
    "dct-angles-fit",
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
#: DCT coefficients per channel q of the ``nearest+dct`` descriptions.
RATE_Q: tuple[int, ...] = (1, 2, 3, 4, 6)
#: Shape channels of a one-arm segment: the two bone directions' coordinates.
SHAPE_CHANNELS = 6


# ---------------------------------------------------------------------------- counting


def segment_numbers(
    family: str, n_channels: int, m: int = 0, q: int = 0, shape_channels: int = SHAPE_CHANNELS
) -> int:
    """Numbers stored per segment by a primitive description of ``family``: the primitive
    id, the duration and ``n_channels`` posture numbers, plus a gain (``nearest+gain``),
    ``m`` coefficients (``residual``), or a gain and one warp number (``warp``);
    ``projection`` stores ``m`` coefficients, the duration and the posture (no id);
    ``nearest+dct`` stores ``q`` DCT coefficients of each of the ``shape_channels``
    channels of the segment's shape (6 for one arm's bone directions), and
    ``residual+dct`` both ``m`` residual and ``q`` DCT coefficients per channel.
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
    if family == "nearest+dct":
        return base + int(q) * int(shape_channels)
    if family == "residual+dct":
        return base + int(m) + int(q) * int(shape_channels)
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


def movement_numbers(
    family: str,
    n_segments: int,
    n_channels: int,
    m: int = 0,
    q: int = 0,
    shape_channels: int = SHAPE_CHANNELS,
) -> int:
    """All the numbers of one movement of ``n_segments`` consecutive segments: its start
    time, each segment's numbers (:func:`segment_numbers`) and, for the ``bridge``
    descriptions, the posture at each of the ``n_segments + 1`` boundaries (two unit bone
    directions, :data:`BOUNDARY_NUMBERS`)."""
    total = 1 + int(n_segments) * segment_numbers(family, n_channels, m, q, shape_channels)
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


def dct_residual(
    vectors: NDArray[np.float64],
    predicted: NDArray[np.float64],
    n_channels: int,
    q: int,
    skip_constant: bool = True,
) -> NDArray[np.float64]:
    """``predicted`` segment vectors ``(N, d)`` corrected by the first ``q`` non-constant
    orthonormal DCT-II coefficients of each channel of their residual ``vectors −
    predicted`` along the segment's samples (the constant term is left out: both are
    posture-relative, so the residual's mean is what the posture already stores; with
    ``skip_constant=False``, for absolute curves, the first ``q`` terms)."""
    from scipy.fft import dct, idct

    from visprim.vectors import to_curves, to_vectors

    r = to_curves(vectors - predicted, n_channels)  # (N, n, C)
    c = dct(r, type=2, norm="ortho", axis=1)
    keep = np.zeros(c.shape[1], dtype=bool)
    first = 1 if skip_constant else 0
    keep[first : first + int(q)] = True
    c[:, ~keep, :] = 0.0
    return np.asarray(predicted + to_vectors(idct(c, type=2, norm="ortho", axis=1)))


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
    if family == "nearest+dct":
        k = RESIDUAL_K if RESIDUAL_K in book.centers else max(book.centers)
        centre = book.centers[k][book.nearest(vectors, k)[:, 0]]
        return dct_residual(vectors, centre, n_channels, int(param))
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


# ---------------------------------------------------------------------------- eigen-movements

#: Samples per channel of a whole movement resampled onto its own duration for the
#: eigen-movements (at least the frames of a 5.4 s movement at the study's 29.4 frames/s,
#: the longest HDM05 cut movement, so resampling loses nothing there).
EIGEN_SAMPLES = 160
#: The eigen-movement descriptions of a whole movement (no segments): ``eigen`` stores its
#: first m coefficients along the eigen-movements; ``eigen/dct`` also lets the encoder take
#: the truncated DCT of the 4 arm angles instead, whichever rebuilds the movement closer,
#: with one number that says which.
EIGEN_FAMILIES: tuple[str, ...] = (
    "eigen",
    "eigen/dct",
    "eigen/dct-split2",
    "eigen/dct-fit1",
    "eigen/dct-fit2",
    "eigen/dct-fit3",
)
#: Prefix of the ``eigen/dct-splitD`` families: the encoder also chooses, per movement, how
#: the DCT's coefficients are split over the 4 angle channels, each channel within ``D``
#: coefficients of the even share (:func:`dct_splits`), and stores the choice in the one
#: number that ``eigen/dct`` spends on its flag (an integer: 0 for the eigen-movements,
#: 1 + the split's index for the DCT).
SPLIT_PREFIX = "eigen/dct-split"
#: Prefix of the ``eigen/dct-fitD`` families: as ``eigen/dct-splitD``, and the chosen
#: split's coefficients are then fitted to the bone directions (:func:`fit_dct_coefficients`)
#: instead of being the truncated DCT of the angles. The decoder is the same.
FIT_PREFIX = "eigen/dct-fit"
#: Gauss–Newton steps of :func:`fit_dct_coefficients`.
FIT_ITERATIONS = 4
#: Numbers per movement an eigen-movement description needs besides its coefficients: its
#: start and its duration.
EIGEN_HEAD = 2
#: Numbers of the choice between eigen-movements and DCT (one flag per movement).
EIGEN_CHOICE = 1


#: Rates (numbers per second) of the ``eigen/dct-split`` and ``eigen/dct-fit`` families:
#: those of :data:`BASELINE_RATES` from 8 to 20, where numbers are scarce (the encoder's
#: search over splits and its fit cost about 0.05 s per movement and rate).
SPLIT_RATES: tuple[float, ...] = tuple(r for r in BASELINE_RATES if 8 <= r <= 20)


def eigen_rates(family: str) -> tuple[float, ...]:
    """The rates at which the benchmark measures an eigen-movement ``family``."""
    if family.startswith((SPLIT_PREFIX, FIT_PREFIX)):
        return SPLIT_RATES
    return BASELINE_RATES


def eigen_numbers(rate: float, seconds: float) -> int:
    """All the numbers an eigen-movement description of a ``seconds``-long movement
    stores within ``rate`` numbers per second: ``floor(rate × seconds)`` (the start, the
    duration, the choice flag and coefficients), at least the head and one coefficient. No
    movement exceeds the rate (the DCT baseline rounds to whole coefficients per channel
    and can exceed it a little)."""
    return max(EIGEN_HEAD + EIGEN_CHOICE + 1, int(np.floor(rate * seconds + 1e-9)))


def resample_movement(values: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Channels ``(T, C)`` of a movement read at ``n`` equally spaced instants from its
    first frame to its last (linear interpolation): its shape on its own duration."""
    v = np.asarray(values, dtype=np.float64)
    t = np.linspace(0.0, 1.0, v.shape[0])
    u = np.linspace(0.0, 1.0, int(n))
    return np.stack([np.interp(u, t, v[:, j]) for j in range(v.shape[1])], axis=1)


@dataclass
class EigenMovements:
    """PCA of whole training movements: each movement's bone directions ``(T, 6)`` resampled
    to ``n_samples`` instants over its own duration (:func:`resample_movement`) and
    flattened; ``mean`` ``(n_samples · 6,)`` and ``components`` ``(n_samples · 6, f)``, the
    leading eigen-movements first. A movement is rebuilt as the mean plus a superposition
    of the first m eigen-movements, stretched back onto its duration.

    ``dct_order[rate]``: the order in which the 4 angle channels get the coefficients left
    over when the DCT alternative of ``eigen/dct`` splits its coefficients evenly, learned
    on the training movements (the channel whose last coefficient matters most first)."""

    mean: NDArray[np.float64]
    components: NDArray[np.float64]
    n_samples: int
    dct_order: dict[float, tuple[int, ...]]

    @property
    def n_components(self) -> int:
        return int(self.components.shape[1])

    def coefficients(self, directions: NDArray[np.float64]) -> NDArray[np.float64]:
        """All coefficients ``(f,)`` of one movement's bone directions ``(T, 6)``."""
        x = resample_movement(directions, self.n_samples).ravel()
        return np.asarray((x - self.mean) @ self.components)

    def rebuild(self, directions: NDArray[np.float64], m: int) -> NDArray[np.float64]:
        """Bone directions ``(T, 6)`` of a movement rebuilt from its first ``m`` coefficients
        (the mean movement for m = 0), on its own frames."""
        m = int(np.clip(m, 0, self.n_components))
        p = self.coefficients(directions)[:m]
        curve = (self.mean + self.components[:, :m] @ p).reshape(self.n_samples, -1)
        t = np.linspace(0.0, 1.0, directions.shape[0])
        u = np.linspace(0.0, 1.0, self.n_samples)
        return np.stack([np.interp(t, u, curve[:, j]) for j in range(curve.shape[1])], axis=1)


def dct_counts(n: int, n_channels: int, order: Sequence[int]) -> NDArray[np.int64]:
    """``n`` DCT coefficients split over ``n_channels`` channels: evenly, the remainder one
    each to the first channels of ``order``."""
    counts = np.full(int(n_channels), int(n) // int(n_channels), dtype=np.int64)
    counts[list(order)[: int(n) % int(n_channels)]] += 1
    return counts


def dct_rebuild_counts(
    values: NDArray[np.float64], counts: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Each channel j of ``values`` ``(T, C)`` rebuilt from its first ``counts[j]``
    orthonormal DCT-II coefficients (zero coefficients: the channel is zero)."""
    from scipy.fft import dct, idct

    c = dct(np.asarray(values, dtype=np.float64), type=2, norm="ortho", axis=0)
    rows = np.arange(c.shape[0])[:, None]
    c[rows >= np.asarray(counts)[None, :]] = 0.0
    return np.asarray(idct(c, type=2, norm="ortho", axis=0), dtype=np.float64)


def dct_splits(n: int, n_channels: int, spread: int, n_frames: int) -> NDArray[np.int64]:
    """Every split ``(K, n_channels)`` of ``n`` DCT coefficients over ``n_channels``
    channels with each channel's count within ``spread`` of the even share ``n /
    n_channels``, at least 1 and at most ``n_frames``, in lexicographic order. Encoder and
    decoder both know the list from ``n``, so an index into it says which split was used.
    Empty when no split fits."""
    share = n / n_channels
    lo = max(1, int(np.ceil(share - spread - 1e-9)))
    hi = min(int(n_frames), int(np.floor(share + spread + 1e-9)))
    if hi < lo:
        return np.zeros((0, n_channels), dtype=np.int64)
    grid = np.stack(
        np.meshgrid(*[np.arange(lo, hi + 1)] * n_channels, indexing="ij"), axis=-1
    ).reshape(-1, n_channels)
    return np.ascontiguousarray(grid[grid.sum(axis=1) == n], dtype=np.int64)


def best_dct_split(
    angles: NDArray[np.float64], directions: NDArray[np.float64], n: int, spread: int
) -> tuple[int, NDArray[np.float64], float]:
    """The split of ``n`` DCT coefficients of the arm ``angles`` ``(T, 4)`` among
    :func:`dct_splits` whose rebuilt bone directions lie closest to ``directions``
    ``(T, 6)``: its index, the rebuilt angles and the bone-direction RMS, degrees (index
    −1, the input and infinity when no split fits)."""
    from scipy.fft import dct, idct

    from visprim.features import from_angles

    a = np.asarray(angles, dtype=np.float64)
    t, c = a.shape
    splits = dct_splits(n, c, spread, t)
    if splits.shape[0] == 0:
        return -1, a, float("inf")
    coef = dct(a, type=2, norm="ortho", axis=0)
    rows = np.arange(t)[:, None]
    # Each channel rebuilt from each count a split may give it.
    counts = np.unique(splits)
    partial = {
        int(k): np.asarray(idct(np.where(rows < k, coef, 0.0), type=2, norm="ortho", axis=0))
        for k in counts
    }
    cand = np.stack(
        [np.stack([partial[int(k)][:, j] for j, k in enumerate(split)], axis=1) for split in splits]
    )  # (K, T, C)
    rebuilt = from_angles(cand.reshape(-1, c), "directions").reshape(splits.shape[0], t, -1, 3)
    ref = np.asarray(directions, dtype=np.float64).reshape(1, t, -1, 3)
    cos = np.sum(rebuilt * ref, axis=3) / np.maximum(
        np.linalg.norm(rebuilt, axis=3) * np.linalg.norm(ref, axis=3), 1e-12
    )
    err = np.degrees(np.sqrt(np.mean(np.arccos(np.clip(cos, -1.0, 1.0)) ** 2, axis=(1, 2))))
    best = int(np.argmin(err))
    return best, np.asarray(cand[best]), float(err[best])


def _unit_rows(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(T, 3 b)`` bone directions scaled to unit length per bone, flattened ``(T · 3 b,)``."""
    v = values.reshape(values.shape[0], -1, 3)
    return np.asarray(v / np.maximum(np.linalg.norm(v, axis=2, keepdims=True), 1e-12)).ravel()


def fit_dct_coefficients(
    angles: NDArray[np.float64],
    directions: NDArray[np.float64],
    counts: NDArray[np.int64],
    iterations: int = FIT_ITERATIONS,
) -> tuple[NDArray[np.float64], float]:
    """The first ``counts[j]`` DCT-II coefficients of each angle channel j, chosen so that
    the bone directions they rebuild lie close to ``directions`` ``(T, 6)``, not the
    truncated DCT of ``angles`` ``(T, 4)`` (which is closest in the angles, a metric that
    near the shoulder's singular posture says little about the bones).

    Starts at the truncated DCT and takes ``iterations`` Levenberg–Marquardt steps on the
    squared distance between the unit bone vectors (the chord, ≈ the angle for small
    errors), keeping a step only if the bone-direction RMS falls. Returns the rebuilt
    angles ``(T, 4)`` and their bone-direction RMS, degrees. The stored numbers are the
    same as the truncated DCT's: only the encoder differs."""
    from scipy.fft import dct, idct
    from threadpoolctl import threadpool_limits

    from visprim.features import from_angles
    from visprim.rate.measures import bone_rms_deg

    a = np.asarray(angles, dtype=np.float64)
    t, c = a.shape
    target = _unit_rows(np.asarray(directions, dtype=np.float64))
    mask = np.arange(t)[:, None] < np.asarray(counts)[None, :]  # (T, C): kept coefficients
    coef = np.where(mask, dct(a, type=2, norm="ortho", axis=0), 0.0)
    basis = idct(np.eye(t), type=2, norm="ortho", axis=0)  # basis[:, i]: coefficient i in time
    rows, cols = np.nonzero(mask)  # coefficient i = rows, channel j = cols
    h = 1e-6  # rad, the finite-difference step of the per-frame Jacobian

    def synth(k: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(idct(k, type=2, norm="ortho", axis=0))

    current = synth(coef)
    err = bone_rms_deg(from_angles(current, "directions"), directions)
    damping = 1e-3
    with threadpool_limits(limits=1, user_api="blas"):
        for _ in range(int(iterations)):
            f0 = from_angles(current, "directions")  # (T, 6)
            moved = current[None, :, :] + h * np.eye(c)[:, None, :]  # (C, T, C)
            df = (from_angles(moved.reshape(-1, c), "directions").reshape(c, t, -1) - f0) / h
            # d residual(t, o) / d coefficient (i, j) = df[j, t, o] · basis[t, i]
            jac = (df[cols] * basis[:, rows].T[:, :, None]).reshape(rows.size, -1).T
            r = f0.ravel() - target
            hess = jac.T @ jac
            grad = jac.T @ r
            improved = False
            for _ in range(4):
                step = np.linalg.solve(hess + damping * np.diag(np.diag(hess) + 1e-12), -grad)
                trial = coef.copy()
                trial[rows, cols] += step
                rebuilt = synth(trial)
                e = bone_rms_deg(from_angles(rebuilt, "directions"), directions)
                if e < err:
                    coef, current, err, improved = trial, rebuilt, e, True
                    damping *= 0.3
                    break
                damping *= 10.0
            if not improved:
                break
    return current, float(err)


def _dct_order(
    angles: Sequence[NDArray[np.float64]],
    directions: Sequence[NDArray[np.float64]],
    seconds: Sequence[float],
    rate: float,
) -> tuple[int, ...]:
    """The angle channels ordered by how much the training movements' bone-direction error
    (mean squared, degrees²) grows when that channel has one DCT coefficient fewer than
    the even split of the ``eigen/dct`` DCT alternative at ``rate`` (most first)."""
    from visprim.features import from_angles
    from visprim.rate.measures import bone_rms_deg

    c = angles[0].shape[1]
    loss = np.zeros(c)
    for a, d, s in zip(angles, directions, seconds, strict=True):
        n = eigen_numbers(rate, s) - EIGEN_HEAD - EIGEN_CHOICE
        even = np.full(c, max(1, n // c), dtype=np.int64)
        for j in range(c):
            fewer = even.copy()
            fewer[j] -= 1
            rebuilt = from_angles(dct_rebuild_counts(a, fewer), "directions")
            loss[j] += bone_rms_deg(rebuilt, d) ** 2
    return tuple(int(j) for j in np.argsort(-loss, kind="stable"))


def fit_eigen_movements(
    directions: Sequence[NDArray[np.float64]],
    angles: Sequence[NDArray[np.float64]] | None = None,
    seconds: Sequence[float] | None = None,
    rates: Iterable[float] = (),
    *,
    n_samples: int = EIGEN_SAMPLES,
) -> EigenMovements:
    """Eigen-movements of training movements' bone directions (each ``(T, 6)``): the mean
    and every principal component of their resampled, flattened shapes
    (:class:`EigenMovements`); with their ``angles`` and ``seconds``, the DCT channel order
    of ``eigen/dct`` at each of ``rates``."""
    x = np.stack([resample_movement(d, n_samples).ravel() for d in directions])
    mean = x.mean(axis=0)
    _, s, vt = np.linalg.svd(x - mean, full_matrices=False)
    # Components without training variance carry nothing: keep the rank's.
    keep = int(np.sum(s > s[0] * 1e-10)) if s.size and s[0] > 0 else 0
    order: dict[float, tuple[int, ...]] = {}
    if angles is not None and seconds is not None:
        for rate in rates:
            order[float(rate)] = _dct_order(angles, directions, seconds, float(rate))
    return EigenMovements(
        np.asarray(mean), np.ascontiguousarray(vt[:keep].T), int(n_samples), order
    )


def eigen_describe(
    book: EigenMovements,
    family: str,
    rate: float,
    seconds: float,
    directions: NDArray[np.float64],
    angles: NDArray[np.float64],
) -> tuple[str, NDArray[np.float64], int]:
    """One whole movement described within ``rate`` numbers per second by ``family``
    (:data:`EIGEN_FAMILIES`): which code was used (``"eigen"`` or ``"dct"``), the rebuilt
    channels (bone directions ``(T, 6)`` for eigen-movements, arm angles ``(T, 4)`` for
    the DCT) and the numbers stored (:func:`eigen_numbers`). ``eigen/dct`` keeps the code
    whose bone directions lie closer to the movement's (the encoder has the movement)."""
    from visprim.features import from_angles
    from visprim.rate.measures import bone_rms_deg

    if family not in EIGEN_FAMILIES:
        raise ValueError(f"eigen_describe: unknown family {family!r}")
    numbers = eigen_numbers(rate, seconds)
    if family == "eigen":
        return "eigen", book.rebuild(directions, numbers - EIGEN_HEAD), numbers
    n = numbers - EIGEN_HEAD - EIGEN_CHOICE
    eigen = book.rebuild(directions, n)
    c = angles.shape[1]
    if n < c:
        return "eigen", eigen, numbers
    if family.startswith((SPLIT_PREFIX, FIT_PREFIX)):
        fit = family.startswith(FIT_PREFIX)
        spread = int(family[len(FIT_PREFIX if fit else SPLIT_PREFIX) :])
        index, split, err = best_dct_split(angles, directions, n, spread)
        if fit and index >= 0:
            counts = dct_splits(n, c, spread, angles.shape[0])[index]
            split, err = fit_dct_coefficients(angles, directions, counts)
        if err < bone_rms_deg(eigen, directions):
            return "dct", split, numbers
        return "eigen", eigen, numbers
    order = book.dct_order.get(float(rate), tuple(range(c)))
    dct = dct_rebuild_counts(angles, dct_counts(n, c, order))
    if bone_rms_deg(from_angles(dct, "directions"), directions) < bone_rms_deg(eigen, directions):
        return "dct", dct, numbers
    return "eigen", eigen, numbers
