"""``SweepSpec``: a SWEEP.toml parsed and checked (pure: no Dask, no disk writes).

A SWEEP.toml is a normal scene config plus two tables::

    seed = 7                         # base config, as for ``marsscene build --config``
    [terrain]
    size_m = [60.0, 60.0]
    [sweep]                          # dotted config keys (and ``seed``) -> lists of values
    seed = [1, 2]
    "lighting.tau" = [0.3, 3.0]
    [drive]                          # optional: drive and evaluate every cell
    waypoints = [[-10.0, 0.0], [10.0, 0.0]]
    seconds = 60.0

Every error is a one-line :class:`~marsscene.errors.ConfigError` naming the key and the value.
"""

from __future__ import annotations

import dataclasses
import itertools
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping
from marsscene.config import SceneConfig, read_config_toml
from marsscene.errors import ConfigError
from marsscene.rover.config import noise_profiles

__all__ = ["DriveSpec", "SweepSpec"]


@dataclass(frozen=True, kw_only=True)
class DriveSpec:
    """How every cell is driven (the ``[drive]`` table; see ``marsscene drive``)."""

    waypoints: tuple[tuple[float, float], ...] | None = None
    """Waypoints (x, y) in m; a smooth route avoiding slopes and rocks is authored through them."""
    route: str | None = None
    """A TUM route file instead of waypoints (relative paths resolve against SWEEP.toml)."""
    seconds: float | None = None
    """Sim-time limit in s (default: until the goal)."""
    camera: bool = False
    """Log the mast RGB-D camera with its defaults (:class:`~marsscene.runtime.CameraConfig`:
    640 x 480 at 10 Hz)."""
    lidar: bool = False
    """Log the LiDAR with its defaults (:class:`~marsscene.runtime.LidarConfig`: Ouster OS1-128
    at 10 Hz)."""
    noise_seed: int = 0
    """Seed of the sensor-noise stream (the same in every cell unless swept)."""
    noise_profile: str = "none"
    """IMU and wheel-odometry noise profile (:class:`~marsscene.runtime.NoiseConfig`):
    ``"none"`` (noise-free, as ``marsscene drive``), ``"ln200s"`` (the benchmarks' default) or
    ``"adis16495"``."""
    lookahead_m: float = 1.0
    """Pure-pursuit lookahead."""
    max_slope_deg: float = 20.0
    """Route authoring: steepest slope allowed."""
    corridor_m: float = 15.0
    """Only MJCF rocks within this distance of the route are simulated."""
    bag: bool = False
    """Also write the drive as a ROS 2 bag (``drive/bag``, MCAP; see ``marsscene bag``)."""

    def __post_init__(self) -> None:
        if (self.waypoints is None) == (self.route is None):
            raise ConfigError("[drive] needs exactly one of waypoints or route")
        if self.waypoints is not None:
            pts = self.waypoints
            ok = len(pts) >= 2 and all(
                len(p) == 2 and all(isinstance(v, int | float) for v in p) for p in pts
            )
            if not ok:
                raise ConfigError(
                    f"drive.waypoints = {list(pts)!r}; need at least 2 [x, y] pairs in m"
                )
            object.__setattr__(
                self, "waypoints", tuple((float(p[0]), float(p[1])) for p in pts)
            )
        if self.seconds is not None:
            check_range("drive.seconds", self.seconds, 0.0, 1e6, lo_open=True)
        if isinstance(self.noise_seed, bool) or not isinstance(self.noise_seed, int):
            raise ConfigError(f"drive.noise_seed = {self.noise_seed!r}; must be an integer >= 0")
        check_range("drive.noise_seed", self.noise_seed, 0)
        check_range("drive.lookahead_m", self.lookahead_m, 0.05, 100.0)
        check_range("drive.max_slope_deg", self.max_slope_deg, 0.0, 90.0, lo_open=True)
        check_range("drive.corridor_m", self.corridor_m, 1.0, 1e4)
        for key in ("camera", "lidar", "bag"):
            if not isinstance(getattr(self, key), bool):
                raise ConfigError(f"drive.{key} = {getattr(self, key)!r}; must be true or false")
        profiles = noise_profiles()
        if not isinstance(self.noise_profile, str) or self.noise_profile not in profiles:
            raise ConfigError(f"drive.noise_profile = {self.noise_profile!r} is unknown; known "
                              f"profiles: {', '.join(profiles)}")

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-serialisable; ``None`` values dropped)."""
        out = {k: v for k, v in dataclasses.asdict(self).items() if v is not None}
        if out.get("noise_profile") == "none":  # the default: keeps older sweeps' config hashes
            del out["noise_profile"]
        if "waypoints" in out:
            out["waypoints"] = [list(p) for p in out["waypoints"]]
        return out


@dataclass(frozen=True, kw_only=True)
class SweepSpec:
    """A parsed sweep: the base scene config (as a mapping), the swept axes and the drive."""

    base: dict[str, Any]
    """The scene config without ``[sweep]`` / ``[drive]`` (validated as a :class:`SceneConfig`)."""
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    """(dotted key, values) in file order; the grid is their Cartesian product."""
    drive: DriveSpec | None = None
    source: str = "<dict>"
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: Path | None = None,
                  source: str = "<dict>") -> SweepSpec:
        """Check a parsed sweep mapping: a scene config plus ``[sweep]`` axes and an optional
        ``[drive]`` table; relative route paths resolve against ``base_dir``."""
        return _spec_from_dict(data, base_dir=base_dir, source=source)

    @classmethod
    def from_toml(cls, path: str | Path) -> SweepSpec:
        """Read and check a SWEEP.toml (relative DEM/ortho/route paths resolve against its
        folder)."""
        p = Path(path)
        data = read_config_toml(p, what="sweep file")
        table = data.get("sweep")
        if isinstance(table, dict):  # swept DEM / ortho paths resolve like the base config's
            for key in ("terrain.dem_path", "terrain.ortho_path"):
                values = table.get(key)
                if isinstance(values, list):
                    table[key] = [
                        str((p.parent / v).resolve()) if isinstance(v, str)
                        and not Path(v).is_absolute() else v
                        for v in values
                    ]
        return _spec_from_dict(data, base_dir=p.parent, source=str(p))


def _field_hint(key: str) -> Any:
    """The annotation of a dotted SceneConfig key, or raise ConfigError naming the key."""
    if key == "seed":
        return int
    parts = key.split(".")
    cls: Any = SceneConfig
    hint: Any = None
    for i, part in enumerate(parts):
        if not (dataclasses.is_dataclass(cls) and isinstance(cls, type)):
            raise ConfigError(f"unknown sweep key {key!r}: {'.'.join(parts[:i])} is not a table")
        hints = typing.get_type_hints(cls)
        names = [f.name for f in dataclasses.fields(cls)]
        if part not in names:
            where = ".".join(parts[:i]) or "the top level"
            raise ConfigError(
                f"unknown sweep key {key!r}: no {part!r} in {where}; allowed: {sorted(names)}"
            )
        hint = hints[part]
        cls = hint
    if dataclasses.is_dataclass(hint) and isinstance(hint, type):
        raise ConfigError(f"sweep key {key!r} is a whole table; sweep one of its keys")
    return hint


def set_dotted(mapping: dict[str, Any], key: str, value: Any) -> dict[str, Any]:
    """A deep copy of ``mapping`` with the dotted ``key`` set to ``value``."""
    out = _deepcopy(mapping)
    node = out
    parts = key.split(".")
    for part in parts[:-1]:
        child = node.get(part)
        node[part] = child = dict(child) if isinstance(child, dict) else {}
        node = child
    node[parts[-1]] = value
    return out


def _deepcopy(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _deepcopy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_deepcopy(v) for v in value]
    return value


def _check_some_cell_valid(base: dict[str, Any], axes: list[tuple[str, tuple[Any, ...]]]) -> None:
    """Raise the first cell's error unless at least one cell's config is valid.

    A bad base config (unknown key, wrong type) fails every cell and is reported here; a swept
    value that is out of range fails only its cells, which the sweep records as ``failed``.
    """
    first: ConfigError | None = None
    for combo in itertools.product(*(values for _, values in axes)):
        config = base
        for (key, _), value in zip(axes, combo, strict=True):
            config = set_dotted(config, key, value)
        try:
            SceneConfig.from_dict(config)
            return
        except ConfigError as err:
            first = first or err
    assert first is not None
    raise first


def _spec_from_dict(data: dict[str, Any], *, base_dir: Path | None = None,
                    source: str = "<dict>") -> SweepSpec:
    """Check a parsed SWEEP.toml mapping and return a :class:`SweepSpec`."""
    data = _deepcopy(data)
    table = data.pop("sweep", None)
    drive_table = data.pop("drive", None)
    if not isinstance(table, dict) or not table:
        raise ConfigError(f"{source}: needs a non-empty [sweep] table of key = [values, ...]")
    axes: list[tuple[str, tuple[Any, ...]]] = []
    for key, values in table.items():
        if isinstance(values, dict):  # "[sweep.lighting] tau = [...]" or unquoted dotted keys
            raise ConfigError(
                f"sweep key {key!r} is a table; quote dotted keys: \"{key}.<name>\" = [...]"
            )
        _field_hint(key)
        if not isinstance(values, list):
            raise ConfigError(f"sweep.{key} = {values!r}; must be a list of values")
        if not values:
            raise ConfigError(f"sweep.{key} = []; give at least one value")
        seen = [repr(v) for v in values]
        if len(set(seen)) != len(seen):
            raise ConfigError(f"sweep.{key} = {values!r} repeats a value")
        axes.append((key, tuple(values)))
    _check_some_cell_valid(data, axes)
    drive = None
    if drive_table is not None:
        if isinstance(drive_table, dict) and isinstance(drive_table.get("route"), str):
            route = Path(drive_table["route"])
            if base_dir is not None and not route.is_absolute():
                drive_table["route"] = str((base_dir / route).resolve())
        drive = dataclass_from_mapping(DriveSpec, drive_table, "drive")
    return SweepSpec(base=data, axes=tuple(axes), drive=drive, source=source)
