"""Alias of :mod:`visprim.io.markers_csv` (the marker CSV lives with the other formats)."""

from visprim.io.markers_csv import (
    FORMAT_LINE,
    POSITION_DECIMALS,
    TIME_DECIMALS,
    MarkerCSVError,
    read_marker_csv,
    truth_path,
    write_marker_csv,
)

__all__ = [
    "FORMAT_LINE",
    "POSITION_DECIMALS",
    "TIME_DECIMALS",
    "MarkerCSVError",
    "read_marker_csv",
    "truth_path",
    "write_marker_csv",
]
