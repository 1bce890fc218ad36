"""The camera and LiDAR observations of a :class:`~.env.BatchNavEnv`: the navcam's RGB and depth
and a LiDAR range image of every rover, cast on the device by :mod:`marsscene.sensors.batch`.

Asked for by the CPU environment's options (:class:`~marsscene.env.observe.ObsConfig`:
``camera=(W, H), depth=True``; ``lidar="os1-64"``, ``lidar_rate_hz``) under the CPU
environment's keys and units, channels first for PyTorch encoders:

==============  =====================  ===================================================
``rgb``         (N, 3, H, W) uint8     exposed sRGB (the CPU ``rgb`` is (H, W, 3))
``depth``       (N, 1, H, W) float32   planar depth in m along the optical axis, 0 where
                                       nothing is seen (the CPU ``depth`` is (H, W))
``lidar_range`` (N, 1, channels,       range in m, 0 where the ray did not return (rows:
                columns) float32       beams in firing order; columns: azimuth steps)
``lidar_mask``  (N, 1, channels,       1 where the ray returned
                columns) int8
==============  =====================  ===================================================

The camera is :class:`~marsscene.sensors.batch.BatchCamera`: the world the CPU camera sees
(regolith texture, the batch's rocks as meshes, sun and shadows, sky, fog, auto exposure), ray
traced from each rover's navcam pose on its own world; its depth is of that world (smooth
terrain and rock meshes), not of the physics' heightfield relief. Its auto exposure keeps one
gain a rover slot, smoothed across that slot's resets. The LiDAR is the CPU LiDAR's beam model
with its datasheet noise, drawn from each rover slot's own seed
(:func:`marsscene.sensors.batch.lidar.world_seeds`). Both see the rover's own world only (a hit
past its tile's edge is no return) and are cast from the pose of the state observed (the
kinematics are recomputed first: a reset rover's sensors are at its new start, on its new
world). Each observation holds copies: the sensors' buffers are overwritten by their next call.
"""

from __future__ import annotations

from typing import Any

from marsscene.env.observe import ObsConfig
from marsscene.errors import ConfigError

__all__ = ["IMAGE_KEYS", "BatchSensors", "check_sensors", "observation_spaces"]

#: The keys the batch returns channels first, (N, 1, ...): the CPU environment's (...).
IMAGE_KEYS = ("depth", "lidar_range", "lidar_mask")
#: The largest image the batch camera renders a rover (its buffers: N x H x W x 20 bytes).
MAX_CAMERA_PX = (640, 480)
#: The navcam in a model with the rover attached.
NAVCAM = "rover/navcam"


def check_sensors(obs: ObsConfig) -> None:
    """Raise where the batch cannot observe what ``obs`` asks for: a camera larger than the
    batch camera's largest size (``MAX_CAMERA_PX``, 640 x 480)."""
    if obs.camera is not None and (obs.camera[0] > MAX_CAMERA_PX[0]
                                   or obs.camera[1] > MAX_CAMERA_PX[1]):
        raise ConfigError(f"camera = {obs.camera}; the batched camera renders up to "
                          f"{MAX_CAMERA_PX[0]} x {MAX_CAMERA_PX[1]}")


def observation_spaces(obs: ObsConfig) -> dict[str, Any]:
    """The ``gymnasium.spaces`` of one rover's keys: :meth:`ObsConfig.spaces
    <marsscene.env.observe.ObsConfig.spaces>`'s, images channels first."""
    from gymnasium import spaces

    out = obs.spaces()
    if "rgb" in out:
        h, w, c = out["rgb"].shape
        out["rgb"] = spaces.Box(0, 255, (c, h, w), out["rgb"].dtype)
    for key in IMAGE_KEYS:
        if key in out:
            box = out[key]
            out[key] = spaces.Box(box.low.flat[0], box.high.flat[0], (1, *box.shape),
                                  box.dtype)
    return out


class BatchSensors:
    """The depth camera and LiDAR of N rovers (either may be absent).

    Parameters
    ----------
    mj_model, mjw_model, mjw : the batch's host model, its device copy and ``mujoco_warp``
    num_envs : int
    obs : ObsConfig
        ``camera`` (with ``depth``) and ``lidar``, ``lidar_rate_hz``.
    control_hz : float
    seed : int
        Seed of the LiDAR's noise.
    backend : Backend
        The environment's array library.
    batch : WorldBatch
        The worlds the camera draws; ``offsets_xy_m`` (W, 2) their tiles in the model frame.
    """

    def __init__(self, mj_model: Any, mjw_model: Any, mjw: Any, num_envs: int, obs: ObsConfig,
                 control_hz: float, seed: int, backend: Any, *, batch: Any,
                 offsets_xy_m: Any) -> None:
        import mujoco

        from marsscene.sensors.batch import BatchCamera, BatchLidar

        self.model, self._mjw, self.bk, self.n = mjw_model, mjw, backend, int(num_envs)
        cam, lidar = obs.camera_config(control_hz), obs.lidar_config()
        self.depth = bool(obs.depth)
        self.camera_id = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_CAMERA, NAVCAM)
        with backend.wp.ScopedDevice(backend.device):
            self.camera = (BatchCamera(batch, self.n, config=cam, offsets_xy_m=offsets_xy_m,
                                       catalogue=batch.catalogues(), rgb=obs.rgb,
                                       device=backend.device)
                           if cam is not None else None)
            self.lidar = (BatchLidar(mj_model, mjw_model, self.n, lidar, seed=seed)
                          if lidar is not None else None)
        self._bounds: Any = None  # the last call's (kept alive while the kernels read it)
        self._world: Any = None

    def restart(self, seed: int) -> None:
        """Restart the LiDAR's noise from ``seed``."""
        if self.lidar is not None:
            self.lidar.restart(seed)

    def observe(self, data: Any, bounds_xy_m: Any, world: Any) -> dict[str, Any]:
        """``rgb``, ``depth``, ``lidar_range`` and ``lidar_mask`` (as asked) of ``data``'s
        state, each rover on world ``world`` (N,), its rectangle ``bounds_xy_m`` (N, 4) (model
        frame)."""
        wp, mjw, bk, xp, n = self.bk.wp, self._mjw, self.bk, self.bk.xp, self.n
        out: dict[str, Any] = {}
        with wp.ScopedDevice(bk.device):
            mjw.kinematics(self.model, data)  # the sensors' poses from qpos (a reset moved it)
            mjw.com_pos(self.model, data)
            if self.camera is not None:
                mjw.camlight(self.model, data)
            if self.lidar is not None and self.lidar.spec.motion_distortion:
                mjw.com_vel(self.model, data)
            self._bounds = b = _warp_bounds(bk, bounds_xy_m)
            if self.camera is not None:
                self._world = _warp_ints(bk, world)
                rgb = self.camera.render_data(data, self._world, self.camera_id)
                if self.camera.shaded:
                    out["rgb"] = xp.asarray(bk.view(rgb), copy=True)
                if self.depth:
                    depth = bk.view(self.camera.depth)
                    out["depth"] = xp.asarray(xp.reshape(depth, (n, 1, *depth.shape[1:])),
                                              copy=True)
            if self.lidar is not None:
                spec = self.lidar.spec
                twist = (self.lidar.site_twist(data) if spec.motion_distortion else None)
                scan = self.lidar.scan(data, twist=twist, bounds_xy_m=b)
                image = (n, 1, spec.channels, spec.horizontal_samples)
                out["lidar_range"] = _image(xp, bk.view(scan.range_m), image)
                out["lidar_mask"] = xp.astype(_image(xp, bk.view(scan.valid), image), xp.int8)
        return out


def _image(xp: Any, rays: Any, shape: tuple[int, int, int, int]) -> Any:
    """(N, R) rays in firing order (``column * channels + beam``) as (N, 1, channels,
    columns), a copy."""
    n, _, channels, columns = shape
    by_beam = xp.permute_dims(xp.reshape(rays, (n, columns, channels)), (0, 2, 1))
    return xp.asarray(xp.reshape(by_beam, shape), copy=True)


def _warp_ints(bk: Any, values: Any) -> Any:
    """(N,) int32 Warp array of ``values`` (no host copy)."""
    xp, wp = bk.xp, bk.wp
    v = xp.astype(values, xp.int32)
    if bk.torch is not None:
        return wp.from_torch(v.contiguous())
    return wp.array(v, dtype=int, device=bk.device)


def _warp_bounds(bk: Any, bounds_xy_m: Any) -> Any:
    """(N, 4) float32 Warp array of the bounds (a view of a device copy; no host copy)."""
    xp, wp = bk.xp, bk.wp
    b = xp.astype(bounds_xy_m, xp.float32)
    if bk.torch is not None:
        return wp.from_torch(b.contiguous())
    return wp.array(b, dtype=float, device=bk.device)
