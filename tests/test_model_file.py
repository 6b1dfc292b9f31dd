"""The model file (visprim.modelfile): round trip, atomic writes, refusals."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from _pipeline_data import SOURCE, default_trials, fitted
from visprim import PrimitiveModel
from visprim.modelfile import FORMAT_VERSION, ModelFileError, read_header, save_model


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
    assert m2.training_source_ == SOURCE
    assert m2.training_vectors_ is None
    x = m.training_vectors_[:20]
    np.testing.assert_array_equal(m2.predict(x), m.predict(x))
    np.testing.assert_allclose(m2.primitive_angles(2), m.primitive_angles(2))
    # Tables travel with the model.
    assert m2.error_table().to_markdown() == m.error_table().to_markdown()
    with pytest.raises(ValueError, match="loaded from a file"):
        m2.error_table(k_values=(5,))


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


def _rewrite_header(src: Path, dst: Path, change) -> None:
    with np.load(src) as npz:
        arrays = {k: npz[k] for k in npz.files}
    header = json.loads(arrays["header"].tobytes().decode())
    change(header)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(dst, **arrays)


def test_other_format_version_is_refused(saved, tmp_path):
    bad = tmp_path / "v99.npz"
    _rewrite_header(saved, bad, lambda h: h.update(format_version=99))
    with pytest.raises(ModelFileError, match=r"format version 99.*reads version 1"):
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
