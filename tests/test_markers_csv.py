"""The plain marker CSV format: round trip, metadata, truth sidecar, malformed files."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from visprim.cli import main as cli_main
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import (
    MarkerCSVError,
    read_marker_csv,
    truth_path,
    write_marker_csv,
)
from visprim.trial import MARKER_NAMES, Trial

HEADER = "time_s," + ",".join(f"{n}_{a}_m" for n in MARKER_NAMES for a in "xyz")


@pytest.fixture(scope="module")
def trial() -> Trial:
    return imitation_experiment(1, 5, preset="strokes")[4]


def _data_rows(path: Path) -> list[str]:
    return [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")][1:]


def test_round_trip_is_exact_to_the_written_precision(tmp_path: Path, trial: Trial) -> None:
    path = write_marker_csv(tmp_path / "a.csv", trial)
    back = read_marker_csv(path)
    assert back.n_frames == trial.n_frames
    assert np.abs(back.times - trial.times).max() <= 0.5e-6 + 1e-12
    assert np.abs(back.markers - trial.markers).max() <= 0.5e-5 + 1e-12
    # and the values are the decimal-rounded ones, not merely close
    np.testing.assert_allclose(back.markers, np.round(trial.markers, 5), rtol=0, atol=1e-12)
    assert back.name == trial.name and back.subject == trial.subject
    assert back.stimulus == trial.stimulus and back.repetitions == trial.repetitions == 2
    assert back.source == str(path)
    assert back.meta["stimulus_name"] == trial.meta["stimulus_name"]
    assert back.meta["seed"] == 0 and back.meta["noise"] is True
    assert abs(back.meta["rate_hz"] - 1 / 0.034) < 0.3
    # the truth sidecar is exact (floats written with full precision)
    assert truth_path(path).is_file()
    assert np.array_equal(back.truth.angles, trial.truth.angles)
    assert np.array_equal(back.truth.boundaries, trial.truth.boundaries)
    assert np.array_equal(back.truth.labels, trial.truth.labels)
    assert back.truth.repetitions == trial.truth.repetitions
    # writing what was read gives the same data rows
    again = write_marker_csv(tmp_path / "b.csv", back)
    assert _data_rows(again) == _data_rows(path)


def test_header_names_sensors_and_units(tmp_path: Path, trial: Trial) -> None:
    path = write_marker_csv(tmp_path / "a.csv", trial, truth=False)
    lines = path.read_text().splitlines()
    assert lines[0] == "# visprim marker CSV v1"
    assert HEADER in lines
    assert "# repetitions: 2" in lines and f"# name: {trial.name}" in lines
    assert any(ln.startswith("# frame: metres") for ln in lines)
    assert not truth_path(path).exists()
    assert read_marker_csv(path).truth is None


def test_repetitions_argument_overrides_the_file(tmp_path: Path, trial: Trial) -> None:
    path = write_marker_csv(tmp_path / "a.csv", trial)
    assert read_marker_csv(path, repetitions=5).repetitions == 5


def _write(tmp_path: Path, text: str, name: str = "rec.csv") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _row(t: float, base: float = 0.1) -> str:
    return f"{t:.3f}," + ",".join(f"{base + 0.01 * i:.4f}" for i in range(12))


def test_minimal_hand_written_file_in_any_column_order_and_mm(tmp_path: Path) -> None:
    cols = HEADER.split(",")
    order = [0] + list(range(12, 0, -1))  # time first, then the sensors reversed
    mm_cols = [c.replace("_m", "_mm") if c != "time_s" else c for c in cols]
    header = ",".join(mm_cols[i] for i in order)
    rows = []
    for t in (0.0, 0.034, 0.068):
        values = [t] + [1000 * (0.1 + 0.01 * i + t) for i in range(12)]
        rows.append(",".join(str(values[i]) for i in order))
    path = _write(tmp_path, "\n".join([header, *rows]) + "\n")
    trial = read_marker_csv(path)
    assert trial.name == "rec" and trial.subject is None and trial.repetitions == 1
    expected = (0.1 + 0.01 * np.arange(12)).reshape(4, 3)
    np.testing.assert_allclose(trial.markers[0], expected, atol=1e-12)
    np.testing.assert_allclose(trial.markers[2], expected + 0.068, atol=1e-12)
    assert trial.meta["units_in_file"] == "mm"


GOOD = [HEADER, _row(0.0), _row(0.034), _row(0.068)]


def _without_column(name: str) -> list[str]:
    cols = HEADER.split(",")
    j = cols.index(name)
    return [",".join(c for i, c in enumerate(line.split(",")) if i != j) for line in GOOD]


MALFORMED = {
    "empty file": ([], r"empty marker CSV"),
    "only comments": (["# name: x", ""], r"empty marker CSV"),
    "header only": ([HEADER], r"at least 2 data rows, found 0"),
    "one row": ([HEADER, _row(0.0)], r"at least 2 data rows, found 1"),
    "missing column": (_without_column("wrist_y_m"), r"line 1: missing column wrist_y_m"),
    "missing time": (_without_column("time_s"), r"line 1: header needs exactly one time column"),
    "three sensors": (
        [",".join(c for c in line.split(",")[:10]) for line in GOOD],
        r"line 1: expected 4 sensors .* found 3 \(missing finger\)",
    ),
    "five sensors": (
        [GOOD[0] + ",elbow_x_m,elbow_y_m,elbow_z_m"] + [r + ",1,2,3" for r in GOOD[1:]],
        r"line 1: expected 4 sensors .* found 5 \(unknown elbow\)",
    ),
    "bad column name": (
        [HEADER.replace("finger_z_m", "finger_q_m")] + GOOD[1:],
        r"line 1: column 13 'finger_q_m' is not",
    ),
    "duplicate column": (
        [HEADER.replace("finger_z_m", "finger_y_m")] + GOOD[1:],
        r"column 'finger_y_m' appears twice",
    ),
    "mixed units": (
        [HEADER.replace("finger_z_m", "finger_z_mm")] + GOOD[1:],
        r"sensor finger mixes units",
    ),
    "non-numeric cell": (
        GOOD[:2] + [GOOD[2].replace("0.1300", "abc")] + GOOD[3:],
        r"line 3: non-numeric value 'abc'",
    ),
    "empty cell": (GOOD[:3] + [GOOD[3].replace("0.1300", "")], r"line 4: non-numeric value ''"),
    "NaN cell": (
        GOOD[:2] + [GOOD[2].replace("0.1300", "nan")],
        r"line 3: column 5 is not a finite number \('nan'\)",
    ),
    "infinite cell": (
        GOOD[:2] + [GOOD[2].replace("0.1300", "inf")],
        r"line 3: column 5 is not a finite number",
    ),
    "short row": (
        GOOD[:2] + [GOOD[2].rsplit(",", 1)[0]] + GOOD[3:],
        r"line 3: expected 13 values, found 12",
    ),
    "repeated timestamp": (
        [HEADER, _row(0.0), _row(0.034), _row(0.034)],
        r"line 4: timestamp 0.034 does not increase",
    ),
    "decreasing timestamp": (
        [HEADER, _row(0.0), _row(0.068), _row(0.034)],
        r"line 4: timestamp 0.034 does not increase",
    ),
    "bad repetitions": (["# repetitions: two"] + GOOD, r"repetitions must be an integer"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_files_raise_a_clear_error(tmp_path: Path, case: str) -> None:
    lines, pattern = MALFORMED[case]
    path = _write(tmp_path, "\n".join(lines) + ("\n" if lines else ""))
    with pytest.raises(MarkerCSVError, match=pattern) as info:
        read_marker_csv(path)
    assert isinstance(info.value, ValueError)
    assert str(path) in str(info.value)


def test_missing_file_and_bad_truth_sidecar(tmp_path: Path, trial: Trial) -> None:
    with pytest.raises(MarkerCSVError, match="cannot read"):
        read_marker_csv(tmp_path / "nope.csv")
    path = write_marker_csv(tmp_path / "a.csv", trial)
    truth_path(path).write_text('{"angles_rad": [[0, 0, 0, 0]]}')
    with pytest.raises(MarkerCSVError, match=r"a\.truth\.json: unreadable truth sidecar"):
        read_marker_csv(path)
    truth_path(path).write_text(
        '{"angles_rad": [[0, 0, 0, 0]], "boundaries_s": [0, 1], "labels": [0]}'
    )
    with pytest.raises(MarkerCSVError, match=r"truth angles have shape \(1, 4\)"):
        read_marker_csv(path)


finite = st.floats(min_value=-5.0, max_value=5.0, allow_nan=False, allow_infinity=False)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    steps=st.lists(st.floats(min_value=0.001, max_value=0.1), min_size=1, max_size=30),
    data=st.data(),
)
def test_round_trip_property(tmp_path: Path, steps: list[float], data: st.DataObject) -> None:
    times = np.concatenate([[0.0], np.cumsum(steps)])
    values = data.draw(st.lists(finite, min_size=12 * times.size, max_size=12 * times.size))
    markers = np.asarray(values).reshape(times.size, 4, 3)
    trial = Trial(times=times, markers=markers, name="prop", subject="ab", repetitions=3)
    back = read_marker_csv(write_marker_csv(tmp_path / "p.csv", trial))
    assert np.abs(back.times - times).max() <= 0.5e-6 + 1e-12
    assert np.abs(back.markers - markers).max() <= 0.5e-5 + 1e-12
    assert back.subject == "ab" and back.repetitions == 3 and back.name == "prop"


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    row=st.integers(min_value=0, max_value=2),
    col=st.integers(min_value=0, max_value=12),
    token=st.sampled_from(["x", "1.2.3", "--1", "0x12", "1e", "one", "1;2", "1a"]),
)
def test_any_corrupted_cell_names_its_line(tmp_path: Path, row: int, col: int, token: str) -> None:
    lines = list(GOOD)
    cells = lines[1 + row].split(",")
    cells[col] = token
    lines[1 + row] = ",".join(cells)
    path = _write(tmp_path, "\n".join(lines) + "\n")
    with pytest.raises(MarkerCSVError, match=rf"line {2 + row}: non-numeric value"):
        read_marker_csv(path)


def test_cli_generate_writes_readable_files(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "exp"
    assert cli_main(["generate", "--out", str(out), "--subjects", "2", "--stimuli", "3"]) == 0
    assert re.search(r"wrote 6 trial files", capsys.readouterr().out)
    files = sorted(out.glob("*.csv"))
    assert [f.stem for f in files] == [f"s{s:02d}_m{m:02d}" for s in range(2) for m in range(3)]
    generated = {t.name: t for t in imitation_experiment(2, 3)}
    for f in files:
        back = read_marker_csv(f)
        ref = generated[back.name]
        assert np.abs(back.markers - ref.markers).max() <= 0.5e-5 + 1e-12
        assert np.array_equal(back.truth.boundaries, ref.truth.boundaries)
        assert back.repetitions == ref.repetitions
