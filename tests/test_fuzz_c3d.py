"""C3D: the reader against the format and against ezc3d, and damaged files.

A damaged C3D must end in a :class:`visprim.io.ReadError` (or read as a valid trial), never
another exception and never a crash. The reader is pure Python/numpy; the cases that crashed
the process inside ezc3d also run in a child process, so that a crash fails the test
instead of killing pytest.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _c3d_files import DEC, INTEL, MIPS, PIG_LABELS, arm_points, c3d_bytes, write_arm_c3d
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from visprim.io import MalformedFileError, ReadError, TruncatedFileError, read
from visprim.io.c3d_format import read_c3d
from visprim.trial import Trial

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
TENNIS = "kineticstoolkit_c3d/kinematics_tennis_serve.c3d"


def _valid(trial: Trial) -> None:
    assert np.isfinite(trial.markers).all() and np.isfinite(trial.times).all()
    assert trial.markers.shape == (trial.n_frames, 4, 3)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("c3d")


@pytest.fixture(scope="module")
def good(folder: Path) -> bytes:
    return write_arm_c3d(folder / "good.c3d").read_bytes()


@pytest.mark.parametrize(
    ("processor", "scale", "units"),
    [
        (INTEL, -1.0, "m"),
        (INTEL, 0.1, "mm"),
        (DEC, -1.0, "mm"),
        (MIPS, -1.0, "cm"),
        (MIPS, 0.01, "cm"),
    ],
)
def test_processors_and_integer_data_round_trip(
    tmp_path: Path, processor: int, scale: float, units: str
) -> None:
    pts = arm_points() * {"m": 1.0, "cm": 100.0, "mm": 1000.0}[units]
    missing = np.zeros(pts.shape[:2], dtype=bool)
    missing[10:13, 2] = True
    path = tmp_path / "t.c3d"
    path.write_bytes(
        c3d_bytes(PIG_LABELS, pts, processor=processor, scale=scale, units=units, missing=missing)
    )
    c3d = read_c3d(path)
    assert c3d.labels("POINT", len(PIG_LABELS)) == PIG_LABELS
    assert c3d.param("POINT", "UNITS") == [units]
    assert float(c3d.param("POINT", "RATE")[0]) == 100.0
    expect = np.where(missing[:, :, None], np.nan, pts)
    tol = scale / 2 if scale > 0 else 1e-4 * np.abs(pts).max()
    np.testing.assert_allclose(c3d.points, expect, atol=tol)
    trial = read(path, max_gap=0.05)
    _valid(trial)
    assert trial.meta["gaps"]["filled_frames"] == 3


def test_synthetic_file_matches_ezc3d(good: bytes, folder: Path) -> None:
    ezc3d = pytest.importorskip("ezc3d")
    path = folder / "same.c3d"
    path.write_bytes(good)
    ref = np.transpose(ezc3d.c3d(str(path))["data"]["points"][:3], (2, 1, 0))
    np.testing.assert_array_equal(read_c3d(path).points, ref)


def test_shared_recordings_match_ezc3d(shared_data: Path) -> None:
    ezc3d = pytest.importorskip("ezc3d")
    for path in sorted(shared_data.glob("*/*.c3d")):
        mine = read_c3d(path)
        c = ezc3d.c3d(str(path))
        ref = np.transpose(c["data"]["points"][:3], (2, 1, 0))
        np.testing.assert_array_equal(np.isnan(mine.points), np.isnan(ref), err_msg=path.name)
        np.testing.assert_allclose(mine.points, ref, rtol=0, atol=1e-9, err_msg=path.name)
        labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
        assert mine.labels("POINT", len(labels)) == labels
        for key in ("RATE", "UNITS"):
            value = c["parameters"]["POINT"][key]["value"]
            assert list(np.ravel(mine.param("POINT", key))) == list(np.ravel(value)), key


# --- the crash found by hand: a parameter's dimension count set to 0xAF -------------------

_CHILD = """
import json, sys, warnings
from visprim.io import ReadError, read
out = {}
for path in sys.argv[1:]:
    print(path, file=sys.stderr, flush=True)  # the last name printed is the one that crashed
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            read(path)
        out[path] = "read"
    except ReadError as exc:
        out[path] = "ReadError: " + str(exc)
print(json.dumps(out))
"""


def _read_in_child(paths: list[Path]) -> dict[str, str]:
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, *map(str, paths)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "python"), *sys.path])},
    )
    last = proc.stderr.strip().splitlines()[-1:] if proc.stderr.strip() else []
    assert proc.returncode == 0, f"child exited with {proc.returncode} while reading {last}"
    return dict(json.loads(proc.stdout.strip().splitlines()[-1]))


def test_parameter_with_175_dimensions_is_a_read_error_not_a_crash(
    shared_data: Path, tmp_path: Path
) -> None:
    data = bytearray((shared_data / TENNIS).read_bytes())
    data[1678] = 0xAF  # EVENT:USED's dimension count: ezc3d read 175 dimensions and crashed
    bad = tmp_path / "bad.c3d"
    bad.write_bytes(bytes(data))
    result = _read_in_child([bad])
    assert result[str(bad)].startswith(f"ReadError: {bad}: parameter 'USED' at byte 1669")
    with pytest.raises(MalformedFileError, match="175 dimensions"):
        read(bad)


def test_random_byte_flips_of_a_real_file_in_a_child_process(
    shared_data: Path, tmp_path: Path
) -> None:
    """100 files with 1–3 random bytes changed in the header and parameter section, read in
    one child process (ezc3d crashed on some of them)."""
    data = (shared_data / TENNIS).read_bytes()
    rng = np.random.default_rng(20261130)
    paths = []
    for i in range(100):
        b = bytearray(data)
        for pos in rng.integers(0, 512 * 8, size=rng.integers(1, 4)):
            b[int(pos)] = int(rng.integers(0, 256))
        paths.append(tmp_path / f"flip{i:03d}.c3d")
        paths[-1].write_bytes(bytes(b))
    result = _read_in_child(paths)
    assert len(result) == 100
    outcomes = [v.split(":")[0] for v in result.values()]
    assert set(outcomes) <= {"read", "ReadError"}
    assert outcomes.count("ReadError") >= 5  # most flips in names or padding are harmless


# --- hypothesis: damaged synthetic files, read in-process ---------------------------------

#: Examples per property (raise it for a longer run: VISPRIM_FUZZ_EXAMPLES=2000).
EXAMPLES = int(os.environ.get("VISPRIM_FUZZ_EXAMPLES", "150"))
_FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


def _read_or_refuse(path: Path) -> None:
    try:
        trial = read(path, max_gap=10.0)
    except ReadError as exc:
        assert str(exc).startswith(str(path)), exc
        return
    _valid(trial)


@_FUZZ
@given(data=st.data())
def test_flipped_bytes_in_header_and_parameters(
    folder: Path, good: bytes, data: st.DataObject
) -> None:
    n_param = 512 * (2 + good[512 + 2])
    b = bytearray(good)
    for _ in range(data.draw(st.integers(1, 4))):
        b[data.draw(st.integers(0, n_param - 1))] = data.draw(st.integers(0, 255))
    path = folder / "flip.c3d"
    path.write_bytes(bytes(b))
    _read_or_refuse(path)


@_FUZZ
@given(data=st.data())
def test_extreme_16_bit_values_in_header_and_parameters(
    folder: Path, good: bytes, data: st.DataObject
) -> None:
    n_param = 512 * (2 + good[512 + 2])
    b = bytearray(good)
    pos = data.draw(st.integers(0, n_param - 2))
    value = data.draw(st.sampled_from([0, 1, 0x7F, 0x80, 0xFF, 0x7FFF, 0x8000, 0xFFFF]))
    b[pos : pos + 2] = value.to_bytes(2, "little")
    path = folder / "extreme.c3d"
    path.write_bytes(bytes(b))
    _read_or_refuse(path)


@_FUZZ
@given(cut=st.integers(0, 10_000))
def test_truncated_files(folder: Path, good: bytes, cut: int) -> None:
    cut = cut % len(good)
    path = folder / "cut.c3d"
    path.write_bytes(good[:cut])
    data_start = 512 * (1 + 1 + good[512 + 2])
    needed = data_start + 60 * len(PIG_LABELS) * 16
    if cut < needed:
        with pytest.raises((TruncatedFileError, MalformedFileError)):
            read(path)
    else:
        _valid(read(path))


@_FUZZ
@given(data=st.data())
def test_random_data_values(folder: Path, good: bytes, data: st.DataObject) -> None:
    """Any float32 bit pattern in the point data (NaN, inf, huge) reads or is refused."""
    data_start = 512 * (1 + 1 + good[512 + 2])
    b = bytearray(good)
    for _ in range(data.draw(st.integers(1, 20))):
        pos = data.draw(st.integers(data_start, data_start + 60 * len(PIG_LABELS) * 16 - 4))
        b[pos : pos + 4] = data.draw(st.binary(min_size=4, max_size=4))
    path = folder / "values.c3d"
    path.write_bytes(bytes(b))
    _read_or_refuse(path)


def test_not_c3d_and_empty(tmp_path: Path) -> None:
    junk = tmp_path / "junk.c3d"
    junk.write_bytes(b"not a c3d file" * 100)
    with pytest.raises(MalformedFileError, match=r"junk\.c3d: not a readable C3D file"):
        read(junk)
    empty = tmp_path / "empty.c3d"
    empty.write_bytes(b"")
    with pytest.raises(TruncatedFileError, match="empty"):
        read(empty)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_coinciding_markers_are_a_read_error(tmp_path: Path) -> None:
    """Elbow and wrist on the same marker: no forearm direction (was a TrialError), and no
    numpy warning before the error."""
    path = write_arm_c3d(tmp_path / "same.c3d")
    mapping = {"acromion": "RSHO", "elbow": "RELB", "wrist": "RELB"}
    with pytest.raises(ReadError, match=r"same\.c3d"):
        read(path, mapping=mapping)


@pytest.mark.parametrize("rate", [1e-9, 1e9, 0.0, -50.0, float("inf"), float("nan")])
def test_absurd_rates_are_refused(tmp_path: Path, rate: float) -> None:
    path = write_arm_c3d(tmp_path / "rate.c3d", rate=rate)
    with pytest.raises(MalformedFileError, match=r"rate\.c3d: POINT:RATE gives a frame period"):
        read(path)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_signalling_nan_coordinates_read_without_a_numpy_warning(tmp_path: Path) -> None:
    """A float coordinate holding a signalling NaN is a missing value like any NaN; widening
    it to float64 must not raise numpy's 'invalid value encountered in cast'."""
    path = write_arm_c3d(tmp_path / "snan.c3d")
    b = bytearray(path.read_bytes())
    data_start = 512 * (1 + 1 + b[512 + 2])
    b[data_start : data_start + 4] = (0x7F800001).to_bytes(4, "little")  # frame 0, point 0, x
    path.write_bytes(bytes(b))
    _read_or_refuse(path)
