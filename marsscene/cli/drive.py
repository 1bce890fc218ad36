"""``marsscene drive``: drive the rover on a built scene along a route and write the logs."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import user_errors
from marsscene.cli.bag import bag_options, write_run_bag
from marsscene.rover.config import noise_profiles
from marsscene.rover.lidar import lidar_models

_PATH = click.Path(exists=True, dir_okay=False, path_type=Path)


_LIDAR_MODELS = tuple(lidar_models())
_NOISE_PROFILES = tuple(noise_profiles())


def _read_waypoints(path: Path) -> Any:
    import numpy as np

    from marsscene.errors import RuntimeSimError

    rows = []
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        parts = text.replace(",", " ").split()
        try:
            rows.append([float(parts[0]), float(parts[1])])
        except (ValueError, IndexError):
            raise RuntimeSimError(
                f"{path}:{lineno}: expected 'x y' in m, got {text[:80]!r}"
            ) from None
    if len(rows) < 2:
        raise RuntimeSimError(f"{path}: need at least 2 waypoints, got {len(rows)}")
    return np.asarray(rows)


def _size(text: str) -> tuple[int, int]:
    from marsscene.errors import ConfigError

    parts = text.lower().split("x")
    try:
        w, h = int(parts[0]), int(parts[1])
        if len(parts) != 2:
            raise ValueError
    except (ValueError, IndexError):
        raise ConfigError(f"--camera-size {text!r} must be WIDTHxHEIGHT, e.g. 640x480") from None
    return w, h


@click.command(short_help="Drive the rover on a built scene and log GT, odometry, IMU, sensors.")
@click.argument("scene_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--route", "route_path", type=_PATH, help="Route as a TUM file (x, y are used).")
@click.option(
    "--waypoints",
    "waypoints_path",
    type=_PATH,
    help="Waypoints 'x y' (m) per line; a smooth route avoiding slopes/rocks is authored.",
)
@click.option(
    "--seconds",
    type=click.FloatRange(min=0, min_open=True),
    default=None,
    help="Sim-time limit (default: until the goal).",
)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path("runs/drive"),
    show_default=True,
    help="Run folder.",
)
@click.option("--camera", is_flag=True, help="Log RGB-D mast camera images (docs/camera.md).")
@click.option("--camera-size", default="640x480", show_default=True, metavar="WxH",
              help="Camera image size in pixels.")
@click.option("--camera-hz", type=float, default=10.0, show_default=True,
              help="Camera rate (must divide 500 Hz).")
@click.option("--stereo", is_flag=True,
              help="Also log a rectified Navcam-like stereo pair (0.424 m baseline).")
@click.option("--exposure", type=click.Choice(["auto", "fixed"]), default="auto",
              show_default=True, help="Auto-exposure (mean 0.45) or a fixed exposure.")
@click.option("--exposure-gain", type=click.FloatRange(min=0, min_open=True), default=1.0,
              show_default=True, help="Gain of --exposure fixed.")
@click.option("--camera-noise", is_flag=True, help="Add seeded shot + read noise to images.")
@click.option("--no-shadows", is_flag=True, help="Turn the sun's shadow map off (faster).")
@click.option("--tau", type=click.FloatRange(0, 10), default=None,
              help="Override the scene's dust optical depth for the camera's lighting.")
@click.option("--sun-elevation", type=click.FloatRange(-10, 90), default=None,
              help="Override the sun elevation (deg) for the camera's lighting.")
@click.option("--lidar", is_flag=True,
              help="Log a spinning 3D LiDAR (default model os1-128: 128 x 1024 at 10 Hz; PLY).")
@click.option("--lidar-model", type=click.Choice(_LIDAR_MODELS), default=None,
              help="LiDAR model from datasheets (docs/runtime.md); implies --lidar.")
@click.option("--run-config", type=_PATH,
              help="TOML/JSON run config: [run], [lidar] (e.g. model = \"vlp16\"), [camera], "
              "[noise] tables; options given on the command line win.")
@click.option("--noise-config", type=_PATH, help="TOML/JSON noise config ([noise] table).")
@click.option("--noise-profile", type=click.Choice(_NOISE_PROFILES), default=None,
              help="Named IMU + wheel-odometry noise profile from datasheets (docs/runtime.md); "
              "keys set in --noise-config / --run-config still win. Default: the config's "
              "profile, else none (noise-free).")
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seed of the sensor-noise stream.",
)
@click.option(
    "--lookahead",
    type=click.FloatRange(min=0.05),
    default=1.0,
    show_default=True,
    help="Pure-pursuit lookahead (m).",
)
@click.option(
    "--max-slope",
    type=click.FloatRange(0, 90, min_open=True),
    default=20.0,
    show_default=True,
    help="Route authoring: steepest slope allowed (deg).",
)
@click.option("--write-rover-xml", is_flag=True, help="Also write SCENE_DIR/mjcf/rover.xml.")
@click.option(
    "--corridor",
    type=click.FloatRange(min=1.0),
    default=15.0,
    show_default=True,
    help="Only MJCF rocks within this distance of the route are simulated (m); widened to "
    "the LiDAR range / camera window when those sensors are on.",
)
@click.option("--bag", "write_bag", is_flag=True,
              help="Also write RUN_DIR/bag, a ROS 2 bag of the run (see `marsscene bag`).")
@click.option("--overwrite", is_flag=True, help="With --bag: replace an existing RUN_DIR/bag.")
@bag_options
def drive(
    scene_dir: Path,
    route_path: Path | None,
    waypoints_path: Path | None,
    seconds: float | None,
    out_dir: Path,
    camera: bool,
    lidar: bool,
    lidar_model: str | None,
    run_config: Path | None,
    noise_config: Path | None,
    noise_profile: str | None,
    seed: int,
    lookahead: float,
    max_slope: float,
    write_rover_xml: bool,
    corridor: float,
    camera_size: str,
    camera_hz: float,
    stereo: bool,
    exposure: str,
    exposure_gain: float,
    camera_noise: bool,
    no_shadows: bool,
    tau: float | None,
    sun_elevation: float | None,
    write_bag: bool = False,
    overwrite: bool = False,
    **bag_opts: Any,
) -> None:
    """Drive the rover along a route with pure pursuit (v <= 0.5 m/s, |w| <= 0.2 rad/s, 50 Hz).

    \b
    Examples:
      marsscene drive scenes/demo --waypoints wp.txt --lidar --out runs/r1
      marsscene drive scenes/demo --route route.tum --seconds 60 --camera
    """
    if (route_path is None) == (waypoints_path is None):
        raise click.UsageError("give exactly one of --route or --waypoints")
    if write_bag and (out_dir / "bag").exists() and not overwrite:
        raise click.ClickException(f"{out_dir / 'bag'} exists; pass --overwrite to replace it")
    with user_errors():
        run = _run_config(run_config, noise_config, lidar, lidar_model, camera or stereo,
                          camera_size=camera_size, noise_profile=noise_profile,
                          rate_hz=camera_hz, stereo=stereo, exposure=exposure,
                          exposure_gain=exposure_gain, sensor_noise=camera_noise,
                          shadows=not no_shadows, tau=tau, sun_elevation_deg=sun_elevation)
        sim, route = _prepare(scene_dir, run, route_path, waypoints_path, out_dir,
                              max_slope=max_slope, corridor=corridor,
                              write_rover_xml=write_rover_xml)
    if write_bag:
        from marsscene.runs.export.bag_writer import require_backends

        with user_errors():
            require_backends(bag_opts.get("bag_compression", "zstd"))
    cache = _jpeg_cache(out_dir, bag_opts) if write_bag and run.camera is not None else None
    try:  # SIGTERM is Ctrl-C until the JPEG cache is gone, the bag's writing included
        with _sigterm_interrupts():
            try:
                with user_errors():
                    res, wall = _drive(sim, route, seconds, out_dir, seed, lookahead, cache)
                _report(res.summary, wall, out_dir)
                if write_bag:
                    t0 = time.perf_counter()
                    with user_errors():
                        write_run_bag(out_dir, None, overwrite=overwrite, jpeg_cache=cache,
                                      **bag_opts)
                    click.echo(f"          bag written in {time.perf_counter() - t0:.1f} s "
                               f"(drive: {wall:.1f} s)")
            finally:
                if cache is not None:
                    cache.remove()
    except KeyboardInterrupt:  # while writing the bag: the run folder is whole, no bag
        click.echo(f"marsscene: interrupted while writing the bag; {out_dir} holds the whole "
                   f"drive (`marsscene bag {out_dir}` writes the bag)", err=True)
        sys.exit(130)


def _report(s: dict[str, Any], wall: float, out_dir: Path) -> None:
    click.echo(
        f"   drove: {s['path_length_m']:.2f} m in {s['sim_time_s']:.2f} sim s "
        f"({s['sim_time_s'] / max(wall, 1e-9):.1f}x real time), goal reached: "
        f"{s['goal_reached']}, cross-track RMS "
        f"{s.get('cross_track_rms_m', float('nan')):.3f} m"
    )
    click.echo(f"    logs: {out_dir}")


@contextmanager
def _sigterm_interrupts() -> Iterator[None]:
    """SIGTERM raises KeyboardInterrupt inside the block (a no-op off the main thread)."""
    import signal

    def terminate(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:  # only the main thread may set handlers
        previous: Any = signal.signal(signal.SIGTERM, terminate)
    except ValueError:
        previous = None
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _jpeg_cache(out_dir: Path, bag_opts: dict[str, Any]) -> Any:
    """The JPEGs the bag will want, encoded while driving (none for PNG-only or raw images)."""
    from marsscene.runs.export.bag_images import JpegCache

    if (bag_opts.get("bag_images", "compressed") == "raw"
            or bag_opts.get("bag_image_format", "jpeg") != "jpeg"):
        return None
    return JpegCache.fresh(out_dir, bag_opts.get("jpeg_quality", 95))


def _run_config(run_config: Path | None, noise_config: Path | None, lidar: bool,
                lidar_model: str | None, camera: bool, *, camera_size: str,
                noise_profile: str | None = None, **camera_kw: Any) -> Any:
    """The drive's :class:`~marsscene.rover.config.RunConfig`: the run config file (if any),
    then the command-line options over it."""
    import dataclasses

    from marsscene.rover.config import CameraConfig, LidarConfig, NoiseConfig, RunConfig

    run = RunConfig.from_file(run_config) if run_config else RunConfig()
    if noise_config:
        run = dataclasses.replace(run, noise=NoiseConfig.from_file(noise_config))
    if noise_profile:
        run = dataclasses.replace(run, noise=run.noise.with_profile(noise_profile))
    if lidar or lidar_model:
        base = run.lidar if run.lidar is not None else LidarConfig()
        lid = dataclasses.replace(base, model=lidar_model) if lidar_model else base
        run = dataclasses.replace(run, lidar=lid)
    if camera:
        w, h = _size(camera_size)
        run = dataclasses.replace(run, camera=CameraConfig(width_px=w, height_px=h, **camera_kw))
    return run


def _prepare(scene_dir: Path, run: Any, route_path: Path | None, waypoints_path: Path | None,
             out_dir: Path, *, max_slope: float, corridor: float, write_rover_xml: bool
             ) -> tuple[Any, Any]:
    """Load the scene, author the route, write ``route.tum``: the simulator and the route."""
    from marsscene.runs.tum import read_tum, write_tum
    from marsscene.sim.mission import prepare_drive
    from marsscene.sim.route import Route

    sim, route = prepare_drive(
        scene_dir, run,
        route=Route.from_trajectory(read_tum(route_path)) if route_path else None,
        waypoints_xy_m=_read_waypoints(waypoints_path) if waypoints_path else None,
        max_slope_deg=max_slope, corridor_m=corridor,
    )
    if sim.rocks_kept[1]:
        click.echo(f"   rocks: {sim.rocks_kept[0]} of {sim.rocks_kept[1]} MJCF rocks lie "
                   "near the route and are simulated", err=True)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_tum(out_dir / "route.tum", route.to_trajectory(sim.heightfield),
              header="authored route (x, y on the terrain; stamps at 0.5 m/s)")
    if write_rover_xml:
        click.echo(f"   rover: {sim.write_rover_xml()}")
    return sim, route


def _drive(sim: Any, route: Any, seconds: float | None, out_dir: Path, seed: int,
           lookahead: float, jpeg_cache: Any = None) -> tuple[Any, float]:
    """Drive with a progress line; the result and the wall time (s). Ctrl-C or SIGTERM stop the
    drive with the run folder finished up to there (exit code 130)."""
    from marsscene.cli._progress import DriveMeter
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import DriveInterrupted
    from marsscene.sim.driver import drive as run_drive
    from marsscene.sim.pursuit import PursuitConfig

    t0 = time.perf_counter()
    meter = DriveMeter()
    try:
        res = run_drive(sim, route=route, seconds=seconds, out_dir=out_dir,
                        rng=stage_rng(seed, "sensors"),
                        pursuit=PursuitConfig(lookahead_m=lookahead), progress=meter,
                        jpeg_cache=jpeg_cache)
    except DriveInterrupted as stop:
        meter.close()
        s = stop.result.summary
        click.echo(f"marsscene: interrupted after {s['path_length_m']:.1f} m and "
                   f"{s['sim_time_s']:.1f} sim s; {out_dir} holds the drive up to there "
                   f"(`marsscene bag {out_dir}` and `marsscene export` read it)", err=True)
        sys.exit(130)
    meter.close()
    return res, time.perf_counter() - t0
