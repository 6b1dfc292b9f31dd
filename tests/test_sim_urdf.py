"""Adonis as URDF: loads back through dartpy with the same links, DOF, masses and inertias,
and the trajectory export puts the URDF's bodies where the DART model's are."""

from __future__ import annotations

import json

import dartpy as dart
import numpy as np
import pytest
from visprim.sim.export import arm_trajectory
from visprim.sim.model import build_adonis
from visprim.sim.sequencer import angles_to_positions
from visprim.sim.urdf import SPLIT_LINK_MASS, mass_table, urdf_joint_names, write_urdf


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    path = write_urdf(tmp_path_factory.mktemp("urdf") / "adonis.urdf")
    skel = dart.utils.DartLoader().parseSkeleton(str(path.resolve()))
    assert skel is not None
    return skel


def test_same_links_dof_masses_and_inertias(loaded) -> None:
    _, model = build_adonis()
    ours, theirs = mass_table(model), mass_table(loaded)
    assert loaded.getNumDofs() == model.getNumDofs() == 20
    assert set(ours) <= set(theirs)
    extra = set(theirs) - set(ours)
    assert all(name.endswith(("_link1", "_link2")) for name in extra)
    assert all(theirs[name][0] == pytest.approx(SPLIT_LINK_MASS) for name in extra)
    for name, (mass, com, moment) in ours.items():
        assert abs(theirs[name][0] - mass) <= 1e-9, name
        np.testing.assert_allclose(theirs[name][1], com, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(theirs[name][2], moment, atol=1e-12, err_msg=name)
    moving = [loaded.getJoint(i) for i in range(loaded.getNumJoints())]
    assert sorted(j.getName() for j in moving if j.getNumDofs()) == sorted(urdf_joint_names())


def test_exported_positions_put_the_urdf_bodies_where_dart_has_them(loaded) -> None:
    _, model = build_adonis()
    rng = np.random.default_rng(0)
    n = 6
    angles = np.column_stack(
        [
            rng.uniform(-3, 3, n),
            rng.uniform(0.05, 3.0, n),
            rng.uniform(-3, 3, n),
            rng.uniform(0, 2.5, n),
        ]
    )
    traj = arm_trajectory(np.arange(n) * 0.1, angles, np.zeros_like(angles))
    for i in range(n):
        model.setPositions(angles_to_positions(model, angles[i : i + 1])[0])
        for j, name in enumerate(traj.joint_names):
            loaded.getJoint(name).setPosition(0, traj.positions[i, j])
        for body in ("r_upper_arm", "r_forearm", "r_hand", "torso", "l_hand"):
            a = model.getBodyNode(body).getWorldTransform().matrix()
            b = loaded.getBodyNode(body).getWorldTransform().matrix()
            np.testing.assert_allclose(a, b, atol=1e-9, err_msg=body)


def test_trajectory_layout_and_velocities(tmp_path) -> None:
    t = np.linspace(0.0, 1.0, 201)
    angles = np.column_stack([0.3 * t, 0.5 + 0.8 * t**2, np.sin(t), 1.0 + 0.5 * np.sin(3 * t)])
    rates = np.column_stack([0.3 + 0 * t, 1.6 * t, np.cos(t), 1.5 * np.cos(3 * t)])
    traj = arm_trajectory(t + 5.0, angles, rates, "test")
    js, cs = traj.write(tmp_path / "sub" / "move")
    doc = json.loads(js.read_text())
    names = doc["joint_names"]
    assert names == urdf_joint_names() and len(names) == 20
    assert len(doc["points"]) == t.size
    p = doc["points"][3]
    assert len(p["positions"]) == len(p["velocities"]) == 20
    assert p["time_from_start"] == {"sec": 0, "nanosec": 15_000_000}
    assert doc["points"][-1]["time_from_start"] == {"sec": 1, "nanosec": 0}
    header = cs.read_text().splitlines()[0].split(",")
    assert header[0] == "time_from_start_s"
    assert header[1:21] == [f"position:{n}" for n in names]
    assert header[21:] == [f"velocity:{n}" for n in names]
    # Velocities agree with the time derivative of the exported positions.
    fd = np.gradient(traj.positions, traj.times, axis=0)
    np.testing.assert_allclose(traj.velocities[5:-5], fd[5:-5], atol=2e-3)
    assert np.abs(traj.velocities).max() > 0.5  # not trivially zero


def test_write_urdf_refuses_other_extensions(tmp_path) -> None:
    with pytest.raises(ValueError, match=r"\.urdf"):
        write_urdf(tmp_path / "adonis.xml")
    assert not list(tmp_path.iterdir())
