"""``TeamNavEnv``: a team of rovers in one world as a PettingZoo parallel environment.

Each agent is a rover of a :class:`~marsscene.sim.team.TeamSim` with a goal of its own, drawn
on traversable ground by the navigation task (:class:`~marsscene.env.task.NavTask`,
:class:`~marsscene.env.task.TaskMap`: the single-rover environments' rule and bounds). The task
is cooperative, "cover the goals": every agent receives the team's reward, the mean of the
agents' progress towards their goals (m per step) plus a bonus for each goal reached, so an
agent gains when a team-mate gets closer. An agent's episode ends when its rover reaches its
goal (terminated; it then stands braked, an obstacle for the others) or tips over past
``task.max_tilt_deg``; every agent is truncated at ``task.max_episode_s``.

Observation of an agent (float32, ground truth, in its rover's heading frame): its goal's
forward and left offset (m) and distance, the cosine and sine of the bearing to it, and for
each other agent its forward and left offset (m). Action: ``(v, omega)`` normalised to
[-1, 1] (:attr:`NavTask.ACTION_SCALE`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from marsscene.env.task import NavTask, TaskMap
from marsscene.errors import RuntimeSimError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.sim.team import Placement, TeamSim, footprint_radius_m
from marsscene.sim.world import load_world

__all__ = ["GOAL_BONUS", "TeamNavEnv"]

#: The team's reward when one of its agents reaches its goal.
GOAL_BONUS = 10.0


class TeamNavEnv(ParallelEnv):
    """Rovers of a team, each driving to its own goal, in one world.

    Parameters
    ----------
    scene_dir : path-like
        A built scene.
    rovers : int or sequence of str or RoverConfig
        The agents' rover types (an int: that many Perseverance-class rovers); agents are named
        ``rover1``, ``rover2``, ...
    task : NavTask, optional
        Goal distances, tolerance, time limit and the ground allowed.
    run : RunConfig, optional
        The control rate (one clock for the team).
    """

    metadata: ClassVar[dict[str, Any]] = {"name": "marsscene_team_nav_v0", "render_modes": []}

    def __init__(self, scene_dir: str | Path, *, rovers: Any = 2, task: NavTask | None = None,
                 run: RunConfig | None = None) -> None:
        types = [RoverConfig()] * rovers if isinstance(rovers, int) else [
            r if isinstance(r, RoverConfig) else RoverConfig.load(str(r)) for r in rovers]
        self.scene_dir, self.task = Path(scene_dir), task if task is not None else NavTask()
        self.run = run if run is not None else RunConfig()
        self.rovers = dict(zip((f"rover{i + 1}" for i in range(len(types))), types, strict=True))
        self.possible_agents = list(self.rovers)
        self.agents: list[str] = []
        world = load_world(self.scene_dir)
        self._map = TaskMap(world.heightfield, world.obstacles, self.task)
        n_obs = 5 + 2 * (len(types) - 1)
        self._obs_space = spaces.Box(-np.inf, np.inf, (n_obs,), np.float32)
        self._act_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self._rng = np.random.default_rng()
        self._team: TeamSim | None = None
        self.goals: dict[str, NDArray[np.float64]] = {}

    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Box:
        return self._act_space

    # ---- episodes ----------------------------------------------------------------------------
    def _draw(self) -> list[tuple[NDArray[np.float64], float, NDArray[np.float64]]]:
        """A start, heading and goal per agent, the starts a footprint apart."""
        gap = 2.0 * max(footprint_radius_m(r) for r in self.rovers.values())
        for _ in range(100):
            draws = [self._map.draw(self._rng) for _ in self.possible_agents]
            starts = np.array([d[0] for d in draws])
            dist = np.hypot(*(starts[:, None] - starts[None]).transpose(2, 0, 1))
            if (dist[np.triu_indices(len(draws), 1)] > gap).all():
                return draws
        raise RuntimeSimError(f"found no {len(self.rovers)} starts {gap:.1f} m apart on the "
                              "world's traversable ground")

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        draws = self._draw()
        self.goals = {a: d[2] for a, d in zip(self.possible_agents, draws, strict=True)}
        if self._team is None:
            self._team = TeamSim(self.scene_dir, [
                Placement(a, self.rovers[a], self.run, (float(s[0]), float(s[1])), yaw)
                for a, (s, yaw, _) in zip(self.possible_agents, draws, strict=True)],
                settle_s=self.task.start_settle_s)
        else:
            for m, (s, yaw, _) in zip(self._team.members, draws, strict=True):
                m.start_xy_m, m.start_yaw_rad = (float(s[0]), float(s[1])), yaw
            self._team.reset()
        self.agents = list(self.possible_agents)
        self._steps = 0
        self._dist = {a: self._distance(a) for a in self.agents}
        return self._observe(), {a: {"goal_xy_m": self.goals[a]} for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[Any, Any, Any, Any, Any]:
        assert self._team is not None, "reset() first"
        for a in self.agents:
            act = np.clip(np.asarray(actions[a], dtype=np.float64), -1.0, 1.0)
            v, w = self.task.command(act)
            self._team.member(a).apply(float(v), float(w))
        self._team.advance(self._team.members[0].substeps)
        self._steps += 1
        progress, reached, tipped = {}, {}, {}
        for a in self.agents:
            d = self._distance(a)
            progress[a], self._dist[a] = self._dist[a] - d, d
            reached[a] = d <= self.task.goal_tolerance_m
            tipped[a] = self._tilt_deg(a) > self.task.max_tilt_deg
        team_reward = float(np.mean(list(progress.values()))) + GOAL_BONUS * sum(reached.values())
        over = self._steps >= self.task.episode_steps(self.run.control_hz)
        obs = self._observe()
        rewards = {a: team_reward for a in self.agents}
        terminated = {a: bool(reached[a] or tipped[a]) for a in self.agents}
        truncated = {a: bool(over and not terminated[a]) for a in self.agents}
        infos = {a: {"distance_m": self._dist[a], "reached": bool(reached[a]),
                     "tipped": bool(tipped[a])} for a in self.agents}
        for a in self.agents:
            if terminated[a] or truncated[a]:
                self._team.member(a).apply(0.0, 0.0)  # braked: an obstacle for the others
        self.agents = [a for a in self.agents if not (terminated[a] or truncated[a])]
        return obs, rewards, terminated, truncated, infos

    # ---- readings ----------------------------------------------------------------------------
    def _xy_yaw(self, agent: str) -> tuple[NDArray[np.float64], float]:
        assert self._team is not None
        m = self._team.member(agent)
        return m.pose()[0][:2], m.yaw_rad()

    def _distance(self, agent: str) -> float:
        return float(np.hypot(*(self.goals[agent] - self._xy_yaw(agent)[0])))

    def _tilt_deg(self, agent: str) -> float:
        assert self._team is not None
        m = self._team.member(agent)
        up = m.data.xmat[m.base_id].reshape(3, 3)[:, 2]  # base_link's z axis in the world
        return math.degrees(math.acos(float(np.clip(up[2], -1.0, 1.0))))

    def _observe(self) -> dict[str, NDArray[np.float32]]:
        out = {}
        for a in self.agents:
            xy, yaw = self._xy_yaw(a)
            c, s = math.cos(yaw), math.sin(yaw)
            body = lambda p, xy=xy, c=c, s=s: (  # noqa: E731  (world -> heading frame)
                c * (p[0] - xy[0]) + s * (p[1] - xy[1]), -s * (p[0] - xy[0]) + c * (p[1] - xy[1]))
            gx, gy = body(self.goals[a])
            d = math.hypot(gx, gy)
            rest = [v for b in self.possible_agents if b != a for v in body(self._xy_yaw(b)[0])]
            out[a] = np.array([gx, gy, d, gx / max(d, 1e-9), gy / max(d, 1e-9), *rest],
                              dtype=np.float32)
        return out

    def close(self) -> None:
        self._team = None
