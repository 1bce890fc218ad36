"""Read asset files into :class:`AssetModel` (the I/O edge of the asset stage).

Mesh formats load with trimesh (a glTF scene is flattened into one mesh; its convex hull is the
collision shape). USD files are not opened here: their extent, up axis and units come from
:func:`marsscene.assets.usd.read_usd_asset` (the input side's ``pxr`` reader), and the
file is referenced from the output stage; its collision shape is its bounding box.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from marsscene.assets.config import USD_SUFFIXES, AssetConfig
from marsscene.assets.habitat import habitat_model
from marsscene.assets.model import AssetModel, normalise_parts
from marsscene.errors import ConfigError

__all__ = ["load_assets"]


def _name(path: Path, i: int, used: set[str]) -> str:
    base = re.sub(r"[^A-Za-z0-9_]", "_", path.stem) or "asset"
    if base[0].isdigit():
        base = f"asset_{base}"
    name = base if base not in used else f"{base}_{i}"
    used.add(name)
    return name


def _y_up(path: Path, cfg: AssetConfig) -> bool:
    if cfg.up_axis == "auto":
        return path.suffix.lower() in (".glb", ".gltf")
    return cfg.up_axis == "y"


def _mesh_asset(path: Path, name: str, cfg: AssetConfig) -> AssetModel:
    import trimesh  # imported on use: keeps ``import marsscene`` light

    try:
        mesh = trimesh.load(str(path), force="mesh")
    except Exception as err:  # trimesh raises many types for bad files
        raise ConfigError(f"{path}: could not read the asset ({err})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise ConfigError(f"{path}: the asset has no triangles")
    mesh = trimesh.Trimesh(mesh.vertices * cfg.scale, mesh.faces, process=False)
    if _y_up(path, cfg):  # +y up -> +z up: rotate +90 deg about x
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    return AssetModel(name=name, parts=normalise_parts([mesh]), source_path=str(path))


def _usd_asset(path: Path, name: str, cfg: AssetConfig) -> AssetModel:
    import trimesh

    from marsscene.assets.usd import read_usd_asset

    info = read_usd_asset(path)
    scale = cfg.scale * info.meters_per_unit
    lo, hi = np.asarray(info.extent_min) * scale, np.asarray(info.extent_max) * scale
    rot = 90.0 if (info.up_axis == "Y" if cfg.up_axis == "auto" else cfg.up_axis == "y") else 0.0
    if rot:  # (x, y, z) -> (x, -z, y)
        lo, hi = (np.array([lo[0], -hi[2], lo[1]]), np.array([hi[0], -lo[2], hi[1]]))
    box = trimesh.creation.box(bounds=np.stack([lo, hi]))
    offset = (float(-(lo[0] + hi[0]) / 2.0), float(-(lo[1] + hi[1]) / 2.0), float(-lo[2]))
    return AssetModel(name=name, parts=normalise_parts([box]), source_path=str(path),
                      usd_root=info.root_prim, usd_offset_m=offset,
                      usd_rotate_x_deg=rot, usd_scale=scale)


def load_assets(cfg: AssetConfig) -> list[AssetModel]:
    """The configured assets (files in order, or the procedural habitat)."""
    if not cfg.files:
        return [habitat_model()] if cfg.habitat else []
    used: set[str] = set()
    out = []
    for i, f in enumerate(cfg.files):
        path = Path(f)
        if not path.is_file():
            raise ConfigError(f"assets.files: {path} does not exist")
        name = _name(path, i, used)
        is_usd = path.suffix.lower() in USD_SUFFIXES
        out.append(_usd_asset(path, name, cfg) if is_usd else _mesh_asset(path, name, cfg))
    return out
