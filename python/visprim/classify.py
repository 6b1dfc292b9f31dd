"""Classifying segments and whole movements by their primitives (paper §7).

Segments
--------
Each segment of a new movement goes to its nearest primitive (nearest cluster centre in the
f-D projection space, :meth:`~visprim.model.PrimitiveModel.assign`); a trial becomes the
*sequence* of its segments' primitives and the *histogram* of that sequence
(:func:`classify_trials`). On generated data (trials with :class:`~visprim.trial.Truth`) the
segment labels can be compared with the true strokes: each segment is matched to the true
stroke it overlaps most in time (:func:`match_strokes`), then :func:`score_against_truth`
reports the adjusted Rand index (chance-corrected agreement of the two partitions, 1 =
identical, ≈ 0 = chance) and the purity (fraction of segments whose primitive's majority
stroke label is their own).

Whole movements
---------------
* :class:`MotionClassifier` (scikit-learn classifier on trials): the movement re-expressed
  through the primitives' PCA basis, frame by frame, compared by dynamic time warping
  (1-nearest neighbour); see its docstring for the method and how it was chosen.
* :class:`DTWClassifier`: the baseline — 1-nearest neighbour with dynamic time warping on
  the upper-arm and forearm directions (:func:`arm_directions`).
* :class:`PrimitiveHistogramClassifier`: a classifier of the trials' primitive histograms
  (nearest centroid or logistic regression).

A movement is a :class:`~visprim.trial.Trial` of one arm or of both
(``visprim.io.read(path, arm="both")``); all movements given to one classifier have the
same arms. :func:`leave_one_group_out` cross-validates any of these classifiers.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from itertools import product
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import LogisticRegression
from sklearn.metrics import adjusted_rand_score
from sklearn.neighbors import NearestCentroid

from visprim import kernels, params
from visprim.features import from_angles, periodic_channels
from visprim.ik import implied_joint_centres
from visprim.model import PrimitiveModel
from visprim.trial import Trial
from visprim.vectors import to_curves, vectors_from_frames


@dataclass(frozen=True)
class TrialClassification:
    """The primitives of one trial.

    Attributes
    ----------
    name : str — the trial's name.
    segments : (n, 2) float array, seconds — the trial's segments (model's segmentation).
    primitives : (n,) int array — primitive index of each segment (a cluster of the model,
        not a class label), in time order (the *sequence*); ``labels`` is an alias kept for
        older code.
    distances : (n,) float array, radians — Euclidean distance of each segment's projection
        to its primitive's centre.
    n_primitives : int — number of primitives k of the model.
    """

    name: str
    segments: NDArray[np.float64]
    primitives: NDArray[np.int64]
    distances: NDArray[np.float64]
    n_primitives: int

    @property
    def labels(self) -> NDArray[np.int64]:
        """The same as :attr:`primitives` (its former name)."""
        return self.primitives

    @property
    def sequence(self) -> tuple[int, ...]:
        """The primitives in time order."""
        return tuple(int(v) for v in self.primitives)

    @property
    def histogram(self) -> NDArray[np.int64]:
        """(k,) number of segments assigned to each primitive."""
        return np.bincount(self.primitives, minlength=self.n_primitives).astype(np.int64)


def classify_trials(
    model: PrimitiveModel, trials: Sequence[Trial] | Trial
) -> list[TrialClassification]:
    """Segment ``trials`` with the model's (fitted) settings and give each segment its
    nearest primitive. Trials where no segment is found get empty sequences."""
    model._check_fitted()
    if isinstance(trials, Trial):
        trials = [trials]
    trials = list(trials)
    if not trials:
        raise ValueError("classify_trials: no trials given")
    corpus = model.prepare(trials)
    k = model.n_primitives
    if corpus.segmentation.n_segments == 0:
        labels = np.zeros(0, dtype=np.int64)
        dist = np.zeros(0)
        trial_of = np.zeros(0, dtype=np.int64)
        starts = ends = np.zeros(0)
    else:
        sv = model.vectorize(corpus)
        labels, dist = model.assign(model.transform(sv.vectors))
        trial_of, starts, ends = sv.trial, sv.starts, sv.ends
    out = []
    for i, name in enumerate(corpus.names):
        m = trial_of == i
        out.append(
            TrialClassification(
                name=name,
                segments=np.stack([starts[m], ends[m]], axis=1),
                primitives=labels[m],
                distances=dist[m],
                n_primitives=k,
            )
        )
    return out


def match_strokes(
    segments: ArrayLike, boundaries: ArrayLike, labels: ArrayLike
) -> NDArray[np.int64]:
    """True stroke label of each segment: the stroke it overlaps most in time.

    Parameters
    ----------
    segments : (n, 2) seconds — found segments.
    boundaries : (m + 1,) seconds — true stroke boundaries (start of the first stroke to
        the end of the last).
    labels : (m,) int — true label of each stroke.

    Returns
    -------
    (n,) int64: the label, or −1 for a segment overlapping no stroke.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2)
    b = np.asarray(boundaries, dtype=np.float64)
    lab = np.asarray(labels, dtype=np.int64)
    if b.ndim != 1 or lab.shape != (max(b.size - 1, 0),):
        raise ValueError(f"need boundaries (m + 1,) and labels (m,), got {b.shape} and {lab.shape}")
    if seg.shape[0] == 0 or lab.size == 0:
        return np.full(seg.shape[0], -1, dtype=np.int64)
    lo = np.maximum(seg[:, :1], b[None, :-1])
    hi = np.minimum(seg[:, 1:], b[None, 1:])
    overlap = np.clip(hi - lo, 0.0, None)
    best = np.argmax(overlap, axis=1)
    out = lab[best]
    out[overlap[np.arange(seg.shape[0]), best] <= 0] = -1
    return out


def purity(predicted: ArrayLike, truth: ArrayLike) -> float:
    """Fraction of items whose cluster's most frequent true label equals their own."""
    p = np.asarray(predicted, dtype=np.int64)
    t = np.asarray(truth, dtype=np.int64)
    if p.shape != t.shape or p.ndim != 1:
        raise ValueError(
            f"predicted and truth must be 1-D of equal length, got {p.shape}, {t.shape}"
        )
    if p.size == 0:
        raise ValueError("purity of an empty labelling is undefined")
    _, pi = np.unique(p, return_inverse=True)
    _, ti = np.unique(t, return_inverse=True)
    table = np.zeros((pi.max() + 1, ti.max() + 1), dtype=np.int64)
    np.add.at(table, (pi, ti), 1)
    return float(table.max(axis=1).sum() / p.size)


@dataclass(frozen=True)
class ClassificationScores:
    """Agreement of segment primitives with the true stroke labels.

    ``ari``: adjusted Rand index; ``purity``: see :func:`purity`; ``n_segments``: segments
    scored (matched to a stroke); ``n_unmatched``: segments overlapping no stroke (left
    out); ``n_primitives``: k; ``n_true_labels``: distinct true labels among the scored.
    """

    ari: float
    purity: float
    n_segments: int
    n_unmatched: int
    n_primitives: int
    n_true_labels: int

    def __str__(self) -> str:
        return (
            f"ARI {self.ari:.3f}, purity {self.purity:.3f} over {self.n_segments} segments "
            f"(k = {self.n_primitives}, {self.n_true_labels} true stroke labels; "
            f"{self.n_unmatched} segments outside every stroke left out)"
        )


def score_against_truth(
    model: PrimitiveModel,
    trials: Sequence[Trial],
    classifications: Sequence[TrialClassification] | None = None,
) -> ClassificationScores:
    """ARI and purity of the model's segment primitives against the true stroke labels of
    generated ``trials`` (every trial needs ``truth``)."""
    trials = list(trials)
    missing = [t.name for t in trials if t.truth is None]
    if missing:
        raise ValueError(
            f"score_against_truth needs generated trials with truth; {len(missing)} have none "
            f"(e.g. {missing[0]!r})"
        )
    if classifications is None:
        classifications = classify_trials(model, trials)
    pred, true = [], []
    for trial, c in zip(trials, classifications, strict=True):
        assert trial.truth is not None
        pred.append(c.primitives)
        true.append(match_strokes(c.segments, trial.truth.boundaries, trial.truth.labels))
    p = np.concatenate(pred)
    t = np.concatenate(true)
    keep = t >= 0
    if not np.any(keep):
        raise ValueError("no segment overlaps a true stroke; nothing to score")
    return ClassificationScores(
        ari=float(adjusted_rand_score(t[keep], p[keep])),
        purity=purity(p[keep], t[keep]),
        n_segments=int(keep.sum()),
        n_unmatched=int((~keep).sum()),
        n_primitives=model.n_primitives,
        n_true_labels=int(np.unique(t[keep]).size),
    )


# ------------------------------------------------------------------ primitive histograms

METHODS: tuple[str, ...] = ("centroid", "logistic")
FEATURES: tuple[str, ...] = ("counts", "frequencies")


def primitive_histograms(
    model: Any, trials: Sequence[Trial], *, features: str = "counts"
) -> NDArray[np.float64]:
    """(n_trials, k) histogram of each trial's segment primitives under a fitted ``model``.

    ``features="frequencies"`` normalises each row by its number of segments (rows of trials
    without segments stay zero).
    """
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

    Attributes
    ----------
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
        labels = _labels_of(y, "trials")
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


def group_folds(
    groups: Sequence[Any] | NDArray[Any],
) -> list[tuple[Any, NDArray[np.intp], NDArray[np.intp]]]:
    """``(group, train indices, test indices)`` of each leave-one-group-out fold
    (:class:`sklearn.model_selection.LeaveOneGroupOut`), in the order the groups first
    appear. Needs at least two groups."""
    from sklearn.model_selection import LeaveOneGroupOut

    g = np.asarray(list(groups))
    folds = {g[test[0]]: (train, test) for train, test in LeaveOneGroupOut().split(g, g, g)}
    return [(grp, *folds[grp]) for grp in dict.fromkeys(g.tolist())]


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
    for _, train, test in group_folds(g):
        clf = make_classifier().fit([trials[i] for i in train], list(y[train]))
        pred[test] = clf.predict([trials[i] for i in test])
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


# ------------------------------------------------------------------ whole movements


def _trials_of(movements: Sequence[Trial] | Trial, what: str) -> list[Trial]:
    trials = [movements] if isinstance(movements, Trial) else list(movements)
    if not trials:
        raise ValueError(f"{what}: no movements given")
    for i, t in enumerate(trials):
        if not isinstance(t, Trial):
            raise TypeError(f"{what}: item {i} is a {type(t).__name__}, expected visprim.Trial")
    arms = {t.arms for t in trials}
    if len(arms) != 1:
        raise ValueError(
            f"{what}: movements have different arms ({sorted(list(a) for a in arms)}); read "
            "them all with the same arm= option"
        )
    return trials


def arm_directions(trial: Trial) -> NDArray[np.float64]:
    """Unit upper-arm (shoulder → elbow) and forearm (elbow → wrist) directions per frame,
    in the torso's axes (``body_frame``; the recording axes without one): (T, 6 n_arms),
    arm by arm. Uses the recording's joint centres when it has them, else the centres the
    markers imply (:func:`visprim.ik.implied_joint_centres`)."""
    blocks = []
    for a in range(trial.n_arms):
        if trial.joints is not None:
            c = trial.joints[:, 3 * a : 3 * a + 3]
        else:
            c = implied_joint_centres(trial.markers[:, 4 * a : 4 * a + 4])
        upper = c[:, 1] - c[:, 0]
        fore = c[:, 2] - c[:, 1]
        if trial.body_frame is not None:
            upper = np.einsum("tji,tj->ti", trial.body_frame, upper)
            fore = np.einsum("tji,tj->ti", trial.body_frame, fore)
        for v in (upper, fore):
            norm = np.linalg.norm(v, axis=1, keepdims=True)
            blocks.append(v / np.where(norm > 0, norm, 1.0))
    return np.hstack(blocks)


def arm_velocities(trial: Trial) -> NDArray[np.float64]:
    """Angular velocity of the upper-arm and forearm directions (:func:`arm_directions`)
    between consecutive frames, rad/s: (T − 1, 6 n_arms). How fast each bone turns, and
    which way: the rhythm of a movement, which the directions themselves carry only
    through DTW's warping."""
    d = arm_directions(trial)
    dt = np.diff(trial.times)[:, None]
    return np.diff(d, axis=0) / dt


def torso_pose(trial: Trial) -> NDArray[np.float64]:
    """Where the trunk is and how it leans, per frame: (T, 6). The midpoint of the arms'
    shoulder centres (one shoulder for a one-arm trial) minus its place at the first frame,
    metres in the recording frame (+z up, the subject facing +x at the first frame), and the
    torso's up axis (``body_frame[:, :, 2]``, a unit vector: a lean of δ rad moves it by
    ≈ δ; +z for a trial without a torso, whose recording axes are also not turned to the
    subject's heading). What the arms' root does: a step or a hop carries
    the shoulders, a crouch or a bend lowers them and tilts the trunk, which the arm
    directions in the torso's axes do not see. Shoulder centres as in
    :func:`arm_directions`."""
    shoulders = []
    for a in range(trial.n_arms):
        if trial.joints is not None:
            shoulders.append(trial.joints[:, 3 * a])
        else:
            shoulders.append(implied_joint_centres(trial.markers[:, 4 * a : 4 * a + 4])[:, 0])
    mid = np.mean(shoulders, axis=0)
    if trial.body_frame is not None:
        up = trial.body_frame[:, :, 2]
    else:
        up = np.tile([0.0, 0.0, 1.0], (trial.n_frames, 1))
    return np.hstack([mid - mid[0], up])


def duration_costs(
    queries: Sequence[Trial], references: Sequence[Trial] | None = None
) -> NDArray[np.float64]:
    """``|log(T_q / T_r)|`` between the movements' durations (T, seconds): how many times
    longer one lasts than the other, which DTW's length-normalised cost discards."""
    q = np.log(np.array([max(t.duration, 1e-9) for t in queries]))
    r = q if references is None else np.log(np.array([max(t.duration, 1e-9) for t in references]))
    return np.abs(q[:, None] - r[None, :])


def _ragged(sequences: Sequence[NDArray[np.float64]]) -> tuple[NDArray[np.float64], Any]:
    lengths = [s.shape[0] for s in sequences]
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return np.ascontiguousarray(np.concatenate(sequences), dtype=np.float64), offsets


def dtw_matrix(
    queries: Sequence[NDArray[np.float64]],
    references: Sequence[NDArray[np.float64]] | None = None,
    *,
    band: float | None = None,
) -> NDArray[np.float64]:
    """Length-normalised DTW costs between lists of (T_i, D) sequences
    (:func:`visprim.kernels.dtw_distances`); ``references=None``: among the queries."""
    q, qo = _ragged(queries)
    if references is None:
        return np.asarray(kernels.dtw_distances(q, qo, band=band))
    r, ro = _ragged(references)
    return np.asarray(kernels.dtw_distances(q, qo, r, ro, band=band))


class _NearestSequences(ClassifierMixin, BaseEstimator):
    """k-nearest neighbours of movements under a DTW cost of per-frame features."""

    band: float | None
    n_neighbors: int

    def _features(self, trials: list[Trial]) -> Any:
        raise NotImplementedError

    def _check_common(self) -> None:
        if self.band is not None and not 0.0 <= float(self.band) <= 1.0:
            raise ValueError(f"band must be None or a fraction in [0, 1], got {self.band!r}")
        if not isinstance(self.n_neighbors, (int, np.integer)) or self.n_neighbors < 1:
            raise ValueError(f"n_neighbors must be an integer >= 1, got {self.n_neighbors!r}")

    def _fit_features(self, trials: list[Trial]) -> None:
        """Learn whatever the features need (nothing for fixed features)."""

    def _fit_common(self, movements: Sequence[Trial], y: Sequence[Any]) -> list[Trial]:
        self._check_common()
        trials = _trials_of(movements, "fit")
        labels = _labels_of(y, "movements")
        if len(trials) != labels.shape[0]:
            raise ValueError(f"fit: {len(trials)} movements but {labels.shape[0]} labels")
        if np.unique(labels).size < 2:
            raise ValueError("fit: the training movements need at least two different labels")
        self.arms_ = trials[0].arms
        self.train_labels_ = labels
        self.classes_ = np.unique(labels)
        return trials

    def fit(self, movements: Sequence[Trial], y: Sequence[Any]) -> _NearestSequences:
        """Keep the training movements' features and labels ``y``."""
        trials = self._fit_common(movements, y)
        self._fit_features(trials)
        self.train_features_ = self._features(trials)
        return self

    def _check_fitted(self) -> None:
        if not hasattr(self, "train_features_"):
            raise NotFittedError(f"{type(self).__name__} is not fitted; call fit first")

    def _query(self, movements: Sequence[Trial]) -> list[Trial]:
        self._check_fitted()
        trials = _trials_of(movements, "predict")
        if trials[0].arms != self.arms_:
            raise ValueError(
                f"predict: movements have arms {list(trials[0].arms)}, the classifier was "
                f"fitted on {list(self.arms_)}"
            )
        return trials

    def distances(self, movements: Sequence[Trial]) -> NDArray[np.float64]:
        """(n_movements, n_training) DTW costs to the training movements."""
        trials = self._query(movements)
        return dtw_matrix(self._features(trials), self.train_features_, band=self.band)

    def predict_proba_from_distances(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        """Class fractions among the ``n_neighbors`` nearest training movements, (n, classes)
        (columns in the order of ``classes_``); ties go to the earlier training movement."""
        self._check_fitted()
        k = min(int(self.n_neighbors), d.shape[1])
        nearest = np.argsort(d, axis=1, kind="stable")[:, :k]
        idx = np.searchsorted(self.classes_, self.train_labels_[nearest])
        proba = np.zeros((d.shape[0], self.classes_.shape[0]))
        np.add.at(proba, (np.repeat(np.arange(d.shape[0]), k), idx.ravel()), 1.0 / k)
        return proba

    def predict_from_distances(self, d: NDArray[np.float64]) -> NDArray[Any]:
        """Labels given the costs ``d`` (n, n_training) to the training movements: the most
        frequent among the ``n_neighbors`` nearest (the nearest for 1)."""
        if int(self.n_neighbors) == 1:
            self._check_fitted()
            return np.asarray(self.train_labels_[np.argmin(d, axis=1)])
        proba = self.predict_proba_from_distances(d)
        return np.asarray(self.classes_[np.argmax(proba, axis=1)])

    def predict_proba(self, movements: Sequence[Trial]) -> NDArray[np.float64]:
        """Class fractions among the nearest training movements (see
        :meth:`predict_proba_from_distances`)."""
        return self.predict_proba_from_distances(self.distances(movements))

    def predict(self, movements: Sequence[Trial]) -> NDArray[Any]:
        """Label of each movement."""
        return self.predict_from_distances(self.distances(movements))


class DTWClassifier(_NearestSequences):
    """Baseline: k-nearest neighbours (default 1) under dynamic time warping of the arms'
    upper-arm and forearm directions (:func:`arm_directions`, 6 values per arm and frame;
    the local cost is the Euclidean distance, the path cost is divided by the two lengths).

    Parameters
    ----------
    band : float or None
        Sakoe–Chiba band as a fraction of the length (default None: no band).
    n_neighbors : int
        Neighbours voting (default 1).
    """

    def __init__(self, band: float | None = None, n_neighbors: int = 1) -> None:
        self.band = band
        self.n_neighbors = n_neighbors

    def _features(self, trials: list[Trial]) -> list[NDArray[np.float64]]:
        return [arm_directions(t) for t in trials]


def _labels_of(y: Any, what: str) -> NDArray[Any]:
    """The labels ``y`` of ``fit`` as a 1-D array; a ValueError naming the problem for
    None, a scalar or a table."""
    if y is None or isinstance(y, (str, bytes)) or not hasattr(y, "__iter__"):
        raise ValueError(f"fit: y must be one label per training {what[:-1]}, got {y!r}")
    labels = np.asarray(list(y))
    if labels.ndim != 1:
        raise ValueError(
            f"fit: y must be one label per training {what[:-1]}, got shape {labels.shape}"
        )
    return labels


def _windows(
    model: PrimitiveModel, trials: Sequence[Trial], window: float, step: int = 1
) -> tuple[Any, NDArray[np.int64], NDArray[np.float64]]:
    """The window of ``window`` seconds around every ``step``-th frame of every trial (from
    its first frame), as segment vectors of the model's features: ``(SegmentVectors, where
    each trial's windows start in them (n_trials,), position of each frame in its window in
    [0, 1])``. The window is centred on the frame, shifted to stay inside the trial, and
    covers the whole trial when the trial is shorter."""
    if not window > 0:
        raise ValueError(f"window must be a positive number of seconds, got {window!r}")
    if not (isinstance(step, (int, np.integer)) and step >= 1):
        raise ValueError(f"step must be a whole number of frames >= 1, got {step!r}")
    corpus = model.prepare(list(trials), tune_seg2=False)
    period = np.array([t.frame_period for t in trials])
    lengths = np.diff(np.append(corpus.offsets, corpus.times_all.shape[0]))
    kept = -(-lengths // step)  # frames 0, step, 2 step, ... of each trial
    trial = np.repeat(np.arange(len(trials)), kept)
    first = np.concatenate([[0], np.cumsum(kept)[:-1]]).astype(np.int64)
    local = ((np.arange(trial.shape[0]) - np.repeat(first, kept)) * step).astype(np.float64)
    last = (lengths - 1)[trial].astype(np.float64)
    width = np.minimum(window / period[trial], last)
    start = np.clip(local - width / 2, 0.0, None)
    start = np.minimum(start, last - width)
    end = start + width
    base = corpus.offsets[trial]
    sv = vectors_from_frames(
        corpus.values,
        base + start,
        base + end,
        trial=trial,
        starts=start,
        ends=end,
        n_samples=int(model.n_samples),
        periodic_channels=periodic_channels(corpus.features, len(corpus.arms)),
        offsets=str(model.offsets),
    )
    position = np.divide(local - start, width, out=np.zeros_like(width), where=width > 0)
    return sv, first, np.clip(position, 0.0, 1.0)


def segment_descriptions(model: PrimitiveModel, sv: Any) -> NDArray[np.float64]:
    """What the model knows of each segment of ``sv``: its projection ``p`` (f values)
    and, for a model with ``offsets="mean"``, its mean posture ``o`` (C values) scaled by
    ``√n_samples``. A vector is its shape plus its posture repeated ``n`` times, and the
    shape has zero mean per channel, so ``‖[p, √n o] − [p', √n o']‖`` is the distance of
    the absolute vectors up to the PCA projection error: (N, f) or (N, f + C)."""
    p = np.asarray(model.transform(sv.vectors))
    if getattr(model, "offsets", "turns") != "mean":
        return p
    return np.hstack([p, np.sqrt(float(model.n_samples)) * sv.offsets])


def primitive_coordinates(
    model: PrimitiveModel, trials: Sequence[Trial], window: float, step: int = 1
) -> list[NDArray[np.float64]]:
    """Each frame of each trial in the primitives' space: the description
    (:func:`segment_descriptions`: the projection ``p = E_fᵀ (s − s̄)``, and the mean
    posture for ``offsets="mean"``) of the segment vector ``s`` of the ``window`` seconds
    around the frame (the model's per-frame features, low-passed, resampled to
    ``n_samples`` like a training segment), at every ``step``-th frame. One (T_i, f) or
    (T_i, f + C) array per trial (T_i = ⌈frames / step⌉)."""
    sv, first, _ = _windows(model, trials, window, step)
    return np.split(segment_descriptions(model, sv), first[1:])


def reconstructed_directions(
    model: PrimitiveModel, trials: Sequence[Trial], window: float, step: int = 1
) -> list[NDArray[np.float64]]:
    """Each frame of each trial as the primitives' basis rebuilds it: the window around the
    frame (as in :func:`primitive_coordinates`) projected onto the f eigenvectors and
    rebuilt (``E_f p + s̄``), read at the frame's place in the window, as unit upper-arm and
    forearm directions (the model's own channels for ``features="directions"``, forward
    kinematics of the angles for ``"zyz"``), at every ``step``-th frame. One
    (⌈frames / step⌉, 6 n_arms) array per trial."""
    sv, first, position = _windows(model, trials, window, step)
    p = model.transform(sv.vectors)
    rec = p @ model.components_.T + model.mean_
    curves = to_curves(rec, sv.n_channels) + sv.offsets[:, None, :]  # (F, n, C)
    n = curves.shape[1]
    x = position * (n - 1)
    i0 = np.clip(np.floor(x).astype(np.int64), 0, n - 2)
    w = (x - i0)[:, None]
    rows = np.arange(curves.shape[0])
    values = curves[rows, i0] * (1.0 - w) + curves[rows, i0 + 1] * w
    if model.features != "directions":
        values = from_angles(values, "directions")
    v = values.reshape(values.shape[0], -1, 3)
    norm = np.linalg.norm(v, axis=2, keepdims=True)
    v = v / np.where(norm > 0, norm, 1.0)
    return np.split(v.reshape(values.shape), first[1:])


MOTION_METHODS: tuple[str, ...] = params.MOTION_METHODS
#: The costs of ``method="combined"`` (:data:`visprim.params.COMBINED_TERMS`).
COMBINED_TERMS: tuple[str, ...] = params.COMBINED_TERMS
#: Candidate weights of each further term (:data:`visprim.params.TERM_WEIGHTS`).
SEGMENT_WEIGHTS: tuple[float, ...] = params.TERM_WEIGHTS
_DEFAULTS = {p.name: p.default for p in params.CLASSIFIER_PARAMETERS}


class MotionClassifier(_NearestSequences):
    """Classify whole movements by the primitives they are made of.

    ``fit`` learns a :class:`~visprim.model.PrimitiveModel` (segmentation, PCA basis and
    primitives) from the training movements only, and keeps them expressed through it;
    ``predict`` gives each movement the label of its nearest training movement(s) under a
    dynamic time warping (DTW) cost of one of these descriptions:

    * ``"frames"``: every frame re-expressed through the primitives' PCA basis — the
      segment-length window around it (``window`` times the median training segment
      duration) projected onto the f eigenvectors and rebuilt — read as unit upper-arm and
      forearm directions (:func:`reconstructed_directions`).
    * ``"coordinates"``: the windows' f-D projections themselves
      (:func:`primitive_coordinates`): the movement as a path in the primitives' space.
    * ``"segments"``: the sequence of the segments' f-D projections (one point per
      segment, in time order): which strokes, in which order.
    * ``"combined"`` (default): the sum of five costs (:data:`COMBINED_TERMS` and, with
      ``torso=True``, the trunk's), each divided by its median over pairs of training
      movements::

          D = D_coordinates + w_s · D_segments + w_v · D_velocity + w_d · D_duration
              + w_t · D_torso

      ``D_velocity`` is the DTW cost of the bones' angular velocities
      (:func:`arm_velocities`: how fast and which way each bone turns, the rhythm that
      warping hides), ``D_duration`` the ratio of the durations ``|log(T_q / T_r)|``
      (:func:`duration_costs`: how long the movement lasts, which the length-normalised
      DTW cost discards), ``D_torso`` the DTW cost of the trunk's pose
      (:func:`torso_pose`: how far the shoulders have moved since the first frame and how
      the trunk leans, which tells a kick, a hop and a sneak, or a bend to the floor,
      apart when the legs are not seen). The four weights are chosen in ``fit`` from
      ``term_weights`` (4⁴ = 256 candidates; 4³ = 64 with ``torso=False``) by
      leave-one-group-out 1-NN accuracy on the training movements (``groups`` given to
      ``fit``; else leave-one-out), the first best in the order ``w_s``, ``w_v``, ``w_d``,
      ``w_t`` ascending (the smaller weights on ties). Nothing of a held-out group is used
      to choose them.
    * ``"histogram"``: :class:`PrimitiveHistogramClassifier` (nearest centroid of the
      primitive histograms).

    The default was chosen by measurement on the shared recordings, leave one group out,
    both arms, with the weights chosen by the inner leave-one-group-out of each fold; the
    figures and the commands reproducing them are in ``docs/evaluate.rst``. The per-frame
    path says *how* the arm moves, the segment sequence *which strokes in which order*,
    the velocities *at what rhythm*, the duration *for how long* and the torso *what the
    body carrying the arms does*; the weights let each corpus weigh them.

    The defaults of the settings below are declared in
    :data:`visprim.params.CLASSIFIER_PARAMETERS`.

    Parameters
    ----------
    model_params : dict, optional
        Keyword arguments of :class:`~visprim.model.PrimitiveModel`.
    method : {"combined", "frames", "coordinates", "segments", "histogram"}
    window : float
        Window of the per-frame descriptions as a multiple of the median training segment
        duration (default 1.0: one typical stroke).
    band : float or None
        Sakoe–Chiba band of the DTW as a fraction of the length (default None).
    n_neighbors : int
        Neighbours voting (default 1).
    step : int
        The per-frame descriptions in primitive space are taken at every ``step``-th
        frame (default 2: 68 ms at the 34 ms period). Windows a stroke long that start one
        frame apart overlap almost entirely, so every second one carries the same path at a
        quarter of the DTW cost.
    term_weights : sequence of float
        Candidate weights of each further term of ``method="combined"`` (default
        0, 0.25, 0.5, 1).
    torso : bool
        ``method="combined"`` also sums the cost of the trunk's pose (default True; chosen
        by the nested measurement in ``docs/evaluate.rst``). It needs the recordings'
        shoulder centres in the recording frame (and their ``body_frame``, else the trunk
        is taken as upright): movements whose arms are given in a shoulder frame carry no
        trunk, their torso costs are all 0 and the weight changes nothing.

    Attributes
    ----------
    model_ : the fitted PrimitiveModel.
    window_seconds_ : float — the window of the per-frame descriptions, seconds.
    weights_ : dict — weight of each DTW cost in the sum (already divided by its scale).
    scales_ : dict — median training cost of each term.
    term_weights_ : dict — the chosen weight of each term (1 for the first).
    segment_weight_ : float — ``w_s`` of ``method="combined"``.
    inner_accuracy_ : dict — inner leave-one-group-out accuracy of each candidate
        ``(w_s, w_v, w_d, w_t)`` (``(w_s, w_v, w_d)`` with ``torso=False``).
    classes_ : the labels seen in ``fit``.
    """

    def __init__(
        self,
        model_params: Mapping[str, Any] | None = None,
        method: str = _DEFAULTS["method"],
        window: float = _DEFAULTS["window"],
        band: float | None = _DEFAULTS["band"],
        n_neighbors: int = _DEFAULTS["n_neighbors"],
        step: int = _DEFAULTS["step"],
        term_weights: Sequence[float] = _DEFAULTS["term_weights"],
        torso: bool = _DEFAULTS["torso"],
    ) -> None:
        self.model_params = model_params
        self.method = method
        self.window = window
        self.band = band
        self.n_neighbors = n_neighbors
        self.step = step
        self.term_weights = term_weights
        self.torso = torso

    def _terms(self) -> tuple[str, ...]:
        if self.method != "combined":
            return (self.method,)
        return COMBINED_TERMS + (("torso",) if self.torso else ())

    def _fit_features(self, trials: list[Trial]) -> None:
        for p in params.CLASSIFIER_PARAMETERS:
            why = p.check(getattr(self, p.name))
            if why is not None:
                raise ValueError(f"MotionClassifier {p.name}={getattr(self, p.name)!r}: {why}")
        self.model_ = PrimitiveModel(**dict(self.model_params or {})).fit(trials)
        durations = self.model_.segment_ends_ - self.model_.segment_starts_
        self.window_seconds_ = float(self.window) * float(np.median(durations))

    def _features(self, trials: list[Trial]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for term in self._terms():
            if term == "frames":
                out[term] = reconstructed_directions(
                    self.model_, trials, self.window_seconds_, self.step
                )
            elif term == "coordinates":
                out[term] = primitive_coordinates(
                    self.model_, trials, self.window_seconds_, self.step
                )
            elif term == "velocity":
                out[term] = [arm_velocities(t) for t in trials]
            elif term == "duration":
                out[term] = trials
            elif term == "torso":
                out[term] = [torso_pose(t) for t in trials]
            else:
                out[term] = self._segment_projections(trials)
        return out

    def _costs(self, term: str, queries: Any, references: Any | None = None) -> NDArray[np.float64]:
        if term == "duration":
            return duration_costs(queries, references)
        return dtw_matrix(queries, references, band=self.band)

    def _segment_projections(self, trials: list[Trial]) -> list[NDArray[np.float64]]:
        corpus = self.model_.prepare(trials, tune_seg2=False)
        f = int(self.model_.n_components)
        if getattr(self.model_, "offsets", "turns") == "mean":
            f += int(self.model_.n_channels)
        out = [np.zeros((1, f)) for _ in trials]  # no segment: one point at the mean
        if corpus.segmentation.n_segments:
            sv = self.model_.vectorize(corpus)
            p = segment_descriptions(self.model_, sv)
            for i in np.unique(sv.trial):
                out[int(i)] = p[sv.trial == i]
        return out

    def fit(
        self, movements: Sequence[Trial], y: Sequence[Any], groups: Sequence[Any] | None = None
    ) -> MotionClassifier:
        """Learn the primitives from ``movements`` and keep them with their labels ``y``.

        ``groups`` (optional, one per movement: subject, style, ...) is only used to choose
        the weights of ``method="combined"`` by leave-one-group-out on these movements;
        without it, leave-one-out.
        """
        if self.method == "histogram":
            trials = self._fit_common(movements, y)
            self.histogram_ = PrimitiveHistogramClassifier(self.model_params).fit(trials, y)
            self.model_ = self.histogram_.model_
            self.train_features_: Any = {}
            return self
        super().fit(movements, y)
        terms = self._terms()
        n = self.train_labels_.shape[0]
        self.scales_ = {t: 1.0 for t in terms}
        self.weights_ = {terms[0]: 1.0}
        self.term_weights_ = {terms[0]: 1.0}
        if self.method != "combined":
            return self
        g = np.arange(n) if groups is None else np.asarray(list(groups))
        if g.shape[0] != n:
            raise ValueError(f"fit: {n} movements but {g.shape[0]} groups")
        off = ~np.eye(n, dtype=bool)
        train = {}
        for t in terms:
            c = self._costs(t, self.train_features_[t])
            m = float(np.median(c[off])) if n > 1 else 0.0
            self.scales_[t] = m if m > 0 else 1.0
            train[t] = c / self.scales_[t]
        grid = [
            tuple(float(w) for w in ws) for ws in product(self.term_weights, repeat=len(terms) - 1)
        ]
        scores = []
        for ws in grid:
            d = train[terms[0]] + sum(w * train[t] for w, t in zip(ws, terms[1:], strict=True))
            scores.append(_inner_accuracy(d, self.train_labels_, g))
        best = grid[int(np.argmax(scores))]
        self.inner_accuracy_ = dict(zip(grid, scores, strict=True))
        self.term_weights_ = {terms[0]: 1.0, **dict(zip(terms[1:], best, strict=True))}
        self.segment_weight_ = self.term_weights_["segments"]
        self.weights_ = {t: w / self.scales_[t] for t, w in self.term_weights_.items()}
        return self

    def distances(self, movements: Sequence[Trial]) -> NDArray[np.float64]:
        """(n_movements, n_training) weighted costs to the training movements."""
        trials = self._query(movements)
        if self.method == "histogram":
            raise ValueError("method='histogram' compares histograms, not distances")
        feats = self._features(trials)
        total = np.zeros((len(trials), self.train_labels_.shape[0]))
        for term, w in self.weights_.items():
            if w:
                total += w * self._costs(term, feats[term], self.train_features_[term])
        return total

    def predict(self, movements: Sequence[Trial]) -> NDArray[Any]:
        """Label of each movement."""
        if self.method == "histogram":
            return self.histogram_.predict(self._query(movements))
        return super().predict(movements)

    def predict_proba(self, movements: Sequence[Trial]) -> NDArray[np.float64]:
        """Class probabilities, (n, n_classes) in the order of ``classes_``."""
        if self.method == "histogram":
            pred = self.predict(movements)
            return (pred[:, None] == self.classes_[None, :]).astype(np.float64)
        return super().predict_proba(movements)


def _inner_accuracy(d: NDArray[np.float64], y: NDArray[Any], groups: NDArray[Any]) -> float:
    """1-NN accuracy when each group is held out in turn from the others (costs ``d``)."""
    if np.unique(groups).size < 2:
        return 0.0
    right = 0
    for _, train, test in group_folds(groups):
        sub = d[np.ix_(test, train)]
        right += int(np.sum(y[train][np.argmin(sub, axis=1)] == y[test]))
    return right / y.shape[0]
