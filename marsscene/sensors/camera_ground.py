"""The camera's ground: a near and a far terrain mesh with baked, non-repeating albedo textures.

MuJoCo's classic renderer gives a material one texture and no vertex colours, so the ground
albedo ``detail(x, y) * exp(log_gain(x, y))`` (the periodic regolith detail tile times the
large-scale field of :mod:`marsscene.terrain.albedo_field`, orthoimage included) is *baked*
into two world-anchored textures, each over its own mesh:

* **near** (``near_m``, 16 m square, full-resolution posts): placed ahead of the camera and
  re-placed when the desired square has moved by a quarter of its side; its texture has the
  detail tile's own texels (8 m / 2048 = 3.9 mm; 4096 px over 16 m at 0.25 m posts);
* **far** (the ``window_m`` window, posts every ``far_stride`` = 2, 0.5 m): texture of
  ``FAR_BLOCK`` x coarser texels (3.1 cm; the detail tile's 8 x 8 block means), re-baked with
  the window. Far posts strictly inside the near square are lowered by ``NEAR_DROP_M`` so the
  near mesh covers them (no depth fighting).

Both meshes are world-anchored: texture coordinates follow the posts, so the pattern stays
fixed to the ground as the meshes move. Textures hold ``albedo / ALBEDO_SCALE`` in 8 bits.
With terrain shadows, :meth:`GroundWindow.sunlit` multiplies a texture by the sun's
visibility for the ground's sun layer (:mod:`marsscene.sensors.camera_shadow`), and at a low
sun by the rocks' shadows too (:mod:`marsscene.sensors.rock_shadow`, on the rendered mesh's
surface).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.sensors.camera_shadow import texel_visibility
from marsscene.sensors.rock_shadow import rock_visibility
from marsscene.terrain.albedo_field import AlbedoField
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.horizon import SunShadow

__all__ = ["FAR_BLOCK", "NEAR_DROP_M", "GroundWindow", "bake_ground", "far_window_bounds",
           "next_window_origin", "window_posts"]

FAR_BLOCK = 8
NEAR_DROP_M = 0.25
_CHUNK_ROWS = 512
#: Texels per side of one terrain-shadow value (near 4 x 3.9 mm, far 2 x 3.1 cm): edges
#: sharper than the meshes' posts at a fraction of the per-texel cost.
NEAR_SHADOW_BLOCK, FAR_SHADOW_BLOCK = 4, 2


def _interp_matrix(n_out: int, n_in: int, pos: NDArray[Any]) -> NDArray[np.float32]:
    """(n_out, n_in) linear interpolation weights at fractional input positions ``pos``."""
    p = np.clip(pos, 0, n_in - 1)
    i0 = np.minimum(np.floor(p).astype(np.int64), max(n_in - 2, 0))
    f = p - i0
    w = np.zeros((n_out, n_in), dtype=np.float32)
    rows = np.arange(n_out)
    w[rows, i0] = 1 - f
    if n_in > 1:
        w[rows, i0 + 1] += f
    return w


def bake_ground(tile_u8: NDArray[np.uint8], tile_texel_m: float, field: AlbedoField, *,
                x0_m: float, y0_m: float, size_px: tuple[int, int], texel_m: float
                ) -> NDArray[np.uint8]:
    """Texture (rows, cols, 3) of ``tile * exp(field)`` over a rectangle (row 0 at ``y0_m``).

    Texel (i, j) covers ``x0 + j texel .. x0 + (j+1) texel`` (and likewise in y); it takes the
    tile texel under its centre (the tile is world-anchored: tile texel ``floor(x / tile_texel)
    mod n``) times the field, which is evaluated every 0.125 m and interpolated linearly.
    """
    rows, cols = size_px
    n = tile_u8.shape[0]
    xc = x0_m + (np.arange(cols) + 0.5) * texel_m
    yc = y0_m + (np.arange(rows) + 0.5) * texel_m
    ci = np.floor(xc / tile_texel_m + 1e-9).astype(np.int64) % n
    ri = np.floor(yc / tile_texel_m + 1e-9).astype(np.int64) % n
    step = 0.125
    gx = x0_m + np.arange(int(np.ceil(cols * texel_m / step)) + 2) * step
    gy = y0_m + np.arange(int(np.ceil(rows * texel_m / step)) + 2) * step
    gxx, gyy = np.meshgrid(gx, gy)
    gain = np.exp(field.log_gain(gxx, gyy)).astype(np.float32)
    wx = _interp_matrix(cols, len(gx), (xc - x0_m) / step)
    wy = _interp_matrix(rows, len(gy), (yc - y0_m) / step)
    gain_x = gain @ wx.T  # (len(gy), cols)
    out = np.zeros((rows, cols, 3), dtype=np.uint8)
    cols_tile = tile_u8[:, ci]  # (n, cols, 3)
    for a in range(0, rows, _CHUNK_ROWS):
        b = min(a + _CHUNK_ROWS, rows)
        g = wy[a:b] @ gain_x  # (b - a, cols)
        val = cols_tile[ri[a:b]].astype(np.float32) * g[..., None]
        np.clip(np.rint(val), 0, 255, out=val)
        out[a:b] = val.astype(np.uint8)
    return out


def shade_texture(texture: NDArray[np.uint8], factor: NDArray[np.float32], block: int
                  ) -> NDArray[np.uint8]:
    """``texture`` (rows, cols, 3) times ``factor`` (one value per ``block`` x ``block``)."""
    rows, cols, _ = texture.shape
    out = np.zeros_like(texture)
    for a in range(0, rows, _CHUNK_ROWS):
        b = min(a + _CHUNK_ROWS, rows)
        f = np.repeat(factor[a // block : (b + block - 1) // block], block, axis=0)
        f = np.repeat(f[a % block : a % block + b - a], block, axis=1)[:, :cols]
        val = texture[a:b].astype(np.float32) * f[..., None]
        np.clip(np.rint(val), 0, 255, out=val)
        out[a:b] = val.astype(np.uint8)
    return out


def _block_mean(tile_u8: NDArray[np.uint8], block: int) -> NDArray[np.uint8]:
    n = tile_u8.shape[0]
    if n % block:
        return tile_u8
    m = tile_u8.reshape(n // block, block, n // block, block, 3).astype(np.float32)
    return np.rint(m.mean(axis=(1, 3))).astype(np.uint8)


def window_posts(hf: Heightfield, window_m: float) -> tuple[int, int, int, int]:
    """The far window's size: ``(n, rows, cols, step)`` in posts (``n`` asked for, ``rows`` x
    ``cols`` drawn; the window is re-placed once the camera moved ``step`` posts)."""
    rows, cols = hf.shape
    n = int(window_m / hf.cell_size_m) // 2 * 2 + 1
    return n, min(n, rows), min(n, cols), max(n // 4, 1)


def _window_origin(hf: Heightfield, nr: int, nc: int, xy_m: tuple[float, float],
                   *, clamp: bool = True) -> tuple[int, int]:
    rows, cols = hf.shape
    r, c = hf.rowcol_of(float(xy_m[0]), float(xy_m[1]))
    r0, c0 = round(float(r)) - nr // 2, round(float(c)) - nc // 2
    if not clamp:
        return r0, c0
    return int(np.clip(r0, 0, rows - nr)), int(np.clip(c0, 0, cols - nc))


def next_window_origin(hf: Heightfield, nr: int, nc: int, step: int,
                       current: tuple[int, int] | None, xy_m: tuple[float, float]
                       ) -> tuple[int, int] | None:
    """The far window's new origin for a camera at ``xy_m``, or ``None`` to keep ``current``.

    The window is re-placed once the camera is ``step`` posts or more from the window centred
    on it along an axis whose clamped origin would change, measured before clamping to the
    heightfield: near the heightfield's edge the clamped origin moves less than the camera, and
    a rule on the clamped origin alone would leave the camera to drive out of its window. An
    axis already clamped where the camera wants it counts for nothing: driving along the edge,
    the window moves every ``step`` posts, not every post. An unchanged clamped origin is never
    re-placed."""
    target = _window_origin(hf, nr, nc, xy_m)
    if current is None:
        return target
    if target == current:
        return None
    free = _window_origin(hf, nr, nc, xy_m, clamp=False)
    moved = max(abs(f - c) for f, c, t in zip(free, current, target, strict=True) if t != c)
    return target if moved >= step else None


def far_window_bounds(hf: Heightfield, window_m: float, xy_m: NDArray[np.float64]
                      ) -> NDArray[np.float64]:
    """``(x0, y0, x1, y1)`` of the far window for each of a camera's frames rendered at the
    positions ``xy_m`` (N, 2) in turn: :meth:`GroundWindow.place`'s rule (placed at the first,
    re-placed once the camera moved ``step`` posts), so a caller can tell which of the scene's
    meshes the camera drew (those centred inside; the others it hides). A sequential rule:
    one small step per frame."""
    _, nr, nc, step = window_posts(hf, window_m)
    out = np.zeros((len(xy_m), 4), dtype=np.float64)
    origin: tuple[int, int] | None = None
    for i, xy in enumerate(np.asarray(xy_m, dtype=np.float64)):
        origin = next_window_origin(hf, nr, nc, step, origin, (xy[0], xy[1])) or origin
        assert origin is not None
        (x0, y0), (x1, y1) = hf.xy_of(*origin), hf.xy_of(origin[0] + nr - 1, origin[1] + nc - 1)
        out[i] = (min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1))
    return out


class GroundWindow:
    """Near and far terrain meshes and their baked textures (see the module doc)."""

    def __init__(self, hf: Heightfield, *, window_m: float, near_m: float, far_stride: int,
                 tile_u8: NDArray[np.uint8], tile_m: float, field: AlbedoField,
                 sun_shadow: SunShadow | None = None,
                 shadow_rocks: NDArray[np.float64] | None = None) -> None:
        self.hf = hf
        self.sun_shadow = sun_shadow  # the terrain's shadows (the sun layer); None: none
        #: rocks whose shadows are baked into the sun layer (catalogue rows); None: the map's
        self.shadow_rocks = shadow_rocks
        cell = hf.cell_size_m
        _, self.nr, self.nc, self.step = window_posts(hf, window_m)
        s = int(far_stride)
        self.s = s if s > 1 and (self.nr - 1) % s == 0 and (self.nc - 1) % s == 0 else 1
        nn = max(int(near_m / cell) // self.s * self.s, self.s) + 1
        self.nn_r, self.nn_c = min(nn, self.nr), min(nn, self.nc)
        self.near_step = max((nn - 1) // 4, 1)
        self.field = field
        self.tile = tile_u8
        self.tile_texel_m = tile_m / tile_u8.shape[0]
        # near texels: the tile's own size, rounded so a whole number fits in one post spacing
        self.q_near = max(round(cell / self.tile_texel_m), 1)
        self.tile_far = _block_mean(tile_u8, FAR_BLOCK)
        self.far_texel_m = tile_m / self.tile_far.shape[0]
        self.q_far = max(round(cell * self.s / self.far_texel_m), 1)
        self.origin: tuple[int, int] | None = None
        self.near_origin: tuple[int, int] | None = None

    # ---- sizes ------------------------------------------------------------------------------
    @property
    def far_shape(self) -> tuple[int, int]:
        return ((self.nr - 1) // self.s + 1, (self.nc - 1) // self.s + 1)

    def far_tex_px(self) -> tuple[int, int]:
        fr, fc = self.far_shape
        return ((fr - 1) * self.q_far, (fc - 1) * self.q_far)

    def near_tex_px(self) -> tuple[int, int]:
        return ((self.nn_r - 1) * self.q_near, (self.nn_c - 1) * self.q_near)

    # ---- placement --------------------------------------------------------------------------
    def near_origin_for(self, centre_xy_m: tuple[float, float], origin: tuple[int, int]
                        ) -> tuple[int, int]:
        """Near square origin (on the far grid) centred as close as possible to the point."""
        r, c = self.hf.rowcol_of(float(centre_xy_m[0]), float(centre_xy_m[1]))
        s = self.s
        out = []
        for x, o, n_win, n_near in ((r, origin[0], self.nr, self.nn_r),
                                    (c, origin[1], self.nc, self.nn_c)):
            k = round((float(x) - n_near // 2 - o) / s)
            out.append(o + s * int(np.clip(k, 0, (n_win - n_near) // s)))
        return out[0], out[1]

    def bounds_xy_m(self) -> tuple[float, float, float, float]:
        r0, c0 = self.origin if self.origin is not None else (0, 0)
        x0, y0 = self.hf.xy_of(r0, c0)
        x1, y1 = self.hf.xy_of(r0 + self.nr - 1, c0 + self.nc - 1)
        return (float(min(x0, x1)), float(min(y0, y1)), float(max(x0, x1)), float(max(y0, y1)))

    # ---- arrays -----------------------------------------------------------------------------
    def _grid(self, r0: int, c0: int, nr: int, nc: int, s: int) -> tuple[Any, Any, Any, Any]:
        hf = self.hf
        rr = np.arange(r0, r0 + nr, s)
        cc = np.arange(c0, c0 + nc, s)
        z = hf.z_m[np.ix_(rr, cc)].astype(np.float64)
        x, y = hf.xy_of(rr[:, None] + 0 * cc[None], cc[None] + 0 * rr[:, None])
        gy, gx = np.gradient(z, hf.cell_size_m * s)
        nrm = np.stack([-gx, -gy, np.ones_like(z)], axis=-1)
        nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
        return x, y, z, nrm

    def far_arrays(self) -> tuple[Any, Any, Any]:
        r0, c0 = self.origin if self.origin is not None else (0, 0)
        x, y, z, nrm = self._grid(r0, c0, self.nr, self.nc, self.s)
        if self.near_origin is not None:  # lower the far posts the near mesh covers
            nr0, nc0 = self.near_origin
            a, b = (nr0 - r0) // self.s, (nc0 - c0) // self.s
            ka, kb = (self.nn_r - 1) // self.s, (self.nn_c - 1) // self.s
            z[a + 1 : a + ka, b + 1 : b + kb] -= NEAR_DROP_M
        v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
        uv = np.stack([(x - x[0, 0]) / (x[-1, -1] - x[0, 0]),
                       (y - y[0, 0]) / (y[-1, -1] - y[0, 0])], axis=-1).reshape(-1, 2)
        return v, nrm.reshape(-1, 3), uv

    def near_arrays(self) -> tuple[Any, Any, Any]:
        r0, c0 = self.near_origin if self.near_origin is not None else (0, 0)
        x, y, z, nrm = self._grid(r0, c0, self.nn_r, self.nn_c, 1)
        v = np.stack([x, y, z], axis=-1).reshape(-1, 3)
        uv = np.stack([(x - x[0, 0]) / (x[-1, -1] - x[0, 0]),
                       (y - y[0, 0]) / (y[-1, -1] - y[0, 0])], axis=-1).reshape(-1, 2)
        return v, nrm.reshape(-1, 3), uv

    def far_texture(self) -> NDArray[np.uint8]:
        r0, c0 = self.origin if self.origin is not None else (0, 0)
        x0, y0 = self.hf.xy_of(r0, c0)
        return bake_ground(self.tile_far, self.far_texel_m, self.field, x0_m=float(x0),
                           y0_m=float(y0), size_px=self.far_tex_px(),
                           texel_m=self.hf.cell_size_m * self.s / self.q_far)

    def near_texture(self) -> NDArray[np.uint8]:
        r0, c0 = self.near_origin if self.near_origin is not None else (0, 0)
        x0, y0 = self.hf.xy_of(r0, c0)
        return bake_ground(self.tile, self.tile_texel_m, self.field, x0_m=float(x0),
                           y0_m=float(y0), size_px=self.near_tex_px(),
                           texel_m=self.hf.cell_size_m / self.q_near)

    def sunlit(self, texture: NDArray[np.uint8], *, near: bool) -> NDArray[np.uint8]:
        """The sun layer's texture: ``texture`` (:meth:`far_texture` or :meth:`near_texture`)
        times the sun's visibility (unchanged without terrain shadows)."""
        if self.sun_shadow is None:
            return texture
        origin = self.near_origin if near else self.origin
        r0, c0 = origin if origin is not None else (0, 0)
        x0, y0 = self.hf.xy_of(r0, c0)
        texel = self.hf.cell_size_m / self.q_near if near else (
            self.hf.cell_size_m * self.s / self.q_far)
        block = NEAR_SHADOW_BLOCK if near else FAR_SHADOW_BLOCK
        vis = texel_visibility(self.sun_shadow, x0_m=float(x0), y0_m=float(y0),
                               size_px=texture.shape[:2], texel_m=texel, block=block)
        if self.shadow_rocks is not None and len(self.shadow_rocks):
            n_r, n_c = vis.shape
            xc = float(x0) + (np.arange(n_c) + 0.5) * block * texel
            yc = float(y0) + (np.arange(n_r) + 0.5) * block * texel
            xy = np.stack(np.broadcast_arrays(xc[None, :], yc[:, None]), axis=-1)
            z = self.mesh_height(xy, origin=(r0, c0), stride=1 if near else self.s)
            rocks = rock_visibility(self.shadow_rocks, self.sun_shadow.sun_direction_enu, xy,
                                    z, step_m=block * texel,
                                    sun_radius_rad=self.sun_shadow.sun_radius_rad)
            vis = np.minimum(vis, rocks)
        return shade_texture(texture, vis, block)

    def mesh_height(self, xy_m: NDArray[Any], *, origin: tuple[int, int], stride: int
                    ) -> NDArray[np.float64]:
        """Height (m) of a ground mesh at points (..., 2): the posts ``stride`` apart from
        ``origin`` (row, col), two triangles per cell split along the rising diagonal as the
        meshes are (:func:`marsscene.sensors.camera_world._grid_faces`)."""
        hf = self.hf
        rows, cols = hf.shape
        r, c = hf.rowcol_of(xy_m[..., 0], xy_m[..., 1])
        fr = (np.asarray(r, dtype=np.float64) - origin[0]) / stride
        fc = (np.asarray(c, dtype=np.float64) - origin[1]) / stride
        i0 = np.clip(np.floor(fr), 0, (rows - 1 - origin[0]) // stride - 1).astype(np.int64)
        j0 = np.clip(np.floor(fc), 0, (cols - 1 - origin[1]) // stride - 1).astype(np.int64)
        a, b = np.clip(fr - i0, 0.0, 1.0), np.clip(fc - j0, 0.0, 1.0)
        rr, cc = origin[0] + i0 * stride, origin[1] + j0 * stride
        z00, z01 = hf.z_m[rr, cc], hf.z_m[rr, cc + stride]
        z10, z11 = hf.z_m[rr + stride, cc], hf.z_m[rr + stride, cc + stride]
        upper = b >= a  # the triangle (r, c), (r, c+1), (r+1, c+1)
        return np.where(upper, z00 + b * (z01 - z00) + a * (z11 - z01),
                        z00 + a * (z10 - z00) + b * (z11 - z10))

    # ---- motion -----------------------------------------------------------------------------
    def place(self, xy_m: tuple[float, float], forward_xy: tuple[float, float],
              force: bool = False) -> tuple[bool, bool]:
        """Move the window / near square for a camera at ``xy_m`` looking along ``forward_xy``.

        Returns ``(far_changed, near_changed)``: the far window moved (far texture re-baked),
        the near square moved (near mesh and texture; the far mesh's lowered posts too).
        """
        far = False
        origin = next_window_origin(self.hf, self.nr, self.nc, self.step,
                                    None if force else self.origin, xy_m)
        if origin is not None:
            self.origin, far = origin, True
        assert self.origin is not None
        f = np.asarray(forward_xy, dtype=np.float64)
        f = f / max(float(np.hypot(*f)), 1e-9)
        ahead = 0.5 * (self.nn_c - 1) * self.hf.cell_size_m - 2.0  # 2 m behind the camera
        centre = (xy_m[0] + ahead * f[0], xy_m[1] + ahead * f[1])
        near_origin = self.near_origin_for(centre, self.origin)
        near = far or self.near_origin is None or max(
            abs(near_origin[0] - self.near_origin[0]),
            abs(near_origin[1] - self.near_origin[1])) >= self.near_step
        if near:
            self.near_origin = near_origin
        return far, near
