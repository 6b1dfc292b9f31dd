"""The method's settings are declared once (visprim.params) and every entry point reads them:
the estimator, its paper preset, the command line and the demo."""

from __future__ import annotations

import inspect

import pytest
from visprim import params
from visprim.cli import common
from visprim.cli.main import build_parser
from visprim.model import PrimitiveModel

#: Table 3 of Fod, Matarić & Jenkins: total angular error (degrees), at f = 30.
PAPER_TABLE3 = {
    "seg2": {10: 41.42, 20: 32.71, 30: 29.50, 100: 20.22, 170: 19.42},
    "seg1": {10: 60.28, 20: 26.68, 30: 24.43},
}
#: The rows the generated experiment is calibrated on, and the tolerance of the ratio.
CALIBRATED = {"seg2": (20, 30, 100, 170), "seg1": (20, 30)}
FACTOR = 1.3


def _args(*argv: str):
    return build_parser().parse_args(list(argv))


def test_the_constructor_defaults_are_the_declared_ones():
    signature = inspect.signature(PrimitiveModel.__init__).parameters
    declared = params.defaults()
    assert list(declared) == [n for n in signature if n != "self"]
    assert {n: signature[n].default for n in declared} == declared
    assert PrimitiveModel().get_params() == declared


def test_paper_preset_is_the_same_from_the_api_learn_and_demo():
    paper = PrimitiveModel.paper().get_params()
    assert {k: paper[k] for k in params.PAPER} == dict(params.PAPER)
    assert paper["offsets"] == "turns" and paper["features"] == "zyz"
    learn = common.model_from_args(_args("learn", "--out", "m.npz", "--paper")).get_params()
    demo = common.model_from_args(_args("demo", "--out", "d")).get_params()
    assert learn == paper
    assert demo == paper


def test_the_command_line_passes_on_only_what_was_given():
    assert common.model_from_args(_args("learn", "--out", "m.npz")).get_params() == (
        PrimitiveModel().get_params()
    )
    m = common.model_from_args(
        _args("learn", "--out", "m.npz", "--paper", "--features", "directions", "--clusters", "7")
    )
    assert m.get_params() == PrimitiveModel.paper(features="directions", n_clusters=7).get_params()
    m = common.model_from_args(_args("demo", "--out", "d", "--seg1-adaptive", "--offsets", "mean"))
    assert m.seg1_adaptive is True and m.offsets == "mean" and m.features == "zyz"


def test_every_option_is_declared_and_sets_its_parameter():
    assert common.MODEL_OPTIONS == {
        p.name: p.option for p in params.PARAMETERS if p.option is not None
    }
    flags = {
        "filter_order": "6",
        "cutoff": "0.3",
        "segmentation": "seg1",
        "zvc_threshold_deg": "4",
        "window": "0.25",
        "seg2_tuning": "repetitions",
        "seg2_boundary": "slowest",
        "features": "zyz",
        "offsets": "turns",
        "n_samples": "50",
        "n_components": "10",
        "n_clusters": "9",
        "n_init": "2",
        "max_iter": "40",
        "seed": "3",
    }
    argv = ["learn", "--out", "m.npz"]
    for name, text in flags.items():
        argv += [common.MODEL_OPTIONS[name], text]
    got = common.model_from_args(_args(*argv)).get_params()
    for name, text in flags.items():
        assert str(got[name]) == text or float(got[name]) == float(text), name


@pytest.mark.parametrize(
    ("name", "bad"),
    [
        ("filter_order", 0),
        ("filter_order", 2.5),
        ("cutoff", 1.0),
        ("segmentation", "seg3"),
        ("zvc_threshold_deg", float("nan")),
        ("window", -1.0),
        ("seg1_adaptive", "yes"),
        ("seg2_threshold", 0.0),
        ("seg2_tuning", "fast"),
        ("seg2_boundary", "middle"),
        ("features", "quaternions"),
        ("offsets", "none"),
        ("amplitude", 1),
        ("n_samples", 1),
        ("n_clusters", 0),
        ("n_init", True),
        ("max_iter", 0),
        ("tol", -1.0),
        ("seed", -1),
    ],
)
def test_each_declared_constraint_refuses_a_bad_value(name, bad):
    with pytest.raises(ValueError, match=f"parameter {name}="):
        PrimitiveModel(**{name: bad})._validate_params()


def test_the_demo_reproduces_the_papers_table3():
    """The demo's models (the paper's method on the default generated experiment) give the
    paper's Table 3 within a factor 1.3 on the calibrated rows."""
    from visprim.cli.demo import paper_models
    from visprim.report.paper import total_error_by_k

    args = _args("demo", "--out", "d", "--no-sim")
    source = common.generated_source(args)
    trials = common.load_source(source)
    ratios = {}
    for method, model in paper_models(args, trials, source):
        ours = total_error_by_k(model.error_table(k_values=CALIBRATED[method]))
        for k in CALIBRATED[method]:
            ratios[(method, k)] = ours[k] / PAPER_TABLE3[method][k]
    assert len(ratios) == 6
    for key, ratio in ratios.items():
        assert 1 / FACTOR <= ratio <= FACTOR, (key, ratio)


@pytest.mark.parametrize("preset", [[], ["--paper"]])
def test_the_printed_seg2_constant_given_back_cuts_the_same_segments(tmp_path, capsys, preset):
    """``learn`` prints c in (deg/s)^2, the unit ``--seg2-threshold`` takes: pasting it back
    gives the same segmentation."""
    import re

    import numpy as np
    from visprim.cli import main

    small = ["--subjects", "2", "--stimuli", "6", "--clusters", "5", "--components", "8"]
    assert main(["learn", "--out", str(tmp_path / "a.npz"), *small, *preset]) == 0
    out = capsys.readouterr().out
    found = re.search(r"SEG-2 c = (\S+) \(deg/s\)\^2 \(--seg2-threshold\)", out)
    assert found is not None, out
    printed = found.group(1)
    tuned = PrimitiveModel.load(tmp_path / "a.npz")
    assert float(printed) == pytest.approx(tuned.seg2_threshold_ * params.DEG2_PER_RAD2, rel=1e-5)
    argv = ["learn", "--out", str(tmp_path / "b.npz"), *small, *preset]
    assert main([*argv, "--seg2-threshold", printed]) == 0
    given = PrimitiveModel.load(tmp_path / "b.npz")
    assert given.seg2_threshold == pytest.approx(tuned.seg2_threshold_, rel=1e-5)
    assert given.n_training_segments_ == tuned.n_training_segments_
    np.testing.assert_allclose(given.segment_starts_, tuned.segment_starts_)
    np.testing.assert_allclose(given.segment_ends_, tuned.segment_ends_)
    # The tables are printed in deg^2, as report and demo print them.
    assert "(deg^2)" in out and "(rad^2)" not in out


def test_reader_options_are_declared_once():
    """read, read_pieces and read_many take exactly the declared options, with the declared
    defaults; the command line offers the declared choices."""
    from visprim import io

    for fn in (io.read, io.read_pieces):
        sig = inspect.signature(fn).parameters
        declared = {n: o.default for n, o in params.READ_OPTIONS.items()}
        assert {n: sig[n].default for n in sig if n not in ("path", "arm")} == declared
    assert set(io.read_option_names()) == {"arm", *params.READ_OPTIONS}
    parser = build_parser()
    learn = next(
        a
        for a in parser._subparsers._group_actions[0].choices["learn"]._actions  # type: ignore[union-attr]
        if "--on-gap" in a.option_strings
    )
    assert tuple(learn.choices) == params.ON_GAP
    # Only what the user gave reaches the readers.
    assert common.reader_options(_args("learn", "--out", "m.npz")) == {"arm": "right"}
    given = common.reader_options(_args("learn", "--out", "m.npz", "--on-gap", "longest"))
    assert given == {"arm": "right", "on_gap": "longest"}
