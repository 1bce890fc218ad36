"""Crater catalogue written beside the scene: ``craters.csv``.

One row per crater, in formation order (oldest first). Columns::

    id, x_m, y_m, [lon_deg, lat_deg,] diameter_m, diameter_km, depth_m, rim_height_m, age_ga,
    axis_ratio, azimuth_deg, profile, in_scene

``x_m, y_m`` are scene metres (x east, y north, origin at the terrain centre). ``lon_deg,
lat_deg`` (planetocentric, east-positive) are present when the terrain is georeferenced; they
use a local equirectangular approximation about the scene origin on the Mars 2000 sphere
(:mod:`marsscene.craters.geo`). ``in_scene`` is 1 when the centre lies on the terrain (count
those for crater statistics; the others are rim/ejecta-crossing craters centred outside).
Plain comma-separated values with a header line, readable by craterstats-style tools and
spreadsheets (``diameter_km`` for tools that expect km).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["CATALOG_NAME", "crater_catalog_text", "write_crater_catalog"]

CATALOG_NAME = "craters.csv"


def crater_catalog_text(scene: Any) -> str:
    """The catalogue as CSV text (deterministic formatting)."""
    from marsscene.craters.geo import xy_to_lonlat_deg
    from marsscene.craters.morphology import PROFILE_MODELS

    t = scene.craters
    frame = scene.provenance.frame
    x, y = t.center_xy_m[:, 0], t.center_xy_m[:, 1]
    inside = scene.heightfield.contains(x, y)
    geo = frame is not None and frame.origin_lonlat_deg is not None
    header = ["id", "x_m", "y_m"]
    if geo:
        header += ["lon_deg", "lat_deg"]
        lon, lat = xy_to_lonlat_deg(x, y, origin_lonlat_deg=tuple(frame.origin_lonlat_deg),
                                    grid_convergence_deg=frame.grid_convergence_deg)
    header += ["diameter_m", "diameter_km", "depth_m", "rim_height_m", "age_ga", "axis_ratio",
               "azimuth_deg", "profile", "in_scene"]
    lines = [",".join(header)]
    for i in range(len(t)):
        row = [str(i), f"{x[i]:.4f}", f"{y[i]:.4f}"]
        if geo:
            row += [f"{lon[i]:.8f}", f"{lat[i]:.8f}"]
        row += [
            f"{t.diameter_m[i]:.4f}", f"{t.diameter_m[i] / 1e3:.7f}", f"{t.depth_m[i]:.4f}",
            f"{t.rim_height_m[i]:.4f}", f"{t.age_ga[i]:.6f}", f"{t.axis_ratio[i]:.4f}",
            f"{t.azimuth_deg[i]:.3f}", PROFILE_MODELS[int(t.profile[i])], str(int(inside[i])),
        ]
        lines.append(",".join(row))
    return "\n".join(lines) + "\n"


def write_crater_catalog(scene: Any, out_dir: Path) -> list[Path]:
    """Write ``out_dir/craters.csv``; nothing when the stage is disabled."""
    if scene.craters is None:
        return []
    path = Path(out_dir) / CATALOG_NAME
    path.write_text(crater_catalog_text(scene), encoding="utf-8", newline="\n")
    return [path]
