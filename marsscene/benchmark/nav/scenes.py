"""A navigation benchmark's scenes: built once, with their ground-truth and orbital planning
grids and their seeded pairs.

``OUT/scenes/<name>/`` holds ``scene/`` (the built scene; absent for a ``path`` scene),
``plan_gt.npz`` and ``plan_orbital.npz`` (:class:`~marsscene.benchmark.nav.grid.PlanGrid`) and
``scene.json`` (its key, paths, timings and the pairs), written last: a scene whose
``scene.json`` holds the current key is reused by a resumed run.
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.benchmark.nav.pairs import draw_pairs, pairs_rng
from marsscene.benchmark.nav.spec import NavSceneSpec, NavSpec

__all__ = ["SCENE_FILE", "orbital_traversability", "prepare_scene", "scene_folder"]

SCENE_FILE = "scene.json"


def scene_folder(root: Path, name: str) -> Path:
    return root / "scenes" / name


def _key(scene: NavSceneSpec, spec: NavSpec) -> str:
    doc = {"scene": scene.path or scene.base_config(), "seed": spec.seed, "pairs": spec.pairs,
           "distance_m": list(spec.distance_m), "version": 1}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()


def orbital_traversability(omap: Any) -> Any:
    """The traversability of an :class:`~marsscene.orbital.OrbitalMap`'s DTM alone (no
    rocks, no soil; cells without data are hazards)."""
    from marsscene.terrain.heightfield import Heightfield
    from marsscene.traversability import compute

    z = np.asarray(omap.dem_m, dtype=np.float32)
    holes = ~np.isfinite(z)
    if holes.any():
        z = np.where(holes, np.float32(np.nanmean(z)), z)
    t = compute(Heightfield(z, float(omap.cell_m), tuple(omap.origin_xy_m)))
    if holes.any():
        from dataclasses import replace

        t = replace(t, hazard=t.hazard | holes, cost=np.where(holes, 1.0, t.cost))
    return t


def _orbital_of_folder(scene_dir: Path) -> Any:
    """A built scene's orbital map: ``orbital/`` when it was built with ``--orbital-map``,
    else its terrain through the orbital model without rocks."""
    from marsscene.orbital import procedural_orbital_map, read_orbital_map
    from marsscene.sim.world import load_world

    if (scene_dir / "orbital").is_dir():
        return read_orbital_map(scene_dir)
    return procedural_orbital_map(load_world(scene_dir).heightfield, None, 0, image=False)


def prepare_scene(scene: NavSceneSpec, spec: NavSpec, root: Path) -> dict[str, Any]:
    """Build (or reuse) one scene with its grids and pairs; returns its ``scene.json``."""
    from marsscene import SceneConfig, build_scene, write_scene
    from marsscene.orbital import orbital_map
    from marsscene.traversability.scene import read_scene_inputs, scene_traversability

    folder = scene_folder(root, scene.name)
    key = _key(scene, spec)
    meta_path = folder / SCENE_FILE
    if meta_path.is_file():
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
        if meta.get("key") == key:
            return dict(meta)
    folder.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    if scene.path is not None:
        scene_dir = Path(scene.path)
        omap = _orbital_of_folder(scene_dir)
    else:
        cfg = SceneConfig.from_dict({**scene.base_config(), "seed": spec.seed})
        built = build_scene(cfg, seed=spec.seed)
        scene_dir = folder / "scene"
        write_scene(built, scene_dir, formats=("mjcf",))
        omap = orbital_map(built)
    timings["build_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    gt = PlanGrid.of(scene_traversability(read_scene_inputs(scene_dir)))
    timings["traversability_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    orbital = PlanGrid.of(orbital_traversability(omap))
    timings["orbital_s"] = time.perf_counter() - t0
    gt.save(folder / "plan_gt.npz")
    orbital.save(folder / "plan_orbital.npz")
    t0 = time.perf_counter()
    pairs = draw_pairs(gt, spec.pairs, spec.distance_m, rng=pairs_rng(spec.seed, scene.name),
                       scene=scene.name)
    timings["pairs_s"] = time.perf_counter() - t0
    meta = {"key": key, "name": scene.name, "scene_dir": str(scene_dir),
            "hazard_fraction_gt": round(float(gt.hazard.mean()), 4),
            "hazard_fraction_orbital": round(float(orbital.hazard.mean()), 4),
            "timings_s": {k: round(v, 3) for k, v in timings.items()}, "pairs": pairs}
    write_atomic(meta_path, json.dumps(meta, indent=1, sort_keys=True) + "\n")
    return meta


def load_grids(root: Path, name: str) -> dict[str, PlanGrid]:
    folder = scene_folder(root, name)
    return {"gt": PlanGrid.load(folder / "plan_gt.npz"),
            "orbital": PlanGrid.load(folder / "plan_orbital.npz")}
