"""The AMC fast path (regular frames parsed as one table) equals the line-by-line parser."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from visprim.io import asfamc

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


@pytest.mark.skipif(not (DATA / "cmu_asfamc").is_dir(), reason="../shared/data not present")
@pytest.mark.parametrize(
    ("asf", "amc"),
    [
        ("hdm05_cut_amc/HDM_bd.asf", "hdm05_cut_amc/HDM_bd_depositFloorR_001_120.amc"),
        ("cmu_asfamc/backflip.asf", "cmu_asfamc/backflip.amc"),
    ],
)
def test_regular_fast_path_equals_line_parser(asf: str, amc: str, monkeypatch) -> None:
    asf_path, amc_path = DATA / asf, DATA / amc
    skeleton = asfamc.parse_asf(asf_path)
    fast = asfamc.parse_amc(amc_path, skeleton)
    lines = asfamc._read_lines(str(amc_path))
    dofs = {b.name: len(b.dof) for b in skeleton.bones if b.dof}
    assert asfamc._parse_amc_regular(str(amc_path), lines, dofs) is not None  # it did apply
    monkeypatch.setattr(asfamc, "_parse_amc_regular", lambda *args: None)
    slow = asfamc.parse_amc(amc_path, skeleton)
    assert (fast.n_frames, fast.first_frame, fast.angle_unit) == (
        slow.n_frames,
        slow.first_frame,
        slow.angle_unit,
    )
    assert fast.values.keys() == slow.values.keys()
    for bone, values in fast.values.items():
        np.testing.assert_array_equal(values, slow.values[bone])


def test_irregular_frames_fall_back_to_the_line_parser() -> None:
    dofs = {"root": 2, "arm": 1}
    regular = [":DEGREES", "1", "root 0 1", "arm 2", "2", "root 3 4", "arm 5"]
    m = asfamc._parse_amc_regular("x.amc", regular, dofs)
    assert m is not None and m.n_frames == 2 and m.angle_unit == "deg"
    np.testing.assert_array_equal(m.values["root"], [[0, 1], [3, 4]])
    swapped = [":DEGREES", "1", "root 0 1", "arm 2", "2", "arm 5", "root 3 4"]
    assert asfamc._parse_amc_regular("x.amc", swapped, dofs) is None
    gap = [":DEGREES", "1", "root 0 1", "arm 2", "3", "root 3 4", "arm 5"]
    assert asfamc._parse_amc_regular("x.amc", gap, dofs) is None
    word = [":DEGREES", "1", "root 0 x", "arm 2"]
    assert asfamc._parse_amc_regular("x.amc", word, dofs) is None
