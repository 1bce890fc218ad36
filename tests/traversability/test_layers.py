"""The traversability layers against analytic terrain: planes, a sinusoid, a step, rocks under
the wheels and the belly, soil slip, and the combined cost's rules."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig
from marsscene.rover.terramechanics import soil
from marsscene.soil.map import SoilMap
from marsscene.terrain.heightfield import Heightfield
from marsscene.traversability import HAZARD_BITS, RoverFootprint, TraversabilityConfig, compute
from marsscene.traversability.compute import _combine, _limits
from marsscene.traversability.slip import rigid_slip, soil_slip

FP = RoverFootprint.of()
FLAT = Heightfield.centered(np.zeros((81, 81), np.float32), 0.25)  # 20 m x 20 m
MID = (40, 40)


def _plane(deg: float, azimuth_deg: float = 30.0, shape: tuple[int, int] = (61, 81)) -> Heightfield:
    rows, cols = shape
    y, x = np.mgrid[0:rows, 0:cols] * 0.25
    g = math.tan(math.radians(deg))
    az = math.radians(azimuth_deg)
    z = g * (math.cos(az) * x + math.sin(az) * y)
    return Heightfield.centered(z.astype(np.float32), 0.25)


def _bit(t, name: str) -> np.ndarray:
    return (t.hazard_bits & HAZARD_BITS[name]) > 0


@pytest.mark.parametrize("deg", [0.0, 15.0, 35.0])
def test_plane_slope_is_its_tilt_everywhere_and_roughness_zero(deg: float) -> None:
    t = compute(_plane(deg))
    np.testing.assert_allclose(t.slope_deg, deg, atol=1e-3)  # edges too (cut discs)
    assert float(t.roughness_m.max()) < 1e-5
    assert float(np.abs(t.belly_m[~_bit(t, "edge")]).max()) < 1e-5
    inner = ~_bit(t, "edge")
    assert bool(_bit(t, "slope")[inner].any()) is (deg >= 30.0)  # the 30 deg limit


def test_roughness_of_a_sinusoid_is_its_rms() -> None:
    amp, wave = 0.05, 0.4  # m: many waves per footprint, the plane takes out none of them
    x = np.arange(121) * 0.05
    z = np.tile(amp * np.sin(2 * np.pi * x / wave), (121, 1)).astype(np.float32)
    t = compute(Heightfield.centered(z, 0.05))
    inner = t.roughness_m[40:81, 40:81]
    np.testing.assert_allclose(inner, amp / math.sqrt(2), rtol=0.05)
    assert float(np.abs(t.slope_deg[40:81, 40:81]).max()) < 2.0


@pytest.mark.parametrize(("height_m", "hazard"), [(0.3, False), (0.6, True)])
def test_a_step_is_measured_and_a_hazard_above_a_wheel_diameter(height_m: float,
                                                               hazard: bool) -> None:
    z = np.zeros((81, 81), np.float32)
    z[:, 41:] = height_m
    t = compute(Heightfield.centered(z, 0.25))
    assert float(t.step_m[MID]) == pytest.approx(height_m, abs=1e-6)
    assert float(t.step_m[MID[0], 5:12].max()) == 0.0  # 6 m from the step: none
    assert bool(_bit(t, "step")[MID]) is hazard
    assert t.limits["step"] == pytest.approx(2 * FP.wheel_radius_m)


def _rock(d_m: float, h_m: float):
    return compute(FLAT, rocks_xy_m=[[0.0, 0.0]], rocks_diameter_m=[d_m], rocks_height_m=[h_m])


def test_a_rock_taller_than_a_wheel_climbs_is_a_hazard_where_a_wheel_meets_it() -> None:
    tall, small = _rock(0.4, 0.55), _rock(0.4, 0.3)
    ring = (MID[0], MID[1] + 5)  # 1.25 m east: a wheel stands on the rock at some heading
    assert bool(_bit(tall, "rock")[ring]) and bool(tall.hazard[ring])
    assert not small.hazard[ring] and float(small.rock_m[ring]) == pytest.approx(0.3)
    assert 0.5 < float(small.cost[ring]) < 1.0
    # Straddled under the belly (0.6 m clearance): no wheel on it, no hazard.
    assert not tall.hazard[MID] and float(tall.rock_m[MID]) == 0.0
    assert float(tall.belly_m[MID]) == pytest.approx(0.55)
    far = (MID[0], MID[1] + 12)  # 3 m away: nothing
    assert float(tall.cost[far]) == 0.0


def test_a_rock_taller_than_the_belly_clearance_is_a_belly_hazard() -> None:
    t = _rock(0.4, 0.7)
    assert bool(_bit(t, "belly")[MID]) and not bool(_bit(t, "rock")[MID])
    assert FP.belly_clearance_m == pytest.approx(0.6)  # chassis underside on level ground
    # A smooth mound under the belly, no rock: the same test on the terrain.
    y, x = (np.mgrid[0:81, 0:81] - 40) * 0.25
    mound = (0.7 * np.exp(-(x * x + y * y) / (2 * 0.25**2))).astype(np.float32)
    m = compute(Heightfield.centered(mound, 0.25))
    assert bool(_bit(m, "belly")[MID])


def test_slip_grows_with_slope_on_sand_and_not_on_rigid_ground() -> None:
    slopes = np.array([0.0, 2.0, 4.0, 6.0, 8.0])
    kw = {"radius_m": FP.wheel_radius_m, "width_m": FP.wheel_width_m, "weight_n": FP.weight_n}
    sand = soil_slip(slopes, soil("drift_sand"), **kw)
    firm = soil_slip(slopes, soil("firm_regolith"), **kw)
    assert np.all(np.diff(sand) > 0) and np.all(sand >= firm) and sand[-1] > 0.5
    assert np.all(rigid_slip(slopes, FP.friction) == 0.0)
    assert float(rigid_slip(np.array([40.0]), FP.friction)[0]) == 1.0  # past atan(0.8)
    plane = _plane(8.0)
    on_sand = compute(plane, soil=SoilMap.uniform(soil("drift_sand")))
    rigid = compute(plane)
    assert float(on_sand.slip[30, 40]) == pytest.approx(float(sand[4]), abs=0.01)
    assert float(rigid.slip.max()) == 0.0 and on_sand.soils == ("drift_sand",)
    assert bool(_bit(on_sand, "slip")[30, 40]) and not bool(rigid.hazard[30, 40])


TERMS = ("slope", "roughness", "step", "rock", "belly", "slip")


@settings(max_examples=40, deadline=None)
@example([0.0, 0.0, 0.0, 0.0, 1.0, 0.0], "slope", 0.0)  # a term exactly at its limit
@given(st.lists(st.floats(0.0, 2.0), min_size=6, max_size=6), st.sampled_from(TERMS),
       st.floats(0.0, 1.0))
def test_cost_is_monotone_in_each_term_and_one_at_a_hazard(ratios: list[float], term: str,
                                                          more: float) -> None:
    cfg = TraversabilityConfig()
    limits = _limits(FP, cfg)  # the rover's own (belly: 0.6000000000000001 m, not 0.6)
    assert limits["slope"] == 30.0 and limits["belly"] == pytest.approx(0.6)

    def cost(r: list[float]):
        terms = {k: np.array([[v * limits[k]]]) for k, v in zip(TERMS, r, strict=True)}
        return _combine(0.25, (0.0, 0.0), terms, np.zeros((1, 1), bool),
                        np.zeros((1, 1), np.uint8), None, FP, cfg)

    base = cost(ratios)
    bumped = list(ratios)
    bumped[TERMS.index(term)] += more
    higher = cost(bumped)
    assert float(higher.cost[0, 0]) >= float(base.cost[0, 0])
    assert 0.0 <= float(base.cost[0, 0]) <= 1.0
    assert bool(base.hazard[0, 0]) is (max(ratios) >= 1.0)
    if base.hazard[0, 0]:
        assert float(base.cost[0, 0]) == 1.0


@settings(max_examples=25, deadline=None)
@given(rows=st.integers(2, 40), cols=st.integers(2, 40), post=st.floats(0.05, 2.0),
       relief=st.floats(0.0, 5.0), seed=st.integers(0, 2**16),
       cell=st.one_of(st.none(), st.floats(0.01, 5.0)), slope=st.floats(1.0, 89.0),
       slip=st.floats(0.01, 1.0), n_rocks=st.integers(0, 20), wheel=st.floats(0.05, 0.6),
       track=st.floats(1.5, 4.0))
def test_any_valid_grid_gives_finite_layers_in_range(rows: int, cols: int, post: float,
                                                     relief: float, seed: int,
                                                     cell: float | None, slope: float,
                                                     slip: float, n_rocks: int, wheel: float,
                                                     track: float) -> None:
    rng = np.random.default_rng(seed)
    hf = Heightfield.centered((relief * rng.random((rows, cols))).astype(np.float32), post)
    x0, y0, x1, y1 = hf.bounds_xy_m
    rocks = {"rocks_xy_m": rng.uniform([x0, y0], [x1, y1], (n_rocks, 2)),
             "rocks_diameter_m": rng.uniform(0.05, 2.0, n_rocks),
             "rocks_height_m": rng.uniform(0.0, 1.0, n_rocks)}
    try:
        cfg = TraversabilityConfig(cell_m=cell, max_slope_deg=slope, max_slip=slip)
        rover = RoverConfig(wheel_radius_m=wheel, track_m=track, ride_height_m=wheel + 0.5)
        t = compute(hf, config=cfg, rover=rover, **rocks)
    except ConfigError as err:
        assert "\n" not in str(err)
        return
    for name, layer in t.layers().items():
        assert np.isfinite(layer).all(), name
    assert ((t.slope_deg >= 0) & (t.slope_deg <= 90)).all()
    assert (t.roughness_m >= 0).all() and (t.step_m >= 0).all() and (t.rock_m >= 0).all()
    assert ((t.cost >= 0) & (t.cost <= 1)).all() and ((t.slip >= 0) & (t.slip <= 1)).all()
    assert np.array_equal(t.hazard, t.hazard_bits > 0)


def test_the_grid_keeps_to_its_budget_and_refuses_a_finer_cell() -> None:
    t = compute(FLAT, config=TraversabilityConfig(max_cells=1000))
    assert t.cell_m == pytest.approx(0.75) and t.shape == (27, 27)  # every third post
    assert compute(FLAT, config=TraversabilityConfig(cell_m=1.1)).cell_m == pytest.approx(1.0)
    with pytest.raises(ConfigError, match=r"finer than the terrain's 0\.25 m posts"):
        compute(FLAT, config=TraversabilityConfig(cell_m=0.1))
    with pytest.raises(ConfigError, match="max_slope_deg"):
        TraversabilityConfig(max_slope_deg=0.0)
