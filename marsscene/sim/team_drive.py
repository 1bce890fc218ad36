"""``drive_team_sim``: drive every robot of a :class:`~marsscene.sim.team.TeamSim` at once.

Each robot has its own :class:`~marsscene.sim.session.DriveSession` (its controller, sensors,
noise streams, odometry and run folder) over its :class:`~marsscene.sim.team.TeamMember`; one
loop steps the shared physics by the greatest common divisor of every robot's sensor periods,
lets each session sample what is due, and at each control tick (one clock for the team) asks
every robot's controller for its command. A robot whose controller is done, or whose time
limit passes, has its run folder finished and stands braked (``cmd_vel`` zero) while the others
drive on: it is still an obstacle the others can touch.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from marsscene.sim.driver import (
    DriveInterrupted,
    DriveProgress,
    DriveResult,
    _checked,
    _controller,
    _result,
    _Rows,
    _time_limit_s,
)
from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Route
from marsscene.sim.session import DriveSession, SessionOptions
from marsscene.sim.team import TeamSim

__all__ = ["MemberDrive", "TeamProgress", "drive_team_sim"]


@dataclass(frozen=True)
class MemberDrive:
    """What one robot of a team does: a route, a controller or an open-loop command (as
    :func:`~marsscene.sim.driver.drive_sim` takes them), its time limit, its noise stream,
    its run folder (None: kept in memory), listeners of its samples and extra ``run.json``
    entries."""

    name: str
    rng: np.random.Generator
    route: Route | None = None
    controller: Any = None
    command: Any = None
    seconds: float | None = None
    out_dir: Path | None = None
    pursuit: PursuitConfig | None = None
    listeners: tuple[Any, ...] = ()
    meta: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class TeamProgress:
    """One robot's :class:`~marsscene.sim.driver.DriveProgress`, with its name."""

    robot: str
    drive: DriveProgress


class _Driving:
    """One robot's session, controller and limit while the team drives."""

    def __init__(self, team: TeamSim, plan: MemberDrive, options: SessionOptions,
                 progress: Callable[[TeamProgress], None] | None) -> None:
        self.name, self._progress = plan.name, progress
        self.ctrl, meta = _controller(plan.route, plan.controller, plan.command, plan.pursuit)
        self.route = plan.route
        self.limit_s = _time_limit_s(plan.route, plan.seconds)
        self.limit_steps = round(self.limit_s / team.dt_physics_s)
        self.rows = _Rows() if plan.out_dir is None else None
        heard = (*plan.listeners, *((self.rows,) if self.rows is not None else ()))
        opts = replace(options, listeners=(*options.listeners, *heard)) if heard else options
        self.member = team.member(plan.name)
        self.loop = DriveSession(self.member, rng=plan.rng, out_dir=plan.out_dir, options=opts,
                                 meta={**meta, "team": [m.name for m in team.members],
                                       **plan.meta})
        self.follower = self.ctrl if isinstance(self.ctrl, PurePursuit) else None
        self.result: DriveResult | None = None

    def report(self, t: float) -> None:
        """Its progress at sim time ``t`` (each whole second), to the team's ``progress``."""
        if self._progress is None:
            return
        f = self.follower
        self._progress(TeamProgress(self.name, DriveProgress(
            t, self.limit_s, self.loop.distance_m, float(f.s[f.index]) if f else None,
            float(f.s[-1]) if f else None)))

    def command(self) -> bool:
        """Observe, ask the controller, apply; False when its controller is done."""
        v, w = _checked(self.ctrl(self.loop.observe()))
        self.loop.act(v, w)
        return not getattr(self.ctrl, "done", False)

    def finish(self, status: str) -> None:
        self.member.apply(0.0, 0.0)  # braked where it stands
        self.result = _result(self.loop, self.rows, self.ctrl, self.route, status)


def _command(active: list[_Driving]) -> list[_Driving]:
    """Every active robot's command of this control tick; those whose controller is done are
    finished and left out."""
    still = []
    for d in active:
        if d.command():
            still.append(d)
        else:
            d.finish("complete")
    return still


def drive_team_sim(
    team: TeamSim,
    plans: Sequence[MemberDrive],
    *,
    session: SessionOptions | None = None,
    progress: Callable[[TeamProgress], None] | None = None,
) -> dict[str, DriveResult]:
    """Drive every robot of ``team`` (reset at its starts) by its plan, in lockstep.

    Returns each robot's :class:`~marsscene.sim.driver.DriveResult` by name. On Ctrl-C every
    robot still driving has its run folder finished up to that moment (``"interrupted"``)
    and :class:`~marsscene.sim.driver.DriveInterrupted` carries the first robot's result
    (``result``) and every robot's (``team``, by name).
    """
    opts = session if session is not None else SessionOptions()
    driving = [_Driving(team, p, opts, progress) for p in plans]
    active = list(driving)
    tick = math.gcd(*(d.loop.tick for d in driving))
    control = driving[0].loop.periods["control"]
    k = 0
    try:
        active = _command(active)
        while active:
            for d in active:
                d.loop.sample_due(d.report)
            team.advance(tick)
            k += tick
            for d in list(active):
                d.loop.k = k
                if k > d.limit_steps:
                    d.finish("complete")
                    active.remove(d)
            if k % control == 0:
                active = _command(active)
    except KeyboardInterrupt:
        for d in active:
            if d.result is None:
                d.finish("interrupted")
        first = driving[0].result
        if first is None:
            raise
        stop = DriveInterrupted(first)
        stop.team = {d.name: d.result for d in driving if d.result is not None}
        raise stop from None
    except BaseException:
        for d in active:
            if d.result is None:
                d.loop.close()
        raise
    return {d.name: d.result for d in driving if d.result is not None}
