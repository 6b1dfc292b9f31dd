"""Adonis: a 20-DOF humanoid torso on static legs, built in DART from one table of dimensions.

Structure (:data:`LINKS`, one row per rigid body)::

    pelvis (welded to the world; carries the static legs; not a moving link)
    └── torso            waist, ball joint (3 DOF)
        ├── head         neck, ball joint (3 DOF)
        ├── r_upper_arm  right shoulder, ball joint (3 DOF)
        │   └── r_forearm    right elbow, revolute (1 DOF)
        │       └── r_hand       right wrist, ball joint (3 DOF)
        └── l_upper_arm, l_forearm, l_hand   the mirror image (3 + 1 + 3 DOF)

Eight moving links, 20 DOF. Frames: world = body frame of :mod:`visprim.trial` (+x forward,
+y the figure's left, +z up, metres, floor at z = 0). Every body frame is axis-aligned with
the world at rest (all joint positions zero): upright torso and head, arms hanging along -z
with straight elbows, palms facing the thighs.

Dimensions are those of an adult of about 1.75 m: segment lengths of the arm are
:class:`visprim.arm.ArmLengths` (upper arm 0.30 m, forearm 0.26 m, hand 0.19 m) so that the
simulated hand follows :func:`visprim.arm.forward_kinematics`; widths were chosen so that the
segment masses from the shapes at :data:`DENSITY` land near Winter's mass fractions for a
75 kg adult (Winter, *Biomechanics and Motor Control of Human Movement*, table 4.1: upper arm
0.028, forearm 0.016, hand 0.006, head and neck 0.081, thorax + abdomen 0.355 of body mass).
The resulting masses are listed by :func:`link_masses` (torso ≈ 26 kg, head ≈ 5 kg,
upper arm ≈ 2.1 kg, forearm ≈ 1.2 kg, hand ≈ 0.5 kg; ≈ 39 kg moving in all).

Mass, centre of mass and inertia of each body are computed from its shapes
(:func:`composite_inertia`: the shapes' own inertias about their centres, moved to the common
centre of mass with the parallel-axis theorem) at a uniform human body density of
1,050 kg/m³. Shapes overlap at the joints (capsules extend a radius beyond each joint
centre); that volume is counted once per body, which is within the accuracy of the model.
No collision aspects are created: the simulation has no contacts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import dartpy as dart
import numpy as np
from numpy.typing import NDArray

from visprim.arm import ELBOW_AXIS_BODY, ArmLengths

#: Human body density used for every shape, kg/m³.
DENSITY: float = 1050.0
#: Gravity, m/s² (world frame, +z up).
GRAVITY: tuple[float, float, float] = (0.0, 0.0, -9.81)

ShapeKind = Literal["capsule", "box", "sphere"]


@dataclass(frozen=True)
class ShapeSpec:
    """One solid primitive attached to a body, axis-aligned with the body frame.

    ``size`` in metres: capsule ``(radius, length)`` where ``length`` is the distance between
    the centres of its two hemispherical caps (DART's ``CapsuleShape`` height) and the axis is
    the body's z; box ``(x, y, z)`` edge lengths; sphere ``(radius,)``. ``centre`` is the
    shape's centre in the body frame (metres). ``color`` is an RGB triple for rendering.
    """

    kind: ShapeKind
    size: tuple[float, ...]
    centre: tuple[float, float, float]
    color: tuple[float, float, float] = (0.80, 0.66, 0.55)

    def volume(self) -> float:
        """Volume in m³."""
        if self.kind == "capsule":
            r, h = self.size
            return float(np.pi * r * r * h + 4.0 / 3.0 * np.pi * r**3)
        if self.kind == "box":
            x, y, z = self.size
            return float(x * y * z)
        (r,) = self.size
        return float(4.0 / 3.0 * np.pi * r**3)

    def inertia_about_centre(self, mass: float) -> NDArray[np.float64]:
        """Inertia tensor (kg·m²) of the solid of ``mass`` kg about its centre, body axes."""
        if self.kind == "capsule":
            r, h = self.size
            v_cyl = np.pi * r * r * h
            v_caps = 4.0 / 3.0 * np.pi * r**3
            m_cyl = mass * v_cyl / (v_cyl + v_caps)
            m_caps = mass - m_cyl  # both hemispheres together
            # Hemisphere: centroid 3r/8 from its flat face, which sits h/2 from the centre.
            transverse = m_cyl * (h * h / 12.0 + r * r / 4.0) + m_caps * (
                2.0 * r * r / 5.0 + h * h / 4.0 + 3.0 * h * r / 8.0
            )
            axial = m_cyl * r * r / 2.0 + m_caps * 2.0 * r * r / 5.0
            return np.diag([transverse, transverse, axial])
        if self.kind == "box":
            x, y, z = self.size
            return mass / 12.0 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])
        (r,) = self.size
        return np.eye(3) * (2.0 / 5.0 * mass * r * r)


@dataclass(frozen=True)
class LinkSpec:
    """One rigid body of the model and the joint that connects it to its parent.

    ``joint_offset`` is the joint centre in the parent's body frame (metres); the child's
    body frame has its origin at the joint centre and is aligned with the parent's at rest.
    ``axis`` is the revolute joint's axis in the child frame (unit vector).
    """

    name: str
    parent: str | None
    joint: Literal["weld", "ball", "revolute"]
    joint_name: str
    joint_offset: tuple[float, float, float]
    shapes: tuple[ShapeSpec, ...]
    axis: tuple[float, float, float] | None = None


_ARM = ArmLengths()
_SKIN = (0.80, 0.66, 0.55)
_SHIRT = (0.25, 0.42, 0.70)
_TROUSERS = (0.30, 0.30, 0.36)
_HAIR = (0.35, 0.25, 0.18)
#: Height of the waist joint above the floor, metres.
WAIST_HEIGHT: float = 1.00
#: Shoulder joint centre in the torso frame, metres (right shoulder: y negative).
SHOULDER_OFFSET: tuple[float, float, float] = (0.0, 0.20, 0.42)
#: Neck joint centre in the torso frame, metres.
NECK_OFFSET: tuple[float, float, float] = (0.0, 0.0, 0.46)


def _arm_links(side: Literal["r", "l"]) -> tuple[LinkSpec, ...]:
    sign = -1.0 if side == "r" else 1.0
    x, y, z = SHOULDER_OFFSET
    upper, fore, hand = _ARM.upper_arm, _ARM.forearm, _ARM.hand
    elbow_axis = tuple(float(v) for v in ELBOW_AXIS_BODY)
    return (
        LinkSpec(
            f"{side}_upper_arm",
            "torso",
            "ball",
            f"{side}_shoulder",
            (x, sign * y, z),
            (ShapeSpec("capsule", (0.042, upper), (0.0, 0.0, -upper / 2), _SHIRT),),
        ),
        LinkSpec(
            f"{side}_forearm",
            f"{side}_upper_arm",
            "revolute",
            f"{side}_elbow",
            (0.0, 0.0, -upper),
            (ShapeSpec("capsule", (0.034, fore), (0.0, 0.0, -fore / 2), _SKIN),),
            axis=elbow_axis,  # type: ignore[arg-type]
        ),
        LinkSpec(
            f"{side}_hand",
            f"{side}_forearm",
            "ball",
            f"{side}_wrist",
            (0.0, 0.0, -fore),
            # Palm in the x-z plane (thin along y): facing the thigh at rest.
            (ShapeSpec("box", (0.085, 0.03, hand), (0.0, 0.0, -hand / 2), _SKIN),),
        ),
    )


#: The table of dimensions: every body, its joint and its shapes (metres).
LINKS: tuple[LinkSpec, ...] = (
    LinkSpec(
        "pelvis",
        None,
        "weld",
        "ground",
        (0.0, 0.0, WAIST_HEIGHT),
        (
            ShapeSpec("box", (0.18, 0.30, 0.16), (0.0, 0.0, -0.08), _TROUSERS),
            # Static legs: thighs hip (z = -0.12) to knee (-0.55), shanks knee to ankle (-0.93).
            ShapeSpec("capsule", (0.070, 0.43), (0.0, -0.09, -0.335), _TROUSERS),
            ShapeSpec("capsule", (0.070, 0.43), (0.0, 0.09, -0.335), _TROUSERS),
            ShapeSpec("capsule", (0.050, 0.38), (0.0, -0.09, -0.74), _TROUSERS),
            ShapeSpec("capsule", (0.050, 0.38), (0.0, 0.09, -0.74), _TROUSERS),
            ShapeSpec("box", (0.25, 0.09, 0.05), (0.06, -0.09, -0.975), (0.15, 0.15, 0.15)),
            ShapeSpec("box", (0.25, 0.09, 0.05), (0.06, 0.09, -0.975), (0.15, 0.15, 0.15)),
        ),
    ),
    LinkSpec(
        "torso",
        "pelvis",
        "ball",
        "waist",
        (0.0, 0.0, 0.0),
        (ShapeSpec("box", (0.18, 0.30, 0.46), (0.0, 0.0, 0.23), _SHIRT),),
    ),
    LinkSpec(
        "head",
        "torso",
        "ball",
        "neck",
        NECK_OFFSET,
        (
            ShapeSpec("capsule", (0.05, 0.06), (0.0, 0.0, 0.04), _SKIN),
            ShapeSpec("sphere", (0.10,), (0.0, 0.0, 0.17), _SKIN),
        ),
    ),
    *_arm_links("r"),
    *_arm_links("l"),
)

#: Point of the right hand that corresponds to the finger sensor of the method (metres,
#: hand frame): ``ArmLengths.hand_marker`` along the hand's long axis.
HAND_POINT: tuple[float, float, float] = (0.0, 0.0, -_ARM.hand_marker)


@dataclass(frozen=True)
class BodyInertia:
    """Mass (kg), centre of mass (m, body frame) and inertia about it (kg·m², body axes)."""

    mass: float
    com: NDArray[np.float64]
    moment: NDArray[np.float64]


def composite_inertia(shapes: Sequence[ShapeSpec], density: float = DENSITY) -> BodyInertia:
    """Mass properties of a union of axis-aligned solids of uniform ``density`` (kg/m³).

    Each shape contributes ``density * volume`` kg at its centre; its own inertia is moved to
    the common centre of mass with the parallel-axis theorem.
    """
    if not shapes:
        raise ValueError("composite_inertia: a body needs at least one shape")
    if not density > 0:
        raise ValueError(f"composite_inertia: density must be > 0 kg/m³, got {density}")
    masses = np.array([density * s.volume() for s in shapes])
    centres = np.array([s.centre for s in shapes], dtype=np.float64)
    mass = float(masses.sum())
    com = (masses[:, None] * centres).sum(axis=0) / mass
    moment = np.zeros((3, 3))
    for s, m, c in zip(shapes, masses, centres, strict=True):
        d = c - com
        moment += s.inertia_about_centre(float(m)) + m * (d @ d * np.eye(3) - np.outer(d, d))
    return BodyInertia(mass, com, moment)


def link_masses(density: float = DENSITY) -> dict[str, float]:
    """Mass in kg of every moving link of :data:`LINKS` at ``density`` kg/m³."""
    return {
        link.name: composite_inertia(link.shapes, density).mass
        for link in LINKS
        if link.joint != "weld"
    }


def _dart_shape(spec: ShapeSpec) -> dart.dynamics.Shape:
    if spec.kind == "capsule":
        return dart.dynamics.CapsuleShape(spec.size[0], spec.size[1])
    if spec.kind == "box":
        return dart.dynamics.BoxShape(np.asarray(spec.size, dtype=np.float64))
    return dart.dynamics.SphereShape(spec.size[0])


def _translation(xyz: Sequence[float]) -> dart.math.Isometry3:
    iso = dart.math.Isometry3()
    iso.set_identity()
    iso.set_translation(np.asarray(xyz, dtype=np.float64))
    return iso


def build_skeleton(
    links: Sequence[LinkSpec] = LINKS, density: float = DENSITY, name: str = "adonis"
) -> dart.dynamics.Skeleton:
    """A DART skeleton from a table of links (default: Adonis, :data:`LINKS`).

    The root link must come first and is welded to the world at its ``joint_offset``; every
    other link must follow its parent. Bodies get mass and inertia from their shapes at
    ``density`` kg/m³ and a visual aspect per shape (no collision aspect).
    """
    skel = dart.dynamics.Skeleton(name)
    bodies: dict[str, dart.dynamics.BodyNode] = {}
    for i, link in enumerate(links):
        if (link.parent is None) != (i == 0):
            raise ValueError(f"build_skeleton: link {link.name!r}: only the first link is a root")
        parent = bodies.get(link.parent) if link.parent is not None else None
        if link.parent is not None and parent is None:
            raise ValueError(
                f"build_skeleton: link {link.name!r} comes before its parent {link.parent!r}"
            )
        if link.joint == "weld":
            joint, body = skel.createWeldJointAndBodyNodePair(parent)
        elif link.joint == "ball":
            joint, body = skel.createBallJointAndBodyNodePair(parent)
        elif link.joint == "revolute":
            if link.axis is None:
                raise ValueError(f"build_skeleton: revolute link {link.name!r} needs an axis")
            props = dart.dynamics.RevoluteJointProperties()
            props.mAxis = np.asarray(link.axis, dtype=np.float64)
            joint, body = skel.createRevoluteJointAndBodyNodePair(parent, props)
        else:
            raise ValueError(f"build_skeleton: link {link.name!r}: unknown joint {link.joint!r}")
        joint.setName(link.joint_name)
        body.setName(link.name)
        joint.setTransformFromParentBodyNode(_translation(link.joint_offset))
        inertia = composite_inertia(link.shapes, density)
        body.setInertia(dart.dynamics.Inertia(inertia.mass, inertia.com, inertia.moment))
        for j, spec in enumerate(link.shapes):
            node = body.createShapeNode(_dart_shape(spec), f"{link.name}_shape{j}")
            node.setRelativeTransform(_translation(spec.centre))
            node.createVisualAspect().setColor(np.asarray(spec.color, dtype=np.float64))
        bodies[link.name] = body
    return skel


def build_adonis(
    dt: float = 0.001, density: float = DENSITY
) -> tuple[dart.simulation.World, dart.dynamics.Skeleton]:
    """A world with gravity and time step ``dt`` (seconds) holding Adonis at rest.

    Returns ``(world, skeleton)``. The skeleton has 20 DOF (see the module docstring); all
    joint positions are zero (upright, arms hanging). Joints carry no damping or springs: the
    servo (:mod:`visprim.sim.servo`) configures them.
    """
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"build_adonis: dt must be a positive number of seconds, got {dt}")
    skel = build_skeleton(LINKS, density)
    world = dart.simulation.World("adonis_world")
    world.setGravity(np.asarray(GRAVITY, dtype=np.float64))
    world.setTimeStep(dt)
    world.addSkeleton(skel)
    return world, skel
