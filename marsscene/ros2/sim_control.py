"""Simulation control as ``simulation_interfaces`` has it: the services and the action of a
served session (one rover, entity ``rover``, or a team, an entity per robot by its name, on a
static world).

States: playing (the session's ``pace``), paused (sim time stands still: no step is taken,
``/clock`` says the same time again) and stopped (paused, the rover back at its start). A
*step* is one pass of the simulation loop (every robot of a team), one control step (``1 /
control_hz`` s, the physics sub-steps within it): ``StepSimulation(n)`` and ``SimulateSteps``
take exactly n of them, with the command in force (the newest ``cmd_vel`` and its time-out),
publish every sample they make and answer once the last one is out. A reset puts the rover
(every robot) back at its start at rest; sim time runs on (``SIMULATION_RESET_TIME`` is not
offered: the clock never jumps). ``SetEntityState`` teleports as ``/marsscene/teleport`` does:
``base_link`` at the request's x, y and heading (:mod:`.teleport`), z, roll and pitch from the
ground, at rest. The ``SimulateSteps`` action is :mod:`.sim_action`'s; :class:`SimControl` is
its host (the state and the one run of steps :meth:`SimControl.gate` takes, for the service or
the action).
"""

from __future__ import annotations

import math
import re
import time
from typing import Any

import numpy as np

from marsscene.ros2.services import Service
from marsscene.ros2.sim_action import PAUSED, SimulateStepsAction, StepRun
from marsscene.ros2.sim_types import SERVICES, register
from marsscene.transforms import yaw_of_quat

__all__ = ["FEATURES", "SimControl"]

_P = "simulation_interfaces"
#: ``SimulatorFeatures`` codes offered (exactly what is served).
FEATURES = (10, 11, 12, 8, 20, 22, 23, 24, 25, 26, 31, 32, 33)
STOPPED, PLAYING, QUITTING = 0, 1, 3
UNSUPPORTED, OK, NOT_FOUND, FAILED = 0, 1, 2, 4
ROVER, ROBOT = "rover", 1
_ALREADY, _INCORRECT_TRANSITION = 101, 103


class SimControl:
    """The services of a session's bridge, and its pause / step gate (the host of the
    ``SimulateSteps`` action, :class:`~.sim_action.ActionHost`).

    Parameters
    ----------
    bridge : Bridge
    namespace : str
        In front of every service and the action (``/`` or e.g. ``/gzserver``).

    ``entities`` maps each entity's name to the bridge of its robot (``{"rover": bridge}``; a
    served team sets one per robot).
    """

    def __init__(self, bridge: Any, namespace: str = "/") -> None:
        self.b, self.store, self.T = bridge, bridge.store, bridge.store.types
        self.entities: dict[str, Any] = {ROVER: bridge}
        register(self.store)
        ns = namespace.rstrip("/")
        self.state = PLAYING
        self.run: StepRun | None = None
        self.obs: Any = None
        self.steps = 0  # steps taken while not playing (by the services and the action)
        self.services = [Service(bridge.part, self.store, f"{ns}/{name}", f"{_P}/srv/{srv}",
                                 getattr(self, "_" + name)) for name, srv in SERVICES.items()]
        self.action = SimulateStepsAction(self, bridge.part, self.store, ns)
        self.services += self.action.services

    # ---- the gate: called at the start of every control step -------------------------------
    @property
    def playing(self) -> bool:
        return self.state == PLAYING

    def poll(self) -> None:
        for s in self.services:
            s.poll()

    def gate(self, obs: Any) -> bool:
        """Serve requests; while not playing, hold sim time until a step is asked for. True:
        this control step is one asked for (drive it, unpaced)."""
        self.obs = obs
        run = self.run
        if run is not None and run.started > run.completed:
            run.completed += 1
            if run.progress is not None:
                run.progress(run)
        self.poll()
        if self.playing or self.b.done:
            return False
        b, said, since = self.b, -math.inf, time.perf_counter()
        obs.lidar  # noqa: B018 (the scan being cast goes out before the wait)
        while not self.b.done and self.state != PLAYING:
            run = self.run
            if run is not None and run.completed >= run.n:
                self.run = None
                run.finish(run)
                continue
            if run is not None:
                run.started += 1
                self.steps += 1
                return True
            if time.perf_counter() - said > 0.1 and b.wanted("/clock"):
                b.publish([("/clock", b.msgs.b.clock(obs.t_s))])
                said = time.perf_counter()
            for cmd in b._read_commands():  # the command the next steps drive
                b.cmd, b.cmd_t_s = cmd, obs.t_s
            b._read_control()
            self.poll()
            time.sleep(0.0005 if time.perf_counter() - since < 0.1 else 0.005)
        b.wall0 = None  # realtime pacing starts again from here
        return False

    # ---- helpers ------------------------------------------------------------------------------
    def result(self, code: int = OK, text: str = "") -> Any:
        return self.T[f"{_P}/msg/Result"](result=code, error_message=text)

    def _reply(self, srv: str, **fields: Any) -> Any:
        return self.T[f"{_P}/srv/{srv}_Response"](**fields)

    def stamp(self) -> Any:
        return self.b.msgs.b.header(self.obs.t_s if self.obs is not None else 0.0, "map")

    # ---- simulation state --------------------------------------------------------------------
    def _get_simulator_features(self, req: Any, _r: Any) -> Any:
        feats = self.T[f"{_P}/msg/SimulatorFeatures"](
            features=np.array(FEATURES, dtype=np.uint16), spawn_formats=[],
            custom_info=f"marsscene: {self._who()} on a static world; a step is one control "
                        "step; reset keeps sim time running")
        return self._reply("GetSimulatorFeatures", features=feats)

    def _get_simulation_state(self, req: Any, _r: Any) -> Any:
        return self._reply("GetSimulationState", result=self.result(),
                           state=self.T[f"{_P}/msg/SimulationState"](state=self.state))

    def _set_simulation_state(self, req: Any, _r: Any) -> Any:
        want, now = int(req.state.state), self.state
        if want == now:
            res = self.result(_ALREADY, "already in that state")
        elif want == STOPPED:
            self.abort_run()
            self._all_to_start()
            self.state, res = STOPPED, self.result()
        elif want in (PLAYING, PAUSED):
            if want == PLAYING:
                self.abort_run()
            self.state, res = want, self.result()
        elif want == QUITTING:
            self.abort_run()
            for b in self.entities.values():
                b.done = True
            res = self.result()
        else:
            res = self.result(UNSUPPORTED, "no world loading: one static scene a session")
        return self._reply("SetSimulationState", result=res)

    def _reset_simulation(self, req: Any, _r: Any) -> Any:
        scope = int(req.scope)
        if scope not in (0, 255) and not scope & 6:  # SCOPE_TIME alone
            return self._reply("ResetSimulation", result=self.result(
                UNSUPPORTED, "sim time is not reset (SIMULATION_RESET_TIME)"))
        ok = self._all_to_start()
        return self._reply("ResetSimulation", result=self.result(
            OK if ok else FAILED, "" if scope & 2 and not scope & 1 else
            f"{'the rover is' if len(self.entities) == 1 else 'every robot is'} back at its "
            "start; sim time keeps running"))

    def _all_to_start(self) -> bool:
        """Every robot back at its start, at rest."""
        ok = True
        for b in self.entities.values():
            placed = b._place(*b.start_pose)
            b.stats.resets += int(placed)
            ok = ok and placed
        return ok

    def _who(self) -> str:
        names = list(self.entities)
        return ("one rover (entity 'rover')" if names == [ROVER] else
                f"a team of {len(names)} robots (entities {', '.join(map(repr, names))})")

    def _step_simulation(self, req: Any, reply: Any) -> Any:
        if self.state != PAUSED or self.run is not None:
            return self._reply("StepSimulation", result=self.result(
                FAILED, "pause the simulation first" if self.state != PAUSED
                else "steps are being taken"))

        def done(run: StepRun) -> None:
            res = self.result() if run.completed >= run.n else self.result(
                FAILED, f"the simulation left the paused state after {run.completed} of "
                        f"{run.n} steps")
            reply(self._reply("StepSimulation", result=res))

        self.run = StepRun(max(int(req.steps), 1), done)
        return None

    def abort_run(self) -> None:
        run, self.run = self.run, None
        if run is not None:
            run.finish(run)

    # ---- entities ----------------------------------------------------------------------------
    def _get_entities(self, req: Any, _r: Any) -> Any:
        f = req.filters
        if len(f.tags.tags) or int(f.bounds.type) != 0:
            return self._reply("GetEntities", result=self.result(
                UNSUPPORTED, "no entity tags or bounds"), entities=[])
        try:
            named = [n for n in self.entities if not f.filter or re.search(f.filter, n)]
        except re.error as err:
            return self._reply("GetEntities", result=self.result(FAILED, str(err)),
                               entities=[])
        cats = {int(c.category) for c in f.categories}
        found = named if not cats or ROBOT in cats else []
        return self._reply("GetEntities", result=self.result(), entities=found)

    def _missing(self, srv: str, name: str, **extra: Any) -> Any:
        names = list(self.entities)
        known = (f"the one entity is {names[0]!r}" if len(names) == 1 else
                 f"entities: {', '.join(map(repr, names))}")
        return self._reply(srv, result=self.result(NOT_FOUND, f"no entity {name!r}; {known}"),
                           **extra)

    def _bridge(self, entity: str) -> Any:
        """The bridge of the robot an entity name names (a leading ``/`` allowed), or None."""
        return self.entities.get(entity.strip("/"))

    def _get_entity_info(self, req: Any, _r: Any) -> Any:
        bridge = self._bridge(req.entity)
        names = (bridge if bridge is not None else self.b).msgs.names
        what = ("the served rover" if names.namespace == ROVER and not names.frame_prefix
                else f"robot {names.namespace!r}")
        info = self.T[f"{_P}/msg/EntityInfo"](
            category=self.T[f"{_P}/msg/EntityCategory"](category=ROBOT),
            description=f"{what} ({names.frame('base_link')}; its topics under "
                        f"/{names.namespace})", tags=[])
        if bridge is None:
            return self._missing("GetEntityInfo", req.entity, info=info)
        return self._reply("GetEntityInfo", result=self.result(), info=info)

    def _entity_state(self, bridge: Any) -> Any:
        b, sim = self.b.msgs.b, bridge.sim
        xyz, q = sim.pose()
        ang: tuple[float, ...] = (0.0, 0.0, 0.0)
        lin: tuple[float, ...] = ang
        qvel = getattr(getattr(sim, "data", None), "qvel", None)
        if qvel is not None:  # MuJoCo's free joint: linear (world), angular (body) velocity
            i = sim.qvel_root
            lin = tuple(float(v) for v in qvel[i:i + 3])
            ang = tuple(float(v) for v in _rotate(q, qvel[i + 3:i + 6]))
        V3 = self.T["geometry_msgs/msg/Vector3"]
        P = self.T["geometry_msgs/msg/Point"]
        pose = self.T["geometry_msgs/msg/Pose"](
            position=P(x=float(xyz[0]), y=float(xyz[1]), z=float(xyz[2])),
            orientation=b.quat((float(q[1]), float(q[2]), float(q[3]), float(q[0]))))
        twist = self.T["geometry_msgs/msg/Twist"](linear=V3(x=lin[0], y=lin[1], z=lin[2]),
                                                   angular=V3(x=ang[0], y=ang[1], z=ang[2]))
        zero = V3(x=0.0, y=0.0, z=0.0)
        return self.T[f"{_P}/msg/EntityState"](
            header=self.stamp(), pose=pose, twist=twist,
            acceleration=self.T["geometry_msgs/msg/Accel"](linear=zero, angular=zero))

    def _get_entity_state(self, req: Any, _r: Any) -> Any:
        bridge = self._bridge(req.entity)
        if bridge is None:
            return self._missing("GetEntityState", req.entity, state=self._entity_state(self.b))
        return self._reply("GetEntityState", result=self.result(),
                           state=self._entity_state(bridge))

    def _set_entity_state(self, req: Any, _r: Any) -> Any:
        bridge = self._bridge(req.entity)
        if bridge is None:
            return self._missing("SetEntityState", req.entity)
        st = req.state
        tw = st.twist
        if req.set_twist and any(abs(v) > 0 for v in (
                tw.linear.x, tw.linear.y, tw.linear.z, tw.angular.x, tw.angular.y,
                tw.angular.z)):
            return self._reply("SetEntityState", result=self.result(
                FAILED, "the rover is placed at rest: a twist other than zero is not set"))
        if st.header.frame_id not in ("", "world", "map"):
            return self._reply("SetEntityState", result=self.result(
                FAILED, f"frame {st.header.frame_id!r}: poses are in the map (world) frame"))
        if req.set_pose:
            q = st.pose.orientation
            if not all(math.isfinite(v) for v in (q.w, q.x, q.y, q.z, st.pose.position.x,
                                                     st.pose.position.y)) \
                    or abs(q.w**2 + q.x**2 + q.y**2 + q.z**2 - 1.0) > 1e-3:
                return self._reply("SetEntityState", result=self.result(
                    101, "a pose with a unit quaternion and finite x, y"))
            yaw = float(yaw_of_quat((q.w, q.x, q.y, q.z)))
            if not bridge._place((st.pose.position.x, st.pose.position.y), yaw):
                return self._reply("SetEntityState", result=self.result(
                    101, "off the terrain"))
            bridge.stats.teleports += 1
        elif req.set_twist:
            bridge._place(bridge.sim.pose()[0][:2], bridge.sim.yaw_rad())
        return self._reply("SetEntityState", result=self.result(
            OK, "z, roll and pitch from the ground" if req.set_pose else ""))

    def _get_spawnables(self, req: Any, _r: Any) -> Any:
        return self._reply("GetSpawnables", result=self.result(
            UNSUPPORTED, "a static world: nothing to spawn"), spawnables=[])

    def _spawn_entity(self, req: Any, _r: Any) -> Any:
        return self._reply("SpawnEntity", result=self.result(
            UNSUPPORTED, "a static world: nothing is spawned"), entity_name="")

    def _delete_entity(self, req: Any, _r: Any) -> Any:
        return self._reply("DeleteEntity", result=self.result(
            UNSUPPORTED, "a static world: nothing is deleted"))


def _rotate(q_wxyz: Any, v: Any) -> Any:
    """``v`` (body frame) in the world frame, by the unit quaternion ``q_wxyz``."""
    w, x, y, z = (float(c) for c in q_wxyz)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return r @ np.asarray(v, dtype=float)
