"""The one way visprim writes CSV: :mod:`csv` quoting, and no spreadsheet formulas.

Every CSV the package writes (``classify --out``, ``summary.csv`` and ``predictions.csv`` of
``evaluate``, the report's tables, the imitation and trajectory files) goes through
:func:`csv_text`:

* cells are quoted as :mod:`csv` does (``QUOTE_MINIMAL``; every cell of a row holding a
  carriage return): a name holding a comma, a quote or a line break stays one cell;
* a text cell that a spreadsheet would run as a formula — one starting with ``=``, ``+``,
  ``-``, ``@``, a tab or a carriage return, such as a label ``=HYPERLINK(...)`` or a file
  ``+cmd|' -C calc'!A0.bvh`` — gets a leading ``'`` (OWASP's advice against CSV injection),
  so it shows as text. Numbers are left alone, including negative ones written as text
  (``-1.5``, ``-2e-3``): they stay numeric.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from typing import Any

#: First characters that make a spreadsheet evaluate a cell.
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return text.strip() == text


def safe_cell(value: Any) -> Any:
    """``value`` as written: a text cell starting a formula is prefixed with ``'`` (see the
    module docstring); numbers and other text unchanged."""
    if isinstance(value, str) and value.startswith(FORMULA_START) and not _is_number(value):
        return "'" + value
    return value


class SafeWriter:
    r""":func:`csv.writer` on ``fh`` (``\n`` line ends) whose rows go through
    :func:`safe_cell`."""

    def __init__(self, fh: Any) -> None:
        self._writer = csv.writer(fh, lineterminator="\n")
        # csv quotes a field holding the line terminator ("\n"), not one holding "\r":
        # rows with a carriage return are written with every cell quoted.
        self._quoted = csv.writer(fh, lineterminator="\n", quoting=csv.QUOTE_ALL)

    def writerow(self, row: Iterable[Any]) -> None:
        cells = [safe_cell(c) for c in row]
        cr = any(isinstance(c, str) and "\r" in c for c in cells)
        (self._quoted if cr else self._writer).writerow(cells)

    def writerows(self, rows: Iterable[Iterable[Any]]) -> None:
        for row in rows:
            self.writerow(row)


def writer(fh: Any) -> SafeWriter:
    """A :class:`SafeWriter` on the text file ``fh`` (opened with ``newline=""``)."""
    return SafeWriter(fh)


def csv_text(header: Sequence[Any] | None, rows: Iterable[Sequence[Any]]) -> str:
    """CSV text (``\\n`` line ends) of an optional ``header`` row and ``rows``, every cell
    through :func:`safe_cell`."""
    buf = io.StringIO()
    w = SafeWriter(buf)
    if header is not None:
        w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()
