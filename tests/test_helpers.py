"""The one helper of each kind: atomic files (with the umask's mode), leave-one-group-out
folds from scikit-learn, and no import circle between imitate and the side-by-side video."""

from __future__ import annotations

import ast
import os
import stat
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from visprim.atomic import atomic_file, write_text
from visprim.classify import group_folds

ROOT = Path(__file__).resolve().parents[1] / "python" / "visprim"


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_atomic_files_get_the_umask_mode_and_leave_nothing_behind(tmp_path, umask_022):
    out = write_text(tmp_path / "a" / "b.txt", "x")
    assert out.read_text() == "x" and _mode(out) == 0o644
    with pytest.raises(ZeroDivisionError), atomic_file(out) as tmp:
        tmp.write_text("half")
        1 / 0  # noqa: B018
    assert out.read_text() == "x"
    assert sorted(p.name for p in out.parent.iterdir()) == ["b.txt"]


def test_gifs_and_trajectories_are_not_private_files(tmp_path, umask_022):
    from visprim.sim.video import write_video

    frames = [Image.new("RGB", (8, 8), (i * 40, 0, 0)) for i in range(3)]
    gif = write_video(tmp_path / "v.gif", frames, fps=10)
    assert _mode(gif) == 0o644
    pytest.importorskip("dartpy")
    from visprim.sim.export import JointTrajectory

    t = JointTrajectory(("a",), np.array([0.0, 0.1]), np.zeros((2, 1)), np.zeros((2, 1)))
    for path in t.write(tmp_path / "trajectory"):
        assert _mode(path) == 0o644, path


def test_group_folds_are_sklearns_in_first_appearance_order():
    from sklearn.model_selection import LeaveOneGroupOut

    groups = np.array(["b", "a", "b", "c", "a"])
    folds = group_folds(groups)
    assert [g for g, _, _ in folds] == ["b", "a", "c"]
    expected = {
        groups[te[0]]: (tr, te) for tr, te in LeaveOneGroupOut().split(groups, groups, groups)
    }
    for g, train, test in folds:
        np.testing.assert_array_equal(train, expected[g][0])
        np.testing.assert_array_equal(test, np.flatnonzero(groups == g))


def test_the_side_by_side_video_does_not_import_imitate():
    tree = ast.parse((ROOT / "sim" / "sidebyside.py").read_text(encoding="utf-8"))
    imported = {
        node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module
    }
    assert "visprim.imitate" not in imported
