"""Error analysis of the primitives (paper §6, Tables 1–3).

All errors are *mean squared errors per segment vector*: the squared Euclidean distance
between a 400-D segment vector ``s`` (radians, see :mod:`visprim.vectors`) and an
approximation of it, averaged over the N training segments (units rad²).

* **Projection error** (Table 1), for ``f`` eigenvectors: ``mean ‖s − (E_f p + s̄)‖²``.
  With the covariance divisor N it equals the sum of the dropped eigenvalues
  ``Σ_{i>f} λ_i`` exactly; the table reports both (they agree to rounding). The eigenvalues
  of a covariance are ≥ 0, but the eigensolver returns those of a rank-deficient K (fewer
  segments than dimensions) as ±rounding (~1e-16 · trace K each); the sum uses
  :func:`clipped_eigenvalues`, which sets negatives no larger in magnitude than
  :data:`NEGATIVE_EIGENVALUE_TOLERANCE` · trace K to 0 and refuses (``ValueError``) larger
  negatives, which no covariance can have (a damaged model, a basis of something else).
  "Variance kept" uses the same clipped eigenvalues.
* **Clustering error** (Table 2), for ``k`` clusters in the f-D projection space:
  ``mean ‖p − c_{label(p)}‖²`` (k-means inertia / N).
* **Total error** (Table 3): ``mean ‖s − (E_f c_{label} + s̄)‖²``, the error of
  reconstructing each segment from its cluster centre. Because the projection residual
  ``s − ŝ`` is orthogonal to the span of ``E_f`` and ``ŝ − (E_f c + s̄) = E_f (p − c)`` lies in
  it, total = projection + clustering (Pythagoras); the table reports the measured total
  and the sum.
* **Angular error**: ``sqrt(MSE / d)`` converted to degrees, with ``d = 4 n`` the vector
  dimension (400): the RMS error of one angle sample.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from visprim import kernels
from visprim.pca import PCABasis

#: Table 1 rows: numbers of eigenvectors (clipped to the vector dimension).
DEFAULT_F_VALUES: tuple[int, ...] = (10, 20, 30, 40, 50, 60, 80, 100)
#: Table 2/3 rows: numbers of clusters (clipped to the number of segments).
DEFAULT_K_VALUES: tuple[int, ...] = (10, 20, 30, 100, 170)


def angular_error_deg(mse: float, dim: int) -> float:
    """RMS angle error in degrees from a mean squared vector error ``mse`` (rad²) in ``dim``
    dimensions: ``degrees(sqrt(mse / dim))``."""
    if dim < 1:
        raise ValueError(f"dim must be >= 1, got {dim}")
    return math.degrees(math.sqrt(max(float(mse), 0.0) / dim))


def mean_squared_distance(a: ArrayLike, b: ArrayLike) -> float:
    """``mean_i ‖a_i − b_i‖²`` over rows of two (N, d) arrays."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"shapes differ: {a.shape} vs {b.shape}")
    diff = a - b
    return float(np.einsum("ij,ij->", diff, diff) / max(a.shape[0], 1))


#: Relative tolerance of :func:`clipped_eigenvalues`: negatives down to this fraction of
#: trace K are rounding and count as 0; below it they are an error.
NEGATIVE_EIGENVALUE_TOLERANCE = 1e-9


def clipped_eigenvalues(eigenvalues: ArrayLike) -> NDArray[np.float64]:
    """Eigenvalues of a covariance matrix (rad²) with rounding negatives set to 0.

    A covariance is positive semi-definite, so an eigenvalue ``λ_i < 0`` is rounding when
    ``λ_i ≥ −tol`` with ``tol = NEGATIVE_EIGENVALUE_TOLERANCE · Σ_j |λ_j|`` (``Σ |λ_j|``
    equals trace K for a PSD matrix and is never negative); it is set to 0.

    Raises
    ------
    ValueError
        An eigenvalue below ``−tol`` (not the spectrum of a covariance) or a non-finite one.
    """
    w = np.array(eigenvalues, dtype=np.float64, copy=True).reshape(-1)
    if not np.all(np.isfinite(w)):
        raise ValueError("eigenvalues contain NaN or infinity")
    tol = NEGATIVE_EIGENVALUE_TOLERANCE * float(np.sum(np.abs(w)))
    low = w < -tol
    if np.any(low):
        i = int(np.argmin(w))
        raise ValueError(
            f"eigenvalue {i} is {w[i]:.6g}, below -{NEGATIVE_EIGENVALUE_TOLERANCE:g} x trace "
            f"= {-tol:.6g}: a covariance matrix has no such negative eigenvalue ({int(low.sum())} "
            "of them; the model or basis is damaged or not a PCA)"
        )
    np.maximum(w, 0.0, out=w)
    return w


def projection_error(basis: PCABasis, f: int) -> float:
    """Projection error of ``f`` eigenvectors: the sum of the dropped eigenvalues (rad²),
    rounding negatives counted as 0 (:func:`clipped_eigenvalues`)."""
    w = clipped_eigenvalues(basis.eigenvalues)
    if not 0 <= int(f) <= w.shape[0]:
        raise ValueError(f"f must be in [0, {w.shape[0]}], got {f}")
    return float(np.sum(w[int(f) :]))


def variance_kept(basis: PCABasis, f: int) -> float:
    """Fraction of the total variance kept by the first ``f`` eigenvectors, from the clipped
    eigenvalues (1 when the total variance is 0)."""
    w = clipped_eigenvalues(basis.eigenvalues)
    total = float(np.sum(w))
    if total <= 0.0:
        return 1.0
    return 1.0 - projection_error(basis, f) / total


def measured_projection_error(basis: PCABasis, vectors: ArrayLike, f: int) -> float:
    """``mean ‖s − (E_f E_fᵀ (s − s̄) + s̄)‖²`` measured on ``vectors`` (rad²)."""
    x = np.asarray(vectors, dtype=np.float64)
    return mean_squared_distance(x, basis.reconstruct(basis.project(x, f)))


def clustering_error(projections: ArrayLike, centers: ArrayLike, labels: ArrayLike) -> float:
    """``mean ‖p − c_label‖²`` in the projection space (rad²)."""
    c = np.asarray(centers, dtype=np.float64)
    return mean_squared_distance(projections, c[np.asarray(labels, dtype=np.int64)])


def total_error(
    basis: PCABasis, vectors: ArrayLike, centers: ArrayLike, labels: ArrayLike
) -> float:
    """``mean ‖s − (E_f c_label + s̄)‖²`` (rad²); ``f`` is the width of ``centers``."""
    c = np.asarray(centers, dtype=np.float64)
    recon = basis.reconstruct(c[np.asarray(labels, dtype=np.int64)])
    return mean_squared_distance(vectors, recon)


@dataclass(frozen=True)
class ErrorTable:
    """One table: a title, column names and rows of numbers (see :mod:`visprim.accuracy`)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[float, ...], ...]
    notes: tuple[str, ...] = ()

    def column(self, name: str) -> NDArray[np.float64]:
        """The values of one column."""
        j = self.columns.index(name)
        return np.array([r[j] for r in self.rows], dtype=np.float64)

    def to_markdown(self) -> str:
        """A GitHub-flavoured Markdown table with its title and notes."""
        lines = [f"**{self.title}**", ""]
        lines.append("| " + " | ".join(self.columns) + " |")
        lines.append("|" + "|".join("---:" for _ in self.columns) + "|")
        for row in self.rows:
            lines.append("| " + " | ".join(_fmt(v) for v in row) + " |")
        for note in self.notes:
            lines.append("")
            lines.append(note)
        return "\n".join(lines) + "\n"

    def to_csv(self) -> str:
        """CSV text: a header line of column names, one line per row (full precision)."""
        from visprim.csvfile import csv_text

        return csv_text(
            self.columns,
            ([repr(float(v)) if not _is_int(v) else str(int(v)) for v in row] for row in self.rows),
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (used by the model file)."""
        return {
            "title": self.title,
            "columns": list(self.columns),
            "rows": [[float(v) for v in r] for r in self.rows],
            "notes": list(self.notes),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ErrorTable:
        """Inverse of :meth:`to_dict`."""
        return cls(
            title=str(d["title"]),
            columns=tuple(str(c) for c in d["columns"]),
            rows=tuple(tuple(float(v) for v in r) for r in d["rows"]),
            notes=tuple(str(n) for n in d.get("notes", ())),
        )


def _is_int(v: float) -> bool:
    return float(v).is_integer() and abs(v) < 2**53


def _fmt(v: float) -> str:
    if _is_int(v):
        return str(int(v))
    if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5):
        return f"{v:.3e}"
    return f"{v:.4f}"


@dataclass(frozen=True)
class ErrorTables:
    """Tables 1–3 of the paper for one fitted model.

    ``projection`` (Table 1) has one row per number of eigenvectors; ``clustering``
    (Table 2) and ``total`` (Table 3) one row per number of clusters, at the model's number
    of eigenvectors ``f``.
    """

    projection: ErrorTable
    clustering: ErrorTable
    total: ErrorTable
    meta: dict[str, Any] = field(default_factory=dict)

    def __iter__(self) -> Iterator[ErrorTable]:
        return iter((self.projection, self.clustering, self.total))

    def to_markdown(self) -> str:
        """All three tables as Markdown."""
        return "\n".join(t.to_markdown() for t in self)

    def __str__(self) -> str:
        return self.to_markdown()

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (used by the model file)."""
        return {
            "projection": self.projection.to_dict(),
            "clustering": self.clustering.to_dict(),
            "total": self.total.to_dict(),
            "meta": dict(self.meta),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> ErrorTables:
        """Inverse of :meth:`to_dict`."""
        return cls(
            projection=ErrorTable.from_dict(d["projection"]),
            clustering=ErrorTable.from_dict(d["clustering"]),
            total=ErrorTable.from_dict(d["total"]),
            meta=dict(d.get("meta", {})),
        )


def compute_error_tables(
    basis: PCABasis,
    vectors: ArrayLike,
    n_components: int,
    *,
    f_values: Sequence[int] = DEFAULT_F_VALUES,
    k_values: Sequence[int] = DEFAULT_K_VALUES,
    n_init: int = 10,
    max_iter: int = 300,
    tol: float = 1e-4,
    seed: int = 0,
    known: dict[int, tuple[NDArray[np.float64], NDArray[np.int64]]] | None = None,
) -> ErrorTables:
    """Compute Tables 1–3 on the training vectors.

    Parameters
    ----------
    basis : PCABasis
        PCA of ``vectors``.
    vectors : (N, d) array, radians
        The segment vectors the basis was fitted on.
    n_components : int
        ``f`` used for Tables 2 and 3.
    f_values, k_values : sequences of int
        Rows of Table 1 (clipped to d) and Tables 2–3 (clipped to N; duplicates after
        clipping are dropped and noted).
    n_init, max_iter, tol, seed
        k-means settings (:func:`visprim.kernels.kmeans`) for each k.
    known : dict, optional
        ``{k: (centers, labels)}`` already computed (e.g. the model's own clustering).
    """
    x = np.ascontiguousarray(vectors, dtype=np.float64)
    n, d = x.shape
    f = int(n_components)
    notes1: list[str] = []
    rows1 = []
    fs = sorted({min(int(v), d) for v in f_values if int(v) >= 1})
    if any(int(v) > d for v in f_values):
        notes1.append(f"Numbers of eigenvectors above the dimension d = {d} were clipped to d.")
    for fv in fs:
        mse = projection_error(basis, fv)
        measured = measured_projection_error(basis, x, fv)
        rows1.append(
            (
                fv,
                mse,
                measured,
                100.0 * variance_kept(basis, fv),
                angular_error_deg(mse, d),
            )
        )
    table1 = ErrorTable(
        title=f"Table 1: projection error vs number of eigenvectors (N = {n} segments, d = {d})",
        columns=(
            "eigenvectors f",
            "sum of dropped eigenvalues (rad^2)",
            "measured projection MSE (rad^2)",
            "variance kept (%)",
            "angular error (deg)",
        ),
        rows=tuple(rows1),
        notes=tuple(notes1),
    )

    p = basis.project(x, f)
    proj_mse = projection_error(basis, f)
    known = dict(known or {})
    ks: list[tuple[int, int]] = []
    seen = set()
    for kv in k_values:
        used = min(int(kv), n)
        if used < 1 or used in seen:
            continue
        seen.add(used)
        ks.append((int(kv), used))
    notes2 = []
    if any(req != used for req, used in ks):
        notes2.append(
            f"Numbers of clusters above the number of segments N = {n} were clipped to N."
        )
    rows2, rows3 = [], []
    for _req, k in ks:
        if k in known:
            centers, labels = known[k]
        else:
            res = kernels.kmeans(p, k, n_init=n_init, max_iter=max_iter, tol=tol, seed=seed)
            centers, labels = np.asarray(res.centers), np.asarray(res.labels)
        clu = clustering_error(p, centers, labels)
        tot = total_error(basis, x, centers, labels)
        rows2.append((k, clu, angular_error_deg(clu, d)))
        rows3.append((k, proj_mse, clu, proj_mse + clu, tot, angular_error_deg(tot, d)))
    table2 = ErrorTable(
        title=f"Table 2: clustering error vs number of clusters (f = {f} eigenvectors)",
        columns=("clusters k", "clustering MSE (rad^2)", "angular error (deg)"),
        rows=tuple(rows2),
        notes=tuple(notes2),
    )
    table3 = ErrorTable(
        title=f"Table 3: total error vs number of clusters (f = {f} eigenvectors)",
        columns=(
            "clusters k",
            "projection MSE (rad^2)",
            "clustering MSE (rad^2)",
            "projection + clustering (rad^2)",
            "measured total MSE (rad^2)",
            "angular error (deg)",
        ),
        rows=tuple(rows3),
        notes=tuple(notes2),
    )
    return ErrorTables(
        projection=table1,
        clustering=table2,
        total=table3,
        meta={"n_segments": n, "dim": d, "n_components": f},
    )
