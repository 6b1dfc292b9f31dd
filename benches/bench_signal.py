"""Signal kernels: visprim vs scipy / numpy on the issue's corpus, same data, one run.

Workload: 10,000 trials x 4 channels x 150 frames of smooth arm-like angles (three slow
sinusoids per channel plus noise), seeded. Sections:

* filtering (Butterworth order 10, cutoff 0.25): ``visprim.kernels.sosfiltfilt_ragged`` on
  the concatenated ``(frames, 4)`` corpus and ``sosfiltfilt`` on ``(signals, 150)`` rows,
  against ``scipy.signal.sosfiltfilt`` batched (``axis=0`` on a ``(150, 10000, 4)`` stack) and
  in a per-trial loop;
* ZVC detection + resampling: crossings of the filtered corpus's velocity, segments between
  consecutive crossings of channel 0 in each trial, each resampled to 100 points per channel,
  against the same computation in whole-corpus numpy and with ``np.interp`` per segment.

visprim uses all cores (rayon); scipy and numpy run these on one. Every comparison first
checks that both sides give the same numbers. Run via ``benches/compare.py`` (``make bench``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.signal as ss
from _harness import Table, median_time
from visprim import kernels as K

CHANNELS = 4
FRAMES = 150
ORDER, CUTOFF = 10, 0.25
N_POINTS = 100


def make_corpus(trials: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Angles ``(trials * FRAMES, CHANNELS)`` in radians and the trial offsets (int64)."""
    rng = np.random.default_rng(seed)
    s = np.arange(FRAMES) / FRAMES
    amp = rng.uniform(0.0, 1.0, (trials, 1, CHANNELS, 3))
    freq = rng.uniform(0.3, 1.8, (trials, 1, CHANNELS, 3))
    phase = rng.uniform(0.0, 2 * np.pi, (trials, 1, CHANNELS, 3))
    x = (amp * np.sin(2 * np.pi * freq * s[None, :, None, None] + phase)).sum(axis=-1)
    x += rng.uniform(-0.005, 0.005, x.shape)
    values = np.ascontiguousarray(x.reshape(trials * FRAMES, CHANNELS))
    offsets = np.arange(trials, dtype=np.int64) * FRAMES
    return values, offsets


def _max_diff(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def bench_filter(table: Table, values: np.ndarray, offsets: np.ndarray, loop_trials: int) -> None:
    trials = len(offsets)
    n = values.size
    sos = K.butter_sos(ORDER, CUTOFF)
    np.testing.assert_allclose(sos, ss.butter(ORDER, CUTOFF, output="sos"), rtol=0, atol=1e-10)
    work = f"filter {trials}x{CHANNELS}x{FRAMES} (order {ORDER})"
    stack = np.ascontiguousarray(values.reshape(trials, FRAMES, CHANNELS).transpose(1, 0, 2))
    rows = np.ascontiguousarray(values.reshape(trials, FRAMES, CHANNELS).transpose(0, 2, 1))
    rows = rows.reshape(trials * CHANNELS, FRAMES)

    ours = K.sosfiltfilt_ragged(sos, values, offsets)
    ref = ss.sosfiltfilt(sos, stack, axis=0)
    diff = _max_diff(ours.reshape(trials, FRAMES, CHANNELS).transpose(1, 0, 2), ref)
    assert diff < 1e-10, diff
    diff_rows = _max_diff(
        K.sosfiltfilt(sos, rows).reshape(trials, CHANNELS, FRAMES).transpose(2, 0, 1), ref
    )
    assert diff_rows < 1e-10, diff_rows

    def per_ns(t: float) -> str:
        return f"{t / n * 1e9:.2f} ns/sample-channel"

    t_ragged = median_time(lambda: K.sosfiltfilt_ragged(sos, values, offsets), repeat=7)
    note = f"max diff {diff:.1e}"
    table.add(work, "visprim sosfiltfilt_ragged", t_ragged, per_ns(t_ragged), note)
    t_rows = median_time(lambda: K.sosfiltfilt(sos, rows), repeat=7)
    table.add(work, "visprim sosfiltfilt (signals, 150)", t_rows, per_ns(t_rows))
    t_batch = median_time(lambda: ss.sosfiltfilt(sos, stack, axis=0), repeat=3)
    table.add(work, "scipy sosfiltfilt batched axis=0", t_batch, per_ns(t_batch))

    sub = values[: loop_trials * FRAMES]
    t_loop = median_time(
        lambda: [
            ss.sosfiltfilt(sos, sub[i * FRAMES : (i + 1) * FRAMES], axis=0)
            for i in range(loop_trials)
        ],
        repeat=3,
    )
    t_loop *= trials / loop_trials
    note = f"timed on {loop_trials} trials, scaled" if loop_trials < trials else ""
    table.add(work, "scipy sosfiltfilt per-trial loop", t_loop, per_ns(t_loop), note)
    table.ratio(work, "scipy batched", t_batch, t_ragged)
    table.ratio(work, "scipy per-trial loop", t_loop, t_ragged)


def velocity_of(values: np.ndarray, trials: int) -> np.ndarray:
    """Per-trial central differences (np.gradient along frames), radians per frame."""
    v = np.gradient(values.reshape(trials, FRAMES, CHANNELS), axis=1)
    return np.ascontiguousarray(v.reshape(trials * FRAMES, CHANNELS))


def segments_from(
    trial: np.ndarray, channel: np.ndarray, frame: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Global start/end frames between consecutive channel-0 crossings of each trial."""
    keep = channel == 0
    t, f = trial[keep], frame[keep] + offsets[trial[keep]]
    same = t[1:] == t[:-1]
    return f[:-1][same], f[1:][same]


def visprim_zvc_resample(
    vel: np.ndarray, values: np.ndarray, offsets: np.ndarray, min_change: float
) -> np.ndarray:
    tr, ch, fr = K.zero_velocity_crossings_ragged(vel, offsets, min_change, positions=values)
    starts, ends = segments_from(tr, ch, fr, offsets)
    return K.resample_segments(values, starts, ends, N_POINTS)


def numpy_crossings(vel: np.ndarray, trials: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Whole-corpus numpy: sign changes between frames i and i + 1 of a trial, at the linear
    root (no threshold; the data has no exact zeros). Sorted by trial, channel, frame."""
    v = vel.reshape(trials, FRAMES, CHANNELS)
    a, b = v[:, :-1], v[:, 1:]
    tr, i, ch = np.nonzero(a * b < 0)
    frac = a[tr, i, ch] / (a[tr, i, ch] - b[tr, i, ch])
    order = np.lexsort((i, ch, tr))
    return tr[order], ch[order], (i + frac)[order]


def numpy_resample(values: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Whole-corpus numpy: all segments at once, np.interp's formula, channel-major rows."""
    step = (ends - starts) / (N_POINTS - 1)
    x = np.arange(N_POINTS) * step[:, None] + starts[:, None]
    x[:, -1] = ends
    j = np.minimum(x.astype(np.int64), len(values) - 2)
    frac = (x - j)[..., None]
    lo, hi = values[j], values[j + 1]
    out = (hi - lo) * frac + lo
    out = np.where(frac == 1.0, hi, out)
    return out.transpose(0, 2, 1).reshape(len(starts), CHANNELS * N_POINTS)


def numpy_zvc_resample(vel: np.ndarray, values: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    tr, ch, fr = numpy_crossings(vel, len(offsets))
    starts, ends = segments_from(tr, ch, fr, offsets)
    return numpy_resample(values, starts, ends)


def interp_zvc_resample(
    vel: np.ndarray, values: np.ndarray, offsets: np.ndarray, max_segments: int
) -> tuple[np.ndarray, int]:
    """Crossings in numpy, then np.interp per segment and channel on the segment's window."""
    tr, ch, fr = numpy_crossings(vel, len(offsets))
    starts, ends = segments_from(tr, ch, fr, offsets)
    starts, ends = starts[:max_segments], ends[:max_segments]
    out = np.empty((len(starts), CHANNELS * N_POINTS))
    for s, (a, b) in enumerate(zip(starts, ends, strict=True)):
        lo, hi = int(a), min(int(np.ceil(b)), len(values) - 1)
        grid = np.arange(lo, hi + 1)
        x = np.linspace(a, b, N_POINTS)
        for c in range(CHANNELS):
            out[s, c * N_POINTS : (c + 1) * N_POINTS] = np.interp(x, grid, values[lo : hi + 1, c])
    return out, len(starts)


def bench_zvc_resample(
    table: Table, values: np.ndarray, offsets: np.ndarray, interp_segments: int
) -> None:
    trials = len(offsets)
    sos = K.butter_sos(ORDER, CUTOFF)
    angles = K.sosfiltfilt_ragged(sos, values, offsets)
    vel = velocity_of(angles, trials)

    ours = visprim_zvc_resample(vel, angles, offsets, 0.0)
    ref = numpy_zvc_resample(vel, angles, offsets)
    assert ours.shape == ref.shape, (ours.shape, ref.shape)
    diff = _max_diff(ours, ref)
    assert diff < 1e-9, diff
    some, count = interp_zvc_resample(vel, angles, offsets, 50)
    assert _max_diff(ours[:count], some) < 1e-9
    n_out = ours.size
    work = f"ZVC + resample {trials}x{CHANNELS}x{FRAMES} ({len(ours)} segments)"

    def per_ns(t: float, outputs: int = n_out) -> str:
        return f"{t / outputs * 1e9:.2f} ns/output"

    t_ours = median_time(lambda: visprim_zvc_resample(vel, angles, offsets, 0.0), repeat=7)
    table.add(work, "visprim zvc_ragged + resample", t_ours, per_ns(t_ours), f"max diff {diff:.1e}")
    t_thr = median_time(lambda: visprim_zvc_resample(vel, angles, offsets, 0.05), repeat=7)
    n_thr = visprim_zvc_resample(vel, angles, offsets, 0.05).size
    table.add(
        work,
        "visprim, min_change 0.05 rad",
        t_thr,
        per_ns(t_thr, n_thr),
        f"{n_thr // (CHANNELS * N_POINTS)} segments",
    )
    t_np = median_time(lambda: numpy_zvc_resample(vel, angles, offsets), repeat=5)
    table.add(work, "numpy whole-corpus", t_np, per_ns(t_np))
    t_interp = median_time(
        lambda: interp_zvc_resample(vel, angles, offsets, interp_segments), repeat=3
    )
    n_seg = min(interp_segments, len(ours))
    t_interp *= len(ours) / n_seg
    note = f"timed on {n_seg} segments, scaled" if n_seg < len(ours) else ""
    table.add(work, "numpy + np.interp per segment", t_interp, per_ns(t_interp), note)
    table.ratio(work, "numpy whole-corpus", t_np, t_ours)
    table.ratio(work, "np.interp per segment", t_interp, t_ours)

    # Each kernel alone.
    tr, ch, fr = K.zero_velocity_crossings_ragged(vel, offsets, 0.0, positions=angles)
    starts, ends = segments_from(tr, ch, fr, offsets)
    t_z = median_time(
        lambda: K.zero_velocity_crossings_ragged(vel, offsets, 0.0, positions=angles), repeat=7
    )
    table.add(work, "  of which zero_velocity_crossings_ragged", t_z, per_ns(t_z))
    t_r = median_time(lambda: K.resample_segments(angles, starts, ends, N_POINTS), repeat=7)
    table.add(work, "  of which resample_segments", t_r, per_ns(t_r))


def run(table: Table, quick: bool = False) -> None:
    """Add the signal rows to ``table``; ``quick`` uses 500 trials."""
    trials = 500 if quick else 10_000
    values, offsets = make_corpus(trials)
    print(f"signal kernels: {trials} trials x {CHANNELS} channels x {FRAMES} frames")
    sections: list[Callable[[], None]] = [
        lambda: bench_filter(table, values, offsets, loop_trials=100 if quick else 2_000),
        lambda: bench_zvc_resample(table, values, offsets, 200 if quick else 3_000),
    ]
    for section in sections:
        section()
