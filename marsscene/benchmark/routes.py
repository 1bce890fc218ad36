"""Benchmark routes: waypoints, a TUM file, or an automatic loop / out-and-back of a given
length authored through traversable terrain with :func:`marsscene.sim.route.author_route`.

An automatic route starts from a simple closed shape around ``center_xy_m``: a circle through
``K`` waypoints (``loop``) or a thin rectangle, out along ``heading_deg`` on one lane and back
on a lane ``width_m`` beside it (``out-and-back``, so the return revisits the outbound terrain
from the opposite direction). The planner detours around slopes and rocks, which lengthens the
route; the shape is rescaled (a few passes) until the authored route is within
``tolerance`` of ``length_m``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.benchmark.slam.spec import RouteSpec
from marsscene.errors import RuntimeSimError
from marsscene.sim.route import Obstacles, Route, author_route
from marsscene.terrain.heightfield import Heightfield

__all__ = ["MAX_LENGTH_ERROR", "asset_xy_m", "auto_route", "centred_on_asset", "shape_waypoints"]

#: An automatic route further than this from its asked length (relative) is refused, not driven.
MAX_LENGTH_ERROR = 0.5


def asset_xy_m(scene_dir: Path, name: str) -> tuple[float, float]:
    """Where the built scene placed asset ``name`` (``manifest.json`` ``summary.assets``)."""
    try:
        doc = json.loads((Path(scene_dir) / "manifest.json").read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise RuntimeSimError(f"{scene_dir}: no readable manifest.json ({err})") from None
    placed = (doc.get("summary") or {}).get("assets") or []
    for asset in placed:
        if asset.get("name") == name:
            x, y = asset["xy_m"]
            return float(x), float(y)
    names = ", ".join(repr(a.get("name")) for a in placed) or "none"
    raise RuntimeSimError(f"route.center_asset = {name!r}: the scene has no such asset "
                          f"(placed assets: {names}; enable one with [assets] habitat = true)")


def centred_on_asset(spec: RouteSpec, scene_dir: Path) -> RouteSpec:
    """``spec`` with ``center_xy_m`` where the scene placed ``center_asset`` (if it names one)."""
    if spec.center_asset is None:
        return spec
    return dataclasses.replace(spec, center_xy_m=asset_xy_m(scene_dir, spec.center_asset))


def shape_waypoints(spec: RouteSpec, scale: float) -> NDArray[np.float64]:
    """Waypoints (K, 2) in m of the closed shape of ``spec`` at ``scale`` (1 = nominal length,
    ignoring detours); the last equals the first."""
    assert spec.length_m is not None
    cx, cy = spec.center_xy_m
    h = math.radians(spec.heading_deg)
    length = spec.length_m * scale
    if spec.shape == "loop":
        k = max(8, math.ceil(length / 20.0))
        radius = length / (2.0 * math.pi)
        # start on the circle, first leg along heading (the centre on the left)
        ang = h - math.pi / 2 + np.linspace(0.0, 2.0 * math.pi, k + 1)
        pts = np.column_stack([cx + radius * np.cos(ang), cy + radius * np.sin(ang)])
    else:
        w = min(spec.width_m, length / 4.0)
        half = max((length - 2.0 * w) / 4.0, 0.5)
        d, n = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
        per_leg = max(1, math.ceil(2.0 * half / 20.0))
        s = np.linspace(-half, half, per_leg + 1)[:, None]
        out = np.array([cx, cy]) + s * d - w / 2 * n
        back = out[::-1] + w * n
        pts = np.vstack([out, back, out[:1]])
    pts[-1] = pts[0]
    return pts


def _fit_inside(pts: NDArray[np.float64], hf: Heightfield, margin_m: float) -> None:
    x0, y0, x1, y1 = hf.bounds_xy_m
    ok = ((pts[:, 0] >= x0 + margin_m) & (pts[:, 0] <= x1 - margin_m)
          & (pts[:, 1] >= y0 + margin_m) & (pts[:, 1] <= y1 - margin_m))
    if not ok.all():
        raise RuntimeSimError(
            f"an automatic route of this length does not fit inside the terrain x [{x0:.1f}, "
            f"{x1:.1f}], y [{y0:.1f}, {y1:.1f}] m around its centre; shorten route.length_m or "
            "move route.center_xy_m")


def auto_route(spec: RouteSpec, hf: Heightfield, obstacles: Obstacles | None, *,
               tolerance: float = 0.03, passes: int = 5, margin_m: float = 3.0) -> Route:
    """Author the automatic route of ``spec`` (``shape`` and ``length_m`` set) on ``hf``.

    Parameters
    ----------
    spec : RouteSpec
    hf : Heightfield
        The scene terrain.
    obstacles : Obstacles, optional
        Rocks (and assets) to keep clear of (:func:`marsscene.sim.world.load_world`).
    tolerance : float
        Accepted relative length error.
    passes : int
        Rescaling passes before the closest route so far is returned.

    Returns
    -------
    Route
        Closed (it ends where it starts), within ``tolerance`` of ``length_m`` when possible,
        else the closest one authored.

    Raises
    ------
    RuntimeSimError
        When the shape does not fit the terrain, or the closest route authored is more than
        :data:`MAX_LENGTH_ERROR` off ``length_m`` (a short route around a large asset).
    """
    if spec.shape is None or spec.length_m is None:
        raise RuntimeSimError("auto_route needs route.shape and route.length_m")
    scale, best, tried = 1.0, None, []
    for _ in range(passes):
        pts = shape_waypoints(spec, scale)
        _fit_inside(pts, hf, margin_m)
        route = author_route(pts, hf, max_slope_deg=spec.max_slope_deg, obstacles=obstacles)
        tried.append(f"{route.length_m:.0f}")
        err = route.length_m / spec.length_m - 1.0
        if best is None or abs(err) < abs(best[0]):
            best = (err, route)
        if abs(err) <= tolerance or err <= -1.0:  # within tolerance, or shrunk to nothing
            break
        scale /= 1.0 + err
    assert best is not None
    if abs(best[0]) > MAX_LENGTH_ERROR:
        raise RuntimeSimError(
            f"no {spec.shape} route of about {spec.length_m:g} m could be authored around "
            f"({spec.center_xy_m[0]:.1f}, {spec.center_xy_m[1]:.1f}) m: the planner's detours "
            f"around rocks, slopes and assets gave {', '.join(tried)} m; choose another "
            "route.length_m (--length-m) or route.center_xy_m")
    return best[1]
