"""Gap filling / splitting, resampling, and the C3D reader's gap, mapping and error paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation
from visprim.io import (
    GapError,
    MalformedFileError,
    MissingPointError,
    TruncatedFileError,
    read,
    read_pieces,
    resample_trial,
)
from visprim.io.gaps import fill_and_split, missing_runs
from visprim.trial import Trial

RATE = 100.0


def _signal(n: int = 300) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / RATE
    x = np.stack([np.sin(2 * np.pi * 0.7 * t), np.cos(2 * np.pi * 0.4 * t), 0.3 * t], axis=1)
    return t, np.stack([x, 2 * x], axis=1)  # (T, 2, 3)


def test_missing_runs() -> None:
    m = np.array([0, 1, 1, 0, 0, 1, 0, 1], bool)
    assert missing_runs(m) == [(1, 3), (5, 6), (7, 8)]
    assert missing_runs(np.zeros(4, bool)) == []


@pytest.mark.parametrize("method", ["cubic", "pchip", "linear"])
def test_short_gaps_are_filled_close_to_the_true_signal(method: str) -> None:
    t, x = _signal()
    holed = x.copy()
    holed[100:115, 0] = np.nan  # 0.15 s
    holed[200:203, 1, 2] = np.nan
    pieces, report = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, method=method)
    assert len(pieces) == 1 and pieces[0][:2] == (0, 300)
    filled = pieces[0][2]
    assert np.isfinite(filled).all()
    ok = np.isfinite(holed).all(axis=2)  # a point with any NaN coordinate is missing
    np.testing.assert_array_equal(filled[ok], x[ok])
    # A chord across the 0.16 s hole in a unit 0.7 Hz sine errs by up to (ωh)²/8 ≈ 0.061;
    # the cubic spline through all samples does much better.
    tol = {"cubic": 1e-3, "pchip": 0.065, "linear": 0.065}[method]
    assert np.abs(filled - x).max() < tol
    assert report.as_dict()["filled_frames"] == 18 and report.as_dict()["filled_runs"] == 2


def test_long_gaps_split_raise_or_keep_the_longest() -> None:
    t, x = _signal()
    holed = x.copy()
    holed[80:140, 1] = np.nan  # 0.6 s > max_gap
    pieces, report = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2)
    assert [(a, b) for a, b, _ in pieces] == [(0, 80), (140, 300)]
    assert report.long == [("b", 80, 140)]
    for a, b, p in pieces:
        np.testing.assert_array_equal(p, x[a:b])
    with pytest.raises(
        GapError, match=r"sig: 1 gap\(s\) longer than max_gap=0.2 s.*b missing in frames 80–139"
    ):
        fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, on_gap="raise")
    longest, _ = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, on_gap="longest")
    assert [(a, b) for a, b, _ in longest] == [(140, 300)]
    # A larger max_gap fills it instead.
    one, _ = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.7)
    assert len(one) == 1


def test_edges_are_trimmed_never_extrapolated_and_short_pieces_dropped() -> None:
    t, x = _signal()
    holed = x.copy()
    holed[:5, 0] = np.nan
    holed[-3:, 1] = np.nan
    holed[150:190, 0] = np.nan  # long
    holed[190:200, 1] = np.nan  # short, but now at the start of the second piece
    holed[260:262, 0] = np.nan
    pieces, report = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, min_duration=0.5)
    assert [(a, b) for a, b, _ in pieces] == [(5, 150), (200, 297)]
    assert report.trimmed_frames == 5 + 3 + 10
    with pytest.warns(UserWarning, match="dropped 1 piece"):
        pieces, report = fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, min_duration=1.2)
    assert [(a, b) for a, b, _ in pieces] == [(5, 150)] and report.dropped_pieces == [(200, 297)]
    with pytest.raises(GapError, match="no piece of at least 5 s"), pytest.warns(UserWarning):
        fill_and_split("sig", t, holed, ["a", "b"], max_gap=0.2, min_duration=5)


@pytest.mark.filterwarnings("ignore:sig. dropped")
@settings(max_examples=60, deadline=None)
@given(
    holes=st.lists(
        st.tuples(st.integers(0, 199), st.integers(1, 40), st.integers(0, 1)), max_size=6
    ),
    max_gap=st.sampled_from([0.05, 0.1, 0.3]),
)
def test_gap_handling_never_keeps_nan_or_fills_long_gaps(
    holes: list[tuple[int, int, int]], max_gap: float
) -> None:
    t, x = _signal(200)
    holed = x.copy()
    for start, length, p in holes:
        holed[start : start + length, p] = np.nan
    try:
        pieces, report = fill_and_split(
            "sig", t, holed, ["a", "b"], max_gap=max_gap, min_duration=0.0
        )
    except GapError:
        return  # nothing usable left: allowed, and reported as an error
    for a, b, piece in pieces:
        assert np.isfinite(piece).all()
        valid = np.isfinite(holed[a:b]).all(axis=2)
        # Inside a piece every missing run is short and has data on both sides.
        for p in range(2):
            assert valid[0, p] and valid[-1, p]
            for ra, rb in missing_runs(~valid[:, p]):
                assert (rb - ra) / RATE <= max_gap + 1e-9
        np.testing.assert_array_equal(piece[valid], holed[a:b][valid])


# --- resampling -------------------------------------------------------------------------


def _trial(n: int = 240, rate: float = 120.0) -> Trial:
    t = np.arange(n) / rate
    s = np.zeros((n, 3)) + [0, -0.2, 1.4]
    e = s + np.stack([0.1 * np.sin(2 * np.pi * 0.5 * t), 0 * t, -0.28 + 0 * t], axis=1)
    w = e + np.stack([0.25 + 0 * t, 0.05 * np.cos(2 * np.pi * 0.5 * t), 0 * t], axis=1)
    f = w + [0.1, 0, 0]
    joints = np.stack([s, e, w], axis=1)
    markers = np.stack([(s + e) / 2, (e + w) / 2, w, f], axis=1)
    yaw = 40 * np.sin(2 * np.pi * 0.25 * t)
    body = Rotation.from_euler("z", yaw[:, None], degrees=True).as_matrix()
    return Trial(times=t, markers=markers, joints=joints, body_frame=body, name="syn")


def test_resampling_to_34_ms_keeps_signals_and_marker_geometry() -> None:
    trial = _trial()
    out = resample_trial(trial, 0.034)
    assert out.n_frames == int(np.floor(trial.duration / 0.034)) + 1
    np.testing.assert_allclose(np.diff(out.times), 0.034)
    t = out.times
    expected_elbow_x = 0.1 * np.sin(2 * np.pi * 0.5 * t)
    np.testing.assert_allclose(out.joints[:, 1, 0], expected_elbow_x, atol=2e-3)
    np.testing.assert_allclose(out.markers[:, 1], (out.joints[:, 1] + out.joints[:, 2]) / 2)
    yaw = Rotation.from_matrix(out.body_frame).as_euler("zyx", degrees=True)[:, 0]
    np.testing.assert_allclose(yaw, 40 * np.sin(2 * np.pi * 0.25 * t), atol=0.5)
    assert out.meta["resampled"]["antialias_cutoff_hz"] == pytest.approx(0.8 * 0.5 / 0.034)
    up = resample_trial(trial, 0.004)  # upsampling: no anti-aliasing filter
    assert up.meta["resampled"]["antialias_cutoff_hz"] is None
    np.testing.assert_allclose(up.joints[:, 1, 0], 0.1 * np.sin(np.pi * up.times), atol=1e-6)
    with pytest.raises(ValueError, match="positive"):
        resample_trial(trial, 0)
    with pytest.raises(ValueError, match="leaves 1 frame"):
        resample_trial(trial, 5.0)


def test_resampling_removes_content_above_the_new_nyquist() -> None:
    trial = _trial(600, 120.0)
    t = trial.times
    noisy = trial.markers.copy()
    noisy[:, :, 2] += 0.01 * np.sin(2 * np.pi * 25.0 * t)[:, None]  # 25 Hz > 14.7 Hz Nyquist
    trial2 = Trial(times=t, markers=noisy, name="noisy")
    out = resample_trial(trial2, 0.034)
    clean = resample_trial(Trial(times=t, markers=trial.markers, name="c"), 0.034)
    # Without the filter the 25 Hz wobble would alias to ~4.4 Hz with 10 mm amplitude.
    assert np.abs(out.markers - clean.markers)[20:-20].max() < 1e-3
    raw = resample_trial(trial2, 0.034, antialias=False)
    assert np.abs(raw.markers - clean.markers)[20:-20].max() > 5e-3


# --- C3D gap / mapping / error paths on a real file (modified copies in tmp_path) -------


@pytest.fixture(scope="module")
def tennis(shared_data: Path) -> Path:
    return shared_data / "kineticstoolkit_c3d" / "kinematics_tennis_serve.c3d"


def _with_gap(src: Path, dst: Path, label: str, frames: slice) -> Path:
    import ezc3d

    c = ezc3d.c3d(str(src))
    labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
    pts = c["data"]["points"]
    pts[:3, labels.index(label), frames] = np.nan
    c["data"]["points"] = pts
    c.write(str(dst))
    return dst


def test_c3d_short_gap_is_filled_near_the_recorded_trajectory(tennis: Path, tmp_path: Path) -> None:
    orig = read(tennis)
    # 0.1 s gap in the elbow marker while the arm is slow (frame 600 of 1092).
    gappy = _with_gap(tennis, tmp_path / "g.c3d", "Derrick:RELB", slice(600, 605))
    t = read(gappy)
    assert t.meta["gaps"]["filled_frames"] == 5
    err = np.linalg.norm(t.joints[600:605, 1] - orig.joints[600:605, 1], axis=1).max()
    assert err < 0.01  # a 0.1 s cubic fill within 1 cm of the marker's real path
    np.testing.assert_allclose(t.joints[:600], orig.joints[:600], atol=1e-6)


def test_c3d_long_gap_splits_raises_or_keeps_longest(tennis: Path, tmp_path: Path) -> None:
    gappy = _with_gap(tennis, tmp_path / "g.c3d", "Derrick:RWRB", slice(400, 450))  # 1 s
    pieces = read_pieces(gappy)
    assert [p.name for p in pieces] == ["g_part1", "g_part2"]
    assert [p.meta["frame_range"] for p in pieces] == [[0, 400], [450, 1092]]
    assert pieces[1].times[0] == pytest.approx(450 / 50)
    # Both pieces share one heading (computed once for the recording).
    assert pieces[0].meta["heading_deg"] == pieces[1].meta["heading_deg"]
    with pytest.raises(GapError, match="split the recording into 2 pieces"):
        read(gappy)
    with pytest.raises(GapError, match=r"g\.c3d: 1 gap\(s\) longer than max_gap=0.2 s"):
        read(gappy, on_gap="raise")
    assert read(gappy, on_gap="longest").meta["frame_range"] == [450, 1092]
    assert read(gappy, max_gap=1.5).n_frames == 1092


def test_c3d_mapping_file_markers_and_missing_markers(tennis: Path) -> None:
    t = read(tennis, markers="file")
    # The file's own sensors: RUPA, RFRM, mid-wrist bar, RFIN.
    assert t.meta["marker_names"]["upper_arm"] == ["Derrick:RUPA"]
    assert not np.allclose(t.markers[:, 0], (t.joints[:, 0] + t.joints[:, 1]) / 2)
    m = read(
        tennis,
        mapping={"shoulder": "RSHO", "elbow": "RELB", "wrist": ["RWRA", "RWRB"], "finger": "RFIN"},
    )
    assert m.meta["preset"] == "mapping" and m.meta["shoulder_from"] == "shoulder marker"
    assert m.body_frame is not None  # torso markers borrowed from the matching preset
    with pytest.raises(MissingPointError, match="elbow \\(RKNEEX\\)"):
        read(tennis, mapping={"shoulder": "RSHO", "elbow": "RKNEEX", "wrist": "RWRA"})
    with pytest.raises(MissingPointError, match="cannot find the right arm's markers"):
        read(tennis, preset="anatomical_landmarks")
    left = read(tennis, arm="left")
    assert left.meta["marker_names"]["acromion"] == ["Derrick:LSHO"]


def test_c3d_truncated_and_garbage_files(tennis: Path, tmp_path: Path) -> None:
    data = tennis.read_bytes()
    cut = tmp_path / "cut.c3d"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(TruncatedFileError, match=r"cut\.c3d: the header declares 1092 frames"):
        read(cut)
    tiny = tmp_path / "tiny.c3d"
    tiny.write_bytes(data[:300])
    with pytest.raises(TruncatedFileError, match="cut short"):
        read(tiny)
    junk = tmp_path / "junk.c3d"
    junk.write_bytes(b"not a c3d file" * 100)
    with pytest.raises(MalformedFileError, match=r"junk\.c3d: not a readable C3D file"):
        read(junk)
    empty = tmp_path / "empty.c3d"
    empty.write_bytes(b"")
    with pytest.raises(TruncatedFileError, match="empty"):
        read(empty)


def test_reader_warnings_from_worker_processes_reach_the_caller(
    tennis: Path, tmp_path: Path
) -> None:
    """`read_movements` reads in spawned workers; a reader's warning (here a piece shorter
    than min_duration dropped before a long gap) is handed back and raised in the caller,
    where the CLI shows it as a ``warning:`` line, not printed raw by the worker."""
    from visprim.evaluate import Recording, read_movements

    gappy = _with_gap(tennis, tmp_path / "g.c3d", "Derrick:RWRB", slice(10, 60))
    recordings = [Recording(gappy, "serve")] * 4  # four: the worker pool is used
    with pytest.warns(UserWarning, match=r"g\.c3d: dropped 1 piece") as caught:
        trials, errors = read_movements(recordings, arm="right", jobs=2)
    assert errors == [] and all(t is not None for t in trials)
    assert sum("dropped 1 piece" in str(w.message) for w in caught) == 4
