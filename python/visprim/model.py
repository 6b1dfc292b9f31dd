"""The learned primitives: :class:`PrimitiveModel`, a scikit-learn style estimator.

``fit(trials)`` runs the whole method of Fod, Matarić & Jenkins on a list of
:class:`~visprim.trial.Trial`:

1. inverse kinematics → 4 angles per arm (radians, :mod:`visprim.ik`);
2. zero-phase Butterworth low-pass (:mod:`visprim.filtering`);
3. the angles in the chosen description (``features``, :mod:`visprim.features`): the
   paper's Z-Y-Z angles, or the singularity-free bone directions (default);
4. segmentation, SEG-2 (default) or SEG-1 (:mod:`visprim.segment`), on those channels;
5. each segment resampled to ``n_samples`` per channel → a ``C n``-D vector (400-D for the
   paper's one arm), γ and α shifted by whole turns so that the segment's mean angle lies
   in (−π, π] (:mod:`visprim.vectors`; reconstructions on a trial's clock add them back);
6. PCA (:mod:`visprim.pca`), keeping ``n_components`` eigenvectors ``E_f``;
7. k-means with ``n_clusters`` clusters in the f-D projection space: the primitives
   (:mod:`visprim.clustering`; above 50,000 segments seeded on a sample of them).

The paper's exact method is one named setting, :meth:`PrimitiveModel.paper`: Z-Y-Z angles
and SEG-2's constant tuned from the repetitions. The defaults are made for real
recordings: bone directions (no Z-Y-Z singularity with the arm hanging) and SEG-2's
constant scaled to the corpus' movement speed (robust to static trials and slow movers).

Everything numeric runs in the Rust kernels (:mod:`visprim.kernels`). Units: seconds and
radians throughout the API; degrees only in reports (and the ``zvc_threshold_deg`` option).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from os import PathLike
from typing import Any, Literal, TypeGuard

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, ClusterMixin, TransformerMixin
from sklearn.exceptions import NotFittedError

from visprim import kernels
from visprim.accuracy import DEFAULT_F_VALUES, DEFAULT_K_VALUES, ErrorTables, compute_error_tables
from visprim.clustering import kmeans_projections
from visprim.features import n_channels, periodic_channels, to_angles
from visprim.params import PAPER, check_params, defaults
from visprim.pca import PCABasis, fit_pca
from visprim.preprocess import PreparedCorpus, prepare_corpus
from visprim.provenance import Provenance
from visprim.trial import Trial
from visprim.vectors import (
    SegmentVectors,
    amplitude_gains,
    stretch,
    to_curves,
    vectors_from_frames,
)

Source = Literal["projection", "cluster"]

__all__ = ["PrimitiveModel", "rebuild_from_centers"]

_DEFAULTS = defaults()


class PrimitiveModel(TransformerMixin, ClusterMixin, BaseEstimator):
    """Movement primitives learned from arm trials (PCA + k-means of segment vectors).

    Parameters
    ----------
    filter_order : int
        Butterworth order of the zero-phase low-pass (default 10).
    cutoff : float
        Normalised cutoff of the low-pass, a fraction of the Nyquist frequency of the frame
        rate, in (0, 1) (default 0.25).
    segmentation : {"seg2", "seg1"}
        Which segmentation produces the training segments (default "seg2").
    zvc_threshold_deg : float
        Significant-movement threshold of the zero-velocity crossings, **degrees** (default
        5.0; used by SEG-1).
    window : float
        SEG-1 window in seconds: ZVCs of different angles closer than this form one event
        (default 0.3).
    seg1_adaptive : bool
        SEG-1 cuts fast cyclic motion at its half-cycles with a shorter window where the
        DOFs reverse faster than ``window`` (default True; :mod:`visprim.segment.seg1`).
    seg2_threshold : float or None
        SEG-2 constant ``c`` on ``z(t) = Σ θ̇ᵢ²`` (the channels' summed squared velocity) in
        (rad/s)²; ``None`` (default) tunes it on the training corpus (``seg2_tuning``).
    seg2_tuning : {"robust", "repetitions"}
        How ``c`` is tuned: scaled to the corpus' movement speed, with lower thresholds for
        slow trials (default; :func:`visprim.segment.seg2.robust_seg2_thresholds`), or the
        paper's rule, every trial yields at least its ``repetitions`` segments.
    seg2_boundary : {"first_stop", "slowest"}
        Where SEG-2 cuts after a movement run (:mod:`visprim.segment.seg2`): at the run's
        first stop (first local minimum of ``z``, or rest), the same point whether or not
        another run follows, so that the online segmenter can close every segment as soon
        as it stops (default; docs/online.rst for the measurements), or at the slowest frame
        of the rest before the next run (the paper's preset).
    features : {"directions", "zyz"}
        What the segmentation and the vectors use (:mod:`visprim.features`): unit upper-arm
        and forearm directions, 6 channels per arm (default), or the paper's Z-Y-Z Euler
        angles and elbow, 4 channels per arm.
    offsets : {"mean", "turns"}
        What each segment vector is taken relative to (:mod:`visprim.vectors`): every
        channel's mean over the segment (default), so that primitives are shapes of
        movement and a segment is rebuilt from its primitive placed at the segment's own
        mean posture (C numbers per segment); or the absolute curves with only whole turns
        of γ and α removed (the paper: a primitive also fixes where the arm is).
    amplitude : bool
        Rebuild a segment from its primitive scaled by the least-squares gain ``a ≥ 0``
        that fits the segment's own shape best (:func:`visprim.vectors.amplitude_gains`;
        one more number per segment beside its duration and posture), so that one primitive
        serves the same movement made larger or smaller. Only with ``offsets="mean"``
        (default False: the primitive as it is).
    n_samples : int
        Samples per channel in a segment vector (default 100; vectors are ``C n_samples``-D,
        C channels per frame: 4 or 6 per arm, see ``features``).
    n_components : int
        Eigenvectors kept, ``f`` (default 30).
    n_clusters : int
        k-means clusters = primitives, ``k`` (default 30).
    n_init, max_iter, tol : int, int, float
        k-means restarts, iterations per restart and convergence tolerance (scikit-learn's
        meaning of ``tol``); above 50,000 segments the restarts run on a sample of them
        (:mod:`visprim.clustering`).
    seed : int
        Seed of k-means (results are deterministic for a seed).

    Attributes
    ----------
    n_features_in_ : int
        Dimension of the segment vectors seen in ``fit``, ``d = C n_samples``.
    mean_ : ndarray of shape (d,)
        The mean segment vector ``s̄``, radians.
    eigenvalues_ : ndarray of shape (d,)
        Eigenvalues of the covariance K (divisor N), descending, rad².
    eigenvectors_ : ndarray of shape (d, m)
        Unit eigenvectors as columns: all d, or, fitted from N ≤ d segments, those of the
        non-zero eigenvalues and at least ``n_components`` (:mod:`visprim.pca`).
    components_ : ndarray of shape (d, f)
        ``E_f``, the first ``n_components`` eigenvectors.
    cluster_centers_ : ndarray of shape (k, f)
        Primitive centres in the projection space, radians.
    labels_ : ndarray of shape (N,)
        Primitive of each training segment (int).
    inertia_ : float
        k-means inertia (sum of squared distances to the centres, rad²).
    segment_trial_, segment_starts_, segment_ends_ : ndarray of shape (N,)
        Where each training segment came from: trial index, start and end in seconds
        (-1 and NaN when fitted on bare segment vectors).
    primitive_durations_ : ndarray of shape (k,)
        Mean duration of each primitive's member segments, seconds (NaN when fitted on
        bare segment vectors).
    seg2_threshold_ : float or None
        The SEG-2 constant used (tuned or given).
    trial_names_ : list of str
        Names of the training trials.
    training_vectors_ : ndarray of shape (N, d) or None
        The training segment vectors (written to the model file unless
        ``save(..., include_vectors=False)``).
    error_tables_ : ErrorTables or None
        Tables 1–3 once :meth:`error_table` ran (saved with the model).
    provenance_ : Provenance
        What the model was fitted on (:mod:`visprim.provenance`): the generated experiment,
        recordings, bare vectors or trials given in memory; ``visprim report`` reads the
        trials again from it.
    frame_period_ : float or None
        Frame period of the training trials, seconds (None: recordings at their own rates,
        or bare vectors); recordings given to the model later are resampled to it.
    eigen_movements_ : EigenMovements or None
        The principal components of the training movements, whole (one arm each,
        :func:`visprim.rate.budget.learn_eigen_movements`): ``visprim learn`` stores them,
        and ``visprim imitate --budget`` also considers describing a recording whole
        through them. None unless set (``fit`` does not compute them; older model files
        have none).

    See Also
    --------
    visprim.accuracy : Tables 1–3 (projection, clustering and total error).

    Notes
    -----
    A scikit-learn estimator: a transformer (segments → projections) and a clusterer
    (segments → primitives). ``X`` is a list of :class:`~visprim.trial.Trial` (segmented
    with the model's settings) or an array of segment vectors of shape (N, C n_samples),
    C channels per frame (see ``features`` and :mod:`visprim.vectors`). :meth:`score` is the
    negative total error, so ``GridSearchCV`` picks the parameters that rebuild held-out
    segments best.

    Examples
    --------
    >>> from visprim.datasets import imitation_experiment
    >>> trials = imitation_experiment(n_subjects=2, n_stimuli=4, seed=0)
    >>> model = PrimitiveModel(n_components=8, n_clusters=5).fit(trials)
    >>> model.transform(trials).shape[1]
    8
    """

    def __init__(
        self,
        *,
        filter_order: int = _DEFAULTS["filter_order"],
        cutoff: float = _DEFAULTS["cutoff"],
        segmentation: str = _DEFAULTS["segmentation"],
        zvc_threshold_deg: float = _DEFAULTS["zvc_threshold_deg"],
        window: float = _DEFAULTS["window"],
        seg1_adaptive: bool = _DEFAULTS["seg1_adaptive"],
        seg2_threshold: float | None = _DEFAULTS["seg2_threshold"],
        seg2_tuning: str = _DEFAULTS["seg2_tuning"],
        seg2_boundary: str = _DEFAULTS["seg2_boundary"],
        features: str = _DEFAULTS["features"],
        offsets: str = _DEFAULTS["offsets"],
        amplitude: bool = _DEFAULTS["amplitude"],
        n_samples: int = _DEFAULTS["n_samples"],
        n_components: int = _DEFAULTS["n_components"],
        n_clusters: int = _DEFAULTS["n_clusters"],
        n_init: int = _DEFAULTS["n_init"],
        max_iter: int = _DEFAULTS["max_iter"],
        tol: float = _DEFAULTS["tol"],
        seed: int = _DEFAULTS["seed"],
    ) -> None:
        self.filter_order = filter_order
        self.cutoff = cutoff
        self.segmentation = segmentation
        self.zvc_threshold_deg = zvc_threshold_deg
        self.window = window
        self.seg1_adaptive = seg1_adaptive
        self.seg2_threshold = seg2_threshold
        self.seg2_tuning = seg2_tuning
        self.seg2_boundary = seg2_boundary
        self.features = features
        self.offsets = offsets
        self.amplitude = amplitude
        self.n_samples = n_samples
        self.n_components = n_components
        self.n_clusters = n_clusters
        self.n_init = n_init
        self.max_iter = max_iter
        self.tol = tol
        self.seed = seed

    # ------------------------------------------------------------------ validation

    def _validate_params(self) -> None:
        """Check every parameter against its declared constraint (:mod:`visprim.params`),
        then the combinations."""
        check_params(self.get_params())
        if self.amplitude and self.offsets != "mean":
            raise ValueError(
                f"PrimitiveModel parameter amplitude={self.amplitude!r}: scales "
                "posture-relative shapes: needs offsets='mean'"
            )
        d = n_channels(self.features) * int(self.n_samples)
        if not 1 <= self.n_components <= d:
            raise ValueError(
                f"PrimitiveModel parameter n_components={self.n_components!r}: must be an "
                f"integer in [1, channels * n_samples = {d}]"
            )

    @classmethod
    def paper(cls, **params: Any) -> PrimitiveModel:
        """The paper's method exactly: Z-Y-Z Euler angles and elbow (``features="zyz"``),
        absolute segment vectors (``offsets="turns"``), SEG-2's constant tuned from the
        repetitions (``seg2_tuning="repetitions"``), SEG-1's fixed window
        (``seg1_adaptive=False``); other parameters as given (their defaults are the
        paper's). The preset is declared in :data:`visprim.params.PAPER`."""
        return cls(**{**PAPER, **params})

    def _check_fitted(self) -> None:
        if not hasattr(self, "cluster_centers_"):
            raise NotFittedError(
                "This PrimitiveModel is not fitted yet; call fit(trials) or "
                "PrimitiveModel.load(path)"
            )

    # ------------------------------------------------------------------ fitting

    def prepare(
        self,
        trials: Sequence[Trial],
        *,
        tune_seg2: bool | None = None,
        segmentation: str | None = None,
    ) -> PreparedCorpus:
        """IK, low-pass and segmentation of ``trials`` with this model's settings.

        Before ``fit`` (or with ``tune_seg2=True``) SEG-2's constant is tuned on these
        trials (unless ``seg2_threshold`` is given); after ``fit`` the fitted constant
        ``seg2_threshold_`` is reused so that new trials are cut like the training ones.
        ``segmentation`` overrides the model's method (e.g. SEG-2 partitions of a SEG-1
        model's trials for whole-movement reconstructions).
        """
        if tune_seg2 is None:
            tune_seg2 = not hasattr(self, "seg2_threshold_")
        threshold = self.seg2_threshold
        if not tune_seg2 and getattr(self, "seg2_threshold_", None) is not None:
            threshold = self.seg2_threshold_
        if hasattr(self, "arms_"):
            arms = {t.arms for t in trials}
            if arms != {tuple(self.arms_)}:
                raise ValueError(
                    f"the model was fitted on arms {list(self.arms_)}, the trials have "
                    f"{sorted(list(a) for a in arms)}; read them with the same arm= option"
                )
        return prepare_corpus(
            trials,
            filter_order=int(self.filter_order),
            cutoff=float(self.cutoff),
            segmentation=str(segmentation or self.segmentation),
            zvc_threshold_deg=float(self.zvc_threshold_deg),
            window=float(self.window),
            seg2_threshold=threshold,
            seg2_tuning=str(self.seg2_tuning),
            seg2_boundary=str(self.seg2_boundary),
            features=str(self.features),
            seg1_adaptive=bool(self.seg1_adaptive),
        )

    def vectorize(self, corpus: PreparedCorpus) -> SegmentVectors:
        """Segment vectors (N, 4 n_samples) of a prepared corpus (radians), with γ and α of
        each segment shifted by whole turns (:attr:`SegmentVectors.offsets`, see
        :mod:`visprim.vectors`)."""
        seg = corpus.segmentation
        if seg.n_segments == 0:
            raise ValueError(
                f"no {seg.method.upper().replace('SEG', 'SEG-')} segment found in "
                f"{corpus.n_trials} trial(s) "
                f"({', '.join(corpus.names[:3])}{', ...' if corpus.n_trials > 3 else ''})"
            )
        starts, ends = seg.global_frames()
        return vectors_from_frames(
            corpus.values,
            starts,
            ends,
            trial=seg.trial,
            starts=seg.start,
            ends=seg.end,
            n_samples=int(self.n_samples),
            periodic_channels=periodic_channels(corpus.features, len(corpus.arms)),
            offsets=str(self.offsets),
        )

    def fit(
        self,
        trials: Sequence[Trial] | ArrayLike,
        y: Any = None,
        *,
        source: Provenance | Mapping[str, Any] | None = None,
        client: Any = None,
    ) -> PrimitiveModel:
        """Learn the primitives from trials or from segment vectors.

        Parameters
        ----------
        trials : list of Trial, or array-like of shape (N, C n_samples)
            The training movements (:class:`~visprim.trial.Trial`, segmented with this
            model's settings), or their segment vectors in radians (see
            :mod:`visprim.vectors`; the model then has no durations or trial names).
        y : None
            Ignored (scikit-learn convention).
        source : Provenance, optional
            What the trials are (:class:`visprim.provenance.Provenance`, or its dict), so
            that ``visprim report`` can redraw the trial figures; default: trials given in
            memory (or bare vectors), which cannot be read again.
        client : dask.distributed.Client, str or True, optional
            Learn a lazy corpus on Dask: a client, a scheduler address, or ``True`` for a
            local cluster (see below).

        Returns
        -------
        self : PrimitiveModel
            The fitted model.

        ``trials`` may also be a lazy corpus (:class:`visprim.io.Corpus`,
        :class:`visprim.io.corpus.GeneratedCorpus`), learned in bounded memory, and
        ``client`` a Dask client, scheduler address or ``True`` (local cluster) to learn
        on a cluster (``pip install visprim[dask]``); see :mod:`visprim.scale`. Those fits
        keep no ``training_vectors_``.

        Raises
        ------
        ValueError
            Bad parameters, an empty corpus, fewer segments than ``n_clusters`` (or than 2).
        """
        record = None if source is None else _as_provenance(source)
        if client is not None or hasattr(trials, "chunk_ranges"):
            from visprim.scale import fit_corpus

            return fit_corpus(self, trials, client=client, source=record)
        self._validate_params()
        if not _are_trials(trials):
            return self._fit_array(trials, source=record or Provenance.arrays())
        trials = _as_trials(trials)
        record = record or Provenance.trials(trials)
        for attr in [a for a in vars(self) if a.endswith("_") and not a.startswith("_")]:
            delattr(self, attr)
        corpus = self.prepare(trials, tune_seg2=True)
        sv = self.vectorize(corpus)
        return self._fit_vectors(sv, corpus, source=record)

    def _fit_vectors(
        self,
        sv: SegmentVectors,
        corpus: PreparedCorpus | None = None,
        *,
        source: Provenance,
    ) -> PrimitiveModel:
        n = len(sv)
        if n < 2:
            raise ValueError(f"fit: the corpus yielded {n} segment(s); PCA needs at least 2")
        if int(self.n_clusters) > n:
            raise ValueError(
                f"fit: n_clusters={self.n_clusters} exceeds the number of segments found ({n}); "
                "lower n_clusters or give more trials"
            )
        basis = fit_pca(sv.vectors, n_keep=int(self.n_components))
        counts = corpus.segmentation.counts() if corpus is not None else np.zeros(0)
        return self._set_fitted(
            basis,
            basis.project(sv.vectors, int(self.n_components)),
            trial=sv.trial,
            starts=sv.starts,
            ends=sv.ends,
            seg2_threshold=corpus.seg2_threshold if corpus is not None else None,
            trial_names=list(corpus.names) if corpus is not None else [],
            arms=tuple(corpus.arms) if corpus is not None else ("right",),
            n_without_segments=int(np.sum(counts == 0)),
            n_short=int(corpus.n_short) if corpus is not None else 0,
            vectors=sv.vectors,
            source=source,
        )

    def _set_fitted(
        self,
        basis: PCABasis,
        projections: NDArray[np.float64] | None,
        *,
        trial: NDArray[np.int64],
        starts: NDArray[np.float64],
        ends: NDArray[np.float64],
        seg2_threshold: float | None,
        trial_names: list[str],
        arms: tuple[str, ...],
        n_without_segments: int,
        n_short: int,
        vectors: NDArray[np.float64] | None,
        source: Provenance,
        clusters: tuple[NDArray[np.float64], NDArray[np.int64], float, int] | None = None,
    ) -> PrimitiveModel:
        """Store the fitted state: the PCA ``basis``, k-means of the (N, f) ``projections``
        (or the given ``clusters`` = centres, labels, inertia, iterations) and where the N
        segments came from. Shared by the in-memory and the corpus fits
        (:mod:`visprim.scale`)."""
        if clusters is None:
            clusters = kmeans_projections(
                np.asarray(projections),
                int(self.n_clusters),
                n_init=int(self.n_init),
                max_iter=int(self.max_iter),
                tol=float(self.tol),
                seed=int(self.seed),
            )
        centers, labels, inertia, n_iter = clusters
        self.mean_ = basis.mean
        self.eigenvalues_ = basis.eigenvalues
        self.eigenvectors_ = basis.eigenvectors
        self.n_training_segments_ = int(trial.shape[0])
        self.cluster_centers_ = np.asarray(centers, dtype=np.float64)
        self.labels_ = np.asarray(labels, dtype=np.int64)
        self.inertia_ = float(inertia)
        self.n_iter_ = int(n_iter)
        self.segment_trial_ = trial
        self.segment_starts_ = starts
        self.segment_ends_ = ends
        self.primitive_durations_ = _mean_durations(
            ends - starts, self.labels_, int(self.n_clusters)
        )
        self.seg2_threshold_ = seg2_threshold
        self.trial_names_ = trial_names
        self.arms_ = tuple(arms)
        self.n_features_in_ = int(basis.mean.shape[0])
        self.n_trials_without_segments_ = int(n_without_segments)
        self.n_short_trials_ = int(n_short)
        self.training_vectors_: NDArray[np.float64] | None = vectors
        self.training_projections_: NDArray[np.float64] | None = projections
        self.error_tables_: ErrorTables | None = None
        self.provenance_ = source
        self.frame_period_ = source.frame_period
        self.eigen_movements_: Any = None
        return self

    # ------------------------------------------------------------------ properties

    @property
    def basis_(self) -> PCABasis:
        """The PCA basis (mean, eigenvalues, eigenvectors) as a :class:`PCABasis`."""
        self._check_fitted()
        return PCABasis(
            self.mean_, self.eigenvalues_, self.eigenvectors_, self.n_training_segments_
        )

    @property
    def components_(self) -> NDArray[np.float64]:
        """``E_f``: the first ``n_components`` eigenvectors as columns, (d, f)."""
        self._check_fitted()
        return self.eigenvectors_[:, : int(self.n_components)]

    @property
    def n_primitives(self) -> int:
        """Number of primitives k (cluster centres)."""
        self._check_fitted()
        return int(self.cluster_centers_.shape[0])

    @property
    def n_channels(self) -> int:
        """Channels per frame: 4 (``"zyz"``) or 6 (``"directions"``) per arm."""
        return n_channels(str(self.features), len(getattr(self, "arms_", ("right",))))

    @property
    def dim(self) -> int:
        """Dimension of a segment vector, ``n_channels · n_samples`` (400 for the paper)."""
        return self.n_channels * int(self.n_samples)

    def _to_angles(self, curves: NDArray[np.float64]) -> NDArray[np.float64]:
        """Angle curves ``(..., n, 4 n_arms)`` of channel curves ``(..., n, C)``, each curve
        converted on its own (:func:`visprim.features.to_angles`)."""
        if self.features == "zyz":
            return curves
        flat = curves.reshape(-1, curves.shape[-2], curves.shape[-1])
        out = np.stack([to_angles(c, str(self.features)) for c in flat])
        return out.reshape(*curves.shape[:-1], out.shape[-1])

    # ------------------------------------------------------------------ transform / predict

    def _vectors_of(self, X: ArrayLike | Sequence[Trial] | Trial) -> NDArray[np.float64]:
        return self._segment_vectors_of(X)[0]

    def _segment_vectors_of(
        self, X: ArrayLike | Sequence[Trial] | Trial
    ) -> tuple[NDArray[np.float64], SegmentVectors | None]:
        """``(vectors (N, d), SegmentVectors or None)``: the segments of trial(s) (with their
        whole-turn offsets), or vectors given directly (checked; no offsets)."""
        if isinstance(X, Trial) or (
            isinstance(X, (list, tuple)) and len(X) > 0 and isinstance(X[0], Trial)
        ):
            sv = self.vectorize(self.prepare(_as_trials(X)))
            return sv.vectors, sv
        return self._check_vectors(X, fitting=False), None

    def transform(self, X: ArrayLike | Sequence[Trial] | Trial) -> NDArray[np.float64]:
        """Projections ``p = E_fᵀ (s − s̄)`` of segments on the first f eigenvectors.

        Parameters
        ----------
        X : array-like of shape (N, d), Trial or list of Trial
            Segment vectors in radians, or trial(s), which are segmented with the fitted
            settings first (segments in trial order).

        Returns
        -------
        ndarray of shape (N, f)
            The projections, radians.
        """
        self._check_fitted()
        return self.basis_.project(self._vectors_of(X), int(self.n_components))

    def predict(self, X: ArrayLike | Sequence[Trial] | Trial) -> NDArray[np.int64]:
        """Primitive (nearest cluster centre in the projection space) of each segment.

        Parameters
        ----------
        X : array-like of shape (N, d), Trial or list of Trial
            Segment vectors in radians, or trial(s) (see :meth:`transform`).

        Returns
        -------
        ndarray of shape (N,)
            Primitive index of each segment (int).
        """
        labels, _ = self.assign(self.transform(X))
        return labels

    def assign(self, projections: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
        """Nearest centre of f-D projections: ``(labels (N,), Euclidean distances (N,))``
        (distances in the units of the projections, radians)."""
        self._check_fitted()
        p = np.ascontiguousarray(np.atleast_2d(projections), dtype=np.float64)
        if p.shape[1] != self.cluster_centers_.shape[1]:
            raise ValueError(
                f"projections must have {self.cluster_centers_.shape[1]} columns, got {p.shape}"
            )
        labels, dist = kernels.kmeans_predict(p, self.cluster_centers_)
        return np.asarray(labels, dtype=np.int64), np.asarray(dist, dtype=np.float64)

    # ------------------------------------------------------------------ reconstruction

    def reconstruct(
        self, X: ArrayLike | Sequence[Trial] | Trial, *, source: Source = "projection"
    ) -> NDArray[np.float64]:
        """Reconstructed segments as angle curves, shape (N, n_samples, 4 n_arms), radians.

        ``source="projection"``: ``s = E_f p + s̄`` with ``p`` the segment's projection;
        ``source="cluster"``: ``s = E_f c + s̄`` with ``c`` the centre of its primitive.
        For segment vectors ``X`` the curves are in the vectors' own frame; for trial(s)
        each segment's whole-turn offsets of γ and α are added back, so the curves are on
        the trial's own angles. Use :func:`visprim.vectors.stretch` (or
        :meth:`reconstruct_segment`) to put a curve back on its segment's duration.
        """
        self._check_fitted()
        x, sv = self._segment_vectors_of(X)
        rec = self._reconstruct_vectors(x, source)
        curves = to_curves(rec, self.n_channels) if sv is None else sv.to_trial_angles(rec)
        return self._to_angles(curves)

    def _reconstruct_vectors(self, x: NDArray[np.float64], source: Source) -> NDArray[np.float64]:
        """Segment vectors ``x`` (N, d) rebuilt from their projections or primitives."""
        if source == "projection":
            return self.basis_.project(x, int(self.n_components)) @ self.components_.T + self.mean_
        if source != "cluster":
            raise ValueError(f"source must be 'projection' or 'cluster', got {source!r}")
        return rebuild_from_centers(self, x, self.cluster_centers_)

    def primitive_angles(self, k: int) -> NDArray[np.float64]:
        """Primitive ``k`` (its cluster centre) as angle curves, (n_samples, 4 n_arms)
        radians."""
        self._check_fitted()
        if not 0 <= int(k) < self.n_primitives:
            raise IndexError(f"primitive index {k} out of range [0, {self.n_primitives})")
        s = self.cluster_centers_[int(k)] @ self.components_.T + self.mean_
        return self._to_angles(to_curves(s, self.n_channels))

    def reconstruct_movement(
        self,
        trial: Trial,
        *,
        source: Source = "projection",
        return_original: bool = False,
    ) -> tuple[NDArray[np.float64], ...]:
        """A whole movement rebuilt from its consecutive SEG-2 segments.

        The trial is segmented with SEG-2 (with the fitted constant ``seg2_threshold_`` when
        the model has one, else tuned on this trial), each segment is projected and
        reconstructed (from its projection or its primitive, ``source``), its whole-turn
        offsets of γ and α added back (so the result follows the trial's unwrapped angles,
        see :mod:`visprim.vectors`), stretched back to its duration and evaluated at the
        trial's frame times.

        Returns
        -------
        times : (m,) seconds — the trial's frame times covered by the segments.
        angles : (m, 4 n_arms) radians — the reconstruction.
        original : (m, 4 n_arms) radians — the low-passed IK angles at the same frames (only
            with ``return_original=True``).
        """
        self._check_fitted()
        corpus = self.prepare([trial], segmentation="seg2")
        if corpus.segmentation.n_segments == 0:
            raise ValueError(f"trial {trial.name!r}: SEG-2 found no segment to reconstruct")
        segments = corpus.segments[0]
        times = corpus.times_all
        sv = self.vectorize(corpus)
        curves = sv.to_trial_angles(self._reconstruct_vectors(sv.vectors, source))
        mask = (times >= segments[0, 0]) & (times <= segments[-1, 1])
        out_t = times[mask]
        # Segment j covers [start_j, end_j); the last one also its end.
        which = np.clip(np.searchsorted(segments[:, 1], out_t, side="right"), 0, len(segments) - 1)
        values = np.empty((out_t.size, curves.shape[2]))
        for j, (start, end) in enumerate(segments):
            rows = which == j
            values[rows] = stretch(curves[j], start, end, out_t[rows])
        angles = values if self.features == "zyz" else to_angles(values, str(self.features), out_t)
        original = corpus.angles_all[mask]
        if self.features != "zyz":
            angles = _nearest_turns(angles, original, len(corpus.arms))
        result = (out_t, angles)
        if return_original:
            return (*result, original)
        return result

    def reconstruct_segment(
        self,
        times: ArrayLike,
        angles: ArrayLike,
        start: float,
        end: float,
        *,
        source: Source = "projection",
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """One segment [start, end] s of a (low-passed) angle trajectory ``(T, 4 n_arms)``
        radians, reconstructed (whole-turn offsets of γ and α added back, so it lies on the
        trajectory's own angles) and stretched back to its duration:
        ``(frame times (m,) s, angles (m, 4 n_arms) rad)``."""
        from visprim.features import from_angles

        self._check_fitted()
        t = np.asarray(times, dtype=np.float64)
        a = np.asarray(angles, dtype=np.float64)
        values = from_angles(a, str(self.features))
        i0, i1 = np.interp([start, end], t, np.arange(t.size))
        sv = vectors_from_frames(
            values,
            [i0],
            [i1],
            trial=[0],
            starts=[start],
            ends=[end],
            n_samples=int(self.n_samples),
            periodic_channels=periodic_channels(str(self.features), a.shape[1] // 4),
            offsets=str(self.offsets),
        )
        curve = sv.to_trial_angles(self._reconstruct_vectors(sv.vectors, source))[0]
        mask = (t >= start) & (t <= end)
        out = stretch(curve, start, end, t[mask])
        if self.features != "zyz":
            out = _nearest_turns(
                to_angles(out, str(self.features), t[mask]), a[mask], a.shape[1] // 4
            )
        return t[mask], out

    # ------------------------------------------------------------------ errors

    def error_table(
        self,
        f_values: Sequence[int] = DEFAULT_F_VALUES,
        k_values: Sequence[int] = DEFAULT_K_VALUES,
    ) -> ErrorTables:
        """Tables 1–3 (projection, clustering and total error; see :mod:`visprim.accuracy`)
        on the training segments.

        Needs the training vectors (kept after ``fit``). After :meth:`load` the tables saved
        in the file are returned (only for the default rows).
        """
        self._check_fitted()
        default = tuple(f_values) == DEFAULT_F_VALUES and tuple(k_values) == DEFAULT_K_VALUES
        if default and getattr(self, "error_tables_", None) is not None:
            return self.error_tables_  # type: ignore[return-value]
        if getattr(self, "training_vectors_", None) is None:
            raise ValueError(
                "error_table: this model has no training vectors (it was loaded from a file); "
                "only the tables saved with it (default rows) are available"
                if default
                else "error_table: this model was loaded from a file without its training "
                "vectors; only the saved tables (default rows) are available"
            )
        tables = compute_error_tables(
            self.basis_,
            self.training_vectors_,  # type: ignore[arg-type]
            int(self.n_components),
            f_values=f_values,
            k_values=k_values,
            n_init=int(self.n_init),
            max_iter=int(self.max_iter),
            tol=float(self.tol),
            seed=int(self.seed),
            known={self.n_primitives: (self.cluster_centers_, self.labels_)},
        )
        if default:
            self.error_tables_ = tables
        return tables

    # ------------------------------------------------------------------ persistence

    def save(self, path: str | PathLike[str], *, include_vectors: bool = True) -> None:
        """Write the fitted model to one file (see :mod:`visprim.modelfile`), atomically.

        ``include_vectors=False`` leaves out the training segment vectors (N × d float64):
        a smaller file whose :meth:`error_table` only returns the tables computed before
        saving.
        """
        from visprim.modelfile import FITTED_FIELDS, REQUIRED_ARRAYS, write_model_file

        self._check_fitted()
        arrays: dict[str, Any] = {name: getattr(self, name + "_") for name in REQUIRED_ARRAYS}
        if include_vectors and getattr(self, "training_vectors_", None) is not None:
            arrays["training_vectors"] = self.training_vectors_
        book = getattr(self, "eigen_movements_", None)
        if book is not None:
            arrays["eigen_movements_mean"] = book.mean
            arrays["eigen_movements_components"] = book.components
        tables = getattr(self, "error_tables_", None)
        fitted = {name: _fitted_value(getattr(self, name + "_")) for name in FITTED_FIELDS}
        header = {
            "parameters": self.get_params(),
            "fitted": fitted,
            "error_tables": tables.to_dict() if tables is not None else None,
        }
        write_model_file(path, header, arrays)

    @classmethod
    def load(cls, path: str | PathLike[str]) -> PrimitiveModel:
        """Read a model written by :meth:`save` (see :mod:`visprim.modelfile`); its
        parameters are checked as :meth:`fit` checks them."""
        from visprim.modelfile import FITTED_FIELDS, REQUIRED_ARRAYS, ModelFileError, load_model

        contents = load_model(path)
        a, fitted = contents.arrays, contents.fitted
        try:
            # Files written before the ``offsets`` parameter hold absolute vectors, those
            # written before ``seg2_boundary`` were cut at the slowest frame of each gap.
            model = cls(**{"offsets": "turns", "seg2_boundary": "slowest", **contents.parameters})
            model._validate_params()
            tables = contents.error_tables
            model.error_tables_ = ErrorTables.from_dict(tables) if tables else None
            provenance = Provenance.from_dict(fitted["provenance"])
        except (TypeError, ValueError, LookupError, AttributeError) as exc:
            raise ModelFileError(f"{contents.path}: model parameters not accepted: {exc}") from None
        for name in FITTED_FIELDS:
            setattr(model, name + "_", fitted[name])
        model.arms_ = tuple(fitted["arms"])
        model.provenance_ = provenance
        model.frame_period_ = provenance.frame_period
        model.n_training_segments_ = int(fitted["n_training_segments"]) or len(a["labels"])
        for name in REQUIRED_ARRAYS:
            setattr(model, name + "_", a[name])
        model.training_vectors_ = a.get("training_vectors")
        model.eigen_movements_ = _eigen_movements(a)
        model.training_projections_ = None
        model.n_features_in_ = int(a["mean"].shape[0])
        problem = check_fitted_arrays(model)
        if problem is not None:
            raise ModelFileError(f"{contents.path}: damaged model file: {problem}")
        return model

    def __sklearn_is_fitted__(self) -> bool:
        return hasattr(self, "cluster_centers_")

    # ------------------------------------------------------------------ scikit-learn API

    def _check_vectors(self, X: Any, *, fitting: bool) -> NDArray[np.float64]:
        """``X`` as a finite float64 array of segment vectors (N, d), checked like
        scikit-learn does (no sparse, complex or 1-D input; ``d`` = ``n_features_in_``
        after fitting)."""
        from sklearn.utils.validation import check_array

        x: NDArray[np.float64] = check_array(
            X, dtype=np.float64, order="C", ensure_min_samples=2 if fitting else 1
        )
        d = int(x.shape[1])
        if fitting:
            if int(self.n_components) > d:
                raise ValueError(
                    f"n_components={self.n_components} exceeds the dimension of the vectors "
                    f"(n_features = {d}); lower n_components"
                )
            return x
        expected = int(getattr(self, "n_features_in_", self.dim))
        if d != expected:
            raise ValueError(
                f"X has {d} features, but PrimitiveModel is expecting {expected} features as "
                f"input (segment vectors of shape (N, {expected}), or trials)"
            )
        return x

    def _fit_array(self, X: Any, *, source: Provenance) -> PrimitiveModel:
        """``fit`` on vectors (N, d): segment vectors (d = C n_samples), or any features, for
        which the PCA and k-means parts work but the angle-curve methods do not."""
        x = self._check_vectors(X, fitting=True)
        for attr in [a for a in vars(self) if a.endswith("_") and not a.startswith("_")]:
            delattr(self, attr)
        n = x.shape[0]
        sv = SegmentVectors(
            vectors=x,
            trial=np.full(n, -1, dtype=np.int64),
            starts=np.full(n, np.nan),
            ends=np.full(n, np.nan),
            n_samples=int(self.n_samples),
            offsets=np.zeros((n, self.n_channels)),
        )
        return self._fit_vectors(sv, None, source=source)

    def fit_transform(
        self, X: ArrayLike | Sequence[Trial], y: Any = None, **fit_params: Any
    ) -> NDArray[np.float64]:
        """Fit, then return the projections of the training segments.

        Parameters
        ----------
        X : array-like of shape (N, d), or list of Trial
            Training segment vectors (radians) or trials (see :meth:`fit`).
        y : None
            Ignored.
        **fit_params : dict
            Passed to :meth:`fit` (``source``).

        Returns
        -------
        ndarray of shape (N, f)
            The projections of the training segments, equal to ``fit(X).transform(X)``.
        """
        self.fit(X, y, **fit_params)
        return np.array(self.training_projections_, dtype=np.float64)

    def fit_predict(
        self, X: ArrayLike | Sequence[Trial], y: Any = None, **fit_params: Any
    ) -> NDArray[np.int64]:
        """Fit, then return the primitive of each training segment (``labels_``).

        Parameters
        ----------
        X : array-like of shape (N, d), or list of Trial
            Training segment vectors (radians) or trials (see :meth:`fit`).
        y : None
            Ignored.
        **fit_params : dict
            Passed to :meth:`fit` (``source``).

        Returns
        -------
        ndarray of shape (N,)
            Primitive index of each training segment.
        """
        self.fit(X, y, **fit_params)
        return np.array(self.labels_, dtype=np.int64)

    def score(self, X: ArrayLike | Sequence[Trial] | Trial, y: Any = None) -> float:
        """Negative total error: ``−mean ‖s − (E_f c + s̄)‖²`` over the segments of ``X``.

        Each segment vector ``s`` is rebuilt from the centre ``c`` of its primitive; this is
        Table 3's total error (projection + clustering, see :mod:`visprim.accuracy`) on
        ``X`` instead of the training segments. Higher is better, so ``GridSearchCV`` can
        pick ``n_components``, ``n_clusters``, the segmentation...

        Parameters
        ----------
        X : array-like of shape (N, d), Trial or list of Trial
            Segment vectors in radians, or trial(s) (see :meth:`transform`).
        y : None
            Ignored.

        Returns
        -------
        float
            Minus the mean squared error per segment vector, rad².
        """
        self._check_fitted()
        x, _ = self._segment_vectors_of(X)
        rebuilt = self._reconstruct_vectors(x, "cluster")
        return -float(np.mean(np.sum((x - rebuilt) ** 2, axis=1)))


def rebuild_from_centers(
    model: PrimitiveModel,
    vectors: ArrayLike,
    centers: ArrayLike,
    *,
    amplitude: bool | None = None,
) -> NDArray[np.float64]:
    """Segment vectors ``(N, d)`` rebuilt from the nearest of ``centers`` ``(k, f)`` to
    their projections (the model's ``E_f`` and ``s̄``), each scaled by its least-squares
    amplitude against the segment's own vector when ``amplitude`` (default: the model's
    ``amplitude`` parameter)."""
    x = np.ascontiguousarray(np.atleast_2d(vectors), dtype=np.float64)
    c = np.ascontiguousarray(centers, dtype=np.float64)
    labels, _ = kernels.kmeans_predict(model.transform(x), c)
    rebuilt = c[np.asarray(labels)] @ model.components_.T + model.mean_
    if model.amplitude if amplitude is None else amplitude:
        rebuilt *= amplitude_gains(x, rebuilt)[:, None]
    return rebuilt


def _are_trials(X: Any) -> TypeGuard[Sequence[Trial] | Trial]:
    """Whether ``fit`` takes ``X`` as trials (else as segment vectors): a Trial, or a
    sequence that is not rows of numbers (other items are reported by :func:`_as_trials`)."""
    if isinstance(X, Trial):
        return True
    if isinstance(X, np.ndarray):
        return X.dtype == object and X.size > 0 and isinstance(X.flat[0], Trial)
    if isinstance(X, (list, tuple)):
        if not X:
            return True
        first = X[0]
        row = isinstance(first, (list, tuple)) or (
            isinstance(first, np.ndarray) and first.ndim <= 1
        )
        return not (row or isinstance(first, (int, float, np.number)))
    return False


def _as_trials(trials: Sequence[Trial] | Trial) -> list[Trial]:
    if isinstance(trials, Trial):
        return [trials]
    out = list(trials)
    if not out:
        raise ValueError("expected at least one Trial, got an empty sequence")
    for i, t in enumerate(out):
        if not isinstance(t, Trial):
            raise TypeError(f"item {i} is a {type(t).__name__}, expected visprim.Trial")
    return out


def _nearest_turns(
    angles: NDArray[np.float64], reference: NDArray[np.float64], n_arms: int
) -> NDArray[np.float64]:
    """``angles`` with γ and α of each arm shifted by the whole turns that bring their mean
    closest to ``reference``'s (angles rebuilt from directions start on the principal
    branch; the trial's own angles are unwrapped from wherever the trial started)."""
    out = angles.copy()
    for c in periodic_channels("zyz", n_arms):
        turns = np.round(np.mean(reference[:, c] - out[:, c]) / (2 * np.pi))
        out[:, c] += 2 * np.pi * turns
    return out


def _mean_durations(
    durations: NDArray[np.float64], labels: NDArray[np.int64], k: int
) -> NDArray[np.float64]:
    """Mean member duration per cluster; a cluster without members gets the overall mean."""
    counts = np.bincount(labels, minlength=k).astype(np.float64)
    sums = np.bincount(labels, weights=durations, minlength=k)
    overall = float(np.mean(durations))
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(counts > 0, sums / np.maximum(counts, 1), overall)
    return out


def _as_provenance(source: Provenance | Mapping[str, Any]) -> Provenance:
    """``fit``'s ``source``: a record, or its dict (checked)."""
    if isinstance(source, Provenance):
        return source
    if isinstance(source, Mapping):
        return Provenance.from_dict(source)
    raise TypeError(f"source must be a visprim.provenance.Provenance, got {type(source).__name__}")


def _eigen_movements(arrays: Mapping[str, NDArray[Any]]) -> Any:
    """The eigen-movements of a model file's (checked) arrays, or None (older files)."""
    if "eigen_movements_mean" not in arrays:
        return None
    from visprim.rate.descriptions import EigenMovements

    mean = arrays["eigen_movements_mean"]
    return EigenMovements(mean, arrays["eigen_movements_components"], mean.size // 6, {})


def _fitted_value(value: Any) -> Any:
    """A fitted attribute as the model file's header holds it (JSON types)."""
    if isinstance(value, Provenance):
        return value.to_dict()
    if isinstance(value, tuple):
        return list(value)
    if isinstance(value, (np.integer, np.floating)):
        return value.item()
    if isinstance(value, list):
        return [str(v) for v in value]
    return value


#: Longest mean primitive duration a model file may hold, seconds.
MAX_PRIMITIVE_S = 3600.0


def check_fitted_arrays(model: PrimitiveModel) -> str | None:  # noqa: C901 (a flat list)
    """The first inconsistency between a (loaded) model's arrays and its parameters, or
    None: shapes (d, f, k, N), finite values, labels in range, segment times finite and
    ordered, primitive durations finite, positive and at most :data:`MAX_PRIMITIVE_S`
    (NaN for a model fitted on bare vectors)."""
    trial = model.segment_trial_
    bare = trial.ndim == 1 and trial.size > 0 and bool(np.all(trial == -1))
    # Bare vectors may be any features; segment vectors have the parameters' dimension.
    d = int(model.mean_.shape[0]) if bare and model.mean_.ndim == 1 else model.dim
    f, k = int(model.n_components), int(model.n_clusters)
    centers, labels = model.cluster_centers_, model.labels_
    n = labels.shape[0] if labels.ndim == 1 else -1
    shapes = {
        "mean": (model.mean_, (d,)),
        "eigenvalues": (model.eigenvalues_, (d,)),
        "cluster_centers": (centers, (k, f)),
        "labels": (labels, (n,)),
        "segment_trial": (model.segment_trial_, (n,)),
        "segment_starts": (model.segment_starts_, (n,)),
        "segment_ends": (model.segment_ends_, (n,)),
        "primitive_durations": (model.primitive_durations_, (k,)),
    }
    for name, (arr, shape) in shapes.items():
        if arr.shape != shape:
            return f"'{name}' has shape {arr.shape}, the parameters need {shape}"
    e = model.eigenvectors_
    if e.ndim != 2 or e.shape[0] != d or not f <= e.shape[1] <= d:
        return f"'eigenvectors' has shape {e.shape}, the parameters need ({d}, f..{d}) with f = {f}"
    if n < max(k, 2) or model.n_training_segments_ != n:
        return f"{n} training segments for {k} primitives ({model.n_training_segments_} recorded)"
    for name in ("mean", "eigenvalues", "eigenvectors", "cluster_centers"):
        if not np.all(np.isfinite(getattr(model, name + "_"))):
            return f"'{name}' holds values that are not finite"
    if labels.dtype.kind != "i" or labels.size and (labels.min() < 0 or labels.max() >= k):
        return f"'labels' are not primitive indices in [0, {k})"
    n_trials = len(model.trial_names_)
    if not bare and (trial.min() < 0 or trial.max() >= max(n_trials, 1)):
        return f"'segment_trial' is not a trial index in [0, {n_trials})"
    starts, ends, durations = model.segment_starts_, model.segment_ends_, model.primitive_durations_
    if bare:
        if not (np.all(np.isnan(starts)) and np.all(np.isnan(ends))):
            return "a model fitted on bare vectors has segment times"
        if not np.all(np.isnan(durations) | ((durations > 0) & (durations <= MAX_PRIMITIVE_S))):
            return "'primitive_durations' out of range"
    else:
        if not (np.all(np.isfinite(starts)) and np.all(np.isfinite(ends))):
            return "segment times are not finite"
        if np.any(ends <= starts):
            return "a segment ends before it starts"
        if not (np.all(np.isfinite(durations)) and np.all(durations > 0)):
            return "'primitive_durations' are not finite positive seconds"
        if np.any(durations > MAX_PRIMITIVE_S):
            return f"'primitive_durations' exceed {MAX_PRIMITIVE_S:g} s"
    tv = model.training_vectors_
    if tv is not None and (tv.shape != (n, d) or not np.all(np.isfinite(tv))):
        return f"'training_vectors' are not {n} finite vectors of dimension {d}"
    return None
