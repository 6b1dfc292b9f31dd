"""Adonis in DART: a 20-DOF humanoid torso that performs the learned primitives.

- :mod:`~visprim.sim.model`: the body (one table of dimensions; mass and inertia from the
  shapes at 1,050 kg/m³), :func:`build_adonis` → ``(world, skeleton)``.
- :mod:`~visprim.sim.servo`: the stable-PD joint servo, the paper's explicit PD, the gains.
- :mod:`~visprim.sim.sequencer`: the right arm's 4 angles → joint targets, via points.
- :mod:`~visprim.sim.playback`: :func:`play` → :class:`Playback` (tracking metrics, frames).
- :mod:`~visprim.sim.kinematics`: forward kinematics of the skeleton in numpy, batched.
- :mod:`~visprim.sim.render`: :func:`render_png`, :func:`render_gif` (PIL, headless).
- :mod:`~visprim.sim.showcase`: primitive trajectories, playbacks and the demo GIFs.
- :mod:`~visprim.sim.joining`: segment curves joined with no step in angle or velocity.
- :mod:`~visprim.sim.sidebyside`: the imitation video (human arm beside Adonis).
- :mod:`~visprim.sim.video`: .gif / .mp4 writing, atomic.
- :mod:`~visprim.sim.urdf`: Adonis as URDF from the same table; :mod:`~visprim.sim.mjcf`: as
  MJCF (MuJoCo);
  :mod:`~visprim.sim.export`: joint trajectories (CSV, JSON for a ROS JointTrajectory).

Units: seconds, metres, radians (degrees only in fields named ``_deg``).
"""

from __future__ import annotations

from visprim.sim.model import build_adonis
from visprim.sim.playback import Playback, SimulationDiverged, play
from visprim.sim.render import Camera, render_gif, render_png

__all__ = [
    "Camera",
    "Playback",
    "SimulationDiverged",
    "build_adonis",
    "play",
    "render_gif",
    "render_png",
]
