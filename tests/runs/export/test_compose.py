"""One composition of each ROS message: the bag and the live publisher call the same functions
(:mod:`marsscene.runs.export.compose_state`, :mod:`~marsscene.runs.export.compose_sensors`), and
a run folder's logs replayed sample by sample through the live publisher give the bag's messages
(read back with the independent ``mcap`` + ``mcap-ros2-support`` reader): the same bytes where
both sides do the same arithmetic, and the documented differences only where a live stream
cannot know what the bag knows (the next sample)."""

from __future__ import annotations

import functools
from collections import Counter, defaultdict
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from marsscene.runs.export import bag_data as bd
from marsscene.runs.export import compose_sensors, compose_state
from marsscene.runs.export.bag import write_bag
from marsscene.runs.export.bag_topics import ImageOptions
from marsscene.runs.export.imu_noise import rate_hz
from marsscene.runs.export.sample_messages import SampleMessages
from marsscene.runs.runlog import RunLog, read_image, read_ply

IMAGES = ImageOptions(images="both", depth_cloud=True)
STATE = ("/clock", "/tf", "/rover/cmd_vel", "/rover/odom", "/rover/GT_Trajectory",
         "/rover/joint_states", "/rover/imu_noisy", "/rover/imu")


def _wxyz(q_xyzw: np.ndarray) -> np.ndarray:
    return np.asarray(q_xyzw)[[3, 0, 1, 2]]


def _replay(run: RunLog, sm: SampleMessages) -> dict[tuple[str, int], bytes]:
    """The run's logged samples through the live publisher, one at a time, as a drive hands
    them to its listeners."""
    got: dict[tuple[str, int], bytes] = {}

    def keep(t: float, pairs: list[tuple[str, Any]]) -> None:
        for topic, msg in pairs:
            got[(topic, round(float(t) * 1e9))] = bytes(sm.b.serialize(msg))

    gt, od = run.gt, run.odom
    for i, t in enumerate(od.timestamps_s):
        w = run.wheels[i]
        keep(t, sm.control(t, run.cmd[i, 1], run.cmd[i, 2], w[1:7], w[7:11],
                           (gt.xyz_m[i], _wxyz(gt.quat_xyzw[i])),
                           (od.xyz_m[i], _wxyz(od.quat_xyzw[i]))))
    for noisy, true in zip(run.imu, run.imu_true, strict=True):
        keep(noisy[0], sm.imu(noisy[0], noisy[1:4], noisy[4:7], true[1:4], true[4:7]))
    cams = run.camera_streams()
    for i, t in enumerate(cams[0].stamps_s):
        depth_m = read_image(cams[0].depth_files[i]) / 1000.0
        keep(t, sm.camera(t, i, read_image(cams[0].rgb_files[i]), depth_m))
        keep(t, sm.stereo(t, i, [read_image(c.rgb_files[i]) for c in cams[1:]]))
    for i, (t, file) in enumerate(zip(*run.lidar, strict=True)):
        rec = read_ply(file)
        scan = {"xyz_m": np.stack([rec["x"], rec["y"], rec["z"]], axis=1),
                "intensity": rec["intensity"], "ring": rec["ring"], "t_s": rec["t"] / 1e9}
        keep(t, sm.lidar(t, i, scan))
    return got


def _live(run: RunLog) -> SampleMessages:
    """The live publisher of the run's sensors; the IMU's variances at the rate the bag
    measures from the stamps (a live drive states its configured rate)."""
    cams = run.camera_streams()
    return SampleMessages(run.rover, bd.noise_of_run(run.meta), imu_hz=rate_hz(run.imu[:, 0]),
                          lidar=run.meta["lidar"], camera=cams[0].intrinsics,
                          stereo={c.name: c.intrinsics for c in cams[1:]}, images=IMAGES)


def _bag_messages(bag: Path) -> dict[str, list[tuple[int, bytes, Any]]]:
    """``topic -> [(log time ns, CDR bytes, decoded message)]`` by the mcap reader."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, list[tuple[int, bytes, Any]]] = defaultdict(list)
    with open(next(bag.glob("*.mcap")), "rb") as fh:
        for _, channel, message, decoded in make_reader(
                fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            out[channel.topic].append((message.log_time, bytes(message.data), decoded))
    return out


@pytest.fixture(scope="module")
def replayed(stereo_run: Path, tmp_path_factory: pytest.TempPathFactory):
    bag = write_bag(stereo_run, tmp_path_factory.mktemp("compose") / "bag", images="both",
                    depth_cloud=True).path
    run = RunLog(stereo_run)
    live = _live(run)
    got = _replay(run, live)
    for topic, msg in live.static(float(run.gt.timestamps_s[0])):
        got[(topic, round(float(run.gt.timestamps_s[0]) * 1e9))] = bytes(live.b.serialize(msg))
    return run, got, _bag_messages(bag)


def test_bag_and_live_call_the_one_composition(stereo_run: Path, tmp_path: Path, monkeypatch):
    """A spy on each composing function: writing the bag and publishing live both go through
    it (the control-rate fields once for the whole bag, once per sample live)."""
    calls: Counter[tuple[str, str]] = Counter()
    side = ["bag"]
    for module in (compose_state, compose_sensors):
        for name in module.__all__:
            fn = getattr(module, name)
            if callable(fn) and not isinstance(fn, type):
                def spy(*a: Any, _fn: Any = fn, _name: str = name, **k: Any) -> Any:
                    calls[(side[0], _name)] += 1
                    return _fn(*a, **k)
                monkeypatch.setattr(module, name, spy)

    class Fields(compose_state.ControlFields):
        def __init__(self, *a: Any, **k: Any) -> None:
            calls[(side[0], "ControlFields")] += 1
            super().__init__(*a, **k)

    monkeypatch.setattr(compose_state, "ControlFields", Fields)
    run = RunLog(stereo_run)
    write_bag(stereo_run, tmp_path / "bag", images="both", depth_cloud=True)
    side[0] = "live"
    sm = _live(run)
    sm.static(0.0)
    _replay(run, sm)
    bag = {name for s, name in calls if s == "bag"}
    live = {name for s, name in calls if s == "live"}
    every = {name for m in (compose_state, compose_sensors) for name in m.__all__
             if callable(getattr(m, name)) and not isinstance(getattr(m, name), type)}
    every.add("ControlFields")
    # what calls the others: pinhole_k through camera_info and depth_cloud, on both sides
    assert bag == live == every - {"wheel_soil"}  # no soil in this run
    n = len(run.odom)
    assert calls[("bag", "ControlFields")] == 1 and calls[("live", "ControlFields")] == n
    assert calls[("bag", "odometry")] == calls[("live", "odometry")] == n
    assert calls[("bag", "imu_variances")] == calls[("live", "imu_variances")] == 1


def test_replayed_live_messages_are_the_bags_bytes(replayed):
    """Clock, TF (map -> odom from ground truth, odom -> base_link), command, both IMU topics,
    the latched ones and every camera, stereo and LiDAR topic: the same bytes, every message."""
    _, live, bag = replayed
    odometry = {"/rover/odom", "/rover/GT_Trajectory", "/rover/joint_states"}
    assert set(STATE) <= set(bag) and len(bag) == 25
    for topic in set(bag) - odometry:
        assert len(bag[topic]) >= (1 if topic in ("/tf_static", "/rover/robot_description")
                                   else 10), topic
        for k, (ns, raw, msg) in enumerate(bag[topic]):
            if topic == "/tf" and k == 0:  # one row alone: scipy's single-rotation apply
                a = _decode(live[(topic, ns)], "tf2_msgs/msg/TFMessage")  # rounds otherwise
                np.testing.assert_allclose(_vec(a.transforms[0].transform.translation),
                                           _vec(msg.transforms[0].transform.translation),
                                           rtol=0, atol=4e-16)
                continue
            assert live[(topic, ns)] == raw, (topic, ns)
    cov = bag["/rover/imu_noisy"][0][2].angular_velocity_covariance
    assert cov[0] > 0 and cov[0] == cov[4] == cov[8]  # density^2 * rate, the noisy run's


@functools.cache
def _store() -> Any:
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def _decode(raw: bytes, msgtype: str) -> Any:
    return _store().deserialize_cdr(raw, msgtype)


def _vec(v: Any) -> np.ndarray:
    return np.array([v.x, v.y, v.z])


def test_replayed_odometry_is_the_bags(replayed):
    """``/rover/odom``: the pose and twist covariance exact; the pose covariance, a running sum
    live and a cumulative sum in the bag, to rounding; the twist to rounding (one batched
    solve for the bag, one per sample live)."""
    _, live, bag = replayed
    rows = bag["/rover/odom"]
    for ns, _, b in rows:
        a = _decode(live[("/rover/odom", ns)], "nav_msgs/msg/Odometry")
        pa, pb = a.pose.pose, b.pose.pose
        assert (pa.position.x, pa.position.y, pa.position.z, pa.orientation.w) == (
            pb.position.x, pb.position.y, pb.position.z, pb.orientation.w)
        np.testing.assert_array_equal(a.twist.covariance, b.twist.covariance)
        np.testing.assert_allclose(a.pose.covariance, b.pose.covariance, rtol=1e-12, atol=0)
        np.testing.assert_allclose([a.twist.twist.linear.x, a.twist.twist.angular.z],
                                   [b.twist.twist.linear.x, b.twist.twist.angular.z],
                                   rtol=1e-14, atol=1e-17)
    last = np.array(rows[-1][2].pose.covariance).reshape(6, 6)
    assert last[0, 0] > 0 and last[5, 5] > 0 and last[2, 2] == bd.UNOBSERVED_VAR


def test_replayed_rates_differ_only_where_the_bag_knows_the_next_sample(replayed):
    """Ground-truth twist and steering rates: the bag takes central differences, the live side
    backward ones (it has no next sample). At the last sample both have the same samples and
    agree; at the first the live side has no previous one (zero) and the bag a forward one."""
    _, live, bag = replayed
    gt = bag["/rover/GT_Trajectory"]
    joints = bag["/rover/joint_states"]

    def pair(topic: str, rows: list, k: int, msgtype: str) -> tuple[Any, Any]:
        return _decode(live[(topic, rows[k][0])], msgtype), rows[k][2]

    for k in range(len(gt)):
        a, b = pair("/rover/GT_Trajectory", gt, k, "nav_msgs/msg/Odometry")
        assert _vec(a.pose.pose.position).tolist() == _vec(b.pose.pose.position).tolist()
        ja, jb = pair("/rover/joint_states", joints, k, "sensor_msgs/msg/JointState")
        np.testing.assert_array_equal(ja.position, jb.position)  # angles: the same sums
        np.testing.assert_array_equal(ja.velocity[:6], jb.velocity[:6])  # measured rates
    a, b = pair("/rover/GT_Trajectory", gt, -1, "nav_msgs/msg/Odometry")
    for f in ("linear", "angular"):
        np.testing.assert_allclose(_vec(getattr(a.twist.twist, f)),
                                   _vec(getattr(b.twist.twist, f)), rtol=1e-12, atol=1e-15)
    ja, jb = pair("/rover/joint_states", joints, -1, "sensor_msgs/msg/JointState")
    np.testing.assert_allclose(ja.velocity, jb.velocity, rtol=1e-12, atol=1e-15)
    a, b = pair("/rover/GT_Trajectory", gt, 0, "nav_msgs/msg/Odometry")
    assert not np.any(_vec(a.twist.twist.linear)) and np.any(_vec(b.twist.twist.linear))
    # inside, the bag's central difference lies between the live side's two backward ones
    lin_x = np.array([_decode(live[("/rover/GT_Trajectory", ns)], "nav_msgs/msg/Odometry")
                      .twist.twist.linear.x for ns, _, _ in gt])
    bag_x = np.array([m.twist.twist.linear.x for _, _, m in gt])
    mid = 0.5 * (lin_x[1:-1] + lin_x[2:])
    assert np.median(np.abs(bag_x[1:-1] - mid)) < 0.1 * np.median(np.abs(bag_x[1:-1]))


def test_carry_steps_give_the_whole_drives_integrals(bag_run: Path):
    """The live carry (joint angles, pose covariance) stepped over a drive ends where the
    whole-drive fields do."""
    run = RunLog(bag_run)
    rover, noise = run.rover, bd.noise_of_run(run.meta)
    whole = compose_state.ControlFields(compose_state.ControlRows.of_run(run), rover, noise)
    carry, every = compose_state.Carry(), compose_state.ControlRows.of_run(run)
    for i in range(len(run.odom)):
        s = slice(max(i - 1, 0), i + 1)
        rows = compose_state.ControlRows(*(getattr(every, k.name)[s] for k in fields(every)))
        f = compose_state.ControlFields(rows, rover, noise, carry)
        assert f.t_s.shape == (1,) and f.t_s[0] == whole.t_s[i]
    assert np.any(f.joint_position[0, :6] != 0)
    np.testing.assert_array_equal(f.joint_position[0], whole.joint_position[-1])
    np.testing.assert_allclose(f.pose_cov[0], whole.pose_cov[-1], rtol=1e-12)
    assert f.pose_cov[0, 0] > 0


def test_stereo_projection_and_pinhole():
    intr = {"fx": 200.0, "fy": 201.0, "cx": 40.0, "cy": 30.0, "baseline_m": 0.3}
    assert compose_sensors.projection_tx("right", intr) == -60.0
    assert compose_sensors.projection_tx("left", intr) == 0.0
    assert compose_sensors.projection_tx("right", {"fx": 100.0, "stereo_baseline_m": 0.5}) == -50
    np.testing.assert_array_equal(compose_sensors.pinhole_k(intr),
                                  [[200.0, 0.0, 40.0], [0.0, 201.0, 30.0], [0.0, 0.0, 1.0]])
