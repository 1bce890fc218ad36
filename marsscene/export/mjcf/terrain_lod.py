"""The outer terrain of a level-of-detail scene as a second MuJoCo hfield.

MuJoCo cannot cut a hole in an hfield, so the coarse hfield ``terrain_outer`` covers the whole
footprint with its posts strictly inside the focus square lowered by :data:`HOLE_DEPTH_M`
below the (identical) fine heights there. The full-resolution focus hfield ``terrain`` (the one
the runtime drives on) is then the only surface a body on the focus can touch; the coarse
border posts are not lowered, so the two surfaces meet along the focus border.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import numpy as np

from marsscene.export.mjcf.hfield import hfield_spec

__all__ = ["HOLE_DEPTH_M", "OUTER_HFIELD_ASSET", "add_outer_terrain", "lowered_outer"]

#: Depth (in m) of the coarse posts inside the focus square below the fine surface. Larger than
#: the fine terrain's deviation from the coarse posts' bilinear surface (sub-metre detail and
#: small craters between 1 m posts), so the coarse surface stays under the fine one.
HOLE_DEPTH_M = 2.0
OUTER_HFIELD_ASSET = "assets/terrain_outer.bin"


def lowered_outer(scene: Any) -> Any:
    """The coarse heightfield with its posts strictly inside the focus lowered."""
    hf = scene.outer.heightfield
    x0, y0, x1, y1 = scene.outer.focus_bounds_xy_m
    xs, ys = hf.grid_xy()
    eps = 1e-6 * hf.cell_size_m
    inside = (((ys > y0 + eps) & (ys < y1 - eps))[:, None]
              & ((xs > x0 + eps) & (xs < x1 - eps))[None, :])
    return hf.with_z(hf.z_m - np.float32(HOLE_DEPTH_M) * inside)


def add_outer_terrain(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add the ``terrain_outer`` hfield and geom (nothing for scenes without an outer level)."""
    if scene.outer is None:
        return
    from marsscene.export.mjcf.common import REGOLITH_FRICTION, fmt

    spec = hfield_spec(lowered_outer(scene))
    asset = root.find("asset")
    world = root.find("worldbody")
    assert asset is not None and world is not None
    ET.SubElement(asset, "hfield", name="terrain_outer", file=OUTER_HFIELD_ASSET,
                  size=fmt(spec.size, 9))
    assets[OUTER_HFIELD_ASSET] = spec.bin_bytes
    ET.SubElement(world, "geom", name="terrain_outer", type="hfield", hfield="terrain_outer",
                  pos=fmt(spec.pos, 9), material="regolith", friction=fmt(REGOLITH_FRICTION),
                  condim="3", contype="1", conaffinity="1")
