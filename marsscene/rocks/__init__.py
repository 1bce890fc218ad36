"""Rocks: Golombek–Huertas size-frequency, placement, prototypes and collision parts."""

from __future__ import annotations

from marsscene.rocks.config import RockConfig as RockConfig
from marsscene.rocks.population import place_rocks as place_rocks
from marsscene.rocks.sfd import cumulative_area_fraction as cumulative_area_fraction
from marsscene.rocks.sfd import (
    cumulative_number_density_per_m2 as cumulative_number_density_per_m2,
)
from marsscene.rocks.sfd import diameter_cdf as diameter_cdf
from marsscene.rocks.sfd import differential_number_density as differential_number_density
from marsscene.rocks.sfd import expected_count as expected_count
from marsscene.rocks.sfd import sample_diameters as sample_diameters
from marsscene.rocks.shapes import RockPrototype as RockPrototype
from marsscene.rocks.shapes import make_prototypes as make_prototypes
from marsscene.rocks.shapes import rock_mesh as rock_mesh
from marsscene.rocks.table import RockTable as RockTable

__all__ = [
    "RockConfig",
    "RockPrototype",
    "RockTable",
    "cumulative_area_fraction",
    "cumulative_number_density_per_m2",
    "diameter_cdf",
    "differential_number_density",
    "expected_count",
    "make_prototypes",
    "place_rocks",
    "rock_mesh",
    "sample_diameters",
]
