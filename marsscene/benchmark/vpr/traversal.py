"""A VPR traversal's frames and poses: the lighting it is driven under, its offset route, and
its JPEGs named by pose with their ``poses.csv`` rows, written from its run folder (a CPU drive's
or a batch drive's: :mod:`.dataset`, :mod:`.device`)."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.benchmark.vpr.spec import TraversalSpec, VprSpec

__all__ = ["COLUMNS", "image_name", "irradiance_scale", "offset_route", "write_rows",
           "write_traversal"]


def image_name(east_m: float, north_m: float, frame: int, yaw_deg: float, pitch_deg: float,
               roll_deg: float, z_m: float, t_s: float, split: str) -> str:
    """``@east@north@zone@letter@lat@lon@id@tile@heading@pitch@roll@height@time@note@.jpg``."""
    return (f"@{east_m:.3f}@{north_m:.3f}@@@@@D{frame:07d}@@{yaw_deg:.2f}@{pitch_deg:.2f}"
            f"@{roll_deg:.2f}@{z_m:.3f}@{t_s:.3f}@{split}@.jpg")


def offset_route(xy_m: NDArray[np.float64], offset_m: float) -> NDArray[np.float64]:
    """The polyline shifted sideways by ``offset_m`` (positive: to the left of travel); a
    closed one (its last point its first) stays closed, shifted at the seam along the mean of
    its first and last legs' directions."""
    xy = np.asarray(xy_m, dtype=np.float64)
    d = np.gradient(xy, axis=0)
    if len(xy) > 2 and np.array_equal(xy[0], xy[-1]):
        d[0] = d[-1] = 0.5 * (xy[1] - xy[-2])
    n = np.column_stack([-d[:, 1], d[:, 0]]) / np.maximum(np.hypot(d[:, 0], d[:, 1]),
                                                          1e-12)[:, None]
    return xy_m + offset_m * n


def irradiance_scale(lighting: TraversalSpec, scene_dir: Path) -> float:
    """Global horizontal irradiance of the sun at ``irradiance_of_sun_elevation_deg`` over
    that of the traversal's own sun (1 without it), on the scene's site and ``tau``."""
    if lighting.irradiance_of_sun_elevation_deg is None:
        return 1.0
    from marsscene.sensors.camera_scene import scene_lighting

    def ghi(el: float) -> float:
        return float(scene_lighting(scene_dir, tau=lighting.tau, sun_elevation_deg=el,
                                    sun_azimuth_deg=lighting.sun_azimuth_deg
                                    ).global_horizontal_w_m2)

    return ghi(lighting.irradiance_of_sun_elevation_deg) / ghi(lighting.sun_elevation_deg)


def _write_split(split: str, run_dir: Path, dest: Path, quality: int,
                 lighting: TraversalSpec) -> list[list[Any]]:
    """JPEGs named by pose into ``dest``; the run's PNGs are removed. Rows of poses.csv."""
    from PIL import Image
    from scipy.spatial.transform import Rotation

    from marsscene.runs.export.datasets import camera_trajectory
    from marsscene.runs.export.frames import camera_frame, frame_in_base, static_transforms
    from marsscene.runs.runlog import RunLog

    run = RunLog(run_dir)
    cam = run.camera_streams()[0]
    xyz, q = camera_trajectory(run, frame_in_base(static_transforms(run.rover, {}),
                                                  camera_frame(cam.name)))
    idx = np.clip(np.searchsorted(run.gt.timestamps_s, cam.stamps_s - 1e-7), 0, len(xyz) - 1)
    # heading / pitch / roll of the camera's viewing axis (optical +z) in the map frame
    fwd = Rotation.from_quat(q[idx]).apply([0.0, 0.0, 1.0])
    yaw = np.degrees(np.arctan2(fwd[:, 1], fwd[:, 0]))
    pitch = np.degrees(np.arcsin(np.clip(fwd[:, 2], -1.0, 1.0)))
    roll = Rotation.from_quat(run.gt.quat_xyzw[idx]).as_euler("xyz", degrees=True)[:, 0]
    dest.mkdir()
    rows = []
    for i, (t, png) in enumerate(zip(cam.stamps_s, cam.rgb_files, strict=True)):
        p, r = xyz[idx[i]], q[idx[i]]
        name = image_name(p[0], p[1], i, yaw[i], pitch[i], roll[i], p[2], t, split)
        with Image.open(png) as im:
            im.convert("RGB").save(dest / name, format="JPEG", quality=quality)
        png.unlink()
        rows.append([split, f"{split}/{name}", f"{t:.6f}", *(f"{v:.6f}" for v in p),
                     *(f"{v:.9f}" for v in r), f"{yaw[i]:.3f}", lighting.tau,
                     lighting.sun_elevation_deg])
    return rows


COLUMNS = ["split", "file", "t_s", "x_m", "y_m", "z_m", "qx", "qy", "qz", "qw", "yaw_deg", "tau",
            "sun_elevation_deg"]


def write_rows(path: Path, rows: list[list[Any]], *, landmark: bool = False) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS + (["landmark_px"] if landmark else []))
    w.writerows(rows)
    write_atomic(path, buf.getvalue())


def write_traversal(spec: VprSpec, split: str, run_dir: Path, dest: Path, key: str) -> None:
    """A driven traversal's JPEGs into ``dest``, its ``poses.csv`` and its key."""
    rows = _write_split(split, run_dir, dest, spec.jpeg_quality, getattr(spec, split))
    write_rows(run_dir / "poses.csv", rows)
    (run_dir / "vpr_key.json").write_text(key, encoding="utf-8")
