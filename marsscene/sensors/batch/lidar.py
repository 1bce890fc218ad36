"""A spinning LiDAR on every world of a MuJoCo Warp batch: the CPU LiDAR's beam models
(:func:`marsscene.sensors.lidar.beam_geometry` of a :class:`~marsscene.rover.lidar.LidarConfig`),
cast by ``mujoco_warp.rays`` through a render context's BVH, with the CPU LiDAR's returns.

One :meth:`BatchLidar.scan` casts one revolution in every world from the LiDAR site's pose in
that world's ``Data`` (or, with ``twist``, from the pose each ray has at its firing time, as the
CPU LiDAR's ``motion_distortion`` does). It returns dense device arrays, one row a world and
one column a ray in firing order (``column * channels + beam``, the CPU scan's ``ray``): the
range, the point in the sensor frame of its firing time, the intensity and whether the ray
returned. The CPU LiDAR keeps returns only; :meth:`BatchScan.returns` gives one world's scan in
that form. Range noise and dropouts are the CPU model's (the datasheet sigma, the dropout
probability), drawn on the device from each world's own seed and scan count
(:mod:`._kernels`): the same seed gives the same bytes, whatever the batch size.

``rays`` without a render context tests every geom (about 6,000 times slower), so the LiDAR
builds one (BVHs of the geoms of ``geom_groups``; the heightfield's mesh is built in Python,
seconds on a large tiled heightfield) unless it is given one. Static geoms need no refit; where
the BVH holds moving geoms the LiDAR refits it before each scan.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.rover.lidar import LidarConfig, LidarSpec
from marsscene.sensors.lidar import beam_geometry

__all__ = ["BatchLidar", "BatchScan", "check_bounds", "world_seeds"]

#: The LiDAR's site in a model with the rover attached (``marsscene.sim.rover_sim.PREFIX``).
LIDAR_SITE = "rover/lidar"
#: Geom groups a LiDAR sees by default: the CPU LiDAR's (terrain, rocks, static geoms; the
#: rover's own geoms are group 2).
LIDAR_GROUPS = (0, 1)


def world_seeds(seed: int, n: int, streams: Any = None, sensor: int = 0) -> NDArray[np.int32]:
    """Seed of each of ``n`` worlds: world ``w``'s depends on ``(seed, streams[w])`` only
    (``streams`` default: the world's index; a batch of drives passes each drive's seed, so a
    drive's LiDAR noise does not depend on its slot in the batch); ``sensor`` > 0 gives another
    sensor of the same worlds streams of its own (the LiDAR's is 0, the camera's 1)."""
    keys = range(n) if streams is None else [int(k) for k in streams]
    if len(keys) != n:
        raise ConfigError(f"{len(keys)} noise streams for {n} worlds")
    extra = [int(sensor)] if sensor else []
    states = [np.random.SeedSequence([int(seed), k, *extra]).generate_state(1)[0]
              for k in keys]
    return np.asarray(states, dtype=np.uint32).view(np.int32)


@dataclass(frozen=True, eq=False)
class BatchScan:
    """One revolution in every world: Warp arrays on the batch's device, (N, R) with R the
    rays of one revolution (``xyz_m`` (N, R, 3)). Each buffer is the LiDAR's own and is
    overwritten by its next scan; ``wp.to_torch`` views them without a copy.

    Attributes
    ----------
    range_m, intensity : float32 (N, R)
        0 where the ray did not return.
    xyz_m : float32 (N, R, 3)
        The point in the sensor frame of its firing time (0 where none).
    valid : bool (N, R)
        The ray returned (a hit within range that survived its dropout draw).
    spec : LidarSpec
    t_s, ring : ndarray (R,)
        Firing time after the scan's stamp (float64) and ring (uint16) of each ray.
    """

    range_m: Any
    xyz_m: Any
    intensity: Any
    valid: Any
    spec: LidarSpec
    t_s: NDArray[np.float64]
    ring: NDArray[np.uint16]

    def returns(self, world: int) -> dict[str, NDArray[Any]]:
        """World ``world``'s scan as :meth:`marsscene.sensors.lidar.Lidar.scan` returns it
        (returns only, in firing order; a host copy)."""
        if not 0 <= world < self.valid.shape[0]:
            raise ConfigError(f"world {world} is out of range; the scan has "
                              f"{self.valid.shape[0]}")
        idx = np.flatnonzero(self.valid[world].numpy())  # one world's row is copied
        return {
            "xyz_m": self.xyz_m[world].numpy().reshape(-1, 3)[idx],
            "intensity": self.intensity[world].numpy()[idx],
            "ring": self.ring[idx],
            "t_s": self.t_s[idx],
            "range_m": self.range_m[world].numpy()[idx],
            "ray": idx.astype(np.int32),
        }


class BatchLidar:
    """One spinning LiDAR per world of a MuJoCo Warp batch.

    Parameters
    ----------
    mj_model : mujoco.MjModel
        The host model the batch was put from (``BatchNavEnv.mj_model``).
    model : mujoco_warp.Model
        Its device copy (``BatchNavEnv.mjw_model``).
    nworld : int
        Worlds in the batch.
    config : LidarConfig, optional
        The beam model (default ``LidarConfig()``, the OS1-128).
    site : str or int
        The LiDAR site (default the rover's ``rover/lidar``).
    seed : int
        Seed of the range noise and dropouts (:func:`world_seeds`).
    streams : sequence of int, optional
        Each world's noise stream under ``seed`` (default: its index; :func:`world_seeds`).
    geom_groups : tuple of int
        The geom groups it sees (default: 0 and 1, as the CPU LiDAR).
    render_context : mujoco_warp.RenderContext, optional
        A context whose BVH holds those groups (default: one built here, for ``nworld``).
    cast_order : {"beam", "firing"}
        The order the rays are traced in (the output is in firing order either way):
        ``"beam"`` traces one beam's columns side by side (neighbouring threads follow nearly
        parallel rays: sky with sky, ground with ground), ``"firing"`` a column's beams.
    """

    def __init__(self, mj_model: Any, model: Any, nworld: int,
                 config: LidarConfig | None = None, *, site: str | int = LIDAR_SITE,
                 seed: int = 0, geom_groups: tuple[int, ...] = LIDAR_GROUPS,
                 render_context: Any = None, cast_order: str = "beam",
                 streams: Any = None) -> None:
        import mujoco_warp as mjw
        import warp as wp

        self._wp, self._mjw, self.model = wp, mjw, model
        self.spec = spec = (config if config is not None else LidarConfig()).spec
        self.nworld = int(nworld)
        self.site = _site_id(mj_model, site)
        self.body = int(mj_model.site_bodyid[self.site])
        dirs, self.ring, self.t_s = beam_geometry(spec)
        t_col = np.repeat(self.t_s.reshape(spec.horizontal_samples, -1)[:, 0], spec.channels)
        order = _cast_order(spec, cast_order)  # order[i]: the ray traced in slot i
        slot = np.argsort(order).astype(np.int32)
        self.rc = render_context if render_context is not None else mjw.create_render_context(
            mj_model, nworld=self.nworld, cam_active=[], render_rgb=False, render_depth=False,
            use_textures=False, enabled_geom_groups=list(geom_groups))
        enabled = np.isin(mj_model.geom_group, geom_groups)
        self.refit = bool(np.any(mj_model.body_weldid[mj_model.geom_bodyid[enabled]] != 0))
        n, rays = self.nworld, len(dirs)
        self.groups = wp.types.vector(6, wp.float32)(*[float(g in geom_groups) for g in range(6)])
        with wp.ScopedDevice(model.geom_type.device):
            self._dirs: Any = wp.array(dirs.astype(np.float32), dtype=wp.vec3)
            self._slot: Any = wp.array(slot, dtype=int)
            self._cast: dict[str, Any] = {  # world_rays' sensor arrays, in cast order
                "dirs": wp.array(dirs[order].astype(np.float32), dtype=wp.vec3),
                "t_ray": wp.array(self.t_s[order].astype(np.float32), dtype=float),
                "t_col": wp.array(t_col[order].astype(np.float32), dtype=float)}
            self._exclude = wp.full(rays, -1, dtype=int)
            self._no_twist = wp.zeros((1, 6), dtype=float)
            self._no_bounds = wp.zeros((1, 4), dtype=float)
            self.twist = wp.zeros((n, 6), dtype=float)
            self._pnt, self._vec = (wp.zeros((n, rays), dtype=wp.vec3) for _ in range(2))
            self._dist = wp.zeros((n, rays), dtype=float)
            self._geom = wp.zeros((n, rays), dtype=int)
            self._normal = wp.zeros((n, rays), dtype=wp.vec3)
            self._streams = None if streams is None else [int(k) for k in streams]
            self._seed: Any = wp.array(world_seeds(seed, n, self._streams), dtype=int)
            self._count = wp.zeros(n, dtype=int)
            self.out = BatchScan(
                range_m=wp.zeros((n, rays), dtype=float), xyz_m=wp.zeros((n, rays), dtype=wp.vec3),
                intensity=wp.zeros((n, rays), dtype=float),
                valid=wp.zeros((n, rays), dtype=wp.bool), spec=spec, t_s=self.t_s, ring=self.ring)

    @property
    def rays_per_scan(self) -> int:
        return len(self.t_s)

    def restart(self, seed: int) -> None:
        """Restart every world's stream of draws from ``seed`` (scan count 0)."""
        wp = self._wp
        wp.copy(self._seed, wp.array(world_seeds(seed, self.nworld, self._streams), dtype=int,
                                     device=self._seed.device))
        self._count.zero_()

    def site_twist(self, data: Any) -> Any:
        """The LiDAR site's twist in every world (angular, linear; world frame), (N, 6) float
        (the buffer :meth:`scan` takes as ``twist``; overwritten by the next call)."""
        wp, m = self._wp, self.model
        wp.launch(_k().site_twist, dim=self.nworld,
                  inputs=[data.cvel, data.subtree_com, data.site_xpos, m.body_rootid,
                          self.body, self.site], outputs=[self.twist], device=self.twist.device)
        return self.twist

    def scan(self, data: Any, *, twist: Any = None, bounds_xy_m: Any = None) -> BatchScan:
        """One revolution in every world from ``data``'s current kinematics (``site_xpos``,
        ``site_xmat``, ``geom_xpos``: after ``mujoco_warp.step`` or ``kinematics``).

        Parameters
        ----------
        data : mujoco_warp.Data
        twist : warp array (N, 6), optional
            Each site's angular and linear velocity (world frame), held for the sweep: with
            the spec's ``motion_distortion`` each ray is cast from the pose at its firing time
            (:meth:`site_twist` gives it from ``data``). None: every ray from the current pose.
        bounds_xy_m : warp array (N, 4), optional
            Each world's rectangle ``x0, y0, x1, y1`` in the model frame: a hit outside it is
            no return (a tiled batch's neighbouring tiles and the floor between them; the CPU
            LiDAR's world ends at its edge). None: every hit counts.
        """
        wp, mjw, m, n = self._wp, self._mjw, self.model, self.nworld
        if data.nworld != n:
            raise ConfigError(f"BatchLidar was made for {n} worlds; data has {data.nworld}")
        distort = twist is not None and self.spec.motion_distortion
        if distort and tuple(twist.shape) != (n, 6):
            raise ConfigError(f"twist must be ({n}, 6); got {tuple(twist.shape)}")
        clip = check_bounds(bounds_xy_m, n)
        dim, dev, k, spec = (n, self.rays_per_scan), self._dist.device, _k(), self.spec
        if self.refit:
            mjw.refit_bvh(m, data, self.rc)
        wp.launch(k.world_rays, dim=dim, device=dev, inputs=[
            data.site_xpos, data.site_xmat, self.site, *self._cast.values(),
            twist if distort else self._no_twist, int(distort)], outputs=[self._pnt, self._vec])
        mjw.rays(m, data, self._pnt, self._vec, self.groups, True, self._exclude, self._dist,
                 self._geom, self._normal, self.rc)
        o = self.out
        wp.launch(k.returns, dim=dim, device=dev, inputs=[
            self._dist, self._normal, self._pnt, self._vec,
            bounds_xy_m if clip else self._no_bounds, int(clip), self._dirs, self._slot,
            *spec.range_m,
            spec.range_noise_sigma_m, spec.dropout_probability, spec.dust_extinction_per_m,
            self._seed, self._count], outputs=[o.range_m, o.xyz_m, o.intensity, o.valid])
        wp.launch(k.advance, dim=n, inputs=[self._count], device=dev)
        return o


def _k() -> Any:
    from marsscene.sensors.batch import _kernels

    return _kernels


def check_bounds(bounds_xy_m: Any, n: int) -> bool:
    """Whether there are bounds to clip by (raising if they are not (n, 4))."""
    if bounds_xy_m is None:
        return False
    if tuple(bounds_xy_m.shape) != (n, 4):
        raise ConfigError(f"bounds_xy_m must be ({n}, 4); got {tuple(bounds_xy_m.shape)}")
    return True


def _cast_order(spec: LidarSpec, order: str) -> NDArray[np.intp]:
    """The firing-order index of the ray traced in each slot."""
    rays = np.arange(spec.horizontal_samples * spec.channels)
    if order == "firing":
        return rays
    if order == "beam":  # slot beam * columns + column holds ray column * channels + beam
        return np.asarray(rays.reshape(spec.horizontal_samples, spec.channels).T.ravel())
    raise ConfigError(f"cast_order {order!r}; use 'beam' or 'firing'")


def _site_id(mj_model: Any, site: str | int) -> int:
    import mujoco

    if isinstance(site, str):
        sid = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, site)
        if sid < 0:
            raise ConfigError(f"the model has no site {site!r}")
        return int(sid)
    if not 0 <= int(site) < mj_model.nsite:
        raise ConfigError(f"site id {site} is out of range; the model has {mj_model.nsite}")
    return int(site)
