"""Rocks in MJCF: contact-relevant rocks as static convex mesh geoms.

Which rocks: :func:`marsscene.rocks.report.mjcf_rock_selection` (diameter >=
``mjcf_min_diameter_m``, optionally within a region, at most ``mjcf_max_rocks``, largest first).
The rule and the counts are recorded in the manifest notes.

Meshes: MuJoCo scales meshes per *asset*, so each exported rock gets its own ``<mesh>`` asset
with its own ``scale`` that references the **shared** OBJ file of its prototype's convex
collision part (``assets/rock_NN_part_M.obj``, unit frame). Files are therefore written once
per prototype part while every rock keeps its exact size and elongation. The geom ``pos`` is the
rock's base centre and ``quat`` its orientation (w, x, y, z), as in USD.

Rocks not exported are dropped, or with ``mjcf_small_rocks = "bake"`` raised into the hfield as
bumps: the nearest post rises by ``h * min(1, (pi D^2 / 4) / post^2)`` (volume-conserving
for rocks smaller than a post).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import numpy as np

from marsscene.export.mjcf.common import TORSION_ROLL_FRICTION
from marsscene.rocks.report import inside_focus, mjcf_focus, mjcf_rock_selection

__all__ = ["ROCK_FRICTION", "add_rocks", "obj_bytes"]

#: Rock friction (sliding, torsional, rolling); rubber/metal on rock ~0.8-1.0.
ROCK_FRICTION = (0.9, *TORSION_ROLL_FRICTION)


def obj_bytes(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """A minimal Wavefront OBJ (fixed float formatting: deterministic bytes)."""
    v = "".join(f"v {x:.7g} {y:.7g} {z:.7g}\n" for x, y, z in np.asarray(vertices).tolist())
    f = "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in np.asarray(faces).tolist())
    return (v + f).encode("ascii")


def add_rocks(root: ET.Element, assets: dict[str, bytes], scene: Any) -> None:
    """Add rock geoms (nothing when the stage is disabled)."""
    if scene.rocks is None:
        return
    from marsscene.export.mjcf.common import fmt

    rocks = scene.rocks
    cfg = scene.config.rocks
    protos = tuple(scene.rock_prototypes or ())
    focus = mjcf_focus(scene)  # two levels: focus rocks only
    sel = mjcf_rock_selection(rocks, cfg, within=focus)
    if cfg.mjcf_small_rocks == "bake":
        unselected = np.ones(len(rocks), dtype=bool) if focus is None else \
            inside_focus(focus, rocks.position_xyz_m[:, 0], rocks.position_xyz_m[:, 1])
        unselected[sel] = False
        _bake(root, assets, scene, np.flatnonzero(unselected))
    if len(sel) == 0 or not protos:
        return
    asset = root.find("asset")
    world = root.find("worldbody")
    assert asset is not None and world is not None
    ET.SubElement(asset, "material", name="rock", rgba="0.36 0.29 0.24 1", specular="0.1",
                  shininess="0.1")
    used = np.unique(rocks.prototype[sel])
    files = {}
    for p in used.tolist():  # a handful of prototypes
        for m, part in enumerate(protos[p].collision):
            rel = f"assets/{protos[p].name}_part_{m}.obj"
            assets[rel] = obj_bytes(part.vertices, part.faces)
            files[(p, m)] = rel
    pos = rocks.position_xyz_m[sel]
    quat = rocks.orientation_wxyz[sel]
    scale = rocks.scale_xyz_m[sel]
    proto = rocks.prototype[sel]
    friction = fmt(ROCK_FRICTION)
    # one XML element per exported rock part (bounded by mjcf_max_rocks): element creation
    # itself has no vectorised form
    for j in range(len(sel)):
        p = int(proto[j])
        s = fmt(scale[j], 6)
        for m in range(len(protos[p].collision)):
            name = f"rock_{int(sel[j])}_{m}"
            ET.SubElement(asset, "mesh", name=name, file=files[(p, m)], scale=s)
            ET.SubElement(world, "geom", name=name, type="mesh", mesh=name, pos=fmt(pos[j], 9),
                          quat=fmt(quat[j], 9), material="rock", friction=friction,
                          contype="1", conaffinity="1", condim="3")


def _bake(root: ET.Element, assets: dict[str, bytes], scene: Any, idx: np.ndarray) -> None:
    from marsscene.export.mjcf.common import HFIELD_ASSET, fmt
    from marsscene.export.mjcf.hfield import hfield_spec

    hf = scene.heightfield
    rocks = scene.rocks
    if len(idx) == 0:
        return
    r, c = hf.rowcol_of(rocks.position_xyz_m[idx, 0], rocks.position_xyz_m[idx, 1])
    rows, cols = hf.shape
    flat = (np.clip(np.rint(r), 0, rows - 1).astype(np.int64) * cols
            + np.clip(np.rint(c), 0, cols - 1).astype(np.int64))
    d = rocks.diameter_m[idx]
    bump = rocks.height_m[idx] * np.minimum(1.0, np.pi * d * d / 4.0 / hf.cell_size_m**2)
    grid = np.zeros(rows * cols)
    np.maximum.at(grid, flat, bump)
    spec = hfield_spec(hf.with_z(hf.z_m + grid.reshape(rows, cols).astype(np.float32)))
    assets[HFIELD_ASSET] = spec.bin_bytes
    hfield = root.find("asset/hfield[@name='terrain']")
    geom = root.find("worldbody/geom[@name='terrain']")
    if hfield is not None and geom is not None:
        hfield.set("size", fmt(spec.size, 9))
        geom.set("pos", fmt(spec.pos, 9))
