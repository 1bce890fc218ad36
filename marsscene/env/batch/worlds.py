"""``WorldBatch``: the worlds of a batched environment as arrays, and the episodes drawn on them.

Each world is a built scene (a folder, or a :class:`~marsscene.env.worlds.WorldSampler`'s world):
its terrain posts, its rocks (as the height scan sees them: domes of their footprint radius and
exposed height, :func:`~marsscene.env.observe.rock_terrain`), its bounds, and a pool of episode
starts drawn as the CPU environment draws them (:class:`~marsscene.env.task.TaskMap`: free
ground, a start heading, a goal in ``task.distance_m`` joined by free ground), from the seed
``(seed, world)``.

A batch is built once from the scene folders (about a second a world: the MJCF is compiled to
read its terrain and rocks) and saved as one ``.npz`` (a few MB for 16 worlds of 60 m): a GPU
machine then loads it with numpy alone, no scene folders, no build.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError

__all__ = ["WorldBatch"]

#: The arrays of a saved batch (``np.savez``); ``rock_world`` holds the world of each rock.
_FIELDS = ("posts_z_m", "cell_m", "origins_xy_m", "rock_xy_m", "rock_radius_m", "rock_height_m",
           "rock_world", "starts_xy_m", "yaws_rad", "goals_xy_m")
#: Saved too, absent from a batch saved before them (then empty).
_OPTIONAL = ("catalogue_rocks", "catalogue_world")


@dataclass(frozen=True, eq=False)
class WorldBatch:
    """W worlds of one terrain size and post spacing, with P drawn episodes each.

    Attributes
    ----------
    posts_z_m : ndarray (W, rows, cols) float32
        Terrain posts (no rocks), row 0 at the lowest y.
    cell_m : float
        Post spacing (m).
    origins_xy_m : ndarray (W, 2)
        World position of post (0, 0) of each world.
    rock_xy_m, rock_radius_m, rock_height_m, rock_world : ndarray
        The rocks of all worlds (centre, footprint radius, exposed height, world index).
    starts_xy_m, goals_xy_m : ndarray (W, P, 2); yaws_rad : ndarray (W, P)
        The drawn episodes: start, start heading, goal.
    catalogue_rocks : ndarray (K, 6); catalogue_world : ndarray (K,)
        The rock catalogue's rocks that are not MJCF geoms (what the camera draws besides
        the rocks above; :func:`~marsscene.sensors.camera_rocks.read_rock_catalog`'s rows:
        id, x, y, z, diameter, height + burial) and the world of each.
    """

    posts_z_m: NDArray[np.float32]
    cell_m: float
    origins_xy_m: NDArray[np.float64]
    rock_xy_m: NDArray[np.float64]
    rock_radius_m: NDArray[np.float64]
    rock_height_m: NDArray[np.float64]
    rock_world: NDArray[np.int64]
    starts_xy_m: NDArray[np.float64]
    yaws_rad: NDArray[np.float64]
    goals_xy_m: NDArray[np.float64]
    catalogue_rocks: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 6)))
    catalogue_world: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def count(self) -> int:
        """Number of worlds W."""
        return int(self.posts_z_m.shape[0])

    @property
    def pool(self) -> int:
        """Episodes drawn per world P."""
        return int(self.starts_xy_m.shape[1])

    @property
    def size_m(self) -> tuple[float, float]:
        """Each world's extent (x, y) in m."""
        rows, cols = self.posts_z_m.shape[1:]
        return (cols - 1) * self.cell_m, (rows - 1) * self.cell_m

    @property
    def bounds_xy_m(self) -> NDArray[np.float64]:
        """(W, 4): ``x0, y0, x1, y1`` of each world."""
        sx, sy = self.size_m
        o = self.origins_xy_m
        return np.column_stack([o[:, 0], o[:, 1], o[:, 0] + sx, o[:, 1] + sy])

    def heightfield(self, world: int) -> Any:
        """World ``world``'s bare terrain as a :class:`~marsscene.terrain.heightfield.
        Heightfield`."""
        from marsscene.terrain.heightfield import Heightfield

        o = self.origins_xy_m[world]
        return Heightfield(self.posts_z_m[world], self.cell_m, (float(o[0]), float(o[1])))

    def obstacles(self, world: int) -> Any:
        """World ``world``'s rocks as :class:`~marsscene.sim.route.Obstacles`."""
        from marsscene.sim.route import Obstacles

        k = self.rock_world == world
        return Obstacles(self.rock_xy_m[k], self.rock_radius_m[k], self.rock_height_m[k])

    def catalogues(self) -> list[NDArray[np.float64]]:
        """Each world's catalogue rocks (rows of :attr:`catalogue_rocks`)."""
        return [self.catalogue_rocks[self.catalogue_world == w] for w in range(self.count)]

    def rock_terrains(self) -> list[Any]:
        """Each world's terrain with its rocks on it, as the height scan samples it
        (:func:`~marsscene.env.observe.rock_terrain`; up to 5 cm posts)."""
        from marsscene.env.observe import rock_terrain

        return [rock_terrain(self.heightfield(w), self.obstacles(w)) for w in range(self.count)]

    # ---- building, saving, loading ---------------------------------------------------------
    @classmethod
    def build(cls, worlds: Any, *, task: Any = None, pool: int = 256, seed: int = 0,
              progress: Any = None) -> WorldBatch:
        """The worlds of ``worlds`` (a :class:`~marsscene.env.worlds.WorldSampler`, a scene
        folder or a list of them) with ``pool`` episodes drawn on each for ``task``
        (a :class:`~marsscene.env.task.NavTask`; default ``NavTask()``)."""
        from marsscene.env.task import NavTask, TaskMap
        from marsscene.env.worlds import world_paths
        from marsscene.rover.config import RunConfig
        from marsscene.sensors.camera_rocks import read_rock_catalog
        from marsscene.sim.rover_sim import RoverSim
        from marsscene.sim.world import scene_obstacles

        task = task if task is not None else NavTask()
        if not 1 <= int(pool) <= 100_000:
            raise ConfigError(f"pool = {pool}; draw 1 to 100000 episodes a world")
        count, path = world_paths(worlds)
        posts: list[NDArray[np.float32]] = []
        origins: list[tuple[float, float]] = []
        rocks: list[Any] = []
        draws: list[list[Any]] = []
        catalogue: list[NDArray[np.float64]] = []
        cell = None
        for w in range(count):
            sim = RoverSim(path(w), run=RunConfig(), settle_s=0.0, soil="rigid")  # terrain only
            hf, obstacles = sim.heightfield, scene_obstacles(sim)
            if cell is None:
                cell = hf.cell_size_m
            if posts and (hf.z_m.shape != posts[0].shape or abs(hf.cell_size_m - cell) > 1e-9):
                raise ConfigError(f"world {w}: terrain {hf.z_m.shape} posts at "
                                  f"{hf.cell_size_m:g} m; a batch needs one size and spacing "
                                  f"(world 0: {posts[0].shape} at {cell:g} m)")
            posts.append(np.asarray(hf.z_m, dtype=np.float32))
            origins.append(hf.origin_xy_m)
            rocks.append(obstacles)
            catalogue.append(read_rock_catalog(Path(path(w))))
            task_map = TaskMap(hf, obstacles, task)
            rng = np.random.default_rng([seed, w])
            draws.append([task_map.draw(rng, tries=1000) for _ in range(int(pool))])
            if progress is not None:
                progress(w + 1, count)
        return cls(
            posts_z_m=np.stack(posts), cell_m=float(cell or 1.0),
            origins_xy_m=np.asarray(origins, dtype=np.float64),
            rock_xy_m=np.concatenate([r.xy_m for r in rocks]).reshape(-1, 2),
            rock_radius_m=np.concatenate([r.radius_m for r in rocks]),
            rock_height_m=np.concatenate([r.height_m for r in rocks]),
            rock_world=np.concatenate([np.full(len(r.radius_m), w) for w, r in
                                       enumerate(rocks)]).astype(np.int64),
            starts_xy_m=np.array([[d[0] for d in ds] for ds in draws], dtype=np.float64),
            yaws_rad=np.array([[d[1] for d in ds] for ds in draws], dtype=np.float64),
            goals_xy_m=np.array([[d[2] for d in ds] for ds in draws], dtype=np.float64),
            catalogue_rocks=np.concatenate(catalogue).reshape(-1, 6),
            catalogue_world=np.concatenate([np.full(len(c), w) for w, c in
                                            enumerate(catalogue)]).astype(np.int64),
        )

    def save(self, path: str | Path) -> Path:
        """Write the batch as one ``.npz`` (the arrays above)."""
        out = Path(path)
        with open(out, "wb") as f:
            arrays: dict[str, Any] = {k: np.asarray(getattr(self, k))
                                      for k in (*_FIELDS, *_OPTIONAL)}
            np.savez_compressed(f, **arrays)
        return out

    @classmethod
    def load(cls, path: str | Path) -> WorldBatch:
        """Read a batch written by :meth:`save`."""
        try:
            with np.load(Path(path)) as z:
                arrays = {k: z[k] for k in _FIELDS}
                arrays.update({k: z[k] for k in _OPTIONAL if k in z.files})
        except (OSError, KeyError, ValueError) as err:
            raise ConfigError(f"{path}: not a world batch written by WorldBatch.save "
                              f"({err})") from None
        arrays["cell_m"] = float(arrays["cell_m"])
        return cls(**arrays)
