"""``SceneConfig``: the frozen configuration of a whole build, one table per stage.

TOML layout::

    seed = 7
    preset = "main-crater"   # optional: a reference scene expanded under the keys below
    [terrain]   source = "default" | "procedural" | "dem", dem_path, size_m, post_m, hurst, ...
    [craters]   enabled = true, ...
    [rocks]     enabled = true, ...
    [lighting]  enabled = true, ...
    [assets]    files = ["habitat.glb"], xy_m = [[x, y]], habitat = true, ...
    [soil]      enabled = false, ground = "firm_regolith", patches = "drift_sand", ...
    [export]    formats = ["usd", "mjcf"], usd_format = "usda"

Unknown keys and out-of-range values raise :class:`~marsscene.errors.ConfigError` naming the
key, the value and the allowed range.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import dataclass_from_mapping, load_toml
from marsscene.assets.config import AssetConfig
from marsscene.craters.config import CraterConfig
from marsscene.errors import ConfigError
from marsscene.export.config import ExportConfig
from marsscene.lighting.config import LightingConfig
from marsscene.presets import apply_preset
from marsscene.rocks.config import RockConfig
from marsscene.soil.config import SoilConfig
from marsscene.terrain.config import TerrainConfig

__all__ = ["SceneConfig", "read_config_toml"]


def _jsonable(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple | list):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    return value


def read_config_toml(path: str | os.PathLike[str], *, what: str = "config file") -> dict[str, Any]:
    """A TOML config as a mapping, with relative ``terrain.dem_path``, ``terrain.ortho_path``
    and ``assets.files`` resolved against the file's folder (one-line errors)."""
    p = Path(path)
    data = load_toml(p, what=what)
    terrain = data.get("terrain")
    if isinstance(terrain, dict):
        for key in ("dem_path", "ortho_path"):
            if isinstance(terrain.get(key), str) and not Path(terrain[key]).is_absolute():
                terrain[key] = str((p.parent / terrain[key]).resolve())
    assets = data.get("assets")
    if isinstance(assets, dict) and isinstance(assets.get("files"), list):
        assets["files"] = [str((p.parent / f).resolve()) if isinstance(f, str) and not
                           Path(f).is_absolute() else f for f in assets["files"]]
    return data


@dataclass(frozen=True, slots=True, kw_only=True)
class SceneConfig:
    """Configuration of a scene build (every stage's parameters; the seed is passed separately
    to :func:`marsscene.build_scene` but may also be given here as ``seed``)."""

    seed: int | None = None
    """Seed of the build when :func:`marsscene.build_scene` is not given one (default 0)."""
    preset: str | None = None
    """Reference-scene preset expanded under the other keys (see :mod:`marsscene.presets`)."""
    terrain: TerrainConfig = field(default_factory=TerrainConfig)
    """``[terrain]``: the DEM or procedural terrain (:class:`marsscene.terrain.TerrainConfig`)."""
    craters: CraterConfig = field(default_factory=CraterConfig)
    """``[craters]``: the crater population (:class:`marsscene.craters.CraterConfig`)."""
    rocks: RockConfig = field(default_factory=RockConfig)
    """``[rocks]``: the rock population (:class:`marsscene.rocks.RockConfig`)."""
    lighting: LightingConfig = field(default_factory=LightingConfig)
    """``[lighting]``: sun and sky (:class:`marsscene.lighting.LightingConfig`)."""
    export: ExportConfig = field(default_factory=ExportConfig)
    """``[export]``: output formats, USD encoding, rock catalogue format."""
    assets: AssetConfig = field(default_factory=AssetConfig)
    """``[assets]``: habitats and user assets (:class:`marsscene.assets.AssetConfig`)."""
    soil: SoilConfig = field(default_factory=SoilConfig)
    """``[soil]``: the soil map the wheels meet (:class:`marsscene.soil.SoilConfig`)."""

    def __post_init__(self) -> None:
        if self.seed is not None and (
            isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0
        ):
            raise ConfigError(f"seed = {self.seed!r}; must be a non-negative integer")

    @classmethod
    def from_dict(cls, mapping: dict[str, Any]) -> SceneConfig:
        """Build from a nested mapping (as parsed from TOML); a ``preset`` key is expanded
        underneath the mapping's own keys."""
        return dataclass_from_mapping(cls, apply_preset(mapping), "")

    @classmethod
    def from_toml(cls, path: str | os.PathLike[str], *, preset: str | None = None) -> SceneConfig:
        """Read a TOML config file; relative ``dem_path``, ``ortho_path`` and asset paths
        resolve against its folder. ``preset`` (if given) replaces the file's ``preset``."""
        data = read_config_toml(path)
        if preset is not None:
            data["preset"] = preset
        return cls.from_dict(data)

    def replace(self, **changes: Any) -> SceneConfig:
        """A copy with some top-level fields replaced (stage configs are replaced whole)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON/TOML-serialisable)."""
        out: dict[str, Any] = _jsonable(self)
        return out

    def config_hash(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`to_dict` (stable across runs)."""
        blob = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode("utf-8")).hexdigest()
