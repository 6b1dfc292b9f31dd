"""The ``visprim`` command line (one module per command; :mod:`visprim.cli.main` builds
the parser)."""

from visprim.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
