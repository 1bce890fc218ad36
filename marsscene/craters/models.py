"""Names and citations of the crater models a configuration uses (for the manifest)."""

from __future__ import annotations

from marsscene.craters.config import CraterConfig
from marsscene.craters.functions import chronology_system, equilibrium_citation
from marsscene.craters.resurfacing import CITATION as RESURFACING_CITATION

__all__ = ["PROFILE_CITATIONS", "crater_models"]

#: Citation of each profile model (manifest).
PROFILE_CITATIONS: dict[str, str] = {
    "watters-2015": (
        "power-law cavity, exponent 1.75 (Watters, Geiger, Fendrock et al. 2015, JGR Planets "
        "120, doi:10.1002/2014JE004630); fresh d/D from Garvin & Frawley (1998, "
        "doi:10.1029/1998GL900177) held constant below 50 m (Millot et al. 2024, "
        "doi:10.1029/2024JE008844); rim height 0.036 D (Melosh 1989); ejecta (r/R)^-3 "
        "(McGetchin, Settle & Head 1973, doi:10.1016/0012-821X(73)90118-0)"
    ),
    "fassett-thomson-2014": (
        "Fassett, C. I., Thomson, B. J. (2014), Crater degradation on the lunar maria, JGR "
        "Planets 119, doi:10.1002/2014JE004698, Eq. 4"
    ),
    "ftmod": (
        "FTmod profile (Fassett pers. comm. 2022, as implemented in NeoGeographyToolkit/"
        "synthterrain) after Fassett & Thomson (2014), doi:10.1002/2014JE004698"
    ),
}


def crater_models(config: CraterConfig) -> list[tuple[str, str]]:
    """``(name, citation)`` of every crater model a :class:`CraterConfig` uses (manifest)."""
    cs = chronology_system(config.system)
    out = [
        (f"production function {cs.production}", cs.production_citation),
        (f"chronology function {cs.chronology}", cs.chronology_citation),
    ]
    if config.equilibrium != "none":
        out.append(("equilibrium hartmann-1984", equilibrium_citation()))
    out.append((f"crater profile {config.profile}",
                PROFILE_CITATIONS[config.profile]))
    if config.degradation == "diffusion":
        background = (f"; background kappa = {config.diffusivity_m2_per_myr} m^2/Myr"
                      if config.diffusivity_m2_per_myr > 0 else "")
        out.append((
            "crater degradation by topographic diffusion",
            "linear diffusion (Culling 1960; Soderblom 1970, doi:10.1029/JB075i014p02655), "
            "impact-driven on the crater-count clock so that craters stay recognisable "
            "(s <= 0.6) exactly until their size reaches the Hartmann (1984) equilibrium "
            "(size-dependent diffusivity as in Fassett & Thomson 2014, "
            f"doi:10.1002/2014JE004698){background}",
        ))
    if config.resurfacing:
        out.append(("partial resurfacing forward model", RESURFACING_CITATION))
    return out
