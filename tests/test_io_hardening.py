"""The readers' error contract on hostile inputs: read_many(on_error="warn") lets only
ReadError out and never hangs on symbolic-link loops; absurd frame periods are refused
before anything is allocated; non-UTF-8 names and comments are read; parsing stays
linear in the file size."""

from __future__ import annotations

import gc
import os
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from visprim.io import MalformedFileError, ReadError, read, read_many
from visprim.io.asfamc import parse_asf
from visprim.io.bvh import parse_bvh
from visprim.io.markers_csv import MarkerCSVError, read_marker_csv

# A BVH whose right arm is found by the Mixamo-style preset (Hips, Spine, arm chain).
ARM_BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 100 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT RightArm
  {
    OFFSET -18 40 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT RightForeArm
    {
      OFFSET -28 0 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightHand
      {
        OFFSET -25 0 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET -9 0 0
        }
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.04
0 0 0 0 0 0 0 0 0 0 10 0 0 0 0
0 0 0 0 0 0 0 5 0 0 20 0 0 0 0
0 0 0 0 0 0 0 10 0 0 30 0 0 0 0
"""


def _only_read_errors(record: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in record if str(w.message).startswith("skipped:")]


def test_the_arm_bvh_reads(tmp_path: Path) -> None:
    (tmp_path / "ok.bvh").write_text(ARM_BVH)
    assert read(tmp_path / "ok.bvh").n_frames == 3


def test_read_many_warn_skips_explicit_files_of_other_formats(tmp_path: Path) -> None:
    (tmp_path / "ok.bvh").write_text(ARM_BVH)
    for name in ("notes.md", "notes.txt", "skeleton.asf", "noext"):
        (tmp_path / name).write_text("x")
    files = [tmp_path / n for n in ("notes.md", "ok.bvh", "notes.txt", "skeleton.asf", "noext")]
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        trials = read_many(files, on_error="warn")
    assert [t.name for t in trials] == ["ok"]
    skipped = _only_read_errors(record)
    assert len(skipped) == 4
    assert any("skeleton.asf" in s and "skeleton without motion" in s for s in skipped)
    with pytest.raises(ReadError, match=r"notes\.md: unknown extension"):
        read_many(files)


def test_read_many_warn_turns_degenerate_arms_into_read_errors(tmp_path: Path) -> None:
    # Zero-length forearm and hand: elbow, wrist and finger coincide (no hand axis).
    coincide = ARM_BVH.replace("OFFSET -28 0 0", "OFFSET 0 0 0").replace(
        "OFFSET -25 0 0", "OFFSET 0 0 0"
    )
    (tmp_path / "flat.bvh").write_text(coincide)
    (tmp_path / "ok.bvh").write_text(ARM_BVH)
    with pytest.raises(ReadError, match="flat.bvh"):
        read(tmp_path / "flat.bvh", units="cm")
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        trials = read_many(tmp_path, on_error="warn", units="cm")
    assert [t.name for t in trials] == ["ok"]
    assert any("flat.bvh" in s for s in _only_read_errors(record))


def test_bad_arguments_still_raise_in_warn_mode(tmp_path: Path) -> None:
    (tmp_path / "ok.bvh").write_text(ARM_BVH)
    with pytest.raises(ValueError, match="unknown preset"):
        read_many(tmp_path, on_error="warn", preset="nope")
    with pytest.raises(ValueError, match="resample"):
        read_many(tmp_path, on_error="warn", resample=1e-9)
    with pytest.raises(TypeError, match="unexpected option"):
        read_many(tmp_path, on_error="warn", skeletn="x.asf")


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="needs symbolic links")
def test_symlink_loops_do_not_hang_folders_or_globs(tmp_path: Path) -> None:
    root = tmp_path / "data"
    (root / "a" / "b").mkdir(parents=True)
    (root / "a" / "b" / "ok.bvh").write_text(ARM_BVH)
    os.symlink(root, root / "a" / "b" / "up")  # loop back to the top
    os.symlink(root / "a", root / "a" / "b" / "again")  # a second loop
    os.symlink(tmp_path / "missing", root / "dangling")
    start = time.perf_counter()
    assert [t.name for t in read_many(root)] == ["ok"]
    assert [t.name for t in read_many(str(root / "**" / "*.bvh"))] == ["ok"]
    assert [t.name for t in read_many(str(root / "**" / "ok.bvh"))] == ["ok"]
    assert time.perf_counter() - start < 20  # a loop would run until the path is too long


# --- absurd values ------------------------------------------------------------------------


@pytest.mark.parametrize("frame_time", ["1e300", "1e-9", "0", "-0.01", "inf", "nan"])
def test_absurd_bvh_frame_times_are_refused(tmp_path: Path, frame_time: str) -> None:
    path = tmp_path / "t.bvh"
    path.write_text(ARM_BVH.replace("Frame Time: 0.04", f"Frame Time: {frame_time}"))
    with pytest.raises(MalformedFileError, match=r"t\.bvh: line \d+: 'Frame Time:'"):
        read(path)


def test_absurd_periods_are_refused_before_allocating(tmp_path: Path) -> None:
    path = tmp_path / "t.bvh"
    path.write_text(ARM_BVH)
    for period in (1e-9, 0.0, -1.0, float("nan"), 1e300):
        with pytest.raises(ValueError, match="resample"):
            read(path, resample=period)
    # Plausible periods still read (0.01 s is a plausible 100 Hz).
    assert read(path, resample=0.01).n_frames == 9


def test_resampling_to_too_many_frames_is_refused(tmp_path: Path) -> None:
    from visprim.io.resample import resample_trial
    from visprim.trial import Trial

    long = Trial(times=np.array([0.0, 1e6]), markers=np.zeros((2, 4, 3)) + np.arange(4)[:, None])
    with pytest.raises(ValueError, match=r"more than 10,000,000.*in seconds"):
        resample_trial(long, 1e-4)


def test_amc_rate_argument_is_checked(tmp_path: Path) -> None:
    from test_io_fuzz import AMC, ASF

    (tmp_path / "t.asf").write_text(ASF)
    (tmp_path / "t.amc").write_text(AMC)
    assert read(tmp_path / "t.amc", rate=60).meta["rate_hz"] == 60
    for rate in (1e9, 1e-300, 0, -5):
        with pytest.raises(ValueError, match="rate must be"):
            read(tmp_path / "t.amc", rate=rate)


def test_csv_time_steps_in_the_wrong_unit_are_refused(tmp_path: Path) -> None:
    header = "time_s," + ",".join(
        f"{s}_{a}_m" for s in ("upper_arm", "forearm", "wrist", "finger") for a in "xyz"
    )
    zeros = ",".join(["0.1"] * 12)
    for times in ([0, 1e-9, 2e-9], [0, 1e300, 2e300]):
        path = tmp_path / "t.csv"
        path.write_text(header + "\n" + "\n".join(f"{t!r},{zeros}" for t in times) + "\n")
        with pytest.raises(MarkerCSVError, match="time step"):
            read_marker_csv(path)


# --- encodings ----------------------------------------------------------------------------


def test_latin1_names_and_comments_are_read(tmp_path: Path) -> None:
    from test_io_fuzz import AMC, ASF

    bvh = ARM_BVH.replace("ROOT Hips", "ROOT Hüfte")
    (tmp_path / "t.bvh").write_bytes(bvh.encode("latin-1"))
    trial = read(tmp_path / "t.bvh")
    assert trial.n_frames == 3
    (tmp_path / "u.bvh").write_bytes(bvh.encode("utf-8"))
    np.testing.assert_array_equal(read(tmp_path / "u.bvh").markers, trial.markers)
    asf = ASF.replace(":name tiny", "# Schlüssel für Bonn\n:name tiny")
    (tmp_path / "t.asf").write_bytes(asf.encode("latin-1"))
    (tmp_path / "t.amc").write_bytes(("# X:\\für Bonn\n" + AMC).encode("latin-1"))
    assert read(tmp_path / "t.amc").n_frames == 3
    assert parse_asf(tmp_path / "t.asf").name == "tiny"


def test_binary_junk_is_still_refused(tmp_path: Path) -> None:
    path = tmp_path / "b.bvh"
    path.write_bytes(b"HIERARCHY\x00\x01\x02")
    with pytest.raises(MalformedFileError, match="not a text file"):
        read(path)


def test_unmodified_hdm05_amc_with_its_latin1_comment_reads(
    shared_data: Path, tmp_path: Path
) -> None:
    folder = shared_data / "hdm05_cut_amc"
    src = folder / "HDM_bd_depositFloorR_001_120.amc"
    text = src.read_text(encoding="utf-8")
    assert "\u00fc" in text.splitlines()[0]  # the re-encoded ü of "für Bonn"
    # Back to the original bytes: one Latin-1 byte (0xFC) in the first comment line.
    (tmp_path / src.name).write_bytes(text.encode("latin-1"))
    (tmp_path / "HDM_bd.asf").write_bytes((folder / "HDM_bd.asf").read_bytes())
    assert b"\xfc" in (tmp_path / src.name).read_bytes().splitlines()[0]
    original = read(tmp_path / src.name)
    np.testing.assert_array_equal(original.markers, read(src).markers)


# --- linear parsing -----------------------------------------------------------------------


def _bvh_with_joints(n: int) -> str:
    joints = "".join(
        f"  JOINT j{i}\n  {{\n    OFFSET 0 1 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
        "    End Site\n    {\n      OFFSET 0 1 0\n    }\n  }\n"
        for i in range(n)
    )
    row = " ".join(["0"] * (3 + 3 * n))
    return (
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n"
        + joints
        + "}\nMOTION\nFrames: 2\nFrame Time: 0.01\n"
        + f"{row}\n{row}\n"
    )


def _asf_with_bones(n: int) -> str:
    bones = "".join(
        f"  begin\n    name b{i}\n    direction 0 1 0\n    length 1\n    axis 0 0 0 XYZ\n"
        "    dof rx ry rz\n  end\n"
        for i in range(n)
    )
    chain = "    root b0\n" + "".join(f"    b{i} b{i + 1}\n" for i in range(n - 1))
    return f":units\n  length 1\n:bonedata\n{bones}:hierarchy\n  begin\n{chain}  end\n"


def _parse_time(path: Path, parse: Callable[[Path], object], runs: int) -> float:
    """CPU seconds of the fastest of ``runs`` parses, with the garbage collector off.

    CPU time of this process is not stretched by other processes on the machine, and a
    collection triggered by the many objects of a big file is not part of the parse.
    """
    best = float("inf")
    for _ in range(runs):
        gc.collect()
        gc.disable()
        try:
            start = time.process_time()
            try:
                parse(path)
            except MarkerCSVError:
                pass
            best = min(best, time.process_time() - start)
        finally:
            gc.enable()
    return best


def _growth(
    tmp_path: Path, make: Callable[[int], str], parse: Callable[[Path], object], n: int
) -> tuple[float, float]:
    """Parse times (best of 3) of files with n/8 and n elements."""
    times = []
    for size in (n // 8, n):
        path = tmp_path / f"f{size}"
        path.write_text(make(size))
        times.append(_parse_time(path, parse, 3))
    return times[0], times[1]


# At the sizes below the quadratic parsers took 11 s (BVH, 20,000 joints), 41 s (ASF, 40,000
# bones) and 75 s (CSV, 100,000 columns); 8x the elements take ~64x the time of a quadratic
# parser and ~8x that of a linear one: the bound is 24x (plus 0.3 s of slack for timer noise on
# tiny times), far from both.
# Absolute times are measured in benches/bench_io.py.
def test_bvh_parsing_is_linear_in_the_number_of_joints(tmp_path: Path) -> None:
    t_eighth, t_full = _growth(tmp_path, _bvh_with_joints, parse_bvh, 20_000)
    assert t_full < 24 * t_eighth + 0.3, (t_eighth, t_full)


def test_asf_parsing_is_linear_in_the_number_of_bones(tmp_path: Path) -> None:
    t_eighth, t_full = _growth(tmp_path, _asf_with_bones, parse_asf, 40_000)
    assert t_full < 24 * t_eighth + 0.3, (t_eighth, t_full)


def _csv_with_columns(n: int) -> str:
    cols = ["time_s"] + [f"s{i}_x_m" for i in range(n)]
    return ",".join(cols) + "\n" + ",".join(["0"] * len(cols)) + "\n"


def test_csv_header_parsing_is_linear_in_the_number_of_columns(tmp_path: Path) -> None:
    t_eighth, t_full = _growth(tmp_path, _csv_with_columns, read_marker_csv, 100_000)
    assert t_full < 24 * t_eighth + 0.3, (t_eighth, t_full)
    path = tmp_path / "big.csv"
    path.write_text(_csv_with_columns(100_000))
    with pytest.raises(MarkerCSVError, match=r"unknown s0, s1, s2, s3, s4 \.\.\.") as info:
        read_marker_csv(path)
    assert len(str(info.value)) < 400  # one line, not 100,000 names
