"""``LocSpec``: a localization benchmark spec (TOML) parsed and checked (pure: no disk writes).

::

    [benchmark]
    name = "loc"
    seed = 0                       # seeds the query places and the priors
    queries = 20                   # query places per scene
    tau = [0.5, 6.0]               # dust of the camera (the first cell also drives the LiDAR)
    sun_elevation_deg = 35.0       # optional: the camera's sun (default: the scene's)
    [prior]
    position_error_m = [5.0, 50.0] # the prior's distance from the truth: uniform in this range
    heading_error_deg = 3.0        # the prior's heading error: uniform in +- this
    [local]
    scans = 5                      # LiDAR scans of the short drive that make the local map
    lidar_model = "os1-64"
    lidar_rate_hz = 1.0
    radius_m = 30.0                # the local map keeps points this close to the rover
    camera = { width_px = 320, height_px = 240 }
    [[scenes]]
    name = "plain"
    preset = "jezero-plain"        # or config = "scene.toml", or scene_dir = "built/scene"
    route = { shape = "loop", length_m = 200.0 }
    [[methods]]
    name = "dem"
    kind = "dem-correlation"       # or ortho-match, prior, command, python

docs/benchmark_loc.md documents every key; every error is a one-line ConfigError.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import check_choice, check_range, dataclass_from_mapping, load_toml
from marsscene.benchmark.slam.items import RouteSpec, SceneSpec
from marsscene.errors import ConfigError

__all__ = ["LOC_KINDS", "LocMethod", "LocScene", "LocSpec"]

#: Built-in methods and the two for "your method".
LOC_KINDS = ("dem-correlation", "ortho-match", "prior", "command", "python")
_SENSOR_OF = {"dem-correlation": "lidar", "ortho-match": "camera", "prior": "none"}


@dataclass(frozen=True, kw_only=True)
class LocScene:
    """A scene: a preset or config built per cell (:class:`SceneSpec`), or a scene folder
    already built with ``--orbital-map``."""

    name: str
    route: RouteSpec
    preset: str | None = None
    config: str | None = None
    overrides: dict[str, Any] = field(default_factory=dict)
    scene_dir: str | None = None

    def __post_init__(self) -> None:
        if self.scene_dir is not None and (self.preset or self.config or self.overrides):
            raise ConfigError(f"scene {self.name!r}: scene_dir is a built scene; give no "
                              "preset, config or overrides with it")
        self.as_scene_spec()  # the name and preset / config checks

    def as_scene_spec(self) -> SceneSpec:
        return SceneSpec(name=self.name, preset=self.preset, config=self.config,
                         overrides=self.overrides, route=self.route)


@dataclass(frozen=True, kw_only=True)
class LocMethod:
    """A method: built-in, a command per query or a Python ``module:function``."""

    name: str
    kind: str
    command: str | None = None
    """``command``: a template with {query_dir} {answer} (the answer file to write)."""
    function: str | None = None
    """``python``: ``module:function`` called as ``function(query_dir, answer_path)``."""
    sensor: str | None = None
    """``lidar`` (first-tau cells), ``camera`` (every tau) or ``none`` (first-tau cells)."""
    timeout_s: float = 600.0
    options: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or any(
                not (c.isalnum() or c in "-_.") for c in self.name):
            raise ConfigError(f"methods.name = {self.name!r}; use letters, digits, - _ .")
        check_choice(f"method {self.name!r} kind", self.kind, LOC_KINDS)
        if (self.kind == "command") != bool(self.command):
            raise ConfigError(f"method {self.name!r}: command = \"...\" goes with kind = "
                              "\"command\" (and only there)")
        if (self.kind == "python") != bool(self.function) or (
                self.function is not None and ":" not in self.function):
            raise ConfigError(f"method {self.name!r}: function = \"module:function\" goes with "
                              "kind = \"python\" (and only there)")
        object.__setattr__(self, "sensor", self.sensor or _SENSOR_OF.get(self.kind, "lidar"))
        check_choice(f"method {self.name!r} sensor", self.sensor, ("lidar", "camera", "none"))
        check_range(f"method {self.name!r} timeout_s", self.timeout_s, 0.0, 1e6, lo_open=True)


@dataclass(frozen=True, kw_only=True)
class LocSpec:
    """A parsed localization benchmark: scenes x tau cells of seeded queries, methods."""

    scenes: tuple[LocScene, ...]
    methods: tuple[LocMethod, ...]
    seed: int = 0
    queries: int = 20
    tau: tuple[float, ...] = (0.5,)
    sun_elevation_deg: float | None = None
    position_error_m: tuple[float, float] = (5.0, 50.0)
    heading_error_deg: float = 3.0
    scans: int = 5
    lidar_model: str = "os1-64"
    lidar_rate_hz: float = 1.0
    radius_m: float = 30.0
    camera: dict[str, Any] = field(default_factory=lambda: {"width_px": 320, "height_px": 240})
    name: str = "loc"
    source: str = "<dict>"

    def __post_init__(self) -> None:
        if not self.scenes or not self.methods:
            raise ConfigError(f"{self.source}: needs [[scenes]] and [[methods]] tables")
        for what, names in (("scene", [s.name for s in self.scenes]),
                            ("method", [m.name for m in self.methods])):
            dupes = sorted({n for n in names if names.count(n) > 1})
            if dupes:
                raise ConfigError(f"{what} name {dupes[0]!r} is used twice")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"benchmark.seed = {self.seed!r}; must be an integer >= 0")
        if isinstance(self.queries, bool) or not isinstance(self.queries, int) or not (
                1 <= self.queries <= 10000):
            raise ConfigError(f"benchmark.queries = {self.queries!r}; need 1..10000")
        if not self.tau or len(set(self.tau)) != len(self.tau):
            raise ConfigError(f"benchmark.tau = {list(self.tau)!r}; need distinct values")
        for t in self.tau:
            check_range("benchmark.tau", t, 0.0, 10.0)
        lo, hi = (float(v) for v in self.position_error_m)
        if not 0.0 <= lo <= hi <= 500.0:
            raise ConfigError(f"prior.position_error_m = {list(self.position_error_m)!r}; need "
                              "[min, max] with 0 <= min <= max <= 500")
        check_range("prior.heading_error_deg", self.heading_error_deg, 0.0, 45.0)
        if isinstance(self.scans, bool) or not isinstance(self.scans, int) or not (
                1 <= self.scans <= 100):
            raise ConfigError(f"local.scans = {self.scans!r}; need 1..100")
        check_range("local.radius_m", self.radius_m, 5.0, 200.0)
        self.run_config(lidar=True)

    @property
    def drive_s(self) -> float:
        """Sim seconds of a query's short drive: ``scans`` scans at ``lidar_rate_hz``."""
        return (self.scans - 1) / self.lidar_rate_hz

    @property
    def needs_camera(self) -> bool:
        """Whether the drives log the camera: unless every method is a built-in one that
        reads no image (``dem-correlation``, ``prior``), which makes a LiDAR-only drive."""
        return any(m.kind not in ("dem-correlation", "prior") or m.sensor == "camera"
                   for m in self.methods)

    def methods_for(self, tau: float) -> tuple[LocMethod, ...]:
        """Camera methods run in every tau's cell; the others in the first tau's."""
        first = tau == self.tau[0]
        return tuple(m for m in self.methods if first or m.sensor == "camera")

    def run_config(self, *, lidar: bool, tau: float | None = None, camera: bool = True
                   ) -> Any:
        """The drive's :class:`~marsscene.rover.config.RunConfig` (camera at ``tau``, or
        none)."""
        from marsscene.rover import CameraConfig, LidarConfig, NoiseConfig, RunConfig

        cam = {"rate_hz": 1.0 / max(self.drive_s, 1.0), **self.camera, "tau": tau,
               "sun_elevation_deg": self.sun_elevation_deg}
        cam_cfg = dataclass_from_mapping(CameraConfig, cam, "local.camera")
        lid = LidarConfig(model=self.lidar_model, rate_hz=self.lidar_rate_hz) if lidar else None
        return RunConfig(camera=cam_cfg if camera else None, lidar=lid,
                         noise=NoiseConfig(profile="ln200s"))

    def doc(self) -> dict[str, Any]:
        """The spec as JSON-able data (``benchmark.json``; a resumed run must match it)."""
        d = dataclasses.asdict(self)
        d.pop("source", None)
        return d

    @classmethod
    def from_toml(cls, path: str | Path) -> LocSpec:
        p = Path(path)
        return cls.from_dict(load_toml(p, what="benchmark spec"), base_dir=p.parent.resolve(),
                             source=str(p))

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: Path | None = None,
                  source: str = "<dict>") -> LocSpec:
        """Check a parsed spec mapping; relative paths resolve against ``base_dir``."""
        unknown = sorted(set(data) - {"benchmark", "prior", "local", "scenes", "methods"})
        if unknown:
            raise ConfigError(f"{source}: unknown table(s) {unknown}; allowed: benchmark, "
                              "prior, local, scenes, methods")
        here = base_dir or Path.cwd()
        kw: dict[str, Any] = {}
        for table, keys in (("benchmark", ("name", "seed", "queries", "tau",
                                           "sun_elevation_deg")),
                            ("prior", ("position_error_m", "heading_error_deg")),
                            ("local", ("scans", "lidar_model", "lidar_rate_hz", "radius_m",
                                       "camera"))):
            raw = data.get(table, {})
            if not isinstance(raw, dict) or set(raw) - set(keys):
                raise ConfigError(f"[{table}]: unknown key(s) {sorted(set(raw) - set(keys))}; "
                                  f"allowed: {', '.join(keys)}")
            kw.update(raw)
        for key in ("tau", "position_error_m"):
            if key in kw:
                if not isinstance(kw[key], list):
                    raise ConfigError(f"{key} = {kw[key]!r}; must be a list")
                kw[key] = tuple(float(v) for v in kw[key])
        scenes = []
        for i, raw in enumerate(data.get("scenes") or ()):
            if not isinstance(raw, dict) or not isinstance(raw.get("route"), dict):
                raise ConfigError(f"scenes[{i}] must be a table with a route table")
            raw = dict(raw)
            raw["route"] = dict(raw["route"])
            if isinstance(raw["route"].get("file"), str):
                raw["route"]["file"] = str((here / raw["route"]["file"]).resolve())
            for key in ("config", "scene_dir"):
                if isinstance(raw.get(key), str):
                    raw[key] = str((here / raw[key]).resolve())
            scenes.append(dataclass_from_mapping(LocScene, raw, f"scenes[{i}]"))
        methods = [dataclass_from_mapping(LocMethod, dict(raw), f"methods[{i}]")
                   if isinstance(raw, dict) else _bad(i, raw)
                   for i, raw in enumerate(data.get("methods") or ())]
        return cls(scenes=tuple(scenes), methods=tuple(methods), source=source, **kw)


def _bad(i: int, raw: Any) -> LocMethod:
    raise ConfigError(f"methods[{i}] must be a table; got {raw!r}")
