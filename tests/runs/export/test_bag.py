"""ROS 2 bags: read back with rosbags (AnyReader) and independently with mcap + mcap-ros2."""

from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pytest.importorskip("rosbags")

from rosbags.highlevel import AnyReader

from marsscene.cli import main
from marsscene.errors import ExportError, RuntimeSimError
from marsscene.runs.export.bag import write_bag
from marsscene.runs.runlog import RunLog, read_image, read_ply
from marsscene.runtime import read_tum

SENSOR_FRAMES = ("imu_link", "lidar_link", "navcam_optical_frame",
                 "stereo_left_optical_frame", "stereo_right_optical_frame")


def _read_rosbags(path: Path) -> tuple[dict[str, list[tuple[int, Any]]], dict[str, Any]]:
    msgs: dict[str, list[tuple[int, Any]]] = defaultdict(list)
    with AnyReader([path]) as reader:
        conns = {c.topic: c for c in reader.connections}
        for conn, stamp, raw in reader.messages():
            msgs[conn.topic].append((stamp, reader.deserialize(raw, conn.msgtype)))
    return msgs, conns


def _stamp(msg: Any) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def _pose(tf: Any) -> np.ndarray:
    m = np.eye(4)
    r = tf.transform.rotation
    m[:3, :3] = Rotation.from_quat([r.x, r.y, r.z, r.w]).as_matrix()
    t = tf.transform.translation
    m[:3, 3] = (t.x, t.y, t.z)
    return m


@pytest.fixture(scope="module")
def mcap_bag(stereo_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_bag(stereo_run, tmp_path_factory.mktemp("bags") / "bag", images="raw",
                     depth_encoding="32FC1").path


@pytest.fixture(scope="module")
def bag_msgs(mcap_bag: Path) -> tuple[dict[str, list[tuple[int, Any]]], dict[str, Any]]:
    return _read_rosbags(mcap_bag)


def test_counts_and_order_agree_with_independent_mcap_reader(mcap_bag, bag_msgs, stereo_run):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    msgs, _ = bag_msgs
    counts: Counter[str] = Counter()
    last: dict[str, int] = {}
    with open(mcap_bag / "bag.mcap", "rb") as fh:
        for _, channel, message, decoded in make_reader(
            fh, decoder_factories=[DecoderFactory()]
        ).iter_decoded_messages(log_time_order=False):
            counts[channel.topic] += 1
            assert message.log_time >= last.get(channel.topic, 0)
            last[channel.topic] = message.log_time
            if channel.topic == "/rover/rgb/image_raw":
                assert decoded.step * decoded.height == len(decoded.data)
    assert counts == Counter({t: len(v) for t, v in msgs.items()})
    run = RunLog(stereo_run)
    cam = run.camera_streams()[0]
    expected = {"/clock": len(run.imu), "/tf": len(run.gt), "/rover/odom": len(run.odom),
                "/rover/GT_Trajectory": len(run.gt), "/rover/cmd_vel": len(run.cmd),
                "/rover/joint_states": len(run.wheels), "/rover/imu_noisy": len(run.imu),
                "/rover/imu": len(run.imu), "/tf_static": 1, "/rover/robot_description": 1,
                "/rover/rgb/image_raw": len(cam.stamps_s), "/rover/depth/points": len(cam.stamps_s),
                "/rover/stereo/right/image_raw": len(cam.stamps_s),
                "/rover/lidar/points": len(run.lidar[0]), "/rover/scan": len(run.lidar[0])}
    for topic, n in expected.items():
        assert counts[topic] == n, topic
    for topic, items in msgs.items():  # header stamps non-decreasing and equal to log time
        if hasattr(items[0][1], "header"):
            stamps = np.array([_stamp(m) for _, m in items])
            assert np.all(np.diff(stamps) >= 0), topic
            np.testing.assert_allclose(stamps, [s * 1e-9 for s, _ in items], atol=1e-9)


def test_images_and_camera_info_match_the_run(bag_msgs, stereo_run):
    msgs, _ = bag_msgs
    run = RunLog(stereo_run)
    cam = run.camera_streams()[0]
    for (_, img), f in zip(msgs["/rover/rgb/image_raw"], cam.rgb_files, strict=True):
        assert img.encoding == "rgb8" and img.step * img.height == len(img.data)
        np.testing.assert_array_equal(img.data.reshape(img.height, img.width, 3), read_image(f))
    for _, info in msgs["/rover/rgb/camera_info"] + msgs["/rover/depth/camera_info"]:
        np.testing.assert_allclose(info.k.reshape(3, 3), cam.k)
        assert (info.width, info.height) == (80, 60)
    _, depth = msgs["/rover/depth/image_raw"][5]
    assert depth.encoding == "32FC1" and depth.step * depth.height == len(depth.data)
    metres = depth.data.view("<f4").reshape(60, 80)
    mm = read_image(cam.depth_files[5])
    ok = (mm > 0) & (mm < 65535)
    np.testing.assert_allclose(metres[ok], mm[ok] / 1000.0, rtol=1e-6)
    assert np.isnan(metres[mm == 0]).all() and np.isposinf(metres[mm == 65535]).all()
    assert ok.any() and (mm == 0).any()  # ground and sky (no return: 0 mm -> NaN) in view
    _, cloud = msgs["/rover/depth/points"][5]
    pts = np.frombuffer(cloud.data.tobytes(), "<f4").reshape(cloud.height, cloud.width, 3)
    assert (cloud.height, cloud.width) == (15, 20)  # stride 4
    sub, ok4 = mm[::4, ::4] / 1000.0, ok[::4, ::4]
    np.testing.assert_allclose(pts[..., 2][ok4], sub[ok4], rtol=1e-6)
    assert np.isnan(pts[~ok4]).all()
    v, u = np.nonzero(ok4)  # pixels reproject through K
    np.testing.assert_allclose(pts[v, u, 0], (4 * u - cam.k[0, 2]) / cam.k[0, 0] * sub[v, u],
                               rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(pts[v, u, 1], (4 * v - cam.k[1, 2]) / cam.k[1, 1] * sub[v, u],
                               rtol=1e-5, atol=1e-6)
    # stereo: right camera_info carries Tx = -fx * baseline (ROS convention)
    _, right = msgs["/rover/stereo/right/camera_info"][0]
    assert right.p[3] == pytest.approx(-cam.k[0, 0] * 0.3)
    _, mono = msgs["/rover/stereo/left/image_raw"][0]
    assert mono.encoding == "mono8" and mono.step * mono.height == len(mono.data)


def test_poses_equal_the_run_tum_files_and_tf_closes(bag_msgs, stereo_run):
    msgs, _ = bag_msgs
    gt, odom = read_tum(stereo_run / "gt.tum"), read_tum(stereo_run / "odom.tum")
    for name, traj in (("/rover/odom", odom), ("/rover/GT_Trajectory", gt)):
        xyz = np.array([[m.pose.pose.position.x, m.pose.pose.position.y,
                         m.pose.pose.position.z] for _, m in msgs[name]])
        q = np.array([[m.pose.pose.orientation.x, m.pose.pose.orientation.y,
                       m.pose.pose.orientation.z, m.pose.pose.orientation.w]
                      for _, m in msgs[name]])
        np.testing.assert_allclose(xyz, traj.xyz_m, atol=1e-9)
        np.testing.assert_allclose(q, traj.quat_xyzw, atol=1e-9)
    assert {m.header.frame_id for _, m in msgs["/rover/odom"]} == {"odom"}
    assert {m.header.frame_id for _, m in msgs["/rover/GT_Trajectory"]} == {"map"}
    # map->odom (from GT) composed with odom->base_link (odometry) is the ground truth
    for i, (_, tf) in enumerate(msgs["/tf"]):
        mo, ob = tf.transforms
        assert (mo.header.frame_id, mo.child_frame_id) == ("map", "odom")
        assert (ob.header.frame_id, ob.child_frame_id) == ("odom", "base_link")
        m = _pose(mo) @ _pose(ob)
        np.testing.assert_allclose(m[:3, 3], gt.xyz_m[i], atol=1e-9)
        np.testing.assert_allclose(Rotation.from_matrix(m[:3, :3]).as_quat(canonical=True),
                                   Rotation.from_quat(gt.quat_xyzw[i]).as_quat(canonical=True),
                                   atol=1e-9)
    # cmd_vel and noisy IMU equal their CSV logs
    cmd = np.loadtxt(stereo_run / "cmd.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose([[m.linear.x, m.angular.z] for _, m in msgs["/rover/cmd_vel"]],
                               cmd[:, 1:], atol=1e-12)
    imu = np.loadtxt(stereo_run / "imu.csv", delimiter=",", skiprows=1)
    got = [[m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z,
            m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z]
           for _, m in msgs["/rover/imu_noisy"]]
    np.testing.assert_allclose(got, imu[:, 1:], atol=1e-12)
    true = [m.angular_velocity.z for _, m in msgs["/rover/imu"]]
    assert np.std(np.array(true) - imu[:, 6]) == pytest.approx(0.01, rel=0.2)  # the gyro noise


def test_tf_tree_connects_every_sensor_frame_and_is_latched(bag_msgs):
    msgs, conns = bag_msgs
    parent = {}
    for _, m in msgs["/tf_static"] + msgs["/tf"][:1]:
        for t in m.transforms:
            assert t.child_frame_id not in parent or parent[t.child_frame_id] == t.header.frame_id
            parent[t.child_frame_id] = t.header.frame_id
    used = {m.header.frame_id for topic, items in msgs.items() for _, m in items[:1]
            if hasattr(m, "header") and topic not in ("/tf", "/tf_static")}
    assert set(SENSOR_FRAMES) <= used | {"imu_link"}
    for frame in used | set(SENSOR_FRAMES):
        chain = [frame]
        while chain[-1] in parent:
            chain.append(parent[chain[-1]])
        assert chain[-1] == "map" and ("base_link" in chain or frame in ("map", "odom")), chain
    for topic in ("/tf_static", "/rover/robot_description"):
        (qos,) = conns[topic].ext.offered_qos_profiles
        assert qos.durability.name == "TRANSIENT_LOCAL" and qos.depth == 1
    # the URDF names every joint in joint_states and every sensor frame as a link
    urdf = ET.fromstring(msgs["/rover/robot_description"][0][1].data)
    links = {e.get("name") for e in urdf.iter("link")}
    joints = {e.get("name"): e.get("type") for e in urdf.iter("joint")}
    assert set(SENSOR_FRAMES) <= links
    _, js = msgs["/rover/joint_states"][-1]
    assert all(joints[n] in ("continuous", "revolute") for n in js.name)


def test_lidar_cloud_and_scan_equal_the_ply_scans(bag_msgs, stereo_run):
    msgs, _ = bag_msgs
    run = RunLog(stereo_run)
    _, files = run.lidar
    for (_, cloud), (_, scan), f in zip(msgs["/rover/lidar/points"], msgs["/rover/scan"], files,
                                        strict=True):
        ply = read_ply(f)
        # the fields ouster-ros publishes: t is uint32 ns after the stamp (PointField 6)
        assert [(p.name, p.datatype, p.offset) for p in cloud.fields] == [
            ("x", 7, 0), ("y", 7, 4), ("z", 7, 8), ("intensity", 7, 12), ("t", 6, 16),
            ("ring", 4, 20)]
        got = np.frombuffer(cloud.data.tobytes(), ply.dtype)
        np.testing.assert_array_equal(got, ply)
        assert np.all(np.diff(got["t"].astype(np.int64)) >= 0) and got["t"].max() < 1e8
        ring = ply[ply["ring"] == 2]  # -10 deg: the ring nearest to horizontal
        finite = np.isfinite(scan.ranges)
        assert finite.sum() == len(ring) > 0
        r = np.sqrt(ring["x"] ** 2 + ring["y"] ** 2 + ring["z"] ** 2)
        np.testing.assert_allclose(np.sort(scan.ranges[finite]), np.sort(r), rtol=1e-6)
        assert len(scan.ranges) == 90 and scan.angle_increment == pytest.approx(np.pi / 45)


def test_sqlite3_storage_same_messages_and_deterministic_bytes(stereo_run, mcap_bag, bag_msgs,
                                                                 tmp_path):
    sq = write_bag(stereo_run, tmp_path / "sq", storage="sqlite3", images="raw")  # 16UC1 default
    msgs, _ = _read_rosbags(sq.path)
    ref, _ = bag_msgs
    assert {t: len(v) for t, v in msgs.items()} == {t: len(v) for t, v in ref.items()}
    assert (sq.path / "sq.db3").is_file()
    _, depth = msgs["/rover/depth/image_raw"][3]
    assert depth.encoding == "16UC1" and depth.step == 160
    again = write_bag(stereo_run, tmp_path / "again" / "bag", images="raw",
                      depth_encoding="32FC1")  # same bytes
    assert (again.path / "bag.mcap").read_bytes() == (mcap_bag / "bag.mcap").read_bytes()
    assert (again.path / "metadata.yaml").read_bytes() == (mcap_bag / "metadata.yaml").read_bytes()


def test_bad_inputs_are_refused_and_leave_nothing(bag_run, tmp_path):
    partial = tmp_path / "partial"
    shutil.copytree(bag_run, partial)
    (partial / "odom.tum").unlink()
    with pytest.raises(RuntimeSimError, match=r"missing odom\.tum"):
        write_bag(partial)
    bare = tmp_path / "bare"
    shutil.copytree(bag_run, bare, ignore=shutil.ignore_patterns("camera", "lidar"))
    with pytest.raises(RuntimeSimError, match="no camera logs"):
        write_bag(bare, sensors=["camera"])
    with pytest.raises(RuntimeSimError, match="no stereo"):
        write_bag(bag_run, tmp_path / "b", sensors=["stereo"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bare", "partial"]
    ok = write_bag(bare)  # no sensors: state topics only
    assert "/rover/rgb/image_raw" not in ok.counts and ok.counts["/rover/odom"] > 0
    before = (ok.path / "bag.mcap").stat().st_mtime_ns
    with pytest.raises(ExportError, match="exists"):
        write_bag(bare)
    assert (ok.path / "bag.mcap").stat().st_mtime_ns == before
    assert write_bag(bare, overwrite=True).counts == ok.counts
    assert sorted(p.name for p in bare.iterdir() if p.name.startswith(".")) == []
    meta = json.loads((bare / "run.json").read_text())
    assert meta["summary"]["camera_frames"] > 0  # the run had a camera; only the logs were cut


def test_cli_bag_and_drive_bag(runner, bag_run, gentle_scene, tmp_path):
    res = runner.invoke(main, ["bag", str(bag_run), "--out", str(tmp_path / "b"),
                               "--bag-storage", "sqlite3", "--sensor", "lidar"])
    assert res.exit_code == 0, res.output
    msgs, _ = _read_rosbags(tmp_path / "b")
    assert "/rover/scan" in msgs and "/rover/rgb/image_raw" not in msgs
    res = runner.invoke(main, ["bag", str(tmp_path)])
    assert res.exit_code == 1 and "not a complete run folder" in res.output
    assert "Traceback" not in res.output and len(res.output.strip().splitlines()) == 1
    res = runner.invoke(main, ["bag", str(bag_run), "--out", str(tmp_path / "b")])
    assert res.exit_code == 1 and "exists" in res.output
    wp = tmp_path / "wp.txt"
    wp.write_text("-5 -5\n-2 -5\n")
    out = tmp_path / "run"
    res = runner.invoke(main, ["drive", str(gentle_scene), "--waypoints", str(wp),
                               "--seconds", "2", "--out", str(out), "--bag"])
    assert res.exit_code == 0, res.output
    msgs, _ = _read_rosbags(out / "bag")
    assert len(msgs["/rover/odom"]) == len(read_tum(out / "odom.tum"))
    before = (out / "gt.tum").read_bytes()
    (out / "gt.tum").write_text("# marker\n" + before.decode())
    res = runner.invoke(main, ["drive", str(gentle_scene), "--waypoints", str(wp),
                               "--seconds", "2", "--out", str(out), "--bag"])
    assert res.exit_code == 1 and "--overwrite" in res.output  # refused before driving
    assert (out / "gt.tum").read_text().startswith("# marker")


def test_stereo_placement_from_run_config_or_refused(stereo_run, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(stereo_run, run, ignore=shutil.ignore_patterns("bag"))
    for side in ("left", "right"):
        path = run / "camera" / side / "intrinsics.json"
        intr = json.loads(path.read_text())
        del intr["baseline_m"]
        path.write_text(json.dumps(intr))
    meta = json.loads((run / "run.json").read_text())
    (meta.get("camera") or {}).pop("stereo_baseline_m", None)  # runs record it since issue 10
    (run / "run.json").write_text(json.dumps(meta))
    with pytest.raises(RuntimeSimError, match="cannot place it"):
        write_bag(run, sensors=["stereo"])
    assert not (run / "bag").exists()
    meta = json.loads((run / "run.json").read_text())
    meta["camera"]["stereo_baseline_m"] = 0.2
    (run / "run.json").write_text(json.dumps(meta))
    msgs, _ = _read_rosbags(write_bag(run, sensors=["stereo"]).path)
    right = msgs["/rover/stereo/right/camera_info"][0][1]
    assert right.p[3] == pytest.approx(-right.k[0] * 0.2)
    (tf_static,) = [m for _, m in msgs["/tf_static"]]
    y = {t.child_frame_id: t.transform.translation.y for t in tf_static.transforms}
    assert y["stereo_left_optical_frame"] == pytest.approx(0.1)
    assert y["stereo_right_optical_frame"] == pytest.approx(-0.1)
    assert "/rover/rgb/image_raw" not in msgs and "/rover/scan" not in msgs


def test_odometry_declares_the_simulated_wheel_noise(bag_msgs, stereo_run):
    """bag_run's wheel encoders carry N(0, 0.05 rad/s) per sample and wheel, nothing else."""
    msgs, _ = bag_msgs
    run = RunLog(stereo_run)
    odom = [m for _, m in msgs["/rover/odom"]]
    tw = np.array([m.twist.covariance for m in odom]).reshape(-1, 6, 6)
    pose = np.array([m.pose.covariance for m in odom]).reshape(-1, 6, 6)
    for k in (1, 2, 3, 4):  # vy vz wx wy: not observed by wheel odometry
        assert np.all(tw[:, k, k] == 1e6)
    for k in (2, 3, 4):  # z roll pitch
        assert np.all(pose[:, k, k] == 1e6)
    # left-right symmetric wheels, steering straight: v is the mean of the six r * rate,
    # so var(v) = r^2 sigma^2 / 6 (independent of the module's Jacobian)
    steer = run.wheels[:, 7:11]
    straight = np.abs(steer).max(axis=1) < 0.005
    assert straight.any()
    expect = run.rover.wheel_radius_m**2 * 0.05**2 / 6
    np.testing.assert_allclose(tw[straight, 0, 0], expect, rtol=1e-4)
    assert np.all(tw[:, 5, 5] > 0) and np.all(tw[:, 0, 0] > 0)
    # dead reckoning from the start: zero at first, then growing in x, y and yaw
    assert np.all(pose[0][np.ix_([0, 1, 5], [0, 1, 5])] == 0)
    for k in (0, 1, 5):
        assert np.all(np.diff(pose[:, k, k]) >= -1e-18) and pose[-1, k, k] > 0
    np.testing.assert_allclose(pose, pose.transpose(0, 2, 1))
    truth = np.array([m.pose.covariance for _, m in msgs["/rover/GT_Trajectory"]])
    assert np.all(truth == 0)
