"""End-to-end pipeline: visprim vs the same pipeline in batched scipy / numpy / scikit-learn.

Workload: 10,000 generated trials (``--quick``: 600) → zero-phase Butterworth low-pass
(order 10, cutoff 0.25) → zero-velocity crossings (5° significant-movement threshold) and
SEG-1 → every segment resampled to 100 samples per angle (400-D) → PCA keeping 30
eigenvectors → k-means with 30 clusters (k-means++ seeding, 4 restarts, Lloyd, float64).

Both pipelines start from the same inverse-kinematics angles (computed once, untimed). They
differ where visprim uses its Rust kernels:

============  =====================================  =========================================
stage         visprim                                reference
============  =====================================  =========================================
filter        ``sosfiltfilt_ragged`` (one call)      ``scipy.signal.sosfiltfilt`` on 3-D stacks
                                                     of equal-length trials (batched by length)
velocity      ``gradient_ragged``                    ``np.gradient``'s uneven-step formula on
                                                     the whole corpus (one numpy pass)
ZVC           ``zero_velocity_crossings_ragged``,    numpy: sign changes on the whole corpus,
              ``frames_to_times``                    then the significant-movement walk batched
                                                     over all (trial, angle) series
SEG-1         ``seg1_events``, ``times_to_frames``   numpy: lexsort by (trial, time), events by
                                                     cumsum/bincount, ``searchsorted`` frames
resample      ``resample_segments``                  ``np.interp`` per angle on the corpus
PCA           ``covariance`` + ``eigh``              ``sklearn PCA(svd_solver="covariance_eigh")``
k-means       ``kmeans``                             ``sklearn KMeans(algorithm="lloyd")``
============  =====================================  =========================================

Threads: both sides use every core by default (rayon; OpenBLAS / OpenMP for scipy and
scikit-learn). On a machine shared with other work the references' spinning thread pools
suffer most; ``RAYON_NUM_THREADS=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1`` gives a
single-thread comparison that is far less sensitive to the load.

The run checks that both pipelines find the same segments, nearly equal vectors and
eigenvalues, and k-means inertias within 2 %, then records the median of 5 runs of each
(run alternately, so both see the same load on a shared machine).
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np
import scipy.signal
from _harness import Table
from sklearn.cluster import KMeans
from sklearn.decomposition import PCA
from visprim import kernels
from visprim.datasets import imitation_experiment
from visprim.filtering import lowpass_concatenated
from visprim.ik import arm_angles_corpus
from visprim.pca import fit_pca
from visprim.segment import segment_concatenated
from visprim.segment.zvc import CorpusCrossings

ORDER, CUTOFF, MIN_CHANGE_DEG, N_SAMPLES, F, K, N_INIT, SEED = 10, 0.25, 5.0, 100, 30, 30, 4, 0
#: The paper's SEG-1 (one 300 ms window for every trial), which the numpy reference implements;
#: visprim's default also shortens the window of fast cyclic trials (``seg1_adaptive``).
SEG1_ADAPTIVE = False


def corpus(n_trials: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times (F,), IK angles (F, 4), offsets) of ``n_trials`` generated trials."""
    n_stimuli = 200 if n_trials >= 2000 else 20
    n_subjects = int(np.ceil(n_trials / n_stimuli))
    trials = imitation_experiment(n_subjects, n_stimuli, seed=0)[:n_trials]
    angles = np.concatenate(arm_angles_corpus(trials))
    times = np.concatenate([t.times for t in trials])
    lengths = np.array([t.n_frames for t in trials])
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return times, angles, offsets


# ---------------------------------------------------------------------------- visprim


def visprim_pipeline(times, angles, offsets):
    filtered = lowpass_concatenated(angles, offsets, order=ORDER, cutoff=CUTOFF)
    seg = segment_concatenated(
        times,
        filtered,
        offsets,
        method="seg1",
        tuning="repetitions",
        min_change_deg=MIN_CHANGE_DEG,
        seg1_adaptive=SEG1_ADAPTIVE,
    )
    starts, ends = seg.global_frames()
    vectors = kernels.resample_segments(filtered, starts, ends, n=N_SAMPLES)
    basis = fit_pca(vectors)
    proj = basis.project(vectors, F)
    km = kernels.kmeans(proj, K, n_init=N_INIT, max_iter=300, tol=1e-4, seed=SEED)
    return {
        "filtered": filtered,
        "n_segments": seg.n_segments,
        "vectors": vectors,
        "eigenvalues": basis.eigenvalues[:F],
        "inertia": float(km.inertia),
    }


# ---------------------------------------------------------------------------- reference


def ref_filter(angles, offsets):
    """scipy sosfiltfilt, batched over trials of equal length (3-D stacks, axis=1)."""
    sos = scipy.signal.butter(ORDER, CUTOFF, output="sos")
    lengths = np.diff(np.append(offsets, angles.shape[0]))
    out = np.empty_like(angles)
    for n in np.unique(lengths):
        idx = np.flatnonzero(lengths == n)
        rows = offsets[idx][:, None] + np.arange(n)[None, :]
        out[rows] = scipy.signal.sosfiltfilt(sos, angles[rows], axis=1)
    return out


def ref_velocity(times, x, offsets):
    """``np.gradient(x_i, times_i, axis=0)`` of every trial in one numpy pass over the corpus
    (the uneven-step weights of ``np.gradient``; one-sided differences at each trial's ends)."""
    n = x.shape[0]
    ends = np.append(offsets[1:], n) - 1  # last frame of each trial
    h = np.diff(times)  # across trial joins meaningless but unused
    v = np.empty_like(x)
    h0, h1 = h[:-1], h[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        w_prev = (-h1 / (h0 * (h0 + h1)))[:, None]
        w_here = ((h1 - h0) / (h0 * h1))[:, None]
        w_next = (h0 / (h1 * (h0 + h1)))[:, None]
    np.multiply(w_prev, x[:-2], out=v[1:-1])
    v[1:-1] += w_here * x[1:-1]
    v[1:-1] += w_next * x[2:]
    v[offsets] = (x[offsets + 1] - x[offsets]) / h[offsets, None]
    v[ends] = (x[ends] - x[ends - 1]) / h[ends - 1, None]
    return v


def ref_crossings(times, angles, offsets, min_change_deg):
    """ZVCs with the significant-movement rule, in numpy (same definition as the kernel)."""
    vel = ref_velocity(times, angles, offsets)
    n, c = vel.shape
    trial_of = np.repeat(np.arange(offsets.size), np.diff(np.append(offsets, n)))
    same = trial_of[1:] == trial_of[:-1]
    v0, v1 = vel[:-1], vel[1:]
    hit = (((v0 > 0) & (v1 < 0)) | ((v0 < 0) & (v1 > 0))) & same[:, None]
    # Exact zeros (a crossing through a run of zeros, placed mid-run by the kernel) are not
    # handled here: low-passed measured angles have none (check_same would notice).
    ch, fi = np.nonzero(hit.T)
    frac = vel[fi, ch] / (vel[fi, ch] - vel[fi + 1, ch])
    gframe = fi + frac
    pos = angles[fi, ch] + frac * (angles[fi + 1, ch] - angles[fi, ch])
    tr = trial_of[fi]
    # Walk each (trial, channel) series in time order, batched over all series at once.
    order = np.lexsort((gframe, ch, tr))
    tr, ch, gframe, pos = tr[order], ch[order], gframe[order], pos[order]
    series = tr * c + ch
    starts = np.flatnonzero(np.r_[True, series[1:] != series[:-1]])
    counts = np.diff(np.r_[starts, series.size])
    rank = np.arange(series.size) - np.repeat(starts, counts)
    grid = np.full((starts.size, counts.max()), np.nan)
    grid[np.repeat(np.arange(starts.size), counts), rank] = pos
    first_tr, first_ch = tr[starts], ch[starts]
    last = angles[offsets[first_tr], first_ch]
    keep_grid = np.zeros(grid.shape, dtype=bool)
    thr = np.deg2rad(min_change_deg)
    for j in range(grid.shape[1]):
        col = grid[:, j]
        keep = np.abs(col - last) > thr  # NaN (no crossing) compares False
        keep_grid[:, j] = keep
        last = np.where(keep, col, last)
    keep = keep_grid[np.repeat(np.arange(starts.size), counts), rank]
    tr, ch, gframe = tr[keep], ch[keep], gframe[keep]
    frame = gframe - offsets[tr]
    return CorpusCrossings(tr, ch, frame, ref_frames_to_times(times, offsets, tr, frame))


def ref_frames_to_times(times, offsets, trial, frame):
    """Seconds of fractional frames (relative to each trial's start), in numpy."""
    last = np.append(offsets[1:], times.shape[0]) - 1
    g = offsets[trial] + frame
    i = np.maximum(np.minimum(np.floor(g).astype(np.int64), last[trial] - 1), offsets[trial])
    return times[i] + (g - i) * (times[i + 1] - times[i])


def ref_seg1(crossings, window=0.3, min_dofs=2):
    """SEG-1 segments ``(trial, start s, end s)`` from the ZVCs, in numpy: crossings sorted by
    (trial, time), events by single linkage (gap < window), median times, distinct DOFs."""
    order = np.lexsort((crossings.time, crossings.trial))
    trial, time, dof = crossings.trial[order], crossings.time[order], crossings.dof[order]
    new = np.ones(trial.size, dtype=bool)
    new[1:] = (trial[1:] != trial[:-1]) | (np.diff(time) >= window)
    event = np.cumsum(new) - 1
    m = int(event[-1]) + 1
    counts = np.bincount(event, minlength=m)
    first = np.flatnonzero(new)
    median_time = 0.5 * (time[first + (counts - 1) // 2] + time[first + counts // 2])
    n_dof = int(dof.max()) + 1
    pairs = np.unique(event * n_dof + dof)
    snip = np.bincount(pairs // n_dof, minlength=m) >= min_dofs
    ev_trial = trial[new]
    keep = (ev_trial[1:] == ev_trial[:-1]) & snip[1:] & snip[:-1]
    return ev_trial[:-1][keep], median_time[:-1][keep], median_time[1:][keep]


def ref_times_to_frames(times, offsets, trial, t):
    """Fractional frames (relative to each trial's start) of times, by ``np.searchsorted`` on
    the corpus's timestamps made increasing across trials."""
    n = times.shape[0]
    last = np.append(offsets[1:], n) - 1
    trial_of = np.repeat(np.arange(offsets.size), last - offsets + 1)
    local = times - times[offsets][trial_of]
    span = float(local.max()) + 1.0
    key = local + trial_of * span  # increasing over the whole corpus
    q = np.clip(t - times[offsets][trial], 0.0, local[last][trial]) + trial * span
    i = np.clip(np.searchsorted(key, q, side="right") - 1, offsets[trial], last[trial] - 1)
    frac = (q - key[i]) / (key[i + 1] - key[i])
    return (i - offsets[trial]) + np.clip(frac, 0.0, 1.0)


def ref_resample(values, starts, ends, n):
    """np.interp per angle on the whole corpus (channel-major output)."""
    grid = starts[:, None] + (ends - starts)[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    frames = np.arange(values.shape[0], dtype=np.float64)
    return np.concatenate(
        [np.interp(grid, frames, values[:, c]) for c in range(values.shape[1])], axis=1
    )


def reference_pipeline(times, angles, offsets):
    filtered = ref_filter(angles, offsets)
    crossings = ref_crossings(times, filtered, offsets, MIN_CHANGE_DEG)
    trial, start, end = ref_seg1(crossings)
    base = offsets[trial].astype(np.float64)
    starts = base + ref_times_to_frames(times, offsets, trial, start)
    ends = base + ref_times_to_frames(times, offsets, trial, end)
    vectors = ref_resample(filtered, starts, ends, N_SAMPLES)
    pca = PCA(n_components=F, svd_solver="covariance_eigh")
    proj = pca.fit_transform(vectors)
    km = KMeans(K, n_init=N_INIT, max_iter=300, tol=1e-4, random_state=SEED, algorithm="lloyd")
    km.fit(proj)
    n = vectors.shape[0]
    return {
        "filtered": filtered,
        "n_segments": int(trial.size),
        "vectors": vectors,
        "eigenvalues": pca.explained_variance_ * (n - 1) / n,
        "inertia": float(km.inertia_),
    }


# ---------------------------------------------------------------------------- run


def interleaved_medians(a, b, repeat: int) -> tuple[float, float]:
    """Median wall times of ``a()`` and ``b()`` run alternately (a, b, a, b, ...), so that
    both see the same machine load (this machine is shared)."""
    ta, tb = [], []
    for _ in range(repeat):
        for fn, out in ((a, ta), (b, tb)):
            t0 = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t0)
    return statistics.median(ta), statistics.median(tb)


def check_same(ours: dict, ref: dict) -> str:
    """Both pipelines computed the same thing; returns a note for the table."""
    np.testing.assert_allclose(ours["filtered"], ref["filtered"], rtol=0, atol=1e-9)
    if ours["n_segments"] != ref["n_segments"]:
        raise AssertionError(f"segments differ: {ours['n_segments']} vs {ref['n_segments']}")
    np.testing.assert_allclose(ours["vectors"], ref["vectors"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(ours["eigenvalues"], ref["eigenvalues"], rtol=1e-7)
    rel = ours["inertia"] / ref["inertia"] - 1.0
    if rel > 0.02:
        raise AssertionError(f"visprim k-means inertia {rel:+.2%} above scikit-learn's")
    return f"{ours['n_segments']} segments; inertia visprim/sklearn - 1 = {rel:+.2%}"


def run(table: Table, quick: bool = False) -> None:
    n_trials = 600 if quick else 10_000
    env = ", ".join(
        f"{v}={os.environ.get(v, 'unset')}"
        for v in ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")
    )
    print(f"pipeline: thread settings {env}", flush=True)
    print(f"pipeline: generating {n_trials} trials (untimed) ...", flush=True)
    t0 = time.perf_counter()
    times, angles, offsets = corpus(n_trials)
    print(f"  {angles.shape[0]} frames x 4 angles in {time.perf_counter() - t0:.1f} s", flush=True)
    ours = visprim_pipeline(times, angles, offsets)
    ref = reference_pipeline(times, angles, offsets)
    note = check_same(ours, ref)
    t_ours, t_ref = interleaved_medians(
        lambda: visprim_pipeline(times, angles, offsets),
        lambda: reference_pipeline(times, angles, offsets),
        repeat=3 if quick else 5,
    )
    work = f"pipeline {n_trials} trials"
    per = f"{ours['n_segments']} segments"
    table.add(work, "visprim (Rust kernels)", t_ours, per, note)
    table.add(work, "scipy/numpy/sklearn batched", t_ref, per, "")
    table.ratio(work, "scipy/numpy/sklearn batched", t_ref, t_ours)
    for stage, impl, seconds in stage_timings(times, angles, offsets):
        table.add(f"  {work}: {stage} (one run)", impl, seconds, "", "")


def stage_timings(times, angles, offsets) -> list[tuple[str, str, float]]:
    """One timing of each stage of both pipelines (to see where the time goes):
    ``(stage, implementation, seconds)``."""
    out: list[tuple[str, str, float]] = []

    def timed(label, impl, fn):
        t0 = time.perf_counter()
        r = fn()
        out.append((label, impl, time.perf_counter() - t0))
        return r

    f1 = timed("filter", "visprim", lambda: lowpass_concatenated(angles, offsets))
    f2 = timed("filter", "scipy", lambda: ref_filter(angles, offsets))
    seg = timed(
        "ZVC+SEG-1",
        "visprim",
        lambda: segment_concatenated(
            times,
            f1,
            offsets,
            method="seg1",
            tuning="repetitions",
            min_change_deg=MIN_CHANGE_DEG,
            seg1_adaptive=SEG1_ADAPTIVE,
        ),
    )
    timed(
        "ZVC+SEG-1",
        "numpy",
        lambda: ref_seg1(ref_crossings(times, f2, offsets, MIN_CHANGE_DEG)),
    )
    s, e = seg.global_frames()
    v = timed("resample", "visprim", lambda: kernels.resample_segments(f1, s, e, n=N_SAMPLES))
    timed("resample", "numpy", lambda: ref_resample(f2, s, e, N_SAMPLES))
    b = timed("PCA", "visprim", lambda: fit_pca(v))
    timed("PCA", "sklearn", lambda: PCA(F, svd_solver="covariance_eigh").fit_transform(v))
    p = b.project(v, F)
    timed("k-means", "visprim", lambda: kernels.kmeans(p, K, n_init=N_INIT, seed=SEED))
    timed(
        "k-means",
        "sklearn",
        lambda: KMeans(K, n_init=N_INIT, random_state=SEED, algorithm="lloyd").fit(p),
    )
    return out


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    tab = Table()
    run(tab, quick=args.quick)
    tab.print()
