"""Joining segment curves: no step in angle or velocity at boundaries, gaps bridged."""

from __future__ import annotations

import numpy as np
import pytest
from visprim.sim.joining import JoinedTrajectory

EPS = 1e-6  # seconds either side of a boundary


def _curves(rng, n_seg: int, n: int = 100) -> list[np.ndarray]:
    u = np.linspace(0.0, 1.0, n)[:, None]
    out = []
    for _ in range(n_seg):
        a, b, c = rng.normal(0, 1, (3, 4))
        out.append(a + b * np.sin(2.5 * u + c))  # ends that do not meet their neighbours'
    return out


def _jumps(traj: JoinedTrajectory, at: float) -> tuple[float, float]:
    """Largest step in angle and in finite-difference velocity across instant ``at``."""
    h = 1e-5
    t = np.array([at - EPS - h, at - EPS, at + EPS, at + EPS + h])
    a, _ = traj(t)
    v_left = (a[1] - a[0]) / h
    v_right = (a[3] - a[2]) / h
    return float(np.abs(a[2] - a[1]).max()), float(np.abs(v_right - v_left).max())


def test_touching_segments_join_without_steps() -> None:
    rng = np.random.default_rng(1)
    bounds = np.array([[0.0, 0.7], [0.7, 1.5], [1.5, 1.9], [1.9, 3.0]])
    curves = _curves(rng, 4)
    traj = JoinedTrajectory(curves, bounds)
    for b in bounds[1:, 0]:
        step, vstep = _jumps(traj, b)
        assert step < 1e-4  # ~ velocity * 2 EPS
        assert vstep < 1e-2
    # The same curves simply concatenated do jump: the check above can fail.
    naive = [np.abs(c1[-1] - c2[0]).max() for c1, c2 in zip(curves[:-1], curves[1:], strict=True)]
    assert min(naive) > 0.05


def test_analytic_velocity_matches_the_derivative() -> None:
    rng = np.random.default_rng(2)
    bounds = np.array([[0.0, 0.5], [0.5, 1.2]])
    traj = JoinedTrajectory(_curves(rng, 2), bounds)
    t = np.linspace(0.01, 1.19, 50)
    h = 1e-6
    _, v = traj(t)
    fd = (traj(t + h)[0] - traj(t - h)[0]) / (2 * h)
    np.testing.assert_allclose(v, fd, atol=1e-4)


def test_gap_is_bridged_smoothly_and_ends_keep_their_states() -> None:
    rng = np.random.default_rng(3)
    bounds = np.array([[0.2, 0.8], [1.1, 2.0]])
    curves = _curves(rng, 2)
    traj = JoinedTrajectory(curves, bounds)
    for b in (0.8, 1.1):
        step, vstep = _jumps(traj, b)
        assert step < 1e-4 and vstep < 1e-2
    # Outer ends are not moved: the first and last samples of the curves.
    a, _ = traj(np.array([0.2, 2.0]))
    np.testing.assert_allclose(a[0], curves[0][0], atol=1e-12)
    np.testing.assert_allclose(a[1], curves[1][-1], atol=1e-12)


def test_a_smooth_curve_cut_in_pieces_is_unchanged() -> None:
    t = np.linspace(0.0, 2.0, 2001)
    f = np.stack([np.sin(3 * t), np.cos(2 * t), t**2, np.sin(t)], axis=1)
    cuts = [0.0, 0.6, 1.3, 2.0]
    curves, bounds = [], []
    for s, e in zip(cuts[:-1], cuts[1:], strict=True):
        u = np.linspace(s, e, 100)
        curves.append(np.stack([np.sin(3 * u), np.cos(2 * u), u**2, np.sin(u)], axis=1))
        bounds.append((s, e))
    a, _ = JoinedTrajectory(curves, bounds)(t)
    np.testing.assert_allclose(a, f, atol=1e-5)


def test_bad_input_is_refused() -> None:
    c = [np.zeros((10, 4))]
    with pytest.raises(ValueError, match="one per segment"):
        JoinedTrajectory(c, [[0, 1], [1, 2]])
    with pytest.raises(ValueError, match="start < end"):
        JoinedTrajectory(c, [[1, 1]])
    with pytest.raises(ValueError, match="overlap"):
        JoinedTrajectory(c * 2, [[0, 1], [0.5, 2]])
    with pytest.raises(ValueError, match="finite"):
        JoinedTrajectory([np.full((10, 4), np.nan)], [[0, 1]])
