"""The ``visprim`` command line: ``visprim SUBCOMMAND --help`` for each."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def _generate(args: argparse.Namespace) -> int:
    from visprim.datasets import export_experiment

    paths = export_experiment(
        args.out, n_subjects=args.subjects, n_stimuli=args.stimuli, seed=args.seed
    )
    print(f"wrote {len(paths)} trial files to {args.out}")
    return 0


def _simulate(args: argparse.Namespace) -> int:
    from visprim.sim.cli import run_simulate

    return run_simulate(args)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="visprim", description="Movement primitives from human motion capture."
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("generate", help="write the generated imitation experiment as CSV files")
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--subjects", type=int, default=11, help="number of subjects (default 11)")
    p.add_argument("--stimuli", type=int, default=20, help="number of stimuli (default 20)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(func=_generate)

    p = sub.add_parser("simulate", help="play primitives of a model on the Adonis humanoid (DART)")
    p.add_argument("model", help="model file written by `visprim learn`")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--primitive", type=int, help="index of the primitive (cluster) to play")
    group.add_argument("--movement", help="a trial file whose reconstructed movement to play")
    p.add_argument("--out", default="adonis.gif", help="output GIF (default adonis.gif)")
    p.set_defaults(func=_simulate)

    # demo, learn, report, classify: registered by visprim.pipeline_cli (issue 4).
    try:
        from visprim.pipeline_cli import add_subcommands
    except ImportError:
        pass
    else:
        add_subcommands(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
