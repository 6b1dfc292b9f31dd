"""Frames are drawn in a second thread a few ahead of the encoder: order kept, errors raised
in the writer, nothing written on failure, and never more than a few frames held."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from visprim.sim.video import PREFETCH, prefetched, write_video


def test_order_and_bounded_lead() -> None:
    made = []

    def frames():
        for i in range(50):
            made.append(i)
            yield i

    seen = []
    for i in prefetched(frames()):
        # The producer is at most the queue's depth (plus the frame it is handing over)
        # ahead of what was consumed.
        assert len(made) - len(seen) <= PREFETCH + 2
        seen.append(i)
    assert seen == list(range(50))


def test_an_error_while_drawing_reaches_the_writer_and_leaves_no_file(tmp_path) -> None:
    def frames():
        for i in range(5):
            if i == 3:
                raise RuntimeError("drawing failed")
            yield Image.fromarray(np.full((8, 8, 3), 40 * i, dtype=np.uint8))

    with pytest.raises(RuntimeError, match="drawing failed"):
        write_video(tmp_path / "v.gif", frames(), 10.0)
    assert list(tmp_path.iterdir()) == []


def test_leaving_early_stops_the_producer() -> None:
    def frames():
        yield from range(10**9)

    it = prefetched(frames())
    assert next(it) == 0
    it.close()  # joins the producer thread: returns only once it stopped
