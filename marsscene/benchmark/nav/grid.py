"""The planning grid of a navigation benchmark: a traversability map at 1 m cells, its
8-connected graph and shortest paths on it.

A 1 m cell is a hazard when any of the traversability cells inside it is (the map is a
configuration-space map for the rover's centre, so hazards stay where the rover may not
stand), and its cost is their largest. Shortest paths are Dijkstra's algorithm on the grid
graph (``scipy.sparse.csgraph.dijkstra``: an A* with a zero heuristic, so the same optimal
paths), step cost = step length x (1 + w x cost), hazard cells removed; the path is then
pulled taut (each node joined to the farthest later node in straight line of sight over free
cells), so a path's length is not the 8-connected grid's, up to 8 % longer than the straight
line. Searches run in a
window around the start and the goal (their bounding box widened by half their distance, at
least 20 m), which keeps a 3.6 km scene's searches as small as a 0.5 km scene's.

References: Dijkstra, E. W. (1959), A note on two problems in connexion with graphs, Numerische
Mathematik 1, 269-271; Hart, P. E., Nilsson, N. J., Raphael, B. (1968), A formal basis for the
heuristic determination of minimum cost paths, IEEE Trans. SSC 4(2), 100-107.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["PLAN_CELL_M", "PlanGrid"]

#: The planners' and the scoring's cell (m).
PLAN_CELL_M = 1.0
_STEPS = ((0, 1), (1, 0), (1, 1), (1, -1))


@dataclass(frozen=True, eq=False)
class PlanGrid:
    """Cost in [0, 1] and hazard per cell; cell ``[r, c]`` is centred at ``origin_xy_m +
    (c, r) * cell_m`` (rows south to north)."""

    cost: NDArray[np.float32]
    hazard: NDArray[np.bool_]
    cell_m: float
    origin_xy_m: tuple[float, float]

    @classmethod
    def of(cls, t: object, cell_m: float = PLAN_CELL_M) -> PlanGrid:
        """A :class:`~marsscene.traversability.Traversability` pooled to ``cell_m`` cells."""
        cost = np.asarray(t.cost, dtype=np.float32)  # type: ignore[attr-defined]
        hazard: NDArray[np.bool_] = np.asarray(t.hazard, dtype=np.bool_)  # type: ignore[attr-defined]
        src = float(t.cell_m)  # type: ignore[attr-defined]
        k = max(1, round(cell_m / src))
        rows, cols = (cost.shape[0] // k) * k, (cost.shape[1] // k) * k
        shape = (rows // k, k, cols // k, k)
        ox, oy = t.origin_xy_m  # type: ignore[attr-defined]
        off = 0.5 * (k - 1) * src
        return cls(cost[:rows, :cols].reshape(shape).max(axis=(1, 3)),
                   np.asarray(hazard[:rows, :cols].reshape(shape).any(axis=(1, 3)), np.bool_),
                   src * k,
                   (float(ox) + off, float(oy) + off))

    @property
    def shape(self) -> tuple[int, int]:
        return (int(self.cost.shape[0]), int(self.cost.shape[1]))

    def rowcol(self, xy_m: NDArray[np.float64]) -> NDArray[np.int64]:
        """The (row, col) of the cells holding points ``xy_m`` (..., 2), clipped to the grid."""
        xy = np.asarray(xy_m, dtype=np.float64)
        c = np.rint((xy[..., 0] - self.origin_xy_m[0]) / self.cell_m).astype(np.int64)
        r = np.rint((xy[..., 1] - self.origin_xy_m[1]) / self.cell_m).astype(np.int64)
        rows, cols = self.shape
        return np.stack([np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1)], axis=-1)

    def xy(self, rc: NDArray[np.int64]) -> NDArray[np.float64]:
        """Centres (..., 2) of cells ``rc`` (..., 2)."""
        rc = np.asarray(rc)
        return np.stack([self.origin_xy_m[0] + rc[..., 1] * self.cell_m,
                         self.origin_xy_m[1] + rc[..., 0] * self.cell_m], axis=-1)

    def hazard_at(self, xy_m: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether points ``xy_m`` (..., 2) lie in hazard cells (outside the grid: hazard)."""
        xy = np.asarray(xy_m, dtype=np.float64)
        rc = self.rowcol(xy)
        back = self.xy(rc)
        out = np.abs(back - xy).max(axis=-1) > 0.5 * self.cell_m + 1e-9
        return np.asarray(self.hazard[rc[..., 0], rc[..., 1]] | out)

    def save(self, path: Path) -> None:
        np.savez_compressed(path, cost=self.cost, hazard=self.hazard,
                            cell_m=np.float64(self.cell_m),
                            origin_xy_m=np.asarray(self.origin_xy_m))

    @classmethod
    def load(cls, path: Path) -> PlanGrid:
        with np.load(path) as f:
            o = f["origin_xy_m"]
            return cls(f["cost"], f["hazard"], float(f["cell_m"]), (float(o[0]), float(o[1])))

    def window(self, a_rc: NDArray[np.int64], b_rc: NDArray[np.int64]
               ) -> tuple[slice, slice]:
        """The search window of two cells: their box widened by half their distance (at
        least 20 m)."""
        pad = max(20.0 / self.cell_m, 0.5 * float(np.hypot(*(a_rc - b_rc))))
        lo = np.maximum(np.minimum(a_rc, b_rc) - math.ceil(pad), 0)
        hi = np.minimum(np.maximum(a_rc, b_rc) + math.ceil(pad) + 1, self.shape)
        return slice(int(lo[0]), int(hi[0])), slice(int(lo[1]), int(hi[1]))

    def shortest(self, a_xy: NDArray[np.float64], b_xy: NDArray[np.float64], *,
                 cost_weight: float = 0.0) -> tuple[NDArray[np.float64] | None, float]:
        """The least-cost path from ``a_xy`` to ``b_xy`` through free cells: its cell centres
        (N, 2) (None if none) and its length (m; inf if none). ``cost_weight`` 0 gives the
        shortest traversable path."""
        a, b = self.rowcol(np.asarray(a_xy)), self.rowcol(np.asarray(b_xy))
        win = self.window(a, b)
        nodes = _path(~self.hazard[win], self.cost[win], cost_weight,
                      (int(a[0] - win[0].start), int(a[1] - win[1].start)),
                      (int(b[0] - win[0].start), int(b[1] - win[1].start)))
        if nodes is None:
            return None, math.inf
        nodes = _shortcut(~self.hazard[win], nodes)
        nodes = nodes + np.array([win[0].start, win[1].start])
        xy = self.xy(nodes)
        return xy, float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum()) if len(xy) > 1 \
            else 0.0


def _clear(free: NDArray[np.bool_], a: NDArray[np.int64], b: NDArray[np.int64]) -> bool:
    """Every cell the segment a-b crosses (sampled at a quarter cell) is free."""
    n = int(4 * np.abs(b - a).max()) + 2
    t = np.linspace(0.0, 1.0, n)[:, None]
    rc = np.rint(a + t * (b - a)).astype(np.int64)
    return bool(free[rc[:, 0], rc[:, 1]].all())


def _shortcut(free: NDArray[np.bool_], nodes: NDArray[np.int64]) -> NDArray[np.int64]:
    """The path through the fewest of its own nodes with straight, free segments between."""
    keep, i, n = [0], 0, len(nodes)
    while i < n - 1:
        j = i + 1
        while j + 1 < n and _clear(free, nodes[i], nodes[j + 1]):
            j += 1
        keep.append(j)
        i = j
    return nodes[keep]


def _path(free: NDArray[np.bool_], cost: NDArray[np.float32], weight: float,
          start: tuple[int, int], goal: tuple[int, int]) -> NDArray[np.int64] | None:
    """Cells (N, 2) of the least-cost 8-connected path (None when the goal is unreachable)."""
    from scipy import sparse
    from scipy.sparse.csgraph import dijkstra

    if not (free[start] and free[goal]):
        return None
    rows, cols = free.shape
    idx = np.arange(rows * cols).reshape(rows, cols)
    c = 1.0 + weight * np.asarray(cost, dtype=np.float64)
    src, dst, w = [], [], []
    for dr, dc in _STEPS:
        r0, r1 = max(0, -dr), rows - max(0, dr)
        c0, c1 = max(0, -dc), cols - max(0, dc)
        ok = free[r0:r1, c0:c1] & free[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
        src.append(idx[r0:r1, c0:c1][ok])
        dst.append(idx[r0 + dr:r1 + dr, c0 + dc:c1 + dc][ok])
        mean = 0.5 * (c[r0:r1, c0:c1][ok] + c[r0 + dr:r1 + dr, c0 + dc:c1 + dc][ok])
        w.append(math.hypot(dr, dc) * mean)
    g = sparse.csr_matrix((np.concatenate(w), (np.concatenate(src), np.concatenate(dst))),
                          shape=(rows * cols, rows * cols))
    s, t = int(idx[start]), int(idx[goal])
    dist, pred = dijkstra(g, directed=False, indices=s, return_predecessors=True)
    if not np.isfinite(dist[t]):
        return None
    path = [t]
    while path[-1] != s:
        path.append(int(pred[path[-1]]))
    nodes = np.array(path[::-1])
    return np.column_stack([nodes // cols, nodes % cols])
