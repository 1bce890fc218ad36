"""What the mast camera reads from a scene folder: lighting, seed, large-scale albedo field.

**Twilight.** The lighting stage's diffuse sky (Appelbaum & Flood's table) falls to 0 with the
sun on the horizon and models no twilight. Mars' twilight is long and bright: dust up to tens
of km keeps scattering sunlight (Kahn, Goody & Pollack 1981, JGR 86(A7) 5833: dust scale height
~10 km); Mars Pathfinder's imager saw the sky fade to 1 % of its brightness at sunset about an
hour (~15 deg of solar depression at its latitude) after sunset and glow for ~2 h. The camera
therefore lights the ground with the sky alone below ``TWILIGHT_ANCHOR_DEG``: the diffuse
irradiance at that elevation times ``10 ** (min(e, 0) / TWILIGHT_DECADE_DEG)`` (a decade per
7.5 deg of depression), and no direct sun below the horizon (the lighting stage's direct beam
is 0 there already). An order-of-magnitude model of the light level, not of the twilight sky's
colour or its glow around the sunset point.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["TWILIGHT_ANCHOR_DEG", "TWILIGHT_DECADE_DEG", "scaled_irradiance",
           "scene_albedo_field", "scene_lighting", "scene_seed"]

#: Below this sun elevation the sky's irradiance follows the twilight model (module doc).
TWILIGHT_ANCHOR_DEG = 1.0
#: Solar depression (deg) over which the twilight sky's irradiance falls tenfold.
TWILIGHT_DECADE_DEG = 7.5


def scene_lighting(
    scene_dir: Path,
    *,
    tau: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
) -> Any:
    """The scene's :class:`~marsscene.lighting.Lighting` from its manifest, with overrides.

    Below ``TWILIGHT_ANCHOR_DEG`` the diffuse sky follows the twilight model (module doc).
    """
    from marsscene._validate import dataclass_from_mapping
    from marsscene.lighting import LightingConfig, compute_lighting

    path = Path(scene_dir) / "manifest.json"
    doc: dict[str, Any] = {}
    if path.is_file():
        doc = json.loads(path.read_text(encoding="utf-8"))
    cfg = dict((doc.get("config") or {}).get("lighting") or {})
    summary = doc.get("summary") or {}
    cfg.pop("enabled", None)
    az = sun_azimuth_deg if sun_azimuth_deg is not None else summary.get(
        "lighting_sun_azimuth_deg", 135.0)
    el = sun_elevation_deg if sun_elevation_deg is not None else summary.get(
        "lighting_sun_elevation_deg", 35.0)
    cfg.update(utc=None, ltst_h=None, sun_azimuth_deg=float(az), sun_elevation_deg=float(el))
    if tau is not None:
        cfg["tau"] = float(tau)
    convergence = float(summary.get("grid_convergence_deg", 0.0))
    config = dataclass_from_mapping(LightingConfig, cfg, "lighting")
    lt = compute_lighting(config, lat_deg=0.0, lon_east_deg=0.0,
                          grid_convergence_deg=convergence)
    if lt.sun_elevation_deg >= TWILIGHT_ANCHOR_DEG:
        return lt
    cfg["sun_elevation_deg"] = TWILIGHT_ANCHOR_DEG
    anchor = compute_lighting(dataclass_from_mapping(LightingConfig, cfg, "lighting"),
                              lat_deg=0.0, lon_east_deg=0.0, grid_convergence_deg=convergence)
    sky = anchor.diffuse_horizontal_w_m2 * 10.0 ** (
        min(lt.sun_elevation_deg, 0.0) / TWILIGHT_DECADE_DEG)
    diffuse = max(lt.diffuse_horizontal_w_m2, sky)
    return dataclasses.replace(lt, diffuse_horizontal_w_m2=diffuse,
                               global_horizontal_w_m2=lt.direct_horizontal_w_m2 + diffuse)


def scaled_irradiance(lt: Any, scale: float) -> Any:
    """``lt`` with the sun's and the sky's irradiance times ``scale`` (directions, colours and
    the direct share, hence the shadows, unchanged)."""
    if scale == 1.0:
        return lt
    return dataclasses.replace(
        lt, direct_normal_w_m2=lt.direct_normal_w_m2 * scale,
        diffuse_horizontal_w_m2=lt.diffuse_horizontal_w_m2 * scale,
        direct_horizontal_w_m2=lt.direct_horizontal_w_m2 * scale,
        global_horizontal_w_m2=lt.global_horizontal_w_m2 * scale)


def scene_albedo_field(scene_dir: Any, heightfield: Any) -> Any:
    """The scene's large-scale albedo field (seeded), with its orthoimage if it drapes one."""
    from marsscene.seeding import stage_rng
    from marsscene.terrain.albedo_field import albedo_field, ortho_gain

    ortho = None
    from marsscene._layout import MJCF_TEXTURE_ASSET as TEXTURE_ASSET

    path = Path(scene_dir) / "mjcf" / TEXTURE_ASSET
    if path.is_file():
        from PIL import Image

        with Image.open(path) as im:
            img = np.asarray(im.convert("RGB"))
        x0, y0 = heightfield.xy_of(0, 0)
        ortho = ortho_gain(img, x0_m=float(x0), y0_m=float(y0),
                           width_m=float(heightfield.size_m[0]))
    return albedo_field(rng=stage_rng(scene_seed(scene_dir), "albedo"), ortho=ortho)


def scene_seed(scene_dir: Any) -> int:
    path = Path(scene_dir) / "manifest.json"
    if path.is_file():
        seed = json.loads(path.read_text(encoding="utf-8")).get("seed")
        if isinstance(seed, int) and seed >= 0:
            return seed
    return 0
