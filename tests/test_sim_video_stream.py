"""The imitation video is drawn incrementally and written one frame at a time: the
incremental frames equal frames drawn from scratch, and the GIF holds exactly the frames."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
from visprim.imitate import imitate
from visprim.sim.sidebyside import SideBySide
from visprim.sim.video import write_video


@pytest.fixture(scope="module")
def imitation():
    trials = imitation_experiment(2, 4, seed=3, preset="strokes")
    model = PrimitiveModel(n_clusters=6, n_init=2, seed=0).fit(trials[:-1])
    return imitate(model, trials[-1])


def test_incremental_frames_equal_frames_drawn_from_scratch(imitation):
    view = SideBySide(imitation, (96, 96))
    n = view.n_frames
    assert n > 20
    sequential = [np.asarray(view.frame(i)) for i in range(n)]
    rng = np.random.default_rng(0)
    for i in rng.choice(n, size=8, replace=False):
        fresh = SideBySide(imitation, (96, 96))  # nothing drawn yet: the whole trail at once
        np.testing.assert_array_equal(np.asarray(fresh.frame(int(i))), sequential[i])
    # Going back in time (random access) redraws the trails from the start.
    for i in (n - 1, 3, n // 2, 0):
        np.testing.assert_array_equal(np.asarray(view.frame(i)), sequential[i])
    # The trails grow: the last frame differs from the first.
    assert not np.array_equal(sequential[0], sequential[-1])


def test_gif_streams_every_frame_exactly(tmp_path):
    rng = np.random.default_rng(1)
    colours = rng.integers(0, 256, size=(6, 3), dtype=np.uint8)
    frames = [Image.fromarray(colours[rng.integers(0, 6, size=(40, 56))]) for _ in range(30)]
    path = write_video(tmp_path / "v.gif", iter(frames), 25.0)
    with Image.open(path) as gif:
        assert gif.n_frames == 30 and gif.info["loop"] == 0 and gif.info["duration"] == 40
        for k, frame in enumerate(frames):
            gif.seek(k)
            np.testing.assert_array_equal(np.asarray(gif.convert("RGB")), np.asarray(frame))


def test_a_frame_draws_a_bounded_number_of_line_points(imitation, monkeypatch):
    """Linear time: the last frame draws no more than the first (the old drawing redrew
    the whole trail and the whole target path on every frame)."""
    from PIL import ImageDraw

    counted = [0]
    line = ImageDraw.ImageDraw.line

    def counting(self, xy, *args, **kwargs):
        counted[0] += len(xy) if not isinstance(xy[0], (int, float)) else len(xy) // 2
        return line(self, xy, *args, **kwargs)

    monkeypatch.setattr(ImageDraw.ImageDraw, "line", counting)
    view = SideBySide(imitation, (96, 96))
    per_frame = []
    for i in range(view.n_frames):
        counted[0] = 0
        view.frame(i)
        per_frame.append(counted[0])
    # After the first frame (which draws the target path once), a frame draws a few
    # segments of each trail and the arm's bones, unless a via point was just reached.
    steady = sorted(per_frame[1:])[: len(per_frame) // 2]
    assert max(steady) <= 60, per_frame
    assert np.median(per_frame[-10:]) <= 60, per_frame
