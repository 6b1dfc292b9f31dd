"""visprim: movement primitives learned from human motion capture.

Implements and extends Fod, Matarić & Jenkins, "Automated derivation of primitives for
movement classification" / "Visual primitives for imitation learning": arm markers →
shoulder-frame inverse kinematics → filtering → segmentation (SEG-1 / SEG-2) → PCA →
k-means primitives → reconstruction, error analysis, classification and playback on a
simulated humanoid (DART).

Units throughout the API: seconds, metres, radians (degrees only in reports).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from visprim.trial import JOINT_NAMES, MARKER_NAMES, Trial, Truth

__version__ = "0.1.0"

__all__ = ["JOINT_NAMES", "MARKER_NAMES", "PrimitiveModel", "Trial", "Truth", "__version__"]

if TYPE_CHECKING:
    from visprim.model import PrimitiveModel


def __getattr__(name: str) -> Any:
    # The model pulls in the pipeline; keep `import visprim` light.
    if name == "PrimitiveModel":
        from visprim.model import PrimitiveModel

        return PrimitiveModel
    raise AttributeError(f"module 'visprim' has no attribute {name!r}")
