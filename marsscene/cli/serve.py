"""``marsscene serve``: the live rover on ROS 2 (DDS, no ROS installation)."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose, user_errors
from marsscene.cli.drive import _LIDAR_MODELS, _NOISE_PROFILES, _run_config, _sigterm_interrupts

_sensor_options = compose(
    click.option("--camera", is_flag=True, help="RGB-D navcam (docs/camera.md)."),
    click.option("--camera-size", default="640x480", show_default=True, metavar="WxH",
                 help="Camera image size in pixels."),
    click.option("--camera-hz", type=float, default=10.0, show_default=True,
                 help="Camera rate (must divide 500 Hz)."),
    click.option("--stereo", is_flag=True, help="Also a rectified stereo pair."),
    click.option("--lidar", is_flag=True, help="Spinning 3D LiDAR (default model os1-128)."),
    click.option("--lidar-model", type=click.Choice(_LIDAR_MODELS), default=None,
                 help="LiDAR model (implies --lidar)."),
    click.option("--noise-profile", type=click.Choice(_NOISE_PROFILES), default=None,
                 help="IMU + wheel-odometry noise profile (default: noise-free)."),
    click.option("--run-config", type=click.Path(exists=True, dir_okay=False, path_type=Path),
                 help="TOML/JSON run config ([run], [lidar], [camera], [noise])."),
)

_ros_options = compose(
    click.option("--ros2", is_flag=True, default=True,
                 help="Speak ROS 2 over DDS (Cyclone DDS; the only transport so far)."),
    click.option("--domain-id", type=click.IntRange(0, 232), default=None,
                 help="DDS domain (default: ROS_DOMAIN_ID, else 0)."),
    click.option("--localhost/--network", "localhost", default=None,
                 help="Keep DDS on 127.0.0.1 (no multicast) or use the network (default: "
                 "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or ROS_LOCALHOST_ONLY=1 turn it on)."),
    click.option("--cmd-vel-topic", default="/cmd_vel", show_default=True,
                 help="Velocity commands to obey."),
    click.option("--cmd-vel-stamped", is_flag=True,
                 help="geometry_msgs/TwistStamped commands (Nav2 enable_stamped_cmd_vel)."),
    click.option("--cmd-timeout", type=click.FloatRange(min=0), default=0.5, show_default=True,
                 help="Stop after this many sim seconds without a command (0: never)."),
    click.option("--pace", type=click.Choice(["realtime", "max"]), default="realtime",
                 show_default=True, help="Follow the wall clock, or run as fast as it goes."),
    click.option("--rtf", type=click.FloatRange(min=0, min_open=True), default=1.0,
                 show_default=True, help="Sim seconds per wall second with --pace realtime."),
    click.option("--sensor-qos", type=click.Choice(["best-effort", "reliable"]),
                 default="best-effort", show_default=True,
                 help="QoS of IMU, camera and LiDAR topics."),
    click.option("--images", type=click.Choice(["both", "raw", "compressed"]), default="both",
                 show_default=True, help="Image topics offered (each encoded only while "
                 "subscribed)."),
    click.option("--stop-at-goal", is_flag=True,
                 help="End when the goal (/marsscene/goal) is reached."),
    click.option("--ros-distro", type=click.Choice(["jazzy", "humble"]), default="jazzy",
                 show_default=True, help="Message definitions."),
    click.option("--map-tf/--no-map-tf", default=True, show_default=True,
                 help="Publish map -> odom from ground truth (off when a SLAM stack does)."),
)


@click.command(short_help="Serve the live rover on ROS 2 (DDS, no ROS install).")
@click.argument("scene_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@_ros_options
@_sensor_options
@click.option("--start", nargs=2, type=float, default=None, metavar="X Y",
              help="Start position in m (default: the terrain centre).")
@click.option("--yaw", type=float, default=0.0, show_default=True,
              help="Start heading (rad, counter-clockwise from east).")
@click.option("--seconds", type=click.FloatRange(min=0, min_open=True), default=None,
              help="Sim-time limit (default: until Ctrl-C).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Also write the session's run folder.")
@click.option("--record", is_flag=True, help="Write OUT/bag, the session's ROS 2 bag (needs "
              "--out).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True,
              help="Seed of the sensor noise.")
def serve(scene_dir: Path, start: tuple[float, float] | None, yaw: float,
          seconds: float | None, out_dir: Path | None, record: bool, seed: int,
          **opts: Any) -> None:
    """Run the rover live: sensors published, /cmd_vel obeyed, sim time on /clock.

    \b
    Examples:
      marsscene serve scenes/demo --ros2 --lidar --camera --localhost
      marsscene serve scenes/demo --ros2 --pace max --seconds 60 --out runs/live --record
    Then, on a machine with ROS 2: ros2 topic list; rviz2 (docs/ros2_live.md).
    """
    import marsscene as ms
    from marsscene.ros2 import Ros2Options
    from marsscene.runs.export.options import BagOptions

    with user_errors():
        from marsscene.ros2 import serve as serve_live  # MissingDependencyError: one line

        run = _run_config(**_drive_defaults(opts))
        ros = Ros2Options(
            domain_id=opts["domain_id"], localhost=opts["localhost"],
            cmd_vel_topic=opts["cmd_vel_topic"], cmd_vel_stamped=opts["cmd_vel_stamped"],
            cmd_timeout_s=opts["cmd_timeout"], pace=opts["pace"], realtime_factor=opts["rtf"],
            sensor_qos=opts["sensor_qos"], images=opts["images"],
            stop_at_goal=opts["stop_at_goal"], distro=opts["ros_distro"], map_tf=opts["map_tf"])
        options = ms.DriveOptions(start_xy_m=start, start_yaw_rad=yaw)
        where = "127.0.0.1 only" if ros.localhost_only else "the network"
        meter = _Meter()
        with _sigterm_interrupts(), _interrupted_before_start():
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


@contextmanager
def _interrupted_before_start() -> Iterator[None]:
    """Ctrl-C while the scene loads (a started session ends normally): exit 130, one line."""
    try:
        yield
    except KeyboardInterrupt:
        click.echo("marsscene: interrupted before the session started", err=True)
        sys.exit(130)


def _drive_defaults(opts: dict[str, Any]) -> dict[str, Any]:
    """The drive command's sensor defaults for what serve does not offer."""
    return {"noise_config": None, "exposure": "auto", "exposure_gain": 1.0,
            "camera_noise": False, "no_shadows": False, "tau": None, "sun_elevation": None,
            **opts}


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
