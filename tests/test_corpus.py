"""visprim.io.Corpus: files, folders and globs read on demand, in chunks."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from visprim.datasets import export_experiment
from visprim.io import Corpus, ReadError, read_many
from visprim.io.corpus import GeneratedCorpus
from visprim.model import PrimitiveModel


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("csv")
    export_experiment(out, n_subjects=2, n_stimuli=6, seed=2)
    (out / "README.md").write_text("not a recording")
    return out


def test_folder_glob_and_file_sources(folder):
    corpus = Corpus(folder)
    assert len(corpus) == 12  # the CSV files; truth sidecars and README skipped
    assert [p.name for p in corpus.paths] == sorted(p.name for p in folder.glob("*.csv"))
    assert len(Corpus(str(folder / "s00_*.csv"))) == 6
    both = Corpus([folder / "s01_m02.csv", str(folder / "s01_*.csv")])
    assert len(both) == 6 and both.paths[0].name == "s01_m02.csv"  # duplicates dropped


def test_reading_is_lazy_and_equals_read_many(folder, monkeypatch):
    import visprim.io as vio

    calls = []
    real = vio.read_pieces
    monkeypatch.setattr(vio, "read_pieces", lambda *a, **k: calls.append(a[0]) or real(*a, **k))
    corpus = Corpus(folder)
    assert calls == []  # nothing read at construction
    chunks = list(corpus.chunks(5))
    assert [len(c) for c in chunks] == [5, 5, 2]
    assert len(calls) == 12
    eager = read_many(folder)
    lazy = [t for c in chunks for t in c]
    assert [t.name for t in lazy] == [t.name for t in eager]
    for a, b in zip(lazy, eager, strict=True):
        np.testing.assert_array_equal(a.markers, b.markers)
    assert [t.name for t in corpus] == [t.name for t in eager]  # iteration
    assert [t.name for t in corpus.read([3, 0])] == [eager[3].name, eager[0].name]


def test_options_reach_the_reader(folder):
    corpus = Corpus(folder, resample=0.05)
    trial = corpus.read([0])[0]
    np.testing.assert_allclose(np.diff(trial.times), 0.05, atol=1e-9)
    record = corpus.provenance
    assert record.kind == "recordings" and record.frame_period == 0.05


def test_subset_and_pickle(folder):
    corpus = Corpus(folder)
    sub = corpus.subset([4, 1])
    assert len(sub) == 2 and sub.paths == [corpus.paths[4], corpus.paths[1]]
    back = pickle.loads(pickle.dumps(sub))
    assert [t.name for t in back.read([0, 1])] == [corpus.paths[4].stem, corpus.paths[1].stem]
    gen = GeneratedCorpus(2, 3, seed=5, noise=False)
    gen2 = pickle.loads(pickle.dumps(gen))
    np.testing.assert_array_equal(gen2.read([4])[0].markers, gen.read([4])[0].markers)
    gsub = gen.subset([5, 0])
    assert [t.name for t in gsub.read([0, 1])] == ["s01_m02", "s00_m00"]


def test_errors(folder, tmp_path):
    with pytest.raises(ReadError, match="no such file or folder"):
        Corpus(tmp_path / "missing")
    with pytest.raises(ReadError, match="matches no recording"):
        Corpus(str(tmp_path / "*.bvh"))
    with pytest.raises(ValueError, match="on_error"):
        Corpus(folder, on_error="ignore")
    with pytest.raises(ValueError, match="chunk size"):
        list(Corpus(folder).chunks(0))
    with pytest.raises(IndexError, match="out of range"):
        Corpus(folder).read([12])
    with pytest.raises(ValueError, match="positive integer"):
        GeneratedCorpus(0, 3)


def test_unreadable_files_raise_or_are_skipped(folder, tmp_path):
    for p in sorted(folder.glob("s00_m0[01].csv")):
        (tmp_path / p.name).write_bytes(p.read_bytes())
    (tmp_path / "broken.csv").write_text("garbage\n1,2\n")
    with pytest.raises(ReadError, match="broken.csv"):
        Corpus(tmp_path).read(range(3))
    with pytest.warns(UserWarning, match="skipped: .*broken.csv"):
        trials = Corpus(tmp_path, on_error="warn").read(range(3))
    assert [t.name for t in trials] == ["s00_m00", "s00_m01"]


def test_streaming_fit_of_files_equals_the_in_memory_fit(folder):
    params = dict(n_components=10, n_clusters=5, n_init=2, seed=1)
    eager = PrimitiveModel(**params).fit(read_many(folder))
    lazy = PrimitiveModel(**params).fit(Corpus(folder))
    np.testing.assert_array_equal(lazy.segment_starts_, eager.segment_starts_)
    assert lazy.trial_names_ == eager.trial_names_
    assert abs(lazy.inertia_ - eager.inertia_) <= 0.005 * eager.inertia_
    assert lazy.provenance_.kind == "recordings"
    assert len(lazy.provenance_.files) == 12


def test_each_arm_reads_both_arms_as_one_arm_trials(shared_data):
    """``arm="each"``: a file's two arms, the left mirrored (as ``split_arms``), and the
    choice survives pickling (Dask workers) and is recorded in the source."""
    from visprim.io import read
    from visprim.trial import split_arms

    files = sorted((shared_data / "bandai_namco_ds2").glob("*.bvh"))[:2]
    corpus = Corpus(files, arm="each")
    got = corpus.read([0, 1])
    want = split_arms([read(f, "both") for f in files])
    assert [t.name for t in got] == [t.name for t in want]
    for a, b in zip(got, want, strict=True):
        np.testing.assert_array_equal(a.markers, b.markers)
    assert pickle.loads(pickle.dumps(corpus)).arm == "each"
    assert corpus.provenance.reader_options == {"arm": "each"}
    assert Corpus(files).provenance.reader_options == {}
    with pytest.raises(ValueError, match="arm"):
        Corpus(files, arm="several")
