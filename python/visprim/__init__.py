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

#: Names loaded on first use (module that defines each): ``import visprim`` stays light
#: (numpy only), and ``from visprim import PrimitiveModel`` loads the pipeline then.
_LAZY: dict[str, str] = {
    "PrimitiveModel": "visprim.model",
    "MotionClassifier": "visprim.classify",
    "DTWClassifier": "visprim.classify",
    "read": "visprim.io",
    "read_many": "visprim.io",
}

__all__ = [
    "JOINT_NAMES",
    "MARKER_NAMES",
    "DTWClassifier",
    "MotionClassifier",
    "PrimitiveModel",
    "Trial",
    "Truth",
    "__version__",
    "read",
    "read_many",
]

if TYPE_CHECKING:
    from visprim.classify import DTWClassifier, MotionClassifier
    from visprim.io import read, read_many
    from visprim.model import PrimitiveModel


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'visprim' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
