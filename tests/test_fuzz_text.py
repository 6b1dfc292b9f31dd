"""Hypothesis over raw bytes of the text formats, and over folders of mixed files.

``test_io_fuzz.py`` breaks numbers and keywords of valid files; here any byte (Latin-1,
control characters, invalid UTF-8, NUL) lands anywhere, and ``read_many(..., on_error="warn")``
gets folders of random files: the only exception a reader may raise is
:class:`~visprim.io.ReadError`, and in warn mode nothing escapes.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_io_fuzz import AMC, ASF, BVH
from visprim.io import ReadError, read, read_many
from visprim.io.markers_csv import write_marker_csv
from visprim.trial import Trial

#: Examples per property (raise it for a longer run: VISPRIM_FUZZ_EXAMPLES=2000).
EXAMPLES = int(os.environ.get("VISPRIM_FUZZ_EXAMPLES", "100"))
_FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("textfuzz")


@pytest.fixture(scope="module")
def csv_bytes(folder: Path) -> bytes:
    t = np.arange(6) * 0.034
    markers = np.zeros((6, 4, 3)) + np.arange(12).reshape(4, 3) * 0.01 + t[:, None, None]
    path = write_marker_csv(folder / "ok.csv", Trial(times=t, markers=markers), truth=False)
    return path.read_bytes()


def _read_or_refuse(path: Path, *also: Path) -> str:
    """Read ``path``; a refusal must name it (or ``also``: the AMC's skeleton)."""
    try:
        trial = read(path)
    except ReadError as exc:
        assert any(str(exc).startswith(str(p)) for p in (path, *also)), exc
        return "refused"
    assert np.isfinite(trial.markers).all() and trial.markers.shape == (trial.n_frames, 4, 3)
    return "read"


def _splice(original: bytes, data: st.DataObject) -> bytes:
    b = bytearray(original)
    for _ in range(data.draw(st.integers(1, 3))):
        pos = data.draw(st.integers(0, len(b)))
        how = data.draw(st.sampled_from(["insert", "replace", "delete"]))
        junk = data.draw(st.binary(min_size=1, max_size=6))
        if how == "insert":
            b[pos:pos] = junk
        elif how == "replace":
            b[pos : pos + len(junk)] = junk
        else:
            del b[pos : pos + len(junk)]
    return bytes(b)


@_FUZZ
@given(data=st.data())
def test_bvh_with_random_bytes(folder: Path, data: st.DataObject) -> None:
    path = folder / "b.bvh"
    path.write_bytes(_splice(BVH.encode(), data))
    _read_or_refuse(path)


@_FUZZ
@given(data=st.data(), which=st.sampled_from(["asf", "amc"]))
def test_asf_amc_with_random_bytes(folder: Path, data: st.DataObject, which: str) -> None:
    asf, amc = ASF.encode(), AMC.encode()
    if which == "asf":
        asf = _splice(asf, data)
    else:
        amc = _splice(amc, data)
    (folder / "t.asf").write_bytes(asf)
    (folder / "t.amc").write_bytes(amc)
    _read_or_refuse(folder / "t.amc", folder / "t.asf")


@_FUZZ
@given(data=st.data())
def test_csv_with_random_bytes(folder: Path, csv_bytes: bytes, data: st.DataObject) -> None:
    path = folder / "c.csv"
    path.write_bytes(_splice(csv_bytes, data))
    _read_or_refuse(path)


@_FUZZ
@given(byte=st.integers(0x80, 0xFF), where=st.sampled_from(["name", "comment"]))
def test_any_8_bit_byte_in_names_and_comments_reads(folder: Path, byte: int, where: str) -> None:
    ch = bytes([byte])
    if where == "name":
        bvh = BVH.encode().replace(b"ROOT Hips", b"ROOT Hips" + ch)
        asf = ASF.encode().replace(b":name tiny", b":name tiny" + ch)
    else:
        bvh = BVH.encode()  # BVH has no comment syntax: names only
        asf = ASF.encode().replace(b":units", b"# r\xe9sum\xe9 " + ch + b"\n:units")
    (folder / "n.bvh").write_bytes(bvh)
    assert _read_or_refuse(folder / "n.bvh") == "read"
    (folder / "n.asf").write_bytes(asf)
    (folder / "n.amc").write_bytes(b"# " + ch + b"\n" + AMC.encode())
    assert _read_or_refuse(folder / "n.amc") == "read"


_NAMES = st.sampled_from(["a", "b", "t", "README", "x.tar", "ok"])
_EXTS = st.sampled_from([".bvh", ".amc", ".asf", ".c3d", ".csv", ".md", ".txt", ""])


@settings(
    max_examples=max(EXAMPLES // 3, 10),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    files=st.lists(
        st.tuples(_NAMES, _EXTS, st.sampled_from(["bvh", "asf", "amc", "junk", "empty"])),
        min_size=1,
        max_size=6,
    ),
    junk=st.binary(max_size=64),
)
def test_read_many_warn_lets_nothing_escape(
    tmp_path_factory: pytest.TempPathFactory, files: list[tuple[str, str, str]], junk: bytes
) -> None:
    root = tmp_path_factory.mktemp("many")
    content = {"bvh": BVH.encode(), "asf": ASF.encode(), "amc": AMC.encode(), "junk": junk}
    paths = []
    for name, ext, kind in files:
        path = root / f"{name}{ext}"
        path.write_bytes(content.get(kind, b""))
        paths.append(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for sources in (root, paths, str(root / "**" / "*")):
            try:
                trials = read_many(sources, on_error="warn")
            except ReadError as exc:
                # Only the listing itself may fail: no recording at all in a folder/pattern.
                assert "no recordings" in str(exc) or "matches no recording" in str(exc)
                continue
            assert all(isinstance(t, Trial) for t in trials)
