"""Command-line outputs: never overwritten silently (--force), checked extensions, and
atomic writes (an interrupted run leaves the previous complete output or none)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import visprim.report
from PIL import Image
from visprim.cli import main, outputs
from visprim.sim.trajectories import minimum_jerk

SMALL = ["--subjects", "2", "--stimuli", "20", "--clusters", "6", "--n-init", "2"]


def run(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


@pytest.fixture(scope="module")
def model_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("outputs") / "model.npz"
    assert main(["-q", "learn", "--out", str(path), *SMALL]) == 0
    return path


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def fake_report(tag: str, fail_after: int | None = None):
    """A stand-in for visprim.report.write_report writing three files (and index.html last),
    optionally interrupted (Ctrl-C) after ``fail_after`` files, half-way through one."""

    def write(model, out_dir, trials=None, **kwargs):
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        files = []
        for i, name in enumerate(["eigenvalues.png", "table1.csv", "index.html"]):
            if fail_after is not None and i == fail_after:
                (out / name).write_bytes(b"trunc")
                raise KeyboardInterrupt
            (out / name).write_text(f"{tag} {name}\n" * 100, encoding="utf-8")
            files.append(out / name)
        return visprim.report.Report(out_dir=out, index=out / "index.html", files=files)

    return write


def test_report_is_replaced_only_with_force_and_atomically(
    model_file, tmp_path, monkeypatch, capsys
):
    out = tmp_path / "rep"
    monkeypatch.setattr(visprim.report, "write_report", fake_report("first"))
    assert run(["report", str(model_file), "--out", str(out)]) == 0
    assert f"report written to {out / 'index.html'} (3 files)" in capsys.readouterr().out
    first = snapshot(out)
    assert first["index.html"].startswith(b"first") and outputs.MARKER in first

    # An existing report is not replaced without --force.
    monkeypatch.setattr(visprim.report, "write_report", fake_report("second"))
    assert run(["report", str(model_file), "--out", str(out)]) == 2
    assert "pass --force to replace it" in capsys.readouterr().err
    assert snapshot(out) == first

    # Interrupted at each file: the previous complete report stays, no temporary is left.
    for k in range(3):
        monkeypatch.setattr(visprim.report, "write_report", fake_report("second", k))
        assert run(["report", str(model_file), "--out", str(out), "--force"]) == 130
        assert snapshot(out) == first
        assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]

    monkeypatch.setattr(visprim.report, "write_report", fake_report("second"))
    assert run(["report", str(model_file), "--out", str(out), "--force"]) == 0
    second = snapshot(out)
    assert second["index.html"].startswith(b"second") and set(second) == set(first)


def test_interrupted_first_report_leaves_none(model_file, tmp_path, monkeypatch):
    monkeypatch.setattr(visprim.report, "write_report", fake_report("x", 2))
    assert run(["report", str(model_file), "--out", str(tmp_path / "rep")]) == 130
    assert list(tmp_path.iterdir()) == []


def test_report_refuses_to_delete_its_own_input(model_file, tmp_path, capsys, monkeypatch):
    out = model_file.parent
    (out / "index.html").write_text("an old report", encoding="utf-8")
    monkeypatch.setattr(visprim.report, "write_report", fake_report("x"))
    try:
        assert run(["report", str(model_file), "--out", str(out), "--force"]) == 2
        assert "holds the input" in capsys.readouterr().err
        assert model_file.is_file()
    finally:
        (out / "index.html").unlink()


def test_stale_temporaries_of_killed_runs_are_removed(tmp_path):
    target = tmp_path / "rep"
    dead = tmp_path / ".rep.visprim-tmp-999999999-deadbeef"  # no such process
    dead.mkdir()
    (dead / "index.html").write_text("half", encoding="utf-8")
    mine_elsewhere = tmp_path / ".other.visprim-tmp-999999999-deadbeef"
    mine_elsewhere.mkdir()
    with outputs.atomic_folder(target, "test") as tmp:
        (tmp / "a.txt").write_text("a", encoding="utf-8")
    assert not dead.exists() and mine_elsewhere.exists()
    assert (target / "a.txt").read_text(encoding="utf-8") == "a"


def test_atomic_file_keeps_the_old_file_on_failure(tmp_path):
    target = tmp_path / "t.csv"
    target.write_text("old", encoding="utf-8")
    with pytest.raises(RuntimeError), outputs.atomic_file(target) as tmp:
        tmp.write_text("new, half", encoding="utf-8")
        raise RuntimeError("disk full")
    assert target.read_text(encoding="utf-8") == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["t.csv"]
    with outputs.atomic_file(target) as tmp:
        tmp.write_text("new", encoding="utf-8")
    assert target.read_text(encoding="utf-8") == "new"
    assert oct(target.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def test_learn_and_classify_need_force_to_replace(model_file, tmp_path, capsys):
    model = tmp_path / "m.npz"
    model.write_bytes(b"keep me")
    assert run(["learn", "--out", str(model), *SMALL]) == 2
    assert model.read_bytes() == b"keep me"
    assert run(["-q", "learn", "--out", str(model), *SMALL, "--force"]) == 0
    assert model.read_bytes()[:2] == b"PK"  # a zip archive (.npz)
    table = tmp_path / "labels.csv"
    table.write_text("keep", encoding="utf-8")
    argv = ["classify", str(model_file), "--subjects", "1", "--stimuli", "2", "--out", str(table)]
    assert run(argv) == 2 and table.read_text(encoding="utf-8") == "keep"
    assert run([*argv, "--force"]) == 0
    assert table.read_text(encoding="utf-8").startswith("trial,segment,")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_generate_writes_a_complete_folder(tmp_path, capsys):
    out = tmp_path / "data"
    assert run(["generate", "--out", str(out), "--subjects", "1", "--stimuli", "2"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        [outputs.MARKER, "s00_m00.csv", "s00_m00.truth.json", "s00_m01.csv", "s00_m01.truth.json"]
    )
    assert run(["generate", "--out", str(out), "--subjects", "1", "--stimuli", "1"]) == 2
    assert run(["generate", "--out", str(out), "--subjects", "1", "--stimuli", "1", "--force"]) == 0
    assert len(list(out.glob("*.csv"))) == 1  # replaced, not merged


class TinyModel:
    """Duck-typed model: one minimum-jerk stroke as its only primitive."""

    n_primitives = 1
    primitive_durations_ = np.array([0.4])

    def primitive_angles(self, k: int) -> np.ndarray:
        _, a = minimum_jerk(np.array([[0.0, 0.4, 0.0, 0.4], [0.3, 1.0, 0.3, 1.0]]), [0.4], 99 / 0.4)
        return a[:100]


def test_simulate_writes_the_picture_its_extension_names(tmp_path, monkeypatch, capsys):
    import visprim.cli.simulate as simulate_cli

    model = tmp_path / "model.npz"
    model.write_bytes(b"stand-in")
    monkeypatch.setattr(simulate_cli, "_load_model", lambda path: TinyModel())
    png, gif = tmp_path / "last.png", tmp_path / "clip.gif"
    assert run(["simulate", str(model), "--primitive", "0", "--out", str(png)]) == 0
    assert run(["simulate", str(model), "--primitive", "0", "--out", str(gif)]) == 0
    with Image.open(png) as im:
        assert im.format == "PNG" and getattr(im, "n_frames", 1) == 1
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames > 5
    assert "PNG of the last frame" in capsys.readouterr().out
    assert run(["simulate", str(model), "--primitive", "0", "--out", str(png)]) == 2
    assert run(["simulate", str(model), "--primitive", "0", "--out", str(tmp_path / "a.mp4")]) == 2
    assert not (tmp_path / "a.mp4").exists()
