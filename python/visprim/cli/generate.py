"""``visprim generate``: write the generated imitation experiment as marker CSV files."""

from __future__ import annotations

import argparse
from typing import Any

from visprim.cli import common, outputs


def run(args: argparse.Namespace) -> int:
    from visprim.datasets import export_experiment

    out = outputs.check_folder(args.out, force=args.force)
    with outputs.atomic_folder(out, "generate") as tmp:
        paths = export_experiment(
            tmp, n_subjects=args.subjects, n_stimuli=args.stimuli, seed=args.seed
        )
    print(f"wrote {len(paths)} trial files to {out}")
    return 0


def register(sub: Any) -> None:
    """Add the command to ``sub`` (from :meth:`argparse.ArgumentParser.add_subparsers`)."""
    p = sub.add_parser("generate", help="write the generated imitation experiment as CSV files")
    p.add_argument("--out", required=True, metavar="FOLDER", help="output folder")
    common.add_force_option(p)
    p.add_argument(
        "--subjects", type=common.positive_int, default=11, help="number of subjects (default 11)"
    )
    p.add_argument(
        "--stimuli", type=common.positive_int, default=20, help="number of stimuli (default 20)"
    )
    p.add_argument("--seed", type=common.seed_int, default=0, help="random seed (default 0)")
    p.set_defaults(func=run)
