"""The labelled-data benchmark (visprim.evaluate, `visprim evaluate`)."""

from __future__ import annotations

from pathlib import Path

import pytest
from _motion_data import movements
from visprim.classify import MotionClassifier
from visprim.evaluate import (
    Recording,
    evaluate_benchmark,
    find_recordings,
    make_benchmarks,
    read_movements,
    to_html,
    to_markdown,
    write_report,
)

SMALL_MODEL = {"n_samples": 20, "n_components": 5, "n_clusters": 4, "n_init": 1}


def _touch(folder: Path, *names: str) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for n in names:
        (folder / n).write_text("")


def test_labels_from_tables_and_bandai_names(tmp_path: Path) -> None:
    _touch(tmp_path / "corpus", "a1.bvh", "a2.bvh", "b1.bvh", "other.bvh", "README.md")
    (tmp_path / "corpus" / "labels.tsv").write_text(
        "file\tlabel\tstyle\tsubject\ttake\tgroup\tdescription\n"
        "a1.bvh\twave\tfast\tx\t1\tarm\t\n"
        "a2.bvh\twave\tslow\ty\t2\tarm\t\n"
        "b1.bvh\traise\tslow\tx\t1\tarm\t\n"
    )
    _touch(tmp_path / "corpus_extra", "dataset-2_wave-right-hand_elderly_004.bvh")
    recs, unlabelled = find_recordings([tmp_path])
    assert [p.name for p in unlabelled] == ["other.bvh"]
    by_name = {r.path.name: r for r in recs}
    assert by_name["a2.bvh"] == Recording(
        tmp_path / "corpus" / "a2.bvh", "wave", "slow", "y", "2", "corpus"
    )
    bandai = by_name["dataset-2_wave-right-hand_elderly_004.bvh"]
    assert (bandai.label, bandai.style, bandai.take, bandai.benchmark) == (
        "wave-right-hand",
        "elderly",
        "004",
        "corpus",
    )
    # A labels file given explicitly replaces the tables beside the data.
    table = tmp_path / "mine.tsv"
    table.write_text("file\tlabel\tsubject\nother.bvh\tjump\tz\n")
    recs, unlabelled = find_recordings([tmp_path / "corpus"], labels=table)
    assert [(r.path.name, r.label, r.subject) for r in recs] == [("other.bvh", "jump", "z")]
    assert len(unlabelled) == 3
    table.write_text("name\tlabel\nother.bvh\tjump\n")
    with pytest.raises(ValueError, match="file"):
        find_recordings([tmp_path / "corpus"], labels=table)
    with pytest.raises(ValueError, match="no such file"):
        find_recordings([tmp_path / "missing"])


def test_unreadable_recordings_are_skipped_with_a_reason(tmp_path: Path) -> None:
    bad = tmp_path / "broken.bvh"
    bad.write_text("HIERARCHY\nROOT")
    trials, errors = read_movements([Recording(bad, "x")], jobs=1)
    assert trials == [None]
    assert len(errors) == 1 and errors[0].startswith("skipped ") and "broken.bvh" in errors[0]


def test_benchmarks_choose_groups_and_drop_unlearnable_classes() -> None:
    def rec(label: str, subject: str, style: str) -> Recording:
        return Recording(Path(f"{label}{subject}{style}.bvh"), label, style, subject, "", "b")

    recs = [rec("a", "s1", "x"), rec("a", "s2", "x"), rec("b", "s1", "y"), rec("b", "s2", "y")]
    recs.append(rec("c", "s1", "x"))  # only one subject: can never be recognised
    benches, notes = make_benchmarks(recs, list(range(len(recs))))  # type: ignore[arg-type]
    assert len(benches) == 1 and benches[0].group_by == "subject"
    assert benches[0].left_out_classes == ["c"] and "left out c" in notes[0]
    benches, notes = make_benchmarks(recs, list(range(5)), group_by="style")  # type: ignore[arg-type]
    assert benches == [] and "skipped" in notes[-1]
    with pytest.raises(ValueError, match="group"):
        make_benchmarks(recs, list(range(5)), group_by="colour")  # type: ignore[arg-type]


def test_evaluate_benchmark_on_synthetic_movements(tmp_path: Path) -> None:
    data, labels = movements(3, seed=0)
    groups = ["g1", "g2", "g3"]
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", groups[i // 3], "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    benches, notes = make_benchmarks(recs, data)
    assert notes == [] and benches[0].group_by == "subject"
    res = evaluate_benchmark(benches[0], classifier=MotionClassifier(model_params=SMALL_MODEL))
    assert res.n_trials == 9 and res.classes == ["raise", "sweep", "wave"]
    assert res.accuracy == 1.0 and res.baseline_accuracy == 1.0
    assert res.confusion.trace() == 9 and res.baseline_confusion.sum() == 9
    assert res.n_arm_trials == 9 and set(res.seg2_thresholds) == set(groups)
    assert res.segments_per_trial > 0
    assert 0.0 <= res.coverage_min <= res.coverage_median <= 1.0
    # k = 30 and 100 primitives need more training segments than these few movements have.
    assert res.reconstruction_deg == {}
    md = to_markdown([res], ["a note"])
    assert "| synthetic | 3 subject | 9 | 3 | **1.000** | 1.000 |" in md
    assert "| - | - | - | - |" in md
    assert "- a note" in md
    page = to_html(md)
    assert page.count("<table>") == 3 and "<b>1.000</b>" in page
    paths = write_report([res], [], tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(
        p.name for p in paths.values()
    )
    summary = paths["summary"].read_text().splitlines()
    assert summary[0].startswith("benchmark,group_by,trials,classes,groups,accuracy,")
    assert len(paths["predictions"].read_text().splitlines()) == 10


def test_two_arm_movements_are_rebuilt_arm_by_arm() -> None:
    """Each arm is rebuilt from one-arm primitives learned from both arms: the resting left
    arm of these movements is easy to rebuild, so the movement error falls against the
    two-arm primitives that must cut both arms at the same times."""
    data, labels = movements(3, seed=1)
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic")
        for i, lab in enumerate(labels)
    ]
    bench = make_benchmarks(recs, data)[0][0]
    clf = MotionClassifier(model_params=SMALL_MODEL)
    each = evaluate_benchmark(bench, classifier=clf)
    joint = evaluate_benchmark(bench, classifier=clf, reconstruction="joint")
    assert (each.reconstruction, joint.reconstruction) == ("each arm", "joint")
    assert each.accuracy == joint.accuracy and each.n_arm_trials == joint.n_arm_trials == 9
    assert 0.0 < each.movement_rms_deg < joint.movement_rms_deg
    assert "one-arm primitives learned from both arms" in to_markdown([each])
    assert "one-arm primitives" not in to_markdown([joint])
    with pytest.raises(ValueError, match="reconstruction must be one of"):
        evaluate_benchmark(bench, classifier=clf, reconstruction="left")


def test_cli_on_bandai_recordings(shared_data: Path, tmp_path: Path) -> None:
    """`visprim evaluate` end to end on the 34 original Bandai dataset-2 takes (labels from
    the file names; 4 gestures, leave one of 7 styles out)."""
    from visprim.cli.main import main

    out = tmp_path / "report"
    assert main(["evaluate", str(shared_data / "bandai_namco_ds2"), "--out", str(out)]) == 0
    summary = (out / "summary.csv").read_text().splitlines()
    assert len(summary) == 2
    row = dict(zip(summary[0].split(","), summary[1].split(","), strict=True))
    assert row["benchmark"] == "bandai_namco_ds2" and row["group_by"] == "style"
    assert (row["trials"], row["classes"], row["groups"]) == ("34", "4", "7")
    # Chance is 0.25; both classifiers see both arms (right- vs both-hand gestures).
    assert float(row["accuracy"]) >= 0.75
    assert float(row["dtw_baseline_accuracy"]) >= 0.5
    assert "<table>" in (out / "evaluate.html").read_text()
    # An existing report is replaced only with --force, refused before any work.
    before = (out / "summary.csv").read_text()
    assert main(["evaluate", str(shared_data / "bandai_namco_ds2"), "--out", str(out)]) == 2
    assert (out / "summary.csv").read_text() == before
    assert main(["evaluate", str(tmp_path / "nothing"), "--out", str(tmp_path / "r2")]) == 2


def test_cli_methods_match_the_classifier() -> None:
    from visprim.classify import MOTION_METHODS
    from visprim.cli.evaluate import METHODS

    assert METHODS == MOTION_METHODS


def test_cli_reconstructions_match_the_library() -> None:
    from visprim.cli.evaluate import RECONSTRUCTIONS as CLI
    from visprim.evaluate import RECONSTRUCTIONS

    assert CLI == RECONSTRUCTIONS


def test_read_movements_reads_the_arm_asked_for(shared_data: Path) -> None:
    recordings, _ = find_recordings([shared_data / "bandai_namco_ds2"])
    two = recordings[:2]
    right, errors = read_movements(two, arm="right", jobs=1)
    both, _ = read_movements(two, jobs=1)
    assert not errors
    assert [t.arms for t in right if t is not None] == [("right",), ("right",)]
    assert [t.arms for t in both if t is not None] == [("right", "left")] * 2
    # The right arm of a two-arm read is the one-arm read.
    assert right[0] is not None and both[0] is not None
    assert right[0].markers.shape[1] == 4 and both[0].markers.shape[1] == 8
    assert abs(right[0].markers - both[0].markers[:, :4]).max() < 1e-12


def test_page_is_styled_with_figures_and_label_sources(tmp_path: Path) -> None:
    """evaluate.html: the report page's style sheet, wide tables in a scrolling box, a
    confusion-matrix and a per-group figure per benchmark, and where the labels came from."""
    from PIL import Image
    from visprim.evaluate import BANDAI_RULE
    from visprim.report.html import CSS

    _touch(tmp_path / "c", "a1.bvh", "dataset-2_wave-right-hand_elderly_004.bvh")
    (tmp_path / "c" / "labels.tsv").write_text("file\tlabel\na1.bvh\twave\n")
    recs, _ = find_recordings([tmp_path / "c"])
    sources = {r.path.name: r.label_source for r in recs}
    assert sources == {
        "a1.bvh": str(tmp_path / "c" / "labels.tsv"),
        "dataset-2_wave-right-hand_elderly_004.bvh": BANDAI_RULE,
    }

    data, labels = movements(3, seed=0)
    recs = [
        Recording(Path(f"m{i}.bvh"), lab, "", f"g{i // 3}", "", "synthetic", "my.tsv")
        for i, lab in enumerate(labels)
    ]
    res = evaluate_benchmark(
        make_benchmarks(recs, data)[0][0], classifier=MotionClassifier(model_params=SMALL_MODEL)
    )
    assert res.label_sources == {"my.tsv": 9}
    assert "Labels from my.tsv (9 recordings)." in to_markdown([res])
    paths = write_report([res], [], tmp_path / "out")
    page = paths["html"].read_text()
    assert CSS in page
    assert page.count('<div class="scroll"><table>') == page.count("<table>") == 3
    for kind in ("confusion", "groups"):
        png = paths[f"{kind} synthetic"]
        assert f'<img src="{png.name}"' in page
        with Image.open(png) as im:
            assert im.format == "PNG" and im.size[0] >= 400
    assert "Labels from my.tsv" in page
