"""Generate a place-recognition dataset: two traversals of one route, a frame per 0.1 m.

Output folder (the layout of ``gmberton/VPR-methods-evaluation``, read unchanged)::

    OUT/
      database/@E@N@@@@@D0001234@@HEADING@PITCH@ROLL@Z@T@database@.jpg
      queries/@E@N@...@queries@.jpg    E, N: the camera's east / north in scene metres
      poses.csv            split, file, t_s, x_m, y_m, z_m, qx, qy, qz, qw (navcam optical
                           frame in map), yaw_deg, tau, sun_elevation_deg, landmark_px (the
                           landmark's size in the frame, px: the smaller side of its
                           projected box; 0: not in view)
      dataset.json         the spec, the route, each traversal's offset and lookahead, counts
      route.tum            the route both traversals follow (each shifted sideways)
      scene/               the built scene (reused when its config is unchanged)
      traversals/<split>/  each traversal's run folder (trajectories, run.json; no images)

The file names carry the 14 ``@``-separated fields of that format: east, north, UTM zone and
letter (empty: scene metres), latitude and longitude (empty), a frame id, tile (empty), the
camera heading, pitch and roll in degrees, its height, the sim time and the split.
"""

from __future__ import annotations

import csv
import functools
import json
import logging
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import replacing_dir, write_atomic
from marsscene.benchmark.vpr.spec import SPLITS, TraversalSpec, VprSpec
from marsscene.benchmark.vpr.traversal import (
    image_name,
    irradiance_scale,
    offset_route,
    write_rows,
    write_traversal,
)
from marsscene.errors import RuntimeSimError

__all__ = ["generate_vpr", "image_name", "irradiance_scale", "offset_route"]

log = logging.getLogger(__name__)


def _scene(spec: VprSpec, out: Path) -> Path:
    """Build the scene into ``out/scene`` unless the same config is there already."""
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict(spec.scene.base_config())
    key = json.dumps({"config": cfg.to_dict(), "seed": spec.scene_seed}, sort_keys=True,
                     default=str)
    final = out / "scene"
    stamp = final / "vpr_scene_key.json"
    if stamp.is_file() and stamp.read_text(encoding="utf-8") == key:
        return final
    log.info("building scene %s (seed %d)", spec.scene.name, spec.scene_seed)
    scene = ms.build_scene(cfg, seed=spec.scene_seed)
    with replacing_dir(final, overwrite=True) as tmp:
        ms.write_scene(scene, tmp, formats=("mjcf",))
        (tmp / "vpr_scene_key.json").write_text(key, encoding="utf-8")
    return final


def _route(spec: VprSpec, scene_dir: Path) -> Any:
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.runs.tum import read_tum
    from marsscene.sim.route import Route, author_route
    from marsscene.sim.world import load_world

    r = spec.scene.route
    if r.file is not None:
        return Route.from_trajectory(read_tum(r.file))
    world = load_world(scene_dir)
    if r.waypoints is not None:
        return author_route(np.asarray(r.waypoints), world.heightfield,
                            max_slope_deg=r.max_slope_deg, obstacles=world.obstacles)
    return auto_route(centred_on_asset(r, scene_dir), world.heightfield, world.obstacles)


def _traverse(spec: VprSpec, split: str, lighting: TraversalSpec, scene_dir: Path, route: Any,
              offset_m: float, lookahead_m: float, run_dir: Path,
              progress: Callable[[Any], None] | None) -> None:
    import marsscene as ms
    from marsscene.sim.pursuit import PursuitConfig
    from marsscene.sim.route import Route

    camera = spec.camera_config(lighting, irradiance_scale(lighting, scene_dir))
    ms.drive(scene_dir, route=Route(offset_route(route.xy_m, offset_m)),
             config=ms.RunConfig(camera=camera),
             options=ms.DriveOptions(pursuit=PursuitConfig(lookahead_m=lookahead_m)),
             out_dir=run_dir, seed=spec.seed + 1000 * SPLITS.index(split), progress=progress)


def _landmark(name: str, scene_dir: Path, out: Path, rows: list[list[Any]],
              window_m: float) -> dict[str, Any]:
    """Append each frame's landmark size (px) to its row; the shares of frames in view. The
    camera's terrain window (``window_m``, replayed per traversal from the camera positions)
    bounds what it drew."""
    from marsscene.benchmark.vpr.landmark import landmark_parts, landmark_pixels
    from marsscene.sensors.camera_ground import far_window_bounds

    mark, hf = landmark_parts(scene_dir, name)
    intr = json.loads((out / "traversals" / SPLITS[0] / "camera" / "intrinsics.json")
                      .read_text(encoding="utf-8"))
    a = np.array([[float(v) for v in r[3:10]] for r in rows]).reshape(-1, 7)
    of_split = np.array([r[0] for r in rows])
    drawn = np.zeros((len(rows), 4))
    for s in SPLITS:
        drawn[of_split == s] = far_window_bounds(hf, window_m, a[of_split == s, :2])
    px = landmark_pixels(mark, a[:, :3], a[:, 3:], intr, hf, drawn)
    for r, v in zip(rows, px, strict=True):
        r.append(f"{v:.1f}")
    info: dict[str, Any] = {"name": name, "box_m": np.round(mark.box, 3).tolist(),
                            "splits": {}}
    for split in SPLITS:
        mine = px[[r[0] == split for r in rows]]
        seen = mine[mine > 0]
        info["splits"][split] = {
            "in_view_share": round(float((mine > 0).mean()), 4) if len(mine) else 0.0,
            "at_least_20px_share": round(float((mine >= 20).mean()), 4) if len(mine) else 0.0,
            "median_px_in_view": round(float(np.median(seen)), 1) if len(seen) else 0.0}
    return info


def _make_split(spec: VprSpec, split: str, scene_dir: Path, route_xy_m: NDArray[np.float64],
                offset_m: float, lookahead_m: float, out: Path, key: str,
                progress: Callable[[Any], None] | None = None) -> None:
    """Drive one traversal and write its JPEGs (module level: runs in a worker process too)."""
    from marsscene.sim.route import Route

    lighting: TraversalSpec = getattr(spec, split)
    with replacing_dir(out / "traversals" / split, overwrite=True) as run_dir, \
            replacing_dir(out / split, overwrite=True, create=False) as dest:
        _traverse(spec, split, lighting, scene_dir, Route(route_xy_m), offset_m, lookahead_m,
                  run_dir, progress)
        write_traversal(spec, split, run_dir, dest, key)


def generate_vpr(spec: VprSpec, out_dir: str | Path, *, overwrite: bool = False,
                 resume: bool = False, workers: int = 1, device: str | None = None,
                 progress: Callable[[str, Any], None] | None = None) -> dict[str, Any]:
    """Build the scene, drive both traversals, write the dataset; returns ``dataset.json``.

    Each traversal drives the route shifted sideways by a seeded offset in
    ``+-lateral_offset_m`` with a seeded pure-pursuit lookahead, so database and queries are
    never pixel-identical; frames are captured every ``spacing_m`` metres driven.
    ``progress(split, DriveProgress)`` is called once per simulated second (with
    ``workers=1``; ``workers=2`` drives the two traversals in two processes at once, the same
    bytes in half the time on two free cores). ``resume`` reuses traversals finished in
    ``out_dir`` with the same spec (``overwrite`` redoes them).
    """
    out = Path(out_dir)
    if (out.exists() and any(p.name in SPLITS for p in out.iterdir()) and not overwrite
            and not resume):
        raise RuntimeSimError(f"{out} already holds a VPR dataset; pass overwrite=True "
                              "(--overwrite) to replace it or resume=True (--resume)")
    out.mkdir(parents=True, exist_ok=True)
    scene_dir = _scene(spec, out)
    route = _route(spec, scene_dir)
    rng = np.random.default_rng(spec.seed)
    draws = {s: (float(rng.uniform(-1, 1)) * spec.lateral_offset_m,
                 2.0 + float(rng.uniform(-1, 1)) * spec.lookahead_jitter_m) for s in SPLITS}
    doc: dict[str, Any] = {"spec": {k: v for k, v in asdict(spec).items() if k != "source"},
                           "source": spec.source, "route_length_m": round(route.length_m, 3),
                           "traversals": {}}
    todo = []
    for split in SPLITS:
        parts = {"spec": doc["spec"], "split": split, "route": np.round(route.xy_m, 6).tolist()}
        if device is not None:
            from marsscene.benchmark.vpr.device import BATCH_ENGINE

            parts["engine"] = doc["engine"] = BATCH_ENGINE
        key = json.dumps(parts, sort_keys=True, default=str)
        done = out / "traversals" / split / "vpr_key.json"
        if resume and done.is_file() and done.read_text(encoding="utf-8") == key \
                and (out / split).is_dir():
            log.info("%s: reusing the finished traversal", split)
        else:
            todo.append((spec, split, scene_dir, route.xy_m, *draws[split], out, key))
    if device is not None and todo:
        from marsscene.benchmark.vpr.device import drive_traversals

        drive_traversals(todo, device)
    elif workers > 1 and len(todo) > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(min(workers, len(todo)), mp.get_context("spawn")) as pool:
            for f in [pool.submit(_make_split, *job) for job in todo]:
                f.result()
    else:
        for job in todo:
            split = job[1]
            _make_split(*job, progress=None if progress is None
                        else functools.partial(progress, split))
    rows: list[list[Any]] = []
    for split in SPLITS:
        with open(out / "traversals" / split / "poses.csv", encoding="utf-8") as fh:
            split_rows = list(csv.reader(fh))[1:]
        rows += split_rows
        lighting = getattr(spec, split)
        doc["traversals"][split] = {"offset_m": round(draws[split][0], 6),
                                    "lookahead_m": round(draws[split][1], 6),
                                    "irradiance_scale": round(irradiance_scale(lighting,
                                                                               scene_dir), 6),
                                    "frames": len(split_rows), **asdict(getattr(spec, split))}
    if spec.landmark_name:
        doc["landmark"] = _landmark(spec.landmark_name, scene_dir, out, rows,
                                    spec.camera_config(spec.database).terrain_window_m)
    write_rows(out / "poses.csv", rows, landmark=bool(spec.landmark_name))
    from marsscene.runs.tum import write_tum
    from marsscene.sim.world import load_world

    write_tum(out / "route.tum", route.to_trajectory(load_world(scene_dir).heightfield),
              header="VPR route (before offsets)")
    write_atomic(out / "dataset.json", json.dumps(doc, indent=1, sort_keys=True, default=str)
                 + "\n")
    return doc
