"""The DTW kernel (visprim.kernels.dtw_distances) against a plain numpy table."""

from __future__ import annotations

import numpy as np
import pytest
from visprim import kernels


def _dtw(a: np.ndarray, b: np.ndarray, band: float | None) -> float:
    """Textbook DTW on the full table, with the documented normalised-time band."""
    n, m = len(a), len(b)
    cost = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    table = np.full((n + 1, m + 1), np.inf)
    table[0, 0] = 0.0
    if band is not None and n > 1 and m > 1:
        rho = max(band, (1 / (n - 1) + 1 / (m - 1)) / 2)
        i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
        allowed = np.abs(i * (m - 1) - j * (n - 1)) <= rho * (n - 1) * (m - 1)
    else:
        allowed = np.ones((n, m), dtype=bool)
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            if allowed[i - 1, j - 1]:
                best = min(table[i - 1, j], table[i, j - 1], table[i - 1, j - 1])
                table[i, j] = cost[i - 1, j - 1] + best
    return float(table[n, m])


def _set(rng: np.random.Generator, lengths: list[int], dim: int):
    seqs = [rng.normal(size=(n, dim)) for n in lengths]
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return seqs, np.concatenate(seqs), offsets


@pytest.mark.parametrize("band", [None, 0.0, 0.15, 1.0])
def test_matches_a_numpy_table(band: float | None) -> None:
    rng = np.random.default_rng(1)
    qs, q, qo = _set(rng, [1, 7, 12], 3)
    rs, r, ro = _set(rng, [5, 1, 16, 9], 3)
    raw = kernels.dtw_distances(q, qo, r, ro, band=band, normalize=False)
    norm = kernels.dtw_distances(q, qo, r, ro, band=band)
    assert raw.shape == (3, 4)
    for i, a in enumerate(qs):
        for j, b in enumerate(rs):
            want = _dtw(a, b, band)
            assert np.isfinite(want)
            assert raw[i, j] == pytest.approx(want, rel=1e-12)
            assert norm[i, j] == pytest.approx(want / (len(a) + len(b)), rel=1e-12)


def test_symmetric_form_and_time_warping() -> None:
    rng = np.random.default_rng(2)
    _, x, o = _set(rng, [6, 9, 4, 11], 2)
    sym = kernels.dtw_distances(x, o, band=0.2)
    cross = kernels.dtw_distances(x, o, x, o, band=0.2)
    np.testing.assert_array_equal(sym, sym.T)
    np.testing.assert_array_equal(np.diag(sym), 0.0)
    np.testing.assert_allclose(sym, cross, rtol=1e-12, atol=1e-12)
    # A sequence played at half speed is at cost 0 from the original, not so the reverse.
    a = rng.normal(size=(10, 2))
    slow = np.repeat(a, 2, axis=0)
    seqs = np.concatenate([a, slow, a[::-1]])
    d = kernels.dtw_distances(seqs, np.array([0, 10, 30]))
    assert d[0, 1] == pytest.approx(0.0, abs=1e-15)
    assert d[0, 2] > 0.1


def test_threads_do_not_change_results() -> None:
    rng = np.random.default_rng(3)
    _, x, o = _set(rng, [20, 31, 17, 25, 40, 12], 4)
    one = kernels.dtw_distances(x, o, n_threads=1)
    two = kernels.dtw_distances(x, o, n_threads=2)
    np.testing.assert_array_equal(one, two)


def test_bad_inputs_raise_readable_errors() -> None:
    x = np.zeros((6, 2))
    o = np.array([0, 3])
    # Other real dtypes are converted as numpy converts them (visprim.kernels).
    np.testing.assert_array_equal(
        kernels.dtw_distances(x.astype(np.float32), o), kernels.dtw_distances(x, o)
    )
    with pytest.raises(TypeError, match="int64|integer"):
        kernels.dtw_distances(x, o.astype(np.float64) + 0.5)
    with pytest.raises(ValueError, match="2-D"):
        kernels.dtw_distances(np.zeros(6), o)
    with pytest.raises(ValueError, match="channels"):
        kernels.dtw_distances(x, o, np.zeros((4, 3)), np.array([0]))
    with pytest.raises(ValueError, match="both"):
        kernels.dtw_distances(x, o, x)
    with pytest.raises(ValueError, match="strictly increasing"):
        kernels.dtw_distances(x, np.array([0, 3, 3]))
    bad = x.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="frame 4, channel 1"):
        kernels.dtw_distances(bad, o)
    with pytest.raises(ValueError, match="band"):
        kernels.dtw_distances(x, o, band=1.5)
    with pytest.raises(ValueError, match="n_threads"):
        kernels.dtw_distances(x, o, n_threads=0)
