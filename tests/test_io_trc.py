"""OpenSim / Pose2Sim TRC files through visprim.io.read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _keypoint_data import arm_angles_truth, body_keypoints
from visprim.ik import arm_angles
from visprim.io import MalformedFileError, read, read_pieces

NAMES = ("Hip", "RHip", "LHip", "RShoulder", "RElbow", "RWrist", "LShoulder", "LElbow", "LWrist")


def _write_trc(
    path: Path, pts: np.ndarray, rate: float, units: str, *, time_column: bool = True
) -> None:
    """``pts`` (T, K, 3) in the file's axes and units; NaN written as empty fields."""
    n, k, _ = pts.shape
    lines = [
        f"PathFileType\t4\t(X/Y/Z)\t{path.name}",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame"
        "\tOrigNumFrames",
        f"{rate:g}\t{rate:g}\t{n}\t{k}\t{units}\t{rate:g}\t1\t{n}",
        "Frame#\t" + ("Time\t" if time_column else "") + "\t\t\t".join(NAMES) + "\t\t",
        "\t"
        + ("\t" if time_column else "")
        + "\t".join(f"X{i + 1}\tY{i + 1}\tZ{i + 1}" for i in range(k)),
        "",
    ]
    for i in range(n):
        vals = ["" if not np.isfinite(v) else f"{v:.6f}" for v in pts[i].ravel()]
        head = [str(i + 1)] + ([f"{i / rate:.6f}"] if time_column else [])
        lines.append("\t".join(head + vals))
    path.write_text("\n".join(lines) + "\n")


def _file_points(n: int, rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    right, left = arm_angles_truth(n, rate), arm_angles_truth(n, rate, phase=0.7)
    kp = body_keypoints(right, left)
    kp["hip"] = (kp["right_hip"] + kp["left_hip"]) / 2
    order = (
        "hip",
        "right_hip",
        "left_hip",
        "right_shoulder",
        "right_elbow",
        "right_wrist",
        "left_shoulder",
        "left_elbow",
        "left_wrist",
    )
    body = np.stack([kp[r] for r in order], axis=1)
    # OpenSim axes: +Y up; (x, y, z)_file = (y, z, x)_body, so that the reader's +Y-up
    # rotation (x, y, z)_trial = (z, x, y)_file gives the body frame back.
    return body[..., [1, 2, 0]], right, left


def test_trc_units_rate_axes_and_names(tmp_path):
    pts, right, left = _file_points(120, 60.0)
    f = tmp_path / "walk.trc"
    _write_trc(f, pts * 1000.0, 60.0, "mm")
    trial = read(f, arm="both")
    assert trial.meta["format"] == "trc" and trial.meta["units"] == "mm"
    assert trial.meta["rate"] == 60.0
    np.testing.assert_allclose(trial.times, np.arange(120) / 60.0, atol=1e-6)
    ik = arm_angles(trial)
    np.testing.assert_allclose(ik[:, :4], right, atol=1e-5)
    np.testing.assert_allclose(ik[:, 4:], left, atol=1e-5)
    # Metres from the header's unit: the upper arm is 0.30 m.
    np.testing.assert_allclose(
        np.linalg.norm(trial.joints[:, 1] - trial.joints[:, 0], axis=1), 0.30, atol=1e-5
    )
    assert trial.meta["keypoints"]["right_shoulder"] == ["RShoulder"]


def test_trc_rate_from_header_without_time_column(tmp_path):
    pts, right, _ = _file_points(90, 30.0)
    f = tmp_path / "a.trc"
    _write_trc(f, pts, 30.0, "m", time_column=False)
    trial = read(f)
    assert trial.meta["times_from"] == "Frame# / DataRate"
    np.testing.assert_allclose(trial.times, np.arange(90) / 30.0)
    np.testing.assert_allclose(arm_angles(trial), right, atol=1e-4)  # 1 µm in the file


def test_trc_gaps_follow_the_c3d_policy(tmp_path):
    pts, _, _ = _file_points(240, 60.0)
    pts[40:44, 5] = np.nan  # right wrist: 4 frames, filled
    pts[120:150, 4] = np.nan  # right elbow: 0.5 s, split
    f = tmp_path / "g.trc"
    _write_trc(f, pts, 60.0, "m")
    pieces = read_pieces(f, min_duration=0.3)
    assert [p.meta["frame_range"] for p in pieces] == [[0, 120], [150, 240]]
    assert pieces[0].meta["gaps"]["filled_frames"] == 4


def test_trc_errors_name_the_file(tmp_path):
    f = tmp_path / "bad.trc"
    f.write_text("PathFileType\t4\nDataRate\tNumMarkers\tUnits\n60\t2\tfurlongs\nFrame#\tTime\n\n")
    with pytest.raises(MalformedFileError, match=r"bad\.trc: unknown Units 'furlongs'"):
        read(f)
    g = tmp_path / "short.trc"
    pts, _, _ = _file_points(30, 60.0)
    _write_trc(g, pts[:, 3:6], 60.0, "m")  # 3 markers declared but 9 names
    with pytest.raises(MalformedFileError, match="declares 3 markers, line 4 names 9"):
        read(g)
