"""Wheels on deformable soil in MuJoCo: slip, sinkage and the forces they make, each step.

With a soil on, the terrain's contacts with the rover carry only normal force (the terrain
geoms take contact priority with ``condim = 1``) and :class:`WheelSoil` adds, before every
physics step, what the soil does to each wheel (rocks keep their Coulomb friction):

1. The wheel's load ``W`` is the normal force of its terrain contacts at the last step, its
   contact normal ``n`` their load-weighted mean; its heading ``f = a x n`` (``a``: the axle).
2. Slip from the hub's speed ``v`` along ``f`` and the rim's ``u = r omega``: with ``d`` the
   sign of the faster of the two, ``s = d (u - v) / max(|u|, |v|)`` (driving ``0 < s <= 1``,
   braking or skidding ``-1 <= s < 0``).
3. Sinkage, thrust, motion resistance and torque from the Wong--Reece model for that load and
   slip (:class:`marsscene.rover.soil_table.SoilTable`); the thrust acts at the hub along
   ``d f``, the resistance against the hub's motion (smoothly: ``tanh(v / v_r)``, so a wheel
   spinning in place meets none) and the torque against the wheel's turning about ``a``.
   Below ``v_r`` of hub and rim (0.02 m/s at 500 Hz, 0.05 m/s at 100 Hz) the patch's shear
   (next item) takes over, acting at the hub, so a rover at rest holds still.
4. Sideways (and longitudinally at rest), the Janosi--Hanamoto shear law over the contact
   patch, ``F = (c b l + W tan(phi)) (1 - exp(-|j| / K))`` (``l = r theta_1``, the contact
   length), with the patch's shear displacement ``j`` a state: sheared by the slip speed and
   renewed as the wheel rolls over fresh soil, ``dj/dt = v_slip - j |v| / (l / 2)``. Rolling
   steadily it settles at ``j_y = (l / 2) tan(beta)``, the patch mean of Ishigami et al.'s
   (2007) lateral displacement ``r (theta_1 - theta) tan(beta)`` (``beta`` the slip angle);
   at rest it is the soil's elastic hold.
5. The wheel sinks: its collision radius shrinks by the sinkage, so the hub, the chassis and
   the IMU ride that much lower. The sinkage follows the load (lagged :data:`LOAD_LAG_S`) and
   slip with a lag of :data:`SINK_LAG_S`, at most :data:`SINK_RATE_M_S`, and a lifted wheel
   keeps it.

Forces are applied explicitly: the patch's shear gets a small damping (a tenth of ``m_w / dt``,
``m_w`` a sixth of the rover's mass) to steady it. References:
:mod:`marsscene.rover.terramechanics`; Ishigami, G., Miwa, A., Nagatani, K., Yoshida, K.
(2007), J. Field Robotics 24(3), 233-250, doi:10.1002/rob.20187.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.soil_table import soil_table
from marsscene.soil.map import SoilMap

__all__ = ["LOAD_LAG_S", "SINK_LAG_S", "SINK_RATE_M_S", "WheelSoil", "soften_terrain",
           "soil_map_of"]

#: Time constant (s) of a wheel's sinkage following its load and slip.
SINK_LAG_S = 0.2
#: The fastest a wheel sinks or rises (m/s): no faster than the rover settles under Mars
#: gravity, or the shrinking wheel leaves the ground and bounces back.
SINK_RATE_M_S = 0.05
#: Time constant (s) of the load the sinkage follows (the contact force is noisy step to step).
LOAD_LAG_S = 0.05
#: Speeds (m/s) below which slip is not defined (the slip's denominator floor).
_SPEED_FLOOR_M_S = 1e-3
#: Below this speed (m/s) of hub and rim, or the time step times :data:`_ROLLING_M_S2` if more
#: (0.02 m/s at 500 Hz, 0.05 m/s at 100 Hz: slower, the coarser step rocks the rover), the
#: wheel is not rolling: the patch's shear (static friction) takes over from the Wong--Reece
#: rolling model (linearly from rest).
_ROLLING_M_S = 0.02
_ROLLING_M_S2 = 5.0
#: Shear displacement is held within this many shear moduli (99.3 % of the soil's strength).
_SHEAR_LIMIT = 5.0
#: The patch's shear damping, as a share of the largest the explicit step stays stable with
#: (a sixth of the rover's mass over the time step).
_DAMPING_RATIO = 0.1
#: The soil carries up to this many times a level wheel's share of the rover's weight on the
#: grid of its table (beyond, sinkage holds and forces scale with the load).
_TABLE_LOAD_FACTOR = 4.0


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Row-wise cross product of (N, 3) arrays (``np.cross`` costs ~50 us on six rows)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


def soften_terrain(spec: Any, names: tuple[str, ...] = ("terrain", "terrain_outer")) -> None:
    """Make the named geoms of an ``MjSpec`` normal-force-only for whatever touches them
    (contact priority 1, ``condim = 1``): their tangential forces come from the soil."""
    for geom in spec.geoms:
        if geom.name in names:
            geom.priority, geom.condim = 1, 1


class WheelSoil:
    """The soil's forces on a rover's wheels in one MuJoCo model (see the module docstring).

    Parameters
    ----------
    model, data
        The compiled scene + rover (terrain geoms already frictionless, see
        :func:`soften_terrain`).
    wheel_geoms, drive_dofs : array of int
        The six wheels' collision geoms and drive joints' dofs (one order).
    terrain_geoms : sequence of int
        The geoms the soil covers.
    soil_map : SoilMap
    radius_m, width_m, mass_kg : float
        Wheel size and the rover's mass.
    """

    def __init__(self, model: Any, data: Any, *, wheel_geoms: NDArray[np.intp],
                 drive_dofs: NDArray[np.intp], terrain_geoms: Any, soil_map: SoilMap,
                 radius_m: float, width_m: float, mass_kg: float) -> None:
        self.model, self.data = model, data
        self.geoms = np.asarray(wheel_geoms, dtype=np.intp)
        self.bodies = np.asarray(model.geom_bodyid[self.geoms], dtype=np.intp)
        self.dofs = np.asarray(drive_dofs, dtype=np.intp)
        self.roots = np.asarray(model.body_rootid[self.bodies], dtype=np.intp)
        self.r, self.b = float(radius_m), float(width_m)
        n = len(self.geoms)
        self._wheel_of = np.full(model.ngeom, -1, np.intp)
        self._wheel_of[self.geoms] = np.arange(n)
        self._terrain = np.zeros(model.ngeom, bool)
        self._terrain[list(terrain_geoms)] = True
        self._weight_n = mass_kg * float(np.linalg.norm(model.opt.gravity))
        self.use(soil_map)
        self.rolling_m_s = max(_ROLLING_M_S, _ROLLING_M_S2 * float(model.opt.timestep))
        self.damping_n_s_m = _DAMPING_RATIO * mass_kg / n / float(model.opt.timestep)
        self._one = np.zeros(n, np.intp)
        self.shear_m = np.zeros((n, 2))
        self.sinkage_m = np.zeros(n)
        self.slip = np.zeros(n)
        self.load_n = np.zeros(n)
        self._load_lagged = np.zeros(n)
        self.reset()

    @classmethod
    def of(cls, sim: Any, soil_map: SoilMap) -> WheelSoil:
        """The soil under a :class:`~marsscene.sim.rover_sim.RoverSim`'s wheels (its terrain
        geoms softened with :func:`soften_terrain`)."""
        import mujoco

        terrain = [g for g in (mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, name)
                               for name in ("terrain", "terrain_outer")) if g >= 0]
        return cls(sim.model, sim.data, wheel_geoms=sim.wheel_geoms, drive_dofs=sim.drive_dof,
                   terrain_geoms=terrain, soil_map=soil_map, radius_m=sim.rover.wheel_radius_m,
                   width_m=sim.rover.wheel_width_m, mass_kg=sim.rover.mass_kg)

    def use(self, soil_map: SoilMap) -> None:
        """Lay another soil map (an environment's episode drawing its soil)."""
        self.map = soil_map
        n = len(self.geoms)
        self.tables = [soil_table(s, self.r, self.b, _TABLE_LOAD_FACTOR * self._weight_n / n)
                       for s in soil_map.soils]
        self._tan_phi = np.array([math.tan(math.radians(s.friction_deg)) for s in soil_map.soils])
        self._cohesion = np.array([s.cohesion_pa for s in soil_map.soils])
        self._k_m = np.array([s.shear_modulus_m for s in soil_map.soils])

    def reset(self) -> None:
        """Wheels back on the surface (full radius, no slip)."""
        self.sinkage_m[:] = self.slip[:] = self.load_n[:] = self._load_lagged[:] = 0.0
        self.shear_m[:] = 0.0
        self.model.geom_size[self.geoms, 0] = self.r
        self.data.xfrc_applied[self.bodies] = 0.0

    def _contacts(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Each wheel's terrain load (N), load-weighted contact normal (into the wheel) and
        contact point."""
        n, d = len(self.geoms), self.data
        load, normal, point = np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3))
        if d.ncon == 0:
            return load, normal, point
        con = d.contact
        g1, g2, efc = con.geom1, con.geom2, con.efc_address
        w1, w2 = self._wheel_of[g1], self._wheel_of[g2]
        on = (efc >= 0) & (((w2 >= 0) & self._terrain[g1]) | ((w1 >= 0) & self._terrain[g2]))
        if not on.any():
            return load, normal, point
        wheel = np.where(w2 >= 0, w2, w1)[on]
        f = np.maximum(d.efc_force[efc[on]], 0.0)
        nrm = con.frame[on, :3] * np.where(w2 >= 0, 1.0, -1.0)[on, None]
        weights = np.zeros((n, len(f)))
        weights[wheel, np.arange(len(f))] = f  # contact forces by wheel
        load = weights.sum(1)
        normal, point = weights @ nrm, weights @ con.pos[on]
        point /= np.maximum(load, 1e-9)[:, None]
        normal /= np.maximum(np.sqrt((normal * normal).sum(1)), 1e-12)[:, None]
        return load, normal, point

    def apply(self) -> None:
        """Set the wheels' soil forces (``xfrc_applied``) and sinkage for the next step."""
        d, m, dt = self.data, self.model, float(self.model.opt.timestep)
        load, n, point = self._contacts()
        touching = load > 0.0
        lagged = self._load_lagged
        lagged += (load - lagged) * min(1.0, dt / LOAD_LAG_S)
        lagged[touching] = np.maximum(lagged[touching], 1.0)
        axle = d.xmat[self.bodies].reshape(-1, 3, 3)[:, :, 1]
        head = _cross(axle, n)
        head /= np.maximum(np.sqrt((head * head).sum(1)), 1e-12)[:, None]
        side = _cross(n, head)
        cvel = d.cvel[self.bodies]  # (angular, linear) at the tree's centre of mass
        hub_v = cvel[:, 3:] + _cross(cvel[:, :3], d.xpos[self.bodies]
                                     - d.subtree_com[self.roots])
        v, vy = (hub_v * head).sum(1), (hub_v * side).sum(1)
        u = self.r * d.qvel[self.dofs]
        sense = np.where(np.abs(u) >= np.abs(v), np.sign(u), np.sign(v))
        sense[sense == 0] = 1.0
        speed = np.maximum(np.abs(u), np.abs(v))
        slip = np.clip(sense * (u - v) / np.maximum(speed, _SPEED_FLOOR_M_S), -1.0, 1.0)
        which = self.map.at(point[:, :2]) if len(self.tables) > 1 else self._one
        z, thrust, resist, torque = (np.zeros(len(u)) for _ in range(4))
        for k in (np.unique(which[touching]) if len(self.tables) > 1 else (0,)):
            sel = touching & (which == k)
            st = self.tables[k].lookup(lagged[sel], slip[sel])
            scale = load[sel] / lagged[sel]  # forces follow the load itself, ~ in proportion
            z[sel], thrust[sel], resist[sel], torque[sel] = (
                st.sinkage_m, st.thrust_n * scale, st.resistance_n * scale, st.torque_nm * scale)
        # Shear drives the wheel's way; compaction resistance opposes the hub's own motion
        # (none on a wheel spinning in place).
        dp = thrust - resist * np.tanh(sense * v / self.rolling_m_s)
        # The patch's shear displacement (m), sheared by slip and renewed as the wheel rolls on
        # (over half the contact length): Janosi--Hanamoto's law in the form of a state.
        half_contact_m = 0.5 * self.r * np.arccos(np.clip(1.0 - self.sinkage_m / self.r, 0, 1))
        renew = np.abs(v) / np.maximum(half_contact_m, 1e-3)
        self.shear_m += (np.stack([u - v, vy], 1) - self.shear_m * renew[:, None]) * dt
        k_m = self._k_m[which]
        np.clip(self.shear_m, -_SHEAR_LIMIT * k_m[:, None], _SHEAR_LIMIT * k_m[:, None],
                out=self.shear_m)
        strength = (self._cohesion[which] * self.b * 2.0 * half_contact_m
                    + load * self._tan_phi[which])
        sheared = np.sign(self.shear_m) * (1.0 - np.exp(-np.abs(self.shear_m) / k_m[:, None]))
        damp = self.damping_n_s_m * np.stack([u - v, vy], 1)
        shear_n = np.clip(strength[:, None] * sheared + damp, -strength[:, None],
                          strength[:, None])
        # Rolling: Wong--Reece's drawbar pull and torque; at rest: the patch's shear alone, at
        # the hub (the wheel is held by its motor).
        rolling = np.minimum(speed / self.rolling_m_s, 1.0)
        f_long = rolling * sense * dp + (1.0 - rolling) * shear_n[:, 0]
        t_soil = -rolling * sense * torque
        f_lat = -shear_n[:, 1]
        lateral = f_lat[:, None] * side  # acts at the contact, below the hub
        force = np.where(touching[:, None], f_long[:, None] * head + lateral, 0.0)
        moment = t_soil[:, None] * axle + _cross(point - d.xipos[self.bodies], lateral)
        d.xfrc_applied[self.bodies, :3] = force
        d.xfrc_applied[self.bodies, 3:] = np.where(touching[:, None], moment, 0.0)
        step = np.clip((z - self.sinkage_m) * min(1.0, dt / SINK_LAG_S), -SINK_RATE_M_S * dt,
                       SINK_RATE_M_S * dt)
        self.sinkage_m += np.where(touching, step, 0.0)  # a lifted wheel keeps its sinkage
        m.geom_size[self.geoms, 0] = self.r - self.sinkage_m
        self.slip[:] = np.where(touching, slip, 0.0)
        self.load_n[:] = load

def soil_map_of(soil: Any) -> SoilMap | None:
    """A :class:`SoilMap` from a soil's name, a ``Soil`` or a map (None or ``"rigid"``: no
    soil)."""
    from marsscene.rover.terramechanics import soil as soil_named

    if soil is None or soil == "rigid":
        return None
    if isinstance(soil, SoilMap):
        return soil
    return SoilMap.uniform(soil_named(soil) if isinstance(soil, str) else soil)
