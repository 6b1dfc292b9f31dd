"""What the commands share: errors, option types, reading DATA or the generated experiment,
the model options.

Data: ``DATA...`` are recording files, folders or globs read with
:func:`visprim.io.read_many`; without DATA (or with ``--generated``) the default generated
imitation experiment (:func:`visprim.datasets.imitation_experiment`) is used. The model file
records where its trials came from, so ``visprim report MODEL`` can redraw the per-trial
figures from the same data without DATA.

Frame rate of recordings: the method's low-pass cutoff (``--cutoff``) is a fraction of the
Nyquist frequency and its SEG-1 window and SEG-2 constant were set for the original study's
34 ms frame period, so ``learn`` resamples DATA to ``--resample`` seconds (default 0.034, see
:func:`visprim.io.resample_trial`; ``--no-resample`` keeps each file's rate). The period is
recorded in the model file; ``report`` and ``classify`` resample their DATA the same way.

Errors: a command raises :class:`CLIError` (exit status 1) or :class:`UsageError` (2) with
one line naming the problem and the fix; :func:`visprim.cli.main.main` prints it.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from visprim.params import ON_GAP, SHORT_POLICIES, SHORT_POLICY, STUDY_FRAME_PERIOD_S, UP_AXES
from visprim.provenance import PRESETS, Provenance
from visprim.trial import EACH_ARM, Trial

log = logging.getLogger(__name__)

#: Frame period (s) recordings are resampled to by default: the original study's 34 ms.
DEFAULT_RESAMPLE_S = STUDY_FRAME_PERIOD_S
#: Accepted range of ``--resample`` (s): 0.1 ms to 10 s.
RESAMPLE_RANGE_S = (1e-4, 10.0)


# ---------------------------------------------------------------------------- errors


class CLIError(Exception):
    """A failure the user can fix: one line naming the problem and the fix (exit status 1)."""

    status = 1


class UsageError(CLIError):
    """A bad combination of arguments (exit status 2, like argparse's own usage errors)."""

    status = 2


# ---------------------------------------------------------------------------- option types


def _typed(convert: Callable[[str], Any], check: Callable[[Any], bool], what: str) -> Any:
    def parse(text: str) -> Any:
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if not check(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}")
        return value

    parse.__name__ = what  # argparse names the type in its messages
    return parse


#: ``type=`` for options that count something (>= 1).
positive_int = _typed(int, lambda v: v >= 1, "an integer >= 1")
#: ``type=`` for seeds (>= 0).
seed_int = _typed(int, lambda v: v >= 0, "an integer >= 0")
#: ``type=`` for positive finite numbers.
positive_float = _typed(float, lambda v: math.isfinite(v) and v > 0, "a positive number")
#: ``type=`` for non-negative finite numbers.
nonneg_float = _typed(float, lambda v: math.isfinite(v) and v >= 0, "a number >= 0")
#: ``type=`` for fractions of the Nyquist frequency, in (0, 1).
fraction = _typed(float, lambda v: 0.0 < v < 1.0, "a number between 0 and 1 (exclusive)")
#: ``type=`` for ``--resample`` periods in seconds (see :data:`RESAMPLE_RANGE_S`).
period_s = _typed(
    float,
    lambda v: RESAMPLE_RANGE_S[0] <= v <= RESAMPLE_RANGE_S[1],
    f"a frame period in seconds between {RESAMPLE_RANGE_S[0]:g} and {RESAMPLE_RANGE_S[1]:g}",
)


def add_force_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--force", action="store_true", help="replace an existing output (never done silently)"
    )


# ---------------------------------------------------------------------------- data


def generated_source(args: argparse.Namespace) -> Provenance:
    """The generated experiment the options describe (``--subjects`` ... ``--data-preset``)."""
    return Provenance.generated(
        int(getattr(args, "subjects", 11)),
        int(getattr(args, "stimuli", 20)),
        int(getattr(args, "data_seed", 0)),
        str(getattr(args, "data_preset", "paper")),
    )


def load_source(source: Provenance, lowpass: tuple[int, float] | None = None) -> list[Trial]:
    """The trials of a provenance record (a model's ``provenance_``; see the module
    docstring), bounded as :meth:`Provenance.check_reproducible` says; recordings too short
    for the ``lowpass`` (order, cutoff) are left out as ``learn`` did. Raises
    :class:`CLIError` for a record that cannot (or may not) be read again."""
    from visprim.provenance import ProvenanceError

    try:
        source.check_reproducible()
    except ProvenanceError as exc:
        raise CLIError(f"cannot read the training data again: {exc}; give DATA instead") from None
    if source.kind == "generated":
        from visprim.datasets import imitation_experiment

        return imitation_experiment(
            int(source.n_subjects or 0),
            int(source.n_stimuli or 0),
            int(source.seed or 0),
            preset=str(source.preset),
            **dict(source.generator_options),
        )
    trials = read_files(
        list(source.files), source.frame_period, dict(source.reader_options), on_error="warn"
    )
    return trials if lowpass is None else drop_short(trials, lowpass, source.short)


def read_files(
    paths: Sequence[str],
    resample: float | None = None,
    options: dict[str, Any] | None = None,
    *,
    on_error: str = "raise",
) -> list[Trial]:
    """The trials of ``paths`` (files, folders, globs) read with ``options`` (reader keyword
    arguments, see :func:`reader_options`; ``arm=EACH_ARM`` gives each file's arms as
    one-arm trials); ``on_error="warn"`` skips unreadable files."""
    from visprim.io import FORMATS, read_many

    for item in paths:
        path = Path(item)
        if path.is_file() and path.suffix.lower() not in FORMATS:
            fix = (
                "give its .amc motion file (with --skeleton if needed)"
                if path.suffix.lower() == ".asf"
                else "give recordings, or folders of them"
            )
            raise CLIError(
                f"{item} is not a recording (the readers take {', '.join(sorted(FORMATS))}); " + fix
            )
    options = dict(options or {})
    each = options.get("arm") == EACH_ARM
    if each:
        options["arm"] = "both"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        trials = read_many(list(paths), resample=resample, on_error=on_error, **options)
    if each:
        from visprim.trial import split_arms

        trials = split_arms(trials)
    skipped = [w for w in caught if str(w.message).startswith("skipped")]
    for w in caught:
        log.warning("%s", w.message)
    if skipped:
        log.warning(
            "%d unreadable file(s) skipped (listed above); --strict stops at the first one",
            len(skipped),
        )
    if not trials:
        raise CLIError(
            f"no trials could be read from {', '.join(paths)}; give recordings "
            f"({', '.join(sorted(FORMATS))}) or the reader options their messages ask for"
        )
    return list(trials)


def trials_and_source(
    args: argparse.Namespace,
    resample: float | None = None,
    lowpass: tuple[int, float] | None = None,
) -> tuple[list[Trial], Provenance]:
    """DATA (resampled to ``resample`` s, None = file rate) or the generated experiment.

    ``lowpass``: (order, cutoff) of the model's filter; with ``--short drop`` recordings too
    short for it are left out (see :func:`drop_short`)."""
    data = list(getattr(args, "data", []) or [])
    if data and getattr(args, "generated", False):
        raise UsageError("give DATA files or --generated, not both")
    if data:
        options = reader_options(args, allow_each=True)
        on_error = "raise" if getattr(args, "strict", False) else "warn"
        trials = read_files(data, resample, options, on_error=on_error)
        short = str(getattr(args, "short", SHORT_POLICY))
        if lowpass is not None:
            trials = drop_short(trials, lowpass, short)
        return trials, Provenance.recordings(data, resample, options, short)
    source = generated_source(args)
    return load_source(source), source


def model_lowpass(model: Any) -> tuple[int, float]:
    """(order, cutoff) of a model's low-pass filter."""
    return int(model.filter_order), float(model.cutoff)


def model_period(model: Any) -> float | None:
    """The period DATA given to ``report``/``classify`` is resampled to: the model's
    ``frame_period_`` (None: each file's own rate)."""
    period = model.frame_period_
    return None if period is None else float(period)


def add_generated_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("generated data (used without DATA, or with --generated)")
    g.add_argument("--generated", action="store_true", help="use the generated experiment")
    g.add_argument("--subjects", type=positive_int, default=11, help="subjects (default 11)")
    g.add_argument("--stimuli", type=positive_int, default=20, help="stimuli (default 20)")
    g.add_argument("--data-seed", type=seed_int, default=0, help="generator seed (default 0)")
    g.add_argument(
        "--data-preset",
        choices=PRESETS,
        default="paper",
        help="generator preset: paper-like gestures (default) or easy strokes",
    )


# ---------------------------------------------------------------------------- reader options


def add_reader_options(p: argparse.ArgumentParser, *, many: bool = True) -> None:
    """The options of :func:`visprim.io.read_pieces` that DATA recordings may need
    (``many``: also ``--short`` and ``--strict``, for commands reading several files)."""
    g = p.add_argument_group("reading recordings (DATA; see help(visprim.io))")
    g.add_argument(
        "--arm",
        default="right",
        help="arm to read: right (default), left or both"
        + (
            "; each: both arms, as one-arm recordings (the left mirrored), to learn one-arm "
            "primitives from both"
            if many
            else ""
        ),
    )
    g.add_argument(
        "--skeleton", metavar="ASF", default=None, help="AMC files: the .asf skeleton to use"
    )
    g.add_argument(
        "--rate",
        type=positive_float,
        metavar="HZ",
        default=None,
        help="AMC files: frames per second (default 120, CMU; AMC does not store it)",
    )
    g.add_argument(
        "--preset",
        default=None,
        help="joint/marker naming preset (visprim.io.RIG_PRESETS for BVH/AMC, "
        "MARKER_PRESETS for C3D; default: the first that fits the file)",
    )
    g.add_argument(
        "--mapping",
        type=_mapping,
        default=None,
        metavar="JSON",
        help='explicit names per role as JSON, or a .json file, e.g. \'{"shoulder": '
        '"RightArm", "elbow": "RightForeArm", "wrist": "RightHand"}\'',
    )
    g.add_argument(
        "--up-axis",
        choices=UP_AXES,
        default=None,
        help="the files' vertical axis (default: +y for BVH/AMC, detected for C3D)",
    )
    g.add_argument(
        "--on-gap",
        choices=ON_GAP,
        default=None,
        help="gaps longer than 0.2 s (C3D markers, video and TRC keypoints): split the "
        "recording (default), keep the longest piece, or stop with an error",
    )
    g.add_argument(
        "--person",
        type=_typed(int, lambda v: v >= 0, "a person number (0, 1, ...)"),
        default=None,
        help="videos with several people: follow person N, numbered from 0 by size, largest "
        "first (default: the largest)",
    )
    if not many:
        return
    g.add_argument(
        "--short",
        choices=SHORT_POLICIES,
        default=SHORT_POLICY,
        help="recordings with no more frames than the low-pass filter's padding: filter them "
        "with less padding (default), leave them out with a warning, or stop with an error",
    )
    g.add_argument(
        "--strict",
        action="store_true",
        help="stop at the first unreadable file (default: skip it with a warning)",
    )


def _mapping(text: str) -> dict[str, Any]:
    """``--mapping``: a JSON object ``role -> name or [names]``, inline or in a .json file."""
    source = "--mapping"
    if not text.lstrip().startswith("{"):
        path = Path(text)
        if not path.is_file():
            raise argparse.ArgumentTypeError(
                f"{text!r} is neither a JSON object nor an existing .json file"
            )
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise argparse.ArgumentTypeError(f"cannot read {path}: {exc}") from None
        source = str(path)
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise argparse.ArgumentTypeError(f"{source} is not valid JSON ({exc})") from None
    ok = isinstance(value, dict) and all(
        isinstance(v, str) or (isinstance(v, list) and all(isinstance(s, str) for s in v))
        for v in value.values()
    )
    if not ok or not value:
        raise argparse.ArgumentTypeError(
            f"{source} must be a JSON object mapping each role to a name or a list of names"
        )
    return value


def reader_options(args: argparse.Namespace, *, allow_each: bool = False) -> dict[str, Any]:
    """Keyword arguments for :func:`visprim.io.read_many` from the reader options (only those
    given; ``arm`` always, which may be :data:`EACH_ARM` when ``allow_each``, for
    :func:`read_files`). Raises :class:`UsageError` for a bad ``--arm``."""
    from visprim.io.presets import check_arm

    given = str(getattr(args, "arm", "right"))
    try:
        arm = EACH_ARM if allow_each and given.lower() == EACH_ARM else check_arm(given)
    except ValueError as exc:
        each = ", or 'each' to learn one-arm primitives from both" if allow_each else ""
        raise UsageError(f"--arm: {exc}{each}") from None
    opts: dict[str, Any] = {"arm": arm}
    for name in ("skeleton", "rate", "preset", "mapping", "up_axis", "person"):
        value = getattr(args, name, None)
        if value is not None:
            opts[name] = value
    on_gap = getattr(args, "on_gap", None)
    if on_gap is not None:
        opts["on_gap"] = on_gap
    return opts


def drop_short(trials: list[Trial], lowpass: tuple[int, float], mode: str) -> list[Trial]:
    """``--short``: trials with no more frames than the padding of the ``lowpass`` (order,
    cutoff) filter are kept (``"reduce"``: the model filters them with less padding), left
    out with a warning (``"drop"``) or refused (``"error"``)."""
    if mode == SHORT_POLICY:
        return trials
    from visprim.filtering import butterworth, default_padlen

    order, cutoff = int(lowpass[0]), float(lowpass[1])
    pad = default_padlen(butterworth(order, cutoff))
    kept = [t for t in trials if t.n_frames > pad]
    dropped = [t for t in trials if t.n_frames <= pad]
    names = ", ".join(f"{t.name} ({t.n_frames} frames)" for t in dropped[:5])
    more = f" and {len(dropped) - 5} more" if len(dropped) > 5 else ""
    if dropped and mode == "error":
        raise CLIError(
            f"{len(dropped)} trial(s) have no more frames than the filter padding ({pad}): "
            f"{names}{more}; pass --short reduce (pad them less) or --short drop"
        )
    if dropped:
        log.warning(
            "left out %d trial(s) with no more frames than the filter padding (%d): %s%s",
            len(dropped),
            pad,
            names,
            more,
        )
    if not kept:
        raise CLIError(
            f"every trial is too short for the order-{order} low-pass "
            f"({pad} frames of padding); lower --filter-order or give longer recordings"
        )
    return kept


# ---------------------------------------------------------------------------- model


def _model_option_type(param: Any) -> Callable[[str], Any]:
    """``type=`` of a model option: the declared constraint, in the option's unit."""
    convert = int if isinstance(param.default, int) else float
    words = param.constraint.words.removeprefix("must be ")
    unit = f" {param.option_unit}" if param.option_unit else ""
    what = (
        f"a positive number{unit}"
        if param.option_scale != 1.0
        else words.removeprefix("None (tune it) or ")
    )
    return _typed(convert, lambda v: param.constraint.accepts(param.from_option(v)), what)


def add_model_options(p: argparse.ArgumentParser) -> None:
    """The options of every :class:`~visprim.model.PrimitiveModel` parameter that has one,
    built from :data:`visprim.params.PARAMETERS`. An option not given is not set
    (``argparse.SUPPRESS``), so :func:`model_from_args` passes on only what the user gave
    and the model's (or the paper's) defaults apply to the rest."""
    from visprim.params import PARAMETERS

    g = p.add_argument_group("model parameters (visprim.PrimitiveModel)")
    for param in PARAMETERS:
        if param.option is None:
            continue
        default = param.to_option(param.default)
        shown = (
            "tuned on the data"
            if default is None
            else f"{default:g}"
            if not isinstance(default, str)
            else default
        )
        if isinstance(param.default, bool):
            shown = "on" if param.default else "off"
        paper = ""
        if param.fixed_by_paper:
            value = param.paper
            paper = f"; --paper: {('on' if value else 'off') if isinstance(value, bool) else value}"
        help_text = f"{param.help} (default {shown}{paper})"
        kwargs: dict[str, Any] = {"dest": param.dest, "default": argparse.SUPPRESS}
        if param.choices is not None:
            kwargs["choices"] = param.choices
        elif isinstance(param.default, bool):
            kwargs["action"] = argparse.BooleanOptionalAction
        else:
            kwargs["type"] = _model_option_type(param)
        g.add_argument(param.option, help=help_text, **kwargs)
    g.add_argument(
        "--paper",
        action="store_true",
        default=argparse.SUPPRESS,
        help="the paper's exact method ("
        + ", ".join(f"{n}={v!r}" for n, v in _paper_preset().items())
        + ") unless the options above say otherwise",
    )


def _paper_preset() -> dict[str, Any]:
    from visprim.params import PAPER

    return dict(PAPER)


def _model_options() -> dict[str, str]:
    from visprim.params import PARAMETERS

    return {p.name: p.option for p in PARAMETERS if p.option is not None}


#: PrimitiveModel parameter -> the command-line option that sets it.
MODEL_OPTIONS: dict[str, str] = _model_options()


def model_params_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """The model parameters the user gave as options, in the API's units."""
    from visprim.params import PARAMETERS

    given = vars(args)
    return {
        p.name: p.from_option(given[p.dest])
        for p in PARAMETERS
        if p.dest is not None and p.dest in given
    }


def model_from_args(args: argparse.Namespace, **overrides: Any) -> Any:
    """The model the options describe: :meth:`PrimitiveModel.paper` with ``--paper`` (or a
    command whose preset is the paper's, as ``demo``), else ``PrimitiveModel()``, with the
    options the user gave and ``overrides``."""
    from visprim.model import PrimitiveModel

    params = {**model_params_from_args(args), **overrides}
    paper = bool(getattr(args, "paper", False))
    model = PrimitiveModel.paper(**params) if paper else PrimitiveModel(**params)
    if model.n_components > model.dim:
        raise UsageError(
            f"--components {model.n_components} exceeds the segment vector dimension "
            f"{model.dim} (channels x --samples); lower --components"
        )
    if model.amplitude and model.offsets != "mean":
        raise UsageError("--amplitude scales posture-relative shapes: it needs --offsets mean")
    return model


def load_model(path: str) -> Any:
    """The model file ``path``, or a :class:`CLIError` naming the problem and the fix."""
    from visprim.model import PrimitiveModel
    from visprim.modelfile import ModelFileError

    p = Path(path)
    fix = "give a model file written by `visprim learn --out MODEL.npz`"
    if not p.exists():
        raise CLIError(f"model file {path} does not exist; {fix}")
    if p.is_dir():
        raise CLIError(f"{path} is a folder, not a model file; {fix}")
    try:
        return PrimitiveModel.load(p)
    except ModelFileError as exc:
        raise CLIError(f"{exc}; {fix}") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise CLIError(f"{path}: not a readable visprim model ({exc}); {fix}") from None


def label(method: str) -> str:
    """Display name of a segmentation method ("SEG-1", "SEG-2")."""
    return method.replace("seg", "SEG-")


def _trials_without_segments(model: Any, shown: int = 5) -> str:
    """The names of the training trials in which no segment was found, in parentheses
    (at most ``shown``, then how many more), or "" when the model does not know them."""
    used = {int(i) for i in getattr(model, "segment_trial_", ())}
    names = [n for i, n in enumerate(getattr(model, "trial_names_", ())) if i not in used]
    if not names:
        return ""
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return f" ({', '.join(names[:shown])}{more})"


def summary(model: Any, n_trials: int) -> str:
    """One line on a fitted model: segments, SEG-2 c, f and k."""
    import math

    from visprim.params import BY_NAME

    deg2 = math.degrees(1.0) ** 2
    thr = model.seg2_threshold_
    # c in the unit --seg2-threshold takes, (deg/s)^2: Euler angles in rad, or unit bone
    # directions whose speed is the bone's angular speed in rad/s. Six digits, so that the
    # printed value given back to --seg2-threshold cuts the same segments.
    option = BY_NAME["seg2_threshold"]
    c = (
        f", SEG-2 c = {option.to_option(thr):.6g} {option.option_unit} ({option.option})"
        if thr is not None
        else ""
    )
    empty = getattr(model, "n_trials_without_segments_", 0)
    short = getattr(model, "n_short_trials_", 0)
    notes = (
        f"; {empty} trial(s) without a segment{_trials_without_segments(model)}" if empty else ""
    )
    notes += f"; {short} trial(s) shorter than the filter padding (padded less)" if short else ""
    inertia = (
        f"{model.inertia_ * deg2:.4g} deg^2"
        if getattr(model, "features", "zyz") == "zyz"
        else f"{model.inertia_:.4g}"
    )
    return (
        f"{n_trials} trials -> {model.n_training_segments_} {label(model.segmentation)} "
        f"segments{c}; PCA f = {model.n_components} of {model.dim}; "
        f"k-means k = {model.n_primitives} (inertia {inertia}){notes}"
    )
