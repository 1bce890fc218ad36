"""The rock budget (marsscene.rocks.budget): one level while the footprint's population fits
rocks.max_rocks, else the full population over the focus square and a cut-off outside it; the
plan of every configuration fits the budget or is refused in one line naming the option."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from marsscene.errors import ConfigError
from marsscene.rocks.budget import CUTOFF_STEP_M, expected_rocks, gib, plan_levels
from marsscene.rocks.config import RockConfig
from marsscene.rocks.sfd import cumulative_number_density_per_m2

#: An option a refusal names: a config key, or a command-line flag.
OPTION = re.compile(r"\b(rocks|terrain)\.[a-z_]+\b|--[a-z-]+")


def _square(side_m: float, cx: float = 0.0, cy: float = 0.0) -> tuple[float, float, float, float]:
    return (cx - side_m / 2, cy - side_m / 2, cx + side_m / 2, cy + side_m / 2)


def test_expected_rocks_is_the_golombek_count() -> None:
    """Reference: area x [N(>d_min) - N(>d_max)] at k (k = 0.05: 1.03 rocks/m^2 from 0.1 m, the
    issue's 2.33e6 rocks on 1.5 km x 1.5 km)."""
    cfg = RockConfig()
    n = cumulative_number_density_per_m2([0.1, 3.0], k=0.05)
    assert expected_rocks(1500.0**2, cfg, 0.1) == pytest.approx((n[0] - n[1]) * 1500.0**2)
    assert expected_rocks(1500.0**2, cfg, 0.1) == pytest.approx(2.33e6, rel=0.01)
    assert expected_rocks(1e6, cfg, 3.0) == 0.0
    field = RockConfig(field_polygon_xy_m=((0, 0), (100, 0), (100, 100), (0, 100)), field_k=0.3)
    n3 = cumulative_number_density_per_m2([0.1, 3.0], k=0.3)
    assert expected_rocks(1e6, field, 0.1) == pytest.approx(
        (n[0] - n[1]) * (1e6 - 1e4) + (n3[0] - n3[1]) * 1e4)


def test_1km_is_one_level_and_1500m_gets_two() -> None:
    cfg = RockConfig()
    one = plan_levels(cfg, _square(1000.0), _square(1000.0))
    assert not one.two_level and one.outer_d_min_m == 0.1
    assert one.expected == pytest.approx(1.03e6, rel=0.01)
    two = plan_levels(cfg, _square(1500.0), _square(1000.0))
    assert two.two_level and two.outer_d_min_m == 1.0 and not two.raised
    assert two.focus_expected == pytest.approx(one.expected)
    assert two.outer_expected == pytest.approx(expected_rocks(1.25e6, cfg, 1.0))
    assert "cut-off of 1 m outside (rocks.outer_d_min_m)" in two.describe(0.1)


def test_the_cut_off_is_raised_to_the_smallest_that_fits() -> None:
    cfg = RockConfig(outer_d_min_m=0.2)
    levels = plan_levels(cfg, _square(3600.0), _square(1000.0), two_level_terrain=True)
    room = cfg.max_rocks - levels.focus_expected
    outer_area = 3600.0**2 - 1e6
    assert levels.raised and levels.expected <= cfg.max_rocks
    assert expected_rocks(outer_area, cfg, levels.outer_d_min_m - CUTOFF_STEP_M) > room
    assert "raised from rocks.outer_d_min_m" in levels.describe(cfg.d_min_m)


def test_every_rock_everywhere_is_refused_with_its_memory_then_given_on_asking() -> None:
    ask = RockConfig(outer_d_min_m=0.1)
    full = expected_rocks(4e6, ask, 0.1)
    with pytest.raises(ConfigError) as err:
        plan_levels(ask, _square(2000.0), _square(1000.0))
    msg = str(err.value)
    assert "\n" not in msg and "rocks.max_rocks" in msg and f"{gib(full):.2g} GiB" in msg
    need = int(re.search(r"rocks.max_rocks >= (\d+)", msg).group(1))  # type: ignore[union-attr]
    levels = plan_levels(RockConfig(outer_d_min_m=0.1, max_rocks=need), _square(2000.0),
                         _square(1000.0))
    assert not levels.two_level and levels.expected == pytest.approx(full)
    # a raised budget alone gives the full population too (the footprint then fits)
    assert not plan_levels(RockConfig(max_rocks=need), _square(2000.0), None).two_level


def test_a_focus_over_the_budget_names_what_to_change() -> None:
    with pytest.raises(ConfigError, match=r"terrain.focus_size_m \(--focus-size-m\)"):
        plan_levels(RockConfig(k=0.3), _square(3000.0), _square(1000.0), two_level_terrain=True)


sizes = st.floats(100.0, 4000.0)


@settings(max_examples=300, deadline=None)
@given(w=sizes, h=sizes, focus=st.floats(50.0, 2000.0), d_min=st.floats(0.05, 1.5),
       outer=st.floats(0.05, 2.5), k=st.floats(0.02, 0.4), budget=st.integers(1000, 10**7),
       lod=st.booleans(), has_focus=st.booleans())
def test_every_plan_fits_the_budget_or_is_refused_in_one_line(
        w: float, h: float, focus: float, d_min: float, outer: float, k: float, budget: int,
        lod: bool, has_focus: bool) -> None:
    cfg = RockConfig(d_min_m=d_min, outer_d_min_m=outer, k=k, max_rocks=budget)
    side = min(focus, w, h)
    fp = (-w / 2, -h / 2, w / 2, h / 2)
    try:
        levels = plan_levels(cfg, fp, _square(side) if has_focus else None,
                             two_level_terrain=lod and has_focus)
    except ConfigError as err:
        assert "\n" not in str(err) and OPTION.search(str(err)), str(err)
        return
    assert levels.expected <= budget * (1 + 1e-9)
    assert levels.outer_d_min_m >= min(outer, d_min) - 1e-12
    if levels.two_level:  # the focus keeps the full population, from d_min_m
        assert levels.focus_expected == pytest.approx(expected_rocks(side * side, cfg, d_min))
        if levels.raised:
            assert levels.outer_d_min_m > max(outer, d_min)
    else:
        assert levels.outer_d_min_m == d_min
        assert levels.expected == pytest.approx(expected_rocks(w * h, cfg, d_min))
        assert not (lod and has_focus)


def test_plans_grow_no_rocks_when_the_scene_grows() -> None:
    """The cut-off rises with the footprint so the total never passes the budget."""
    cfg = RockConfig(outer_d_min_m=0.3)
    cuts = [plan_levels(cfg, _square(s), _square(1000.0), two_level_terrain=True).outer_d_min_m
            for s in (1500.0, 3000.0, 6000.0, 12000.0)]
    assert cuts == sorted(cuts) and cuts[0] == 0.3 and cuts[-1] > 0.3
    assert np.all(np.diff(cuts) >= 0)
