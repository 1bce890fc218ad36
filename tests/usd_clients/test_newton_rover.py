"""The USD rover in a real client: Newton 1.8 on CPU (``SolverSteel`` through
:class:`marsscene.sim.newton_rover.NewtonRover`). Skipped without the extra ``newton``; CI does
not install it (Warp's CPU kernels compile on first use, about 2 minutes here: see
docs/usd_rover.md). ``python perf/run.py newton`` runs the same checks and prints figures,
and the default-scene comparison with MuJoCo."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

pytest.importorskip("newton", reason="needs the extra [newton]")
pytest.importorskip("warp", reason="needs the extra [newton]")
pytest.importorskip("mujoco")

from marsscene.testing import newton_checks as bn

pytestmark = pytest.mark.newton


def test_parks_across_and_climbs_a_15_degree_slope(tmp_path: Path) -> None:
    res = bn.check_slope(tmp_path)
    assert abs(res["across_roll_deg"]) == pytest.approx(15.0, abs=0.5)  # upright: no tip
    assert abs(res["across_pitch_deg"]) < 0.5
    assert res["across_creep_m_s"] < 0.005  # wheels braked by their velocity drives
    assert res["up_travelled_m"] > 0.9 * 6.0
    assert res["up_grade"] == pytest.approx(math.tan(math.radians(15.0)), rel=0.05)
    assert res["up_tilt_max_deg"] < 17.0


def test_climbs_a_small_rock_and_is_stopped_by_a_large_one(tmp_path: Path) -> None:
    res = bn.check_rock(tmp_path)
    small, big = res["small"], res["big"]
    assert small["x1"] - small["x0"] > 0.9 * 7.5  # drove on, over the rock
    assert small["lift_m"] > 0.03 and small["roll_max_deg"] > 2.0  # ... and it was climbed
    far_edge = res["big_rock_x_m"][1]
    travelled = big["x1"] - big["x0"]
    if big["x1"] > res["big_rock_x_m"][0]:  # past the near face: only by climbing it
        assert big["lift_m"] > 0.3
    assert big["x1"] < far_edge and travelled < 0.9 * res["commanded_m"]


def test_sphere_rests_on_a_large_rock(tmp_path: Path) -> None:
    res = bn.check_sphere(tmp_path)
    assert res["sphere_centre_z_m"] == pytest.approx(res["expected_z_m"], abs=0.02)
    assert res["sphere_speed_after_3s"] < 0.01


def test_speed_and_path_agree_with_the_mujoco_runtime(tmp_path: Path) -> None:
    """The same cmd_vel plan (4 m straight at 0.3 m/s, a 45 deg arc at 0.1 rad/s) on a gentle
    procedural scene with rocks, MuJoCo's RoverSim vs Newton with the same rocks. Tolerances:
    speed 3 %, heading 3 deg, path 0.25 m: two solvers with different contact models (MuJoCo's
    soft convex contacts vs Steel's projected Gauss-Seidel rows) on the same geometry."""
    out = bn.gentle_scene(tmp_path)
    res = bn.compare_drive(out, straight_m=4.0, turn_deg=45.0)
    mj, nt = res["mujoco"], res["newton"]
    assert nt["straight_speed_m_s"] == pytest.approx(mj["straight_speed_m_s"], rel=0.03)
    assert nt["straight_yaw_deg"] == pytest.approx(mj["straight_yaw_deg"], abs=3.0)
    assert nt["turn_deg"] == pytest.approx(mj["turn_deg"], abs=3.0)
    assert res["path_gap_max_m"] < 0.25
    assert np.isfinite(res["newton_run"]["sim_s_per_wall_s"])
