"""Rock colliders for every USD physics loader: native instances (chosen) vs merged meshes.

OpenUSD's physics parser (``UsdPhysics.LoadUsdPhysicsFromRange``, which Newton uses) skips
``PointInstancer`` subtrees, so the rocks' collision is authored apart from the render
instancer. Two ways were measured (issue 34):

* **A, instances** (what ``marsscene`` writes): one ``instanceable`` prim per rock referencing
  a collider prototype (``marsscene.export.usd.rock_colliders``).
* **B, merged meshes**: per terrain tile, one static triangle mesh (approximation ``none``)
  holding every rock's convex hull, transformed to the world (vectorised numpy, here only).

For each: authoring + export time of the collider layers, their size on disk, usd-core
``Stage.Open`` time of the whole scene (payloads loaded) and of a traversal, the physics
parser's time and collider count, and the Omniverse Asset Validator's issues
(``omni_asset_validate``'s engine, default rules; skipped when not installed or with
``--no-validator``). Run::

    python perf/bench_rock_colliders.py                  # the default scene (seed 7)
    python perf/bench_rock_colliders.py main-crater      # the 3.6 km preset

Each measurement runs in a fresh process (``_measure.measure``). Timings vary with the load
of the shared 2-core machine: run it on a quiet machine.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _measure import measure

_STATE: dict[str, Any] = {}


def _merged_layer(rocks: Any, protos: tuple[Any, ...], bounds: list[Any]) -> Any:
    """Option B: one guide mesh per tile bound ``(x0, y0, x1, y1)`` with every rock's hull."""
    import numpy as np
    from pxr import Sdf, UsdGeom, UsdPhysics, Vt

    from marsscene.export.usd.physics import (
        ROCK_PHYSICS,
        author_physics_material,
        bind_physics_material,
    )
    from marsscene.export.usd.stage import create_asset_stage
    from marsscene.transforms import quat_to_matrix

    stage = create_asset_stage("RockColliders")
    UsdGeom.Scope.Define(stage, "/RockColliders/Looks")
    physics = author_physics_material(stage, Sdf.Path("/RockColliders/Looks"), ROCK_PHYSICS)
    xy = rocks.position_xyz_m[:, :2]
    rot = quat_to_matrix(rocks.orientation_wxyz)
    tile = np.full(len(rocks), -1)
    for k, (x0, y0, x1, y1) in enumerate(bounds):  # the first bound holding a rock takes it
        inside = (xy[:, 0] >= x0) & (xy[:, 0] < x1) & (xy[:, 1] >= y0) & (xy[:, 1] < y1)
        tile[inside & (tile < 0)] = k
    assert (tile >= 0).all()
    for k in range(len(bounds)):
        sel = np.flatnonzero(tile == k)
        pts, nrm, faces, base = [], [], [], 0
        for p, proto in enumerate(protos):  # a handful of prototypes
            idx = sel[rocks.prototype[sel] == p]
            for part in proto.collision:
                v = np.asarray(part.vertices)[None] * rocks.scale_xyz_m[idx, None, :]
                w = np.einsum("nij,nvj->nvi", rot[idx], v) + rocks.position_xyz_m[idx, None]
                n = np.einsum("nij,vj->nvi", rot[idx], np.asarray(part.vertex_normals))
                f = np.asarray(part.faces)[None] + (base + len(part.vertices)
                                                     * np.arange(len(idx)))[:, None, None]
                pts.append(w.reshape(-1, 3))
                nrm.append(n.reshape(-1, 3))
                faces.append(f.reshape(-1))
                base += len(part.vertices) * len(idx)
        if base == 0:
            continue
        mesh = UsdGeom.Mesh.Define(stage, Sdf.Path(f"/RockColliders/tile_{k}"))
        p32 = np.concatenate(pts).astype(np.float32)
        fv = np.concatenate(faces).astype(np.int32)
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(p32))
        mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(np.concatenate(nrm).astype(np.float32)))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(fv))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(fv) // 3, 3, np.int32)))
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        mesh.CreateExtentAttr(Vt.Vec3fArray.FromNumpy(np.stack([p32.min(0), p32.max(0)])))
        mesh.CreatePurposeAttr(UsdGeom.Tokens.guide)
        UsdPhysics.CollisionAPI.Apply(mesh.GetPrim())
        UsdPhysics.MeshCollisionAPI.Apply(mesh.GetPrim()).CreateApproximationAttr(
            UsdPhysics.Tokens.none)
        bind_physics_material(mesh.GetPrim(), physics)
    return stage


def _tile_bounds(scene: Any) -> list[Any]:
    from marsscene.terrain.mesh import tile_ranges

    hf = scene.heightfield
    xs, ys = hf.grid_xy()
    n = scene.config.export.max_tile_posts
    out = []
    for r0, r1 in tile_ranges(len(ys), n):
        for c0, c1 in tile_ranges(len(xs), n):
            x1 = xs[c1 - 1] + (1.0 if c1 == len(xs) else 0.0)  # the last tile keeps its edge
            y1 = ys[r1 - 1] + (1.0 if r1 == len(ys) else 0.0)
            out.append((xs[c0], ys[r0], x1, y1))
    return out


def _write() -> dict[str, Any]:
    """Build and write the scene (option A, the library), then B's layers beside it."""
    import numpy as np

    import marsscene as ms
    from marsscene.export.usd.stage import root_layer

    out = Path(_STATE["dir"])
    mapping: dict[str, Any] = {"export": {"formats": ["usd"], "usd_format": "usdc"}}
    if _STATE["preset"]:
        mapping["preset"] = _STATE["preset"]
    scene = ms.build_scene(ms.SceneConfig.from_dict(mapping), seed=7)
    t0 = time.perf_counter()
    ms.write_scene(scene, out / "A")
    write_a = time.perf_counter() - t0
    from marsscene.export.usd.rock_colliders import author_collider_layer

    t0 = time.perf_counter()  # A's collider layers alone (same work as inside write_scene)
    layer = author_collider_layer(scene.rocks, np.arange(len(scene.rocks)), scene.rock_prototypes)
    layer.Export(str(out / "a_alone.usdc"))
    alone_a = time.perf_counter() - t0
    bounds = _tile_bounds(scene)  # B: merged per (focus) terrain tile, + one for outer rocks
    if scene.outer is not None:
        x0, y0, x1, y1 = scene.outer.heightfield.bounds_xy_m
        bounds.append((x0, y0, x1 + 1, y1 + 1))  # the rest: rocks outside the focus tiles
    t0 = time.perf_counter()
    merged = _merged_layer(scene.rocks, tuple(scene.rock_prototypes), bounds)
    root_layer(merged).Export(str(out / "b_colliders.usdc"))
    alone_b = time.perf_counter() - t0
    return {"rocks": len(scene.rocks), "write_scene_A_s": round(write_a, 2),
            "author_export_A_s": round(alone_a, 2), "author_export_B_s": round(alone_b, 2)}


def _variant_b(out: Path) -> Path:
    """scene_B.usdc: the A scene with /World/RockColliders replaced by B's merged layer."""
    from pxr import Sdf

    layer = Sdf.Layer.FindOrOpen(str(out / "A" / "scene.usdc"))
    spec = layer.GetPrimAtPath("/World/RockColliders")
    for name in list(spec.nameChildren.keys()):  # level-of-detail scenes: a group of payloads
        del spec.nameChildren[name]
    spec.payloadList.ClearEdits()
    spec.payloadList.Prepend(Sdf.Payload("./b_colliders.usdc"))
    spec.SetInfo("kind", "component")
    target = out / "A" / "scene_B.usdc"
    layer.Export(str(target))
    (out / "A" / "b_colliders.usdc").write_bytes((out / "b_colliders.usdc").read_bytes())
    return target


def _open() -> dict[str, Any]:
    from pxr import Usd, UsdPhysics

    path = _STATE["open"]
    t0 = time.perf_counter()
    stage = Usd.Stage.Open(path)
    t_open = time.perf_counter() - t0
    n = sum(1 for _ in stage.Traverse())
    t_trav = time.perf_counter() - t0 - t_open
    load = getattr(UsdPhysics, "UsdPhysicsLoadStageFromPrimRange", None) or \
        UsdPhysics.LoadUsdPhysicsFromRange
    t0 = time.perf_counter()
    parsed = load(stage, ["/World"])
    t_parse = time.perf_counter() - t0
    shapes = {str(k).split(".")[-1]: len(v[0]) for k, v in parsed.items()}
    return {"open_s": round(t_open, 2), "traverse_s": round(t_trav, 2), "prims": n,
            "parse_s": round(t_parse, 2), "parsed": shapes}


def _validate() -> dict[str, Any]:
    from omni.asset_validator import ValidationEngine

    t0 = time.perf_counter()
    issues = [str(i) for i in ValidationEngine().validate(_STATE["open"]).issues()]
    return {"validator_s": round(time.perf_counter() - t0, 1), "issues": len(issues),
            "first": issues[:3]}


def main(argv: list[str] | None = None) -> None:
    args = list(argv or [])
    validator = "--no-validator" not in args
    args = [a for a in args if a != "--no-validator"]
    _STATE["preset"] = args[0] if args else ""
    with tempfile.TemporaryDirectory() as tmp:
        _STATE["dir"] = tmp
        _, peak, info = measure(_write)
        print(f"scene {_STATE['preset'] or 'default'}: {json.dumps(info)}, "
              f"peak {peak / 1024:.2f} GB", flush=True)
        out = Path(tmp)
        a_files = [p for p in (out / "A").rglob("rock_colliders*") if p.is_file()]
        a_files += list((out / "A" / "assets" / "rock_colliders").glob("*.usdc"))
        size_a = sum(p.stat().st_size for p in set(a_files)) / 1e6
        size_b = (out / "b_colliders.usdc").stat().st_size / 1e6
        scene_b = _variant_b(out)
        print(f"collider layers on disk: A {size_a:.1f} MB, B {size_b:.1f} MB", flush=True)
        for name, path in (("A instances", out / "A" / "scene.usdc"), ("B merged", scene_b)):
            _STATE["open"] = str(path)
            _, peak, res = measure(_open)
            print(f"{name}: {json.dumps(res)}, peak {peak / 1024:.2f} GB", flush=True)
            if validator:
                try:
                    import omni.asset_validator  # noqa: F401
                except ImportError:
                    print("  (omniverse-asset-validator not installed)")
                    continue
                _, _, res = measure(_validate)
                print(f"  validator: {json.dumps(res)}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
