"""Level-of-detail terrain over a whole DTM without reading it whole at full resolution.

With ``terrain.lod`` and a ``terrain.post_m`` that is a whole multiple (>= 2) of the DTM's posts,
the terrain stage reads

* the **outer level** averaged to ``post_m``, strip by strip
  (:func:`marsscene.dem.decimate.read_dem_averaged`: memory bounded by a strip and the output),
* the **focus window** (the focus square plus a margin for the cubic and the craters' halos) at
  the DTM's own posts, by one rasterio window read,

so a 6 x 20 km HiRISE DTM at 1 m (120 M posts) becomes a 4 m outer level (7.5 M posts) and a
1 km window, never a 120 M-post array. The outer level defines the scene frame (centre, datum);
the window is placed in it by its projected coordinates and shares its datum and vertical scale.
Otherwise (a DEM object passed in, ``detrend``, posts that do not divide) the terrain stage reads
the crop at its posts as before.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from marsscene.config import SceneConfig
from marsscene.dem.model import DEM
from marsscene.terrain.from_dem import GeoFrame, fill_nearest, plan_crop, prepare_dem
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import FocusPlan

__all__ = ["AveragedDEM", "read_averaged_outer"]


@dataclass(frozen=True, eq=False)
class AveragedDEM:
    """The outer level read averaged, and how to read the focus window later."""

    dem: DEM
    inputs: dict[str, str]
    path: Path
    factor: int

    def base_reader(self, config: SceneConfig, frame: GeoFrame
                    ) -> Callable[[FocusPlan], Heightfield]:
        """A function that reads the focus window of ``plan`` at the DTM's posts, in the scene
        frame of the outer level."""
        return lambda plan: _read_focus_window(self, config, frame, plan)


def read_averaged_outer(config: SceneConfig) -> AveragedDEM | None:
    """The outer level of a level-of-detail DTM scene read averaged, or ``None`` when the
    streamed path does not apply (see the module docstring)."""
    from marsscene.dem.decimate import read_dem_averaged
    from marsscene.dem.io import open_source
    from marsscene.terrain.default import default_dem_path

    tcfg = config.terrain
    if not tcfg.lod or tcfg.source == "procedural" or tcfg.post_m is None or tcfg.detrend:
        return None
    path = Path(default_dem_path() if tcfg.source == "default" else str(tcfg.dem_path))
    info = open_source(path)
    native = abs(float(info.transform[0]))
    factor = round(tcfg.post_m / native)
    k = native / tcfg.focus_post_m
    if (factor < 2 or abs(factor * native - tcfg.post_m) > 1e-6 * tcfg.post_m
            or abs(k - round(k)) > 1e-6 or abs(abs(float(info.transform[4])) - native) > 1e-9):
        return None
    spec = plan_crop(tcfg, info.transform, info.shape, default_post_m=tcfg.post_m)
    dem = read_dem_averaged(path, factor=factor, band=tcfg.band, crop=spec)
    inputs = {"dem": str(path)} | ({"ortho": tcfg.ortho_path} if tcfg.ortho_path else {})
    return AveragedDEM(dem, inputs, path, factor)


def _margin_m(config: SceneConfig, native_post_m: float) -> float:
    """The focus window's margin: the widest crater's reach (its halo) and 4 posts."""
    ccfg = config.craters
    reach = (ccfg.ejecta_reach * ccfg.d_max_m / 2.0 / np.sqrt(ccfg.axis_ratio_min)
             if ccfg.enabled else 0.0)
    return float(reach) + 4.0 * native_post_m


def _read_focus_window(src: AveragedDEM, config: SceneConfig, frame: GeoFrame,
                       plan: FocusPlan) -> Heightfield:
    from marsscene.dem.io import read_dem
    from marsscene.dem.ops import Crop

    tcfg = config.terrain
    native = src.dem.post_m / src.factor
    margin = _margin_m(config, native)
    ox, oy = frame.origin_projected_xy_m or (0.0, 0.0)
    x0, y0, x1, y1 = plan.bounds_xy_m
    bounds = (x0 - margin + ox, y0 - margin + oy, x1 + margin + ox, y1 + margin + oy)
    window = read_dem(src.path, band=tcfg.band, crop=Crop(bounds_xy_m=bounds))
    window, _, _, _ = prepare_dem(window, dataclasses.replace(tcfg, post_m=None),
                                  default_post_m=None)
    z = fill_nearest(window.elevation_m.astype(np.float64))  # as heightfield_from_dem does
    a, _, c, _, e, f = window.transform
    rows = z.shape[0]
    # south-west post centre, in the scene frame of the outer level
    sw = (c + 0.5 * a - ox, f + e * (rows - 0.5) - oy)
    z_scene = ((z - frame.datum_m) * frame.z_scale)[::-1, :]
    return Heightfield(z_scene.astype(np.float32), abs(a), sw)
