"""The ``visprim`` command line: ``visprim COMMAND --help`` for each.

Each command is one module of this package with ``register(sub)`` (adds its parser) and
``run(args)`` (does the work, returns the exit status); :data:`COMMANDS` lists them in the
order ``--help`` shows them.

Failures: :func:`main` is the one place that turns an exception into an exit status and one
line on stderr naming the problem and the fix (``visprim COMMAND: error: ...``), with no
traceback unless ``--debug``. Exit status 0 for success, 1 for errors, 2 for usage errors
(argparse's and :class:`~visprim.cli.common.UsageError`), 130 for Ctrl-C, 143 for SIGTERM
(both unwind as an error does: temporary files are removed, earlier outputs are left as
they were).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import re
import signal
import sys
import traceback
from collections.abc import Iterator, Sequence
from typing import Any, NoReturn

from visprim.cli.common import CLIError

#: Command modules of :mod:`visprim.cli`, in help order.
COMMANDS: tuple[str, ...] = (
    "demo",
    "generate",
    "learn",
    "report",
    "classify",
    "evaluate",
    "simulate",
    "imitate",
    "watch",
    "export-robot",
)

EXIT_ERROR = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130

#: Library argument names in error messages → the command-line options that set them.
_OPTION_OF = {
    "skeleton": "--skeleton",
    "rate": "--rate",
    "mapping": "--mapping",
    "preset": "--preset",
    "up_axis": "--up-axis",
    "on_gap": "--on-gap",
    "arm": "--arm",
    "short": "--short",
    "n_clusters": "--clusters",
    "n_components": "--components",
    "n_samples": "--samples",
    "filter_order": "--filter-order",
    "cutoff": "--cutoff",
    "resample": "--resample",
}
_ARGUMENT = re.compile(r"\b(" + "|".join(_OPTION_OF) + r")=")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors (the usage itself is in ``--help``)."""

    def error(self, message: str) -> NoReturn:
        text = " ".join(message.split())
        self.exit(EXIT_USAGE, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def _version() -> str:
    from visprim import __version__

    return __version__


def _add_global_options(p: argparse.ArgumentParser, *, top: bool) -> None:
    # On the top parser and again on each command (so they work before or after it); the
    # commands' copies default to SUPPRESS so they do not reset a value given before.
    default: dict[str, Any] = {} if top else {"default": argparse.SUPPRESS}
    g = p.add_argument_group("output")
    g.add_argument(
        "-v",
        "--verbose",
        action="count",
        help="also print debug messages",
        **({"default": 0} if top else default),
    )
    g.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="print only warnings, errors and results (no progress bars)",
        **default,
    )
    g.add_argument(
        "--debug",
        action="store_true",
        help="on failure, print the traceback too",
        **default,
    )


def build_parser() -> argparse.ArgumentParser:
    """The ``visprim`` parser with every command of :data:`COMMANDS`."""
    parser = _Parser(prog="visprim", description="Movement primitives from human motion capture.")
    parser.add_argument("--version", action="version", version=f"visprim {_version()}")
    _add_global_options(parser, top=True)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        importlib.import_module(f"visprim.cli.{name.replace('-', '_')}").register(sub)
    for p in sub.choices.values():
        _add_global_options(p, top=False)
    return parser


def one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line, library argument names as command-line options."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return _ARGUMENT.sub(lambda m: f"{_OPTION_OF[m[1]]} ", text)


def describe(exc: BaseException) -> tuple[str, int]:
    """``(one-line message naming the problem and the fix, exit status)`` for ``exc``."""
    if isinstance(exc, CLIError):
        return one_line(exc), exc.status
    if any(c.__name__ == "ReadError" for c in type(exc).__mro__):  # (no import of visprim.io)
        return (
            f"{one_line(exc)} (fix the file, give the reader options it needs, or leave it "
            "out: unreadable files are skipped unless --strict)",
            EXIT_ERROR,
        )
    if any(c.__name__ == "SimulationDiverged" for c in type(exc).__mro__):
        text = one_line(exc).removeprefix("play: ").removesuffix("; try a smaller time step")
        return f"{text}; give a smaller --dt (such as 0.0001 with --servo paper)", EXIT_ERROR
    if isinstance(exc, MemoryError):
        return (
            f"out of memory ({one_line(exc)}); give fewer or shorter recordings, or a larger "
            "--resample period",
            EXIT_ERROR,
        )
    if isinstance(exc, FileNotFoundError | PermissionError | IsADirectoryError):
        where = exc.filename or ""
        return (
            f"{where}: {exc.strerror or one_line(exc)}; check the path and its permissions",
            EXIT_ERROR,
        )
    if isinstance(exc, OSError):
        return f"{one_line(exc)}; check the paths, free disk space and permissions", EXIT_ERROR
    if isinstance(exc, ImportError):
        package = (exc.name or "").split(".")[0] or "the missing package"
        return f"{one_line(exc)}; install it (pip install {package})", EXIT_ERROR
    if isinstance(exc, ValueError):
        return one_line(exc), EXIT_ERROR
    return (
        f"internal error {type(exc).__name__}: {one_line(exc)} (a bug in visprim: please "
        "report it with the output of --debug)",
        EXIT_ERROR,
    )


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # no real file behind stdout (tests)
        pass


def _fail(command: str, message: str, status: int, debug: bool) -> int:
    if debug:
        traceback.print_exc()
    kind = "interrupted" if status == EXIT_INTERRUPTED else "error"
    print(f"visprim {command}: {kind}: {message}", file=sys.stderr, flush=True)
    return status


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``visprim`` with ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Usage errors found by argparse exit through :class:`SystemExit` (status 2), as does
    ``--help`` / ``--version`` (status 0).
    """
    from visprim.cli.logs import configured

    try:
        args = build_parser().parse_args(argv)
    except KeyboardInterrupt:
        print("visprim: interrupted: stopped by Ctrl-C", file=sys.stderr)
        return EXIT_INTERRUPTED
    command = str(args.command)
    debug = bool(getattr(args, "debug", False))
    with configured(int(args.verbose or 0), bool(getattr(args, "quiet", False))), _on_sigterm():
        try:
            return int(args.func(args) or 0)
        except KeyboardInterrupt:
            message = "stopped by Ctrl-C; outputs left as before"
            return _fail(command, message, EXIT_INTERRUPTED, debug)
        except _Terminated:
            return _fail(command, "stopped by SIGTERM; outputs left as before", 143, debug)
        except BrokenPipeError:
            _silence_stdout()  # the reader of stdout went away (e.g. `| head`)
            return EXIT_ERROR
        except SystemExit as exc:
            if isinstance(exc.code, int | None):
                return int(exc.code or 0)
            return _fail(command, " ".join(str(exc.code).split()), EXIT_ERROR, debug)
        except Exception as exc:
            message, status = describe(exc)
            return _fail(command, message, status, debug)
        finally:
            from visprim.cli.outputs import release_claims

            release_claims()


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that ``finally`` clauses clean up (temporary
    folders, half-written outputs, output locks) as they do for Ctrl-C."""


@contextlib.contextmanager
def _on_sigterm() -> Iterator[None]:
    def handler(signum: int, frame: Any) -> None:
        raise _Terminated

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread (an embedding application): leave it alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
