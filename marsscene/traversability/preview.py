"""The map's PNG preview: hazards in red and the cost from green to amber over a hillshade."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["hillshade", "preview_rgb"]

#: The preview's longest side in pixels (larger grids are shown every n-th cell).
MAX_PX = 2048
_GREEN, _AMBER, _RED = (np.array(c, np.float64) for c in
                        ((60, 170, 75), (235, 170, 40), (215, 30, 30)))


def hillshade(z_m: NDArray[np.floating], cell_m: float, azimuth_deg: float = 315.0,
              elevation_deg: float = 30.0) -> NDArray[np.float64]:
    """Lambertian shading in [0, 1] of a south-up grid lit from ``azimuth_deg`` (clockwise
    from north) at ``elevation_deg``."""
    dzdy, dzdx = np.gradient(np.asarray(z_m, dtype=np.float64), cell_m)
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    sun = np.array([np.sin(az) * np.cos(el), np.cos(az) * np.cos(el), np.sin(el)])
    norm = np.sqrt(dzdx * dzdx + dzdy * dzdy + 1.0)
    return np.clip((-dzdx * sun[0] - dzdy * sun[1] + sun[2]) / norm, 0.0, 1.0)


def preview_rgb(z_m: NDArray[np.floating], cell_m: float, cost: NDArray[np.floating],
                hazard: NDArray[np.bool_]) -> NDArray[np.uint8]:
    """An RGB image (north up) of the map over its terrain's hillshade."""
    step = max(1, -(-max(cost.shape) // MAX_PX))
    shade = hillshade(z_m, cell_m)[::step, ::step]
    c = np.clip(np.asarray(cost, dtype=np.float64)[::step, ::step], 0.0, 1.0)[..., None]
    haz = np.asarray(hazard)[::step, ::step][..., None]
    tint = np.where(c < 0.5, _GREEN + (_AMBER - _GREEN) * (2 * c), _AMBER)
    tint = np.where(haz, _RED, tint)
    alpha = np.where(haz, 0.7, 0.3)
    grey = (15.0 + 240.0 * shade)[..., None]
    rgb = grey * (1.0 - alpha) + tint * alpha
    return np.ascontiguousarray(np.clip(np.rint(rgb), 0, 255).astype(np.uint8)[::-1])
