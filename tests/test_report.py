"""The report: figures, tables and index.html (visprim.report)."""

from __future__ import annotations

import csv
import math
import re

import pytest
from _pipeline_data import default_trials, fitted
from PIL import Image
from visprim import PrimitiveModel
from visprim.report import write_report

TRIAL_FIGURES = (
    "segmentation.png",
    "seg2_threshold.png",
    "segment_reconstruction.png",
    "movement_reconstruction.png",
)
MODEL_FIGURES = ("eigenvalues.png", "eigenvectors.png", "primitives.png")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    trials = list(default_trials()[:40])
    return write_report(fitted(), out, trials, extra_sections=[("console", "hello <b>")])


def test_all_files_are_written(report):
    names = {p.name for p in report.files}
    for name in (*TRIAL_FIGURES, *MODEL_FIGURES, "index.html", "tables.md"):
        assert name in names, name
    for i in (1, 2, 3):
        assert f"table{i}.md" in names and f"table{i}.csv" in names
    assert "segmentation_scores.md" in names
    assert not report.skipped
    for p in report.files:
        assert p.exists() and p.stat().st_size > 0


def test_figures_are_real_pngs(report):
    for name in (*TRIAL_FIGURES, *MODEL_FIGURES):
        with Image.open(report.out_dir / name) as im:
            assert im.format == "PNG"
            w, h = im.size
            assert w >= 600 and h >= 300, (name, im.size)
            # Not a blank canvas: many distinct colours.
            assert len(im.convert("RGB").getcolors(maxcolors=1 << 20) or []) > 50, name


def test_index_shows_every_figure_and_table(report):
    html = report.index.read_text(encoding="utf-8")
    srcs = set(re.findall(r'<img src="([^"]+)"', html))
    assert srcs == set(TRIAL_FIGURES) | set(MODEL_FIGURES)
    assert html.count("<table>") == 4  # Tables 1-3 and the segmentation scores
    for i in (1, 2, 3):
        assert f'href="table{i}.csv"' in html and f"Table {i}:" in html
    # Extra text is escaped.
    assert "hello &lt;b&gt;" in html
    assert "precision" in html and "ARI" in html


def test_table_csvs_are_numeric_and_in_degrees(report):
    model = fitted()
    deg2 = math.degrees(1.0) ** 2
    for i, table in enumerate(model.error_table(), start=1):
        with open(report.out_dir / f"table{i}.csv", newline="") as fh:
            rows = list(csv.reader(fh))
        assert rows[0] == [c.replace("(rad^2)", "(deg^2)") for c in table.columns]
        assert len(rows) == len(table.rows) + 1
        for row, ref in zip(rows[1:], table.rows, strict=True):
            for name, v, r in zip(table.columns, row, ref, strict=True):
                scale = deg2 if "(rad^2)" in name else 1.0
                assert float(v) == pytest.approx(r * scale, rel=1e-12)


def test_without_trials_only_the_model_part(tmp_path):
    m = fitted()
    path = tmp_path / "m.npz"
    m.error_table()
    m.save(path)
    loaded = PrimitiveModel.load(path)
    rep = write_report(loaded, tmp_path / "r", None)
    names = {p.name for p in rep.files}
    assert set(MODEL_FIGURES) <= names
    assert not names & set(TRIAL_FIGURES)
    assert rep.skipped and "no trials" in rep.skipped[0].lower()
    assert "visprim report MODEL DATA" in rep.index.read_text(encoding="utf-8")


def test_unknown_trial_name(tmp_path):
    with pytest.raises(ValueError, match="no trial named 'zzz'"):
        write_report(fitted(), tmp_path, list(default_trials()[:3]), trial_name="zzz")
