"""OpenSim / Pose2Sim TRC marker files → keypoints → :class:`visprim.Trial`.

A TRC file is tab-separated text::

    PathFileType  4  (X/Y/Z)  walk.trc
    DataRate  CameraRate  NumFrames  NumMarkers  Units  OrigDataRate  ...
    60        60          100        22          m      60            ...
    Frame#  Time  RShoulder         RElbow  ...
                  X1   Y1   Z1      X2  Y2  Z2 ...
    1       0.000 0.1  1.4  0.2     ...

* Units from the header's ``Units`` (m, cm, mm); the rate from ``DataRate``.
* Times from the ``Time`` column; when it is absent or not strictly increasing, from
  ``Frame#`` / ``DataRate`` (``meta["times_from"]`` says which).
* Empty or NaN fields are missing samples: gaps, handled as for C3D (:mod:`visprim.io.gaps`).
* Axes: OpenSim's +Y up unless ``up_axis`` says otherwise (Pose2Sim writes Y-up TRC files).
* Markers are matched to the arm and torso roles by name (``RShoulder``, ``right_shoulder``,
  ``R_Elbow``...; see :mod:`visprim.io.keypoints`), or by an explicit ``mapping`` of roles to
  marker names.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.assemble import check_frame_period
from visprim.io.errors import MalformedFileError, ReadError, TruncatedFileError
from visprim.io.keypoints import read_error, trial_pieces_from_keypoints
from visprim.io.text import read_text

_UNITS = {"m": 1.0, "meters": 1.0, "cm": 0.01, "mm": 0.001, "millimeters": 0.001}
#: Most markers / frames a TRC file may declare (refused before allocating).
MAX_MARKERS = 10_000
MAX_FRAMES = 10_000_000


@dataclass
class TRCData:
    """A decoded TRC file: ``points`` (T, K, 3) in metres (NaN = missing), ``times`` (T,)
    seconds from the first frame, marker ``names``, ``rate`` (Hz) and header fields."""

    points: NDArray[np.float64]
    times: NDArray[np.float64]
    names: list[str]
    rate: float
    units: str
    meta: dict[str, Any] = field(default_factory=dict)


def _number(path: Path, text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise MalformedFileError(path, f"{what} is not a number ({text!r})") from None
    return value


def read_trc(path: str | os.PathLike[str]) -> TRCData:
    """Decode a TRC file (see the module docstring); :class:`ReadError` on any problem."""
    p = Path(path)
    text, _ = read_text(p)
    lines = text.splitlines()
    if len(lines) < 5:
        raise TruncatedFileError(p, f"a TRC file has 5 header lines, this one has {len(lines)}")
    if not lines[0].startswith("PathFileType"):
        raise MalformedFileError(p, "not a TRC file (the first line is not 'PathFileType ...')")
    keys = lines[1].split("\t")
    values = lines[2].split("\t")
    header = {k.strip(): v.strip() for k, v in zip(keys, values, strict=False) if k.strip()}
    for key in ("DataRate", "NumMarkers", "Units"):
        if key not in header:
            raise MalformedFileError(p, f"the header has no {key}")
    rate = _number(p, header["DataRate"], "DataRate")
    period = check_frame_period(str(p), 1.0 / rate if rate > 0 else float("nan"), "DataRate")
    units = header["Units"].lower()
    if units not in _UNITS:
        raise MalformedFileError(p, f"unknown Units {header['Units']!r} (m, cm or mm)")
    n_markers = int(_number(p, header["NumMarkers"], "NumMarkers"))
    if not 0 < n_markers <= MAX_MARKERS:
        raise MalformedFileError(p, f"NumMarkers {n_markers} outside 1..{MAX_MARKERS}")
    cols = lines[3].split("\t")
    if len(cols) < 2 or cols[0].strip() != "Frame#":
        raise MalformedFileError(p, "line 4 does not start with 'Frame#'")
    has_time = cols[1].strip().lower() == "time"
    first = 2 if has_time else 1
    names = [c.strip() for c in cols[first::3] if c.strip()]
    if len(names) != n_markers:
        raise MalformedFileError(
            p, f"the header declares {n_markers} markers, line 4 names {len(names)}"
        )
    rows = [ln for ln in lines[5:] if ln.strip()]
    if not rows:
        raise TruncatedFileError(p, "no data rows")
    if len(rows) > MAX_FRAMES:
        raise MalformedFileError(p, f"more than {MAX_FRAMES} frames")
    width = first + 3 * n_markers
    data = np.full((len(rows), width), np.nan)
    for i, row in enumerate(rows):
        fields = row.split("\t")
        if len(fields) > width and any(f.strip() for f in fields[width:]):
            raise MalformedFileError(p, f"line {i + 6} has {len(fields)} fields, expected {width}")
        for j, f in enumerate(fields[:width]):
            f = f.strip()
            if f:
                try:
                    data[i, j] = float(f)
                except ValueError:
                    raise MalformedFileError(
                        p, f"line {i + 6}, field {j + 1}: {f!r} is not a number"
                    ) from None
    frames = data[:, 0]
    times_from = "Time column"
    t = data[:, 1] if has_time else np.full(len(rows), np.nan)
    if not (np.isfinite(t).all() and np.all(np.diff(t) > 0)):
        if not (np.isfinite(frames).all() and np.all(np.diff(frames) > 0)):
            raise MalformedFileError(p, "neither Time nor Frame# increases strictly")
        t = (frames - frames[0]) * period
        times_from = "Frame# / DataRate"
    points = data[:, first:].reshape(len(rows), n_markers, 3) * _UNITS[units]
    return TRCData(
        points=points,
        times=t - t[0],
        names=names,
        rate=rate,
        units=units,
        meta={"times_from": times_from, "trc_header": header},
    )


def read_trc_pieces(
    path: str | os.PathLike[str],
    arm: str = "right",
    *,
    mapping: Mapping[str, str | Sequence[str]] | None = None,
    up_axis: str | None = None,
    mirror: bool = False,
    **gap_options: Any,
) -> list[Any]:
    """Trials from a TRC file (``arm``, ``mirror`` and the gap options as
    :func:`visprim.io.read_pieces`; ``mapping``: role → marker name(s), see
    :data:`visprim.io.keypoints.ROLES`)."""
    p = Path(path)
    data = read_trc(p)
    try:
        return trial_pieces_from_keypoints(
            data.points,
            "names" if mapping is None else dict(mapping),
            names=data.names,
            times=data.times,
            arm=arm,
            up_axis=up_axis or "+y",
            units="m",
            mirror=mirror,
            name=p.stem,
            source=p,
            meta={"format": "trc", "rate": data.rate, "units": data.units, **data.meta},
            **gap_options,
        )
    except ReadError:
        raise
    except ValueError as exc:
        raise read_error(p, exc) from None
