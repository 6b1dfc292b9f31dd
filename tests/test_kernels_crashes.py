"""Regression tests of inputs that used to crash, abort or panic inside the kernels.

Each case runs in a child interpreter, so a segfault or an abort fails the test instead of
killing pytest. The child prints the name of the exception (or ``ok``) and its message; the
test checks the class and that the message names the argument or the sizes.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

PRELUDE = """
import resource, sys
import numpy as np
from visprim import kernels as K
# An address-space cap makes allocation failures deterministic on any machine.
resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
X = np.random.default_rng(0).standard_normal((40, 4))
def run(f):
    try:
        f()
        print("ok")
    except BaseException as e:
        print(type(e).__name__, str(e).replace("\\n", " "))
"""

#: A small ragged DTW input (two sequences of two frames).
DTW = "np.zeros((4, 2)), np.array([0, 2])"

CASES = [
    # (id, expression, exception class, text the message must contain)
    (
        "resample_n_2**62+1",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=2**62 + 1)",
        "MemoryError",
        "4 x 4611686018427387905",
    ),
    (
        "resample_n_2**62",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=2**62)",
        "MemoryError",
        "4611686018427387904",
    ),
    (
        "resample_n_2**61+1",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=2**61 + 1)",
        "MemoryError",
        "2305843009213693953",
    ),
    (
        "resample_n_2**62_no_segments",
        "K.resample_segments(np.zeros((10, 4)), np.zeros(0), np.zeros(0), n=2**62)",
        "MemoryError",
        "4611686018427387904",
    ),
    (
        "resample_n_10**12",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=10**12)",
        "MemoryError",
        "1000000000000",
    ),
    (
        "resample_n_2**31",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=2**31)",
        "MemoryError",
        "2147483648",
    ),
    (
        "resample_n_2**64",
        "K.resample_segments(np.zeros((10, 4)), np.array([0.]), np.array([5.]), n=2**64)",
        "ValueError",
        "n (samples per channel)",
    ),
    ("covariance_transposed", "K.covariance(np.random.rand(400, 60000))", "MemoryError", "60000"),
    ("accumulator_100_000", "K.CovarianceAccumulator(100_000)", "MemoryError", "100000"),
    ("accumulator_2**40", "K.CovarianceAccumulator(2**40)", "MemoryError", "1099511627776"),
    ("accumulator_-1", "K.CovarianceAccumulator(-1)", "ValueError", "dim"),
    ("kmeans_k_-1", "K.kmeans(X, -1)", "ValueError", "k (the number of clusters)"),
    ("kmeans_k_2**64", "K.kmeans(X, 2**64)", "ValueError", "k (the number of clusters)"),
    ("kmeans_n_init_-1", "K.kmeans(X, 2, n_init=-1)", "ValueError", "n_init"),
    ("kmeans_max_iter_-1", "K.kmeans(X, 2, max_iter=-5)", "ValueError", "max_iter"),
    ("kmeans_trials_-1", "K.kmeans(X, 2, n_local_trials=-1)", "ValueError", "n_local_trials"),
    ("kmeans_n_threads_-1", "K.kmeans(X, 2, n_threads=-1)", "ValueError", "n_threads"),
    ("kmeans_n_threads_2**31", "K.kmeans(X, 2, n_threads=2**31)", "ValueError", "n_threads"),
    ("kmeans_tol_huge_int", "K.kmeans(X, 2, tol=10**400)", "ValueError", "tol"),
    ("kmeanspp_k_-1", "K.kmeans_plusplus(X, -1)", "ValueError", "k (the number of seeds)"),
    ("predict_n_threads_-1", "K.kmeans_predict(X, X[:2], n_threads=-1)", "ValueError", "n_threads"),
    ("covariance_n_threads_-1", "K.covariance(X, n_threads=-1)", "ValueError", "n_threads"),
    ("covariance_n_threads_2**63", "K.covariance(X, n_threads=2**63)", "ValueError", "n_threads"),
    ("dtw_n_threads_-1", f"K.dtw_distances({DTW}, n_threads=-1)", "ValueError", "n_threads"),
    ("dtw_n_threads_5000", f"K.dtw_distances({DTW}, n_threads=5000)", "ValueError", "n_threads"),
    ("dtw_n_threads_2**31", f"K.dtw_distances({DTW}, n_threads=2**31)", "ValueError", "n_threads"),
    ("dtw_n_threads_2**64", f"K.dtw_distances({DTW}, n_threads=2**64)", "ValueError", "n_threads"),
    ("eigh_k_-1", "K.eigh(np.eye(3), k=-1)", "ValueError", "k (leading eigenpairs"),
    ("eigh_k_2**70", "K.eigh(np.eye(3), k=2**70)", "ValueError", "k (leading eigenpairs"),
    (
        "padlen_2**63",
        "K.sosfiltfilt(K.butter_sos(4, 0.3), np.zeros(50), padlen=2**63)",
        "ValueError",
        "padlen",
    ),
    (
        "padlen_-2**64",
        "K.sosfiltfilt_ragged(K.butter_sos(4, 0.3), np.zeros((50, 2)), [0], padlen=-(2**64))",
        "ValueError",
        "padlen",
    ),
    ("butter_order_2**64", "K.butter_sos(2**64, 0.3)", "ValueError", "order"),
    ("butter_order_-1", "K.butter_sos(-1, 0.3)", "ValueError", "order"),
    ("zvc_min_change_huge", "K.zero_velocity_crossings(X, 10**400)", "ValueError", "min_change"),
    ("seg1_window_huge", "K.seg1_events([0], [0], [0.0], -(10**400))", "ValueError", "window"),
    (
        "setstate_dim_2**32",
        "K.CovarianceAccumulator().__setstate__((2**32, 1, np.zeros(0), np.zeros(0)))",
        "ValueError",
        "moments of dimension 4294967296",
    ),
    (
        "setstate_count_-1",
        "K.CovarianceAccumulator().__setstate__((2, -1, np.zeros(2), np.zeros(4)))",
        "ValueError",
        "count",
    ),
    ("merge_self_empty", "(lambda a: a.merge(a))(K.CovarianceAccumulator())", "ok", ""),
    ("merge_self_dim", "(lambda a: a.merge(a))(K.CovarianceAccumulator(3))", "ok", ""),
]


@pytest.fixture(scope="module")
def child_results() -> dict[str, str]:
    """Run every case in one child interpreter, one output line per case. If the child dies,
    the cases it did not report (the crashing one and those after it) fail."""
    lines = [f"print({case_id!r}, end=' '); run(lambda: {expr})" for case_id, expr, _, _ in CASES]
    code = PRELUDE + "\n" + "\n".join(lines) + "\n"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    results = {}
    for line in proc.stdout.splitlines():
        case_id, _, rest = line.partition(" ")
        results[case_id] = rest
    if proc.returncode != 0:
        results["__died__"] = f"child died with code {proc.returncode}: {proc.stderr[-2000:]}"
    return results


@pytest.mark.parametrize(("case_id", "exc", "text"), [(c[0], c[2], c[3]) for c in CASES])
def test_no_crash_in_a_child(
    child_results: dict[str, str], case_id: str, exc: str, text: str
) -> None:
    assert case_id in child_results, child_results.get("__died__", "no output")
    name, _, message = child_results[case_id].partition(" ")
    assert name == exc, child_results[case_id]
    assert text in message, child_results[case_id]


def test_merge_of_itself_doubles_the_weights() -> None:
    code = PRELUDE + textwrap.dedent(
        """
        acc = K.CovarianceAccumulator()
        acc.update(X)
        mean, cov = acc.mean, acc.covariance()
        acc.merge(acc)
        assert acc.count == 2 * len(X), acc.count
        np.testing.assert_allclose(acc.mean, mean, rtol=1e-13)
        np.testing.assert_allclose(acc.covariance(), cov, rtol=1e-12)
        print("ok")
        """
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr[-2000:]
