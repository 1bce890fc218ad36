"""The scene's soils in USD: one physics material per soil under ``/World/Soil``, with the
wheel--soil model's parameters as documented attributes, and the soil map on the terrain.

Each ``/World/Soil/<name>`` is a ``UsdShade.Material`` with ``UsdPhysics.MaterialAPI``
(static = dynamic friction = ``tan(friction angle)``, restitution 0) and ``marsscene:soil:*``
attributes in SI units: ``cohesionPa``, ``frictionDeg``, ``kc`` (N/m^(n+1)), ``kPhi``
(N/m^(n+2)), ``n``, ``nSlip``, ``shearModulusM``, ``a0``, ``a1``, ``exitRatio`` and
``reference`` (the source). ``/World/Terrain`` carries ``marsscene:soil:map`` (the asset
``soil/soil_map.png``: 8-bit indices, north row first, over ``marsscene:soil:boundsXYM``) and
``marsscene:soil:names`` (the soils by index). The model: :doc:`/science/terramechanics`.
"""

from __future__ import annotations

import math
from typing import Any

from pxr import Sdf, Vt

from marsscene.export.usd.physics import PhysicsMaterial, author_physics_material
from marsscene.export.usd.stage import WORLD

__all__ = ["author_soil"]

#: Soil dataclass field -> USD attribute name (``marsscene:soil:`` + this) and type.
_ATTRS = {
    "cohesion_pa": ("cohesionPa", Sdf.ValueTypeNames.Double),
    "friction_deg": ("frictionDeg", Sdf.ValueTypeNames.Double),
    "k_c": ("kc", Sdf.ValueTypeNames.Double),
    "k_phi": ("kPhi", Sdf.ValueTypeNames.Double),
    "n": ("n", Sdf.ValueTypeNames.Double),
    "n_slip": ("nSlip", Sdf.ValueTypeNames.Double),
    "shear_modulus_m": ("shearModulusM", Sdf.ValueTypeNames.Double),
    "a0": ("a0", Sdf.ValueTypeNames.Double),
    "a1": ("a1", Sdf.ValueTypeNames.Double),
    "exit_ratio": ("exitRatio", Sdf.ValueTypeNames.Double),
    "reference": ("reference", Sdf.ValueTypeNames.String),
}


def author_soil(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author the soil materials and map attributes (nothing when the scene has no soil map)."""
    soil_map = getattr(scene, "soil", None)
    if soil_map is None:
        return
    looks = Sdf.Path(f"{WORLD}/Soil")
    stage.DefinePrim(looks, "Scope")
    for s in soil_map.soils:
        mu = math.tan(math.radians(s.friction_deg))
        mat = author_physics_material(stage, looks, PhysicsMaterial(s.name, mu, mu, 0.0))
        prim = mat.GetPrim()
        for field, (name, kind) in _ATTRS.items():
            attr = prim.CreateAttribute(f"marsscene:soil:{name}", kind, custom=True)
            attr.Set(getattr(s, field) if kind == Sdf.ValueTypeNames.String
                     else float(getattr(s, field)))
    terrain = stage.GetPrimAtPath(f"{WORLD}/Terrain")
    terrain.CreateAttribute("marsscene:soil:map", Sdf.ValueTypeNames.Asset,
                            custom=True).Set(Sdf.AssetPath("./soil/soil_map.png"))
    terrain.CreateAttribute("marsscene:soil:names", Sdf.ValueTypeNames.TokenArray,
                            custom=True).Set(Vt.TokenArray([s.name for s in soil_map.soils]))
    terrain.CreateAttribute("marsscene:soil:boundsXYM", Sdf.ValueTypeNames.Double4,
                            custom=True).Set(tuple(float(v) for v in soil_map.bounds_xy_m))
