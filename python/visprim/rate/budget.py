"""One movement described within a budget of numbers per second (``visprim imitate
--budget``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.rate.descriptions import movement_numbers

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
