"""A built scene's terrain and obstacles, for route planning, without the rover.

Compiling ``mjcf/scene.xml`` alone (no rover, no sensors) is what route authoring needs: the
terrain :class:`~marsscene.terrain.heightfield.Heightfield` and the rocks as
:class:`~marsscene.sim.route.Obstacles` (the placed assets' parts among them, as obstacles);
the assets' own meshes (:class:`AssetMesh`) are what a camera draws of them.
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

__all__ = ["ASSET_GEOM_PREFIX", "AssetMesh", "SceneWorld", "asset_meshes", "load_world",
           "scene_obstacles", "world_obstacles"]

#: Names of the MJCF geoms of placed assets (:mod:`marsscene.export.mjcf.assets`).
ASSET_GEOM_PREFIX = "asset_"


@dataclass(frozen=True, eq=False)
class AssetMesh:
    """The placed assets' parts as one triangle mesh in the world frame: ``vertices_m`` (V, 3),
    ``faces`` (F, 3) and each face's material colour ``rgb`` (F, 3) (MuJoCo's rgba)."""

    vertices_m: np.ndarray
    faces: np.ndarray
    rgb: np.ndarray

    @classmethod
    def empty(cls) -> AssetMesh:
        return cls(np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros((0, 3)))


@dataclass(frozen=True)
class SceneWorld:
    """The terrain and the rocks of a built scene (world frame, metres): ``obstacles`` every
    world geom (rocks and assets' parts), ``rocks`` the rocks alone, ``assets`` the assets'
    meshes."""

    heightfield: Heightfield
    obstacles: Obstacles
    rocks: Obstacles
    assets: AssetMesh


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
    return SceneWorld(hf, world_obstacles(model, data, hf),
                      world_obstacles(model, data, hf, assets=False), asset_meshes(model, data))


def scene_obstacles(sim: Any) -> Obstacles:
    """The rocks of a :class:`~marsscene.sim.rover_sim.RoverSim`'s scene as
    :class:`Obstacles`."""
    return world_obstacles(sim.model, sim.data, sim.heightfield)


def _asset_geoms(model: Any) -> np.ndarray:
    """(ngeom,) bool: the placed assets' geoms."""
    return np.array([(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "").startswith(
        ASSET_GEOM_PREFIX) for g in range(model.ngeom)], dtype=bool)


def world_obstacles(model: Any, data: Any, heightfield: Heightfield, *,
                    assets: bool = True) -> Obstacles:
    """Non-terrain world geoms (rocks, and the assets' parts unless ``assets`` is False) as
    :class:`Obstacles`: radius is the geom's horizontal bounding radius, height its top above
    the terrain."""
    keep = ((model.geom_bodyid == 0)
            & (model.geom_type != mujoco.mjtGeom.mjGEOM_HFIELD)
            & (model.geom_type != mujoco.mjtGeom.mjGEOM_PLANE))
    if not assets:
        keep &= ~_asset_geoms(model)
    world = np.flatnonzero(keep)
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


def asset_meshes(model: Any, data: Any) -> AssetMesh:
    """The placed assets' mesh geoms (``asset_*``) in the world frame at ``data``'s
    kinematics, one :class:`AssetMesh`."""
    geoms = np.flatnonzero(_asset_geoms(model) & (model.geom_type == mujoco.mjtGeom.mjGEOM_MESH))
    if not len(geoms):
        return AssetMesh.empty()
    verts, faces, rgb, start = [], [], [], 0
    for g in geoms:
        mesh = int(model.geom_dataid[g])
        va, nv = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        fa, nf = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
        local = np.asarray(model.mesh_vert[va: va + nv], dtype=np.float64)
        rot = np.asarray(data.geom_xmat[g], dtype=np.float64).reshape(3, 3)
        verts.append(local @ rot.T + data.geom_xpos[g])
        faces.append(np.asarray(model.mesh_face[fa: fa + nf], dtype=np.int64) + start)
        mat = int(model.geom_matid[g])
        colour = model.mat_rgba[mat][:3] if mat >= 0 else model.geom_rgba[g][:3]
        rgb.append(np.tile(np.asarray(colour, dtype=np.float64), (nf, 1)))
        start += nv
    return AssetMesh(np.concatenate(verts), np.concatenate(faces), np.concatenate(rgb))
