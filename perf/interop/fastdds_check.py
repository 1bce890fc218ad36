"""Cross-vendor check: a ROS 2 peer on eProsima Fast DDS (ROS 2's default middleware) and the live
rover on Cyclone DDS (``marsscene serve``).

One command: ``python perf/run.py fastdds_check`` (``--seconds`` of served sim time, full 20;
``--camera WxH``, full 640x480; ``--lidar`` model, full os1-128). It

1. generates the ROS 2 message IDL (``perf/interop/fastdds/gen_idl.py``), runs ``fastddsgen`` on
   it and builds ``perf/interop/fastdds/ros2_peer.cpp`` against Debian's Fast DDS with CMake
   (timed);
2. builds a small procedural scene, serves the rover with the camera (raw images) and the LiDAR
   on 127.0.0.1, and runs the peer beside it: it subscribes to IMU, odometry, the raw image and
   the LiDAR cloud and publishes ``/cmd_vel`` (0.4 m/s, 0.05 rad/s);
3. prints what the peer received against what was published, and how far ``/cmd_vel`` drove the
   rover; twice: with Fast DDS's default UDP receive buffer and with 4 MiB (``rmem_max`` here).

Needs (Debian 12): ``apt-get install fastddsgen libfastrtps-dev libfastcdr-dev cmake g++``.
All DDS traffic stays on the loopback interface.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param

os.environ.setdefault("MUJOCO_GL", "egl")

HERE = Path(__file__).resolve().parent / "fastdds"
PARAMS = (Param("seconds", float, "served sim seconds per session", quick=5.0, full=20.0),
          Param("camera", str, "camera size WxH", quick="160x120", full="640x480"),
          Param("lidar", str, "LiDAR model", quick="simple", full="os1-128"))
DOMAIN = 77


def _run(cmd: list[str], **kw: object) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, **kw)  # type: ignore[call-overload]
    return time.perf_counter() - t0


def build(work: Path) -> Path:
    """IDL -> fastddsgen -> CMake; returns the peer binary."""
    missing = [t for t in ("fastddsgen", "cmake", "g++") if shutil.which(t) is None]
    if missing or not Path("/usr/include/fastdds").is_dir():
        sys.exit(f"missing {' '.join(missing) or 'Fast DDS headers'}: apt-get install "
                 "fastddsgen libfastrtps-dev libfastcdr-dev cmake g++")
    gen, build_dir = work / "gen", work / "build"
    gen.mkdir(parents=True)
    build_dir.mkdir()
    t_idl = _run([sys.executable, str(HERE / "gen_idl.py"), str(work / "ros2.idl")])
    t_gen = _run(["fastddsgen", "-replace", "-d", str(gen), str(work / "ros2.idl")])
    t_cmake = _run(["cmake", "-S", str(HERE), "-B", str(build_dir), f"-DGEN_DIR={gen}",
                    "-DCMAKE_BUILD_TYPE=Release"])
    t_make = _run(["make", "-C", str(build_dir), "-j2"])
    print(f"build: IDL {t_idl:.1f} s, fastddsgen {t_gen:.1f} s, cmake {t_cmake:.1f} s, "
          f"compile + link {t_make:.1f} s (2 cores): {t_idl + t_gen + t_cmake + t_make:.1f} s")
    return build_dir / "ros2_peer"


def main(seconds: float, camera: str, lidar: str) -> list[dict[str, Any]]:
    import marsscene as ms

    with tempfile.TemporaryDirectory(prefix="marsscene-fastdds-") as tmp:
        work = Path(tmp)
        peer = build(work)
        cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [60, 60],
                                                    "post_m": 0.25, "rms_height_m": 0.05},
                                        "craters": {"enabled": False},
                                        "rocks": {"enabled": False}})
        ms.write_scene(ms.build_scene(cfg, seed=3), work / "scene", formats=("mjcf",))
        return [check(peer, work, rcvbuf, seconds, camera, lidar)
                for rcvbuf in (0, 4 * 1024 * 1024)]


def check(peer: Path, work: Path, rcvbuf: int, seconds: float, camera: str,
          lidar: str) -> dict[str, Any]:
    """One served session with the peer beside it (``rcvbuf``: its UDP receive buffer)."""
    from marsscene.runs.tum import read_tum

    run = work / f"run-{rcvbuf}"
    serve = subprocess.Popen(
        ["marsscene", "serve", str(work / "scene"), "--localhost", "--domain-id",
         str(DOMAIN), "--seconds", str(seconds), "--camera", "--camera-size", camera,
         "--images", "raw", "--lidar-model", lidar, "--out", str(run)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # the peer runs until the session has ended (renderer set-up + sim time + margin)
    got = subprocess.run([str(peer), str(DOMAIN), str(seconds / 0.4 + 30.0), "0.4", "0.05",
                          str(rcvbuf)], capture_output=True, text=True,
                         timeout=seconds / 0.4 + 120.0)
    err, _ = serve.communicate(timeout=60)
    result = json.loads(got.stdout)
    served = [ln for ln in err.splitlines() if "served" in ln or "serving" in ln]
    cmd = (run / "cmd.csv").read_text().splitlines()[1:]
    moving = sum(1 for row in cmd if float(row.split(",")[1]) != 0.0)
    gt = read_tum(run / "gt.tum")
    print(f"\nFast DDS peer, UDP receive buffer "
          f"{f'{rcvbuf / 2**20:.0f} MiB' if rcvbuf else 'Fast DDS default'}:")
    print(json.dumps(result, indent=1))
    print("\n".join(served))
    print(f"served {seconds:.0f} sim s; the Fast DDS peer received: "
          + ", ".join(f"{k} {v['n']}" for k, v in result.items() if isinstance(v, dict))
          + f"; published (100 / 50 / 10 / 10 Hz): {int(100 * seconds) + 1} / "
          f"{int(50 * seconds) + 1} / {int(10 * seconds) + 1} / {int(10 * seconds) + 1}")
    print(f"/cmd_vel from Fast DDS: {moving} of {len(cmd)} control steps moving; the rover "
          f"drove {gt.path_length_m():.2f} m")
    return {"rcvbuf_bytes": rcvbuf, "received": {k: v["n"] for k, v in result.items()
                                                  if isinstance(v, dict)},
            "cmd_moving_steps": moving, "cmd_steps": len(cmd), "driven_m": gt.path_length_m()}

