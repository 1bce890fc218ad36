"""The ``SimulateSteps`` action of :mod:`.sim_control`, as ROS 2 maps an action onto DDS.

``<action>/_action/send_goal`` (``SimulateSteps_SendGoal``: goal id and goal -> accepted and
a stamp), ``_action/get_result`` (goal id -> status and result; answered when the goal ends),
``_action/cancel_goal`` (``action_msgs/CancelGoal``), and the topics ``_action/feedback``
(``SimulateSteps_FeedbackMessage``, after each step) and ``_action/status``
(``action_msgs/GoalStatusArray``, reliable and transient local). A goal is accepted only while
the simulation is paused and no steps are being taken.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PAUSED", "SimulateStepsAction"]

PAUSED = 2  # SimulationState.STATE_PAUSED
_OK, _NOT_FOUND, _FAILED = 1, 2, 4  # Result codes
_EXECUTING, _SUCCEEDED, _CANCELED, _ABORTED = 2, 4, 5, 6  # GoalStatus codes


class _Run:
    """Steps asked for by one call: the service's reply or the action's goal."""

    def __init__(self, n: int, finish: Any, goal_id: Any = None) -> None:
        self.n, self.started, self.completed = int(n), 0, 0
        self.finish, self.goal_id = finish, goal_id


class SimulateStepsAction:
    """The action's handlers (mixed into :class:`~.sim_control.SimControl`, whose state,
    ``run``, ``results``, ``waiting``, writers and helpers they use)."""

    T: Any
    store: Any
    atype: str
    state: int
    run: _Run | None
    results: dict[bytes, tuple[int, Any]]
    waiting: dict[bytes, list[Any]]
    feedback: Any
    status: Any

    def _result(self, code: int = _OK, text: str = "") -> Any:
        raise NotImplementedError

    def _stamp(self) -> Any:
        raise NotImplementedError

    def _abort_run(self) -> None:
        raise NotImplementedError

    def _send_goal(self, req: Any, _r: Any) -> Any:
        gid = bytes(req.goal_id.uuid)
        ok = self.state == PAUSED and self.run is None and int(req.goal.steps) > 0
        if ok:
            self.run = _Run(int(req.goal.steps), self._goal_done, req.goal_id)
            self._status(req.goal_id, _EXECUTING)
        else:
            msg = "pause the simulation first" if self.state != PAUSED else "steps are running"
            self.results[gid] = (_ABORTED, self._result(_FAILED, msg))
        return self.T[f"{self.atype}_SendGoal_Response"](accepted=ok, stamp=self._stamp().stamp)

    def _goal_done(self, run: _Run) -> None:
        done = run.completed >= run.n
        status = _SUCCEEDED if done else _CANCELED
        gid = bytes(run.goal_id.uuid)
        self.results[gid] = (status, self._result(_OK if done else _FAILED,
                                                  "" if done else "stopped before the end"))
        self._status(run.goal_id, status)
        for reply in self.waiting.pop(gid, []):
            reply(self._result_reply(gid))

    def _result_reply(self, gid: bytes) -> Any:
        status, result = self.results[gid]
        return self.T[f"{self.atype}_GetResult_Response"](
            status=status, result=self.T[f"{self.atype}_Result"](result=result))

    def _get_result(self, req: Any, reply: Any) -> Any:
        gid = bytes(req.goal_id.uuid)
        if gid in self.results:
            return self._result_reply(gid)
        run = self.run
        if run is not None and run.goal_id is not None and bytes(run.goal_id.uuid) == gid:
            self.waiting.setdefault(gid, []).append(reply)
            return None
        return self.T[f"{self.atype}_GetResult_Response"](  # an unknown goal
            status=0, result=self.T[f"{self.atype}_Result"](result=self._result(_NOT_FOUND)))

    def _cancel_goal(self, req: Any, _r: Any) -> Any:
        run = self.run
        info = req.goal_info
        mine = run is not None and run.goal_id is not None and (
            bytes(info.goal_id.uuid) in (bytes(run.goal_id.uuid), bytes(16)))
        goals = []
        if mine and run is not None:
            goals = [self.T["action_msgs/msg/GoalInfo"](goal_id=run.goal_id,
                                                        stamp=self._stamp().stamp)]
            self._abort_run()
        return self.T["action_msgs/srv/CancelGoal_Response"](return_code=0 if mine else 2,
                                                             goals_canceling=goals)

    def _feedback(self, run: _Run) -> None:
        fb = self.T[f"{self.atype}_Feedback"](completed_steps=run.completed,
                                              remaining_steps=run.n - run.completed)
        msg = self.T[f"{self.atype}_FeedbackMessage"](goal_id=run.goal_id, feedback=fb)
        self.feedback.write(self.store.serialize_cdr(msg, msg.__msgtype__))

    def _status(self, goal_id: Any, status: int) -> None:
        info = self.T["action_msgs/msg/GoalInfo"](goal_id=goal_id, stamp=self._stamp().stamp)
        arr = self.T["action_msgs/msg/GoalStatusArray"](
            status_list=[self.T["action_msgs/msg/GoalStatus"](goal_info=info, status=status)])
        self.status.write(self.store.serialize_cdr(arr, arr.__msgtype__))
