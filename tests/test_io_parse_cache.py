"""Reading both arms parses a file once; a changed file is parsed again."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
from visprim.io import read


def _first(folder: Path, pattern: str) -> Path:
    return sorted(folder.glob(pattern))[0]


def test_both_arms_equal_two_one_arm_reads(shared_data: Path) -> None:
    for path in (
        _first(shared_data / "bandai_namco_ds2", "*.bvh"),
        _first(shared_data / "hdm05_cut_amc", "*.amc"),
    ):
        both = read(path, "both")
        right, left = read(path, "right"), read(path, "left", mirror=False)
        np.testing.assert_array_equal(both.markers[:, :4], right.markers)
        np.testing.assert_array_equal(both.markers[:, 4:], left.markers)


def test_a_changed_file_is_read_again(shared_data: Path, tmp_path: Path) -> None:
    src = _first(shared_data / "bandai_namco_ds2", "*.bvh")
    path = tmp_path / src.name
    shutil.copy(src, path)
    before = read(path).n_frames
    lines = path.read_text(encoding="latin-1").splitlines()
    frames_at = next(i for i, ln in enumerate(lines) if ln.strip().startswith("Frames:"))
    keep = before // 2
    lines[frames_at] = f"Frames: {keep}"
    path.write_text("\n".join(lines[: frames_at + 2 + keep]) + "\n", encoding="latin-1")
    assert read(path).n_frames == keep
