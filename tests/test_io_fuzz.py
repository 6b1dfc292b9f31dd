"""Hypothesis-generated malformed BVH / ASF+AMC / marker CSV files.

Every corrupted file must end in a :class:`visprim.io.ReadError` (never another exception,
never a crash). Corruptions that certainly break the data — a number replaced by garbage,
a keyword or brace removed, the file cut before its last value — must raise, never return a
silently wrong trial.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from visprim.io import ReadError, read
from visprim.trial import Trial

BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 100 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Chest
  {
    OFFSET 0 30 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Neck
    {
      OFFSET 0 20 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 10 0
      }
    }
    JOINT RightArm
    {
      OFFSET -18 0 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightForeArm
      {
        OFFSET -30 0 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT RightHand
        {
          OFFSET -26 0 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          End Site
          {
            OFFSET -10 0 0
          }
        }
      }
    }
    JOINT LeftArm
    {
      OFFSET 18 0 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 30 0 0
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0
1 0 2 5 0 0 0 3 0 0 0 0 0 0 0 10 0 30 0 0 0 0 0 0
2 0 4 10 0 0 0 6 0 0 0 0 0 0 0 20 0 60 0 0 0 0 0 0
"""

ASF = """:version 1.10
:name tiny
:units
  mass 1.0
  length 1.0
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name lowerback
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx ry rz
    limits (-20.0 45.0)
           (-30.0 30.0)
           (-30.0 30.0)
  end
  begin
     id 2
     name rhumerus
     direction -1 0 0
     length 12
     axis 0 0 90 XYZ
    dof rx ry rz
  end
  begin
     id 3
     name rradius
     direction -1 0 0
     length 10
     axis 0 0 0 XYZ
    dof rx
  end
  begin
     id 4
     name rhand
     direction -1 0 0
     length 4
     axis 0 0 0 XYZ
    dof rx rz
  end
:hierarchy
  begin
    root lowerback
    lowerback rhumerus
    rhumerus rradius
    rradius rhand
  end
"""

AMC = """:FULLY-SPECIFIED
:DEGREES
1
root 1 2 3 0 0 0
lowerback 0 0 0
rhumerus 90 0 0
rradius 10
rhand 0 0
2
root 0 0 0 0 90 0
lowerback 0 0 0
rhumerus 0 0 0
rradius 90
rhand 0 0
3
root 0 0 0 0 80 0
lowerback 0 0 0
rhumerus 0 0 0
rradius 80
rhand 5 0
"""

GARBAGE = st.sampled_from(["nan", "inf", "-inf", "x", "", "1e999", "{", "}", "--", "1.2.3", "0x1"])
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_BVH_KEYWORDS = {
    "HIERARCHY",
    "ROOT",
    "JOINT",
    "OFFSET",
    "CHANNELS",
    "End",
    "Site",
    "{",
    "}",
    "MOTION",
    "Frames:",
    "Frame",
    "Time:",
    "Xposition",
    "Yposition",
    "Zposition",
    "Xrotation",
    "Yrotation",
    "Zrotation",
}


def _tokens(text: str) -> list[re.Match[str]]:
    return list(re.finditer(r"\S+", text))


def _replace(text: str, match: re.Match[str], new: str) -> str:
    return text[: match.start()] + new + text[match.end() :]


def _valid(trial: Trial) -> None:
    assert np.isfinite(trial.markers).all() and np.isfinite(trial.times).all()
    assert trial.markers.shape == (trial.n_frames, 4, 3)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


def test_the_unmodified_inputs_read(folder: Path) -> None:
    (folder / "ok.bvh").write_text(BVH)
    _valid(read(folder / "ok.bvh"))
    (folder / "ok.asf").write_text(ASF)
    (folder / "ok.amc").write_text(AMC)
    _valid(read(folder / "ok.amc"))


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_bvh_with_a_broken_number_or_keyword_raises(folder: Path, data: st.DataObject) -> None:
    toks = [m for m in _tokens(BVH) if _NUMBER.match(m.group()) or m.group() in _BVH_KEYWORDS]
    target = data.draw(st.sampled_from(toks))
    new = data.draw(GARBAGE.filter(lambda g: g != target.group()))
    path = folder / "bad.bvh"
    path.write_text(_replace(BVH, target, new))
    with pytest.raises(ReadError) as info:
        read(path)
    assert str(info.value).startswith(str(path))


@settings(max_examples=100, deadline=None)
@given(cut=st.integers(0, len(BVH) - 1))
def test_truncated_bvh_raises(folder: Path, cut: int) -> None:
    text = BVH[:cut]
    path = folder / "cut.bvh"
    path.write_text(text)
    if len(text.split()) == len(BVH.split()):
        return  # only the last number was shortened: undetectable in BVH (documented)
    with pytest.raises(ReadError):
        read(path)


@settings(max_examples=100, deadline=None)
@given(pos=st.integers(0, len(BVH)), junk=st.text(min_size=1, max_size=8))
def test_bvh_with_inserted_junk_raises_a_read_error_or_reads(
    folder: Path, pos: int, junk: str
) -> None:
    path = folder / "junk.bvh"
    path.write_text(BVH[:pos] + junk + BVH[pos:], encoding="utf-8", errors="surrogatepass")
    try:
        trial = read(path)
    except ReadError:
        return
    _valid(trial)


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_amc_with_a_broken_value_or_line_raises(folder: Path, data: st.DataObject) -> None:
    (folder / "t.asf").write_text(ASF)
    body = AMC.split(":DEGREES\n", 1)[1]
    offset = len(AMC) - len(body)
    toks = [m for m in _tokens(body) if _NUMBER.match(m.group()) or m.group().isalpha()]
    target = data.draw(st.sampled_from(toks))
    new = data.draw(st.sampled_from(["nan", "x", "1e999", "rknee", "{"]))
    start, end = target.start() + offset, target.end() + offset
    text = AMC[:start] + new + AMC[end:]
    if data.draw(st.booleans()):  # or drop a whole line instead
        lines = AMC.splitlines(keepends=True)
        k = data.draw(st.integers(3, len(lines) - 1))
        text = "".join(lines[:k] + lines[k + 1 :])
    path = folder / "t.amc"
    path.write_text(text)
    with pytest.raises(ReadError):
        read(path)


@settings(max_examples=100, deadline=None)
@given(cut=st.integers(0, len(AMC) - 1))
def test_truncated_amc_raises(folder: Path, cut: int) -> None:
    (folder / "t.asf").write_text(ASF)
    path = folder / "t.amc"
    path.write_text(AMC[:cut])
    if len(AMC[:cut].split()) == len(AMC.split()):
        return  # only the last number was shortened: undetectable
    frame_ends = {m.end() for m in re.finditer(r"rhand [^\n]*", AMC)}
    if len(AMC[:cut].rstrip()) in frame_ends:
        return  # cut between whole frames: AMC stores no frame count (documented)
    with pytest.raises(ReadError):
        read(path)


@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_corrupt_asf_raises_a_read_error_or_reads(folder: Path, data: st.DataObject) -> None:
    toks = _tokens(ASF)
    target = data.draw(st.sampled_from(toks))
    new = data.draw(GARBAGE)
    (folder / "t.asf").write_text(_replace(ASF, target, new))
    (folder / "t.amc").write_text(AMC)
    try:
        trial = read(folder / "t.amc")
    except ReadError:
        return
    _valid(trial)


@pytest.fixture(scope="module")
def csv_text(folder: Path) -> str:
    from visprim.io.markers_csv import write_marker_csv

    t = np.arange(6) * 0.034
    markers = np.zeros((6, 4, 3)) + np.arange(12).reshape(4, 3) * 0.01 + t[:, None, None]
    path = write_marker_csv(
        folder / "ok.csv", Trial(times=t, markers=markers, name="ok"), truth=False
    )
    return path.read_text()


def test_the_unmodified_csv_reads(folder: Path, csv_text: str) -> None:
    (folder / "ok2.csv").write_text(csv_text)
    _valid(read(folder / "ok2.csv"))


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_csv_with_a_broken_cell_or_cut_row_raises(
    folder: Path, csv_text: str, data: st.DataObject
) -> None:
    lines = csv_text.splitlines(keepends=True)
    first = next(i for i, ln in enumerate(lines) if ln.startswith("time"))
    row = data.draw(st.integers(first + 1, len(lines) - 1))
    cells = lines[row].rstrip("\n").split(",")
    k = data.draw(st.integers(0, len(cells) - 1))
    how = data.draw(st.sampled_from(["garbage", "drop", "cut"]))
    if how == "garbage":
        cells[k] = data.draw(st.sampled_from(["nan", "inf", "x", "", "1e999", "1,2"]))
        lines[row] = ",".join(cells) + "\n"
        text = "".join(lines)
    elif how == "drop":
        del cells[k]
        lines[row] = ",".join(cells) + "\n"
        text = "".join(lines)
    else:  # cut the file inside this row, before its last cell
        text = "".join(lines[:row]) + ",".join(cells[: max(k, 1)])
        if k == 0:
            text = "".join(lines[:row]) + cells[0][: len(cells[0]) // 2]
    path = folder / "bad.csv"
    path.write_text(text)
    with pytest.raises(ReadError) as info:
        read(path)
    assert "bad.csv" in str(info.value)
