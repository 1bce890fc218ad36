"""The live bridge: a drive's controller and listener that speaks ROS 2 over DDS.

As a **listener** (:mod:`marsscene.sim.session`) it publishes every sample as it is made: the
messages come from :class:`~marsscene.runs.export.sample_messages.SampleMessages` (the bag's
builders) and go out as ``rosbags`` CDR through :mod:`.dds`, on the bag's topics with their QoS
(:mod:`marsscene.runs.export.topic_table`; sensor data as ``sensor_qos`` says); a topic nobody
subscribes to is not built. As the **controller** (:mod:`marsscene.sim.control`) it is called
once per control step: it reads the command topics (``cmd_vel``, reset, teleport, goal), stops
the rover when the command is older than the timeout, and paces the simulation against the wall
clock.

Before each control step the simulation-control services are served (:mod:`.sim_control`):
paused, the step waits there until one is asked for.

Topics it subscribes to (besides ``cmd_vel`` and ``/rover/cmd_vel``), in the spirit of OmniLRS's
robot topics (a team robot's under ``/marsscene/NAME/``, its commands on ``/NAME/cmd_vel``:
:class:`~marsscene.runs.export.topic_table.RosNames`):

* ``/marsscene/reset`` (``std_msgs/Empty``): the rover back to its start pose, at rest;
* ``/marsscene/teleport`` (``geometry_msgs/Pose``, map frame): ``base_link`` to ``x, y`` facing
  the pose's yaw, set on the terrain at rest (z, roll and pitch from the ground);
* ``/marsscene/goal`` (``geometry_msgs/PoseStamped``, map frame): the goal whose reaching (ground
  truth within ``goal_tolerance_m``) is announced on ``/marsscene/goal_reached``
  (``std_msgs/Bool``, latched) and, with ``stop_at_goal``, ends the session.

Sim time never jumps: a reset or teleport moves the rover, the clock runs on; wheel odometry
keeps integrating (``odom -> base_link`` is continuous) and ``map -> odom`` absorbs the jump.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from typing import Any

from marsscene.errors import RuntimeSimError
from marsscene.ros2.dds import Participant, RawWriter
from marsscene.ros2.options import Ros2Options
from marsscene.ros2.stats import SessionStats
from marsscene.ros2.teleport import spawn_point_for
from marsscene.runs.export.sample_messages import SampleMessages
from marsscene.sim.goal import goal_reached
from marsscene.transforms import yaw_of_quat

__all__ = ["Bridge", "SessionStats"]

log = logging.getLogger("marsscene")


class RateLimitedWarning:
    """Warnings in the log at most once per ``period_s`` of wall time; the ones held back are
    counted into the next (bad input on the wire must not flood the server's log)."""

    def __init__(self, period_s: float = 5.0) -> None:
        self.period_s, self.last, self.held = float(period_s), -math.inf, 0

    def warn(self, fmt: str, *args: Any) -> None:
        now = time.monotonic()
        if now - self.last < self.period_s:
            self.held += 1
            return
        more = f" (and {self.held} more in the last {self.period_s:g} s)" if self.held else ""
        log.warning(fmt + more, *args)
        self.last, self.held = now, 0

#: How often a lockstep session looks for the next command while it waits (every 0.5 ms for
#: the first 0.1 s, then every 5 ms: an idle session costs no core), and how often it says
#: ``/clock`` again (a best-effort topic) meanwhile (wall seconds).
_POLL_S, _POLL_IDLE_S, _IDLE_AFTER_S = 0.0005, 0.005, 0.1
_CLOCK_AGAIN_S = 0.1
_CONTROL_TOPICS = {"reset": "std_msgs/msg/Empty", "teleport": "geometry_msgs/msg/Pose",
                   "goal": "geometry_msgs/msg/PoseStamped"}


class Bridge:
    """Controller and listener of one live drive (:func:`marsscene.ros2.serve` makes it).

    Parameters
    ----------
    sim : RoverSim
        The simulator being driven (for reset and teleport).
    messages : SampleMessages
    opts : Ros2Options
    part : Participant
    cmd_topics : tuple of str, optional
        The command topics obeyed (default ``opts.cmd_vel_topics``; a team robot its own).
    clock : bool
        Publish ``/clock`` (one robot of a team does).
    """

    done = False

    def __init__(self, sim: Any, messages: SampleMessages, opts: Ros2Options,
                 part: Participant, *, cmd_topics: tuple[str, ...] | None = None,
                 clock: bool = True) -> None:
        self.sim, self.msgs, self.opts, self.part = sim, messages, opts, part
        names = messages.names
        self.store = messages.b.store
        self.stats = SessionStats()
        self.bad_input = RateLimitedWarning()
        self.lockstep = opts.pace == "lockstep"
        sensor = ("sensor" if opts.sensor_qos == "best-effort" and not self.lockstep
                  else "sensor-reliable")
        self.writers: dict[str, RawWriter] = {  # the command is read here, not published
            t.name: part.writer(self.store, t.name, t.msgtype,
                                sensor if t.qos == "sensor" else t.qos)
            for t in messages.topics()
            if t.name != names.topic("cmd_vel") and (clock or t.name != "/clock")}
        messages.wanted = self.wanted
        cmd_type = ("geometry_msgs/msg/TwistStamped" if opts.cmd_vel_stamped
                    else "geometry_msgs/msg/Twist")
        self.cmd_type = cmd_type
        self.cmd_readers = [part.reader(self.store, t, cmd_type, "default")
                            for t in (cmd_topics or opts.cmd_vel_topics)]
        self.control_readers = {t: part.reader(self.store, f"{names.control}/{t}", mt, "default")
                                for t, mt in _CONTROL_TOPICS.items()}
        self.goal_writer = part.writer(self.store, f"{names.control}/goal_reached",
                                       "std_msgs/msg/Bool", "latched")
        self.start_pose = (sim.pose()[0][:2].copy(), sim.yaw_rad())
        self.cmd: tuple[float, float] = (0.0, 0.0)
        self.cmd_t_s: float | None = None
        self.queued: deque[tuple[float, float]] = deque()  # lockstep: commands not yet driven
        self.steps_left = 0  # lockstep: control steps the command in force still drives
        self.goal_xy: tuple[float, float] | None = None
        self.wall0: float | None = None
        self.wall_start: float | None = None  # perf_counter() at the first control step
        self.control_srv: Any = None  # simulation_interfaces' services (:mod:`.sim_control`)
        if opts.services:
            from marsscene.ros2.sim_control import SimControl

            self.control_srv = SimControl(self, opts.sim_namespace)

    # ---- publishing (listener) -------------------------------------------------------------
    def wanted(self, topic: str) -> bool:
        w = self.writers.get(topic)
        return w is not None and w.subscribers > 0

    def publish(self, pairs: list[tuple[str, Any]]) -> None:
        for topic, msg in pairs:
            t0 = time.perf_counter()
            data = self.msgs.b.serialize(msg)
            self.writers[topic].write(data)
            st = self.stats
            st.write_s[topic] = st.write_s.get(topic, 0.0) + time.perf_counter() - t0
            st.messages[topic] = st.messages.get(topic, 0) + 1
            st.bytes[topic] = st.bytes.get(topic, 0) + len(data)

    def publish_static(self) -> None:
        """``/tf_static``, the URDF and ``/marsscene/goal_reached`` (false), latched."""
        self.publish(self.msgs.static(0.0))
        self._goal_reached(False)

    def _sample(self, stream: str, make: Any, args: tuple[Any, ...]) -> None:
        t0 = time.perf_counter()
        pairs = make(*args)
        st = self.stats
        st.build_s[stream] = st.build_s.get(stream, 0.0) + time.perf_counter() - t0
        self.publish(pairs)

    def control(self, *args: Any) -> None:
        self._sample("control", self.msgs.control, args)

    def imu(self, *args: Any) -> None:
        self._sample("imu", self.msgs.imu, args)

    def lidar(self, *args: Any) -> None:
        self._sample("lidar", self.msgs.lidar, args)

    def camera(self, *args: Any) -> None:
        self._sample("camera", self.msgs.camera, args)

    def stereo(self, *args: Any) -> None:
        self._sample("stereo", self.msgs.stereo, args)

    # ---- the control step (controller) -----------------------------------------------------
    def __call__(self, obs: Any) -> tuple[float, float]:
        srv = self.control_srv
        stepped = False
        while srv is not None and not self.done:
            stepped = srv.gate(obs)  # serves requests; holds while paused
            if stepped or not self.lockstep:
                break
            held = self._lockstep(obs)
            if held is not None:
                return held  # else paused while it waited: the gate holds
        if self.lockstep and srv is None:
            return self._lockstep(obs) or (0.0, 0.0)
        if not stepped:
            self._pace(obs.t_s)
        for cmd in self._read_commands():
            self.cmd, self.cmd_t_s = cmd, obs.t_s
        self._read_control()
        self._check_goal(obs)
        if self.cmd_t_s is None:
            return 0.0, 0.0
        if self.opts.cmd_timeout_s > 0 and obs.t_s - self.cmd_t_s > self.opts.cmd_timeout_s:
            self.stats.timeouts += 1
            self.cmd_t_s = None  # stopped until the next command
            return 0.0, 0.0
        return self.cmd

    def _lockstep(self, obs: Any) -> tuple[float, float] | None:
        """Hold sim time until a command comes; drive each for ``lockstep_steps`` control
        steps. Before waiting, the LiDAR scan being cast goes out and ``/clock`` says that
        every sample before ``obs.t_s`` is out. None: paused (a service) while waiting."""
        if self.wall0 is None:
            self.wall_start = self.wall0 = time.perf_counter()
        if self.steps_left == 0:
            obs.lidar  # noqa: B018 (reading it hands the scan being cast to the listeners)
            said, since = -math.inf, time.perf_counter()
            srv = self.control_srv
            while not self.queued and not self.done:
                if srv is not None:
                    srv.poll()
                    if not srv.playing:
                        return None
                if time.perf_counter() - said > _CLOCK_AGAIN_S and self.wanted("/clock"):
                    self.publish([("/clock", self.msgs.b.clock(obs.t_s))])  # best effort:
                    said = time.perf_counter()  # said again while waiting
                self.queued.extend(self._read_commands())
                self._read_control()
                self._check_goal(obs)
                if not self.queued:
                    idle = time.perf_counter() - since > _IDLE_AFTER_S
                    time.sleep(_POLL_IDLE_S if idle else _POLL_S)
            if self.done:
                return 0.0, 0.0
            self.cmd, self.steps_left = self.queued.popleft(), self.opts.lockstep_steps
        self.steps_left -= 1
        return self.cmd

    def _check_goal(self, obs: Any) -> None:
        if self.goal_xy is not None and self.stats.goal_reached_t_s is None:
            if goal_reached(obs.gt_xyz_m[:2], self.goal_xy, self.opts.goal_tolerance_m):
                self.stats.goal_reached_t_s = float(obs.t_s)
                self._goal_reached(True)
                log.info("goal reached at %.2f sim s", obs.t_s)
                self.done = self.opts.stop_at_goal

    def _pace(self, t_s: float) -> None:
        if self.wall0 is None:
            self.wall_start = time.perf_counter()
            self.wall0 = self.wall_start - t_s / self.opts.realtime_factor
            return
        if self.opts.pace != "realtime":
            return
        ahead = self.wall0 + t_s / self.opts.realtime_factor - time.perf_counter()
        if ahead > 0:
            time.sleep(ahead)
            self.stats.sleep_s += ahead

    def _read_commands(self) -> list[tuple[float, float]]:
        """The finite commands waiting, oldest first (bad ones dropped with a warning)."""
        out = []
        raws = [(r.topic, raw) for r in self.cmd_readers for raw in r.take()]
        for topic, raw in raws:
            try:
                msg: Any = self.store.deserialize_cdr(raw, self.cmd_type)
            except Exception as err:
                self.bad_input.warn("%s: a message that is not a %s dropped (%s)",
                                    topic, self.cmd_type, err)
                continue
            tw = msg.twist if self.opts.cmd_vel_stamped else msg
            v, w = float(tw.linear.x), float(tw.angular.z)
            if math.isfinite(v) and math.isfinite(w):
                out.append((v, w))
            else:
                self.bad_input.warn("%s: a command with linear.x = %r, angular.z = %r "
                                    "dropped (not finite)", topic, v, w)
        self.stats.commands += len(out)
        return out

    def _read_control(self) -> None:
        readers = self.control_readers
        if readers["reset"].take() and self._place(*self.start_pose):
            self.stats.resets += 1
        for raw in readers["teleport"].take()[-1:]:
            pose: Any = self.store.deserialize_cdr(raw, "geometry_msgs/msg/Pose")
            q = pose.orientation
            yaw = float(yaw_of_quat((q.w, q.x, q.y, q.z)))
            if self._place((pose.position.x, pose.position.y), yaw):
                self.stats.teleports += 1
        for raw in readers["goal"].take()[-1:]:
            goal: Any = self.store.deserialize_cdr(raw, "geometry_msgs/msg/PoseStamped")
            self.goal_xy = (float(goal.pose.position.x), float(goal.pose.position.y))
            self.stats.goal_reached_t_s = None
            self._goal_reached(False)
            log.info("goal set at (%.2f, %.2f) m", *self.goal_xy)

    def _place(self, xy: Any, yaw: float) -> bool:
        try:  # base_link at x, y facing yaw (:mod:`.teleport`)
            spot, heading = spawn_point_for(self.sim.heightfield, self.sim.rover,
                                            (float(xy[0]), float(xy[1])), float(yaw))
            self.sim.place(xy_m=spot, yaw_rad=heading)
        except RuntimeSimError as err:  # a pose off the terrain: say so, keep serving
            log.warning("teleport refused: %s", err)
            return False
        self.cmd, self.cmd_t_s = (0.0, 0.0), None
        self.steps_left = 0  # lockstep: the commands queued still come, from the new pose
        return True

    def _goal_reached(self, reached: bool) -> None:
        b = self.msgs.b
        self.goal_writer.write(b.serialize(b.T["std_msgs/msg/Bool"](data=reached)))
