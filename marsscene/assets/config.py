"""Asset stage configuration (``[assets]`` table): habitats, landers and other user assets."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError

__all__ = ["ASSET_SUFFIXES", "MESH_SUFFIXES", "USD_SUFFIXES", "AssetConfig"]

#: Loaded with trimesh (mesh formats) or read by the USD export layer (pxr).
MESH_SUFFIXES = (".obj", ".glb", ".gltf", ".stl", ".ply")
USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")
ASSET_SUFFIXES = MESH_SUFFIXES + USD_SUFFIXES


@dataclass(frozen=True, slots=True, kw_only=True)
class AssetConfig:
    """Assets placed on levelled ground (lengths in m).

    Each file in ``files`` is placed at the matching ``xy_m`` point, or (without ``xy_m``) at
    the flattest suitable site of the terrain. ``habitat = true`` adds the small procedural
    habitat of :mod:`marsscene.assets.habitat` when no file is given.
    """

    files: tuple[str, ...] = ()
    """Asset files: .obj, .glb/.gltf, .stl, .ply (trimesh) or .usd/.usda/.usdc/.usdz."""
    xy_m: tuple[tuple[float, float], ...] | None = None
    """Placement points ``[[x, y], ...]`` (in m, world frame), one per asset; default: search."""
    habitat: bool = False
    """Place the procedural habitat when ``files`` is empty."""
    scale: float = 1.0
    """Scale applied to file assets (e.g. 0.01 for centimetre models)."""
    up_axis: str = "auto"
    """"auto" (Y-up for glTF, as its specification says; Z-up otherwise), "y" or "z"."""
    max_slope_deg: float = 8.0
    """Largest mean terrain slope (tilt) over a searched site's pad before levelling (in deg)."""
    margin_m: float = 1.0
    """Levelled ground beyond the asset's footprint radius (in m)."""
    blend_m: float = 5.0
    """Width of the smooth blend from the levelled pad back to the terrain (in m)."""
    keep_clear_m: float = 15.0
    """Searched sites keep this far (plus the footprint) from the origin, the rover's start."""

    def __post_init__(self) -> None:
        for f in self.files:
            if Path(f).suffix.lower() not in ASSET_SUFFIXES:
                raise ConfigError(f"assets.files: {f!r} is not a supported asset; use one of "
                                  f"{list(ASSET_SUFFIXES)}")
        if self.xy_m is not None:
            n = len(self.files) if self.files else int(self.habitat)
            if len(self.xy_m) != n or any(len(p) != 2 for p in self.xy_m):
                raise ConfigError(f"assets.xy_m = {self.xy_m!r}: need one [x, y] per asset "
                                  f"({n})")
        if not isinstance(self.habitat, bool):
            raise ConfigError(f"assets.habitat must be true or false; got {self.habitat!r}")
        check_range("assets.scale", self.scale, 0.0, 1e6, lo_open=True)
        check_choice("assets.up_axis", self.up_axis, ("auto", "y", "z"))
        check_range("assets.max_slope_deg", self.max_slope_deg, 0.0, 45.0, lo_open=True)
        check_range("assets.margin_m", self.margin_m, 0.0, 100.0)
        check_range("assets.blend_m", self.blend_m, 0.0, 500.0, lo_open=True)
        check_range("assets.keep_clear_m", self.keep_clear_m, 0.0, 10_000.0)

    @property
    def active(self) -> bool:
        """True when there is anything to place."""
        return bool(self.files) or self.habitat
