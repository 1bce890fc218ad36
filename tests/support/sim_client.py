"""An independent ``simulation_interfaces`` client in ``rmw_cyclonedds``'s request/reply form.

Written from ``rmw_cyclonedds_cpp``'s wire form, not from marsscene's server: topics
``rq/<service>Request`` / ``rr/<service>Reply``, types ``<pkg>::srv::dds_::<Srv>_Request_`` /
``_Response_``, each sample the CDR encapsulation, a ``uint64`` client handle and an ``int64``
sequence number, then the plain CDR payload; ``clientid=`` in the endpoints' USER_DATA; an
action as its ``_action/send_goal`` / ``get_result`` services and ``feedback`` topic. The types
come from the interface's own definitions (the ``.msg`` / ``.srv`` / ``.action`` files),
parsed here with ``rosbags``. Imports nothing from marsscene; loopback only.

``python sim_client.py DOMAIN [--namespace /]``: the calls of the service tests, then
``SetSimulationState(QUITTING)`` (the session ends); JSON on stdout.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import struct
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cyclonedds._clayer import ddspy_write
from cyclonedds.idl import annotations as ann
from cyclonedds.idl import make_idl_struct
from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from dds_peer import MASK, STORE, Peer, T, idl, stamp_s, take, twist
from rosbags.typesys import get_types_from_msg

DEFS = Path(__file__).resolve().parents[2] / "marsscene" / "ros2" / "interfaces" / \
    "simulation_interfaces"
P = "simulation_interfaces"
_ = MASK


def _load() -> None:
    """Register the interface's types: ``X.srv`` -> ``X_Request`` / ``X_Response``."""
    texts: dict[str, str] = {}
    for f in (DEFS / "msg").glob("*.msg"):
        texts[f"{P}/msg/{f.stem}"] = f.read_text()
    for f in (DEFS / "srv").glob("*.srv"):
        req, rep = f.read_text().split("\n---\n")
        texts[f"{P}/srv/{f.stem}_Request"], texts[f"{P}/srv/{f.stem}_Response"] = req, rep
    goal, result, fb = (DEFS / "action" / "SimulateSteps.action").read_text().split("\n---\n")
    a = f"{P}/action/SimulateSteps"
    texts.update({f"{a}_Goal": goal, f"{a}_Result": result, f"{a}_Feedback": fb,
                  f"{a}_SendGoal_Request": "unique_identifier_msgs/UUID goal_id\n"
                                           "SimulateSteps_Goal goal\n",
                  f"{a}_SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
                  f"{a}_GetResult_Request": "unique_identifier_msgs/UUID goal_id\n",
                  f"{a}_GetResult_Response": "int8 status\nSimulateSteps_Result result\n",
                  f"{a}_FeedbackMessage": "unique_identifier_msgs/UUID goal_id\n"
                                          "SimulateSteps_Feedback feedback\n"})
    fake = {f"{n.split('/')[0]}/msg/{n.split('/')[2]}": n for n in texts}
    types: dict[str, Any] = {}

    def fix(d: Any) -> Any:
        if d[0] == 2:
            return (2, fake.get(d[1], d[1]))
        if d[0] in (3, 4):
            return (d[0], (fix(d[1][0]), d[1][1]))
        return d

    for name, text in texts.items():
        pkg, _, tail = name.split("/")
        for k, (c, fields) in get_types_from_msg(text, f"{pkg}/msg/{tail}").items():
            types[fake.get(k, k)] = (c, [(f, fix(d)) for f, d in fields])
    STORE.register(types)


def _header_type(msgtype: str) -> Any:
    base = idl(msgtype)
    pkg, kind, name = msgtype.split("/")
    members = {"client_guid": T.uint64, "sequence_number": T.int64,
               **dict(base.__annotations__)}
    return ann.final(make_idl_struct(f"{name}_", f"{pkg}::{kind}::dds_::{name}_", members))


class Client:
    """One ``rmw_cyclonedds``-style client of ``service`` (type ``srvtype``)."""

    seq = 0

    def __init__(self, peer: Peer, service: str, srvtype: str) -> None:
        self.req_t, self.rep_t = f"{srvtype}_Request", f"{srvtype}_Response"
        ud = f"clientid={id(self) & 0xffffffff:x};".encode()
        qos = Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(10))
        self.w = DataWriter(peer.dp, Topic(peer.dp, f"rq{service}Request",
                                           _header_type(self.req_t)),
                            qos + Qos(Policy.Userdata(ud + b"typehash=" +
                                      STORE.hash_rihs01(self.req_t).encode() + b";")))
        self.r = DataReader(peer.dp, Topic(peer.dp, f"rr{service}Reply",
                                           _header_type(self.rep_t)),
                            qos + Qos(Policy.Userdata(ud)))
        self.handle = id(self) & 0xffffffffffff  # any 64-bit id unique to this client

    def call(self, timeout_s: float = 30.0, **fields: Any) -> Any:
        t0 = time.monotonic()
        while self.w.get_publication_matched_status().current_count == 0 or \
                self.r.get_subscription_matched_status().current_count == 0:
            if time.monotonic() - t0 > timeout_s:
                raise SystemExit(f"no service behind {self.req_t}")
            time.sleep(0.01)
        Client.seq += 1
        cdr = bytes(STORE.serialize_cdr(STORE.types[self.req_t](**fields), self.req_t))
        wire = cdr[:4] + struct.pack("<Qq", self.handle, Client.seq) + cdr[4:]
        ddspy_write(self.w._ref, wire + b"\0" * (-len(wire) % 4))
        while time.monotonic() - t0 < timeout_s:
            for raw in take(self.r):
                h, s = struct.unpack("<Qq", raw[4:20])
                if (h, s) == (self.handle, Client.seq):
                    return STORE.deserialize_cdr(raw[:4] + raw[20:], self.rep_t)
            time.sleep(0.0005)
        raise SystemExit(f"no reply from {self.req_t}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("domain", type=int)
    ap.add_argument("--namespace", default="")
    args = ap.parse_args()
    _load()
    peer, ns, ty = Peer(args.domain), args.namespace.rstrip("/"), STORE.types
    clock = peer.reader("/clock", "rosgraph_msgs/msg/Clock", depth=1)
    odom = peer.reader("/rover/odom", "nav_msgs/msg/Odometry", reliable=True)
    scans = peer.reader("/rover/lidar/points", "sensor_msgs/msg/PointCloud2", reliable=True,
                        depth=50)
    cmd = peer.writer("/cmd_vel", "geometry_msgs/msg/Twist")
    sha = {"odom": hashlib.sha256(), "lidar": hashlib.sha256()}
    n = {"odom": 0, "lidar": 0}
    now = [-math.inf]

    def drain() -> None:
        for raw in take(clock):
            now[0] = stamp_s(STORE.deserialize_cdr(raw, "rosgraph_msgs/msg/Clock"))
        for key, r in (("odom", odom), ("lidar", scans)):
            for raw in take(r):
                sha[key].update(raw)
                n[key] += 1

    def srv(name: str, srvtype: str) -> Client:
        return Client(peer, f"{ns}/{name}", f"{P}/srv/{srvtype}")

    def state(s: int) -> Any:
        return ty[f"{P}/msg/SimulationState"](state=s)

    out: dict[str, Any] = {}
    feats = srv("get_simulator_features", "GetSimulatorFeatures").call()
    out["features"] = sorted(int(f) for f in feats.features.features)
    setstate = srv("set_simulation_state", "SetSimulationState")
    out["pause"] = int(setstate.call(state=state(2)).result.result)
    out["state"] = int(srv("get_simulation_state", "GetSimulationState").call(
        structure_needs_at_least_one_member=0).state.state)
    get = srv("get_entity_state", "GetEntityState")
    origin = get.call(entity="rover").state.pose.position
    out["origin_xy"] = [origin.x, origin.y]
    time.sleep(0.3)
    drain()
    before = (now[0], n["odom"])
    time.sleep(0.5)
    drain()
    out["paused_clock_s"] = [before[0], now[0]]
    out["paused_odom"] = n["odom"] - before[1]
    for _ in range(5):
        send = twist(0.4, 0.1)
        ddspy_write(cmd._ref, bytes(STORE.serialize_cdr(send, send.__msgtype__)))
    time.sleep(0.2)
    step = srv("step_simulation", "StepSimulation")
    drain()
    t0, o0 = now[0], n["odom"]
    w0 = time.perf_counter()
    out["step50"] = int(step.call(steps=50).result.result)
    out["step50_wall_s"] = time.perf_counter() - w0
    time.sleep(0.3)
    drain()
    out["step50_clock_s"], out["step50_odom"] = now[0] - t0, n["odom"] - o0
    rtt = []
    for _ in range(10):
        w0 = time.perf_counter()
        step.call(steps=1)
        rtt.append(time.perf_counter() - w0)
    out["step1_rtt_s"] = rtt
    start = get.call(entity="rover").state.pose.position
    out["start_xy"] = [start.x, start.y]
    pose = ty["geometry_msgs/msg/Pose"](
        position=ty["geometry_msgs/msg/Point"](x=start.x + 2.0, y=start.y - 1.0, z=0.0),
        orientation=ty["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(0.4),
                                                       w=math.cos(0.4)))
    es = ty[f"{P}/msg/EntityState"](
        header=ty["std_msgs/msg/Header"](stamp=ty["builtin_interfaces/msg/Time"](sec=0,
                                                                                nanosec=0),
                                         frame_id=""),
        pose=pose, twist=twist(0.0, 0.0),
        acceleration=ty["geometry_msgs/msg/Accel"](linear=twist(0, 0).linear,
                                                   angular=twist(0, 0).angular))
    out["set"] = int(srv("set_entity_state", "SetEntityState").call(
        entity="rover", state=es, set_pose=True, set_twist=False,
        set_acceleration=False).result.result)
    got = get.call(entity="rover").state.pose
    q = got.orientation
    out["got_xy_yaw"] = [got.position.x, got.position.y,
                         math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2))]
    again = get.call(entity="rover").state.pose.position
    out["got_again_xy"] = [again.x, again.y]
    out["missing"] = int(get.call(entity="nobody").result.result)
    out["reset"] = int(srv("reset_simulation", "ResetSimulation").call(scope=0).result.result)
    back = get.call(entity="rover").state.pose.position
    out["reset_xy"] = [back.x, back.y]
    ent = srv("get_entities", "GetEntities").call(filters=ty[f"{P}/msg/EntityFilters"](
        filter="", categories=[], tags=ty[f"{P}/msg/TagsFilter"](tags=[], filter_mode=0),
        bounds=ty[f"{P}/msg/Bounds"](type=0, points=[])))
    out["entities"] = list(ent.entities)
    out["info"] = int(srv("get_entity_info", "GetEntityInfo").call(
        entity="rover").info.category.category)
    res = ty[f"{P}/msg/Resource"](uri="model://x", resource_string="")
    ps = ty["geometry_msgs/msg/PoseStamped"](header=es.header, pose=pose)
    out["not_supported"] = [
        int(srv("get_spawnables", "GetSpawnables").call(sources=[]).result.result),
        int(srv("spawn_entity", "SpawnEntity").call(
            name="x", allow_renaming=False, entity_resource=res, entity_namespace="",
            initial_pose=ps).result.result),
        int(srv("delete_entity", "DeleteEntity").call(entity="rover").result.result)]
    act = f"{ns}/simulate_steps/_action"
    a = f"{P}/action/SimulateSteps"
    goal = Client(peer, f"{act}/send_goal", f"{a}_SendGoal")
    result = Client(peer, f"{act}/get_result", f"{a}_GetResult")
    feedback = peer.reader(f"{act}/feedback", f"{a}_FeedbackMessage", reliable=True, depth=100)
    import numpy as np

    gid = ty["unique_identifier_msgs/msg/UUID"](uuid=np.arange(16, dtype=np.uint8))
    drain()
    t0 = now[0]
    w0 = time.perf_counter()
    acc = goal.call(goal_id=gid, goal=ty[f"{a}_Goal"](steps=10))
    fin = result.call(goal_id=gid)
    out["action_wall_s"] = time.perf_counter() - w0
    out["action"] = [bool(acc.accepted), int(fin.status), int(fin.result.result.result)]
    time.sleep(0.3)
    drain()
    out["action_clock_s"] = now[0] - t0
    out["feedback"] = [int(STORE.deserialize_cdr(r, f"{a}_FeedbackMessage").feedback
                           .completed_steps) for r in take(feedback)]
    out["play_step"] = int(step.call(steps=1).result.result)  # still paused: OK
    out["sha256"] = {k: h.hexdigest() for k, h in sha.items()}
    out["counts"] = dict(n)
    setstate.call(state=state(3))
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()
