"""A built scene's terrain and obstacles, for route planning, without the rover.

Compiling ``mjcf/scene.xml`` alone (no rover, no sensors) is what route authoring needs: the
terrain :class:`~marsscene.terrain.heightfield.Heightfield` and the rocks as
:class:`~marsscene.sim.route.Obstacles`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from marsscene.errors import RuntimeSimError
from marsscene.sim.route import Obstacles
from marsscene.sim.rover_sim import load_scene_spec
from marsscene.sim.terrain import scene_heightfield
from marsscene.terrain.heightfield import Heightfield

__all__ = ["SceneWorld", "load_world", "scene_obstacles", "world_obstacles"]


@dataclass(frozen=True)
class SceneWorld:
    """The terrain and the rocks of a built scene (world frame, metres)."""

    heightfield: Heightfield
    obstacles: Obstacles


def load_world(scene_dir: str | Path) -> SceneWorld:
    """Compile ``scene_dir/mjcf/scene.xml`` (without the rover) and read its terrain and rocks.

    Examples
    --------
    >>> world = load_world("scenes/demo")  # doctest: +SKIP
    >>> route = author_route([[-5, -5], [5, 5]], world.heightfield, obstacles=world.obstacles)
    ... # doctest: +SKIP
    """
    spec, xml, _ = load_scene_spec(scene_dir, rock_contacts=False)  # planning only: no hulls
    try:
        model = spec.compile()
    except Exception as err:
        raise RuntimeSimError(f"{xml}: cannot compile the scene: {err}") from None
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hf = scene_heightfield(model)
    return SceneWorld(hf, world_obstacles(model, data, hf))


def scene_obstacles(sim: Any) -> Obstacles:
    """The rocks of a :class:`~marsscene.sim.rover_sim.RoverSim`'s scene as
    :class:`Obstacles`."""
    return world_obstacles(sim.model, sim.data, sim.heightfield)


def world_obstacles(model: Any, data: Any, heightfield: Heightfield) -> Obstacles:
    """Non-terrain world geoms (rocks) as :class:`Obstacles`: radius is the geom's horizontal
    bounding radius, height its top above the terrain."""
    world = np.flatnonzero(
        (model.geom_bodyid == 0)
        & (model.geom_type != mujoco.mjtGeom.mjGEOM_HFIELD)
        & (model.geom_type != mujoco.mjtGeom.mjGEOM_PLANE)
    )
    if len(world) == 0:
        return Obstacles(np.zeros((0, 2)), np.zeros(0), np.zeros(0))
    aabb = model.geom_aabb[world]  # (n, 6): centre offset, half sizes in the geom frame
    rot = data.geom_xmat[world].reshape(-1, 3, 3)
    half_world = np.einsum("nij,nj->ni", np.abs(rot), aabb[:, 3:])
    centre = data.geom_xpos[world] + np.einsum("nij,nj->ni", rot, aabb[:, :3])
    top = centre[:, 2] + half_world[:, 2]
    ground = heightfield.sample(centre[:, 0], centre[:, 1])
    return Obstacles(
        centre[:, :2].copy(),
        np.hypot(half_world[:, 0], half_world[:, 1]),
        np.maximum(top - ground, 0.0),
    )
