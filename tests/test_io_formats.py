"""visprim.io on small hand-written files: forward kinematics against hand-computed answers,
rotation orders against scipy, presets, mappings, units, round trips, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from visprim.io import (
    GapError,
    MalformedFileError,
    MissingPointError,
    ReadError,
    TruncatedFileError,
    UnknownFormatError,
    labels_from_name,
    read,
    read_many,
)
from visprim.io.asfamc import forward_kinematics as amc_fk
from visprim.io.asfamc import parse_amc, parse_asf
from visprim.io.assemble import up_rotation
from visprim.io.bvh import forward_kinematics, parse_bvh, write_bvh

# --- BVH --------------------------------------------------------------------------------

CHAIN = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Arm
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Fore
    {
      OFFSET 0 -20 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 -5 0
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.04
1 2 3 90 0 0 0 90 0 0 0 0
0 0 0 0 0 0 0 0 0 0 0 0
"""


def test_bvh_forward_kinematics_matches_a_hand_computed_pose(tmp_path: Path) -> None:
    path = tmp_path / "chain.bvh"
    path.write_text(CHAIN)
    data = parse_bvh(path)
    assert data.names == ["Hips", "Arm", "Fore"]
    assert data.frame_time == pytest.approx(0.04)
    pos, _ = forward_kinematics(data)
    # Frame 0: root at (1,2,3) turned 90° about z; Arm at (1,2,3) + Rz90·(10,0,0) = (1,12,3);
    # Arm turns 90° about its x: Rz90·Rx90·(0,-20,0) = Rz90·(0,0,-20) = (0,0,-20).
    np.testing.assert_allclose(pos[0], [[1, 2, 3], [1, 12, 3], [1, 12, -17]], atol=1e-12)
    np.testing.assert_allclose(pos[1], [[0, 0, 0], [10, 0, 0], [10, -20, 0]], atol=1e-12)


def _two_joint_bvh(order: str, angles: np.ndarray) -> str:
    chans = " ".join(f"{a}rotation" for a in order)
    rows = "\n".join(" ".join(f"{v:.10f}" for v in [0, 0, 0, *row, 0, 0, 0]) for row in angles)
    return f"""HIERARCHY
ROOT Root
{{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition {chans}
  JOINT Tip
  {{
    OFFSET 3 4 12
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {{
      OFFSET 0 0 0
    }}
  }}
}}
MOTION
Frames: {len(angles)}
Frame Time: 0.01
{rows}
"""


@pytest.mark.parametrize("order", ["XYZ", "ZYX", "YZX", "XZY"])
def test_bvh_any_rotation_order_gives_the_same_pose_as_scipy(tmp_path: Path, order: str) -> None:
    rng = np.random.default_rng(3)
    ref = Rotation.from_euler("ZXY", rng.uniform(-80, 80, size=(5, 3)), degrees=True)
    angles = ref.as_euler(order, degrees=True)  # intrinsic: BVH channel semantics
    path = tmp_path / f"{order}.bvh"
    path.write_text(_two_joint_bvh(order, angles))
    pos, rot = forward_kinematics(parse_bvh(path))
    np.testing.assert_allclose(rot[:, 0], ref.as_matrix(), atol=1e-9)
    np.testing.assert_allclose(pos[:, 1], ref.apply([3, 4, 12]), atol=1e-8)


def _rig_bvh(names: dict[str, str], frames: int = 4, scale: float = 1.0) -> str:
    """A small upright humanoid (Y up, facing +Z) with the given joint names; the right
    elbow flexes over the frames."""
    n = names
    s = scale

    def j(name: str, off: tuple[float, float, float], body: str, kind: str = "JOINT") -> str:
        o = " ".join(f"{v * s:g}" for v in off)
        return (
            f"{kind} {name}\n{{\nOFFSET {o}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{body}}}\n"
        )

    end = "End Site\n{\nOFFSET 0 0 0\n}\n"
    right = j(
        n["rs"],
        (-0.18, 0, 0),
        j(
            n["re"],
            (-0.3, 0, 0),
            j(n["rw"], (-0.26, 0, 0), j(n["rf"], (-0.1, 0, 0), end) if "rf" in n else end),
        ),
    )
    left = j(n["ls"], (0.18, 0, 0), j(n["le"], (0.3, 0, 0), j(n["lw"], (0.26, 0, 0), end)))
    neck = j(n["neck"], (0, 0.2, 0), end)
    chest = j(n["chest"], (0, 0.3, 0), neck + right + left)
    root = (
        f"ROOT {n['hips']}\n{{\nOFFSET 0 {1.0 * s:g} 0\n"
        "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        f"{chest}}}\n"
    )
    n_ch = 6 + 3 * root.count("JOINT")
    order = [ln.split()[1] for ln in root.splitlines() if ln.startswith(("ROOT", "JOINT"))]
    rows = []
    for f in range(frames):
        row = np.zeros(n_ch)
        k = 6 + 3 * (order.index(n["re"]) - 1)
        row[k + 2] = 20.0 * f  # elbow Y rotation: the forearm swings forward
        rows.append(" ".join(f"{v:g}" for v in row))
    return (
        f"HIERARCHY\n{root}MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n"
        + "\n".join(rows)
        + "\n"
    )


MIXAMO = {
    "hips": "mixamorig:Hips",
    "chest": "mixamorig:Spine2",
    "neck": "mixamorig:Neck",
    "rs": "mixamorig:RightArm",
    "re": "mixamorig:RightForeArm",
    "rw": "mixamorig:RightHand",
    "rf": "mixamorig:RightHandMiddle1",
    "ls": "mixamorig:LeftArm",
    "le": "mixamorig:LeftForeArm",
    "lw": "mixamorig:LeftHand",
}
CUSTOM = {
    "hips": "pelvis",
    "chest": "torso",
    "neck": "neck",
    "rs": "r_sh",
    "re": "r_el",
    "rw": "r_wr",
    "ls": "l_sh",
    "le": "l_el",
    "lw": "l_wr",
}


def test_mixamo_preset_is_detected_and_gives_the_arm_in_the_common_frame(tmp_path: Path) -> None:
    path = tmp_path / "mix.bvh"
    path.write_text(_rig_bvh(MIXAMO, scale=100.0))  # centimetres
    t = read(path)
    assert t.meta["preset"] == "mixamo"
    assert t.meta["units_in_file"] == "cm"
    assert t.meta["finger_from"] == "joint mixamorig:RightHandMiddle1"
    # Frame 0: arm straight out to the subject's right (-y), at shoulder height 1.3 m.
    np.testing.assert_allclose(t.joints[0, 0], [0, -0.18, 1.3], atol=1e-9)
    np.testing.assert_allclose(t.joints[0, 1], [0, -0.48, 1.3], atol=1e-9)
    np.testing.assert_allclose(t.joints[0, 2], [0, -0.74, 1.3], atol=1e-9)
    np.testing.assert_allclose(t.markers[0, 3], [0, -0.84, 1.3], atol=1e-9)
    np.testing.assert_allclose(t.body_frame[0], np.eye(3), atol=1e-12)
    # Virtual markers: midpoints and the wrist centre, every frame.
    j = t.joints
    np.testing.assert_allclose(t.markers[:, 0], (j[:, 0] + j[:, 1]) / 2)
    np.testing.assert_allclose(t.markers[:, 1], (j[:, 1] + j[:, 2]) / 2)
    np.testing.assert_allclose(t.markers[:, 2], j[:, 2])
    # The elbow rotation flexes the forearm; bone lengths stay.
    fore = np.linalg.norm(j[:, 2] - j[:, 1], axis=1)
    np.testing.assert_allclose(fore, 0.26, atol=1e-12)
    assert np.linalg.norm(j[-1, 2] - j[0, 2]) > 0.2


def test_explicit_mapping_and_missing_joint_errors(tmp_path: Path) -> None:
    path = tmp_path / "custom.bvh"
    path.write_text(_rig_bvh(CUSTOM))
    with pytest.raises(MissingPointError, match=r"custom\.bvh: cannot find the right arm"):
        read(path)
    t = read(path, mapping={"shoulder": "r_sh", "elbow": "r_el", "wrist": "r_wr"})
    assert t.meta["preset"] == "mapping"
    assert t.meta["units_in_file"] == "m"
    # No finger joint: extrapolated 0.45 × forearm beyond the wrist along the hand.
    np.testing.assert_allclose(t.markers[0, 3], [0, -0.74 - 0.45 * 0.26, 1.3], atol=1e-9)
    assert t.body_frame is None  # no torso roles in the mapping or a preset
    with pytest.raises(MissingPointError, match="elbow"):
        read(path, mapping={"shoulder": "r_sh", "elbow": "nope", "wrist": "r_wr"})
    with pytest.raises(ValueError, match="unknown role"):
        read(path, mapping={"shoulder": "r_sh", "elbow": "r_el", "wrist": "r_wr", "knee": "x"})
    with pytest.raises(ValueError, match="arm must be"):
        read(path, arm="middle")


def test_left_arm_and_mirror(tmp_path: Path) -> None:
    path = tmp_path / "mix.bvh"
    path.write_text(_rig_bvh(MIXAMO, scale=100.0))
    left = read(path, arm="left")
    np.testing.assert_allclose(left.joints[0, 2], [0, 0.74, 1.3], atol=1e-9)
    mirrored = read(path, arm="left", mirror=True)
    np.testing.assert_allclose(mirrored.joints[0, 2], [0, -0.74, 1.3], atol=1e-9)
    assert mirrored.meta["mirrored"] is True
    assert np.linalg.det(mirrored.body_frame[0]) == pytest.approx(1.0)


def test_units_argument_and_undetectable_units(tmp_path: Path) -> None:
    path = tmp_path / "mix.bvh"
    path.write_text(_rig_bvh(MIXAMO, scale=1000.0))
    assert read(path).meta["units_in_file"] == "mm"
    t = read(path, units=0.0005)  # a made-up unit: the arm comes out half as long
    np.testing.assert_allclose(np.linalg.norm(t.joints[0, 1] - t.joints[0, 0]), 0.15)
    tiny = tmp_path / "tiny.bvh"
    tiny.write_text(_rig_bvh(MIXAMO, scale=0.01))
    with pytest.raises(ReadError, match="cannot tell the length unit"):
        read(tiny)


def test_up_axis_rotations_are_proper_and_put_up_on_z() -> None:
    for up, vec in [("+x", [1, 0, 0]), ("+y", [0, 1, 0]), ("-y", [0, -1, 0]), ("+z", [0, 0, 1])]:
        a = up_rotation(up)
        assert np.linalg.det(a) == pytest.approx(1.0)
        np.testing.assert_allclose(a @ a.T, np.eye(3), atol=1e-15)
        np.testing.assert_allclose(a @ np.array(vec, float), [0, 0, 1])


def test_bvh_write_parse_round_trip(tmp_path: Path) -> None:
    src = tmp_path / "mix.bvh"
    src.write_text(_rig_bvh(MIXAMO, scale=100.0))
    data = parse_bvh(src)
    out = tmp_path / "copy.bvh"
    write_bvh(out, data)
    again = parse_bvh(out)
    assert again.names == data.names
    assert [j.channels for j in again.joints] == [j.channels for j in data.joints]
    np.testing.assert_allclose(again.motion, data.motion, atol=5e-7)
    a, b = read(src), read(out)
    np.testing.assert_allclose(a.markers, b.markers, atol=1e-8)


BROKEN_BVH = {
    "no motion": (
        "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n",
        TruncatedFileError,
        "no MOTION",
    ),
    "bad channel": (
        CHAIN.replace(
            "Zrotation Xrotation Yrotation\n    JOINT Fore",
            "Zrotation Xrotation Wobble\n    JOINT Fore",
        ),
        MalformedFileError,
        "unknown channel 'Wobble'",
    ),
    "short row": (
        CHAIN.replace("1 2 3 90 0 0 0 90 0 0 0 0", "1 2 3 90 0 0 0 90 0 0"),
        MalformedFileError,
        "frame 0 has 10 values, expected 12",
    ),
    "nan": (CHAIN.replace("1 2 3 90", "1 nan 3 90"), MalformedFileError, "NaN or infinite"),
    "word": (CHAIN.replace("1 2 3 90", "1 two 3 90"), MalformedFileError, "'two' is not a number"),
    "few rows": (
        CHAIN.replace("Frames: 2", "Frames: 3"),
        TruncatedFileError,
        "only 2 complete frame rows",
    ),
    "extra rows": (
        CHAIN.replace("Frames: 2", "Frames: 1"),
        ReadError,
        "declared but the file has 2",
    ),
    "cut row": (CHAIN[: CHAIN.rindex(" 0 0 0\n")] + "\n", TruncatedFileError, "file cut short"),
    "braces": (CHAIN.replace("  }\n}\nMOTION", "}\nMOTION"), MalformedFileError, "line"),
    "frame time": (CHAIN.replace("0.04", "-1"), MalformedFileError, "positive number"),
}


@pytest.mark.parametrize("case", sorted(BROKEN_BVH))
def test_malformed_bvh_errors_name_the_file_and_problem(tmp_path: Path, case: str) -> None:
    text, exc, message = BROKEN_BVH[case]
    path = tmp_path / "broken.bvh"
    path.write_text(text)
    with pytest.raises(exc, match=message) as info:
        parse_bvh(path)
    assert str(info.value).startswith(str(path))


# --- ASF/AMC ----------------------------------------------------------------------------

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
     name lowerback
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx ry rz
  end
  begin
     name thorax
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx ry rz
  end
  begin
     name lowerneck
     direction 0 1 0
     length 3
     axis 0 0 0 XYZ
  end
  begin
     name rclavicle
     direction -1 0 0
     length 6
     axis 0 0 0 XYZ
  end
  begin
     name lclavicle
     direction 1 0 0
     length 6
     axis 0 0 0 XYZ
  end
  begin
     name rhumerus
     direction -1 0 0
     length 12
     axis 0 0 90 XYZ
    dof rx ry rz
  end
  begin
     name lhumerus
     direction 1 0 0
     length 12
     axis 0 0 0 XYZ
    dof rx ry rz
  end
  begin
     name rradius
     direction -1 0 0
     length 10
     axis 0 0 0 XYZ
    dof rx
  end
  begin
     name rhand
     direction -1 0 0
     length 4
     axis 0 0 0 XYZ
    dof rx rz
  end
:hierarchy
  begin
    root lowerback
    lowerback thorax
    thorax lowerneck rclavicle lclavicle
    rclavicle rhumerus
    lclavicle lhumerus
    rhumerus rradius
    rradius rhand
  end
"""

AMC = """:FULLY-SPECIFIED
:DEGREES
1
root 1 2 3 0 0 0
lowerback 0 0 0
thorax 0 0 0
rhumerus 90 0 0
lhumerus 0 0 0
rradius 0
rhand 0 0
2
root 0 0 0 0 90 0
lowerback 0 0 0
thorax 0 0 0
rhumerus 0 0 0
lhumerus 0 0 0
rradius 90
rhand 0 0
"""


def test_asf_amc_forward_kinematics_matches_hand_computed_positions(tmp_path: Path) -> None:
    (tmp_path / "tiny.asf").write_text(ASF)
    (tmp_path / "tiny.amc").write_text(AMC)
    skel = parse_asf(tmp_path / "tiny.asf")
    motion = parse_amc(tmp_path / "tiny.amc", skel)
    starts, ends, _ = amc_fk(skel, motion)
    i = {b.name: k for k, b in enumerate(skel.bones)}
    # Frame 0: root at (1,2,3); shoulder = root + (0,20,0) + (-6,0,0) = (-5,22,3).
    np.testing.assert_allclose(starts[0, i["rhumerus"]], [-5, 22, 3])
    # rhumerus axis (0,0,90): its local x is the world y; rx=90 turns the bone (-1,0,0)
    # about +y: Ry(90)·(-1,0,0) = (0,0,1); the elbow is 12 units further along +z.
    np.testing.assert_allclose(ends[0, i["rhumerus"]], [-5, 22, 15], atol=1e-12)
    np.testing.assert_allclose(ends[0, i["rradius"]], [-5, 22, 25], atol=1e-12)
    # Frame 1: the root turns 90° about y: (-1,0,0) → (0,0,1); the elbow (rradius rx=90,
    # axis 0): Rx(90) turns (-1,0,0) into itself, so the arm stays straight.
    np.testing.assert_allclose(starts[1, i["rhumerus"]], [0, 20, 6], atol=1e-12)
    np.testing.assert_allclose(ends[1, i["rradius"]], [0, 20, 28], atol=1e-12)


def test_amc_read_uses_units_rate_and_skeleton_lookup(tmp_path: Path) -> None:
    (tmp_path / "tiny.asf").write_text(ASF)
    (tmp_path / "take1.amc").write_text(AMC)  # found as the only .asf in the folder
    t = read(tmp_path / "take1.amc", rate=60)
    assert t.times[1] == pytest.approx(1 / 60)
    assert t.meta["skeleton"].endswith("tiny.asf")
    # length unit 1 → 1 inch per unit: upper arm 12 in = 0.3048 m.
    np.testing.assert_allclose(np.linalg.norm(t.joints[:, 1] - t.joints[:, 0], axis=1), 0.3048)
    # Frame 0 has the upper arm pointing forward (+z in the file = +x in the common frame
    # after turning the subject to face +x... the subject faces +z in the file).
    assert t.meta["heading_deg"] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(t.joints[0, 1] - t.joints[0, 0], [0.3048, 0, 0], atol=1e-12)
    assert read(tmp_path / "take1.amc").meta["rate_hz"] == 120.0
    # Format-specific options: an error for read(), passed only to AMC files by read_many().
    (tmp_path / "x.bvh").write_text(_rig_bvh(MIXAMO, scale=100.0))
    with pytest.raises(ValueError, match="rate= applies to amc"):
        read(tmp_path / "x.bvh", rate=60)
    mixed = read_many(tmp_path, rate=60)
    assert [t.name for t in mixed] == ["take1", "x"]
    assert mixed[0].meta["rate_hz"] == 60 and mixed[1].meta["rate_hz"] == pytest.approx(30, 1e-5)


BROKEN_AMC = {
    "unknown bone": (
        AMC.replace("lhumerus 0 0 0\nrradius 0", "lhumerus 0 0 0\nrknee 0"),
        MalformedFileError,
        "'rknee' is not a bone of",
    ),
    "value count": (
        AMC.replace("rradius 90", "rradius 90 1"),
        MalformedFileError,
        "has 2 values, its dof needs 1",
    ),
    "cut": (AMC[: AMC.rindex("rradius 90")], TruncatedFileError, "lacks rradius, rhand"),
    "missing bone": (
        AMC.replace("rhumerus 90 0 0\n", ""),
        ReadError,
        "frame 1 .* no values for rhumerus",
    ),
    "number": (
        AMC.replace("rradius 90", "rradius ninety"),
        MalformedFileError,
        "'ninety' is not a number",
    ),
    "frame order": (AMC.replace("\n2\n", "\n5\n"), ReadError, "frame 5 follows frame 1"),
}


@pytest.mark.parametrize("case", sorted(BROKEN_AMC))
def test_malformed_amc_errors(tmp_path: Path, case: str) -> None:
    text, exc, message = BROKEN_AMC[case]
    (tmp_path / "tiny.asf").write_text(ASF)
    (tmp_path / "tiny.amc").write_text(text)
    with pytest.raises(exc, match=message) as info:
        read(tmp_path / "tiny.amc")
    assert str(tmp_path / "tiny.amc") in str(info.value)


def test_malformed_asf_errors(tmp_path: Path) -> None:
    (tmp_path / "tiny.amc").write_text(AMC)
    cases = {
        ASF.replace("thorax lowerneck", "thorax ribcage"): "unknown bone 'ribcage'",
        ASF.replace(
            "dof rx ry rz\n  end\n  begin\n     name thorax",
            "dof rx rq rz\n  end\n  begin\n     name thorax",
        ): "unknown dof 'rq'",
        ASF.split(":hierarchy")[0]: "no :hierarchy section",
        ASF.replace("length 12", "length twelve"): "length needs 1 numbers",
    }
    for text, message in cases.items():
        (tmp_path / "tiny.asf").write_text(text)
        with pytest.raises(ReadError, match=message) as info:
            read(tmp_path / "tiny.amc")
        assert "tiny.asf" in str(info.value)


# --- dispatch ---------------------------------------------------------------------------


def test_dispatch_errors(tmp_path: Path) -> None:
    (tmp_path / "a.xyz").write_text("x")
    with pytest.raises(UnknownFormatError, match=r"a\.xyz: unknown extension '\.xyz'"):
        read(tmp_path / "a.xyz")
    (tmp_path / "s.asf").write_text(ASF)
    with pytest.raises(UnknownFormatError, match="skeleton without motion"):
        read(tmp_path / "s.asf")
    with pytest.raises(ReadError, match="no such file"):
        read(tmp_path / "missing.bvh")
    with pytest.raises(ReadError, match="matches no recording"):
        read_many(str(tmp_path / "*.bvh"))
    with pytest.raises(ReadError, match="no recordings"):
        read_many(tmp_path)
    with pytest.raises(ValueError, match="max_gap"):
        read(tmp_path / "a.bvh", max_gap=-1)


def test_read_many_folders_globs_and_warn_mode(tmp_path: Path) -> None:
    (tmp_path / "a.bvh").write_text(_rig_bvh(MIXAMO, scale=100.0))
    (tmp_path / "b.bvh").write_text(_rig_bvh(MIXAMO, scale=100.0))
    (tmp_path / "README.md").write_text("not a recording")
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "c.bvh").write_text(CHAIN.replace("Frames: 2", "Frames: 9"))  # broken
    assert [t.name for t in read_many(tmp_path, recursive=False)] == ["a", "b"]
    assert [t.name for t in read_many([tmp_path / "a.bvh", str(tmp_path / "*.bvh")])] == ["a", "b"]
    with pytest.raises(TruncatedFileError):
        read_many(tmp_path)  # subfolders by default
    with pytest.warns(UserWarning, match="skipped: .*c.bvh"):
        assert len(read_many(tmp_path, on_error="warn")) == 2


def test_bandai_labels_from_file_names() -> None:
    assert labels_from_name("dataset-2_wave-right-hand_normal_003") == {
        "dataset": 2,
        "content": "wave-right-hand",
        "style": "normal",
        "take": 3,
    }
    assert labels_from_name("lambada") == {}


def test_gap_error_type_is_a_read_error() -> None:
    assert issubclass(GapError, ReadError) and issubclass(ReadError, ValueError)


def test_marker_csv_dispatch_round_trip_and_options(tmp_path: Path) -> None:
    from visprim.io.markers_csv import write_marker_csv

    (tmp_path / "mix.bvh").write_text(_rig_bvh(MIXAMO, scale=100.0))
    trial = read(tmp_path / "mix.bvh")
    write_marker_csv(tmp_path / "mix.csv", trial)
    back = read(tmp_path / "mix.csv")
    # The CSV keeps 0.01 mm and 1 µs (visprim.io.markers_csv): the trial survives the trip.
    assert np.abs(back.markers - trial.markers).max() <= 0.5e-5 + 1e-12
    assert np.abs(back.times - trial.times).max() <= 0.5e-6 + 1e-12
    assert read(tmp_path / "mix.csv", repetitions=3).repetitions == 3
    with pytest.raises(ValueError, match="mirror= applies to bvh/.*amass.* files, not mix.csv"):
        read(tmp_path / "mix.csv", mirror=True)
    with pytest.raises(ValueError, match="one \\(right\\) arm"):
        read(tmp_path / "mix.csv", arm="left")
    both = read_many(tmp_path, mirror=True, arm="right")  # mirror only reaches the BVH
    assert [Path(t.source).suffix for t in both] == [".bvh", ".csv"]
    assert both[0].meta["mirrored"] is True
    np.testing.assert_array_equal(both[1].markers, back.markers)
    (tmp_path / "bad.csv").write_text("time_s,upper_arm_x_m\n0,1\n")
    with pytest.raises(MalformedFileError, match=r"bad\.csv: "):
        read(tmp_path / "bad.csv")
