"""The ``visprim`` command line: ``visprim COMMAND --help`` for each.

Each command is one module of this package with ``register(sub)`` (adds its parser) and
``run(args)`` (does the work, returns the exit status); :data:`COMMANDS` lists them in the
order ``--help`` shows them.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

#: Command modules of :mod:`visprim.cli`, in help order.
COMMANDS: tuple[str, ...] = (
    "demo",
    "generate",
    "learn",
    "report",
    "classify",
    "evaluate",
    "simulate",
)


def build_parser() -> argparse.ArgumentParser:
    """The ``visprim`` parser with every command of :data:`COMMANDS`."""
    parser = argparse.ArgumentParser(
        prog="visprim", description="Movement primitives from human motion capture."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"visprim.cli.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``visprim`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    args = build_parser().parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
