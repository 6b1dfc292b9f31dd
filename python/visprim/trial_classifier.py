"""Classifying whole trials by the primitives they are made of.

A :class:`~visprim.model.PrimitiveModel` turns a trial into the sequence of its segments'
nearest primitives (:func:`visprim.classify.classify_trials`). Its *histogram* — how many
segments went to each primitive — is the trial's feature vector here, and a small supervised
classifier on these vectors labels whole trials:

* ``method="centroid"`` (default): nearest class centroid (Euclidean) of the histograms;
* ``method="logistic"``: L2-regularised logistic regression (scikit-learn).

``features="counts"`` (default) uses the raw counts (so the number of segments counts, e.g.
a wave has many back-and-forth segments, a raise has two); ``"frequencies"`` divides each
histogram by its trial's number of segments.

:class:`PrimitiveHistogramClassifier` learns both stages from labelled trials: ``fit`` learns
the primitives (unsupervised) and the classifier from the same training trials only, so in a
cross-validation the held-out trials are never seen, not even unlabelled.
:func:`leave_one_group_out` runs that cross-validation; :func:`bandai_wave_vs_raise` gives the
labels ("wave" / "raise", from ``Trial.meta["content"]``) and groups (the performance style)
of Bandai-Namco trials read by :mod:`visprim.io`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import LogisticRegression
from sklearn.neighbors import NearestCentroid

from visprim.trial import Trial

METHODS: tuple[str, ...] = ("centroid", "logistic")
FEATURES: tuple[str, ...] = ("counts", "frequencies")


def primitive_histograms(
    model: Any, trials: Sequence[Trial], *, features: str = "counts"
) -> NDArray[np.float64]:
    """(n_trials, k) histogram of each trial's segment primitives under a fitted ``model``.

    ``features="frequencies"`` normalises each row by its number of segments (rows of trials
    without segments stay zero).
    """
    from visprim.classify import classify_trials

    if features not in FEATURES:
        raise ValueError(f"features must be one of {', '.join(FEATURES)}, got {features!r}")
    rows = np.array([c.histogram for c in classify_trials(model, list(trials))], dtype=float)
    if features == "frequencies":
        total = rows.sum(axis=1, keepdims=True)
        rows = np.divide(rows, total, out=np.zeros_like(rows), where=total > 0)
    return rows


class PrimitiveHistogramClassifier(ClassifierMixin, BaseEstimator):
    """Primitives (PrimitiveModel) + a classifier of their per-trial histograms.

    Parameters
    ----------
    model_params : dict, optional
        Keyword arguments of :class:`~visprim.model.PrimitiveModel` (e.g. ``n_clusters``).
    method : {"centroid", "logistic"}
        Classifier on the histograms (see the module docstring).
    features : {"counts", "frequencies"}
        Raw segment counts per primitive, or their fractions.
    C : float
        Inverse regularisation strength of the logistic regression.

    Attributes (after ``fit``)
    --------------------------
    model_ : the fitted PrimitiveModel.
    classifier_ : the fitted scikit-learn classifier.
    classes_ : (n_classes,) the labels seen in ``fit``.
    """

    def __init__(
        self,
        model_params: Mapping[str, Any] | None = None,
        method: str = "centroid",
        features: str = "counts",
        C: float = 1.0,
    ) -> None:
        self.model_params = model_params
        self.method = method
        self.features = features
        self.C = C

    def _histograms(self, trials: Sequence[Trial]) -> NDArray[np.float64]:
        return primitive_histograms(self.model_, trials, features=self.features)

    def fit(self, trials: Sequence[Trial], y: Sequence[Any]) -> PrimitiveHistogramClassifier:
        """Learn the primitives from ``trials`` and the classifier from their labels ``y``."""
        from visprim.model import PrimitiveModel

        if self.method not in METHODS:
            raise ValueError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        if self.features not in FEATURES:
            raise ValueError(
                f"features must be one of {', '.join(FEATURES)}, got {self.features!r}"
            )
        trials = list(trials)
        labels = np.asarray(list(y))
        if len(trials) != labels.shape[0]:
            raise ValueError(f"fit: {len(trials)} trials but {labels.shape[0]} labels")
        if np.unique(labels).size < 2:
            raise ValueError("fit: the training trials need at least two different labels")
        self.model_ = PrimitiveModel(**dict(self.model_params or {})).fit(trials)
        h = self._histograms(trials)
        if self.method == "centroid":
            clf: Any = NearestCentroid()
        else:
            clf = LogisticRegression(C=float(self.C), max_iter=1000)
        self.classifier_ = clf.fit(h, labels)
        self.classes_ = self.classifier_.classes_
        return self

    def predict(self, trials: Sequence[Trial]) -> NDArray[Any]:
        """Label of each trial."""
        if not hasattr(self, "classifier_"):
            raise NotFittedError("PrimitiveHistogramClassifier is not fitted; call fit first")
        return np.asarray(self.classifier_.predict(self._histograms(list(trials))))


@dataclass(frozen=True)
class GroupCrossValidation:
    """Result of :func:`leave_one_group_out`.

    Attributes
    ----------
    accuracy : float — fraction of trials whose held-out prediction equals their label.
    predictions, labels, groups : (n,) arrays, in the order of the trials given.
    per_group : dict group → accuracy on that group's trials.
    """

    accuracy: float
    predictions: NDArray[Any]
    labels: NDArray[Any]
    groups: NDArray[Any]
    per_group: dict[Any, float]

    def __str__(self) -> str:
        n = self.labels.shape[0]
        right = int(np.sum(self.predictions == self.labels))
        lines = [f"leave-one-group-out accuracy {self.accuracy:.3f} ({right}/{n} trials)"]
        for g, acc in self.per_group.items():
            m = self.groups == g
            hits = int(np.sum(self.predictions[m] == self.labels[m]))
            lines.append(f"  {g}: {acc:.2f} ({hits}/{int(m.sum())})")
        return "\n".join(lines)


def leave_one_group_out(
    make_classifier: Callable[[], PrimitiveHistogramClassifier],
    trials: Sequence[Trial],
    labels: Sequence[Any],
    groups: Sequence[Any],
) -> GroupCrossValidation:
    """Train on all groups but one, predict the held-out group; every group in turn.

    ``make_classifier()`` returns a fresh, unfitted classifier for each fold (primitives
    and classifier are learned from the training groups only).
    """
    trials = list(trials)
    y = np.asarray(list(labels))
    g = np.asarray(list(groups))
    if not (len(trials) == y.shape[0] == g.shape[0]):
        raise ValueError(
            f"{len(trials)} trials, {y.shape[0]} labels and {g.shape[0]} groups must match"
        )
    order = list(dict.fromkeys(g.tolist()))
    if len(order) < 2:
        raise ValueError("leave-one-group-out needs at least two groups")
    pred = np.empty(y.shape[0], dtype=y.dtype)
    for group in order:
        test = g == group
        train = ~test
        clf = make_classifier().fit([t for t, m in zip(trials, train, strict=True) if m], y[train])
        pred[test] = clf.predict([t for t, m in zip(trials, test, strict=True) if m])
    per_group = {grp: float(np.mean(pred[g == grp] == y[g == grp])) for grp in order}
    return GroupCrossValidation(
        accuracy=float(np.mean(pred == y)),
        predictions=pred,
        labels=y,
        groups=g,
        per_group=per_group,
    )


def bandai_wave_vs_raise(trials: Sequence[Trial]) -> tuple[list[Trial], list[str], list[str]]:
    """The Bandai-Namco wave / raise trials among ``trials``, their labels and styles.

    Uses ``Trial.meta["content"]`` (``wave-right-hand``, ``raise-up-both-hands``, ...) and
    ``Trial.meta["style"]`` as set by :func:`visprim.io.read` from the file names. Raises
    ``ValueError`` if none is found.
    """
    keep, labels, styles = [], [], []
    for t in trials:
        content = str(t.meta.get("content", ""))
        if content.startswith("wave"):
            label = "wave"
        elif content.startswith("raise"):
            label = "raise"
        else:
            continue
        keep.append(t)
        labels.append(label)
        styles.append(str(t.meta.get("style", "")))
    if not keep:
        raise ValueError("no Bandai wave/raise trials (meta['content']) among the trials given")
    return keep, labels, styles
