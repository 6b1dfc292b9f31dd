"""The C3D binary format, read with numpy: header, parameter section and 3-D points.

Every offset, count and size in the file is checked against the file's own length before
it is used, so a damaged file raises a :class:`~visprim.io.errors.ReadError` naming the
problem; nothing is allocated beyond what the file holds. (The C++ reader ezc3d, used
before, dereferenced unchecked parameter dimensions: one flipped byte crashed the process.)

Layout (C3D.org, "The C3D File Format User Guide"), in 512-byte blocks:

* block 1, the header: byte 0 = first parameter block, byte 1 = 0x50 (the C3D key);
  16-bit words 2-12: points per frame, analog values per frame, first and last frame,
  maximum interpolation gap, scale factor (float; negative means float data), first data
  block, analog samples per frame, frame rate (float).
* the parameter section: 4 bytes (byte 2 = number of blocks, byte 3 = 83 + processor: 1
  Intel, 2 DEC, 3 MIPS = big-endian), then group and parameter records, each with a signed
  name length, a group id (negative: group), the name, a 16-bit offset to the next record,
  and for parameters a type (-1 char, 1 byte, 2 int16, 4 float), dimensions and values.
* the data: per frame, for every point X, Y, Z and a residual word (negative: the point is
  missing), then the analog samples; 16-bit integers times ``POINT:SCALE``, or 32-bit
  floats when the scale is negative.

Points whose residual is negative are NaN. Analog samples are not decoded (only their
channel labels and rate are reported).
"""

from __future__ import annotations

import math
import os
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.io.errors import MalformedFileError, ReadError, TruncatedFileError
from visprim.io.text import MAX_RECORDING_BYTES, check_file_size

BLOCK = 512
C3D_KEY = 0x50
#: Processor byte (83 + type) → name.
PROCESSORS = {84: "Intel", 85: "DEC", 86: "MIPS"}
_TYPES = {-1: 1, 1: 1, 2: 2, 4: 4}  # parameter type → bytes per value


@dataclass
class C3DFile:
    """A decoded C3D file.

    ``points`` (T, N, 3): coordinates in the file's units and axes, NaN where missing;
    ``parameters[group][name]``: a list of strings (char) or a 1-D array (numbers);
    ``n_frames_declared``: the frame count the header (or TRIAL group) declares.
    """

    path: str
    processor: str
    points: NDArray[np.float64]
    header_rate: float
    first_frame: int
    n_frames_declared: int
    parameters: dict[str, dict[str, Any]] = field(default_factory=dict)

    def param(self, group: str, name: str) -> Any:
        """A parameter's value, or None when the file does not have it."""
        return self.parameters.get(group, {}).get(name)

    def labels(self, group: str, n: int) -> list[str]:
        """``group:LABELS`` continued by ``LABELS2``, ``LABELS3``... (files with > 255
        points), cut to ``n`` names."""
        out: list[str] = []
        key, k = "LABELS", 1
        while len(out) < n:
            value = self.param(group, key)
            if value is None:
                break
            out.extend(str(v) for v in (value if isinstance(value, list) else [value]))
            k += 1
            key = f"LABELS{k}"
        return out[:n]


def _dec_to_ieee(raw: bytes | NDArray[np.uint8]) -> NDArray[np.float32]:
    """DEC (VAX F-floating) 4-byte floats → IEEE: swap the 16-bit halves, divide by 4."""
    b = np.frombuffer(raw, dtype=np.uint8).reshape(-1, 4)[:, [2, 3, 0, 1]]
    return (np.ascontiguousarray(b).view("<f4").ravel() / 4).astype(np.float32)


class _Reader:
    """Checked access to the file's bytes in its processor's byte order."""

    def __init__(self, path: str, data: bytes, processor: int) -> None:
        self.path = path
        self.data = data
        self.dec = processor == 85
        self.end = ">" if processor == 86 else "<"

    def need(self, pos: int, n: int, what: str) -> None:
        if pos < 0 or pos + n > len(self.data):
            raise TruncatedFileError(
                self.path,
                f"{what} at byte {pos} lies beyond the end of the file ({len(self.data)} bytes)",
            )

    def ints(self, pos: int, n: int, fmt: str, what: str) -> tuple[int, ...]:
        size = struct.calcsize(fmt) * n
        self.need(pos, size, what)
        return struct.unpack_from(self.end + fmt * n, self.data, pos)

    def floats(self, pos: int, n: int, what: str) -> NDArray[np.float32]:
        self.need(pos, 4 * n, what)
        raw = self.data[pos : pos + 4 * n]
        if self.dec:
            return _dec_to_ieee(raw)
        return np.frombuffer(raw, dtype=self.end + "f4").astype(np.float32)


def _text(raw: bytes) -> str:
    try:
        return raw.decode("utf-8").strip(" \x00")
    except UnicodeDecodeError:
        return raw.decode("latin-1").strip(" \x00")


def _parameters(r: _Reader, start: int, n_blocks: int) -> dict[str, dict[str, Any]]:
    """Walk the group and parameter records of the parameter section (bounds-checked)."""
    path = r.path
    end = start + n_blocks * BLOCK
    groups: dict[int, str] = {}
    params: list[tuple[int, str, Any, int]] = []
    pos = start + 4
    while pos + 2 <= end:
        n_chars, gid = struct.unpack_from("bb", r.data, pos)
        if n_chars == 0:
            break
        at = pos
        name_len = abs(n_chars)
        if gid == 0:
            raise MalformedFileError(path, f"parameter record at byte {at} has group id 0")
        if pos + 2 + name_len + 2 > end:
            raise MalformedFileError(
                path, f"parameter record at byte {at} runs past the parameter section"
            )
        name = _text(r.data[pos + 2 : pos + 2 + name_len]).upper()
        if not name:
            raise MalformedFileError(path, f"parameter record at byte {at} has an empty name")
        link = pos + 2 + name_len
        (offset,) = r.ints(link, 1, "h", "parameter offset")
        if offset < 0:
            raise MalformedFileError(path, f"record {name!r} at byte {at}: negative offset")
        nxt = link + offset if offset > 0 else end
        if nxt > end:
            raise MalformedFileError(
                path, f"record {name!r} at byte {at} points past the parameter section"
            )
        q = link + 2
        if gid < 0:
            if -gid in groups and groups[-gid] != name:
                raise MalformedFileError(path, f"group id {-gid} is used by two groups")
            groups[-gid] = name
        else:
            if q + 2 > nxt:
                raise MalformedFileError(path, f"parameter {name!r} at byte {at} is cut short")
            type_code, n_dims = struct.unpack_from("bB", r.data, q)
            if type_code not in _TYPES:
                raise MalformedFileError(
                    path, f"parameter {name!r} at byte {at} has unknown type {type_code}"
                )
            if n_dims > 7:
                raise MalformedFileError(
                    path, f"parameter {name!r} at byte {at} has {n_dims} dimensions (max 7)"
                )
            dims = list(r.data[q + 2 : q + 2 + n_dims])
            count = math.prod(dims)
            size = count * _TYPES[type_code]
            body = q + 2 + n_dims
            if body + size > nxt:
                raise MalformedFileError(
                    path,
                    f"parameter {name!r} at byte {at}: dimensions {dims} need {size} bytes, "
                    f"the record holds {max(nxt - body, 0)}",
                )
            params.append((gid, name, _value(r, body, type_code, dims), at))
        if offset == 0:
            break
        pos = nxt
    out: dict[str, dict[str, Any]] = {g: {} for g in groups.values()}
    for gid, name, value, at in params:
        if gid not in groups:
            raise MalformedFileError(
                path, f"parameter {name!r} at byte {at} belongs to group {gid}, which is missing"
            )
        out[groups[gid]][name] = value
    return out


def _value(r: _Reader, pos: int, type_code: int, dims: list[int]) -> Any:
    count = math.prod(dims)
    if type_code == -1:
        raw = r.data[pos : pos + count]
        if count == 0:
            return []
        if len(dims) <= 1:
            return [_text(raw)]
        width = dims[0]
        return [_text(raw[i : i + width]) for i in range(0, count, width)]
    if type_code == 1:
        return np.frombuffer(r.data[pos : pos + count], dtype=np.int8).astype(np.int64)
    if type_code == 2:
        return np.frombuffer(r.data[pos : pos + 2 * count], dtype=r.end + "i2").astype(np.int64)
    return r.floats(pos, count, "parameter values").astype(np.float64)


def _scalar(value: Any, default: float | None = None) -> float | None:
    if value is None or isinstance(value, list) or np.size(value) == 0:
        return default
    return float(np.ravel(value)[0])


def read_c3d(path: str | os.PathLike[str]) -> C3DFile:
    """Decode a C3D file's header, parameters and points (see the module docstring).

    Raises
    ------
    TruncatedFileError
        Empty file, cut inside the header or parameters, or fewer frames than declared.
    MalformedFileError
        Not a C3D file, or an inconsistent header or parameter section.
    """
    path = os.fspath(path)
    size = check_file_size(path, MAX_RECORDING_BYTES)
    try:
        with open(path, "rb") as fh:
            data = fh.read(size + 1)
    except OSError as exc:
        raise ReadError(path, f"cannot read: {exc.strerror or exc}") from None
    if not data:
        raise TruncatedFileError(path, "the file is empty")
    if len(data) < BLOCK:
        raise TruncatedFileError(
            path, f"cut short ({len(data)} bytes; a C3D header alone is {BLOCK})"
        )
    param_block, key = data[0], data[1]
    if key != C3D_KEY or param_block < 2:
        raise MalformedFileError(
            path, "not a readable C3D file (no C3D key 0x50 / parameter block in the header)"
        )
    p_start = (param_block - 1) * BLOCK
    if p_start + 4 > len(data):
        raise TruncatedFileError(
            path, f"cut short before the parameter section ({len(data)} bytes)"
        )
    n_blocks, proc = data[p_start + 2], data[p_start + 3]
    if proc not in PROCESSORS:
        raise MalformedFileError(
            path, f"not a readable C3D file (unknown processor type {proc}; expected 84-86)"
        )
    if n_blocks == 0:
        raise MalformedFileError(path, "the parameter section declares 0 blocks")
    if p_start + n_blocks * BLOCK > len(data):
        raise TruncatedFileError(
            path,
            f"cut short inside the parameter section ({n_blocks} blocks from block "
            f"{param_block}; the file has {len(data)} bytes)",
        )
    r = _Reader(path, data, proc)
    (n_points, n_analog, first, last, _gap) = r.ints(2, 5, "H", "header")
    scale_h = float(r.floats(12, 1, "header scale")[0])
    (data_start,) = r.ints(16, 1, "H", "header")
    (analog_per_frame,) = r.ints(18, 1, "H", "header")
    rate_h = float(r.floats(20, 1, "header rate")[0])
    params = _parameters(r, p_start, n_blocks)

    n_frames = last - first + 1
    trial = params.get("TRIAL", {})
    start_f, end_f = trial.get("ACTUAL_START_FIELD"), trial.get("ACTUAL_END_FIELD")
    if start_f is not None and end_f is not None and np.size(start_f) >= 2 and np.size(end_f) >= 2:
        s = int(start_f[0]) & 0xFFFF | (int(start_f[1]) & 0xFFFF) << 16
        e = int(end_f[0]) & 0xFFFF | (int(end_f[1]) & 0xFFFF) << 16
        if e >= s >= 1 and e - s + 1 > n_frames:
            first, n_frames = s, e - s + 1
    if n_frames < 0:
        raise MalformedFileError(path, f"header: last frame {last} precedes first frame {first}")
    used = _scalar(params.get("POINT", {}).get("USED"))
    if used is not None and int(used) & 0xFFFF != n_points:
        raise MalformedFileError(
            path, f"POINT:USED is {int(used)} but the header declares {n_points} points"
        )
    scale = _scalar(params.get("POINT", {}).get("SCALE"), scale_h)
    assert scale is not None
    if not math.isfinite(scale):
        raise MalformedFileError(path, f"the point scale factor is {scale!r}")
    is_float = scale < 0
    if analog_per_frame and n_analog % analog_per_frame:
        raise MalformedFileError(
            path,
            f"header: {n_analog} analog values per frame is not a multiple of "
            f"{analog_per_frame} samples per frame",
        )
    if data_start < param_block + n_blocks:
        raise MalformedFileError(
            path,
            f"header: data block {data_start} lies inside the parameter section "
            f"(blocks {param_block}-{param_block + n_blocks - 1})",
        )
    width = 4 if is_float else 2
    frame_values = 4 * n_points + n_analog
    frame_bytes = frame_values * width
    d_start = (data_start - 1) * BLOCK
    available = max(len(data) - d_start, 0)
    held = available // frame_bytes if frame_bytes else n_frames
    if held < n_frames:
        raise TruncatedFileError(
            path, f"the header declares {n_frames} frames but the file holds only {held}"
        )
    points = _points(r, d_start, n_frames, n_points, frame_values, is_float, abs(scale))
    return C3DFile(
        path=path,
        processor=PROCESSORS[proc],
        points=points,
        header_rate=rate_h,
        first_frame=first,
        n_frames_declared=n_frames,
        parameters=params,
    )


def _points(
    r: _Reader,
    start: int,
    n_frames: int,
    n_points: int,
    frame_values: int,
    is_float: bool,
    scale: float,
) -> NDArray[np.float64]:
    """(T, N, 3) coordinates, NaN where the residual word is negative."""
    if n_points == 0 or n_frames == 0:
        return np.zeros((n_frames, n_points, 3))
    width = 4 if is_float else 2
    raw = r.data[start : start + n_frames * frame_values * width]
    if is_float:
        flat = _dec_to_ieee(raw) if r.dec else np.frombuffer(raw, dtype=r.end + "f4")
    else:
        flat = np.frombuffer(raw, dtype=r.end + "i2")
    table = flat.reshape(n_frames, frame_values)[:, : 4 * n_points].reshape(n_frames, n_points, 4)
    # (A signalling NaN in float data widens to a quiet NaN: a missing value like any other.)
    with np.errstate(invalid="ignore"):
        xyz = table[:, :, :3].astype(np.float64)
    if not is_float:
        xyz *= scale
    if is_float:
        with np.errstate(invalid="ignore"):
            resid = np.trunc(table[:, :, 3].astype(np.float64))
        missing = ~(resid >= 0)  # NaN residuals count as missing too
    else:
        missing = table[:, :, 3] < 0
    xyz[missing] = np.nan
    return xyz
