"""Long playbacks go to disk: a spilled :class:`Trace` indexes like the array it holds, and a
playback (and its video) streamed through it is the same, bit for bit, as one in memory."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim import play, trace
from visprim.sim.trace import Trace, TraceWriter


def _written(rows: np.ndarray, spill: int, block: int = 7) -> np.ndarray | Trace:
    w = TraceWriter(rows.shape[1:], rows.dtype, spill_bytes=spill)
    for i in range(0, rows.shape[0], block):
        w.append(rows[i : i + block])
    return w.finish()


def test_a_spilled_trace_indexes_like_its_array() -> None:
    rng = np.random.default_rng(0)
    rows = rng.normal(size=(103, 3, 2))
    small = _written(rows, spill=1 << 20)
    assert isinstance(small, np.ndarray) and np.array_equal(small, rows)
    t = _written(rows, spill=100)
    assert isinstance(t, Trace) and t.shape == rows.shape and len(t) == 103
    idx = rng.integers(-103, 103, size=40)
    mask = rng.random(103) < 0.3
    for key in (0, -1, 57, slice(None), slice(10, 20), slice(5, None, 7), slice(None, None, -3)):
        np.testing.assert_array_equal(t[key], rows[key])
    np.testing.assert_array_equal(t[idx], rows[idx])
    np.testing.assert_array_equal(t[mask], rows[mask])
    np.testing.assert_array_equal(t[[3, 3, 1]], rows[[3, 3, 1]])
    np.testing.assert_array_equal(t[-1, 2], rows[-1, 2])
    np.testing.assert_array_equal(t[:, 1, 0], rows[:, 1, 0])
    np.testing.assert_array_equal(t[idx, 0], rows[idx, 0])
    np.testing.assert_array_equal(np.asarray(t), rows)
    assert np.all(np.isfinite(t))
    with pytest.raises(IndexError):
        t[103]
    with pytest.raises(IndexError):
        t[np.array([0, 200])]
    with pytest.raises(ValueError):
        TraceWriter((3, 2)).append(np.zeros((2, 3)))


def test_a_playback_streamed_to_disk_is_the_same_as_in_memory(monkeypatch, tmp_path) -> None:
    from visprim.sim.render import render_gif

    t = np.linspace(0.0, 9.0, 300)
    a = np.stack(
        [0.5 * np.sin(t), 1.0 + 0.4 * np.cos(0.7 * t), 0.3 * np.sin(1.3 * t), 1 + 0.5 * np.sin(t)],
        axis=1,
    )
    memory = play(t, a, dt=0.002, render_fps=10.0)  # 4,500 steps: more than a window, a block
    assert isinstance(memory.q_actual, np.ndarray)
    monkeypatch.setattr(trace, "SPILL_BYTES", 0)
    disk = play(t, a, dt=0.002, render_fps=10.0)
    for name in ("q_actual", "q_target", "joint_errors_deg", "frames"):
        assert isinstance(getattr(disk, name), Trace), name
        np.testing.assert_array_equal(np.asarray(getattr(disk, name)), getattr(memory, name))
    for name in ("rms_error_deg", "max_error_deg", "completion_time", "n_reached"):
        assert getattr(disk, name) == getattr(memory, name), name
    np.testing.assert_array_equal(disk.hand_path, memory.hand_path)
    gifs = [
        render_gif(pb, tmp_path / f"{k}.gif", size=(64, 64)) for k, pb in enumerate((memory, disk))
    ]
    assert gifs[0].read_bytes() == gifs[1].read_bytes()
