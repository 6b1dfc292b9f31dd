"""Type stubs of the compiled extension visprim._visprim (see visprim.kernels)."""

import numpy as np
from numpy.typing import NDArray

# --- signal kernels (filter, zvc, resample) ---

# --- linalg kernels (covariance, eigh, kmeans) ---
