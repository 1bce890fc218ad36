"""``marsscene fly``: fly the Ingenuity-class scout over a built scene and log its run folder."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from marsscene.cli._common import user_errors


@click.command(short_help="Fly the helicopter scout through waypoints; log poses, images, "
                          "altimeter.")
@click.argument("scene_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--waypoints", "waypoints_path", required=True,
              type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="Text file of 'x y' lines (map frame, m); the scout lands at the last.")
@click.option("--altitude", default=10.0, show_default=True, type=click.FloatRange(1.0, 40.0),
              help="Flight height above the ground (m; the altimeter reads to 40 m).")
@click.option("--speed", default=3.0, show_default=True, type=click.FloatRange(0.1, 10.0),
              help="Cruise speed (m/s).")
@click.option("--camera-size", default="160x120", show_default=True,
              help="Navigation camera WIDTHxHEIGHT in pixels.")
@click.option("--camera-hz", default=2.0, show_default=True, type=click.FloatRange(0.1, 50.0))
@click.option("--density", type=click.FloatRange(0.001, 0.1), default=None,
              help="Air density (kg/m^3); default: the Jezero model (marsscene.scout.config).")
@click.option("--seed", default=0, show_default=True, type=int)
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=Path),
              help="Run folder to write.")
def fly(scene_dir: Path, waypoints_path: Path, altitude: float, speed: float, camera_size: str,
        camera_hz: float, density: float | None, seed: int, out_dir: Path) -> None:
    """Take off from the scene's centre, fly to each waypoint at ALTITUDE above the ground and
    land at the last one; write gt.tum, images/ + images.tum, altimeter.csv and run.json."""
    from marsscene.scout import FlightPlan
    from marsscene.scout import fly as fly_scout

    try:
        w, h = (int(v) for v in camera_size.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"{camera_size!r} is not WIDTHxHEIGHT",
                                 param_hint="--camera-size") from None
    with user_errors():
        try:
            wp = np.loadtxt(waypoints_path, ndmin=2)[:, :2]
        except (ValueError, IndexError) as err:
            raise click.BadParameter(f"{waypoints_path}: {err}", param_hint="--waypoints") from None
        plan = FlightPlan(altitude_m=altitude, speed_m_s=speed, camera_px=(w, h),
                          camera_hz=camera_hz)
        flight = fly_scout(scene_dir, wp, plan=plan, density_kg_m3=density, out_dir=out_dir,
                           seed=seed)
    s = flight.summary
    click.echo(f"flew {s['sim_time_s']:.1f} s, waypoints reached {sum(flight.reached)}/"
               f"{len(flight.reached)}, landed: {flight.touchdown_s is not None}, "
               f"{s['energy_wh']:.2f} Wh ({s['mean_power_w']:.0f} W mean), "
               f"{s['images']} images, real-time factor {flight.realtime_factor:.1f}")
    click.echo(f"   run: {out_dir}")
