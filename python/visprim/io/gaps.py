"""Gaps in marker data: fill the short ones, split (or refuse) at the long ones.

A *gap* is a run of consecutive frames where a point is missing (NaN in any coordinate).
Its length is ``frames × frame period`` (seconds).

* Interior gaps up to ``max_gap`` seconds are filled by interpolating each coordinate through
  all valid samples of that point in the piece: ``"cubic"`` (default; scipy's not-a-knot
  ``CubicSpline``), ``"pchip"`` (shape-preserving, no overshoot) or ``"linear"``.
* Longer gaps are never filled: with ``on_gap="split"`` the recording is cut there into
  pieces, with ``"longest"`` only the longest piece is kept, with ``"raise"`` a
  :class:`~visprim.io.errors.GapError` names the point and the frames.
* Missing frames at the start or end of a piece cannot be interpolated (no sample on one
  side) and are never extrapolated: they are trimmed. Trimming more than ``max_gap`` counts
  as a long gap (so ``"raise"`` raises).
* Pieces shorter than ``min_duration`` seconds are dropped with a warning.

Everything done is reported in a :class:`GapReport` (stored in ``Trial.meta["gaps"]``).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline, PchipInterpolator

from visprim import params
from visprim.io.errors import GapError

GAP_METHODS = params.GAP_METHODS
ON_GAP = params.ON_GAP


@dataclass
class GapReport:
    """What gap handling did (frame indices refer to the original recording)."""

    filled: list[tuple[str, int, int]] = field(default_factory=list)
    long: list[tuple[str, int, int]] = field(default_factory=list)
    trimmed_frames: int = 0
    dropped_pieces: list[tuple[int, int]] = field(default_factory=list)
    pieces: list[tuple[int, int]] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return {
            "filled_runs": len(self.filled),
            "filled_frames": int(sum(b - a for _, a, b in self.filled)),
            "long_gaps": [{"point": p, "frames": [a, b]} for p, a, b in self.long],
            "trimmed_frames": self.trimmed_frames,
            "dropped_pieces": [list(x) for x in self.dropped_pieces],
            "pieces": [list(x) for x in self.pieces],
        }


def missing_runs(missing: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``[start, stop)`` frame ranges of the True runs of a 1-D boolean array."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], missing.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def check_gap_options(max_gap: float, on_gap: str, method: str) -> None:
    """Validate the gap arguments (ValueError naming the argument)."""
    if not np.isfinite(max_gap) or max_gap < 0:
        raise ValueError(f"max_gap must be a non-negative number of seconds, got {max_gap!r}")
    if on_gap not in ON_GAP:
        raise ValueError(f"on_gap must be one of {', '.join(ON_GAP)}, got {on_gap!r}")
    if method not in GAP_METHODS:
        raise ValueError(f"gap_method must be one of {', '.join(GAP_METHODS)}, got {method!r}")


def _interpolate(
    t: NDArray[np.float64], y: NDArray[np.float64], ok: NDArray[np.bool_], method: str
) -> NDArray[np.float64]:
    """Fill ``y[~ok]`` (rows) from ``y[ok]``; ``ok`` is True at both ends."""
    tv, yv = t[ok], y[ok]
    tq = t[~ok]
    if method == "linear" or tv.size < 4:
        filled = np.stack([np.interp(tq, tv, yv[:, k]) for k in range(y.shape[1])], axis=1)
    elif method == "pchip":
        filled = PchipInterpolator(tv, yv, axis=0)(tq)
    else:
        filled = CubicSpline(tv, yv, axis=0)(tq)
    out = y.copy()
    out[~ok] = filled
    return out


def fill_and_split(
    path: str,
    times: NDArray[np.float64],
    points: NDArray[np.float64],
    names: Sequence[str],
    *,
    max_gap: float = 0.2,
    on_gap: str = "split",
    method: str = "cubic",
    min_duration: float = 0.5,
) -> tuple[list[tuple[int, int, NDArray[np.float64]]], GapReport]:
    """Fill short gaps and cut at long ones.

    Parameters
    ----------
    path : str
        For error messages.
    times : (T,) seconds
    points : (T, P, 3) with NaN where a point is missing
    names : P point names, for messages and the report
    max_gap, on_gap, method, min_duration : see the module docstring

    Returns
    -------
    pieces : list of ``(start, stop, filled)``, ``filled`` (stop − start, P, 3) finite
    report : GapReport
    """
    check_gap_options(max_gap, on_gap, method)
    n = times.shape[0]
    period = float(np.median(np.diff(times))) if n > 1 else 0.0
    valid = np.asarray(np.isfinite(points).all(axis=2), dtype=bool)
    report = GapReport()
    cut = np.zeros(n, dtype=bool)
    long_mask = np.zeros(n, dtype=bool)
    for p, name in enumerate(names):
        for a, b in missing_runs(~valid[:, p]):
            edge = a == 0 or b == n
            too_long = (b - a) * period > max_gap + 1e-9
            if too_long:
                report.long.append((name, a, b))
                long_mask[a:b] = True
            if too_long or edge:
                cut[a:b] = True
    report.trimmed_frames = int(np.count_nonzero(cut & ~long_mask))
    if report.long and on_gap == "raise":
        name, a, b = max(report.long, key=lambda r: r[2] - r[1])
        raise GapError(
            path,
            f"{len(report.long)} gap(s) longer than max_gap={max_gap:g} s; the longest: "
            f"{name} missing in frames {a}–{b - 1} ({(b - a) * period:.3f} s). Use "
            "on_gap='split' to cut the recording there, or a larger max_gap",
        )
    pieces: list[tuple[int, int, NDArray[np.float64]]] = []
    for a, b in missing_runs(~cut):
        # Trim frames at the piece's ends where some point is missing (never extrapolate).
        ok_rows = np.asarray(valid[a:b].all(axis=1), dtype=bool)
        if not ok_rows.any():
            report.trimmed_frames += b - a
            continue
        first = a + int(np.argmax(ok_rows))
        last = a + len(ok_rows) - int(np.argmax(ok_rows[::-1]))
        report.trimmed_frames += (first - a) + (b - last)
        a, b = first, last
        piece = points[a:b].copy()
        t = times[a:b]
        for p, name in enumerate(names):
            ok = valid[a:b, p]
            if ok.all():
                continue
            for ra, rb in missing_runs(~ok):
                report.filled.append((name, a + ra, a + rb))
            piece[:, p] = _interpolate(t, piece[:, p], ok, method)
        if b - a < 2 or times[b - 1] - times[a] < min_duration:
            report.dropped_pieces.append((a, b))
            continue
        pieces.append((a, b, piece))
    if report.dropped_pieces:
        warnings.warn(
            f"{path}: dropped {len(report.dropped_pieces)} piece(s) between long gaps, "
            f"shorter than min_duration={min_duration:g} s or 2 frames",
            stacklevel=3,
        )
    if not pieces:
        raise GapError(
            path,
            f"no piece of at least {min_duration:g} s without gaps longer than "
            f"max_gap={max_gap:g} s (longest gap: "
            + (
                "{} frames {}–{}".format(*max(report.long, key=lambda r: r[2] - r[1]))
                if report.long
                else "none"
            )
            + ")",
        )
    if on_gap == "longest" and len(pieces) > 1:
        keep = max(pieces, key=lambda x: x[1] - x[0])
        for a, b, _ in pieces:
            if (a, b) != keep[:2]:
                report.dropped_pieces.append((a, b))
        pieces = [keep]
    report.pieces = [(a, b) for a, b, _ in pieces]
    return pieces, report
