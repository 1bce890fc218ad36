"""``SlamSpec``: a SLAM benchmark spec (TOML) parsed and checked (pure: no disk writes).

::

    [benchmark]
    extends = "paper.toml"          # optional: this file's tables over another spec's
    seeds = [7]                     # scene seeds (one cell per scene x tau x seed)
    tau = [0.5, 6.0]                # dust optical depths of the camera runs
    lidar_tau = 0.5                 # the one tau whose cell also logs the LiDAR (default: first)
    [sensors]
    noise_profile = "ln200s"        # IMU + wheel noise profile (default ln200s; "none" = exact)
    [sensors.camera]                # a run config's tables (``marsscene drive --run-config``)
    width_px = 320
    [sensors.lidar]                 # omit for no LiDAR
    [[scenes]]
    name = "mars-base"
    preset = "mars-base"            # or config = "scene.toml" (relative to this file)
    route = { shape = "loop", length_m = 440.0 }
    [[methods]]
    name = "wheel"
    kind = "wheel-odometry"

docs/benchmark.md documents every key. Every error is a one-line
:class:`~marsscene.errors.ConfigError` naming the key and the value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping, load_toml
from marsscene.benchmark.slam.items import (
    BENCHMARK_NOISE_PROFILE,
    METHOD_KINDS,
    MethodSpec,
    RouteSpec,
    SceneSpec,
    distinct_seeds,
)
from marsscene.config import SceneConfig
from marsscene.errors import ConfigError

__all__ = ["BENCHMARK_NOISE_PROFILE", "METHOD_KINDS", "MethodSpec", "RouteSpec", "SceneSpec",
           "SlamSpec"]


@dataclass(frozen=True, kw_only=True)
class SlamSpec:
    """A parsed SLAM benchmark: scenes x tau x seeds cells, sensors, methods, scoring."""

    scenes: tuple[SceneSpec, ...]
    methods: tuple[MethodSpec, ...]
    tau: tuple[float, ...] = (0.5, 6.0)
    seeds: tuple[int, ...] = (0,)
    lidar_tau: float | None = None
    sensors: dict[str, Any] = field(default_factory=dict)
    """``camera`` / ``lidar`` / ``noise`` tables of a run config, plus ``noise_seed``."""
    min_tracked_fraction: float = 0.5
    rpe_distance_m: float = 10.0
    name: str = "slam"
    source: str = "<dict>"

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: Path | None = None,
                  source: str = "<dict>") -> SlamSpec:
        """Check a parsed benchmark mapping (``[benchmark]``, ``[sensors]``, ``[[scenes]]``,
        ``[[methods]]``); relative paths resolve against ``base_dir`` (default: the current
        folder)."""
        return _spec_from_dict(data, base_dir=base_dir, source=source)

    @classmethod
    def from_toml(cls, path: str | Path) -> SlamSpec:
        """Read and check a benchmark TOML (relative config / route paths resolve against
        it)."""
        p = Path(path)
        return _spec_from_dict(_load_extended(p), base_dir=p.parent.resolve(), source=str(p))

    def __post_init__(self) -> None:
        if not self.scenes:
            raise ConfigError(f"{self.source}: needs at least one [[scenes]] table")
        if not self.methods:
            raise ConfigError(f"{self.source}: needs at least one [[methods]] table")
        for what, names in (("scene", [s.name for s in self.scenes]),
                            ("method", [m.name for m in self.methods])):
            dupes = sorted({n for n in names if names.count(n) > 1})
            if dupes:
                raise ConfigError(f"{what} name {dupes[0]!r} is used twice")
        if not self.tau or len(set(self.tau)) != len(self.tau):
            raise ConfigError(f"benchmark.tau = {list(self.tau)!r}; need distinct values")
        for t in self.tau:
            check_range("benchmark.tau", t, 0.0, 50.0)
        if not distinct_seeds(self.seeds):
            raise ConfigError(f"benchmark.seeds = {list(self.seeds)!r}; need distinct ints >= 0")
        lidar_tau = self.tau[0] if self.lidar_tau is None else self.lidar_tau
        if not any(math.isclose(lidar_tau, t) for t in self.tau):
            raise ConfigError(f"benchmark.lidar_tau = {lidar_tau!r} is not one of benchmark.tau "
                              f"= {list(self.tau)!r}")
        object.__setattr__(self, "lidar_tau", lidar_tau)
        check_range("benchmark.min_tracked_fraction", self.min_tracked_fraction, 0.0, 1.0)
        check_range("benchmark.rpe_distance_m", self.rpe_distance_m, 0.1, 1e4)
        unknown = sorted(set(self.sensors) - {"camera", "lidar", "noise", "noise_seed",
                                              "noise_profile", "bag", "lidar_files",
                                              "keep_images"})
        if unknown:
            raise ConfigError(f"unknown sensors key(s) {unknown}; allowed: camera, lidar, noise "
                              "(tables), noise_seed, noise_profile, bag, lidar_files, "
                              "keep_images")
        if not isinstance(self.sensors.get("noise_profile", ""), str):
            raise ConfigError(f"sensors.noise_profile = {self.sensors['noise_profile']!r}; "
                              "must be a profile name (a string)")
        for key in ("bag", "lidar_files", "keep_images"):
            if not isinstance(self.sensors.get(key, False), bool):
                raise ConfigError(f"sensors.{key} = {self.sensors[key]!r}; must be true or "
                                  "false")
        seed = self.sensors.get("noise_seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(f"sensors.noise_seed = {seed!r}; must be an integer >= 0")
        self.run_config(lidar=True)  # validate the tables now
        for m in self.methods:
            if m.sensor != "none" and m.sensor not in self.sensors:
                raise ConfigError(f"method {m.name!r} needs the {m.sensor}; add a "
                                  f"[sensors.{m.sensor}] table")

    @property
    def all_seeds(self) -> tuple[int, ...]:
        """``seeds`` and then every further seed a method runs on (sorted)."""
        extra = {s for m in self.methods for s in (m.seeds or ())} - set(self.seeds)
        return (*self.seeds, *sorted(extra))

    def methods_for(self, tau: float, seed: int) -> tuple[MethodSpec, ...]:
        """The methods of the cell (tau, seed): camera methods in every tau cell, the others
        in the ``lidar_tau`` cell; each on its seeds."""
        lidar_cell = math.isclose(tau, float(self.lidar_tau or self.tau[0]))
        return tuple(m for m in self.methods if (lidar_cell or m.sensor == "camera")
                     and seed in (m.seeds if m.seeds is not None else self.seeds))

    def run_config(self, *, lidar: bool, camera: bool = True) -> Any:
        """The :class:`~marsscene.rover.config.RunConfig` of a cell (LiDAR only if ``lidar``,
        the camera only if ``camera``)."""
        from marsscene.rover.config import CameraConfig, NoiseConfig, RunConfig
        from marsscene.rover.lidar import LidarConfig

        kinds: dict[str, Any] = {"camera": CameraConfig, "lidar": LidarConfig,
                                 "noise": NoiseConfig}
        given = {k: v for k, v in self.sensors.items() if k in kinds
                 and (lidar or k != "lidar") and (camera or k != "camera")}
        noise = given.get("noise", {})
        if isinstance(noise, dict) and "profile" not in noise:  # a realistic IMU by default
            given["noise"] = {"profile": self.sensors.get("noise_profile",
                                                          BENCHMARK_NOISE_PROFILE), **noise}
        tables: dict[str, Any] = {
            k: dataclass_from_mapping(kinds[k], v, f"sensors.{k}") for k, v in given.items()}
        return RunConfig(**tables)

    def shortened(self, *, length_m: float | None = None,
                  scenes: tuple[str, ...] | None = None) -> SlamSpec:
        """The same benchmark on automatic routes of ``length_m`` and/or only ``scenes`` (a
        quick check of a long protocol: ``--length-m 40 --scene grand-canyon``)."""
        chosen = self.scenes
        if scenes:
            unknown = sorted(set(scenes) - {s.name for s in self.scenes})
            if unknown:
                raise ConfigError(f"no scene {unknown[0]!r} in {self.source}; scenes: "
                                  f"{', '.join(s.name for s in self.scenes)}")
            chosen = tuple(s for s in self.scenes if s.name in scenes)
        if length_m is not None:
            fixed = [s.name for s in chosen if s.route.shape is None]
            if fixed:
                raise ConfigError(f"--length-m needs automatic routes (route.shape); scene "
                                  f"{fixed[0]!r} has none")
            chosen = tuple(replace(s, route=replace(s.route, length_m=float(length_m)))
                           for s in chosen)
        return replace(self, scenes=chosen)

    @property
    def noise_seed(self) -> int:
        return int(self.sensors.get("noise_seed", 0))

    def needs_bag(self) -> bool:
        """A method reads the cell's bag (KISS-ICP runs during the drive and needs none)."""
        return any(m.kind == "command" and "{bag_dir}" in str(m.command) for m in self.methods)


def _load_extended(path: Path, depth: int = 0) -> dict[str, Any]:
    """A spec TOML merged over the one its ``benchmark.extends`` names (relative to it):
    ``[benchmark]`` and ``[sensors]`` keys override, ``[[scenes]]`` replace the base's when
    given, ``[[methods]]`` replace the base's of the same name and add the others."""
    data = load_toml(path, what="benchmark spec")
    base_name = _table(data, "benchmark").get("extends")
    if base_name is None:
        return data
    if not isinstance(base_name, str) or depth > 8:
        raise ConfigError(f"{path}: benchmark.extends = {base_name!r}; need a spec file name "
                          "(at most 8 levels)")
    base_path = (path.parent / base_name).resolve()
    if not base_path.is_file():
        raise ConfigError(f"{path}: benchmark.extends: no spec at {base_path}")
    base = _load_extended(base_path, depth + 1)
    for raw in base.get("scenes") or ():  # the base's relative paths stay relative to it
        if isinstance(raw, dict) and isinstance(raw.get("config"), str):
            raw["config"] = str((base_path.parent / raw["config"]).resolve())
        route = raw.get("route") if isinstance(raw, dict) else None
        if isinstance(route, dict) and isinstance(route.get("file"), str):
            route["file"] = str((base_path.parent / route["file"]).resolve())
    out = dict(base)
    for key in ("benchmark", "sensors"):
        out[key] = {**_table(base, key), **_table(data, key)}
    out["benchmark"].pop("extends", None)
    if "scenes" in data:
        out["scenes"] = data["scenes"]
    mine = {m.get("name"): m for m in data.get("methods") or () if isinstance(m, dict)}
    out["methods"] = [mine.pop(m.get("name"), m) if isinstance(m, dict) else m
                      for m in base.get("methods") or ()] + list(mine.values())
    return out


def _table(data: Any, key: str) -> dict[str, Any]:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise ConfigError(f"[{key}] must be a table; got {value!r}")
    return value


def _spec_from_dict(data: dict[str, Any], *, base_dir: Path | None = None,
                    source: str = "<dict>") -> SlamSpec:
    """Check a parsed benchmark TOML mapping and return a :class:`SlamSpec`."""
    unknown = sorted(set(data) - {"benchmark", "sensors", "scenes", "methods"})
    if unknown:
        raise ConfigError(f"{source}: unknown table(s) {unknown}; allowed: benchmark, sensors, "
                          "scenes, methods")
    bench = dict(_table(data, "benchmark"))
    for key in ("tau", "seeds"):
        if key in bench:
            if not isinstance(bench[key], list):
                raise ConfigError(f"benchmark.{key} = {bench[key]!r}; must be a list")
            bench[key] = tuple(bench[key])
    allowed = {"tau", "seeds", "lidar_tau", "min_tracked_fraction", "rpe_distance_m", "name"}
    if set(bench) - allowed:
        raise ConfigError(f"unknown key benchmark.{sorted(set(bench) - allowed)[0]}; allowed: "
                          f"{sorted(allowed)}")
    here = base_dir or Path.cwd()
    scenes = []
    for i, raw in enumerate(data.get("scenes") or ()):
        if not isinstance(raw, dict):
            raise ConfigError(f"scenes[{i}] must be a table; got {raw!r}")
        raw = dict(raw)
        route = dict(_table(raw, "route")) if "route" in raw else None
        if route is None:
            raise ConfigError(f"scene {raw.get('name', i)!r} needs a route table")
        if isinstance(route.get("file"), str):
            route["file"] = str((here / route["file"]).resolve())
        raw["route"] = route
        if isinstance(raw.get("config"), str):
            raw["config"] = str((here / raw["config"]).resolve())
        scene = dataclass_from_mapping(SceneSpec, raw, f"scenes[{i}]")
        try:  # a bad preset, file or override fails here, before any cell runs
            SceneConfig.from_dict(scene.base_config())
        except ConfigError as err:
            raise ConfigError(f"scene {scene.name!r}: {err}") from None
        scenes.append(scene)
    methods = []
    for i, raw in enumerate(data.get("methods") or ()):
        if not isinstance(raw, dict):
            raise ConfigError(f"methods[{i}] must be a table; got {raw!r}")
        methods.append(dataclass_from_mapping(MethodSpec, raw, f"methods[{i}]"))
    sensors = _table(data, "sensors")
    return SlamSpec(scenes=tuple(scenes), methods=tuple(methods), sensors=dict(sensors),
                    source=source, **bench)
