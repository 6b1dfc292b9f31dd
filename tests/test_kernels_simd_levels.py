"""The kernels at every SIMD level this CPU runs, and ``VISPRIM_SIMD``.

The level is read once per process, so each level runs in a child process
(``_simd_child.py``) and the outputs are compared here: bit for bit where the kernels promise
it, within the tolerances that :func:`visprim.kernels.instruction_sets` states elsewhere. The
filter and the covariance also check that the capped level really ran (their portable code
gives other bits than the SIMD code).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.signal
from visprim import kernels as K

CHILD = Path(__file__).with_name("_simd_child.py")
LEVELS = ("portable", "avx2", "avx512")
SUPPORTED = K.simd_levels()
INSTRUCTION_SET = {"portable": "portable", "avx2": "avx2+fma", "avx512": "avx512f"}
# Stated in kernels.instruction_sets().
FILTER_TOL = 1e-12
COV_TOL = 1e-12


def _env(value: str | None) -> dict[str, str]:
    env = dict(os.environ)
    env.pop(K.SIMD_ENV, None)
    if value is not None:
        env[K.SIMD_ENV] = value
    return env


def _run_child(tmp: Path, value: str | None) -> subprocess.CompletedProcess[str]:
    out = tmp / f"{value}.npz"
    return subprocess.run(
        [sys.executable, str(CHILD), str(out)],
        env=_env(value),
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.fixture(scope="module")
def at_level(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, np.ndarray]]:
    """The child's outputs at every level this CPU runs."""
    tmp = tmp_path_factory.mktemp("simd")
    results = {}
    for level in SUPPORTED:
        proc = _run_child(tmp, level)
        assert proc.returncode == 0, f"{K.SIMD_ENV}={level}: {proc.stderr}"
        with np.load(tmp / f"{level}.npz") as f:
            results[level] = {k: f[k] for k in f.files}
    return results


def _level(name: str) -> str:
    if name not in SUPPORTED:
        pytest.skip(f"this CPU does not run the {name} level (it runs {', '.join(SUPPORTED)})")
    return name


def _pairs() -> list[tuple[str, str]]:
    return [(a, b) for i, a in enumerate(LEVELS) for b in LEVELS[i + 1 :]]


def test_simd_levels_follow_the_cpu_flags() -> None:
    cpuinfo = Path("/proc/cpuinfo")
    if platform.machine() != "x86_64" or not cpuinfo.exists():
        pytest.skip("reads the x86-64 flags of /proc/cpuinfo")
    flags = set(
        next(ln for ln in cpuinfo.read_text().splitlines() if ln.startswith("flags")).split()
    )
    want = ["portable"]
    if {"avx2", "fma"} <= flags:
        want.append("avx2")
        if {"avx512f", "avx512vl", "f16c"} <= flags:
            want.append("avx512")
    assert SUPPORTED == want
    if os.environ.get(K.SIMD_ENV, ""):
        assert K.instruction_set() == INSTRUCTION_SET[os.environ[K.SIMD_ENV]]
    else:
        assert K.instruction_set() == INSTRUCTION_SET[want[-1]]


@pytest.mark.parametrize("level", LEVELS)
def test_each_kernel_reports_the_capped_level(
    level: str, at_level: dict[str, dict[str, np.ndarray]]
) -> None:
    got = at_level[_level(level)]
    assert str(got["instruction_set"]) == INSTRUCTION_SET[level]
    sets = json.loads(str(got["instruction_sets"]))
    assert set(sets) == {
        "sosfiltfilt",
        "resample_segments",
        "covariance",
        "kmeans",
        "kmeans_predict",
        "kmeans_plusplus",
        "eigh",
        "dtw_distances",
    }
    first = {name: text.split()[0] for name, text in sets.items()}
    isa = INSTRUCTION_SET[level]
    assert first["sosfiltfilt"] == first["resample_segments"] == isa
    assert first["kmeans"] == first["kmeans_predict"] == isa
    assert first["kmeans_plusplus"] == ("portable" if level == "portable" else "avx2+fma")
    assert first["covariance"] == ("faer's" if level == "portable" else isa)
    assert first["eigh"] == "faer's" and first["dtw_distances"] == "portable"


def _tolerance(key: str, a: str, out: dict[str, np.ndarray]) -> float:
    """0 where levels ``a`` < b promise the same bits, else the absolute tolerance."""
    if key.startswith("filter_"):
        x = out["filter_ragged_x" if "ragged" in key else "filter_x"]
        return FILTER_TOL * float(np.abs(x).max())
    if key.startswith(("cov_", "acc_")) and key.endswith("_40") and a == "portable":
        # faer's product against the packed kernel (whose two tiles give the same bits).
        return COV_TOL * float(np.abs(out[key]).max())
    if key.startswith(("resample_", "kmeans", "predict_", "cov_", "acc_")):
        return 0.0
    raise AssertionError(f"no comparison rule for {key}")


@pytest.mark.parametrize(("a", "b"), _pairs())
def test_levels_agree(a: str, b: str, at_level: dict[str, dict[str, np.ndarray]]) -> None:
    x, y = at_level[_level(a)], at_level[_level(b)]
    assert x.keys() == y.keys()
    for key in x:
        if key.startswith("instruction_set") or key.endswith("_x"):
            continue
        tol = _tolerance(key, a, x)
        if tol == 0.0:
            np.testing.assert_array_equal(x[key], y[key], err_msg=f"{key}: {a} vs {b}")
        else:
            np.testing.assert_allclose(
                x[key], y[key], rtol=0, atol=tol, err_msg=f"{key}: {a} vs {b}"
            )


def test_portable_filter_is_scipys_arithmetic_and_simd_is_not(
    at_level: dict[str, dict[str, np.ndarray]],
) -> None:
    # If a level ignored the cap, the portable run would give the fused multiply-add bits.
    got = at_level["portable"]
    for order in (7, 10):
        want = scipy.signal.sosfiltfilt(K.butter_sos(order, 0.15), got["filter_x"])
        np.testing.assert_allclose(got[f"filter_rows_{order}"], want, rtol=0, atol=1e-12)
    for level in SUPPORTED[1:]:
        for key in ("filter_rows_7", "filter_rows_10", "filter_ragged"):
            assert not np.array_equal(at_level[level][key], got[key]), f"{key} at {level}"


def test_portable_covariance_is_faers_product(
    at_level: dict[str, dict[str, np.ndarray]],
) -> None:
    if len(SUPPORTED) < 2:
        pytest.skip("this CPU runs the portable level only")
    got = at_level["portable"]
    for level in SUPPORTED[1:]:
        for key in ("cov_40", "acc_cov_40"):
            assert not np.array_equal(at_level[level][key], got[key]), f"{key} at {level}"


def _kernel_calls() -> dict[str, object]:
    x = np.random.default_rng(0).standard_normal((200, 20))
    sos = K.butter_sos(2, 0.3)
    return {
        "instruction_set": lambda: K.instruction_set(),
        "instruction_sets": lambda: K.instruction_sets(),
        "sosfiltfilt": lambda: K.sosfiltfilt(sos, x.T),
        "sosfiltfilt_ragged": lambda: K.sosfiltfilt_ragged(sos, x, [0, 100]),
        "resample_segments": lambda: K.resample_segments(x, [0.0], [10.0], 5),
        "covariance": lambda: K.covariance(x),
        "CovarianceAccumulator.update": lambda: K.CovarianceAccumulator().update(x),
        "kmeans": lambda: K.kmeans(x, 3, seed=0),
        "kmeans_predict": lambda: K.kmeans_predict(x, x[:3]),
        "kmeans_plusplus": lambda: K.kmeans_plusplus(x, 3),
    }


_CALL_ALL = """
import sys
sys.path.insert(0, sys.argv[1])
from test_kernels_simd_levels import _kernel_calls
from visprim import kernels as K
assert K.simd_levels()[0] == "portable"  # never raises
for name, call in _kernel_calls().items():
    try:
        call()
    except ValueError as exc:
        print(name, "|", exc)
    else:
        print(name, "| no error")
"""


def _errors_with(value: str) -> dict[str, str]:
    proc = subprocess.run(
        [sys.executable, "-c", _CALL_ALL, str(Path(__file__).parent)],
        env=_env(value),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    return dict(line.split(" | ", 1) for line in proc.stdout.splitlines())


def test_an_unknown_level_is_a_clear_error_from_every_kernel() -> None:
    errors = _errors_with("sse4")
    assert errors.keys() == _kernel_calls().keys()
    best = SUPPORTED[-1]
    for name, msg in errors.items():
        assert msg == (
            f'VISPRIM_SIMD="sse4" is not a SIMD level: use portable, avx2 or avx512 (this '
            f"CPU's best is {best}), or unset VISPRIM_SIMD"
        ), name


def test_a_level_the_cpu_lacks_is_a_clear_error_from_every_kernel() -> None:
    lacking = [lv for lv in LEVELS if lv not in SUPPORTED]
    if not lacking:
        pytest.skip("this CPU runs every level")
    best = SUPPORTED[-1]
    for level in lacking:
        errors = _errors_with(level)
        assert errors.keys() == _kernel_calls().keys()
        for name, msg in errors.items():
            assert msg.startswith(
                f"VISPRIM_SIMD={level} asks for a level this CPU lacks: it has no "
            ), f"{name}: {msg}"
            assert msg.endswith(
                f"(its best level is {best}); use {', '.join(SUPPORTED)}, or unset VISPRIM_SIMD"
            ), f"{name}: {msg}"


def test_an_empty_setting_is_the_best_level() -> None:
    proc = subprocess.run(
        [sys.executable, "-c", "from visprim import kernels as K; print(K.instruction_set())"],
        env=_env(""),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.stdout.strip() == INSTRUCTION_SET[SUPPORTED[-1]], proc.stderr
