"""The rover on deformable soil (marsscene.sim.wheel_soil): its slip on a slope against the
single-wheel theory solved independently, odometry that overestimates where wheels slip,
sinkage in the ground truth, a parked rover that stays put, and the run log."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

pytest.importorskip("mujoco")

from marsscene.errors import ConfigError
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.rover.terramechanics import sinkage_for_load, soil, wheel_forces
from marsscene.sim.rover_sim import RoverSim

ROVER = RoverConfig()
SPEED_M_S = 0.2


def _on_slope(scene: Path, soil_name: str, slope_deg: float, **kw: object) -> RoverSim:
    """The rover facing +x up a slope of ``slope_deg`` (gravity tilted: the flat scene)."""
    sim = RoverSim(scene, soil=soil_name, start_xy_m=(-8.0, 0.0), settle_s=1.5,
                   **kw)  # type: ignore[arg-type]
    g, a = float(np.linalg.norm(sim.model.opt.gravity)), math.radians(slope_deg)
    sim.model.opt.gravity[:] = (-g * math.sin(a), 0.0, -g * math.cos(a))
    sim.reset()
    return sim


def _steady_slip(sim: RoverSim, seconds: float = 5.0) -> float:
    """Wheel slip ``1 - v / (r omega)`` over the second half of a straight drive."""
    sim.apply(SPEED_M_S, 0.0)
    n = round(seconds * sim.run.control_hz)
    xs = []
    for _ in range(n):
        sim.advance(sim.substeps)
        xs.append(sim.pose()[0][0])
    v = (xs[-1] - xs[n // 2]) / ((n - 1 - n // 2) / sim.run.control_hz)
    return 1.0 - v / (float(sim.wheel_rates().mean()) * ROVER.wheel_radius_m)


def _theory_slip(name: str, slope_deg: float) -> float:
    """The slip at which a wheel carrying a sixth of the rover's weight pulls its sixth of the
    downhill force (sinkage solved for the load; drawbar pull by the model's quadrature)."""
    sl, a = soil(name), math.radians(slope_deg)
    w = ROVER.mass_kg * 3.71 * math.cos(a) / 6

    def excess(s: float) -> float:
        z = sinkage_for_load(sl, ROVER.wheel_radius_m, ROVER.wheel_width_m, w, s)
        dp = wheel_forces(sl, ROVER.wheel_radius_m, ROVER.wheel_width_m, z, s).drawbar_n
        return float(dp) - w * math.tan(a)

    return brentq(excess, 0.0, 0.99, xtol=1e-4)


@pytest.mark.parametrize(("name", "slope_deg"), [("firm_regolith", 15.0), ("dry_sand", 10.0)])
def test_slip_on_a_slope_matches_the_single_wheel_theory(flat_scene: Path, name: str,
                                                         slope_deg: float) -> None:
    got = _steady_slip(_on_slope(flat_scene, name, slope_deg))
    assert got == pytest.approx(_theory_slip(name, slope_deg), abs=0.06)


def test_rigid_contact_does_not_slip(flat_scene: Path) -> None:
    # (a rover bogged in sand: tests/env/test_nav_env.py, the episode ends stuck)
    assert abs(_steady_slip(_on_slope(flat_scene, "rigid", 10.0), 3.0)) < 0.02


def test_wheels_sink_into_sand_and_the_ground_truth_shows_it(flat_scene: Path) -> None:
    rigid = RoverSim(flat_scene, soil="rigid").pose()[0][2]
    sim = RoverSim(flat_scene, soil="dry_sand")
    sunk = rigid - sim.pose()[0][2]
    load = ROVER.mass_kg * 3.71 / 6
    z = float(sinkage_for_load(soil("dry_sand"), ROVER.wheel_radius_m, ROVER.wheel_width_m,
                               load, 0.0))
    assert sunk == pytest.approx(z, abs=0.008)  # the rocker-bogie shares its load unevenly
    assert np.all(sim.wheel_soil.sinkage_m > 0.5 * z)


def test_a_parked_rover_holds_on_a_slope_as_on_rigid_ground(flat_scene: Path) -> None:
    drift = {}
    for name in ("rigid", "dry_sand"):
        sim = _on_slope(flat_scene, name, 15.0)
        x0 = sim.pose()[0][0]
        sim.apply(0.0, 0.0)
        sim.advance(round(6.0 / sim.dt_physics_s))
        drift[name] = abs(sim.pose()[0][0] - x0)
    assert drift["dry_sand"] < max(2.0 * drift["rigid"], 0.02)


def test_same_inputs_same_trajectory(flat_scene: Path) -> None:
    poses = []
    for _ in range(2):
        sim = _on_slope(flat_scene, "drift_sand", 5.0)
        sim.apply(SPEED_M_S, 0.05)
        sim.advance(150)
        poses.append(np.concatenate(sim.pose()).tobytes())
    assert poses[0] == poses[1]


def test_odometry_overestimates_where_wheels_slip_and_the_log_says_why(
        flat_scene: Path, tmp_path: Path) -> None:
    import marsscene as ms

    out = tmp_path / "run"
    ms.drive(flat_scene, waypoints=[(-10.0, 0.0), (10.0, 0.0)], seconds=8.0,
             config=RunConfig(soil="drift_sand"), out_dir=out)
    gt = np.loadtxt(out / "gt.tum", comments="#")
    odom = np.loadtxt(out / "odom.tum", comments="#")
    travelled = np.linalg.norm(gt[-1, 1:3] - gt[0, 1:3])
    counted = np.linalg.norm(odom[-1, 1:3] - odom[0, 1:3])
    with open(out / "soil.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    slip = np.mean([float(r["slip_ml"]) for r in rows[len(rows) // 2:]])
    assert 0.1 < slip < 0.5
    # the encoders count the rim's travel: the ground covered over (1 - slip)
    assert counted > travelled * 1.1
    assert float(rows[-1]["sinkage_m_rl"]) > 0.01
    # the bag's /rover/wheel_soil, read back by rosbags: sinkage, slip, load per drive joint
    pytest.importorskip("rosbags")
    from rosbags.highlevel import AnyReader

    from marsscene.runs.export.bag import write_bag

    write_bag(out)
    with AnyReader([out / "bag"]) as reader:
        conns = [c for c in reader.connections if c.topic == "/rover/wheel_soil"]
        msgs = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(conns)]
    assert len(msgs) == len(rows)
    last = msgs[-1]
    assert list(last.name)[4] == "drive_rl"
    assert last.position[4] == pytest.approx(float(rows[-1]["sinkage_m_rl"]))
    assert last.velocity[2] == pytest.approx(float(rows[-1]["slip_ml"]))
    assert last.effort[0] == pytest.approx(float(rows[-1]["load_n_fl"]))


def test_unknown_soil_is_a_one_line_error() -> None:
    with pytest.raises(ConfigError, match="soil 'quicksand' is unknown"):
        RunConfig(soil="quicksand")
    with pytest.raises(ConfigError, match="soil"):
        RunConfig.from_dict({"run": {"soil": "quicksand"}})
