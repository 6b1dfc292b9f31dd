"""CSV cells are quoted and formula-leading text is neutralised (OWASP), numbers are not."""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import pytest
from visprim import PrimitiveModel
from visprim.cli import main
from visprim.csvfile import csv_text, safe_cell
from visprim.datasets import imitation_experiment
from visprim.io.markers_csv import write_marker_csv

EVIL = [
    '=HYPERLINK("http://evil.example","B")',
    "+cmd|' -C calc'!A0",
    "-2+3",
    "@SUM(A1:A2)",
    "\tx",
    "\rx",
]


@pytest.mark.parametrize("cell", EVIL)
def test_formula_cells_get_a_leading_quote(cell):
    assert safe_cell(cell) == "'" + cell


@pytest.mark.parametrize("cell", ["-1.5", "-2e-3", "+4", "walk", "a=b", 3, -1.5, "-inf"])
def test_numbers_and_plain_text_are_unchanged(cell):
    assert safe_cell(cell) == cell


def test_names_with_separators_stay_one_cell():
    names = ['a,b;c"d.bvh', "two\nlines", *EVIL]
    text = csv_text(["name", "x"], [[n, -1.5] for n in names])
    rows = list(csv.reader(io.StringIO(text, newline="")))
    assert all(len(r) == 2 for r in rows)
    assert [r[0] for r in rows[1:]] == [safe_cell(n) for n in names]
    assert {r[1] for r in rows[1:]} == {"-1.5"}


def test_classify_csv_quotes_and_neutralises_trial_names(tmp_path, capsys):
    trials = imitation_experiment(2, 4, seed=4)
    model = PrimitiveModel(n_clusters=4, n_init=1).fit(trials)
    model.save(tmp_path / "m.npz")
    data = tmp_path / "data"
    data.mkdir()
    names = ['a,b;c"d', "+cmd|' -C calc'!A0", "=1+1"]
    for name, trial in zip(names, trials, strict=False):
        trial.name = name
        write_marker_csv(data / f"{name}.csv", trial)
    out = tmp_path / "seg.csv"
    assert main(["-q", "classify", str(tmp_path / "m.npz"), str(data), "--out", str(out)]) == 0
    rows = list(csv.reader(out.open(encoding="utf-8", newline="")))
    assert rows[0] == ["trial", "segment", "start_s", "end_s", "primitive", "distance_rad"]
    assert all(len(r) == 6 for r in rows)
    assert {r[0] for r in rows[1:]} == {'a,b;c"d', "'+cmd|' -C calc'!A0", "'=1+1"}


def test_every_csv_writer_of_the_package_is_the_safe_one():
    root = Path(__file__).resolve().parents[1] / "python" / "visprim"
    raw = re.compile(r"csv\.(writer|DictWriter)\(")
    users = sorted(
        str(p.relative_to(root)) for p in root.rglob("*.py") if raw.search(p.read_text("utf-8"))
    )
    assert users == ["csvfile.py"]
