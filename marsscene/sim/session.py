"""``DriveSession``: one drive as a stepper, the loop that every drive runs.

Every sensor is sampled on one simulation clock. The physics advances in ticks of the greatest
common divisor of all sensor periods; at each control tick (``run.control_hz``) the session
reads the wheel encoders, integrates the odometry and hands an
:class:`~marsscene.sim.control.Observation` out (:meth:`DriveSession.observe`); the command that
comes back is applied and logged (:meth:`DriveSession.act`); then the IMU, LiDAR and camera
sample at the ticks up to the next control tick (:meth:`DriveSession.advance`).

:func:`marsscene.sim.driver.drive_sim` runs a controller through it; a Gymnasium environment or
a live bridge can hold it and step it themselves. Each sample goes to the run folder's
:class:`~marsscene.sim.run_writer.RunWriter` and to every **listener** (an object with any of
the writer's methods ``control``, ``imu``, ``lidar``, ``camera``, ``stereo``), e.g. a publisher
that sends each sample on as it is made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.errors import RuntimeSimError
from marsscene.sensors.camera_world import read_rock_catalog
from marsscene.sensors.imu import ImuNoise
from marsscene.sensors.lidar import Lidar
from marsscene.sensors.odometry import WheelOdometry, measure_wheels
from marsscene.sim.control import CameraFrame, Observation
from marsscene.sim.run_writer import RunWriter

__all__ = ["DriveSession", "SessionOptions", "sensor_rng"]

_STREAMS = ("control", "imu", "lidar", "camera", "stereo")
#: Each sensor's child of the session's noise stream, by a fixed index: turning one sensor on
#: or off never moves another's noise (a LiDAR-only drive scans as a camera + LiDAR drive does).
_SENSOR_CHILD = {"camera": 0, "lidar": 1}


def sensor_rng(rng: np.random.Generator, sensor: str) -> np.random.Generator:
    """The noise stream of ``sensor``: the child of ``rng``'s seed sequence at the sensor's
    fixed index (what ``rng.spawn`` gives in that place on a fresh generator)."""
    seq = rng.bit_generator.seed_seq
    if not isinstance(seq, np.random.SeedSequence):
        raise RuntimeSimError("sensor noise needs a generator seeded by a SeedSequence")
    child = np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, _SENSOR_CHILD[sensor]),
                                   pool_size=seq.pool_size)
    return np.random.Generator(type(rng.bit_generator)(child))


def _period(sim: Any, rate_hz: float) -> int:
    """Physics steps per sample at ``rate_hz`` (it must divide the physics rate)."""
    steps = 1.0 / (rate_hz * sim.dt_physics_s)
    if steps < 1.0 - 1e-9 or abs(steps - round(steps)) > 1e-6:
        raise RuntimeSimError(f"a rate of {rate_hz:g} Hz does not divide the "
                              f"{1.0 / sim.dt_physics_s:g} Hz physics rate")
    return round(steps)


@dataclass(frozen=True)
class SessionOptions:
    """What a drive's session does with its samples besides logging them: one object that
    :func:`marsscene.drive` fills and hands down to the session.

    Parameters
    ----------
    keep_sensors : bool
        Keep LiDAR scans, images and IMU samples in memory (:attr:`DriveSession.scans` ...).
    lidar_files : bool
        Write each LiDAR scan to the run folder (False: to the listeners only, stamps kept).
    listeners : tuple
        Objects that receive every sample as the run writer does.
    jpeg_cache : JpegCache, optional
        Also JPEG-encode every colour frame into this cache (for a bag written right after).
    sensors_at_observe : bool
        Take the camera frame and the LiDAR scan when :meth:`DriveSession.observe` is called
        (an environment's observation at each control step) instead of at their own rates.
    """

    keep_sensors: bool = False
    lidar_files: bool = True
    listeners: tuple[Any, ...] = ()
    jpeg_cache: Any = None
    sensors_at_observe: bool = False


class DriveSession:
    """One drive of ``sim`` (a reset :class:`~marsscene.sim.rover_sim.RoverSim`), step by step.

    Parameters
    ----------
    sim : RoverSim
    rng : numpy.random.Generator
        Sensor noise (e.g. ``stage_rng(seed, "sensors")``); the LiDAR and camera draw from
        their own children of it (:func:`sensor_rng`), so adding a sensor never moves another
        sensor's noise.
    out_dir : path, optional
        Run folder; nothing is written if omitted.
    options : SessionOptions, optional
        Samples kept in memory, LiDAR files, listeners, the bag's JPEG cache.
    meta : dict, optional
        Extra ``run.json`` entries (``pursuit``: the follower's config; ``controller``).
    renderer, lidar : optional
        The camera renderer and the LiDAR of an earlier session of ``sim``, reused (restarted
        with this session's noise streams) instead of built again (``close(release=False)``
        keeps them for the next session).
    """

    def __init__(self, sim: Any, *, rng: np.random.Generator, out_dir: str | Path | None = None,
                 options: SessionOptions | None = None, meta: dict[str, Any] | None = None,
                 renderer: Any = None, lidar: Lidar | None = None):
        run = sim.run
        opts = options if options is not None else SessionOptions()
        self.sim, self.rng, self.keep = sim, rng, opts.keep_sensors
        self.at_observe = opts.sensors_at_observe
        self.periods = {"control": _period(sim, run.control_hz), "imu": _period(sim, run.imu_hz)}
        self.renderer = None
        self.trigger_m = run.camera.trigger_distance_m if run.camera is not None else None
        self.next_frame_m = 0.0
        if run.camera is not None:
            if self.trigger_m is None and not self.at_observe:
                self.periods["camera"] = _period(sim, run.camera.rate_hz)
            if renderer is None:
                self.renderer = sim.make_renderer(rng=sensor_rng(rng, "camera"))
            else:  # a renderer of an earlier drive of this simulator (its scene costs seconds)
                self.renderer = renderer
                renderer.restart(sim, rng=sensor_rng(rng, "camera"))
        self.lidar = lidar
        if run.lidar is not None:  # its own stream: LiDAR noise never moves IMU/wheel noise
            if not self.at_observe:
                self.periods["lidar"] = _period(sim, run.lidar.spec.rate_hz)
            if lidar is None:
                self.lidar = Lidar(run.lidar, rng=sensor_rng(rng, "lidar"),
                                   rocks=read_rock_catalog(Path(sim.scene_dir)))
            else:  # an earlier drive's LiDAR (its ray-casting structures are built once)
                lidar.rng = sensor_rng(rng, "lidar")
        self.stereo = self.renderer is not None and self.renderer.stereo_ids is not None
        out = Path(out_dir) if out_dir is not None else None
        self.writer = RunWriter(out, sim, lidar=self.lidar is not None,
                                camera=self.renderer is not None, stereo=self.stereo,
                                meta=meta or {}, jpeg_cache=opts.jpeg_cache,
                                lidar_files=opts.lidar_files)
        self.sinks: dict[str, list[Any]] = {
            s: [x for x in (self.writer, *opts.listeners) if hasattr(x, s)] for s in _STREAMS}
        pos0, _ = sim.pose()
        self.odo = WheelOdometry(sim.rover, pos0[0], pos0[1], pos0[2], sim.yaw_rad())
        self.tick = math.gcd(*self.periods.values())
        self.k = 0  # physics steps since the start
        self.t_s = 0.0  # time of the last tick sampled
        self._next_report = 1.0  # sim time of the next progress report and log flush
        self.distance_m, self._last_xy = 0.0, (float(pos0[0]), float(pos0[1]))
        self.n_control = self.n_lidar = self.n_cam = 0
        self.imu_rows: list[np.ndarray] = []
        self.scans: list[dict[str, Any]] = []
        self.images: list[tuple[np.ndarray, np.ndarray | None]] = []
        self.stereo_images: list[tuple[np.ndarray, np.ndarray]] = []
        self._lidar_pool: ThreadPoolExecutor | None = None
        self._pending: tuple[float, Future[dict[str, Any]]] | None = None
        self._measured: tuple[Any, ...] | None = None
        self._imu_last: tuple[float, np.ndarray, np.ndarray] | None = None
        self._frame: CameraFrame | None = None
        self._scan: dict[str, Any] | None = None
        self.imu_noise = ImuNoise(run.noise, run.imu_hz, rng=rng)  # draws the turn-on biases

    # ---- the control step ------------------------------------------------------------------
    def observe(self) -> Observation:
        """Read the encoders, integrate the odometry to now, and the observation of this step.

        Call once per control tick (after :meth:`advance` returned True, or at the start).
        With ``sensors_at_observe`` the camera and LiDAR are sampled now."""
        sim = self.sim
        if self.at_observe:
            self._sample_now(self.k * sim.dt_physics_s)
        pos, quat = sim.pose()
        rates, steer = measure_wheels(sim.wheel_rates(), sim.steer_angles(), sim.run.noise,
                                      rng=self.rng)
        if self.k > 0:
            self.odo.update(rates, steer, self.periods["control"] * sim.dt_physics_s)
        opos, oquat = self.odo.pose()
        self._measured = (pos, quat, rates, steer, opos, oquat)
        imu = self._imu_last
        return Observation(
            t_s=self.k * sim.dt_physics_s, step=self.n_control, odom_xyz_m=opos,
            odom_quat_wxyz=oquat, odom_yaw_rad=float(self.odo.yaw_rad), wheel_rates_rad_s=rates,
            steer_rad=steer, imu_t_s=imu[0] if imu else None,
            accel_m_s2=imu[1] if imu else None, gyro_rad_s=imu[2] if imu else None,
            cmd=sim.cmd, gt_xyz_m=pos, gt_quat_wxyz=quat, gt_yaw_rad=sim.yaw_rad(),
            camera=self._frame, lidar=self.latest_scan)

    def act(self, v_m_s: float, omega_rad_s: float) -> None:
        """Apply ``cmd_vel`` at this control tick and log the step (after :meth:`observe`)."""
        assert self._measured is not None, "observe() before act()"
        sim, t = self.sim, self.k * self.sim.dt_physics_s
        pos, quat, rates, steer, opos, oquat = self._measured
        self._measured = None
        sim.apply(v_m_s, omega_rad_s)
        self.distance_m += math.hypot(pos[0] - self._last_xy[0], pos[1] - self._last_xy[1])
        self._last_xy = (float(pos[0]), float(pos[1]))
        for sink in self.sinks["control"]:
            sink.control(t, v_m_s, omega_rad_s, rates, steer, (pos, quat), (opos, oquat))
        self.n_control += 1

    def advance(self, steps_limit: float = math.inf,
                progress: Callable[[float], None] | None = None) -> bool:
        """Sample the sensors due at this tick and the ticks after it, stepping the physics,
        up to the next control tick. False once the step count passes ``steps_limit``
        (nothing more is due), True at the next control tick (call :meth:`observe`).

        ``progress(t_s)`` is called at each whole simulated second (the logs are flushed)."""
        while True:
            self.sample_due(progress)
            self.sim.advance(self.tick)
            if not self.stepped(self.tick, steps_limit):
                return False
            if self.control_due():
                return True

    def sample_due(self, progress: Callable[[float], None] | None = None) -> None:
        """Sample the sensors due at this physics step (one tick of :meth:`advance`, for a
        loop that steps the physics itself: a team's)."""
        periods, k = self.periods, self.k
        t = k * self.sim.dt_physics_s
        if k % periods["imu"] == 0:
            self._sample_imu(t)
        if "lidar" in periods and k % periods["lidar"] == 0:
            self._start_scan(t)
        if self.renderer is not None and not self.at_observe and self._camera_due(k):
            self._frame_at(t)
        if t >= self._next_report:
            self.writer.flush()
            if progress is not None:
                progress(t)
            self._next_report += 1.0
        self.t_s = t

    def stepped(self, nstep: int, steps_limit: float = math.inf) -> bool:
        """The physics went ``nstep`` steps on; False once past ``steps_limit``."""
        self.k += nstep
        return self.k <= steps_limit

    def control_due(self) -> bool:
        """This physics step is a control tick (:meth:`observe` and :meth:`act` are due)."""
        return self.k % self.periods["control"] == 0

    # ---- sensors ---------------------------------------------------------------------------
    def _sample_imu(self, t: float) -> None:
        acc_true, gyr_true = self.sim.imu_true()
        acc, gyr = self.imu_noise.measure(acc_true, gyr_true)
        bias = (*self.imu_noise.gyro_bias_rad_s, *self.imu_noise.accel_bias_m_s2)
        for sink in self.sinks["imu"]:
            sink.imu(t, acc, gyr, acc_true, gyr_true, bias)
        self._imu_last = (t, acc, gyr)
        if self.keep:
            self.imu_rows.append(np.concatenate([[t], acc, gyr]))

    def _start_scan(self, t: float) -> None:
        """Read the LiDAR's pose now; cast on the helper thread while the simulation goes on
        (the previous scan is collected first, so scans are written in order)."""
        assert self.lidar is not None
        sim = self.sim
        others = getattr(sim, "other_robots", None)  # a team's: the LiDAR sees them
        cast = self.lidar.prepare(sim.model, sim.data, sim.lidar_site, sim.heightfield,
                                  twist=sim.site_twist(sim.lidar_site),
                                  boxes=None if others is None else others())
        self.collect_scan()
        if self._lidar_pool is None:
            self._lidar_pool = ThreadPoolExecutor(1, thread_name_prefix="marsscene-lidar")
        self._pending = (t, self._lidar_pool.submit(cast))

    def _sample_now(self, t: float) -> None:
        """The camera frame and the LiDAR scan of this instant (``sensors_at_observe``)."""
        if self.renderer is not None:
            self._frame_at(t)
        if self.lidar is not None:
            self._start_scan(t)

    def collect_scan(self) -> None:
        """Wait for the scan on the helper thread (if any) and hand it to the sinks."""
        if self._pending is None:
            return
        t, future = self._pending
        self._pending = None
        scan = future.result()
        for sink in self.sinks["lidar"]:
            sink.lidar(t, self.n_lidar, scan)
        self._scan = {"t": t, **scan}
        if self.keep:
            self.scans.append(self._scan)
        self.n_lidar += 1

    def latest_scan(self) -> dict[str, Any] | None:
        """The newest finished LiDAR scan (waits for the one being cast)."""
        self.collect_scan()
        return self._scan

    def _frame_at(self, t: float) -> None:
        assert self.renderer is not None
        rgb, depth = self.sim.render(self.renderer)
        for sink in self.sinks["camera"]:
            sink.camera(t, self.n_cam, rgb, depth)
        self._frame = CameraFrame(t, rgb, depth)
        if self.stereo:
            pair = self.renderer.render_stereo(self.sim)
            for sink in self.sinks["stereo"]:
                sink.stereo(t, self.n_cam, pair)
            if self.keep:
                self.stereo_images.append(pair)
        if self.keep:
            self.images.append((rgb, depth))
        self.n_cam += 1

    def _camera_due(self, k: int) -> bool:
        """A frame at this physics step: every camera period, or (``trigger_distance_m``) at
        the first control step at or past the next multiple of the trigger distance."""
        if self.trigger_m is None:
            return k % self.periods["camera"] == 0
        if k % self.periods["control"] != 0 or self.distance_m < self.next_frame_m:
            return False
        self.next_frame_m = (math.floor(self.distance_m / self.trigger_m) + 1) * self.trigger_m
        return True

    def close(self, *, release: bool = True) -> None:
        """Collect the last scan, stop the helper thread, close the writer and (unless
        ``release`` is false: kept for the next session) the renderer."""
        self.collect_scan()
        if self._lidar_pool is not None:
            self._lidar_pool.shutdown()
            self._lidar_pool = None
        self.writer.close()
        if self.renderer is not None and release:
            self.renderer.close()
