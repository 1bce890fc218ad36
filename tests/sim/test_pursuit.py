"""Routes and pure pursuit: 20 m square on gentle terrain, command bounds, avoidance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.errors import ConfigError, RuntimeSimError
from marsscene.runtime import (
    Obstacles,
    PurePursuit,
    PursuitConfig,
    Route,
    author_route,
)
from marsscene.seeding import stage_rng
from marsscene.sim.cross_track import cross_track_m
from marsscene.sim.driver import drive_sim
from marsscene.sim.rover_sim import RoverSim
from marsscene.terrain.heightfield import Heightfield

SQUARE = np.array([[-10, -10], [10, -10], [10, 10], [-10, 10], [-10, -10]], dtype=float)


def test_pure_pursuit_20m_square(gentle_scene) -> None:
    sim = RoverSim(gentle_scene, start_xy_m=(-10.0, -10.0), start_yaw_rad=0.0)
    route = author_route(SQUARE, sim.heightfield)
    assert route.length_m == pytest.approx(80.0, rel=0.05)  # corners rounded by smoothing
    res = drive_sim(sim, route=route, rng=stage_rng(0, "sensors"))
    assert res.summary["goal_reached"]
    assert res.summary["cross_track_rms_m"] < 0.3
    v, w = res.cmd[:, 1], res.cmd[:, 2]
    assert v.min() >= 0.0 and v.max() <= 0.5 + 1e-12
    assert np.abs(w).max() <= 0.2 + 1e-12
    assert np.diff(res.cmd[:, 0]) == pytest.approx(0.02)  # 50 Hz
    # the rover drove the whole loop and came back to the start
    assert res.gt.path_length_m() == pytest.approx(route.length_m, rel=0.05)
    assert np.linalg.norm(res.gt.xyz_m[-1, :2] - SQUARE[0]) < 0.5


@pytest.mark.parametrize("start_m", [(0.0, 0.0), (-0.05, 0.0), (-0.1, 0.03)])
def test_short_closed_loop_is_driven_round(start_m: tuple[float, float]) -> None:
    """A closed loop shorter than the forward window (3 lookaheads + 1 m): the rover, started
    at, or a little behind, the start (and so beside the end), drives it round before it stops
    (a unicycle at 50 Hz)."""
    t = np.linspace(0.0, 2 * math.pi, 121)
    route = Route(np.column_stack([np.sin(t), 1.0 - np.cos(t)]))  # 6.28 m, heading +x at 0
    pp = PurePursuit(route, PursuitConfig(lookahead_m=2.0))
    x, y, yaw, path, dt = *start_m, 0.0, 0.0, 0.02
    for _ in range(3000):
        v, w = pp.command(x, y, yaw)
        if pp.done:
            break
        x, y, yaw = x + v * math.cos(yaw) * dt, y + v * math.sin(yaw) * dt, yaw + w * dt
        path += v * dt
    assert pp.done and pp.index > 0.9 * len(route.s_m)
    assert path > 0.8 * route.length_m  # round the loop, not stopped at its start


def test_pursuit_commands_bounded_for_any_pose() -> None:
    rng = np.random.default_rng(5)
    t = np.linspace(0, 2 * math.pi, 400)
    route = Route(np.c_[6 * np.cos(t), 3 * np.sin(2 * t)])  # a figure of eight
    for lookahead in (0.3, 1.0, 3.0):
        pp = PurePursuit(route, PursuitConfig(lookahead_m=lookahead))
        for x, y, yaw in rng.uniform([-8, -8, -4], [8, 8, 4], size=(300, 3)):
            pp.index = int(rng.integers(0, 399))
            v, w = pp.command(x, y, yaw)
            assert 0.0 <= v <= 0.5 and abs(w) <= 0.2


def test_pursuit_config_rejects_protocol_violations() -> None:
    with pytest.raises(ConfigError, match="v_max_m_s"):
        PursuitConfig(v_max_m_s=0.8)
    with pytest.raises(ConfigError, match="omega_max_rad_s"):
        PursuitConfig(omega_max_rad_s=0.5)


def test_pursuit_rate_is_the_control_rate() -> None:
    """Pure pursuit runs at ``RunConfig.control_hz``: a ``rate_hz`` in a drive table (the
    removed, never-read field) is a one-line ConfigError naming the allowed keys."""
    from marsscene.sim.mission import DriveOptions

    assert "rate_hz" not in PursuitConfig.__dataclass_fields__
    with pytest.raises(ConfigError, match=r"unknown key drive\.pursuit\.rate_hz.*lookahead_m"):
        DriveOptions.from_dict({"pursuit": {"lookahead_m": 2.0, "rate_hz": 50.0}})


def _hill() -> Heightfield:
    x = (np.arange(161) - 80) * 0.25
    xx, yy = np.meshgrid(x, x)
    z = 4.0 * np.exp(-(xx**2 + yy**2) / (2 * 3.0**2))  # a steep 4 m hill at the centre
    return Heightfield.centered(z, 0.25)


def test_route_avoids_steep_slope() -> None:
    hf = _hill()
    assert hf.slope_deg().max() > 30
    route = author_route([[-15, 0.5], [15, 0.5]], hf, max_slope_deg=15.0)
    xy = route.xy_m
    gx, gy = hf.gradient(xy[:, 0], xy[:, 1])
    assert np.degrees(np.arctan(np.hypot(gx, gy))).max() < 15.0
    assert route.length_m > 30.5  # went around
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    assert steps[:-1] == pytest.approx(steps.mean(), rel=0.02)  # resampled by arc length
    np.testing.assert_allclose(xy[[0, -1]], [[-15, 0.5], [15, 0.5]])


def test_route_avoids_tall_rocks_only() -> None:
    hf = Heightfield.centered(np.zeros((121, 121)), 0.25)
    tall = Obstacles(np.array([[0.0, 0.0]]), np.array([0.4]), np.array([0.8]))
    small = Obstacles(np.array([[0.0, 0.2]]), np.array([0.3]), np.array([0.1]))
    kw = {"max_obstacle_height_m": 0.3, "clearance_m": 1.5}
    around = author_route([[-10, 0], [10, 0]], hf, obstacles=tall, **kw)
    assert np.hypot(*around.xy_m.T).min() > 0.4 + 1.5 * 0.9
    assert around.length_m > 20.0
    through = author_route([[-10, 0], [10, 0]], hf, obstacles=small, **kw)
    assert np.abs(through.xy_m[:, 1]).max() < 1e-9  # small rock ignored: straight line
    assert through.length_m == pytest.approx(20.0)


def test_route_leaves_a_waypoint_inside_a_rock_clearance_by_the_shortest_way() -> None:
    """A start 1 m from a tall rock (inside its 1.5 m clearance + inflation) used to give
    "no route": the start cell was opened but stayed walled in by blocked cells."""
    hf = Heightfield.centered(np.zeros((161, 161)), 0.25)
    rock = Obstacles(np.array([[0.0, 0.0]]), np.array([0.4]), np.array([0.8]))
    start, goal = np.array([1.0, 0.0]), np.array([-15.0, 0.0])
    route = author_route([start, goal], hf, obstacles=rock, max_obstacle_height_m=0.3,
                         clearance_m=1.5)
    xy = route.xy_m
    np.testing.assert_allclose(xy[[0, -1]], [start, goal])
    dist = np.hypot(*xy.T)
    # it moves away from the rock first (never closer than the start), then goes around it
    assert dist.min() >= 1.0 - 0.05
    assert np.abs(xy[:, 1]).max() > 0.4 + 1.5 * 0.9
    assert route.length_m < 30.0


def test_route_outside_terrain_error() -> None:
    hf = Heightfield.centered(np.zeros((41, 41)), 0.25)
    with pytest.raises(RuntimeSimError, match=r"waypoint 1 .* outside the terrain"):
        author_route([[0, 0], [50, 0]], hf)


def test_cross_track_distance() -> None:
    route = Route(np.array([[0.0, 0.0], [10.0, 0.0]]))
    np.testing.assert_allclose(cross_track_m(route, [[5, 2], [-3, 4], [11, 0]]), [2, 5, 1])


def test_route_leaves_a_pocket_walled_in_by_rocks() -> None:
    """A waypoint on free ground that a ring of tall rocks walls in (the grand-canyon route of
    scene seed 3 had one) leaves the pocket for the larger free area instead of "no route"."""
    hf = Heightfield.centered(np.zeros((161, 161)), 0.25)
    ang = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([4.5 * np.cos(ang), 4.5 * np.sin(ang)])  # rocks 1.18 m apart
    rocks = Obstacles(ring, np.full(24, 0.4), np.full(24, 0.8))
    start, goal = np.array([0.0, 0.0]), np.array([-15.0, 0.0])
    route = author_route([start, goal], hf, obstacles=rocks, max_obstacle_height_m=0.3,
                         clearance_m=1.5)
    xy = route.xy_m
    np.testing.assert_allclose(xy[[0, -1]], [start, goal])
    assert np.hypot(*xy[-1]) > 4.5 and route.length_m < 20.0  # out through the ring, the short way
    # a route from a free area to itself is untouched by the pocket rule
    free = author_route([[-15.0, -5.0], [-15.0, 5.0]], hf, obstacles=rocks,
                        max_obstacle_height_m=0.3, clearance_m=1.5)
    assert np.abs(free.xy_m[:, 0] + 15.0).max() < 1e-9
