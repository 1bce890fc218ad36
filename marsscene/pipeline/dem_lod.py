"""Level-of-detail terrain over a whole DTM without reading it whole at full resolution.

With ``terrain.lod`` and a ``terrain.post_m`` that is a whole multiple (>= 2) of the DTM's posts,
the terrain stage reads

* the **outer level** averaged to ``post_m``, strip by strip
  (:func:`marsscene.dem.decimate.read_dem_averaged`: memory bounded by a strip and the output),
* the **focus window** (the focus square plus a margin for the cubic and the craters' halos) at
  the DTM's own posts, by one rasterio window read,

so a 6 x 20 km HiRISE DTM at 1 m (120 M posts) becomes a 4 m outer level (7.5 M posts) and a
1 km window, never a 120 M-post array. The outer level defines the scene frame (centre, datum);
the window is placed in it by its projected coordinates and shares its datum and vertical scale.
Otherwise (a DEM object passed in, ``detrend``, posts that do not divide) the terrain stage reads
the crop at its posts as before.

:func:`resolve_dem_lod` decides, from the DEM's header alone (no pixel read), whether a DEM scene
gets two levels: with ``terrain.lod = "auto"`` a crop whose one grid would be refused (more than
``MAX_POSTS`` posts, or over ``terrain.max_memory_gb``) gets the DEM averaged to the smallest
whole multiple of its posts that keeps the outer level under the auto budget, and a focus square
at the DEM's posts (or at a finer ``post_m`` that divides them).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from marsscene.config import SceneConfig
from marsscene.dem.model import DEM
from marsscene.errors import MemoryBudgetError
from marsscene.terrain.from_dem import GeoFrame, fill_nearest, plan_crop, prepare_dem
from marsscene.terrain.heightfield import Heightfield
from marsscene.terrain.lod import FocusPlan

__all__ = ["AveragedDEM", "LodBudget", "read_averaged_outer", "resolve_dem_lod"]


@dataclass(frozen=True, eq=False)
class AveragedDEM:
    """The outer level read averaged, and how to read the focus window later."""

    dem: DEM
    inputs: dict[str, str]
    path: Path
    factor: int

    def base_reader(self, config: SceneConfig, frame: GeoFrame
                    ) -> Callable[[FocusPlan], Heightfield]:
        """A function that reads the focus window of ``plan`` at the DTM's posts, in the scene
        frame of the outer level."""
        return lambda plan: _read_focus_window(self, config, frame, plan)


def read_averaged_outer(config: SceneConfig) -> AveragedDEM | None:
    """The outer level of a level-of-detail DTM scene read averaged, or ``None`` when the
    streamed path does not apply (see the module docstring)."""
    from marsscene.dem.decimate import read_dem_averaged
    from marsscene.dem.io import open_source
    from marsscene.terrain.default import default_dem_path

    tcfg = config.terrain
    if not tcfg.lod or tcfg.source == "procedural" or tcfg.post_m is None or tcfg.detrend:
        return None
    path = Path(default_dem_path() if tcfg.source == "default" else str(tcfg.dem_path))
    info = open_source(path)
    native = abs(float(info.transform[0]))
    factor = round(tcfg.post_m / native)
    k = native / tcfg.focus_post_m
    if (factor < 2 or abs(factor * native - tcfg.post_m) > 1e-6 * tcfg.post_m
            or abs(k - round(k)) > 1e-6 or abs(abs(float(info.transform[4])) - native) > 1e-9):
        return None
    spec = plan_crop(tcfg, info.transform, info.shape, default_post_m=tcfg.post_m)
    dem = read_dem_averaged(path, factor=factor, band=tcfg.band, crop=spec)
    inputs = {"dem": str(path)} | ({"ortho": tcfg.ortho_path} if tcfg.ortho_path else {})
    return AveragedDEM(dem, inputs, path, factor)


@dataclass(frozen=True)
class LodBudget:
    """The post budgets :func:`resolve_dem_lod` works to (passed in by
    :func:`marsscene.pipeline.terrain.resolve_lod`, which owns them)."""

    max_posts: int
    """Most posts of one grid (:data:`marsscene.terrain.synth.MAX_POSTS`)."""
    outer_posts: int
    """Posts an automatic outer level stays within."""
    focus_posts_per_side: int
    """Largest side of an automatic focus square (in posts)."""


@dataclass(frozen=True)
class _CropGrid:
    """The crop a DEM scene reads, from the DEM's header: its posts and what it would cost as
    one grid."""

    what: str
    rows: int
    cols: int
    post_xy_m: tuple[float, float]
    target_m: float
    from_file: bool  # read_dem checks the memory budget; a DEM object is already read

    @property
    def native_m(self) -> float:
        return self.post_xy_m[0]

    @property
    def size_m(self) -> tuple[float, float]:
        return ((self.cols - 1) * self.post_xy_m[0], (self.rows - 1) * self.post_xy_m[1])

    def posts_at(self, post_m: float) -> int:
        """Posts of the crop resampled to ``post_m`` (outer post centres kept)."""
        if abs(post_m - self.native_m) <= 1e-9 * post_m:
            return self.rows * self.cols
        w, h = self.size_m
        return (round(h / post_m) + 1) * (round(w / post_m) + 1)

    def over(self, post_m: float, max_posts: int, max_memory_gb: float) -> str | None:
        """Why one grid at ``post_m`` would be refused, or ``None`` when it would not."""
        from marsscene.dem.ops import estimate_bytes

        posts, n = self.posts_at(post_m), self.rows * self.cols
        if posts > max_posts:
            return f"would hold {posts:,} posts (limit {max_posts:,})"
        need = estimate_bytes(n, int(n * (self.native_m / post_m) ** 2))
        if self.from_file and need > max_memory_gb * 1e9:
            return (f"would need about {need / 1e9:.2g} GB "
                    f"(terrain.max_memory_gb = {max_memory_gb:g})")
        return None


def _crop_grid(config: SceneConfig, dem: DEM | None) -> _CropGrid | None:
    """The crop :func:`marsscene.pipeline.inputs.load_inputs` will read, planned the same way
    from the header (a DEM object: from its array's shape); ``None`` for a CRS the read
    refuses (it says why)."""
    from marsscene.dem.crs import is_projected_metres
    from marsscene.dem.ops import crop_window
    from marsscene.errors import MarsSceneWarning
    from marsscene.terrain.default import default_dem_path

    tcfg = config.terrain
    default_post = 0.25 if tcfg.source == "default" else None
    if dem is not None:
        transform, shape, crs = dem.transform, dem.shape, dem.crs_wkt
        name = Path(str(dem.source_path)).name if dem.source_path else "the DEM"
        crop_post = None
    else:
        from marsscene.dem.io import open_source

        info = open_source(default_dem_path() if tcfg.source == "default"
                           else str(tcfg.dem_path))
        transform, shape, crs = info.transform, info.shape, info.crs_wkt
        name, crop_post = Path(info.source_path).name, default_post
    if crs and not is_projected_metres(crs):
        return None
    with warnings.catch_warnings():  # the read plans the same crop again, and warns then
        warnings.simplefilter("ignore", MarsSceneWarning)
        spec = plan_crop(tcfg, transform, shape, default_post_m=crop_post)
        win = crop_window(transform, shape, crs, spec) if spec is not None else None
    rows, cols = (win.rows, win.cols) if win is not None else shape
    post_xy = (abs(float(transform[0])), abs(float(transform[4])))
    w, h = (cols - 1) * post_xy[0], (rows - 1) * post_xy[1]
    what = (f"the whole {w:g} x {h:g} m DEM {name}" if spec is None
            else f"the {w:g} x {h:g} m crop of {name}")
    target = tcfg.post_m if tcfg.post_m is not None else (default_post or post_xy[0])
    return _CropGrid(what, rows, cols, post_xy, target, dem is None)


def _outer_factor(rows: int, cols: int, outer_posts: int) -> int:
    """The smallest whole factor >= 2 whose averaged grid (every k-th post) holds at most
    ``outer_posts`` posts."""
    k = max(2, math.isqrt(rows * cols // max(outer_posts, 1)))  # no smaller k can do
    while ((rows - 1) // k + 1) * ((cols - 1) // k + 1) > outer_posts:
        k += 1
    return k


def resolve_dem_lod(config: SceneConfig, dem: DEM | None, budget: LodBudget
                    ) -> tuple[SceneConfig, str | None]:
    """``terrain.lod`` of a DEM scene decided from the DEM's header (no pixel is read), and the
    note saying what was chosen.

    * ``"auto"``: one grid, unless the crop at the target posts (``post_m``, else the DEM's)
      would be refused as one (more than ``budget.max_posts`` posts, or, for a file, over
      ``terrain.max_memory_gb``); then two levels: the DEM averaged to the smallest whole
      multiple of its posts that keeps the outer level within ``budget.outer_posts``, and a
      focus square (``focus_size_m``, at most ``budget.focus_posts_per_side`` posts a side) at
      the DEM's posts, or at ``post_m`` where that is finer and divides them. A ``post_m``
      finer than the DEM on a crop that fits at the DEM's own posts keeps one grid (and its
      refusal): the crop is not too large, the request is.
    * ``true`` without ``post_m``: the outer level is the DEM's posts, unless that grid would be
      refused: then the DEM averaged as above (the focus as configured).
    * ``false``: a grid of more than ``budget.max_posts`` posts is refused here, naming the
      options that would work (a crop over the memory budget is refused by the read).
    """
    tcfg = config.terrain
    if tcfg.lod is True and tcfg.post_m is not None:
        return config, None
    grid = _crop_grid(config, dem)
    if grid is None:
        return config.replace(terrain=dataclasses.replace(
            tcfg, lod=False if tcfg.lod == "auto" else tcfg.lod)), None
    native, (w, h) = grid.native_m, grid.size_m
    square = abs(grid.post_xy_m[1] - native) <= 1e-9 * native
    if tcfg.lod is True:
        reason = grid.over(native, budget.max_posts, tcfg.max_memory_gb)
        if reason is None or not square:
            return config, None
        outer = _outer_factor(grid.rows, grid.cols, budget.outer_posts) * native
        note = (f"terrain: the outer level, {grid.what} at the DEM's {native:g} m posts, "
                f"{reason}, so it is the DEM averaged to {outer:g} m posts (the smallest whole "
                f"multiple within {budget.outer_posts:,} posts; --post-m sets it)")
        return config.replace(terrain=dataclasses.replace(tcfg, post_m=outer)), note
    target = grid.target_m
    if tcfg.lod is False:
        posts = grid.posts_at(target)
        if posts > budget.max_posts:
            raise MemoryBudgetError(
                f"{grid.what} at {target:g} m posts would hold {posts:,} posts as one grid "
                f"(limit {budget.max_posts:,}; terrain.lod = false, --no-lod): leave out "
                '--no-lod (terrain.lod = "auto" builds it with two levels) or give --lod '
                "(with --focus-size-m, --focus-xy), raise --post-m, or crop smaller "
                "(--size-m, --crop-lonlat, --crop-px)")
        return config, None
    reason = grid.over(target, budget.max_posts, tcfg.max_memory_gb)
    upsampled = target < native * (1 - 1e-9)  # a crop that fits at the DEM's posts: one grid
    if (reason is None or not square
            or (upsampled and grid.over(native, budget.max_posts, tcfg.max_memory_gb) is None)):
        return config.replace(terrain=dataclasses.replace(tcfg, lod=False)), None
    ratio = native / target
    focus_post = target if ratio > 1 + 1e-9 and abs(ratio - round(ratio)) <= 1e-6 else native
    outer = _outer_factor(grid.rows, grid.cols, budget.outer_posts) * native
    side_posts = min(budget.focus_posts_per_side, math.isqrt(budget.max_posts) - 1)
    focus = min(tcfg.focus_size_m, w, h, side_posts * focus_post)
    focus = max(1, math.floor(focus / outer + 1e-9)) * outer  # whole outer cells: posts kept
    lod = dataclasses.replace(tcfg, lod=True, post_m=outer, focus_post_m=focus_post,
                              focus_size_m=focus)
    fine = ("the DEM's posts" if focus_post == native
            else f"the DEM's {native:g} m posts with seeded detail")
    size = f" --focus-size-m {focus:g}" if focus != tcfg.focus_size_m else ""
    where = (f"the central {focus:g} m square" if tcfg.focus_xy_m is None
             else "the {:g} m square centred at ({:g}, {:g}) m".format(focus, *tcfg.focus_xy_m))
    note = (f"terrain: {grid.what} at {target:g} m posts {reason}, so the terrain has two "
            f'levels (terrain.lod = "auto"): {focus_post:g} m posts ({fine}) in {where} '
            f"(move it with --focus-xy X Y{size} --focus-post-m {focus_post:g}), "
            f"the DEM averaged to {outer:g} m outside; --no-lod insists on one grid")
    return config.replace(terrain=lod), note


def _margin_m(config: SceneConfig, native_post_m: float) -> float:
    """The focus window's margin: the widest crater's reach (its halo) and 4 posts."""
    ccfg = config.craters
    reach = (ccfg.ejecta_reach * ccfg.d_max_m / 2.0 / np.sqrt(ccfg.axis_ratio_min)
             if ccfg.enabled else 0.0)
    return float(reach) + 4.0 * native_post_m


def _read_focus_window(src: AveragedDEM, config: SceneConfig, frame: GeoFrame,
                       plan: FocusPlan) -> Heightfield:
    from marsscene.dem.io import read_dem
    from marsscene.dem.ops import Crop

    tcfg = config.terrain
    native = src.dem.post_m / src.factor
    margin = _margin_m(config, native)
    ox, oy = frame.origin_projected_xy_m or (0.0, 0.0)
    x0, y0, x1, y1 = plan.bounds_xy_m
    bounds = (x0 - margin + ox, y0 - margin + oy, x1 + margin + ox, y1 + margin + oy)
    window = read_dem(src.path, band=tcfg.band, crop=Crop(bounds_xy_m=bounds))
    window, _, _, _ = prepare_dem(window, dataclasses.replace(tcfg, post_m=None),
                                  default_post_m=None)
    z = fill_nearest(window.elevation_m.astype(np.float64))  # as heightfield_from_dem does
    a, _, c, _, e, f = window.transform
    rows = z.shape[0]
    # south-west post centre, in the scene frame of the outer level
    sw = (c + 0.5 * a - ox, f + e * (rows - 0.5) - oy)
    z_scene = ((z - frame.datum_m) * frame.z_scale)[::-1, :]
    return Heightfield(z_scene.astype(np.float32), abs(a), sw)
