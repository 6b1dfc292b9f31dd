"""Segmentation (visprim.segment): velocities, ZVCs, SEG-1, SEG-2, threshold tuning, scores,
on analytic signals and synthetic minimum-jerk strokes with known boundaries."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment
from visprim import segment as S
from visprim.segment.seg2 import seg2_segment_counts, tune_seg2_threshold_concatenated

DEG = np.pi / 180
DT = 0.034


def jittered_times(duration: float, rng: np.random.Generator) -> np.ndarray:
    n = int(duration / DT) + 1
    t = np.arange(n) * DT + rng.uniform(-0.0009, 0.0009, n)
    t[0] = 0.0
    return t


def min_jerk(tau: np.ndarray) -> np.ndarray:
    tau = np.clip(tau, 0.0, 1.0)
    return 10 * tau**3 - 15 * tau**4 + 6 * tau**5


def strokes_trial(
    deltas_deg: list[list[float]],
    durations: list[float],
    *,
    rest: float = 0.5,
    pauses: list[float] | None = None,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (s), 4-DOF angles (rad) of minimum-jerk strokes, and the true boundaries (s)."""
    rng = np.random.default_rng(seed)
    pauses = pauses or [0.0] * (len(durations) - 1)
    starts, t0 = [], rest
    for i, d in enumerate(durations):
        starts.append(t0)
        t0 += d + (pauses[i] if i < len(pauses) else 0.0)
    times = jittered_times(t0 + rest, rng)
    angles = np.tile(np.array([0.3, 0.8, -0.2, 0.9]), (times.size, 1))
    for s, d, delta in zip(starts, durations, deltas_deg, strict=True):
        angles += np.outer(min_jerk((times - s) / d), np.asarray(delta) * DEG)
    bounds = [starts[0]]
    for i, (s, d) in enumerate(zip(starts, durations, strict=True)):
        end = s + d
        bounds.append(end + 0.5 * pauses[i] if i < len(pauses) else end)
    return times, angles, np.array(bounds)


# Strokes that reverse at least two DOFs at every interior boundary (what SEG-1 looks for).
ZIGZAG = [[30, 20, 0, 25], [-30, -20, 10, -25], [25, 15, -10, 30], [-25, -15, 0, -30]]
ZIGZAG_T = [0.8, 0.6, 1.0, 0.7]
TOL1 = 0.06  # s, SEG-1 timing on exact data (see test_seg1_finds_interior_reversals...)
TOL2 = 0.05  # s, SEG-2 timing on exact data: central differences spread a stop by a frame


# --- velocities -------------------------------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(lengths=st.lists(st.integers(2, 40), min_size=1, max_size=5), seed=st.integers(0, 999))
def test_velocity_concatenated_equals_gradient(lengths: list[int], seed: int) -> None:
    rng = np.random.default_rng(seed)
    times = [np.cumsum(rng.uniform(0.01, 0.05, n)) for n in lengths]
    values = [rng.normal(size=(n, 3)) for n in lengths]
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    v = S.velocity_concatenated(np.concatenate(times), np.concatenate(values), offsets)
    ref = np.concatenate([np.gradient(x, t, axis=0) for x, t in zip(values, times, strict=True)])
    np.testing.assert_allclose(v, ref, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(S.angular_velocity(times[0], values[0]), ref[: lengths[0]])


def test_velocity_errors() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        S.angular_velocity([0.0, 0.1, 0.1], np.zeros((3, 2)))
    with pytest.raises(ValueError, match="fewer than 2 frames"):
        S.velocity_concatenated(np.arange(5.0), np.zeros((5, 1)), [0, 4])


# --- zero-velocity crossings ------------------------------------------------------------------


def test_zvc_of_sines_at_analytic_times() -> None:
    rng = np.random.default_rng(7)
    t = jittered_times(4.0, rng)
    f = np.array([0.5, 0.8])
    angles = 0.5 * np.sin(2 * np.pi * f[None, :] * t[:, None])
    c = S.zvc(t, angles, min_change_deg=5.0)
    for dof in (0, 1):
        found = c.time[c.dof == dof]
        k = np.arange(20)
        expected = (k + 0.5) / (2 * f[dof])
        expected = expected[(expected > t[1]) & (expected < t[-2])]
        np.testing.assert_allclose(found, expected, atol=2e-3)
    # Sorted by DOF then time; fractional frames map back to the same seconds.
    assert np.all(np.diff(c.dof) >= 0)
    np.testing.assert_allclose(np.interp(c.frame, np.arange(t.size), t), c.time, atol=1e-12)


def test_zvc_significant_movement_threshold() -> None:
    t = np.arange(0, 3, DT)
    wiggle = 2 * DEG * np.sin(2 * np.pi * 1.5 * t)  # ±2°: below a 5° threshold
    big = 30 * DEG * np.sin(2 * np.pi * 0.5 * t)
    angles = np.stack([wiggle, big], axis=1)
    c5 = S.zvc(t, angles, min_change_deg=5.0)
    assert set(c5.dof.tolist()) == {1}
    c0 = S.zvc(t, angles, min_change_deg=0.0)
    assert np.sum(c0.dof == 0) >= 8
    with pytest.raises(ValueError, match="min_change_deg"):
        S.zvc(t, angles, min_change_deg=-1.0)


# --- SEG-1 ------------------------------------------------------------------------------------


def test_seg1_finds_interior_reversals_and_does_not_partition() -> None:
    t, a, truth = strokes_trial(ZIGZAG, ZIGZAG_T)
    segs = S.seg1(t, a)
    found = S.segment_boundaries(segs)
    # Every interior boundary (a multi-DOF reversal) is found, nothing false; the onset from
    # rest has no velocity sign change so it is never found. The final stop may be: the
    # non-uniform gradient flips sign in the flat tail of a stroke tens of ms after it stops
    # (as noise does in real data), which also delays crossings of DOFs that stop for good.
    assert S.boundary_matches(found, truth, TOL1) == (found.size, found.size, truth.size)
    assert S.boundary_matches(found, truth[1:-1], TOL1)[0] == truth.size - 2
    assert not np.any(np.abs(found - truth[0]) < 0.1)
    assert np.all(segs[:, 1] - segs[:, 0] > 0.3)
    assert np.all(segs[1:, 0] >= segs[:-1, 1])


def test_seg1_drops_segments_next_to_a_lone_zvc() -> None:
    deltas = [list(d) for d in ZIGZAG]
    deltas[2] = [0, 0, 0, 40]  # only the elbow moves: boundary 3 has one reversing DOF
    deltas[3] = [0, 0, 0, -40]
    t, a, truth = strokes_trial(deltas, ZIGZAG_T)
    segs = S.seg1(t, a)
    assert segs.shape == (1, 2)  # only stroke 2 is bounded by two multi-DOF snips
    np.testing.assert_allclose(segs[0], truth[1:3], atol=TOL1)
    ev = S.seg1_events(S.zvc_concatenated(t, a, [0]))
    assert ev.is_snip.tolist()[:3] == [True, True, False] and not np.any(ev.is_snip[3:])
    with pytest.raises(ValueError, match="window"):
        S.seg1(t, a, window=0.0)


# --- SEG-2 ------------------------------------------------------------------------------------


def test_seg2_partitions_at_true_boundaries() -> None:
    deltas = [[30, 20, 0, 25], [10, 15, 0, 30], [-40, -35, 0, -55]]  # incl. same-direction
    t, a, truth = strokes_trial(deltas, [0.8, 0.6, 1.2], pauses=[0.0, 0.2])
    trace = S.seg2_trace(t, a, threshold=0.05)
    assert trace.boundaries.size == truth.size
    # Any instant of the 0.2 s pause (true boundary in its middle) is a right boundary.
    matched = S.boundary_matches(trace.boundaries, truth, TOL2, truth_halfwidth=[0, 0, 0.1, 0])
    assert matched == (4, 4, 4)
    np.testing.assert_allclose(trace.boundaries[[0, 1, 3]], truth[[0, 1, 3]], atol=TOL2)
    segs = S.seg2(t, a, threshold=0.05)
    np.testing.assert_array_equal(segs[1:, 0], segs[:-1, 1])  # a partition
    ref = np.sum(np.gradient(a, t, axis=0) ** 2, axis=1)
    np.testing.assert_allclose(trace.z, ref, rtol=1e-9, atol=1e-20)
    assert trace.threshold == 0.05
    np.testing.assert_array_equal(t[trace.boundary_frames], trace.boundaries)


def test_seg2_ignores_jitter_at_rest() -> None:
    t, a, truth = strokes_trial(ZIGZAG[:2], ZIGZAG_T[:2], rest=1.0)
    bumps = np.zeros_like(a)
    for centre, dof in [(0.2, 0), (0.6, 2), (2.7, 3), (3.1, 1)]:  # in the rests
        bumps[:, dof] += 0.7 * DEG * np.exp(-0.5 * ((t - centre) / 0.03) ** 2)
    z = S.speed_squared(t, a + bumps)
    assert z[(t > 0.1) & (t < 0.3)].max() > 0.02  # the bumps rise above c = 0.01 ...
    segs = S.seg2(t, a + bumps, threshold=0.01)  # ... but travel ~1.4°, below 5°
    np.testing.assert_allclose(S.segment_boundaries(segs), truth, atol=TOL2)


def test_seg2_without_movement_has_no_segment() -> None:
    t = np.arange(0, 2, DT)
    a = np.zeros((t.size, 4))
    a[:, 0] = 1 * DEG * np.sin(2 * np.pi * t)  # 4° of travel in total
    assert S.seg2(t, a, threshold=1e-4).shape == (0, 2)


def test_segment_counts_and_tuning_meet_repetitions() -> None:
    """A repeated movement whose speed only dips between repetitions: the tuned c must be
    high enough to cut it into its repetitions."""
    t = np.arange(0, 4.0, DT)
    phase = 2 * np.pi * 0.75 * t  # 3 cycles
    speed_profile = 0.55 - 0.45 * np.cos(phase)  # dips to 0.1 of its peak, never to 0
    a = np.zeros((t.size, 4))
    a[:, 2] = np.cumsum(speed_profile) * DT * np.sign(np.sin(phase / 2) + 1e-9)
    a[:, 3] = 0.5 * np.cumsum(speed_profile) * DT
    z = S.speed_squared(t, a)
    off = np.zeros(1, dtype=np.int64)
    c = tune_seg2_threshold_concatenated(t, z, off, 3)
    assert S.seg2(t, a, threshold=c).shape[0] >= 3
    assert S.seg2(t, a, repetitions=3).shape[0] >= 3
    grid = np.geomspace(z.max() * 1e-4, z.max(), 30)
    counts = seg2_segment_counts(t, z, off, grid)
    brute = [S.seg2(t, a, threshold=g).shape[0] for g in grid]
    np.testing.assert_array_equal(counts[0], brute)


# --- corpus ---------------------------------------------------------------------------------


def synthetic_corpus(n: int) -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    rng = np.random.default_rng(11)
    times, angles, truths = [], [], []
    for k in range(n):
        m = int(rng.integers(2, 5))
        deltas = [list(rng.choice([-1, 1]) * rng.uniform(15, 40, 4)) for _ in range(m)]
        t, a, b = strokes_trial(deltas, list(rng.uniform(0.4, 1.2, m)), seed=k)
        times.append(t)
        angles.append(a)
        truths.append(b)
    return times, angles, truths


def test_segment_corpus_matches_per_trial_and_frames() -> None:
    times, angles, truths = synthetic_corpus(12)
    for method in ("seg1", "seg2"):
        res = S.segment_corpus(times, angles, method, threshold=0.05)
        assert res.n_trials == 12 and res.method == method
        per = res.per_trial()
        for t, a, segs in zip(times, angles, per, strict=True):
            ref = S.seg1(t, a) if method == "seg1" else S.seg2(t, a, threshold=0.05)
            np.testing.assert_allclose(segs, ref, atol=1e-12)
        # Fractional frames and seconds agree; global frames index the concatenation.
        t_all = np.concatenate(times)
        g0, g1 = res.global_frames()
        np.testing.assert_allclose(np.interp(g0, np.arange(t_all.size), t_all), res.start)
        np.testing.assert_allclose(np.interp(g1, np.arange(t_all.size), t_all), res.end)
        assert np.all(res.durations > 0)
    res = S.segment_corpus(times, angles, "seg2")
    assert res.threshold is not None and res.z is not None and res.z.shape == (res.n_frames,)
    assert S.corpus_boundary_scores(res.per_trial(), truths).f1 > 0.99


def test_segment_corpus_errors() -> None:
    times, angles, _ = synthetic_corpus(2)
    with pytest.raises(ValueError, match="method"):
        S.segment_corpus(times, angles, "seg3")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="equal length"):
        S.segment_corpus(times, angles[:1], "seg2")
    with pytest.raises(ValueError, match="threshold"):
        S.segment_corpus(times, angles, "seg2", threshold=-1.0)
    with pytest.raises(ValueError, match="repetitions"):
        S.segment_corpus(times, angles, "seg2", repetitions=[1, 0])


# --- scores ---------------------------------------------------------------------------------


def test_boundary_scores_known_cases() -> None:
    truth = np.array([0.5, 1.5, 2.5, 3.5])
    segs = np.array([[0.45, 1.58], [1.58, 2.75], [2.75, 3.45]])  # 2.75 is 250 ms off
    p, r, f = S.boundary_scores(segs, truth)
    assert (p, r) == (0.75, 0.75) and f == pytest.approx(0.75)
    # One to one: two found boundaries near one true boundary count once.
    assert S.boundary_matches([1.0, 1.05], [1.02]) == (1, 2, 1)
    assert S.boundary_scores([], truth) == (1.0, 0.0, 0.0)
    assert S.boundary_scores([], []) == (1.0, 1.0, 1.0)
    # Widened windows (pauses): 2.75 lies within 0.2 + 0.1 of 2.5.
    wide = S.boundary_scores(segs, truth, truth_halfwidth=[0, 0, 0.2, 0])
    assert wide.precision == 1.0
    with pytest.raises(ValueError, match="tolerance"):
        S.boundary_scores(segs, truth, tolerance=-1)
    with pytest.raises(ValueError, match="truth_halfwidth"):
        S.boundary_scores(segs, truth, truth_halfwidth=[0.1])
    total = S.corpus_boundary_scores([segs, [[0.0, 1.0]]], [truth, [0.0, 1.0]])
    assert total.precision == pytest.approx(5 / 6) and total.recall == pytest.approx(5 / 6)


@settings(max_examples=300, deadline=None)
@given(
    found=st.lists(st.floats(0, 5), max_size=8),
    truth=st.lists(st.floats(0, 5), max_size=8),
    halves=st.lists(st.floats(0, 0.3), min_size=8, max_size=8),
)
def test_matching_is_maximum(found: list[float], truth: list[float], halves: list[float]) -> None:
    f = S.segment_boundaries(np.array(found))
    t = np.array(truth)
    h = np.array(halves[: t.size])
    # The windows as documented, [t - h - tol, t + h + tol], in the same float arithmetic
    # (|f - t| <= h + tol rounds differently at the edges, e.g. f = 1.1, t = 1.0, h = 0).
    lo, hi = (t - h - 0.1)[None, :], (t + h + 0.1)[None, :]
    ok = (f[:, None] >= lo) & (f[:, None] <= hi)
    if ok.size:
        rows, cols = linear_sum_assignment(-ok.astype(float))
        best = int(ok[rows, cols].sum())
    else:
        best = 0
    assert S.boundary_matches(f, t, 0.1, truth_halfwidth=h)[0] == best


def test_adaptive_seg1_window_is_half_the_median_gap_per_trial() -> None:
    """Known answer: a trial's window is min(window, median / 2) of the gaps between
    consecutive crossings of one DOF; a trial without such gaps keeps the window."""
    from visprim.segment.seg1 import _trial_windows

    # Trial 0: DOF 0 at 0, 0.2, 0.6 (gaps 0.2, 0.4), DOF 1 at 1.0, 1.1 (gap 0.1): median 0.2,
    # window 0.1. Trial 2: DOF 3 at 0, 0.5, 0.8 (gaps 0.5, 0.3; an even count, so the mean of
    # the middle two, 0.4): window 0.2. Trial 1: one crossing per DOF, no gap: the window
    # itself (0.3). Crossings given out of order.
    trial = np.array([2, 0, 0, 1, 0, 2, 0, 0, 1, 2])
    dof = np.array([3, 0, 1, 0, 0, 3, 0, 1, 2, 3])
    time = np.array([0.0, 0.2, 1.1, 5.0, 0.0, 0.5, 0.6, 1.0, 5.5, 0.8])
    want = np.array([0.2, 0.1, 0.1, 0.3, 0.1, 0.2, 0.1, 0.1, 0.3, 0.2])
    np.testing.assert_allclose(_trial_windows(trial, dof, time, 0.3), want, rtol=1e-12)
