"""Command-line failures: one line on stderr naming the problem and the fix, no traceback
(unless --debug), exit status 1 for errors, 2 for usage, 130 for Ctrl-C; logging levels."""

from __future__ import annotations

import logging
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import visprim.cli.learn as learn_cli
from visprim.cli import main
from visprim.cli.logs import configured
from visprim.cli.main import COMMANDS, one_line
from visprim.datasets import imitation_experiment

REPO = Path(__file__).resolve().parents[1]
README = str(REPO / "README.md")
SMALL = ["--subjects", "2", "--stimuli", "20", "--clusters", "6", "--n-init", "2"]


def run(argv: list[str]) -> int:
    """main(argv) with argparse's own exits turned into their status."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


def one_error_line(capsys, command: str) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert lines[0].startswith(f"visprim {command}: error: "), lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def model_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("errors") / "model.npz"
    assert main(["-q", "learn", "--out", str(path), *SMALL]) == 0
    return path


# The failures of the hardening issue, each with its exit status and words of the fix.
CASES = [
    (["report", "nope.npz", "--out", "rep"], 1, "visprim learn --out"),
    (["classify", "nope.npz"], 1, "visprim learn --out"),
    (["report", README, "--out", "rep"], 1, "not a visprim model"),
    (["learn", "--out", README + "/m.npz"], 2, "is a file, not a folder"),
    (["learn", "--out", "."], 2, "give a model file name such as model.npz"),
    (["learn", "--out", "m.npz", "--subjects", "0"], 2, "an integer >= 1"),
    (["learn", README, "--out", "m.npz"], 1, "is not a recording"),
    (["learn", "--out", "m.npz", "--resample", "1e-9"], 2, "frame period in seconds between"),
    (["learn", "--out", "m.pkl"], 2, "name it m.npz"),
    (["learn", "--out", "m.npz", "--cutoff", "1.5"], 2, "between 0 and 1"),
    (["learn", "--out", "m.npz", "--components", "700", "--samples", "100"], 2, "--components"),
    (["learn", "--out", "m.npz", "--mapping", "{bad json"], 2, "--mapping"),
    (["learn", ".", "--out", "m.npz", "--arm", "middle"], 2, "--arm"),
    (["learn", ".", "--generated", "--out", "m.npz"], 2, "not both"),
    (["classify", "MODEL", "--out", "x.txt"], 2, "name it x.csv"),
    (["simulate", "MODEL", "--primitive", "0", "--out", "x.mp4"], 2, ".gif or .png"),
    (["simulate", "MODEL", "--primitive", "999", "--out", "x.gif"], 2, "out of range"),
    (["simulate", "MODEL", "--out", "x.gif"], 2, "--primitive K or --movement"),
    (["generate", "--out", README], 2, "is a file"),
    (["report", "MODEL", "--out", "report.html"], 2, "give a folder name such as report"),
    (["report", "MODEL", "--out", "rep", "--trial", "nope"], 1, "--trial nope: no trial"),
    (["report", "MODEL", "--out", str(REPO)], 2, "folder of other files"),
    (["nonsense"], 2, "invalid choice"),
]


@pytest.mark.parametrize(("argv", "status", "fix"), CASES, ids=[" ".join(c[0])[:50] for c in CASES])
def test_failures_are_one_line(argv, status, fix, model_file, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    argv = [str(model_file) if a == "MODEL" else a for a in argv]
    command = argv[0] if argv[0] in COMMANDS else ""
    assert run(argv) == status
    line = one_error_line(capsys, command) if command else capsys.readouterr().err
    assert fix in line
    assert not (tmp_path / "m.npz").exists() and not (tmp_path / "rep").exists()


def test_debug_shows_the_traceback(tmp_path, capsys):
    assert run(["report", "nope.npz", "--out", str(tmp_path / "r"), "--debug"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err
    assert err.strip().splitlines()[-1].startswith("visprim report: error: model file nope.npz")
    # --debug (like -v and --quiet) is accepted before the command too.
    assert run(["--debug", "report", "nope.npz", "--out", str(tmp_path / "r")]) == 1
    assert "Traceback" in capsys.readouterr().err


def test_ctrl_c_exits_130_and_writes_nothing(tmp_path, monkeypatch, capsys):
    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(learn_cli.common, "trials_and_source", lambda *a, **k: interrupted(a))
    assert run(["learn", "--out", str(tmp_path / "m.npz"), *SMALL]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["visprim learn: interrupted: stopped by Ctrl-C; outputs left as before"]
    assert not (tmp_path / "m.npz").exists()


def test_unexpected_errors_are_one_line_and_name_debug(tmp_path, monkeypatch, capsys):
    def broken(*args, **kwargs):
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(learn_cli.common, "trials_and_source", broken)
    assert run(["learn", "--out", str(tmp_path / "m.npz"), *SMALL]) == 1
    line = one_error_line(capsys, "learn")
    assert "internal error RuntimeError: boom second line" in line and "--debug" in line


def test_library_argument_names_become_options():
    assert one_line(ValueError("x.amc: pass skeleton=PATH")) == "x.amc: pass --skeleton PATH"
    assert "--up-axis '+z'" in one_line(ValueError("pass up_axis='+z' (or '+y')"))
    assert one_line(ValueError("a\n  b")) == "a b"


def test_process_exit_status_and_stderr(tmp_path):
    """The installed entry point's behaviour, in a separate process."""
    proc = subprocess.run(
        [sys.executable, "-m", "visprim.cli", "report", "nope.npz", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 1
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stdout == ""


# ---------------------------------------------------------------------------- logging


def test_verbose_shows_debug_messages(tmp_path, capsys):
    assert run(["learn", "--out", str(tmp_path / "a.npz"), *SMALL]) == 0
    assert capsys.readouterr().err == ""
    assert run(["-v", "learn", "--out", str(tmp_path / "b.npz"), *SMALL]) == 0
    assert "debug: visprim.cli.learn: learning from 40 trials" in capsys.readouterr().err


def test_logging_levels_and_warnings_as_one_line(capsys):
    log = logging.getLogger("visprim.some.module")
    with configured(verbose=1):
        log.debug("detail")
        warnings.warn("careful\nnow", UserWarning, stacklevel=1)
    err = capsys.readouterr().err.splitlines()
    assert err == ["debug: visprim.some.module: detail", "warning: careful now"]
    with configured(quiet=True):
        log.info("hidden")
        log.warning("shown")
    assert capsys.readouterr().err.splitlines() == ["warning: shown"]
    # Outside the command line visprim configures nothing.
    assert logging.getLogger("visprim").handlers == []


def test_library_modules_do_not_print():
    """Outside visprim/cli/, messages go through logging (print is for the command line)."""
    import ast

    offenders = []
    for path in sorted((REPO / "python" / "visprim").rglob("*.py")):
        if "cli" in path.relative_to(REPO / "python" / "visprim").parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "print":
                offenders.append(f"{path.name}:{node.lineno}")
    assert offenders == []


# ---------------------------------------------------------------------------- reader options


def test_reader_options_reach_read_many(tmp_path, monkeypatch, capsys):
    import visprim.io

    seen = {}
    trials = imitation_experiment(2, 20, 0)

    def fake_read_many(paths, **kwargs):
        seen.update(kwargs, paths=paths)
        return trials

    monkeypatch.setattr(visprim.io, "read_many", fake_read_many)
    mapping = tmp_path / "names.json"
    mapping.write_text('{"shoulder": "RShoulder", "elbow": ["REL", "REM"]}', encoding="utf-8")
    argv = ["learn", str(tmp_path), "--out", str(tmp_path / "m.npz"), "--clusters", "6"]
    argv += ["--arm", "LEFT", "--skeleton", "s.asf", "--rate", "60", "--preset", "cmu"]
    argv += ["--mapping", str(mapping), "--up-axis", "+z", "--on-gap", "raise", "--strict"]
    assert run(argv) == 0
    assert seen == {
        "paths": [str(tmp_path)],
        "arm": "left",
        "skeleton": "s.asf",
        "rate": 60.0,
        "preset": "cmu",
        "mapping": {"shoulder": "RShoulder", "elbow": ["REL", "REM"]},
        "up_axis": "+z",
        "on_gap": "raise",
        "on_error": "raise",
        "resample": 0.034,
    }
    # Defaults: unreadable files skipped with a warning; options recorded for `report`.
    from visprim import PrimitiveModel

    assert PrimitiveModel.load(tmp_path / "m.npz").provenance_.reader_options["rate"] == 60.0
    seen.clear()
    assert run(["learn", str(tmp_path), "--out", str(tmp_path / "n.npz"), "--clusters", "6"]) == 0
    assert seen["on_error"] == "warn" and seen["arm"] == "right" and "mapping" not in seen


def test_short_trials_kept_left_out_or_refused(tmp_path, monkeypatch, capsys):
    import dataclasses

    import visprim.io

    trials = imitation_experiment(2, 20, 0)
    t = trials[0]
    short = dataclasses.replace(t, times=t.times[:20], markers=t.markers[:20], truth=None)
    short = dataclasses.replace(short, joints=None, body_frame=None, name="tiny")
    monkeypatch.setattr(visprim.io, "read_many", lambda paths, **kw: [short, *trials[1:]])

    def learn(name: str, *options: str) -> int:
        out = str(tmp_path / name)
        return run(["learn", str(tmp_path), "--out", out, "--clusters", "6", *options])

    # Default: kept, filtered with less padding (the model says so in its summary).
    assert learn("a.npz") == 0
    assert "1 trial(s) shorter than the filter padding" in capsys.readouterr().out
    assert learn("b.npz", "--short", "drop") == 0
    captured = capsys.readouterr()
    assert "left out 1 trial(s) with no more frames than the filter padding (33): tiny (20 " in (
        captured.err
    )
    assert captured.out.startswith("39 trials -> ")
    assert learn("c.npz", "--short", "error") == 1
    line = one_error_line(capsys, "learn")
    assert "tiny (20 frames)" in line and "--short reduce" in line
    assert not (tmp_path / "c.npz").exists()


def test_learn_real_recordings_as_given(shared_data, tmp_path, capsys):
    """A folder of real recordings, one of them shorter than the filter's padding, learns
    with the defaults (the whole ../shared/data as well: see the README)."""
    folder = shared_data / "bandai_namco_ds1_extra"
    out = tmp_path / "m.npz"
    assert run(["learn", str(folder), "--out", str(out), "--clusters", "5"]) == 0
    captured = capsys.readouterr()
    assert "1 trial(s) shorter than the filter padding (padded less)" in captured.out
    assert f"model written to {out}" in captured.out
    assert np.isfinite(np.load(out)["cluster_centers"]).all()


def test_summary_names_the_trials_without_a_segment() -> None:
    from types import SimpleNamespace

    from visprim.cli import common

    model = SimpleNamespace(
        seg2_threshold_=None,
        n_trials_without_segments_=2,
        n_short_trials_=0,
        segment_trial_=[0, 0, 2, 2],
        trial_names_=["walk", "still", "wave", "idle"],
        features="directions",
        inertia_=1.0,
        segmentation="seg2",
        n_training_segments_=4,
        n_components=3,
        dim=600,
        n_primitives=2,
    )
    assert "2 trial(s) without a segment (still, idle)" in common.summary(model, 4)


def test_python_dash_m_visprim_runs_the_cli():
    """``python -m visprim`` is the same command line as ``visprim``."""
    import subprocess
    import sys

    import visprim

    done = subprocess.run(
        [sys.executable, "-m", "visprim", "--version"], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"visprim {visprim.__version__}"
