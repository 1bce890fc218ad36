"""A ray-cast spinning 3D LiDAR: with ``embreex`` the terrain, the catalogue rocks and the static
geoms in one Embree scene (:class:`~marsscene.sensors.raycast.TerrainCaster`), else the terrain
by :func:`~marsscene.sensors.raycast.ray_heightfield` (exact, vectorised) and the geoms by
MuJoCo rays (``mj_multiRay``).

The sensor is a :class:`~marsscene.rover.lidar.LidarSpec` (a named datasheet model, see
``marsscene/rover/data/lidar_models.toml``). One :meth:`Lidar.scan` is one revolution that starts
at the scan's stamp: every ray carries its firing time, and with ``motion_distortion`` each
column is cast from the pose the sensor has at that time (the current twist held for the sweep),
so a moving rover's scan is skewed as a real one is; points stay in the sensor frame of their
own firing time (drivers publish them so; deskewing uses the times). Range noise is Gaussian
with the datasheet's sigma, dropouts are Bernoulli; both draw from the Generator passed in.
Intensity is ``|cos(incidence)| * exp(-2 alpha r)``: dust attenuates intensity, never range.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.rover.lidar import LidarConfig, LidarSpec
from marsscene.sensors.lidar_boxes import Boxes, ray_boxes
from marsscene.sensors.raycast import TerrainCaster, embree_available
from marsscene.sensors.rock_mesh import static_geom_mesh
from marsscene.terrain.heightfield import Heightfield

__all__ = ["Lidar", "beam_geometry", "rotation_about"]

_GRAZE = 0.05  # |cos(incidence)| floor of the rock plane correction (motion distortion)


def beam_geometry(spec: LidarSpec) -> tuple[NDArray[np.float64], NDArray[np.uint16],
                                             NDArray[np.float64]]:
    """Every ray of one revolution in firing order (``column * channels + beam``): its unit
    direction in the sensor frame (n, 3), its ring (n,) and its firing time after the scan's
    stamp in s (n,). The CPU :class:`Lidar` and the batched one
    (:mod:`marsscene.sensors.batch`) cast these."""
    elev = np.radians(np.asarray(spec.vertical_angles_deg))
    a, e = np.meshgrid(spec.column_azimuth_rad(), elev, indexing="ij")  # (columns, beams)
    dirs = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)],
                    axis=-1).reshape(-1, 3)
    ring = np.tile(spec.rings(), spec.horizontal_samples).astype(np.uint16)
    return dirs, ring, spec.firing_time_s().T.reshape(-1)


def rotation_about(omega_t: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 3, 3) rotation matrices of the rotation vectors ``omega_t`` (n, 3) (Rodrigues)."""
    theta = np.linalg.norm(omega_t, axis=1)
    safe = np.where(theta > 1e-12, theta, 1.0)
    k = omega_t / safe[:, None]
    kx = np.zeros((len(k), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx[:, 1, 0], kx[:, 2, 0], kx[:, 2, 1] = k[:, 2], -k[:, 1], k[:, 0]
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.asarray(np.eye(3)[None] + s * kx + (1.0 - c) * (kx @ kx), dtype=np.float64)


class Lidar:
    """One spinning LiDAR. ``rng`` draws range noise and dropouts (required when the model has
    either); ``rocks`` are the scene's catalogue rocks that are not MuJoCo geoms ((N, 6), see
    :func:`marsscene.sensors.camera_world.read_rock_catalog`), cast with the terrain."""

    def __init__(self, config: LidarConfig, *, rng: np.random.Generator | None = None,
                 rocks: NDArray[np.float64] | None = None):
        self.config = config
        self.rocks = rocks
        self.spec = spec = config.spec
        if rng is None and (spec.range_noise_sigma_m > 0 or spec.dropout_probability > 0):
            raise ValueError("a LiDAR with range noise or dropouts needs rng=")
        self.rng = rng
        elev = np.radians(np.asarray(spec.vertical_angles_deg))
        azim = spec.column_azimuth_rad()
        self.dirs_sensor, self.ring, self.t_s = beam_geometry(spec)
        n = len(self.dirs_sensor)
        # a column's world directions are cos(e) R [cos a, sin a, 0] + sin(e) R [0, 0, 1]
        self._cos_sin_azim = np.stack([np.cos(azim), np.sin(azim)], axis=1)  # (columns, 2)
        self._cos_elev = np.cos(elev).astype(np.float32)[None, :, None]
        self._sin_elev = np.sin(elev).astype(np.float32)[None, :, None]
        t_col = self.t_s.reshape(spec.horizontal_samples, -1)
        self._column_times = bool(np.all(t_col == t_col[:, :1]))  # one time per column
        self._geomid = np.zeros(n, dtype=np.int32)
        self._dist = np.zeros(n, dtype=np.float64)
        self._normal = np.zeros((n, 3), dtype=np.float64)
        self._groups = np.array([1, 1, 0, 0, 0, 0], dtype=np.uint8)
        self._caster: TerrainCaster | None = None

    def caster(self, terrain: Heightfield, model: Any = None, data: Any = None
               ) -> TerrainCaster:
        """The caster of ``terrain``, the catalogue rocks and the model's static geoms (kept
        while the terrain is the same object)."""
        if self._caster is None or self._caster.hf is not terrain:
            static = static_geom_mesh(model, data) if model is not None else None
            self._caster = TerrainCaster(terrain, self.spec.range_m[1], rocks=self.rocks,
                                         static=static)
        return self._caster

    def _mujoco_rays(self, model: Any, data: Any, origin: NDArray[np.float64],
                     origins: NDArray[np.float64] | None, dirs: NDArray[np.float64],
                     terrain: Heightfield | None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Without Embree: MuJoCo rays for the geoms (and the hfield without ``terrain``),
        the numpy march for ``terrain``."""
        import mujoco

        rmin, rmax = self.spec.range_m
        groups = self._groups if terrain is not None else np.array([1, 1, 0, 1, 0, 0], np.uint8)
        mujoco.mj_multiRay(model, data, origin, dirs.ravel(), groups, 1, -1, self._geomid,
                           self._dist, self._normal.ravel(), len(dirs), rmax + 1.0)
        dist = np.where(self._geomid >= 0, self._dist, np.inf)
        normals = self._normal.reshape(-1, 3).copy()
        if origins is not None:
            # geoms were cast from the sweep's first origin: move each hit along its ray to
            # where the ray from the column's own origin meets the same plane
            dn = np.einsum("ij,ij->i", dirs, normals)
            shift = np.einsum("ij,ij->i", origins - origin, normals)
            ok = np.isfinite(dist) & (np.abs(dn) > _GRAZE)
            dist = np.where(ok, dist + shift / np.where(ok, dn, 1.0), dist)
        if terrain is not None:
            t_dist, t_normal = self.caster(terrain).cast(
                origins if origins is not None else origin, dirs, (rmin, rmax))
            closer = t_dist < dist
            dist = np.where(closer, t_dist, dist)
            normals[closer] = t_normal[closer]
        return dist, normals

    def _world_rays(self, rot: NDArray[np.float64], origin: NDArray[np.float64],
                    twist: NDArray[np.float64] | None
                    ) -> tuple[NDArray[np.float64] | None, NDArray[np.float64]]:
        """Per-ray origins (n, 3) (None: all at ``origin``) and unit directions (n, 3) in the
        world frame."""
        if twist is None or not self.spec.motion_distortion:
            return None, self.dirs_sensor @ rot.T
        omega, vel = twist[:3], twist[3:]
        t_col = self.t_s.reshape(self.spec.horizontal_samples, -1)[:, 0]
        r_col = rotation_about(t_col[:, None] * omega[None, :]) @ rot  # (columns, 3, 3)
        d = self.dirs_sensor.reshape(self.spec.horizontal_samples, -1, 3)
        dirs = np.einsum("cij,cbj->cbi", r_col, d).reshape(-1, 3)
        origins = origin[None, :] + self.t_s[:, None] * vel[None, :]
        return origins, dirs

    def scan(self, model: Any, data: Any, site_id: int, terrain: Heightfield | None = None,
             *, twist: NDArray[np.float64] | None = None) -> dict[str, NDArray[Any]]:
        """One revolution from the current state.

        Parameters
        ----------
        model, data : mujoco.MjModel, mujoco.MjData
        site_id : int
            The ``lidar`` site.
        terrain : Heightfield, optional
            The terrain (``RoverSim`` moves its hfield geom to group 3). With ``embreex`` the
            terrain, the catalogue rocks and the static geoms of groups 0 and 1 are cast in one
            Embree scene; without it MuJoCo rays see groups 0 and 1 and the numpy march the
            terrain. Without ``terrain`` MuJoCo casts against groups 0, 1 and 3.
        twist : ndarray of shape (6,), optional
            The site's angular and linear velocity (world frame, ``mj_objectVelocity`` order)
            held during the sweep for motion distortion.

        Returns
        -------
        dict with ``xyz_m`` (N, 3) float32 (sensor frame at each point's firing time),
        ``intensity`` (N,) float32 in [0, 1], ``ring`` (N,) uint16, ``t_s`` (N,) float64
        firing time after the stamp, ``range_m`` (N,) float32, ``ray`` (N,) int32 (the ray's
        index, ``column * channels + beam``: where it sits in a range image): only returns, in
        firing order.
        """
        return self.prepare(model, data, site_id, terrain, twist=twist)()

    def prepare(self, model: Any, data: Any, site_id: int, terrain: Heightfield | None = None,
                *, twist: NDArray[np.float64] | None = None,
                boxes: Sequence[Boxes] | None = None
                ) -> Callable[[], dict[str, NDArray[Any]]]:
        """:meth:`scan` in two steps: read the state now, cast when the returned function is
        called. With Embree the call touches no MuJoCo data, so it may run on another thread
        while the simulation advances (call the functions in order: the noise draws are).

        ``boxes`` are moving obstacles cast besides the scene: sets of boxes (the other
        robots of a team, :func:`~marsscene.sensors.lidar_boxes.robot_boxes` each, read now)."""
        rot = np.asarray(data.site_xmat[site_id], dtype=np.float64).reshape(3, 3).copy()
        origin = np.asarray(data.site_xpos[site_id], dtype=np.float64).copy()
        twist = None if twist is None else np.asarray(twist, dtype=np.float64).copy()
        if terrain is not None and embree_available():  # everything in one Embree scene
            caster = self.caster(terrain, model, data)  # built here: it reads the model

            def cast() -> dict[str, NDArray[Any]]:
                dirs = self._world_dirs32(rot, twist)
                origins = self._origins32(origin, twist)
                idx, dist, normals = caster.cast_hits(origins, dirs, self.spec.range_m)
                if boxes is not None:
                    full, nrm = np.full(len(dirs), np.inf), np.zeros((len(dirs), 3))
                    full[idx], nrm[idx] = dist, normals
                    full, nrm = self._nearer_boxes(full, nrm, origins, dirs, boxes)
                    idx = self._in_range(full)
                    dist, normals = full[idx], nrm[idx]
                return self._returns(idx, dist, normals, dirs[idx])

            return cast
        origins, dirs = self._world_rays(rot, origin, twist)
        dist, normals = self._mujoco_rays(model, data, origin, origins, dirs, terrain)
        if boxes is not None:
            dist, normals = self._nearer_boxes(dist, normals, origin if origins is None
                                               else origins, dirs, boxes)
        idx = self._in_range(dist)
        return lambda: self._returns(idx, dist[idx], normals[idx], dirs[idx])

    def _in_range(self, dist: NDArray[np.float64]) -> NDArray[np.intp]:
        rmin, rmax = self.spec.range_m
        return np.flatnonzero(np.isfinite(dist) & (dist >= rmin) & (dist <= rmax))

    def _nearer_boxes(self, dist: NDArray[np.float64], normals: NDArray[np.float64],
                      origins: Any, dirs: Any, boxes: Sequence[Boxes]
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``dist`` and ``normals`` of every ray, where a box is nearer: the box's."""
        b_dist, b_normal = ray_boxes(origins, dirs, boxes, self.spec.range_m[1])
        closer = b_dist < dist
        dist = np.where(closer, b_dist, dist)
        normals = np.where(closer[:, None], b_normal, normals)
        return dist, normals

    def _origins32(self, origin: NDArray[np.float64], twist: NDArray[np.float64] | None
                   ) -> NDArray[np.float32]:
        """:meth:`_world_rays`' origins as float32: (3,) or (n, 3) with motion distortion."""
        if twist is None or not self.spec.motion_distortion:
            return origin.astype(np.float32)
        if not self._column_times:
            return (origin[None, :] + self.t_s[:, None] * twist[None, 3:]).astype(np.float32)
        t_col = self.t_s.reshape(self.spec.horizontal_samples, -1)[:, 0]
        per_col = (origin[None, :] + t_col[:, None] * twist[None, 3:]).astype(np.float32)
        return np.repeat(per_col, self.spec.channels, axis=0)

    def _world_dirs32(self, rot: NDArray[np.float64], twist: NDArray[np.float64] | None
                      ) -> NDArray[np.float32]:
        """:meth:`_world_rays`' directions as float32 (n, 3), from two vectors per column
        (the rotated azimuth and the rotated vertical) instead of a matrix per ray."""
        if twist is None or not self.spec.motion_distortion:
            r_col = rot[None]
        else:
            t_col = self.t_s.reshape(self.spec.horizontal_samples, -1)[:, 0]
            r_col = rotation_about(t_col[:, None] * twist[None, :3]) @ rot  # (columns, 3, 3)
        cs = self._cos_sin_azim
        u = (r_col[:, :, 0] * cs[:, :1] + r_col[:, :, 1] * cs[:, 1:]).astype(np.float32)
        w = np.broadcast_to(r_col[:, :, 2], u.shape).astype(np.float32)
        out = u[:, None, :] * self._cos_elev  # (columns, beams, 3), fresh: casts may overlap
        out += w[:, None, :] * self._sin_elev
        return out.reshape(-1, 3)

    def _returns(self, idx: NDArray[np.intp], dist: NDArray[np.float64],
                 normals: NDArray[np.float64], dirs: NDArray[np.floating[Any]]
                 ) -> dict[str, NDArray[Any]]:
        """The scan's returns from the rays ``idx`` (ascending) that hit within range, their
        distances, unit normals and directions: dropouts, range noise, intensity."""
        spec = self.spec
        if spec.dropout_probability > 0:  # one draw per ray, hit or not
            assert self.rng is not None
            keep = self.rng.random(len(self.t_s))[idx] >= spec.dropout_probability
            idx, dist, normals, dirs = idx[keep], dist[keep], normals[keep], dirs[keep]
        r = dist
        if spec.range_noise_sigma_m > 0:
            assert self.rng is not None
            r = np.maximum(r + spec.range_noise_sigma_m * self.rng.standard_normal(r.size), 0.0)
        cos_inc = np.abs(np.einsum("ij,ij->i", normals, dirs.astype(np.float64)))
        intensity = np.clip(cos_inc, 0.0, 1.0) * np.exp(-2.0 * spec.dust_extinction_per_m * r)
        return {
            "xyz_m": (self.dirs_sensor[idx] * r[:, None]).astype(np.float32),
            "intensity": intensity.astype(np.float32),
            "ring": self.ring[idx],
            "t_s": self.t_s[idx],
            "range_m": r.astype(np.float32),
            "ray": idx.astype(np.int32),
        }
