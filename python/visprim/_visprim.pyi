"""Type stubs of the compiled extension visprim._visprim (see visprim.kernels)."""

import numpy as np
from numpy.typing import NDArray

# --- signal kernels (filter, zvc, resample) ---

def butter_sos(order: int, cutoff: float) -> NDArray[np.float64]: ...
def default_padlen(sos: NDArray[np.float64]) -> int: ...
def sosfiltfilt(
    sos: NDArray[np.float64], x: NDArray[np.float64], padlen: int | None = None
) -> NDArray[np.float64]: ...
def sosfiltfilt_ragged(
    sos: NDArray[np.float64],
    values: NDArray[np.float64],
    offsets: NDArray[np.int64],
    padlen: int | None = None,
) -> NDArray[np.float64]: ...
def zero_velocity_crossings(
    velocity: NDArray[np.float64],
    min_change: float = 0.0,
    positions: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...
def zero_velocity_crossings_ragged(
    velocity: NDArray[np.float64],
    offsets: NDArray[np.int64],
    min_change: float = 0.0,
    positions: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]: ...
def resample_segments(
    values: NDArray[np.float64],
    starts: NDArray[np.float64],
    ends: NDArray[np.float64],
    n: int = 100,
) -> NDArray[np.float64]: ...

# --- linalg kernels (covariance, eigh, kmeans) ---
