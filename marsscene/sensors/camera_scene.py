"""What the mast camera reads from a scene folder: lighting, seed, large-scale albedo field."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["scene_albedo_field", "scene_lighting", "scene_seed"]


def scene_lighting(
    scene_dir: Path,
    *,
    tau: float | None = None,
    sun_elevation_deg: float | None = None,
    sun_azimuth_deg: float | None = None,
) -> Any:
    """The scene's :class:`~marsscene.lighting.Lighting` from its manifest, with overrides."""
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
    config = dataclass_from_mapping(LightingConfig, cfg, "lighting")
    return compute_lighting(config, lat_deg=0.0, lon_east_deg=0.0,
                            grid_convergence_deg=float(summary.get("grid_convergence_deg", 0.0)))


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
