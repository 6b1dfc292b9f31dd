"""The plain marker CSV format: one row per sample, a timestamp and each sensor's x, y, z.

It mirrors the original FastTrak recordings of the method (four sensors read every 34 ms)
and is what ``visprim generate --out DIR`` writes. Example::

    # visprim marker CSV v1
    # name: s03_m07
    # subject: 3
    # stimulus: 7
    # repetitions: 2
    # frame: metres; +x forward, +y subject's left, +z up; right arm
    # sensors: upper_arm = centre of the upper arm; forearm = centre of the forearm; ...
    # precision: time 1e-6 s, position 1e-5 m
    time_s,upper_arm_x_m,upper_arm_y_m,upper_arm_z_m,forearm_x_m,...,finger_z_m
    0.000000,0.05012,-0.21034,1.27311,...

Rules (the reader enforces them and raises :class:`MarkerCSVError`, a ValueError naming
the file, the line and the problem):

* Comment lines start with ``#``; ``# key: value`` lines before the header are metadata
  (``name``, ``subject``, ``stimulus``, ``repetitions`` are understood, the others go to
  ``Trial.meta``). Blank lines are ignored.
* The header has ``time_s`` (or ``time_ms``) and, for each of the four sensors of
  :data:`visprim.trial.MARKER_NAMES`, the columns ``<sensor>_<axis>_<unit>`` with axis x, y,
  z and unit ``m`` or ``mm`` (all three axes of a sensor in the same unit). Columns may come
  in any order; unknown columns are an error.
* Every row has one finite number per column; timestamps strictly increase.

Precision: :func:`write_marker_csv` writes times with 6 decimals (1 µs) and positions in
metres with 5 decimals (0.01 mm), so a round trip reproduces times within 0.5 µs and
positions within 0.005 mm, and re-writing a file that was read back gives the same
data rows.

Ground truth (generated trials) goes to a sidecar ``<stem>.truth.json`` beside the CSV
(angles in radians, boundaries in seconds, labels, repetitions; floats written exactly);
:func:`read_marker_csv` attaches it as ``Trial.truth`` when present.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from visprim.io.assemble import period_problem
from visprim.io.errors import ReadError, TruncatedFileError
from visprim.io.text import read_text
from visprim.trial import MARKER_NAMES, Trial, TrialError, Truth

FORMAT_LINE = "# visprim marker CSV v1"
TIME_DECIMALS = 6
POSITION_DECIMALS = 5
_UNITS = {"m": 1.0, "mm": 1e-3}
_TIME_UNITS = {"time_s": 1.0, "time_ms": 1e-3}
_SENSOR_DESCRIPTIONS = {
    "upper_arm": "centre of the upper arm",
    "forearm": "centre of the forearm",
    "wrist": "just above the wrist",
    "finger": "middle finger, proximal phalanx",
}
_FRAME = "metres; +x forward, +y subject's left, +z up; right arm"
_RESERVED = {"name", "subject", "stimulus", "repetitions"}


class MarkerCSVError(ValueError):
    """A marker CSV file is malformed; the message names the file, line and problem."""


def truth_path(path: str | Path) -> Path:
    """The ground-truth sidecar of a marker CSV: ``<stem>.truth.json`` beside it."""
    p = Path(path)
    return p.with_name(p.stem + ".truth.json")


def _header_columns() -> list[str]:
    cols = ["time_s"]
    for name in MARKER_NAMES:
        cols += [f"{name}_{axis}_m" for axis in "xyz"]
    return cols


def _meta_value(value: Any) -> str | None:
    """A metadata value as one line of text, or None if it does not fit in a comment."""
    if isinstance(value, bool | int | float | str) and not isinstance(value, np.ndarray):
        text = str(value)
        return text if "\n" not in text and "\r" not in text else None
    if isinstance(value, np.integer | np.floating):
        return str(value.item())
    return None


def write_marker_csv(path: str | Path, trial: Trial, *, truth: bool = True) -> Path:
    """Write ``trial`` as a marker CSV file (and its truth sidecar).

    Parameters
    ----------
    path : str or Path
        Output file (parent folders must exist).
    trial : Trial
        Times in seconds, markers (T, 4, 3) in metres.
    truth : bool
        Also write ``<stem>.truth.json`` when ``trial.truth`` is set (default True).

    Returns
    -------
    Path
        ``path``. Scalar ``trial.meta`` entries are written as comments; arrays are not.
    """
    p = Path(path)
    lines = [FORMAT_LINE]
    header: dict[str, Any] = {
        "name": trial.name or p.stem,
        "subject": trial.subject,
        "stimulus": trial.stimulus,
        "repetitions": trial.repetitions,
        "frame": _FRAME,
        "sensors": "; ".join(f"{k} = {v}" for k, v in _SENSOR_DESCRIPTIONS.items()),
        "precision": f"time 1e-{TIME_DECIMALS} s, position 1e-{POSITION_DECIMALS} m",
    }
    for key, value in trial.meta.items():
        if key not in header and key.isidentifier():
            header[key] = value
    for key, value in header.items():
        text = _meta_value(value)
        if text is not None:
            lines.append(f"# {key}: {text}")
    lines.append(",".join(_header_columns()))
    table = np.concatenate(
        [trial.times[:, None], trial.markers.reshape(trial.n_frames, 12)], axis=1
    )
    fmt = ",".join([f"%.{TIME_DECIMALS}f"] + [f"%.{POSITION_DECIMALS}f"] * 12)
    rows = [fmt % tuple(row) for row in table.tolist()]
    p.write_text("\n".join(lines + rows) + "\n", encoding="utf-8")
    if truth and trial.truth is not None:
        t = trial.truth
        doc = {
            "name": trial.name or p.stem,
            "angles_rad": t.angles.tolist(),
            "boundaries_s": t.boundaries.tolist(),
            "labels": [int(x) for x in t.labels],
            "repetitions": int(t.repetitions),
        }
        truth_path(p).write_text(json.dumps(doc), encoding="utf-8")
    return p


def _parse_header(
    cells: list[str], where: str
) -> tuple[int, float, list[tuple[int, int, int, float]]]:
    """Map header cells to (time column, time scale, [(column, sensor, axis, scale)])."""
    cells = [c.strip() for c in cells]
    time_cols = [i for i, c in enumerate(cells) if c in _TIME_UNITS]
    if len(time_cols) != 1:
        raise MarkerCSVError(
            f"{where}: header needs exactly one time column (time_s or time_ms), "
            f"found {len(time_cols)}: {','.join(cells[:14])}{',...' if len(cells) > 14 else ''}"
        )
    seen: dict[tuple[str, str], tuple[int, str]] = {}
    sensors: dict[str, None] = {}  # insertion-ordered set
    for i, cell in enumerate(cells):
        if i == time_cols[0]:
            continue
        parts = cell.rsplit("_", 2)
        if len(parts) != 3 or parts[1] not in ("x", "y", "z") or parts[2] not in _UNITS:
            raise MarkerCSVError(f"{where}: column {i + 1} {cell!r} is not <sensor>_<x|y|z>_<m|mm>")
        sensor, axis, unit = parts
        if (sensor, axis) in seen:
            raise MarkerCSVError(f"{where}: column {cell!r} appears twice")
        seen[(sensor, axis)] = (i, unit)
        sensors.setdefault(sensor)
    if set(sensors) != set(MARKER_NAMES):
        missing = [s for s in MARKER_NAMES if s not in sensors]
        extra = [s for s in sensors if s not in MARKER_NAMES]
        detail = []
        if missing:
            detail.append("missing " + ", ".join(missing))
        if extra:
            detail.append("unknown " + ", ".join(extra[:5]) + (" ..." if len(extra) > 5 else ""))
        raise MarkerCSVError(
            f"{where}: expected {len(MARKER_NAMES)} sensors ({', '.join(MARKER_NAMES)}), "
            f"found {len(sensors)}" + (f" ({'; '.join(detail)})" if detail else "")
        )
    columns = []
    for k, sensor in enumerate(MARKER_NAMES):
        units = set()
        for a, axis in enumerate("xyz"):
            if (sensor, axis) not in seen:
                raise MarkerCSVError(f"{where}: missing column {sensor}_{axis}_m")
            col, unit = seen[(sensor, axis)]
            units.add(unit)
            columns.append((col, k, a, _UNITS[unit]))
        if len(units) > 1:
            raise MarkerCSVError(f"{where}: sensor {sensor} mixes units {sorted(units)}")
    return time_cols[0], _TIME_UNITS[cells[time_cols[0]]], columns


def _parse_int(value: str, key: str, where: str) -> int:
    try:
        return int(value)
    except ValueError:
        raise MarkerCSVError(f"{where}: {key} must be an integer, got {value!r}") from None


def _read_truth(path: Path, n_frames: int) -> Truth:
    where = str(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        angles = np.asarray(doc["angles_rad"], dtype=np.float64)
        boundaries = np.asarray(doc["boundaries_s"], dtype=np.float64)
        labels = np.asarray(doc["labels"], dtype=np.int64)
        reps = int(doc.get("repetitions", 1))
    except (OSError, json.JSONDecodeError, KeyError, TypeError, ValueError) as exc:
        raise MarkerCSVError(f"{where}: unreadable truth sidecar ({exc})") from None
    if angles.shape != (n_frames, 4):
        raise MarkerCSVError(
            f"{where}: truth angles have shape {angles.shape}, the CSV has {n_frames} frames"
        )
    if boundaries.ndim != 1 or labels.shape != (boundaries.size - 1,):
        raise MarkerCSVError(
            f"{where}: {boundaries.size} boundaries do not fit {labels.size} stroke labels"
        )
    return Truth(angles=angles, boundaries=boundaries, labels=labels, repetitions=reps)


def read_marker_csv(path: str | Path, *, repetitions: int | None = None) -> Trial:
    """Read a marker CSV file (format in the module docstring) into a :class:`Trial`.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    repetitions : int, optional
        Repetitions of the movement; default: the file's ``# repetitions:`` entry, else 1.

    Returns
    -------
    Trial
        Times in seconds, markers (T, 4, 3) in metres (``mm`` columns are converted),
        ``name`` (file metadata, else the file stem), ``subject`` / ``stimulus`` (int when
        they are integers), ``source`` = the path, ``meta`` with the other ``# key: value``
        entries and ``rate_hz`` (from the median frame period), ``truth`` from the
        ``<stem>.truth.json`` sidecar when present.

    Raises
    ------
    MarkerCSVError
        Unreadable, empty or malformed file: missing/unknown/duplicate columns, wrong
        sensor count, a row with the wrong number of cells, a non-numeric or non-finite
        cell, non-increasing timestamps, fewer than 2 rows.
    """
    p = Path(path)
    try:
        text, _ = read_text(p)
    except TruncatedFileError:
        raise MarkerCSVError(f"{p}: empty marker CSV (no header line)") from None
    except ReadError as exc:
        raise MarkerCSVError(f"{p}: {exc.reason}") from None
    meta: dict[str, Any] = {}
    header: tuple[int, float, list[tuple[int, int, int, float]]] | None = None
    n_cols = 0
    line_numbers: list[int] = []
    rows: list[list[float]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            if header is None and ":" in line:
                key, _, value = line[1:].partition(":")
                key = key.strip()
                if key:
                    meta[key] = value.strip()
            continue
        cells = line.split(",")
        if header is None:
            header = _parse_header(cells, f"{p}, line {lineno}")
            n_cols = len(cells)
            continue
        if len(cells) != n_cols:
            raise MarkerCSVError(
                f"{p}, line {lineno}: expected {n_cols} values, found {len(cells)}"
            )
        try:
            values = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _is_float(c))
            raise MarkerCSVError(f"{p}, line {lineno}: non-numeric value {bad.strip()!r}") from None
        if not all(math.isfinite(v) for v in values):
            col = next(i for i, v in enumerate(values) if not math.isfinite(v))
            cell = cells[col].strip()
            raise MarkerCSVError(
                f"{p}, line {lineno}: column {col + 1} is not a finite number ({cell!r})"
            )
        rows.append(values)
        line_numbers.append(lineno)
    if header is None:
        raise MarkerCSVError(f"{p}: empty marker CSV (no header line)")
    if len(rows) < 2:
        raise MarkerCSVError(f"{p}: a marker CSV needs at least 2 data rows, found {len(rows)}")
    table = np.asarray(rows, dtype=np.float64)
    time_col, time_scale, columns = header
    times = table[:, time_col] * time_scale
    steps = np.diff(times)
    if np.any(steps <= 0):
        i = int(np.argmax(steps <= 0)) + 1
        raise MarkerCSVError(
            f"{p}, line {line_numbers[i]}: timestamp {float(table[i, time_col])!r} does not "
            f"increase (previous row: {float(table[i - 1, time_col])!r})"
        )
    markers = np.empty((table.shape[0], len(MARKER_NAMES), 3))
    for col, k, a, scale in columns:
        markers[:, k, a] = table[:, col] * scale

    name = meta.pop("name", None) or p.stem
    subject = _maybe_int(meta.pop("subject", None))
    stimulus = _maybe_int(meta.pop("stimulus", None))
    file_reps = meta.pop("repetitions", None)
    if repetitions is None:
        repetitions = _parse_int(file_reps, "repetitions", str(p)) if file_reps else 1
    for key, value in list(meta.items()):
        meta[key] = _maybe_number(value)
    period = float(np.median(steps))
    problem = period_problem(period)
    if problem is not None:
        raise MarkerCSVError(f"{p}: the median time step is {problem}; check the time unit")
    meta["rate_hz"] = 1.0 / period
    meta["units_in_file"] = "mm" if any(s != 1.0 for *_, s in columns) else "m"
    sidecar = truth_path(p)
    truth = _read_truth(sidecar, table.shape[0]) if sidecar.is_file() else None
    try:
        return Trial(
            times=times,
            markers=markers,
            name=name,
            subject=subject,
            stimulus=stimulus,
            repetitions=repetitions,
            truth=truth,
            source=str(p),
            meta=meta,
        )
    except TrialError as exc:
        raise MarkerCSVError(str(exc)) from None


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _maybe_int(value: str | None) -> str | int | None:
    if value is None or value in ("", "None"):
        return None
    try:
        return int(value)
    except ValueError:
        return value


def _maybe_number(value: str) -> Any:
    for cast in (int, float):
        try:
            return cast(value)
        except ValueError:
            pass
    if value in ("True", "False"):
        return value == "True"
    return value
