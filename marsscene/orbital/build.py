"""The orbital map of a scene: the input DTM and orthoimage of a DEM scene, or a procedural
scene's terrain seen through the orbital model (:mod:`marsscene.orbital.model`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.orbital.grid import OrbitalMap, sample_bilinear
from marsscene.orbital.model import OrbitalModel, apply_psf, correlated_noise
from marsscene.orbital.shading import lambert_mu0
from marsscene.rocks.table import RockTable
from marsscene.scene import Scene
from marsscene.seeding import stage_rng
from marsscene.terrain.heightfield import Heightfield

__all__ = ["orbital_map", "procedural_orbital_map", "raise_resolved_rocks"]


def raise_resolved_rocks(hf: Heightfield, rocks: RockTable | None, d_min_m: float
                         ) -> NDArray[np.float64]:
    """The terrain's posts with every rock of diameter ``>= d_min_m`` raised into it as a
    half-ellipsoid (radius ``D / 2``, exposed height ``height_m``); smaller rocks are left out.
    """
    z = np.asarray(hf.z_m, dtype=np.float64).copy()
    if rocks is None or len(rocks) == 0:
        return z
    keep = np.flatnonzero(rocks.diameter_m >= d_min_m)
    if keep.size == 0:
        return z
    xyz, radius = rocks.position_xyz_m[keep], 0.5 * rocks.diameter_m[keep]
    base = xyz[:, 2] + rocks.burial_m[keep]  # the local surface under the rock
    k = math.ceil(float(radius.max()) / hf.cell_size_m)
    off = np.arange(-k, k + 1)
    r_c, c_c = hf.rowcol_of(xyz[:, 0], xyz[:, 1])
    rows = np.rint(r_c).astype(np.int64)[:, None, None] + off[None, :, None]
    cols = np.rint(c_c).astype(np.int64)[:, None, None] + off[None, None, :]
    px, py = hf.xy_of(rows, cols)
    rr = np.hypot(px - xyz[:, 0, None, None], py - xyz[:, 1, None, None]) / radius[:, None, None]
    top = base[:, None, None] + rocks.height_m[keep][:, None, None] * np.sqrt(
        np.clip(1.0 - rr * rr, 0.0, None))
    n_r, n_c = hf.shape
    ok = (rr < 1.0) & (rows >= 0) & (rows < n_r) & (cols >= 0) & (cols < n_c)
    flat = (rows * n_c + cols)[ok]
    out = z.reshape(-1)
    np.maximum.at(out, flat, top[ok])
    return out.reshape(z.shape)


def _posts(lo: float, hi: float, step: float) -> NDArray[np.float64]:
    n = math.floor((hi - lo) / step + 1e-9) + 1
    return np.asarray(lo + step * np.arange(n), dtype=np.float64)


def _image(hf: Heightfield, surface_m: NDArray[np.float64], seed: int, model: OrbitalModel
           ) -> tuple[NDArray[np.float64], tuple[float, float]]:
    """The scene's albedo (HiRISE RED ~ the soil's red albedo times the seeded albedo field,
    the camera's own: ``stage_rng(seed, "albedo")``) at pixel centres over the footprint, times
    the shading of ``surface_m`` (the terrain on ``hf``'s posts, resolved rocks raised) under
    the orbiter's sun (:mod:`marsscene.orbital.shading`), through the image's PSF."""
    from marsscene.terrain.albedo_field import albedo_field
    from marsscene.terrain.appearance import AppearanceModel

    x0, y0, x1, y1 = hf.bounds_xy_m
    px = model.image_pixel_m
    xs = x0 + px * (np.arange(max(1, round((x1 - x0) / px))) + 0.5)
    ys = y0 + px * (np.arange(max(1, round((y1 - y0) / px))) + 0.5)
    gx, gy = np.meshgrid(xs, ys)
    field = albedo_field(rng=stage_rng(seed, "albedo"))
    red = AppearanceModel.default().soil_rgb[0]
    img = red * np.exp(field.log_gain(gx, gy).astype(np.float64))
    if model.image_shading == "lambert" and min(img.shape) >= 2:
        z_px = sample_bilinear(surface_m, hf.origin_xy_m, hf.cell_size_m, gx, gy)
        del gx, gy
        img *= lambert_mu0(z_px, px, model.image_sun_incidence_deg, model.image_sun_azimuth_deg)
    return apply_psf(img, px, model.image_psf_fwhm_m), (float(xs[0]), float(ys[0]))


def procedural_orbital_map(hf: Heightfield, rocks: RockTable | None, seed: int,
                           model: OrbitalModel | None = None, *, image: bool = True
                           ) -> OrbitalMap:
    """A terrain seen from orbit: resolved rocks raised in, the DTM's PSF, resampled to
    ``model.dem_post_m`` posts (bilinear) from the footprint's south-west post, correlated noise;
    and the albedo image, shaded by the same surface under the orbiter's sun
    (``model.image_shading``), through its PSF with its noise. Noise from ``stage_rng(seed,
    "orbital")``: the DTM's draws first, then the image's (both drawn whatever the sigmas)."""
    m = model if model is not None else OrbitalModel()
    surface = raise_resolved_rocks(hf, rocks, m.rock_resolved_d_m)
    z = apply_psf(surface, hf.cell_size_m, m.dem_psf_fwhm_m)
    x0, y0, x1, y1 = hf.bounds_xy_m
    xs, ys = _posts(x0, x1, m.dem_post_m), _posts(y0, y1, m.dem_post_m)
    if min(len(xs), len(ys)) < 2:
        raise ConfigError(f"the terrain ({x1 - x0:g} x {y1 - y0:g} m) is smaller than two "
                          f"orbital posts of {m.dem_post_m:g} m")
    gx, gy = np.meshgrid(xs, ys)
    dem = sample_bilinear(z, hf.origin_xy_m, hf.cell_size_m, gx, gy)
    rng = stage_rng(seed, "orbital")
    dem = dem + correlated_noise(dem.shape, m.dem_post_m, m.dem_noise_sigma_m,
                                 m.dem_noise_correlation_m, rng=rng)
    img = img0 = None
    if image:
        img, img0 = _image(hf, surface, seed, m)
        img = img * (1.0 + m.image_noise_fraction * rng.standard_normal(img.shape))
    return OrbitalMap(dem.astype(np.float32), m.dem_post_m, (float(xs[0]), float(ys[0])),
                      "procedural", m, int(seed),
                      image=None if img is None else img.astype(np.float32),
                      image_pixel_m=m.image_pixel_m if image else None,
                      image_origin_xy_m=img0)


def _dem_orbital_map(scene: Scene, hf: Heightfield, model: OrbitalModel) -> OrbitalMap:
    """The input DTM (and orthoimage) read again over the scene's footprint, at their posts."""
    from marsscene.dem.io import read_dem
    from marsscene.dem.ops import Crop
    from marsscene.terrain.from_dem import footprint_projected_m

    frame, inputs = scene.provenance.frame, scene.provenance.inputs
    bounds = footprint_projected_m(hf, frame)
    assert frame.origin_projected_xy_m is not None
    ox, oy = frame.origin_projected_xy_m
    dem = read_dem(inputs["dem"], band=scene.config.terrain.band, crop=Crop(bounds_xy_m=bounds))
    z = ((dem.elevation_m.astype(np.float64) - frame.datum_m) * frame.z_scale)[::-1]
    x_sw, y_sw = dem.xy_of(dem.shape[0] - 1, 0)
    img = img_px = img0 = None
    ortho = dem.ortho
    if inputs.get("ortho"):
        from marsscene.dem.io_ortho import read_ortho

        ortho = read_ortho(inputs["ortho"], bounds_xy_m=bounds)
    if ortho is not None:
        bands = np.asarray(ortho.image, dtype=np.float64)
        count = np.isfinite(bands).sum(axis=2)  # the bands' mean; NaN where none has data
        mean = np.nansum(bands, axis=2) / np.maximum(count, 1)
        img = np.where(count > 0, mean, np.nan)[::-1].astype(np.float32)
        img_px = ortho.pixel_m
        ix, iy = ortho.xy_of(ortho.shape[0] - 1, 0)
        img0 = (float(ix) - ox, float(iy) - oy)
    return OrbitalMap(z.astype(np.float32), dem.post_m, (float(x_sw) - ox, float(y_sw) - oy),
                      "dem", model, int(scene.seed), image=img, image_pixel_m=img_px,
                      image_origin_xy_m=img0, crs_wkt=frame.crs_wkt,
                      origin_projected_xy_m=(float(ox), float(oy)))


def orbital_map(scene: Scene, model: OrbitalModel | None = None) -> OrbitalMap:
    """The orbital map of a built scene (:class:`~marsscene.scene.Scene`).

    A DEM scene with a projected frame gets its input DTM and orthoimage (``provenance.inputs``)
    over its footprint, at their own posts and georeferencing; any other scene gets its terrain
    (the level-of-detail outer terrain where it has one: the whole footprint) and its rocks of
    ``model.rock_resolved_d_m`` and more through :func:`procedural_orbital_map`. The scene's
    heightfield never holds rocks (they are meshes), so the terrain is rock-free as it stands.
    """
    m = model if model is not None else OrbitalModel()
    hf = scene.outer.heightfield if scene.outer is not None else scene.heightfield
    frame = scene.provenance.frame
    if scene.provenance.inputs.get("dem") and frame.origin_projected_xy_m is not None:
        return _dem_orbital_map(scene, hf, m)
    return procedural_orbital_map(hf, scene.rocks, scene.seed, m)
