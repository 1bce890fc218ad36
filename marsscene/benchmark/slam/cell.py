"""One SLAM benchmark cell (scene x tau x seed): build, route, drive, export, run the methods.

A cell folder ``DIR/cells/<cell_id>/`` holds::

    config.toml, scene/, result.json   the build, by :func:`marsscene.sweep.run_cell`
    drive/                             the run folder (gt.tum, odom.tum, camera/, lidar/ ...),
                                       route.tum, bag/ (if needed)
    drive/tum_rgbd/, drive/euroc/      the camera's dataset exports, written after the drive
    drive/live/<method>.tum            KISS-ICP's estimate, made during the drive
    estimates/<method>.tum             each method's raw estimate

KISS-ICP registers each scan as the drive makes it (:class:`.kiss_icp.LiveKissIcp`, the
estimate ``kiss_icp_pipeline`` gives on the bag), so the LiDAR stream is stored only when asked
(``[sensors] lidar_files = true``, or a bag with ``[sensors] bag = true``). With
``[sensors] keep_images = false`` the camera images are deleted once the cell's methods are
scored (a resumed benchmark that must run a camera method again drives the cell again).
    methods/<method>.json              each method's score row (written last: marks it done)

Every stage is atomic and keyed by a hash of its inputs (:mod:`.keys`), so a resumed benchmark
redoes only what changed or never finished (a drive killed while exporting its datasets keeps
the drive and writes the missing dataset folders); a cell whose rows are all current is reused from
its result files alone (:mod:`.pack`: no scene or logs needed). Errors never escape
:func:`run_slam_cell`.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir, write_atomic
from marsscene.benchmark.slam.keys import (
    batch_error,
    batch_key,
    drive_key,
    method_file,
    read_json,
    write_json,
)
from marsscene.benchmark.slam.methods import DRIVE_FILE, CellData, estimate
from marsscene.benchmark.slam.metrics import failed_score, score_estimate
from marsscene.benchmark.slam.pack import scored_cell
from marsscene.benchmark.slam.plan import cell_plan
from marsscene.benchmark.slam.spec import MethodSpec, SceneSpec, SlamSpec
from marsscene.errors import MarsSceneError
from marsscene.sweep.cell import run_cell
from marsscene.sweep.grid import Cell

__all__ = ["DRIVE_FILE", "run_slam_cell"]

log = logging.getLogger("marsscene")
IMAGES_REMOVED = "images_removed.txt"  # in drive/: the camera images were deleted after scoring


def _route(scene: SceneSpec, scene_dir: Path) -> dict[str, Any]:
    """The route arguments of :func:`marsscene.drive` (automatic routes authored here)."""
    spec = scene.route
    if spec.file is not None:
        return {"route": spec.file}
    if spec.waypoints is not None:
        return {"waypoints": spec.waypoints}
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.sim.world import load_world

    world = load_world(scene_dir)
    return {"route": auto_route(centred_on_asset(spec, scene_dir), world.heightfield,
                                world.obstacles)}


def _drive(spec: SlamSpec, scene: SceneSpec, cell_dir: Path, lidar: bool, scene_hash: str,
           force: bool, camera: bool = True, live: tuple[MethodSpec, ...] = (),
           device: str | None = None) -> dict[str, Any]:
    """Drive the cell's route with its sensors into ``cell_dir/drive`` (unless done); the
    ``live`` methods (KISS-ICP) run on the LiDAR during the drive. With ``device`` the drive
    was made in a batch (:mod:`.device`): it is read, or its error raised."""
    final = cell_dir / "drive"
    live = live if lidar else ()
    key, bag = drive_key(spec, scene, lidar, scene_hash, camera, live)
    run = spec.run_config(lidar=lidar, camera=camera)
    if device is not None:
        key = batch_key(key)
    done = None if force and device is None else read_json(final / DRIVE_FILE)
    if done is not None and done.get("key") == key:
        _export_datasets(final, camera=run.camera is not None)
        return dict(done["summary"])
    if device is not None:
        raise MarsSceneError(batch_error(cell_dir, device))
    import marsscene as ms
    from marsscene.benchmark.slam.kiss_icp import LiveKissIcp, lidar_mount
    from marsscene.rover.config import RoverConfig

    # every sensor with [sensors] bag = true, else the LiDAR alone (a command reading {bag_dir})
    bag_options = ms.BagOptions(sensors=None if spec.sensors.get("bag") else ("lidar",)) \
        if bag else None
    mount = lidar_mount(RoverConfig())  # the rover every drive runs
    odometry = {m.name: LiveKissIcp(lidar_mount=mount, **m.options) for m in live}
    with replacing_dir(final) as tmp:
        t0 = time.perf_counter()
        drv = ms.drive(
            cell_dir / "scene", **_route(scene, cell_dir / "scene"), seconds=scene.seconds,
            config=run, out_dir=tmp, seed=spec.noise_seed, listeners=list(odometry.values()),
            options=ms.DriveOptions(max_slope_deg=scene.route.max_slope_deg,
                                    route_note=f"route of scene {scene.name}: {{length_m:.1f}} m"),
            export=ms.ExportOptions(bag=bag_options,  # the datasets: a stage of their own
                                    lidar_files=bag or bool(spec.sensors.get("lidar_files"))))
        summary = {"route_m": round(drv.route.length_m, 3) if drv.route else None,
                   "t_drive_s": time.perf_counter() - t0 - drv.export_s,
                   **write_live(tmp, odometry, "during the drive"),
                   **{k: drv.summary.get(k) for k in ("path_length_m", "sim_time_s",
                                                      "goal_reached", "cross_track_rms_m")}}
        write_json(tmp / DRIVE_FILE, {"key": key, "summary": summary})
    _export_datasets(final, camera=run.camera is not None)
    return summary


def write_live(run_dir: Path, odometry: dict[str, Any], when: str) -> dict[str, Any]:
    """Each live KISS-ICP's estimate as ``run_dir/live/<name>.tum`` (``when``: how it was fed,
    for the header); the drive summary's ``t_live_s`` and ``icp_steps_kept``."""
    from marsscene.runs.tum import write_tum

    for name, odo in odometry.items():
        traj = odo.trajectory()
        if traj is not None:
            prior = " with the wheel odometry's prior" if odo.wheel_prior else ""
            write_tum(run_dir / "live" / f"{name}.tum", traj,
                      header=f"{name}: KISS-ICP fed each scan {when}{prior}")
    return {"t_live_s": {n: round(o.seconds, 3) for n, o in odometry.items()},
            "icp_steps_kept": {n: [o.icp_steps_kept, len(o.poses)]
                               for n, o in odometry.items() if o.wheel_prior}}


def _export_datasets(run_dir: Path, camera: bool) -> None:
    """Write the drive's missing dataset folders (TUM RGB-D, EuRoC) that the camera methods and
    command templates read. Each is atomic, so one that exists is whole; none after the images
    were deleted."""
    if not camera or (run_dir / IMAGES_REMOVED).is_file():
        return
    from marsscene.runs.export.datasets import export_dataset
    from marsscene.runs.export.options import dataset_folder

    for fmt in ("tum-rgbd", "euroc"):
        if not (run_dir / dataset_folder(fmt)).is_dir():
            t0 = time.perf_counter()
            export_dataset(run_dir, fmt)
            log.info("%s: %s written in %.0f s", run_dir, dataset_folder(fmt),
                     time.perf_counter() - t0)


def _remove_images(run_dir: Path) -> int:
    """Delete the camera images of a scored cell (the run's PNGs and the datasets' links to
    them); stamps, trajectories and estimates stay. Returns the files removed."""
    files = [p for sub in ("camera", "tum_rgbd", "euroc") for p in (run_dir / sub).rglob("*")
             if p.suffix in (".png", ".jpg") and p.is_file()]
    write_atomic(run_dir / IMAGES_REMOVED,
                 f"{len(files)} camera images were deleted once the benchmark's methods were "
                 "scored ([sensors] keep_images = false).\n")
    for p in files:
        p.unlink()
    return len(files)


def _needs_images(spec: SlamSpec, methods: list[MethodSpec], cell_dir: Path) -> bool:
    """A camera method of the cell must run, but its images were deleted after scoring."""
    run_dir = cell_dir / "drive"
    if not (run_dir / IMAGES_REMOVED).is_file():
        return False
    drive_hash = str((read_json(run_dir / DRIVE_FILE) or {}).get("key"))
    for m in methods:  # a tum-file method reads its own file, a command maybe the images
        if m.kind == "tum-file" or (m.sensor != "camera" and m.kind != "command"):
            continue
        path, key = method_file(spec, m, cell_dir, drive_hash)
        done = read_json(path)
        if done is None or done.get("key") != key:
            return True
    return False


def _score(spec: SlamSpec, method: MethodSpec, *, data: CellData, drive_hash: str,
           force: bool, processes: int = 1) -> dict[str, Any]:
    """The method's row, from ``methods/<name>.json`` when its inputs did not change."""
    path, key = method_file(spec, method, data.cell_dir, drive_hash)
    done = None if force or method.kind == "tum-file" else read_json(path)
    if done is not None and done.get("key") == key:
        return dict(done["row"])
    t0 = time.perf_counter()
    out_tum = data.cell_dir / "estimates" / f"{method.name}.tum"
    est = estimate(method, data, out_tum, processes=processes)
    try:
        gt = data.ground_truth(str(method.frame))
        if est.trajectory is None:
            score = failed_score(est.status, est.note, align=str(method.align),
                                 path_m=gt.path_length_m())
        else:
            score = score_estimate(
                est.trajectory, gt, align=str(method.align),
                frames_total=data.frames(str(method.sensor)), frames_tracked=est.frames_tracked,
                min_tracked_fraction=spec.min_tracked_fraction,
                rpe_distance_m=spec.rpe_distance_m)
            if est.note:  # after the score's own (e.g. the tracked fraction)
                score = dataclasses.replace(score, note="; ".join(filter(None, (
                    score.note, est.note))))
    except MarsSceneError as err:
        score = failed_score("failed", f"{type(err).__name__}: {err}", align=str(method.align))
    row = {"method": method.name, "kind": method.kind, **score.as_row(),
           "t_method_s": round(time.perf_counter() - t0, 3)}
    write_json(path, {"key": key, "row": row})
    return row


def _score_or_fail(spec: SlamSpec, method: MethodSpec, **kw: Any) -> dict[str, Any]:
    """:func:`_score`, with an unexpected error as the method's ``failed`` row (the other
    methods of the cell, maybe running beside it, keep theirs)."""
    try:
        return _score(spec, method, **kw)
    except Exception as err:
        msg = " ".join(f"{type(err).__name__}: {err}".split())
        log.warning("method %s failed: %s", method.name, msg)
        return {"method": method.name, "kind": method.kind,
                **failed_score("failed", msg, align=str(method.align)).as_row()}


def _images_to_remove(spec: SlamSpec, camera: bool, cell_dir: Path) -> bool:
    """The cell's camera images are still on disk, to be deleted once it is scored."""
    return camera and not spec.sensors.get("keep_images", True) \
        and not (cell_dir / "drive" / IMAGES_REMOVED).is_file()


def _with_drive(row: dict[str, Any], drv: dict[str, Any]) -> dict[str, Any]:
    """``row`` with the drive's summary and its columns of the cells' table."""
    row["drive"] = drv
    row.update(distance_m=drv.get("path_length_m"), sim_time_s=drv.get("sim_time_s"),
               goal_reached=drv.get("goal_reached"), t_drive_s=drv.get("t_drive_s"),
               cross_track_rms_m=drv.get("cross_track_rms_m"))
    return row


def run_slam_cell(cell: Cell, *, out_dir: str, spec: SlamSpec, force: bool = False,
                  method_workers: int = 1, method_processes: int = 1,
                  device: str | None = None) -> dict[str, Any]:
    """Build, drive and score one cell into ``out_dir/<cell_id>/``; return its row.

    The row has the sweep's build row (``status``, ``error``, timings ...) plus ``drive``
    (route and drive summary) and ``methods``: one score row per method that runs in this cell
    (LiDAR and wheel odometry only in the ``lidar_tau`` cell). A failed build or drive gives
    ``status = "failed"`` and a ``failed`` row for every method. ``method_workers`` threads
    score the methods side by side (rows in the spec's order whatever the finishing order);
    ``method_processes`` processes share a method's work where it splits (Open3D RGB-D's
    frame pairs). Neither changes a row. With ``device`` the cell's drive was made in a batch
    on that device (:func:`.device.drive_cells`) and is read from its folder.
    """
    plan = cell_plan(spec, cell)
    scene, tau, seed, lidar, camera = plan.scene, plan.tau, plan.seed, plan.lidar, plan.camera
    methods = list(plan.methods)
    cell_dir = Path(out_dir) / cell.cell_id
    live = tuple(m for m in methods if m.kind == "kiss-icp")
    stored_row = None if force else scored_cell(spec, scene, cell, cell_dir, methods,
                                                lidar=lidar, camera=camera, live=live,
                                                device=device)
    if stored_row is not None and not _images_to_remove(spec, camera, cell_dir):
        return _with_drive(stored_row, stored_row["drive"])  # a packed cell: no scene needed
    row = run_cell(cell, out_dir, None, force=force)
    row["methods"] = []
    try:
        if row["status"] == "failed":
            raise MarsSceneError(row["error"])
        redrive = force or _needs_images(spec, methods, cell_dir)
        drv = _drive(spec, scene, cell_dir, lidar, str(row.get("config_hash")), redrive,
                     camera, live, device)
        _with_drive(row, drv)
        stored = read_json(cell_dir / "drive" / DRIVE_FILE) or {}
        data = CellData(cell_dir, scene.name, tau, seed)
        score = partial(_score_or_fail, spec, data=data, drive_hash=str(stored.get("key")),
                        force=force, processes=method_processes)
        if method_workers <= 1 or len(methods) <= 1:
            row["methods"] += [score(m) for m in methods]
        else:
            with ThreadPoolExecutor(min(method_workers, len(methods)),
                                    thread_name_prefix="slam-method") as pool:
                row["methods"] += list(pool.map(score, methods))  # in the spec's order
        if _images_to_remove(spec, camera, cell_dir):
            _remove_images(cell_dir / "drive")
    except Exception as err:  # one failing cell never stops the benchmark
        msg = " ".join(f"{type(err).__name__}: {err}".split())
        log.warning("cell %s failed: %s", cell.cell_id, msg)
        row.update(status="failed", error=row.get("error") or msg)
        done = {m["method"] for m in row["methods"]}
        row["methods"] += [{"method": m.name, "kind": m.kind,
                            **failed_score("failed", msg, align=str(m.align)).as_row()}
                           for m in methods if m.name not in done]
    return row
