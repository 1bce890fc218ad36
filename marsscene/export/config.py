"""Export configuration (``[export]`` table).

The smallest contact rock is the rock layer's fact (:mod:`marsscene.rocks.config`, which the
MJCF rock rule also defaults to); the exporters' defaults use it.
"""

from __future__ import annotations

from dataclasses import dataclass

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError
from marsscene.rocks.config import CONTACT_MIN_DIAMETER_M

__all__ = ["CONTACT_MIN_DIAMETER_M", "EXPORT_FORMATS", "OBSTACLE_MIN_DIAMETER_M",
           "ROCK_CATALOGUES", "USD_FORMATS", "ExportConfig"]

EXPORT_FORMATS = ("usd", "mjcf")
USD_FORMATS = ("usda", "usdc", "usdz")
ROCK_CATALOGUES = ("csv", "parquet", "both")
#: Rocks at least this wide are obstacles (m): about 0.25 m tall, as tall as the wheel radius,
#: a step the rocker-bogie climbs rather than rolls over; USD gives each its own collider prim.
OBSTACLE_MIN_DIAMETER_M = 0.5


@dataclass(frozen=True, slots=True, kw_only=True)
class ExportConfig:
    """What to write and how."""

    formats: tuple[str, ...] = ("usd", "mjcf")
    """Outputs to write: any of "usd", "mjcf"."""
    usd_format: str = "usda"
    """Root USD layer encoding: "usda" (text), "usdc" (binary crate) or "usdz" (package)."""
    max_tile_posts: int = 513
    """Largest terrain mesh tile, in posts per side (bounds the vertex count per USD prim)."""
    rock_catalogue: str = "csv"
    """Rock catalogue file(s): "csv" (``rocks.csv``), "parquet" (``rocks.parquet``, needs
    pyarrow: extra ``parquet``) or "both"."""
    rover: bool = False
    """Place the USD rover (``assets/rover.usda``, always written with USD) in the scene as
    ``/World/Rover``, at the MuJoCo runtime's spawn pose."""
    rover_xy_m: tuple[float, float] | None = None
    """Where to place it (m, world frame); default: the terrain centre, as the runtime."""
    rover_yaw_deg: float = 0.0
    """Its heading (deg, counter-clockwise from east)."""
    rock_collider_min_diameter_m: float = CONTACT_MIN_DIAMETER_M
    """Rocks at least this wide are colliders under ``/World/RockColliders`` (m), as in the
    MJCF; the smaller ones are rendered only. 0: every rock."""
    rock_instance_min_diameter_m: float = OBSTACLE_MIN_DIAMETER_M
    """Colliders of rocks at least this wide are one native instance prim each (m); the
    smaller colliders are merged into one static mesh per 64 m tile. 0: one prim per collider
    (about 80 us a rock to write: a minute for 10^6 rocks)."""

    def __post_init__(self) -> None:
        if isinstance(self.formats, str) or not self.formats:
            raise ConfigError(f"export.formats must be a non-empty list; got {self.formats!r}")
        for f in self.formats:
            check_choice("export.formats", f, EXPORT_FORMATS)
        check_choice("export.usd_format", self.usd_format, USD_FORMATS)
        check_choice("export.rock_catalogue", self.rock_catalogue, ROCK_CATALOGUES)
        check_range("export.max_tile_posts", self.max_tile_posts, 2, 4097)
        if not isinstance(self.rover, bool):
            raise ConfigError(f"export.rover must be true or false; got {self.rover!r}")
        if self.rover_xy_m is not None:
            xy = tuple(self.rover_xy_m)
            if len(xy) != 2:
                raise ConfigError(f"export.rover_xy_m = {self.rover_xy_m!r} must be [x, y] (m)")
            for i, v in enumerate(xy):
                check_range(f"export.rover_xy_m[{i}]", v, -1e7, 1e7)
            object.__setattr__(self, "rover_xy_m", (float(xy[0]), float(xy[1])))
        check_range("export.rover_yaw_deg", self.rover_yaw_deg, -360.0, 360.0)
        check_range("export.rock_collider_min_diameter_m", self.rock_collider_min_diameter_m,
                    0.0, 1e4)
        check_range("export.rock_instance_min_diameter_m", self.rock_instance_min_diameter_m,
                    0.0, 1e4)
