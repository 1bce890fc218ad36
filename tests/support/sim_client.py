"""An independent ``simulation_interfaces`` client in ``rmw_cyclonedds``'s request/reply form.

Written from ``rmw_cyclonedds_cpp``'s wire form, not from marsscene's server: topics
``rq/<service>Request`` / ``rr/<service>Reply``, types ``<pkg>::srv::dds_::<Srv>_Request_`` /
``_Response_``, each sample the CDR encapsulation, a ``uint64`` client handle and an ``int64``
sequence number, then the plain CDR payload; ``clientid=`` in the endpoints' USER_DATA; an
action as its ``_action/send_goal`` / ``get_result`` / ``cancel_goal`` services and its
``feedback`` and ``status`` topics. The types come from the interface's own definitions (the
``.msg`` / ``.srv`` / ``.action`` files), parsed here with ``rosbags``; ``action_msgs``'s
``CancelGoal`` is written out below from ``rcl_interfaces``. Imports nothing from marsscene;
loopback only.

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
import numpy as np
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
LONG_GOAL = 100_000  # steps of the goal that is cancelled
#: action_msgs/srv/CancelGoal (ros2/rcl_interfaces), request and response.
CANCEL_GOAL = ("action_msgs/GoalInfo goal_info\n",
               "int8 ERROR_NONE=0\nint8 ERROR_REJECTED=1\nint8 ERROR_UNKNOWN_GOAL_ID=2\n"
               "int8 ERROR_GOAL_TERMINATED=3\nint8 return_code\n"
               "action_msgs/GoalInfo[] goals_canceling\n")


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
    texts["action_msgs/srv/CancelGoal_Request"], texts["action_msgs/srv/CancelGoal_Response"] = \
        CANCEL_GOAL
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
        return self.wait(self.send(timeout_s, **fields), timeout_s)

    def send(self, timeout_s: float = 30.0, **fields: Any) -> int:
        """Write a request (once the service is there); its sequence number."""
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
        return Client.seq

    def wait(self, seq: int, timeout_s: float = 30.0) -> Any:
        """The reply to request ``seq``."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout_s:
            for raw in take(self.r):
                h, s = struct.unpack("<Qq", raw[4:20])
                if (h, s) == (self.handle, seq):
                    return STORE.deserialize_cdr(raw[:4] + raw[20:], self.rep_t)
            time.sleep(0.0005)
        raise SystemExit(f"no reply from {self.req_t}")


def _yaw(q: Any) -> float:
    """Heading of a quaternion's x axis seen from above (ZYX yaw)."""
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y**2 + q.z**2))


def _cancel(peer: Peer, act: str, goal: Client, result: Client, feedback: Any, status: Any,
            drain: Any, now: list[float]) -> dict[str, Any]:
    """A long ``SimulateSteps`` goal, cancelled after a few feedback messages; cancel requests
    for it again, for a goal never sent and for every goal when none runs."""
    ty, a = STORE.types, f"{P}/action/SimulateSteps"
    cancel = Client(peer, f"{act}/cancel_goal", "action_msgs/srv/CancelGoal")
    uuid = ty["unique_identifier_msgs/msg/UUID"]
    gid = uuid(uuid=np.arange(100, 116, dtype=np.uint8))
    zero = ty["builtin_interfaces/msg/Time"](sec=0, nanosec=0)

    def info(goal_id: Any) -> Any:
        return ty["action_msgs/msg/GoalInfo"](goal_id=goal_id, stamp=zero)

    out: dict[str, Any] = {}
    t0 = now[0]
    acc = goal.call(goal_id=gid, goal=ty[f"{a}_Goal"](steps=LONG_GOAL))
    held = result.send(goal_id=gid)  # answered when the goal ends
    seen: list[Any] = []
    deadline = time.monotonic() + 30.0
    while len(seen) < 5 and time.monotonic() < deadline:
        seen += [STORE.deserialize_cdr(r, f"{a}_FeedbackMessage").feedback for r in take(feedback)]
        time.sleep(0.0005)
    w0 = time.perf_counter()
    rep = cancel.call(goal_info=info(gid))
    out["cancel_wall_s"] = time.perf_counter() - w0
    fin = result.wait(held)
    again = result.call(goal_id=gid)
    time.sleep(0.3)
    drain()
    seen += [STORE.deserialize_cdr(r, f"{a}_FeedbackMessage").feedback for r in take(feedback)]
    out["cancel_accepted"] = bool(acc.accepted)
    out["cancel"] = [int(rep.return_code), [bytes(g.goal_id.uuid).hex() for g in
                                            rep.goals_canceling]]
    out["cancel_gid"] = bytes(gid.uuid).hex()
    out["canceled"] = [int(fin.status), int(fin.result.result.result),
                       str(fin.result.result.error_message)]
    out["canceled_again"] = [int(again.status), int(again.result.result.result)]
    out["cancel_feedback"] = [[int(f.completed_steps), int(f.remaining_steps)] for f in seen]
    out["cancel_clock_s"] = now[0] - t0
    statuses: list[int] = []  # this goal's, as the status topic said them, in order
    for raw in take(status):
        for st in STORE.deserialize_cdr(raw, "action_msgs/msg/GoalStatusArray").status_list:
            if bytes(st.goal_info.goal_id.uuid) == bytes(gid.uuid) and \
                    (not statuses or statuses[-1] != int(st.status)):
                statuses.append(int(st.status))
    out["cancel_statuses"] = statuses
    out["cancel_terminated"] = int(cancel.call(goal_info=info(gid)).return_code)
    out["cancel_unknown"] = int(cancel.call(
        goal_info=info(uuid(uuid=np.full(16, 0xAB, dtype=np.uint8)))).return_code)
    idle = cancel.call(goal_info=info(uuid(uuid=np.zeros(16, dtype=np.uint8))))
    out["cancel_all_idle"] = [int(idle.return_code), len(idle.goals_canceling)]
    return out


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
    status = peer.reader(f"{ns}/simulate_steps/_action/status", "action_msgs/msg/GoalStatusArray",
                         reliable=True, transient_local=True, depth=100)
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
    out["asked_xy_yaw"] = [pose.position.x, pose.position.y, 0.8]
    got = get.call(entity="rover").state.pose
    out["got_xy_yaw"] = [got.position.x, got.position.y, _yaw(got.orientation)]
    again = get.call(entity="rover").state.pose.position
    out["got_again_xy"] = [again.x, again.y]
    out["settle"] = int(step.call(steps=50).result.result)  # 1 s at rest, wheels braked
    settled = get.call(entity="rover").state.pose
    out["settled_xy_yaw"] = [settled.position.x, settled.position.y,
                             _yaw(settled.orientation)]
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
    out["counts"] = dict(n)  # (what follows depends on when a cancel lands: not hashed)
    time.sleep(0.3)
    drain()
    odom0 = n["odom"]
    out.update(_cancel(peer, act, goal, result, feedback, status, drain, now))
    out["cancel_odom"] = n["odom"] - odom0
    out["state_after_cancel"] = int(srv("get_simulation_state", "GetSimulationState").call(
        structure_needs_at_least_one_member=0).state.state)
    setstate.call(state=state(3))
    sys.stdout.write(json.dumps(out) + "\n")


if __name__ == "__main__":
    main()
