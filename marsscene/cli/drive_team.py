"""``marsscene drive SCENE_DIR --team FILE``: a team of robots in one world, a run folder each."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click


def drive_team_cli(scene_dir: Path, team_path: Path, seconds: float | None, out_dir: Path,
                   seed: int, run: Any, options: Any, export: Any = None) -> None:
    """Drive the team of ``team_path`` (:func:`marsscene.runtime.robot.read_team_file`) on
    ``scene_dir``; the command line's run options are the sensors of every robot without its
    own ``run`` table, and the file's ``seconds`` / ``seed`` give way to the options;
    ``export`` writes each robot's bag and datasets (``OUT/NAME/bag``: topics under
    ``/NAME``)."""
    from marsscene.runtime.robot import read_team_file
    from marsscene.runtime.team import drive_team
    from marsscene.sim.driver import DriveInterrupted

    robots, settings = read_team_file(team_path)
    seconds = seconds if seconds is not None else settings.get("seconds")
    seed = seed if seed else int(settings.get("seed", 0))
    last: dict[str, int] = {}

    def progress(p: Any) -> None:  # a line per robot every 10 simulated seconds
        t = int(p.drive.sim_time_s)
        if t // 10 > last.get(p.robot, -1):
            last[p.robot] = t // 10
            click.echo(f"   {p.robot}: {t} sim s, {p.drive.distance_m:.1f} m", err=True)

    try:
        res = drive_team(scene_dir, robots, seconds=seconds, config=run, options=options,
                         out_dir=out_dir, seed=seed, progress=progress, export=export,
                         scouts=settings.get("scouts", ()))
    except DriveInterrupted as stop:
        t = stop.result.summary["sim_time_s"]
        click.echo(f"marsscene: interrupted at {t:.1f} sim s; each robot's folder under "
                   f"{out_dir} holds its drive up to there", err=True)
        sys.exit(130)
    for name, r in res.robots.items():
        s = r.summary
        click.echo(f"   {name}: {s['path_length_m']:.2f} m in {s['sim_time_s']:.2f} sim s, "
                   f"goal reached: {s['goal_reached']} -> {r.out_dir}")
        if r.bag is not None:
            click.echo(f"          bag: {r.bag.path} (topics under /{name})")
        for fmt, path in r.datasets.items():
            click.echo(f"          {fmt}: {path}")
    for name, f in res.scouts.items():
        click.echo(f"   {name}: flew {len(f.reached)} waypoints ({sum(f.reached)} reached), "
                   f"{f.summary['images']} images -> {f.out_dir}")
    if res.scouts and out_dir is not None:
        click.echo(f"   crossview: {res.crossview} scout images paired with a rover frame -> "
                   f"{out_dir / 'crossview.csv'}")
    click.echo(f"    team: {len(res.robots)} robots in {res.wall_s:.1f} s "
               f"({res.realtime_factor:.2f}x real time) -> {out_dir}")
