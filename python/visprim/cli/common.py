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

from visprim.trial import EACH_ARM, Trial

log = logging.getLogger(__name__)

#: Frame period (s) recordings are resampled to by default: the original study's 34 ms.
DEFAULT_RESAMPLE_S = 0.034
#: Accepted range of ``--resample`` (s): 0.1 ms to 10 s.
RESAMPLE_RANGE_S = (1e-4, 10.0)
#: ``--on-gap`` choices (those of :data:`visprim.io.gaps.ON_GAP`; a test keeps them equal).
ON_GAP_CHOICES = ("split", "longest", "raise")
#: ``--up-axis`` choices (:data:`visprim.io.assemble.UP_AXES`; a test keeps them equal).
UP_AXIS_CHOICES = ("+x", "-x", "+y", "-y", "+z", "-z")


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


def generated_source(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "kind": "generated",
        "n_subjects": int(getattr(args, "subjects", 11)),
        "n_stimuli": int(getattr(args, "stimuli", 20)),
        "seed": int(getattr(args, "data_seed", 0)),
        "preset": str(getattr(args, "data_preset", "paper")),
    }


def load_source(source: dict[str, Any], lowpass: tuple[int, float] | None = None) -> list[Trial]:
    """Trials described by a model's ``training_source_`` (see the module docstring);
    recordings too short for the ``lowpass`` (order, cutoff) are left out, as ``learn``
    does by default."""
    kind = source.get("kind")
    if kind == "generated":
        from visprim.datasets import imitation_experiment

        # Sources written before the presets existed describe the "strokes" generator.
        return imitation_experiment(
            int(source.get("n_subjects", 11)),
            int(source.get("n_stimuli", 20)),
            int(source.get("seed", 0)),
            preset=str(source.get("preset", "strokes")),
        )
    if kind == "files":
        trials = read_files(
            list(source.get("paths", [])),
            source.get("resample"),
            dict(source.get("options") or {}),
            on_error="warn",
        )
        mode = str(source.get("short", "reduce"))
        return trials if lowpass is None else drop_short(trials, lowpass, mode)
    raise CLIError(f"unknown data source {source!r} recorded in the model; give DATA instead")


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
            "(.bvh, .amc, .c3d, .csv) or the reader options their messages ask for"
        )
    return list(trials)


def trials_and_source(
    args: argparse.Namespace,
    resample: float | None = None,
    lowpass: tuple[int, float] | None = None,
) -> tuple[list[Trial], dict[str, Any]]:
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
        short = str(getattr(args, "short", "reduce"))
        if lowpass is not None:
            trials = drop_short(trials, lowpass, short)
        paths = [str(Path(p).resolve()) for p in data]
        source: dict[str, Any] = {"kind": "files", "paths": paths, "resample": resample}
        if options:
            source["options"] = options
        if short == "drop":
            source["short"] = short
        return trials, source
    source = generated_source(args)
    return load_source(source), source


def model_lowpass(model: Any) -> tuple[int, float]:
    """(order, cutoff) of a model's low-pass filter."""
    return int(model.filter_order), float(model.cutoff)


def model_period(model: Any) -> float | None:
    """The period DATA given to ``report``/``classify`` is resampled to: the model's own
    (recorded by ``learn``), else the default (models of generated data: 34 ms frames)."""
    period = (model.training_source_ or {}).get("resample", DEFAULT_RESAMPLE_S)
    return None if period is None else float(period)


def add_generated_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("generated data (used without DATA, or with --generated)")
    g.add_argument("--generated", action="store_true", help="use the generated experiment")
    g.add_argument("--subjects", type=positive_int, default=11, help="subjects (default 11)")
    g.add_argument("--stimuli", type=positive_int, default=20, help="stimuli (default 20)")
    g.add_argument("--data-seed", type=seed_int, default=0, help="generator seed (default 0)")
    g.add_argument(
        "--data-preset",
        choices=("paper", "strokes"),
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
        choices=UP_AXIS_CHOICES,
        default=None,
        help="the files' vertical axis (default: +y for BVH/AMC, detected for C3D)",
    )
    g.add_argument(
        "--on-gap",
        choices=ON_GAP_CHOICES,
        default="split",
        help="C3D gaps longer than 0.2 s: split the recording (default), keep the longest "
        "piece, or stop with an error",
    )
    if not many:
        return
    g.add_argument(
        "--short",
        choices=("reduce", "drop", "error"),
        default="reduce",
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
    for name in ("skeleton", "rate", "preset", "mapping", "up_axis"):
        value = getattr(args, name, None)
        if value is not None:
            opts[name] = value
    on_gap = getattr(args, "on_gap", "split")
    if on_gap != "split":
        opts["on_gap"] = on_gap
    return opts


def drop_short(trials: list[Trial], lowpass: tuple[int, float], mode: str) -> list[Trial]:
    """``--short``: trials with no more frames than the padding of the ``lowpass`` (order,
    cutoff) filter are kept (``"reduce"``: the model filters them with less padding), left
    out with a warning (``"drop"``) or refused (``"error"``)."""
    if mode == "reduce":
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


def add_model_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("model parameters (visprim.PrimitiveModel)")
    g.add_argument(
        "--segmentation",
        choices=("seg2", "seg1"),
        default="seg2",
        help="segmentation of the training movements (default seg2)",
    )
    g.add_argument(
        "--filter-order", type=positive_int, default=10, help="Butterworth order (default 10)"
    )
    g.add_argument(
        "--cutoff",
        type=fraction,
        default=0.25,
        help="normalised low-pass cutoff, fraction of Nyquist (default 0.25)",
    )
    g.add_argument(
        "--zvc-threshold",
        type=nonneg_float,
        default=5.0,
        help="ZVC significant-movement threshold, degrees (default 5)",
    )
    g.add_argument(
        "--window", type=positive_float, default=0.3, help="SEG-1 window, s (default 0.3)"
    )
    g.add_argument(
        "--features",
        choices=("directions", "zyz"),
        default=None,
        help="what segments are made of: bone directions (default) or the paper's Z-Y-Z angles",
    )
    g.add_argument(
        "--seg2-tuning",
        choices=("robust", "repetitions"),
        default=None,
        help="how SEG-2's c is tuned: to the corpus' speed (default) or the paper's rule "
        "from the repetitions",
    )
    g.add_argument(
        "--paper",
        action="store_true",
        help="the paper's exact method (Z-Y-Z angles, c from repetitions, fixed SEG-1 "
        "window) unless --features / --seg2-tuning say otherwise",
    )
    g.add_argument(
        "--seg2-threshold",
        type=positive_float,
        default=None,
        help="SEG-2 constant c, (rad/s)^2 (default: tuned on the data)",
    )
    g.add_argument(
        "--samples", type=positive_int, default=100, help="samples per angle (default 100)"
    )
    g.add_argument(
        "--components", type=positive_int, default=30, help="eigenvectors f (default 30)"
    )
    g.add_argument("--clusters", type=positive_int, default=30, help="primitives k (default 30)")
    g.add_argument("--n-init", type=positive_int, default=10, help="k-means restarts (default 10)")
    g.add_argument("--seed", type=seed_int, default=0, help="k-means seed (default 0)")


#: PrimitiveModel parameter -> the command-line option that sets it.
MODEL_OPTIONS = {
    "segmentation": "--segmentation",
    "filter_order": "--filter-order",
    "cutoff": "--cutoff",
    "zvc_threshold_deg": "--zvc-threshold",
    "window": "--window",
    "seg2_threshold": "--seg2-threshold",
    "n_samples": "--samples",
    "n_components": "--components",
    "n_clusters": "--clusters",
    "n_init": "--n-init",
    "seed": "--seed",
}


def model_from_args(args: argparse.Namespace, **overrides: Any) -> Any:
    from visprim.model import PrimitiveModel

    paper = bool(getattr(args, "paper", False))
    params = dict(
        features=getattr(args, "features", None) or ("zyz" if paper else "directions"),
        seg2_tuning=getattr(args, "seg2_tuning", None) or ("repetitions" if paper else "robust"),
        seg1_adaptive=not paper,
        segmentation=args.segmentation,
        filter_order=args.filter_order,
        cutoff=args.cutoff,
        zvc_threshold_deg=args.zvc_threshold,
        window=args.window,
        seg2_threshold=args.seg2_threshold,
        n_samples=args.samples,
        n_components=args.components,
        n_clusters=args.clusters,
        n_init=args.n_init,
        seed=args.seed,
    )
    params.update(overrides)
    model = PrimitiveModel(**params)
    if params["n_components"] > model.dim:
        raise UsageError(
            f"--components {params['n_components']} exceeds the segment vector dimension "
            f"{model.dim} (channels x --samples); lower --components"
        )
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

    deg2 = math.degrees(1.0) ** 2
    thr = model.seg2_threshold_
    # c in (deg/s)^2: Euler angles in rad, or unit bone directions whose speed is the
    # bone's angular speed in rad/s.
    c = f", SEG-2 c = {thr * deg2:.4g} (deg/s)^2" if thr is not None else ""
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
