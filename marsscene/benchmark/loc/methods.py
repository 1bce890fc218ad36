"""The methods of the localization benchmark, each reading only a query folder
(:mod:`.query`) and writing an answer: one TUM line, the pose of the local frame in the scene
(``t x y z qx qy qz qw``; z is not scored; ``#`` lines are comments; no line = lost).

* ``dem-correlation``: :func:`marsscene.orbital.match_dem` of the local elevation map
  (:func:`marsscene.orbital.local_elevation_map` of ``local/points.npy``, the map tile's posts)
  over the prior's search square (``position_error_max_m`` + 5 m) and heading window
  (``heading_error_max_deg`` + 2 deg); option ``scans = N`` keeps the query's last N scans
  only (the local map of fewer scans on the same query);
* ``ortho-match``: :func:`.ortho.match_ortho` of the camera's ground image (needs OpenCV);
* ``prior``: the prior itself (the floor any method must beat);
* ``command``: ``command.format(query_dir=..., answer=...)`` run in a shell;
* ``python``: ``module:function`` called as ``function(query_dir, answer_path)``.
"""

from __future__ import annotations

import importlib
import json
import math
import shlex
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from marsscene.benchmark.loc.spec import LocMethod
from marsscene.errors import ConfigError, missing_dependency

__all__ = ["last_scans", "read_answer", "run_method", "write_answer"]


def write_answer(path: Path, x_m: float, y_m: float, yaw_rad: float, *, stamp_s: float = 0.0,
                 note: str = "") -> None:
    """Write a one-pose answer file."""
    q = Rotation.from_euler("Z", yaw_rad).as_quat()
    path.write_text(f"# {note or 'pose of the local frame in the scene'}\n{stamp_s:.6f} "
                    f"{x_m:.6f} {y_m:.6f} 0.000000 {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} "
                    f"{q[3]:.9f}\n", encoding="utf-8")


def read_answer(path: Path) -> tuple[float, float, float] | None:
    """(x_m, y_m, yaw_rad) of an answer file's last pose; None when it has none."""
    if not path.is_file():
        return None
    lines = [ln.split() for ln in path.read_text(encoding="utf-8").splitlines()
             if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        return None
    v = [float(x) for x in lines[-1]]
    if len(v) != 8 or not all(math.isfinite(x) for x in v):
        raise ConfigError(f"{path}: an answer line is 't x y z qx qy qz qw'; got {lines[-1]}")
    yaw = float(Rotation.from_quat(v[4:8]).as_euler("ZYX")[0])
    return v[1], v[2], yaw


def _query(qdir: Path) -> dict[str, Any]:
    return dict(json.loads((qdir / "query.json").read_text(encoding="utf-8")))


def _prior(doc: dict[str, Any]) -> tuple[float, float, float]:
    p = doc["prior"]
    return float(p["x_m"]), float(p["y_m"]), float(p["yaw_rad"])


def last_scans(points: np.ndarray, doc: dict[str, Any], scans: Any) -> np.ndarray:
    """The points of a query's last ``scans`` LiDAR scans (``query.json``'s per-scan counts)."""
    counts = (doc.get("lidar") or {}).get("points_per_scan")
    if counts is None:
        raise ConfigError("option scans needs a query folder with lidar.points_per_scan "
                          "(made by this version)")
    if isinstance(scans, bool) or not isinstance(scans, int) or not 1 <= scans <= len(counts):
        raise ConfigError(f"option scans = {scans!r}; need 1..{len(counts)} (the query's scans)")
    return points[len(points) - int(sum(counts[-scans:])):]


def _dem(qdir: Path, answer: Path, options: dict[str, Any]) -> str:
    from marsscene.orbital import local_elevation_map, match_dem, read_orbital_map

    doc = _query(qdir)
    tile = read_orbital_map(qdir)
    pts = np.load(qdir / "local" / "points.npy").astype(np.float64)
    options = dict(options)
    if "scans" in options:
        pts = last_scans(pts, doc, options.pop("scans"))
    local = local_elevation_map(pts, cell_m=tile.cell_m, radius_m=float(doc["local_radius_m"]))
    s = doc["search"]
    m = match_dem(local, tile, _prior(doc),
                  search_radius_m=float(s["position_error_max_m"]) + 5.0,
                  yaw_window_deg=float(s["heading_error_max_deg"]) + 2.0, **options)
    write_answer(answer, m.x_m, m.y_m, m.yaw_rad, stamp_s=float(doc["stamp_s"]),
                 note=f"dem-correlation: peak {m.peak_ncc:.3f}, confidence {m.confidence:.3f}")
    return f"peak {m.peak_ncc:.3f} conf {m.confidence:.3f}"


def _ortho(qdir: Path, answer: Path, options: dict[str, Any]) -> str:
    try:
        import cv2  # noqa: F401
    except ImportError:
        raise missing_dependency("opencv-python-headless", "bench") from None
    from marsscene.benchmark.loc.ortho import ground_points, match_ortho
    from marsscene.orbital import read_orbital_map

    doc = _query(qdir)
    tile = read_orbital_map(qdir)
    if tile.image is None or tile.image_pixel_m is None or tile.image_origin_xy_m is None:
        raise ConfigError(f"{qdir}: the map tile has no orthoimage")
    s = doc["search"]
    x, y, yaw, peak = match_ortho(
        ground_points(qdir / "local" / "camera"), tile.image, tile.image_pixel_m,
        tile.image_origin_xy_m, _prior(doc),
        search_radius_m=float(s["position_error_max_m"]) + 5.0,
        yaw_window_deg=float(s["heading_error_max_deg"]) + 2.0, **options)
    write_answer(answer, x, y, yaw, stamp_s=float(doc["stamp_s"]),
                 note=f"ortho-match: peak {peak:.3f}")
    return f"peak {peak:.3f}"


def _prior_method(qdir: Path, answer: Path, options: dict[str, Any]) -> str:
    x, y, yaw = _prior(_query(qdir))
    write_answer(answer, x, y, yaw, note="the prior")
    return ""


def run_method(method: LocMethod, qdir: Path, answer: Path) -> str:
    """Run ``method`` on the query folder ``qdir``, its answer into ``answer``; returns a
    note. Raises on failure (the caller scores it as failed)."""
    if method.kind == "dem-correlation":
        return _dem(qdir, answer, method.options)
    if method.kind == "ortho-match":
        return _ortho(qdir, answer, method.options)
    if method.kind == "prior":
        return _prior_method(qdir, answer, method.options)
    if method.kind == "python":
        assert method.function is not None
        mod, _, name = method.function.partition(":")
        getattr(importlib.import_module(mod), name)(qdir, answer)
        return ""
    assert method.command is not None
    cmd = method.command.format(query_dir=shlex.quote(str(qdir)),
                                answer=shlex.quote(str(answer)))
    done = subprocess.run(cmd, shell=True, capture_output=True, text=True,
                          timeout=method.timeout_s, check=False)
    if done.returncode != 0:
        tail = " ".join((done.stderr or done.stdout).split()[-30:])
        raise ConfigError(f"command exited with {done.returncode}: {tail}")
    return ""
