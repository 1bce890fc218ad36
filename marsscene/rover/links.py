"""The rover as a tree of links, joints and shapes (pure): the one table of numbers that both
rover writers read, MJCF (:mod:`marsscene.sim.rover_model`) and USD
(:mod:`marsscene.export.usd.rover`).

Every link frame is parallel to ``base_link`` (x forward, y left, z up) in the zero pose; a
link's ``pos_m`` is its origin in its parent's frame and also the joint's position (hinge
axes in ``Joint.axis``). Shapes carry their own mass; a link's mass, centre of mass and
inertia follow from its shapes with MuJoCo's rules (uniform density per shape,
:func:`link_inertia`), so the USD ``MassAPI`` values equal what MuJoCo computes for the MJCF
(tested against the compiled model).

The differential: MuJoCo couples the rockers with a joint equality
(``rocker_left = -rocker_right``). USD has no such coupling that both PhysX and Newton read,
so the USD rover carries the mechanism instead (:func:`differential_links`): a bar on the
deck pivoting about x and two vertical rods, bar to rocker, with ball joints at both ends;
the rod-to-rocker joints close the loops and are excluded from the articulation. Their 3 kg
come out of the chassis, so both rovers weigh ``RoverConfig.mass_kg``
(:func:`loop_joints`).
Numbers and sources: :doc:`/runtime`; the USD rover: :doc:`/usd_rover`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.config import PERSEVERANCE_BODY as _P
from marsscene.rover.config import RoverBody, RoverConfig, rover_body

__all__ = [
    "BOGIE_KG",
    "DRIVE_ARMATURE_KG_M2",
    "DRIVE_DAMPING_NM_S",
    "ROCKER_KG",
    "STEER_ACT_KV_NM_S",
    "STEER_KG",
    "WHEEL_KG",
    "Joint",
    "Link",
    "LoopJoint",
    "Shape",
    "chassis_mass_kg",
    "differential_links",
    "link_inertia",
    "loop_joints",
    "rover_links",
]

# The Perseverance-class rover's body (a rover type's own: rover_body(cfg)). Masses (kg):
# rockers, bogies, corner steering units, wheels; the chassis body (incl. mast, arm, RTG) takes
# the rest of RoverConfig.mass_kg.
ROCKER_KG, BOGIE_KG, STEER_KG, WHEEL_KG = _P.rocker_kg, _P.bogie_kg, _P.steer_kg, _P.wheel_kg
CHASSIS_HALF_M = _P.chassis_half_m
CHASSIS_Z_M = _P.chassis_z_m
ROCKER_RANGE_RAD, BOGIE_RANGE_RAD = 0.5, 0.6
ROCKER_DAMPING_NM_S = BOGIE_DAMPING_NM_S = 20.0
STEER_ARMATURE_KG_M2, STEER_DAMPING_NM_S = 1.0, 50.0
STEER_ACT_KV_NM_S = 200.0
"""Damping of the steering position servo (MJCF ``kv``)."""
DRIVE_ARMATURE_KG_M2, DRIVE_DAMPING_NM_S = 0.5, 0.5
# The USD differential: a bar on the deck and two rods (masses taken from the chassis).
DIFF_BAR_KG, DIFF_ROD_KG = 2.0, 0.5
DIFF_ROD_RADIUS_M = 0.02


@dataclass(frozen=True, slots=True)
class Shape:
    """A primitive shape of a link (frame of the link, m and kg).

    ``kind``: ``"box"`` (``size_m`` = half extents), ``"cylinder"`` (radius, half height;
    along ``axis``), ``"capsule"`` (radius; between ``fromto_m``'s two points), ``"sphere"``
    (radius). ``collides``: a collision shape (else visual only).
    """

    kind: str
    size_m: tuple[float, ...]
    mass_kg: float
    collides: bool
    pos_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: str = "z"
    fromto_m: tuple[float, ...] = ()
    name: str = ""
    rgba: tuple[float, float, float, float] | None = None
    """Colour when it differs from the shape's class (MJCF defaults: wheel, body, visual)."""


@dataclass(frozen=True, slots=True)
class Joint:
    """A hinge (``kind = "revolute"``, about ``axis``) or ball joint at the child link's
    origin."""

    name: str
    kind: str = "revolute"
    axis: str = "y"
    range_rad: tuple[float, float] | None = None
    damping_nm_s: float = 0.0
    armature_kg_m2: float = 0.0


@dataclass(frozen=True, slots=True)
class LoopJoint:
    """A ball joint closing a kinematic loop (USD: excluded from the articulation): at
    ``parent_pos_m`` in ``parent``'s frame and ``child_pos_m`` in ``child``'s."""

    name: str
    parent: str
    child: str
    parent_pos_m: tuple[float, float, float]
    child_pos_m: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Link:
    """A rigid link: its origin in ``parent``'s frame, the joint to the parent, its shapes."""

    name: str
    parent: str | None
    pos_m: tuple[float, float, float]
    joint: Joint | None
    shapes: tuple[Shape, ...] = ()


def chassis_mass_kg(cfg: RoverConfig, *, differential: bool = False) -> float:
    """Mass of the chassis body: the rover's mass minus every other link (and, for the USD
    rover, the differential's bar and rods)."""
    b = rover_body(cfg)
    rest = 2 * (b.rocker_kg + b.bogie_kg) + 4 * b.steer_kg + 6 * b.wheel_kg
    return cfg.mass_kg - rest - (DIFF_BAR_KG + 2 * DIFF_ROD_KG if differential else 0.0)


def _wheel(cfg: RoverConfig, tag: str, parent: str, pos: tuple[float, float, float],
           steered: bool) -> tuple[Link, ...]:
    r, hw = cfg.wheel_radius_m, cfg.wheel_width_m / 2.0
    b = rover_body(cfg)
    shapes: tuple[Shape, ...]
    if cfg.wheel_collision == "cylinder":
        shapes = (Shape("cylinder", (r, hw), b.wheel_kg, True, axis="y", name=f"wheel_{tag}"),)
    else:  # collision sphere + visual cylinder
        shapes = (Shape("sphere", (r,), b.wheel_kg, True, name=f"wheel_{tag}",
                        rgba=(0.0, 0.0, 0.0, 0.0)),
                  Shape("cylinder", (r, hw), 0.0, False, axis="y", rgba=(0.6, 0.6, 0.6, 1.0)))
    drive = Joint(f"drive_{tag}", axis="y", damping_nm_s=DRIVE_DAMPING_NM_S,
                  armature_kg_m2=DRIVE_ARMATURE_KG_M2)
    if not steered:
        return (Link(f"hub_{tag}", parent, pos, None),
                Link(f"wheel_{tag}", f"hub_{tag}", (0.0, 0.0, 0.0), drive, shapes))
    lim = cfg.steer_limit_rad
    rad, half, z = b.steer_unit_m
    steer = Joint(f"steer_{tag}", axis="z", range_rad=(-lim, lim),
                  damping_nm_s=STEER_DAMPING_NM_S, armature_kg_m2=STEER_ARMATURE_KG_M2)
    unit = (Shape("cylinder", (rad, half), b.steer_kg, False, pos_m=(0.0, 0.0, z)),)
    return (Link(f"steer_{tag}", parent, pos, steer, unit),
            Link(f"wheel_{tag}", f"steer_{tag}", (0.0, 0.0, 0.0), drive, shapes))


def _side(cfg: RoverConfig, side: str, sign: float) -> tuple[Link, ...]:
    r, ride, b = cfg.wheel_radius_m, cfg.ride_height_m, rover_body(cfg)
    y_rocker = sign * b.rocker_y_frac * cfg.track_m
    dy = sign * cfg.track_m / 2.0 - y_rocker
    s = side[0]
    pz = b.pivot_above_ground_m
    bz = b.bogie_above_ground_m - pz
    xb = -cfg.wheelbase_rear_m + b.bogie_half_m  # bogie pivot x
    xf = cfg.wheelbase_front_m
    rocker = Link(
        f"rocker_{side}", "base_link", (0.0, y_rocker, pz - ride),
        Joint(f"rocker_{side}", range_rad=(-ROCKER_RANGE_RAD, ROCKER_RANGE_RAD),
              damping_nm_s=ROCKER_DAMPING_NM_S),
        (Shape("capsule", (b.rocker_radius_m,), b.rocker_kg, False,
               fromto_m=(xb, 0.0, bz, xf, 0.0, r - pz + b.rocker_rise_m)),),
    )
    bogie = Link(
        f"bogie_{side}", rocker.name, (xb, 0.0, bz),
        Joint(f"bogie_{side}", range_rad=(-BOGIE_RANGE_RAD, BOGIE_RANGE_RAD),
              damping_nm_s=BOGIE_DAMPING_NM_S),
        (Shape("capsule", (b.bogie_radius_m,), b.bogie_kg, False,
               fromto_m=(-b.bogie_half_m, 0.0, 0.0, b.bogie_half_m, 0.0, 0.0)),),
    )
    zb = r - b.bogie_above_ground_m
    return (rocker, *_wheel(cfg, f"f{s}", rocker.name, (xf, dy, r - pz), True), bogie,
            *_wheel(cfg, f"m{s}", bogie.name, (b.bogie_half_m, dy, zb), False),
            *_wheel(cfg, f"r{s}", bogie.name, (-b.bogie_half_m, dy, zb), True))


def rover_links(cfg: RoverConfig | None = None, *,
                differential: bool = False) -> tuple[Link, ...]:
    """The rover's links, parents before children (MJCF body order).

    ``base_link`` sits at ``(0, 0, ride_height_m)`` (wheels on the ground at z = 0) and has no
    joint (free). Collision shapes: the chassis box and the six wheels (rover links never
    collide with each other). With ``differential``, the USD differential's bar and rods follow
    (:func:`differential_links`) and the chassis is lighter by their mass.
    """
    cfg = cfg if cfg is not None else RoverConfig()
    mast, b = cfg.mast_height_m - cfg.ride_height_m, rover_body(cfg)
    base = Link("base_link", None, (0.0, 0.0, cfg.ride_height_m), None, (
        Shape("box", b.chassis_half_m, chassis_mass_kg(cfg, differential=differential), True,
              pos_m=(0.0, 0.0, b.chassis_z_m), name="chassis"),
        Shape("cylinder", (b.mast_radius_m, mast / 2), 0.0, False,
              pos_m=(b.mast_x_m, 0.0, 0.25 + mast / 2 - 0.125)),
    ))
    links = (base, *_side(cfg, "left", 1.0), *_side(cfg, "right", -1.0))
    return links + (differential_links(cfg) if differential else ())


def differential_links(cfg: RoverConfig) -> tuple[Link, ...]:
    """The differential as a mechanism (USD rover): the bar and its two rods.

    The bar pivots about x at the body's ``(diff_x_m, 0, diff_z_m)`` in ``base_link``; each
    rod hangs on a ball joint from a bar end straight down to its rocker, where
    :func:`loop_joints` ties it (``-diff_x_m`` behind the rocker pivot). A rocker turning by
    ``a`` lifts its rod by ``-diff_x_m sin a``, which tilts the bar and lowers the other rod as
    much: the rockers turn by opposite angles, as the MJCF equality
    ``rocker_left = -rocker_right`` says.
    """
    b = rover_body(cfg)
    bar = Link("diff_bar", "base_link", (b.diff_x_m, 0.0, b.diff_z_m),
               Joint("differential", axis="x"),
               (Shape("box", b.diff_bar_half_m, DIFF_BAR_KG, False),))
    rod = Shape("capsule", (DIFF_ROD_RADIUS_M,), DIFF_ROD_KG, False,
                fromto_m=(0.0, 0.0, 0.0, 0.0, 0.0, -_rod_length_m(cfg)))
    y_r = b.rocker_y_frac * cfg.track_m
    return (bar, *(Link(f"diff_rod_{side}", "diff_bar", (0.0, sign * y_r, 0.0),
                        Joint(f"diff_rod_{side}", kind="ball"), (rod,))
                   for side, sign in (("left", 1.0), ("right", -1.0))))


def _rod_length_m(cfg: RoverConfig) -> float:
    b: RoverBody = rover_body(cfg)
    return b.diff_z_m - (b.pivot_above_ground_m - cfg.ride_height_m)


def loop_joints(cfg: RoverConfig | None = None) -> tuple[LoopJoint, ...]:
    """The joints closing the differential's loops: each rod's lower end to its rocker."""
    cfg = cfg if cfg is not None else RoverConfig()
    return tuple(LoopJoint(f"diff_link_{side}", f"rocker_{side}", f"diff_rod_{side}",
                           (rover_body(cfg).diff_x_m, 0.0, 0.0),
                           (0.0, 0.0, -_rod_length_m(cfg)))
                 for side in ("left", "right"))


def _shape_inertia(shape: Shape) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centre (3,) and inertia tensor (3, 3) about it, MuJoCo's formulas (uniform density)."""
    m = shape.mass_kg
    if shape.kind == "capsule":
        a, b = np.asarray(shape.fromto_m[:3]), np.asarray(shape.fromto_m[3:])
        r, h = shape.size_m[0], float(np.linalg.norm(b - a))
        cyl, sph = math.pi * r * r * h, 4.0 / 3.0 * math.pi * r**3
        mc, ms_ = m * cyl / (cyl + sph), m * sph / (cyl + sph)
        along = mc * r * r / 2 + ms_ * 0.4 * r * r
        across = mc * (3 * r * r + h * h) / 12 + ms_ * (0.4 * r * r + 0.375 * r * h + 0.25 * h * h)
        u = (b - a) / h
        return (a + b) / 2, across * np.eye(3) + (along - across) * np.outer(u, u)
    centre = np.asarray(shape.pos_m, dtype=np.float64)
    if shape.kind == "box":
        x, y, z = shape.size_m
        return centre, np.diag([m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y)]) / 3
    if shape.kind == "sphere":
        return centre, np.eye(3) * 0.4 * m * shape.size_m[0] ** 2
    r, h = shape.size_m  # cylinder: radius, half height
    along, across = m * r * r / 2, m * (3 * r * r + 4 * h * h) / 12
    u = np.eye(3)["xyz".index(shape.axis)]
    return centre, across * np.eye(3) + (along - across) * np.outer(u, u)


def link_inertia(link: Link) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Mass (kg), centre of mass (3,) in the link frame (m) and the inertia tensor (3, 3) about
    the centre of mass (kg m^2) of a link's shapes (massless shapes add nothing)."""
    parts = [(s.mass_kg, *_shape_inertia(s)) for s in link.shapes if s.mass_kg > 0]
    mass = float(sum(m for m, _, _ in parts))
    if mass == 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = sum(m * c for m, c, _ in parts) / mass
    tensor = np.zeros((3, 3))
    for m, c, inertia in parts:  # parallel axis theorem
        d = c - com
        tensor += inertia + m * (float(d @ d) * np.eye(3) - np.outer(d, d))
    return mass, np.asarray(com, dtype=np.float64), tensor
