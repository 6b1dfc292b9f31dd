"""``visprim classify``: each segment of new movements -> its nearest primitive."""

from __future__ import annotations

import argparse
from typing import Any

from visprim.cli import common, outputs


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from visprim.classify import classify_trials, score_against_truth

    out = None
    if args.out:
        out = outputs.check_file(args.out, (".csv",), force=args.force, what="segment table")
    model = common.load_model(args.model)
    trials, _ = common.trials_and_source(
        args, common.model_period(model), common.model_lowpass(model)
    )
    results = classify_trials(model, trials)
    lines = []
    for r in results:
        hist = r.histogram
        top = np.argsort(-hist, kind="stable")[: min(5, hist.size)]
        top_s = ", ".join(f"#{i}x{hist[i]}" for i in top if hist[i] > 0)
        lines.append(f"{r.name}: sequence {list(r.sequence)}; histogram {top_s or '-'}")
    print("\n".join(lines))
    if out is not None:
        from visprim.csvfile import writer

        with outputs.atomic_file(out) as tmp, tmp.open("w", encoding="utf-8", newline="") as fh:
            w = writer(fh)
            w.writerow(["trial", "segment", "start_s", "end_s", "primitive", "distance_rad"])
            for r in results:
                for j, ((s, e), lab, d) in enumerate(
                    zip(r.segments, r.primitives, r.distances, strict=True)
                ):
                    w.writerow([r.name, j, f"{s:.6f}", f"{e:.6f}", int(lab), f"{d:.6g}"])
        print(f"segment primitives written to {out}")
    if all(t.truth is not None for t in trials):
        print(f"against the true strokes: {score_against_truth(model, trials, results)}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "classify",
        help="give each segment of new movements its nearest primitive",
        description="Segment DATA with the model's settings and print each trial's sequence "
        "and histogram of primitives (and ARI/purity on generated data).",
    )
    p.add_argument("model", metavar="MODEL", help="model file written by `visprim learn`")
    p.add_argument(
        "data", nargs="*", metavar="DATA", help="recordings (default: the generated experiment)"
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="CSV",
        help="also write one row per segment: trial, segment, start_s, end_s, primitive (the "
        "index of its nearest primitive, a cluster of the model, not a class label), "
        "distance_rad (.csv)",
    )
    common.add_force_option(p)
    common.add_reader_options(p)
    common.add_generated_options(p)
    p.set_defaults(func=run)
