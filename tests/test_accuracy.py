"""Error analysis (Tables 1-3): the identities of the paper on real fits, and the formats."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
from _pipeline_data import fitted
from visprim.accuracy import (
    NEGATIVE_EIGENVALUE_TOLERANCE,
    ErrorTables,
    angular_error_deg,
    clipped_eigenvalues,
    clustering_error,
    compute_error_tables,
    measured_projection_error,
    total_error,
)
from visprim.pca import PCABasis, fit_pca


@pytest.fixture(scope="module", params=["seg2", "seg1"])
def model(request):
    return fitted(request.param)


@pytest.fixture(scope="module")
def tables(model):
    return model.error_table()


def test_angular_error_definition():
    # 1 degree on every one of the 400 samples: MSE = 400 (pi/180)^2.
    assert angular_error_deg(400 * math.radians(1.0) ** 2, 400) == pytest.approx(1.0)
    assert angular_error_deg(0.0, 400) == 0.0
    assert angular_error_deg(4.0, 1) == pytest.approx(math.degrees(2.0))


def test_projection_error_is_the_sum_of_dropped_eigenvalues(model, tables):
    x = model.training_vectors_
    b = model.basis_
    for f in (1, 10, 30, 45):
        dropped = float(np.sum(model.eigenvalues_[f:]))
        measured = measured_projection_error(b, x, f)
        assert measured == pytest.approx(dropped, rel=1e-9, abs=1e-12)
    t1 = tables.projection
    np.testing.assert_allclose(
        t1.column("measured projection MSE (rad^2)"),
        t1.column("sum of dropped eigenvalues (rad^2)"),
        rtol=1e-8,
        atol=1e-12,
    )
    assert list(t1.column("eigenvectors f")) == [10, 20, 30, 40, 50, 60, 80, 100]
    assert np.all(np.diff(t1.column("sum of dropped eigenvalues (rad^2)")) <= 0)


def test_total_is_projection_plus_clustering(model, tables):
    """The residual of the projection is orthogonal to the span of E_f, so squared errors
    add (Pythagoras), per vector and on average."""
    x = model.training_vectors_
    b = model.basis_
    p = model.transform(x)
    f = model.n_components
    proj = measured_projection_error(b, x, f)
    clu = clustering_error(p, model.cluster_centers_, model.labels_)
    tot = total_error(b, x, model.cluster_centers_, model.labels_)
    assert tot == pytest.approx(proj + clu, rel=1e-9)
    # Per vector too.
    resid = x - b.reconstruct(p)
    per_vec_proj = np.sum(resid**2, axis=1)
    per_vec_clu = np.sum((p - model.cluster_centers_[model.labels_]) ** 2, axis=1)
    per_vec_tot = np.sum((x - b.reconstruct(model.cluster_centers_[model.labels_])) ** 2, axis=1)
    np.testing.assert_allclose(per_vec_tot, per_vec_proj + per_vec_clu, rtol=1e-8, atol=1e-12)
    # The clustering error is the k-means inertia per segment.
    assert clu == pytest.approx(model.inertia_ / x.shape[0], rel=1e-9)
    t3 = tables.total
    np.testing.assert_allclose(
        t3.column("measured total MSE (rad^2)"),
        t3.column("projection + clustering (rad^2)"),
        rtol=1e-9,
    )
    np.testing.assert_allclose(
        t3.column("clustering MSE (rad^2)"), tables.clustering.column("clustering MSE (rad^2)")
    )


def test_clustering_error_falls_with_k(tables):
    t2 = tables.clustering
    assert list(t2.column("clusters k")) == [10, 20, 30, 100, 170]
    assert np.all(np.diff(t2.column("clustering MSE (rad^2)")) < 0)
    np.testing.assert_allclose(
        t2.column("angular error (deg)"),
        np.degrees(np.sqrt(t2.column("clustering MSE (rad^2)") / 400)),
    )


def test_k_is_clipped_to_the_number_of_segments():
    m = fitted()
    n = m.n_training_segments_
    t = m.error_table(f_values=(5, 1000), k_values=(10, n + 5, n + 50))
    assert list(t.clustering.column("clusters k")) == [10, n]
    assert any("clipped" in note for note in t.clustering.notes)
    assert list(t.projection.column("eigenvectors f")) == [5, 400]
    # At k = N every segment is its own centre: no clustering error.
    assert t.clustering.rows[-1][1] == pytest.approx(0.0, abs=1e-18)


def test_markdown_csv_and_dict_round_trip(tables):
    md = tables.to_markdown()
    assert md.count("**Table") == 3
    assert "| eigenvectors f |" in md
    rows = list(csv.reader(io.StringIO(tables.total.to_csv())))
    assert rows[0] == list(tables.total.columns)
    assert [float(v) for v in rows[1]] == pytest.approx(list(tables.total.rows[0]))
    again = ErrorTables.from_dict(tables.to_dict())
    assert again.to_markdown() == md


def test_rounding_negative_eigenvalues_count_as_zero_and_real_negatives_are_refused():
    w = np.array([3.0, 1.0, 1e-15, -1e-14, -2e-13])
    np.testing.assert_array_equal(clipped_eigenvalues(w), [3.0, 1.0, 1e-15, 0.0, 0.0])
    assert w[-1] == -2e-13  # the input is not modified
    # The tolerance is relative to the trace (sum of |eigenvalues|, 4 here).
    edge = -NEGATIVE_EIGENVALUE_TOLERANCE * 4.0 * 0.99
    assert clipped_eigenvalues([3.0, 1.0, edge])[-1] == 0.0
    with pytest.raises(ValueError, match=r"eigenvalue 2 is -0\.001.*covariance"):
        clipped_eigenvalues([3.0, 1.0, -1e-3])
    with pytest.raises(ValueError, match="NaN"):
        clipped_eigenvalues([1.0, np.nan])


def _small_corpus_basis():
    """PCA of 6 vectors in 40-D: rank 5, so eigenvalues 5.. are rounding around 0."""
    rng = np.random.default_rng(4)
    x = rng.normal(size=(6, 40)) @ np.diag(np.linspace(2.0, 0.1, 40))
    return x, fit_pca(x)


def test_table1_of_a_small_corpus_has_no_negative_dropped_sum():
    x, b = _small_corpus_basis()
    # The solver's eigenvalues beyond the rank are rounding of both signs; force a typical
    # case (trailing values negative, as seen on real corpora) to check the clipping.
    w = b.eigenvalues.copy()
    w[5:] = -np.abs(w[5:]) - 1e-15
    rounded = PCABasis(b.mean, w, b.eigenvectors, b.n_vectors)
    for basis in (b, rounded):
        t1 = compute_error_tables(basis, x, 3, f_values=(2, 5, 10, 40), k_values=(2,)).projection
        dropped = t1.column("sum of dropped eigenvalues (rad^2)")
        measured = t1.column("measured projection MSE (rad^2)")
        assert np.all(dropped >= 0.0)
        np.testing.assert_allclose(dropped, measured, rtol=1e-8, atol=1e-12)
        assert np.all(t1.column("variance kept (%)") <= 100.0)
    t1 = compute_error_tables(rounded, x, 3, f_values=(5, 10, 40), k_values=(2,)).projection
    np.testing.assert_array_equal(t1.column("sum of dropped eigenvalues (rad^2)"), 0.0)
    np.testing.assert_array_equal(t1.column("variance kept (%)"), 100.0)


def test_a_genuinely_negative_eigenvalue_is_an_error_not_a_table():
    x, b = _small_corpus_basis()
    w = b.eigenvalues.copy()
    w[-1] = -1e-6 * float(np.sum(w))
    bad = PCABasis(b.mean, w, b.eigenvectors, b.n_vectors)
    with pytest.raises(ValueError, match="eigenvalue 39 is"):
        compute_error_tables(bad, x, 3, f_values=(10,), k_values=(2,))
