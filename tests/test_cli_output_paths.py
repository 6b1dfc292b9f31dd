"""Every output path is checked before any work (``learn --stream``/``--dask``,
``imitate --video``), one run at a time per output, and SIGTERM cleans up."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from visprim import PrimitiveModel
from visprim.cli import main, outputs
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv

SMALL = ["--subjects", "2", "--stimuli", "20", "--clusters", "6", "--n-init", "2"]
PYTHONPATH = str(Path(__file__).resolve().parents[1] / "python")


def run(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


@pytest.fixture
def no_fit(monkeypatch):
    """Fitting is work: a check that comes after it fails the test."""

    def fit(self, *args, **kwargs):
        raise AssertionError("the fit started before the output was checked")

    monkeypatch.setattr(PrimitiveModel, "fit", fit)


@pytest.mark.parametrize("how", [["--stream"], ["--dask"]])
def test_lazy_learn_checks_out_before_fitting(how, tmp_path, capsys, no_fit):
    keep = tmp_path / "keep.npz"
    keep.write_bytes(b"keep me")
    assert run(["learn", *how, "--out", str(keep), *SMALL]) == 2
    assert keep.read_bytes() == b"keep me"
    assert "pass --force" in capsys.readouterr().err
    assert run(["learn", *how, "--out", str(tmp_path / "notes.txt"), *SMALL]) == 2
    assert "not .txt" in capsys.readouterr().err
    assert run(["learn", *how, "--out", str(keep / "m.npz"), *SMALL]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err
    assert not (tmp_path / "notes.txt").exists()


@pytest.fixture(scope="module")
def imitate_files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("video_paths")
    trials = imitation_experiment(2, 4, seed=4)
    model = PrimitiveModel(n_clusters=5, n_init=2).fit(trials[:-1])
    model.save(tmp / "model.npz")
    return tmp / "model.npz", write_marker_csv(tmp / "take.csv", trials[-1])


@pytest.mark.parametrize("where", ["other/victim.gif", "../victim.gif", "ABS"])
def test_imitate_video_is_a_name_inside_out(where, imitate_files, tmp_path, capsys):
    model, rec = imitate_files
    victim = tmp_path / ("other" if where.startswith("other") else "") / "victim.gif"
    victim.parent.mkdir(exist_ok=True)
    victim.write_bytes(b"not yours")
    victim.chmod(0o644)
    video = str(victim) if where == "ABS" else where
    out = tmp_path / "o"
    argv = ["imitate", str(model), str(rec), "--out", str(out), "--video", video, "--size", "64"]
    assert run(argv) == 2
    assert "give a file name, written inside --out" in capsys.readouterr().err
    assert victim.read_bytes() == b"not yours" and victim.stat().st_mode & 0o777 == 0o644
    assert not out.exists()


def test_a_second_run_to_the_same_out_stops(tmp_path, capsys):
    out = tmp_path / "m.npz"
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        lock = outputs._lock_path(out)
        lock.write_text(f"{holder.pid}\n", encoding="ascii")
        assert run(["-q", "learn", "--out", str(out), *SMALL]) == 2
        err = capsys.readouterr().err
        assert f"being written by another run (process {holder.pid})" in err
        assert not out.exists() and lock.read_text(encoding="ascii") == f"{holder.pid}\n"
    finally:
        holder.kill()
        holder.wait()
    # The holder is gone: its lock is stale, taken over, and released at the end.
    assert run(["-q", "learn", "--out", str(out), *SMALL]) == 0
    assert out.is_file() and not lock.exists()


def test_claim_is_exclusive_between_processes(tmp_path):
    out = tmp_path / "report"
    code = (
        "import sys, time; from visprim.cli import outputs; "
        f"outputs.claim({str(out)!r}); print('held', flush=True); time.sleep(60)"
    )
    env = {**os.environ, "PYTHONPATH": PYTHONPATH}
    child = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, env=env)
    try:
        assert child.stdout is not None and child.stdout.readline() == b"held\n"
        with pytest.raises(outputs.UsageError, match="being written by another run"):
            outputs.claim(out)
    finally:
        child.kill()
        child.wait()
    outputs.claim(out)  # the child was killed: its lock is stale
    outputs.release_claims()
    assert not outputs._lock_path(out).exists()


def test_sigterm_during_stream_learn_leaves_no_spill_folder(tmp_path):
    spill = tmp_path / "tmp"
    spill.mkdir()
    env = {**os.environ, "PYTHONPATH": PYTHONPATH, "TMPDIR": str(spill)}
    argv = ["learn", "--stream", "--out", str(tmp_path / "m.npz"), "--subjects", "11"]
    argv += ["--stimuli", "200", "--clusters", "6", "--n-init", "1"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "visprim.cli", "-q", *argv],
        env=env,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not list(spill.glob("visprim-fit-*")):
        assert proc.poll() is None and time.monotonic() < deadline, "no spill folder appeared"
        time.sleep(0.05)
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "stopped by SIGTERM" in err and "Traceback" not in err
    assert list(spill.glob("visprim-fit-*")) == []
    assert list(spill.glob("visprim-out-*.lock")) == []
    assert not (tmp_path / "m.npz").exists()
