"""Rays against oriented boxes: what a LiDAR sees of the other robots of a team.

The terrain and the rocks are static and cast in one Embree scene (:mod:`.lidar_embree`); the
other rovers of a team move, so their collision geoms are cast here each scan, each geom as its
oriented bounding box (MuJoCo's ``geom_aabb`` in the geom's frame: a chassis box exactly, a wheel
cylinder as its box), by the slab method (Kay & Kajiya, SIGGRAPH 1986), vectorised over rays;
only the rays through a robot's bounding sphere are tested against its boxes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["Boxes", "ray_boxes", "robot_boxes"]

Boxes = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""Centres (k, 3), rotations (k, 3, 3; box frame to world) and half sizes (k, 3), in m."""


def robot_boxes(model: Any, data: Any, geoms: NDArray[np.intp]) -> Boxes:
    """The oriented bounding boxes of ``geoms`` at the current state (world frame)."""
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3).astype(np.float64)
    aabb = model.geom_aabb[geoms].astype(np.float64)
    centre = data.geom_xpos[geoms] + np.einsum("kij,kj->ki", rot, aabb[:, :3])
    return centre, rot, aabb[:, 3:]


def ray_boxes(origins: NDArray[np.floating[Any]], dirs: NDArray[np.floating[Any]],
              groups: Sequence[Boxes], max_m: float
              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Distance along each ray (n,) to the nearest box it enters within ``max_m`` (inf where
    none; a ray starting inside a box ignores that box) and the unit normal there (n, 3).

    ``origins`` is (3,) or (n, 3), ``dirs`` (n, 3) unit vectors; ``groups`` are sets of boxes
    (a robot's geoms each): only the rays that pass through a group's bounding sphere are
    tested against its boxes.
    """
    d = np.asarray(dirs, dtype=np.float64)
    o = np.broadcast_to(np.asarray(origins, dtype=np.float64), d.shape)
    best = np.full(len(d), np.inf)
    normal = np.zeros_like(d)
    for centres, rots, halfs in groups:
        mid = centres.mean(axis=0)
        radius = float((np.linalg.norm(centres - mid, axis=1)
                        + np.linalg.norm(halfs, axis=1)).max())
        rel = mid - o
        along = np.einsum("ij,ij->i", rel, d)
        miss2 = np.einsum("ij,ij->i", rel, rel) - along**2
        rays = np.flatnonzero((miss2 <= radius**2) & (along > -radius)
                              & (along - radius < max_m))
        for c, r, h in zip(centres, rots, halfs, strict=True):
            if len(rays):
                _slab(o[rays], d[rays], c, r, h, max_m, rays, best, normal)
    return best, normal


def _slab(o: NDArray[np.float64], d: NDArray[np.float64], c: NDArray[np.float64],
          r: NDArray[np.float64], h: NDArray[np.float64], max_m: float, rays: NDArray[np.intp],
          best: NDArray[np.float64], normal: NDArray[np.float64]) -> None:
    """Where the rays ``rays`` (origins ``o``, directions ``d``) enter the box (centre ``c``,
    rotation ``r``, half sizes ``h``) nearer than ``best``: update ``best`` and ``normal``."""
    ol = (o - c) @ r  # into the box frame: r.T @ (o - c) per ray
    dl = d @ r
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dl
        t1, t2 = (-h - ol) * inv, (h - ol) * inv
    near = np.nan_to_num(np.minimum(t1, t2), nan=-np.inf)
    far = np.nan_to_num(np.maximum(t1, t2), nan=np.inf)
    t_in, axis = near.max(axis=1), near.argmax(axis=1)
    hit = (t_in <= far.min(axis=1)) & (t_in > 0.0) & (t_in < np.minimum(best[rays], max_m))
    if not hit.any():
        return
    i = np.flatnonzero(hit)
    best[rays[i]] = t_in[i]
    n_local = np.zeros((len(i), 3))
    n_local[np.arange(len(i)), axis[i]] = -np.sign(dl[i, axis[i]])
    normal[rays[i]] = n_local @ r.T
