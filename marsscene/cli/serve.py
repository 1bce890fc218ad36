"""``marsscene serve``: the live rover on ROS 2 (DDS, no ROS installation)."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose, sigterm_interrupts, user_errors
from marsscene.cli.options_run import RUN_OPTION_NAMES, run_config, run_option
from marsscene.ros2.options import PACES, SENSOR_QOS, Ros2Options
from marsscene.rover.config import LidarConfig
from marsscene.runs.export.options import DISTROS, IMAGES

_R = Ros2Options()  # the defaults live in Ros2Options only

#: The run options serve offers (the drive's others take their defaults), with serve's help.
_sensor_options = compose(
    run_option("camera", "RGB-D navcam (docs/camera.md)."),
    run_option("camera_size"),
    run_option("camera_hz"),
    run_option("stereo", "Also a rectified stereo pair."),
    run_option("lidar", f"Spinning 3D LiDAR (default model {LidarConfig().model})."),
    run_option("lidar_model", "LiDAR model (implies --lidar)."),
    run_option("soil"),
    run_option("noise_profile", "IMU + wheel-odometry noise profile (default: noise-free)."),
    run_option("run_config", "TOML/JSON run config ([run], [lidar], [camera], [noise])."),
)

_ros_options = compose(
    click.option("--domain-id", type=click.IntRange(0, 232), default=None,
                 help="DDS domain (default: ROS_DOMAIN_ID, else 0)."),
    click.option("--localhost/--network", "localhost", default=None,
                 help="Keep DDS on 127.0.0.1 (no multicast) or use the network (default: "
                 "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or ROS_LOCALHOST_ONLY=1 turn it on)."),
    click.option("--cmd-vel-topic", default=_R.cmd_vel_topic, show_default=True,
                 help="Velocity commands to obey."),
    click.option("--rover-cmd-vel/--no-rover-cmd-vel", default=_R.rover_cmd_vel,
                 show_default=True, help="Also obey /rover/cmd_vel (MarsLab's command topic)."),
    click.option("--services/--no-services", default=_R.services, show_default=True,
                 help="simulation_interfaces services and the SimulateSteps action (clients "
                 "on RMW_IMPLEMENTATION=rmw_cyclonedds_cpp)."),
    click.option("--sim-namespace", default=_R.sim_namespace, show_default=True,
                 help="Namespace of the services (/gzserver: Gazebo's)."),
    click.option("--cmd-vel-stamped", is_flag=True,
                 help="geometry_msgs/TwistStamped commands (Nav2 enable_stamped_cmd_vel)."),
    click.option("--cmd-timeout-s", "cmd_timeout", type=click.FloatRange(min=0),
                 default=_R.cmd_timeout_s, show_default=True,
                 help="Stop after this many sim seconds without a command (0: never)."),
    click.option("--pace", type=click.Choice(PACES), default=_R.pace, show_default=True,
                 help="Follow the wall clock, run as fast as it goes, or advance only when "
                 "a command comes (lockstep)."),
    click.option("--lockstep-steps", type=click.IntRange(min=1), default=_R.lockstep_steps,
                 show_default=True, help="Control steps each command drives with --pace "
                 "lockstep."),
    click.option("--rtf", type=click.FloatRange(min=0, min_open=True),
                 default=_R.realtime_factor, show_default=True,
                 help="Sim seconds per wall second with --pace realtime."),
    click.option("--sensor-qos", type=click.Choice(SENSOR_QOS), default=_R.sensor_qos,
                 show_default=True, help="QoS of IMU, camera and LiDAR topics."),
    # listed as before, the default first: both, raw, compressed
    click.option("--images", type=click.Choice(IMAGES[::-1]), default=_R.images,
                 show_default=True, help="Image topics offered (each encoded only while "
                 "subscribed)."),
    click.option("--stop-at-goal", is_flag=True,
                 help="End when the goal (/marsscene/goal) is reached."),
    click.option("--ros-distro", type=click.Choice(DISTROS), default=_R.distro,
                 show_default=True, help="Message definitions."),
    click.option("--map-tf/--no-map-tf", default=_R.map_tf, show_default=True,
                 help="Publish map -> odom from ground truth (off when a SLAM stack does)."),
)


@click.command(short_help="Serve the live rover on ROS 2 (DDS, no ROS install).")
@click.argument("scene_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@_ros_options
@_sensor_options
@click.option("--start-xy", "start", nargs=2, type=float, default=None, metavar="X Y",
              help="Start position (m, world frame; default: the terrain centre), as build "
              "--rover-xy.")
@click.option("--yaw-deg", type=click.FloatRange(-360.0, 360.0), default=0.0,
              show_default=True, help="Start heading (degrees, counter-clockwise from east).")
@click.option("--seconds", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Sim-time limit (default: until Ctrl-C).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Also write the session's run folder.")
@click.option("--record", is_flag=True, help="Write OUT/bag, the session's ROS 2 bag (needs "
              "--out).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Seed of the sensor noise.")
@click.option("--team", "team_path", type=click.Path(exists=True, dir_okay=False,
              path_type=Path), default=None, help="Serve a team (TOML [[robots]] tables: "
              "name, rover, start_xy_m, run), each robot under /NAME (docs/team.md).")
def serve(scene_dir: Path, start: tuple[float, float] | None, yaw_deg: float,
          seconds: float | None, out_dir: Path | None, record: bool, seed: int,
          team_path: Path | None, **opts: Any) -> None:
    """Run the rover live: sensors published, /cmd_vel obeyed, sim time on /clock.

    \b
    Examples:
      marsscene serve scenes/demo --lidar --camera --localhost
      marsscene serve scenes/demo --pace max --seconds 60 --out runs/live --record
      marsscene serve scenes/demo --team examples/team_serve.toml --localhost
    Then, on a machine with ROS 2: ros2 topic list; rviz2 (docs/ros2_live.md).
    """
    import marsscene as ms
    from marsscene.runs.export.options import BagOptions

    yaw = math.radians(yaw_deg)
    with user_errors():
        from marsscene.ros2 import serve as serve_live  # MissingDependencyError: one line

        run = run_config({k: opts.pop(k) for k in list(opts) if k in RUN_OPTION_NAMES})
        ros = Ros2Options(
            domain_id=opts["domain_id"], localhost=opts["localhost"],
            cmd_vel_topic=opts["cmd_vel_topic"], cmd_vel_stamped=opts["cmd_vel_stamped"],
            rover_cmd_vel=opts["rover_cmd_vel"], services=opts["services"],
            sim_namespace=opts["sim_namespace"],
            cmd_timeout_s=opts["cmd_timeout"], pace=opts["pace"], realtime_factor=opts["rtf"],
            lockstep_steps=opts["lockstep_steps"],
            sensor_qos=opts["sensor_qos"], images=opts["images"],
            stop_at_goal=opts["stop_at_goal"], distro=opts["ros_distro"], map_tf=opts["map_tf"])
        options = ms.DriveOptions(start_xy_m=start, start_yaw_rad=yaw)
        where = "127.0.0.1 only" if ros.localhost_only else "the network"
        if team_path is not None:
            if start is not None or yaw_deg:
                raise click.UsageError("--team gives each robot's start: no --start-xy or "
                                       "--yaw-deg")
            _serve_team(scene_dir, team_path, ros, run, seconds, out_dir, record, seed, where)
            return
        meter = _Meter()
        with sigterm_interrupts(), _interrupted_before_start():
            res = serve_live(scene_dir, ros=ros, config=run, options=options, seconds=seconds,
                             out_dir=out_dir, record=BagOptions() if record else None,
                             seed=seed, progress=meter,
                             ready=lambda b: click.echo(
                                 f"marsscene: serving /{ros.node_name} on DDS domain "
                                 f"{ros.domain} ({where}); {len(b.writers)} topics; "
                                 "Ctrl-C ends", err=True))
    st = res.stats
    click.echo(f"  served: {res.sim_s:.1f} sim s in {res.wall_s:.1f} s "
               f"({res.realtime_factor:.2f}x real time), {sum(st['messages'].values())} "
               f"messages, {st['commands']} commands, {st['command_timeouts']} time-outs")
    if res.bag is not None:
        click.echo(f"     bag: {res.bag.path}")
    if out_dir is not None:
        click.echo(f"    logs: {out_dir}")


def _serve_team(scene_dir: Path, team_path: Path, ros: Ros2Options, run: Any,
                seconds: float | None, out_dir: Path | None, record: bool, seed: int,
                where: str) -> None:
    """``serve --team``: every robot of the file under its own namespace."""
    import marsscene as ms
    from marsscene.ros2.live_team import serve_team
    from marsscene.runtime.robot import read_team_file

    if record and out_dir is None:
        raise click.UsageError("--record needs --out (each robot's bag is OUT/NAME/bag)")
    robots, settings = read_team_file(team_path)
    if settings.get("scouts"):
        raise click.UsageError(f"{team_path}: serve drives rovers only; fly the [[scouts]] "
                               "with `marsscene drive --team` or `marsscene fly`")
    seconds = seconds if seconds is not None else settings.get("seconds")
    export = ms.ExportOptions(bag=ms.BagOptions()) if record else None

    def ready(bridges: dict[str, Any]) -> None:
        click.echo(f"marsscene: serving {len(bridges)} robots ("
                   f"{', '.join('/' + n for n in bridges)}) on DDS domain {ros.domain} "
                   f"({where}); Ctrl-C ends", err=True)

    with sigterm_interrupts(), _interrupted_before_start():
        res = serve_team(scene_dir, robots, ros=ros, config=run, seconds=seconds,
                         out_dir=out_dir, export=export, seed=seed or settings.get("seed", 0),
                         ready=ready)
    for name, r in res.robots.items():
        st = r.stats
        click.echo(f"  {name}: {r.sim_s:.1f} sim s, {r.summary['path_length_m']:.2f} m, "
                   f"{st['commands']} commands, {sum(st['messages'].values())} messages"
                   + (f" -> {r.out_dir}" if r.out_dir is not None else ""))
    click.echo(f"  served: {len(res.robots)} robots in {res.wall_s:.1f} s "
               f"({res.realtime_factor:.2f}x real time)")


@contextmanager
def _interrupted_before_start() -> Iterator[None]:
    """Ctrl-C while the scene loads (a started session ends normally): exit 130, one line."""
    try:
        yield
    except KeyboardInterrupt:
        click.echo("marsscene: interrupted before the session started", err=True)
        sys.exit(130)


class _Meter:
    """A status line every 10 wall seconds: sim time, real-time factor, distance driven."""

    def __init__(self) -> None:
        self.t0: float | None = None  # the first report (after the sensors' set-up)
        self.last = 0.0

    def __call__(self, p: Any) -> None:
        now = time.monotonic()
        if self.t0 is None:
            self.t0 = self.last = now - p.sim_time_s
            return
        if now - self.last >= 10.0:
            self.last = now
            sys.stderr.write(f"marsscene: sim {p.sim_time_s:.0f} s | "
                             f"{p.sim_time_s / max(now - self.t0, 1e-9):.2f}x real time | "
                             f"{p.distance_m:.1f} m driven\n")
