"""One movement described within a budget of numbers per second (``visprim imitate
--budget``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.rate.descriptions import (
    POSTURES,
    dct_residual,
    movement_numbers,
    unit_bones,
    unit_posture,
)

#: Most DCT coefficients per channel of the residual among the candidates.
DCT_Q_MAX = 6

#: The whole-movement code of ``visprim imitate --budget`` (:func:`describe_movement`): what
#: the nested leave-one-actor-out chose on HDM05 at every budget from 10 to 20 numbers per
#: second (docs/rate.rst).
WHOLE_FAMILY = "eigen/dct-fit3"
#: Channels of one arm's bone directions (upper arm and forearm, 3 each) and angles.
ARM_DIRECTIONS = 6
ARM_ANGLES = 4

# ---------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class Settings:
    """How a movement's segments are stored within a budget: each segment's ``posture``
    (:data:`~visprim.rate.descriptions.POSTURES`: its channel means, or the unit bone
    directions of that mean) and the longest stroke, ``max_stroke`` seconds (longer
    segments are cut into equal parts, :func:`~visprim.rate.split_long`; None: never).
    :func:`budget_settings` gives the defaults of :data:`visprim.params.RATE_OPTIONS`."""

    posture: str = "mean"
    max_stroke: float | None = None

    def __post_init__(self) -> None:
        if self.posture not in POSTURES:
            raise ValueError(f"posture must be one of {list(POSTURES)}, got {self.posture!r}")
        if self.max_stroke is not None and not self.max_stroke > 0:
            raise ValueError(f"max_stroke must be positive seconds or None, got {self.max_stroke}")

    def for_model(self, model: Any) -> Settings:
        """These settings as ``model`` can store them: unit postures need bone directions
        and posture-relative vectors (``features="directions"``, ``offsets="mean"``),
        else each channel's mean is kept."""
        unit_ok = model.offsets == "mean" and getattr(model, "features", "zyz") == "directions"
        return self if unit_ok or self.posture == "mean" else Settings("mean", self.max_stroke)

    def to_dict(self) -> dict[str, Any]:
        return {"posture": self.posture, "max_stroke_s": self.max_stroke}


def budget_settings(**override: Any) -> Settings:
    """The settings ``visprim imitate --budget`` uses: the defaults of
    :data:`visprim.params.RATE_OPTIONS` (chosen by the nested leave-one-group-out of
    :mod:`visprim.rate.nested`), with any of ``posture``, ``max_stroke`` given instead."""
    from visprim.params import RATE_OPTIONS

    values = {k: RATE_OPTIONS[k].default for k in ("posture", "max_stroke")}
    unknown = set(override) - set(values)
    if unknown:
        raise ValueError(f"unknown budget setting(s) {sorted(unknown)}")
    return Settings(**{**values, **override})


def posture_numbers(model: Any, settings: Settings) -> int:
    """Posture numbers stored per segment: none for absolute curves (``offsets="turns"``),
    each channel's mean, or two per bone for unit bone directions (4 per arm)."""
    if model.offsets != "mean":
        return 0
    c = int(model.n_channels)
    return c // 3 * 2 if settings.for_model(model).posture == "unit" else c


def rebuilt_postures(
    model: Any, settings: Settings, postures: NDArray[np.float64], rebuilt: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Posture offsets ``(N, C)`` added to rebuilt posture-relative segment vectors
    ``(N, d)``: the stored means ``postures`` themselves, or (``posture="unit"``) their unit
    bone directions scaled by :func:`~visprim.rate.descriptions.unit_posture` for the
    rebuilt shapes."""
    from visprim.vectors import to_curves

    if settings.for_model(model).posture == "mean" or model.offsets != "mean":
        return postures
    shapes = to_curves(rebuilt, int(model.n_channels))
    return unit_posture(unit_bones(postures), shapes)


def cut_vectors(model: Any, corpus: Any, max_stroke: float | None) -> Any:
    """Segment vectors (:class:`visprim.vectors.SegmentVectors`, the model's offsets) of a
    prepared one-trial ``corpus`` with every segment longer than ``max_stroke`` seconds cut
    into equal parts (:func:`~visprim.rate.split_long`; ``model.vectorize`` for None)."""
    from visprim.features import periodic_channels
    from visprim.rate.benchmark import split_long
    from visprim.vectors import time_to_frame, vectors_from_frames

    if max_stroke is None or corpus.segmentation.n_segments == 0:
        return model.vectorize(corpus)
    bounds = split_long(corpus.segments[0], max_stroke)
    frames = time_to_frame(corpus.times[0], bounds) + corpus.offsets[0]
    return vectors_from_frames(
        corpus.values,
        frames[:, 0],
        frames[:, 1],
        trial=np.zeros(bounds.shape[0], dtype=np.int64),
        starts=bounds[:, 0],
        ends=bounds[:, 1],
        n_samples=int(model.n_samples),
        periodic_channels=periodic_channels(corpus.features, len(corpus.arms)),
        offsets=str(model.offsets),
    )


# ---------------------------------------------------------------------------- one movement


@dataclass(frozen=True)
class Description:
    """The description chosen for one movement's segments: ``family`` (:data:`FAMILIES`),
    its ``m`` coefficients, the ``numbers`` it stores and the ``seconds`` it covers, and
    ``q`` DCT coefficients per channel of the residual (``nearest+dct``,
    ``residual+dct``)."""

    family: str
    m: int
    numbers: int
    seconds: float
    q: int = 0
    settings: Settings = Settings()

    @property
    def numbers_per_s(self) -> float:
        return self.numbers / self.seconds if self.seconds > 0 else float("inf")

    @property
    def label(self) -> str:
        if self.family == "nearest+dct":
            return f"nearest primitive + {self.q} DCT coefficient(s) per channel"
        if self.family == "residual+dct":
            return (
                f"nearest primitive + {self.m} residual + {self.q} DCT coefficient(s) per channel"
            )
        if self.family == "residual":
            return f"nearest primitive + {self.m} residual coefficient(s)"
        if self.family == "projection":
            return f"own projection ({self.m} coefficients)"
        if self.family == "eigen":
            return f"whole movement: {self.m} eigen-movement coefficient(s)"
        if self.family == "eigen/dct":
            return f"whole movement: DCT of the arm angles, {self.m} coefficient(s) in all"
        return {"nearest": "nearest primitive", "nearest+gain": "nearest primitive × gain"}[
            self.family
        ]

    def to_dict(self) -> dict[str, Any]:
        return {
            "description": self.label,
            "family": self.family,
            "coefficients": self.m,
            "dct_coefficients_per_channel": self.q,
            "numbers": self.numbers,
            "seconds": self.seconds,
            "numbers_per_s": self.numbers_per_s,
            "posture": self.settings.posture,
            "max_stroke_s": self.settings.max_stroke,
        }


def _candidates(
    model: Any,
    vectors: NDArray[np.float64],
    seconds: float,
    settings: Settings | None = None,
    postures: NDArray[np.float64] | None = None,
    *,
    family: str | None = None,
) -> tuple[list[tuple[Description, float]], Callable[[Description], NDArray[np.float64]]]:
    """Every description :func:`describe_segments` chooses from (those of ``family`` only,
    if given), with the squared error of its rebuild (posture included: the stored posture
    of ``settings`` against the segments' own ``postures``), and the function that rebuilds
    the segments by one of them."""
    from visprim.vectors import amplitude_gains

    x = np.asarray(vectors, dtype=np.float64)
    n_seg = x.shape[0]
    f = int(model.n_components)
    settings = (settings or Settings()).for_model(model)
    posture = posture_numbers(model, settings)
    if postures is None:
        postures = np.zeros((n_seg, int(model.n_channels)))
    n_s = int(model.n_samples)

    def error(r: NDArray[np.float64]) -> float:
        off = rebuilt_postures(model, settings, postures, r) - postures
        d = (x - r).reshape(n_seg, -1, n_s) + off[:, :, None]
        return float(np.sum(d**2))

    p = model.transform(x)
    labels, _ = model.assign(p)
    centre = model.cluster_centers_[labels]
    c = int(model.n_channels)

    def rebuild(d: Description) -> NDArray[np.float64]:
        if d.family == "projection":
            return np.asarray(p @ model.components_.T + model.mean_)
        coef = centre.copy()
        coef[:, : d.m] = p[:, : d.m]
        out = np.asarray(coef @ model.components_.T + model.mean_)
        if d.family == "nearest+gain":
            out = out * amplitude_gains(x, out)[:, None]
        if d.q:
            out = dct_residual(x, out, c, d.q, skip_constant=model.offsets == "mean")
        return out

    options = [("nearest", 0, 0)] + ([("nearest+gain", 0, 0)] if model.offsets == "mean" else [])
    options += [("residual", m, 0) for m in range(1, f)] + [("projection", f, 0)]
    q_max = min(DCT_Q_MAX, int(model.n_samples) - 1)
    options += [("nearest+dct", 0, q) for q in range(1, q_max + 1)]
    options += [("residual+dct", m, q) for m in range(1, f) for q in range(1, q_max + 1)]
    if family is not None:
        options = [o for o in options if o[0] == family]
    out = []
    for fam, m, q in options:
        numbers = movement_numbers(fam, n_seg, posture, m, q, c)
        d = Description(fam, m, numbers, float(seconds), q, settings)
        out.append((d, error(rebuild(d))))
    return out, rebuild


def describe_segments(
    model: Any,
    vectors: NDArray[np.float64],
    seconds: float,
    *,
    family: str | None = None,
    budget: float | None = None,
    settings: Settings | None = None,
    postures: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], Description]:
    """One movement's segment vectors ``(N, d)`` (``seconds`` long) rebuilt through a fitted
    :class:`~visprim.model.PrimitiveModel`, and the description used.

    Without ``budget``: ``family`` (default the model's own, the nearest primitive, scaled
    by its gain if ``model.amplitude``; or ``"projection"``). With ``budget`` (numbers per
    second of movement): of the nearest primitive, with its gain, with m = 1 … f − 1
    residual coefficients, the own projection (m = f), and the nearest primitive (with
    or without m residual coefficients) corrected by q = 1 … :data:`DCT_Q_MAX` DCT
    coefficients per channel of what is left (:func:`~visprim.rate.descriptions.dct_residual`),
    the one whose rebuild lies
    closest to the segments (squared error of the segment vectors) among those that fit
    the budget. Posture numbers are counted for posture-relative models
    (``offsets="mean"``; ``settings.posture``, :func:`posture_numbers`, 6 or 4 per arm, and
    the closeness counts the posture's error too, the segments' own ``postures`` ``(N, C)``
    against what is stored, :func:`rebuilt_postures`); a model of absolute curves stores
    none. The rebuilt vectors are posture-relative: add
    ``rebuilt_postures(model, description.settings, postures, rebuilt)``.
    """
    if budget is None:
        fam = family or ("nearest+gain" if model.amplitude else "nearest")
        if fam not in ("nearest", "nearest+gain", "projection"):
            raise ValueError(f"family must be nearest, nearest+gain or projection, got {fam!r}")
        candidates, rebuild = _candidates(model, vectors, seconds, settings, postures, family=fam)
        if not candidates:
            raise ValueError(f"family {fam!r} needs a model of posture-relative curves")
        d = candidates[0][0]
        return rebuild(d), d
    candidates, rebuild = _candidates(model, vectors, seconds, settings, postures)
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
    settings: Settings | None = None,
    postures: Sequence[NDArray[np.float64]] | None = None,
) -> list[float]:
    """Per-part budgets (numbers per second of each part) that share ``budget`` numbers per
    second of a ``span``-second recording between its parts (its arms imitated one by one,
    each ``(segment vectors, seconds)``): the combination of descriptions (one per part,
    :func:`describe_segments`) with the least summed squared error whose numbers together
    fit ``budget × span``. ``settings`` and each part's ``postures`` as in
    :func:`describe_segments`."""
    posts = list(postures) if postures is not None else [None] * len(parts)
    options = [
        _candidates(model, x, sec, settings, post)[0]
        for (x, sec), post in zip(parts, posts, strict=True)
    ]
    total = budget * span * (1 + 1e-12)
    # Every combination, as arrays over the grid of one choice per part.
    numbers = np.zeros(())
    errors = np.zeros(())
    for o in options:
        numbers = np.add.outer(numbers, [d.numbers for d, _ in o])
        errors = np.add.outer(errors, [e for _, e in o])
    fits = numbers <= total
    best: tuple[float, tuple[int, ...]] | None = None
    if fits.any():
        flat = int(np.argmin(np.where(fits, errors, np.inf)))
        best = (
            float(errors.flat[flat]),
            tuple(int(i) for i in np.unravel_index(flat, errors.shape)),
        )
    if best is None:
        least = sum(o[0][0].numbers for o in options) / span
        raise ValueError(
            f"budget {budget:g} numbers/s is below the smallest description of this movement "
            f"({least:.1f} numbers/s: the nearest primitive for each of its {len(parts)} parts)"
        )
    return [o[j][0].numbers_per_s for o, j in zip(options, best[1], strict=True)]


# ---------------------------------------------------------------------------- whole movement


def describe_movement(
    book: Any,
    directions: NDArray[np.float64],
    angles: NDArray[np.float64],
    seconds: float,
    budget: float,
    code_family: str = WHOLE_FAMILY,
) -> tuple[NDArray[np.float64], Description]:
    """One whole movement (no segments) described within ``budget`` numbers per second
    through the eigen-movements ``book`` (:class:`~visprim.rate.descriptions.EigenMovements`,
    learned from training movements): its bone directions ``(T, 6)`` rebuilt by the
    encoder's choice of the eigen-movements or the DCT of its 4 arm angles ``(T, 4)``
    (``code_family``, one of :data:`~visprim.rate.descriptions.EIGEN_FAMILIES` but
    ``eigen``; by default ``eigen/dct-fit3``, what the nested leave-one-actor-out chose on
    HDM05 at every budget from 10 to 20, docs/rate.rst;
    :func:`~visprim.rate.descriptions.eigen_describe`), and the :class:`Description` used:
    ``family`` ``"eigen"`` (eigen-movement coefficients) or ``"eigen/dct"`` (DCT
    coefficients), ``m`` its coefficients, ``numbers`` all it stores (start, duration, the
    flag or split index and the coefficients)."""
    from visprim.features import from_angles
    from visprim.rate.descriptions import EIGEN_CHOICE, EIGEN_HEAD, eigen_describe

    if code_family == "eigen":
        raise ValueError("code_family: a family with a DCT alternative, not 'eigen'")
    code, rebuilt, numbers = eigen_describe(book, code_family, budget, seconds, directions, angles)
    m = numbers - EIGEN_HEAD - EIGEN_CHOICE
    family = "eigen" if code == "eigen" else "eigen/dct"
    values = rebuilt if code == "eigen" else from_angles(rebuilt, "directions")
    return values, Description(family, m, numbers, float(seconds))


# ------------------------------------------------------------------ a model's eigen-movements


def one_arm_movements(
    model: Any, trials: Sequence[Any]
) -> list[tuple[NDArray[np.float64], NDArray[np.float64], float]]:
    """The one-arm movements of ``trials`` as a fitted ``model`` segments them: for every
    trial with a segment and every arm of it, the low-passed bone directions ``(T, 6)``
    and arm angles ``(T, 4)`` rad (a left arm in the mirror convention, so it moves like a
    right arm) over the span its segments cover, and that span, seconds. These are the
    movements :func:`describe_movement` describes, in training and in imitation alike."""
    from visprim.features import from_angles

    corpus = model.prepare(list(trials))
    out = []
    for times, angles, segs in zip(corpus.times, corpus.angles, corpus.segments, strict=True):
        if segs.shape[0] == 0:
            continue
        span = (times >= segs[0, 0] - 1e-9) & (times <= segs[-1, 1] + 1e-9)
        seconds = float(segs[-1, 1] - segs[0, 0])
        for c in range(0, angles.shape[1], ARM_ANGLES):
            arm = np.ascontiguousarray(angles[span, c : c + ARM_ANGLES])
            out.append((from_angles(arm, "directions"), arm, seconds))
    return out


def learn_eigen_movements(model: Any, trials: Sequence[Any]) -> Any:
    """The eigen-movements (:class:`~visprim.rate.descriptions.EigenMovements`) of a
    fitted ``model``'s training ``trials``: :func:`~visprim.rate.fit_eigen_movements` of
    their one-arm movements (:func:`one_arm_movements`, every arm the model has, the left
    mirrored), what ``visprim learn`` stores in the model file for ``imitate --budget``.
    None with fewer than two movements or no variance among them (nothing to learn)."""
    from visprim.rate.descriptions import fit_eigen_movements

    movements = one_arm_movements(model, trials)
    if len(movements) < 2:
        return None
    book = fit_eigen_movements([d for d, _, _ in movements])
    return book if book.n_components > 0 else None
