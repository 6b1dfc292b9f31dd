"""Classification of movements by their primitives (paper §7).

Each segment of a new movement goes to its nearest primitive (nearest cluster centre in the
f-D projection space, :meth:`~visprim.model.PrimitiveModel.assign`); a trial becomes the
*sequence* of its segments' primitives and the *histogram* of that sequence.

On generated data (trials with :class:`~visprim.trial.Truth`) the segment labels can be
compared with the true strokes: each segment is matched to the true stroke it overlaps most
in time (:func:`match_strokes`), then :func:`score_against_truth` reports the adjusted Rand
index (chance-corrected agreement of the two partitions, 1 = identical, ≈ 0 = chance) and
the purity (fraction of segments whose primitive's majority stroke label is their own).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.metrics import adjusted_rand_score

from visprim.model import PrimitiveModel
from visprim.trial import Trial


@dataclass(frozen=True)
class TrialClassification:
    """The primitives of one trial.

    Attributes
    ----------
    name : str — the trial's name.
    segments : (n, 2) float array, seconds — the trial's segments (model's segmentation).
    labels : (n,) int array — primitive of each segment, in time order (the *sequence*).
    distances : (n,) float array, radians — Euclidean distance of each segment's projection
        to its primitive's centre.
    n_primitives : int — number of primitives k of the model.
    """

    name: str
    segments: NDArray[np.float64]
    labels: NDArray[np.int64]
    distances: NDArray[np.float64]
    n_primitives: int

    @property
    def sequence(self) -> tuple[int, ...]:
        """The primitives in time order."""
        return tuple(int(v) for v in self.labels)

    @property
    def histogram(self) -> NDArray[np.int64]:
        """(k,) number of segments assigned to each primitive."""
        return np.bincount(self.labels, minlength=self.n_primitives).astype(np.int64)


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
                labels=labels[m],
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
        pred.append(c.labels)
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
