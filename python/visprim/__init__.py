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


def _version() -> str:
    """The installed distribution's version; in a source tree, Cargo.toml's (the one place
    the version is written; maturin gives it to the wheel)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("visprim")
    except PackageNotFoundError:
        import tomllib
        from pathlib import Path

        cargo = Path(__file__).resolve().parents[2] / "Cargo.toml"
        try:
            return str(tomllib.loads(cargo.read_text(encoding="utf-8"))["package"]["version"])
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "0+unknown"


__version__: str = _version()

__all__ = ["JOINT_NAMES", "MARKER_NAMES", "PrimitiveModel", "Trial", "Truth", "__version__"]

if TYPE_CHECKING:
    from visprim.model import PrimitiveModel


def __getattr__(name: str) -> Any:
    # The model pulls in the pipeline; keep `import visprim` light.
    if name == "PrimitiveModel":
        from visprim.model import PrimitiveModel

        return PrimitiveModel
    raise AttributeError(f"module 'visprim' has no attribute {name!r}")
