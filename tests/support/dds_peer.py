"""An independent ROS 2 peer over DDS for tests and benchmarks: plain ``cyclonedds`` + ``rosbags``.

It imports nothing from marsscene (run it as a script: ``python dds_peer.py MODE ...``), so it
checks the live rover the way a foreign ROS 2 node would: its own DDS types made from the
``rosbags`` typestore (``<pkg>::msg::dds_::<Type>_``, ``@final``), topics ``rt/<name>``,
loopback only (127.0.0.1, no multicast, unicast discovery). Modes (JSON on stdout):

* ``listen DOMAIN SECONDS TOPICS_JSON``: take every sample of the topics (``{name: [msgtype,
  reliable, transient_local]}``), decode each with rosbags; counts, stamps, sizes, and the
  SHA-256 of each topic's first payload, the frame ids seen (``--dump DIR`` writes the raw
  payloads; ``--until-idle S`` stops S seconds after the last sample of a volatile topic);
* ``cmd DOMAIN SECONDS V W [--stamped] [--hz 20] [--topic /cmd_vel]``: publish the command
  on the topic for SECONDS;
* ``latency DOMAIN V [--repeats 5]``: command ``V`` from rest, wall time until ``/rover/odom``
  reports ``|v| >= V / 2``, then stop and wait until it stops;
* ``lockstep DOMAIN STEPS DT V W [--sleep-per-scan S]``: drive a lockstep session
  (``pace="lockstep"``, one control step of DT s a command): send a command, take every
  sample until ``/clock`` reaches the step's end, sleeping S s after each LiDAR scan (a slow
  subscriber), STEPS times, then one stop command; counts and the SHA-256 of the odometry and
  LiDAR payloads, in order;
* ``goto DOMAIN DX DY [--stop-m 3.0]``: a DDS-only closed loop: drive towards the point ``(DX,
  DY)`` m from the start on ``/rover/odom`` and stop short of the first obstacle that
  ``/rover/lidar/points`` shows ahead in the rover's path (a step of 0.4 m within 1.6 m of the
  path's centre line, :func:`nearest_obstacle_m`).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from cyclonedds._clayer import ddspy_take, ddspy_write
from cyclonedds.core import InstanceState, SampleState, ViewState
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.idl import annotations as ann
from cyclonedds.idl import make_idl_struct
from cyclonedds.idl import types as _types
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from rosbags.typesys import Stores, get_typestore

STORE: Any = get_typestore(Stores.ROS2_JAZZY)
T: Any = _types
_BASE = {"bool": bool, "int8": T.int8, "uint8": T.uint8, "byte": T.byte, "char": T.uint8,
         "int16": T.int16, "uint16": T.uint16, "int32": T.int32, "uint32": T.uint32,
         "int64": T.int64, "uint64": T.uint64, "float32": T.float32, "float64": T.float64}
_CACHE: dict[str, Any] = {}
LOOPBACK = ('<CycloneDDS><Domain Id="any"><General><Interfaces>'
            '<NetworkInterface address="127.0.0.1"/></Interfaces>'
            "<AllowMulticast>false</AllowMulticast></General><Discovery>"
            "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>31"
            "</MaxAutoParticipantIndex><Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
            "</Domain></CycloneDDS>")
MASK = SampleState.Any | ViewState.Any | InstanceState.Any


def idl(msgtype: str) -> Any:
    """The DDS type of a ROS 2 message, from its rosbags definition."""
    if msgtype not in _CACHE:
        pkg, kind, name = msgtype.split("/")
        members = {n: _field(*spec) for n, spec in STORE.fielddefs[msgtype][1]}
        members = members or {"structure_needs_at_least_one_member": T.uint8}
        _CACHE[msgtype] = ann.final(make_idl_struct(f"{name}_", f"{pkg}::{kind}::dds_::{name}_",
                                                    members))
    return _CACHE[msgtype]


def _field(node: int, spec: Any) -> Any:
    if node == 1:
        return (T.bounded_str[spec[1]] if spec[1] else str) if spec[0] == "string" \
            else _BASE[spec[0]]
    if node == 2:
        return idl(spec)
    (sub_node, sub_spec), size = spec
    sub = _field(sub_node, sub_spec)
    if node == 3:
        return T.array[sub, size]
    return T.sequence[sub, size] if size else T.sequence[sub]


class Peer:
    """One participant on ``domain``, loopback only."""

    def __init__(self, domain: int) -> None:
        self.domain = Domain(domain, LOOPBACK)
        self.dp = DomainParticipant(domain)

    def reader(self, topic: str, msgtype: str, reliable: bool = False,
               transient_local: bool = False, depth: int = 100) -> Any:
        qos = Qos(Policy.Reliability.Reliable(100_000_000) if reliable
                  else Policy.Reliability.BestEffort,
                  Policy.Durability.TransientLocal if transient_local
                  else Policy.Durability.Volatile, Policy.History.KeepLast(depth))
        name = "rt" + topic if topic.startswith("/") else topic  # ros_discovery_info: as is
        return DataReader(self.dp, Topic(self.dp, name, idl(msgtype)), qos)

    def writer(self, topic: str, msgtype: str) -> Any:
        qos = Qos(Policy.Reliability.Reliable(100_000_000), Policy.History.KeepLast(10))
        return DataWriter(self.dp, Topic(self.dp, "rt" + topic, idl(msgtype)), qos)


def take(reader: Any) -> list[bytes]:
    return [bytes(d) for d, info in ddspy_take(reader._ref, MASK, 256) if info.valid_data]


def send(writer: Any, msg: Any) -> None:
    data = bytes(STORE.serialize_cdr(msg, msg.__msgtype__))
    ddspy_write(writer._ref, data + b"\0" * (-len(data) % 4))


def twist(v: float, w: float, stamped: bool = False, t_s: float = 0.0) -> Any:
    ty = STORE.types
    tw = ty["geometry_msgs/msg/Twist"](linear=ty["geometry_msgs/msg/Vector3"](x=v, y=0.0, z=0.0),
                                       angular=ty["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=w))
    if not stamped:
        return tw
    ns = round(t_s * 1e9)
    hdr = ty["std_msgs/msg/Header"](stamp=ty["builtin_interfaces/msg/Time"](
        sec=ns // 10**9, nanosec=ns % 10**9), frame_id="base_link")
    return ty["geometry_msgs/msg/TwistStamped"](header=hdr, twist=tw)


def stamp_s(msg: Any) -> float | None:
    if getattr(msg, "transforms", None):  # tf2_msgs/TFMessage
        msg = msg.transforms[0]
    st = getattr(getattr(msg, "header", None), "stamp", None) or getattr(msg, "clock", None)
    return None if st is None else st.sec + st.nanosec * 1e-9


def listen(peer: Peer, seconds: float, topics: dict[str, list[Any]],
           dump: Path | None, until_idle_s: float = math.inf) -> dict[str, Any]:
    readers = {n: (spec[0], peer.reader(n, spec[0], bool(spec[1]), bool(spec[2])))
               for n, spec in topics.items()}
    got: dict[str, dict[str, Any]] = {n: {"n": 0, "stamps": [], "bytes": 0, "sha256": None}
                                      for n in topics}
    t0, last = time.monotonic(), math.inf  # last: the newest sample of a volatile topic
    while time.monotonic() - t0 < seconds and time.monotonic() - last < until_idle_s:
        for name, (mt, r) in readers.items():
            for data in take(r):
                if not topics[name][2]:
                    last = time.monotonic()
                msg = STORE.deserialize_cdr(data, mt)  # raises on a bad payload
                g = got[name]
                if g["n"] == 0:
                    g["sha256"] = hashlib.sha256(data).hexdigest()
                    if dump is not None:
                        (dump / (name.strip("/").replace("/", "_") + ".cdr")).write_bytes(data)
                g["n"] += 1
                g["bytes"] = len(data)
                g["stamps"].append(stamp_s(msg))
                g["frames"] = sorted(set(map(tuple, g.get("frames", []))) | _frames(msg))
                for node in getattr(msg, "node_entities_info_seq", ()):  # ros_discovery_info
                    g["nodes"] = [*g.get("nodes", []), [
                        node.node_namespace, node.node_name, len(node.reader_gid_seq),
                        len(node.writer_gid_seq)]]
        time.sleep(0.002)
    return got


def _frames(msg: Any) -> set[tuple[str, str]]:
    """A message's ``(frame_id, child_frame_id)`` pairs: each transform's of a ``TFMessage``,
    else its header's (child ``""`` where it has none)."""
    items = getattr(msg, "transforms", None) or [msg]
    return {(m.header.frame_id, getattr(m, "child_frame_id", "")) for m in items
            if hasattr(m, "header")}


def latency(peer: Peer, v: float, repeats: int) -> dict[str, Any]:
    odom, cmd = peer.reader("/rover/odom", "nav_msgs/msg/Odometry", reliable=True), \
        peer.writer("/cmd_vel", "geometry_msgs/msg/Twist")
    out = []
    deadline = time.monotonic() + 60.0
    while not take(odom) and time.monotonic() < deadline:  # the rover is up
        time.sleep(0.05)
    for _ in range(repeats):
        t0, moving = time.monotonic(), None
        while moving is None and time.monotonic() - t0 < 10.0:
            send(cmd, twist(v, 0.0))
            for data in take(odom):
                if abs(STORE.deserialize_cdr(data, "nav_msgs/msg/Odometry").twist.twist.linear.x) \
                        >= 0.5 * abs(v):
                    moving = time.monotonic() - t0
            time.sleep(0.001)
        out.append(moving)
        t1 = time.monotonic()
        while time.monotonic() - t1 < 10.0:  # stop, and wait until it stands
            send(cmd, twist(0.0, 0.0))
            rows = [STORE.deserialize_cdr(d, "nav_msgs/msg/Odometry") for d in take(odom)]
            if rows and abs(rows[-1].twist.twist.linear.x) < 0.01:
                break
            time.sleep(0.02)
    return {"latency_s": out}


def nearest_obstacle_m(pts: Any, half_width_m: float = 1.6, step_m: float = 0.4,
                       cell_m: float = 0.5) -> float:
    """Distance ahead (LiDAR x) of the nearest obstacle in the rover's path: points binned into
    ``cell_m`` cells; a cell in the path (``|y| < half_width_m``) whose highest point stands
    ``step_m`` above the lowest point of its 3 x 3 neighbourhood (the local ground) is one."""
    x, y, z = pts["x"], pts["y"], pts["z"]
    keep = (x > 0.5) & (x < 30.0) & (np.abs(y) < half_width_m + 2 * cell_m) & np.isfinite(z)
    i = np.floor(x[keep] / cell_m).astype(int)
    j = np.floor((y[keep] + half_width_m + 2 * cell_m) / cell_m).astype(int)
    shape = (int(30.0 / cell_m) + 2, int(2 * (half_width_m + 2 * cell_m) / cell_m) + 2)
    lo, hi = np.full(shape, np.inf), np.full(shape, -np.inf)
    np.minimum.at(lo, (i, j), z[keep])
    np.maximum.at(hi, (i, j), z[keep])
    pad = np.pad(lo, 1, constant_values=np.inf)
    ground = np.min([pad[a:a + shape[0], b:b + shape[1]] for a in range(3) for b in range(3)],
                    axis=0)
    cols = np.arange(shape[1]) * cell_m - half_width_m - 2 * cell_m + cell_m / 2
    in_path = np.abs(cols) < half_width_m
    hit = (hi - ground > step_m) & np.isfinite(ground) & in_path[None, :]
    rows = np.nonzero(hit.any(axis=1))[0]
    return float(rows[0] * cell_m) if len(rows) else math.inf


def goto(peer: Peer, dx: float, dy: float, stop_m: float, seconds: float) -> dict[str, Any]:
    """Drive to (dx, dy) from the start on odometry; stop before an obstacle in the cloud."""
    odom = peer.reader("/rover/odom", "nav_msgs/msg/Odometry", reliable=True)
    cloud = peer.reader("/rover/lidar/points", "sensor_msgs/msg/PointCloud2", depth=2)
    cmd = peer.writer("/cmd_vel", "geometry_msgs/msg/Twist")
    start = pose = None
    blocked_at, reason, t0 = None, "timeout", time.monotonic()
    while time.monotonic() - t0 < seconds:
        for data in take(odom):
            m = STORE.deserialize_cdr(data, "nav_msgs/msg/Odometry").pose.pose
            q = m.orientation
            pose = (m.position.x, m.position.y,
                    math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2)))
            start = start or pose
        for data in take(cloud)[-1:]:
            pc = STORE.deserialize_cdr(data, "sensor_msgs/msg/PointCloud2")
            kinds = {7: "<f4", 6: "<u4", 4: "<u2", 2: "u1"}  # PointField datatypes
            layout: Any = {"names": [f.name for f in pc.fields],
                           "formats": [kinds[f.datatype] for f in pc.fields],
                           "offsets": [f.offset for f in pc.fields], "itemsize": pc.point_step}
            pts: Any = np.frombuffer(pc.data.tobytes(), dtype=np.dtype(layout))
            near = nearest_obstacle_m(pts)
            if near < stop_m:
                blocked_at, reason = near, "obstacle"
        if start is None or pose is None:
            time.sleep(0.01)
            continue
        gx, gy = start[0] + dx, start[1] + dy
        dist = math.hypot(gx - pose[0], gy - pose[1])
        if reason == "obstacle" or dist < 0.5:
            reason = "obstacle" if reason == "obstacle" else "goal"
            for _ in range(20):
                send(cmd, twist(0.0, 0.0))
                time.sleep(0.02)
            break
        err = math.atan2(gy - pose[1], gx - pose[0]) - pose[2]
        err = math.atan2(math.sin(err), math.cos(err))
        send(cmd, twist(0.5 if abs(err) < 0.3 else 0.0, max(-0.2, min(0.2, 1.0 * err))))
        time.sleep(0.02)
    assert start is not None and pose is not None, "no odometry received"
    return {"reason": reason, "obstacle_m": blocked_at, "start": start, "end": pose,
            "travelled_m": math.hypot(pose[0] - start[0], pose[1] - start[1])}


def lockstep(peer: Peer, steps: int, dt_s: float, v: float, w: float,
             sleep_per_scan_s: float) -> dict[str, Any]:
    clock = peer.reader("/clock", "rosgraph_msgs/msg/Clock", depth=1)
    odom = peer.reader("/rover/odom", "nav_msgs/msg/Odometry", reliable=True)
    scans = peer.reader("/rover/lidar/points", "sensor_msgs/msg/PointCloud2", reliable=True,
                        depth=10)
    cmd = peer.writer("/cmd_vel", "geometry_msgs/msg/Twist")
    hashes = {"odom": hashlib.sha256(), "lidar": hashlib.sha256()}
    counts = {"odom": 0, "lidar": 0}
    now = [-math.inf]

    def pump(until_s: float, limit_s: float = 60.0) -> None:
        t0 = time.monotonic()
        while now[0] < until_s - 1e-6:
            if time.monotonic() - t0 > limit_s:
                raise SystemExit(f"no /clock of {until_s:.3f} s (last {now[0]:.3f} s)")
            for raw in take(clock):
                now[0] = max(now[0], stamp_s(STORE.deserialize_cdr(raw, "rosgraph_msgs/msg/Clock")))
            for key, reader in (("odom", odom), ("lidar", scans)):
                for raw in take(reader):
                    hashes[key].update(raw)
                    counts[key] += 1
                    if key == "lidar":
                        time.sleep(sleep_per_scan_s)
            time.sleep(0.0005)

    pump(0.0)  # the session waits at its start
    start, t0 = now[0], time.monotonic()
    for i in range(steps):
        send(cmd, twist(v, w))
        pump(start + (i + 1) * dt_s)
    wall = time.monotonic() - t0
    send(cmd, twist(0.0, 0.0))  # the session's last step
    try:
        pump(math.inf, limit_s=1.0)  # its samples (the session then ends: no /clock)
    except SystemExit:
        pass
    return {"steps": steps, "wall_s": wall, "counts": counts,
            "sha256": {k: h.hexdigest() for k, h in hashes.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="mode", required=True)
    a = sub.add_parser("listen")
    a.add_argument("domain", type=int)
    a.add_argument("seconds", type=float)
    a.add_argument("topics")
    a.add_argument("--dump", type=Path)
    a.add_argument("--until-idle", type=float, default=math.inf,
                   help="stop this many seconds after the last sample")
    c = sub.add_parser("cmd")
    for name, ty in (("domain", int), ("seconds", float), ("v", float), ("w", float)):
        c.add_argument(name, type=ty)
    c.add_argument("--stamped", action="store_true")
    c.add_argument("--hz", type=float, default=20.0)
    c.add_argument("--topic", default="/cmd_vel")
    la = sub.add_parser("latency")
    la.add_argument("domain", type=int)
    la.add_argument("v", type=float)
    la.add_argument("--repeats", type=int, default=5)
    ls = sub.add_parser("lockstep")
    for name, ty in (("domain", int), ("steps", int), ("dt", float), ("v", float),
                     ("w", float)):
        ls.add_argument(name, type=ty)
    ls.add_argument("--sleep-per-scan", type=float, default=0.0)
    g = sub.add_parser("goto")
    for name, ty in (("domain", int), ("dx", float), ("dy", float)):
        g.add_argument(name, type=ty)
    g.add_argument("--stop-m", type=float, default=3.0)
    g.add_argument("--seconds", type=float, default=120.0)
    args = ap.parse_args()
    peer = Peer(args.domain)
    if args.mode == "listen":
        out: Any = listen(peer, args.seconds, json.loads(args.topics), args.dump,
                          args.until_idle)
    elif args.mode == "cmd":
        w = peer.writer(args.topic, "geometry_msgs/msg/TwistStamped" if args.stamped
                        else "geometry_msgs/msg/Twist")
        t0, n = time.monotonic(), 0
        while time.monotonic() - t0 < args.seconds:
            send(w, twist(args.v, args.w, args.stamped, time.time()))
            n += 1
            time.sleep(1.0 / args.hz)
        out = {"sent": n}
    elif args.mode == "latency":
        out = latency(peer, args.v, args.repeats)
    elif args.mode == "lockstep":
        out = lockstep(peer, args.steps, args.dt, args.v, args.w, args.sleep_per_scan)
    else:
        out = goto(peer, args.dx, args.dy, args.stop_m, args.seconds)
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()
