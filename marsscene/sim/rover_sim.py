"""``RoverSim``: a built scene + the rover in MuJoCo, driven by ``cmd_vel``.

The scene's ``mjcf/scene.xml`` is loaded with :class:`mujoco.MjSpec` and the rover is attached
in memory (prefix ``rover/``), so ``scene.xml`` stays rover-free. :meth:`RoverSim.apply` sets the
``cmd_vel`` targets and :meth:`RoverSim.advance` steps the physics; a control period (default
50 Hz) is ``substeps`` physics steps (10 of 2 ms).
"""

from __future__ import annotations

import math
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
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, wheel_commands
from marsscene.rover.spawn import SETTLE_S, spawn_pose
from marsscene.sim.corridor import CORRIDOR_M, cull_scene_xml
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.terrain import scene_heightfield
from marsscene.sim.wheel_soil import WheelSoil, soften_terrain, soil_map_of
from marsscene.soil.map import read_soil_map
from marsscene.terrain.heightfield import Heightfield
from marsscene.transforms import yaw_of_quat

__all__ = ["PREFIX", "RoverSim", "load_scene_spec", "rover_indices"]

PREFIX = "rover/"


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


def rover_indices(m: Any) -> dict[str, Any]:
    """Where the rover (attached with :data:`PREFIX`) lives in a compiled model: body, root
    joint, actuators, joints, wheel geoms, sites, camera and IMU sensor addresses."""
    name = lambda kind, n: mujoco.mj_name2id(m, kind, PREFIX + n)  # noqa: E731
    root = name(mujoco.mjtObj.mjOBJ_JOINT, "root")
    drive_j = [name(mujoco.mjtObj.mjOBJ_JOINT, j) for j in DRIVE_JOINTS]
    steer_j = [name(mujoco.mjtObj.mjOBJ_JOINT, j) for j in STEER_JOINTS]
    acc = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, PREFIX + "imu_accel")
    gyr = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, PREFIX + "imu_gyro")
    return {
        "base_id": name(mujoco.mjtObj.mjOBJ_BODY, "base_link"),
        "qpos_root": int(m.jnt_qposadr[root]),
        "qvel_root": int(m.jnt_dofadr[root]),
        "drive_act": np.array([name(mujoco.mjtObj.mjOBJ_ACTUATOR, j) for j in DRIVE_JOINTS]),
        "steer_act": np.array([name(mujoco.mjtObj.mjOBJ_ACTUATOR, j) for j in STEER_JOINTS]),
        "drive_dof": np.array([m.jnt_dofadr[j] for j in drive_j]),
        "steer_qpos": np.array([m.jnt_qposadr[j] for j in steer_j]),
        "wheel_geoms": np.array([name(mujoco.mjtObj.mjOBJ_GEOM, "wheel_" + j[-2:])
                                 for j in DRIVE_JOINTS]),
        "chassis_geom": name(mujoco.mjtObj.mjOBJ_GEOM, "chassis"),
        "imu_site": name(mujoco.mjtObj.mjOBJ_SITE, "imu"),
        "lidar_site": name(mujoco.mjtObj.mjOBJ_SITE, "lidar"),
        "camera_id": name(mujoco.mjtObj.mjOBJ_CAMERA, "navcam"),
        "_acc_adr": int(m.sensor_adr[acc]),
        "_gyr_adr": int(m.sensor_adr[gyr]),
    }


class RoverSim:
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

    def _ids(self) -> None:
        ix = rover_indices(self.model)
        self.base_id = ix["base_id"]
        self.qpos_root, self.qvel_root = ix["qpos_root"], ix["qvel_root"]
        self.drive_act, self.steer_act = ix["drive_act"], ix["steer_act"]
        self.drive_dof, self.steer_qpos = ix["drive_dof"], ix["steer_qpos"]
        self.wheel_geoms, self.chassis_geom = ix["wheel_geoms"], ix["chassis_geom"]
        self.imu_site, self.lidar_site = ix["imu_site"], ix["lidar_site"]
        self.camera_id = ix["camera_id"]
        self._acc_adr, self._gyr_adr = ix["_acc_adr"], ix["_gyr_adr"]

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
    def apply(self, v_m_s: float, omega_rad_s: float) -> None:
        """Set actuator targets for ``cmd_vel`` (clipped to the actuator ranges by MuJoCo)."""
        rates, steer = wheel_commands(float(v_m_s), float(omega_rad_s), self.rover)
        self.data.ctrl[self.drive_act] = rates
        self.data.ctrl[self.steer_act] = steer
        self.cmd = (float(v_m_s), float(omega_rad_s))

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

    # ---- camera ------------------------------------------------------------------------------
    @property
    def outer_heightfield(self) -> Heightfield | None:
        """A level-of-detail scene's coarse outer terrain (``terrain_outer``; its focus posts
        lowered under the focus terrain), or None."""
        gid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "terrain_outer")
        return scene_heightfield(self.model, "terrain_outer") if gid >= 0 else None

    def make_renderer(self, *, rng: np.random.Generator | None = None,
                      config: Any = None) -> Any:
        """An offscreen mast-camera renderer (:class:`marsscene.sensors.camera.MastCamera`).

        ``rng`` draws sensor noise when ``CameraConfig.sensor_noise`` is on; ``config`` (a
        ``CameraConfig``) replaces the run's camera.
        """
        from marsscene.sensors.camera import MastCamera

        return MastCamera(self, rng=rng, config=config)

    def render(self, renderer: Any) -> tuple[NDArray[np.uint8], NDArray[np.float32] | None]:
        """RGB (H, W, 3) uint8 and depth (H, W) float32 in m (None if depth is off)."""
        return renderer.render(self)

    def camera_intrinsics(self, side: str | None = None) -> dict[str, Any]:
        """Pinhole intrinsics of the mast camera (OpenCV convention, pixels).

        ``side = "left"`` / ``"right"``: one view of the rectified stereo pair (same
        intrinsics; the right camera sits ``baseline_m`` along the left camera's +x).
        """
        cam = self.run.camera
        w, h = (cam.width_px, cam.height_px) if cam is not None else (640, 480)
        fovy = math.radians(float(self.model.cam_fovy[self.camera_id]))
        f = 0.5 * h / math.tan(fovy / 2)
        extra: dict[str, Any] = {}
        if side is not None:
            b = cam.stereo_baseline_m if cam is not None else 0.424
            extra = {
                "side": side,
                "baseline_m": b,
                "rectified": True,
                "T_left_right_m": [b, 0.0, 0.0],
                "offset_from_navcam_m": [(-0.5 if side == "left" else 0.5) * b, 0.0, 0.0],
            }
        return {
            **extra,
            "width": w,
            "height": h,
            "fx": f,
            "fy": f,
            "cx": w / 2,
            "cy": h / 2,
            "depth_unit_m": 0.001,
            "frame": "optical: x right, y down, z forward",
        }

    def write_rover_xml(self, path: str | Path | None = None) -> Path:
        """Write the rover MJCF (default: beside ``scene.xml``, as ``rover.xml``)."""
        target = Path(path) if path is not None else self.scene_xml.parent / "rover.xml"
        return write_atomic(target, self.rover_xml)

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    # ---- state -------------------------------------------------------------------------------
    def pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Ground-truth ``base_link`` pose: position (3,) in m and quaternion (w, x, y, z)."""
        q = self.data.qpos[self.qpos_root : self.qpos_root + 7]
        return q[:3].copy(), q[3:7].copy()

    def yaw_rad(self) -> float:
        """Ground-truth heading of ``base_link`` (rad, counter-clockwise from +x)."""
        return float(yaw_of_quat(self.data.qpos[self.qpos_root + 3: self.qpos_root + 7]))

    def site_twist(self, site_id: int) -> NDArray[np.float64]:
        """A site's angular and linear velocity (rad/s, m/s; world frame), ``(wx, wy, wz, vx,
        vy, vz)``."""
        twist = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_SITE, site_id,
                                 twist, 0)
        return twist

    def wheel_rates(self) -> NDArray[np.float64]:
        """True wheel angular speeds (rad/s), DRIVE_JOINTS order."""
        return self.data.qvel[self.drive_dof].copy()

    def steer_angles(self) -> NDArray[np.float64]:
        """True corner steering angles (rad), STEER_JOINTS order."""
        return self.data.qpos[self.steer_qpos].copy()

    def imu_true(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Noise-free specific force (m/s^2, incl. gravity) and angular rate (rad/s), IMU frame."""
        s = self.data.sensordata
        return s[self._acc_adr : self._acc_adr + 3].copy(), s[
            self._gyr_adr : self._gyr_adr + 3
        ].copy()

    def wheels_in_contact(self) -> NDArray[np.bool_]:
        """Which of the six wheels touch anything (DRIVE_JOINTS order)."""
        n = self.data.ncon
        g = np.concatenate([self.data.contact.geom1[:n], self.data.contact.geom2[:n]])
        return np.isin(self.wheel_geoms, g)

