"""The parts of a SLAM benchmark spec: a route, a scene and a method (pure; no disk writes).

:class:`~marsscene.benchmark.slam.spec.SlamSpec` gathers them; docs/benchmark.md documents
every key.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError
from marsscene.sim.route import MAX_SLOPE_DEG, check_waypoints

__all__ = ["BENCHMARK_NOISE_PROFILE", "METHOD_KINDS", "MethodSpec", "RouteSpec", "SceneSpec"]

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
                               "max_step_dev_deg", "gyro", "decimate"),
               "opencv-mono": ("max_corners", "min_parallax_px", "min_inliers"),
               "wheel-odometry": (),
               "kiss-icp": ("wheel_prior", "max_step_dev_m", "max_step_dev_deg", "gate",
                            "gyro")}


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
    max_slope_deg: float = MAX_SLOPE_DEG
    """Steepest slope the route may cross."""

    def __post_init__(self) -> None:
        given = [k for k in ("waypoints", "file", "shape") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ConfigError(f"route needs exactly one of waypoints, file or shape; got {given}")
        if self.waypoints is not None:
            pts = check_waypoints(self.waypoints, "route.waypoints")
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
        """The scene-config mapping of this scene (preset or file, overrides on top); the
        scene is written as MJCF only unless ``export.formats`` is given (the cells drive in
        MuJoCo; a USD copy of grand-canyon is 0.8 GB per cell)."""
        from marsscene.config import read_config_toml

        base: dict[str, Any] = {}  # neither: the default scene of ``marsscene build``
        if self.preset is not None:
            base = {"preset": self.preset}
        elif self.config is not None:
            base = read_config_toml(str(self.config), what=f"scene {self.name!r} config")
        out = _merged(base, self.overrides)
        if "formats" not in out.get("export", {}):  # cells drive in MuJoCo: no USD unless asked
            out = _merged(out, {"export": {"formats": ["mjcf"]}})
        return out


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
    """Adapter options (e.g. ``max_corners`` for ``opencv-mono``)."""
    seeds: tuple[int, ...] | None = None
    """Scene seeds this method runs on (default: ``benchmark.seeds``): a spread over more
    seeds for the methods that are cheap to run, e.g. the wheel odometry (its cells of the
    extra seeds drive without the camera and, unless a LiDAR method runs there, the LiDAR)."""

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
        if self.seeds is not None:
            seeds = tuple(self.seeds) if isinstance(self.seeds, list | tuple) else ()
            if not distinct_seeds(seeds):
                raise ConfigError(f"method {self.name!r} seeds = {self.seeds!r}; need a list of "
                                  "distinct ints >= 0")
            object.__setattr__(self, "seeds", seeds)
        allowed = _OPTIONS_OF.get(self.kind)
        unknown = sorted(set(self.options) - set(allowed)) if allowed is not None else []
        if unknown:
            raise ConfigError(f"method {self.name!r}: unknown option {unknown[0]!r} for "
                              f"{self.kind}; allowed: {', '.join(allowed or ()) or 'none'}")
        if self.kind == "kiss-icp" and "gate" in self.options:
            from marsscene.benchmark.slam.kiss_icp import GATES

            check_choice(f"method {self.name!r} options.gate", self.options["gate"], GATES)



def distinct_seeds(seeds: Any) -> bool:
    """Whether ``seeds`` is a non-empty sequence of distinct ints >= 0."""
    return bool(seeds) and len(set(seeds)) == len(seeds) and all(
        isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds)


def _merged(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        both = isinstance(value, dict) and isinstance(out.get(key), dict)
        out[key] = _merged(out[key], value) if both else value
    return out
