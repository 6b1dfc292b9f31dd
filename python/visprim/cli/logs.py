"""Logging for the command line.

Library modules log with ``logging.getLogger(__name__)`` and never configure logging; the
command line sends the ``visprim`` loggers to stderr, one line per message:

* default: information and warnings (``warning: ...``);
* ``-v``: also debug messages (with the logger's name);
* ``-q`` / ``--quiet``: warnings and errors only, and no progress bars.

Python warnings raised while a command runs (e.g. a skipped recording) are logged as one
``warning:`` line instead of the interpreter's two-line format.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TextIO

from visprim import progress

#: The logger every visprim module's logger descends from.
ROOT = "visprim"


class _LineFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        text = " ".join(record.getMessage().split("\n"))
        if record.levelno >= logging.WARNING:
            return f"{record.levelname.lower()}: {text}"
        if record.levelno < logging.INFO:
            return f"debug: {record.name}: {text}"
        return text


class _StderrHandler(logging.Handler):
    """Writes through tqdm so that log lines do not break a progress bar."""

    def __init__(self, stream: TextIO | None = None) -> None:
        super().__init__()
        self._stream = stream

    def emit(self, record: logging.LogRecord) -> None:
        try:
            stream = self._stream or sys.stderr
            progress.write(self.format(record), file=stream)
        except Exception:  # logging must never raise
            self.handleError(record)


def level(verbose: int, quiet: bool) -> int:
    """The ``visprim`` logger level for ``-v`` (count) and ``--quiet``."""
    if quiet:
        return logging.WARNING
    return logging.DEBUG if verbose > 0 else logging.INFO


@contextlib.contextmanager
def configured(verbose: int = 0, quiet: bool = False) -> Iterator[logging.Logger]:
    """Within the block, the ``visprim`` loggers write to stderr at the level of ``-v`` /
    ``--quiet``, Python warnings become ``warning:`` lines and ``--quiet`` hides the
    progress bars. Everything is restored afterwards (the CLI may run in-process)."""
    logger = logging.getLogger(ROOT)
    handler = _StderrHandler()
    handler.setFormatter(_LineFormatter())
    old_level = logger.level
    logger.addHandler(handler)
    logger.setLevel(level(verbose, quiet))
    warn_log = logging.getLogger(f"{ROOT}.warnings")

    def show(message: Any, category: type[Warning], *args: Any, **kwargs: Any) -> None:
        warn_log.warning("%s", message)

    try:
        with warnings.catch_warnings(), progress.hidden(quiet):
            warnings.showwarning = show
            yield logger
    finally:
        logger.removeHandler(handler)
        logger.setLevel(old_level)


class _PathRewrite(logging.Filter):
    def __init__(self, old: str, new: str) -> None:
        super().__init__()
        self._old, self._new = old, new

    def filter(self, record: logging.LogRecord) -> bool:
        text = record.getMessage()
        if self._old in text:
            record.msg, record.args = text.replace(self._old, self._new), None
        return True


@contextlib.contextmanager
def paths_shown_as(tmp: Path, final: Path) -> Iterator[None]:
    """Within the block, log lines show paths under the temporary output folder ``tmp`` as
    under ``final`` (where they will be once the folder is swapped in)."""
    rewrite = _PathRewrite(str(tmp), str(final))
    handlers = list(logging.getLogger(ROOT).handlers)
    for h in handlers:
        h.addFilter(rewrite)
    try:
        yield
    finally:
        for h in handlers:
            h.removeFilter(rewrite)
