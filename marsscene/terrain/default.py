"""The embedded default terrain: a 1 m DEM of the Gale crater floor.

``data/gale_missionDEM.tif`` is ``prepare/base/Missions/Test/Data/missionDEM.tif`` from
NASA-AMMOS/MMGIS @ 84afaa9 (Apache-2.0; see ``data/NOTICE.md``): 348 x 337 posts at 1.0 m, Mars
2000 equidistant cylindrical (sphere R = 3396190 m), centre about 4.667 S, 137.370 E. The
elevations are NASA/JPL/University of Arizona HiRISE stereo products (public PDS archive).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["DEFAULT_DEM_CITATION", "default_dem_path"]

DEFAULT_DEM_CITATION = (
    "Gale crater 1 m DEM, missionDEM.tif from NASA-AMMOS/MMGIS (Apache-2.0), "
    "HiRISE stereo elevations courtesy NASA/JPL/University of Arizona"
)


def default_dem_path() -> Path:
    """Path of the bundled Gale crater GeoTIFF."""
    return Path(str(resources.files("marsscene.terrain") / "data" / "gale_missionDEM.tif"))
