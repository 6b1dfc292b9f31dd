"""PrimitiveModel: scikit-learn conventions, fitted state, transform/predict/reconstruct."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _pipeline_data import default_trials, fitted
from sklearn.base import clone
from sklearn.exceptions import NotFittedError
from visprim import PrimitiveModel
from visprim.vectors import to_curves

DEFAULTS = {
    "filter_order": 10,
    "cutoff": 0.25,
    "segmentation": "seg2",
    "zvc_threshold_deg": 5.0,
    "window": 0.3,
    "seg1_adaptive": True,
    "seg2_threshold": None,
    "seg2_tuning": "robust",
    "seg2_boundary": "slowest",
    "features": "directions",
    "offsets": "mean",
    "amplitude": False,
    "n_samples": 100,
    "n_components": 30,
    "n_clusters": 30,
    "n_init": 10,
    "max_iter": 300,
    "tol": 1e-4,
    "seed": 0,
}


def test_parameters_follow_sklearn_conventions():
    m = PrimitiveModel()
    assert m.get_params() == DEFAULTS
    m.set_params(n_clusters=12, segmentation="seg1")
    assert m.n_clusters == 12 and m.segmentation == "seg1"
    c = clone(m)
    assert c.get_params() == m.get_params() and c is not m
    # Constructor arguments are stored unchanged, even invalid ones (validated in fit).
    assert PrimitiveModel(n_components=10_000).n_components == 10_000


def test_not_fitted_errors():
    m = PrimitiveModel()
    x = np.zeros((2, 400))
    for call in (
        lambda: m.transform(x),
        lambda: m.predict(x),
        lambda: m.reconstruct(x),
        lambda: m.primitive_angles(0),
        lambda: m.error_table(),
        lambda: m.n_primitives,
        lambda: m.save("unused.npz"),
    ):
        with pytest.raises(NotFittedError):
            call()


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"segmentation": "seg3"}, "segmentation"),
        ({"cutoff": 1.5}, "cutoff"),
        ({"filter_order": 0}, "filter_order"),
        ({"n_components": 601}, r"n_components.*600"),
        ({"n_samples": 1}, "n_samples"),
        ({"n_clusters": 0}, "n_clusters"),
        ({"seg2_threshold": -1.0}, "seg2_threshold"),
        ({"window": 0.0}, "window"),
        ({"seed": -3}, "seed"),
    ],
)
def test_bad_parameters_are_named_in_fit(params, match):
    with pytest.raises(ValueError, match=match):
        PrimitiveModel(**params).fit(list(default_trials()[:3]))


def test_too_many_clusters_is_a_clear_error():
    trials = list(default_trials()[:2])
    with pytest.raises(ValueError, match=r"n_clusters=500 exceeds the number of segments"):
        PrimitiveModel(n_clusters=500).fit(trials)


def test_fit_rejects_non_trials():
    with pytest.raises(TypeError, match="item 0"):
        PrimitiveModel().fit([np.zeros((10, 4, 3))])
    with pytest.raises(ValueError, match="at least one Trial"):
        PrimitiveModel().fit([])


def test_fitted_state_shapes():
    m = fitted()
    n = m.n_training_segments_
    assert n > 500  # 220 trials of 2-6 strokes
    assert m.mean_.shape == (400,)
    assert m.eigenvalues_.shape == (400,)
    assert m.eigenvectors_.shape == (400, 400)
    assert m.components_.shape == (400, 30)
    assert m.cluster_centers_.shape == (30, 30)
    assert m.labels_.shape == (n,) and m.labels_.min() >= 0 and m.labels_.max() < 30
    assert m.n_primitives == 30
    assert m.seg2_threshold_ is not None and m.seg2_threshold_ > 0
    assert np.all(m.segment_ends_ > m.segment_starts_)
    assert len(m.trial_names_) == 220


def test_pca_and_kmeans_state_agree_with_numpy_on_the_training_vectors():
    m = fitted()
    x = m.training_vectors_
    mean = x.mean(axis=0)
    cov = (x - mean).T @ (x - mean) / x.shape[0]
    w = np.linalg.eigvalsh(cov)[::-1]
    np.testing.assert_allclose(m.mean_, mean, atol=1e-12)
    np.testing.assert_allclose(m.eigenvalues_[:60], w[:60], rtol=1e-8, atol=1e-12)
    # transform is the projection on the first f eigenvectors.
    p = m.transform(x)
    np.testing.assert_allclose(p, (x - mean) @ m.eigenvectors_[:, :30], atol=1e-9)
    # k-means: every training label is the nearest centre; inertia is the sum of distances.
    d2 = ((p[:, None, :] - m.cluster_centers_[None]) ** 2).sum(axis=-1)
    np.testing.assert_array_equal(m.labels_, d2.argmin(axis=1))
    np.testing.assert_allclose(m.inertia_, d2.min(axis=1).sum(), rtol=1e-9)
    np.testing.assert_array_equal(m.predict(x), m.labels_)
    # Centres are the means of their members (Lloyd's fixed point).
    for k in range(m.n_primitives):
        members = p[m.labels_ == k]
        if members.size:
            np.testing.assert_allclose(m.cluster_centers_[k], members.mean(axis=0), atol=1e-6)


def test_transform_of_trials_equals_transform_of_their_vectors():
    m = fitted()
    trials = list(default_trials()[:3])
    from_trials = m.transform(trials)
    first = np.flatnonzero(m.segment_trial_ < 3)
    np.testing.assert_allclose(from_trials, m.transform(m.training_vectors_[first]), atol=1e-9)
    np.testing.assert_array_equal(m.predict(trials), m.labels_[first])


def test_transform_rejects_bad_input():
    m = fitted()
    with pytest.raises(ValueError, match=r"\(N, 400\)"):
        m.transform(np.zeros((3, 399)))
    with pytest.raises(ValueError, match="NaN"):
        m.transform(np.full((1, 400), np.nan))


def test_reconstruction_from_projection_and_cluster():
    m = fitted()
    x = m.training_vectors_[:50]
    rec = m.reconstruct(x)
    assert rec.shape == (50, 100, 4)
    # Exactly E_f p + s̄ split into 4 curves of 100.
    expected = to_curves(m.transform(x) @ m.components_.T + m.mean_)
    np.testing.assert_allclose(rec, expected, atol=1e-12)
    rec_c = m.reconstruct(x, source="cluster")
    centre_curves = np.stack([m.primitive_angles(k) for k in m.labels_[:50]])
    np.testing.assert_allclose(rec_c, centre_curves, atol=1e-12)
    err_p = np.mean((rec - to_curves(x)) ** 2)
    err_c = np.mean((rec_c - to_curves(x)) ** 2)
    assert err_p < err_c
    with pytest.raises(ValueError, match="source"):
        m.reconstruct(x, source="median")


def test_primitive_interface_for_the_simulation():
    m = fitted()
    a = m.primitive_angles(3)
    assert a.shape == (100, 4)
    expected = to_curves(m.cluster_centers_[3] @ m.components_.T + m.mean_)
    np.testing.assert_allclose(a, expected, atol=1e-12)
    with pytest.raises(IndexError):
        m.primitive_angles(30)
    durations = m.segment_ends_ - m.segment_starts_
    for k in range(m.n_primitives):
        members = durations[m.labels_ == k]
        if members.size:
            assert m.primitive_durations_[k] == pytest.approx(members.mean())
    assert np.all((m.primitive_durations_ > 0.05) & (m.primitive_durations_ < 5.0))


def test_reconstruct_movement_covers_the_movement_and_tracks_it():
    m = fitted()
    trial = default_trials()[7]
    t, rec, orig = m.reconstruct_movement(trial, return_original=True)
    assert rec.shape == orig.shape == (t.size, 4)
    assert np.all(np.diff(t) > 0)
    assert np.all(np.isin(t, trial.times))
    # SEG-2 partitions the movement: most of the trial is covered.
    assert t.size > 0.5 * trial.n_frames
    rms_p = math.degrees(np.sqrt(np.mean((rec - orig) ** 2)))
    _, rec_c = m.reconstruct_movement(trial, source="cluster")
    rms_c = math.degrees(np.sqrt(np.mean((rec_c - orig) ** 2)))
    # 30 eigenvectors keep > 99.9 % of the variance; the primitives are coarser.
    assert rms_p < 0.5
    assert rms_p < rms_c


def test_fit_is_deterministic_for_a_seed():
    trials = list(default_trials()[:40])
    a = PrimitiveModel(n_clusters=8, seed=3).fit(trials)
    b = PrimitiveModel(n_clusters=8, seed=3).fit(trials)
    np.testing.assert_array_equal(a.labels_, b.labels_)
    np.testing.assert_array_equal(a.cluster_centers_, b.cluster_centers_)
    np.testing.assert_array_equal(a.eigenvectors_, b.eigenvectors_)


def test_seg1_model_fits_and_refit_clears_state():
    trials = list(default_trials()[:40])
    m = PrimitiveModel(segmentation="seg1", n_clusters=5).fit(trials)
    assert m.seg2_threshold_ is None
    n1 = m.n_training_segments_
    m.set_params(segmentation="seg2").fit(trials)
    assert m.seg2_threshold_ is not None and m.n_training_segments_ != n1


TWO_PI = 2 * np.pi


def _ik_with_whole_turns(monkeypatch, turns):
    """Make the IK return each named trial's angles offset by whole turns of gamma and alpha
    (``turns[name] = (m_gamma, m_alpha)``), as IK's unwrapping in time does on long real
    recordings; the marker data are untouched."""
    import visprim.preprocess as pre

    ik = pre.arm_angles_corpus

    def turned(trials):
        out = ik(trials)
        return [a + _shift(*turns.get(t.name, (0, 0))) for t, a in zip(trials, out, strict=True)]

    monkeypatch.setattr(pre, "arm_angles_corpus", turned)


def _shift(m_gamma, m_alpha):
    return TWO_PI * np.array([m_gamma, 0.0, m_alpha, 0.0])


def test_whole_turn_offsets_of_the_angles_change_no_vector_nor_primitive(monkeypatch):
    m = fitted()
    trials = list(default_trials()[:4])
    base_corpus = m.prepare(trials)
    base = m.vectorize(base_corpus)
    base_labels = m.predict(trials)
    base_curves = m.reconstruct(trials)
    base_t, base_rec, base_orig = m.reconstruct_movement(trials[1], return_original=True)
    turns = {
        trials[0].name: (1, 0),
        trials[1].name: (2, -3),
        trials[2].name: (0, 1),
        trials[3].name: (-4, 5),
    }
    _ik_with_whole_turns(monkeypatch, turns)
    corpus = m.prepare(trials)
    # The low-passed IK angles really are offset (the patch works) ...
    for i, trial in enumerate(trials):
        np.testing.assert_allclose(
            corpus.angles[i], base_corpus.angles[i] + _shift(*turns[trial.name]), atol=1e-9
        )
    moved = m.vectorize(corpus)
    # ... but the segments, vectors and primitives are the same.
    np.testing.assert_allclose(moved.starts, base.starts, atol=1e-9)
    np.testing.assert_allclose(moved.ends, base.ends, atol=1e-9)
    np.testing.assert_allclose(moved.vectors, base.vectors, atol=1e-9)
    expected = np.stack([_shift(*turns[trials[i].name]) for i in moved.trial])
    np.testing.assert_allclose(moved.offsets - base.offsets, expected, atol=1e-9)
    np.testing.assert_array_equal(m.predict(trials), base_labels)
    # Reconstructions of trials are on the trial's own (offset) angles.
    np.testing.assert_allclose(m.reconstruct(trials), base_curves + expected[:, None, :], atol=1e-8)
    t, rec, orig = m.reconstruct_movement(trials[1], return_original=True)
    shift = _shift(*turns[trials[1].name])
    np.testing.assert_array_equal(t, base_t)
    np.testing.assert_allclose(orig, base_orig + shift, atol=1e-9)
    np.testing.assert_allclose(rec, base_rec + shift, atol=1e-8)
    assert math.degrees(np.sqrt(np.mean((rec - orig) ** 2))) < 0.5
    _, rec_c = m.reconstruct_movement(trials[1], source="cluster")
    assert np.max(np.abs(rec_c - orig)) < np.pi  # no whole-turn error anywhere


def test_reconstruct_segment_follows_offset_angles():
    m = fitted()
    trial = default_trials()[5]
    corpus = m.prepare([trial])
    times, angles = corpus.times[0], corpus.angles[0]
    start, end = corpus.segments[0][1]
    t0, r0 = m.reconstruct_segment(times, angles, start, end)
    shift = _shift(-2, 3)
    t1, r1 = m.reconstruct_segment(times, angles + shift, start, end)
    np.testing.assert_array_equal(t1, t0)
    np.testing.assert_allclose(r1, r0 + shift, atol=1e-9)
    inside = (times >= start) & (times <= end)
    assert math.degrees(np.sqrt(np.mean((r1 - (angles + shift)[inside]) ** 2))) < 1.0


def test_real_recordings_segments_are_within_a_turn_and_movements_follow_their_angles(
    shared_data,
):
    """CMU dances: the IK's unwrapped gamma/alpha leave (-pi, pi] (a zombie walk's alpha
    sits near 2 pi); segment vectors are brought back, reconstructions follow the trial."""
    from visprim.io import read_many

    trials = read_many(shared_data / "cmu_asfamc", resample=0.034)
    m = PrimitiveModel.paper(n_clusters=10).fit(trials)
    sv = m.vectorize(m.prepare(trials))
    np.testing.assert_allclose(sv.vectors, m.training_vectors_, atol=1e-12)
    means = to_curves(sv.vectors).mean(axis=1)
    assert np.all((means[:, [0, 2]] > -np.pi) & (means[:, [0, 2]] <= np.pi))
    turned = np.flatnonzero(np.any(sv.offsets != 0, axis=1))
    assert turned.size >= 1  # the real data do need the shift
    np.testing.assert_allclose(np.round(sv.offsets / TWO_PI) * TWO_PI, sv.offsets, atol=1e-12)
    trial = trials[int(sv.trial[turned[0]])]
    t, rec, orig = m.reconstruct_movement(trial, return_original=True)
    assert t.size > 0.5 * trial.n_frames
    assert math.degrees(np.sqrt(np.mean((rec - orig) ** 2))) < 1.0
    _, rec_c = m.reconstruct_movement(trial, source="cluster")
    assert np.max(np.abs(rec_c - orig)) < np.pi


def test_amplitude_scales_the_primitive_to_the_segment() -> None:
    """Fitted on three curve shapes (with small noise), a segment 1.7 times as large as one
    of them is rebuilt as 1.7 times its primitive with ``amplitude=True``, as the
    primitive itself without."""
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 1.0, 100)
    shapes = np.stack(
        [
            np.concatenate([np.sin(np.pi * s), 0.5 * np.cos(np.pi * s), s - 0.5, 0 * s]),
            np.concatenate([0 * s, np.sin(2 * np.pi * s), 0 * s, 0.3 * np.cos(np.pi * s)]),
            np.concatenate([np.cos(np.pi * s), 0 * s, 0.4 * np.sin(3 * np.pi * s), s - 0.5]),
        ]
    )
    train = np.repeat(shapes, 20, axis=0) + rng.normal(0.0, 0.01, (60, 400))
    params = dict(features="zyz", n_components=10, n_clusters=3, seed=0)
    plain = PrimitiveModel(**params).fit(train)
    scaled = PrimitiveModel(amplitude=True, **params).fit(train)
    segment = 1.7 * shapes[1:2]
    want = to_curves(segment, 4)
    got = scaled.reconstruct(segment, source="cluster")
    np.testing.assert_allclose(got, want, atol=0.02)
    np.testing.assert_allclose(plain.reconstruct(segment, source="cluster"), want / 1.7, atol=0.02)
    # The projection itself is not scaled.
    np.testing.assert_array_equal(
        scaled.reconstruct(segment), plain.reconstruct(segment, source="projection")
    )
    with pytest.raises(ValueError, match="amplitude"):
        PrimitiveModel(amplitude=True, offsets="turns").fit(train)
