"""visprim.io on the real recordings in ../shared/data (read in place).

Expected frame counts, rates and sizes come from each folder's SOURCE.md table (parsed
here), segment lengths and elbow ranges from the SOURCE.md text, not from the readers.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from visprim.io import read, read_many
from visprim.trial import Trial

FORMATS = (".bvh", ".amc", ".c3d")


def source_table(folder: Path) -> dict[str, dict[str, str]]:
    """Rows of the per-file table in ``folder/SOURCE.md``: file → column → cell."""
    lines = [ln for ln in (folder / "SOURCE.md").read_text().splitlines() if ln.startswith("|")]
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    rows = {}
    for ln in lines[2:]:
        cells = [c.strip() for c in ln.strip("|").split("|")]
        rows[cells[0].strip("`")] = dict(zip(header, cells, strict=False))
    return rows


@functools.cache
def _load(path: str, arm: str = "right") -> Trial:
    return read(path, arm=arm)


def recordings(shared: Path) -> list[Path]:
    return sorted(p for p in shared.rglob("*") if p.suffix in FORMATS)


def test_every_recording_loads_with_the_frames_and_rate_of_its_source_table(
    shared_data: Path,
) -> None:
    checked = 0
    for folder in sorted(p for p in shared_data.iterdir() if p.is_dir()):
        table = source_table(folder)
        if not all("bytes" in row and "fps" in row for row in table.values()):
            continue  # a per-label table, not per file (the training-corpus folders)
        files = sorted(p for p in folder.iterdir() if p.suffix in FORMATS)
        assert files, folder
        for path in files:
            row = table[path.name]
            assert path.stat().st_size == int(row["bytes"]), path
            t = _load(str(path))
            assert t.n_frames == int(row["frames"]), path
            rate = float(t.meta["rate_hz"])
            assert rate == pytest.approx(float(row["fps"]), rel=2e-5), path
            assert t.frame_period == pytest.approx(1 / float(row["fps"]), rel=2e-5)
            assert t.duration + t.frame_period == pytest.approx(float(row["seconds"]), abs=0.06)
            assert t.joints is not None and t.body_frame is not None, path
            assert np.isfinite(t.markers).all() and np.isfinite(t.joints).all()
            assert t.source == str(path) and t.name == path.stem
            checked += 1
    assert checked == 62  # 34 Bandai + 6 AMC + 2 + 17 iClone + 3 C3D (folders with file tables)


def _lengths(t: Trial) -> tuple[np.ndarray, np.ndarray]:
    j = t.joints
    assert j is not None
    return np.linalg.norm(j[:, 1] - j[:, 0], axis=1), np.linalg.norm(j[:, 2] - j[:, 1], axis=1)


@pytest.mark.parametrize(
    ("folder", "upper", "fore"),
    [("bandai_namco_ds2", 0.243, 0.223), ("cmu_iclone_bvh", 0.252, 0.257)],
)
def test_bvh_bone_lengths_are_constant_and_match_the_source(
    shared_data: Path, folder: str, upper: float, fore: float
) -> None:
    for path in sorted((shared_data / folder).glob("*.bvh")):
        up, fo = _lengths(_load(str(path)))
        assert np.ptp(up) < 1e-3 and np.ptp(fo) < 1e-3, path  # constant within 1 mm
        assert up.mean() == pytest.approx(upper, abs=2e-3), path  # SOURCE.md: 24.3 / 25.2 cm
        assert fo.mean() == pytest.approx(fore, abs=2e-3), path  # SOURCE.md: 22.3 / 25.7 cm


def test_amc_bone_lengths_constant_and_elbow_ranges_as_described(shared_data: Path) -> None:
    for path in sorted((shared_data / "cmu_asfamc").glob("*.amc")):
        t = _load(str(path))
        up, fo = _lengths(t)
        assert np.ptp(up) < 1e-3 and np.ptp(fo) < 1e-3, path
        assert 0.21 <= up.mean() <= 0.34, path  # SOURCE.md: upper arm 0.21-0.33 m
        assert 0.2 <= fo.mean() <= 0.32, path  # elbow to the start of the hand bone
        j = t.joints
        cos = np.sum((j[:, 1] - j[:, 0]) * (j[:, 2] - j[:, 1]), axis=1) / (up * fo)
        flexion = np.degrees(np.arccos(np.clip(cos, -1, 1)))
        if path.stem == "lambada":  # SOURCE.md: "elbow ~80-100 deg"
            assert 75 < np.median(flexion) < 105
        if path.stem == "zombie":  # SOURCE.md: "elbow nearly straight (135-150 deg)"
            assert 25 < np.median(flexion) < 50


def test_c3d_joint_centres_keep_segment_lengths_within_skin_marker_artefact(
    shared_data: Path,
) -> None:
    for path in sorted(shared_data.glob("*/*.c3d")):
        up, fo = _lengths(_load(str(path)))
        # Landmarks on skin move against the bones by a centimetre or two (acromion most).
        assert up.std() < 0.02 and fo.std() < 0.02, (path, up.std(), fo.std())
        assert up.std() / up.mean() < 0.08 and fo.std() / fo.mean() < 0.08, path
        assert 0.15 < up.mean() < 0.4 and 0.15 < fo.mean() < 0.4, path  # metres, not mm


def test_c3d_units_up_axes_and_gaps_follow_the_files(shared_data: Path) -> None:
    tennis = _load(str(shared_data / "kineticstoolkit_c3d/kinematics_tennis_serve.c3d"))
    racing = _load(str(shared_data / "kineticstoolkit_c3d/kinematics_racing_full.c3d"))
    lift = _load(str(shared_data / "pyomeca_c3d/markers_analogs.c3d"))
    assert (tennis.meta["units_in_file"], tennis.meta["up_axis_in_file"]) == ("m", "+z")
    assert (racing.meta["units_in_file"], racing.meta["up_axis_in_file"]) == ("m", "+y")
    assert (lift.meta["units_in_file"], lift.meta["up_axis_in_file"]) == ("mm", "+z")
    assert tennis.meta["preset"] == "plug_in_gait" and tennis.subject == "Derrick"
    assert lift.meta["preset"] == "pyomeca_upper_limb" and lift.subject == "Daphnee"
    assert lift.meta["n_analog_channels"] == 38 and lift.meta["analog_rate_hz"] == 2000
    # SOURCE.md: tennis has no gaps; STYLu is missing in ~5 % of the lift (29 of 580 frames).
    assert tennis.meta["gaps"]["filled_frames"] == 0
    assert lift.meta["gaps"]["filled_frames"] == 29 and not lift.meta["gaps"]["long_gaps"]
    # SOURCE.md: the lift's INDEX marker rises from ~55 mm to ~995 mm (lab z).
    finger_z = lift.markers[:, 3, 2]
    assert np.ptp(finger_z) == pytest.approx(0.94, abs=0.03)
    # Trunk up in the common frame: the torso's z axis points up on average.
    for t in (tennis, racing, lift):
        assert t.body_frame[:, 2, 2].mean() > 0.8, t.name


def test_subject_faces_plus_x_with_the_right_arm_on_minus_y(shared_data: Path) -> None:
    # The right shoulder is to the right of the left one (body -y) in every source that
    # has both, and the first frame faces +x.
    for rel in (
        "bandai_namco_ds2/dataset-2_wave-both-hands_normal_001.bvh",
        "cmu_iclone_bvh/005_02.bvh",
        "cmu_asfamc/lambada.amc",
        "kineticstoolkit_c3d/kinematics_tennis_serve.c3d",
    ):
        right, left = _load(str(shared_data / rel)), _load(str(shared_data / rel), "left")
        d = right.joints[:, 0] - left.joints[:, 0]
        lateral = np.einsum("ti,ti->t", d, right.body_frame[:, :, 1])
        assert np.all(lateral < -0.1), rel
        fwd0 = right.body_frame[0, :, 0]
        assert fwd0[0] > 0.9 and abs(fwd0[1]) < 1e-9, rel


def _wrist_motion(t: Trial) -> float:
    """RMS distance (m) of the wrist from its mean position, relative to the shoulder in
    body axes."""
    w = np.einsum("tij,ti->tj", t.body_frame, t.joints[:, 2] - t.joints[:, 0])
    return float(np.sqrt(np.mean(np.sum((w - w.mean(axis=0)) ** 2, axis=1))))


def test_bandai_right_hand_moves_and_left_hand_stays(shared_data: Path) -> None:
    files = sorted((shared_data / "bandai_namco_ds2").glob("*.bvh"))
    assert len(files) == 34
    for path in files:
        right = _wrist_motion(_load(str(path)))
        left = _wrist_motion(_load(str(path), "left"))
        t = _load(str(path))
        assert t.meta["style"] in path.stem and t.stimulus in path.stem
        assert right > 0.1, path
        if "right-hand" in path.stem:
            assert left < 0.08 and left < 0.3 * right, (path, left, right)
        else:  # both hands
            assert left > 0.1, path


def test_right_arm_moves_in_the_other_sources(shared_data: Path) -> None:
    for path in sorted(shared_data.glob("cmu_*/*")) + sorted(shared_data.glob("*/*.c3d")):
        if path.suffix in FORMATS:  # lambada holds the arm bent (least motion: 4.6 cm RMS)
            assert _wrist_motion(_load(str(path))) > 0.03, path


ORIGINAL = (
    "bandai_namco_ds2",
    "cmu_asfamc",
    "cmu_iclone_bvh",
    "kineticstoolkit_c3d",
    "pyomeca_c3d",
)


def test_read_many_on_folders_and_resampling_to_34_ms(shared_data: Path) -> None:
    trials = read_many([shared_data / f for f in ORIGINAL], resample=0.034)
    assert len(trials) == 45
    for t in trials:
        assert np.allclose(np.diff(t.times), 0.034)
        assert t.meta["resampled"]["period_s"] == 0.034
        # Resampling is linear: the virtual markers stay the joint-centre midpoints.
        np.testing.assert_allclose(t.markers[:, 0], (t.joints[:, 0] + t.joints[:, 1]) / 2)
        np.testing.assert_allclose(t.markers[:, 2], t.joints[:, 2])
