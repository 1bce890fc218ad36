"""The batched environment's contact test: which rovers touch a rock, from MuJoCo Warp's contact
buffers. The step's judgement itself is :func:`marsscene.env.judgement.judge_step`, the CPU
environment's, on (N,) arrays; the termination codes are :data:`marsscene.env.terms.
TERMINATIONS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from array_api_compat import device

from marsscene.env import taskmath

__all__ = ["RockContacts", "collided"]


@dataclass(frozen=True)
class RockContacts:
    """What tells a rock contact of the tiled model apart (arrays of the batch's backend).

    Attributes
    ----------
    chassis_geom : int
        The chassis geom.
    wheel_geoms : list of int
        The wheel geoms.
    rock_cells : (W, rows, cols) float32
        1 where a world's ground is raised by a rock (``ROCK_CONTACT_M``), else 0.
    grid_origins_xy_m : (W, 2)
        Each world's grid post (0, 0), in the world's frame.
    cell_m : float
        The grids' post spacing.
    offsets_xy_m : (W, 2)
        Each world's tile offset in the tiled model.
    """

    chassis_geom: int
    wheel_geoms: list[int]
    rock_cells: Any
    grid_origins_xy_m: Any
    cell_m: float
    offsets_xy_m: Any


def collided(contact: dict[str, Any], ncontact: Any, world: Any, rocks: RockContacts,
             backend: Any) -> Any:
    """(N,) bool: the chassis touches anything, or a wheel touches ground raised by a rock.

    ``contact``: MuJoCo Warp's contact buffers (``geom``, ``worldid``, ``pos``) as arrays;
    ``ncontact`` (1,) the contacts in them; ``world`` (N,) each rover's world; ``backend`` the
    batch's :class:`~marsscene.env.batch.backend.Backend` (its per-rover count).
    """
    xp, n = backend.xp, world.shape[0]
    wid = xp.clip(xp.astype(contact["worldid"], xp.int64), 0, n - 1)
    count = contact["worldid"].shape[0]
    valid = xp.arange(count, device=device(wid)) < xp.astype(ncontact[0], xp.int64)
    g0, g1 = contact["geom"][:, 0], contact["geom"][:, 1]
    chassis = (g0 == rocks.chassis_geom) | (g1 == rocks.chassis_geom)
    wheel = xp.zeros(g0.shape, dtype=xp.bool, device=device(g0))
    for g in rocks.wheel_geoms:
        wheel = wheel | (g0 == g) | (g1 == g)
    tile = world[wid]
    pos = xp.astype(contact["pos"], xp.float64)
    x = pos[:, 0] - rocks.offsets_xy_m[tile, 0]
    y = pos[:, 1] - rocks.offsets_xy_m[tile, 1]
    rock = taskmath.scan_heights(rocks.rock_cells, rocks.grid_origins_xy_m, rocks.cell_m, x, y,
                                 tile) > 0.5
    hit = valid & (chassis | (wheel & rock))
    return backend.count_per(wid, hit, n) > 0
