"""Live ROS 2 (``marsscene serve``): publish rates, real-time factor, ``/cmd_vel`` latency, and the
write time of one image and one cloud.

One command: ``python perf/run.py ros2`` (``--seconds`` of sim time per session, full 10,
quick 2). On a 60 m procedural scene, every DDS packet on 127.0.0.1, with an independent
subscriber process (``tests/support/dds_peer.py``: plain cyclonedds + rosbags) taking every
topic:

1. **write time per message** of a 640 x 480 rgb8 ``sensor_msgs/Image`` (921,600 B of pixels)
   and an os1-128 ``PointCloud2`` (~71,600 points x 22 B) to a matched subscriber: the live
   rover's path (``rosbags`` CDR + Cyclone's C writer) against ``cyclonedds-python``'s own
   (an ``IdlStruct`` sample serialised in Python, ``DataWriter.write``);
2. **sessions** with the camera (640 x 480 RGB-D, 10 Hz) and the LiDAR (os1-128, 10 Hz):
   as fast as it goes and paced to real time, and the LiDAR alone: real-time factor, messages
   published and received per topic against the sensor rates, write seconds per topic;
3. **latency** from a ``/cmd_vel`` message to motion on ``/rover/odom`` (``|v| >= v_cmd / 2``),
   wall clock, with every sensor on and real-time pacing;
4. **lockstep** (``pace="lockstep"``): control steps a second a client drives when it sends a
   command, then waits for ``/clock`` to say the step's samples are out (the peer's
   ``lockstep`` mode, taking odometry and LiDAR), with the LiDAR alone and with the camera too.

``python perf/run.py ros2 --lockstep`` runs part 4 alone.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np

from perf.suite import Param

PARAMS = (
    Param("seconds", float, "sim seconds per session and per lockstep run", quick=2.0,
          full=10.0),
    Param("lockstep", bool, "run the lockstep part (4) alone", quick=False, full=False),
)

PEER = str(Path(__file__).resolve().parents[2] / "tests" / "support" / "dds_peer.py")
ALL = {
    "/clock": ["rosgraph_msgs/msg/Clock", False, False, 100],
    "/tf": ["tf2_msgs/msg/TFMessage", True, False, 50],
    "/rover/odom": ["nav_msgs/msg/Odometry", True, False, 50],
    "/rover/GT_Trajectory": ["nav_msgs/msg/Odometry", True, False, 50],
    "/rover/joint_states": ["sensor_msgs/msg/JointState", True, False, 50],
    "/rover/imu": ["sensor_msgs/msg/Imu", False, False, 100],
    "/rover/imu_noisy": ["sensor_msgs/msg/Imu", False, False, 100],
    "/rover/rgb/image_raw": ["sensor_msgs/msg/Image", False, False, 10],
    "/rover/rgb/image_raw/compressed": ["sensor_msgs/msg/CompressedImage", False, False, 10],
    "/rover/rgb/camera_info": ["sensor_msgs/msg/CameraInfo", False, False, 10],
    "/rover/depth/image_raw": ["sensor_msgs/msg/Image", False, False, 10],
    "/rover/depth/image_raw/compressedDepth": ["sensor_msgs/msg/CompressedImage", False, False,
                                               10],
    "/rover/lidar/points": ["sensor_msgs/msg/PointCloud2", False, False, 10],
    "/rover/scan": ["sensor_msgs/msg/LaserScan", False, False, 10],
}


def _listen(domain: int, topics: dict[str, list[Any]]) -> subprocess.Popen[str]:
    spec = {t: v[:3] for t, v in topics.items()}
    return subprocess.Popen([sys.executable, PEER, "listen", str(domain), "--until-idle", "4",
                             "600", json.dumps(spec)], stdout=subprocess.PIPE, text=True)


def write_times() -> list[dict[str, Any]]:
    """ms per message: rosbags CDR + Cyclone's C writer, against cyclonedds-python's path."""
    from cyclonedds.pub import DataWriter
    from cyclonedds.topic import Topic

    from marsscene.ros2 import dds
    from marsscene.runs.export.bag_messages import MessageBuilder
    from marsscene.runs.logs import scan_record

    b = MessageBuilder()
    rng = np.random.default_rng(0)
    n = 71_600
    rec = scan_record(rng.normal(size=(n, 3)).astype(np.float32),
                      rng.uniform(size=n).astype(np.float32),
                      rng.integers(0, 128, n).astype(np.uint16), np.linspace(0, 0.1, n))
    msgs = {"image 640x480 rgb8": b.image(1.0, "navcam_optical_frame", rng.integers(
        0, 255, (480, 640, 3), dtype=np.uint8), "rgb8"),
            "cloud os1-128 (71,600 points)": b.cloud(1.0, "lidar_link", rec, (1, n))}
    topics = {"/bench/image": ["sensor_msgs/msg/Image", True, False],
              "/bench/cloud": ["sensor_msgs/msg/PointCloud2", True, False],
              "/bench/image_py": ["sensor_msgs/msg/Image", True, False],
              "/bench/cloud_py": ["sensor_msgs/msg/PointCloud2", True, False]}
    listener = _listen(90, topics)
    part = dds.Participant(90, localhost=True)
    rows = []
    try:
        for (name, msg), topic in zip(msgs.items(), ("/bench/image", "/bench/cloud"),
                                      strict=True):
            mt = msg.__msgtype__
            w = part.writer(b.store, topic, mt, "default")
            cls = dds.dds_type(b.store, mt)
            py_w = DataWriter(part.dp, Topic(part.dp, dds.dds_topic(topic + "_py"), cls),
                              dds.QOS["default"])
            t0 = time.monotonic()
            while not w.subscribers and time.monotonic() - t0 < 20:
                time.sleep(0.05)
            ours, ser, theirs, build = [], [], [], []
            for _ in range(30):
                t0 = time.perf_counter()
                data = b.serialize(msg)
                t1 = time.perf_counter()
                w.write(data)
                t2 = time.perf_counter()
                ours.append(t2 - t0)
                ser.append(t1 - t0)
                time.sleep(0.02)
            for _ in range(10):
                t0 = time.perf_counter()
                sample = cls.deserialize(bytes(data))  # the IdlStruct a Python user would build
                t1 = time.perf_counter()
                py_w.write(sample)
                t2 = time.perf_counter()
                theirs.append(t2 - t1)
                build.append(t1 - t0)
                time.sleep(0.02)
            print(f"{name}: {len(bytes(data)) / 1e6:.2f} MB CDR | live path (rosbags CDR "
                  f"{1e3 * statistics.median(ser):.2f} ms + C writer) "
                  f"{1e3 * statistics.median(ours):.2f} ms | cyclonedds-python "
                  f"DataWriter.write (Python CDR) {1e3 * statistics.median(theirs):.1f} ms "
                  f"(+ {1e3 * statistics.median(build):.1f} ms to build the IdlStruct sample)")
            rows.append({"part": "write", "message": name, "cdr_mb": len(bytes(data)) / 1e6,
                         "rosbags_cdr_ms": 1e3 * statistics.median(ser),
                         "live_path_ms": 1e3 * statistics.median(ours),
                         "cyclonedds_python_ms": 1e3 * statistics.median(theirs),
                         "idlstruct_build_ms": 1e3 * statistics.median(build)})
    finally:
        part.close()
        listener.kill()
    return rows


def session(label: str, scene: Path, domain: int, config: Any, pace: str,
            topics: dict[str, list[Any]], seconds: float) -> dict[str, Any]:
    from marsscene.ros2 import Ros2Options, serve

    listener = _listen(domain, topics) if topics else None

    def ready(bridge: Any) -> None:
        t0 = time.monotonic()
        while time.monotonic() - t0 < 30 and not all(
                bridge.writers[t].subscribers for t in topics if t in bridge.writers):
            time.sleep(0.05)

    res = serve(scene, ros=Ros2Options(domain_id=domain, localhost=True, pace=pace),
                config=config, seconds=seconds, ready=ready)
    st = res.stats
    row: dict[str, Any] = {"part": "session", "label": label, "pace": pace, "sim_s": res.sim_s,
                           "wall_s": res.wall_s, "realtime_factor": res.realtime_factor}
    if listener is None:
        print(f"\n{label} (pace {pace}): {res.sim_s:.1f} sim s in {res.wall_s:.1f} s = "
              f"{res.realtime_factor:.2f}x real time (nothing built or sent)")
        return row
    got = json.loads(listener.communicate(timeout=120)[0])
    print(f"\n{label} (pace {pace}): {res.sim_s:.1f} sim s in {res.wall_s:.1f} s = "
          f"{res.realtime_factor:.2f}x real time; building the messages took "
          f"{sum(st['build_s'].values()):.2f} s of it ("
          + ", ".join(f"{k} {v:.2f}" for k, v in st["build_s"].items())
          + f"), CDR + DDS writes {sum(st['write_s'].values()):.2f} s")
    print(f"  {'topic':42s} {'rate Hz':>7s} {'expected':>8s} {'published':>9s} "
          f"{'received':>8s} {'pub Hz (wall)':>13s} {'ms/msg':>7s} {'kB/msg':>7s}")
    per_topic = {}
    for t, spec in topics.items():
        exp = int(spec[3] * seconds) + 1
        pub, rec = st["messages"].get(t, 0), got[t]["n"]
        ms_msg = 1e3 * st["write_s"].get(t, 0.0) / max(pub, 1)
        kb = st["bytes"].get(t, 0) / max(pub, 1) / 1e3
        print(f"  {t:42s} {spec[3]:7d} {exp:8d} {pub:9d} {rec:8d} "
              f"{pub / max(res.wall_s, 1e-9):13.1f} {ms_msg:7.2f} {kb:7.1f}")
        per_topic[t] = {"expected": exp, "published": pub, "received": rec,
                        "ms_per_msg": ms_msg, "kb_per_msg": kb}
    return {**row, "build_s": sum(st["build_s"].values()),
            "write_s": sum(st["write_s"].values()), "topics": per_topic}


def latency(label: str, scene: Path, config: Any, domain: int) -> dict[str, Any]:
    from marsscene.ros2 import Ros2Options, serve

    peer = subprocess.Popen([sys.executable, PEER, "latency", str(domain), "0.4", "--repeats",
                             "8"], stdout=subprocess.PIPE, text=True)
    ros = Ros2Options(domain_id=domain, localhost=True)
    done: dict[str, Any] = {}

    class Stop:  # end the session once the peer has its figures
        def __call__(self, p: Any) -> None:
            if peer.poll() is not None and not done:
                done["out"] = peer.stdout.read() if peer.stdout else ""
                raise KeyboardInterrupt

    serve(scene, ros=ros, config=config, seconds=300.0, progress=Stop())
    out = done.get("out") or peer.communicate(timeout=60)[0]
    lat = [x for x in json.loads(out)["latency_s"] if x is not None]
    print(f"\n/cmd_vel -> motion on /rover/odom (|v| >= 0.2 m/s after a 0.4 m/s step), "
          f"{len(lat)} steps, real-time pacing, {label}: median "
          f"{1e3 * statistics.median(lat):.0f} ms, min {1e3 * min(lat):.0f} ms, max "
          f"{1e3 * max(lat):.0f} ms (in sim time the command is applied at the next 50 Hz "
          "control step and the wheel odometry reads >= 0.2 m/s one step later)")
    return {"part": "latency", "label": label, "steps": len(lat),
            "median_ms": 1e3 * statistics.median(lat), "min_ms": 1e3 * min(lat),
            "max_ms": 1e3 * max(lat)}


def lockstep_rate(label: str, scene: Path, config: Any, domain: int, seconds: float
                  ) -> dict[str, Any]:
    from marsscene.ros2 import Ros2Options, serve

    steps, dt = int(50 * seconds), 1.0 / 50.0
    peer = subprocess.Popen([sys.executable, PEER, "lockstep", str(domain), str(steps),
                             str(dt), "0.4", "0.05"], stdout=subprocess.PIPE, text=True)
    try:
        res = serve(scene, ros=Ros2Options(domain_id=domain, localhost=True, pace="lockstep"),
                    config=config, seconds=steps * dt)
        got = json.loads(peer.communicate(timeout=600)[0])
    finally:
        peer.kill()
    sent = res.stats["messages"]
    print(f"\nlockstep, {label}: {steps} control steps of {1e3 * dt:.0f} ms in "
          f"{got['wall_s']:.1f} s = {steps / got['wall_s']:.0f} steps/s "
          f"({steps * dt / got['wall_s']:.2f}x real time); the client took "
          f"{got['counts']['lidar']} of {sent.get('/rover/lidar/points', 0)} clouds and "
          f"{got['counts']['odom']} of {sent.get('/rover/odom', 0)} odometry messages")
    return {"part": "lockstep", "label": label, "steps": steps, "wall_s": got["wall_s"],
            "steps_per_s": steps / got["wall_s"], "realtime_factor": steps * dt / got["wall_s"],
            "clouds_taken": got["counts"]["lidar"],
            "clouds_sent": sent.get("/rover/lidar/points", 0),
            "odom_taken": got["counts"]["odom"], "odom_sent": sent.get("/rover/odom", 0)}


def main(seconds: float, lockstep: bool) -> list[dict[str, Any]]:
    import marsscene as ms

    with tempfile.TemporaryDirectory(prefix="marsscene-bench-ros2-") as tmp:
        scene = Path(tmp) / "scene"
        cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [60, 60],
                                                    "post_m": 0.25, "rms_height_m": 0.05},
                                        "craters": {"enabled": False},
                                        "rocks": {"enabled": False}})
        ms.write_scene(ms.build_scene(cfg, seed=3), scene, formats=("mjcf",))
        full = ms.RunConfig(camera=ms.CameraConfig(), lidar=ms.LidarConfig())
        lidar = ms.RunConfig(lidar=ms.LidarConfig())
        rows = [lockstep_rate("LiDAR os1-128 only", scene, lidar, 98, seconds),
                lockstep_rate("camera 640x480 + LiDAR os1-128", scene, full, 99, seconds)]
        if lockstep:
            return rows
        rows += write_times()
        every = "camera 640x480 + LiDAR os1-128, every topic subscribed"
        lidar_topics = {t: v for t, v in ALL.items() if "rgb" not in t and "depth" not in t}
        for label, domain, config, pace, topics in (
                (every, 91, full, "max", ALL), (every, 92, full, "realtime", ALL),
                ("camera 640x480 + LiDAR os1-128, no subscriber", 95, full, "max", {}),
                ("LiDAR os1-128 only, every topic subscribed", 94, lidar, "max", lidar_topics),
                ("LiDAR os1-128 only, every topic subscribed", 96, lidar, "realtime",
                 lidar_topics)):
            rows.append(session(label, scene, domain, config, pace, topics, seconds))
        rows.append(latency("camera 640x480 + LiDAR os1-128", scene, full, 93))
        rows.append(latency("LiDAR os1-128 only", scene, lidar, 97))
    return rows
