"""``serve_team``: a team of robots live on ROS 2, each under its own namespace.

A served team is a team drive (:func:`marsscene.drive_team`) whose robots' controllers are
:class:`~.bridge.Bridge` s on one DDS participant, as multi-robot ROS 2 systems name them
(:class:`~marsscene.runs.export.topic_table.RosNames`): robot ``r1`` publishes ``/r1/odom``,
``/r1/imu_noisy``, ``/r1/lidar/points`` ... with frames ``r1/odom``, ``r1/base_link`` ...
under the one ``map``, obeys ``/r1/cmd_vel`` and ``/marsscene/r1/{reset,teleport,goal}``; the
team shares ``/tf``, ``/tf_static`` and one ``/clock`` (the first robot's bridge says it).
The first robot's bridge paces the team and serves the simulation control services, with an
entity per robot (:mod:`.sim_control`); in lockstep every robot waits for its own command.
Each robot's run folder, bag and datasets are a team drive's.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from marsscene.errors import ConfigError
from marsscene.ros2.bridge import Bridge
from marsscene.ros2.dds import Participant
from marsscene.ros2.discovery import publish_discovery_info
from marsscene.ros2.live import FOREVER_S, sample_messages
from marsscene.ros2.options import Ros2Options
from marsscene.rover.config import RunConfig
from marsscene.runs.export.options import ExportOptions
from marsscene.runs.export.topic_table import RosNames
from marsscene.runtime.robot import Robot
from marsscene.runtime.team import TeamRun, drive_team
from marsscene.sim.control import OnStart
from marsscene.sim.mission import DriveOptions

if TYPE_CHECKING:
    from marsscene.scene import Scene

__all__ = ["serve_team"]


def serve_team(
    scene: str | os.PathLike[str] | Scene,
    robots: Sequence[Robot],
    *,
    ros: Ros2Options | None = None,
    config: RunConfig | None = None,
    options: DriveOptions | None = None,
    seconds: float | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    export: ExportOptions | None = None,
    seed: int = 0,
    ready: Callable[[dict[str, Bridge]], None] | None = None,
) -> TeamRun:
    """Serve ``robots`` on ``scene`` live: each robot's sensors out, its ``cmd_vel`` in.

    Parameters
    ----------
    scene : path or Scene
    robots : sequence of Robot
        The team: names, rover types, sensors (``config``) and starts (``start_xy_m``,
        ``start_yaw_rad``); a ROS 2 node drives each, so none has a route or a command.
    ros : Ros2Options, optional
        Domain, localhost mode, pacing, QoS, services, as :func:`marsscene.ros2.serve`'s;
        the command topics are each robot's own (``/NAME/cmd_vel``).
    config : RunConfig, optional
        Sensors of every robot without its own.
    options : DriveOptions, optional
    seconds : float, optional
        Sim-time limit (default: until Ctrl-C).
    out_dir : path, optional
        The team's folder (``team.json``, a run folder per robot).
    export : ExportOptions, optional
        Each robot's bag and datasets at the end (needs ``out_dir``).
    seed : int
    ready : callable, optional
        ``ready({name: bridge})`` once every robot's node side is up, before the first step.

    Returns
    -------
    TeamRun
        Each robot's drive; its ``stats`` hold its bridge's counts.
    """
    ros = ros if ros is not None else Ros2Options()
    robots = list(robots)
    for r in robots:
        if r.route is not None or r.waypoints is not None or r.command is not None \
                or r.controller is not None:
            raise ConfigError(f"robot {r.name!r}: a served robot is driven over ROS 2 "
                              "(/NAME/cmd_vel): no route, waypoints, command or controller")
    options = dataclasses.replace(options or DriveOptions(), stop_on_interrupt=True)
    part = Participant(ros.domain, ros.localhost_only)
    bridges: dict[str, Bridge] = {}

    def maker(robot: Robot, lead: bool) -> Callable[[Any], Bridge]:
        def make(member: Any) -> Bridge:
            names = RosNames.for_robot(robot.name)
            cfg = robot.config if robot.config is not None else (config or RunConfig())
            opts = ros if lead else dataclasses.replace(  # the lead paces and serves
                ros, services=False, pace="max" if ros.pace == "realtime" else ros.pace)
            b = Bridge(member, sample_messages(member, cfg, opts, names), opts, part,
                       cmd_topics=(names.topic("cmd_vel"),), clock=lead)
            bridges[robot.name] = b
            b.publish_static()
            if len(bridges) == len(robots):
                _ready(bridges, part, ros, ready)
            return b
        return make

    served = [_served(r, OnStart(maker(r, i == 0), listen=True)) for i, r in enumerate(robots)]
    try:
        team = drive_team(scene, served, seconds=seconds if seconds is not None else FOREVER_S,
                          config=config, options=options, out_dir=out_dir, seed=seed,
                          export=export)
    finally:
        part.close()
    return dataclasses.replace(team, robots={
        name: dataclasses.replace(run, stats=bridges[name].stats.as_dict())
        for name, run in team.robots.items()})


def _ready(bridges: dict[str, Bridge], part: Participant, ros: Ros2Options,
           ready: Callable[[dict[str, Bridge]], None] | None) -> None:
    """Every robot's bridge is made: the lead's services list every robot, the node is
    announced, and the caller is told."""
    lead = next(iter(bridges.values()))
    if lead.control_srv is not None:
        lead.control_srv.entities = dict(bridges)
    publish_discovery_info(part, lead.store, ros.node_name)
    if ready is not None:
        ready(bridges)


def _served(robot: Robot, controller: OnStart) -> Robot:
    """``robot`` driven by ``controller``."""
    rover = robot.rover_type if robot.rover_type != "custom" else robot.rover_config
    return Robot(name=robot.name, rover=rover, config=robot.config, controller=controller,
                 start_xy_m=robot.start_xy_m, start_yaw_rad=robot.start_yaw_rad,
                 seconds=robot.seconds)
