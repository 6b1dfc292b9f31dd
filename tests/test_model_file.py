"""The model file (visprim.modelfile): round trip, atomic writes, refusals."""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from _pipeline_data import SOURCE, default_trials, fitted
from visprim import PrimitiveModel
from visprim.modelfile import (
    FORMAT_VERSION,
    ModelFileError,
    read_header,
    save_model,
)
from visprim.provenance import Provenance


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> Path:
    m = fitted()
    m.error_table()
    path = tmp_path_factory.mktemp("model") / "m.npz"
    m.save(path)
    return path


def test_round_trip(saved):
    m = fitted()
    m2 = PrimitiveModel.load(saved)
    assert m2.get_params() == m.get_params()
    for attr in (
        "mean_",
        "eigenvalues_",
        "eigenvectors_",
        "cluster_centers_",
        "labels_",
        "segment_trial_",
        "segment_starts_",
        "segment_ends_",
        "primitive_durations_",
    ):
        np.testing.assert_array_equal(getattr(m2, attr), getattr(m, attr), err_msg=attr)
    assert m2.seg2_threshold_ == m.seg2_threshold_
    assert m2.inertia_ == m.inertia_
    assert m2.trial_names_ == m.trial_names_
    assert m2.provenance_ == Provenance.from_dict(SOURCE)
    assert m2.provenance_.preset == "strokes" and m2.frame_period_ == pytest.approx(0.034)
    np.testing.assert_array_equal(m2.training_vectors_, m.training_vectors_)
    x = m.training_vectors_[:20]
    np.testing.assert_array_equal(m2.predict(x), m.predict(x))
    np.testing.assert_allclose(m2.primitive_angles(2), m.primitive_angles(2))
    # Tables travel with the model.
    assert m2.error_table().to_markdown() == m.error_table().to_markdown()


def test_without_vectors_only_the_saved_tables_are_available(tmp_path):
    m = fitted()
    m.error_table()
    path = save_model(m, tmp_path / "small.npz", include_vectors=False)
    m2 = PrimitiveModel.load(path)
    assert m2.training_vectors_ is None
    assert m2.error_table().to_markdown() == m.error_table().to_markdown()
    with pytest.raises(ValueError, match="loaded from a file"):
        m2.error_table(k_values=(5,))
    full = save_model(m, tmp_path / "full.npz")
    vectors = m.training_vectors_.nbytes
    assert path.stat().st_size + vectors <= full.stat().st_size


def test_fit_save_load_then_error_table_and_report(tmp_path, monkeypatch):
    """A model saved straight after fit (no tables computed yet) reports like the fitted one."""
    import visprim.report as report

    m = PrimitiveModel(n_clusters=8).fit(list(default_trials()[:30]))
    assert getattr(m, "error_tables_", None) is None
    m.save(tmp_path / "fresh.npz")
    m2 = PrimitiveModel.load(tmp_path / "fresh.npz")
    assert m2.error_table().to_markdown() == m.error_table().to_markdown()
    assert m2.error_table(k_values=(3,)).clustering.rows[0][0] == 3

    # The report's tables part on a freshly loaded model (figures are test_report's subject:
    # here they are stubbed to keep this test fast).
    def blank(path, *args, **kwargs):
        Path(path).write_bytes(b"")
        return Path(path)

    for name in dir(report.figures):
        if name.startswith("plot_"):
            monkeypatch.setattr(report.figures, name, blank)
    rep = report.write_report(PrimitiveModel.load(tmp_path / "fresh.npz"), tmp_path / "report")
    assert rep.index.is_file()
    # The report's tables are in the paper's units (deg², degrees).
    from visprim.report.paper import tables_in_degrees

    expected = tables_in_degrees(m.error_table()).total.to_markdown()
    assert (tmp_path / "report" / "table3.md").read_text() == expected


def test_header_is_documented_json(saved):
    h = read_header(saved)
    assert h["format"] == "visprim.PrimitiveModel"
    assert h["format_version"] == FORMAT_VERSION
    assert h["parameters"]["n_components"] == 30
    assert set(h["arrays"]) >= {"mean", "eigenvalues", "eigenvectors", "cluster_centers"}
    assert h["arrays"]["eigenvectors"]["shape"] == [400, 400]


def test_vectors_can_be_included(tmp_path):
    m = fitted()
    path = save_model(m, tmp_path / "with_vectors.npz", include_vectors=True)
    m2 = PrimitiveModel.load(path)
    np.testing.assert_array_equal(m2.training_vectors_, m.training_vectors_)
    t = m2.error_table(k_values=(5,))
    assert t.clustering.rows[0][0] == 5


def test_write_is_atomic_and_leaves_no_temporary_file(tmp_path, monkeypatch):
    m = fitted()
    path = tmp_path / "model.npz"
    m.save(path)
    before = path.read_bytes()
    m.save(path)  # overwrite works
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.npz"]

    def boom(*args, **kwargs):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(np, "savez", boom)
    with pytest.raises(OSError, match="simulated"):
        m.save(path)
    # The old file is intact and no temporary file is left behind.
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.npz"]


def _rewrite_header(src: Path, dst: Path, change, *, reseal: bool = False) -> None:
    """Copy ``src`` to ``dst`` with ``change(header)`` applied; ``reseal`` recomputes the
    header checksum (as a deliberate forger would), so later checks are reached."""
    with np.load(src) as npz:
        arrays = {k: npz[k] for k in npz.files}
    header = json.loads(arrays["header"].tobytes().decode())
    change(header)
    if reseal:
        body = {k: v for k, v in header.items() if k != "header_sha256"}
        canonical = json.dumps(body, sort_keys=True, separators=(",", ":")).encode()
        header["header_sha256"] = hashlib.sha256(canonical).hexdigest()
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(dst, **arrays)


def test_a_changed_header_value_is_refused(saved, tmp_path):
    bad = tmp_path / "cutoff.npz"
    _rewrite_header(saved, bad, lambda h: h["parameters"].update(cutoff=0.3))
    with pytest.raises(ModelFileError, match="checksum mismatch in the header"):
        PrimitiveModel.load(bad)


def test_parameters_are_validated_on_load(saved, tmp_path):
    for change, message in (
        ({"cutoff": 5.0}, "cutoff"),
        ({"n_clusters": -1}, "n_clusters"),
        ({"segmentation": "seg9"}, "segmentation"),
        ({"no_such_option": 1}, "no_such_option"),
        ({"n_samples": "100"}, "n_samples|inconsistent"),
    ):
        bad = tmp_path / "params.npz"
        _rewrite_header(saved, bad, lambda h, c=change: h["parameters"].update(c), reseal=True)
        with pytest.raises(ModelFileError, match=message):
            PrimitiveModel.load(bad)


def test_files_without_offsets_hold_absolute_vectors(saved, tmp_path):
    """A file written before the ``offsets`` parameter is read as the paper's absolute
    vectors; a file of today keeps its own setting."""
    assert PrimitiveModel.load(saved).offsets == fitted().offsets
    old = tmp_path / "old.npz"
    _rewrite_header(saved, old, lambda h: h["parameters"].pop("offsets"), reseal=True)
    assert PrimitiveModel.load(old).offsets == "turns"


@pytest.mark.parametrize(
    "change",
    [
        lambda h: h.update(parameters=[1, 2]),
        lambda h: h.update(parameters={"cutoff": {"a": 1}}),
        lambda h: h.update(fitted="x"),
        lambda h: h["fitted"].update(trial_names="abc"),
        lambda h: h["fitted"].update(n_iter=1.5),
        lambda h: h["fitted"].update(provenance=None),
        lambda h: h["fitted"].pop("inertia"),
        lambda h: h.update(arrays={"mean": 3}),
        lambda h: h["arrays"]["mean"].update(shape="400"),
        lambda h: h["arrays"]["mean"].update(dtype="|O"),
        lambda h: h["arrays"].update(extra={"shape": [1], "dtype": "<f8", "sha256": "0"}),
        lambda h: h.update(error_tables=[1]),
        lambda h: h.update(error_tables={"projection": 1}),
    ],
)
def test_header_of_wrong_types_is_a_model_file_error(saved, tmp_path, change):
    bad = tmp_path / "types.npz"
    _rewrite_header(saved, bad, change, reseal=True)
    with pytest.raises(ModelFileError):
        PrimitiveModel.load(bad)


def test_deeply_nested_header_is_a_model_file_error(saved, tmp_path):
    with np.load(saved) as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays["header"] = np.frombuffer(b"[" * 100_000 + b"]" * 100_000, dtype=np.uint8)
    bad = tmp_path / "deep.npz"
    np.savez(bad, **arrays)
    with pytest.raises(ModelFileError, match="nested too deeply|unreadable header"):
        PrimitiveModel.load(bad)


def test_a_huge_declared_shape_is_refused_before_allocating(saved, tmp_path):
    bad = tmp_path / "huge.npz"
    grow = lambda h: h["arrays"]["segment_starts"].update(shape=[10**12])  # noqa: E731
    _rewrite_header(saved, bad, grow, reseal=True)
    with pytest.raises(ModelFileError, match="'segment_starts' has shape"):
        PrimitiveModel.load(bad)
    # Header and .npy member agree on 10^12 values: the member's size gives it away.
    with zipfile.ZipFile(bad) as z:
        members = {n: z.read(n) for n in z.namelist()}
    head = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        head, {"descr": "<f8", "fortran_order": False, "shape": (10**12,)}
    )
    members["segment_starts.npy"] = head.getvalue() + members["segment_starts.npy"][-80:]
    with zipfile.ZipFile(tmp_path / "huge2.npz", "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    with pytest.raises(ModelFileError, match="'segment_starts' holds 80 bytes"):
        PrimitiveModel.load(tmp_path / "huge2.npz")


def test_files_get_the_umask_mode(tmp_path):
    m = fitted()
    old = os.umask(0o022)
    try:
        m.save(tmp_path / "a.npz", include_vectors=False)
        os.umask(0o077)
        m.save(tmp_path / "b.npz", include_vectors=False)
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.npz").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "b.npz").stat().st_mode) == 0o600


_KILLED_SAVE = """
import os, sys
import numpy as np
from visprim import modelfile
os.replace = lambda *a: os._exit(9)  # killed between writing and renaming
arrays = {n: np.zeros(2) for n in modelfile.REQUIRED_ARRAYS}
modelfile.write_model_file(sys.argv[1], {"parameters": {}}, arrays)
"""


def test_a_killed_save_leaves_a_temporary_file_that_the_next_save_removes(tmp_path):
    target = tmp_path / "model.npz"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.run([sys.executable, "-c", _KILLED_SAVE, str(target)], env=env, timeout=120)
    assert proc.returncode == 9
    left = [p.name for p in tmp_path.iterdir()]
    assert len(left) == 1 and left[0].startswith(".model.npz.") and left[0].endswith(".tmp")
    # Another writer's temporary file that is still running is left alone.
    alive = tmp_path / f".model.npz.visprim-tmp-{os.getppid()}-{'0' * 8}.tmp"
    alive.write_bytes(b"in progress")
    fitted().save(target, include_vectors=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["model.npz", alive.name])


def test_other_format_version_is_refused(saved, tmp_path):
    bad = tmp_path / "v99.npz"
    _rewrite_header(saved, bad, lambda h: h.update(format_version=99))
    with pytest.raises(ModelFileError, match=rf"format version 99.*reads version {FORMAT_VERSION}"):
        PrimitiveModel.load(bad)
    other = tmp_path / "other.npz"
    _rewrite_header(saved, other, lambda h: h.update(format="something.else"))
    with pytest.raises(ModelFileError, match="not a visprim model file"):
        PrimitiveModel.load(other)


def test_checksum_detects_a_changed_array(saved, tmp_path):
    with np.load(saved) as npz:
        arrays = {k: npz[k].copy() for k in npz.files}
    arrays["cluster_centers"][0, 0] += 1e-9
    bad = tmp_path / "tampered.npz"
    np.savez(bad, **arrays)
    with pytest.raises(ModelFileError, match="checksum mismatch in 'cluster_centers'"):
        PrimitiveModel.load(bad)


def test_missing_member_is_refused(saved, tmp_path):
    with np.load(saved) as npz:
        arrays = {k: npz[k] for k in npz.files if k != "eigenvectors"}
    bad = tmp_path / "missing.npz"
    np.savez(bad, **arrays)
    with pytest.raises(ModelFileError, match="'eigenvectors' is missing"):
        PrimitiveModel.load(bad)


@pytest.mark.parametrize("cut", [0.3, 0.9])
def test_truncated_file_is_refused(saved, tmp_path, cut):
    data = saved.read_bytes()
    bad = tmp_path / "truncated.npz"
    bad.write_bytes(data[: int(len(data) * cut)])
    with pytest.raises(ModelFileError, match="truncated.npz"):
        PrimitiveModel.load(bad)


def test_flipped_bytes_are_refused(saved, tmp_path):
    data = bytearray(saved.read_bytes())
    # Corrupt bytes inside the eigenvector data (the largest member, mid-file).
    with zipfile.ZipFile(saved) as z:
        info = z.getinfo("eigenvectors.npy")
    pos = info.header_offset + 200 + info.compress_size // 2
    data[pos : pos + 8] = bytes(b ^ 0xFF for b in data[pos : pos + 8])
    bad = tmp_path / "flipped.npz"
    bad.write_bytes(bytes(data))
    with pytest.raises(ModelFileError, match="flipped.npz"):
        PrimitiveModel.load(bad)


def test_not_a_model_file(tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("hello")
    with pytest.raises(ModelFileError, match="not a visprim model file"):
        PrimitiveModel.load(text)
    plain = tmp_path / "plain.npz"
    np.savez(plain, a=np.zeros(3))
    with pytest.raises(ModelFileError, match="'header' is missing"):
        PrimitiveModel.load(plain)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        PrimitiveModel.load(tmp_path / "nope.npz")


def test_loaded_model_classifies_new_trials(saved):
    m2 = PrimitiveModel.load(saved)
    labels = m2.predict(list(default_trials()[200:203]))
    assert labels.ndim == 1 and labels.size >= 3
