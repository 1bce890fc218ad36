"""``marsscene drive``: drive the rover on a built scene along a route and write the logs."""

from __future__ import annotations

import sys
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import sigterm_interrupts, user_errors
from marsscene.cli._progress import DriveMeter, ProgressBar
from marsscene.cli.bag import BAG_OPTION_NAMES, bag_options, bag_options_of, echo_bag
from marsscene.cli.options_run import RUN_OPTION_NAMES, run_config, run_options
from marsscene.rover.config import OMEGA_MAX_RAD_S, V_MAX_M_S, RunConfig
from marsscene.runs.export.options import (
    DATASET_FORMATS,
    DATASET_IMAGES,
    DATASET_IMAGES_HELP,
    ExportOptions,
)
from marsscene.sim.mission import DriveOptions

_PATH = click.Path(exists=True, dir_okay=False, path_type=Path)
_D = DriveOptions()  # the drive's defaults (and their bounds) live in DriveOptions only


def _read_waypoints(path: Path) -> Any:
    """The waypoints of a file of ``x y`` (m) lines (``#`` comments, commas allowed)."""
    from marsscene.errors import ConfigError
    from marsscene.sim.route import check_waypoints

    rows = []
    for lineno, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        parts = text.replace(",", " ").split()
        try:
            rows.append([float(parts[0]), float(parts[1])])
        except (ValueError, IndexError):
            raise ConfigError(f"{path}:{lineno}: expected 'x y' in m, got {text[:80]!r}") from None
    return check_waypoints(rows, str(path))


_HELP = f"""Drive the rover along a route with pure pursuit (v <= {V_MAX_M_S} m/s,
|w| <= {OMEGA_MAX_RAD_S} rad/s, {RunConfig.control_hz:g} Hz), or with your controller.

\b
Examples:
  marsscene drive scenes/demo --waypoints wp.txt --lidar --out runs/r1
  marsscene drive scenes/demo --route route.tum --seconds 60 --camera
  marsscene drive scenes/demo --waypoints wp.txt --camera --bag --dataset euroc
  marsscene drive scenes/demo --waypoints wp.txt --lidar --controller my_nav:Planner
  marsscene drive scenes/demo --waypoints wp.txt --lidar --device cuda --out runs/g1
  marsscene drive --batch drives.toml --lidar --camera --device cuda
  marsscene drive scenes/demo --waypoints wp.txt --rover mer
  marsscene drive scenes/demo --team team.toml --lidar --out runs/team
"""


@click.command(short_help="Drive the rover on a built scene and log GT, odometry, IMU, sensors.",
               help=_HELP)
@click.argument("scene_dir", required=False,
                type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--device", default=None, metavar="DEVICE",
              help="Drive on MuJoCo Warp on this Warp device (cuda, cuda:0, cpu; needs "
              "marsscene[gpu]): the batch's rover and physics (docs/gpu_drives.md).")
@click.option("--batch", "batch_path", type=_PATH, default=None,
              help="A TOML file of [[drive]] tables (scene, waypoints or route, out, seed): "
              "all driven at once on --device (default: the GPU), instead of SCENE_DIR.")
@click.option("--team", "team_path", type=_PATH, default=None,
              help="A TOML file of [[robots]] tables (name, rover, waypoints or route, run): "
              "every robot in one world, a run folder each under --out (docs/team.md).")
@click.option("--rover", "rover_type", default=None, metavar="TYPE",
              help="The rover type: perseverance (default), mer, or a rover TOML file "
              "(docs/rovers.md).")
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
@run_options(*RUN_OPTION_NAMES)
@click.option(
    "--seed",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Seed of the sensor-noise stream.",
)
@click.option(
    "--lookahead-m",
    "lookahead",
    type=float,
    default=_D.pursuit.lookahead_m,
    show_default=True,
    help="Pure-pursuit lookahead (m).",
)
@click.option(
    "--max-slope-deg",
    "max_slope",
    type=float,
    default=_D.max_slope_deg,
    show_default=True,
    help="Route authoring: steepest slope allowed (deg).",
)
@click.option("--write-rover-xml", is_flag=True, help="Also write SCENE_DIR/mjcf/rover.xml.")
@click.option(
    "--corridor-m",
    "corridor",
    type=float,
    default=_D.corridor_m,
    show_default=True,
    help="Only MJCF rocks within this distance of the route are simulated (m); widened to "
    "the LiDAR range / camera window when those sensors are on.",
)
@click.option("--controller", "controller_ref", metavar="MODULE:NAME", default=None,
              help="Steer with your controller instead of pure pursuit: a callable "
              "controller(observation) -> (v, omega), or a class (instantiated with the route "
              "when it takes one); MODULE is imported from the current folder too "
              "(docs/runtime.md). Without --route/--waypoints it starts at the terrain centre "
              "and needs --seconds.")
@click.option("--bag", "write_bag", is_flag=True,
              help="Also write RUN_DIR/bag, a ROS 2 bag of the run (see `marsscene bag`).")
@click.option("--dataset", "datasets", multiple=True, type=click.Choice(DATASET_FORMATS),
              help="Also write RUN_DIR/tum_rgbd or RUN_DIR/euroc (see `marsscene export`; "
              "needs --camera); repeat for both.")
@click.option("--overwrite", is_flag=True,
              help="With --bag / --dataset: replace existing RUN_DIR/bag and dataset folders.")
@click.option("--dataset-images", type=click.Choice(DATASET_IMAGES),
              default=ExportOptions().dataset_images, show_default=True,
              help=DATASET_IMAGES_HELP)
@click.option("--keep-lidar-files", is_flag=True,
              help="With --bag and --lidar: keep RUN_DIR/lidar/*.ply beside the bag (by "
              "default the scans are kept once, in the bag).")
@bag_options
def drive(scene_dir: Path | None, device: str | None, batch_path: Path | None,
          team_path: Path | None, rover_type: str | None, route_path: Path | None,
          waypoints_path: Path | None, seconds: float | None, out_dir: Path, seed: int,
          lookahead: float, max_slope: float, corridor: float, write_rover_xml: bool,
          controller_ref: str | None, write_bag: bool, datasets: tuple[str, ...],
          overwrite: bool, dataset_images: str, keep_lidar_files: bool, **opts: Any) -> None:
    """``marsscene drive`` (its help text: :data:`_HELP`); ``opts`` holds the run and bag
    options."""
    import marsscene as ms
    from marsscene.sim.driver import DriveInterrupted
    from marsscene.sim.pursuit import PursuitConfig

    if route_path is not None and waypoints_path is not None:
        raise click.UsageError("give --route or --waypoints, not both")
    bag_values = {k: opts.pop(k) for k in list(opts) if k in BAG_OPTION_NAMES}
    if batch_path is not None or device is not None:
        if controller_ref or write_bag or datasets or rover_type or team_path:
            raise click.UsageError("--device/--batch drive with pure pursuit and write run "
                                   "folders only (no --controller, --rover, --team, --bag or "
                                   "--dataset yet)")
        with user_errors():
            run = run_config(opts)
            options = DriveOptions(max_slope_deg=max_slope, corridor_m=corridor,
                                   pursuit=PursuitConfig(lookahead_m=lookahead))
            _drive_batch(scene_dir, batch_path, device, route_path, waypoints_path, seconds,
                         out_dir, seed, run, options)
        return
    if scene_dir is None:
        raise click.UsageError("give SCENE_DIR (or --batch FILE)")
    export_of = lambda: ExportOptions(  # noqa: E731
        bag=bag_options_of(bag_values) if write_bag else None, datasets=datasets,
        overwrite=overwrite, dataset_images=dataset_images, keep_lidar_files=keep_lidar_files)
    if team_path is not None:
        if route_path or waypoints_path or controller_ref or rover_type:
            raise click.UsageError("--team lists each robot's rover and route: no --route, "
                                   "--waypoints, --controller or --rover")
        from marsscene.cli.drive_team import drive_team_cli

        with user_errors(), sigterm_interrupts():
            drive_team_cli(scene_dir, team_path, seconds, out_dir, seed, run_config(opts),
                           DriveOptions(max_slope_deg=max_slope, corridor_m=corridor,
                                        pursuit=PursuitConfig(lookahead_m=lookahead)),
                           export_of())
        return
    if route_path is None and waypoints_path is None and controller_ref is None:
        raise click.UsageError("give --route or --waypoints (or a --controller)")
    with user_errors():
        run = run_config(opts)
        options = DriveOptions(max_slope_deg=max_slope, corridor_m=corridor,
                               pursuit=PursuitConfig(lookahead_m=lookahead))
        export = export_of()
        waypoints = _read_waypoints(waypoints_path) if waypoints_path else None
        controller = _load_controller(controller_ref) if controller_ref else None
        if write_rover_xml:
            click.echo(f"   rover: {_write_rover_xml(scene_dir, run)}")
    with ExitStack() as stack, sigterm_interrupts():
        meter = _Progress(stack)
        try:
            with user_errors():
                res = ms.drive(scene_dir, route=route_path, waypoints=waypoints,
                               controller=controller, seconds=seconds, config=run,
                               options=options, export=export, out_dir=out_dir, seed=seed,
                               progress=meter, rover=rover_type)
        except DriveInterrupted as stop:
            meter.close()
            s = stop.result.summary
            _exit_interrupted(f"interrupted after {s['path_length_m']:.1f} m and "
                              f"{s['sim_time_s']:.1f} sim s; {out_dir} holds the drive up to "
                              f"there (`marsscene bag {out_dir}` and `marsscene export` read it)")
        except KeyboardInterrupt:  # while exporting: the run folder is whole
            meter.close()
            _exit_interrupted(f"interrupted while writing the bag; {out_dir} holds the whole "
                              f"drive (`marsscene bag {out_dir}` writes the bag)")
        meter.close()
    _report(res, out_dir)


def _drive_batch(scene_dir: Path | None, batch_path: Path | None, device: str | None,
                 route_path: Path | None, waypoints_path: Path | None, seconds: float | None,
                 out_dir: Path, seed: int, run: Any, options: Any) -> None:
    """``--device`` / ``--batch``: the drives on MuJoCo Warp (:func:`marsscene.drive_batch`)."""
    from marsscene.sim.batch import BatchDrive, drive_batch, read_batch_file

    if batch_path is not None:
        if scene_dir is not None or route_path or waypoints_path:
            raise click.UsageError("--batch lists the drives: no SCENE_DIR, --route or "
                                   "--waypoints with it")
        drives = read_batch_file(batch_path)
    else:
        if scene_dir is None or (route_path is None and waypoints_path is None):
            raise click.UsageError("give SCENE_DIR and --route or --waypoints")
        drives = [BatchDrive(scene=scene_dir, route=route_path, out_dir=out_dir, seed=seed,
                             seconds=seconds, waypoints=(_read_waypoints(waypoints_path)
                                                         if waypoints_path else None))]
    res = drive_batch(drives, config=run, options=options, device=device or "cuda", seed=seed)
    for out, s in zip(res.out_dirs, res.summaries, strict=True):
        click.echo(f"   drove: {s['path_length_m']:.2f} m in {s['sim_time_s']:.2f} sim s, goal "
                   f"reached: {s['goal_reached']}, cross-track RMS "
                   f"{s['cross_track_rms_m']:.3f} m -> {out}")
    click.echo(f"   batch: {len(drives)} drive(s) on {res.device} in {res.wall_s:.1f} s "
               f"({res.realtime_factor:.2f}x real time per rover)")


def _load_controller(ref: str) -> Any:
    """The controller named ``MODULE:NAME``: a callable, or a class instantiated once the drive
    is prepared, with the drive's route (authored or given) if its constructor takes one."""
    import importlib
    import inspect
    import os

    from marsscene.errors import ConfigError
    from marsscene.sim.control import OnStart

    module_name, _, name = ref.partition(":")
    if not module_name or not name:
        raise ConfigError(f"--controller {ref!r}: give MODULE:NAME, e.g. my_nav:Planner")
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        obj: Any = getattr(importlib.import_module(module_name), name)
    except (ImportError, AttributeError) as err:
        raise ConfigError(f"--controller {ref!r}: {type(err).__name__}: {err}") from None
    if not inspect.isclass(obj):
        if not callable(obj):
            raise ConfigError(f"--controller {ref!r} is not callable")
        return obj
    if "route" not in inspect.signature(obj).parameters:
        return obj()

    factory: Any = obj

    def make(sim: Any, route: Any = None) -> Any:  # the drive passes its route
        return factory(route=route)

    return OnStart(make)


def _exit_interrupted(message: str) -> None:
    click.echo(f"marsscene: {message}", err=True)
    sys.exit(130)


class _Progress:
    """The drive's progress line, then a bar per export."""

    def __init__(self, stack: ExitStack) -> None:
        self.stack, self.meter = stack, DriveMeter()
        self.bars: dict[str, Any] = {}
        self.closed = False

    def __call__(self, p: Any) -> None:
        from marsscene.sim.driver import DriveProgress

        if isinstance(p, DriveProgress):
            self.meter(p)
            return
        self.close()
        if p.stage not in self.bars:
            label = "writing bag (messages)" if p.stage == "bag" else f"writing {p.stage}"
            self.bars[p.stage] = ProgressBar(self.stack, label)
        self.bars[p.stage](p.done, p.total)

    def close(self) -> None:
        if not self.closed:
            self.meter.close()
            self.closed = True


def _report(run: Any, out_dir: Path) -> None:
    s = run.summary
    click.echo(
        f"   drove: {s['path_length_m']:.2f} m in {s['sim_time_s']:.2f} sim s "
        f"({s['sim_time_s'] / max(run.wall_s, 1e-9):.1f}x real time), goal reached: "
        f"{s['goal_reached']}, cross-track RMS "
        f"{s.get('cross_track_rms_m', float('nan')):.3f} m"
    )
    if run.bag is not None:
        echo_bag(run.bag)
    for fmt, folder in run.datasets.items():
        click.echo(f"  {fmt}: {folder}")
    click.echo(f"    logs: {out_dir}")


def _write_rover_xml(scene_dir: Path, run: Any) -> Path:
    """``SCENE_DIR/mjcf/rover.xml``: the rover the drive attaches to the scene."""
    from marsscene._atomic import write_atomic
    from marsscene.rover.config import CameraConfig, RoverConfig
    from marsscene.sim.rover_model import rover_mjcf

    fovy = (run.camera or CameraConfig()).fovy_deg  # the navcam, logged or not
    target = scene_dir / "mjcf" / "rover.xml"
    return write_atomic(target, rover_mjcf(RoverConfig(), camera_fovy_deg=fovy))
