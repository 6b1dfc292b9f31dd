"""Adonis as an MJCF file (MuJoCo's format), written from the table that builds the DART model
(:data:`visprim.sim.model.LINKS`).

MJCF has ball joints, so the structure is the DART model's one to one: one ``<body>`` per link
(same name, origin at its joint centre, axes aligned with the parent's at rest, ``pos`` = the
table's joint offset), a ``ball`` joint (3 DOF; its ``qpos`` is a unit quaternion w, x, y, z)
or a ``hinge`` about the table's axis (1 DOF), with the joint's name. The pelvis has no joint:
MuJoCo fixes it to the world. Every body gets an explicit ``<inertial>`` (mass, centre of
mass, full inertia about it, from :func:`visprim.sim.model.composite_inertia`, 17 significant
digits) and ``inertiafromgeom="false"``, so the geoms are drawing only; they have
``contype="0" conaffinity="0"`` (the model has no contacts). Capsules, boxes and spheres map
to MuJoCo's own (half lengths). Gravity and the time step are the DART world's.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

from visprim.sim.model import DENSITY, GRAVITY, LINKS, LinkSpec, ShapeSpec, composite_inertia
from visprim.sim.urdf import _f, _v, write_robot_file

__all__ = ["adonis_mjcf", "mjcf_joint_names", "write_mjcf"]


def mjcf_joint_names(links: Sequence[LinkSpec] = LINKS) -> list[str]:
    """Names of the moving MJCF joints in file order (ball joints 3 DOF, hinges 1)."""
    return [link.joint_name for link in links if link.joint in ("ball", "revolute")]


def _geom(link: LinkSpec, i: int, spec: ShapeSpec) -> str:
    if spec.kind == "capsule":
        r, h = spec.size
        shape = f'type="capsule" size="{_f(r)} {_f(h / 2)}"'
    elif spec.kind == "box":
        shape = f'type="box" size="{_v([s / 2 for s in spec.size])}"'
    else:
        shape = f'type="sphere" size="{_f(spec.size[0])}"'
    return (
        f'<geom name="{link.name}_shape{i}" {shape} pos="{_v(spec.centre)}" '
        f'rgba="{_v(spec.color)} 1" contype="0" conaffinity="0"/>'
    )


def _body(link: LinkSpec, children: dict[str, list[LinkSpec]], density: float, depth: int) -> str:
    pad = "  " * depth
    inertia = composite_inertia(link.shapes, density)
    m = inertia.moment
    lines = [f"{pad}<body name={quoteattr(link.name)} pos={quoteattr(_v(link.joint_offset))}>"]
    lines.append(
        f'{pad}  <inertial pos="{_v(inertia.com)}" mass="{_f(inertia.mass)}" '
        f'fullinertia="{_v([m[0, 0], m[1, 1], m[2, 2], m[0, 1], m[0, 2], m[1, 2]])}"/>'
    )
    if link.joint == "ball":
        lines.append(f'{pad}  <joint name={quoteattr(link.joint_name)} type="ball"/>')
    elif link.joint == "revolute":
        if link.axis is None:
            raise ValueError(f"adonis_mjcf: revolute link {link.name!r} needs an axis")
        lines.append(
            f'{pad}  <joint name={quoteattr(link.joint_name)} type="hinge" axis="{_v(link.axis)}"/>'
        )
    elif link.parent is not None:
        raise ValueError(f"adonis_mjcf: link {link.name!r}: only the root may be welded")
    lines.extend(f"{pad}  {_geom(link, i, s)}" for i, s in enumerate(link.shapes))
    for child in children.get(link.name, []):
        lines.append(_body(child, children, density, depth + 1))
    lines.append(f"{pad}</body>")
    return "\n".join(lines)


def adonis_mjcf(
    links: Sequence[LinkSpec] = LINKS,
    density: float = DENSITY,
    name: str = "adonis",
    dt: float = 0.001,
) -> str:
    """The MJCF text of a link table (default Adonis) at ``density`` kg/m³, time step ``dt``
    seconds."""
    children: dict[str, list[LinkSpec]] = {}
    for link in links[1:]:
        if link.parent is None:
            raise ValueError(f"adonis_mjcf: link {link.name!r}: only the first link is a root")
        children.setdefault(link.parent, []).append(link)
    parts = [
        "<!-- Adonis, written by visprim.sim.mjcf from visprim.sim.model.LINKS. Units: metres,",
        "     kilograms, radians, seconds. Ball joints as in the DART model. -->",
        f"<mujoco model={quoteattr(name)}>",
        '  <compiler angle="radian" inertiafromgeom="false"/>',
        f'  <option timestep="{_f(dt)}" gravity="{_v(GRAVITY)}"/>',
        "  <worldbody>",
        _body(links[0], children, density, 2),
        "  </worldbody>",
        "</mujoco>",
    ]
    return "\n".join(parts) + "\n"


def write_mjcf(path: str | os.PathLike[str], **kwargs: object) -> Path:
    """Write :func:`adonis_mjcf` to ``path`` (``.xml``) atomically; returns the path."""
    return write_robot_file(path, ".xml", "an MJCF", lambda: adonis_mjcf(**kwargs))  # type: ignore[arg-type]
