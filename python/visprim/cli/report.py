"""``visprim report``: figures, Tables 1-3 and index.html of a model."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from visprim.cli import common
from visprim.trial import Trial


def run(args: argparse.Namespace) -> int:
    from visprim.model import PrimitiveModel
    from visprim.report import write_report

    model = PrimitiveModel.load(args.model)
    trials: list[Trial] | None = None
    if args.data or args.generated:
        trials, _ = common.trials_and_source(args, common.model_period(model))
    elif model.training_source_:
        try:
            trials = common.load_source(model.training_source_)
        except (OSError, ValueError, SystemExit) as exc:
            print(
                f"visprim report: cannot read the training data again ({exc}); "
                "writing the model-only part",
                file=sys.stderr,
            )
    rep = write_report(model, args.out, trials, trial_name=args.trial)
    for msg in rep.skipped:
        print(f"note: {msg}")
    print(f"report written to {rep.index} ({len(rep.files)} files)")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "report",
        help="write the figures, Tables 1-3 and index.html of a model",
        description="Write the report of MODEL to --out. Per-trial figures use DATA, or "
        "--generated, or else the data the model was learned from (recorded in the model "
        "file).",
    )
    p.add_argument("model", metavar="MODEL", help="model file written by `visprim learn`")
    p.add_argument("data", nargs="*", metavar="DATA", help="recordings for the trial figures")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--trial", default=None, help="name of the trial to draw")
    common.add_generated_options(p)
    p.set_defaults(func=run)
