"""A scout's survey flight registered by COLMAP: aerial images an off-the-shelf structure-from-
motion tool reconstructs (issue 69).

Run: ``python perf/run.py scout_survey --size quick|full [--leg-m M] [--camera-px N]``; needs
``pycolmap`` (``pip install pycolmap``, not a marsscene dependency).

The Ingenuity-class scout flies a lawnmower survey at 10 m (three legs of ``LEG_M``, 10 m apart)
over a 100 m procedural scene with its downward navigation camera at 1 Hz; COLMAP (pycolmap:
SIFT features, sequential matching, incremental mapping, one pinhole camera with the scout's
intrinsics) reconstructs the image set. Figures: the path flown, images taken and registered,
the reconstruction's points and mean reprojection error, and the camera centres' RMS error
against the flight's ground truth after a similarity alignment (``marsscene.runs.ate``, sim3).
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from perf.suite import Param

PARAMS = (Param("leg_m", float, "length of each survey leg (m)", quick=30.0, full=90.0),
          Param("camera_px", int, "navigation camera width (px; height 3/4 of it)", quick=160,
                full=160))


def _reconstruct(run: Path, work: Path, fov_diag_deg: float) -> Any:
    import pycolmap
    from PIL import Image

    w, h = Image.open(run / "images" / "000000.png").size
    f = math.hypot(w, h) / 2 / math.tan(math.radians(fov_diag_deg) / 2)
    reader = pycolmap.ImageReaderOptions()
    reader.camera_model, reader.camera_params = "PINHOLE", f"{f},{f},{w / 2},{h / 2}"
    db = work / "database.db"
    pycolmap.extract_features(db, run / "images", camera_mode=pycolmap.CameraMode.SINGLE,
                              reader_options=reader)
    pycolmap.match_sequential(db)
    maps = pycolmap.incremental_mapping(db, run / "images", work)
    return max(maps.values(), key=lambda r: r.num_reg_images()) if maps else None


def main(leg_m: float, camera_px: int) -> dict[str, Any]:
    import marsscene as ms
    from marsscene.runs import ate
    from marsscene.runs.tum import Trajectory, read_tum
    from marsscene.scout import FlightPlan, ScoutConfig, fly

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        scene = ms.SceneConfig.from_dict({"terrain": {"source": "procedural",
                                                      "size_m": [100, 100]}})
        ms.write_scene(ms.build_scene(scene, seed=1), root / "scene", formats=("mjcf",))
        h = leg_m / 2
        wps = [[-h, -10], [h, -10], [h, 0], [-h, 0], [-h, 10], [h, 10]]
        plan = FlightPlan(camera_px=(camera_px, camera_px * 3 // 4), camera_hz=1.0)
        flight = fly(root / "scene", wps, plan=plan, out_dir=root / "run")
        (root / "sfm").mkdir()
        t0 = time.perf_counter()
        rec = _reconstruct(root / "run", root / "sfm", ScoutConfig.load().camera_fov_diag_deg)
        sfm_s = time.perf_counter() - t0
        cams = read_tum(root / "run" / "images.tum")
        names = sorted(p.name for p in (root / "run" / "images").glob("*.png"))
        out: dict[str, Any] = {
            "path_m": flight.gt.path_length_m(), "images": len(names), "flight_wall_s":
            flight.wall_s, "sfm_wall_s": sfm_s, "registered": 0}
        if rec is not None:
            at = {n: cams.timestamps_s[i] for i, n in enumerate(names)}
            rows = sorted((at[im.name], im.projection_center()) for im in rec.images.values())
            t = np.array([r[0] for r in rows])
            centres = np.array([r[1] for r in rows])
            est = Trajectory(t, centres, np.tile([0.0, 0, 0, 1], (len(t), 1)))  # centres only
            err = ate(est, cams, align="sim3").stats
            out.update(registered=len(t), points=rec.num_points3D(),
                       reprojection_px=rec.compute_mean_reprojection_error(),
                       centre_rms_m=err.rmse, centre_max_m=err.max)
    for key, value in out.items():
        print(f"{key:16s} {value:.4g}" if isinstance(value, float) else f"{key:16s} {value}")
    return out
