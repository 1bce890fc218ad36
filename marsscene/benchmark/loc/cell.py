"""One localization cell (scene x tau): the scene and its orbital map, the route, the seeded
query places and priors, each query's short drive and folder, every method's answer and score.

A cell folder ``DIR/cells/<cell_id>/`` holds::

    scene/                 the built scene with scene/orbital/ (or none: a spec's scene_dir)
    build.json             the build's key
    queries/NNN/run/       the query's short drive (a run folder)
    queries/NNN/query/     the query folder (:mod:`.query`): all a method may read
    queries/NNN/truth.json the local frame's true pose, and the query's key
    queries/NNN/answers/<method>.tum, queries/NNN/methods/<method>.json  (its score row)

Every stage is atomic and keyed by a hash of its inputs (:func:`marsscene.benchmark.slam.keys.
digest`), so a resumed benchmark redoes only what changed or never finished. Errors never
escape :func:`run_loc_cell`: a failed query or method is a row with its status.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir
from marsscene.benchmark.loc.methods import read_answer, run_method
from marsscene.benchmark.loc.queries import (
    draw_priors,
    query_arc_lengths,
    query_rng,
    segment_before,
)
from marsscene.benchmark.loc.spec import LocMethod, LocScene, LocSpec
from marsscene.benchmark.slam.keys import digest, read_json, write_json
from marsscene.sweep.grid import Cell

__all__ = ["run_loc_cell", "score"]

log = logging.getLogger("marsscene")
SPEED_M_S = 0.5  # the follower's cruise speed (marsscene.sim: v <= 0.5 m/s)


def _scene_dir(scene: LocScene, spec: LocSpec, cell_dir: Path) -> tuple[Path, str]:
    """The cell's scene folder with its orbital map (built here unless the spec names one)."""
    if scene.scene_dir is not None:
        path = Path(scene.scene_dir)
        if not (path / "orbital" / "orbital.json").is_file():
            from marsscene.errors import ConfigError

            raise ConfigError(f"scene {scene.name!r}: {path} has no orbital map; build it with "
                              "marsscene build --orbital-map")
        return path, digest({"scene_dir": str(path)})
    import marsscene as ms
    from marsscene.orbital import OrbitalModel, orbital_map, write_orbital_map

    cfg = {**scene.as_scene_spec().base_config(), "seed": spec.seed}
    key = digest({"config": cfg, "orbital": OrbitalModel().to_dict()})
    done = read_json(cell_dir / "build.json")
    if done is None or done.get("key") != key or not (cell_dir / "scene").is_dir():
        with replacing_dir(cell_dir / "scene") as tmp:
            built = ms.build_scene(ms.SceneConfig.from_dict(cfg), seed=spec.seed)
            ms.write_scene(built, tmp)
            write_orbital_map(orbital_map(built), tmp)
        write_json(cell_dir / "build.json", {"key": key})
    return cell_dir / "scene", key


def _route_xy(scene: LocScene, scene_dir: Path) -> Any:
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.runs.tum import read_tum
    from marsscene.sim.route import author_route
    from marsscene.sim.world import load_world

    spec = scene.route
    if spec.file is not None:
        return read_tum(spec.file).xyz_m[:, :2]
    world = load_world(scene_dir)
    if spec.waypoints is not None:
        return author_route(list(spec.waypoints), world.heightfield, obstacles=world.obstacles,
                            max_slope_deg=spec.max_slope_deg).xy_m
    return auto_route(centred_on_asset(spec, scene_dir), world.heightfield,
                      world.obstacles).xy_m


def score(answer: tuple[float, float, float] | None, truth: dict[str, float]
          ) -> dict[str, Any]:
    """Position and heading error of an answer and the two success flags."""
    if answer is None:
        return {"status": "lost", "position_error_m": None, "heading_error_deg": None,
                "success_1m_2deg": False, "success_5m_5deg": False}
    pos = math.hypot(answer[0] - truth["x_m"], answer[1] - truth["y_m"])
    head = abs(math.degrees((answer[2] - truth["yaw_rad"] + math.pi) % (2 * math.pi) - math.pi))
    return {"status": "ok", "position_error_m": round(pos, 4), "heading_error_deg": round(head, 4),
            "success_1m_2deg": pos <= 1.0 and head <= 2.0,
            "success_5m_5deg": pos <= 5.0 and head <= 5.0}


def _method_row(method: LocMethod, qdir: Path, truth: dict[str, Any]) -> dict[str, Any]:
    key = digest({"method": dataclasses.asdict(method), "query": truth["key"]})
    path = qdir / "methods" / f"{method.name}.json"
    done = read_json(path)
    if done is not None and done.get("key") == key:
        return dict(done["row"])
    answer = qdir / "answers" / f"{method.name}.tum"
    answer.parent.mkdir(parents=True, exist_ok=True)
    answer.unlink(missing_ok=True)
    t0 = time.perf_counter()
    try:
        note = run_method(method, qdir / "query", answer)
        dt = time.perf_counter() - t0
        row = {**score(read_answer(answer), truth), "note": note}
    except Exception as err:  # a failing method is its row, never the cell's end
        dt = time.perf_counter() - t0
        row = {**score(None, truth), "status": "failed",
               "note": " ".join(f"{type(err).__name__}: {err}".split())[:300]}
    row = {"method": method.name, "kind": method.kind, "t_query_s": round(dt, 4), **row}
    write_json(path, {"key": key, "row": row})
    return row


def _query(spec: LocSpec, scene_dir: Path, omap: Any, route_xy: Any, s_m: float, prior: Any,
           k: int, tau: float, qdir: Path, base_key: str) -> dict[str, Any]:
    """The query's drive and folder (unless done with the same key); its truth."""
    import marsscene as ms
    from marsscene.benchmark.loc.query import write_query
    from marsscene.sim.route import Route

    first, camera = tau == spec.tau[0], spec.needs_camera
    key = digest({"base": base_key, "s_m": s_m, "prior": dataclasses.asdict(prior), "k": k,
                  "tau": tau, "first": first, "camera": camera, "spec": {f: spec.doc()[f] for f in (
                      "scans", "lidar_model", "lidar_rate_hz", "radius_m", "camera",
                      "sun_elevation_deg", "position_error_m", "heading_error_deg")}})
    done = read_json(qdir / "truth.json")
    if done is not None and done.get("key") == key:
        return done
    seg = segment_before(route_xy, s_m, SPEED_M_S * spec.drive_s + 3.0)
    with replacing_dir(qdir) as tmp:
        t0 = time.perf_counter()
        ms.drive(scene_dir, route=Route(seg), seconds=spec.drive_s,
                 config=spec.run_config(lidar=first, tau=tau, camera=camera),
                 out_dir=tmp / "run", seed=k)
        truth = write_query(tmp / "run", omap, tmp / "query", prior_error=prior,
                            radius_m=spec.radius_m,
                            position_error_max_m=float(spec.position_error_m[1]),
                            heading_error_max_deg=spec.heading_error_deg,
                            meta={"query": k, "scene": qdir.parent.parent.name, "tau": tau})
        doc = {**truth, "key": key, "s_m": s_m, "prior_distance_m": prior.distance_m,
               "prior_heading_deg": math.degrees(prior.dyaw_rad),
               "t_drive_s": round(time.perf_counter() - t0, 3)}
        write_json(tmp / "truth.json", doc)
    return doc


def run_loc_cell(cell: Cell, *, out_dir: str, spec: LocSpec) -> dict[str, Any]:
    """Build, drive the queries of and score one cell into ``out_dir/<cell_id>/``."""
    scene = next(s for s in spec.scenes if s.name == cell.params["scene"])
    tau = float(cell.params["tau"])
    cell_dir = Path(out_dir) / cell.cell_id
    cell_dir.mkdir(parents=True, exist_ok=True)
    row: dict[str, Any] = {"cell_id": cell.cell_id, "params": dict(cell.params),
                           "status": "ok", "error": "", "rows": []}
    t0 = time.perf_counter()
    try:
        from marsscene.orbital import read_orbital_map

        scene_dir, base_key = _scene_dir(scene, spec, cell_dir)
        row["t_build_s"] = round(time.perf_counter() - t0, 3)
        omap = read_orbital_map(scene_dir)
        route_xy = _route_xy(scene, scene_dir)
        rng = query_rng(spec.seed, scene.name)
        seg = route_xy
        import numpy as np

        length = float(np.linalg.norm(np.diff(seg, axis=0), axis=1).sum())
        s_all = query_arc_lengths(length, spec.queries, SPEED_M_S * spec.drive_s + 3.0, rng=rng)
        priors = draw_priors(spec.queries, spec.position_error_m, spec.heading_error_deg,
                             rng=rng)
        row["route_m"] = round(length, 2)
        for k, (s_m, prior) in enumerate(zip(s_all, priors, strict=True)):
            qdir = cell_dir / "queries" / f"{k:03d}"
            try:
                truth = _query(spec, scene_dir, omap, route_xy, float(s_m), prior, k, tau,
                               qdir, base_key)
            except Exception as err:
                msg = " ".join(f"{type(err).__name__}: {err}".split())[:300]
                log.warning("query %s/%d failed: %s", cell.cell_id, k, msg)
                row["rows"] += [{"query": k, "method": m.name, "kind": m.kind,
                                 "status": "failed", "note": msg}
                                for m in spec.methods_for(tau)]
                continue
            for m in spec.methods_for(tau):
                row["rows"].append({"query": k, "prior_distance_m": truth["prior_distance_m"],
                                    "prior_heading_deg": truth["prior_heading_deg"],
                                    **_method_row(m, qdir, truth)})
    except Exception as err:  # one failing cell never stops the benchmark
        row.update(status="failed", error=" ".join(f"{type(err).__name__}: {err}".split()))
        log.warning("cell %s failed: %s", cell.cell_id, row["error"])
    row["t_cell_s"] = round(time.perf_counter() - t0, 3)
    return row
