"""A built scene's traversability: read the scene folder as the simulator does (the MJCF
terrain, the rock catalogue, the soil map, the manifest's frame) and write
``SCENE_DIR/traversability/``: ``traversability.tif`` (one band per layer, georeferenced in the
scene frame's CRS), ``preview.png`` (hazards in red over a hillshade) and ``summary.json``
(grid, limits, fractions). Same inputs, same bytes.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig
from marsscene.soil.map import SoilMap, read_soil_map
from marsscene.terrain.heightfield import Heightfield
from marsscene.traversability.compute import (
    HAZARD_BITS,
    LAYERS,
    Traversability,
    compute,
    grid_stride,
)
from marsscene.traversability.config import TraversabilityConfig
from marsscene.traversability.preview import preview_rgb

__all__ = ["TRAVERSABILITY_DIR", "SceneInputs", "inputs_of_scene", "read_scene_inputs",
           "scene_traversability", "write_traversability"]

#: The scene folder's traversability files.
TRAVERSABILITY_DIR = "traversability"


@dataclass(frozen=True, eq=False)
class SceneInputs:
    """What a scene folder knows exactly: terrain, rocks (centre, diameter, exposed height),
    soil (None: rigid) and its frame's CRS and projected origin (None: a procedural scene)."""

    heightfield: Heightfield
    rocks_xy_m: NDArray[np.float64]
    rocks_diameter_m: NDArray[np.float64]
    rocks_height_m: NDArray[np.float64]
    soil: SoilMap | None
    crs_wkt: str | None
    origin_projected_xy_m: tuple[float, float] | None


def _rock_columns(scene_dir: Path) -> dict[str, NDArray[np.float64]]:
    """x, y, diameter and exposed height of every catalogue rock (``rocks.csv``, else
    ``rocks.parquet``; none without a catalogue)."""
    from marsscene.sensors.camera_rocks import read_rock_columns

    names = ("x_m", "y_m", "diameter_m", "height_m")
    col = read_rock_columns(scene_dir)
    return {k: col[k] if col is not None else np.zeros(0) for k in names}


def _frame(scene_dir: Path) -> tuple[str | None, tuple[float, float] | None]:
    path = scene_dir / "manifest.json"
    if not path.is_file():
        return None, None
    try:
        frame = json.loads(path.read_text(encoding="utf-8")).get("frame", {})
    except ValueError as err:
        raise ConfigError(f"{path}: not readable JSON ({err})") from None
    origin = frame.get("origin_projected_xy_m")
    if not frame.get("crs_wkt") or origin is None:
        return None, None
    return str(frame["crs_wkt"]), (float(origin[0]), float(origin[1]))


def read_scene_inputs(scene_dir: str | Path) -> SceneInputs:
    """The terrain (``mjcf/scene.xml``'s heightfield, as :func:`marsscene.sim.world.load_world`
    compiles it), rocks, soil and frame of a built scene."""
    from marsscene.sim.world import load_world

    root = Path(scene_dir)
    hf = load_world(root).heightfield
    rocks = _rock_columns(root)
    crs, origin = _frame(root)
    return SceneInputs(hf, np.column_stack([rocks["x_m"], rocks["y_m"]]), rocks["diameter_m"],
                       rocks["height_m"], read_soil_map(root), crs, origin)


def inputs_of_scene(scene: Any) -> SceneInputs:
    """The same inputs from a :class:`~marsscene.scene.Scene` in memory (before or without
    writing it): its heightfield, rock table, soil map and frame."""
    rocks, frame = scene.rocks, scene.provenance.frame
    xy = rocks.position_xyz_m[:, :2] if rocks is not None else np.zeros((0, 2))
    d = rocks.diameter_m if rocks is not None else np.zeros(0)
    h = rocks.height_m if rocks is not None else np.zeros(0)
    georef = bool(frame.crs_wkt) and frame.origin_projected_xy_m is not None
    return SceneInputs(scene.heightfield, np.asarray(xy), np.asarray(d), np.asarray(h),
                       scene.soil, frame.crs_wkt if georef else None,
                       tuple(frame.origin_projected_xy_m) if georef else None)


def scene_traversability(inputs: SceneInputs, *, rover: RoverConfig | None = None,
                         config: TraversabilityConfig | None = None) -> Traversability:
    """:func:`~marsscene.traversability.compute` on a scene's inputs."""
    return compute(inputs.heightfield, rocks_xy_m=inputs.rocks_xy_m,
                   rocks_diameter_m=inputs.rocks_diameter_m, rocks_height_m=inputs.rocks_height_m,
                   soil=inputs.soil, rover=rover, config=config)


def _r(v: Any) -> float:
    return round(float(v), 6)


def summary(t: Traversability, *, georeferenced: bool) -> dict[str, Any]:
    """The JSON summary: grid, rover footprint, limits and the share of each hazard."""
    rows, cols = t.shape
    shares = {name: _r(np.mean((t.hazard_bits & bit) > 0)) for name, bit in HAZARD_BITS.items()}
    soils = {name: _r(np.mean(t.soil_index == k)) for k, name in enumerate(t.soils)}
    return {
        "grid": {"cell_m": _r(t.cell_m), "origin_xy_m": [_r(v) for v in t.origin_xy_m],
                 "shape_rows_cols": [rows, cols],
                 "rows": "south to north (scene frame); the GeoTIFF is north-up, each cell at "
                         "its pixel's centre",
                 "georeferenced": georeferenced},
        "layers": list(LAYERS),
        "hazard_bits": HAZARD_BITS,
        "limits": {k: _r(v) for k, v in t.limits.items()},
        "footprint": {k: _r(v) for k, v in dataclasses.asdict(t.footprint).items()},
        "hazard_fraction": _r(np.mean(t.hazard)),
        "hazard_fraction_by_term": shares,
        "cost_mean": _r(np.mean(t.cost)),
        "soil_shares": soils,
    }


def write_traversability(scene_dir: str | Path, *, rover: RoverConfig | None = None,
                         config: TraversabilityConfig | None = None) -> list[Path]:
    """Compute a built scene's traversability and write ``SCENE_DIR/traversability/``;
    returns the written paths (GeoTIFF, PNG, JSON)."""
    from PIL import Image

    from marsscene.dem.io_write import write_geotiff

    root = Path(scene_dir)
    inputs = read_scene_inputs(root)
    t = scene_traversability(inputs, rover=rover, config=config)
    out = root / TRAVERSABILITY_DIR
    out.mkdir(parents=True, exist_ok=True)
    tif = write_geotiff(out / "traversability.tif", t.layers(), origin_xy_m=t.origin_xy_m,
                        cell_m=t.cell_m, crs_wkt=inputs.crs_wkt,
                        origin_projected_xy_m=inputs.origin_projected_xy_m)
    stride = grid_stride(inputs.heightfield, config or TraversabilityConfig())
    z = inputs.heightfield.z_m[::stride, ::stride]
    png = out / "preview.png"
    Image.fromarray(preview_rgb(z, t.cell_m, t.cost, t.hazard), mode="RGB").save(png)
    doc = summary(t, georeferenced=inputs.crs_wkt is not None)
    meta = out / "summary.json"
    meta.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return [tif, png, meta]
