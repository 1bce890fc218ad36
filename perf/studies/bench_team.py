"""The real-time factor of a team drive with 1, 2, 4, 8 rovers in one world (issue 69).

Run: ``python perf/run.py team --size quick|full [--seconds S] [--sensors state|lead]``.

Each team drives side by side (rows 6 m apart, 30 m routes) on a 60 m procedural scene for
``SECONDS`` sim seconds; ``state`` drives every rover with no camera or LiDAR (ground truth,
wheel odometry, IMU), ``lead`` gives the first rover a 320 x 240 RGB-D camera at 5 Hz and a
VLP-16 at 10 Hz. Figures per team size: wall seconds of the drive and the real-time factor of
the team (sim seconds of each rover per wall second).
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

from perf.suite import Param

PARAMS = (Param("seconds", float, "sim seconds driven", quick=5.0, full=20.0),
          Param("sensors", str, "state (none) or lead (camera + LiDAR on the first rover)",
                quick="state", full="state"),
          Param("sizes", str, "team sizes, comma separated", quick="1,2,4", full="1,2,4,8"))


def main(seconds: float, sensors: str, sizes: str) -> dict[str, Any]:
    import marsscene as ms

    lead = ms.RunConfig(camera=ms.CameraConfig(width_px=320, height_px=240, rate_hz=5.0),
                        lidar=ms.LidarConfig(model="vlp16"))
    out: dict[str, Any] = {"seconds": seconds, "sensors": sensors}
    with tempfile.TemporaryDirectory() as tmp:
        scene = ms.SceneConfig.from_dict({"terrain": {"source": "procedural",
                                                      "size_m": [60, 60]}})
        ms.write_scene(ms.build_scene(scene, seed=1), Path(tmp) / "scene", formats=("mjcf",))
        for n in (int(s) for s in sizes.split(",")):
            robots = [ms.Robot(name=f"rover{i + 1}",
                               config=lead if (i == 0 and sensors == "lead") else None,
                               waypoints=[[-15.0, y], [15.0, y]])
                      for i, y in enumerate(-21.0 + 6.0 * k for k in range(n))]
            team = ms.drive_team(Path(tmp) / "scene", robots, seconds=seconds,
                                 out_dir=Path(tmp) / f"team{n}")
            out[f"wall_s_{n}"] = team.wall_s
            out[f"rtf_{n}"] = team.realtime_factor
            print(f"{n} rover(s): {team.wall_s:6.2f} s wall, {team.realtime_factor:5.2f}x "
                  f"real time", flush=True)
    return out
