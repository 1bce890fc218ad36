"""Seeded start-goal pairs on connected traversable ground (pure: arrays in, a list out).

A scene's pairs are drawn from its own stream, ``SeedSequence(seed, spawn_key=(PAIRS_STAGE,
crc32(scene name)))``, so adding a scene moves no other scene's pairs. Starts and goals are
cells of the largest 8-connected component of free cells of the ground-truth planning grid
(:class:`~marsscene.benchmark.nav.grid.PlanGrid`); a goal is drawn uniformly among the
component's cells whose straight-line distance from the start lies in the range. A pair whose
shortest traversable path cannot be found in its search window is redrawn.
"""

from __future__ import annotations

import zlib
from typing import Any

import numpy as np
from scipy import ndimage

from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.errors import ConfigError

__all__ = ["PAIRS_STAGE", "draw_pairs", "pairs_rng", "reachable_cells"]

#: Stream id of the pairs (fixed, never renumbered).
PAIRS_STAGE = 66
_TRIES_PER_PAIR = 50


def pairs_rng(seed: int, scene: str) -> np.random.Generator:
    """The pairs' generator of one scene of a benchmark seeded with ``seed``."""
    key = (PAIRS_STAGE, zlib.crc32(scene.encode("utf-8")))
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def reachable_cells(grid: PlanGrid) -> np.ndarray:
    """(N, 2) rows and columns of the largest 8-connected component of free cells."""
    labels, n = ndimage.label(~grid.hazard, structure=np.ones((3, 3), bool))
    if n == 0:
        raise ConfigError("the scene has no traversable ground (every cell is a hazard)")
    sizes = np.bincount(labels.ravel())[1:]
    return np.argwhere(labels == 1 + int(np.argmax(sizes)))


def draw_pairs(grid: PlanGrid, n: int, distance_m: tuple[float, float], *,
               rng: np.random.Generator, scene: str = "scene") -> list[dict[str, Any]]:
    """``n`` start-goal pairs with their straight-line and shortest traversable distance.

    Returns
    -------
    list of dict
        ``pair`` (index), ``start_xy_m``, ``goal_xy_m``, ``distance_m`` (straight line),
        ``shortest_m`` (the shortest path through free cells).

    Raises
    ------
    ConfigError
        When the traversable ground holds no pair in the range (in a one-line message).
    """
    cells = reachable_cells(grid)
    xy = grid.xy(cells)
    lo, hi = distance_m
    out: list[dict[str, Any]] = []
    tries = 0
    while len(out) < n:
        tries += 1
        if tries > _TRIES_PER_PAIR * n:
            raise ConfigError(f"scene {scene!r}: found only {len(out)} of {n} start-goal "
                              f"pairs {lo:g}-{hi:g} m apart on connected traversable ground; "
                              "shorten benchmark.distance_m or use a larger scene")
        a = xy[int(rng.integers(len(xy)))]
        d = np.hypot(*(xy - a).T)
        ok = np.flatnonzero((d >= lo) & (d <= hi))
        if ok.size == 0:
            continue
        b = xy[int(ok[rng.integers(ok.size)])]
        _, shortest = grid.shortest(a, b)
        if not np.isfinite(shortest):
            continue  # joined only outside the search window: redraw
        out.append({"pair": len(out), "start_xy_m": [round(float(v), 3) for v in a],
                    "goal_xy_m": [round(float(v), 3) for v in b],
                    "distance_m": round(float(np.hypot(*(b - a))), 3),
                    "shortest_m": round(float(shortest), 3)})
    return out
