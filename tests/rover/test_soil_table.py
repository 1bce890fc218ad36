"""The tabulated wheel--soil model against the direct solution it interpolates, and the
braked wheel's signs."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.rover.soil_table import soil_table
from marsscene.rover.terramechanics import sinkage_for_load, soil, soils, wheel_forces

R_M, B_M = 0.2625, 0.40  # the rover's wheel
MAX_LOAD_N = 4 * 1025.0 * 3.71 / 6


@pytest.mark.parametrize("name", sorted(soils()))
def test_table_matches_the_direct_solution_off_its_grid(name: str) -> None:
    sl = soil(name)
    rng = np.random.default_rng(3)
    load = rng.uniform(50.0, MAX_LOAD_N, 64)
    slip = rng.uniform(-1.0, 1.0, 64)
    got = soil_table(sl, R_M, B_M, MAX_LOAD_N).lookup(load, slip)
    z = sinkage_for_load(sl, R_M, B_M, load, slip)
    f = wheel_forces(sl, R_M, B_M, z, slip)
    np.testing.assert_allclose(got.sinkage_m, z, rtol=0.03, atol=5e-4)
    # forces within 2 % of each wheel's load (1 N near zero load)
    for have, want in ((got.thrust_n, f.thrust_n), (got.resistance_n, f.resistance_n),
                       (got.torque_nm / R_M, f.torque_nm / R_M)):
        assert np.all(np.abs(have - want) < 0.02 * load + 1.0)


def test_loads_beyond_the_table_scale_the_forces() -> None:
    tab = soil_table(soil("dry_sand"), R_M, B_M, MAX_LOAD_N)
    at, twice = tab.lookup(MAX_LOAD_N, 0.3), tab.lookup(2 * MAX_LOAD_N, 0.3)
    assert twice.sinkage_m == at.sinkage_m
    assert twice.thrust_n == pytest.approx(2 * at.thrust_n)


def test_a_braked_wheel_is_held_back_and_turned_on() -> None:
    """Negative slip (the wheel turns slower than it travels): the shear reverses, so drawbar
    pull and the soil's torque on the wheel both change sign against a driven wheel's."""
    sl = soil("firm_regolith")
    z = sinkage_for_load(sl, R_M, B_M, 600.0, np.array([-0.5, 0.5]))
    f = wheel_forces(sl, R_M, B_M, z, np.array([-0.5, 0.5]))
    assert f.drawbar_n[0] < 0 < f.drawbar_n[1]
    assert f.torque_nm[0] < 0 < f.torque_nm[1]
    assert f.thrust_n[0] < 0 < f.resistance_n[0]
