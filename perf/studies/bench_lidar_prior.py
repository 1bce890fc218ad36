"""KISS-ICP with and without the wheel odometry's prior on the paper spec's routes (issue 47).

Run: ``python perf/run.py lidar_prior [--seconds S] [--scenes A,B] [--model M] [--gates G,G]``
(full: each route to its end; ``mars-base,main-crater,grand-canyon``; the spec's ``os1-64``; the
gate of the method's defaults, ``0.05/1``; more as ``M/DEG,M/DEG``, ``inf/inf`` for none, a gate
other than the step gate as ``slip:M/DEG``; ``planar-`` before a gate, e.g.
``planar-step:0.05/1``, takes the prior's rotation from the planar wheel odometry instead of the
gyro). ``python perf/run.py lidar_prior --replay RUN_DIR [--gates G]`` feeds a stored run instead
(the scans of its ``bag/``, its ``odom.tum`` and ``imu.csv``), e.g. a drive on slipping
wheels::

    marsscene build --seed 7 --out /tmp/s
    printf -- '-10 0\n10 0\n10 8\n' > /tmp/wp.txt
    marsscene drive /tmp/s --waypoints /tmp/wp.txt --lidar-model os1-64 --soil dry_sand \
        --noise-profile ln200s --bag --out /tmp/r
    python perf/run.py lidar_prior --replay /tmp/r --gates 0.05/1,slip:0.05/1

For each scene of ``docs/examples/benchmark_slam_paper.toml`` (built as its cells build it,
seed 1, kept in a temporary folder between runs) the rover drives the scene's route (LiDAR
only, ``ln200s`` noise, the spec's noise seed) for at most ``--seconds`` simulated seconds, with
two :class:`~marsscene.benchmark.slam.kiss_icp.LiveKissIcp` listeners on the same scans: plain
(KISS-ICP as ``kiss_icp_pipeline`` runs it) and ``wheel_prior`` (each scan's step predicted by
the wheel odometry). Prints per scene and mode:

* ATE after SE(3) alignment, and as % of the path (the benchmark's figure);
* the anchored error: the estimate against the true ``lidar_link`` motion, both from the first
  scan, at 10 s, 60 s and the end (what the ATE's alignment hides: a jump at the start);
* KISS-ICP's path and its CPU time per scan.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from perf.suite import Param, names, optional

os.environ.setdefault("MUJOCO_GL", "egl")
ROOT = Path(__file__).resolve().parents[2]
SCENES = ("mars-base", "main-crater", "grand-canyon")
PARAMS = (Param("seconds", optional(float), "simulated seconds at most (none: each route to its "
                "end)", quick=10.0, full=None),
          Param("scenes", names, "paper-spec scenes, comma-separated", quick=("main-crater",),
                full=SCENES),
          Param("model", str, "LiDAR model", quick="os1-64", full="os1-64"),
          Param("gates", names, "wheel-prior gates M/DEG (slip:, planar- as above)",
                quick=("0.05/1",), full=("0.05/1",)),
          Param("replay", optional(Path), "a stored run folder to replay instead of driving",
                quick=None, full=None))


def anchored_error_m(estimate, truth, t: float) -> float:
    """|estimate - truth| at ``t``, both as motions from their first pose (no alignment)."""
    from perf.studies.bench_kiss_start import _pose

    t0 = float(estimate.timestamps_s[0])
    true_m = (np.linalg.inv(_pose(truth, t0)) @ _pose(truth, t))[:3, 3]
    est_m = (np.linalg.inv(_pose(estimate, t0)) @ _pose(estimate, t))[:3, 3]
    return float(np.linalg.norm(true_m - est_m))


def _drive(name: str, seconds: float | None, model: str, out: Path, gates: list[str]):
    import dataclasses
    import shutil

    import marsscene as ms
    from marsscene.benchmark.routes import auto_route, centred_on_asset
    from marsscene.benchmark.slam.spec import SlamSpec
    from marsscene.sim.world import load_world
    from perf._measure import paper_scene

    spec = SlamSpec.from_toml(ROOT / "docs" / "examples" / "benchmark_slam_paper.toml")
    scene = next(s for s in spec.scenes if s.name == name)
    t0 = time.perf_counter()
    scene_dir, built = paper_scene(name)
    print(f"{name}: scene {'built' if built else 'reused'} in {time.perf_counter() - t0:.0f} s",
          flush=True)
    world = load_world(scene_dir)
    route = auto_route(centred_on_asset(scene.route, scene_dir), world.heightfield,
                       world.obstacles)
    run = spec.run_config(lidar=True, camera=False)
    run = dataclasses.replace(run, lidar=dataclasses.replace(run.lidar, model=model))
    live = _listeners(gates)
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    ms.drive(scene_dir, route=route, config=run, out_dir=out, seed=spec.noise_seed,
             seconds=seconds, listeners=list(live.values()),
             options=ms.DriveOptions(max_slope_deg=scene.route.max_slope_deg),
             export=ms.ExportOptions(lidar_files=False))  # as a cell: the scans not stored
    print(f"{name}: route {route.length_m:.0f} m, drive {time.perf_counter() - t0:.0f} s wall",
          flush=True)
    return live


def _listeners(gates: list[str]) -> dict:
    """KISS-ICP plain, and with the wheel prior at each gate (``M/DEG`` or ``KIND:M/DEG``,
    ``planar-`` before it for the wheels' rotation)."""
    from marsscene.benchmark.slam.kiss_icp import LiveKissIcp, lidar_mount
    from marsscene.rover.config import RoverConfig

    live = {"plain": LiveKissIcp()}
    for gate in gates:
        planar = gate.startswith("planar-")
        kind, _, devs = gate.removeprefix("planar-").rpartition(":")
        dev_m, dev_deg = (float(v) for v in devs.split("/"))
        live[f"prior {gate}"] = LiveKissIcp(wheel_prior=True, lidar_mount=lidar_mount(
            RoverConfig()), max_step_dev_m=dev_m, max_step_dev_deg=dev_deg, gate=kind or "step",
            gyro=not planar)
    return live


def _bag_scans(bag: Path):
    """(t_s, scan) of each ``/rover/lidar/points`` message of a run's bag, as a drive gives
    them to its listeners."""
    from rosbags.highlevel import AnyReader

    types = {2: "u1", 4: "u2", 6: "u4", 7: "f4", 8: "f8"}
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic == "/rover/lidar/points"]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            dtype = np.dtype({"names": [f.name for f in msg.fields],
                              "formats": [types[f.datatype] for f in msg.fields],
                              "offsets": [f.offset for f in msg.fields],
                              "itemsize": msg.point_step})
            rec = np.frombuffer(msg.data, dtype=dtype, count=msg.width * msg.height)
            yield msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, {
                "xyz_m": np.column_stack([rec["x"], rec["y"], rec["z"]]),
                "intensity": rec["intensity"], "ring": rec["ring"], "t_s": rec["t"] * 1e-9}


def _replay(run_dir: Path, gates: list[str]) -> dict:
    """Feed a stored run (its bag's scans, its ``odom.tum`` and gyro) to the listeners."""
    from marsscene.runs.runlog import RunLog

    live = _listeners(gates)
    run = RunLog(run_dir)
    odom, imu = run.odom, run.imu  # imu: t, accel xyz, gyro xyz
    i = j = 0
    t0 = time.perf_counter()
    for index, (t, scan) in enumerate(_bag_scans(run_dir / "bag")):
        while i < len(odom) and odom.timestamps_s[i] <= t + 1e-9:  # the control steps before it
            wxyz = odom.quat_xyzw[i][[3, 0, 1, 2]]
            for odo in live.values():
                odo.control(odom.timestamps_s[i], 0.0, 0.0, None, None, (None, None),
                            (odom.xyz_m[i], wxyz))
            i += 1
        while j < len(imu) and imu[j, 0] <= t + 1e-9:
            for odo in live.values():
                odo.imu(imu[j, 0], imu[j, 1:4], imu[j, 4:7], None, None)
            j += 1
        for odo in live.values():
            odo.lidar(t, index, scan)
    print(f"{run_dir}: replayed in {time.perf_counter() - t0:.0f} s wall", flush=True)
    return live


def main(seconds: float | None, scenes: tuple[str, ...], model: str, gates: tuple[str, ...],
         replay: Path | None) -> list[dict[str, object]]:
    import tempfile

    from marsscene.benchmark.slam.kiss_icp import lidar_ground_truth, score_lidar_odometry
    from marsscene.runs.runlog import RunLog

    if replay is not None:
        runs = [replay]
        model = "its LiDAR"
    else:
        out = Path(tempfile.gettempdir()) / "bench_lidar_prior"
        runs = [out / name for name in scenes]
    rows: list[dict[str, object]] = []
    for run_dir in runs:
        name = run_dir.name
        live = _replay(run_dir, list(gates)) if replay else _drive(name, seconds, model,
                                                                   run_dir, list(gates))
        run = RunLog(run_dir)
        gt = lidar_ground_truth(run.gt, run.rover)
        for mode, odo in live.items():
            est = odo.trajectory()
            score = score_lidar_odometry(est, run)
            end = float(est.timestamps_s[-1]) if est is not None else 0.0
            marks = [t for t in (10.0, 60.0) if t < end] + [end]
            anchored = ", ".join(f"{t:.0f} s {anchored_error_m(est, gt, t):.2f} m"
                                 for t in marks) if est is not None else "lost"
            print(f"{name:13s} {model} {mode:16s} ATE {score.ate_rmse_m:.3f} m "
                  f"({score.ate_percent:.2f} % of {score.path_m:.1f} m), KISS-ICP path "
                  f"{score.estimated_path_m:.1f} m, {odo.seconds / max(len(odo.poses), 1):.3f} "
                  f"s/scan; anchored error {anchored}"
                  + (f"; ICP steps kept {odo.icp_steps_kept}/{len(odo.poses)}"
                     if odo.wheel_prior else ""), flush=True)
            rows.append({"scene": name, "model": model, "mode": mode,
                         "ate_m": score.ate_rmse_m, "ate_pct": score.ate_percent,
                         "path_m": score.path_m, "kiss_path_m": score.estimated_path_m,
                         "s_per_scan": odo.seconds / max(len(odo.poses), 1),
                         "anchored_error_m": {f"{t:.0f}": anchored_error_m(est, gt, t)
                                              for t in marks} if est is not None else None})
    return rows

