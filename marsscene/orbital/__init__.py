"""The orbital map of a scene and localisation against it (pure numpy/scipy; rasterio only
through :mod:`marsscene.dem`).

* :func:`orbital_map`: a scene's orbital DTM (and orthoimage): a DEM scene's input rasters over
  its footprint, or a procedural terrain through the HiRISE-like model of
  :mod:`marsscene.orbital.model` (1 m posts, a Gaussian PSF halving 3 m relief, 0.25 m noise,
  rocks from 1 m; the image's albedo shaded under the orbiter's 15:00 sun by
  :mod:`marsscene.orbital.shading`); :func:`write_orbital_map` / :func:`read_orbital_map`:
  ``SCENE_DIR/orbital/``.
* :func:`match_dem` (``dem-correlation``): a rover's local elevation map
  (:func:`local_elevation_map` from LiDAR points, :func:`points_in_frame`) matched against the
  orbital DTM over position and heading.
"""

from marsscene.orbital.build import orbital_map, procedural_orbital_map, raise_resolved_rocks
from marsscene.orbital.grid import OrbitalMap
from marsscene.orbital.io import read_orbital_map, write_orbital_map
from marsscene.orbital.local import LocalMap, local_elevation_map, points_in_frame, pose_matrix
from marsscene.orbital.match import DemMatch, match_dem
from marsscene.orbital.model import OrbitalModel, apply_psf, fwhm_of_half_wavelength, psf_gain

__all__ = [
    "DemMatch",
    "LocalMap",
    "OrbitalMap",
    "OrbitalModel",
    "apply_psf",
    "fwhm_of_half_wavelength",
    "local_elevation_map",
    "match_dem",
    "orbital_map",
    "points_in_frame",
    "pose_matrix",
    "procedural_orbital_map",
    "psf_gain",
    "raise_resolved_rocks",
    "read_orbital_map",
    "write_orbital_map",
]
