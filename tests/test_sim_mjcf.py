"""Adonis as MJCF: loads in MuJoCo with the DART model's DOF, joints, masses and inertias, and
puts every body where DART has it for the same joint positions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from visprim.cli.main import main
from visprim.sim.mjcf import mjcf_joint_names
from visprim.sim.model import build_adonis
from visprim.sim.urdf import mass_table

mujoco = pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    path = tmp_path_factory.mktemp("mjcf") / "adonis.xml"
    assert main(["export-robot", "--out", str(path)]) == 0
    return mujoco.MjModel.from_xml_path(str(path))


def _name(model, kind, i) -> str:
    return mujoco.mj_id2name(model, kind, i)


def test_same_dof_joints_masses_and_inertias(loaded) -> None:
    _, skel = build_adonis()
    assert loaded.nv == skel.getNumDofs() == 20
    dart_joints = {
        skel.getJoint(i).getName(): skel.getJoint(i).getNumDofs()
        for i in range(skel.getNumJoints())
        if skel.getJoint(i).getNumDofs()
    }
    ball, hinge = int(mujoco.mjtJoint.mjJNT_BALL), int(mujoco.mjtJoint.mjJNT_HINGE)
    ours = {
        _name(loaded, mujoco.mjtObj.mjOBJ_JOINT, j): {ball: 3, hinge: 1}[int(loaded.jnt_type[j])]
        for j in range(loaded.njnt)
    }
    assert ours == dart_joints
    assert sorted(ours) == sorted(mjcf_joint_names())
    table = mass_table(skel)
    names = [_name(loaded, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, loaded.nbody)]
    assert sorted(names) == sorted(table)
    for b, name in enumerate(names, start=1):
        mass, com, moment = table[name]
        assert abs(loaded.body_mass[b] - mass) <= 1e-9, name
        np.testing.assert_allclose(loaded.body_ipos[b], com, atol=1e-12, err_msg=name)
        # MuJoCo stores principal moments and the rotation to the principal axes.
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, loaded.body_iquat[b])
        rot = rot.reshape(3, 3)
        full = rot @ np.diag(loaded.body_inertia[b]) @ rot.T
        np.testing.assert_allclose(full, moment, atol=1e-12, err_msg=name)
    np.testing.assert_allclose(loaded.opt.gravity, [0.0, 0.0, -9.81])


def test_bodies_where_dart_has_them(loaded) -> None:
    _, skel = build_adonis()
    data = mujoco.MjData(loaded)
    rng = np.random.default_rng(3)
    for _ in range(5):
        positions = np.zeros(skel.getNumDofs())
        for i in range(skel.getNumJoints()):
            joint = skel.getJoint(i)
            n = joint.getNumDofs()
            if n == 0:
                continue
            start = joint.getIndexInSkeleton(0)
            value = rng.uniform(-1.5, 1.5, n) if n == 1 else rng.normal(size=3)
            positions[start : start + n] = value
            j = mujoco.mj_name2id(loaded, mujoco.mjtObj.mjOBJ_JOINT, joint.getName())
            adr = loaded.jnt_qposadr[j]
            if n == 3:  # DART: rotation vector; MuJoCo: unit quaternion (w, x, y, z)
                x, y, z, w = Rotation.from_rotvec(value).as_quat()
                data.qpos[adr : adr + 4] = (w, x, y, z)
            else:
                data.qpos[adr] = value[0]
        skel.setPositions(positions)
        mujoco.mj_kinematics(loaded, data)
        for b in range(1, loaded.nbody):
            tf = skel.getBodyNode(_name(loaded, mujoco.mjtObj.mjOBJ_BODY, b)).getWorldTransform()
            np.testing.assert_allclose(data.xpos[b], tf.translation(), atol=1e-9)
            np.testing.assert_allclose(data.xmat[b].reshape(3, 3), tf.rotation(), atol=1e-9)
