"""Adonis as a URDF file, written from the table that builds the DART model (:data:`LINKS`).

URDF has no ball joint, so each 3-DOF ball joint of :mod:`visprim.sim.model` becomes three
``continuous`` (unlimited revolute) joints ``<joint>_x``, ``<joint>_z``, ``<joint>_y`` about
the child's x, z and y axes in turn, through two links of negligible mass
(:data:`SPLIT_LINK_MASS`) ``<joint>_link1`` and ``<joint>_link2`` at the joint centre: the
joint's rotation is ``Rx(a) Rz(b) Ry(c)`` (intrinsic X-Z-Y Euler angles,
:func:`visprim.sim.export.urdf_positions`). The middle axis is the long axis of
the limbs at rest (vertical), so the decomposition's singularity (``b = ±90°``) lies a
quarter turn of axial twist away from the rest pose, not at it (a Z-Y-Z split, the method's
own shoulder angles, would be singular with the arm hanging). Elbows are one continuous joint
about the table's axis (flexion = the method's elbow angle).

Every real link keeps its name, its frame (origin at its joint centre, axes aligned with the
world at rest), its mass, centre of mass and inertia about the centre of mass (computed by
:func:`visprim.sim.model.composite_inertia`, written with 17 significant digits). Capsules,
which URDF lacks, are drawn as a cylinder and two spheres (visual only; the model has no
collision shapes). The pelvis is fixed to a root link ``world`` (DART's URDF loader then
welds it instead of adding a floating base).

The joint order of the file (depth first, as in :data:`LINKS`) is :func:`urdf_joint_names`:
the column order of the trajectory exports (:mod:`visprim.sim.export`).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Literal
from xml.sax.saxutils import quoteattr

import numpy as np

from visprim.atomic import write_text
from visprim.sim.model import DENSITY, LINKS, LinkSpec, ShapeSpec, composite_inertia

#: Axes (child frame) and name suffixes of the three joints replacing a ball joint, in order.
BALL_AXES: tuple[tuple[str, tuple[float, float, float]], ...] = (
    ("x", (1.0, 0.0, 0.0)),
    ("z", (0.0, 0.0, 1.0)),
    ("y", (0.0, 1.0, 0.0)),
)
#: Mass (kg) and principal inertia (kg·m²) of the links between the axes of a split ball joint
#: (negligible next to the 0.5 kg hands; zero is refused by DART's loader).
SPLIT_LINK_MASS = 1e-6
SPLIT_LINK_INERTIA = 1e-9
#: The matching scipy Euler sequence (upper case: intrinsic).
BALL_EULER: Literal["XZY"] = "XZY"


def _f(x: float) -> str:
    return repr(float(x)) if x != 0 else "0"


def _v(xs: Sequence[float] | np.ndarray) -> str:
    return " ".join(_f(x) for x in xs)


def ball_joint_split(link: LinkSpec) -> list[tuple[str, tuple[float, float, float]]]:
    """URDF joint names and axes replacing a ball joint (see the module docstring)."""
    return [(f"{link.joint_name}_{s}", a) for s, a in BALL_AXES]


def urdf_joint_names(links: Sequence[LinkSpec] = LINKS) -> list[str]:
    """Names of the moving URDF joints in file order (1 DOF each)."""
    names: list[str] = []
    for link in links:
        if link.joint == "ball":
            names.extend(n for n, _ in ball_joint_split(link))
        elif link.joint == "revolute":
            names.append(link.joint_name)
    return names


def _visuals(link: LinkSpec, out: list[str]) -> None:
    for i, spec in enumerate(link.shapes):
        rgba = f"{_v(spec.color)} 1"
        for geom, centre in _geometries(spec):
            out.append(
                f'    <visual name="{link.name}_shape{i}">\n'
                f'      <origin xyz="{_v(centre)}" rpy="0 0 0"/>\n'
                f"      <geometry>{geom}</geometry>\n"
                f'      <material name="{link.name}_shape{i}"><color rgba="{rgba}"/></material>\n'
                "    </visual>"
            )


def _geometries(spec: ShapeSpec) -> list[tuple[str, tuple[float, float, float]]]:
    c = spec.centre
    if spec.kind == "box":
        return [(f'<box size="{_v(spec.size)}"/>', c)]
    if spec.kind == "sphere":
        return [(f'<sphere radius="{_f(spec.size[0])}"/>', c)]
    r, h = spec.size
    return [
        (f'<cylinder radius="{_f(r)}" length="{_f(h)}"/>', c),
        (f'<sphere radius="{_f(r)}"/>', (c[0], c[1], c[2] - h / 2)),
        (f'<sphere radius="{_f(r)}"/>', (c[0], c[1], c[2] + h / 2)),
    ]


def _link(link: LinkSpec, density: float) -> str:
    inertia = composite_inertia(link.shapes, density)
    m = inertia.moment
    out = [
        f"  <link name={quoteattr(link.name)}>",
        "    <inertial>",
        f'      <origin xyz="{_v(inertia.com)}" rpy="0 0 0"/>',
        f'      <mass value="{_f(inertia.mass)}"/>',
        f'      <inertia ixx="{_f(m[0, 0])}" ixy="{_f(m[0, 1])}" ixz="{_f(m[0, 2])}" '
        f'iyy="{_f(m[1, 1])}" iyz="{_f(m[1, 2])}" izz="{_f(m[2, 2])}"/>',
        "    </inertial>",
    ]
    _visuals(link, out)
    out.append("  </link>")
    return "\n".join(out)


def _massless(name: str) -> str:
    # A link without <inertial> gets 1 kg in DART's loader and a zero mass is refused with a
    # warning, so the links between the axes of a ball joint get a negligible one.
    m, i = _f(SPLIT_LINK_MASS), _f(SPLIT_LINK_INERTIA)
    return (
        f"  <link name={quoteattr(name)}>\n"
        f'    <inertial><mass value="{m}"/>'
        f'<inertia ixx="{i}" ixy="0" ixz="0" iyy="{i}" iyz="0" izz="{i}"/></inertial>\n'
        "  </link>"
    )


def _joint(
    name: str,
    kind: str,
    parent: str,
    child: str,
    xyz: Sequence[float],
    axis: Sequence[float] | None = None,
) -> str:
    lines = [
        f"  <joint name={quoteattr(name)} type={quoteattr(kind)}>",
        f"    <parent link={quoteattr(parent)}/>",
        f"    <child link={quoteattr(child)}/>",
        f'    <origin xyz="{_v(xyz)}" rpy="0 0 0"/>',
    ]
    if axis is not None:
        lines.append(f'    <axis xyz="{_v(axis)}"/>')
    lines.append("  </joint>")
    return "\n".join(lines)


def adonis_urdf(
    links: Sequence[LinkSpec] = LINKS, density: float = DENSITY, name: str = "adonis"
) -> str:
    """The URDF text of a link table (default Adonis) at ``density`` kg/m³."""
    parts = [
        '<?xml version="1.0"?>',
        "<!-- Adonis, written by visprim.sim.urdf from visprim.sim.model.LINKS. Units: metres,",
        "     kilograms, radians. Ball joints are split into three continuous joints (see",
        "     visprim.sim.urdf): intrinsic X-Z-Y Euler angles. -->",
        f"<robot name={quoteattr(name)}>",
        '  <link name="world"/>',
    ]
    for link in links:
        parts.append(_link(link, density))
        if link.parent is None:
            parts.append(_joint(link.joint_name, "fixed", "world", link.name, link.joint_offset))
        elif link.joint == "weld":
            parts.append(
                _joint(link.joint_name, "fixed", link.parent, link.name, link.joint_offset)
            )
        elif link.joint == "revolute":
            parts.append(
                _joint(
                    link.joint_name, "continuous", link.parent, link.name, link.joint_offset,
                    link.axis,
                )
            )  # fmt: skip
        else:
            split = ball_joint_split(link)
            chain = [link.parent, f"{link.joint_name}_link1", f"{link.joint_name}_link2", link.name]
            for i, (jname, axis) in enumerate(split):
                if i < 2:
                    parts.append(_massless(chain[i + 1]))
                xyz = link.joint_offset if i == 0 else (0.0, 0.0, 0.0)
                parts.append(_joint(jname, "continuous", chain[i], chain[i + 1], xyz, axis))
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


def write_urdf(path: str | os.PathLike[str], **kwargs: object) -> Path:
    """Write :func:`adonis_urdf` to ``path`` atomically; returns the path."""
    return write_robot_file(path, ".urdf", "a URDF", lambda: adonis_urdf(**kwargs))  # type: ignore[arg-type]


def write_robot_file(
    path: str | os.PathLike[str], suffix: str, what: str, make: Callable[[], str]
) -> Path:
    """Write the text ``make()`` to ``path`` atomically, once its name is checked to end in
    ``suffix`` (``what`` names the format in the error); returns the path."""
    out = Path(path)
    if out.suffix.lower() != suffix:
        raise ValueError(f"{out}: {what} file name must end in {suffix}")
    text = make()
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text(out, text)
    return out


def mass_table(skeleton: object) -> dict[str, tuple[float, np.ndarray, np.ndarray]]:
    """``{body: (mass kg, com (3,) m, inertia about com (3, 3) kg·m²)}`` of a DART skeleton
    (for comparing a loaded URDF with the model)."""
    out = {}
    for i in range(skeleton.getNumBodyNodes()):  # type: ignore[attr-defined]
        b = skeleton.getBodyNode(i)  # type: ignore[attr-defined]
        inertia = b.getInertia()
        out[b.getName()] = (
            float(inertia.getMass()),
            np.asarray(inertia.getLocalCOM(), dtype=np.float64),
            np.asarray(inertia.getMoment(), dtype=np.float64),
        )
    return out
