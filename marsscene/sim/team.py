"""A team of robots in one world: one MuJoCo model holding every rover, stepped together.

:class:`TeamSim` attaches each robot's rover (its own :class:`~marsscene.rover.config.RoverConfig`:
Perseverance- and MER-class rovers may share a world) under the prefix ``<name>/`` to the
scene, compiles one model and steps it for all; each :class:`TeamMember` is one robot's view of
it with the same readings and commands as a :class:`~marsscene.sim.rover_sim.RoverSim`, so the
drive loop (:class:`~marsscene.sim.session.DriveSession`), the sensors and any controller drive
a team member as they drive a lone rover.

Rovers of a team touch each other: each robot's collision geoms carry a contact bit of their
own (``contype`` bit ``2 + i``) that every other robot's geoms accept (``conaffinity``), so
robot i meets robot j but never itself; the terrain and rocks collide with all as with one
rover. The mast cameras render the whole model, other robots included, and each robot's LiDAR
casts against the other robots' collision geoms too (:mod:`marsscene.sensors.lidar_boxes`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from marsscene.errors import ConfigError, RuntimeSimError
from marsscene.rover.config import CameraConfig, RoverConfig, RunConfig
from marsscene.rover.spawn import SETTLE_S, spawn_pose
from marsscene.sensors.lidar_boxes import robot_boxes
from marsscene.sim.corridor import CORRIDOR_M
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.rover_sim import load_scene_spec
from marsscene.sim.rover_view import RoverView
from marsscene.sim.terrain import scene_heightfield
from marsscene.sim.wheel_soil import WheelSoil, soften_terrain, soil_map_of
from marsscene.soil.map import read_soil_map
from marsscene.terrain.heightfield import Heightfield

__all__ = ["MAX_ROBOTS", "Placement", "TeamMember", "TeamSim", "footprint_radius_m"]

#: Robots in one world: each takes a contact bit (bits 2 .. 2 + MAX_ROBOTS - 1 of 32).
MAX_ROBOTS = 16


@dataclass(frozen=True)
class Placement:
    """One robot of a :class:`TeamSim`: its name (the prefix of its bodies, ``name/``), its rover,
    its sensors and rates, and its start pose (m; rad counter-clockwise from east)."""

    name: str
    rover: RoverConfig
    run: RunConfig
    start_xy_m: tuple[float, float]
    start_yaw_rad: float = 0.0


def footprint_radius_m(rover: RoverConfig) -> float:
    """Horizontal radius of a circle holding the rover's wheels (m): half the diagonal of its
    wheelbase by its track, plus a wheel radius."""
    length_m = rover.wheelbase_front_m + rover.wheelbase_rear_m
    return 0.5 * math.hypot(length_m, rover.track_m + rover.wheel_width_m) + rover.wheel_radius_m


def _check(placements: Sequence[Placement]) -> None:
    if not 1 <= len(placements) <= MAX_ROBOTS:
        raise ConfigError(f"a team has 1 to {MAX_ROBOTS} robots, not {len(placements)}")
    names = [p.name for p in placements]
    if len(set(names)) != len(names):
        raise ConfigError(f"robot names must differ: {names}")
    rates = {(p.run.physics_hz, p.run.control_hz) for p in placements}
    if len(rates) > 1:
        raise ConfigError("the robots of a team share one physics model and one control clock: "
                          f"give them the same physics_hz and control_hz (got {sorted(rates)})")
    for i, a in enumerate(placements):
        for b in placements[i + 1:]:
            gap = math.dist(a.start_xy_m, b.start_xy_m)
            need = footprint_radius_m(a.rover) + footprint_radius_m(b.rover)
            if gap < need:
                raise ConfigError(f"robots {a.name!r} and {b.name!r} start {gap:.2f} m apart; "
                                  f"their footprints need {need:.2f} m")


class TeamSim:
    """Every robot of a team on a built scene, in one model.

    Parameters
    ----------
    scene_dir : path-like
        A built scene (``mjcf/scene.xml``).
    placements : sequence of Placement
        The robots (1 to :data:`MAX_ROBOTS`), their rovers, sensors and starts.
    contact_corridor_xy_m : array_like of shape (N, 2), optional
        Rocks farther than ``contact_corridor_m`` from this polyline are left out (as a
        :class:`~marsscene.sim.rover_sim.RoverSim`'s).
    soil : str, Soil or SoilMap, optional
        Deformable soil under every robot's wheels (default: the scene's soil map, else rigid).
    settle_s : float
        Settling time of the team at its starts (all robots together).
    """

    def __init__(self, scene_dir: str | Path, placements: Sequence[Placement], *,
                 contact_corridor_xy_m: Any = None, contact_corridor_m: float = CORRIDOR_M,
                 soil: Any = None, settle_s: float = SETTLE_S) -> None:
        _check(placements)
        self.scene_dir = Path(scene_dir)
        self.placements = tuple(placements)
        self.soil_map = read_soil_map(self.scene_dir) if soil is None else soil_map_of(soil)
        self._corridor = contact_corridor_xy_m
        self._corridor_m = float(contact_corridor_m)
        spec = self.build_spec()
        try:
            self.model = spec.compile()
        except Exception as err:
            raise RuntimeSimError(f"{self.scene_xml}: cannot compile the team: {err}") from None
        self.data = mujoco.MjData(self.model)
        self.heightfield: Heightfield = scene_heightfield(self.model)
        for name in ("terrain", "terrain_outer"):  # the LiDAR marches the terrain itself
            gid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, name)
            if gid >= 0:
                self.model.geom_group[gid] = 3
        physics_hz = self.placements[0].run.physics_hz
        if physics_hz is not None:
            self.model.opt.timestep = 1.0 / physics_hz
        self.dt_physics_s = float(self.model.opt.timestep)
        self.members = [TeamMember(self, p) for p in self.placements]
        self.settle_s = float(settle_s)
        self.reset()

    def build_spec(self) -> Any:
        """A fresh ``MjSpec`` of the scene with every robot attached (not yet compiled)."""
        spec, self.scene_xml, self.rocks_kept = load_scene_spec(
            self.scene_dir, corridor_xy_m=self._corridor, corridor_m=self._corridor_m)
        n = len(self.placements)
        bits = [1 << (2 + i) for i in range(n)]
        for i, p in enumerate(self.placements):
            fovy = (p.run.camera or CameraConfig()).fovy_deg
            rover = mujoco.MjSpec.from_string(rover_mjcf(p.rover, camera_fovy_deg=fovy))
            if n > 1:  # robot i meets every other robot, never itself
                others = sum(bits) - bits[i]
                for geom in rover.geoms:
                    if geom.contype:
                        geom.contype |= bits[i]
                        geom.conaffinity |= others
            spec.attach(rover, prefix=f"{p.name}/", frame=spec.worldbody.add_frame())
        if self.soil_map is not None:
            soften_terrain(spec)
        return spec

    def reset(self) -> None:
        """Every robot at its start, settled on the terrain together (brakes on), time 0."""
        mujoco.mj_resetData(self.model, self.data)
        for m in self.members:
            m.reset_soil()
            q = spawn_pose(self.heightfield, m.start_xy_m, m.start_yaw_rad, m.rover)
            self.data.qpos[m.qpos_root: m.qpos_root + 7] = q
            m.cmd = (0.0, 0.0)
        mujoco.mj_forward(self.model, self.data)
        self.data.ctrl[:] = 0.0
        for i in range(round(self.settle_s / self.dt_physics_s)):
            self.advance(1)
            if i > 100 and i % 25 == 0 and float(np.abs(self.data.qvel).max()) < 2e-3:
                break
        self.data.time = 0.0

    def advance(self, nstep: int) -> None:
        """Step the physics of every robot ``nstep`` times with their current commands."""
        soils = [m.wheel_soil for m in self.members if m.wheel_soil is not None]
        if not soils:
            mujoco.mj_step(self.model, self.data, nstep=int(nstep))
        else:
            for _ in range(int(nstep)):
                for s in soils:
                    s.apply()
                mujoco.mj_step(self.model, self.data)
        if not np.isfinite(self.data.qpos).all():
            raise RuntimeSimError(f"simulation diverged at t = {self.data.time:.3f} s")

    def member(self, name: str) -> TeamMember:
        """The robot called ``name``."""
        for m in self.members:
            if m.name == name:
                return m
        raise ConfigError(f"no robot {name!r} in the team; robots: "
                          f"{[m.name for m in self.members]}")


class TeamMember(RoverView):
    """One robot of a :class:`TeamSim`: a :class:`~marsscene.sim.rover_sim.RoverSim`'s readings
    and commands for its own rover; the physics is stepped by the team."""

    def __init__(self, team: TeamSim, placement: Placement) -> None:
        self.team, self.name = team, placement.name
        self.prefix = f"{placement.name}/"
        self.rover, self.run = placement.rover, placement.run
        self.model, self.data = team.model, team.data
        self.scene_dir, self.scene_xml = team.scene_dir, team.scene_xml
        self.heightfield, self.dt_physics_s = team.heightfield, team.dt_physics_s
        self.rocks_kept, self.soil_map = team.rocks_kept, team.soil_map
        self.start_xy_m = (float(placement.start_xy_m[0]), float(placement.start_xy_m[1]))
        self.start_yaw_rad = float(placement.start_yaw_rad)
        self.substeps = round(1.0 / (self.run.control_hz * self.dt_physics_s))
        self._ids()
        self.wheel_soil = None if self.soil_map is None else WheelSoil.of(self, self.soil_map)
        m = self.model
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in m.geom_bodyid]
        self._others = [  # each other robot's collision geoms
            np.flatnonzero([(m.geom_contype[g] != 0 and names[g].startswith(f"{p.name}/"))
                            for g in range(m.ngeom)])
            for p in team.placements if p.name != placement.name]
        bodies = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in m.dof_bodyid]
        self._dofs = np.flatnonzero([b.startswith(self.prefix) for b in bodies])  # its own

    def place(self, *, xy_m: tuple[float, float], yaw_rad: float) -> None:
        """Move this robot to ``xy_m`` facing ``yaw_rad``, set on the terrain at rest (its own
        joints only; the others drive on), without resetting the clock (a live teleport)."""
        q = spawn_pose(self.heightfield, xy_m, yaw_rad, self.rover)
        self.data.qpos[self.qpos_root: self.qpos_root + 7] = q
        self.data.qvel[self._dofs] = 0.0
        self.reset_soil()
        mujoco.mj_forward(self.model, self.data)

    def other_robots(self) -> Any:
        """The collision geoms of every other robot, as boxes at the current state (what this
        robot's LiDAR casts against besides the scene; None alone)."""
        if not self._others:
            return None
        return [robot_boxes(self.model, self.data, geoms) for geoms in self._others]

    def reset_soil(self) -> None:
        if self.wheel_soil is not None:
            self.wheel_soil.reset()

    def build_spec(self) -> Any:
        """The team's spec (a mast camera renders every robot)."""
        return self.team.build_spec()

    @property
    def outer_heightfield(self) -> Heightfield | None:
        gid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_outer")
        return scene_heightfield(self.model, "terrain_outer") if gid >= 0 else None

    def advance(self, nstep: int) -> None:
        raise RuntimeSimError("a team member is stepped with its team (TeamSim.advance)")
