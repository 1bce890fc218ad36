"""USD export (usd-core; this subpackage is the only importer of ``pxr``).

:func:`to_stage` builds an in-memory stage plus its assets; :func:`write_usd` writes
``scene.usda|usdc|usdz`` and the assets (textures) beside it. Layout::

    /World                      default prim (Xform, kind assembly), Z-up, metres, kilograms
      /PhysicsScene             UsdPhysics.Scene, gravity 3.72 m/s^2
      /Terrain                  component; payload assets/terrain.usdc:
        /Looks/Regolith         UsdPreviewSurface (+ UsdUVTexture of the orthoimage)
        /Looks/RegolithPhysics  UsdPhysics.MaterialAPI (physics-purpose binding)
        /tile_i_j               UsdGeom.Mesh tiles with normals, st, CollisionAPI
      /TerrainLod1              level-of-detail scenes only (group; terrain_lod.py):
        /tile_i_j               component; payload assets/terrain_lod1/tile_i_j.usdc
      /Craters                  payload assets/craters.usdc (guide Points)
      /Rocks                    component; payload assets/rocks.usdc (PointInstancer, render)
      /RockColliders            component; payload assets/rock_colliders.usdc (one native
                                instance per rock: the colliders every physics loader sees)
      /Lights                   group: Sun (DistantLight), Sky (textured DomeLight)
      /Cameras                  group: Navcam (runtime mast camera), Overview
      /Rover                    with [export] rover = true: payload assets/rover.usda (always
                                written; a UsdPhysics articulation) at the runtime's spawn pose
      /Assets                   placed assets (habitat, user files), when [assets] is set

Every default-rule check of NVIDIA's Omniverse Asset Validator passes on ``.usda``, ``.usdc``
and ``.usdz`` outputs (tested).
"""

from __future__ import annotations

from concurrent.futures import Executor, Future
from pathlib import Path
from typing import Any

from marsscene.errors import missing_dependency

__all__ = ["start_textures", "to_stage", "validate_stage", "write_usd"]


def _pxr() -> None:
    try:
        import pxr  # noqa: F401
    except ImportError as err:
        raise missing_dependency("usd-core", None) from err


class _StreamedAssets(dict[str, Any]):
    """Asset files by relative path; each in-memory asset stage is exported to ``out_dir`` as
    soon as it is authored and then dropped, so a scene's tile layers (terrain tiles, rock
    payloads) never sit in memory together: the peak is one layer, not the scene."""

    def __init__(self, out_dir: Path) -> None:
        super().__init__()
        self.out_dir = out_dir

    def __setitem__(self, rel: str, blob: Any) -> None:
        p = self.out_dir / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(blob, bytes):
            p.write_bytes(blob)
        else:
            from marsscene.export.usd.stage import root_layer

            if not root_layer(blob).Export(str(p)):
                raise OSError(f"could not write {p}")
        super().__setitem__(rel, p)


def _import_authors() -> None:
    """Import every module of the USD writer, and with them every pxr module it uses.

    Call before starting a background thread: a pxr module imported while another thread runs
    numpy can deadlock (see :mod:`marsscene._threads`).
    """
    _pxr()
    from pxr import UsdUtils  # noqa: F401  (usdz packaging)

    import marsscene.export.usd.assets
    import marsscene.export.usd.cameras
    import marsscene.export.usd.craters
    import marsscene.export.usd.display
    import marsscene.export.usd.lighting
    import marsscene.export.usd.rock_colliders
    import marsscene.export.usd.rocks
    import marsscene.export.usd.rover
    import marsscene.export.usd.stage
    import marsscene.export.usd.terrain
    import marsscene.export.usd.terrain_lod
    import marsscene.export.usd.usdz  # noqa: F401


def start_textures(scene: Any, executor: Executor) -> Future[Any]:
    """Start encoding the terrain material's textures on ``executor`` (numpy and Pillow, no
    pxr); pass the future to :func:`write_usd` so other work runs meanwhile."""
    _import_authors()
    from marsscene.export.usd.appearance import regolith_textures

    return executor.submit(regolith_textures, scene)


def to_stage(scene: Any, *, stream_to: str | Path | None = None,
             textures: Future[Any] | None = None) -> tuple[Any, dict[str, Any]]:
    """Build the scene's USD stage in memory.

    Parameters
    ----------
    scene : Scene
    stream_to : path-like, optional
        Write each asset file into this folder as soon as it is authored (the returned dict
        then maps relative paths to the written paths).
    textures : Future, optional
        From :func:`start_textures`; by default the textures are made while the terrain tiles
        are authored.

    Returns
    -------
    stage : pxr.Usd.Stage
    assets : dict of str to bytes, pxr.Usd.Stage or pxr.Sdf.Layer
        Files the stage references, by path relative to the stage file: file contents, or
        in-memory asset stages (terrain, rocks, craters) and layers (rock colliders, authored
        without a stage) that :func:`write_usd` exports directly to their ``.usdc`` files (no
        serialise-read-write round trip); :func:`marsscene.export.usd.stage.root_layer` gives
        the layer of either.
    """
    _import_authors()
    from marsscene.export.usd.assets import author_assets
    from marsscene.export.usd.cameras import author_cameras
    from marsscene.export.usd.craters import author_craters
    from marsscene.export.usd.lighting import author_lighting
    from marsscene.export.usd.rock_colliders import author_rock_colliders
    from marsscene.export.usd.rocks import author_rocks
    from marsscene.export.usd.rover import author_rover
    from marsscene.export.usd.soil import author_soil
    from marsscene.export.usd.stage import create_stage
    from marsscene.export.usd.terrain import author_terrain
    from marsscene.export.usd.terrain_lod import author_outer_terrain

    stage = create_stage(scene)
    assets: dict[str, Any] = _StreamedAssets(Path(stream_to)) if stream_to is not None else {}
    author_terrain(stage, scene, assets, textures=textures)
    for author in (author_outer_terrain, author_craters, author_rocks, author_rock_colliders,
                   author_lighting, author_cameras, author_assets, author_rover, author_soil):
        author(stage, scene, assets)
    return stage, assets


def validate_stage(stage: Any) -> list[str]:
    """Run every registered ``pxr.UsdValidation`` validator; return the error messages."""
    _pxr()
    from pxr import UsdValidation

    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    return [err.GetMessage() for err in context.Validate(stage)]


def write_usd(scene: Any, out_dir: str | Path, *, usd_format: str = "usda",
              textures: Future[Any] | None = None) -> list[Path]:
    """Write ``out_dir/scene.<usd_format>`` and its assets; return the written paths.

    The USD writer of :func:`marsscene.write_scene`, which most users call instead (it writes
    atomically and adds the manifest); this one writes into ``out_dir`` as it is.

    Parameters
    ----------
    scene : Scene
        A built scene (:func:`marsscene.build_scene`).
    out_dir : path-like
        Folder to write into (created if missing).
    usd_format : {"usda", "usdc", "usdz"}
        The root layer's format.
    textures : Future, optional
        Terrain textures prepared on another thread (see :func:`to_stage`).

    Returns
    -------
    list of Path
        Every file written: the asset layers, the root layer ``scene.<usd_format>``, then its
        display-referred siblings (``scene_blender.usda``, ...); a ``.usdz`` is one file.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> import marsscene as ms
    >>> from marsscene.export.usd import write_usd
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    >>> out = Path(tempfile.mkdtemp())
    >>> paths = write_usd(ms.build_scene(cfg, seed=7), out)
    >>> out / "scene.usda" in paths
    True
    >>> from pxr import Usd, UsdGeom
    >>> stage = Usd.Stage.Open(str(out / "scene.usda"))
    >>> UsdGeom.GetStageUpAxis(stage), UsdGeom.GetStageMetersPerUnit(stage)
    ('Z', 1.0)
    """
    out = Path(out_dir)
    # asset layers go to disk one at a time
    stage, assets = to_stage(scene, stream_to=out, textures=textures)
    written = [p for _, p in sorted(assets.items())]
    layer = stage.GetRootLayer()
    if usd_format == "usdz":
        from marsscene.export.usd.usdz import package_usdz

        tmp = out / "scene.usdc"
        layer.Export(str(tmp))
        target = out / "scene.usdz"
        package_usdz(tmp, target)  # reproducible bytes: fixed zip header dates
        tmp.unlink()
        for p in written:  # packaged inside the .usdz
            p.unlink()
        for folder in sorted({p.parent for p in written}, reverse=True):
            if folder != out and not any(folder.iterdir()):
                folder.rmdir()
        written = [target]
    else:
        target = out / f"scene.{usd_format}"
        if not layer.Export(str(target)):
            raise OSError(f"could not write {target}")
        written.append(target)
        # display-referred siblings (not for .usdz, which is one self-contained file)
        from marsscene.export.usd.display import write_display_layers

        written += write_display_layers(stage, scene, out, target.name)
    return written
