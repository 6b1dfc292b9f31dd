"""Progress bars for long command-line work (tqdm, on stderr).

Bars show on a terminal and stay silent when stderr is not one (logs, CI, tests) unless
``VISPRIM_PROGRESS=1`` forces them (``=0`` hides them everywhere).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from tqdm.auto import tqdm


def _disable() -> bool | None:
    flag = os.environ.get("VISPRIM_PROGRESS", "")
    if flag == "1":
        return False
    if flag == "0":
        return True
    return None  # tqdm: disable when not a TTY


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
            bar.update(bar.total - bar.n)
    finally:
        bar.close()
