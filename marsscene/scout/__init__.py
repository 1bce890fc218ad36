"""An Ingenuity-class helicopter scout: air density, rotor limits, MuJoCo flight dynamics, a
waypoint flight controller, a downward camera and an altimeter (:doc:`/scout`)."""

from marsscene.scout.aero import endurance_s, hover_power_w, max_thrust_n
from marsscene.scout.config import ScoutConfig, air_density_kg_m3
from marsscene.scout.flight import Flight, FlightPlan, fly

__all__ = ["Flight", "FlightPlan", "ScoutConfig", "air_density_kg_m3", "endurance_s", "fly",
           "hover_power_w", "max_thrust_n"]
