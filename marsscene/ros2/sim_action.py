"""The ``SimulateSteps`` action of :mod:`.sim_control`, as ROS 2 maps an action onto DDS.

``<action>/_action/send_goal`` (``SimulateSteps_SendGoal``: goal id and goal -> accepted and
a stamp), ``_action/get_result`` (goal id -> status and result; answered when the goal ends),
``_action/cancel_goal`` (``action_msgs/CancelGoal``), and the topics ``_action/feedback``
(``SimulateSteps_FeedbackMessage``, after each step) and ``_action/status``
(``action_msgs/GoalStatusArray``, reliable and transient local: every goal accepted, the newest
:data:`KEPT`). A goal is accepted only while the simulation is paused and no steps are being
taken.

A goal ends ``SUCCEEDED`` once its last step's samples are out; ``CANCELED`` when a cancel
request names it (it goes ``CANCELING`` and ends at once: requests are served between steps),
with ``RESULT_OPERATION_FAILED`` and the steps taken in the message; ``ABORTED`` when the
simulation is set playing, stopped or quit under it. Cancel requests follow ``rcl_action``: a
goal id alone names one goal (``ERROR_UNKNOWN_GOAL_ID`` if never accepted,
``ERROR_GOAL_TERMINATED`` if it has ended); a zero id with a zero stamp cancels every goal
running, a stamp those accepted at or before it.

:class:`SimulateStepsAction` holds its services, writers and goals; what it needs from the
simulation control serving it is :class:`ActionHost`: the state, the one run of steps being
taken, and the result and stamp messages.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from marsscene.ros2.services import Service
from marsscene.ros2.sim_types import ACTION

__all__ = ["KEPT", "PAUSED", "ActionHost", "SimulateStepsAction", "StepRun"]

PAUSED = 2  # SimulationState.STATE_PAUSED
#: Goals whose status and result are kept (the status topic's list), the newest.
KEPT = 64
_OK, _NOT_FOUND, _FAILED = 1, 2, 4  # Result codes
_EXECUTING, _CANCELING, _SUCCEEDED, _CANCELED, _ABORTED = 2, 3, 4, 5, 6  # GoalStatus codes
_NONE, _UNKNOWN_GOAL, _TERMINATED = 0, 2, 3  # CancelGoal return codes
_ZERO = bytes(16)


class StepRun:
    """Steps asked for by one call: the service's reply or the action's goal.

    ``finish(run)`` is called once when it ends (all ``n`` steps completed or not),
    ``progress(run)`` after each step completed.
    """

    def __init__(self, n: int, finish: Callable[[StepRun], None], *, goal_id: Any = None,
                 progress: Callable[[StepRun], None] | None = None) -> None:
        self.n, self.started, self.completed = int(n), 0, 0
        self.finish, self.progress, self.goal_id = finish, progress, goal_id
        self.canceled = False  # a cancel request ended it (else: done, or aborted)


class ActionHost(Protocol):
    """What the action needs from the simulation control that serves it."""

    state: int  # SimulationState code
    run: StepRun | None  # the steps being taken (set one to start them)

    def result(self, code: int = _OK, text: str = "") -> Any:
        """A ``simulation_interfaces/msg/Result``."""

    def stamp(self) -> Any:
        """A ``std_msgs/msg/Header`` at the current sim time."""

    def abort_run(self) -> None:
        """End the run being taken now (its ``finish`` is called)."""


class SimulateStepsAction:
    """The action's services and topics, with the goals it has accepted.

    Parameters
    ----------
    host : ActionHost
    part : Participant
    store : rosbags typestore
        Holding the action's types (:func:`.sim_types.register`).
    namespace : str
        In front of the action's name (``""`` or e.g. ``/gzserver``).
    """

    def __init__(self, host: ActionHost, part: Any, store: Any, namespace: str = "") -> None:
        self.host, self.store, self.T = host, store, store.types
        act = f"{namespace}/{ACTION[0]}/_action"
        self.atype = atype = f"simulation_interfaces/action/{ACTION[1]}"
        self.services = [
            Service(part, store, f"{act}/send_goal", f"{atype}_SendGoal", self._send_goal),
            Service(part, store, f"{act}/get_result", f"{atype}_GetResult", self._get_result),
            Service(part, store, f"{act}/cancel_goal", "action_msgs/srv/CancelGoal",
                    self._cancel_goal)]
        self.feedback = part.writer(store, f"{act}/feedback", f"{atype}_FeedbackMessage",
                                    "default")
        self.status = part.writer(store, f"{act}/status", "action_msgs/msg/GoalStatusArray",
                                  "latched")
        self.goals: dict[bytes, Any] = {}  # goal id -> its GoalStatus (accepted, newest last)
        self.results: dict[bytes, tuple[int, Any]] = {}  # goal id -> (status, result)
        self.waiting: dict[bytes, list[Callable[[Any], None]]] = {}  # get_result replies held

    # ---- the services ------------------------------------------------------------------------
    def _send_goal(self, req: Any, _r: Any) -> Any:
        gid, host = bytes(req.goal_id.uuid), self.host
        ok = host.state == PAUSED and host.run is None and int(req.goal.steps) > 0 \
            and gid not in self.goals
        if ok:
            host.run = StepRun(int(req.goal.steps), self._goal_done, goal_id=req.goal_id,
                               progress=self._feedback)
            info = self.T["action_msgs/msg/GoalInfo"](goal_id=req.goal_id,
                                                      stamp=host.stamp().stamp)
            self._set_status(gid, _EXECUTING, info)
        elif gid not in self.goals:  # rejected: get_result says why
            why = ("pause the simulation first" if host.state != PAUSED else
                   "steps are being taken" if host.run is not None else "steps must be > 0")
            self.results[gid] = (_ABORTED, host.result(_FAILED, why))
            for old in list(self.results)[:-2 * KEPT]:
                del self.results[old]
        return self.T[f"{self.atype}_SendGoal_Response"](accepted=ok, stamp=host.stamp().stamp)

    def _get_result(self, req: Any, reply: Callable[[Any], None]) -> Any:
        gid = bytes(req.goal_id.uuid)
        if gid in self.results:
            return self._result_reply(gid)
        if self._running() == gid:
            self.waiting.setdefault(gid, []).append(reply)
            return None
        return self._result_response(0, self.host.result(_NOT_FOUND, "no such goal"))

    def _cancel_goal(self, req: Any, _r: Any) -> Any:
        info = req.goal_info
        gid = bytes(info.goal_id.uuid)
        before_ns = _ns(info.stamp)
        running, run = self._running(), self.host.run
        if gid != _ZERO and before_ns == 0:  # one goal, by its id
            hit = running == gid
            code = _NONE if hit else _TERMINATED if gid in self.goals else _UNKNOWN_GOAL
        else:  # every goal accepted at or before the stamp (zero and zero: all), and the id's
            st = self.goals.get(running) if running is not None else None
            hit = st is not None and (
                running == gid or before_ns == 0 or _ns(st.goal_info.stamp) <= before_ns)
            code = _NONE
        goals = []
        if hit and run is not None and running is not None:
            status = self.goals[running]
            goals = [status.goal_info]
            run.canceled = True
            self._set_status(running, _CANCELING, status.goal_info)
            self.host.abort_run()  # between steps: it ends now (CANCELED)
        return self.T["action_msgs/srv/CancelGoal_Response"](return_code=code,
                                                             goals_canceling=goals)

    # ---- a goal's steps ----------------------------------------------------------------------
    def _feedback(self, run: StepRun) -> None:
        fb = self.T[f"{self.atype}_Feedback"](completed_steps=run.completed,
                                              remaining_steps=run.n - run.completed)
        msg = self.T[f"{self.atype}_FeedbackMessage"](goal_id=run.goal_id, feedback=fb)
        self.feedback.write(self.store.serialize_cdr(msg, msg.__msgtype__))

    def _goal_done(self, run: StepRun) -> None:
        gid, host = bytes(run.goal_id.uuid), self.host
        taken = f"{run.completed} of {run.n} steps taken"
        if run.completed >= run.n:
            status, res = _SUCCEEDED, host.result(_OK)
        elif run.canceled:
            status, res = _CANCELED, host.result(_FAILED, f"canceled: {taken}")
        else:
            status, res = _ABORTED, host.result(
                _FAILED, f"aborted (the simulation left the paused state): {taken}")
        self.results[gid] = (status, res)
        self._set_status(gid, status, self.goals[gid].goal_info)
        for reply in self.waiting.pop(gid, []):
            reply(self._result_reply(gid))

    # ---- helpers -----------------------------------------------------------------------------
    def _running(self) -> bytes | None:
        """The id of the goal whose steps are being taken, if one's are."""
        run = self.host.run
        return None if run is None or run.goal_id is None else bytes(run.goal_id.uuid)

    def _result_response(self, status: int, result: Any) -> Any:
        return self.T[f"{self.atype}_GetResult_Response"](
            status=status, result=self.T[f"{self.atype}_Result"](result=result))

    def _result_reply(self, gid: bytes) -> Any:
        return self._result_response(*self.results[gid])

    def _set_status(self, gid: bytes, status: int, info: Any) -> None:
        """Record a goal's status and publish every kept goal's."""
        self.goals.pop(gid, None)
        self.goals[gid] = self.T["action_msgs/msg/GoalStatus"](goal_info=info, status=status)
        for old in list(self.goals)[:-KEPT]:
            del self.goals[old]
            self.results.pop(old, None)
        arr = self.T["action_msgs/msg/GoalStatusArray"](status_list=list(self.goals.values()))
        self.status.write(self.store.serialize_cdr(arr, arr.__msgtype__))


def _ns(stamp: Any) -> int:
    return int(stamp.sec) * 10**9 + int(stamp.nanosec)
