"""Classification of segments and trials by primitives (visprim.classify)."""

from __future__ import annotations

import numpy as np
import pytest
from _pipeline_data import default_trials, fitted, n_true_strokes
from sklearn.metrics import adjusted_rand_score
from visprim.classify import classify_trials, match_strokes, purity, score_against_truth


def test_match_strokes_by_largest_overlap():
    boundaries = np.array([1.0, 2.0, 3.0, 4.0])
    labels = np.array([7, 8, 9])
    segments = np.array(
        [
            [1.0, 2.0],  # exactly stroke 0
            [1.9, 3.05],  # mostly stroke 1
            [2.8, 3.9],  # mostly stroke 2
            [0.0, 0.9],  # before every stroke
            [3.5, 6.0],  # overlaps stroke 2 only a little, but only it
        ]
    )
    np.testing.assert_array_equal(match_strokes(segments, boundaries, labels), [7, 8, 9, -1, 9])
    assert match_strokes(np.zeros((0, 2)), boundaries, labels).size == 0
    with pytest.raises(ValueError, match="boundaries"):
        match_strokes(segments, boundaries, labels[:2])


def test_purity_known_answers():
    assert purity([0, 0, 1, 1], [5, 5, 6, 6]) == 1.0
    # cluster 0 = {a, a, b} -> 2, cluster 1 = {b} -> 1: 3 of 4.
    assert purity([0, 0, 0, 1], [1, 1, 2, 2]) == 0.75
    # One cluster for everything: the majority share.
    assert purity([3, 3, 3, 3, 3], [1, 1, 1, 2, 2]) == pytest.approx(0.6)
    with pytest.raises(ValueError, match="empty"):
        purity([], [])


def test_classify_trials_sequences_and_histograms():
    m = fitted()
    trials = list(default_trials()[:5])
    results = classify_trials(m, trials)
    assert [r.name for r in results] == [t.name for t in trials]
    all_labels = np.concatenate([r.primitives for r in results])
    np.testing.assert_array_equal(all_labels, m.predict(trials))
    for r in results:
        assert r.histogram.shape == (m.n_primitives,)
        assert r.histogram.sum() == len(r.sequence) == r.segments.shape[0]
        assert np.all(np.diff(r.segments[:, 0]) > 0)
        assert np.all(r.distances >= 0)
        assert r.labels is r.primitives  # the former name still works


@pytest.mark.parametrize(
    ("segmentation", "min_ari", "min_purity"), [("seg1", 0.95, 0.95), ("seg2", 0.9, 0.95)]
)
def test_primitives_recover_the_true_strokes(segmentation, min_ari, min_purity):
    """At k = number of true stroke primitives, segment labels agree with the true stroke
    labels far beyond chance (ARI 0 is chance)."""
    k = n_true_strokes()
    m = fitted(segmentation, k)
    trials = list(default_trials())
    s = score_against_truth(m, trials)
    assert s.n_primitives == k
    assert s.n_segments > 300
    assert s.ari >= min_ari, str(s)
    assert s.purity >= min_purity, str(s)
    # Cross-check the ARI with an independent computation on the same matching.
    results = classify_trials(m, trials)
    pred = np.concatenate([r.primitives for r in results])
    true = np.concatenate(
        [
            match_strokes(r.segments, t.truth.boundaries, t.truth.labels)
            for r, t in zip(results, trials, strict=True)
        ]
    )
    keep = true >= 0
    assert s.ari == pytest.approx(adjusted_rand_score(true[keep], pred[keep]))


def test_scoring_needs_truth():
    m = fitted()
    t = default_trials()[0]
    from dataclasses import replace

    bare = replace(t, truth=None)
    with pytest.raises(ValueError, match="truth"):
        score_against_truth(m, [bare])
