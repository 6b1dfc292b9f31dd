"""Kernel results are bit-identical for any number of threads, and eigenvectors of repeated
eigenvalues come in a basis that depends only on the eigenspace.

The thread counts are set with RAYON_NUM_THREADS (and the BLAS variables) in child
interpreters, since rayon's global pool is sized once per process.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
from visprim import kernels as K

CHILD = """
import hashlib
import numpy as np
from visprim import kernels as K

rng = np.random.default_rng(7)
out = {}
def put(name, *arrays):
    h = hashlib.sha256()
    for a in arrays:
        h.update(np.ascontiguousarray(a).tobytes())
    out[name] = h.hexdigest()[:16]

# Wide rows (parallel product) and narrow rows (parallel parts).
wide = rng.standard_normal((2000, 60)) @ rng.standard_normal((60, 400))  # rank 60 of 400
put("covariance_wide", *K.covariance(wide))
put("covariance_narrow", *K.covariance(rng.standard_normal((20000, 9))))
mean, cov = K.covariance(wide)
# Rank-deficient: 340 eigenvalues at rounding level (one degenerate eigenspace). Before
# the solver's split was fixed, these eigenvectors changed with the thread count.
put("eigh_rank_deficient", *K.eigh(cov))
put("eigh_leading", *K.eigh(cov, k=30))
blobs = np.concatenate([rng.normal(c, 0.3, (700, 30)) for c in rng.uniform(-4, 4, (8, 30))])
r = K.kmeans(blobs, 8, n_init=2, seed=3)
put("kmeans", r.centers, r.labels, np.array([r.inertia, r.n_iter]))
put("kmeans_plusplus", *K.kmeans_plusplus(blobs, 8, seed=5))
put("kmeans_predict", *K.kmeans_predict(blobs, r.centers))
acc = K.CovarianceAccumulator()
for part in np.array_split(wide, 3):
    acc.update(part)
put("accumulator", acc.mean, acc.covariance())
sig = rng.standard_normal((5000, 4)).cumsum(axis=0)
put("filter", K.sosfiltfilt_ragged(K.butter_sos(10, 0.25), sig, [0, 1200, 3000]))
put("resample", K.resample_segments(sig, np.array([0.5, 10.0]), np.array([900.0, 4000.0]), 100))
print(" ".join(f"{k}={v}" for k, v in sorted(out.items())))
"""


def run_with_threads(n: int) -> dict[str, str]:
    env = dict(os.environ)
    for var in ("RAYON_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[var] = str(n)
    proc = subprocess.run(
        [sys.executable, "-c", CHILD], capture_output=True, text=True, timeout=300, env=env
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return dict(item.split("=") for item in proc.stdout.split())


def test_bit_identical_for_1_2_and_7_threads() -> None:
    runs = {n: run_with_threads(n) for n in (1, 2, 7)}
    assert len(runs[1]) == 10
    for n in (2, 7):
        differ = [k for k in runs[1] if runs[1][k] != runs[n][k]]
        assert not differ, f"{n} threads differ from 1 thread in: {differ}"


def random_rotation(m: int, rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.standard_normal((m, m)))
    return q * np.sign(np.diag(r))


def test_repeated_eigenvalue_basis_depends_only_on_the_eigenspace() -> None:
    rng = np.random.default_rng(11)
    d = 12
    q = random_rotation(d, rng)
    values = np.array([5.0, 3.0, 3.0, 3.0, 2.0, 1.0, 1.0, 0.5, 0.0, 0.0, 0.0, 0.0])
    reference = None
    for trial in range(4):
        # The same eigenspaces, each given with another basis inside it.
        basis = q.copy()
        for lo, hi in ((1, 4), (5, 7), (8, 12)):
            basis[:, lo:hi] = basis[:, lo:hi] @ random_rotation(hi - lo, rng)
        a = (basis * values) @ basis.T
        a = (a + a.T) / 2
        got_values, vectors = K.eigh(a)
        np.testing.assert_allclose(got_values, values, atol=1e-13)
        np.testing.assert_allclose(vectors.T @ vectors, np.eye(d), atol=1e-13)
        np.testing.assert_allclose(a @ vectors, vectors * got_values, atol=1e-12)
        if reference is None:
            reference = vectors
        else:
            np.testing.assert_allclose(vectors, reference, atol=1e-10, err_msg=f"trial {trial}")


def test_canonical_basis_convention() -> None:
    # Eigenspace of 1 spanned by e0 + e1 and e2 (eigenvalue 1 repeated), 0 on e0 - e1.
    a = np.array([[0.5, 0.5, 0.0], [0.5, 0.5, 0.0], [0.0, 0.0, 1.0]])
    values, vectors = K.eigh(a)
    np.testing.assert_allclose(values, [1.0, 1.0, 0.0], atol=1e-15)
    # First pivot: the row of largest norm in the eigenspace is row 2 (norm 1): w0 = e2.
    np.testing.assert_allclose(vectors[:, 0], [0.0, 0.0, 1.0], atol=1e-15)
    # Then row 0 (first on the tie with row 1): w1 = (e0 + e1) / sqrt(2), positive at row 0.
    h = np.sqrt(0.5)
    np.testing.assert_allclose(vectors[:, 1], [h, h, 0.0], atol=1e-15)
    # A simple eigenvalue: largest component positive (the first on a tie).
    np.testing.assert_allclose(vectors[:, 2], [h, -h, 0.0], atol=1e-15)
