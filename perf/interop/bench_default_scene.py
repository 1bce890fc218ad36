"""The default scene as its users meet it: build, open, physics parse, validation, Newton.

Each step runs in a fresh process (``_measure.measure``) on one scene folder written by the
command a new user types, ``marsscene build --seed 7``:

* ``build``: the command's wall time, and the rock colliders' files on disk;
* ``open``: usd-core ``Stage.Open`` of ``scene.usda`` with every payload loaded, and with the
  physics payload ``/World/RockColliders`` left unloaded (load rules), with the prim counts;
* ``parse``: OpenUSD's physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, which Newton and
  Isaac Sim build on) over ``/World``: time and the collision shapes it reports by type;
* ``validator``: the Omniverse Asset Validator's default rules (``--validator``; minutes);
* ``newton``: Newton's own ``ModelBuilder.add_usd`` on the stage (not the project's Newton
  helper) and ``finalize`` on the CPU, with the number of shapes made (``--newton``; needs the
  ``newton`` extra; Warp compiles its CPU kernels on first use).

Run::

    python perf/run.py default_scene                         # build, open, parse
    python perf/run.py default_scene --validator --newton    # and the slow clients
    python perf/run.py default_scene --scene DIR             # an already built scene folder

Timings vary with the load of the shared 2-core machine: run it on a quiet machine.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from perf._measure import measure, parse_physics
from perf.suite import Param, optional

PARAMS = (Param("scene", optional(Path), "an already built scene folder (none: build one)",
                quick=None, full=None),
          Param("validator", bool, "the Omniverse Asset Validator (minutes)", quick=False,
                full=False),
          Param("newton", bool, "Newton's add_usd and finalize (extra newton)", quick=False,
                full=False))

_STATE: dict[str, Any] = {}
COLLIDERS = "/World/RockColliders"


def _open() -> dict[str, Any]:
    from pxr import Usd

    path = str(Path(_STATE["scene"]) / "scene.usda")
    t0 = time.perf_counter()
    stage = Usd.Stage.Open(path)
    full_s = time.perf_counter() - t0
    prims = sum(1 for _ in stage.Traverse())
    t0 = time.perf_counter()
    bare = Usd.Stage.Open(path, Usd.Stage.LoadNone)
    rules = Usd.StageLoadRules.LoadAll()
    rules.AddRule(COLLIDERS, Usd.StageLoadRules.NoneRule)
    bare.SetLoadRules(rules)
    bare_s = time.perf_counter() - t0
    return {"open_s": round(full_s, 3), "prims": prims,
            "open_without_colliders_s": round(bare_s, 3),
            "prims_without_colliders": sum(1 for _ in bare.Traverse())}


def _parse() -> dict[str, Any]:
    from pxr import Usd

    stage = Usd.Stage.Open(str(Path(_STATE["scene"]) / "scene.usda"))
    parse_s, shapes = parse_physics(stage)
    return {"parse_s": round(parse_s, 3), "parsed": shapes}


def _validate() -> dict[str, Any]:
    from omni.asset_validator import ValidationEngine

    t0 = time.perf_counter()
    issues = [str(i) for i in
              ValidationEngine().validate(str(Path(_STATE["scene"]) / "scene.usda")).issues()]
    return {"validator_s": round(time.perf_counter() - t0, 1), "issues": len(issues),
            "first": issues[:3]}


def _newton() -> dict[str, Any]:
    import newton
    import warp as wp
    from pxr import Usd

    stage = Usd.Stage.Open(str(Path(_STATE["scene"]) / "scene.usda"))
    builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
    t0 = time.perf_counter()
    builder.add_usd(stage)
    add_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = builder.finalize(device="cpu")
    wp.synchronize_device("cpu")
    fin_s = time.perf_counter() - t0
    keys = [str(k) for k in getattr(model, "shape_key", getattr(model, "shape_label", []))]
    rock_shapes = sum(1 for k in keys if k.startswith(COLLIDERS))
    return {"add_usd_s": round(add_s, 2), "finalize_s": round(fin_s, 2),
            "shapes": int(model.shape_count), "rock_shapes": rock_shapes}


def _build(folder: Path) -> dict[str, Any]:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "marsscene", "build", "--seed", "7", "--out",
                    str(folder)], check=True)
    build_s = time.perf_counter() - t0
    files = [p for p in (folder / "assets").rglob("rock_colliders*") if p.is_file()]
    files += list((folder / "assets" / "rock_colliders").glob("*.usdc"))
    size_mb = sum(p.stat().st_size for p in set(files)) / 1e6
    return {"build_cli_s": round(build_s, 2), "collider_files_mb": round(size_mb, 2)}


def _run(folder: Path, validator: bool, newton: bool) -> list[dict[str, Any]]:
    _STATE["scene"] = str(folder)
    steps = [("open", _open), ("parse", _parse)]
    if validator:
        steps.append(("validator", _validate))
    if newton:
        steps.append(("newton", _newton))
    figures = []
    for name, fn in steps:
        _, peak, res = measure(fn)
        print(f"{name}: {json.dumps(res)}, peak {peak / 1024:.2f} GB", flush=True)
        figures.append({"step": name, **res, "peak_gb": peak / 1024})
    return figures


def main(scene: Path | None, validator: bool, newton: bool) -> list[dict[str, Any]]:
    if scene is not None:
        return _run(scene, validator, newton)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "scene"
        built = _build(folder)
        print(f"build: {json.dumps(built)}", flush=True)
        return [{"step": "build", **built}, *_run(folder, validator, newton)]

