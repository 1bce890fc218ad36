"""Keep only the scene rocks near the rover's route (MuJoCo's cost grows with every geom)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
from numpy.typing import NDArray

__all__ = ["CORRIDOR_M", "cull_scene_xml", "distance_to_polyline"]

#: Default half width of the rock corridor in m: only the MJCF rocks this close to the route
#: are simulated (``DriveOptions.corridor_m`` reads it from here).
CORRIDOR_M = 15.0


def distance_to_polyline(p: NDArray[np.float64], line: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance of points ``p`` (n, 2) to the polyline ``line`` (m, 2) (in m)."""
    if len(line) == 1:
        return np.asarray(np.linalg.norm(p - line[0], axis=1))
    a, b = line[:-1], line[1:]
    ab = b - a
    t = np.einsum("nmk,mk->nm", p[:, None, :] - a[None], ab) / np.maximum(
        np.einsum("mk,mk->m", ab, ab), 1e-12
    )
    foot = a[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
    return np.asarray(np.linalg.norm(p[:, None, :] - foot, axis=2).min(axis=1))


def cull_scene_xml(
    xml: str, corridor_xy_m: NDArray[np.float64], half_width_m: float
) -> tuple[str, int, int]:
    """Remove the ``rock_*`` world geoms (and their mesh assets) of a scene's MJCF text that lie
    farther than ``half_width_m`` from the corridor polyline.

    Editing the XML before compiling is much faster than deleting geoms from an ``MjSpec`` one
    by one, and the dropped rock meshes are not compiled at all.

    Returns
    -------
    xml : str
        The culled MJCF text.
    kept, total : int
        Rock geoms kept and present.
    """
    root = ET.fromstring(xml)
    world = root.find("worldbody")
    rocks = [] if world is None else [
        g for g in world.findall("geom") if g.get("name", "").startswith("rock_")
    ]
    if not rocks:
        return xml, 0, 0
    xy = np.array([[float(v) for v in g.get("pos", "0 0 0").split()[:2]] for g in rocks])
    far = distance_to_polyline(xy, np.asarray(corridor_xy_m, dtype=np.float64).reshape(-1, 2))
    drop = far > half_width_m
    dropped_meshes = set()
    assert world is not None
    for geom, d in zip(rocks, drop, strict=True):
        if d:
            world.remove(geom)
            if geom.get("mesh"):
                dropped_meshes.add(geom.get("mesh"))
    asset = root.find("asset")
    if asset is not None:
        for mesh in asset.findall("mesh"):
            if mesh.get("name") in dropped_meshes:
                asset.remove(mesh)
    return ET.tostring(root, encoding="unicode"), int((~drop).sum()), len(rocks)
