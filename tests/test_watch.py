"""visprim watch: a shared recording replayed through the command (its JSON Lines against the
online pipeline pushed directly), Ctrl-C and SIGTERM, the LSL loopback, Adonis live."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import visprim
from visprim.classify import DTWClassifier
from visprim.model import PrimitiveModel
from visprim.online import OnlinePipeline, SegmentClosed, event_to_dict
from visprim.online.sources import LSL_EXTRA, RecordingSource, lsl_layout
from visprim.trial import Trial

TRAIN = [
    "HDM_bd_depositFloorR_001_120.amc",
    "HDM_bd_grabHighR_001_120.amc",
    "HDM_bd_throwBasketball_001_120.amc",
    "HDM_bk_depositFloorR_007_120.amc",
    "HDM_bk_grabHighR_005_120.amc",
    "HDM_bk_throwBasketball_004_120.amc",
]
#: 6.7 s, two segments: long enough to interrupt on its own clock.
LONG = "HDM_bk_lieDownFloor_005_120.amc"
SHORT = "HDM_mm_grabHighR_017_120.amc"
PYTHONPATH = str(Path(visprim.__file__).resolve().parents[1])


def _read(path: Path) -> Trial:
    from visprim.io import read

    return read(path, "both", resample=0.034)


@pytest.fixture(scope="module")
def folder(shared_data: Path) -> Path:
    f = shared_data / "hdm05_cut_amc"
    missing = [n for n in [*TRAIN, LONG, SHORT] if not (f / n).exists()]
    if missing:
        pytest.skip(f"HDM05 recordings missing: {missing[:2]}")
    return f


@pytest.fixture(scope="module")
def model_file(folder: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    model = PrimitiveModel(n_components=8, n_clusters=8, n_init=2)
    model.fit([_read(folder / n) for n in TRAIN])
    path = tmp_path_factory.mktemp("watch") / "model.npz"
    model.save(path)
    return path, PrimitiveModel.load(path)


def _watch(*args: str, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "visprim.cli", "watch", *args],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": PYTHONPATH},
        **kwargs,
    )


def _lines(path: Path) -> list[dict[str, Any]]:
    text = path.read_text(encoding="utf-8")
    assert text == "" or text.endswith("\n")
    return [json.loads(line) for line in text.splitlines()]


def _same(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> None:
    assert [e["event"] for e in a] == [e["event"] for e in b]
    for x, y in zip(a, b, strict=True):
        assert x.keys() == y.keys()
        for k in x:
            if isinstance(x[k], float) and isinstance(y[k], float):
                assert x[k] == pytest.approx(y[k], rel=1e-9, abs=1e-6), k
            else:
                assert x[k] == y[k], k


def _direct(model: Any, trial: Trial, classifier: Any = None, chunk: int = 1) -> list[dict]:
    pipe = OnlinePipeline(model, classifier)
    return [event_to_dict(e) for e in pipe.replay(trial, chunk=chunk)]


def test_watch_fast_writes_the_events_of_the_pipeline_pushed_directly(
    folder: Path, model_file: tuple[Path, Any], tmp_path: Path
) -> None:
    path, model = model_file
    refs = [folder / n for n in TRAIN[:3]]
    out = tmp_path / "events.jsonl"
    r = _watch(
        str(folder / SHORT),
        "--model",
        str(path),
        "--fast",
        "--chunk",
        "4",
        "--out",
        str(out),
        *[a for p in refs for a in ("--classifier", str(p))],
    )
    assert r.returncode == 0, r.stderr
    got = _lines(out)
    # The classifier fitted here, on the same files with their labels.tsv labels.
    clf = DTWClassifier().fit([_read(p) for p in refs], [p.name.split("_")[2] for p in refs])
    expected = _direct(model, _read(folder / SHORT), clf, chunk=4)
    assert {e["event"] for e in expected} == {"segment", "class", "movement_end"}
    _same(got, expected)
    emitted = [e["emitted"] for e in got]
    assert emitted == sorted(emitted)
    assert len(r.stdout.splitlines()) == len(got)  # one printed line per event
    assert f"{len(got)} events written to {out}" in r.stderr
    # A model of the default SEG-2 rule says how late its segments come, and what to use.
    assert model.seg2_boundary == "slowest" and "--seg2-boundary first_stop" in r.stderr


def test_watch_checks_its_output_and_source_first(
    folder: Path, model_file: tuple[Path, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from visprim.cli.main import main

    path, _ = model_file
    out = tmp_path / "events.jsonl"
    out.write_text("kept\n", encoding="utf-8")
    rec = str(folder / SHORT)
    assert main(["watch", rec, "--model", str(path), "--fast", "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err and out.read_text() == "kept\n"
    assert main(["watch", rec, "--model", str(path), "--out", str(tmp_path / "e.json")]) == 2
    assert ".jsonl" in capsys.readouterr().err
    assert main(["watch", "0", "--model", str(path)]) == 2
    assert "cameras are not supported" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("sig", "status", "after"), [(signal.SIGINT, 130, 3.6), (signal.SIGTERM, 143, 0.3)]
)
def test_a_signal_ends_the_stream_and_keeps_the_events_so_far(
    folder: Path,
    model_file: tuple[Path, Any],
    tmp_path: Path,
    sig: signal.Signals,
    status: int,
    after: float,
) -> None:
    path, model = model_file
    out = tmp_path / "events.jsonl"
    proc = subprocess.Popen(
        [sys.executable, "-m", "visprim.cli", "watch", str(folder / LONG), "--model", str(path)]
        + ["--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": PYTHONPATH},
    )
    assert proc.stderr is not None
    line = proc.stderr.readline()  # the replay starts on its own clock
    assert line.startswith("watching"), line
    time.sleep(after)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == status, stderr
    assert "interrupted" in stderr and "events written" in stderr
    got = _lines(out)
    full = _direct(model, _read(folder / LONG))
    assert got and got[-1]["event"] == "movement_end"  # the open movement ended
    # Events before the interruption are the full replay's; the stream ended early.
    before = [e for e in got if e["emitted"] < got[-1]["emitted"]]
    _same(before, full[: len(before)])
    assert got[-1]["emitted"] < full[-1]["emitted"]
    if sig == signal.SIGINT:
        assert before, "the first segment closes at 3.0 s of stream time"
    assert not list(tmp_path.glob(".*visprim-tmp*"))


def test_recording_source_gives_each_chunk_when_its_last_frame_is_due() -> None:
    now = [100.0]
    waits: list[float] = []

    def sleep(s: float) -> None:
        waits.append(s)
        now[0] += s

    t = Trial(
        times=np.arange(7) * 0.5,
        markers=np.zeros((7, 4, 3)),
        arms=("right",),
        name="x",
    )
    src = RecordingSource(t, chunk=3, clock=lambda: now[0], sleep=sleep)
    sizes = [len(c) for c in src]
    assert sizes == [3, 3, 1]
    assert waits == pytest.approx([1.0, 1.5, 0.5])
    fast = RecordingSource(t, chunk=3, fast=True, clock=lambda: now[0], sleep=sleep)
    assert sum(len(c) for c in fast) == 7 and len(waits) == 3


def test_lsl_layouts_and_the_missing_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    assert lsl_layout(24, 2).n_channels == 24 and not lsl_layout(24, 2).joints
    lay = lsl_layout(42 + 9, 2)
    assert lay.joints and lay.body_frame
    x = np.arange(2 * 51, dtype=float).reshape(2, 51)
    f = lay.frames(x, np.array([0.0, 0.1]))
    assert f.markers.shape == (2, 8, 3) and f.joints is not None and f.joints.shape == (2, 6, 3)
    assert f.body_frame is not None and f.body_frame[1, 2, 2] == x[1, 50]
    with pytest.raises(ValueError, match="needs 24 channels"):
        lsl_layout(25, 2)
    from visprim.online import sources

    monkeypatch.setitem(sys.modules, "mne_lsl", None)
    monkeypatch.setitem(sys.modules, "mne_lsl.lsl", None)
    with pytest.raises(ImportError, match=r"visprim\[lsl\]") as info:
        sources.LslSource("x", 1).open()
    assert str(info.value) == LSL_EXTRA


def test_an_lsl_sample_out_of_order_is_left_out_and_counted() -> None:
    """A repeated timestamp and one that steps back: those samples are left out and
    counted, and the stream goes on (a stub inlet stands in for liblsl)."""
    from visprim.online.sources import LslSource

    x = np.arange(6, dtype=float)[:, None] * np.ones((6, 12))
    pulls = [(x[:3], [10.0, 10.1, 10.1]), (x[3:5], [10.05, 10.2]), (x[5:], [10.15])]

    class Inlet:
        closed = False

        def pull_chunk(self, timeout: float, max_samples: int) -> tuple[Any, list[float]]:
            return pulls.pop(0) if pulls else (np.zeros((0, 12)), [])

        def close_stream(self) -> None:
            self.closed = True

    src = LslSource("stub", 1, idle=0.0)
    inlet = Inlet()
    src.layout, src._inlet = lsl_layout(12, 1), inlet
    frames = list(src)
    times = np.concatenate([f.times for f in frames])
    np.testing.assert_allclose(times, [0.0, 0.1, 0.2])
    kept = np.concatenate([f.markers.reshape(len(f), -1)[:, 0] for f in frames])
    np.testing.assert_array_equal(kept, [0.0, 1.0, 4.0])
    assert src.out_of_order == 3 and inlet.closed


def test_lsl_loopback(folder: Path, model_file: tuple[Path, Any], tmp_path: Path) -> None:
    lsl = pytest.importorskip("mne_lsl.lsl", reason="the extra visprim[lsl] is not installed")
    from visprim.online.sources import publish

    try:
        lsl.library_version()
    except Exception as exc:  # pragma: no cover - a broken liblsl
        pytest.skip(f"liblsl cannot run here: {exc}")
    path, model = model_file
    trial = _read(folder / LONG)
    name = f"visprim-test-{os.getpid()}"
    probe = lsl.StreamOutlet(lsl.StreamInfo(name + "-probe", "x", 1, 0.0, "float64", "p"))
    if not lsl.resolve_streams(timeout=2.0, name=name + "-probe"):
        pytest.skip("LSL streams cannot be resolved on this machine (no multicast on loopback?)")
    del probe
    pushed: list[int] = []
    thread = threading.Thread(
        target=lambda: pushed.append(publish(trial, name, fast=True, wait_for_consumer=30.0)),
        daemon=True,
    )
    thread.start()
    out = tmp_path / "lsl.jsonl"
    r = _watch(f"lsl:{name}", "--model", str(path), "--idle", "1.0", "--out", str(out))
    thread.join(timeout=30)
    assert r.returncode == 0, r.stderr
    assert pushed == [trial.n_frames]
    assert f"{trial.n_frames} frames" in r.stderr
    got = _lines(out)
    # Times on the stream: seconds since its first sample (the recording starts at 0).
    _same(got, _direct(model, trial))


def test_adonis_plays_every_segment_and_keeps_up(
    folder: Path, model_file: tuple[Path, Any]
) -> None:
    from visprim.online.adonis import LiveAdonis

    _, model = model_file
    trial = _read(folder / LONG)
    pipe = OnlinePipeline(model)
    adonis = LiveAdonis(model)
    segments = 0
    for chunk in RecordingSource(trial, chunk=2, fast=True):
        adonis.observe(chunk)
        for ev in pipe.push(chunk):
            if isinstance(ev, SegmentClosed):
                adonis.add(ev)
                segments += 1
        adonis.advance(float(chunk.times[-1]))
    for ev in pipe.flush():
        if isinstance(ev, SegmentClosed):
            adonis.add(ev)
            segments += 1
    adonis.drain()
    rep = adonis.report()
    assert segments == rep.segments >= 2
    assert rep.simulated >= trial.duration - adonis.dt
    assert np.isfinite(rep.real_time_factor) and rep.wall > 0
    assert rep.tracking_rms_deg < 5.0
    # Adonis ends at the last rebuilt posture (its set point), within a few degrees.
    from visprim.sim.sequencer import positions_to_angles

    final = positions_to_angles(adonis.skel, adonis.skel.getPositions(), 2)[0]
    assert np.degrees(np.abs(final[[1, 3, 5, 7]] - adonis.hold[[1, 3, 5, 7]])).max() < 5.0


def test_watch_without_the_lsl_extra_says_so_in_one_line(
    model_file: tuple[Path, Any], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    from visprim.cli.main import main

    monkeypatch.setitem(sys.modules, "mne_lsl", None)
    monkeypatch.setitem(sys.modules, "mne_lsl.lsl", None)
    assert main(["watch", "lsl:nobody", "--model", str(model_file[0])]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "visprim[lsl]" in err[0] and "lsl:nobody" in err[0]
