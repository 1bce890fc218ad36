"""Spinning-LiDAR configuration: named sensor models from datasheets and their beam geometry.

A :class:`LidarConfig` names a model (``data/lidar_models.toml``: ``simple``, ``vlp16``,
``os1-64``, ``os1-128``, each with its source) and may override any of its values; it resolves
to a :class:`LidarSpec` that holds every number the sensor model needs. Beam geometry:

* beam ``b`` has the elevation ``vertical_angles_deg[b]`` (firing order); its **ring** is its
  index among the beams sorted by elevation, lowest first (``velodyne_pointcloud`` convention);
* the head turns counter-clockwise seen from above (x forward, y left, z up) through
  ``horizontal_samples`` columns per revolution; column ``c`` fires at azimuth ``2 pi c / n``
  and at time ``c / (n rate_hz)`` after the scan's stamp, plus, for the VLP-16, the 2.304 us
  offset of each laser inside its firing sequence (VLP-16 manual, sec. 9.5).

Examples
--------
>>> spec = LidarConfig(model="vlp16").spec
>>> spec.channels, spec.horizontal_samples, spec.rings()[:4].tolist()
(16, 1800, [0, 8, 1, 9])
>>> LidarConfig(model="os1-64", horizontal_samples=512).spec.horizontal_samples
512
"""

from __future__ import annotations

import tomllib
from dataclasses import asdict, dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._validate import check_choice, check_range
from marsscene.errors import ConfigError
from marsscene.rover.rates import check_rate

__all__ = ["DEFAULT_LIDAR_MODEL", "LidarConfig", "LidarSpec", "lidar_models"]

#: The model of ``LidarConfig()`` and ``marsscene drive --lidar``.
DEFAULT_LIDAR_MODEL = "os1-128"
_VLP16_LASER_S = 2.304e-6  # one laser's slot inside a VLP-16 firing sequence
_FIRING_OFFSETS = ("none", "velodyne")


@lru_cache(maxsize=1)
def lidar_models() -> dict[str, dict[str, Any]]:
    """The named models (``data/lidar_models.toml``), each a table with its ``source``."""
    text = resources.files("marsscene.rover").joinpath("data/lidar_models.toml").read_text()
    return tomllib.loads(text)


@dataclass(frozen=True)
class LidarSpec:
    """A fully resolved spinning LiDAR (see the module docstring for the conventions)."""

    model: str
    vertical_angles_deg: tuple[float, ...]
    horizontal_samples: int
    rate_hz: float
    range_m: tuple[float, float]
    range_noise_sigma_m: float
    dropout_probability: float
    firing_offsets: str
    motion_distortion: bool
    dust_extinction_per_m: float

    @property
    def channels(self) -> int:
        return len(self.vertical_angles_deg)

    def rings(self) -> NDArray[np.int64]:
        """Ring of each beam (firing order): its rank by elevation, lowest first."""
        order = np.argsort(np.asarray(self.vertical_angles_deg), kind="stable")
        ring = np.zeros(self.channels, dtype=np.int64)
        ring[order] = np.arange(self.channels)
        return ring

    def column_azimuth_rad(self) -> NDArray[np.float64]:
        n = self.horizontal_samples
        return np.asarray(np.arange(n) * (2.0 * np.pi / n), dtype=np.float64)

    def firing_time_s(self) -> NDArray[np.float64]:
        """(channels, columns) firing time of every ray after the scan's stamp (s)."""
        n = self.horizontal_samples
        col = np.arange(n) / (n * self.rate_hz)
        beam = np.zeros(self.channels, dtype=np.float64)
        if self.firing_offsets == "velodyne":
            beam = np.arange(self.channels, dtype=np.float64) * _VLP16_LASER_S
        return np.asarray(beam[:, None] + col[None, :], dtype=np.float64)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready values (``run.json``'s ``lidar``), with ``channels`` and the source."""
        doc = asdict(self)
        doc["channels"] = self.channels
        doc["source"] = lidar_models().get(self.model, {}).get("source", "user-defined")
        return doc


@dataclass(frozen=True, kw_only=True)
class LidarConfig:
    """A spinning 3D LiDAR by ray casting: a named ``model`` (default ``"os1-128"``, the
    Ouster OS1-128; ``DEFAULT_LIDAR_MODEL``) with any of its values overridden.

    ``channels`` with ``vertical_fov_deg`` (or either alone, the other from the model) gives
    uniformly spaced beams; ``vertical_angles_deg`` gives them explicitly. Dust attenuates
    intensity by ``exp(-2 alpha r)`` (``dust_extinction_per_m`` = alpha), never range.
    """

    model: str = DEFAULT_LIDAR_MODEL
    """Datasheet model: ``simple``, ``vlp16``, ``os1-64`` or ``os1-128`` (the default)."""
    channels: int | None = None
    """Number of beams (None: the model's)."""
    vertical_fov_deg: tuple[float, float] | None = None
    """Lowest and highest beam elevation in degrees (None: the model's)."""
    vertical_angles_deg: tuple[float, ...] | None = None
    """Explicit beam elevations in degrees, instead of uniform spacing."""
    horizontal_samples: int | None = None
    """Columns per revolution (None: the model's)."""
    rate_hz: float | None = None
    """Revolutions per second (None: the model's, 10 Hz for all four)."""
    range_m: tuple[float, float] | None = None
    """Minimum and maximum range in m (None: the model's)."""
    range_noise_sigma_m: float | None = None
    """Gaussian range noise, 1 sigma in m (None: the model's datasheet accuracy)."""
    dropout_probability: float | None = None
    """Chance that a return within range is lost (None: the model's, 0)."""
    motion_distortion: bool = True
    """Cast each column from the pose at its firing time (the sensor moves during the sweep)."""
    dust_extinction_per_m: float = 0.0
    """Dust extinction alpha in 1/m: intensity falls as exp(-2 alpha r); range is unaffected."""

    def __post_init__(self) -> None:
        self.spec  # noqa: B018 - resolves and validates

    @property
    def spec(self) -> LidarSpec:
        """The resolved sensor (raises :class:`~marsscene.errors.ConfigError` if invalid)."""
        check_choice("lidar.model", self.model, tuple(lidar_models()))
        base = lidar_models()[self.model]
        spec = LidarSpec(
            model=self.model,
            vertical_angles_deg=self._angles(base),
            horizontal_samples=int(_pick(self.horizontal_samples, base["horizontal_samples"])),
            rate_hz=float(_pick(self.rate_hz, base["rate_hz"])),
            range_m=_pair(_pick(self.range_m, base["range_m"])),
            range_noise_sigma_m=float(_pick(self.range_noise_sigma_m,
                                            base["range_noise_sigma_m"])),
            dropout_probability=float(_pick(self.dropout_probability,
                                            base["dropout_probability"])),
            firing_offsets=str(base.get("firing_offsets", "none")),
            motion_distortion=bool(self.motion_distortion),
            dust_extinction_per_m=float(self.dust_extinction_per_m),
        )
        _check(spec)
        return spec

    def _angles(self, base: dict[str, Any]) -> tuple[float, ...]:
        if self.vertical_angles_deg is not None:
            return tuple(float(a) for a in self.vertical_angles_deg)
        if self.channels is None and self.vertical_fov_deg is None and \
                "vertical_angles_deg" in base:
            return tuple(float(a) for a in base["vertical_angles_deg"])
        if "vertical_fov_deg" not in base and self.vertical_fov_deg is None:
            raise ConfigError(f"lidar.channels on model {self.model!r} (explicit beam angles) "
                              "needs lidar.vertical_fov_deg or lidar.vertical_angles_deg too")
        channels = int(_pick(self.channels, base.get("channels",
                                                     len(base.get("vertical_angles_deg", ())))))
        if not 1 <= channels <= 256:
            raise ConfigError(f"lidar.channels = {channels!r} is out of range; allowed [1, 256]")
        lo, hi = _pair(_pick(self.vertical_fov_deg, base.get("vertical_fov_deg")))
        check_range("lidar.vertical_fov_deg[0]", lo, -90.0, 90.0)
        check_range("lidar.vertical_fov_deg[1]", hi, lo, 90.0)
        angles = np.linspace(lo, hi, channels) if channels > 1 else np.array([lo])
        return tuple(float(a) for a in angles)


def _pick(value: Any, default: Any) -> Any:
    return default if value is None else value


def _pair(value: Any) -> tuple[float, float]:
    try:
        a, b = value
        return float(a), float(b)
    except (TypeError, ValueError):
        raise ConfigError(f"expected two numbers; got {value!r}") from None


def _check(spec: LidarSpec) -> None:
    if not 1 <= spec.channels <= 256:
        raise ConfigError(f"lidar.vertical_angles_deg holds {spec.channels} beams; "
                          "allowed 1 to 256")
    for a in spec.vertical_angles_deg:
        check_range("lidar.vertical_angles_deg[]", a, -90.0, 90.0)
    if not 4 <= spec.horizontal_samples <= 8192:
        raise ConfigError(f"lidar.horizontal_samples = {spec.horizontal_samples!r} is out of "
                          "range; allowed [4, 8192]")
    rmin, rmax = spec.range_m
    check_range("lidar.range_m[0]", rmin, 0.0, 10.0)
    check_range("lidar.range_m[1]", rmax, rmin, 1000.0, lo_open=True)
    check_rate("lidar.rate_hz", spec.rate_hz)
    check_range("lidar.range_noise_sigma_m", spec.range_noise_sigma_m, 0.0, 1.0)
    check_range("lidar.dropout_probability", spec.dropout_probability, 0.0, 1.0)
    check_range("lidar.dust_extinction_per_m", spec.dust_extinction_per_m, 0.0, 1.0)
    check_choice("lidar.firing_offsets", spec.firing_offsets, _FIRING_OFFSETS)
