"""The model file: one ``.npz`` archive holding a fitted :class:`~visprim.model.PrimitiveModel`.

Format (``format_version`` 1)
-----------------------------
A NumPy ``.npz`` (zip) archive, read with ``allow_pickle=False``, with these members:

``header``
    uint8 array: UTF-8 JSON object with
    ``format`` = ``"visprim.PrimitiveModel"``, ``format_version`` = 1, ``visprim_version``,
    ``parameters`` (the estimator's constructor arguments), ``fitted`` (scalars: inertia,
    n_iter, seg2_threshold in (rad/s)², n_training_segments, trial_names, training_source),
    ``error_tables`` (Tables 1–3 or null) and ``arrays``: for every array member its shape,
    dtype and SHA-256 of its bytes (damage detection).
``mean`` (d,) radians; ``eigenvalues`` (d,) rad², descending; ``eigenvectors`` (d, d), columns;
``cluster_centers`` (k, f) in the projection space; ``labels`` (N,) int64;
``segment_trial`` (N,) int64; ``segment_starts`` / ``segment_ends`` (N,) seconds;
``primitive_durations`` (k,) seconds; optionally ``training_vectors`` (N, d) radians.

Writing is atomic: the archive goes to a temporary file in the target's folder, is flushed
to disk, then renamed over the target (:func:`os.replace`). Reading refuses another
``format``/``format_version`` and any damaged file (bad zip, missing member, checksum or
shape mismatch) with :class:`ModelFileError`, naming the file.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
import zipfile
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from visprim.model import PrimitiveModel

FORMAT = "visprim.PrimitiveModel"
FORMAT_VERSION = 1

_REQUIRED = (
    "mean",
    "eigenvalues",
    "eigenvectors",
    "cluster_centers",
    "labels",
    "segment_trial",
    "segment_starts",
    "segment_ends",
    "primitive_durations",
)


class ModelFileError(ValueError):
    """A model file is not readable: wrong format or version, or damaged."""


def _digest(a: NDArray[Any]) -> str:
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


def save_model(
    model: PrimitiveModel, path: str | PathLike[str], *, include_vectors: bool = False
) -> Path:
    """Write ``model`` to ``path`` atomically (see the module docstring); returns the path.

    ``include_vectors=True`` also stores the training segment vectors (N × d float64), so
    that :meth:`~visprim.model.PrimitiveModel.error_table` can compute new rows after
    loading.
    """
    import visprim

    model._check_fitted()
    path = Path(path)
    arrays: dict[str, NDArray[Any]] = {
        "mean": np.asarray(model.mean_, dtype=np.float64),
        "eigenvalues": np.asarray(model.eigenvalues_, dtype=np.float64),
        "eigenvectors": np.asarray(model.eigenvectors_, dtype=np.float64),
        "cluster_centers": np.asarray(model.cluster_centers_, dtype=np.float64),
        "labels": np.asarray(model.labels_, dtype=np.int64),
        "segment_trial": np.asarray(model.segment_trial_, dtype=np.int64),
        "segment_starts": np.asarray(model.segment_starts_, dtype=np.float64),
        "segment_ends": np.asarray(model.segment_ends_, dtype=np.float64),
        "primitive_durations": np.asarray(model.primitive_durations_, dtype=np.float64),
    }
    if include_vectors and getattr(model, "training_vectors_", None) is not None:
        arrays["training_vectors"] = np.asarray(model.training_vectors_, dtype=np.float64)
    tables = getattr(model, "error_tables_", None)
    header = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "visprim_version": visprim.__version__,
        "parameters": {k: _jsonable(v) for k, v in model.get_params().items()},
        "fitted": {
            "inertia": float(model.inertia_),
            "n_iter": int(model.n_iter_),
            "seg2_threshold": None
            if model.seg2_threshold_ is None
            else float(model.seg2_threshold_),
            "n_training_segments": int(model.n_training_segments_),
            "arms": list(getattr(model, "arms_", ("right",))),
            "trial_names": [str(n) for n in model.trial_names_],
            "training_source": _jsonable(model.training_source_),
        },
        "error_tables": tables.to_dict() if tables is not None else None,
        "arrays": {
            name: {"shape": list(a.shape), "dtype": a.dtype.str, "sha256": _digest(a)}
            for name, a in arrays.items()
        },
    }
    blob = np.frombuffer(json.dumps(header, indent=1).encode("utf-8"), dtype=np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            savez: Any = np.savez  # (numpy's stub types **kwds as its keyword options)
            savez(fh, header=blob, **arrays)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return path


def _jsonable(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, Path):
        return str(v)
    return v


def read_header(path: str | PathLike[str]) -> dict[str, Any]:
    """The JSON header of a model file (checks format and version only)."""
    with _open(Path(path)) as npz:
        return _header(npz, Path(path))


@contextlib.contextmanager
def _open(path: Path):  # type: ignore[no-untyped-def]
    if not path.exists():
        raise FileNotFoundError(f"model file {path} does not exist")
    try:
        npz = np.load(path, allow_pickle=False)
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise ModelFileError(
            f"{path}: not a visprim model file or damaged (cannot open the archive: {exc})"
        ) from None
    if not isinstance(npz, np.lib.npyio.NpzFile):
        raise ModelFileError(f"{path}: not a visprim model file (a bare .npy array, not .npz)")
    try:
        yield npz
    finally:
        npz.close()


def _member(npz: Any, name: str, path: Path) -> NDArray[Any]:
    if name not in npz.files:
        raise ModelFileError(f"{path}: damaged model file: member {name!r} is missing")
    try:
        return np.asarray(npz[name])
    except (zipfile.BadZipFile, ValueError, OSError, EOFError, KeyError) as exc:
        raise ModelFileError(f"{path}: damaged model file: cannot read {name!r} ({exc})") from None


def _header(npz: Any, path: Path) -> dict[str, Any]:
    raw = _member(npz, "header", path)
    try:
        header = json.loads(raw.astype(np.uint8).tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelFileError(f"{path}: damaged model file: unreadable header ({exc})") from None
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise ModelFileError(
            f"{path}: not a visprim model file (format {header.get('format')!r}, "
            f"expected {FORMAT!r})"
            if isinstance(header, dict)
            else f"{path}: not a visprim model file (header is not a JSON object)"
        )
    version = header.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(
            f"{path}: model file format version {version!r}; this visprim "
            f"({_visprim_version()}) reads version {FORMAT_VERSION} only - re-run `visprim learn`"
        )
    return header


def _visprim_version() -> str:
    import visprim

    return visprim.__version__


def load_model(path: str | PathLike[str]) -> PrimitiveModel:
    """Read a model written by :func:`save_model` (see the module docstring).

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ModelFileError
        Another format or format version, or a damaged file.
    """
    from visprim.errors import ErrorTables
    from visprim.features import n_channels
    from visprim.model import PrimitiveModel

    path = Path(path)
    with _open(path) as npz:
        header = _header(npz, path)
        try:
            specs = dict(header["arrays"])
            params = dict(header["parameters"])
            fitted = dict(header["fitted"])
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{path}: damaged model file: header lacks {exc}") from None
        arrays: dict[str, NDArray[Any]] = {}
        for name in (*_REQUIRED, "training_vectors"):
            if name not in specs:
                if name == "training_vectors":
                    continue
                raise ModelFileError(f"{path}: damaged model file: header lists no {name!r}")
            a = _member(npz, name, path)
            spec = specs[name]
            if list(a.shape) != list(spec.get("shape", [])) or a.dtype.str != spec.get("dtype"):
                raise ModelFileError(
                    f"{path}: damaged model file: {name!r} has shape {a.shape} dtype "
                    f"{a.dtype.str}, header says {spec.get('shape')} {spec.get('dtype')}"
                )
            if _digest(a) != spec.get("sha256"):
                raise ModelFileError(f"{path}: damaged model file: checksum mismatch in {name!r}")
            arrays[name] = a
    # Files from before the bone-direction features were learned with the paper's method.
    params.setdefault("features", "zyz")
    params.setdefault("seg2_tuning", "repetitions")
    params.setdefault("seg1_adaptive", False)
    arms = fitted.get("arms", ["right"])
    if not isinstance(arms, list) or not arms or any(a not in ("right", "left") for a in arms):
        raise ModelFileError(f"{path}: damaged model file: arms {arms!r} are not arm names")
    try:
        model = PrimitiveModel(**params)
        channels = n_channels(str(params["features"]), len(arms))
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"{path}: model parameters not understood: {exc}") from None
    d, k, n = arrays["mean"].shape[0], arrays["cluster_centers"].shape[0], arrays["labels"].shape[0]
    f = arrays["cluster_centers"].shape[1] if arrays["cluster_centers"].ndim == 2 else -1
    consistent = (
        arrays["eigenvalues"].shape == (d,)
        and arrays["eigenvectors"].shape == (d, d)
        and d == channels * int(params.get("n_samples", -1))
        and f == int(params.get("n_components", -2))
        and arrays["primitive_durations"].shape == (k,)
        and all(
            arrays[a].shape == (n,) for a in ("segment_trial", "segment_starts", "segment_ends")
        )
    )
    if not consistent:
        raise ModelFileError(f"{path}: damaged model file: array shapes are inconsistent")
    model.mean_ = arrays["mean"]
    model.eigenvalues_ = arrays["eigenvalues"]
    model.eigenvectors_ = arrays["eigenvectors"]
    model.cluster_centers_ = arrays["cluster_centers"]
    model.labels_ = arrays["labels"]
    model.segment_trial_ = arrays["segment_trial"]
    model.segment_starts_ = arrays["segment_starts"]
    model.segment_ends_ = arrays["segment_ends"]
    model.primitive_durations_ = arrays["primitive_durations"]
    model.training_vectors_ = arrays.get("training_vectors")
    model.training_projections_ = None
    model.inertia_ = float(fitted.get("inertia", float("nan")))
    model.n_iter_ = int(fitted.get("n_iter", 0))
    thr = fitted.get("seg2_threshold")
    model.seg2_threshold_ = None if thr is None else float(thr)
    model.n_training_segments_ = int(fitted.get("n_training_segments") or n)
    model.arms_ = tuple(arms)
    model.trial_names_ = list(fitted.get("trial_names", []))
    model.training_source_ = dict(fitted.get("training_source") or {})
    tables = header.get("error_tables")
    model.error_tables_ = ErrorTables.from_dict(tables) if tables else None
    return model
