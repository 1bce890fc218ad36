"""Craters: Mars production/chronology functions, populations, profiles and stamping.

>>> import marsscene.craters as mc
>>> round(float(mc.cumulative_density_per_km2(100.0, age_ga=3.5)), 4)  # neukum-ivanov-2001
10.3613
"""

from __future__ import annotations

from marsscene.craters.config import CraterConfig as CraterConfig
from marsscene.craters.config import ResurfacingEvent as ResurfacingEvent
from marsscene.craters.functions import SYSTEMS as SYSTEMS
from marsscene.craters.functions import age_from_n1_ga as age_from_n1_ga
from marsscene.craters.functions import chronology_system as chronology_system
from marsscene.craters.functions import cumulative_density_per_km2 as cumulative_density_per_km2
from marsscene.craters.functions import equilibrium_density_per_km2 as equilibrium_density_per_km2
from marsscene.craters.functions import n1_per_km2 as n1_per_km2
from marsscene.craters.functions import production_shape as production_shape
from marsscene.craters.models import crater_models as crater_models
from marsscene.craters.morphology import PROFILE_IDS as PROFILE_IDS
from marsscene.craters.morphology import crater_profile as crater_profile
from marsscene.craters.morphology import profile_family as profile_family
from marsscene.craters.population import PopulationStats as PopulationStats
from marsscene.craters.population import sample_craters as sample_craters
from marsscene.craters.population import size_distribution as size_distribution
from marsscene.craters.stamp import stamp_craters as stamp_craters
from marsscene.craters.table import CraterTable as CraterTable

__all__ = [
    "PROFILE_IDS",
    "SYSTEMS",
    "CraterConfig",
    "CraterTable",
    "PopulationStats",
    "ResurfacingEvent",
    "age_from_n1_ga",
    "chronology_system",
    "crater_models",
    "crater_profile",
    "cumulative_density_per_km2",
    "equilibrium_density_per_km2",
    "n1_per_km2",
    "production_shape",
    "profile_family",
    "sample_craters",
    "size_distribution",
    "stamp_craters",
]
