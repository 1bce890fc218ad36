"""Constants and helpers shared by the MJCF writer's modules (friction, asset names, PNG
bytes), so ``build`` and its parts import this leaf instead of each other."""

from __future__ import annotations

from typing import Any

from marsscene._format import fmt
from marsscene._layout import MJCF_HFIELD_ASSET, MJCF_TEXTURE_ASSET

__all__ = ["HFIELD_ASSET", "INTEGRATOR", "REGOLITH_FRICTION", "TEXTURE_ASSET",
           "TORSION_ROLL_FRICTION", "fmt", "png_bytes"]

#: MuJoCo's torsional and rolling friction of every contact surface the scene and the rover write
#: (MuJoCo's own defaults are 0.005 and 0.0001; these damp spinning and rolling on the hfield).
TORSION_ROLL_FRICTION = (0.02, 0.002)
#: Regolith friction (sliding, torsional, rolling). Sliding 0.8 ~ tan(38 deg), within the
#: 30-40 deg internal friction angles measured for Martian soils (Sullivan et al. 2011,
#: doi:10.1029/2010JE003625).
REGOLITH_FRICTION = (0.8, *TORSION_ROLL_FRICTION)
#: MuJoCo's integrator of every scene (stable with stiff contacts at a 2-10 ms step).
INTEGRATOR = "implicitfast"
HFIELD_ASSET = MJCF_HFIELD_ASSET
TEXTURE_ASSET = MJCF_TEXTURE_ASSET


def png_bytes(rgb: Any) -> bytes:
    """Deterministic PNG bytes of an ``(rows, cols, 3)`` uint8 image (row 0 at the top)."""
    import io

    import numpy as np
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb, dtype=np.uint8), mode="RGB").save(
        buf, format="PNG", optimize=False)
    return buf.getvalue()
