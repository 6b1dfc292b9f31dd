"""``visprim evaluate``: the benchmark of the method on labelled recordings."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from visprim.cli import common
from visprim.params import CLASSIFIER_PARAMETERS, PARAMETERS, RATE_OPTIONS

#: The classifier's settings by name (their defaults are the options' defaults).
_CLF = {p.name: p for p in CLASSIFIER_PARAMETERS}
#: The model's SEG-2 boundary rule, which the benchmark can compare (declared in params).
_BOUNDARY = next(p for p in PARAMETERS if p.name == "seg2_boundary")


def run(args: argparse.Namespace) -> int:
    if getattr(args, "online", False):
        return _run_online(args)
    from visprim.classify import MotionClassifier
    from visprim.cli import outputs
    from visprim.evaluate import evaluate, to_markdown, write_report

    out = outputs.check_folder(args.out, force=args.force, inputs=args.data)
    if args.rate_only:
        return _run_rate(args, out, None)
    found = _benchmarks(
        evaluate,
        args,
        classifier=MotionClassifier(
            method=args.method,
            band=args.band,
            step=args.step,
            model_params={"seg2_boundary": args.seg2_boundary},
        ),
        reconstruction=args.reconstruction,
    )
    if found is None:
        return 2
    results, notes = found
    print(to_markdown(results, notes), end="")
    if args.rate:
        return _run_rate(args, out, lambda tmp: write_report(results, notes, tmp))
    with outputs.atomic_folder(out, "evaluate") as tmp:
        paths = write_report(results, notes, tmp)
    written = ", ".join(str(outputs.moved(p, tmp, out)) for p in paths.values())
    print(f"\nwritten: {written}")
    return 0


def _run_rate(args: argparse.Namespace, out: Any, also: Any) -> int:
    """The rate–distortion benchmark (:mod:`visprim.rate`), its table printed and its
    files written beside what ``also(folder)`` writes."""
    from visprim.cli import outputs
    from visprim.rate import rate_benchmark, rate_markdown, write_rate_report

    try:
        results = rate_benchmark(
            args.data,
            labels=args.labels,
            group_by=args.group,
            period=args.resample,
            centres=args.rate_centres,
            max_stroke=args.max_stroke,
            posture=args.rate_posture,
            jobs=args.jobs,
        )
    except ValueError as exc:
        print(f"visprim evaluate: {exc}", file=sys.stderr)
        return 2
    print(rate_markdown(results), end="")
    nested = None
    if args.rate_nested:
        from visprim.rate.nested import nested_markdown, nested_rate_benchmark

        try:
            nested = nested_rate_benchmark(
                args.data,
                labels=args.labels,
                group_by=args.group,
                period=args.resample,
                jobs=args.jobs,
            )
        except ValueError as exc:
            print(f"visprim evaluate: {exc}", file=sys.stderr)
            return 2
        print(nested_markdown(nested), end="")
    with outputs.atomic_folder(out, "evaluate") as tmp:
        paths = dict(also(tmp)) if also is not None else {}
        paths.update(write_rate_report(results, tmp))
        if nested is not None:
            from visprim.rate.nested import write_nested_report

            paths.update(write_nested_report(nested, tmp))
    written = ", ".join(str(outputs.moved(p, tmp, out)) for p in paths.values())
    print(f"\nwritten: {written}")
    return 0


#: :data:`visprim.classify.MOTION_METHODS`, spelt out so that building the parser does not
#: import scikit-learn (a test checks they agree).
METHODS = ("combined", "frames", "coordinates", "segments", "histogram")
#: :data:`visprim.evaluate.RECONSTRUCTIONS` (a test checks they agree).
RECONSTRUCTIONS = ("each-arm", "joint")


def _stroke(text: str) -> float | None:
    """``--max-stroke``: seconds, or ``none`` for no cut."""
    if text.strip().lower() == "none":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'none', got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "evaluate",
        help="benchmark primitives on labelled recordings (leave one group out)",
        description="Leave-one-group-out recognition (MotionClassifier beside a DTW 1-NN "
        "baseline), segmentation statistics and held-out reconstruction errors on labelled "
        "recordings. Labels come from labels.tsv beside the data (columns file, label, style, "
        "subject, take, group, description), from --labels, or from Bandai-Namco file names.",
    )
    p.add_argument("data", nargs="+", metavar="DATA", help="recording files or folders")
    p.add_argument("--labels", default=None, help="a labels table (TSV) for every DATA file")
    p.add_argument(
        "--group",
        choices=("subject", "style", "take"),
        default=None,
        help="column holding the groups to leave out (default: subject, else style, else take)",
    )
    p.add_argument("--classes", default=None, help="comma-separated labels to keep (default: all)")
    p.add_argument(
        "--method",
        choices=METHODS,
        default=_CLF["method"].default,
        help=f"MotionClassifier method (default {_CLF['method'].default}; see "
        "help(visprim.MotionClassifier))",
    )
    p.add_argument(
        "--band",
        type=float,
        default=_CLF["band"].default,
        help="Sakoe-Chiba band of the DTW, fraction of the length (default: none)",
    )
    p.add_argument(
        "--step",
        type=int,
        default=_CLF["step"].default,
        help=f"per-frame descriptions at every STEP-th frame (default {_CLF['step'].default})",
    )
    p.add_argument(
        _BOUNDARY.option or "--seg2-boundary",
        choices=_BOUNDARY.choices,
        default=_BOUNDARY.default,
        help=f"{_BOUNDARY.help} (default {_BOUNDARY.default})",
    )
    p.add_argument(
        "--arm",
        choices=("right", "left", "both"),
        default="both",
        help="arms to read and model (default both; marker CSV files hold the right arm)",
    )
    p.add_argument(
        "--reconstruction",
        choices=RECONSTRUCTIONS,
        default="each-arm",
        help="primitives that rebuild two-arm movements: one-arm primitives learned from both "
        "arms (default) or the classifier's two-arm primitives",
    )
    p.add_argument(
        "--resample",
        type=common.period_s,
        default=common.DEFAULT_RESAMPLE_S,
        metavar="SECONDS",
        help=f"frame period in seconds (default {common.DEFAULT_RESAMPLE_S:g})",
    )
    p.add_argument(
        "--jobs", type=common.positive_int, default=None, help="reader processes (default: cores)"
    )
    p.add_argument(
        "--rate",
        action="store_true",
        help="also measure the rate-distortion curve of held-out movements (numbers per "
        "second of movement against rebuild error; rate.md, rate.csv, rate.png)",
    )
    p.add_argument("--rate-only", action="store_true", help="only the rate-distortion benchmark")
    rate = RATE_OPTIONS
    p.add_argument(
        "--rate-centres",
        choices=("projection", "members"),
        default=rate["centres"].default,
        help=f"rate benchmark: {rate['centres'].help} (default {rate['centres'].default})",
    )
    p.add_argument(
        "--rate-posture",
        choices=rate["posture"].searched,
        default=rate["posture"].default,
        help=f"rate benchmark: {rate['posture'].help} (default {rate['posture'].default})",
    )
    p.add_argument(
        "--max-stroke",
        type=_stroke,
        default=rate["max_stroke"].default,
        metavar="S",
        help=f"rate benchmark: {rate['max_stroke'].help}; 'none' or seconds (default "
        f"{rate['max_stroke'].default})",
    )
    p.add_argument(
        "--rate-nested",
        action="store_true",
        help="with --rate or --rate-only: also choose posture, max stroke and description per "
        "budget by nested leave-one-group-out and score only the outer group "
        "(rate_nested.md, rate_nested.csv; slow: groups x (groups - 1) x settings folds)",
    )
    p.add_argument("--out", default="out/evaluate", help="report folder (default out/evaluate)")
    p.add_argument(
        "--online",
        action="store_true",
        help="early recognition instead: accuracy against the fraction of each movement seen "
        "(open-end DTW, leave one group out; visprim.online.early)",
    )
    common.add_force_option(p)
    p.set_defaults(func=run)


def _run_online(args: argparse.Namespace) -> int:
    """``visprim evaluate --online``: the early-recognition table, printed and written to
    ``--out`` (``early_recognition.md`` / ``.json``, in a folder moved into place whole)."""
    from pathlib import Path

    from visprim.cli import outputs
    from visprim.online.early import evaluate_early, to_markdown, write

    out = outputs.check_folder(args.out, force=args.force, inputs=args.data)
    found = _benchmarks(evaluate_early, args)
    if found is None:
        return 2
    results, notes = found
    print(to_markdown(results, notes), end="")
    with outputs.atomic_folder(out, "evaluate") as tmp:
        paths = write(results, notes, Path(tmp))
    print("\nwritten: " + ", ".join(str(outputs.moved(p, tmp, out)) for p in paths))
    return 0


def _benchmarks(run: Any, args: argparse.Namespace, **extra: Any) -> tuple[Any, Any] | None:
    """``(results, notes)`` of ``run`` (:func:`visprim.evaluate.evaluate` or
    :func:`visprim.online.early.evaluate_early`) on the benchmarks the options name, or None
    after a one-line message (a bad input, or no benchmark to run)."""
    classes = [c.strip() for c in args.classes.split(",") if c.strip()] if args.classes else None
    try:
        results, notes = run(
            args.data,
            labels=args.labels,
            group_by=args.group,
            classes=classes,
            period=args.resample,
            arm=args.arm,
            jobs=args.jobs,
            **extra,
        )
    except ValueError as exc:
        print(f"visprim evaluate: {exc}", file=sys.stderr)
        return None
    if not results:
        print("visprim evaluate: no benchmark to run; " + "; ".join(notes), file=sys.stderr)
        return None
    return results, notes
