"""``manifest.json``: seed, config, hashes, models with citations, versions, timings, outputs."""

from __future__ import annotations

import hashlib
import json
import platform
from functools import lru_cache
from importlib import metadata
from pathlib import Path
from typing import Any

from marsscene._version import __version__

__all__ = ["PACKAGES", "manifest_bytes", "manifest_dict", "package_versions", "sha256_file"]

PACKAGES = ("numpy", "scipy", "rasterio", "pyproj", "trimesh", "usd-core", "mujoco",
            "manifold3d", "coacd", "pillow", "click")


def sha256_file(path: str | Path) -> str:
    """SHA-256 of a file, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def package_versions() -> dict[str, str | None]:
    """Installed versions of marsscene's dependencies (``None`` if not installed)."""
    return dict(_package_versions())


@lru_cache(maxsize=1)
def _package_versions() -> tuple[tuple[str, str | None], ...]:
    """Looked up once per process (a sweep writes many manifests)."""
    out: dict[str, str | None] = {"marsscene": __version__, "python": platform.python_version()}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = None
    return tuple(out.items())


def _input_files(paths: dict[str, str]) -> dict[str, dict[str, str]]:
    """Each input's file name and SHA-256: no absolute path, so the manifest does not depend on
    where the inputs (or the package's bundled DEM) live on disk."""
    out = {}
    for role, path in sorted(paths.items()):
        p = Path(path)
        out[role] = {"name": p.name, "sha256": sha256_file(p) if p.is_file() else ""}
    return out


def manifest_dict(
    scene: Any, outputs: list[str], *, timings_s: dict[str, float] | None = None
) -> dict[str, Any]:
    """The manifest of a written scene (``outputs`` relative to the scene folder)."""
    prov = scene.provenance
    frame = prov.frame
    hf = scene.heightfield
    return {
        "marsscene_version": __version__,
        "seed": int(scene.seed),
        "config": scene.config.to_dict(),
        "config_hash": scene.config.config_hash(),
        "inputs": _input_files(prov.inputs),
        "frame": {
            "axes": "x east, y north, z up (REP-103), metres",
            "datum_m": frame.datum_m,
            "z_scale": frame.z_scale,
            "origin_projected_xy_m": list(frame.origin_projected_xy_m)
            if frame.origin_projected_xy_m is not None else None,
            "origin_lonlat_deg": list(frame.origin_lonlat_deg)
            if frame.origin_lonlat_deg is not None else None,
            "crs_wkt": frame.crs_wkt,
        },
        "terrain": {
            "shape_rows_cols": list(hf.shape),
            "post_m": hf.cell_size_m,
            "size_m": list(hf.size_m),
            "z_min_m": float(hf.z_m.min()),
            "z_max_m": float(hf.z_m.max()),
        },
        "models": [{"stage": m.stage, "name": m.name, "citation": m.citation} for m in prov.models],
        "notes": list(prov.notes),
        "summary": prov.extra,
        "package_versions": package_versions(),
        "timings_s": timings_s if timings_s is not None else prov.timings_s,
        "outputs": sorted(outputs),
    }


def manifest_bytes(
    scene: Any, outputs: list[str], *, timings_s: dict[str, float] | None = None
) -> bytes:
    """Canonical JSON bytes of :func:`manifest_dict`."""
    doc = manifest_dict(scene, outputs, timings_s=timings_s)
    text = json.dumps(doc, indent=2, sort_keys=True, allow_nan=False)
    return (text + "\n").encode("utf-8")
