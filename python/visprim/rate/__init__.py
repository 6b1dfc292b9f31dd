"""Rate–distortion of movement descriptions (``visprim evaluate --rate``).

How well is a movement that the primitives have never seen rebuilt, and how many numbers
does its description need? Every description below is measured on held-out groups (leave
one group out: each group, e.g. an HDM05 actor, is held out in turn and everything is
learned from the others) by

* its **rate**: the numbers it stores per second of movement, counted honestly: per
  segment a primitive id, a duration and the segment's mean posture (one number per channel,
  6 for one arm's two bone directions), plus whatever the description adds (a gain, residual
  or projection coefficients, warp numbers); per movement its start time. Baselines store
  their samples or coefficients per channel plus the movement's start and duration;
* its **distortion**: the RMS angle, degrees, between the bone directions (upper arm and
  forearm) of the whole held-out movement and of its rebuilding (:func:`bone_rms_deg`), and
  the joint-space RMS (shoulder geodesic angle and elbow, as ``visprim imitate`` reports);
  the median over held-out movements, with the spread of the per-group medians.

Two-arm recordings are cut into one-arm movements (:func:`visprim.trial.split_arms`, the left
arm mirrored) and the one-arm primitives are learned from both arms of the training groups.
Each movement is segmented with SEG-2 (the constant tuned on the training groups) and every
segment is rebuilt by a description (:data:`FAMILIES`):

``nearest``
    the nearest of k primitives, placed at the segment's mean posture and stretched to its
    duration (k in :data:`RATE_K`); ``nearest+gain`` also scales it by its least-squares
    amplitude (:func:`visprim.vectors.amplitude_gains`, one more number).
``residual``
    the nearest primitive plus the segment's first m coefficients along the eigen-primitives,
    taken relative to the centre (m numbers more): with m = f this *is* the projection.
``projection``
    the segment's own first m PCA coefficients (no primitive id).
``nearest+dct``
    the nearest of 30 primitives corrected by the first q non-constant DCT-II coefficients
    of each of the 6 shape channels of its residual (:func:`dct_residual`, 6 q numbers more).
``warp``
    the nearest primitive with its gain and a monotone time warp inside the segment,
    ``u → u + w u (1 − u)``, ``|w| < 1``, one number (:func:`warp_curves`), the primitive and
    warp chosen together among the nearest few primitives.
``eigen``, ``eigen/dct``
    no segments: the whole movement's bone directions, resampled onto its own duration,
    as the mean plus a superposition of its first m eigen-movements (the principal
    components of the training movements so resampled, :class:`EigenMovements`);
    ``eigen/dct`` lets the encoder take instead the truncated DCT of the 4 arm angles of
    the same size, whichever rebuilds the movement closer, and stores one number that says
    which. They store the start, the duration (and the flag) and ``floor(rate × seconds)``
    numbers in all (:func:`eigen_numbers`), at the rates :data:`BASELINE_RATES`.
``eigen/dct-splitD``, ``eigen/dct-fitD``
    as ``eigen/dct``, with the DCT alternative coded better for the same numbers: the
    encoder also chooses how the DCT's coefficients are split over the 4 angle channels,
    among every split with each channel within D coefficients of the even share
    (:func:`dct_splits`), and the one number that ``eigen/dct`` spends on its flag holds
    the choice (an integer: the eigen-movements or one split); ``fit`` then fits the
    chosen split's coefficients to the movement's bone directions
    (:func:`fit_dct_coefficients`) instead of taking the truncated DCT of its angles. The
    decoder is the same: the first coefficients of each channel, inverse DCT, angles to
    bone directions. The nested search chooses D among 1, 2, 3 (at the rates
    :data:`~visprim.rate.descriptions.SPLIT_RATES`).
``keyframes``, ``dct``
    baselines on the same movements: each channel (the 4 arm angles, or the 6 bone-direction
    coordinates) sampled at equally spaced instants and joined by a cubic spline, or its
    first DCT-II coefficients, at the rates :data:`BASELINE_RATES`; ``dct-angles-fit``
    the same DCT of the angles with its coefficients fitted to the bone directions
    (:func:`fit_dct_coefficients`), what the fit alone gives a DCT coder.

Primitive centres are either the k-means centres in the f-D projection space (the paper
and :class:`~visprim.model.PrimitiveModel`, ``centres="projection"``, the default) or the
means of the members' full segment vectors (``centres="members"``, which keep what the f
eigenvectors drop); on HDM05 (leave one actor out) both rebuild within 0.2° of each other at
every k, so the default stays the model's own. A segment's posture is stored as each
channel's mean (``posture="mean"``, 6 numbers per arm) or as the two unit bone directions
of that mean (``posture="unit"``, 4 numbers, :func:`unit_posture`, the default).
``max_stroke`` (seconds, default 0.8) cuts every segment longer than that into equal parts,
in training and held-out movements alike.

The defaults (:data:`visprim.params.RATE_OPTIONS`) are the settings that the nested
leave-one-group-out of :mod:`visprim.rate.nested` chose on HDM05 (docs/rate.rst).
Modules: :mod:`~visprim.rate.descriptions` (what a description stores and rebuilds),
:mod:`~visprim.rate.measures` (errors, keyframe and DCT baselines),
:mod:`~visprim.rate.benchmark`, :mod:`~visprim.rate.nested`, :mod:`~visprim.rate.report`
and :mod:`~visprim.rate.budget` (one movement within a budget, ``visprim imitate
--budget``).

Everything here is plain NumPy on a few hundred segments. On HDM05 the full benchmark
takes about 10 s of CPU per fold (SEG-2 tuning and scoring every description), and
``visprim evaluate --rate-only --rate-nested`` a few minutes in all on two cores.
"""

from visprim.rate.benchmark import (
    HeldOut,
    RateResult,
    evaluate_rate,
    on_clock,
    rate_benchmark,
    split_long,
)
from visprim.rate.budget import Description, describe_segments, share_budget
from visprim.rate.descriptions import (
    BASELINE_RATES,
    CENTRES,
    EIGEN_FAMILIES,
    FAMILIES,
    POSTURES,
    RATE_K,
    RATE_M,
    Codebook,
    EigenMovements,
    best_dct_split,
    dct_residual,
    dct_splits,
    eigen_describe,
    eigen_numbers,
    fit_codebook,
    fit_dct_coefficients,
    fit_eigen_movements,
    movement_numbers,
    rebuild_segments,
    segment_numbers,
    unit_bones,
    unit_posture,
    warp_curves,
)
from visprim.rate.measures import bone_rms_deg, dct_rebuild, joint_rms_deg, keyframe_rebuild
from visprim.rate.nested import NestedResult, nested_rate, nested_rate_benchmark
from visprim.rate.report import best_within, rate_markdown, write_rate_report

__all__ = [
    "BASELINE_RATES",
    "CENTRES",
    "EIGEN_FAMILIES",
    "FAMILIES",
    "POSTURES",
    "RATE_K",
    "RATE_M",
    "Codebook",
    "Description",
    "EigenMovements",
    "HeldOut",
    "NestedResult",
    "RateResult",
    "best_dct_split",
    "best_within",
    "bone_rms_deg",
    "dct_rebuild",
    "dct_residual",
    "dct_splits",
    "describe_segments",
    "eigen_describe",
    "eigen_numbers",
    "evaluate_rate",
    "fit_codebook",
    "fit_dct_coefficients",
    "fit_eigen_movements",
    "joint_rms_deg",
    "keyframe_rebuild",
    "movement_numbers",
    "nested_rate",
    "nested_rate_benchmark",
    "on_clock",
    "rate_benchmark",
    "rate_markdown",
    "rebuild_segments",
    "segment_numbers",
    "share_budget",
    "split_long",
    "unit_bones",
    "unit_posture",
    "warp_curves",
    "write_rate_report",
]
