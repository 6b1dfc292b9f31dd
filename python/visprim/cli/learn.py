"""``visprim learn``: learn primitives from recordings and write the model file.

Fewer segments than ``--clusters``: ``learn`` stops with an error naming the number of
segments found (it does not silently learn fewer primitives than asked); lower
``--clusters`` or give more recordings."""

from __future__ import annotations

import argparse
from typing import Any

from visprim.cli import common


def run(args: argparse.Namespace) -> int:
    from visprim.modelfile import save_model
    from visprim.progress import stages

    with stages(3, "learn") as st:
        st.step("reading data")
        trials, source = common.trials_and_source(args, args.resample)
        st.step(f"fitting {len(trials)} trials")
        model = common.model_from_args(args)
        try:
            model.fit(trials, source=source)
        except ValueError as exc:
            hint = " (option --clusters)" if "n_clusters=" in str(exc) else ""
            raise SystemExit(f"visprim learn: {exc}{hint}") from None
        st.step("error tables")
        tables = model.error_table()
    path = save_model(model, args.out)
    print(common.summary(model, len(trials)))
    print()
    print(tables.to_markdown())
    print(f"model written to {path}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser(
        "learn",
        help="learn primitives from recordings (or the generated experiment)",
        description="Learn primitives (PCA + k-means of segment vectors) and write the model "
        "file; prints Tables 1-3.",
    )
    p.add_argument(
        "data",
        nargs="*",
        metavar="DATA",
        help="recording files, folders or globs (default: the generated experiment)",
    )
    p.add_argument("--out", required=True, metavar="MODEL", help="model file to write (.npz)")
    p.add_argument(
        "--resample",
        type=float,
        default=common.DEFAULT_RESAMPLE_S,
        metavar="SECONDS",
        help="resample DATA to this frame period before learning, so that --cutoff and the "
        "segmentation mean what they meant at the study's rate (default 0.034)",
    )
    p.add_argument(
        "--no-resample",
        dest="resample",
        action="store_const",
        const=None,
        help="keep each recording's own frame rate",
    )
    common.add_generated_options(p)
    common.add_model_options(p)
    p.set_defaults(func=run)
