"""The model file: one ``.npz`` archive holding a fitted model's arrays and a JSON header.

This module is the file layer only: it writes and reads plain arrays and a header, checked;
:class:`~visprim.model.PrimitiveModel` builds those from itself (``save``) and itself from
them (``load``). It does not import the model.

Format (``format_version`` 2)
-----------------------------
A NumPy ``.npz`` (zip) archive of ``.npy`` members (never pickles), with these members:

``header``
    uint8 array: UTF-8 JSON object with ``format`` = ``"visprim.PrimitiveModel"``,
    ``format_version`` = 2, ``visprim_version``, ``parameters`` (the estimator's constructor
    arguments), ``fitted`` (the fields of :data:`FITTED_FIELDS`: inertia,
    n_iter, seg2_threshold in (rad/s)², n_training_segments, trial_names, arms, counts of
    trials without segments and of short trials, and the provenance record of
    :class:`~visprim.provenance.Provenance`; older files' ``training_source`` is read as
    the provenance), ``error_tables`` (Tables 1–3 or null), ``arrays`` (for
    every array member its shape, dtype and SHA-256 of its bytes) and ``header_sha256``: the
    SHA-256 of the rest of the header as canonical JSON (sorted keys, no spaces). Every byte
    that matters is therefore checksummed: the header directly, the arrays through it.

``mean`` (d,) radians; ``eigenvalues`` (d,) rad², descending; ``eigenvectors`` (d, m), columns
(m = d, or fewer for a model fitted from N ≤ d segments; at least the model's f);
``cluster_centers`` (k, f) in the projection space; ``labels`` (N,) int64;
``segment_trial`` (N,) int64; ``segment_starts`` / ``segment_ends`` (N,) seconds;
``primitive_durations`` (k,) seconds; ``training_vectors`` (N, d) radians (written by
default, so that a loaded model computes error tables like a fitted one);
``eigen_movements_mean`` (6 n,) and ``eigen_movements_components`` (6 n, g), both or
neither: the eigen-movements of the training movements (one arm's two unit bone directions
at n instants over each movement's own duration, flattened instant by instant; the mean
movement, and g ≥ 1 orthonormal components; written by ``visprim learn``,
:func:`visprim.rate.budget.learn_eigen_movements`, and read for ``visprim imitate
--budget``). Files without them load as before; a reader older than them refuses files that
have them (unknown array).

Writing is atomic (:func:`visprim.atomic.atomic_file`): the archive goes to a temporary
file ``.<name>.visprim-tmp-<pid>-<random>.tmp`` in the target's folder, is flushed to disk,
given the mode a new file gets under the umask, then renamed over the target
(:func:`os.replace`). Temporary files left by a writer that was killed (its process no
longer exists) are removed by the next save to the same target.

Reading refuses another ``format``/``format_version`` and any damaged file (bad zip,
missing member, a header of the wrong structure, checksum or shape mismatch) with
:class:`ModelFileError` naming the file; array sizes are checked against the zip member
before anything is allocated.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import stat
import zipfile
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from visprim.atomic import atomic_file

FORMAT = "visprim.PrimitiveModel"
FORMAT_VERSION = 2
#: Array members every model file has (``training_vectors`` is optional).
REQUIRED_ARRAYS = (
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
OPTIONAL_ARRAYS = ("training_vectors", "eigen_movements_mean", "eigen_movements_components")
#: The eigen-movements' arrays: both or neither (files written before them have neither).
EIGEN_ARRAYS = ("eigen_movements_mean", "eigen_movements_components")
#: Coordinates of one arm's two unit bone directions per instant of an eigen-movement.
EIGEN_CHANNELS = 6
#: Most instants an eigen-movement may have (the model writes 160).
MAX_EIGEN_SAMPLES = 10_000
#: How far the eigen-movements' columns may be from orthonormal (the largest entry of
#: EᵀE − I, in absolute value).
EIGEN_ORTHONORMAL_TOL = 1e-6
#: dtypes the arrays may have (little-endian float64 / int64).
_DTYPES = {"<f8", "<i8"}
#: Largest header accepted (bytes); real headers are a few kB (plus trial names).
MAX_HEADER_BYTES = 64 * 2**20
#: Largest model file accepted (bytes): the training vectors of 500,000 segments of 1,200
#: dimensions fit.
MAX_MODEL_BYTES = 8 * 2**30


class ModelFileError(ValueError):
    """A model file is not readable: wrong format or version, or damaged."""


@dataclass
class ModelFileContents:
    """What a model file holds: its checked header and arrays."""

    path: Path
    header: dict[str, Any]
    arrays: dict[str, NDArray[Any]]

    @property
    def parameters(self) -> dict[str, Any]:
        """The estimator's constructor arguments."""
        return dict(self.header["parameters"])

    @property
    def fitted(self) -> dict[str, Any]:
        """Fitted scalars (inertia, n_iter, seg2_threshold, ...)."""
        return dict(self.header["fitted"])

    @property
    def error_tables(self) -> dict[str, Any] | None:
        """Tables 1–3 as saved (:meth:`visprim.accuracy.ErrorTables.to_dict`), or None."""
        tables = self.header.get("error_tables")
        return dict(tables) if tables is not None else None


def _digest(a: NDArray[Any]) -> str:
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


def _canonical(header: Mapping[str, Any]) -> bytes:
    body = {k: v for k, v in header.items() if k != "header_sha256"}
    return json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=True).encode()


def jsonable(v: Any) -> Any:
    """``v`` with numpy scalars, tuples and paths turned into JSON types."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, Path):
        return str(v)
    return v


def write_model_file(
    path: str | PathLike[str], header: Mapping[str, Any], arrays: Mapping[str, NDArray[Any]]
) -> Path:
    """Write ``arrays`` and ``header`` (the model's ``parameters``, ``fitted`` scalars and
    ``error_tables``) to ``path`` atomically (see the module docstring); returns the path.

    ``format``, ``format_version``, ``visprim_version``, ``arrays`` and ``header_sha256``
    are filled in here.
    """
    from visprim import __version__

    path = Path(path)
    missing = [n for n in REQUIRED_ARRAYS if n not in arrays]
    if missing:
        raise ValueError(f"write_model_file: arrays missing {', '.join(missing)}")
    unknown = set(arrays) - set(REQUIRED_ARRAYS) - set(OPTIONAL_ARRAYS)
    if unknown:
        raise ValueError(f"write_model_file: unknown arrays {', '.join(sorted(unknown))}")
    members = {
        name: np.ascontiguousarray(
            a, dtype=np.int64 if np.asarray(a).dtype.kind in "iu" else np.float64
        )
        for name, a in arrays.items()
    }
    full: dict[str, Any] = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "visprim_version": __version__,
        **{k: jsonable(v) for k, v in header.items()},
        "arrays": {
            name: {"shape": list(a.shape), "dtype": a.dtype.str, "sha256": _digest(a)}
            for name, a in members.items()
        },
    }
    full["header_sha256"] = hashlib.sha256(_canonical(full)).hexdigest()
    blob = np.frombuffer(json.dumps(full, indent=1).encode("utf-8"), dtype=np.uint8)
    with atomic_file(path, suffix=".tmp") as tmp, open(tmp, "xb") as fh:
        savez: Any = np.savez  # (numpy's stub types **kwds as its keyword options)
        savez(fh, header=blob, **members)
    return path


def save_model(model: Any, path: str | PathLike[str], *, include_vectors: bool = True) -> Path:
    """``model.save(path, include_vectors=...)``; returns the path (kept for callers that
    hold a model and a path)."""
    model.save(path, include_vectors=include_vectors)
    return Path(path)


# ---------------------------------------------------------------------------- reading


def _fail(path: Path, why: str) -> ModelFileError:
    return ModelFileError(f"{path}: {why}")


def _npy_header(zf: zipfile.ZipFile, member: str, path: Path) -> tuple[tuple[int, ...], str, int]:
    """(shape, dtype str, data offset) of a ``.npy`` member, read from its own header."""
    with zf.open(member) as fh:
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise _fail(path, f"damaged model file: {member} has .npy version {version}")
        offset = fh.tell()
    if fortran or dtype.hasobject:
        raise _fail(path, f"damaged model file: {member} is not a plain C-order array")
    return tuple(int(s) for s in shape), dtype.str, offset


def _read_array(
    zf: zipfile.ZipFile, name: str, spec: Mapping[str, Any], path: Path
) -> NDArray[Any]:
    member = name + ".npy"
    try:
        info = zf.getinfo(member)
    except KeyError:
        raise _fail(path, f"damaged model file: member {name!r} is missing") from None
    shape, dtype, offset = _npy_header(zf, member, path)
    if list(shape) != spec["shape"] or dtype != spec["dtype"]:
        raise _fail(
            path,
            f"damaged model file: {name!r} has shape {shape} dtype {dtype}, header says "
            f"{tuple(spec['shape'])} {spec['dtype']}",
        )
    size = math.prod(shape) * np.dtype(dtype).itemsize
    if offset + size != info.file_size:
        raise _fail(
            path,
            f"damaged model file: {name!r} holds {info.file_size - offset} "
            f"bytes, its shape needs {size}",
        )
    with zf.open(member) as fh:
        fh.seek(offset)
        data = fh.read(size)
    if len(data) != size:
        raise _fail(path, f"damaged model file: {name!r} is cut short")
    if hashlib.sha256(data).hexdigest() != spec["sha256"]:
        raise _fail(path, f"damaged model file: checksum mismatch in {name!r}")
    return np.frombuffer(data, dtype=dtype).reshape(shape).copy()


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _finite(v: Any) -> bool:
    return _is_number(v) and math.isfinite(v)


def _count(v: Any) -> bool:
    return _is_int(v) and v >= 0


#: The fitted scalars of the header's ``fitted`` object: name -> (check, what it must be).
#: The model keeps each as its attribute ``name + "_"`` (``provenance`` as a
#: :class:`~visprim.provenance.Provenance`, checked further when the model is built).
FITTED_FIELDS: dict[str, tuple[Any, str]] = {
    "inertia": (lambda v: _finite(v) and v >= 0, "a finite number >= 0"),
    "n_iter": (_count, "an integer >= 0"),
    "seg2_threshold": (
        lambda v: v is None or (_finite(v) and v > 0),
        "a finite number > 0 or null",
    ),
    "n_training_segments": (_count, "an integer >= 0"),
    "trial_names": (
        lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v),
        "a list of strings",
    ),
    "arms": (
        lambda v: (
            isinstance(v, list) and v in (["right"], ["left"], ["right", "left"], ["left", "right"])
        ),
        "a list of one or two arms ('right', 'left')",
    ),
    "n_trials_without_segments": (_count, "an integer >= 0"),
    "n_short_trials": (_count, "an integer >= 0"),
    "provenance": (lambda v: isinstance(v, dict), "an object"),
}
#: Fitted fields that files written by older versions may lack, and what their absence means.
OLDER_FITTED: dict[str, Any] = {
    "arms": ["right"],
    "n_trials_without_segments": 0,
    "n_short_trials": 0,
}


def _check_structure(header: Any, path: Path) -> dict[str, Any]:
    """Types of every header field this module and the model rely on."""
    if not isinstance(header, dict):
        raise _fail(path, "not a visprim model file (header is not a JSON object)")
    if header.get("format") != FORMAT:
        raise _fail(
            path, f"not a visprim model file (format {header.get('format')!r}, expected {FORMAT!r})"
        )
    version = header.get("format_version")
    if version != FORMAT_VERSION:
        from visprim import __version__

        raise _fail(
            path,
            f"model file format version {version!r}; this visprim ({__version__}) reads "
            f"version {FORMAT_VERSION} only - re-run `visprim learn`",
        )

    def bad(field: str, expected: str) -> ModelFileError:
        return _fail(path, f"damaged model file: header field {field} is not {expected}")

    if not isinstance(header.get("header_sha256"), str):
        raise bad("header_sha256", "a string")
    if hashlib.sha256(_canonical(header)).hexdigest() != header["header_sha256"]:
        raise _fail(path, "damaged model file: checksum mismatch in the header")
    if not isinstance(header.get("parameters"), dict):
        raise bad("parameters", "an object")
    fitted = header.get("fitted")
    if not isinstance(fitted, dict):
        raise bad("fitted", "an object")
    if "provenance" not in fitted and "training_source" in fitted:  # an older file
        fitted["provenance"] = fitted.pop("training_source")
    for key, value in OLDER_FITTED.items():
        fitted.setdefault(key, value)
    for key, (ok, expected) in FITTED_FIELDS.items():
        if key not in fitted or not ok(fitted[key]):
            raise bad(f"fitted.{key}", expected)
    unknown = sorted(set(fitted) - set(FITTED_FIELDS))
    if unknown:
        raise _fail(path, f"damaged model file: unknown fitted field(s) {', '.join(unknown)}")
    if not isinstance(header.get("error_tables"), (dict, type(None))):
        raise bad("error_tables", "an object or null")
    specs = header.get("arrays")
    if not isinstance(specs, dict):
        raise bad("arrays", "an object")
    for name in REQUIRED_ARRAYS:
        if name not in specs:
            raise _fail(path, f"damaged model file: header lists no {name!r}")
    for name, spec in specs.items():
        if name not in REQUIRED_ARRAYS and name not in OPTIONAL_ARRAYS:
            raise _fail(path, f"damaged model file: unknown array {name!r}")
        if (
            not isinstance(spec, dict)
            or not isinstance(spec.get("shape"), list)
            or not all(_is_int(s) and s >= 0 for s in spec["shape"])
            or len(spec["shape"]) > 2
            or not isinstance(spec.get("dtype"), str)
            or spec["dtype"] not in _DTYPES
            or not isinstance(spec.get("sha256"), str)
        ):
            raise bad(f"arrays.{name}", "{shape: [int, ...], dtype: '<f8'|'<i8', sha256: str}")
    return header


def _read_header(zf: zipfile.ZipFile, path: Path) -> dict[str, Any]:
    try:
        info = zf.getinfo("header.npy")
    except KeyError:
        raise _fail(path, "damaged model file: member 'header' is missing") from None
    if info.file_size > MAX_HEADER_BYTES:
        raise _fail(path, f"damaged model file: the header is {info.file_size} bytes")
    shape, dtype, offset = _npy_header(zf, "header.npy", path)
    if len(shape) != 1 or dtype not in ("|u1", "<u1") or offset + shape[0] != info.file_size:
        raise _fail(path, "damaged model file: the header is not a byte array")
    with zf.open("header.npy") as fh:
        fh.seek(offset)
        raw = fh.read(shape[0])
    try:
        header = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        why = "nested too deeply" if isinstance(exc, RecursionError) else str(exc)
        raise _fail(path, f"damaged model file: unreadable header ({why})") from None
    return _check_structure(header, path)


@contextlib.contextmanager
def _open(path: Path):  # type: ignore[no-untyped-def]
    if not path.exists():
        raise FileNotFoundError(f"model file {path} does not exist")
    try:
        info = path.stat()
    except OSError as exc:
        raise _fail(path, f"cannot read the model file ({exc.strerror or exc})") from None
    if not stat.S_ISREG(info.st_mode):
        raise _fail(path, "not a regular file (a device, pipe or folder), not a model file")
    if info.st_size > MAX_MODEL_BYTES:
        raise _fail(
            path,
            f"{info.st_size} bytes, larger than a model file may be "
            f"({MAX_MODEL_BYTES // 2**30} GiB)",
        )
    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise _fail(
            path, f"not a visprim model file or damaged (cannot open the archive: {exc})"
        ) from None
    try:
        yield zf
    except (
        zipfile.BadZipFile,
        zlib.error,
        NotImplementedError,
        OSError,
        EOFError,
        ValueError,
        KeyError,
    ) as exc:
        if isinstance(exc, ModelFileError):
            raise
        raise _fail(path, f"damaged model file ({type(exc).__name__}: {exc})") from None
    finally:
        zf.close()


def read_header(path: str | PathLike[str]) -> dict[str, Any]:
    """The checked JSON header of a model file (arrays are not read)."""
    path = Path(path)
    with _open(path) as zf:
        return _read_header(zf, path)


def load_model(path: str | PathLike[str]) -> ModelFileContents:
    """Read and check a model file (see the module docstring): header and arrays.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ModelFileError
        Another format or format version, or a damaged file.
    """
    path = Path(path)
    with _open(path) as zf:
        header = _read_header(zf, path)
        specs = header["arrays"]
        arrays = {name: _read_array(zf, name, spec, path) for name, spec in specs.items()}
    check_shapes(path, arrays)
    return ModelFileContents(path=path, header=header, arrays=arrays)


def check_shapes(path: Path, arrays: Mapping[str, NDArray[Any]]) -> None:
    """The arrays agree with each other: d from ``mean``, k and f from ``cluster_centers``,
    N from ``labels``; labels index the centres. (Whether d and f fit the parameters is the
    model's to check.)"""
    mean, centres, labels = arrays["mean"], arrays["cluster_centers"], arrays["labels"]
    if mean.ndim != 1 or centres.ndim != 2 or labels.ndim != 1:
        raise _fail(path, "damaged model file: array shapes are inconsistent")
    d, k, n = mean.shape[0], centres.shape[0], labels.shape[0]
    vectors = arrays.get("training_vectors")
    consistent = (
        arrays["eigenvalues"].shape == (d,)
        and arrays["eigenvectors"].ndim == 2
        and arrays["eigenvectors"].shape[0] == d
        and centres.shape[1] <= arrays["eigenvectors"].shape[1] <= d
        and arrays["primitive_durations"].shape == (k,)
        and all(
            arrays[a].shape == (n,) for a in ("segment_trial", "segment_starts", "segment_ends")
        )
        and (vectors is None or vectors.shape == (n, d))
        and (n == 0 or (labels.min() >= 0 and labels.max() < k))
        # Trial indices, or -1 throughout for a model fitted on bare vectors.
        and (
            n == 0
            or arrays["segment_trial"].min() >= 0
            or bool(np.all(arrays["segment_trial"] == -1))
        )
    )
    if not consistent:
        raise _fail(path, "damaged model file: array shapes are inconsistent")
    for name in ("mean", "eigenvalues", "eigenvectors", "cluster_centers"):
        if not np.all(np.isfinite(arrays[name])):
            raise _fail(path, f"damaged model file: {name!r} holds NaN or infinity")
    check_eigen_movements(path, arrays)


def check_eigen_movements(path: Path, arrays: Mapping[str, NDArray[Any]]) -> None:
    """The eigen-movements, if the file has them (:data:`EIGEN_ARRAYS`, both or neither):
    a mean of 6 n finite bone-direction coordinates in [−1, 1] for 2 ≤ n ≤
    :data:`MAX_EIGEN_SAMPLES` instants, and (6 n, g) components, 1 ≤ g ≤ 6 n, finite and
    orthonormal (within :data:`EIGEN_ORTHONORMAL_TOL`)."""
    present = [name for name in EIGEN_ARRAYS if name in arrays]
    if not present:
        return
    if len(present) != len(EIGEN_ARRAYS):
        raise _fail(path, f"damaged model file: {present[0]!r} without its companion")

    def bad(why: str) -> ModelFileError:
        return _fail(path, f"damaged model file: the eigen-movements {why}")

    mean, comps = arrays["eigen_movements_mean"], arrays["eigen_movements_components"]
    if mean.dtype.kind != "f" or comps.dtype.kind != "f":
        raise bad("are not floating-point arrays")
    size = mean.shape[0] if mean.ndim == 1 else 0
    n = size // EIGEN_CHANNELS
    if mean.ndim != 1 or size % EIGEN_CHANNELS or not 2 <= n <= MAX_EIGEN_SAMPLES:
        raise bad(
            f"mean has shape {mean.shape}, not ({EIGEN_CHANNELS} n,) for 2 <= n <= "
            f"{MAX_EIGEN_SAMPLES} instants"
        )
    if comps.ndim != 2 or comps.shape[0] != size or not 1 <= comps.shape[1] <= size:
        raise bad(f"components have shape {comps.shape}, not ({size}, 1..{size})")
    if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(comps))):
        raise bad("hold NaN or infinity")
    if np.max(np.abs(mean)) > 1.0 + 1e-9:
        raise bad("mean is not bone directions (a coordinate beyond [-1, 1])")
    gram = comps.T @ comps
    if np.max(np.abs(gram - np.eye(gram.shape[0]))) > EIGEN_ORTHONORMAL_TOL:
        raise bad("components are not orthonormal")
