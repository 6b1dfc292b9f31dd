"""The bindings word array-argument errors alike, whichever kernel family they belong to.

The raw extension is called (``visprim._visprim``), not ``visprim.kernels``, whose wrappers
convert real dtypes before the bindings see them.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from visprim import _visprim as V

SOS = V.butter_sos(4, 0.25)
FRAMES = np.zeros((40, 2))
OFFSETS = np.array([0], dtype=np.int64)

# (call with the bad argument, argument name); one per binding module.
NOT_FLOAT64 = [
    (lambda a: V.sosfiltfilt_ragged(SOS, a, OFFSETS), "values"),
    (lambda a: V.covariance(a), "X"),
    (lambda a: V.dtw_distances(a, OFFSETS), "queries"),
]


@pytest.mark.parametrize(("call", "name"), NOT_FLOAT64)
def test_a_wrong_dtype_names_the_argument_and_the_fix(call, name):
    with pytest.raises(TypeError) as info:
        call(FRAMES.astype(np.float32))
    assert str(info.value) == (
        f"{name} must have dtype float64, got float32; convert it with .astype(numpy.float64)"
    )


@pytest.mark.parametrize(("call", "name"), NOT_FLOAT64)
def test_a_list_is_refused_naming_its_type(call, name):
    with pytest.raises(TypeError, match=rf"^{name} must be a (2-D )?numpy\.ndarray of float64.*"):
        call(FRAMES.tolist())
    with pytest.raises(TypeError, match=r"got list$"):
        call(FRAMES.tolist())


@pytest.mark.parametrize(
    "call",
    [
        lambda a: V.resample_segments(FRAMES, a, a, 10),
        lambda a: V.covariance(a),
        lambda a: V.dtw_distances(a, OFFSETS),
    ],
)
def test_shapes_are_printed_as_numpy_prints_them(call):
    with pytest.raises(ValueError, match=re.escape("(3, 2, 1)")):
        call(np.zeros((3, 2, 1)))


@pytest.mark.parametrize(
    "call",
    [
        lambda o: V.sosfiltfilt_ragged(SOS, FRAMES, o),
        lambda o: V.dtw_distances(FRAMES, o),
    ],
)
def test_offsets_must_be_int64_and_one_dimensional(call):
    with pytest.raises(TypeError, match=re.escape("convert it with .astype(numpy.int64)")):
        call(OFFSETS.astype(np.int32))
    with pytest.raises(ValueError, match=re.escape("must be 1-D (the first frame of each")):
        call(OFFSETS.reshape(1, 1))


def test_non_contiguous_arrays_give_the_contiguous_result():
    wide = np.random.default_rng(0).standard_normal((40, 4))
    strided = wide[:, ::2]
    assert not strided.flags.c_contiguous
    np.testing.assert_array_equal(
        V.sosfiltfilt_ragged(SOS, strided, OFFSETS),
        V.sosfiltfilt_ragged(SOS, np.ascontiguousarray(strided), OFFSETS),
    )
    offsets = np.array([0, 0, 20, 20], dtype=np.int64)[::2]
    np.testing.assert_array_equal(
        V.dtw_distances(strided, offsets), V.dtw_distances(strided, np.array([0, 20]))
    )
