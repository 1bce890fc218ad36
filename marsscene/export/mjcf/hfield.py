"""Terrain as a MuJoCo ``hfield`` with a binary ``.bin`` asset.

MuJoCo's custom binary hfield file is ``int32 nrow, int32 ncol`` followed by ``nrow*ncol``
float32 elevations, row-major, **row 0 at -y** (the same order as :class:`Heightfield`; PNG
hfields are flipped and cut to 8 bits, so they are not used). MuJoCo rescales the data to
``[0, 1]`` and multiplies by ``size[2]``; the geom is placed at ``z = z_min`` so world heights
match the USD terrain exactly at the posts.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from marsscene.terrain.heightfield import Heightfield

__all__ = ["HfieldSpec", "hfield_spec"]


class HfieldSpec:
    """``size`` and ``pos`` attributes and the ``.bin`` bytes of one hfield."""

    def __init__(self, hf: Heightfield) -> None:
        z_min = float(hf.z_m.min())
        z_range = float(float(hf.z_m.max()) - z_min)
        self.elevation_range_m = max(z_range, 1e-3)
        self.z_min_m = z_min
        width, height = hf.size_m
        self.radius_xy_m = (width / 2.0, height / 2.0)
        x0, y0, x1, y1 = hf.bounds_xy_m
        self.center_xy_m = ((x0 + x1) / 2.0, (y0 + y1) / 2.0)
        #: Thickness of the solid box under the lowest post (in m).
        self.base_m = max(0.1 * self.elevation_range_m, 1.0)
        self._hf = hf

    @cached_property
    def bin_bytes(self) -> bytes:
        """The ``.bin`` asset (made on first use: the extent alone needs only min and max)."""
        rows, cols = self._hf.shape
        # (z - z_min) / range in float64, rounded to float32, a block of rows at a time (no
        # float64 copy of the whole grid; same values)
        norm = np.zeros((rows, cols), dtype="<f4")
        step = max(1, (1 << 16) // cols)
        for r in range(0, rows, step):
            block = self._hf.z_m[r:r + step].astype(np.float64)
            block -= self.z_min_m
            block /= self.elevation_range_m
            norm[r:r + step] = block
        header = np.array([rows, cols], dtype="<i4").tobytes()
        return header + norm.tobytes()

    @property
    def size(self) -> tuple[float, float, float, float]:
        return (*self.radius_xy_m, self.elevation_range_m, self.base_m)

    @property
    def pos(self) -> tuple[float, float, float]:
        return (*self.center_xy_m, self.z_min_m)


def hfield_spec(hf: Heightfield) -> HfieldSpec:
    """Compute the hfield attributes and asset for a heightfield."""
    return HfieldSpec(hf)
