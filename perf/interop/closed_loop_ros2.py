"""Closed loop over DDS only: an external process drives the live rover towards a goal 20 m away
from ``/rover/odom`` and stops before a rock it sees in ``/rover/lidar/points``.

One command: ``python perf/run.py closed_loop_ros2 [--scene DIR]`` (default: builds the default
scene, ``marsscene build --seed 7``, MJCF only, into a temporary folder). It picks a rock of the
scene (simulated, at least 0.45 m tall and 0.8 m wide, on gentle ground with no other tall rock near
the line), starts the rover 12 m before it facing it, with the goal 20 m ahead (8 m beyond the
rock), serves the rover (``marsscene serve --lidar``, os1-128, 127.0.0.1 only) and runs the
independent peer (``tests/support/dds_peer.py goto``: plain cyclonedds + rosbags) with a
stop distance of 6 m. It prints where the peer stopped and why, and the true clearance between
the rover's front and the rock (run folder ground truth).
"""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from perf.suite import Param, optional

os.environ.setdefault("MUJOCO_GL", "egl")

#: the suite's independent DDS peer, run as a script (not imported)
PEER = Path(__file__).resolve().parents[2] / "tests" / "support" / "dds_peer.py"
PARAMS = (Param("scene", optional(Path), "a built scene folder (none: build the default scene)",
                quick=None, full=None),)
DOMAIN, AHEAD_M, GOAL_M, STOP_M = 78, 12.0, 20.0, 4.0
#: base_link to the front of the front wheels (wheelbase 1.05 m + wheel radius 0.2625 m)
FRONT_M = 1.05 + 0.2625


def pick_rock(scene: Path) -> tuple[dict[str, float], float]:
    """A lone, tall, simulated rock with gentle ground before it, and the heading to it."""
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(
        (scene / "rocks.csv").open())]
    tall = [r for r in rows if r["height_m"] >= 0.25]
    from marsscene.sim.world import load_world

    hf = load_world(scene).heightfield
    for rock in sorted((r for r in rows if r["in_mjcf"] == 1 and r["height_m"] >= 0.45
                        and r["diameter_m"] >= 0.8), key=lambda r: -r["height_m"]):
        for yaw in (0.0, math.pi / 2, math.pi, -math.pi / 2):
            c, s = math.cos(yaw), math.sin(yaw)
            sx, sy = rock["x_m"] - AHEAD_M * c, rock["y_m"] - AHEAD_M * s
            gx, gy = sx + GOAL_M * c, sy + GOAL_M * s
            if not (hf.contains(sx - 3, sy - 3) and hf.contains(sx + 3, sy + 3)
                    and hf.contains(gx, gy)):
                continue
            line = [(sx + d * c, sy + d * s) for d in range(0, int(AHEAD_M))]
            zs = [float(hf.sample(x, y)) for x, y in line]
            if max(zs) - min(zs) > 0.5:  # gentle ground only
                continue
            others = [o for o in tall if o is not rock and any(
                math.hypot(o["x_m"] - x, o["y_m"] - y) < 2.5 for x, y in line)]
            if not others:
                return rock, yaw
    sys.exit("no lone tall rock with gentle ground before it in this scene")


def main(scene: Path | None) -> dict[str, object]:
    with tempfile.TemporaryDirectory(prefix="marsscene-closed-loop-") as tmp:
        work = Path(tmp)
        build = scene is None
        scene = scene or work / "scene"
        if build:
            subprocess.run(["marsscene", "build", "--seed", "7", "--out", str(scene)],
                           check=True, stdout=subprocess.DEVNULL)
        rock, yaw = pick_rock(scene)
        sx, sy = rock["x_m"] - AHEAD_M * math.cos(yaw), rock["y_m"] - AHEAD_M * math.sin(yaw)
        print(f"rock {int(rock['id'])}: ({rock['x_m']:.2f}, {rock['y_m']:.2f}) m, "
              f"{rock['diameter_m']:.2f} m wide, {rock['height_m']:.2f} m tall; start "
              f"({sx:.2f}, {sy:.2f}) m facing {math.degrees(yaw):.0f} deg, goal {GOAL_M:.0f} m "
              "ahead")
        run = work / "run"
        serve = subprocess.Popen(
            ["marsscene", "serve", str(scene), "--localhost", "--domain-id",
             str(DOMAIN), "--lidar", "--start-xy", str(sx), str(sy),
             "--yaw-deg", str(math.degrees(yaw)),
             "--seconds", "150", "--out", str(run)],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        dx, dy = GOAL_M * math.cos(yaw), GOAL_M * math.sin(yaw)
        peer = subprocess.run([sys.executable, str(PEER), "goto", str(DOMAIN), str(dx), str(dy),
                               "--stop-m", str(STOP_M), "--seconds", "140"],
                              capture_output=True, text=True, timeout=400)
        serve.terminate()  # Ctrl-C's SIGTERM: the run folder is finished up to now
        log, _ = serve.communicate(timeout=120)
        if peer.returncode != 0:
            sys.exit(f"peer failed:\n{peer.stderr}\n{log}")
        result = json.loads(peer.stdout)
        from marsscene.runs.tum import read_tum

        gt = read_tum(run / "gt.tum")
        x, y = gt.xyz_m[-1, :2]
        centre = math.hypot(rock["x_m"] - x, rock["y_m"] - y)
        print(json.dumps(result))
        print(f"peer stopped: {result['reason']} (nearest point ahead {result['obstacle_m']} m "
              f"in the LiDAR frame) after {result['travelled_m']:.2f} m on odometry")
        print(f"ground truth: rover {centre:.2f} m from the rock's centre; clearance front to "
              f"rock {centre - FRONT_M - rock['diameter_m'] / 2:.2f} m; drove "
              f"{gt.path_length_m():.2f} m of the {GOAL_M:.0f} m to the goal")
        print("\n".join(ln for ln in log.splitlines() if "served" in ln))
        return {**result, "rock_id": int(rock["id"]), "centre_m": centre,
                "clearance_m": centre - FRONT_M - rock["diameter_m"] / 2,
                "driven_m": gt.path_length_m()}

