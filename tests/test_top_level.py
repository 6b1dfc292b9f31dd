"""The names users expect at the top level, loaded lazily so that ``import visprim`` stays
light."""

from __future__ import annotations

import subprocess
import sys

import pytest


def test_the_top_level_names_are_the_librarys():
    import visprim
    from visprim import DTWClassifier, MotionClassifier, PrimitiveModel, read, read_many
    from visprim.classify import DTWClassifier as D
    from visprim.classify import MotionClassifier as M
    from visprim.io import read as r
    from visprim.io import read_many as rm
    from visprim.model import PrimitiveModel as P

    assert (PrimitiveModel, MotionClassifier, DTWClassifier, read, read_many) == (P, M, D, r, rm)
    assert set(visprim.__all__) <= set(dir(visprim))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        visprim.nope  # noqa: B018


def test_importing_visprim_loads_no_heavy_dependency():
    code = (
        "import sys, visprim; "
        "print(','.join(sorted({m.split('.')[0] for m in sys.modules} & "
        "{'sklearn', 'scipy', 'matplotlib', 'dartpy', 'mujoco', 'dask', 'PIL'})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == ""


def test_the_old_markers_csv_alias_is_gone():
    with pytest.raises(ModuleNotFoundError):
        import visprim.markers_csv  # noqa: F401
