"""One navigation episode (scene x pair x method): plan, drive with :func:`marsscene.drive`,
score. Errors never escape :func:`run_episode`: a method that fails is a ``failed`` row.

The row is written to ``OUT/episodes/<cell_id>.json``; a resumed run returns an ``ok`` row of
the same key as it stands (``skipped``) and runs failed ones again.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.nav.methods import plan_method
from marsscene.benchmark.nav.metrics import episode_scores
from marsscene.benchmark.nav.scenes import SCENE_FILE, load_grids, scene_folder
from marsscene.benchmark.nav.spec import NavSpec
from marsscene.rover.config import V_MAX_M_S
from marsscene.sweep.grid import Cell

__all__ = ["episode_key", "run_episode", "time_limit_s"]

#: Half width (m) of the rock corridor around the route (only rocks within it are simulated)
#: of methods that steer themselves, beyond half the pair's distance.
FREE_CORRIDOR_M = 15.0


def time_limit_s(shortest_m: float, factor: float) -> float:
    """An episode's sim-time limit: ``factor`` x the shortest path at full speed, + 60 s."""
    return factor * shortest_m / V_MAX_M_S + 60.0


def episode_key(spec: NavSpec, scene_key: str, params: dict[str, Any]) -> str:
    method = next(m for m in spec.methods if m.name == params["method"])
    doc = {"scene": scene_key, "params": params, "method": repr(method),
           "time_factor": spec.time_factor, "version": 1}
    if method.policy is not None:  # a retrained policy of the same name runs again
        doc["policy_sha256"] = hashlib.sha256(Path(method.policy).read_bytes()).hexdigest()
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]


def _recording(controller: Any, made: list[Any]) -> Any:
    """An :class:`OnStart` whose made controller is kept in ``made`` (its planning time)."""
    from marsscene.sim.control import OnStart

    if not isinstance(controller, OnStart):
        return controller
    make = controller.make

    def recorded(sim: Any) -> Any:
        c = make(sim)
        made.append(c)
        return c

    return OnStart(recorded, listen=controller.listen)


def _drive(spec: NavSpec, scene_dir: str, pair: dict[str, Any], method: Any,
           grids: dict[str, Any]) -> dict[str, Any]:
    import marsscene as ms
    from marsscene.sim.mission import DriveOptions

    start = np.asarray(pair["start_xy_m"], dtype=np.float64)
    goal = np.asarray(pair["goal_xy_m"], dtype=np.float64)
    plan = plan_method(method, start, goal, grids)
    made: list[Any] = []
    steered = plan.controller is not None
    corridor = FREE_CORRIDOR_M + 0.5 * float(pair["distance_m"]) if steered else 15.0
    limit = time_limit_s(float(pair["shortest_m"]), spec.time_factor)
    t0 = time.perf_counter()
    run = ms.drive(scene_dir, route=plan.route, controller=_recording(plan.controller, made),
                   seconds=limit, config=plan.config, options=DriveOptions(corridor_m=corridor),
                   seed=spec.seed)
    wall = time.perf_counter() - t0
    calls, plan_s = plan.plan_calls, plan.plan_s
    if made and hasattr(made[0], "calls"):
        calls, plan_s = int(made[0].calls), float(made[0].seconds)
    elif made and hasattr(made[0], "inner") and hasattr(made[0].inner, "calls"):
        calls, plan_s = int(made[0].inner.calls), float(getattr(made[0].inner, "seconds", 0.0))
    gt = run.gt
    scores = episode_scores(gt.timestamps_s, gt.xyz_m, gt.quat_xyzw,
                            odom_length_m=run.odom.path_length_m(), goal_xy_m=goal,
                            shortest_m=float(pair["shortest_m"]), grid=grids["gt"])
    step = max(1, len(gt.xyz_m) // 2000)  # the path for the plots, at most ~2000 points
    return {**scores, "plan_calls": calls,
            "plan_s": round(plan_s / calls, 6) if calls else None,
            "time_limit_s": round(limit, 1), "wall_s": round(wall, 2),
            "route_m": round(plan.route.length_m, 3),
            "path_xy_m": np.round(gt.xyz_m[::step, :2], 2).tolist()}


def run_episode(cell: Cell, *, root: str, spec: NavSpec) -> dict[str, Any]:
    """Run (or reuse) the episode of ``cell`` (params ``scene``, ``pair``, ``method``)."""
    p = dict(cell.params)
    out = Path(root) / "episodes" / f"{cell.cell_id}.json"
    row: dict[str, Any] = {"cell_id": cell.cell_id, "params": p, **p, "status": "failed",
                           "error": ""}
    try:
        meta = json.loads((scene_folder(Path(root), p["scene"]) / SCENE_FILE).read_text(
            encoding="utf-8"))
        key = episode_key(spec, meta["key"], p)
        row["key"] = key
        if out.is_file():
            old = json.loads(out.read_text(encoding="utf-8"))
            if old.get("key") == key and old.get("status") == "ok":
                return {**old, "status": "ok", "skipped": True}
        pair = meta["pairs"][int(p["pair"])]
        method = next(m for m in spec.methods if m.name == p["method"])
        row.update(kind=method.kind, distance_m=pair["distance_m"],
                   shortest_m=pair["shortest_m"])
        row.update(_drive(spec, meta["scene_dir"], pair, method, load_grids(Path(root),
                                                                            p["scene"])))
        row["status"] = "ok"
    except Exception as err:  # a method that crashes: its row fails, the others go on
        row["error"] = " ".join(f"{type(err).__name__}: {err}".split())
    write_atomic(out, json.dumps(row, sort_keys=True) + "\n")
    return row
