"""Hypothesis over the model file's header: any change to any field, of any JSON type,
with the header checksum kept stale or recomputed (a deliberate forgery), must load as a
valid model or raise :class:`~visprim.modelfile.ModelFileError` — never another exception.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from visprim import PrimitiveModel
from visprim.modelfile import ModelFileError, write_model_file

JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=6),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=8,
)


def _tiny_model_file(path: Path) -> Path:
    """A valid model file with d = 8 (n_samples 2), f = 2, k = 2, N = 5 segments."""
    rng = np.random.default_rng(0)
    params = PrimitiveModel(n_samples=2, n_components=2, n_clusters=2, features="zyz").get_params()
    arrays = {
        "mean": rng.normal(size=8),
        "eigenvalues": np.sort(rng.random(8))[::-1],
        "eigenvectors": np.linalg.qr(rng.normal(size=(8, 8)))[0],
        "cluster_centers": rng.normal(size=(2, 2)),
        "labels": np.array([0, 1, 0, 1, 1]),
        "segment_trial": np.array([0, 0, 1, 1, 1]),
        "segment_starts": np.array([0.0, 0.5, 0.0, 0.4, 0.9]),
        "segment_ends": np.array([0.5, 1.0, 0.4, 0.9, 1.5]),
        "primitive_durations": np.array([0.45, 0.5]),
        "training_vectors": rng.normal(size=(5, 8)),
    }
    header = {
        "parameters": params,
        "fitted": {
            "inertia": 1.5,
            "n_iter": 3,
            "seg2_threshold": 2.0,
            "n_training_segments": 5,
            "trial_names": ["a", "b"],
            "provenance": {"kind": "arrays", "frame_period": None},
        },
        "error_tables": None,
    }
    return write_model_file(path, header, arrays)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("modelfuzz")


@pytest.fixture(scope="module")
def members(folder: Path) -> dict[str, bytes]:
    path = _tiny_model_file(folder / "tiny.npz")
    with np.load(path) as npz:
        return {k: npz[k] for k in npz.files}


def test_the_tiny_model_loads(folder: Path, members: dict[str, Any]) -> None:
    m = PrimitiveModel.load(folder / "tiny.npz")
    assert m.transform(np.zeros((3, 8))).shape == (3, 2)
    assert m.error_table(k_values=(2,)).clustering.rows[0][0] == 2


def _paths(header: dict[str, Any]) -> list[tuple[str, ...]]:
    """Every key path of the header (objects only), the header itself included."""
    out: list[tuple[str, ...]] = [()]
    stack: list[tuple[tuple[str, ...], Any]] = [((), header)]
    while stack:
        prefix, node = stack.pop()
        if isinstance(node, dict):
            for k, v in node.items():
                out.append((*prefix, k))
                stack.append(((*prefix, k), v))
    return out


def _write(path: Path, members: dict[str, Any], header: Any, reseal: bool) -> None:
    if reseal and isinstance(header, dict):
        body = {k: v for k, v in header.items() if k != "header_sha256"}
        canonical = json.dumps(body, sort_keys=True, separators=(",", ":")).encode()
        header["header_sha256"] = hashlib.sha256(canonical).hexdigest()
    blob = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    np.savez(path, **{**members, "header": blob})


def _load_or_refuse(path: Path) -> str:
    try:
        model = PrimitiveModel.load(path)
    except ModelFileError as exc:
        assert str(exc).startswith(str(path)), exc
        return "refused"
    # What loads must be a usable model.
    assert model.transform(np.zeros((1, model.dim))).shape == (1, int(model.n_components))
    return "loaded"


#: Examples per property (raise it for a longer run: VISPRIM_FUZZ_EXAMPLES=2000).
EXAMPLES = int(os.environ.get("VISPRIM_FUZZ_EXAMPLES", "200"))
_FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)


@_FUZZ
@given(data=st.data(), value=JSON, reseal=st.booleans(), delete=st.booleans())
def test_any_header_field_set_to_any_json(
    folder: Path,
    members: dict[str, Any],
    data: st.DataObject,
    value: Any,
    reseal: bool,
    delete: bool,
) -> None:
    original = json.loads(members["header"].tobytes())
    header = json.loads(members["header"].tobytes())
    where = data.draw(st.sampled_from(_paths(header)))
    if not where:
        header = value
    else:
        node = header
        for key in where[:-1]:
            node = node[key]
        if delete:
            del node[where[-1]]
        else:
            node[where[-1]] = value
    path = folder / "fuzz.npz"
    _write(path, members, header, reseal)
    outcome = _load_or_refuse(path)
    if not reseal and header != original:
        assert outcome == "refused"  # the checksum covers every field


@_FUZZ
@given(raw=st.binary(max_size=200))
def test_header_bytes_that_are_not_json(folder: Path, members: dict[str, Any], raw: bytes) -> None:
    path = folder / "raw.npz"
    np.savez(path, **{**members, "header": np.frombuffer(raw, dtype=np.uint8)})
    assert _load_or_refuse(path) == "refused"


@settings(
    max_examples=max(EXAMPLES // 4, 10),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(depth=st.integers(100, 200_000), bracket=st.sampled_from(["[", '{"a":']))
def test_deeply_nested_headers(
    folder: Path, members: dict[str, Any], depth: int, bracket: str
) -> None:
    close = "]" if bracket == "[" else "}"
    path = folder / "deep.npz"
    raw = (bracket * depth + "1" + close * depth).encode()
    np.savez(path, **{**members, "header": np.frombuffer(raw, dtype=np.uint8)})
    assert _load_or_refuse(path) == "refused"
