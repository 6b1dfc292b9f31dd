"""Child process of ``test_kernels_simd_levels.py``: every kernel that chooses an instruction
set, on fixed data, at the level ``VISPRIM_SIMD`` gives this process.

Usage: ``python _simd_child.py OUT.npz``. Writes the outputs, ``instruction_set()`` and
``instruction_sets()``; a ValueError from the kernels (an invalid ``VISPRIM_SIMD``) is printed
on stderr as ``ValueError: <message>`` with exit status 3.
"""

from __future__ import annotations

import json
import sys

import numpy as np
from visprim import kernels as K


def outputs() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(2024)
    out: dict[str, np.ndarray] = {}

    # Filter: 37 rows (full blocks of 32, 16 and 8 lanes, and remainders), order 7 (a single
    # first-order section) and 10; a ragged corpus of 7 channels and trials of 4 lengths.
    x = rng.standard_normal((37, 400)).cumsum(axis=1)
    out["filter_x"] = x
    for order in (7, 10):
        out[f"filter_rows_{order}"] = K.sosfiltfilt(K.butter_sos(order, 0.15), x)
    offsets = np.array([0, 300, 520, 820, 1100, 1400])
    ragged = rng.standard_normal((1650, 7)).cumsum(axis=0)
    out["filter_ragged_x"] = ragged
    out["filter_ragged"] = K.sosfiltfilt_ragged(K.butter_sos(4, 0.2), ragged, offsets)

    # Resampling: 1 to 9 channels (4 has a kernel of its own), segments ending on the last
    # frame, odd and even n.
    for channels in range(1, 10):
        v = rng.standard_normal((211, channels))
        starts = np.concatenate([[0.0, 13.25], rng.uniform(0, 150, 60)])
        ends = np.concatenate([[210.0, 210.0], starts[2:] + rng.uniform(1, 60, 60)])
        for n in (2, 33, 100):
            out[f"resample_{channels}_{n}"] = K.resample_segments(v, starts, ends, n)

    # Covariance: rows of 9 values (faer at every level) and of 40 (the packed kernel),
    # far from the origin; the accumulator in three blocks.
    for d in (9, 40):
        data = rng.standard_normal((6000, d)) @ rng.standard_normal((d, d)) + 50.0
        mean, cov = K.covariance(data)
        out[f"cov_mean_{d}"], out[f"cov_{d}"] = mean, cov
        acc = K.CovarianceAccumulator()
        for block in np.array_split(data, 3):
            acc.update(block)
        out[f"acc_mean_{d}"], out[f"acc_cov_{d}"] = acc.mean, acc.covariance()

    # k-means: few centres (direct scan; Elkan's bounds with AVX-512) and many (restricted
    # scan), the prediction, and the seeding alone.
    blobs = (
        rng.standard_normal((4000, 12))
        + 4.0 * rng.standard_normal((25, 12))[rng.integers(0, 25, 4000)]
    )
    for k in (8, 40):
        r = K.kmeans(blobs, k, n_init=2, seed=3)
        out[f"kmeans_centers_{k}"] = r.centers
        out[f"kmeans_labels_{k}"] = r.labels
        out[f"kmeans_inertia_{k}"] = np.array(r.inertia)
        labels, sq = K.kmeans_predict(blobs[::3], r.centers)
        out[f"predict_labels_{k}"], out[f"predict_sq_{k}"] = labels, sq
    centers, idx = K.kmeans_plusplus(blobs, 30, seed=5)
    out["kmeanspp_centers"], out["kmeanspp_idx"] = centers, idx
    return out


def main() -> None:
    try:
        out = outputs()
        out["instruction_set"] = np.array(K.instruction_set())
        out["instruction_sets"] = np.array(json.dumps(K.instruction_sets()))
    except ValueError as exc:
        print(f"ValueError: {exc}", file=sys.stderr)
        sys.exit(3)
    np.savez(sys.argv[1], **out)


if __name__ == "__main__":
    main()
