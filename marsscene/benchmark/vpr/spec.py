"""``VprSpec``: a visual place-recognition dataset spec (TOML) parsed and checked (pure).

Two traversals of one route, a *database* and a *queries* one, each under its own dust optical
depth and sun elevation, with a frame every ``spacing_m`` metres driven. The three shipped
protocols of the MarsLab paper (Mars Base route, frames every 0.1 m, 2 m positive radius)::

    marsscene benchmark vpr dust --out vpr_dust          # tau 0.05 queries vs tau 0.60 database
    marsscene benchmark vpr day-low-sun --out vpr_lowsun # day queries vs a 3 deg sun's database
    marsscene benchmark vpr day-dim --out vpr_dim        # day queries vs the day's sun, dimmed

A spec file::

    [vpr]
    spacing_m = 0.1            # one frame per 0.1 m driven
    lateral_offset_m = 0.4     # each traversal drives the route shifted by U(-0.4, 0.4) m
    lookahead_jitter_m = 0.5   # and follows it with a lookahead of 2.0 m +- U(0.5) m
    seed = 1                   # draws the offsets (and the sensor noise streams)
    radius_m = 2.0             # positives radius of the evaluation
    landmark = "habitat"       # share of frames showing this asset (default: center_asset)
    scene_seed = 7
    [camera]                   # CameraConfig keys (docs/camera.md); depth is not written
    width_px = 640
    height_px = 480
    [scene]                    # as a SLAM benchmark scene (docs/benchmark.md)
    name = "mars-base"
    preset = "mars-base"
    route = { shape = "loop", length_m = 445.0 }
    [database]
    tau = 0.60
    sun_elevation_deg = 30.0
    [queries]
    tau = 0.05
    sun_elevation_deg = 30.0

docs/benchmark.md documents every key; errors are one-line
:class:`~marsscene.errors.ConfigError` messages naming the key.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping, load_toml
from marsscene.benchmark.slam.spec import SceneSpec
from marsscene.errors import ConfigError
from marsscene.rover.config import CameraConfig

__all__ = ["PROTOCOLS", "TraversalSpec", "VprSpec"]

#: Shipped protocols (``marsscene/benchmark/vpr/data/vpr_<name>.toml``).
PROTOCOLS = ("dust", "day-low-sun", "day-dim")
#: Former protocol names, and what to type instead.
RENAMED = {"day-dark": "the paper's Day/Dark has two readings: day-low-sun (a 3 deg sun, its "
                       "light and long shadows) or day-dim (the day's sun at dusk's light)"}
SPLITS = ("database", "queries")


@dataclass(frozen=True, kw_only=True)
class TraversalSpec:
    """The lighting of one traversal: dust optical depth and sun elevation (and azimuth)."""

    tau: float
    sun_elevation_deg: float
    sun_azimuth_deg: float | None = None
    exposure: str = "auto"
    """``auto`` (frames exposed for a mean of 0.45) or ``fixed`` (a dark frame stays dark)."""
    irradiance_of_sun_elevation_deg: float | None = None
    """Light the scene with the sun's and sky's irradiance of a sun at this elevation (same
    tau), while the sun keeps ``sun_elevation_deg``'s direction and shadows (the camera's
    ``irradiance_scale``); None: its own."""

    def __post_init__(self) -> None:
        check_range("tau", self.tau, 0.0, 10.0)
        check_range("sun_elevation_deg", self.sun_elevation_deg, -10.0, 90.0)
        if self.irradiance_of_sun_elevation_deg is not None:
            check_range("irradiance_of_sun_elevation_deg", self.irradiance_of_sun_elevation_deg,
                        -10.0, 90.0)
        if self.exposure not in ("auto", "fixed"):
            raise ConfigError(f"exposure = {self.exposure!r}; expected auto or fixed")


@dataclass(frozen=True, kw_only=True)
class VprSpec:
    """A VPR dataset: one scene and route, a database and a queries traversal."""

    scene: SceneSpec
    database: TraversalSpec
    queries: TraversalSpec
    camera: dict[str, Any] = field(default_factory=dict)
    spacing_m: float = 0.1
    lateral_offset_m: float = 0.4
    lookahead_jitter_m: float = 0.5
    seed: int = 1
    scene_seed: int = 7
    radius_m: float = 2.0
    jpeg_quality: int = 95
    landmark: str | None = None
    """A placed asset whose presence in each frame is measured (``poses.csv`` ``landmark_px``,
    ``dataset.json``); default: the route's ``center_asset``."""
    name: str = "vpr"
    source: str = "<dict>"

    @property
    def landmark_name(self) -> str | None:
        """The asset measured in view (``landmark``, else the route's ``center_asset``)."""
        return self.landmark or self.scene.route.center_asset

    def __post_init__(self) -> None:
        check_range("vpr.spacing_m", self.spacing_m, 0.01, 100.0)
        check_range("vpr.lateral_offset_m", self.lateral_offset_m, 0.0, 5.0)
        check_range("vpr.lookahead_jitter_m", self.lookahead_jitter_m, 0.0, 1.5)
        check_range("vpr.radius_m", self.radius_m, 0.0, 1e3, lo_open=True)
        check_range("vpr.jpeg_quality", self.jpeg_quality, 1, 100)
        self.camera_config(self.database)  # a bad [camera] key fails here, before any drive

    def camera_config(self, lighting: TraversalSpec, irradiance_scale: float = 1.0
                      ) -> CameraConfig:
        """The camera of one traversal: ``[camera]`` plus its lighting, distance-triggered,
        no depth (``irradiance_scale``: the scene's, :func:`.dataset.irradiance_scale`)."""
        cam = dataclass_from_mapping(CameraConfig, self.camera, "camera")
        return replace(cam, depth=False, stereo=False, trigger_distance_m=self.spacing_m,
                       tau=lighting.tau, sun_elevation_deg=lighting.sun_elevation_deg,
                       sun_azimuth_deg=lighting.sun_azimuth_deg, exposure=lighting.exposure,
                       irradiance_scale=irradiance_scale)

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: Path | None = None,
                  source: str = "<dict>") -> VprSpec:
        """Check a parsed VPR mapping (``[vpr]``, ``[camera]``, ``[scene]``, ``[database]``,
        ``[queries]``); relative paths resolve against ``base_dir``."""
        return _spec_from_dict(data, base_dir=base_dir, source=source)

    @classmethod
    def from_toml(cls, name_or_path: str | Path) -> VprSpec:
        """A spec TOML file, or a shipped protocol by name (:data:`PROTOCOLS`)."""
        p = Path(name_or_path)
        if str(name_or_path) in RENAMED and not p.exists():
            raise ConfigError(f"VPR protocol {name_or_path!r}: {RENAMED[str(name_or_path)]}")
        if str(name_or_path) in PROTOCOLS and not p.exists():
            text = resources.files("marsscene.benchmark.vpr").joinpath(
                f"data/vpr_{str(name_or_path).replace('-', '_')}.toml").read_text("utf-8")
            return _spec_from_dict(tomllib.loads(text), source=f"protocol {name_or_path}")
        if not p.exists() and p.suffix != ".toml":
            raise ConfigError(f"VPR spec not found: {p} (shipped protocols: "
                              f"{', '.join(PROTOCOLS)})")
        return _spec_from_dict(load_toml(p, what="VPR spec"), base_dir=p.parent.resolve(),
                               source=str(p))

    def with_length(self, length_m: float) -> VprSpec:
        """The same protocol on a shorter (or longer) automatic route."""
        if self.scene.route.shape is None:
            raise ConfigError("--length-m needs an automatic route (route.shape in the spec)")
        route = replace(self.scene.route, length_m=float(length_m))
        return replace(self, scene=replace(self.scene, route=route))


def _spec_from_dict(data: dict[str, Any], *, base_dir: Path | None = None,
                    source: str = "<dict>") -> VprSpec:
    """Check a parsed VPR TOML mapping and return a :class:`VprSpec`."""
    allowed = {"vpr", "camera", "scene", *SPLITS}
    if set(data) - allowed:
        raise ConfigError(f"{source}: unknown table(s) {sorted(set(data) - allowed)}; allowed: "
                          f"{', '.join(sorted(allowed))}")
    for key in ("scene", *SPLITS):
        if not isinstance(data.get(key), dict):
            raise ConfigError(f"{source}: needs a [{key}] table")
    here = base_dir or Path.cwd()
    raw_scene = dict(data["scene"])
    route = dict(raw_scene.get("route") or {})
    if isinstance(route.get("file"), str):
        route["file"] = str((here / route["file"]).resolve())
    raw_scene["route"] = route
    if isinstance(raw_scene.get("config"), str):
        raw_scene["config"] = str((here / raw_scene["config"]).resolve())
    scene = dataclass_from_mapping(SceneSpec, raw_scene, "scene")
    splits = {k: dataclass_from_mapping(TraversalSpec, data[k], k) for k in SPLITS}
    top = data.get("vpr", {})
    if not isinstance(top, dict):
        raise ConfigError(f"[vpr] must be a table; got {top!r}")
    known = {f for f in VprSpec.__dataclass_fields__
             if f not in ("scene", "camera", "source", *SPLITS)}
    if set(top) - known:
        raise ConfigError(f"unknown key vpr.{sorted(set(top) - known)[0]}; allowed: "
                          f"{sorted(known)}")
    camera = data.get("camera", {})
    if not isinstance(camera, dict):
        raise ConfigError(f"[camera] must be a table; got {camera!r}")
    try:
        return VprSpec(scene=scene, camera=dict(camera), source=source,
                       database=splits["database"], queries=splits["queries"], **top)
    except TypeError as err:
        raise ConfigError(f"{source}: {err}") from None
