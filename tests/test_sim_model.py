"""Adonis's structure, mass properties and kinematics."""

from __future__ import annotations

import dartpy as dart
import numpy as np
import pytest
from visprim.arm import forward_kinematics
from visprim.sim.model import (
    DENSITY,
    HAND_POINT,
    LINKS,
    ShapeSpec,
    build_adonis,
    composite_inertia,
    link_masses,
)
from visprim.sim.sequencer import angles_to_positions, positions_to_angles


@pytest.fixture(scope="module")
def adonis() -> tuple:
    return build_adonis()


def _moving_bodies(skel) -> list:
    return [b for b in skel.getBodyNodes() if b.getParentJoint().getNumDofs() > 0]


def test_twenty_dofs_and_eight_moving_links(adonis) -> None:
    _, skel = adonis
    assert skel.getNumDofs() == 20
    moving = _moving_bodies(skel)
    assert len(moving) == 8
    dofs = {b.getParentJoint().getName(): b.getParentJoint().getNumDofs() for b in moving}
    assert dofs == {
        "waist": 3,
        "neck": 3,
        "r_shoulder": 3,
        "l_shoulder": 3,
        "r_elbow": 1,
        "l_elbow": 1,
        "r_wrist": 3,
        "l_wrist": 3,
    }
    # The one non-moving body is the welded pelvis carrying the static legs.
    root = skel.getRootBodyNode()
    assert root.getName() == "pelvis" and root.getParentJoint().getNumDofs() == 0


def test_inertias_positive_definite_and_physical(adonis) -> None:
    _, skel = adonis
    for body in _moving_bodies(skel):
        moment = np.asarray(body.getInertia().getMoment())
        assert np.allclose(moment, moment.T), body.getName()
        eig = np.linalg.eigvalsh(moment)
        assert eig.min() > 0, body.getName()
        # Principal moments of a real solid obey the triangle inequality.
        assert eig[0] + eig[1] >= eig[2] * (1 - 1e-9), body.getName()
        assert body.getMass() > 0


def test_masses_plausible_for_an_adult(adonis) -> None:
    _, skel = adonis
    masses = link_masses()
    moving_total = sum(masses.values())
    # Torso + head + arms of a ~75 kg adult: Winter's fractions give ~40 kg.
    assert 30.0 < moving_total < 50.0
    assert sum(b.getMass() for b in _moving_bodies(skel)) == pytest.approx(moving_total)
    winter = {"upper_arm": 0.028, "forearm": 0.016, "hand": 0.006, "head": 0.081}
    for side in ("r", "l"):
        for seg in ("upper_arm", "forearm", "hand"):
            assert masses[f"{side}_{seg}"] == pytest.approx(winter[seg] * 75.0, rel=0.25)
    assert masses["head"] == pytest.approx(winter["head"] * 75.0, rel=0.25)
    assert masses["r_hand"] == masses["l_hand"]


def _monte_carlo(shapes: list[ShapeSpec], n: int = 400_000, seed: int = 0):
    """Mass, COM and inertia by uniform sampling of the union's bounding box."""
    lo, hi = [], []
    for s in shapes:
        c = np.asarray(s.centre)
        if s.kind == "capsule":
            r, h = s.size
            half = np.array([r, r, h / 2 + r])
        elif s.kind == "box":
            half = np.asarray(s.size) / 2
        else:
            half = np.full(3, s.size[0])
        lo.append(c - half)
        hi.append(c + half)
    lo, hi = np.min(lo, axis=0), np.max(hi, axis=0)
    pts = np.random.default_rng(seed).uniform(lo, hi, size=(n, 3))
    inside = np.zeros(n, dtype=bool)
    for s in shapes:
        d = pts - np.asarray(s.centre)
        if s.kind == "capsule":
            r, h = s.size
            z = np.clip(d[:, 2], -h / 2, h / 2)
            inside |= d[:, 0] ** 2 + d[:, 1] ** 2 + (d[:, 2] - z) ** 2 <= r * r
        elif s.kind == "box":
            inside |= np.all(np.abs(d) <= np.asarray(s.size) / 2, axis=1)
        else:
            inside |= np.sum(d * d, axis=1) <= s.size[0] ** 2
    vol = np.prod(hi - lo) * inside.mean()
    p = pts[inside]
    com = p.mean(axis=0)
    d = p - com
    m = DENSITY * vol
    moment = m * (np.eye(3) * np.mean(np.sum(d * d, axis=1)) - d.T @ d / len(d))
    return m, com, moment


@pytest.mark.parametrize(
    "shapes",
    [
        [ShapeSpec("capsule", (0.04, 0.3), (0.0, 0.0, -0.15))],
        [ShapeSpec("box", (0.085, 0.03, 0.19), (0.0, 0.0, -0.095))],
        [ShapeSpec("sphere", (0.1,), (0.0, 0.0, 0.17))],
        # Two disjoint shapes (the composite rule adds volumes, so they must not overlap).
        [
            ShapeSpec("sphere", (0.1,), (0.0, 0.0, 0.25)),
            ShapeSpec("box", (0.1, 0.2, 0.1), (0.05, 0.0, 0.0)),
        ],
    ],
)
def test_composite_inertia_matches_monte_carlo(shapes) -> None:
    got = composite_inertia(shapes)
    m, com, moment = _monte_carlo(shapes)
    assert got.mass == pytest.approx(m, rel=0.01)
    assert np.allclose(got.com, com, atol=1.5e-3)
    scale = np.abs(moment).max()
    assert np.allclose(got.moment, moment, atol=0.02 * scale)


@pytest.mark.parametrize(
    "spec, shape",
    [
        (ShapeSpec("capsule", (0.042, 0.3), (0, 0, 0)), dart.dynamics.CapsuleShape(0.042, 0.3)),
        (ShapeSpec("box", (0.1, 0.2, 0.3), (0, 0, 0)), dart.dynamics.BoxShape([0.1, 0.2, 0.3])),
        (ShapeSpec("sphere", (0.1,), (0, 0, 0)), dart.dynamics.SphereShape(0.1)),
    ],
)
def test_shape_formulas_agree_with_dart(spec, shape) -> None:
    assert spec.volume() == pytest.approx(shape.getVolume(), rel=1e-12)
    assert np.allclose(spec.inertia_about_centre(2.0), shape.computeInertia(2.0), rtol=1e-12)


def test_dart_kinematics_follow_the_arm_convention(adonis) -> None:
    """The simulated right arm puts elbow, wrist and hand where visprim.arm says."""
    _, skel = adonis
    rng = np.random.default_rng(3)
    angles = np.column_stack(
        [
            rng.uniform(-np.pi, np.pi, 50),
            rng.uniform(0.0, np.pi, 50),
            rng.uniform(-np.pi, np.pi, 50),
            rng.uniform(0.0, 2.5, 50),
        ]
    )
    expected = forward_kinematics(angles)  # body frame, shoulder at the origin
    q = angles_to_positions(skel, angles)
    for i in range(len(angles)):
        skel.setPositions(q[i])
        shoulder = skel.getBodyNode("r_upper_arm").getWorldTransform().translation()
        elbow = skel.getBodyNode("r_forearm").getWorldTransform().translation()
        hand_tf = skel.getBodyNode("r_hand").getWorldTransform()
        wrist = hand_tf.translation()
        finger = hand_tf.rotation() @ np.asarray(HAND_POINT) + wrist
        got = np.stack([shoulder, elbow, wrist, finger]) - shoulder
        assert np.allclose(got, expected[i], atol=1e-9), angles[i]
    skel.resetPositions()


def test_positions_to_angles_inverts_the_mapping(adonis) -> None:
    _, skel = adonis
    rng = np.random.default_rng(4)
    angles = np.column_stack(
        [
            rng.uniform(-3.0, 3.0, 200),
            rng.uniform(0.05, np.pi - 0.05, 200),
            rng.uniform(-3.0, 3.0, 200),
            rng.uniform(0.0, 2.5, 200),
        ]
    )
    back = positions_to_angles(skel, angles_to_positions(skel, angles))
    assert np.allclose(back, angles, atol=1e-9)


def test_rest_pose_is_upright_with_hanging_arms(adonis) -> None:
    _, skel = adonis
    skel.resetPositions()
    hand = skel.getBodyNode("r_hand").getWorldTransform().translation()
    shoulder = skel.getBodyNode("r_upper_arm").getWorldTransform().translation()
    assert shoulder[1] < 0 < skel.getBodyNode("l_upper_arm").getWorldTransform().translation()[1]
    assert np.allclose(hand[:2], shoulder[:2]) and hand[2] == pytest.approx(shoulder[2] - 0.56)
    head = skel.getBodyNode("head").getWorldTransform().translation()
    assert 1.4 < head[2] < 1.6


def test_table_lists_parents_before_children() -> None:
    seen: set[str] = set()
    for link in LINKS:
        assert link.parent is None or link.parent in seen
        seen.add(link.name)


@pytest.mark.parametrize("dt", [0.0, -0.001, float("nan")])
def test_build_adonis_rejects_bad_time_step(dt) -> None:
    with pytest.raises(ValueError, match="dt"):
        build_adonis(dt)
