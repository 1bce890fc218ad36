"""Seeded start-goal pairs: deterministic per seed, on connected traversable ground, with the
shortest traversable path; a scene without such pairs is a one-line error."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.benchmark.nav.grid import PlanGrid
from marsscene.benchmark.nav.pairs import draw_pairs, pairs_rng, reachable_cells
from marsscene.errors import ConfigError


def _two_rooms() -> PlanGrid:
    """80 x 80 m: a big room and, behind a full wall at x = 60 m, a small one; a pillar in the
    big room."""
    hazard = np.zeros((80, 80), bool)
    hazard[:, 60:62] = True
    hazard[30:50, 25:35] = True
    rng = np.random.default_rng(0)
    cost = rng.uniform(0.0, 0.5, (80, 80)).astype(np.float32)
    return PlanGrid(cost, hazard, 1.0, (-40.0, -40.0))


def test_pairs_are_deterministic_per_seed() -> None:
    g = _two_rooms()
    a = draw_pairs(g, 8, (20.0, 40.0), rng=pairs_rng(3, "rooms"))
    b = draw_pairs(g, 8, (20.0, 40.0), rng=pairs_rng(3, "rooms"))
    c = draw_pairs(g, 8, (20.0, 40.0), rng=pairs_rng(4, "rooms"))
    d = draw_pairs(g, 8, (20.0, 40.0), rng=pairs_rng(3, "other-scene"))
    assert a == b
    assert a != c and a != d


def test_pairs_lie_on_connected_traversable_ground() -> None:
    g = _two_rooms()
    pairs = draw_pairs(g, 20, (20.0, 40.0), rng=pairs_rng(1, "rooms"))
    big = {tuple(rc) for rc in reachable_cells(g).tolist()}
    assert len(big) == 60 * 80 - 20 * 10  # the big room without its pillar
    for p in pairs:
        for key in ("start_xy_m", "goal_xy_m"):
            rc = g.rowcol(np.asarray(p[key]))
            assert not g.hazard[rc[0], rc[1]] and tuple(rc.tolist()) in big
        assert 20.0 <= p["distance_m"] <= 40.0
        # the shortest traversable path: never shorter than the straight line, finite
        assert p["distance_m"] - 1e-6 <= p["shortest_m"] < 1.5 * p["distance_m"]


def test_shortest_path_goes_round_the_pillar() -> None:
    g = _two_rooms()
    path, length = g.shortest(np.array([-25.0, 0.0]), np.array([5.0, 0.0]))
    assert path is not None
    assert not g.hazard_at(path).any()
    assert length > 30.0 + 1.0  # the straight line crosses the pillar
    assert length < 30.0 + 2 * 12.0  # ... and the detour is short
    none, inf = g.shortest(np.array([-25.0, 0.0]), np.array([30.0, 0.0]))  # behind the wall
    assert none is None and inf == float("inf")


def test_no_pairs_is_a_one_line_error() -> None:
    g = _two_rooms()
    with pytest.raises(ConfigError, match=r"found only 0 of 3 start-goal pairs 200-300 m") as e:
        draw_pairs(g, 3, (200.0, 300.0), rng=pairs_rng(1, "rooms"), scene="rooms")
    assert "\n" not in str(e.value)
