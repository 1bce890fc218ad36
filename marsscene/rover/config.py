"""Runtime configs: rover geometry/limits, sensor noise, sensor rates (frozen, validated)."""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import math
import tomllib
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from marsscene._validate import check_choice, check_range, dataclass_from_mapping
from marsscene.errors import ConfigError
from marsscene.rover.lidar import LidarConfig
from marsscene.rover.rates import check_rate

__all__ = [
    "GOAL_TOLERANCE_M", "OMEGA_MAX_RAD_S", "PERSEVERANCE_BODY", "V_MAX_M_S", "CameraConfig",
    "LidarConfig", "NoiseConfig", "RoverBody", "RoverConfig", "RoverType", "RunConfig",
    "noise_profiles", "rover_body", "rover_types",
]

#: The MarsLab protocol's bounds on ``cmd_vel``: forward speed (m/s) and yaw rate (rad/s). The
#: route follower and the environments' actions are held to them.
V_MAX_M_S = 0.5
OMEGA_MAX_RAD_S = 0.2
#: A point goal is reached within this distance of ``base_link`` (m), horizontally: a sixth of
#: the rover's 3 m length (the navigation task's goal and a live session's ``/marsscene/goal``).
GOAL_TOLERANCE_M = 0.5


def _read_doc(path: str | Path, what: str) -> Any:
    """A ``.json`` or ``.toml`` file's contents (one-line :class:`ConfigError` if unreadable)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        return json.loads(text) if p.suffix == ".json" else tomllib.loads(text)
    except (OSError, ValueError) as err:
        raise ConfigError(f"cannot read {what} {p}: {err}") from None


@dataclass(frozen=True, kw_only=True)
class RoverConfig:
    """Perseverance-class rover (see :doc:`/runtime` for sources of every number).

    Lengths in m, masses in kg, torques in N m, speeds in rad/s.
    """

    mass_kg: float = 1025.0
    wheel_radius_m: float = 0.2625
    wheel_width_m: float = 0.40
    wheelbase_front_m: float = 1.05
    """x of the front wheel axle ahead of the middle axle."""
    wheelbase_rear_m: float = 1.00
    """x of the rear wheel axle behind the middle axle."""
    track_m: float = 2.0
    """Distance between left and right wheel centres."""
    ride_height_m: float = 0.75
    """Height of the chassis frame (base_link) above the ground on flat terrain."""
    drive_torque_limit_nm: float = 300.0
    drive_kv_nm_s: float = 3000.0
    wheel_speed_limit_rad_s: float = 3.0
    steer_limit_rad: float = math.radians(100.0)
    steer_kp_nm: float = 2000.0
    steer_torque_limit_nm: float = 500.0
    friction: float = 0.8
    """Wheel/ground sliding friction (matches the scene's regolith, tan 38.7 deg)."""
    mast_height_m: float = 1.98
    """Navcam height above the ground."""
    wheel_collision: str = "cylinder"
    """``"cylinder"`` (true width, default) or ``"sphere"`` (~1.5x faster, point contact)."""

    def __post_init__(self) -> None:
        check_range("rover.mass_kg", self.mass_kg, 50.0, 5000.0)
        check_range("rover.wheel_radius_m", self.wheel_radius_m, 0.05, 1.0)
        check_range("rover.wheel_width_m", self.wheel_width_m, 0.02, 1.0)
        check_range("rover.wheelbase_front_m", self.wheelbase_front_m, 0.2, 3.0)
        check_range("rover.wheelbase_rear_m", self.wheelbase_rear_m, 0.2, 3.0)
        check_range("rover.track_m", self.track_m, 2 * self.wheel_width_m + 0.2, 5.0)
        check_range("rover.ride_height_m", self.ride_height_m, self.wheel_radius_m + 0.2, 3.0)
        check_range(
            "rover.drive_torque_limit_nm", self.drive_torque_limit_nm, 0.0, 1e4, lo_open=True
        )
        check_range("rover.drive_kv_nm_s", self.drive_kv_nm_s, 0.0, 1e5, lo_open=True)
        check_range("rover.wheel_speed_limit_rad_s", self.wheel_speed_limit_rad_s, 0.1, 50.0)
        check_range("rover.steer_limit_rad", self.steer_limit_rad, 0.0, math.pi, lo_open=True)
        check_range("rover.steer_kp_nm", self.steer_kp_nm, 0.0, 1e6, lo_open=True)
        check_range(
            "rover.steer_torque_limit_nm", self.steer_torque_limit_nm, 0.0, 1e5, lo_open=True
        )
        check_range("rover.friction", self.friction, 0.05, 2.0)
        check_range("rover.mast_height_m", self.mast_height_m, self.ride_height_m, 5.0)
        check_choice("rover.wheel_collision", self.wheel_collision, ("cylinder", "sphere"))

    @classmethod
    def load(cls, name: str) -> RoverConfig:
        """A rover type by name: ``"perseverance"`` (the default :class:`RoverConfig`) or a
        file ``data/rovers/NAME.toml`` (:func:`rover_types`), or a path to such a file.

        Examples
        --------
        >>> RoverConfig.load("mer").mass_kg
        185.0
        """
        if name == "perseverance":
            return RoverConfig()
        path = Path(name)
        if path.suffix != ".toml":
            types = rover_types()
            if name not in types:
                raise ConfigError(f"rover type {name!r} is unknown; known: "
                                  f"{', '.join(['perseverance', *types])}")
            path = types[name]
        return _rover_type(path)


@dataclass(frozen=True, kw_only=True)
class RoverBody:
    """A rover type's suspension, link masses, chassis and sensor mounts (lengths in m, masses
    in kg, ``base_link`` frame); the defaults are the Perseverance-class rover's
    (:doc:`/runtime`). The link table (:mod:`marsscene.rover.links`) and the sensor mounts
    (:mod:`marsscene.rover.geometry`) read them."""

    rocker_kg: float = 30.0
    bogie_kg: float = 20.0
    steer_kg: float = 4.0
    wheel_kg: float = 20.0
    rocker_y_frac: float = 0.375
    """Rocker pivot |y| as a fraction of the track."""
    pivot_above_ground_m: float = 0.65
    """Rocker pivot height on flat ground."""
    bogie_above_ground_m: float = 0.45
    """Bogie pivot height on flat ground."""
    bogie_half_m: float = 0.5
    """Half the bogie's length (middle to rear axle / 2: the middle axle sits at x = 0)."""
    rocker_rise_m: float = 0.2
    """The rocker's front end above the front wheel centre."""
    chassis_half_m: tuple[float, float, float] = (0.9, 0.55, 0.2)
    chassis_z_m: float = 0.05
    mast_x_m: float = 0.7
    mast_radius_m: float = 0.06
    rocker_radius_m: float = 0.06
    bogie_radius_m: float = 0.05
    steer_unit_m: tuple[float, float, float] = (0.05, 0.15, 0.2)
    """Steering unit: radius, half height, z of the centre above the wheel centre."""
    diff_bar_half_m: tuple[float, float, float] = (0.04, 0.75, 0.03)
    diff_x_m: float = -0.6
    diff_z_m: float = 0.35
    lidar_x_m: float = 0.7
    lidar_above_camera_m: float = 0.12
    camera_x_m: float = 0.75
    camera_tilt_deg: float = 20.0

    def __post_init__(self) -> None:
        for key in ("rocker_kg", "bogie_kg", "steer_kg", "wheel_kg"):
            check_range(f"body.{key}", getattr(self, key), 0.0, 500.0, lo_open=True)
        check_range("body.rocker_y_frac", self.rocker_y_frac, 0.05, 0.5)
        check_range("body.camera_tilt_deg", self.camera_tilt_deg, -90.0, 90.0)
        for key in ("chassis_half_m", "steer_unit_m", "diff_bar_half_m"):
            value = tuple(float(v) for v in getattr(self, key))
            if len(value) != 3 or min(value[:2]) <= 0:
                raise ConfigError(f"body.{key} = {value!r} must be 3 numbers, the first two > 0")
            object.__setattr__(self, key, value)


#: The Perseverance-class rover's body: the default of every :class:`RoverConfig`.
PERSEVERANCE_BODY = RoverBody()


@dataclass(frozen=True, kw_only=True)
class RoverType(RoverConfig):
    """A named rover type (``data/rovers/NAME.toml``): a :class:`RoverConfig` with its own
    ``body`` and top speed. ``sources`` cites every number of the file (not compared)."""

    name: str
    body: RoverBody = PERSEVERANCE_BODY
    max_speed_m_s: float = 0.5
    """The published top speed on flat ground (m/s); the wheel speed limit follows from it."""
    sources: tuple[tuple[str, str], ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_range("rover.max_speed_m_s", self.max_speed_m_s, 0.001, 5.0)
        rear = self.wheelbase_rear_m / 2.0
        if abs(self.body.bogie_half_m - rear) > 1e-9:
            raise ConfigError(f"rover {self.name}: body.bogie_half_m = {self.body.bogie_half_m} "
                              f"must be half the rear wheelbase ({rear})")


def rover_body(cfg: RoverConfig) -> RoverBody:
    """The body of ``cfg``: its type's, else the Perseverance-class rover's."""
    return cfg.body if isinstance(cfg, RoverType) else PERSEVERANCE_BODY


def rover_types() -> dict[str, Path]:
    """The rover types shipped as data (``data/rovers/*.toml``): name -> file."""
    folder = resources.files("marsscene.rover").joinpath("data/rovers")
    return {Path(str(p)).stem: Path(str(p)) for p in sorted(folder.iterdir(), key=str)
            if str(p).endswith(".toml")}


@functools.cache
def _rover_type(path: Path) -> RoverType:
    doc = _read_doc(path, "rover type")
    if not isinstance(doc, dict) or not isinstance(doc.get("rover"), dict):
        raise ConfigError(f"{path}: a rover type has a [rover] table")
    rover = dict(doc["rover"])
    sources = doc.get("sources", {})
    if not isinstance(sources, dict):
        raise ConfigError(f"{path}: [sources] maps each number to its reference")
    known = set(RoverType.__dataclass_fields__) | set(RoverBody.__dataclass_fields__)
    uncited = sorted(k for k in (*rover, *doc.get("body", {})) if k != "name" and k not in sources)
    if uncited or set(sources) - known:
        raise ConfigError(f"{path}: uncited numbers {uncited} or unknown sources "
                          f"{sorted(set(sources) - known)}")
    if "steer_limit_deg" in rover:
        rover["steer_limit_rad"] = math.radians(rover.pop("steer_limit_deg"))
    if "max_speed_m_s" in rover and "wheel_radius_m" in rover:  # the speed limit's wheel rate
        limit = rover["max_speed_m_s"] / rover["wheel_radius_m"]
        rover.setdefault("wheel_speed_limit_rad_s", limit)
    rover.setdefault("name", path.stem)
    typed = dataclass_from_mapping(RoverType, {**rover, "body": doc.get("body", {})}, "rover")
    return dataclasses.replace(typed, sources=tuple(sorted(sources.items())))



def noise_profiles() -> dict[str, dict[str, Any]]:
    """The named noise profiles (``data/noise_profiles.toml``), each with its ``source``."""
    return copy.deepcopy(_noise_profiles())


@functools.cache
def _noise_profiles() -> dict[str, dict[str, Any]]:
    text = resources.files("marsscene.rover").joinpath("data/noise_profiles.toml").read_text()
    return tomllib.loads(text)


#: NoiseConfig fields a profile sets (NaN in the dataclass = "take the profile's value").
_PROFILE_KEYS = (
    "gyro_noise_density_rad_s_rthz", "gyro_bias_walk_rad_s2_rthz", "gyro_turn_on_bias_rad_s",
    "accel_noise_density_m_s2_rthz", "accel_bias_walk_m_s3_rthz", "accel_turn_on_bias_m_s2",
    "wheel_rate_sigma_rad_s", "slip_mean", "slip_sigma", "steer_sigma_rad",
)


@dataclass(frozen=True, kw_only=True)
class NoiseConfig:
    """Sensor noise drawn from a seeded rng, starting from a named profile.

    ``profile`` names a table of ``data/noise_profiles.toml`` (``none``: all zero, the
    default; ``ln200s``: Mars-rover class; ``adis16495``: MEMS research-rover class); every
    profile field left unset (NaN) takes the profile's value, a field given overrides it.
    ``dataclasses.replace`` keeps resolved values: switch profiles with :meth:`with_profile`.

    IMU, per axis: ``true + bias + n`` with white noise of density ``*_noise_density_*`` plus
    ``*_sigma_*`` per sample, and a bias = the fixed ``*_bias_*`` + a per-run turn-on bias
    ``N(0, *_turn_on_bias_*)`` + a random walk of density ``*_bias_walk_*``
    (:class:`marsscene.sensors.imu.ImuNoise`). Wheel odometry measures each wheel rate as
    ``w * (1 + slip) + n`` with ``slip ~ N(slip_mean, slip_sigma)`` and
    ``n ~ N(0, wheel_rate_sigma_rad_s)`` per sample and wheel.
    """

    profile: str = "none"
    """Named profile the other fields start from: ``none`` (the default: noise-free, an
    optimistic odometry), ``ln200s`` (the SLAM benchmark's default) or ``adis16495``."""
    wheel_rate_sigma_rad_s: float = math.nan
    """Additive Gaussian noise per wheel-rate sample, rad/s (NaN: the profile's)."""
    slip_mean: float = math.nan
    """Mean of the multiplicative slip of the measured wheel rates (NaN: the profile's)."""
    slip_sigma: float = math.nan
    """Standard deviation of that slip per sample and wheel (NaN: the profile's)."""
    steer_sigma_rad: float = math.nan
    """Steering-encoder noise, rad (NaN: the profile's)."""
    accel_sigma_m_s2: float = 0.0
    """Extra white accelerometer noise per sample, m/s^2."""
    gyro_sigma_rad_s: float = 0.0
    """Extra white gyro noise per sample, rad/s."""
    accel_bias_m_s2: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Fixed accelerometer bias (x, y, z), m/s^2."""
    gyro_bias_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Fixed gyro bias (x, y, z), rad/s."""
    gyro_noise_density_rad_s_rthz: float = math.nan
    """White rate noise, rad/s/sqrt(Hz) (ARW; EuRoC ``gyroscope_noise_density``)."""
    gyro_bias_walk_rad_s2_rthz: float = math.nan
    """Bias random walk, rad/s^2/sqrt(Hz) (EuRoC ``gyroscope_random_walk``)."""
    gyro_turn_on_bias_rad_s: float = math.nan
    """1-sigma constant bias drawn once per run (bias repeatability)."""
    accel_noise_density_m_s2_rthz: float = math.nan
    """White acceleration noise, m/s^2/sqrt(Hz) (VRW; EuRoC ``accelerometer_noise_density``)."""
    accel_bias_walk_m_s3_rthz: float = math.nan
    """Bias random walk, m/s^3/sqrt(Hz) (EuRoC ``accelerometer_random_walk``)."""
    accel_turn_on_bias_m_s2: float = math.nan
    """1-sigma constant bias drawn once per run (bias repeatability)."""

    def __post_init__(self) -> None:
        profiles = _noise_profiles()
        if not isinstance(self.profile, str) or self.profile not in profiles:
            raise ConfigError(f"noise.profile = {self.profile!r} is unknown; known profiles: "
                              f"{', '.join(profiles)}")
        base = profiles[self.profile]
        for key in _PROFILE_KEYS:
            value = getattr(self, key)
            if isinstance(value, float) and math.isnan(value):
                object.__setattr__(self, key, float(base[key]))
        check_range("noise.wheel_rate_sigma_rad_s", self.wheel_rate_sigma_rad_s, 0.0, 10.0)
        check_range("noise.slip_mean", self.slip_mean, -0.5, 0.9)
        check_range("noise.slip_sigma", self.slip_sigma, 0.0, 1.0)
        check_range("noise.steer_sigma_rad", self.steer_sigma_rad, 0.0, 1.0)
        check_range("noise.accel_sigma_m_s2", self.accel_sigma_m_s2, 0.0, 10.0)
        check_range("noise.gyro_sigma_rad_s", self.gyro_sigma_rad_s, 0.0, 10.0)
        for key in _PROFILE_KEYS[:6]:
            check_range(f"noise.{key}", getattr(self, key), 0.0, 1.0)
        for key in ("accel_bias_m_s2", "gyro_bias_rad_s"):
            value = tuple(getattr(self, key))
            if len(value) != 3:
                raise ConfigError(f"noise.{key} = {value!r} must have 3 components (x, y, z)")
            for i, v in enumerate(value):
                check_range(f"noise.{key}[{i}]", v, -10.0, 10.0)
            object.__setattr__(self, key, tuple(float(v) for v in value))

    @classmethod
    def from_dict(cls, mapping: Any) -> NoiseConfig:
        """From a table (optionally wrapped in a ``noise`` key); unknown keys are an error."""
        if isinstance(mapping, dict) and "noise" in mapping:
            mapping = mapping["noise"]
        return dataclass_from_mapping(cls, mapping, "noise")

    @classmethod
    def from_toml(cls, path: str | Path) -> NoiseConfig:
        """Read a ``.toml`` (optionally with a ``[noise]`` table) noise config (``.json`` too)."""
        return cls.from_dict(_read_doc(path, "noise config"))

    def with_profile(self, name: str) -> NoiseConfig:
        """The same config on profile ``name``: fields that differ from the current profile's
        values (explicit overrides) are kept, the rest come from ``name``."""
        base = NoiseConfig(profile=self.profile)
        over = {k: v for k, v in asdict(self).items()
                if k != "profile" and v != getattr(base, k)}
        return NoiseConfig(profile=name, **over)

    def white_sigmas(self, rate_hz: float) -> tuple[float, float]:
        """Per-sample white-noise sigma (gyro rad/s, accel m/s^2) at an IMU rate of ``rate_hz``:
        ``sqrt(sigma^2 + density^2 * rate)``."""
        return (math.hypot(self.gyro_sigma_rad_s,
                           self.gyro_noise_density_rad_s_rthz * math.sqrt(rate_hz)),
                math.hypot(self.accel_sigma_m_s2,
                           self.accel_noise_density_m_s2_rthz * math.sqrt(rate_hz)))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class CameraConfig:
    """Mast RGB-D camera rendered offscreen (``MUJOCO_GL=egl`` or ``osmesa``).

    See :doc:`/camera`: appearance, lighting, exposure and the stereo pair.
    """

    width_px: int = 640
    """Image width in pixels."""
    height_px: int = 480
    """Image height in pixels."""
    fovy_deg: float = 60.0
    """Vertical field of view in degrees (pinhole, no distortion)."""
    rate_hz: float = 10.0
    """Frame rate in Hz (must divide the physics rate)."""
    depth: bool = True
    """Also log a metric depth image (uint16 mm PNG) registered to the colour image."""
    shadows: bool = True
    """Sun shadow map (3072 texels over +-20 m around the camera: 1.3 cm texels, locked to the
    world)."""
    terrain_window_m: float = 60.0
    """Render a full-resolution terrain window this wide around the rover (speed)."""
    texture_tile_m: float = 8.0
    """Ground size of the seeded regolith detail tile (it repeats with this period)."""
    texture_px: int = 2048
    """Texels per side of the detail tile (8 m / 2048 = 3.9 mm texels)."""
    near_window_m: float = 16.0
    """Full-resolution ground square ahead of the camera, textured at the tile's texel size."""
    far_post_stride: int = 2
    """The rest of the terrain window uses every n-th post (and 8x coarser texels)."""
    exposure: str = "auto"
    """``"auto"`` (mean sRGB intensity -> ``target_mean``) or ``"fixed"`` (``exposure_gain``)."""
    target_mean: float = 0.45
    """Auto mode: mean sRGB intensity the exposure aims for."""
    exposure_gain: float = 1.0
    """Fixed mode: linear 1.0 = albedo 0.5 under 600 W/m^2, times this gain."""
    sensor_noise: bool = False
    """Shot + read noise (10 000 e- full well, 10 e- read noise), from the sensor rng."""
    stereo: bool = False
    """Also render a rectified Navcam-like stereo pair (camera/left, camera/right)."""
    stereo_baseline_m: float = 0.424
    """Stereo baseline in m (Perseverance's Navcams: 0.424 m)."""
    tau: float | None = None
    """Override the scene's dust optical depth (lighting is recomputed)."""
    sun_elevation_deg: float | None = None
    """Override the sun's elevation in degrees (lighting is recomputed)."""
    sun_azimuth_deg: float | None = None
    """Override the sun's azimuth in degrees clockwise from north (lighting is recomputed)."""
    irradiance_scale: float = 1.0
    """Multiplies the sun's and the sky's irradiance; their directions, colours and the
    shadows stay. With ``exposure = "fixed"`` the frames darken by this factor (a dimmer scene
    under the same sun); the auto exposure brings them back up to its longest exposure."""
    trigger_distance_m: float | None = None
    """Capture a frame every this many metres driven (horizontal path, checked at the control
    rate) instead of at ``rate_hz``: place-recognition datasets sample space, not time."""

    def __post_init__(self) -> None:
        if not (16 <= int(self.width_px) <= 4096 and 16 <= int(self.height_px) <= 4096):
            raise ConfigError(
                f"camera size {self.width_px}x{self.height_px} is out of range; allowed 16..4096 px"
            )
        check_range("camera.fovy_deg", self.fovy_deg, 5.0, 170.0)
        check_range("camera.terrain_window_m", self.terrain_window_m, 5.0, 1e5)
        check_range("camera.texture_tile_m", self.texture_tile_m, 0.5, 100.0)
        check_range("camera.near_window_m", self.near_window_m, 1.0, 1e4)
        if not 1 <= int(self.far_post_stride) <= 8:
            raise ConfigError(f"camera.far_post_stride = {self.far_post_stride!r}; allowed 1..8")
        if not 64 <= int(self.texture_px) <= 8192:
            raise ConfigError(f"camera.texture_px = {self.texture_px!r}; allowed 64..8192")
        check_choice("camera.exposure", self.exposure, ("auto", "fixed"))
        check_range("camera.target_mean", self.target_mean, 0.05, 0.95)
        check_range("camera.exposure_gain", self.exposure_gain, 0.0, 1e4, lo_open=True)
        check_range("camera.stereo_baseline_m", self.stereo_baseline_m, 0.01, 5.0)
        if self.tau is not None:
            check_range("camera.tau", self.tau, 0.0, 10.0)
        if self.sun_elevation_deg is not None:
            check_range("camera.sun_elevation_deg", self.sun_elevation_deg, -10.0, 90.0)
        if self.sun_azimuth_deg is not None:
            check_range("camera.sun_azimuth_deg", self.sun_azimuth_deg, -360.0, 360.0)
        check_range("camera.irradiance_scale", self.irradiance_scale, 0.0, 1e3, lo_open=True)
        if self.trigger_distance_m is not None:
            check_range("camera.trigger_distance_m", self.trigger_distance_m, 0.01, 1e4)
        check_rate("camera.rate_hz", self.rate_hz)


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """Rates of the physics, the control loop and the logs, the sensors and their noise.

    Every rate divides the physics rate: the scene's (:data:`~marsscene.rover.rates.PHYSICS_HZ`,
    a 2 ms step), or ``physics_hz``.
    A coarser physics step is faster and stays close to the 2 ms reference: 100 Hz (10 ms) runs
    about 4x faster and drives the same route to within a few centimetres over 20 s
    (:doc:`/runtime`, "Physics rate").
    """

    control_hz: float = 50.0
    """Control rate in Hz: pure pursuit or the controller, odometry and ground truth logs."""
    imu_hz: float = 100.0
    """IMU rate in Hz."""
    lidar: LidarConfig | None = None
    """The LiDAR, or None for none (the default)."""
    camera: CameraConfig | None = None
    """The mast camera, or None for none (the default)."""
    noise: NoiseConfig = field(default_factory=NoiseConfig)
    """IMU and wheel-odometry noise; the default is the ``none`` profile (noise-free: an
    optimistic odometry; the SLAM benchmark uses ``ln200s``)."""
    physics_hz: float | None = None
    """Physics rate (Hz); None: the scene's (:data:`~marsscene.rover.rates.PHYSICS_HZ`)."""
    soil: str | None = None
    """Deformable soil under the wheels, by name (``marsscene.rover.terramechanics.soils``:
    slip, sinkage and their forces, :doc:`/science/terramechanics`); None: the terrain's
    rigid contact."""

    def __post_init__(self) -> None:
        if self.soil is not None and self.soil != "rigid":
            from marsscene.rover.terramechanics import soil

            soil(self.soil)  # one-line error for an unknown name
        if self.physics_hz is None:
            check_rate("run.control_hz", self.control_hz)
            check_rate("run.imu_hz", self.imu_hz)
            return
        check_range("run.physics_hz", self.physics_hz, 50.0, 2000.0)
        rates = {"run.control_hz": self.control_hz, "run.imu_hz": self.imu_hz}
        if self.lidar is not None:
            rates["lidar.rate_hz"] = self.lidar.spec.rate_hz
        if self.camera is not None and self.camera.trigger_distance_m is None:
            rates["camera.rate_hz"] = self.camera.rate_hz
        for key, rate in rates.items():
            check_rate(key, rate, self.physics_hz)

    @classmethod
    def from_toml(cls, path: str | Path) -> RunConfig:
        r"""Read a run config: ``.toml`` (or ``.json``) with optional tables ``[run]``
        (``control_hz``, ``imu_hz``), ``[lidar]`` (e.g. ``model = "vlp16"``), ``[camera]`` and
        ``[noise]``; a sensor without its table is off.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> p = pathlib.Path(tempfile.mkdtemp()) / "run.toml"
        >>> _ = p.write_text('[lidar]\nmodel = "vlp16"\n')
        >>> RunConfig.from_toml(p).lidar.spec.channels
        16
        """
        p = Path(path)
        return cls.from_dict(_read_doc(p, "run config"), source=str(p))

    @classmethod
    def from_dict(cls, doc: Any, *, source: str = "run config") -> RunConfig:
        """From a table of tables ``run``, ``lidar``, ``camera``, ``noise`` (a sensor without
        its table is off)."""
        p = source
        if not isinstance(doc, dict):
            raise ConfigError(f"{p}: a run config is a table of tables")
        unknown = sorted(set(doc) - {"run", "lidar", "camera", "noise"})
        if unknown:
            raise ConfigError(f"{p}: unknown table(s) {unknown}; allowed: run, lidar, camera, "
                              "noise")
        rates = doc.get("run", {})
        if not isinstance(rates, dict) or set(rates) - {"control_hz", "imu_hz", "physics_hz",
                                                        "soil"}:
            raise ConfigError(f"{p}: [run] takes control_hz, imu_hz, physics_hz and soil; got "
                              f"{rates!r}")
        sensors = {
            key: dataclass_from_mapping(kind, doc[key], key)
            for key, kind in (("lidar", LidarConfig), ("camera", CameraConfig),
                              ("noise", NoiseConfig)) if key in doc
        }
        rates = {k: v if k == "soil" else float(v) for k, v in rates.items()}
        return cls(**rates, **sensors)  # type: ignore[arg-type]
