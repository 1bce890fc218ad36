"""The batched environment's MuJoCo model: every world's terrain, rocks included, as tiles of one
heightfield, and the rover.

MuJoCo Warp steps N copies ("worlds") of one model, so the W terrains of a batch share one
``hfield``: each is sampled at ``post_m`` from its terrain with the rocks on it (the domes the
height scan sees, :func:`~marsscene.env.observe.rock_terrain`; each post raised by the highest
rock within half a post, so none falls between posts) and laid out on a grid of tiles
``gap_m`` apart, as Isaac Lab's and mjlab's terrain generators lay out their sub-terrains. A
rover on tile w is in world w's coordinates shifted by ``offsets_xy_m[w]``; it never reaches a
neighbour, since an episode ends ``task.edge_m`` inside its world's edge.

Rocks are relief of the heightfield, not mesh geoms: MuJoCo Warp collides every world's rover
with the one heightfield instead of with thousands of static meshes. The posts are the scenes'
own (0.25 m for :data:`~marsscene.env.worlds.WORLD_KINDS`): at 0.1 m a wheel overlaps more
prisms than the 50 contacts MuJoCo Warp 4.0 keeps for a geom pair, and the rover parts from
MuJoCo C's (``python perf/run.py batch_env --what agree``). What this
changes against the CPU environment's mesh rocks (convex hulls with overhangs and sharp
edges) is measured in :doc:`/results/gym`.

The scene's physics settings come from the MJCF writer: gravity, integrator, regolith friction
(:mod:`marsscene.export.mjcf.common`); the rover is :func:`~marsscene.sim.rover_model.rover_mjcf`,
attached as :class:`~marsscene.sim.rover_sim.RoverSim` attaches it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.export.mjcf.common import INTEGRATOR, REGOLITH_FRICTION
from marsscene.rover.config import RoverConfig
from marsscene.sim.rover_model import rover_mjcf
from marsscene.sim.rover_sim import PREFIX, rover_indices
from marsscene.units import MARS_GRAVITY_M_S2

__all__ = ["TiledModel", "WarpPhysics", "tiled_model", "warp_model"]


@dataclass(frozen=True)
class WarpPhysics:
    """How MuJoCo Warp steps a batch.

    Attributes
    ----------
    post_m : float, optional
        Post spacing of the heightfield (rocks as relief); default: the worlds' own.
    iterations, ls_iterations : int
        The constraint solver's iteration and line-search limits (MuJoCo's defaults: 100 and
        50). A batch steps until its slowest world converges or the limit is reached.
    nconmax, njmax : int
        Contacts and constraint rows allocated per world.
    deterministic : bool
        MuJoCo Warp's deterministic mode (sorted contacts, canonical constraint rows,
        order-invariant sums): the same seed gives the same bytes on a GPU too, at a cost.
    """

    post_m: float | None = None
    iterations: int = 100
    ls_iterations: int = 50
    nconmax: int = 48
    njmax: int = 192
    deterministic: bool = False

    def __post_init__(self) -> None:
        for name in ("iterations", "ls_iterations", "nconmax", "njmax"):
            if int(getattr(self, name)) < 1:
                raise ConfigError(f"WarpPhysics.{name} must be at least 1, "
                                  f"got {getattr(self, name)}")
        if self.post_m is not None and not self.post_m > 0:
            raise ConfigError(f"WarpPhysics.post_m must be positive, got {self.post_m}")


@dataclass(frozen=True, eq=False)
class TiledModel:
    """The compiled model and where things are in it.

    Attributes
    ----------
    model : mujoco.MjModel
    offsets_xy_m : ndarray (W, 2)
        Tile coordinates minus world coordinates, per world.
    ids : dict
        :func:`~marsscene.sim.rover_sim.rover_indices` of the rover.
    """

    model: Any
    offsets_xy_m: NDArray[np.float64]
    ids: dict[str, Any]


def _tile(terrain: Any, bare: Any, post_m: float) -> NDArray[np.float64]:
    """The bare terrain at ``post_m`` posts (row 0 at the lowest y), raised at each post by the
    highest rock within half a post of it (so no rock falls between posts)."""
    from scipy import ndimage

    x0, y0, x1, y1 = terrain.bounds_xy_m
    xs = x0 + np.arange(math.floor((x1 - x0) / post_m + 1e-9) + 1) * post_m
    ys = y0 + np.arange(math.floor((y1 - y0) / post_m + 1e-9) + 1) * post_m
    t, cell = terrain, terrain.cell_size_m
    fine_x = t.origin_xy_m[0] + np.arange(t.z_m.shape[1]) * cell
    fine_y = t.origin_xy_m[1] + np.arange(t.z_m.shape[0]) * cell
    lift = t.z_m - bare.sample(*np.meshgrid(fine_x, fine_y))
    lift = ndimage.maximum_filter(lift, size=max(1, round(post_m / cell)), mode="nearest")
    gx, gy = np.meshgrid(xs, ys)
    r = np.clip(np.rint((gy - t.origin_xy_m[1]) / cell).astype(int), 0, t.z_m.shape[0] - 1)
    c = np.clip(np.rint((gx - t.origin_xy_m[0]) / cell).astype(int), 0, t.z_m.shape[1] - 1)
    return np.asarray(bare.sample(gx, gy), dtype=np.float64) + np.maximum(lift[r, c], 0.0)


def tiled_model(terrains: list[Any], bare: list[Any], *, rover: RoverConfig,
                physics_hz: float, post_m: float, gap_m: float = 2.0,
                physics: WarpPhysics | None = None) -> TiledModel:
    """Compile the rover on the tiles of ``terrains`` (rock terrains, one per world, of one
    size; ``bare`` the same without rocks), sampled at ``post_m``, with the solver limits of
    ``physics``."""
    physics = physics if physics is not None else WarpPhysics()
    made: dict[tuple[int, int], NDArray[np.float64]] = {}  # worlds shared by many tiles
    for t, b in zip(terrains, bare, strict=True):
        if (id(t), id(b)) not in made:
            made[id(t), id(b)] = _tile(t, b, post_m)
    tiles = [made[id(t), id(b)] for t, b in zip(terrains, bare, strict=True)]
    rows, cols = tiles[0].shape
    per_row = math.ceil(math.sqrt(len(tiles)))
    gap = math.ceil(gap_m / post_m)
    pitch_r, pitch_c = rows + gap, cols + gap
    n_r = math.ceil(len(tiles) / per_row)
    floor = float(min(t.min() for t in tiles)) - 1.0
    z = np.full((n_r * pitch_r - gap, per_row * pitch_c - gap), floor)
    offsets = np.zeros((len(tiles), 2))
    for w, (tile, terrain) in enumerate(zip(tiles, terrains, strict=True)):
        r, c = divmod(w, per_row)
        z[r * pitch_r: r * pitch_r + rows, c * pitch_c: c * pitch_c + cols] = tile
        x0, y0 = terrain.bounds_xy_m[:2]
        offsets[w] = (c * pitch_c * post_m - x0, r * pitch_r * post_m - y0)
    lo, hi = float(z.min()), float(z.max())
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.option.timestep = 1.0 / float(physics_hz)
    spec.option.gravity = [0.0, 0.0, -MARS_GRAVITY_M_S2]
    spec.option.integrator = getattr(mujoco.mjtIntegrator, "mjINT_" + INTEGRATOR.upper())
    spec.option.iterations = int(physics.iterations)
    spec.option.ls_iterations = int(physics.ls_iterations)
    rx, ry = (z.shape[1] - 1) * post_m / 2.0, (z.shape[0] - 1) * post_m / 2.0
    hfield = spec.add_hfield(name="terrain", size=[rx, ry, max(hi - lo, 1e-3), 1.0],
                             nrow=z.shape[0], ncol=z.shape[1])
    hfield.userdata = ((z - lo) / max(hi - lo, 1e-3)).astype(np.float32).ravel()
    spec.worldbody.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_HFIELD,
                            hfieldname="terrain", pos=[rx, ry, lo],
                            friction=list(REGOLITH_FRICTION), condim=3)
    rover_spec = mujoco.MjSpec.from_string(rover_mjcf(rover))
    spec.attach(rover_spec, prefix=PREFIX, frame=spec.worldbody.add_frame())
    model = spec.compile()
    return TiledModel(model=model, offsets_xy_m=offsets, ids=rover_indices(model))


def warp_model(model: Any, physics: WarpPhysics) -> Any:
    """MuJoCo Warp's copy of ``model`` (on the current Warp device), in deterministic mode where
    ``physics`` asks for it."""
    import mujoco_warp as mjw

    out = mjw.put_model(model)
    if physics.deterministic:
        out.opt.deterministic = int(mjw.DeterminismType.ALL)
    return out
