"""Is the landmark in view? The habitat's box projected into every VPR frame.

A landmark is a placed asset of the scene (``habitat``): its MJCF part geoms
(``asset_<name>_<i>``, convex meshes) in the world. A part is in a frame when all its
vertices lie in front of the camera and the box around their projection overlaps the image;
the landmark is in view when a part is and the line of sight from the camera to the top centre
of the landmark's box clears the terrain (48 samples along it against the heightfield). The
measure is the smaller side (px) of the box around the parts in view, clipped to the image: a
sliver at the image's edge counts for its width, a distant habitat for its height; 0 when none
is in view. The camera draws the scene's meshes only inside its terrain window (it hides
those centred outside, which would float in the sky): with the frames' window bounds given,
a part outside them is not in view.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError
from marsscene.terrain.heightfield import Heightfield

__all__ = ["Landmark", "landmark_parts", "landmark_pixels"]

_NEAR_M = 0.5
_SIGHT_SAMPLES = 48


class Landmark:
    """An asset's parts in the world: vertices (m) of each convex part, and their box."""

    def __init__(self, parts: list[NDArray[np.float64]],
                 centres: NDArray[np.float64] | None = None) -> None:
        self.parts = parts
        #: each part's geom centre (m), where the camera decides whether to draw it
        self.centres = (np.asarray(centres, dtype=np.float64) if centres is not None
                        else np.array([p.mean(axis=0) for p in parts]))
        every = np.concatenate(parts)
        self.box = np.stack([every.min(axis=0), every.max(axis=0)])


def landmark_parts(scene_dir: str | Path, name: str) -> tuple[Landmark, Heightfield]:
    """The parts of asset ``name`` (its ``asset_<name>_<i>`` mesh geoms) and the terrain."""
    import mujoco

    from marsscene.sim.rover_sim import load_scene_spec
    from marsscene.sim.terrain import scene_heightfield

    spec, xml, _ = load_scene_spec(scene_dir)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    parts, centres = [], []
    for g in range(model.ngeom):
        if not (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g) or "").startswith(
                f"asset_{name}_"):
            continue
        mid = int(model.geom_dataid[g])
        if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH and mid >= 0:
            a, n = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
            local = model.mesh_vert[a : a + n].astype(np.float64)
        else:  # a primitive: its bounding box corners
            c, h = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
            local = c + h * np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1)
                                      for k in (-1, 1)], dtype=np.float64)
        rot = data.geom_xmat[g].reshape(3, 3)
        parts.append(local @ rot.T + data.geom_xpos[g])
        centres.append(np.array(data.geom_xpos[g], dtype=np.float64))
    if not parts:
        raise RuntimeSimError(f"{xml}: no geoms of an asset {name!r} (asset_{name}_*); the VPR "
                              "landmark must be a placed asset of the scene")
    return Landmark(parts, np.array(centres)), scene_heightfield(model)


def landmark_pixels(landmark: Landmark, cam_xyz_m: NDArray[np.float64],
                    cam_quat_xyzw: NDArray[np.float64], intrinsics: dict[str, Any],
                    heightfield: Heightfield,
                    drawn_xy_m: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """Size (px) of the landmark in each frame: the smaller side of the box around its parts
    in view, clipped to the image (0: not in view).

    Parameters
    ----------
    landmark : Landmark
    cam_xyz_m, cam_quat_xyzw : ndarray of shape (N, 3), (N, 4)
        The camera's optical frame (x right, y down, z forward) in the world.
    intrinsics : dict
        ``width``, ``height``, ``fx``, ``fy``, ``cx``, ``cy`` (px).
    heightfield : Heightfield
        Terrain that may hide the landmark.
    drawn_xy_m : ndarray of shape (N, 4), optional
        Each frame's terrain window ``(x0, y0, x1, y1)``
        (:func:`marsscene.sensors.camera_ground.far_window_bounds`): parts centred outside it
        are not drawn. Default: every part is drawn.
    """
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_quat(cam_quat_xyzw).as_matrix()  # (N, 3, 3): camera to world
    w, h = float(intrinsics["width"]), float(intrinsics["height"])
    n = len(cam_xyz_m)
    lo, hi = np.full((n, 2), np.inf), np.full((n, 2), -np.inf)
    for k, verts in enumerate(landmark.parts):
        drawn = np.ones(n, dtype=bool)
        if drawn_xy_m is not None:
            c = landmark.centres[k]
            b = np.asarray(drawn_xy_m, dtype=np.float64)
            drawn = (b[:, 0] <= c[0]) & (c[0] <= b[:, 2]) & (b[:, 1] <= c[1]) & (c[1] <= b[:, 3])
        rel = verts[None, :, :] - cam_xyz_m[:, None, :]
        pc = np.einsum("nji,nkj->nki", rot, rel)  # vertices in the camera frame (N, V, 3)
        front = (pc[..., 2] > _NEAR_M).all(axis=1)
        z = np.where(pc[..., 2] > _NEAR_M, pc[..., 2], 1.0)
        u = intrinsics["fx"] * pc[..., 0] / z + intrinsics["cx"]
        v = intrinsics["fy"] * pc[..., 1] / z + intrinsics["cy"]
        u0, u1 = np.clip(u.min(axis=1), 0, w), np.clip(u.max(axis=1), 0, w)
        v0, v1 = np.clip(v.min(axis=1), 0, h), np.clip(v.max(axis=1), 0, h)
        inside = (drawn & front & (u1 > u0) & (v1 > v0))[:, None]
        lo = np.where(inside, np.minimum(lo, np.stack([u0, v0], 1)), lo)
        hi = np.where(inside, np.maximum(hi, np.stack([u1, v1], 1)), hi)
    box = landmark.box
    top = np.array([box[:, 0].mean(), box[:, 1].mean(), box[1, 2]])
    t = np.linspace(0.02, 0.98, _SIGHT_SAMPLES)[None, :, None]
    line = cam_xyz_m[:, None, :] + t * (top - cam_xyz_m)[:, None, :]
    ground = heightfield.sample(line[..., 0], line[..., 1])
    clear = (ground < line[..., 2]).all(axis=1)
    size = np.where(np.isfinite(lo[:, 0]), (hi - lo).min(axis=1), 0.0)
    return np.where(clear, size, 0.0)
