"""Rock collider layouts, all written by the library through ``[export]`` settings (issue 42).

OpenUSD's physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, which Newton uses) skips
``PointInstancer`` subtrees, so the rocks' collision is authored apart from the render
instancer, under ``/World/RockColliders``. Three layouts of the same colliders (every rock at
least ``rock_collider_min_diameter_m`` wide):

* **tiers** (the default): a native instance prim per obstacle rock (D >= 0.5 m), the other
  colliding rocks merged into one static mesh per 64 m tile;
* **prims**: ``rock_instance_min_diameter_m = 0``, one instance prim per colliding rock;
* **merged**: ``rock_instance_min_diameter_m = 1e4``, every colliding rock in the tile meshes.

For each: ``write_scene`` time (USD only), the collider files on disk, ``Stage.Open`` of the
whole scene (payloads loaded), the physics parser's time and collider count, and the Omniverse
Asset Validator's issues and time (``omni_asset_validate``'s engine, default rules; skipped
when not installed or with ``--no-validator``). Run::

    python perf/run.py rock_colliders                      # the default scene (seed 7)
    python perf/run.py rock_colliders --preset main-crater # the 3.6 km preset
    python perf/run.py rock_colliders --all-rocks          # colliders for every rock (D >= 0)

Each measurement runs in a fresh process (``_measure.measure``). Timings vary with the load
of the shared 2-core machine: run it on a quiet machine.
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path
from typing import Any

from perf._measure import measure, parse_physics
from perf.suite import Param, names

PARAMS = (Param("preset", str, "a preset to build (empty: the default scene)", quick="",
                full=""),
          Param("layouts", names, "collider layouts: tiers, prims, merged", quick=("tiers",),
                full=("tiers", "prims", "merged")),
          Param("validator", bool, "the Omniverse Asset Validator's rules (when installed)",
                quick=False, full=True),
          Param("all_rocks", bool, "colliders for every rock (D >= 0)", quick=False, full=False))

LAYOUTS = {"tiers": None, "prims": 0.0, "merged": 1e4}
_STATE: dict[str, Any] = {}


def _write() -> dict[str, Any]:
    import marsscene as ms

    export: dict[str, Any] = {"formats": ["usd"]}
    if _STATE["instance_min"] is not None:
        export["rock_instance_min_diameter_m"] = _STATE["instance_min"]
    if _STATE["all_rocks"]:
        export["rock_collider_min_diameter_m"] = 0.0
    mapping: dict[str, Any] = {"export": export}
    if _STATE["preset"]:
        mapping["preset"] = _STATE["preset"]
    scene = ms.build_scene(ms.SceneConfig.from_dict(mapping), seed=7)
    out = Path(_STATE["out"])
    t0 = time.perf_counter()
    ms.write_scene(scene, out)
    write_s = time.perf_counter() - t0
    files = list(out.glob("assets/rock_colliders*.usdc"))
    files += list(out.glob("assets/rock_colliders/*.usdc"))
    return {"rocks": len(scene.rocks or ()), "write_scene_s": round(write_s, 2),
            "collider_mb": round(sum(p.stat().st_size for p in files) / 1e6, 1)}


def _open() -> dict[str, Any]:
    from pxr import Usd

    t0 = time.perf_counter()
    stage = Usd.Stage.Open(str(Path(_STATE["out"]) / "scene.usda"))
    t_open = time.perf_counter() - t0
    prims = sum(1 for _ in stage.Traverse())
    t_parse, shapes = parse_physics(stage)
    return {"open_s": round(t_open, 3), "prims": prims, "parse_s": round(t_parse, 3),
            "mesh_colliders": shapes.get("MeshShape", 0)}


def _validate() -> dict[str, Any]:
    from omni.asset_validator import ValidationEngine

    t0 = time.perf_counter()
    path = str(Path(_STATE["out"]) / "scene.usda")
    issues = [str(i) for i in ValidationEngine().validate(path).issues()]
    return {"validator_s": round(time.perf_counter() - t0, 1), "issues": len(issues),
            "first": issues[:3]}


def main(preset: str, layouts: tuple[str, ...], validator: bool,
         all_rocks: bool) -> list[dict[str, Any]]:
    _STATE.update(all_rocks=all_rocks, preset=preset)
    out = []
    if validator:
        try:
            import omni.asset_validator  # noqa: F401
        except ImportError:
            print("(omniverse-asset-validator not installed: no validator figures)")
            validator = False
    with tempfile.TemporaryDirectory() as tmp:
        for name in layouts:
            instance_min = LAYOUTS[name]
            _STATE["instance_min"], _STATE["out"] = instance_min, str(Path(tmp) / name)
            figures: dict[str, Any] = {}
            for step in (_write, _open) + ((_validate,) if validator else ()):
                _, peak, res = measure(step)
                figures.update(res, **{f"{step.__name__[1:]}_peak_gb": round(peak / 1024, 2)})
            print(f"{_STATE['preset'] or 'default'} {name}: {json.dumps(figures)}", flush=True)
            out.append({"layout": name, **figures})
    return out

