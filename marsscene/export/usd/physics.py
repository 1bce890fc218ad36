"""Physics materials (``UsdPhysics.MaterialAPI``) bound with the ``physics`` purpose.

The values are the MJCF exporter's, so a rover meets the same contact in Isaac Sim and MuJoCo:

* **Regolith** (terrain): static = dynamic friction = MJCF sliding friction
  (:data:`marsscene.export.mjcf.build.REGOLITH_FRICTION`, 0.8 ~ tan 38 deg; Martian soils have
  internal friction angles of 30-40 deg, Sullivan et al. 2011, doi:10.1029/2010JE003625).
* **Rock** (rock colliders): :data:`marsscene.export.mjcf.rocks.ROCK_FRICTION` (0.9; metal or
  rubber on rock 0.8-1.0).
* Restitution 0 for both: loose regolith is a dissipative granular medium, and MuJoCo's default
  contact (``solref`` 0.02 s, damping ratio 1) is critically damped, i.e. does not bounce either.

MuJoCo has one sliding coefficient, so static and dynamic friction are equal here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pxr import Sdf, UsdPhysics, UsdShade

from marsscene.export.mjcf.common import REGOLITH_FRICTION
from marsscene.export.mjcf.rocks import ROCK_FRICTION

__all__ = ["REGOLITH_PHYSICS", "ROCK_PHYSICS", "PhysicsMaterial", "author_physics_material",
           "bind_physics_material"]


@dataclass(frozen=True, slots=True)
class PhysicsMaterial:
    """Contact parameters of one surface."""

    name: str
    static_friction: float
    dynamic_friction: float
    restitution: float


REGOLITH_PHYSICS = PhysicsMaterial("RegolithPhysics", REGOLITH_FRICTION[0], REGOLITH_FRICTION[0],
                                   0.0)
ROCK_PHYSICS = PhysicsMaterial("RockPhysics", ROCK_FRICTION[0], ROCK_FRICTION[0], 0.0)


def author_physics_material(stage: Any, looks: Sdf.Path, spec: PhysicsMaterial) -> Any:
    """Define ``looks/<spec.name>``: a ``UsdShade.Material`` with ``UsdPhysics.MaterialAPI``."""
    mat = UsdShade.Material.Define(stage, looks.AppendChild(spec.name))
    api = UsdPhysics.MaterialAPI.Apply(mat.GetPrim())
    api.CreateStaticFrictionAttr(float(spec.static_friction))
    api.CreateDynamicFrictionAttr(float(spec.dynamic_friction))
    api.CreateRestitutionAttr(float(spec.restitution))
    return mat


def bind_physics_material(prim: Any, material: Any) -> None:
    """Bind ``material`` to ``prim`` for the ``physics`` purpose (render bindings untouched)."""
    UsdShade.MaterialBindingAPI.Apply(prim).Bind(
        material, UsdShade.Tokens.weakerThanDescendants, "physics"
    )
