"""Parity of the signal kernels with scipy / numpy, and every input error they raise."""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.signal as ss
from visprim import _visprim as V
from visprim import kernels as K

ORDERS = range(1, 13)
CUTOFFS = [0.001, 0.01, 0.05, 0.1, 0.2, 0.25, 1 / 3, 0.5, 0.7, 0.9, 0.99, 0.999]


# --- reference implementations, written from the documented rules ---------------------------


def zvc_reference(
    velocity: np.ndarray, min_change: float = 0.0, positions: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Plain-Python zero-velocity crossings of a (frames, channels) array, as documented in
    visprim.kernels.zero_velocity_crossings."""
    v = velocity.reshape(len(velocity), -1)
    p = np.cumsum(v, axis=0) if positions is None else positions.reshape(v.shape)
    frames_out: list[float] = []
    chans_out: list[int] = []
    for c in range(v.shape[1]):
        reference = p[0, c]
        last = None  # (frame, value) of the last non-zero sample
        for t in range(v.shape[0]):
            x = v[t, c]
            if x == 0:
                continue
            if last is not None and (last[1] > 0) != (x > 0):
                a, va = last
                if t == a + 1:
                    i0, frac = a, va / (va - x)
                else:
                    i0, frac = (a + t) // 2, 0.5 if (a + t) % 2 else 0.0
                at = p[i0, c] if frac == 0 else p[i0, c] + frac * (p[i0 + 1, c] - p[i0, c])
                if min_change == 0 or abs(at - reference) > min_change:
                    frames_out.append(i0 + frac)
                    chans_out.append(c)
                    reference = at
            last = (t, x)
    return np.array(frames_out, dtype=float), np.array(chans_out, dtype=np.int64)


def resample_reference(
    values: np.ndarray, starts: np.ndarray, ends: np.ndarray, n: int
) -> np.ndarray:
    """np.interp of np.linspace(start, end, n) per channel, channel-major rows."""
    v = values.reshape(len(values), -1)
    grid = np.arange(len(v))
    rows = [
        np.concatenate([np.interp(np.linspace(s, e, n), grid, v[:, c]) for c in range(v.shape[1])])
        for s, e in zip(starts, ends, strict=True)
    ]
    return np.array(rows).reshape(len(starts), v.shape[1] * n)


def ragged(lengths: list[int], channels: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    values = rng.standard_normal((sum(lengths), channels)).cumsum(axis=0) * 0.1
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return values, offsets


# --- butter_sos ------------------------------------------------------------------------------


@pytest.mark.parametrize("order", ORDERS)
def test_butter_sos_matches_scipy(order: int) -> None:
    for cutoff in CUTOFFS:
        ours = K.butter_sos(order, cutoff)
        ref = ss.butter(order, cutoff, output="sos")
        assert ours.shape == ref.shape == ((order + 1) // 2, 6)
        assert ours.dtype == np.float64
        np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-10, err_msg=f"cutoff {cutoff}")


def test_butter_sos_accepts_numpy_scalars() -> None:
    np.testing.assert_array_equal(K.butter_sos(np.int64(4), np.float64(0.3)), K.butter_sos(4, 0.3))


# --- sosfiltfilt -----------------------------------------------------------------------------


@pytest.mark.parametrize("order", [1, 2, 3, 4, 7, 10, 12])
@pytest.mark.parametrize("cutoff", [0.001, 0.05, 0.25, 0.8, 0.999])
def test_sosfiltfilt_matches_scipy_2d(order: int, cutoff: float) -> None:
    rng = np.random.default_rng(order * 100 + int(cutoff * 1000))
    sos = ss.butter(order, cutoff, output="sos")
    x = rng.standard_normal((37, 120 + order * 7))  # 2 full blocks of 16 and a remainder
    np.testing.assert_allclose(K.sosfiltfilt(sos, x), ss.sosfiltfilt(sos, x), rtol=0, atol=1e-10)


def test_sosfiltfilt_1d_and_padlen() -> None:
    rng = np.random.default_rng(3)
    sos = K.butter_sos(6, 0.2)
    x = rng.standard_normal(90) * 5
    for padlen in [None, 0, 1, 17, 89]:
        ours = K.sosfiltfilt(sos, x, padlen=padlen)
        assert ours.shape == x.shape
        np.testing.assert_allclose(ours, ss.sosfiltfilt(sos, x, padlen=padlen), atol=1e-10)
    assert K.default_padlen(sos) == 3 * (2 * len(sos) + 1)


def test_sosfiltfilt_general_sections() -> None:
    # Not a Butterworth design: numerators other than [1, 2, 1], a band-pass.
    rng = np.random.default_rng(4)
    x = rng.standard_normal((3, 300))
    for sos in [
        ss.cheby1(5, 1.0, 0.3, output="sos"),
        ss.ellip(4, 0.5, 40, [0.1, 0.4], btype="bandpass", output="sos"),
        ss.butter(4, 0.3, btype="highpass", output="sos"),
    ]:
        np.testing.assert_allclose(K.sosfiltfilt(sos, x), ss.sosfiltfilt(sos, x), atol=1e-10)


def test_sosfiltfilt_non_contiguous_inputs() -> None:
    rng = np.random.default_rng(5)
    sos = K.butter_sos(4, 0.3)
    base = rng.standard_normal((200, 60))
    want = ss.sosfiltfilt(sos, base.T)
    for x in [base.T, np.asfortranarray(base.T), base.T[:, ::1]]:
        np.testing.assert_allclose(K.sosfiltfilt(sos, x), want, atol=1e-10)
    strided = rng.standard_normal(400)[::2]
    np.testing.assert_allclose(
        K.sosfiltfilt(sos, strided), ss.sosfiltfilt(sos, strided), atol=1e-10
    )
    # A Fortran-ordered sos is read in C order too.
    np.testing.assert_allclose(K.sosfiltfilt(np.asfortranarray(sos), base.T), want, atol=1e-10)


def test_sosfiltfilt_does_not_modify_input_and_returns_new_array() -> None:
    x = np.random.default_rng(6).standard_normal((4, 100))
    before = x.copy()
    y = K.sosfiltfilt(K.butter_sos(3, 0.2), x)
    np.testing.assert_array_equal(x, before)
    assert not np.shares_memory(x, y)
    assert y.flags.c_contiguous and y.flags.writeable


def test_sosfiltfilt_accepts_lists() -> None:
    x = [float(v) for v in np.sin(np.arange(50) * 0.3)]
    sos = ss.butter(2, 0.3, output="sos")
    np.testing.assert_allclose(K.sosfiltfilt(sos.tolist(), x), ss.sosfiltfilt(sos, x), atol=1e-10)


def test_sosfiltfilt_ragged_matches_per_trial_scipy() -> None:
    sos = K.butter_sos(10, 0.25)
    # Equal lengths (lockstep blocks) and odd ones (remainders), 4 and 3 channels.
    lengths = [150] * 21 + [34, 35, 80, 80, 80, 200]
    for channels in [4, 3, 1]:
        values, offsets = ragged(lengths, channels, seed=channels)
        out = K.sosfiltfilt_ragged(sos, values, offsets)
        assert out.shape == values.shape
        bounds = [*offsets.tolist(), len(values)]
        for i in range(len(lengths)):
            a, b = bounds[i], bounds[i + 1]
            want = ss.sosfiltfilt(sos, values[a:b], axis=0)
            np.testing.assert_allclose(out[a:b], want, rtol=0, atol=1e-10, err_msg=f"trial {i}")


def test_sosfiltfilt_ragged_1d_and_padlen() -> None:
    sos = K.butter_sos(4, 0.3)
    values, offsets = ragged([40, 12, 60], 1, seed=9)
    flat = values[:, 0].copy()
    out = K.sosfiltfilt_ragged(sos, flat, offsets, padlen=5)
    assert out.shape == flat.shape
    for a, b in [(0, 40), (40, 52), (52, 112)]:
        np.testing.assert_allclose(out[a:b], ss.sosfiltfilt(sos, flat[a:b], padlen=5), atol=1e-10)
    # int32 offsets are converted exactly.
    out32 = K.sosfiltfilt_ragged(sos, flat, offsets.astype(np.int32), padlen=5)
    np.testing.assert_array_equal(out32, out)


# --- zero-velocity crossings -----------------------------------------------------------------


def test_zvc_documented_examples() -> None:
    frames, chans = K.zero_velocity_crossings(np.array([2.0, 1.0, -3.0, -1.0, 1.0]))
    np.testing.assert_array_equal(frames, [1.25, 3.5])
    np.testing.assert_array_equal(chans, [0, 0])
    # Exact zeros: one zero -> that frame; a run -> its middle; touching zero -> nothing.
    assert K.zero_velocity_crossings(np.array([1.0, 0.0, -1.0]))[0].tolist() == [1.0]
    assert K.zero_velocity_crossings(np.array([1.0, 0.0, 0.0, -1.0]))[0].tolist() == [1.5]
    assert K.zero_velocity_crossings(np.array([1.0, 0.0, 2.0]))[0].size == 0
    assert K.zero_velocity_crossings(np.array([0.0, 0.0, 3.0, 0.0]))[0].size == 0


def test_zvc_significant_movement_rule() -> None:
    p = np.array([0.0, 10.0, 9.0, 9.5, 0.0])
    v = np.array([1.0, 1.0, -1.0, 1.0, -1.0])
    # Crossings at 1.5 (p 9.5), 2.5 (p 9.25), 3.5 (p 4.75).
    assert K.zero_velocity_crossings(v, 0.0, p)[0].tolist() == [1.5, 2.5, 3.5]
    # 2.5 is within 2 of the last KEPT crossing (1.5); 3.5 is 4.75 away from it.
    assert K.zero_velocity_crossings(v, 2.0, p)[0].tolist() == [1.5, 3.5]
    assert K.zero_velocity_crossings(v, 5.0, p)[0].tolist() == [1.5]
    # Strictly greater: a change of exactly min_change is not significant.
    assert K.zero_velocity_crossings(v, 9.5, p)[0].size == 0


def test_zvc_matches_reference_with_zeros_and_channels() -> None:
    rng = np.random.default_rng(11)
    for trial in range(20):
        frames, channels = 60 + trial, 1 + trial % 5
        v = np.round(rng.standard_normal((frames, channels)), 1)  # many exact zeros
        p = np.cumsum(rng.standard_normal((frames, channels)), axis=0)
        for min_change in [0.0, 0.3, 2.0]:
            for pos in [None, p]:
                got = K.zero_velocity_crossings(v, min_change, pos)
                want = zvc_reference(v, min_change, pos)
                np.testing.assert_array_equal(got[1], want[1])
                np.testing.assert_allclose(got[0], want[0], rtol=0, atol=1e-12)


def test_zvc_matches_vectorised_numpy_without_zeros() -> None:
    rng = np.random.default_rng(12)
    v = np.sin(np.linspace(0, 40, 3000))[:, None] + rng.uniform(-0.2, 0.2, (3000, 4))
    frames, chans = K.zero_velocity_crossings(v)
    a, b = v[:-1], v[1:]
    i, c = np.nonzero(a * b < 0)
    want = i + a[i, c] / (a[i, c] - b[i, c])
    order = np.lexsort((want, c))
    np.testing.assert_array_equal(chans, c[order])
    np.testing.assert_allclose(frames, want[order], rtol=0, atol=1e-12)


def test_zvc_ragged_equals_per_trial() -> None:
    values, offsets = ragged([30, 31, 100, 5, 64] * 30, 4, seed=13)
    vel = np.diff(values, axis=0, prepend=values[:1])
    vel[np.abs(vel) < 0.02] = 0.0
    tr, ch, fr = K.zero_velocity_crossings_ragged(vel, offsets, 0.1, positions=values)
    bounds = [*offsets.tolist(), len(values)]
    got_trials = []
    for i in range(len(offsets)):
        a, b = bounds[i], bounds[i + 1]
        frames, chans = K.zero_velocity_crossings(vel[a:b], 0.1, values[a:b])
        sel = tr == i
        np.testing.assert_array_equal(ch[sel], chans)
        np.testing.assert_array_equal(fr[sel], frames)
        got_trials.append(sel.sum())
    assert sum(got_trials) == len(tr) > 100
    # sorted by trial, then channel, then frame
    assert np.all(np.diff(tr) >= 0)
    key = tr * 10 + ch
    assert np.all(np.diff(key) >= 0)
    same = np.diff(key) == 0
    assert np.all(np.diff(fr)[same] > 0)


def test_zvc_default_positions_restart_per_trial() -> None:
    # With default positions the running sum restarts at each trial.
    v = np.array([5.0, 1.0, -0.5, 1.0, -0.2, 0.1])
    tr, _, fr = K.zero_velocity_crossings_ragged(v, np.array([0, 3]), min_change=0.3)
    alone = K.zero_velocity_crossings(v[3:], 0.3)[0]
    np.testing.assert_array_equal(fr[tr == 1], alone)


# --- resample_segments -----------------------------------------------------------------------


def test_resample_matches_np_interp() -> None:
    rng = np.random.default_rng(21)
    values = rng.standard_normal((500, 4)).cumsum(axis=0)
    starts = rng.uniform(0, 400, 300)
    ends = starts + rng.uniform(0.01, 99, 300)
    starts[:3], ends[:3] = [0.0, 250.0, 10.0], [499.0, 499.0, 10.5]
    for n in [2, 7, 100, 101]:
        got = K.resample_segments(values, starts, ends, n)
        assert got.shape == (300, 4 * n)
        np.testing.assert_allclose(got, resample_reference(values, starts, ends, n), atol=1e-12)


@pytest.mark.parametrize("channels", [1, 2, 3, 5, 8, 9])
def test_resample_any_channel_count(channels: int) -> None:
    rng = np.random.default_rng(channels)
    values = rng.standard_normal((60, channels))
    starts = np.array([0.0, 1.5, 30.25])
    ends = np.array([59.0, 2.0, 58.75])
    got = K.resample_segments(values, starts, ends, 50)
    np.testing.assert_allclose(got, resample_reference(values, starts, ends, 50), atol=1e-12)


def test_resample_1d_non_contiguous_and_empty() -> None:
    base = np.random.default_rng(22).standard_normal((80, 6))
    values = base[:, ::2]  # not contiguous
    starts, ends = np.array([3.0, 10.5]), np.array([70.0, 79.0])
    np.testing.assert_allclose(
        K.resample_segments(values, starts, ends, 10),
        resample_reference(np.ascontiguousarray(values), starts, ends, 10),
        atol=1e-12,
    )
    one = K.resample_segments(base[:, 0].copy(), starts, ends, 10)
    np.testing.assert_allclose(one, resample_reference(base[:, :1], starts, ends, 10), atol=1e-12)
    empty = K.resample_segments(base, np.empty(0), np.empty(0), 10)
    assert empty.shape == (0, 60)


# --- errors ----------------------------------------------------------------------------------

SOS = ss.butter(4, 0.25, output="sos")


@pytest.mark.parametrize(
    ("order", "cutoff", "match"),
    [
        (0, 0.5, "order"),
        (-3, 0.5, "order"),
        (4, 0.0, "cutoff"),
        (4, 1.0, "cutoff"),
        (4, 1.5, "cutoff"),
        (4, -0.1, "cutoff"),
        (4, float("nan"), "cutoff"),
    ],
)
def test_butter_sos_errors(order: int, cutoff: float, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        K.butter_sos(order, cutoff)


def test_butter_sos_non_integer_order() -> None:
    with pytest.raises(TypeError):
        K.butter_sos(4.5, 0.3)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("sos", "x", "kwargs", "exc", "match"),
    [
        (SOS, np.zeros(100, dtype=np.complex64), {}, TypeError, "x must hold real numbers"),
        (SOS, np.array(["a"] * 100), {}, TypeError, "x must hold real numbers"),
        (
            SOS,
            np.zeros((2, 2, 100)),
            {},
            ValueError,
            r"x must be 1-D or 2-D, got shape \(2, 2, 100\)",
        ),
        (SOS[:, :5], np.zeros(100), {}, ValueError, r"sos must have shape \(n_sections, 6\)"),
        (SOS[0], np.zeros(100), {}, ValueError, "sos must be 2-D"),
        (SOS * np.array([1, 1, 1, 2, 1, 1]), np.zeros(100), {}, ValueError, "a0"),
        (SOS[:0], np.zeros(100), {}, ValueError, "at least one section"),
        (np.where(SOS == 1.0, np.inf, SOS), np.zeros(100), {}, ValueError, "NaN or infinity"),
        (SOS.astype(np.complex128), np.zeros(100), {}, TypeError, "sos must hold real numbers"),
        (SOS, np.zeros(0), {}, ValueError, "empty"),
        (SOS, np.zeros((0, 50)), {}, ValueError, "empty"),
        (
            SOS,
            np.zeros(100),
            {"padlen": -1},
            ValueError,
            r"padlen \(samples of odd extension at each end\) must be an integer >= 0",
        ),
        ("not an array", np.zeros(100), {}, TypeError, "sos must hold real numbers"),
    ],
)
def test_sosfiltfilt_errors(sos, x, kwargs, exc, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(exc, match=match):
        K.sosfiltfilt(sos, x, **kwargs)


def test_sosfiltfilt_nan_names_position() -> None:
    x = np.zeros((3, 100))
    x[2, 41] = np.nan
    with pytest.raises(ValueError, match=r"NaN or infinity \(row 2, sample 41\)"):
        K.sosfiltfilt(SOS, x)
    x[2, 41] = -np.inf
    with pytest.raises(ValueError, match="NaN or infinity"):
        K.sosfiltfilt(SOS, x)


def test_sosfiltfilt_too_short_names_both_lengths() -> None:
    padlen = K.default_padlen(SOS)
    with pytest.raises(ValueError, match=rf"has {padlen} samples.*padlen = {padlen}"):
        K.sosfiltfilt(SOS, np.zeros(padlen))
    with pytest.raises(ValueError, match=r"has 10 samples.*padlen = 12"):
        K.sosfiltfilt(SOS, np.zeros(10), padlen=12)


@pytest.mark.parametrize(
    ("offsets", "exc", "match"),
    [
        (np.array([0, 50, 50]), ValueError, re.escape("offsets[2] = 50 follows offsets[1] = 50")),
        (np.array([0, 80, 60]), ValueError, "strictly increasing"),
        (np.array([10, 60]), ValueError, r"offsets\[0\] must be 0"),
        (np.array([0, 200]), ValueError, "out of range"),
        (np.array([0, -5]), ValueError, "strictly increasing"),
        (np.array([], dtype=np.int64), ValueError, "offsets is empty"),
        (np.array([[0, 50]]), ValueError, "offsets must be 1-D"),
        (
            np.array([0.0, 50.0]),
            TypeError,
            r"offsets must hold integers \(indices\), got dtype float64",
        ),
        (np.array([0, 2**63], dtype=np.uint64), ValueError, "beyond the int64 range"),
        (np.array([0, 50], dtype=np.uint16), None, ""),
        ([0, 50], None, ""),
    ],
)
def test_ragged_offsets_errors(offsets, exc, match) -> None:  # type: ignore[no-untyped-def]
    values = np.zeros((150, 2))
    for call in (
        lambda: K.sosfiltfilt_ragged(SOS, values, offsets),
        lambda: K.zero_velocity_crossings_ragged(values, offsets),
    ):
        if exc is None:
            call()
        else:
            with pytest.raises(exc, match=match):
                call()


def test_sosfiltfilt_ragged_errors() -> None:
    values = np.zeros((150, 2))
    with pytest.raises(
        ValueError, match=r"trial 1 \(frames 140\.\.150\) has 10 frames.*padlen = 15"
    ):
        K.sosfiltfilt_ragged(SOS, values, np.array([0, 140]))
    with pytest.raises(TypeError, match="values must have dtype float64"):
        V.sosfiltfilt_ragged(SOS, values.astype(np.float32), np.array([0]))
    with pytest.raises(ValueError, match=r"values must be 1-D or 2-D"):
        K.sosfiltfilt_ragged(SOS, np.zeros((5, 5, 5)), np.array([0]))
    bad = values.copy()
    bad[140, 1] = np.nan
    with pytest.raises(ValueError, match=r"NaN or infinity \(frame 140, channel 1\)"):
        K.sosfiltfilt_ragged(SOS, bad, np.array([0, 100]))
    with pytest.raises(ValueError, match="empty"):
        K.sosfiltfilt_ragged(SOS, np.zeros((0, 2)), np.array([0]))


def test_zvc_errors() -> None:
    v = np.array([1.0, -1.0, 1.0])
    with pytest.raises(TypeError, match="velocity must have dtype float64"):
        V.zero_velocity_crossings(v.astype(np.float32))
    with pytest.raises(ValueError, match="velocity must be 1-D or 2-D"):
        K.zero_velocity_crossings(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="empty"):
        K.zero_velocity_crossings(np.zeros(0))
    with pytest.raises(
        ValueError, match=r"velocity contains NaN or infinity \(frame 1, channel 0\)"
    ):
        K.zero_velocity_crossings(np.array([1.0, np.nan, 1.0]))
    with pytest.raises(ValueError, match="positions contains NaN or infinity"):
        K.zero_velocity_crossings(v, positions=np.array([0.0, np.inf, 0.0]))
    for bad in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="min_change must be a finite number >= 0"):
            K.zero_velocity_crossings(v, bad)
    with pytest.raises(ValueError, match=r"positions must have the shape of velocity \(3,\)"):
        K.zero_velocity_crossings(v, positions=np.zeros(4))
    with pytest.raises(TypeError, match="positions must have dtype float64"):
        V.zero_velocity_crossings(v, positions=np.zeros(3, dtype=np.float32))


def test_resample_errors() -> None:
    values = np.arange(20.0).reshape(10, 2)
    one = np.array([1.0])
    cases = [
        ((np.array([3.0]), np.array([3.0])), ValueError, r"segment 0: need 0 <= start < end"),
        ((np.array([-0.5]), one), ValueError, "segment 0"),
        ((np.array([0.0, 2.0]), np.array([1.0, 9.5])), ValueError, r"segment 1.*frames - 1 = 9"),
        ((np.array([np.nan]), one), ValueError, "not finite"),
        ((np.array([0.0, 1.0]), one), ValueError, "same length"),
        ((np.zeros((1, 1)), one), ValueError, "starts must be 1-D"),
        ((np.array([0j]), one), TypeError, "starts must hold real numbers"),
    ]
    for (starts, ends), exc, match in cases:
        with pytest.raises(exc, match=match):
            K.resample_segments(values, starts, ends, 5)
    with pytest.raises(ValueError, match=r"n \(samples per channel\) must be an integer >= 2"):
        K.resample_segments(values, np.array([0.0]), one, 1)
    with pytest.raises(ValueError, match=r"values contains NaN or infinity \(frame 3, channel 1\)"):
        bad = values.copy()
        bad[3, 1] = np.inf
        K.resample_segments(bad, np.array([0.0]), one, 5)
    with pytest.raises(ValueError, match="empty"):
        K.resample_segments(np.zeros((0, 2)), np.empty(0), np.empty(0), 5)
    with pytest.raises(TypeError, match="values must have dtype float64"):
        V.resample_segments(values.astype(np.float32), np.array([0.0]), one, 5)


def test_index_and_value_arrays_of_any_real_dtype_are_converted() -> None:
    values = np.arange(200.0).reshape(100, 2)
    want = K.resample_segments(values, np.array([0.0, 50.0]), np.array([40.0, 99.0]), 7)
    got = K.resample_segments(values, np.array([0, 50]), np.array([40, 99], dtype=np.uint8), 7)
    np.testing.assert_array_equal(got, want)
    got32 = K.resample_segments(values.astype(np.float32), [0, 50], [40, 99], np.int16(7))
    np.testing.assert_array_equal(got32, want)
    filt = K.sosfiltfilt_ragged(SOS, values, np.array([0, 40], dtype=np.uint32), padlen=5)
    filt_int = K.sosfiltfilt_ragged(SOS, values.astype(np.int32), [0, 40], padlen=np.int64(5))
    np.testing.assert_array_equal(filt, filt_int)
