"""A world loaded for episodes: its simulator, free ground, height scanner and sensors, kept
compiled between episodes (building them costs about a second; the camera's scene more)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from marsscene.env.observe import HeightScanner, ObsConfig
from marsscene.env.task import NavTask, TaskMap
from marsscene.rover.config import CameraConfig, RoverConfig, RunConfig
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
        self.renderer: Any = None
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
        """The navcam renderer, ``size`` (width, height) px, built at the first call."""
        if self.renderer is None:
            from marsscene.sensors.camera import MastCamera

            cam = CameraConfig(width_px=size[0], height_px=size[1],
                               rate_hz=self.sim.run.control_hz, depth=self.obs.depth,
                               shadows=self.obs.shadows, texture_px=1024)
            self.renderer = MastCamera(self.sim, config=cam)
        return self.renderer

    def restart_sensors(self, *, lidar_rng: np.random.Generator,
                        camera_rng: np.random.Generator) -> None:
        """Start an episode's observed sensors (built at the first episode) with these noise
        streams."""
        lidar = self.obs.lidar_config()
        if lidar is not None:
            if self.lidar is None:
                from marsscene.sensors.camera_world import read_rock_catalog
                from marsscene.sensors.lidar import Lidar

                self.lidar = Lidar(lidar, rng=lidar_rng,
                                   rocks=read_rock_catalog(self.sim.scene_dir))
            self.lidar.rng = lidar_rng
        if self.obs.camera is not None:
            self.camera(self.obs.camera).restart(self.sim, rng=camera_rng)

    def scan_lidar(self) -> dict[str, Any]:
        """A LiDAR scan from the rover's pose now."""
        sim = self.sim
        scan: dict[str, Any] = self.lidar.scan(sim.model, sim.data, sim.lidar_site,
                                               sim.heightfield,
                                               twist=sim.site_twist(sim.lidar_site))
        return scan

    def close(self) -> None:
        if self.renderer is not None:
            self.renderer.close()
            self.renderer = None
