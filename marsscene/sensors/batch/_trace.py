# mypy: ignore-errors
# (Warp's kernel language: its annotations and indexing are not Python's typing)
"""Warp kernels of the batch RGB-D camera: one thread a pixel traces its camera's world.

Terrain: the world's posts as the CPU camera's ground mesh triangulates them (two triangles a
cell, the diagonal from post (r, c) to (r + 1, c + 1)), walked along the ray on two levels (a
2-D DDA in post units): blocks of 8 x 8 cells, skipped whole where the ray passes above the
block's highest post, and within a block cell by cell, a cell skipped where the ray passes
above its highest post (a two-level maximum map, exact: no hit is missed). Smooth normals
(central differences at the posts, interpolated over the triangle). Rocks: one static
``wp.Mesh`` of every rock of the batch (``wp.mesh_query_ray``). The hit's albedo, a shadow ray
to the sun through both, the sky's and the sun's terms, linear fog, then exposure and sRGB
(:mod:`.appearance` states the units). Ray parameters are planar depth: a pixel's camera-frame
ray has z = -1.
"""

from __future__ import annotations

import warp as wp

wp.set_module_options({"enable_backward": False})

@wp.func
def _tri(o: wp.vec3, d: wp.vec3, a: wp.vec3, b: wp.vec3, c: wp.vec3) -> wp.vec3:
    """Moller-Trumbore: (t, u, v) of the hit (p = a + u (b - a) + v (c - a)); t < 0: none."""
    e1 = b - a
    e2 = c - a
    q = wp.cross(d, e2)
    det = wp.dot(e1, q)
    if wp.abs(det) < 1.0e-12:
        return wp.vec3(-1.0, 0.0, 0.0)
    inv = 1.0 / det
    s = o - a
    u = wp.dot(s, q) * inv
    r = wp.cross(s, e1)
    v = wp.dot(d, r) * inv
    if u < 0.0 or v < 0.0 or u + v > 1.0:
        return wp.vec3(-1.0, 0.0, 0.0)
    return wp.vec3(wp.dot(e2, r) * inv, u, v)


@wp.func
def _post(posts: wp.array3d[float], w: int, r: int, c: int) -> wp.vec3:
    return wp.vec3(float(c), float(r), posts[w, r, c])


@wp.func
def _post_normal(posts: wp.array3d[float], w: int, r: int, c: int, cell: float) -> wp.vec3:
    rows = posts.shape[1]
    cols = posts.shape[2]
    c0 = wp.max(c - 1, 0)
    c1 = wp.min(c + 1, cols - 1)
    r0 = wp.max(r - 1, 0)
    r1 = wp.min(r + 1, rows - 1)
    gx = (posts[w, r, c1] - posts[w, r, c0]) / (float(c1 - c0) * cell)
    gy = (posts[w, r1, c] - posts[w, r0, c]) / (float(r1 - r0) * cell)
    return wp.normalize(wp.vec3(-gx, -gy, 1.0))


@wp.func
def _slab(o: float, d: float, hi: float, t: wp.vec2) -> wp.vec2:
    """``t`` (t0, t1) clipped to the slab 0 <= o + t d <= hi (t0 > t1: empty)."""
    if wp.abs(d) < 1.0e-12:
        if o < 0.0 or o > hi:
            return wp.vec2(1.0, -1.0)
        return t
    ta = (0.0 - o) / d
    tb = (hi - o) / d
    return wp.vec2(wp.max(t[0], wp.min(ta, tb)), wp.min(t[1], wp.max(ta, tb)))


#: Cells a side of a block of :func:`march`'s coarse level (its highest post skips the block).
BLOCK = wp.constant(8)


@wp.func
def _crossings(o: wp.vec3, d: wp.vec3, c: int, r: int, sc: int, sr: int,
               size: float) -> wp.vec4:
    """The grid walk's start in cell (r, c) of ``size``-unit cells, stepping (sr, sc): the
    ray parameter at its first column and row crossings and between crossings, (nx, ny, dx,
    dy); 1e30 along an axis the ray does not cross."""
    big = wp.float32(1.0e30)
    g = wp.vec4(big, big, big, big)
    if wp.abs(d[0]) > 1.0e-12:
        g[0] = (float(c + wp.max(sc, 0)) * size - o[0]) / d[0]
        g[2] = size / wp.abs(d[0])
    if wp.abs(d[1]) > 1.0e-12:
        g[1] = (float(r + wp.max(sr, 0)) * size - o[1]) / d[1]
        g[3] = size / wp.abs(d[1])
    return g


@wp.func
def _cells(posts: wp.array3d[float], w: int, o: wp.vec3, d: wp.vec3, t: float, t_end: float,
           t_min: float, t_max: float) -> wp.vec4:
    """The first cell hit of the ray walked from ``t`` to ``t_end`` (at most one block's
    cells), each cell's two triangles tried where the ray passes below its highest post; as
    :func:`march` returns it."""
    rows = posts.shape[1]
    cols = posts.shape[2]
    p = o + t * d
    c = wp.clamp(int(wp.floor(p[0])), 0, cols - 2)
    r = wp.clamp(int(wp.floor(p[1])), 0, rows - 2)
    sc = wp.where(d[0] < 0.0, -1, 1)
    sr = wp.where(d[1] < 0.0, -1, 1)
    g = _crossings(o, d, c, r, sc, sr, 1.0)
    nx = g[0]
    ny = g[1]
    dx = g[2]
    dy = g[3]
    for _ in range(2 * BLOCK + 2):  # a block's cells along a ray, and the one it starts in
        t_out = wp.min(wp.min(nx, ny), t_end)
        z_lo = wp.min(o[2] + t * d[2], o[2] + t_out * d[2])
        a = _post(posts, w, r, c)
        b = _post(posts, w, r, c + 1)
        e = _post(posts, w, r + 1, c + 1)
        f = _post(posts, w, r + 1, c)
        if z_lo <= wp.max(wp.max(a[2], b[2]), wp.max(e[2], f[2])):
            h0 = _tri(o, d, a, b, e)
            h1 = _tri(o, d, a, e, f)
            best = wp.vec4(-1.0, 0.0, 0.0, 0.0)
            if h0[0] >= t_min and h0[0] <= t_max:
                best = wp.vec4(h0[0], float(r) + h0[2], float(c) + h0[1] + h0[2], 0.0)
            if h1[0] >= t_min and h1[0] <= t_max and (best[0] < 0.0 or h1[0] < best[0]):
                best = wp.vec4(h1[0], float(r) + h1[1] + h1[2], float(c) + h1[1], 1.0)
            if best[0] >= 0.0:
                return best
        if t_out >= t_end:
            break
        if nx < ny:
            c += sc
            t = nx
            nx += dx
        else:
            r += sr
            t = ny
            ny += dy
        if c < 0 or c > cols - 2 or r < 0 or r > rows - 2:
            break
    return wp.vec4(-1.0, 0.0, 0.0, 0.0)


@wp.func
def march(posts: wp.array3d[float], tops: wp.array3d[float], w: int, o: wp.vec3, d: wp.vec3,
          t_min: float, t_max: float, z_top: float) -> wp.vec4:
    """First terrain hit of the ray ``o + t d`` (post units in x, y; m in z) within
    [t_min, t_max]: (t, r + v, c + u, triangle) with t < 0 where none; triangle 0 is
    (r, c), (r, c+1), (r+1, c+1), 1 is (r, c), (r+1, c+1), (r+1, c). The ray walks
    :data:`BLOCK`-cell blocks (``tops``: each block's highest post, :func:`block_tops`) and
    walks a block's cells only where it passes below that block's top."""
    rows = posts.shape[1]
    cols = posts.shape[2]
    span = _slab(o[0], d[0], float(cols - 1), wp.vec2(t_min, t_max))
    span = _slab(o[1], d[1], float(rows - 1), span)
    if d[2] > 0.0:
        span = wp.vec2(span[0], wp.min(span[1], (z_top - o[2]) / d[2]))
    elif d[2] < 0.0:
        span = wp.vec2(wp.max(span[0], (z_top - o[2]) / d[2]), span[1])
    elif o[2] > z_top:
        return wp.vec4(-1.0, 0.0, 0.0, 0.0)
    t = span[0]
    t_end = span[1]
    if t > t_end:
        return wp.vec4(-1.0, 0.0, 0.0, 0.0)
    size = float(BLOCK)
    brows = tops.shape[1]
    bcols = tops.shape[2]
    p = o + t * d
    c = wp.clamp(int(wp.floor(p[0] / size)), 0, bcols - 1)
    r = wp.clamp(int(wp.floor(p[1] / size)), 0, brows - 1)
    sc = wp.where(d[0] < 0.0, -1, 1)
    sr = wp.where(d[1] < 0.0, -1, 1)
    g = _crossings(o, d, c, r, sc, sr, size)
    nx = g[0]
    ny = g[1]
    dx = g[2]
    dy = g[3]
    for _ in range(brows + bcols):
        t_out = wp.min(wp.min(nx, ny), t_end)
        z_lo = wp.min(o[2] + t * d[2], o[2] + t_out * d[2])
        if z_lo <= tops[w, r, c]:
            hit = _cells(posts, w, o, d, t, t_out, t_min, t_max)
            if hit[0] >= 0.0:
                return hit
        if t_out >= t_end:
            break
        if nx < ny:
            c += sc
            t = nx
            nx += dx
        else:
            r += sr
            t = ny
            ny += dy
        if c < 0 or c > bcols - 1 or r < 0 or r > brows - 1:
            break
    return wp.vec4(-1.0, 0.0, 0.0, 0.0)


@wp.func
def _terrain_normal(posts: wp.array3d[float], w: int, hit: wp.vec4, cell: float) -> wp.vec3:
    """Smooth normal at a :func:`march` hit (its triangle's post normals, barycentric)."""
    rf = hit[1]
    cf = hit[2]
    r = wp.clamp(int(wp.floor(rf)), 0, posts.shape[1] - 2)
    c = wp.clamp(int(wp.floor(cf)), 0, posts.shape[2] - 2)
    u = wp.clamp(cf - float(c), 0.0, 1.0)
    v = wp.clamp(rf - float(r), 0.0, 1.0)
    n00 = _post_normal(posts, w, r, c, cell)
    n11 = _post_normal(posts, w, r + 1, c + 1, cell)
    if hit[3] < 0.5:  # (r, c), (r, c+1), (r+1, c+1): weights 1 - u, u - v, v
        n = (1.0 - u) * n00 + (u - v) * _post_normal(posts, w, r, c + 1, cell) + v * n11
    else:  # (r, c), (r+1, c+1), (r+1, c): weights 1 - v, u, v - u
        n = (1.0 - v) * n00 + u * n11 + (v - u) * _post_normal(posts, w, r + 1, c, cell)
    return wp.normalize(n)


@wp.func
def _albedo(tile: wp.array[wp.vec3], levels: int, n: int, texel_m: float, footprint_m: float,
            gain: wp.array3d[float], w: int, x: float, y: float, corner: wp.vec2,
            step_m: float) -> wp.vec3:
    """Ground albedo at world point (x, y): the world-anchored detail tile's texel under it
    at the mip level of the pixel's footprint (``tile`` holds the levels n, n/2, ... one
    after the other), times the bilinear gain (grid from ``corner`` every ``step_m``)."""
    lv = wp.int32(0)
    if footprint_m > texel_m:
        lv = wp.min(int(wp.log2(footprint_m / texel_m)), levels - 1)
    size = n >> lv
    base = (n * n - size * size) * 4 // 3  # the levels before lv: n^2 (1 + 1/4 + ...)
    texel = texel_m * float(n // size)
    ti = ((int(wp.floor(y / texel + 1.0e-6)) % size) + size) % size
    tj = ((int(wp.floor(x / texel + 1.0e-6)) % size) + size) % size
    rows = gain.shape[1]
    cols = gain.shape[2]
    fx = wp.clamp((x - corner[0]) / step_m, 0.0, float(cols - 1) - 1.0e-3)
    fy = wp.clamp((y - corner[1]) / step_m, 0.0, float(rows - 1) - 1.0e-3)
    c = int(wp.floor(fx))
    r = int(wp.floor(fy))
    u = fx - float(c)
    v = fy - float(r)
    g = ((1.0 - v) * ((1.0 - u) * gain[w, r, c] + u * gain[w, r, c + 1])
         + v * ((1.0 - u) * gain[w, r + 1, c] + u * gain[w, r + 1, c + 1]))
    return g * tile[base + ti * size + tj]


@wp.func
def _grid(p: wp.vec3, origin: wp.vec2, cell_m: float) -> wp.vec3:
    """A tile-frame point (or, with origin 0, a direction) in post units."""
    return wp.vec3((p[0] - origin[0]) / cell_m, (p[1] - origin[1]) / cell_m, p[2])


@wp.func
def _rock(mesh: wp.uint64, o: wp.vec3, d: wp.vec3, t_max: float) -> wp.vec4:
    """First rock hit along ``o + t d`` (t planar, ``d`` of any length) before ``t_max``:
    (t, u, v, face), t < 0 where none."""
    length = wp.length(d)
    q = wp.mesh_query_ray(mesh, o, d / length, t_max * length)
    if q.result:
        return wp.vec4(q.t / length, q.u, q.v, float(q.face))
    return wp.vec4(-1.0, 0.0, 0.0, 0.0)


@wp.func
def _below(z: float, dz: float, z_top: float, far_m: float) -> float:
    """The ray parameter up to which a ray from height ``z`` rising at ``dz`` can still meet
    anything under ``z_top`` (``far_m`` at most)."""
    if dz > 0.0:
        return wp.min(far_m, wp.max((z_top - z) / dz, 0.0))
    return far_m


@wp.kernel
def trace(
    cam_xpos: wp.array2d[wp.vec3], cam_xmat: wp.array2d[wp.mat33], camera: int,
    rays: wp.array[wp.vec3], world: wp.array[int],
    posts: wp.array3d[float], tops: wp.array3d[float], grid_origin: wp.array[wp.vec2],
    z_top: wp.array[float],
    cell_m: float, offset: wp.array[wp.vec2],
    mesh: wp.uint64, faces: wp.array[int], vnormal: wp.array[wp.vec3],
    face_albedo: wp.array[wp.vec3],
    tile: wp.array[wp.vec3], levels: int, tile_px: int, texel_m: float, pixel_rad: float,
    gain: wp.array3d[float],
    gain_corner: wp.array[wp.vec2], step_m: float,
    sun_dir: wp.array[wp.vec3], sun_rgb: wp.array[wp.vec3], sky_rgb: wp.array[wp.vec3],
    visibility_m: wp.array[float], near_m: float, far_m: float, shadow_lift_m: float,
    shaded: int,
    linear: wp.array2d[wp.vec3], depth: wp.array2d[float], seg: wp.array2d[wp.uint8],
):
    """Linear colour (render units, clipped to 1), planar depth (0: sky) and class (0 sky,
    1 terrain, 2 rock) of pixel ``k`` of camera ``i`` (on world ``world[i]``); with
    ``shaded`` 0 only the depth and class (``linear`` is left as it is)."""
    i, k = wp.tid()
    w = world[i]
    rot = cam_xmat[i, camera]
    o = cam_xpos[i, camera]
    d = rot @ rays[k]
    og = _grid(o, grid_origin[w], cell_m)
    dg = _grid(d, wp.vec2(0.0, 0.0), cell_m)
    hit = march(posts, tops, w, og, dg, near_m, far_m, z_top[w])
    t_ground = _below(o[2], d[2], z_top[w], far_m)
    if hit[0] >= 0.0:
        t_ground = hit[0]
    rock = _rock(mesh, o, d, t_ground)
    kind = wp.uint8(0)
    t = wp.float32(0.0)
    if rock[0] >= near_m:
        pg = og + rock[0] * dg
        if (pg[0] >= 0.0 and pg[1] >= 0.0 and pg[0] <= float(posts.shape[2] - 1)
                and pg[1] <= float(posts.shape[1] - 1)):
            t = rock[0]
            kind = wp.uint8(2)
    if kind == wp.uint8(0) and hit[0] >= 0.0:
        t = hit[0]
        kind = wp.uint8(1)
    depth[i, k] = t
    seg[i, k] = kind
    if shaded == 0:
        return
    n = wp.vec3(0.0, 0.0, 1.0)
    a = wp.vec3(0.0)
    if kind == wp.uint8(2):
        f = int(rock[3])
        u = rock[1]
        v = rock[2]
        n = wp.normalize(u * vnormal[faces[3 * f]] + v * vnormal[faces[3 * f + 1]]
                         + (1.0 - u - v) * vnormal[faces[3 * f + 2]])
        a = face_albedo[f]
    elif kind == wp.uint8(1):
        n = _terrain_normal(posts, w, hit, cell_m)
        p = o + t * d
        off = offset[w]
        dist = t * wp.length(d)
        foot = dist * pixel_rad / wp.max(wp.abs(wp.dot(n, d)) / wp.length(d), 0.2)
        a = _albedo(tile, levels, tile_px, texel_m, foot, gain, w, p[0] - off[0],
                    p[1] - off[1], gain_corner[w], step_m)
    sky = sky_rgb[i]
    colour = wp.vec3(0.0)
    if kind == wp.uint8(0):
        colour = sky * (1.0 - 0.2 * wp.normalize(d)[2])  # MuJoCo's gradient skybox
    else:
        s = sun_dir[i]
        lit = wp.dot(n, s)
        sun = wp.vec3(0.0)
        if lit > 0.0 and wp.length(sun_rgb[i]) > 0.0:
            q = o + t * d + shadow_lift_m * n
            shade = march(posts, tops, w, _grid(q, grid_origin[w], cell_m),
                          _grid(s, wp.vec2(0.0, 0.0), cell_m), 0.0, far_m, z_top[w])
            blocked = shade[0] >= 0.0
            if not blocked:
                blocked = _rock(mesh, q, s, _below(q[2], s[2], z_top[w], far_m))[0] >= 0.0
            if not blocked:
                sun = lit * sun_rgb[i]
        colour = wp.cw_mul(a, sky + sun)
        fog = wp.clamp(1.0 - t / visibility_m[i], 0.0, 1.0)
        fog_rgb = wp.vec3(wp.min(1.2 * sky[0], 1.0), wp.min(1.2 * sky[1], 1.0),
                          wp.min(1.2 * sky[2], 1.0))
        colour = fog * colour + (1.0 - fog) * fog_rgb
    linear[i, k] = wp.vec3(wp.min(colour[0], 1.0), wp.min(colour[1], 1.0),
                           wp.min(colour[2], 1.0))
