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
import json
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping
from marsscene.config import SceneConfig, read_config_toml
from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig, LidarConfig, NoiseConfig, RunConfig
from marsscene.sim.mission import DriveOptions
from marsscene.sim.route import check_waypoints

__all__ = ["DriveSpec", "SweepSpec"]


#: The ``[drive]`` keys of the sweep itself; every other key is a :class:`DriveOptions` key.
_SWEEP_DRIVE_KEYS = ("waypoints", "route", "seconds", "camera", "lidar", "noise_seed",
                     "noise_profile", "bag")
#: Keys that moved, with where they went (a one-line error names the new key).
_MOVED = {"lookahead_m": "pursuit.lookahead_m ([drive.pursuit] lookahead_m = ...)"}


@dataclass(frozen=True, kw_only=True)
class DriveSpec:
    """How every cell is driven (the ``[drive]`` table; see ``marsscene drive``).

    The table holds the sweep's own keys (below) and any :class:`~marsscene.DriveOptions` key
    (``max_slope_deg``, ``corridor_m``, ``settle_s``, a ``pursuit`` table, ...), read by
    ``DriveOptions.from_dict``: their defaults and bounds are the drive's.
    """

    waypoints: tuple[tuple[float, float], ...] | None = None
    """Waypoints (x, y) in m; a smooth route avoiding slopes and rocks is authored through them."""
    route: str | None = None
    """A TUM route file instead of waypoints (relative paths resolve against SWEEP.toml)."""
    seconds: float | None = None
    """Sim-time limit in s (default: until the goal)."""
    camera: bool = False
    """Log the mast RGB-D camera with its defaults (:class:`~marsscene.runtime.CameraConfig`)."""
    lidar: bool = False
    """Log the LiDAR with its defaults (:class:`~marsscene.runtime.LidarConfig`)."""
    noise_seed: int = 0
    """Seed of the sensor-noise stream (the same in every cell unless swept)."""
    noise_profile: str | None = None
    """IMU and wheel-odometry noise profile (:class:`~marsscene.runtime.NoiseConfig`; default:
    its default, noise-free as ``marsscene drive``), e.g. ``"ln200s"`` (the benchmarks')."""
    bag: bool = False
    """Also write the drive as a ROS 2 bag (``drive/bag``, MCAP; see ``marsscene bag``)."""
    options: DriveOptions = field(default_factory=DriveOptions)
    """The drive's set-up: the table's :class:`~marsscene.DriveOptions` keys."""

    def __post_init__(self) -> None:
        if (self.waypoints is None) == (self.route is None):
            raise ConfigError("[drive] needs exactly one of waypoints or route")
        if self.waypoints is not None:
            wp = check_waypoints(self.waypoints, "drive.waypoints")
            object.__setattr__(self, "waypoints", tuple((float(x), float(y)) for x, y in wp))
        if self.seconds is not None:
            check_range("drive.seconds", self.seconds, 0.0, 1e6, lo_open=True)
        if isinstance(self.noise_seed, bool) or not isinstance(self.noise_seed, int):
            raise ConfigError(f"drive.noise_seed = {self.noise_seed!r}; must be an integer >= 0")
        check_range("drive.noise_seed", self.noise_seed, 0)
        for key in ("camera", "lidar", "bag"):
            if not isinstance(getattr(self, key), bool):
                raise ConfigError(f"drive.{key} = {getattr(self, key)!r}; must be true or false")
        try:
            self.run_config()
        except ConfigError as err:
            raise ConfigError(f"drive.noise_profile: {err}") from None

    @classmethod
    def from_dict(cls, mapping: Any) -> DriveSpec:
        """From a ``[drive]`` table: the sweep's keys, the rest to ``DriveOptions.from_dict``."""
        if not isinstance(mapping, dict):
            raise ConfigError(f"[drive] must be a table; got {mapping!r}")
        for old, new in _MOVED.items():
            if old in mapping:
                raise ConfigError(f"drive.{old} = {mapping[old]!r}: now drive.{new}, as in "
                                  "DriveOptions")
        allowed = {*_SWEEP_DRIVE_KEYS, *(f.name for f in dataclasses.fields(DriveOptions))}
        for key, value in mapping.items():
            if key not in allowed:
                raise ConfigError(f"unknown key drive.{key} = {value!r}; allowed keys: "
                                  f"{sorted(allowed)}")
        options = DriveOptions.from_dict(
            {k: v for k, v in mapping.items() if k not in _SWEEP_DRIVE_KEYS})
        own = {k: v for k, v in mapping.items() if k in _SWEEP_DRIVE_KEYS}
        return dataclasses.replace(dataclass_from_mapping(cls, own, "drive"), options=options)

    def run_config(self) -> RunConfig:
        """The drive's sensors and noise."""
        noise = NoiseConfig() if self.noise_profile is None else NoiseConfig(
            profile=self.noise_profile)
        return RunConfig(lidar=LidarConfig() if self.lidar else None,
                         camera=CameraConfig() if self.camera else None, noise=noise)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-serialisable; ``None`` values dropped), the cell's config hash: a
        default noise profile is left out and ``lookahead_m``, ``max_slope_deg``, ``corridor_m``
        are written flat as they were (older sweeps keep their hashes); other drive options
        only where they differ from the default, under ``options``."""
        out = {k: getattr(self, k) for k in _SWEEP_DRIVE_KEYS if getattr(self, k) is not None}
        if out.get("noise_profile") == NoiseConfig().profile:
            del out["noise_profile"]
        if "waypoints" in out:
            out["waypoints"] = [list(p) for p in out["waypoints"]]
        opt = self.options
        out.update(lookahead_m=opt.pursuit.lookahead_m, max_slope_deg=opt.max_slope_deg,
                   corridor_m=opt.corridor_m)
        changed = _changed(dataclasses.asdict(opt), dataclasses.asdict(DriveOptions()))
        changed.pop("max_slope_deg", None)
        changed.pop("corridor_m", None)
        if changed.get("pursuit", {}).pop("lookahead_m", None) is not None and \
                not changed["pursuit"]:
            del changed["pursuit"]
        if changed:
            out["options"] = json.loads(json.dumps(changed))  # tuples as lists
        return out


def _changed(doc: dict[str, Any], default: dict[str, Any]) -> dict[str, Any]:
    """The entries of ``doc`` that differ from ``default`` (nested tables compared by key)."""
    out: dict[str, Any] = {}
    for key, value in doc.items():
        if isinstance(value, dict):
            sub = _changed(value, default[key])
            if sub:
                out[key] = sub
        elif value != default[key]:
            out[key] = value
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
        drive = DriveSpec.from_dict(drive_table)
    return SweepSpec(base=data, axes=tuple(axes), drive=drive, source=source)
