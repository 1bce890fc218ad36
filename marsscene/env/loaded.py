"""A world loaded for episodes: its simulator, free ground and height scanner, and the camera
and LiDAR its episodes' sessions built, kept between episodes (building them costs about a
second; the camera's scene more)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from marsscene.env.observe import HeightScanner, ObsConfig
from marsscene.env.task import NavTask, TaskMap
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.sim.rover_sim import RoverSim
from marsscene.sim.world import scene_obstacles

__all__ = ["LoadedWorld"]


class LoadedWorld:
    """One loaded world: the simulator, its free ground, its height scanner and sensors."""

    def __init__(self, path: Any, run: RunConfig, rover: RoverConfig, task: NavTask,
                 obs: ObsConfig) -> None:
        self.sim = RoverSim(path, run=run, rover=rover, settle_s=0.0)
        self.obs = obs
        obstacles = scene_obstacles(self.sim)
        self.task_map = TaskMap(self.sim.heightfield, obstacles, task)
        self.scanner = (HeightScanner(obs.height_scan, self.sim.heightfield, obstacles)
                        if obs.height_scan is not None else None)
        m = self.sim.model
        self.chassis = np.zeros(m.ngeom, bool)  # per geom id: what it is
        self.chassis[self.sim.chassis_geom] = True
        self.wheel = np.zeros(m.ngeom, bool)
        self.wheel[np.asarray(self.sim.wheel_geoms)] = True
        self.rock = (m.geom_bodyid == 0) & (m.geom_type != mujoco.mjtGeom.mjGEOM_HFIELD)
        self.renderer: Any = None  # the sessions' camera and LiDAR, kept between episodes
        self.lidar: Any = None

    def collided(self) -> bool:
        """The chassis touches anything, or a wheel touches a rock."""
        d = self.sim.data
        g1, g2 = d.contact.geom1[: d.ncon], d.contact.geom2[: d.ncon]
        hit = (self.chassis[g1] | self.chassis[g2] | (self.wheel[g1] & self.rock[g2])
               | (self.wheel[g2] & self.rock[g1]))
        return bool(hit.any())

    # ---- sensors ---------------------------------------------------------------------------
    def camera(self, size: tuple[int, int]) -> Any:
        """The navcam renderer: the observed camera's (kept from the episodes' sessions), or one
        of ``size`` (width, height) px for ``render()``, built at the first call."""
        if self.renderer is None:
            self.renderer = self.sim.make_renderer(config=self.obs.camera_config(
                self.sim.run.control_hz, size))
        return self.renderer

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None
