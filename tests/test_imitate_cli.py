"""``visprim imitate`` and ``visprim export-robot`` from the command line."""

from __future__ import annotations

import importlib.util
import json

import pytest
from visprim import PrimitiveModel
from visprim.cli.main import main
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv

#: The default video: MP4 with imageio-ffmpeg, else GIF.
DEFAULT_VIDEO = (
    "imitation.mp4" if importlib.util.find_spec("imageio_ffmpeg") is not None else "imitation.gif"
)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("imitate_cli")
    trials = imitation_experiment(2, 4, seed=4)
    model = PrimitiveModel(n_clusters=5, n_init=2).fit(trials[:-1])
    model_path = tmp / "model.npz"
    model.save(model_path)
    rec = write_marker_csv(tmp / "take.csv", trials[-1])
    return model_path, rec, model.n_primitives


def test_imitate_writes_metrics_trajectories_and_video(files, tmp_path, capsys) -> None:
    model, rec, _ = files
    out = tmp_path / "out"
    assert main(["imitate", str(model), str(rec), "--out", str(out), "--size", "96"]) == 0
    printed = capsys.readouterr().out
    assert "primitives" in printed and "uncovered" in printed and "Adonis vs human" in printed
    names = {p.name for p in out.iterdir()}
    assert {"imitation.json", "imitation.csv", "trajectory.json", "trajectory.csv"} <= names
    assert DEFAULT_VIDEO in names
    doc = json.loads((out / "imitation.json").read_text())
    assert doc["adonis"]["servo"] == "stable" and doc["model"].endswith("model.npz")
    assert not [n for n in names if n.startswith(".") and "tmp" in n]  # no temporary files


def test_imitate_projection_is_labelled(files, tmp_path, capsys) -> None:
    model, rec, _ = files
    out = tmp_path / "near"
    argv = ["imitate", str(model), str(rec), "--out", str(out), "--no-video"]
    assert main([*argv, "--source", "projection"]) == 0
    assert "NEAR-COPY" in capsys.readouterr().out
    assert json.loads((out / "imitation.json").read_text())["source"] == "projection"


def test_without_imageio_ffmpeg_the_default_is_a_gif_and_says_so(files, tmp_path, capsys):
    import builtins

    real = builtins.__import__

    def no_ffmpeg(name, *args, **kwargs):
        if name == "imageio_ffmpeg":
            raise ImportError(name)
        return real(name, *args, **kwargs)

    model, rec, _ = files
    out = tmp_path / "g"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(builtins, "__import__", no_ffmpeg)
        assert main(["imitate", str(model), str(rec), "--out", str(out), "--size", "64"]) == 0
        err = capsys.readouterr().err
        assert "imageio-ffmpeg is not installed" in err and "imitation.gif" in err
        assert (out / "imitation.gif").is_file() and not (out / "imitation.mp4").exists()
        out2 = tmp_path / "m"
        argv = ["imitate", str(model), str(rec), "--out", str(out2), "--video", "v.mp4"]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "imageio-ffmpeg" in err and err.count("\n") == 1 and not out2.exists()


def test_imitate_refuses_bad_input_in_one_line(files, tmp_path, capsys) -> None:
    model, rec, _ = files
    out = tmp_path / "x"
    assert main(["imitate", str(model), str(rec), "--out", str(out), "--video", "a.avi"]) == 2
    err = capsys.readouterr().err
    assert "unsupported video format" in err and err.count("\n") == 1
    assert not out.exists()
    assert main(["imitate", str(model), str(tmp_path / "none.bvh"), "--out", str(out)]) == 2
    assert "not found" in capsys.readouterr().err
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nnonsense\n")
    assert main(["imitate", str(model), str(bad), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("visprim imitate: error:") and "bad.bvh" in err
    assert err.count("\n") == 1
    assert not out.exists()


def test_imitate_checks_folders_and_size_up_front(files, tmp_path, capsys) -> None:
    model, rec, _ = files
    out = tmp_path / "x"
    assert main(["imitate", str(model), str(rec.parent), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "is a folder" in err and rec.name in err and "one recording file" in err
    assert err.count("\n") == 1
    assert main(["imitate", str(model.parent), str(rec), "--out", str(out)]) == 2
    assert "model file" in capsys.readouterr().err
    # A video size PIL cannot draw is refused before the simulation runs.
    assert main(["imitate", str(model), str(rec), "--out", str(out), "--size", "0"]) == 2
    err = capsys.readouterr().err
    assert "--size 0" in err and err.count("\n") == 1
    assert not out.exists()
    assert (
        main(["imitate", str(model), str(rec), "--out", str(out), "--size", "0", "--no-video"]) == 0
    )


@pytest.mark.parametrize(
    ("option", "value"),
    [("--size", "100000"), ("--dt", "0"), ("--dt", "nan"), ("--dt", "-1"), ("--dt", "0.5")],
)
def test_a_size_or_step_out_of_range_is_refused_before_any_work(
    files, tmp_path, capsys, monkeypatch, option, value
) -> None:
    """A panel of 100,000 px once ran the machine out of memory after the simulation; a bad
    step failed only after the recording was read and rebuilt."""
    import visprim.imitate

    def never(*args, **kwargs):
        raise AssertionError("imitate ran")

    monkeypatch.setattr(visprim.imitate, "imitate", never)
    model, rec, _ = files
    out = tmp_path / "x"
    assert main(["imitate", str(model), str(rec), "--out", str(out), option, value]) == 2
    err = capsys.readouterr().err
    assert f"{option} " in err and err.count("\n") == 1
    assert not out.exists()


def test_export_robot_writes_urdf_and_primitive_trajectories(files, tmp_path, capsys) -> None:
    model, _, k = files
    urdf = tmp_path / "adonis.urdf"
    traj = tmp_path / "traj"
    argv = ["export-robot", "--out", str(urdf), "--model", str(model), "--trajectories", str(traj)]
    assert main(argv) == 0
    assert urdf.read_text().startswith('<?xml version="1.0"?>')
    assert len(list(traj.glob("primitive_*.json"))) == len(list(traj.glob("primitive_*.csv"))) == k
    doc = json.loads((traj / "primitive_00.json").read_text())
    assert len(doc["joint_names"]) == 20 and doc["points"][0]["time_from_start"]["sec"] == 0
    assert main(["export-robot", "--out", str(tmp_path / "a.sdf")]) == 2
    assert ".urdf or .xml" in capsys.readouterr().err
    assert main(argv) == 2  # outputs exist
    assert "--force" in capsys.readouterr().err
    assert main([*argv, "--force"]) == 0


def test_one_arm_primitives_imitate_both_arms_of_a_recording(shared_data, tmp_path, capsys):
    """``learn --arm each`` then ``imitate --arm both``: Adonis plays both arms of a Bandai
    take, each rebuilt from the same one-arm primitives; the video shows both."""
    files = sorted((shared_data / "bandai_namco_ds2").glob("*wave-both-hands*.bvh"))
    model = tmp_path / "each.npz"
    learn = ["learn", *map(str, files[1:]), "--arm", "each", "--clusters", "8", "--out", str(model)]
    assert main(learn) == 0
    out = tmp_path / "both"
    argv = ["imitate", str(model), str(files[0]), "--arm", "both", "--out", str(out)]
    assert main([*argv, "--size", "96"]) == 0
    printed = capsys.readouterr().out
    assert "right arm" in printed and "left arm" in printed
    doc = json.loads((out / "imitation.json").read_text())
    assert doc["arms_imitated"] == "one by one"
    assert {s["arm"] for s in doc["segments"]} == {"right", "left"}
    assert doc["adonis"]["vs_rebuild_joint_rms_deg"]["overall"] < 2.0
    header = (out / "imitation.csv").read_text().splitlines()[0]
    assert "adonis_left_elbow_rad" in header.split(",")
    assert (out / DEFAULT_VIDEO).stat().st_size > 0
