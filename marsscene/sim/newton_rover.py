"""Drive the USD rover in Newton (NVIDIA's open-source physics engine; CPU through Warp).

The optional extra ``newton`` (``pip install "marsscene[newton]"``) brings Newton and Warp; this
module is the only importer of ``newton`` and ``warp``. :class:`NewtonRover` loads a scene
written with ``[export] rover = true`` (``/World/Rover``, the UsdPhysics articulation of
``assets/rover.usda``) through Newton's own USD importer (``ModelBuilder.add_usd``, built on
OpenUSD's physics parser) and maps ``cmd_vel`` to joint targets with the MuJoCo runtime's
kinematics (:func:`marsscene.rover.geometry.wheel_commands`): wheel rates to the six velocity
drives (clipped to ``wheel_speed_limit_rad_s``, as MuJoCo clips actuator controls), corner
angles to the four position drives.

Solver: ``SolverSteel`` (reduced coordinates, projected Gauss-Seidel contacts, implicit
drives, loop-closing ball joints: the rover's differential). It is experimental in Newton 1.8;
the maximal-coordinate solvers (XPBD, semi-implicit) diverge on this rover's mass ratios
(20 kg wheels on 4 kg steering units) and Featherstone ignores loop joints. See
:doc:`/usd_rover`.

Rocks: Newton's importer turns every collider prim into its own mesh (about 1 ms a prim), so
the rock colliders (``/World/RockColliders``: an instance per obstacle rock, the smaller rocks
merged per tile) are read here instead (:mod:`marsscene.export.usd.rock_colliders_read`): one
convex hull per prototype part shared by the obstacle rocks, one static mesh per tile of the
merged ones, optionally only the rocks within ``rocks_within_m`` of the rover.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._optional import quiet_warp
from marsscene.errors import RuntimeSimError, missing_dependency
from marsscene.export.usd.rock_colliders import COLLIDERS_PATH
from marsscene.export.usd.rock_colliders_read import merged_rocks, rock_instances
from marsscene.rover.config import RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, wheel_commands
from marsscene.rover.rates import PHYSICS_HZ
from marsscene.transforms import yaw_of_quat

__all__ = ["NewtonRover", "rock_instances"]

ROVER_PATH = "/World/Rover"
#: Contact buffer of the collision pipeline (the rover makes about 70 contacts on rough ground).
CONTACTS_MAX = 2048
#: Candidate shape pairs of the broad phase per step.
PAIRS_MAX = 16384


def _newton() -> tuple[Any, Any]:
    try:
        import newton
        import warp as wp
    except ImportError as err:
        raise missing_dependency("newton", "newton") from err
    return newton, quiet_warp(wp)


class NewtonRover:
    """The USD rover on a scene in Newton, driven by ``cmd_vel``.

    Parameters
    ----------
    scene_usd : path-like
        ``scene.usda`` / ``.usdc`` written with ``[export] rover = true``.
    rover : RoverConfig, optional
        The config the rover asset was written with (default ``RoverConfig()``).
    rocks_within_m : float or None
        Load the rocks whose centre lies within this horizontal distance of the rover's
        start (m); ``None``: every rock.
    rock_rows : collection of int, optional
        Load only these rows of the rock table (e.g. the rocks the MJCF scene simulates, for
        a like-for-like comparison with the MuJoCo runtime).
    dt_s : float
        Physics step (s).
    control_hz : float
        Rate of :meth:`step` (one control period = ``1 / (control_hz dt_s)`` steps).
    edit_builder : callable, optional
        ``f(builder)`` called before the model is finalized (add test bodies).
    device : str
        Warp device (``"cpu"`` by default; ``"cuda"`` on a GPU machine).
    """

    def __init__(self, scene_usd: str | Path, *, rover: RoverConfig | None = None,
                 rocks_within_m: float | None = 30.0, rock_rows: Any = None,
                 dt_s: float = 1.0 / PHYSICS_HZ,
                 control_hz: float = 50.0, edit_builder: Callable[[Any], None] | None = None,
                 device: str = "cpu") -> None:
        newton, _ = _newton()
        from pxr import Usd

        self.rover = rover if rover is not None else RoverConfig()
        path = Path(scene_usd)
        if not path.is_file():
            raise RuntimeSimError(f"{path} does not exist (write a scene with `marsscene build`)")
        stage = Usd.Stage.Open(str(path))
        if not stage.GetPrimAtPath(ROVER_PATH):
            raise RuntimeSimError(f"{path} has no {ROVER_PATH}: write the scene with "
                                  "`marsscene build --rover` ([export] rover = true)")
        builder = newton.ModelBuilder(up_axis=newton.Axis.Z)
        builder.add_usd(stage, ignore_paths=[COLLIDERS_PATH])
        self.load_info = {"rocks_loaded": self._add_rocks(builder, stage, rocks_within_m,
                                                          rock_rows)}
        if edit_builder is not None:
            edit_builder(builder)
        self.builder = builder
        self.model = builder.finalize(device=device)
        # Bounded buffers: Steel's step time grows with the contact buffer, which Newton sizes
        # by shape count (21 000 slots for 600 rocks; a rover makes ~70 contacts), and the
        # candidate-pair buffer with its square (120 000 rocks: 7e9 pairs, beyond Warp's arrays)
        self._pipeline = newton.CollisionPipeline(self.model, broad_phase="sap",
                                                  rigid_contact_max=CONTACTS_MAX,
                                                  shape_pairs_max=PAIRS_MAX)
        self.model.rigid_contact_max = CONTACTS_MAX
        self.contacts = self._pipeline.contacts()
        self.solver = newton.solvers.SolverSteel(self.model, enable_joint_limits=True,
                                                 articulation_constraint_max=512)
        self.state, self._next = self.model.state(), self.model.state()
        self.control = self.model.control()
        newton.eval_fk(self.model, self.model.joint_q, self.model.joint_qd, self.state)
        self.dt_s = float(dt_s)
        self.substeps = max(1, round(1.0 / (control_hz * self.dt_s)))
        self.time_s = 0.0
        labels = list(builder.joint_label)
        q0 = self.model.joint_q_start.numpy()
        qd0 = self.model.joint_qd_start.numpy()

        def joint(name: str) -> int:
            hits = [i for i, lab in enumerate(labels) if lab.endswith(f"/Joints/{name}")]
            if len(hits) != 1:
                raise RuntimeSimError(f"{path}: the rover has no joint {name!r}")
            return hits[0]

        self._joint = joint
        self._q_start, self._qd_start = q0, qd0
        self.drive_dofs = np.array([qd0[joint(j)] for j in DRIVE_JOINTS])
        # position targets follow the coordinate layout (joint_q), rate targets the DOF one
        self.steer_coords = np.array([q0[joint(j)] for j in STEER_JOINTS])
        bodies = [i for i, lab in enumerate(builder.body_label)
                  if lab == f"{ROVER_PATH}/base_link"]
        self.base_body = bodies[0]
        self.cmd = (0.0, 0.0)

    @staticmethod
    def _add_rocks(builder: Any, stage: Any, within_m: float | None, only: Any) -> int:
        from pxr import UsdGeom

        from marsscene.transforms import matrix_to_quat

        newton, wp = _newton()
        rover = stage.GetPrimAtPath(ROVER_PATH)
        start = np.asarray(UsdGeom.XformCache().GetLocalToWorldTransform(rover))[3, :2]
        rows_only = None if only is None else np.fromiter(only, dtype=np.int64)

        def wanted(xy: Any, rows: Any) -> Any:
            keep = np.ones(len(rows), dtype=bool) if within_m is None else \
                np.hypot(*(xy - start).T) <= within_m
            return keep if rows_only is None else keep & np.isin(rows, rows_only)

        parts, mats, keys, rows, friction = rock_instances(stage)
        cfg = newton.ModelBuilder.ShapeConfig(mu=friction)
        keep = wanted(mats[:, 3, :2], rows)
        meshes = {k: [newton.Mesh(v, i, compute_inertia=False) for v, i in p]
                  for k, p in parts.items()}
        scale = np.linalg.norm(mats[:, :3, :3], axis=2)  # rows: the scaled axes
        quat = matrix_to_quat(np.swapaxes(mats[:, :3, :3] / scale[:, :, None], 1, 2))
        for j in np.flatnonzero(keep):  # a shape per obstacle rock part: no instancing
            w, x, y, z = quat[j].tolist()
            tf = wp.transform(wp.vec3(*mats[j, 3, :3].tolist()), wp.quat(x, y, z, w))
            for mesh in meshes[keys[j]]:
                builder.add_shape_convex_hull(-1, xform=tf, mesh=mesh,
                                              scale=wp.vec3(*scale[j].tolist()), cfg=cfg)
        loaded = int(keep.sum())
        for tile in merged_rocks(stage):  # a static mesh per tile of the smaller rocks
            points, faces, n = tile.select(wanted(tile.centres_xy_m(), tile.rows))
            if n:
                builder.add_shape_mesh(-1, mesh=newton.Mesh(points, faces.ravel(),
                                                            compute_inertia=False),
                                       cfg=newton.ModelBuilder.ShapeConfig(mu=tile.friction))
                loaded += n
        return loaded

    # ---- commands --------------------------------------------------------------------------
    def apply(self, v_m_s: float, omega_rad_s: float) -> None:
        """Set the drive targets for ``cmd_vel``: wheel rates (clipped to the rover's wheel
        speed limit) and corner steering angles (clipped to its steering limit)."""
        rates, steer = wheel_commands(float(v_m_s), float(omega_rad_s), self.rover)
        lim = self.rover.wheel_speed_limit_rad_s
        qd = self.control.joint_target_qd.numpy()
        q = self.control.joint_target_q.numpy()
        qd[self.drive_dofs] = np.clip(rates, -lim, lim)
        q[self.steer_coords] = np.clip(steer, -self.rover.steer_limit_rad,
                                     self.rover.steer_limit_rad)
        self.control.joint_target_qd.assign(qd)
        self.control.joint_target_q.assign(q)
        self.cmd = (float(v_m_s), float(omega_rad_s))

    def step(self, v_m_s: float, omega_rad_s: float) -> None:
        """Apply ``cmd_vel`` and advance one control period."""
        self.apply(v_m_s, omega_rad_s)
        self.advance(self.substeps)

    def advance(self, nstep: int) -> None:
        """Advance ``nstep`` physics steps with the current targets."""
        for _ in range(int(nstep)):
            self.state.clear_forces()
            self._pipeline.collide(self.state, self.contacts)
            self.solver.step(self.state, self._next, self.control, self.contacts, self.dt_s)
            self.state, self._next = self._next, self.state
        self.time_s += int(nstep) * self.dt_s
        if not np.isfinite(self.state.body_q.numpy()[self.base_body]).all():
            raise RuntimeSimError(f"Newton simulation diverged at t = {self.time_s:.3f} s")

    # ---- state -----------------------------------------------------------------------------
    def pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``base_link`` position (m) and quaternion (w, x, y, z), world frame."""
        q = self.state.body_q.numpy()[self.base_body].astype(np.float64)
        return q[:3].copy(), np.array([q[6], q[3], q[4], q[5]])

    def yaw_rad(self) -> float:
        """Heading of ``base_link`` (rad, counter-clockwise from +x)."""
        return float(yaw_of_quat(self.pose()[1]))

    def joint_positions(self, names: tuple[str, ...]) -> NDArray[np.float64]:
        """Joint coordinates (rad) of single-DOF joints by name (e.g. ``"rocker_left"``)."""
        q = self.state.joint_q.numpy()
        return np.array([q[self._q_start[self._joint(n)]] for n in names], dtype=np.float64)
