"""Streaming fit of a lazy corpus: equal to the in-memory fit of the same trials."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from visprim.datasets import imitation_experiment
from visprim.io.corpus import GeneratedCorpus, sample_items
from visprim.model import PrimitiveModel
from visprim.provenance import Provenance
from visprim.scale import TrialList, fit_streaming, tune_threshold
from visprim.segment.seg2 import speed_squared_concatenated, tune_seg2_threshold_concatenated

N_SUBJECTS, N_STIMULI = 3, 12
PARAMS = dict(n_components=12, n_clusters=8, n_init=3, seed=4)


def covariance(m: PrimitiveModel) -> np.ndarray:
    """K from the model's eigenpairs (eigenvalues beyond the stored eigenvectors are 0)."""
    e = m.eigenvectors_
    return (e * m.eigenvalues_[: e.shape[1]]) @ e.T


def assert_same_fit(a: PrimitiveModel, b: PrimitiveModel, inertia_rtol: float = 0.005) -> None:
    """The issue's tolerances: covariance within 1e-9 relative, the same segments, k-means
    inertia within 0.5 %."""
    ca, cb = covariance(a), covariance(b)
    assert np.max(np.abs(ca - cb)) <= 1e-9 * np.max(np.abs(ca))
    np.testing.assert_allclose(a.mean_, b.mean_, rtol=0, atol=1e-12)
    assert a.seg2_threshold_ == b.seg2_threshold_
    np.testing.assert_array_equal(a.segment_trial_, b.segment_trial_)
    np.testing.assert_array_equal(a.segment_starts_, b.segment_starts_)
    np.testing.assert_array_equal(a.segment_ends_, b.segment_ends_)
    assert a.trial_names_ == b.trial_names_
    assert abs(a.inertia_ - b.inertia_) <= inertia_rtol * a.inertia_


@pytest.fixture(scope="module")
def trials():
    return imitation_experiment(N_SUBJECTS, N_STIMULI, seed=1)


@pytest.fixture(scope="module")
def in_memory(trials):
    return PrimitiveModel(**PARAMS).fit(trials)


def test_generated_corpus_gives_the_experiments_trials(trials):
    corpus = GeneratedCorpus(N_SUBJECTS, N_STIMULI, seed=1)
    assert len(corpus) == len(trials)
    lazy = [t for chunk in corpus.chunks(5) for t in chunk]
    assert [t.name for t in lazy] == [t.name for t in trials]
    for a, b in zip(lazy, trials, strict=True):
        np.testing.assert_array_equal(a.markers, b.markers)
        np.testing.assert_array_equal(a.times, b.times)
        assert a.repetitions == b.repetitions
    # Random access, negative indices, out of range.
    np.testing.assert_array_equal(corpus.read([-1])[0].markers, trials[-1].markers)
    with pytest.raises(IndexError, match="out of range"):
        corpus.read([len(trials)])


def test_paper_method_streaming_equals_in_memory(trials):
    a = PrimitiveModel.paper(**PARAMS).fit(trials)
    b = PrimitiveModel.paper(**PARAMS).fit(GeneratedCorpus(N_SUBJECTS, N_STIMULI, seed=1))
    assert_same_fit(a, b)
    assert b.dim == 400 and b.n_trials_without_segments_ == a.n_trials_without_segments_


@pytest.mark.parametrize("chunk", [1, 7, 1000])
def test_streaming_fit_equals_the_in_memory_fit(in_memory, chunk):
    corpus = GeneratedCorpus(N_SUBJECTS, N_STIMULI, seed=1)
    streamed = PrimitiveModel(**PARAMS)
    fit_streaming(streamed, corpus, chunk_size=chunk)
    assert_same_fit(in_memory, streamed)
    np.testing.assert_array_equal(streamed.labels_, in_memory.labels_)
    assert streamed.provenance_ == Provenance.generated(N_SUBJECTS, N_STIMULI, 1, "paper")


def test_fit_dispatches_a_lazy_corpus_and_keeps_only_what_the_model_needs(in_memory):
    m = PrimitiveModel(**PARAMS).fit(GeneratedCorpus(N_SUBJECTS, N_STIMULI, seed=1))
    assert_same_fit(in_memory, m)
    assert m.training_vectors_ is None
    d = m.dim
    for name, value in vars(m).items():
        if isinstance(value, np.ndarray) and name != "eigenvectors_":
            assert value.ndim < 2 or value.shape[1] != d, f"{name} holds (N, d) vectors"
    np.testing.assert_allclose(
        m.training_projections_, in_memory.training_projections_, rtol=0, atol=1e-9
    )
    # The fitted model works as usual.
    x = in_memory.training_vectors_[:30]
    np.testing.assert_array_equal(m.predict(x), in_memory.predict(x))
    with pytest.raises(ValueError, match="training vectors"):
        m.error_table()


def test_save_and_load_a_streamed_model(tmp_path):
    m = PrimitiveModel(**PARAMS).fit(GeneratedCorpus(2, 6, seed=3))
    m.save(tmp_path / "m.npz")
    m2 = PrimitiveModel.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(m2.cluster_centers_, m.cluster_centers_)
    assert m2.provenance_ == m.provenance_ and m2.provenance_.kind == "generated"


def test_seg2_is_tuned_on_the_in_memory_fits_sample(trials):
    """With more trials than the tuning limit, the streamed sample is the one the in-memory
    tuning subsets (checked with a small limit; the paper's tuning from repetitions)."""
    model = PrimitiveModel.paper(**PARAMS)
    prepared = model.set_params(seg2_threshold=1.0).prepare(trials)
    model.set_params(seg2_threshold=None)
    z = speed_squared_concatenated(prepared.times_all, prepared.angles_all, prepared.offsets)
    reps = np.array([t.repetitions for t in trials])
    for limit in (5, 17, len(trials), 1000):
        expected = tune_seg2_threshold_concatenated(
            prepared.times_all, z, prepared.offsets, reps, max_trials=limit
        )
        got = tune_threshold(model, TrialList(trials), max_trials=limit)
        assert got == pytest.approx(expected, rel=1e-12), limit
    assert list(sample_items(10, 4)) == [0, 3, 6, 9]
    assert list(sample_items(3, 4)) == [0, 1, 2]


def test_given_threshold_and_seg1_skip_tuning():
    class NoRead(TrialList):
        def read_item(self, index):
            raise AssertionError("tuning should not read the corpus")

    corpus = NoRead([])
    assert tune_threshold(PrimitiveModel(seg2_threshold=2.5), corpus) == 2.5
    assert tune_threshold(PrimitiveModel(segmentation="seg1"), corpus) is None


def test_seg1_streaming_equals_in_memory(trials):
    params = dict(PARAMS, segmentation="seg1")
    a = PrimitiveModel(**params).fit(trials)
    b = PrimitiveModel(**params).fit(TrialList(trials))
    assert_same_fit(a, b)


def test_errors(trials):
    with pytest.raises(ValueError, match="exceeds the number of segments"):
        PrimitiveModel(n_clusters=500).fit(TrialList(trials[:2]))
    with pytest.raises(ValueError, match="empty"):
        PrimitiveModel().fit(TrialList([]))
    with pytest.raises(ValueError, match="n_components"):
        PrimitiveModel(n_components=0).fit(GeneratedCorpus(1, 2))
    with pytest.raises(ValueError, match="chunk size"):
        fit_streaming(PrimitiveModel(), GeneratedCorpus(1, 2), chunk_size=0)


def test_core_does_not_import_dask():
    code = (
        "import sys, visprim\n"
        "from visprim.io.corpus import GeneratedCorpus\n"
        "from visprim.datasets import imitation_experiment\n"
        "m = visprim.PrimitiveModel(n_clusters=4, n_init=1)\n"
        "m.fit(GeneratedCorpus(1, 6))\n"
        "m.fit(imitation_experiment(1, 6))\n"
        "bad = sorted(k for k in sys.modules if k.split('.')[0] in ('dask', 'distributed'))\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
