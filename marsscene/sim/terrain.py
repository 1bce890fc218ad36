"""The terrain of a compiled MuJoCo scene as a
:class:`~marsscene.terrain.heightfield.Heightfield`."""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene.terrain.heightfield import Heightfield

__all__ = ["scene_heightfield"]


def scene_heightfield(model: Any, geom_name: str = "terrain") -> Heightfield:
    """Rebuild the terrain :class:`Heightfield` from a compiled model's hfield geom (exact)."""
    import mujoco

    gid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, geom_name)
    if gid < 0:
        from marsscene.errors import RuntimeSimError

        raise RuntimeSimError(f"the scene has no hfield geom named {geom_name!r}")
    hid = int(model.geom_dataid[gid])
    rows, cols = int(model.hfield_nrow[hid]), int(model.hfield_ncol[hid])
    adr = int(model.hfield_adr[hid])
    rx, ry, zr, _ = (float(v) for v in model.hfield_size[hid])
    px, py, pz = (float(v) for v in model.geom_pos[gid])
    z = pz + zr * model.hfield_data[adr : adr + rows * cols].reshape(rows, cols)
    return Heightfield(z.astype(np.float32), 2 * rx / (cols - 1), (px - rx, py - ry))
