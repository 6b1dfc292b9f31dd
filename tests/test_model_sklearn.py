"""PrimitiveModel as a scikit-learn estimator: estimator checks, transformer / clusterer
behaviour, score for GridSearchCV, fitting on segment vectors, numpydoc docstrings."""

from __future__ import annotations

import inspect
import warnings

import numpy as np
import pytest
from sklearn.base import ClusterMixin, TransformerMixin, is_clusterer
from sklearn.model_selection import GridSearchCV
from sklearn.utils.estimator_checks import check_estimator
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment

#: Checks of scikit-learn that do not apply, with the reason. Everything else must pass.
SKIPPED_CHECKS = {
    "check_array_api_input": "visprim's kernels compute on NumPy float64 arrays in Rust; "
    "other array-API namespaces (CuPy, torch) are not supported",
}

#: The checks generate data with 1 to 10 features and a few dozen rows, so the instance
#: they run on keeps f and k small (the defaults, f = k = 30, need larger data).
CHECKED = PrimitiveModel(n_components=1, n_clusters=2, n_init=1)


def test_estimator_checks_pass() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = check_estimator(CHECKED, expected_failed_checks=SKIPPED_CHECKS, on_fail=None)
    failed = [
        (r["check_name"], str(r["exception"])[:200]) for r in results if r["status"] == "failed"
    ]
    assert not failed, failed
    names = {r["check_name"] for r in results}
    passed = {r["check_name"] for r in results if r["status"] == "passed"}
    # The skip list names real checks, and the core ones ran and passed.
    assert set(SKIPPED_CHECKS) <= names
    for core in (
        "check_transformer_general",
        "check_clustering",
        "check_fit_idempotent",
        "check_n_features_in",
        "check_estimators_nan_inf",
        "check_methods_subset_invariance",
        "check_estimators_pickle",
    ):
        assert core in passed, core
    assert len(passed) >= 40


@pytest.fixture(scope="module")
def trials():
    return imitation_experiment(n_subjects=2, n_stimuli=6, seed=0)


def test_transformer_and_clusterer(trials) -> None:
    m = PrimitiveModel(n_components=6, n_clusters=4, n_init=2)
    assert isinstance(m, TransformerMixin) and isinstance(m, ClusterMixin) and is_clusterer(m)
    p = m.fit_transform(trials)
    np.testing.assert_allclose(p, m.transform(trials), atol=1e-10)
    labels = PrimitiveModel(n_components=6, n_clusters=4, n_init=2).fit_predict(trials)
    np.testing.assert_array_equal(labels, m.labels_)
    assert m.n_features_in_ == m.dim == m.n_channels * m.n_samples


def test_fit_on_segment_vectors_matches_fit_on_trials(trials) -> None:
    a = PrimitiveModel(n_components=6, n_clusters=4, n_init=2).fit(trials)
    b = PrimitiveModel(n_components=6, n_clusters=4, n_init=2).fit(a.training_vectors_)
    assert b.n_features_in_ == a.dim
    np.testing.assert_allclose(b.cluster_centers_, a.cluster_centers_, atol=1e-9)
    np.testing.assert_array_equal(b.predict(a.training_vectors_), a.labels_)
    assert np.all(np.isnan(b.primitive_durations_)) and np.all(b.segment_trial_ == -1)
    with pytest.raises(
        ValueError, match=f"X has 8 features, but PrimitiveModel is expecting {a.dim}"
    ):
        b.transform(np.zeros((3, 8)))


def test_score_is_minus_the_total_error(trials) -> None:
    m = PrimitiveModel(n_components=6, n_clusters=4, n_init=2).fit(trials)
    x = m.training_vectors_
    rebuilt = m.cluster_centers_[m.labels_] @ m.components_.T + m.mean_
    expected = -np.mean(np.sum((x - rebuilt) ** 2, axis=1))
    assert m.score(trials) == pytest.approx(expected, rel=1e-9)
    assert m.score(x) == pytest.approx(expected, rel=1e-9)
    # Table 3's total error at (f, k) of the model is the same number.
    total = m.error_table(f_values=(6,), k_values=(4,)).total
    assert -m.score(trials) == pytest.approx(
        total.column("measured total MSE (rad^2)")[0], rel=1e-6
    )


def test_grid_search_on_trials(trials) -> None:
    grid = GridSearchCV(
        PrimitiveModel(n_components=4, n_init=1), {"n_clusters": [2, 6]}, cv=2, error_score="raise"
    )
    grid.fit(trials)
    # More primitives rebuild held-out segments better.
    assert grid.best_params_ == {"n_clusters": 6}
    assert np.all(np.isfinite(grid.cv_results_["mean_test_score"]))


@pytest.mark.parametrize(
    "method", ["fit", "transform", "predict", "score", "fit_transform", "fit_predict"]
)
def test_numpydoc_sections_match_the_signature(method) -> None:
    from numpydoc.docscrape import FunctionDoc

    func = getattr(PrimitiveModel, method)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # unknown sections, bad formatting
        doc = FunctionDoc(func)
    documented = [name for p in doc["Parameters"] for name in p.name.replace("*", "").split(", ")]
    signature = [n for n in inspect.signature(func).parameters if n != "self"]
    assert documented == signature
    assert doc["Returns"], method


def test_class_docstring_sections() -> None:
    from numpydoc.docscrape import ClassDoc

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        doc = ClassDoc(PrimitiveModel)
    params = [name for p in doc["Parameters"] for name in p.name.split(", ")]
    assert params == list(inspect.signature(PrimitiveModel).parameters)
    attrs = {name for p in doc["Attributes"] for name in p.name.split(", ")}
    assert {"n_features_in_", "cluster_centers_", "labels_", "components_"} <= attrs
