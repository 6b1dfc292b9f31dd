"""What a model was fitted on (visprim.provenance): one record per fit path, read back by
``visprim report``; a model file's record and arrays are data, checked on load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.cli import main
from visprim.datasets import export_experiment, imitation_experiment
from visprim.io.corpus import GeneratedCorpus
from visprim.modelfile import ModelFileError, load_model, write_model_file
from visprim.provenance import Provenance, ProvenanceError

SMALL = ["--subjects", "2", "--stimuli", "6", "--clusters", "5", "--components", "8"]


def _learn(tmp_path: Path, name: str, *argv: str) -> PrimitiveModel:
    path = tmp_path / name
    assert main(["learn", "--out", str(path), *SMALL, *argv]) == 0
    return PrimitiveModel.load(path)


def _report(model_path: Path, out: Path, capsys: pytest.CaptureFixture[str]) -> str:
    assert main(["report", str(model_path), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    return (out / "index.html").read_text(encoding="utf-8") + captured.err


@pytest.mark.parametrize("preset", ["paper", "strokes"])
def test_a_streamed_generated_model_records_and_learns_its_preset(tmp_path, preset):
    m = _learn(tmp_path, "m.npz", "--stream", "--data-preset", preset)
    assert m.provenance_ == Provenance.generated(2, 6, 0, preset)
    assert m.frame_period_ == pytest.approx(0.034)
    # The lazy corpus is the preset's experiment, trial for trial.
    lazy = list(GeneratedCorpus(2, 6, 0, preset=preset))
    eager = imitation_experiment(2, 6, 0, preset=preset)
    assert [t.name for t in lazy] == [t.name for t in eager]
    np.testing.assert_array_equal(lazy[3].markers, eager[3].markers)
    in_memory = _learn(tmp_path, "e.npz", "--data-preset", preset)
    assert in_memory.provenance_ == m.provenance_
    assert m.trial_names_ == in_memory.trial_names_


@pytest.mark.parametrize("how", [[], ["--stream"]])
@pytest.mark.parametrize("preset", ["paper", "strokes"])
def test_report_redraws_generated_models_from_their_own_data(tmp_path, capsys, how, preset):
    path = tmp_path / "m.npz"
    assert main(["learn", "--out", str(path), *SMALL, "--data-preset", preset, *how]) == 0
    page = _report(path, tmp_path / "r", capsys)
    assert f"preset &#x27;{preset}&#x27;" in page or f"preset '{preset}'" in page
    assert "cannot read the training data" not in page
    # The trial figures are drawn from the regenerated trials.
    assert (tmp_path / "r" / "segmentation.png").exists() or "Fig. 5" in page
    if how:
        assert "Error tables are not available" in page
        assert not (tmp_path / "r" / "table1.md").exists()
    else:
        assert (tmp_path / "r" / "table1.md").exists()


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("recordings")
    export_experiment(folder, n_subjects=2, n_stimuli=6, seed=0, preset="strokes")
    return folder


@pytest.mark.parametrize("how", [[], ["--stream"]])
def test_report_redraws_recording_models_from_their_files(tmp_path, capsys, recordings, how):
    path = tmp_path / "m.npz"
    argv = ["learn", str(recordings), "--out", str(path), "--clusters", "5"]
    assert main([*argv, "--components", "8", "--resample", "0.05", *how]) == 0
    m = PrimitiveModel.load(path)
    assert m.provenance_.kind == "recordings"
    # The folder (in memory), or its files (a lazy corpus lists them).
    assert m.provenance_.files and all(f.startswith(str(recordings)) for f in m.provenance_.files)
    assert m.frame_period_ == pytest.approx(0.05)
    page = _report(path, tmp_path / "r", capsys)
    assert "cannot read the training data" not in page
    assert str(recordings) in page
    assert ("Error tables are not available" in page) == bool(how)


def test_report_of_a_model_whose_files_are_gone_draws_the_model_part(tmp_path, capsys):
    folder = tmp_path / "gone"
    export_experiment(folder, n_subjects=2, n_stimuli=6, seed=0, preset="strokes")
    path = tmp_path / "m.npz"
    assert main(["learn", str(folder), "--out", str(path), "--clusters", "5"]) == 0
    for f in folder.iterdir():
        f.unlink()
    folder.rmdir()
    page = _report(path, tmp_path / "r", capsys)
    assert "cannot read the training data again" in page


def test_a_model_fitted_on_bare_vectors_saves_loads_and_reports(tmp_path, capsys):
    rng = np.random.default_rng(0)
    m = PrimitiveModel(n_components=6, n_clusters=4).fit(rng.normal(size=(40, 600)))
    assert m.provenance_ == Provenance.arrays() and m.frame_period_ is None
    m.save(tmp_path / "m.npz")
    m2 = PrimitiveModel.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(m2.cluster_centers_, m.cluster_centers_)
    assert m2.provenance_.kind == "arrays"
    # Vectors of any dimension (features that are not segment vectors) too.
    other = PrimitiveModel(n_components=3, n_clusters=2).fit(rng.normal(size=(10, 7)))
    other.save(tmp_path / "o.npz")
    assert PrimitiveModel.load(tmp_path / "o.npz").n_features_in_ == 7


def test_trials_in_memory_record_their_frame_period():
    trials = imitation_experiment(2, 4, 0, preset="strokes")
    m = PrimitiveModel(n_components=6, n_clusters=4).fit(trials)
    assert m.provenance_.kind == "trials" and m.frame_period_ == pytest.approx(0.034, rel=0.02)


# ---------------------------------------------------------------------------- tampered files


@pytest.fixture(scope="module")
def model_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("model") / "m.npz"
    trials = imitation_experiment(2, 6, 0, preset="strokes")
    m = PrimitiveModel.paper(n_components=8, n_clusters=5).fit(
        trials, source=Provenance.generated(2, 6, 0, "strokes")
    )
    m.save(path)
    return path


def _rewrite(src: Path, dst: Path, change) -> Path:
    """``src`` with its header/arrays changed by ``change`` and written again with valid
    checksums (so only the model's own checks can refuse it)."""
    contents = load_model(src)
    header = {k: contents.header[k] for k in ("parameters", "fitted", "error_tables")}
    arrays = dict(contents.arrays)
    change(header, arrays)
    write_model_file(dst, header, arrays)
    return dst


def _set_array(name, value):
    def change(header, arrays):
        a = np.array(arrays[name], dtype=np.float64 if arrays[name].dtype.kind == "f" else None)
        a[0] = value
        arrays[name] = a

    return change


@pytest.mark.parametrize(
    ("change", "why"),
    [
        (lambda h, a: a.update(cluster_centers=np.zeros((50, 8))), "cluster_centers|inconsistent"),
        (_set_array("primitive_durations", np.nan), "primitive_durations"),
        (_set_array("primitive_durations", -1.0), "primitive_durations"),
        (_set_array("primitive_durations", 1e300), "primitive_durations"),
        (_set_array("segment_starts", np.nan), "segment times"),
        (_set_array("labels", 99), "labels|inconsistent"),
        (_set_array("cluster_centers", np.inf), "cluster_centers"),
        (lambda h, a: h["fitted"].update(seg2_threshold=float("nan")), "seg2_threshold"),
        (lambda h, a: h["fitted"].update(seg2_threshold=0.0), "seg2_threshold"),
        (lambda h, a: h["fitted"].update(seg2_threshold=-2.0), "seg2_threshold"),
        (lambda h, a: h["fitted"]["provenance"].update(n_subjects=10_000_000), "n_subjects"),
        (lambda h, a: h["fitted"]["provenance"].update(preset="evil"), "preset"),
        (
            lambda h, a: h["fitted"].update(
                provenance={
                    "kind": "recordings",
                    "frame_period": 0.034,
                    "files": ["/tmp"],
                    "reader_options": {"exec": "rm"},
                }
            ),
            "unknown option",
        ),
        (lambda h, a: h["fitted"].update(surprise=1), "unknown fitted"),
    ],
)
def test_load_refuses_inconsistent_or_out_of_range_models(model_file, tmp_path, change, why):
    bad = _rewrite(model_file, tmp_path / "bad.npz", change)
    with pytest.raises(ModelFileError, match=why):
        PrimitiveModel.load(bad)


def test_an_untouched_rewrite_loads(model_file, tmp_path):
    same = _rewrite(model_file, tmp_path / "same.npz", lambda h, a: None)
    assert PrimitiveModel.load(same).provenance_.preset == "strokes"


def test_report_does_not_walk_system_folders_from_a_model_file(model_file, tmp_path, capsys):
    def to_proc(header, arrays):
        header["fitted"]["provenance"] = {
            "kind": "recordings",
            "frame_period": 0.034,
            "files": ["/proc/self"],
            "reader_options": {},
        }

    bad = _rewrite(model_file, tmp_path / "proc.npz", to_proc)
    page = _report(bad, tmp_path / "r", capsys)
    assert "a system folder" in page


def test_older_training_source_dicts_are_read():
    old = {"kind": "files", "paths": ["/x/a.bvh"], "resample": None, "options": {"arm": "left"}}
    record = Provenance.from_dict(old)
    assert record == Provenance(
        kind="recordings", frame_period=None, files=("/x/a.bvh",), reader_options={"arm": "left"}
    )
    assert Provenance.from_dict({"kind": "generated", "n_subjects": 3}).preset == "strokes"
    assert Provenance.from_dict({}).frame_period == pytest.approx(0.034)
    with pytest.raises(ProvenanceError):
        Provenance.from_dict({"kind": "ftp"})


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null"])
def test_report_refuses_a_device_in_one_line(tmp_path, capsys, device):
    if not Path(device).exists():
        pytest.skip(f"no {device}")
    assert main(["report", device, "--out", str(tmp_path / "r")]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "not a regular file" in err and device in err


@pytest.mark.parametrize("existing", ["keep.npz", "notes.txt"])
def test_a_streamed_learn_checks_its_output_first(tmp_path, capsys, existing):
    target = tmp_path / existing
    target.write_text("precious", encoding="utf-8")
    assert main(["learn", "--out", str(target), *SMALL, "--stream"]) == 2
    assert target.read_text(encoding="utf-8") == "precious"
    assert "--out" in capsys.readouterr().err
