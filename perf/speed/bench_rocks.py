"""Rock benchmark: 1 km x 1 km, k = 0.05, D in [0.1, 3] m (~1e6 rocks) on a 0.25 m terrain.

Steps timed: prototypes, sample + place (``place_rocks``), author the USD PointInstancer and
serialise it as ``.usdc``, author and serialise the rock colliders (``assets/rock_colliders.usdc``
with the default ``[export]`` thresholds: obstacle rocks as instance prims, the other colliding
rocks merged per tile; issue 42), the catalogue as ``rocks.csv`` and as ``rocks.parquet`` (each
formatted and written to a file, median of 3; the Parquet one when pyarrow is installed).
Target: < 10 s total, < 2 GB peak RSS.
Run: ``python perf/run.py rocks``; ``python perf/run.py rocks --collider-min-m 0`` makes every
rock a collider (``[export] rock_collider_min_diameter_m = 0``).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from marsscene.export.config import ExportConfig
from perf.suite import Param, optional

PARAMS = (Param("size_m", float, "side of the square terrain (m)", quick=100.0, full=1000.0),
          Param("collider_min_m", optional(float), "smallest collider diameter (m; none: the "
                "[export] default)", quick=None, full=None))
POST_M = 0.25
_SET = {"size_m": 1000.0, "collider_min_m": ExportConfig().rock_collider_min_diameter_m}


def _terrain() -> Any:
    from marsscene.terrain.heightfield import Heightfield

    n = int(_SET["size_m"] / POST_M) + 1
    x = np.linspace(0.0, _SET["size_m"], n, dtype=np.float32)
    rng = np.random.default_rng(0)
    z = (3.0 * np.sin(x / 57.0)[None, :] * np.cos(x / 83.0)[:, None]
         + 0.02 * rng.standard_normal((n, n), dtype=np.float32))
    return Heightfield.centered(z.astype(np.float32), POST_M)


def _run() -> dict[str, float]:
    from pxr import Sdf

    from marsscene.craters.table import CraterTable
    from marsscene.export.usd.rock_colliders import author_collider_layer
    from marsscene.export.usd.rocks import author_instancer
    from marsscene.export.usd.stage import crate_bytes, create_asset_stage
    from marsscene.rocks import RockConfig, make_prototypes, place_rocks
    from marsscene.seeding import stage_rng

    hf = _terrain()
    cfg = RockConfig(k=0.05, d_min_m=0.1, d_max_m=3.0, placement="uniform")
    out: dict[str, float] = {}
    t0 = time.perf_counter()
    protos = make_prototypes(cfg, rng=stage_rng(7, "rock_shapes"))
    t1 = time.perf_counter()
    rocks = place_rocks(hf, CraterTable.empty(), cfg, rng=stage_rng(7, "rocks"))
    t2 = time.perf_counter()
    stage = create_asset_stage("Rocks")
    author_instancer(stage, Sdf.Path("/Rocks"), rocks, protos)
    blob = crate_bytes(stage)
    t3 = time.perf_counter()
    export = ExportConfig(rock_collider_min_diameter_m=_SET["collider_min_m"])
    keep = np.flatnonzero(rocks.diameter_m >= export.rock_collider_min_diameter_m)
    layer = author_collider_layer(rocks.take(keep), keep, protos,
                                  instance_min_diameter_m=export.rock_instance_min_diameter_m)
    with tempfile.TemporaryDirectory() as tmp:
        layer.Export(str(Path(tmp) / "rock_colliders.usdc"))
        colliders_mb = (Path(tmp) / "rock_colliders.usdc").stat().st_size / 2**20
    t4 = time.perf_counter()
    big = int((rocks.diameter_m >= export.rock_instance_min_diameter_m).sum())
    scene = SimpleNamespace(rocks=rocks, config=SimpleNamespace(rocks=cfg), outer=None,
                            provenance=SimpleNamespace(extra={}))  # a one-grid scene
    out.update(rocks=len(rocks), prototypes_s=t1 - t0, place_s=t2 - t1, usd_s=t3 - t2,
               usdc_mb=len(blob) / 2**20, colliders_s=t4 - t3, colliders_mb=colliders_mb,
               collider_rocks=len(keep), collider_prims=big)
    out.update(_catalogues(scene))
    return out


def _catalogues(scene: Any) -> dict[str, float]:
    """Median write time (s) and size (MB) of rocks.csv and rocks.parquet."""
    import statistics

    from marsscene.export.catalog_rocks import write_rock_catalog

    out: dict[str, float] = {}
    kinds = ["csv"]
    try:
        import pyarrow  # noqa: F401

        kinds.append("parquet")
    except ImportError:
        pass
    with tempfile.TemporaryDirectory() as tmp:
        for kind in kinds:
            scene.config.export = SimpleNamespace(rock_catalogue=kind)
            secs = []
            for _ in range(3):
                t0 = time.perf_counter()
                (path,) = write_rock_catalog(scene, Path(tmp))
                secs.append(time.perf_counter() - t0)
            out[f"{kind}_s"] = statistics.median(secs)
            out[f"{kind}_mb"] = path.stat().st_size / 2**20
    return out


def main(size_m: float, collider_min_m: float | None) -> dict[str, float]:
    from perf._measure import measure

    _SET["size_m"] = size_m
    if collider_min_m is not None:
        _SET["collider_min_m"] = collider_min_m

    wall, peak_mb, r = measure(_run)
    n = r["rocks"]
    print(f"terrain {size_m:g} m x {size_m:g} m at {POST_M} m ({int(size_m / POST_M) + 1}^2 "
          f"posts); k = 0.05, D in [0.1, 3] m")
    print(f"rocks placed          : {n:,.0f}")
    for step in ("prototypes", "place", "usd", "colliders", "csv", "parquet"):
        if f"{step}_s" not in r:
            continue
        secs = r[f"{step}_s"]
        rate = f"{n / secs:,.0f} rocks/s" if step != "prototypes" else ""
        print(f"{step:<22}: {secs:6.2f} s  {rate}")
    rock_s = r["prototypes_s"] + r["place_s"] + r["usd_s"] + r["colliders_s"]
    print(f"sample+place+USD      : {rock_s:6.2f} s, colliders included (target < 10 s)")
    print(f"colliders             : {r['collider_rocks']:,.0f} rocks (D >= the collider "
          f"minimum), {r['collider_prims']:,.0f} of them instance prims, the rest merged; "
          f"rock_colliders.usdc {r['colliders_mb']:.1f} MB")
    sizes = f"rocks.csv {r['csv_mb']:.1f} MB"
    if "parquet_mb" in r:
        sizes += f"; rocks.parquet {r['parquet_mb']:.1f} MB"
    print(f"rocks.usdc            : {r['usdc_mb']:.1f} MB; {sizes}")
    print(f"wall incl. terrain    : {wall:6.2f} s; peak RSS {peak_mb:,.0f} MB (target < 2048)")
    return {**r, "sample_place_usd_s": rock_s, "wall_s": wall, "peak_rss_mb": peak_mb}

