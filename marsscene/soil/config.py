"""Soil map configuration (``[soil]`` table): which soil covers the ground, crater floors,
steep slopes and seeded drift patches. Soils by name: ``marsscene.rover.terramechanics.soils``
(``marsscene/rover/data/soils.toml``, each with its source)."""

from __future__ import annotations

from dataclasses import dataclass

from marsscene._validate import check_range
from marsscene.rover.terramechanics import soil

__all__ = ["SoilConfig"]


@dataclass(frozen=True, slots=True, kw_only=True)
class SoilConfig:
    """Rules that lay soils over the terrain, in order: the ground, then drift patches, crater
    floors and steep slopes over it (lengths in m, angles in degrees)."""

    enabled: bool = False
    """Author a soil map with the scene (off: the wheels meet rigid ground unless a run picks a
    soil)."""
    ground: str = "firm_regolith"
    """The soil everywhere no rule below claims."""
    patches: str = "drift_sand"
    """The soil of seeded drift patches."""
    patch_fraction: float = 0.15
    """Share of the area in drift patches, in [0, 1]."""
    patch_m: float = 8.0
    """Typical patch size (the correlation length of the seeded field that draws them)."""
    crater_floor: str = "drift_sand"
    """The soil that fills crater floors (wind-blown fill)."""
    crater_floor_fraction: float = 0.6
    """Crater floors: within this fraction of each crater's radius, in [0, 1] (0: none)."""
    steep: str = "firm_regolith"
    """The soil of slopes steeper than ``steep_deg`` (loose sand does not rest there)."""
    steep_deg: float = 25.0
    """Slope above which ``steep`` lies, in (0, 90]."""

    def __post_init__(self) -> None:
        for key in ("ground", "patches", "crater_floor", "steep"):
            soil(getattr(self, key))  # one-line error naming the unknown soil
        check_range("soil.patch_fraction", self.patch_fraction, 0.0, 1.0)
        check_range("soil.patch_m", self.patch_m, 0.5, 1e4)
        check_range("soil.crater_floor_fraction", self.crater_floor_fraction, 0.0, 1.0)
        check_range("soil.steep_deg", self.steep_deg, 0.0, 90.0, lo_open=True)

    def names(self) -> tuple[str, ...]:
        """The soils the rules use, each once, in rule order (the map's indices)."""
        out: list[str] = []
        for name, used in ((self.ground, True), (self.patches, self.patch_fraction > 0),
                           (self.crater_floor, self.crater_floor_fraction > 0),
                           (self.steep, True)):
            if used and name not in out:
                out.append(name)
        return tuple(out)
