"""``SlamSpec``: a SLAM benchmark spec (TOML) parsed and checked (pure: no disk writes).

::

    [benchmark]
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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import check_choice, check_range, dataclass_from_mapping, load_toml
from marsscene.config import SceneConfig
from marsscene.errors import ConfigError

__all__ = ["BENCHMARK_NOISE_PROFILE", "METHOD_KINDS", "MethodSpec", "RouteSpec", "SceneSpec",
           "SlamSpec"]

#: Built-in adapters (``marsscene.benchmark.slam.methods``) plus the two for "your method".
#: Noise profile of a benchmark's drives unless ``sensors.noise_profile`` or
#: ``[sensors.noise] profile`` says otherwise: a Mars-rover class IMU and wheel odometry.
BENCHMARK_NOISE_PROFILE = "ln200s"
METHOD_KINDS = ("wheel-odometry", "kiss-icp", "open3d-rgbd", "opencv-mono", "tum-file", "command")
_FRAMES = ("base", "camera", "lidar")
_SENSOR_OF = {"wheel-odometry": "none", "kiss-icp": "lidar", "open3d-rgbd": "camera",
              "opencv-mono": "camera"}
#: Adapter options per built-in kind (``[[methods]] options = {...}``).
_OPTIONS_OF = {"open3d-rgbd": ("depth_trunc_m", "wheel_prior", "max_step_dev_m",
                               "max_step_dev_deg"),
               "opencv-mono": ("max_corners", "min_parallax_px", "min_inliers"),
               "wheel-odometry": (), "kiss-icp": ()}


@dataclass(frozen=True, kw_only=True)
class RouteSpec:
    """The route of a scene: waypoints, a TUM file, or an automatic loop / out-and-back."""

    waypoints: tuple[tuple[float, float], ...] | None = None
    """(x, y) in m; a smooth route avoiding slopes and rocks is authored through them."""
    file: str | None = None
    """A TUM route file (relative paths resolve against the spec's folder)."""
    shape: str | None = None
    """``loop`` or ``out-and-back``: authored automatically through traversable terrain."""
    length_m: float | None = None
    """Target length of an automatic route (within a few %)."""
    center_xy_m: tuple[float, float] = (0.0, 0.0)
    """Centre of an automatic route."""
    center_asset: str | None = None
    """Centre an automatic route on this placed asset of the scene instead (its name in the
    scene manifest, e.g. ``"habitat"``; its position depends on the terrain and seed)."""
    heading_deg: float = 0.0
    """Direction of the first leg (counter-clockwise from +x = east)."""
    width_m: float = 6.0
    """Distance between the out and the back lane of an ``out-and-back``."""
    max_slope_deg: float = 20.0
    """Steepest slope the route may cross."""

    def __post_init__(self) -> None:
        given = [k for k in ("waypoints", "file", "shape") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ConfigError(f"route needs exactly one of waypoints, file or shape; got {given}")
        if self.waypoints is not None:
            pts = self.waypoints
            if len(pts) < 2 or not all(len(p) == 2 and all(
                    isinstance(v, int | float) and not isinstance(v, bool) for v in p)
                    for p in pts):
                raise ConfigError(f"route.waypoints = {list(pts)!r}; need >= 2 [x, y] pairs in m")
            object.__setattr__(self, "waypoints", tuple((float(x), float(y)) for x, y in pts))
        if self.shape is not None:
            check_choice("route.shape", self.shape, ("loop", "out-and-back"))
            if self.length_m is None:
                raise ConfigError(f"route.shape = {self.shape!r} needs route.length_m")
            check_range("route.length_m", self.length_m, 5.0, 1e5)
        elif self.length_m is not None:
            raise ConfigError("route.length_m is for automatic routes (route.shape)")
        if len(self.center_xy_m) != 2:
            raise ConfigError(f"route.center_xy_m = {self.center_xy_m!r}; need [x, y] in m")
        if self.center_asset is not None and (self.shape is None or not isinstance(
                self.center_asset, str) or not self.center_asset):
            raise ConfigError(f"route.center_asset = {self.center_asset!r}: an asset name, for "
                              "automatic routes (route.shape)")
        check_range("route.heading_deg", self.heading_deg, -360.0, 360.0)
        check_range("route.width_m", self.width_m, 1.0, 1e3)
        check_range("route.max_slope_deg", self.max_slope_deg, 0.0, 90.0, lo_open=True)


@dataclass(frozen=True, kw_only=True)
class SceneSpec:
    """One benchmark scene: a preset, a scene config file or the default scene (plus
    overrides), and its route."""

    name: str
    preset: str | None = None
    config: str | None = None
    """Scene config TOML (as for ``marsscene build --config``)."""
    overrides: dict[str, Any] = field(default_factory=dict)
    """Scene-config tables merged over the preset / file (e.g. ``{"rocks": {"k": 0.02}}``)."""
    route: RouteSpec
    seconds: float | None = None
    """Sim-time limit of the drive in s (default: until the end of the route)."""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or any(
                not (c.isalnum() or c in "-_.") for c in self.name):
            raise ConfigError(f"scenes.name = {self.name!r}; use letters, digits, - _ .")
        if self.preset is not None and self.config is not None:
            raise ConfigError(f"scene {self.name!r}: give preset or config, not both")
        if self.seconds is not None:
            check_range(f"scene {self.name!r} seconds", self.seconds, 0.0, 1e6, lo_open=True)

    def base_config(self) -> dict[str, Any]:
        """The scene-config mapping of this scene (preset or file, overrides on top)."""
        from marsscene.config import read_config_toml

        base: dict[str, Any] = {}  # neither: the default scene of ``marsscene build``
        if self.preset is not None:
            base = {"preset": self.preset}
        elif self.config is not None:
            base = read_config_toml(str(self.config), what=f"scene {self.name!r} config")
        return _merged(base, self.overrides)


@dataclass(frozen=True, kw_only=True)
class MethodSpec:
    """One method: a built-in adapter, a TUM file per cell, or a command run per cell."""

    name: str
    kind: str
    align: str | None = None
    """``se3`` or ``sim3`` (default: ``sim3`` for ``opencv-mono``, else ``se3``)."""
    frame: str | None = None
    """Body frame of the estimate: ``base``, ``camera`` (navcam optical) or ``lidar``."""
    sensor: str | None = None
    """``camera``, ``lidar`` or ``none``: which cells run it (LiDAR ones at ``lidar_tau``)."""
    command: str | None = None
    """``kind = "command"``: template with {cell_dir} {run_dir} {tum_rgbd_dir} {euroc_dir}
    {bag_dir} {scene_dir} {out_tum} {tau} {seed} {scene}."""
    file: str = "{cell_dir}/estimates/{method}.tum"
    """``kind = "tum-file"``: where the estimate is dropped (same placeholders + {method})."""
    timeout_s: float = 3600.0
    options: dict[str, Any] = field(default_factory=dict)
    """Adapter options (e.g. ``max_features`` for ``opencv-mono``)."""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or any(
                not (c.isalnum() or c in "-_.") for c in self.name):
            raise ConfigError(f"methods.name = {self.name!r}; use letters, digits, - _ .")
        check_choice(f"method {self.name!r} kind", self.kind, METHOD_KINDS)
        if self.kind == "command" and not self.command:
            raise ConfigError(f"method {self.name!r}: kind = \"command\" needs command = \"...\"")
        if self.command is not None and self.kind != "command":
            raise ConfigError(f"method {self.name!r}: command is only for kind = \"command\"")
        builtin = self.kind in _SENSOR_OF
        default_align = "sim3" if self.kind == "opencv-mono" else "se3"
        default_frame = {"wheel-odometry": "base", "kiss-icp": "lidar"}.get(self.kind, "camera")
        object.__setattr__(self, "align", self.align or default_align)
        object.__setattr__(self, "frame", self.frame or default_frame)
        object.__setattr__(self, "sensor", self.sensor or _SENSOR_OF.get(
            self.kind, "lidar" if self.frame == "lidar" else "camera"))
        check_choice(f"method {self.name!r} align", self.align, ("se3", "sim3"))
        check_choice(f"method {self.name!r} frame", self.frame, _FRAMES)
        check_choice(f"method {self.name!r} sensor", self.sensor, ("camera", "lidar", "none"))
        if builtin and self.frame != default_frame:
            raise ConfigError(f"method {self.name!r}: {self.kind} estimates the "
                              f"{default_frame} frame; frame = {self.frame!r} is not allowed")
        check_range(f"method {self.name!r} timeout_s", self.timeout_s, 0.0, 1e6, lo_open=True)
        allowed = _OPTIONS_OF.get(self.kind)
        unknown = sorted(set(self.options) - set(allowed)) if allowed is not None else []
        if unknown:
            raise ConfigError(f"method {self.name!r}: unknown option {unknown[0]!r} for "
                              f"{self.kind}; allowed: {', '.join(allowed or ()) or 'none'}")


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
        return _spec_from_dict(load_toml(p, what="benchmark spec"),
                               base_dir=p.parent.resolve(), source=str(p))

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
        if not self.seeds or len(set(self.seeds)) != len(self.seeds) or not all(
                isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in self.seeds):
            raise ConfigError(f"benchmark.seeds = {list(self.seeds)!r}; need distinct ints >= 0")
        lidar_tau = self.tau[0] if self.lidar_tau is None else self.lidar_tau
        if not any(math.isclose(lidar_tau, t) for t in self.tau):
            raise ConfigError(f"benchmark.lidar_tau = {lidar_tau!r} is not one of benchmark.tau "
                              f"= {list(self.tau)!r}")
        object.__setattr__(self, "lidar_tau", lidar_tau)
        check_range("benchmark.min_tracked_fraction", self.min_tracked_fraction, 0.0, 1.0)
        check_range("benchmark.rpe_distance_m", self.rpe_distance_m, 0.1, 1e4)
        unknown = sorted(set(self.sensors) - {"camera", "lidar", "noise", "noise_seed",
                                              "noise_profile", "bag"})
        if unknown:
            raise ConfigError(f"unknown sensors key(s) {unknown}; allowed: camera, lidar, noise "
                              "(tables), noise_seed, noise_profile, bag")
        if not isinstance(self.sensors.get("noise_profile", ""), str):
            raise ConfigError(f"sensors.noise_profile = {self.sensors['noise_profile']!r}; "
                              "must be a profile name (a string)")
        if not isinstance(self.sensors.get("bag", False), bool):
            raise ConfigError(f"sensors.bag = {self.sensors['bag']!r}; must be true or false")
        seed = self.sensors.get("noise_seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ConfigError(f"sensors.noise_seed = {seed!r}; must be an integer >= 0")
        self.run_config(lidar=True)  # validate the tables now
        for m in self.methods:
            if m.sensor != "none" and m.sensor not in self.sensors:
                raise ConfigError(f"method {m.name!r} needs the {m.sensor}; add a "
                                  f"[sensors.{m.sensor}] table")

    def run_config(self, *, lidar: bool) -> Any:
        """The :class:`~marsscene.rover.config.RunConfig` of a cell (LiDAR only if ``lidar``)."""
        from marsscene.rover.config import CameraConfig, NoiseConfig, RunConfig
        from marsscene.rover.lidar import LidarConfig

        kinds: dict[str, Any] = {"camera": CameraConfig, "lidar": LidarConfig,
                                 "noise": NoiseConfig}
        given = {k: v for k, v in self.sensors.items() if k in kinds and (lidar or k != "lidar")}
        noise = given.get("noise", {})
        if isinstance(noise, dict) and "profile" not in noise:  # a realistic IMU by default
            given["noise"] = {"profile": self.sensors.get("noise_profile",
                                                          BENCHMARK_NOISE_PROFILE), **noise}
        tables: dict[str, Any] = {
            k: dataclass_from_mapping(kinds[k], v, f"sensors.{k}") for k, v in given.items()}
        return RunConfig(**tables)

    @property
    def noise_seed(self) -> int:
        return int(self.sensors.get("noise_seed", 0))

    def needs_bag(self) -> bool:
        return any(m.kind == "kiss-icp" or (m.kind == "command" and "{bag_dir}" in str(m.command))
                   for m in self.methods)


def _merged(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        both = isinstance(value, dict) and isinstance(out.get(key), dict)
        out[key] = _merged(out[key], value) if both else value
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
