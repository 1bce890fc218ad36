"""``simulation_interfaces`` on ``marsscene serve``: round-trip times of the services.

One command: ``python perf/run.py sim_services`` (``--lidar`` model, quick and full
``simple``). A lockstep session on a 20 m procedural scene, every DDS packet on 127.0.0.1, and
the independent client (``tests/support/sim_client.py``: rmw_cyclonedds's request/reply form,
nothing from marsscene) in its own process: after pausing, the wall time from sending a request
to taking its reply of ``StepSimulation(1)`` (10 calls), ``StepSimulation(50)`` and a 10-step
``SimulateSteps`` goal (send_goal, then get_result until the last step's samples are out).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

from perf.suite import Param

PARAMS = (
    Param("lidar", str, "LiDAR model in the session", quick="simple", full="simple"),
)

CLIENT = str(Path(__file__).resolve().parents[2] / "tests" / "support" / "sim_client.py")


def main(lidar: str) -> list[dict[str, Any]]:
    import marsscene as ms
    from marsscene.ros2 import Ros2Options, serve

    with tempfile.TemporaryDirectory(prefix="marsscene-bench-srv-") as tmp:
        scene = Path(tmp) / "scene"
        cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [20, 20]}})
        ms.write_scene(ms.build_scene(cfg, seed=1), scene, formats=("mjcf",))
        peer = subprocess.Popen([sys.executable, CLIENT, "221"], stdout=subprocess.PIPE,
                                text=True)
        try:
            serve(scene, ros=Ros2Options(domain_id=221, localhost=True, pace="lockstep"),
                  config=ms.RunConfig(lidar=ms.LidarConfig(model=lidar)), seconds=60.0,
                  seed=3)
            out, _ = peer.communicate(timeout=120)
        finally:
            peer.kill()
    got = json.loads(out)
    rtt = sorted(got["step1_rtt_s"])
    return [{"case": f"StepSimulation(1), LiDAR {lidar}", "calls": len(rtt),
             "median_ms": round(1e3 * statistics.median(rtt), 2),
             "max_ms": round(1e3 * rtt[-1], 2), "min_ms": round(1e3 * rtt[0], 2)},
            {"case": f"StepSimulation(50), LiDAR {lidar}",
             "wall_ms": round(1e3 * got["step50_wall_s"], 1)},
            {"case": f"SimulateSteps(10) send_goal + get_result, LiDAR {lidar}",
             "wall_ms": round(1e3 * got["action_wall_s"], 1),
             "feedback": len(got["feedback"])}]


if __name__ == "__main__":
    for row in main("simple"):
        print(json.dumps(row))
