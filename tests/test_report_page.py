"""The report page: contents, units, provenance, GIFs, the paper comparison, real trials."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from _pipeline_data import default_trials, fitted
from visprim.accuracy import ErrorTable, ErrorTables
from visprim.report import UNITS_NOTE, repetitions_text, write_report
from visprim.report.html import markdown_table, slug
from visprim.report.paper import (
    PAPER_TOTAL_DEG,
    comparison_markdown,
    comparison_rows,
    tables_in_degrees,
)
from visprim.trial import Trial


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    out = tmp_path_factory.mktemp("page")
    gif = out / "primitives" / "p0.gif"
    gif.parent.mkdir()
    gif.write_bytes(b"GIF89a")
    tables = {"seg2": fitted().error_table()}
    rep = write_report(
        fitted(),
        out,
        list(default_trials()[:12]),
        comparison=comparison_markdown(tables),
        gifs=[gif],
        provenance="Recorded somewhere, 34 ms frames.",
    )
    return rep.index.read_text(encoding="utf-8")


def test_contents_link_every_section(page):
    headings = re.findall(r'<h2 id="([^"]+)">', page)
    links = re.findall(r'<li><a href="#([^"]+)">', page)
    assert headings and links == headings
    assert len(set(headings)) == len(headings)


def test_units_stated_once_and_provenance_shown(page):
    assert page.count(UNITS_NOTE.replace("'", "&#x27;")) == 1
    assert "Recorded somewhere, 34 ms frames." in page


def test_gifs_embedded_relative(page):
    assert '<img src="primitives/p0.gif"' in page


def test_figure_numbers_follow_the_paper(page):
    for n in (5, 6, 7, 8, 9, 10, 11):
        assert f"Fig. {n}:" in page, n


def test_comparison_table_on_the_page(page):
    assert "Comparison with the paper" in page
    assert "<td>32.71</td>" in page  # paper's SEG-2 value at k = 20


def test_comparison_rows_and_ratio():
    t3 = ErrorTable(
        "t3",
        ("clusters k", "angular error (deg)"),
        ((10, 20.71), (20, 16.355), (30, 29.5)),
    )
    empty = ErrorTable("x", ("a",), ())
    tables = {"seg2": ErrorTables(empty, empty, t3)}
    rows = comparison_rows(tables)
    assert [r[1] for r in rows] == [10, 20, 30]
    assert rows[0][4] == pytest.approx(0.5) and rows[1][4] == pytest.approx(0.5)
    assert rows[2][4] == pytest.approx(1.0)
    text = comparison_markdown(tables)
    assert "| SEG-2 | 20* | 32.71 | 16.36 | 0.50 |" in text
    assert "| SEG-2 | 10 |" in text  # k = 10 is shown but not a calibrated row
    assert PAPER_TOTAL_DEG["seg1"][20] == 26.68


def test_tables_in_degrees_converts_only_squared_errors():
    t = ErrorTable("t", ("k", "mse (rad^2)", "angular error (deg)"), ((3, 1.0, 2.0),))
    out = tables_in_degrees(ErrorTables(t, t, t)).total
    assert out.columns == ("k", "mse (deg^2)", "angular error (deg)")
    assert out.rows[0] == (3, pytest.approx(math.degrees(1.0) ** 2), 2.0)


def test_markdown_table_and_slug():
    html = markdown_table("| a | b |\n|---|---:|\n| 1 | <x> |\n")
    assert html == (
        '<div class="scroll"><table><tr><th>a</th><th>b</th></tr>'
        "<tr><td>1</td><td>&lt;x&gt;</td></tr></table></div>"
    )
    assert slug("Error analysis (Tables 1–3)") == "error-analysis-tables-1-3"


def test_repetitions_unknown_on_real_trials():
    t = np.linspace(0, 1, 10)
    real = Trial(times=t, markers=np.zeros((10, 4, 3)) + np.arange(4)[None, :, None])
    assert repetitions_text(real) == "unknown"
    real.meta["repetitions"] = 3
    real.repetitions = 3
    assert repetitions_text(real) == "3"
    assert repetitions_text(default_trials()[0]) == str(default_trials()[0].repetitions)
