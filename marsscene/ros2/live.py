"""``serve``: the live rover on ROS 2 (over DDS, no ROS installation), one call.

It sets the rover on the scene as a drive does (:func:`~marsscene.sim.mission.prepare_drive`),
opens a DDS participant (:mod:`.dds`), announces the node (:mod:`.discovery`), and drives with
the :class:`~.bridge.Bridge` as controller and listener (:func:`~marsscene.sim.driver.drive_sim`,
the loop of every drive), so a served session writes the same run folder a drive does; with
``record`` its bag is written from that folder at the end, as ``marsscene drive --bag`` does.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from marsscene.errors import RuntimeSimError
from marsscene.ros2.bridge import Bridge
from marsscene.ros2.dds import Participant
from marsscene.ros2.discovery import publish_discovery_info
from marsscene.ros2.options import Ros2Options
from marsscene.rover.config import RunConfig
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.options import BagOptions
from marsscene.runs.export.sample_messages import SampleMessages
from marsscene.runtime.api import _scene_dir
from marsscene.seeding import stage_rng
from marsscene.sim.driver import DriveInterrupted, DriveProgress, DriveResult, drive_sim
from marsscene.sim.mission import DriveOptions, prepare_drive

if TYPE_CHECKING:
    from marsscene.runs.export.bag import BagSummary
    from marsscene.scene import Scene

__all__ = ["ServeResult", "serve"]

#: Sim-time limit of a session without ``seconds`` (it ends with Ctrl-C or at the goal).
FOREVER_S = 1e9


@dataclass(frozen=True)
class ServeResult:
    """A finished live session.

    Attributes
    ----------
    out_dir : Path or None
        The run folder (None without one).
    result : DriveResult
        Ground truth, odometry, commands and the summary, as a drive's.
    stats : dict
        Messages, bytes and write seconds per topic; commands, time-outs, resets, teleports,
        the goal's sim time.
    wall_s : float
        Wall-clock seconds from the first control step to the end.
    bag : BagSummary or None
        The recorded bag (``record``).
    """

    out_dir: Path | None
    result: DriveResult
    stats: dict[str, Any] = field(default_factory=dict)
    wall_s: float = math.nan
    bag: BagSummary | None = None

    @property
    def sim_s(self) -> float:
        return float(self.result.summary["sim_time_s"])

    @property
    def realtime_factor(self) -> float:
        """Sim seconds per wall second."""
        return self.sim_s / self.wall_s if self.wall_s > 0 else math.nan


def serve(
    scene: str | os.PathLike[str] | Scene,
    *,
    ros: Ros2Options | None = None,
    config: RunConfig | None = None,
    options: DriveOptions | None = None,
    seconds: float | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    record: BagOptions | None = None,
    seed: int = 0,
    progress: Callable[[DriveProgress], None] | None = None,
    ready: Callable[[Bridge], None] | None = None,
) -> ServeResult:
    """Run the rover on ``scene`` live: sensors out, ``cmd_vel`` in, over ROS 2's DDS.

    Parameters
    ----------
    scene : path or Scene
        A built scene folder, or a :class:`~marsscene.Scene`.
    ros : Ros2Options, optional
        Domain, localhost mode, command topic and time-out, pacing, QoS (``docs/ros2_live.md``).
    config : RunConfig, optional
        Sensors and noise, as for :func:`marsscene.drive`.
    options : DriveOptions, optional
        The start pose (``start_xy_m``, ``start_yaw_rad``) and settling.
    seconds : float, optional
        Sim-time limit (default: until Ctrl-C, or the goal with ``ros.stop_at_goal``).
    out_dir : path, optional
        Also write the session's run folder here.
    record : BagOptions, optional
        Write the session's bag into ``out_dir/bag`` at the end (needs ``out_dir``).
    seed : int
        Seed of the sensor noise.
    progress : callable, optional
        ``progress(DriveProgress)`` once per simulated second.
    ready : callable, optional
        ``ready(bridge)`` once the node is announced, before the first step.

    Returns
    -------
    ServeResult

    Raises
    ------
    MarsSceneError
        A missing scene, a start off the terrain, a bag without a run folder.
    MissingDependencyError
        Without ``cyclonedds`` or ``rosbags`` (``pip install "marsscene[ros2]"``).
    """
    ros = ros if ros is not None else Ros2Options()
    config = config if config is not None else RunConfig()
    out = Path(out_dir) if out_dir is not None else None
    if record is not None and out is None:
        raise RuntimeSimError("recording a bag needs a run folder: give out_dir (--out)")
    if record is not None and out is not None and (out / "bag").exists():
        raise RuntimeSimError(f"{out / 'bag'} exists; choose another --out")
    with _scene_dir(scene, out) as scene_path:
        sim, _ = prepare_drive(scene_path, config, options=options)
        bridge = _bridge(sim, config, ros)
        try:
            publish_discovery_info(bridge.part, bridge.store, ros.node_name)
            bridge.publish_static()
            if ready is not None:
                ready(bridge)
            res = drive_sim(sim, controller=bridge, listeners=[bridge],
                            seconds=seconds if seconds is not None else FOREVER_S, out_dir=out,
                            rng=stage_rng(seed, "sensors"), progress=progress)
        except DriveInterrupted as stop:  # Ctrl-C: the usual end of a served session
            res = stop.result
        finally:
            # from the first control step (the renderer's set-up before it is not session time)
            wall = time.perf_counter() - (bridge.wall_start or time.perf_counter())
            bridge.part.close()
    bag = None
    if record is not None and out is not None:
        from marsscene.runs.export.bag import write_bag

        bag = write_bag(out, options=record)
    return ServeResult(out, res, bridge.stats.as_dict(), wall, bag)


def _bridge(sim: Any, config: RunConfig, ros: Ros2Options) -> Bridge:
    cam = config.camera
    msgs = SampleMessages(
        sim.rover, config.noise, imu_hz=config.imu_hz,
        lidar=config.lidar.spec.to_dict() if config.lidar is not None else None,
        camera=sim.camera_intrinsics() if cam is not None else None,
        stereo=({s: sim.camera_intrinsics(s) for s in ("left", "right")}
                if cam is not None and cam.stereo else None),
        camera_depth=cam is not None and cam.depth,
        images=ImageOptions(images=ros.images), distro=ros.distro, map_tf=ros.map_tf)
    return Bridge(sim, msgs, ros, Participant(ros.domain, ros.localhost_only))
