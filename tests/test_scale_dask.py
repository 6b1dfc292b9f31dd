"""Dask fit on a LocalCluster of 2 worker processes: equal to the streaming and in-memory
fits within the tolerances; a worker killed during pass 1 changes nothing, a task that keeps
killing workers ends with a clear error."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
import cloudpickle  # noqa: E402 (a dependency of distributed)
import dask  # noqa: E402
from visprim import clustering  # noqa: E402
from visprim.cli.main import main as cli_main  # noqa: E402
from visprim.datasets import imitation_experiment  # noqa: E402
from visprim.io.corpus import GeneratedCorpus  # noqa: E402
from visprim.model import PrimitiveModel  # noqa: E402
from visprim.scale import fit_dask, fit_streaming, local_client  # noqa: E402

# Workers unpickle the corpus classes below by value (tests/ is not importable there).
cloudpickle.register_pickle_by_value(sys.modules[__name__])

N_SUBJECTS, N_STIMULI, SEED = 3, 12, 1
PARAMS = dict(n_components=12, n_clusters=8, n_init=3, seed=4)


def covariance(m: PrimitiveModel) -> np.ndarray:
    e = m.eigenvectors_  # eigenvalues beyond the stored eigenvectors are 0
    return (e * m.eigenvalues_[: e.shape[1]]) @ e.T


def assert_close_fit(a: PrimitiveModel, b: PrimitiveModel) -> None:
    ca, cb = covariance(a), covariance(b)
    assert np.max(np.abs(ca - cb)) <= 1e-9 * np.max(np.abs(ca))
    assert a.seg2_threshold_ == b.seg2_threshold_
    np.testing.assert_array_equal(a.segment_trial_, b.segment_trial_)
    np.testing.assert_array_equal(a.segment_starts_, b.segment_starts_)
    np.testing.assert_array_equal(a.segment_ends_, b.segment_ends_)
    assert a.trial_names_ == b.trial_names_
    assert abs(a.inertia_ - b.inertia_) <= 0.005 * a.inertia_, (a.inertia_, b.inertia_)
    assert a.labels_.shape == b.labels_.shape


@pytest.fixture(scope="module")
def client():
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        c = local_client(2)
    try:
        yield c
    finally:
        cluster = c.cluster
        c.close()
        cluster.close()


@pytest.fixture(scope="module")
def in_memory():
    return PrimitiveModel(**PARAMS).fit(imitation_experiment(N_SUBJECTS, N_STIMULI, SEED))


def test_dask_fit_equals_streaming_and_in_memory(client, in_memory):
    corpus = GeneratedCorpus(N_SUBJECTS, N_STIMULI, SEED)
    on_dask = PrimitiveModel(**PARAMS).fit(corpus, client=client)
    streamed = fit_streaming(PrimitiveModel(**PARAMS), corpus)
    assert_close_fit(in_memory, on_dask)
    assert_close_fit(streamed, on_dask)
    # Few segments: k-means on every row in one place, the in-memory fit's own call.
    assert in_memory.n_training_segments_ <= clustering.sample_size(PARAMS["n_clusters"])
    np.testing.assert_array_equal(on_dask.labels_, in_memory.labels_)
    assert on_dask.inertia_ == pytest.approx(in_memory.inertia_, rel=1e-9)
    assert on_dask.provenance_.kind == "generated"
    # Labels are the nearest centres of the projections.
    np.testing.assert_array_equal(
        on_dask.labels_, on_dask.assign(in_memory.training_projections_)[0]
    )


def test_above_the_sample_size_dask_seeds_and_iterates_as_in_memory(client, monkeypatch):
    # A small seeding sample makes this corpus "large": k-means++ on the sample, the best
    # candidate on every row, then Lloyd's iterations on the workers.
    monkeypatch.setattr(clustering, "SAMPLE_SIZE", 60)
    params = dict(PARAMS, n_clusters=4)
    trials = imitation_experiment(N_SUBJECTS, N_STIMULI, SEED)
    ref = PrimitiveModel(**params).fit(trials)
    assert ref.n_training_segments_ > 1.5 * clustering.sample_size(4)
    corpus = GeneratedCorpus(N_SUBJECTS, N_STIMULI, SEED)
    streamed = fit_streaming(PrimitiveModel(**params), corpus)
    on_dask = fit_dask(PrimitiveModel(**params), corpus, client, chunk_size=5)
    for m in (streamed, on_dask):
        assert_close_fit(ref, m)
        np.testing.assert_array_equal(m.labels_, ref.labels_)
        np.testing.assert_allclose(m.cluster_centers_, ref.cluster_centers_, atol=1e-9)
        assert m.inertia_ == pytest.approx(ref.inertia_, rel=1e-9)
        assert m.n_iter_ == ref.n_iter_


def test_dask_fit_of_a_trial_list(client, in_memory):
    trials = imitation_experiment(N_SUBJECTS, N_STIMULI, SEED)
    m = PrimitiveModel(**PARAMS).fit(trials, client=client)
    assert_close_fit(in_memory, m)


def test_cli_learn_on_a_cluster(client, tmp_path, capsys):
    out = tmp_path / "m.npz"
    address = client.scheduler.address
    code = cli_main(
        [
            "learn",
            "--generated",
            "--subjects",
            "2",
            "--stimuli",
            "8",
            "--clusters",
            "6",
            "--n-init",
            "2",
            "--out",
            str(out),
            "--dask",
            address,
        ]
    )
    assert code == 0 and out.exists()
    printed = capsys.readouterr().out
    assert "Dask" in printed and "model written" in printed
    m = PrimitiveModel.load(out)
    ref = PrimitiveModel(n_clusters=6, n_init=2).fit(imitation_experiment(2, 8, 0))
    assert m.n_training_segments_ == ref.n_training_segments_
    assert abs(m.inertia_ - ref.inertia_) <= 0.005 * ref.inertia_


# Worker kills last: the replaced workers start cold.
class KillOnce(GeneratedCorpus):
    """Reading item ``victim`` kills the worker process the first time (a marker file
    remembers it)."""

    def __init__(self, marker: str, victim: int, always: bool = False) -> None:
        super().__init__(N_SUBJECTS, N_STIMULI, SEED)
        self.marker, self.victim, self.always = marker, victim, always

    def __getstate__(self):
        return {**super().__getstate__(), "kill": (self.marker, self.victim, self.always)}

    def __setstate__(self, state):
        super().__setstate__(state)
        self.marker, self.victim, self.always = state["kill"]

    def read_item(self, index):
        if index == self.victim and (self.always or not Path(self.marker).exists()):
            Path(self.marker).touch()
            os._exit(1)
        return super().read_item(index)


def test_a_worker_killed_in_pass_1_does_not_change_the_result(client, in_memory, tmp_path):
    # A given SEG-2 constant: no tuning reads, so the kill happens in pass 1.
    params = dict(PARAMS, seg2_threshold=in_memory.seg2_threshold_)
    corpus = KillOnce(str(tmp_path / "killed"), victim=20)
    m = PrimitiveModel(**params).fit(corpus, client=client)
    assert (tmp_path / "killed").exists()
    assert_close_fit(in_memory, m)


def test_a_task_that_keeps_killing_workers_ends_with_a_clear_error(client, in_memory, tmp_path):
    params = dict(PARAMS, seg2_threshold=in_memory.seg2_threshold_)
    corpus = KillOnce(str(tmp_path / "killed"), victim=3, always=True)
    with pytest.raises(RuntimeError, match="kept killing workers"):
        PrimitiveModel(**params).fit(corpus, client=client)


def test_report_redraws_a_dask_model_from_its_own_data(client, tmp_path, capsys):
    from visprim.cli import main
    from visprim.provenance import Provenance

    m = PrimitiveModel(**PARAMS).fit(GeneratedCorpus(2, 6, 0, preset="strokes"), client=client)
    assert m.provenance_ == Provenance.generated(2, 6, 0, "strokes")
    m.save(tmp_path / "m.npz")
    assert main(["report", str(tmp_path / "m.npz"), "--out", str(tmp_path / "r")]) == 0
    page = (tmp_path / "r" / "index.html").read_text(encoding="utf-8")
    err = capsys.readouterr().err
    assert "cannot read the training data" not in err
    assert "strokes" in page and "Error tables are not available" in page
