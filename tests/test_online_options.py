"""The online pipeline's settings are declared once (visprim.params.ONLINE_OPTIONS)."""

from __future__ import annotations

import inspect

from visprim.cli.main import build_parser
from visprim.cli.watch import online_options
from visprim.online import OnlinePipeline
from visprim.online.segmenter import OnlineSegmenter
from visprim.params import ONLINE_OPTIONS, SEG2_MIN_TRAVEL_DEG
from visprim.segment.seg2 import DEFAULT_MIN_TRAVEL_DEG


def _defaults(func) -> dict:
    return {
        n: p.default
        for n, p in inspect.signature(func).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


def test_every_online_setting_is_a_keyword_with_the_declared_default():
    given = {**_defaults(OnlineSegmenter.__init__), **_defaults(OnlinePipeline.__init__)}
    for name, option in ONLINE_OPTIONS.items():
        assert name in given, name
        assert given[name] == option.default, name
    segmenter_keywords = set(_defaults(OnlineSegmenter.__init__))
    assert segmenter_keywords <= set(ONLINE_OPTIONS), segmenter_keywords - set(ONLINE_OPTIONS)


def test_offline_and_online_seg2_share_the_least_travel():
    assert DEFAULT_MIN_TRAVEL_DEG == SEG2_MIN_TRAVEL_DEG
    assert ONLINE_OPTIONS["min_travel_deg"].default == SEG2_MIN_TRAVEL_DEG


def test_watch_passes_only_the_settings_given():
    parse = build_parser().parse_args
    assert online_options(parse(["watch", "r.bvh", "--model", "m.npz"])) == {}
    args = parse(
        ["watch", "r.bvh", "--model", "m.npz", "--rest-timeout", "2", "--threshold", "fixed"]
    )
    assert online_options(args) == {"rest_timeout": 2.0, "threshold": "fixed"}


def test_the_segmenter_checks_its_settings_against_their_declaration(monkeypatch):
    """The choices and units the segmenter accepts are the declared ones: a choice added to
    the declaration is accepted by the check, one removed is refused."""
    import dataclasses

    import pytest
    from visprim.online import segmenter

    with pytest.raises(ValueError, match="threshold must be 'adaptive' or 'fixed'"):
        segmenter._checked("threshold", "median")
    with pytest.raises(ValueError, match="segment_filter"):
        segmenter._checked("segment_filter", "none")
    for name in ("rest_timeout", "max_segment", "speed_window"):
        assert ONLINE_OPTIONS[name].unit == "s"
        for bad in (0.0, -1.0, float("nan"), float("inf"), "1"):
            with pytest.raises(ValueError, match=f"{name} must be a positive number"):
                segmenter._checked(name, bad)
        assert segmenter._checked(name, 0.5) == 0.5
    changed = dict(ONLINE_OPTIONS)
    changed["threshold"] = dataclasses.replace(ONLINE_OPTIONS["threshold"], choices=("fixed",))
    monkeypatch.setattr(segmenter, "ONLINE_OPTIONS", changed)
    assert segmenter._checked("threshold", "fixed") == "fixed"
    with pytest.raises(ValueError, match="must be 'fixed', got 'adaptive'"):
        segmenter._checked("threshold", "adaptive")
