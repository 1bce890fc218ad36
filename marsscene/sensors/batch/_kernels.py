# mypy: ignore-errors
# (Warp's kernel language: its annotations and indexing are not Python's typing)
"""Warp kernels of the batched sensors: LiDAR ray generation (motion distortion included), the
returns (range gate, dropouts, range noise, intensity, sensor-frame points) and the LiDAR
site's twist from MuJoCo Warp's body velocities.

Layout: world ``w``, ray ``j`` (firing order, ``column * channels + beam``). The rays are cast
in another order (``slot[j]``: the LiDAR's ``cast_order``), so that neighbouring GPU threads
trace neighbouring rays. Every random draw
of world ``w``'s scan ``k`` comes from ``rand_init(mix(seed[w], k), j)``: a world's noise
depends on its seed and scan count alone, never on the batch size or on the other worlds.
"""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})


@wp.func
def _rotation_about(v: wp.vec3) -> wp.mat33:
    """The rotation by the rotation vector ``v`` (Rodrigues)."""
    theta = wp.length(v)
    if theta < 1.0e-12:
        return wp.identity(n=3, dtype=float)
    k = v / theta
    kx = wp.mat33(0.0, -k[2], k[1], k[2], 0.0, -k[0], -k[1], k[0], 0.0)
    return wp.identity(n=3, dtype=float) + wp.sin(theta) * kx + (1.0 - wp.cos(theta)) * (kx @ kx)


@wp.kernel
def world_rays(
    site_xpos: wp.array2d[wp.vec3],
    site_xmat: wp.array2d[wp.mat33],
    site: int,
    dirs_sensor: wp.array[wp.vec3],
    t_ray: wp.array[float],
    t_column: wp.array[float],
    twist: wp.array2d[float],
    distort: int,
    pnt_out: wp.array2d[wp.vec3],
    vec_out: wp.array2d[wp.vec3],
):
    """Origin and unit direction of every ray (in cast order: the sensor arrays are permuted)
    in the world frame: from the site's pose, or with
    ``distort`` from the pose at each ray's firing time (the twist, angular then linear in the
    world frame, held for the sweep: the column's rotation, the ray's own translation)."""
    w, j = wp.tid()
    rot = site_xmat[w, site]
    origin = site_xpos[w, site]
    if distort != 0:
        omega = wp.vec3(twist[w, 0], twist[w, 1], twist[w, 2])
        vel = wp.vec3(twist[w, 3], twist[w, 4], twist[w, 5])
        rot = _rotation_about(t_column[j] * omega) @ rot
        origin = origin + t_ray[j] * vel
    pnt_out[w, j] = origin
    vec_out[w, j] = wp.normalize(rot @ dirs_sensor[j])


@wp.func
def _scan_seed(seed: int, count: int) -> int:
    """One world's seed of one scan."""
    return int(wp.rand_init(seed, count))


@wp.func
def _inside(bounds: wp.array2d[float], w: int, p: wp.vec3) -> bool:
    """Whether ``p`` lies over world ``w``'s rectangle (x0, y0, x1, y1)."""
    return (p[0] >= bounds[w, 0] and p[1] >= bounds[w, 1] and p[0] <= bounds[w, 2]
            and p[1] <= bounds[w, 3])


@wp.kernel
def returns(
    dist: wp.array2d[float],
    normal: wp.array2d[wp.vec3],
    pnt: wp.array2d[wp.vec3],
    vec: wp.array2d[wp.vec3],
    bounds: wp.array2d[float],
    clip: int,
    dirs_sensor: wp.array[wp.vec3],
    slot: wp.array[int],
    range_min_m: float,
    range_max_m: float,
    sigma_m: float,
    dropout: float,
    alpha_per_m: float,
    seed: wp.array[int],
    count: wp.array[int],
    range_out: wp.array2d[float],
    xyz_out: wp.array2d[wp.vec3],
    intensity_out: wp.array2d[float],
    valid_out: wp.array2d[wp.bool],
):
    """The CPU LiDAR's returns (:meth:`marsscene.sensors.lidar.Lidar._returns`) on every ray:
    a hit within range that survives its dropout draw (one per ray, hit or not) returns its
    range plus Gaussian noise (floored at 0); intensity is ``|cos(incidence)| exp(-2 alpha r)``.
    With ``clip`` a hit outside the world's rectangle (``bounds``) is no return: in a tiled
    batch, a neighbouring world's tile or the floor between tiles. Rays without a return hold
    range 0, point 0, intensity 0. Output in firing order."""
    w, j = wp.tid()
    i = slot[j]
    state = wp.rand_init(_scan_seed(seed[w], count[w]), j)
    d = dist[w, i]
    ok = d >= range_min_m and d <= range_max_m
    if clip != 0 and ok:
        ok = _inside(bounds, w, pnt[w, i] + d * vec[w, i])
    if dropout > 0.0:
        if wp.randf(state) < dropout:
            ok = False
    r = wp.float32(0.0)
    inten = wp.float32(0.0)
    if ok:
        r = d
        if sigma_m > 0.0:
            r = wp.max(r + sigma_m * wp.randn(state), 0.0)
        cos_inc = wp.abs(wp.dot(normal[w, i], vec[w, i]))
        inten = wp.min(cos_inc, 1.0) * wp.exp(-2.0 * alpha_per_m * r)
    range_out[w, j] = r
    xyz_out[w, j] = dirs_sensor[j] * r
    intensity_out[w, j] = inten
    valid_out[w, j] = ok


@wp.kernel
def clip_depth(
    rays: wp.array[wp.vec3],
    cam_xpos: wp.array2d[wp.vec3],
    cam_xmat: wp.array2d[wp.mat33],
    camera: int,
    bounds: wp.array2d[float],
    depth: wp.array2d[float],
):
    """Planar depth 0 (nothing seen) where the pixel sees a point outside its world's
    rectangle. ``rays``: each pixel's unit ray in the camera frame (the render context's)."""
    w, k = wp.tid()
    z = depth[w, k]
    if z > 0.0:
        ray = rays[k]
        p = cam_xpos[w, camera] + cam_xmat[w, camera] @ (ray * (z / -ray[2]))
        if not _inside(bounds, w, p):
            depth[w, k] = 0.0


@wp.kernel
def advance(count: wp.array[int]):
    """One scan more in every world."""
    w = wp.tid()
    count[w] = count[w] + 1


@wp.kernel
def site_twist(
    cvel: wp.array2d[wp.spatial_vector],
    subtree_com: wp.array2d[wp.vec3],
    site_xpos: wp.array2d[wp.vec3],
    body_rootid: wp.array[int],
    body: int,
    site: int,
    twist_out: wp.array2d[float],
):
    """The site's angular and linear velocity in the world frame (``mj_objectVelocity``'s
    order, ``flg_local=0``): the body's com-based velocity moved to the site."""
    w = wp.tid()
    v = cvel[w, body]
    omega = wp.vec3(v[0], v[1], v[2])
    lin = wp.vec3(v[3], v[4], v[5])
    lin = lin + wp.cross(omega, site_xpos[w, site] - subtree_com[w, body_rootid[body]])
    for i in range(3):
        twist_out[w, i] = omega[i]
        twist_out[w, 3 + i] = lin[i]
