"""The settings of the method, declared once: :class:`~visprim.model.PrimitiveModel`'s
parameters, the paper's preset, the study's frame period and the short-trial policy.

Each parameter of :data:`PARAMETERS` carries its default, its constraint (the allowed
values, as scikit-learn's ``_parameter_constraints``), a one-line description with its
unit, the command-line option that sets it (with the option's unit when it is not the
API's) and the value the paper's preset fixes, if it fixes one. Everything else reads
this table:

- ``PrimitiveModel.__init__``'s defaults (a test checks they are these), its
  ``_validate_params`` (:func:`check_params`) and ``PrimitiveModel.paper()``
  (:data:`PAPER`);
- the command-line model options (:func:`visprim.cli.common.add_model_options`,
  ``MODEL_OPTIONS``, ``model_from_args``) and ``visprim demo``'s preset.

Units: the API works in seconds and radians (``zvc_threshold_deg`` is the one parameter in
degrees); the command line prints and reads degrees, so ``--seg2-threshold`` takes
(deg/s)², converted here (:meth:`Parameter.from_option`).

This module imports nothing heavy (it is read when the command line builds its parser).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

__all__ = [
    "CLASSIFIER_PARAMETERS",
    "COMBINED_TERMS",
    "DEG2_PER_RAD2",
    "FEATURES",
    "MOTION_METHODS",
    "OFFSETS",
    "PAPER",
    "PARAMETERS",
    "RATE_OPTIONS",
    "SEG2_BOUNDARIES",
    "SEGMENTATIONS",
    "SHORT_POLICIES",
    "SHORT_POLICY",
    "STUDY_FRAME_PERIOD_S",
    "TERM_WEIGHTS",
    "TUNINGS",
    "Parameter",
    "check_params",
    "defaults",
]

#: The original study's frame period, seconds (FastTrak sensors read every 34 ms). The
#: generated experiment samples at it and recordings are resampled to it by default, so
#: that the cutoff, SEG-1's window and SEG-2's constant mean what they meant in the study.
STUDY_FRAME_PERIOD_S: float = 0.034

#: What ``learn`` does with recordings that have no more frames than the low-pass filter's
#: padding: filter them with less padding ("reduce"), leave them out with a warning
#: ("drop") or stop ("error").
SHORT_POLICIES: tuple[str, ...] = ("reduce", "drop", "error")
#: The default of :data:`SHORT_POLICIES` (the model's own behaviour: pad them less).
SHORT_POLICY: Literal["reduce"] = "reduce"

#: (deg/s)² per (rad/s)²: SEG-2's constant is printed and given on the command line in
#: (deg/s)² and held in (rad/s)² by the API.
DEG2_PER_RAD2: float = math.degrees(1.0) ** 2

#: Segmentation methods (:mod:`visprim.segment`).
SEGMENTATIONS: tuple[str, ...] = ("seg2", "seg1")
#: Channel descriptions (:mod:`visprim.features`).
FEATURES: tuple[str, ...] = ("zyz", "directions")
#: What a segment vector is taken relative to (:mod:`visprim.vectors`).
OFFSETS: tuple[str, ...] = ("turns", "mean")
#: How SEG-2's constant is tuned (:mod:`visprim.segment.seg2`).
TUNINGS: tuple[str, ...] = ("repetitions", "robust")
#: Where SEG-2 puts the boundary after a movement run (:mod:`visprim.segment.seg2`): at the
#: slowest frame of the rest before the next run ("slowest"), or at the run's first stop,
#: the same point whether or not another run follows ("first_stop").
SEG2_BOUNDARIES: tuple[str, ...] = ("slowest", "first_stop")


# ---------------------------------------------------------------------------- constraints


def _is_int(v: Any) -> bool:
    import numbers

    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _is_real(v: Any) -> bool:
    import numbers

    return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(float(v))


def _is_bool(v: Any) -> bool:
    return isinstance(v, bool) or type(v).__name__ == "bool_"


@dataclass(frozen=True)
class Constraint:
    """Allowed values of a parameter: ``accepts(value)`` and the words of the error."""

    accepts: Callable[[Any], bool]
    words: str


def integer(low: int) -> Constraint:
    return Constraint(lambda v: _is_int(v) and v >= low, f"must be an integer >= {low}")


def real(
    low: float, high: float = math.inf, *, open_low: bool, unit: str = "", words: str = ""
) -> Constraint:
    def ok(v: Any) -> bool:
        if not _is_real(v):
            return False
        x = float(v)
        return (x > low if open_low else x >= low) and x < high

    unit = f" {unit}" if unit else ""
    if words:
        return Constraint(ok, words)
    if high < math.inf:
        return Constraint(ok, f"must be a number in ({low:g}, {high:g}){unit}")
    return Constraint(ok, f"must be a finite number {'>' if open_low else '>='} {low:g}{unit}")


def options(values: tuple[str, ...]) -> Constraint:
    return Constraint(
        lambda v: isinstance(v, str) and v in values, f"must be one of {list(values)}"
    )


BOOLEAN = Constraint(_is_bool, "must be True or False")


def optional(c: Constraint, none_means: str) -> Constraint:
    return Constraint(
        lambda v: v is None or c.accepts(v),
        f"must be None ({none_means}) or {c.words.removeprefix('must be ')}",
    )


# ---------------------------------------------------------------------------- parameters

#: The paper's preset leaves a parameter as given (its default is already the paper's).
_FREE = object()


@dataclass(frozen=True)
class Parameter:
    """One parameter of :class:`~visprim.model.PrimitiveModel`.

    Attributes
    ----------
    name : the constructor argument.
    default : its default value.
    constraint : the allowed values.
    doc : what it is, with its unit (one line).
    option : the command-line option that sets it (None: not on the command line).
    help : the option's help (its default and the paper's value are added).
    paper : the value the paper's preset fixes (see :attr:`fixed_by_paper`).
    option_scale : option value = API value x ``option_scale`` (unit conversion).
    option_unit : the option's unit when it is not the API's.
    """

    name: str
    default: Any
    constraint: Constraint
    doc: str
    option: str | None
    help: str = ""
    paper: Any = _FREE
    option_scale: float = 1.0
    option_unit: str = ""
    choices: tuple[str, ...] | None = field(default=None)

    @property
    def fixed_by_paper(self) -> bool:
        """Whether :meth:`PrimitiveModel.paper` fixes this parameter."""
        return self.paper is not _FREE

    @property
    def dest(self) -> str | None:
        """The ``argparse`` attribute of the option."""
        return None if self.option is None else self.option.lstrip("-").replace("-", "_")

    def from_option(self, value: Any) -> Any:
        """The API value of a value given to :attr:`option` (in the option's unit)."""
        if value is None or self.option_scale == 1.0:
            return value
        return float(value) / self.option_scale

    def to_option(self, value: Any) -> Any:
        """``value`` (API unit) in the option's unit, to print it."""
        if value is None or self.option_scale == 1.0:
            return value
        return float(value) * self.option_scale

    def check(self, value: Any) -> str | None:
        """None if ``value`` is allowed, else the reason."""
        return None if self.constraint.accepts(value) else self.constraint.words


_P = Parameter
#: Every parameter of :class:`~visprim.model.PrimitiveModel`, in the constructor's order.
PARAMETERS: tuple[Parameter, ...] = (
    _P(
        "filter_order",
        10,
        integer(1),
        "Butterworth order of the zero-phase low-pass",
        "--filter-order",
        "Butterworth order",
    ),
    _P(
        "cutoff",
        0.25,
        real(
            0.0,
            1.0,
            open_low=True,
            words="must be a number between 0 and 1 (exclusive), a fraction of Nyquist",
        ),
        "normalised cutoff of the low-pass, a fraction of the Nyquist frequency, in (0, 1)",
        "--cutoff",
        "normalised low-pass cutoff, fraction of Nyquist",
    ),
    _P(
        "segmentation",
        "seg2",
        options(SEGMENTATIONS),
        "which segmentation produces the training segments",
        "--segmentation",
        "segmentation of the training movements",
        choices=SEGMENTATIONS,
    ),
    _P(
        "zvc_threshold_deg",
        5.0,
        real(0.0, open_low=False, unit="(degrees)"),
        "significant-movement threshold of the zero-velocity crossings, degrees (SEG-1)",
        "--zvc-threshold",
        "ZVC significant-movement threshold, degrees",
    ),
    _P(
        "window",
        0.3,
        real(0.0, open_low=True, unit="(seconds)"),
        "SEG-1 window, seconds",
        "--window",
        "SEG-1 window, s",
    ),
    _P(
        "seg1_adaptive",
        True,
        BOOLEAN,
        "SEG-1 cuts fast cyclic motion at its half-cycles with a shorter window",
        "--seg1-adaptive",
        "SEG-1 cuts fast cyclic motion at its half-cycles (--no-seg1-adaptive: the "
        "paper's fixed window)",
        paper=False,
    ),
    _P(
        "seg2_threshold",
        None,
        optional(real(0.0, open_low=True, unit="(rad/s)^2"), "tune it"),
        "SEG-2 constant c on the summed squared channel velocity, (rad/s)^2; None tunes it",
        "--seg2-threshold",
        "SEG-2 constant c, (deg/s)^2 as learn prints it",
        option_scale=DEG2_PER_RAD2,
        option_unit="(deg/s)^2",
    ),
    _P(
        "seg2_tuning",
        "robust",
        options(TUNINGS),
        "how an unset SEG-2 constant is tuned: to the corpus' speed, or the paper's rule "
        "from the repetitions",
        "--seg2-tuning",
        "how SEG-2's c is tuned: to the corpus' speed or the paper's rule from the repetitions",
        paper="repetitions",
        choices=("robust", "repetitions"),
    ),
    _P(
        "seg2_boundary",
        "slowest",
        options(SEG2_BOUNDARIES),
        "where SEG-2 cuts after a movement run: the slowest frame of the rest before the "
        "next run, or the run's first stop (first local minimum of the squared speed, or "
        "rest), the same whether or not another run follows",
        "--seg2-boundary",
        "where SEG-2 cuts after a run: the slowest frame of the following rest, or the "
        "run's first stop (lets the online segmenter close each segment at once: "
        "for models used live)",
        paper="slowest",
        choices=SEG2_BOUNDARIES,
    ),
    _P(
        "features",
        "directions",
        options(FEATURES),
        "what segments are made of: unit bone directions or Z-Y-Z Euler angles and elbow",
        "--features",
        "what segments are made of: bone directions or the paper's Z-Y-Z angles",
        paper="zyz",
        choices=("directions", "zyz"),
    ),
    _P(
        "offsets",
        "mean",
        options(OFFSETS),
        "what each segment vector is relative to: its channels' mean, or absolute up to "
        "whole turns",
        "--offsets",
        "segment vectors relative to each segment's mean posture, or absolute up to whole "
        "turns (the paper)",
        paper="turns",
        choices=("mean", "turns"),
    ),
    _P(
        "amplitude",
        False,
        BOOLEAN,
        "rebuild a segment from its primitive scaled by a least-squares gain (needs "
        "offsets='mean')",
        "--amplitude",
        "rebuild each segment from its primitive scaled by a least-squares gain",
    ),
    _P(
        "n_samples",
        100,
        integer(2),
        "samples per channel in a segment vector",
        "--samples",
        "samples per channel",
    ),
    _P("n_components", 30, integer(1), "eigenvectors kept, f", "--components", "eigenvectors f"),
    _P(
        "n_clusters",
        30,
        integer(1),
        "k-means clusters = primitives, k",
        "--clusters",
        "primitives k",
    ),
    _P("n_init", 10, integer(1), "k-means restarts", "--n-init", "k-means restarts"),
    _P(
        "max_iter",
        300,
        integer(1),
        "k-means iterations per restart",
        "--max-iter",
        "k-means iterations per restart",
    ),
    _P(
        "tol",
        1e-4,
        real(0.0, open_low=False),
        "k-means convergence tolerance (scikit-learn's meaning)",
        None,
    ),
    _P("seed", 0, integer(0), "seed of k-means", "--seed", "k-means seed"),
)

#: The parameters by name.
BY_NAME: Mapping[str, Parameter] = {p.name: p for p in PARAMETERS}

#: The paper's exact method: the values its preset fixes (the other defaults are the
#: paper's already).
PAPER: Mapping[str, Any] = {p.name: p.paper for p in PARAMETERS if p.fixed_by_paper}


def defaults() -> dict[str, Any]:
    """Every parameter's default."""
    return {p.name: p.default for p in PARAMETERS}


def check_params(params: Mapping[str, Any], owner: str = "PrimitiveModel") -> None:
    """Raise ValueError naming the first parameter of ``params`` that its constraint
    refuses (unknown names are refused too)."""
    for name, value in params.items():
        p = BY_NAME.get(name)
        if p is None:
            raise ValueError(f"{owner} has no parameter {name!r}")
        why = p.check(value)
        if why is not None:
            raise ValueError(f"{owner} parameter {name}={value!r}: {why}")


# ---------------------------------------------------------------------------- classifier

#: Descriptions :class:`~visprim.classify.MotionClassifier` compares movements by.
MOTION_METHODS: tuple[str, ...] = ("combined", "frames", "coordinates", "segments", "histogram")
#: The DTW costs summed by ``MotionClassifier(method="combined")``, in order; the first has
#: weight 1, each other one of :data:`TERM_WEIGHTS` (chosen in ``fit``).
COMBINED_TERMS: tuple[str, ...] = ("coordinates", "segments", "velocity", "duration")
#: Candidate weights of each further term of ``method="combined"`` (each cost already divided
#: by its median over pairs of training movements); ``fit`` picks them by leave-one-group-out
#: on the training groups.
TERM_WEIGHTS: tuple[float, ...] = (0.0, 0.25, 0.5, 1.0)


def _weights(v: Any) -> bool:
    try:
        items = tuple(v)
    except TypeError:
        return False
    return bool(items) and all(_is_real(w) and float(w) >= 0 for w in items)


#: The settings of :class:`~visprim.classify.MotionClassifier` (its constructor's
#: defaults are these; ``model_params`` are :data:`PARAMETERS`).
CLASSIFIER_PARAMETERS: tuple[Parameter, ...] = (
    _P(
        "method",
        "combined",
        options(MOTION_METHODS),
        "what movements are compared by (see MotionClassifier)",
        "--method",
        "MotionClassifier method",
        choices=MOTION_METHODS,
    ),
    _P(
        "window",
        1.0,
        real(0.0, open_low=True, unit="(median segment durations)"),
        "window of the per-frame descriptions, a multiple of the median training segment duration",
        None,
    ),
    _P(
        "band",
        None,
        Constraint(
            lambda v: v is None or (_is_real(v) and 0.0 <= float(v) <= 1.0),
            "must be None (no band) or a fraction in [0, 1]",
        ),
        "Sakoe-Chiba band of the DTW, a fraction of the length",
        "--band",
        "Sakoe-Chiba band of the DTW, fraction of the length",
    ),
    _P("n_neighbors", 1, integer(1), "training movements voting", None),
    _P(
        "step",
        2,
        integer(1),
        "the per-frame descriptions are taken at every step-th frame",
        "--step",
        "per-frame descriptions at every STEP-th frame",
    ),
    _P(
        "term_weights",
        TERM_WEIGHTS,
        Constraint(_weights, "must be a non-empty sequence of finite numbers >= 0"),
        "candidate weights of each further DTW cost of method='combined'",
        None,
    ),
    _P(
        "torso",
        True,
        BOOLEAN,
        "method='combined' also sums the DTW cost of the trunk's pose (torso_pose)",
        None,
    ),
)


# ---------------------------------------------------------------------------- reader options

#: What happens at a recording gap longer than ``max_gap`` (:mod:`visprim.io.gaps`).
ON_GAP: tuple[str, ...] = ("split", "longest", "raise")
#: How gaps up to ``max_gap`` are filled (:mod:`visprim.io.gaps`).
GAP_METHODS: tuple[str, ...] = ("cubic", "pchip", "linear")
#: A file's vertical axis (:mod:`visprim.io.assemble`).
UP_AXES: tuple[str, ...] = ("+x", "-x", "+y", "-y", "+z", "-z")
#: Which markers a C3D trial carries: the arm's virtual sensors or the file's own.
MARKER_SOURCES: tuple[str, ...] = ("virtual", "file")


@dataclass(frozen=True)
class ReadOption:
    """One keyword option of :func:`visprim.io.read_pieces` (and ``read``, ``read_many``,
    :class:`visprim.io.Corpus`): its default and the formats it applies to (None: all)."""

    name: str
    default: Any
    formats: tuple[str, ...] | None = None


#: Every reader option (besides ``arm``), declared once: the readers, their checks, the
#: lazy corpus and the command line's reader options read this.
READ_OPTIONS: Mapping[str, ReadOption] = {
    o.name: o
    for o in (
        ReadOption("skeleton", None, ("amc",)),
        ReadOption("rate", None, ("amc",)),
        ReadOption("mapping", None, ("bvh", "amc", "c3d", "trc")),
        ReadOption("preset", None, ("bvh", "amc", "c3d")),
        ReadOption("up_axis", None, ("bvh", "amc", "c3d", "amass", "trc", "video")),
        ReadOption("units", None, ("bvh",)),
        ReadOption("markers", "virtual"),
        ReadOption("max_gap", 0.2),
        ReadOption("on_gap", "split"),
        ReadOption("gap_method", "cubic"),
        ReadOption("min_duration", 0.5),
        ReadOption("resample", None),
        ReadOption("repetitions", None),
        ReadOption("mirror", False, ("bvh", "amc", "c3d", "amass", "trc", "video")),
        ReadOption("person", None, ("video",)),
    )
}


# ---------------------------------------------------------------------------- rate benchmark


@dataclass(frozen=True)
class RateOption:
    """One setting of the rate–distortion benchmark (:mod:`visprim.rate`, ``visprim
    evaluate --rate``): its default, the values the nested leave-one-group-out searches
    (:mod:`visprim.rate.nested`) and what it means."""

    name: str
    default: Any
    searched: tuple[Any, ...]
    help: str


#: Every setting of the rate benchmark, declared once: the benchmark, its nested search and
#: the command line read this. The defaults are the settings the nested leave-one-actor-out
#: on HDM05 chose most often within 12 numbers per second (docs/rate.rst).
RATE_OPTIONS: Mapping[str, RateOption] = {
    o.name: o
    for o in (
        RateOption(
            "posture",
            "unit",
            ("mean", "unit"),
            "a segment's posture: its 6 channel means, or the 2 unit bone directions of that "
            "mean (4 numbers)",
        ),
        RateOption(
            "max_stroke",
            0.8,
            (None, 0.8),
            "segments longer than this many seconds are cut into equal parts (None: never)",
        ),
        RateOption(
            "centres",
            "projection",
            ("projection",),
            "primitive centres: k-means centres in the projection space (the paper's) or the "
            "means of the members' segment vectors ('members', within 0.2 degrees on HDM05)",
        ),
    )
}


# ---------------------------------------------------------------------------- video keypoints

#: Four-view triangulation (:func:`visprim.io.views.triangulate_keypoints`): an observation
#: whose reprojection error exceeds this many pixels is left out (worst view first, while
#: more than ``min_views`` remain). Pose2Sim's default threshold, for 1080p views.
TRIANGULATION_MAX_REPROJECTION_PX: float = 15.0

#: Time alignment of the views (``sync`` of :func:`visprim.io.read_views`): False takes the
#: videos as frame-synchronised (frame i of each is the same instant); True estimates each
#: view's whole-frame offset from the data (:func:`visprim.io.views.estimate_offsets`). Off by
#: default, by measurement (benches/video_accuracy.py, docs/video.rst): on the shared,
#: hardware-synchronised Pose2Sim clip the pairs of views disagree on the offsets (by 2
#: frames), and applying them neither lowers the reprojection error consistently nor moves
#: any single camera's agreement with the reference; turn it on for cameras started by hand.
VIEWS_SYNC: bool = False
#: The largest offset (s) ``sync=True`` searches, either way (at 60 fps, 12 frames).
VIEWS_SYNC_MAX_OFFSET_S: float = 0.2

#: Self-calibration of the cameras (``refine_calibration`` of :func:`visprim.io.read_views`,
#: :mod:`visprim.io.refine`): ``"auto"`` refines unless a view
#: found several people (the views may then follow different people, which the held-out
#: check cannot tell from a calibration error); True always tries, False never (see
#: ``docs/video.rst`` for the measurements that set it).
VIEWS_REFINE_CALIBRATION: bool | str = "auto"

#: Zero-phase low-pass cutoff (Hz) of video keypoints before they become a trial
#: (``lowpass_hz`` of :func:`visprim.io.keypoints.trial_pieces_from_keypoints`; None: no
#: smoothing). Chosen by ``benches/video_accuracy.py`` (single camera against the four-view
#: reference, leave one camera out; see docs/video.rst).
VIDEO_LOWPASS_HZ: float | None = None
#: Butterworth order of that low-pass (forward and backward, so twice this in effect).
VIDEO_LOWPASS_ORDER: int = 4
#: Single-view reading (:func:`visprim.io.video.read_video_pieces`): put back the frames where
#: the estimator took the person for their mirror image (left and right labels exchanged),
#: found by the image continuity of the limbs (:mod:`visprim.io.video_sides`). On by
#: measurement (benches/video_accuracy.py, docs/video.rst).
VIDEO_REPAIR_SIDES: bool = True


# ---------------------------------------------------------------------------- online pipeline

#: SEG-2's least travel of a movement (degrees), offline (:mod:`visprim.segment.seg2`) and
#: online alike.
SEG2_MIN_TRAVEL_DEG: float = 5.0


@dataclass(frozen=True)
class OnlineOption:
    """One setting of the online pipeline (:class:`visprim.online.OnlinePipeline` and its
    segmenter; ``visprim watch``): default, unit, allowed choices and what it means."""

    name: str
    default: Any
    help: str
    unit: str = ""
    choices: tuple[Any, ...] | None = None


#: Every setting of the online pipeline, declared once: the segmenter's and the pipeline's
#: defaults and the options of ``visprim watch`` read this (measurements behind the defaults:
#: docs/online.rst, ``benches/bench_online.py``).
ONLINE_OPTIONS: Mapping[str, OnlineOption] = {
    o.name: o
    for o in (
        OnlineOption(
            "causal_filter",
            "fir",
            "causal low-pass of the angles: an FIR filter that approximates the model's own "
            "zero-phase filter with one frame of look-ahead ('fir'), or a causal "
            "Butterworth filter of filter_order at the model's cutoff ('butterworth')",
            choices=("fir", "butterworth"),
        ),
        OnlineOption(
            "clock",
            "model",
            "frames segmented on the model's clock (its frame_period_: a stream at another "
            "rate is resampled causally by linear interpolation, at most one input frame of "
            "latency; 'model') or at the stream's own times ('stream')",
            choices=("model", "stream"),
        ),
        OnlineOption(
            "filter_order",
            2,
            "order of the causal Butterworth low-pass (causal_filter='butterworth'), at the "
            "model's cutoff (None: the model's own order)",
        ),
        OnlineOption(
            "threshold",
            "adaptive",
            "SEG-2 threshold: c lowered for slow movers as the offline robust tuning does "
            "('adaptive', from the 95th percentile of the recent squared speed), or c as "
            "fitted ('fixed')",
            choices=("adaptive", "fixed"),
        ),
        OnlineOption(
            "rest_timeout",
            1.0,
            "a movement ends after this long without a segment",
            "s",
        ),
        OnlineOption("max_segment", 10.0, "a segment is closed after at most this long", "s"),
        OnlineOption(
            "speed_window", 10.0, "window of the adaptive threshold's recent squared speed", "s"
        ),
        OnlineOption(
            "min_travel_deg",
            SEG2_MIN_TRAVEL_DEG,
            "travel that makes a run of fast frames a movement (the offline SEG-2's "
            "DEFAULT_MIN_TRAVEL_DEG)",
            "deg",
        ),
        OnlineOption(
            "confirm_frames",
            1,
            "an inner boundary is emitted once the next run of fast frames has lasted this "
            "many frames (or travelled min_travel_deg, whichever comes first; None: travel "
            "only, as offline SEG-2; 1: as soon as the speed is back above c)",
            "frames",
        ),
        OnlineOption(
            "segment_filter",
            "zero_phase",
            "a closed segment is described after the model's zero-phase filter over the "
            "frames received ('zero_phase') or after the causal one ('causal')",
            choices=("zero_phase", "causal"),
        ),
        OnlineOption(
            "max_gap",
            READ_OPTIONS["max_gap"].default,
            "a stream with no complete frame for longer than this (a long occlusion, a "
            "stalled feed) is split there, as reading a recording splits at a gap: the "
            "movement in progress ends at the last frame before it, and the frames after it "
            "are segmented afresh (shorter gaps are interpolated across)",
            "s",
        ),
        OnlineOption(
            "max_movement",
            60.0,
            "frames of the movement in progress kept for a whole-movement classifier",
            "s",
        ),
    )
}
