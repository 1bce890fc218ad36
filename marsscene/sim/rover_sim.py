"""``RoverSim``: a built scene + the rover in MuJoCo, driven by ``cmd_vel``.

The scene's ``mjcf/scene.xml`` is loaded with :class:`mujoco.MjSpec` and the rover is attached
in memory (prefix ``rover/``), so ``scene.xml`` stays rover-free. :meth:`RoverSim.apply` sets the
``cmd_vel`` targets and :meth:`RoverSim.advance` steps the physics; a control period (default
50 Hz) is ``substeps`` physics steps (10 of 2 ms).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import RuntimeSimError
from marsscene.rover.config import CameraConfig, RoverConfig, RunConfig
from marsscene.rover.spawn import SETTLE_S, spawn_pose
from marsscene.sim.corridor import CORRIDOR_M, cull_scene_xml
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.rover_view import PREFIX, RoverView, rover_indices
from marsscene.sim.terrain import scene_heightfield
from marsscene.sim.wheel_soil import WheelSoil, soften_terrain, soil_map_of
from marsscene.soil.map import read_soil_map
from marsscene.terrain.heightfield import Heightfield

__all__ = ["PREFIX", "RoverSim", "load_scene_spec", "rover_indices"]


def load_scene_spec(
    scene_dir: str | Path,
    *,
    corridor_xy_m: Any = None,
    corridor_m: float = CORRIDOR_M,
    rock_contacts: bool = True,
) -> tuple[Any, Path, tuple[int, int]]:
    """Open ``scene_dir/mjcf/scene.xml`` as an ``MjSpec`` (clear error if it is missing).

    With a corridor polyline, rock geoms farther than ``corridor_m`` from it are left out
    (:func:`marsscene.sim.corridor.cull_scene_xml`). With ``rock_contacts=False`` the rock geoms
    collide with nothing (``contype``, ``conaffinity`` 0): MuJoCo then makes no convex hulls,
    the compile takes about a third of the time, and the rocks' bounding boxes, what
    :func:`~marsscene.sim.world.world_obstacles` reads, are the same (a world to plan routes
    on, never simulated). Returns ``(spec, xml path, (rocks kept, rocks in the scene))``.
    """
    root = Path(scene_dir)
    xml = root / "mjcf" / "scene.xml"
    if not root.is_dir():
        raise RuntimeSimError(f"scene directory {root} does not exist")
    if not xml.is_file():
        raise RuntimeSimError(
            f"{root} is not a built scene: {xml} is missing (build one with `marsscene build`)"
        )
    text = xml.read_text(encoding="utf-8")
    total = kept = text.count('<geom name="rock_')
    try:
        if corridor_xy_m is None or total == 0:
            spec = mujoco.MjSpec.from_file(str(xml))
        else:
            culled, kept, total = cull_scene_xml(text, corridor_xy_m, corridor_m)
            files = set(re.findall(r'file="([^"]+)"', culled))
            assets = {f: (xml.parent / f).read_bytes() for f in files}
            spec = mujoco.MjSpec.from_string(culled, assets=assets)
    except (ValueError, OSError) as err:  # mujoco raises ValueError with the parser message
        raise RuntimeSimError(f"{xml}: MuJoCo cannot parse it: {err}") from None
    if not rock_contacts:
        for geom in spec.geoms:
            if geom.name.startswith("rock_"):
                geom.contype = geom.conaffinity = 0
    return spec, xml, (kept, total)


class RoverSim(RoverView):
    """A rover on a built scene.

    Parameters
    ----------
    scene_dir : path-like
        Folder written by :func:`marsscene.write_scene` (needs ``mjcf/scene.xml``).
    rover : RoverConfig, optional
    run : RunConfig, optional
        Control rate and sensor configs.
    start_xy_m : tuple of float, optional
        Spawn position (default: the terrain centre).
    start_yaw_rad : float
        Spawn heading, counter-clockwise from east.
    edit_spec : callable, optional
        ``f(spec)`` called on the scene ``MjSpec`` before compiling (e.g. to add obstacles).
    contact_corridor_xy_m : array_like of shape (N, 2), optional
        A polyline (e.g. the route). When given, scene rock geoms farther than
        ``contact_corridor_m`` from it are left out of the simulation: MuJoCo recomputes every
        geom's pose each step, so 1000 static rock meshes cost ~20 us per 2 ms step. The rover
        only meets rocks near its route; the number kept is in :attr:`rocks_kept`.
    contact_corridor_m : float
        Half-width of the corridor (in m).
    settle_s : float
        Maximum settling time after spawning (sim time is reset to 0 afterwards).
    soil : str, Soil or SoilMap, optional
        Deformable soil under the wheels (:mod:`marsscene.sim.wheel_soil`): a soil's name
        (:func:`marsscene.rover.terramechanics.soils`), a ``Soil``, or a map of them. None:
        the run's (``RunConfig.soil``), else the scene's soil map (``soil/``, built with
        ``[soil] enabled``), else rigid; ``"rigid"``: the terrain's rigid Coulomb contact.
    """

    def __init__(
        self,
        scene_dir: str | Path,
        *,
        rover: RoverConfig | None = None,
        run: RunConfig | None = None,
        start_xy_m: tuple[float, float] | None = None,
        start_yaw_rad: float = 0.0,
        edit_spec: Callable[[Any], None] | None = None,
        settle_s: float = SETTLE_S,
        contact_corridor_xy_m: Any = None,
        contact_corridor_m: float = CORRIDOR_M,
        soil: Any = None,
    ) -> None:
        self.rover = rover if rover is not None else RoverConfig()
        self.run = run if run is not None else RunConfig()
        self.scene_dir = Path(scene_dir)
        choice = soil if soil is not None else self.run.soil
        self.soil_map = read_soil_map(self.scene_dir) if choice is None else soil_map_of(choice)
        fovy = (self.run.camera or CameraConfig()).fovy_deg  # the navcam, logged or not
        self.rover_xml = rover_mjcf(self.rover, camera_fovy_deg=fovy)
        self._edit_spec = edit_spec
        self._corridor = (
            None if contact_corridor_xy_m is None
            else np.asarray(contact_corridor_xy_m, dtype=np.float64).reshape(-1, 2)
        )
        self._corridor_m = float(contact_corridor_m)
        self.rocks_kept: tuple[int, int] = (0, 0)
        spec = self.build_spec()
        try:
            self.model = spec.compile()
        except Exception as err:
            raise RuntimeSimError(
                f"{self.scene_xml}: cannot compile scene + rover: {err}"
            ) from None
        self.spec = spec
        self.data = mujoco.MjData(self.model)
        self.heightfield: Heightfield = scene_heightfield(self.model)
        # The LiDAR ray-marches the terrain itself (fast); keep MuJoCo rays off the hfields by
        # moving them to geom group 3 (the camera renders group 3 too). scene.xml is untouched.
        # A level-of-detail scene's coarse "terrain_outer" goes there too (LiDAR: focus only).
        for name in ("terrain", "terrain_outer"):
            gid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, name)
            if gid >= 0:
                self.model.geom_group[gid] = 3
        self._vis = mujoco.MjvOption()
        self._vis.geomgroup[3] = 1
        if self.run.physics_hz is not None:
            self.model.opt.timestep = 1.0 / self.run.physics_hz
        self.dt_physics_s = float(self.model.opt.timestep)
        self.substeps = round(1.0 / (self.run.control_hz * self.dt_physics_s))
        self._ids()
        self.wheel_soil = None if self.soil_map is None else WheelSoil.of(self, self.soil_map)
        self.settle_s = settle_s
        x0, y0, x1, y1 = self.heightfield.bounds_xy_m
        self.start_xy_m = start_xy_m if start_xy_m is not None else ((x0 + x1) / 2, (y0 + y1) / 2)
        self.start_yaw_rad = float(start_yaw_rad)
        self.reset()

    # ---- setup -------------------------------------------------------------------------------
    def build_spec(self) -> Any:
        """A fresh ``MjSpec`` of scene + rover (+ ``edit_spec``), not yet compiled."""
        spec, self.scene_xml, self.rocks_kept = load_scene_spec(
            self.scene_dir, corridor_xy_m=self._corridor, corridor_m=self._corridor_m
        )
        rover_spec = mujoco.MjSpec.from_string(self.rover_xml)
        spec.attach(rover_spec, prefix=PREFIX, frame=spec.worldbody.add_frame())
        if self._edit_spec is not None:
            self._edit_spec(spec)
        if self.soil_map is not None:
            soften_terrain(spec)
        return spec

    def _spawn_pose(self, xy: tuple[float, float], yaw: float) -> NDArray[np.float64]:
        return spawn_pose(self.heightfield, xy, yaw, self.rover)

    def reset(
        self,
        *,
        xy_m: tuple[float, float] | None = None,
        yaw_rad: float | None = None,
    ) -> None:
        """Spawn the rover on the terrain at ``xy_m`` facing ``yaw_rad`` (default: the start
        pose), let it settle (wheels braked), set time to 0."""
        mujoco.mj_resetData(self.model, self.data)
        if self.wheel_soil is not None:
            self.wheel_soil.reset()
        xy = xy_m if xy_m is not None else self.start_xy_m
        yaw = self.start_yaw_rad if yaw_rad is None else float(yaw_rad)
        self.data.qpos[self.qpos_root : self.qpos_root + 7] = self._spawn_pose(xy, yaw)
        mujoco.mj_forward(self.model, self.data)
        self.data.ctrl[:] = 0.0
        steps = round(self.settle_s / self.dt_physics_s)
        for i in range(steps):
            self._step(1)
            if i > 100 and i % 25 == 0:
                if float(np.abs(self.data.qvel).max()) < 2e-3:
                    break
        self.data.time = 0.0
        self.cmd = (0.0, 0.0)

    def place(self, *, xy_m: tuple[float, float], yaw_rad: float) -> None:
        """Move the rover to ``xy_m`` facing ``yaw_rad``, set on the terrain at rest, without
        settling or resetting the clock (a live session's teleport; :meth:`reset` restarts)."""
        self.data.qpos[self.qpos_root : self.qpos_root + 7] = self._spawn_pose(xy_m, yaw_rad)
        self.data.qvel[:] = 0.0
        if self.wheel_soil is not None:
            self.wheel_soil.reset()
        mujoco.mj_forward(self.model, self.data)

    # ---- stepping ----------------------------------------------------------------------------
    def advance(self, nstep: int) -> None:
        """Advance the physics ``nstep`` steps with the current actuator targets."""
        self._step(int(nstep))
        if not np.isfinite(self.data.qpos).all():
            raise RuntimeSimError(f"simulation diverged at t = {self.data.time:.3f} s")

    def _step(self, nstep: int) -> None:
        if self.wheel_soil is None:
            mujoco.mj_step(self.model, self.data, nstep=nstep)
            return
        for _ in range(nstep):
            self.wheel_soil.apply()
            mujoco.mj_step(self.model, self.data)

    # ---- scene -------------------------------------------------------------------------------
    @property
    def outer_heightfield(self) -> Heightfield | None:
        """A level-of-detail scene's coarse outer terrain (``terrain_outer``; its focus posts
        lowered under the focus terrain), or None."""
        gid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_outer")
        return scene_heightfield(self.model, "terrain_outer") if gid >= 0 else None

    def write_rover_xml(self, path: str | Path | None = None) -> Path:
        """Write the rover MJCF (default: beside ``scene.xml``, as ``rover.xml``)."""
        target = Path(path) if path is not None else self.scene_xml.parent / "rover.xml"
        return write_atomic(target, self.rover_xml)

