"""A model's bits do not depend on the BLAS thread count (OpenBLAS changes its summation
order with it): fits in child processes with OPENBLAS_NUM_THREADS=1 and 2 agree exactly."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

PYTHONPATH = str(Path(__file__).resolve().parents[1] / "python")

CHILD = """
import hashlib
import numpy as np
from visprim import PrimitiveModel
from visprim.datasets import imitation_experiment
# More segments than dimensions: the covariance path and a tall projection product.
trials = imitation_experiment(11, 20, seed=0)
m = PrimitiveModel(n_clusters=30, n_init=2, seed=0).fit(trials)
assert m.n_training_segments_ > m.eigenvectors_.shape[0]
for name in ("cluster_centers_", "training_projections_", "eigenvectors_", "mean_"):
    a = np.ascontiguousarray(getattr(m, name))
    print(name, hashlib.sha256(a.tobytes()).hexdigest())
"""


def fit_digests(threads: int) -> str:
    env = {**os.environ, "PYTHONPATH": PYTHONPATH, "OPENBLAS_NUM_THREADS": str(threads)}
    env.pop("OMP_NUM_THREADS", None)
    proc = subprocess.run(
        [sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=600, env=env
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def test_model_bits_identical_for_one_and_two_blas_threads():
    one, two = fit_digests(1), fit_digests(2)
    assert one.count("\n") == 4
    assert one == two
