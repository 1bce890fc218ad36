"""The scout as a MuJoCo free body on a built scene: fuselage, rotor disk and four feet, with a
thrust actuator along the body z axis at the rotor hub and three body-torque actuators (the
rotors' cyclic and differential collective as moments; Grip et al. 2019 model the vehicle the
same way, as a rigid body with thrust and torque inputs). Gravity is the scene's (3.72 m/s^2);
aerodynamic drag ``-1/2 rho C_D A |v| v`` is applied at the centre of mass each control step.
The feet collide with the terrain (and the rocks) as the rover's wheels do.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError
from marsscene.scout.aero import max_thrust_n
from marsscene.scout.config import ScoutConfig
from marsscene.sim.rover_sim import load_scene_spec
from marsscene.sim.terrain import scene_heightfield

__all__ = ["ScoutSim"]

_FOOT_RADIUS_M = 0.04


def _add_scout(spec: Any, cfg: ScoutConfig, density_kg_m3: float) -> None:
    body = spec.worldbody.add_body(name="scout", pos=[0.0, 0.0, 0.0])
    body.add_freejoint(name="scout_root")
    body.explicitinertial = True
    body.mass = cfg.mass_kg
    body.inertia = list(cfg.inertia_kg_m2)
    half = cfg.leg_half_span_m
    box = body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.07, 0.08],
                        contype=0, conaffinity=0, density=0.0, rgba=[0.8, 0.7, 0.5, 1.0])
    box.name = "scout_fuselage"
    rotor_z = cfg.rotor_above_feet_m - cfg.body_above_feet_m
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[cfg.rotor_diameter_m / 2, 0.01, 0],
                  pos=[0.0, 0.0, rotor_z], contype=0, conaffinity=0, density=0.0,
                  rgba=[0.2, 0.2, 0.2, 0.5])
    for i, (sx, sy) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1))):
        foot = body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[_FOOT_RADIUS_M, 0, 0],
                             pos=[sx * half, sy * half, _FOOT_RADIUS_M - cfg.body_above_feet_m],
                             contype=2, conaffinity=1, density=0.0, condim=3)
        foot.name = f"scout_foot_{i}"
    body.add_site(name="scout_rotor", pos=[0.0, 0.0, rotor_z])
    tilt, yaw = cfg.tilt_torque_max_nm, cfg.yaw_torque_max_nm
    limits = {"thrust": (0.0, max_thrust_n(cfg, density_kg_m3)), "roll": (-tilt, tilt),
              "pitch": (-tilt, tilt), "yaw": (-yaw, yaw)}
    for i, (name, (lo, hi)) in enumerate(limits.items()):
        gear = [0.0] * 6
        gear[2 if i == 0 else 2 + i] = 1.0
        act = spec.add_actuator(name=f"scout_{name}", target="scout_rotor",
                                trntype=mujoco.mjtTrn.mjTRN_SITE, gear=gear)
        act.ctrllimited = True
        act.ctrlrange = [lo, hi]


class ScoutSim:
    """A scout on a built scene (``scene_dir/mjcf/scene.xml``), feet on the terrain at
    ``start_xy_m``.

    ``ctrl`` order: thrust (N), roll, pitch, yaw torques (N m) about the body axes.
    """

    def __init__(self, scene_dir: str | Path, cfg: ScoutConfig, *, density_kg_m3: float,
                 start_xy_m: tuple[float, float] | None = None, yaw_rad: float = 0.0) -> None:
        spec, xml, _ = load_scene_spec(scene_dir, rock_contacts=True)
        _add_scout(spec, cfg, density_kg_m3)
        try:
            self.model = spec.compile()
        except Exception as err:
            raise RuntimeSimError(f"{xml}: cannot compile scene + scout: {err}") from None
        self.data = mujoco.MjData(self.model)
        self.cfg, self.density_kg_m3 = cfg, float(density_kg_m3)
        self.heightfield = scene_heightfield(self.model)
        self.body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "scout")
        self.feet = {mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"scout_foot_{i}")
                     for i in range(4)}
        x0, y0, x1, y1 = self.heightfield.bounds_xy_m
        xy = start_xy_m if start_xy_m is not None else ((x0 + x1) / 2, (y0 + y1) / 2)
        half = cfg.leg_half_span_m  # on the highest ground under the feet, then settled
        offsets = np.linspace(-half, half, 5)
        gx, gy = np.meshgrid(xy[0] + offsets, xy[1] + offsets)
        ground = float(np.max(self.heightfield.sample(gx, gy)))
        self.data.qpos[:3] = (xy[0], xy[1], ground + cfg.body_above_feet_m + 0.01)
        self.data.qpos[3:7] = (np.cos(yaw_rad / 2), 0.0, 0.0, np.sin(yaw_rad / 2))
        mujoco.mj_forward(self.model, self.data)

    @property
    def dt_s(self) -> float:
        return float(self.model.opt.timestep)

    def state(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                             NDArray[np.float64]]:
        """Position (3,), world velocity (3,), rotation body-to-world (3, 3), body rates (3,)."""
        d = self.data
        rot = d.xmat[self.body].reshape(3, 3).copy()
        return d.qpos[:3].copy(), d.qvel[:3].copy(), rot, d.qvel[3:6].copy()

    def feet_in_contact(self) -> int:
        """Feet touching anything (the terrain, a rock)."""
        con = self.data.contact[:self.data.ncon]
        return len({int(g) for c in con for g in c.geom} & self.feet)

    def step(self, ctrl: NDArray[np.float64], n: int) -> None:
        """``n`` physics steps with ``ctrl`` held and the drag of the current velocity."""
        v = self.data.qvel[:3]
        drag = -0.5 * self.density_kg_m3 * self.cfg.drag_area_m2 * float(np.linalg.norm(v)) * v
        self.data.xfrc_applied[self.body, :3] = drag
        self.data.ctrl[:4] = ctrl
        mujoco.mj_step(self.model, self.data, nstep=n)
