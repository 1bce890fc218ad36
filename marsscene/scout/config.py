"""The Ingenuity-class scout's numbers (``data/ingenuity.toml``, each cited there) and the Mars
air density it flies in.

Air density: an isothermal atmosphere, ``p = p0 exp(-z / H)`` with the mean surface pressure
``p0 = 610 Pa`` at the MOLA datum and the scale height ``H = 11.1 km`` (NASA NSSDC Mars fact
sheet), and the ideal gas ``rho = p / (R T)`` of CO2 (``R = 188.92 J/(kg K)``). At the Jezero
crater floor (-2,600 m, MOLA) and a daytime near-surface 220 K this gives 0.0185 kg/m^3, inside
the 0.014-0.020 kg/m^3 the helicopter was designed for (Balaram et al. 2018). The season moves
the pressure by about +-10 % (Perseverance MEDA; Viking landers): ``pressure_scale``.
"""

from __future__ import annotations

import functools
import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping
from marsscene.errors import ConfigError

__all__ = ["JEZERO_ELEVATION_M", "ScoutConfig", "air_density_kg_m3"]

SURFACE_PRESSURE_PA = 610.0
SCALE_HEIGHT_M = 11_100.0
CO2_GAS_CONSTANT_J_KG_K = 188.92
#: Jezero crater floor (MOLA), the default site's elevation.
JEZERO_ELEVATION_M = -2_600.0


def air_density_kg_m3(elevation_m: float = JEZERO_ELEVATION_M, *, temperature_k: float = 220.0,
                      pressure_scale: float = 1.0) -> float:
    """Mars near-surface air density (module doc) at ``elevation_m`` above the MOLA datum."""
    check_range("temperature_k", temperature_k, 120.0, 320.0)
    check_range("pressure_scale", pressure_scale, 0.5, 1.5)
    check_range("elevation_m", elevation_m, -9_000.0, 22_000.0)
    p = pressure_scale * SURFACE_PRESSURE_PA * math.exp(-elevation_m / SCALE_HEIGHT_M)
    return p / (CO2_GAS_CONSTANT_J_KG_K * temperature_k)


@dataclass(frozen=True, kw_only=True)
class ScoutConfig:
    """The helicopter (units in the names; ``data/ingenuity.toml`` cites each number)."""

    mass_kg: float
    rotor_diameter_m: float
    rpm_min: float
    rpm_max: float
    hover_rpm_ref: float
    density_ref_kg_m3: float
    coaxial_factor: float
    figure_of_merit: float
    drive_efficiency: float
    avionics_power_w: float
    battery_energy_wh: float
    published_hover_power_w: float
    published_flight_s: float
    drag_area_m2: float
    inertia_kg_m2: tuple[float, float, float]
    yaw_torque_max_nm: float
    tilt_torque_max_nm: float
    leg_half_span_m: float
    body_above_feet_m: float
    rotor_above_feet_m: float
    camera_fov_diag_deg: float
    altimeter_range_m: float
    altimeter_sigma_m: float
    sources: tuple[tuple[str, str], ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        check_range("scout.mass_kg", self.mass_kg, 0.1, 100.0)
        check_range("scout.rotor_diameter_m", self.rotor_diameter_m, 0.1, 10.0)
        check_range("scout.rpm_max", self.rpm_max, self.rpm_min, 1e5)
        for key in ("figure_of_merit", "drive_efficiency"):
            check_range(f"scout.{key}", getattr(self, key), 0.0, 1.0, lo_open=True)
        object.__setattr__(self, "inertia_kg_m2", tuple(float(v) for v in self.inertia_kg_m2))

    @classmethod
    def load(cls, name: str = "ingenuity") -> ScoutConfig:
        """A helicopter of ``data/NAME.toml`` (only ``ingenuity`` ships)."""
        return _load(name)

    @property
    def disk_area_m2(self) -> float:
        """One rotor's disk area (both rotors of a coaxial share it)."""
        return math.pi * (self.rotor_diameter_m / 2.0) ** 2


@functools.cache
def _load(name: str) -> ScoutConfig:
    path = resources.files("marsscene.scout").joinpath(f"data/{name}.toml")
    if not path.is_file():
        raise ConfigError(f"scout {name!r} is unknown; known: ingenuity")
    doc: dict[str, Any] = tomllib.loads(path.read_text())
    uncited = sorted(set(doc["vehicle"]) - set(doc["sources"]))
    if uncited:
        raise ConfigError(f"data/{name}.toml: uncited numbers {uncited}")
    cfg = dataclass_from_mapping(ScoutConfig, doc["vehicle"], "vehicle")
    import dataclasses

    return dataclasses.replace(cfg, sources=tuple(sorted(doc["sources"].items())))
