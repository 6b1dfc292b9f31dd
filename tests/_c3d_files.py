"""A small C3D writer for tests: Intel / DEC / MIPS processors, float or integer data.

Written from the format description (C3D.org user guide), independently of the reader in
:mod:`visprim.io.c3d_format`, so that round trips test the reader against the format.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

INTEL, DEC, MIPS = 84, 85, 86
# Plug-in Gait upper body: right arm, left shoulder and thorax markers.
PIG_LABELS = [
    "RSHO",
    "RUPA",
    "RELB",
    "RFRM",
    "RWRA",
    "RWRB",
    "RFIN",
    "LSHO",
    "C7",
    "T10",
    "CLAV",
    "STRN",
]


def _float_bytes(values: np.ndarray, processor: int) -> bytes:
    v = np.asarray(values, dtype=np.float64).ravel()
    if processor == MIPS:
        return v.astype(">f4").tobytes()
    if processor == DEC:
        ieee = (v * 4.0).astype("<f4").view(np.uint8).reshape(-1, 4)
        return np.ascontiguousarray(ieee[:, [2, 3, 0, 1]]).tobytes()
    return v.astype("<f4").tobytes()


def _end(processor: int) -> str:
    return ">" if processor == MIPS else "<"


def _param(name: str, gid: int, type_code: int, dims: list[int], data: bytes, proc: int) -> bytes:
    body = struct.pack("bB", type_code, len(dims)) + bytes(dims) + data + b"\x00"
    return (
        struct.pack("bb", len(name), gid)
        + name.encode()
        + struct.pack(_end(proc) + "h", 2 + len(body))
        + body
    )


def _group(name: str, gid: int, proc: int) -> bytes:
    body = b"\x00"
    return (
        struct.pack("bb", len(name), -gid)
        + name.encode()
        + struct.pack(_end(proc) + "h", 2 + len(body))
        + body
    )


def _chars(values: list[str]) -> tuple[list[int], bytes]:
    width = max(1, max(len(v) for v in values))
    return [width, len(values)], b"".join(v.ljust(width).encode() for v in values)


def c3d_bytes(
    labels: list[str],
    points: np.ndarray,
    *,
    rate: float = 100.0,
    units: str = "m",
    y_screen: str | None = "+Z",
    processor: int = INTEL,
    scale: float = -1.0,
    missing: np.ndarray | None = None,
) -> bytes:
    """A C3D file of ``points`` (T, N, 3) named ``labels``; ``scale`` < 0: float data,
    > 0: int16 data times ``scale``; ``missing`` (T, N) bool marks points with a negative
    residual."""
    n_frames, n_points = points.shape[:2]
    e = _end(processor)
    i16 = lambda *v: struct.pack(e + "h" * len(v), *v)  # noqa: E731
    records = [_group("POINT", 1, processor), _group("ANALOG", 2, processor)]
    records.append(_param("USED", 1, 2, [], i16(n_points), processor))
    records.append(_param("FRAMES", 1, 2, [], i16(n_frames), processor))
    records.append(_param("SCALE", 1, 4, [], _float_bytes(np.array([scale]), processor), processor))
    records.append(_param("RATE", 1, 4, [], _float_bytes(np.array([rate]), processor), processor))
    dims, raw = _chars(labels)
    records.append(_param("LABELS", 1, -1, dims, raw, processor))
    dims, raw = _chars([units])
    records.append(_param("UNITS", 1, -1, dims[:1], raw, processor))
    if y_screen is not None:
        dims, raw = _chars([y_screen])
        records.append(_param("Y_SCREEN", 1, -1, dims[:1], raw, processor))
    records.append(_param("USED", 2, 2, [], i16(0), processor))
    records.append(_param("RATE", 2, 4, [], _float_bytes(np.array([0.0]), processor), processor))
    params = b"".join(records) + b"\x00\x00"
    n_blocks = (4 + len(params) + 511) // 512
    section = bytes([1, 0x50, n_blocks, processor]) + params
    section = section.ljust(n_blocks * 512, b"\x00")
    data_start = 2 + n_blocks
    header = bytearray(512)
    header[0], header[1] = 2, 0x50
    struct.pack_into(e + "HHHHH", header, 2, n_points, 0, 1, n_frames, 0)
    header[12:16] = _float_bytes(np.array([scale]), processor)
    struct.pack_into(e + "HH", header, 16, data_start, 0)
    header[20:24] = _float_bytes(np.array([rate]), processor)
    miss = np.zeros((n_frames, n_points), dtype=bool) if missing is None else missing
    table = np.zeros((n_frames, n_points, 4))
    if scale < 0:
        table[:, :, :3] = points
        table[:, :, 3] = np.where(miss, -1.0, 0.0)
        data = _float_bytes(table, processor)
    else:
        table[:, :, :3] = np.round(points / scale)
        table[:, :, 3] = np.where(miss, -1, 0)
        data = table.astype(e + "i2").tobytes()
    return bytes(header) + section + data.ljust((len(data) + 511) // 512 * 512, b"\x00")


def arm_points(n_frames: int = 60, rate: float = 100.0) -> np.ndarray:
    """(T, 12, 3) metres, +z up, for :data:`PIG_LABELS`: a subject facing +x raising the
    right forearm."""
    t = np.arange(n_frames) / rate
    angle = 0.8 * np.sin(2 * np.pi * 0.7 * t)
    pts = np.zeros((n_frames, len(PIG_LABELS), 3))
    shoulder = np.array([0.0, -0.18, 1.45])
    elbow = shoulder + [0.0, 0.0, -0.29]
    fore = np.stack([0.26 * np.sin(angle), np.zeros_like(angle), -0.26 * np.cos(angle)], axis=1)
    wrist = elbow + fore
    place = {
        "RSHO": np.broadcast_to(shoulder, (n_frames, 3)),
        "RUPA": np.broadcast_to(shoulder + [0.03, 0.0, -0.14], (n_frames, 3)),
        "RELB": np.broadcast_to(elbow, (n_frames, 3)),
        "RFRM": elbow + 0.5 * fore + [0.0, -0.03, 0.0],
        "RWRA": wrist + [0.0, -0.02, 0.0],
        "RWRB": wrist + [0.0, 0.02, 0.0],
        "RFIN": elbow + 1.4 * fore,
        "LSHO": np.broadcast_to([0.0, 0.18, 1.45], (n_frames, 3)),
        "C7": np.broadcast_to([-0.08, 0.0, 1.50], (n_frames, 3)),
        "T10": np.broadcast_to([-0.10, 0.0, 1.20], (n_frames, 3)),
        "CLAV": np.broadcast_to([0.06, 0.0, 1.42], (n_frames, 3)),
        "STRN": np.broadcast_to([0.09, 0.0, 1.25], (n_frames, 3)),
    }
    for k, name in enumerate(PIG_LABELS):
        pts[:, k] = place[name]
    return pts


def write_arm_c3d(path: Path, **kw: object) -> Path:
    """:func:`arm_points` as a C3D file at ``path`` (options of :func:`c3d_bytes`)."""
    pts = arm_points()
    units = str(kw.get("units", "m"))
    factor = {"m": 1.0, "cm": 100.0, "mm": 1000.0}[units]
    path.write_bytes(c3d_bytes(PIG_LABELS, pts * factor, **kw))  # type: ignore[arg-type]
    return path
