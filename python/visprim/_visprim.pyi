"""Type stubs of the compiled extension visprim._visprim (see visprim.kernels)."""

from collections.abc import Sequence
from typing import final

import numpy as np
from numpy.typing import NDArray

def instruction_set() -> str: ...
def instruction_sets() -> list[tuple[str, str]]: ...
def simd_levels() -> list[str]: ...

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
def gradient_ragged(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    offsets: NDArray[np.int64],
) -> NDArray[np.float64]: ...
def zero_velocity_crossings(
    velocity: NDArray[np.float64],
    min_change: float = 0.0,
    positions: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...
def zero_velocity_crossings_of_positions(
    times: NDArray[np.float64],
    positions: NDArray[np.float64],
    offsets: NDArray[np.int64],
    min_change: float = ...,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]: ...
def zero_velocity_crossings_ragged(
    velocity: NDArray[np.float64],
    offsets: NDArray[np.int64],
    min_change: float = 0.0,
    positions: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]: ...
def seg1_events(
    trial: NDArray[np.int64],
    channel: NDArray[np.int64],
    time: NDArray[np.float64],
    window: float,
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.int64]]: ...
def times_to_frames(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    t: NDArray[np.float64],
) -> NDArray[np.float64]: ...
def frames_to_times(
    times: NDArray[np.float64],
    offsets: NDArray[np.int64],
    trial: NDArray[np.int64],
    frame: NDArray[np.float64],
) -> NDArray[np.float64]: ...
def resample_segments(
    values: NDArray[np.float64],
    starts: NDArray[np.float64],
    ends: NDArray[np.float64],
    n: int = 100,
) -> NDArray[np.float64]: ...

# --- linalg kernels (covariance, eigh, kmeans) ---

def covariance(
    x: NDArray[np.float64], *, n_threads: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

@final
class OnlineDtw:
    def __new__(cls, references: NDArray[np.float64], offsets: NDArray[np.int64]) -> OnlineDtw: ...
    def push(self, frames: NDArray[np.float64]) -> None: ...
    def costs(self) -> NDArray[np.float64]: ...
    def open_end(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...
    def running(self, codes: NDArray[np.int64]) -> tuple[int, float, float]: ...
    def reset(self) -> None: ...
    @property
    def n_frames(self) -> int: ...
    @property
    def n_references(self) -> int: ...
    @property
    def dim(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...

class CausalSos:
    def __new__(cls, sos: NDArray[np.float64], channels: int) -> CausalSos: ...
    def filter(self, x: NDArray[np.float64]) -> NDArray[np.float64]: ...
    def reset(self) -> None: ...
    @property
    def channels(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...

class StreamResampler:
    def __new__(
        cls,
        period: float,
        width: int,
        rotations_from: int | None = None,
        max_gap: float = ...,
    ) -> StreamResampler: ...
    def push(
        self, times: NDArray[np.float64], rows: NDArray[np.float64]
    ) -> tuple[
        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], int, bool, list[int]
    ]: ...
    def reset(self) -> None: ...
    @property
    def period(self) -> float: ...
    @property
    def width(self) -> int: ...
    @property
    def emitted(self) -> int: ...
    @property
    def memory_bytes(self) -> int: ...

def segment_channels(
    sos: NDArray[np.float64],
    raw: NDArray[np.float64],
    start: int,
    stop: int,
    features: str,
) -> NDArray[np.float64]: ...

class OnlineFrontEnd:
    def __new__(
        cls,
        sos: NDArray[np.float64],
        arms: Sequence[str],
        features: str,
        singular_angle: float,
        c: float,
        adaptive: bool,
        quantile: float,
        fraction: float,
        slowest: float,
        every: int,
        speed_window: float,
    ) -> OnlineFrontEnd: ...
    def push(
        self,
        times: NDArray[np.float64],
        markers: NDArray[np.float64],
        joints: NDArray[np.float64] | None = None,
        body_frame: NDArray[np.float64] | None = None,
    ) -> tuple[
        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]
    ]: ...
    def push_values(
        self, times: NDArray[np.float64], values: NDArray[np.float64]
    ) -> NDArray[np.float64]: ...
    def finish(self) -> NDArray[np.float64]: ...
    def reset(self) -> None: ...
    @property
    def channels(self) -> int: ...
    @property
    def n_frames(self) -> int: ...
    @property
    def period(self) -> float | None: ...
    @property
    def window_frames(self) -> int | None: ...
    @property
    def memory_bytes(self) -> int: ...

class GifFrames:
    TRANSPARENT: int
    def __new__(cls, width: int, height: int, lut: bytes) -> GifFrames: ...
    def frame(self, pixels: bytes, delay: int) -> tuple[bytes, tuple[int, int, int, int]]: ...
    def frame_arrow(
        self, schema: object, array: object, delay: int
    ) -> tuple[bytes, tuple[int, int, int, int]]: ...
    @property
    def memory_bytes(self) -> int: ...

def rgb_to_yuv420(pixels: bytes, width: int, height: int) -> NDArray[np.uint8]: ...
def rgb_to_yuv420_arrow(
    schema: object, array: object, width: int, height: int
) -> NDArray[np.uint8]: ...

class CovarianceAccumulator:
    def __new__(cls, dim: int | None = None) -> CovarianceAccumulator: ...
    def update(self, x: NDArray[np.float64], *, n_threads: int | None = None) -> None: ...
    def merge(self, other: CovarianceAccumulator) -> None: ...
    @property
    def count(self) -> int: ...
    @property
    def dim(self) -> int | None: ...
    @property
    def mean(self) -> NDArray[np.float64]: ...
    @property
    def scatter(self) -> NDArray[np.float64]: ...
    def covariance(self) -> NDArray[np.float64]: ...
    def __getstate__(self) -> tuple[object, ...]: ...
    def __setstate__(self, state: tuple[object, ...]) -> None: ...

def eigh(
    a: NDArray[np.float64], *, k: int | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

@final
class KMeansResult:
    @property
    def centers(self) -> NDArray[np.float64]: ...
    @property
    def labels(self) -> NDArray[np.int64]: ...
    @property
    def inertia(self) -> float: ...
    @property
    def n_iter(self) -> int: ...

def kmeans(
    x: NDArray[np.float64],
    k: int,
    *,
    n_init: int = 1,
    max_iter: int = 300,
    tol: float = 1e-4,
    seed: int | None = None,
    init: NDArray[np.float64] | None = None,
    n_local_trials: int | None = None,
    n_threads: int | None = None,
) -> KMeansResult: ...
def kmeans_predict(
    x: NDArray[np.float64], centers: NDArray[np.float64], *, n_threads: int | None = None
) -> tuple[NDArray[np.int64], NDArray[np.float64]]: ...
def kmeans_plusplus(
    x: NDArray[np.float64],
    k: int,
    *,
    seed: int | None = None,
    n_local_trials: int | None = None,
    n_threads: int | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]: ...

# --- dtw ---

def dtw_distances(
    queries: NDArray[np.float64],
    query_offsets: NDArray[np.int64],
    references: NDArray[np.float64] | None = None,
    reference_offsets: NDArray[np.int64] | None = None,
    *,
    band: float | None = None,
    normalize: bool = True,
    n_threads: int | None = None,
) -> NDArray[np.float64]: ...
def triangulate_points(
    projections: NDArray[np.float64],
    points: NDArray[np.float64],
    weights: NDArray[np.float64],
    *,
    min_views: int = 2,
) -> NDArray[np.float64]: ...
