"""``marsscene benchmark``: benchmark protocols (``slam``; more subcommands join the group
from their own modules)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import dask_options, dask_where, user_errors


@click.group(short_help="Benchmark protocols: SLAM (ATE/RPE) and visual place recognition.")
def benchmark() -> None:
    """Benchmark protocols run on generated scenes (see docs/benchmark.md)."""


@benchmark.command(short_help="Scenes x tau x seeds: drive, export, run SLAM methods, score.")
@click.argument("spec_toml", type=click.Path(exists=True, dir_okay=False, path_type=Path))
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              required=True, help="Benchmark folder: cells/, results.csv, table.md, report.md.")
@dask_options
@click.option("--resume", is_flag=True,
              help="Continue the benchmark in --out: finished builds, drives and methods are "
              "reused.")
@click.option("--method-workers", type=click.IntRange(1, 16), default=2, show_default=True,
              help="Methods of one cell run side by side on this many threads (KISS-ICP and "
              "command methods are processes of their own; results do not depend on it).")
@click.option("--method-processes", type=click.IntRange(1, 64), default=1, show_default=True,
              help="Processes that share a method's work where it splits: Open3D RGB-D's "
              "frame pairs, per RGB-D row (for cores no cell uses; results do not depend on "
              "it).")
@click.option("--length-m", type=click.FloatRange(min=5.0), default=None,
              help="A quick check: every automatic route shortened to this length (m).")
@click.option("--scene", "scenes", multiple=True,
              help="Only this scene of the spec (repeat for several).")
@click.option("--device", default=None, metavar="DEVICE",
              help="Drive every cell at once on MuJoCo Warp on this Warp device (cuda, "
              "cuda:0, cpu; needs marsscene[gpu]), then run the methods on the CPU cores "
              "(docs/gpu_drives.md).")
def slam(spec_toml: Path, out_dir: Path, workers: int | None, scheduler: str | None,
         serial: bool, resume: bool, method_workers: int, method_processes: int,
         length_m: float | None, scenes: tuple[str, ...], device: str | None) -> None:
    """Run the SLAM benchmark SPEC_TOML into OUT.

    Every cell (scene x tau x seed) is built, driven along its route with the camera (and, in
    one tau per scene, the LiDAR), exported as TUM RGB-D / EuRoC (and a ROS 2 bag when a method
    needs one), and every method is scored: ATE after Umeyama SE(3) alignment (Sim(3) for
    monocular), RPE per distance, tracked fraction. A method that fails is a row with its
    status, not an error.

    \b
    Examples:
      marsscene benchmark slam docs/examples/benchmark_slam_quick.toml --out bench/quick
      marsscene benchmark slam paper.toml --out /shared/bench --scheduler tcp://head:8786
      marsscene benchmark slam paper.toml --out bench/paper --resume
      marsscene benchmark slam paper.toml --out bench/p40 --length-m 40 --scene mars-base
      marsscene benchmark slam paper.toml --out bench/gpu --device cuda
    """
    from marsscene.benchmark.slam.run import run_slam_benchmark, slam_cells
    from marsscene.benchmark.slam.spec import SlamSpec

    where = dask_where(workers, scheduler, serial)

    def show(p: Any) -> None:
        row = p.row
        methods = ", ".join(
            f"{m['method']} {m['ate_rmse_m']:.3f} m" if m.get("status") == "ok"
            else f"{m['method']} {m.get('status')}" for m in row.get("methods", ()))
        mark = "FAILED" if row["status"] == "failed" else "done"
        click.echo(f"[{p.done}/{p.total}] {mark} {row['cell_id']}: "
                   f"{row.get('error') if row['status'] == 'failed' else methods}", err=True)

    with user_errors():
        spec = SlamSpec.from_toml(spec_toml)
        if length_m is not None or scenes:
            spec = spec.shortened(length_m=length_m, scenes=scenes or None)
        n = len(slam_cells(spec))
        click.echo(f"benchmark slam: {n} cells x {len(spec.methods)} methods {where}", err=True)
        if device is not None:  # before any folder is made: a spec the batch cannot drive
            from marsscene.sim.batch.api import check_batch_config

            check_batch_config(spec.run_config(lidar=True, camera=True))
            click.echo(f"benchmark slam: every cell's drive at once on {device} (MuJoCo Warp) "
                       "first, then the methods", err=True)
        res = run_slam_benchmark(spec, out_dir, workers=workers, scheduler=scheduler,
                                 serial=serial, resume=resume, progress=show,
                                 method_workers=method_workers,
                                 method_processes=method_processes, device=device)
    click.echo(f"methods: {res.count('ok')} ok, {res.count('lost')} lost, "
               f"{res.count('failed')} failed, {res.count('missing')} missing")
    for f in res.files:
        click.echo(f"wrote: {f}")
    if any(c["status"] == "failed" for c in res.cells):
        raise SystemExit(1)


@benchmark.command(short_help="Copy a SLAM benchmark's results, without its scenes and logs.")
@click.argument("bench_dir", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.argument("dest", type=click.Path(file_okay=False, path_type=Path))
@click.option("--max-rate-hz", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Thin every trajectory to about this many poses a second (the plots need "
              "about 1; the rows are scored already). Default: every pose.")
def pack(bench_dir: Path, dest: Path, max_rate_hz: float | None) -> None:
    """Copy the results of the SLAM benchmark in BENCH_DIR to DEST: its table, plots and
    report, and each cell's rows, estimates and ground truth (megabytes where the cells hold
    gigabytes). `benchmark slam SPEC --out DEST --resume` reuses every cell of DEST whose rows
    are all current and runs the rest; DEST may be an earlier pack, updated. With
    --max-rate-hz the trajectories are thinned (each file says so): the table and report
    stay the same, the plots draw fewer poses.

    \b
    Example (a long benchmark carried over to another machine, finished cells only):
      marsscene benchmark pack bench/paper results/paper --max-rate-hz 1
      marsscene benchmark slam paper.toml --out results/paper --resume
    """
    from marsscene.benchmark.slam.pack import pack_benchmark

    with user_errors():
        done = pack_benchmark(bench_dir, dest, max_rate_hz=max_rate_hz)
    click.echo(f"packed {done.cells} cells: {done.files} files, {done.bytes / 1e6:.1f} MB "
               f"into {dest}")
