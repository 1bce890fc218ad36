"""``serve``: the live rover on ROS 2 (over DDS, no ROS installation), one call.

A served session is a drive (:func:`marsscene.drive`, the one place a drive is set up) whose
controller is the :class:`~.bridge.Bridge`: made from the prepared simulator
(:class:`~marsscene.sim.control.OnStart`), it opens a DDS participant (:mod:`.dds`), announces
the node (:mod:`.discovery`), obeys ``/cmd_vel`` and ``/rover/cmd_vel``, serves the simulation
control services (:mod:`.sim_control`) and, as a listener, publishes every sample.
So a session writes the run folder, bag and dataset folders a drive writes, with the drive's
JPEG cache, overwrite rule, progress and errors; Ctrl-C is its usual end
(``DriveOptions.stop_on_interrupt``).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from marsscene.errors import RuntimeSimError
from marsscene.ros2.bridge import Bridge
from marsscene.ros2.dds import Participant
from marsscene.ros2.discovery import publish_discovery_info
from marsscene.ros2.options import Ros2Options
from marsscene.rover.config import RunConfig
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.options import BagOptions, ExportOptions
from marsscene.runs.export.sample_messages import SampleMessages
from marsscene.runs.export.topic_table import ROVER, RosNames
from marsscene.runtime.api import DriveRun, drive
from marsscene.sim.control import OnStart
from marsscene.sim.driver import DriveProgress
from marsscene.sim.mission import DriveOptions

if TYPE_CHECKING:
    from marsscene.scene import Scene

__all__ = ["FOREVER_S", "sample_messages", "serve"]

#: Sim-time limit of a session without ``seconds`` (it ends with Ctrl-C or at the goal).
FOREVER_S = 1e9


def serve(
    scene: str | os.PathLike[str] | Scene,
    *,
    ros: Ros2Options | None = None,
    config: RunConfig | None = None,
    options: DriveOptions | None = None,
    seconds: float | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    record: BagOptions | None = None,
    export: ExportOptions | None = None,
    seed: int = 0,
    progress: Callable[[Any], None] | None = None,
    ready: Callable[[Bridge], None] | None = None,
) -> DriveRun:
    """Run the rover on ``scene`` live: sensors out, ``cmd_vel`` in, over ROS 2's DDS.

    Parameters
    ----------
    scene : path or Scene
        A built scene folder, or a :class:`~marsscene.Scene`.
    ros : Ros2Options, optional
        Domain, localhost mode, command topic and time-out, pacing, QoS (:doc:`/ros2_live`).
    config : RunConfig, optional
        Sensors and noise, as for :func:`marsscene.drive`.
    options : DriveOptions, optional
        The start pose (``start_xy_m``, ``start_yaw_rad``) and settling.
    seconds : float, optional
        Sim-time limit (default: until Ctrl-C, or the goal with ``ros.stop_at_goal``).
    out_dir : path, optional
        Also write the session's run folder here.
    record : BagOptions, optional
        Write the session's bag into ``out_dir/bag`` at the end (needs ``out_dir``); the
        same as ``export=ExportOptions(bag=record)``.
    export : ExportOptions, optional
        Bag and dataset folders written from the run folder at the end, as a drive's
        (``overwrite=True`` replaces existing ones).
    seed : int
        Seed of the sensor noise.
    progress : callable, optional
        ``progress(DriveProgress)`` once per simulated second.
    ready : callable, optional
        ``ready(bridge)`` once the node is announced, before the first step.

    Returns
    -------
    DriveRun
        The drive's result; ``stats`` holds the bridge's counts and ``wall_s`` runs from the
        first control step (the renderer's set-up before it is not session time).

    Raises
    ------
    MarsSceneError
        A missing scene, a start off the terrain, exports that cannot be written.
    MissingDependencyError
        Without ``cyclonedds`` or ``rosbags`` (``pip install "marsscene[ros2]"``).

    Examples
    --------
    One simulated second served on DDS domain 57, on this machine only (a ROS 2 node on the
    same domain sees the topics and may publish ``/cmd_vel``):

    >>> import marsscene as ms
    >>> from marsscene.ros2 import Ros2Options, serve
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
    >>> run = serve(ms.build_scene(cfg, seed=1), ros=Ros2Options(domain_id=57, localhost=True),
    ...             seconds=1.0)
    >>> run.summary["status"], run.sim_s
    ('complete', 1.0)
    >>> bool(run.stats["messages"])
    True
    """
    ros = ros if ros is not None else Ros2Options()
    config = config if config is not None else RunConfig()
    if record is not None and export is not None and export.bag is not None:
        raise RuntimeSimError("give the bag's options once: record= or export=, not both")
    if record is not None:
        export = dataclasses.replace(export or ExportOptions(), bag=record)
    options = dataclasses.replace(options or DriveOptions(), stop_on_interrupt=True)
    made: list[Bridge] = []

    def start(sim: Any) -> Bridge:
        made.append(_bridge(sim, config, ros))
        publish_discovery_info(made[0].part, made[0].store, ros.node_name)
        made[0].publish_static()
        if ready is not None:
            ready(made[0])
        return made[0]

    def drive_progress(p: Any) -> None:  # the session's progress; not the exports'
        if progress is not None and isinstance(p, DriveProgress):
            progress(p)

    try:
        run = drive(scene, controller=OnStart(start, listen=True), config=config,
                    options=options, export=export, out_dir=out_dir, seed=seed,
                    seconds=seconds if seconds is not None else FOREVER_S,
                    progress=drive_progress)
    finally:
        for bridge in made:
            bridge.part.close()
    bridge = made[0]
    wall = run.wall_s  # from the first control step to the end of the drive, when there was one
    if bridge.wall_start is not None:
        wall = min(time.perf_counter() - run.export_s - bridge.wall_start, run.wall_s)
    return dataclasses.replace(run, stats=bridge.stats.as_dict(), wall_s=wall)


def sample_messages(sim: Any, config: RunConfig, ros: Ros2Options,
                    names: RosNames = ROVER) -> SampleMessages:
    """The live messages of the rover ``sim`` with ``config``'s sensors, under ``names``."""
    cam = config.camera
    return SampleMessages(
        sim.rover, config.noise, imu_hz=config.imu_hz,
        lidar=config.lidar.spec.to_dict() if config.lidar is not None else None,
        camera=sim.camera_intrinsics() if cam is not None else None,
        stereo=({s: sim.camera_intrinsics(s) for s in ("left", "right")}
                if cam is not None and cam.stereo else None),
        camera_depth=cam is not None and cam.depth,
        images=ImageOptions(images=ros.images), distro=ros.distro, map_tf=ros.map_tf,
        soil=getattr(sim, "wheel_soil", None), names=names)


def _bridge(sim: Any, config: RunConfig, ros: Ros2Options) -> Bridge:
    msgs = sample_messages(sim, config, ros)
    part = Participant(ros.domain, ros.localhost_only)
    try:
        return Bridge(sim, msgs, ros, part)
    except BaseException:
        part.close()
        raise
