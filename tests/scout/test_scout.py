"""The Ingenuity-class scout: hover power and thrust margin against the published vehicle
(Balaram et al. 2018: 1.8 kg, 1.21 m coaxial rotors, about 350 W in hover, 2,400-2,900 rpm),
the Mars air density, and a flight on a built scene: waypoints reached, take-off and landing
on the terrain, the run folder, the same bytes from the same seed."""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from marsscene.scout import FlightPlan, ScoutConfig, air_density_kg_m3, fly
from marsscene.scout.aero import hover_power_w, max_thrust_n, thrust_coefficient
from marsscene.units import MARS_GRAVITY_M_S2

CFG = ScoutConfig.load()
WEIGHT_N = CFG.mass_kg * MARS_GRAVITY_M_S2


def test_air_density_at_jezero_is_in_the_design_range() -> None:
    """0.015-0.020 kg/m^3 at the Jezero floor by day (module doc of marsscene.scout.config),
    thinner higher up (one scale height: 1/e) and colder air denser."""
    rho = air_density_kg_m3()
    assert 0.015 < rho < 0.020
    assert air_density_kg_m3(-2_600.0 + 11_100.0) == pytest.approx(rho / np.e)
    assert air_density_kg_m3(temperature_k=200.0) > rho


def test_hover_power_matches_the_published_figure() -> None:
    """~350 W in hover at 1.8 kg (Balaram et al. 2018): within 10 % at the design density
    0.0175 kg/m^3; the induced power scales as rho^-1/2 (momentum theory)."""
    assert hover_power_w(CFG, 0.0175) == pytest.approx(CFG.published_hover_power_w, rel=0.10)
    assert hover_power_w(CFG, 0.014) / hover_power_w(CFG, 0.0175) == pytest.approx(
        np.sqrt(0.0175 / 0.014))


def test_thrust_to_weight_margin_at_the_top_rotor_speed() -> None:
    """At 2,900 rpm the thrust is (2900 / 2537)^2 = 1.31 weights at the reference density
    (C_T of the flight-1 hover at 2,537 rpm), above 1 even at the thin end of the design range
    (0.014 kg/m^3); the hover rpm lies inside the published 2,400-2,900 rpm."""
    assert max_thrust_n(CFG, 0.0175) / WEIGHT_N == pytest.approx((2900 / 2537) ** 2)
    assert max_thrust_n(CFG, 0.014) / WEIGHT_N > 1.0
    assert 0.005 < thrust_coefficient(CFG) < 0.02
    assert CFG.rpm_min < CFG.hover_rpm_ref < CFG.rpm_max


@pytest.fixture(scope="module")
def scene(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [30, 30]}})
    out = tmp_path_factory.mktemp("scout") / "scene"
    ms.write_scene(ms.build_scene(cfg, seed=4), out)
    return out


PLAN = FlightPlan(altitude_m=3.0, speed_m_s=2.0, hover_s=0.5, camera_px=(32, 24),
                  camera_hz=1.0)
WAYPOINTS = [[4.0, 0.0], [4.0, 3.0]]


@pytest.fixture(scope="module")
def flight(scene: Path, tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    return fly(scene, WAYPOINTS, plan=PLAN, out_dir=tmp_path_factory.mktemp("f") / "run", seed=3)


def test_the_controller_reaches_each_waypoint_and_lands_on_the_terrain(flight, scene) -> None:  # type: ignore[no-untyped-def]
    """Every waypoint reached within the plan's 0.5 m, the climb to 3 m above the ground, and a
    touchdown on the terrain: the feet rest on it (base 0.30 m above the ground under it) within
    0.5 m of the last waypoint, and the last altimeter range is the leg height."""
    from marsscene.scout.vehicle import ScoutSim

    assert flight.reached == [True, True] and flight.touchdown_s is not None
    xyz = flight.gt.xyz_m
    hf = ScoutSim(scene, CFG, density_kg_m3=0.0185).heightfield
    ground = np.asarray(hf.sample(xyz[:, 0], xyz[:, 1]))
    assert (xyz[:, 2] - ground).max() == pytest.approx(3.0 + 0.0, abs=0.5)
    assert np.hypot(*(xyz[-1, :2] - WAYPOINTS[-1])) < PLAN.tolerance_m
    assert xyz[-1, 2] - ground[-1] == pytest.approx(CFG.body_above_feet_m, abs=0.06)
    alt = np.loadtxt(flight.out_dir / "altimeter.csv", delimiter=",", skiprows=1)
    assert alt[-1, 2] == pytest.approx(CFG.body_above_feet_m, abs=0.06)
    assert np.std(alt[:, 1] - alt[:, 2]) == pytest.approx(CFG.altimeter_sigma_m, rel=0.2)
    assert 250.0 < flight.summary["mean_power_w"] < 450.0


def test_run_folder_has_poses_images_and_altimeter_and_repeats_byte_for_byte(
        flight, scene, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from marsscene.runs.tum import read_tum

    out = flight.out_dir
    images = sorted((out / "images").glob("*.png"))
    cams = read_tum(out / "images.tum")
    assert len(images) == len(cams.timestamps_s) == flight.summary["images"] > 5
    assert len(read_tum(out / "gt.tum").timestamps_s) == len(flight.gt.timestamps_s)
    again = fly(scene, WAYPOINTS, plan=PLAN, out_dir=tmp_path / "run", seed=3)

    def digest(folder: Path) -> dict[str, str]:
        return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
                for p in sorted(folder.rglob("*")) if p.is_file()}

    assert digest(out) == digest(again.out_dir)


def test_fly_cli_reports_user_mistakes_in_one_line(scene: Path, tmp_path: Path) -> None:
    """A waypoint off the terrain is a one-line error (exit 1), a bad camera size a usage error
    (exit 2); nothing is written."""
    from click.testing import CliRunner

    from marsscene.cli import main

    wp = tmp_path / "wp.txt"
    wp.write_text("100 0\n")
    out = tmp_path / "run"
    res = CliRunner().invoke(main, ["fly", str(scene), "--waypoints", str(wp), "--out", str(out)])
    assert res.exit_code == 1 and "waypoints outside the terrain" in res.output
    assert len(res.output.strip().splitlines()) == 1 and not out.exists()
    res = CliRunner().invoke(main, ["fly", str(scene), "--waypoints", str(wp), "--out", str(out),
                                    "--camera-size", "big"])
    assert res.exit_code == 2 and "WIDTHxHEIGHT" in res.output
