"""``drive_batch``: many drives at once on one MuJoCo Warp model, each written as a CPU drive
writes its run folder.

Each drive has its scene, route (or waypoints), run folder and seed; the batch has one
:class:`~marsscene.rover.config.RunConfig` (sensors, rates, noise). The batch's rover has
sphere wheels (:data:`marsscene.env.batch.env.BATCH_ROVER`) on a heightfield with the rocks as
relief (:mod:`marsscene.env.batch.model`): what this changes against the CPU drive is measured
by ``perf/studies/bench_batch_vs_cpu.py`` (:doc:`/gpu_drives`).
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from marsscene._optional import quiet_warp
from marsscene.errors import ConfigError
from marsscene.rover.config import RunConfig
from marsscene.rover.rates import PHYSICS_HZ
from marsscene.sim.batch.spec import BatchDrive
from marsscene.sim.mission import DriveOptions

__all__ = ["BatchRun", "check_batch_config", "drive_batch"]


@dataclass(frozen=True)
class BatchRun:
    """A finished batch: each drive's run folder and summary, and the batch's wall time."""

    out_dirs: list[Path]
    summaries: list[dict[str, Any]]
    wall_s: float
    device: str

    @property
    def sim_s(self) -> float:
        """The longest drive's simulated seconds."""
        return max(float(s["sim_time_s"]) for s in self.summaries)

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall second of each rover (the batch's longest drive)."""
        return self.sim_s / self.wall_s if self.wall_s > 0 else float("nan")


def _warp(device: str | None) -> tuple[Any, str]:
    try:
        import mujoco_warp  # noqa: F401
        import warp as wp
    except ImportError:
        raise ConfigError('batched drives need MuJoCo Warp: pip install "marsscene[gpu]"'
                          ) from None
    quiet_warp(wp).init()
    name = device or ("cuda:0" if wp.is_cuda_available() else "cpu")
    if name.startswith("cuda") and not wp.is_cuda_available():
        raise ConfigError(f"device {name!r}: Warp sees no CUDA GPU here (use device='cpu')")
    try:
        return wp, str(wp.get_device(name))
    except (RuntimeError, ValueError) as err:
        raise ConfigError(f"device {name!r}: {err}") from None


def check_batch_config(config: RunConfig) -> None:
    """Raise :class:`~marsscene.errors.ConfigError` where a batch of drives cannot run
    ``config`` (a stereo camera, deformable soil)."""
    cam = config.camera
    if cam is not None and cam.stereo:
        raise ConfigError("batched drives have no stereo camera yet")
    if config.soil not in (None, "rigid"):
        raise ConfigError(f"batched drives have rigid ground only (soil = {config.soil!r})")


def drive_batch(drives: Sequence[BatchDrive | dict[str, Any]], *,
                config: RunConfig | None = None, options: DriveOptions | None = None,
                device: str | None = None, physics: Any = None, seed: int = 0,
                workers: int | None = None, progress: Any = None) -> BatchRun:
    """Drive every drive of ``drives`` at once and write their run folders.

    Parameters
    ----------
    drives : sequence of BatchDrive (or dicts of its fields)
        Scene, route or waypoints, run folder and noise seed of each drive.
    config : RunConfig, optional
        Sensors, rates and noise of every drive (default: no camera, no LiDAR, noise-free);
        the camera renders RGB and depth (``camera/rgb``, ``camera/depth``; no depth where the
        camera config has ``depth=False``) by :class:`~marsscene.sensors.batch.BatchCamera`,
        each drive under its scene's lighting (``BatchDrive.tau`` for its dust,
        ``sun_elevation_deg``, ``sun_azimuth_deg`` and ``irradiance_scale`` for its sun,
        ``exposure`` for its camera's).
    options : DriveOptions, optional
        Route authoring, settling and the follower (as :func:`marsscene.drive`).
    device : str, optional
        Warp device: ``"cuda"``/``"cuda:0"`` or ``"cpu"`` (default: a GPU where there is one).
    physics : WarpPhysics, optional
        MuJoCo Warp's solver limits and determinism.
    seed : int
        Seed of the batch's LiDAR noise: each drive draws the stream of ``(seed,
        drive.seed)``, whatever its slot in the batch.
    workers : int, optional
        Threads writing the run folders (default: the CPU cores, at most 16).
    progress : callable, optional
        ``progress(sim_time_s)`` once per simulated second.

    Returns
    -------
    BatchRun
    """
    from marsscene.env.batch.backend import Backend
    from marsscene.env.batch.env import BATCH_ROVER
    from marsscene.env.batch.model import WarpPhysics
    from marsscene.runtime._steps import write_route
    from marsscene.sim.batch.loop import BatchLoop
    from marsscene.sim.batch.noise import BatchNoise
    from marsscene.sim.batch.setup import DriveSim, batch_model, prepare_drives
    from marsscene.sim.batch.sink import BatchSink, DriveSink, SinkPool, meta_of

    _, dev = _warp(device)
    config = config if config is not None else RunConfig()
    options = options if options is not None else DriveOptions()
    physics = physics if physics is not None else WarpPhysics()
    check_batch_config(config)
    items = [d if isinstance(d, BatchDrive) else BatchDrive(**d) for d in drives]
    if config.lidar is not None and not any(d.lidar for d in items):
        config = replace(config, lidar=None)  # no drive logs it: none is cast
    prepared = prepare_drives(items, options)
    physics_hz = config.physics_hz if config.physics_hz is not None else PHYSICS_HZ
    tiled = batch_model(prepared, rover=BATCH_ROVER, physics_hz=physics_hz, physics=physics)
    backend = Backend(dev, "numpy" if dev == "cpu" else None, seed)
    loop = BatchLoop(tiled, prepared, run=config, backend=backend, physics=physics,
                     pursuit=options.pursuit, settle_s=options.settle_s, seed=seed,
                     rover=BATCH_ROVER)
    sinks = []
    lidar = (loop.lidar.ring, loop.lidar.t_s) if loop.lidar is not None else None
    for i, p in enumerate(prepared):
        own = config if p.drive.lidar or config.lidar is None else replace(config, lidar=None)
        sim = DriveSim(own, BATCH_ROVER, loop.dt_s, p.heightfield,
                       scene_dir=Path(p.drive.scene))
        out = Path(os.fspath(p.drive.out_dir))  # type: ignore[arg-type]
        write_route(out, sim, p.route, options)
        sinks.append(DriveSink(i, sim=sim, out=out,
                               meta=meta_of(options.pursuit, dev, i, len(prepared),
                                            BATCH_ROVER),
                               lidar=lidar if own.lidar is not None else None,
                               camera=config.camera is not None, route=p.route))
    pool = SinkPool(sinks, workers if workers is not None else min(16, os.cpu_count() or 1))
    noise = BatchNoise(config.noise, config.imu_hz, [int(p.drive.seed) for p in prepared])
    host = BatchSink(pool, noise, ids=loop.ids, offsets_xy_m=tiled.offsets_xy_m,
                     qpos0=loop.qpos0, rover=BATCH_ROVER,
                     dt_control_s=loop.dt_s * loop.periods["control"])
    t0 = time.perf_counter()

    def put(tick: Any) -> None:
        host.put(tick)
        if progress is not None and tick.flush:
            progress(tick.t_s)

    try:
        loop.drive(put)
    finally:
        host.close()
    wall = time.perf_counter() - t0
    summaries = [s.finish(noise.bias_summary(i)) for i, s in enumerate(sinks)]
    return BatchRun([Path(os.fspath(p.drive.out_dir)) for p in prepared],  # type: ignore[arg-type]
                    summaries, wall, dev)
