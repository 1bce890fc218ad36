"""A SLAM benchmark's drives as batches on one device (``benchmark slam --device cuda``).

Every cell is built as before (:func:`marsscene.sweep.run_cell`); then every cell whose drive
is not done is driven in one :func:`marsscene.sim.batch.drive_batch` per group of cells with
the same camera and terrain size (one MuJoCo Warp model carries one rover and one heightfield
size), each cell its own scene, route, lighting, noise seed and LiDAR or none. Each drive is
then finished as the CPU cell finishes its own (:mod:`.cell`): the live methods (KISS-ICP) are
fed the drive's files in the drive's order (:func:`.replay.replay_run`: the estimate they give
live), the bag is written where the methods need one, ``drive/benchmark_drive.json`` records
the drive, and the TUM RGB-D and EuRoC folders are exported. The methods then run on the CPU
cores as in any benchmark, reading the folders unchanged.

A batch drive is keyed apart from a CPU drive of the same inputs (:func:`.keys.batch_key`: its
physics differs, :doc:`/gpu_drives`), so a benchmark folder never mixes the two silently. A
group that fails leaves its error in each of its cells (``drive_error.txt``), whose rows then
fail with it.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir, write_atomic
from marsscene.benchmark.slam.cell import _export_datasets, _route, write_live
from marsscene.benchmark.slam.keys import (
    BATCH_ENGINE,
    ERROR_FILE,
    batch_key,
    drive_key,
    read_json,
    write_json,
)
from marsscene.benchmark.slam.methods import DRIVE_FILE
from marsscene.benchmark.slam.plan import CellPlan, cell_plan
from marsscene.benchmark.slam.spec import SlamSpec
from marsscene.sweep.cell import run_cell
from marsscene.sweep.grid import Cell

__all__ = ["drive_cells"]

log = logging.getLogger("marsscene")

def _pending(spec: SlamSpec, cell: Cell, cells_dir: Path
             ) -> tuple[CellPlan, Path, str, bool] | None:
    """Build the cell; its plan, folder, drive key and bag flag if its drive must run."""
    plan = cell_plan(spec, cell)
    cell_dir = cells_dir / cell.cell_id
    row = run_cell(cell, cells_dir, None)
    if row["status"] == "failed":
        return None  # its row reports the build's error
    key, bag = drive_key(spec, plan.scene, plan.lidar, str(row.get("config_hash")),
                         plan.camera, plan.live)
    done = read_json(cell_dir / "drive" / DRIVE_FILE)
    if done is not None and done.get("key") == batch_key(key):
        return None
    return plan, cell_dir, batch_key(key), bag


def _group_key(plan: CellPlan, scene_dir: Path) -> tuple[Any, ...]:
    from marsscene.sim.world import load_world

    hf = load_world(scene_dir).heightfield
    return plan.camera, hf.z_m.shape, round(hf.cell_size_m, 9)


def drive_cells(spec: SlamSpec, cells: list[Cell], cells_dir: Path, *, device: str,
                workers: int | None = None,
                progress: Callable[[str], None] | None = None) -> dict[str, str]:
    """Build every cell and drive every cell not yet driven, in batches on ``device``; the
    errors by cell id (also left in each cell's ``drive_error.txt``)."""
    groups: dict[tuple[Any, ...], list[tuple[CellPlan, Path, str, bool]]] = {}
    for cell in cells:
        item = _pending(spec, cell, cells_dir)
        if item is not None:
            (item[1] / ERROR_FILE).unlink(missing_ok=True)
            groups.setdefault(_group_key(item[0], item[1] / "scene"), []).append(item)
    errors: dict[str, str] = {}
    for items in groups.values():
        if progress is not None:
            progress(f"driving {len(items)} cells at once on {device}")
        try:
            _drive_group(spec, items, device=device, workers=workers)
        except Exception as err:  # the group's cells fail with it; the others go on
            msg = " ".join(f"{type(err).__name__}: {err}".split())
            log.warning("batch of %d cells failed: %s", len(items), msg)
            for _, cell_dir, _, _ in items:
                errors[cell_dir.name] = msg
                write_atomic(cell_dir / ERROR_FILE, msg + "\n")
    return errors


def _drive_group(spec: SlamSpec, items: list[tuple[CellPlan, Path, str, bool]], *,
                 device: str, workers: int | None) -> None:
    """One batch: every cell of ``items`` driven at once, then finished in its folder."""
    import marsscene as ms

    run = spec.run_config(lidar=any(plan.lidar for plan, *_ in items),
                          camera=items[0][0].camera)
    with ExitStack() as stack:
        tmps = [stack.enter_context(replacing_dir(cell_dir / "drive"))
                for _, cell_dir, _, _ in items]
        drives = []
        for (plan, cell_dir, _, _), tmp in zip(items, tmps, strict=True):
            route = _route(plan.scene, cell_dir / "scene")
            drives.append(ms.BatchDrive(scene=cell_dir / "scene", route=route.get("route"),
                                     waypoints=route.get("waypoints"), out_dir=tmp,
                                     seed=spec.noise_seed, seconds=plan.scene.seconds,
                                     lidar=plan.lidar))
        options = ms.DriveOptions(max_slope_deg=items[0][0].scene.route.max_slope_deg)
        res = ms.drive_batch(drives, config=run, options=options, device=device,
                          workers=workers)
        for (plan, _, key, bag), tmp, summary in zip(items, tmps, res.summaries, strict=True):
            _finish(spec, plan, tmp, key, bag, summary, res.wall_s / len(items))
    for _, cell_dir, _, _ in items:
        _export_datasets(cell_dir / "drive", camera=run.camera is not None)


def _finish(spec: SlamSpec, plan: CellPlan, run_dir: Path, key: str, bag: bool,
            summary: dict[str, Any], wall_share_s: float) -> None:
    """The cell's live estimates, bag and ``drive.json``, as a CPU cell writes them."""
    import marsscene as ms
    from marsscene.benchmark.slam.kiss_icp import LiveKissIcp, lidar_mount
    from marsscene.benchmark.slam.replay import replay_run
    from marsscene.rover.config import RoverConfig
    from marsscene.runs.export.bag import write_bag
    from marsscene.runs.tum import read_tum

    mount = lidar_mount(RoverConfig())
    live = {m.name: LiveKissIcp(lidar_mount=mount, **m.options) for m in plan.live}
    if live:
        replay_run(run_dir, list(live.values()))
    fed = write_live(run_dir, live, "of the batch drive, after it")
    if bag:
        t0 = time.perf_counter()
        write_bag(run_dir, run_dir / "bag", ms.BagOptions(
            sensors=None if spec.sensors.get("bag") else ("lidar",)))
        log.info("%s: bag written in %.0f s", run_dir, time.perf_counter() - t0)
    route = read_tum(run_dir / "route.tum")
    write_json(run_dir / DRIVE_FILE, {"key": key, "summary": {
        "route_m": round(route.path_length_m(), 3), "t_drive_s": round(wall_share_s, 3),
        **fed,
        "engine": BATCH_ENGINE,
        **{k: summary.get(k) for k in ("path_length_m", "sim_time_s", "goal_reached",
                                       "cross_track_rms_m")}}})
