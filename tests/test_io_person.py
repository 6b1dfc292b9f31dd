"""``person=``: which person of a video to follow, through read, read_many and the CLI."""

from __future__ import annotations

import numpy as np
import pytest
import visprim.io.video as video
from visprim import io
from visprim.cli.common import reader_options
from visprim.cli.main import build_parser
from visprim.trial import Trial


@pytest.fixture
def fake_video(tmp_path, monkeypatch):
    """A '.mp4' file whose reader records the person it was asked for."""
    path = tmp_path / "clip.mp4"
    path.write_bytes(b"not decoded: the reader is replaced")
    asked: list[int | None] = []

    def read_video_pieces(p, arm="right", *, person=None, **kw):
        asked.append(person)
        n = 40
        return [Trial(np.arange(n) * 0.034, np.zeros((n, 4, 3)), name=path.stem)]

    monkeypatch.setattr(video, "read_video_pieces", read_video_pieces)
    return path, asked


def test_person_reaches_the_video_reader(fake_video):
    path, asked = fake_video
    io.read(path)
    io.read(path, person=2)
    io.read_many([path], person=1)
    assert asked == [None, 2, 1]


@pytest.mark.parametrize("bad", [-1, 1.5, True, "0"])
def test_a_bad_person_is_refused_before_reading(fake_video, bad):
    path, asked = fake_video
    with pytest.raises(ValueError, match="person must be"):
        io.read(path, person=bad)
    with pytest.raises(ValueError, match="person must be"):
        io.read_many([path], person=bad)
    assert asked == []


def test_person_does_not_apply_to_motion_capture(tmp_path):
    bvh = tmp_path / "a.bvh"
    bvh.write_text("HIERARCHY\n")
    with pytest.raises(ValueError, match="person= applies to video files"):
        io.read(bvh, person=0)


def test_the_cli_option_gives_person():
    args = build_parser().parse_args(["learn", "x.mp4", "--person", "1", "--out", "m.npz"])
    assert reader_options(args)["person"] == 1
    args = build_parser().parse_args(["learn", "x.mp4", "--out", "m.npz"])
    assert "person" not in reader_options(args)
    with pytest.raises(SystemExit):
        build_parser().parse_args(["learn", "x.mp4", "--person", "-1", "--out", "m.npz"])
