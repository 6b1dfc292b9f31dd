"""Bounded reads and one error contract: declared sizes are checked before anything is
decompressed, devices are refused, and every failure of ``read`` is a ReadError naming the
file (so ``read_many(on_error="warn")`` and the commands skip it)."""

from __future__ import annotations

import io
import subprocess
import sys
import textwrap
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from test_io_fuzz import AMC, ASF
from visprim.io import ReadError, read, read_many
from visprim.io.markers_csv import write_marker_csv

PYTHONPATH = str(Path(__file__).resolve().parents[1] / "python")


def good_npz(path: Path, n: int = 12, rate: float = 120.0) -> Path:
    rng = np.random.default_rng(0)
    np.savez_compressed(
        path,
        poses=rng.normal(scale=0.3, size=(n, 156)),
        trans=np.zeros((n, 3)),
        mocap_framerate=np.array(rate),
    )
    return path


def npy_header(shape: tuple[int, ...], dtype: str = "<f8") -> bytes:
    buf = io.BytesIO()
    header = {"descr": dtype, "fortran_order": False, "shape": shape}
    np.lib.format.write_array_header_1_0(buf, header)
    return np.lib.format.MAGIC_PREFIX + b"\x01\x00" + buf.getvalue()[8:]


def lying_npz(path: Path, shape: tuple[int, ...], zeros: int) -> Path:
    """An archive whose ``poses`` declares ``shape`` and holds ``zeros`` zero bytes (deflated:
    a few MB on disk for GBs declared)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        with zf.open("poses.npy", "w", force_zip64=True) as fh:
            fh.write(npy_header(shape))
            block = bytes(1 << 24)
            left = zeros
            while left > 0:
                fh.write(block[: min(left, len(block))])
                left -= len(block)
        buf = io.BytesIO()
        np.save(buf, np.array(120.0))
        zf.writestr("mocap_framerate.npy", buf.getvalue())
    return path


def read_in_child(path: Path, limit_gb: float = 2.0) -> tuple[str, int]:
    """(outcome, peak RSS in MB, the child's own) of ``read(path)`` in a child with an
    address-space cap."""
    code = textwrap.dedent(
        f"""
        import resource, sys
        resource.setrlimit(resource.RLIMIT_AS, ({int(limit_gb * 2**30)},) * 2)
        from visprim.io import ReadError, read
        try:
            read({str(path)!r})
            out = "read"
        except ReadError as exc:
            out = "ReadError " + str(exc)
        except BaseException as exc:
            out = "other " + type(exc).__name__ + " " + str(exc)
        # VmHWM is this program's own peak: ru_maxrss would also count the parent's
        # memory, which a vfork-started child inherits until its exec.
        status = open("/proc/self/status").read().split("VmHWM:")[1]
        rss = int(status.split()[0]) // 1024
        print(out.replace(chr(10), " ")); print(rss)
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=300,
        env={"PYTHONPATH": PYTHONPATH, "OPENBLAS_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"},
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    outcome, rss = proc.stdout.strip().splitlines()[-2:]
    return outcome, int(rss)


def test_a_deflated_bomb_is_refused_before_it_is_inflated(tmp_path):
    # 500 MiB of zeros: deflated to about 0.5 MB; declares (420,000, 156) float64 frames.
    path = lying_npz(tmp_path / "bomb_poses.npz", (420_000, 156), 420_000 * 156 * 8)
    assert path.stat().st_size < 10 << 20
    outcome, rss = read_in_child(path)
    assert outcome.startswith(f"ReadError {path}:"), outcome
    assert "MiB, more than" in outcome
    assert rss < 1024, f"{rss} MB peak"


def test_a_declared_petabyte_is_a_read_error(tmp_path):
    path = lying_npz(tmp_path / "huge_poses.npz", (2**40, 156), 1024)
    with pytest.raises(ReadError, match="declares") as info:
        read(path)
    assert str(info.value).startswith(str(path))


def test_too_many_frames_are_refused_from_the_header(tmp_path):
    path = lying_npz(tmp_path / "long_poses.npz", (300_000, 66), 300_000 * 66 * 8)
    with pytest.raises(ReadError, match="300,000 frames, more than 250,000"):
        read(path)


@pytest.mark.parametrize("rate", [1e-6, 0.01, 2e5, 1e300])
def test_implausible_amass_rates_are_refused(tmp_path, rate):
    with pytest.raises(ReadError, match="frame rate"):
        read(good_npz(tmp_path / "r_poses.npz", rate=rate))


def damaged(tmp_path: Path) -> dict[str, Path]:
    raw = good_npz(tmp_path / "ok_poses.npz").read_bytes()
    out = {}
    out["truncated"] = tmp_path / "cut_poses.npz"
    out["truncated"].write_bytes(raw[: len(raw) // 2])
    flipped = bytearray(raw)
    flipped[len(raw) // 3] ^= 0xFF
    out["flipped"] = tmp_path / "flip_poses.npz"
    out["flipped"].write_bytes(bytes(flipped))
    encrypted = bytearray(raw)
    i = 0
    while (i := encrypted.find(b"PK\x01\x02", i)) >= 0:  # the central directory's flags
        encrypted[i + 8] |= 1
        i += 4
    out["encrypted"] = tmp_path / "enc_poses.npz"
    out["encrypted"].write_bytes(bytes(encrypted))
    bad_dtype = tmp_path / "obj_poses.npz"
    with zipfile.ZipFile(bad_dtype, "w") as zf:
        zf.writestr("poses.npy", npy_header((4, 156), "|O") + b"\x00" * 64)
    out["object"] = bad_dtype
    short = tmp_path / "short_poses.npz"
    with zipfile.ZipFile(short, "w") as zf:
        zf.writestr("poses.npy", npy_header((4, 156)) + b"\x00" * 64)
    out["short"] = short
    return out


@pytest.mark.parametrize("kind", ["truncated", "flipped", "encrypted", "object", "short"])
def test_damaged_archives_are_read_errors_naming_the_file(tmp_path, kind):
    path = damaged(tmp_path)[kind]
    with pytest.raises(ReadError) as info:
        read(path)
    assert str(info.value).startswith(f"{path}:")


def test_read_many_warn_skips_every_damaged_archive(tmp_path):
    files = damaged(tmp_path)
    good = good_npz(tmp_path / "good_poses.npz")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trials = read_many([good, *files.values()], on_error="warn")
    assert [t.name for t in trials] == ["good_poses"]
    assert len(caught) == len(files)


def amc_folder(tmp_path: Path, first_frame: str) -> Path:
    folder = tmp_path / "amc"
    folder.mkdir()
    (folder / "tiny.asf").write_text(ASF, encoding="utf-8")
    lines = AMC.splitlines()
    k = next(i for i, line in enumerate(lines) if line.strip() == "1")
    lines[k] = first_frame
    (folder / "tiny.amc").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return folder


def test_a_huge_amc_frame_number_is_a_read_error(tmp_path):
    folder = amc_folder(tmp_path, "99999999999999999999999")
    with pytest.raises(ReadError, match="frame number") as info:
        read(folder / "tiny.amc")
    assert str(info.value).startswith(str(folder / "tiny.amc"))


def test_a_device_as_skeleton_is_refused_at_once(tmp_path):
    folder = amc_folder(tmp_path, "1")
    with pytest.raises(ReadError, match="not a regular file"):
        read(folder / "tiny.amc", skeleton="/dev/zero")


def test_an_oversized_skeleton_is_refused(tmp_path):
    folder = amc_folder(tmp_path, "1")
    big = tmp_path / "big.asf"
    with open(big, "wb") as fh:
        fh.truncate(17 << 20)
    with pytest.raises(ReadError, match="larger than a skeleton"):
        read(folder / "tiny.amc", skeleton=big)


def test_learn_skips_an_unreadable_file_and_strict_stops(tmp_path, capsys):
    from visprim.cli import main
    from visprim.datasets import imitation_experiment

    data = tmp_path / "data"
    data.mkdir()
    for i, trial in enumerate(imitation_experiment(2, 6, seed=3)):
        write_marker_csv(data / f"t{i:02d}.csv", trial)
    (data / "zz_poses.npz").write_bytes(b"PK\x03\x04 not really a zip")
    argv = ["-q", "learn", str(data), "--clusters", "4", "--n-init", "1", "--no-resample"]
    assert main([*argv, "--out", str(tmp_path / "m.npz")]) == 0
    err = capsys.readouterr().err
    assert "zz_poses.npz" in err and "internal error" not in err
    assert main([*argv, "--out", str(tmp_path / "s.npz"), "--strict"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "zz_poses.npz" in err[0] and "internal error" not in err[0]
