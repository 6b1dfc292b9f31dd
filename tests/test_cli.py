"""The pipeline subcommands of the CLI: demo, learn, report, classify (the happy paths;
failures in test_cli_errors.py, outputs in test_cli_outputs.py)."""

from __future__ import annotations

import re
from html import escape as html_escape

import numpy as np
import pytest
from visprim import PrimitiveModel
from visprim.cli import build_parser, main
from visprim.provenance import Provenance

SMALL = ["--subjects", "2", "--stimuli", "20", "--clusters", "8"]


@pytest.mark.parametrize("command", ["demo", "learn", "report", "classify"])
def test_help(command, capsys):
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert command in out and "--out" in out


def test_top_level_help_lists_the_subcommands():
    text = build_parser().format_help()
    for command in ("demo", "learn", "report", "classify", "generate", "simulate"):
        assert command in text


@pytest.fixture(scope="module")
def learned(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "model.npz"
    assert main(["learn", "--out", str(path), *SMALL]) == 0
    return path


def test_learn_writes_a_model_and_prints_tables(learned, capsys):
    m = PrimitiveModel.load(learned)
    assert m.n_primitives == 8
    assert m.provenance_ == Provenance.generated(2, 20, 0, "paper")
    assert m.error_tables_ is not None
    assert m.get_params()["n_clusters"] == 8


def test_learn_output(tmp_path, capsys):
    path = tmp_path / "m.npz"
    assert main(["learn", "--generated", "--out", str(path), *SMALL, "--segmentation", "seg1"]) == 0
    out = capsys.readouterr().out
    assert "SEG-1 segments" in out
    assert out.count("**Table") == 3
    assert f"model written to {path}" in out


def test_learn_bad_parameter_is_a_clear_error(tmp_path, capsys):
    code = main(
        [
            "learn",
            "--out",
            str(tmp_path / "m.npz"),
            "--subjects",
            "1",
            "--stimuli",
            "3",
            "--clusters",
            "100000",
        ]
    )
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("visprim learn: error: --clusters 100000 exceeds")
    assert "lower --clusters" in err[-1]
    assert not (tmp_path / "m.npz").exists()


def test_version(capsys):
    import visprim

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"visprim {visprim.__version__}"


def test_report_from_the_recorded_source(learned, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["report", str(learned), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"report written to {out / 'index.html'}" in printed
    assert (out / "segmentation.png").exists()
    assert (out / "movement_reconstruction.png").exists()
    assert (out / "table3.csv").exists()


def test_classify_prints_sequences_and_scores(learned, tmp_path, capsys):
    csv_path = tmp_path / "labels.csv"
    assert (
        main(
            ["classify", str(learned), "--subjects", "1", "--stimuli", "4", "--out", str(csv_path)]
        )
        == 0
    )
    out = capsys.readouterr().out
    lines = [line for line in out.splitlines() if line.startswith("s00_m0")]
    assert len(lines) == 4
    assert all("sequence [" in line for line in lines)
    assert re.search(r"against the true strokes: ARI -?\d\.\d+, purity \d\.\d+", out)
    rows = csv_path.read_text().splitlines()
    assert rows[0].startswith("trial,segment,start_s,end_s,primitive")
    labels = np.array([int(r.split(",")[4]) for r in rows[1:]])
    assert labels.size > 0 and labels.max() < 8


def test_demo_quiet_prints_only_where_the_results_are(tmp_path, capsys):
    out = tmp_path / "demo"
    argv = ["-q", "demo", "--out", str(out), "--no-sim", "--subjects", "2", "--stimuli", "6"]
    assert main([*argv, "--clusters", "4"]) == 0
    printed = capsys.readouterr().out
    assert "Table 1" not in printed and "| SEG-1 |" not in printed
    assert f"Report:  {out / 'index.html'}" in printed
    assert (out / "table1.md").exists()


def test_demo_small(tmp_path, capsys):
    out = tmp_path / "demo"
    assert (
        main(
            [
                "demo",
                "--out",
                str(out),
                "--no-sim",
                "--subjects",
                "2",
                "--stimuli",
                "20",
                "--clusters",
                "8",
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "Segmentation against the true stroke boundaries" in printed
    assert "| SEG-1 |" in printed and "| SEG-2 |" in printed
    assert printed.count("**Table 1") == 2  # SEG-1 and SEG-2 models
    # One heading, the same scores on the console and on the page.
    scores = re.search(r"Segment primitives vs true stroke labels: (.*)", printed)
    assert scores is not None and "at k = " in scores[1] and "SEG-2 model (k = 8)" in scores[1]
    assert html_escape(scores[1]) in (out / "index.html").read_text(encoding="utf-8")
    assert f"Report:  {out / 'index.html'}" in printed
    assert f"saved {out / 'model_seg2.npz'}" in printed  # final paths, not the temporary ones
    for name in ("index.html", "model_seg1.npz", "model_seg2.npz", "primitives.png", "table1.md"):
        assert (out / name).exists(), name
    page = (out / "index.html").read_text(encoding="utf-8")
    assert ".visprim-tmp" not in page
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo"]  # no temporary left
    assert "| SEG-2 | 20* | 32.71 |" in printed  # the comparison with the paper's Table 3
    html = (out / "index.html").read_text(encoding="utf-8")
    assert "Comparison with the paper" in html and "deg²" in html
    assert "Tables 1-3 (SEG-1" not in html  # no console dump on the page
