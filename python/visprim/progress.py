"""Progress bars for long command-line work (tqdm, on stderr).

Bars show on a terminal and stay silent when stderr is not one (logs, CI, tests) unless
``VISPRIM_PROGRESS=1`` forces them (``=0`` hides them everywhere); the command line's
``--quiet`` hides them too (:func:`hidden`).

* :func:`stages`: a bar over named stages of one piece of work;
* :func:`bar`: a bar over the items of an iterable (trials, folds, frames).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import Any, TextIO, TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")

_hidden = False


def _disable() -> bool | None:
    flag = os.environ.get("VISPRIM_PROGRESS", "")
    if _hidden or flag == "0":
        return True
    if flag == "1":
        return False
    return None  # tqdm: disable when not a TTY


@contextmanager
def hidden(hide: bool = True) -> Iterator[None]:
    """Within the block, no bar is shown if ``hide`` (the command line's ``--quiet``)."""
    global _hidden
    before = _hidden
    _hidden = before or hide
    try:
        yield
    finally:
        _hidden = before


def write(text: str, file: TextIO | None = None) -> None:
    """Print ``text`` (one line) without breaking a bar that is showing."""
    tqdm.write(text, file=file or sys.stderr)


class Stages:
    """A bar over named stages: ``step("filtering")`` advances it and shows the name."""

    def __init__(self, bar: Any) -> None:
        self._bar = bar
        self._started = False

    def step(self, name: str) -> None:
        """Mark the previous stage done and show ``name`` as the current one."""
        if self._bar.disable:
            return
        if self._started:
            self._bar.update(1)
        self._started = True
        self._bar.set_postfix_str(name)


@contextmanager
def stages(total: int, desc: str) -> Iterator[Stages]:
    """Context manager yielding :class:`Stages` over ``total`` steps."""
    bar = tqdm(total=total, desc=desc, unit="stage", disable=_disable(), leave=False)
    try:
        yield Stages(bar)
        if not bar.disable:
            bar.update(total - bar.n)
    finally:
        bar.close()


def bar(
    items: Iterable[T], desc: str, *, total: int | None = None, unit: str = "it"
) -> Iterator[T]:
    """Iterate over ``items`` showing a bar (``total`` defaults to ``len(items)``)."""
    if total is None and hasattr(items, "__len__"):
        total = len(items)  # type: ignore[arg-type]
    with tqdm(items, desc=desc, total=total, unit=unit, disable=_disable(), leave=False) as it:
        yield from it
