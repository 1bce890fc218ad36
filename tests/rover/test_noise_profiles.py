"""Named sensor-noise profiles: the IMU model's statistics (Allan deviation), the per-run bias,
determinism, config errors, and exports that declare the noise actually simulated."""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.rover.config import NoiseConfig, RunConfig, noise_profiles
from marsscene.sensors.imu import ImuNoise, allan_deviation, imu_measure

REALISTIC = ("ln200s", "adis16495")
IMU_KEYS = ("gyro_noise_density_rad_s_rthz", "gyro_bias_walk_rad_s2_rthz",
            "gyro_turn_on_bias_rad_s", "accel_noise_density_m_s2_rthz",
            "accel_bias_walk_m_s3_rthz", "accel_turn_on_bias_m_s2")
SENSORS = (("gyro", "gyro_noise_density_rad_s_rthz", "gyro_bias_walk_rad_s2_rthz"),
           ("accel", "accel_noise_density_m_s2_rthz", "accel_bias_walk_m_s3_rthz"))


def _static(cfg: NoiseConfig, rate_hz: float, n: int, seed: int) -> dict[str, np.ndarray]:
    """``n`` samples of a static IMU (true = 0), gyro and accel, shape (n, 3)."""
    imu = ImuNoise(cfg, rate_hz, rng=np.random.default_rng(seed))
    a, g = imu.measure(np.zeros((n, 3)), np.zeros((n, 3)))
    return {"gyro": g, "accel": a}


def _model(nd: float, rw: float, tau: np.ndarray) -> np.ndarray:
    return np.sqrt(nd**2 / tau + rw**2 * tau / 3.0)


def _slope(tau: np.ndarray, adev: np.ndarray) -> float:
    return float(np.polyfit(np.log(tau), np.log(adev), 1)[0])


def test_profiles_are_cited_data_with_every_key() -> None:
    profiles = noise_profiles()
    assert {"none", *REALISTIC} <= set(profiles)
    for name, table in profiles.items():
        assert table["description"] and table["source"], name
        cfg = NoiseConfig(profile=name)
        for key in IMU_KEYS:
            assert getattr(cfg, key) == table[key], (name, key)
    assert all(v == 0.0 for k, v in NoiseConfig().to_dict().items()
               if isinstance(v, float))  # the default stays noise-free
    for name in REALISTIC:
        cfg = NoiseConfig(profile=name)
        assert all(getattr(cfg, k) > 0 for k in IMU_KEYS), name
        assert "doi:" in profiles[name]["source"]
    # datasheet figures, converted: LN-200 0.07 deg/sqrt(h), 50 ug/sqrt(Hz); ADIS 0.09 deg/sqrt(h)
    ln = NoiseConfig(profile="ln200s")
    assert ln.gyro_noise_density_rad_s_rthz == pytest.approx(math.radians(0.07) / 60, rel=1e-4)
    assert ln.accel_noise_density_m_s2_rthz == pytest.approx(50e-6 * 9.80665, rel=1e-4)
    adis = NoiseConfig(profile="adis16495")
    assert adis.gyro_noise_density_rad_s_rthz == pytest.approx(math.radians(0.09) / 60, rel=1e-4)


@pytest.mark.parametrize("name", REALISTIC)
def test_allan_deviation_at_1s_is_the_noise_density(name: str) -> None:
    """One hour at 100 Hz: sigma(1 s) = density (white noise), slope -1/2 below the bias walk."""
    cfg = NoiseConfig(profile=name)
    data = _static(cfg, 100.0, 360_000, seed=1)
    for sensor, nd_key, rw_key in SENSORS:
        nd, rw = getattr(cfg, nd_key), getattr(cfg, rw_key)
        one = allan_deviation(data[sensor], 100.0, [1.0])[0]  # (3,) axes
        assert np.all(np.abs(one / nd - 1.0) < 0.04), (sensor, one / nd)
        assert one.mean() / _model(nd, rw, np.array([1.0]))[0] == pytest.approx(1.0, abs=0.02)
        tau_corner = math.sqrt(3.0) * nd / rw  # where the walk takes over
        taus = np.geomspace(0.05, min(2.0, tau_corner / 20.0), 6)
        adev = allan_deviation(data[sensor], 100.0, taus).mean(axis=1)
        assert _slope(taus, adev) == pytest.approx(-0.5, abs=0.04), sensor


@pytest.mark.parametrize("name", REALISTIC)
def test_allan_deviation_shows_the_bias_random_walk(name: str) -> None:
    """Long static series (sampled at 50 per corner time, 8 runs x 3 axes): slope +1/2 at long
    tau with sigma(tau) = K sqrt(tau / 3), and the minimum where the model puts it."""
    cfg = NoiseConfig(profile=name)
    for sensor, nd_key, rw_key in SENSORS:
        nd, rw = getattr(cfg, nd_key), getattr(cfg, rw_key)
        corner_s = math.sqrt(3.0) * nd / rw
        rate = 50.0 / corner_s
        series = np.hstack([_static(cfg, rate, 200_000, seed=s)[sensor] for s in range(8)])
        taus = corner_s * np.array([0.1, 1.0, 10.0, 20.0, 40.0])
        adev = allan_deviation(series, rate, taus).mean(axis=1)
        np.testing.assert_allclose(adev, _model(nd, rw, taus), rtol=0.06)
        walk = taus >= 10 * corner_s
        assert _slope(taus[walk], adev[walk]) == pytest.approx(
            _slope(taus[walk], _model(nd, rw, taus[walk])), abs=0.06)
        assert _slope(taus[walk], adev[walk]) > 0.4
        k_est = adev[-1] / math.sqrt(taus[-1] / 3.0)  # the white part adds < 0.2 % here
        assert k_est == pytest.approx(rw, rel=0.08), sensor
        floor = math.sqrt(2.0 * nd * rw / math.sqrt(3.0))  # min of the model, at the corner
        assert adev[1] == pytest.approx(floor, rel=0.06)


def test_adis16495_allan_floor_is_the_datasheet_bias_stability() -> None:
    """The walk was derived from the in-run bias stability: the simulated Allan minimum
    reproduces 0.8 deg/h (gyro) and 3.2 ug (accel) from the ADIS16495-1 data sheet."""
    cfg = NoiseConfig(profile="adis16495")
    for sensor, nd_key, rw_key, datasheet in (
            ("gyro", "gyro_noise_density_rad_s_rthz", "gyro_bias_walk_rad_s2_rthz",
             math.radians(0.8) / 3600.0),
            ("accel", "accel_noise_density_m_s2_rthz", "accel_bias_walk_m_s3_rthz",
             3.2e-6 * 9.80665)):
        corner_s = math.sqrt(3.0) * getattr(cfg, nd_key) / getattr(cfg, rw_key)
        rate = 50.0 / corner_s
        series = np.hstack([_static(cfg, rate, 100_000, seed=s)[sensor] for s in range(8)])
        taus = corner_s * np.geomspace(0.25, 4.0, 9)
        adev = allan_deviation(series, rate, taus).mean(axis=1)
        assert adev.min() == pytest.approx(datasheet, rel=0.05), sensor


def test_turn_on_bias_is_constant_in_a_run_and_differs_between_seeds() -> None:
    cfg = NoiseConfig(profile="ln200s", gyro_bias_walk_rad_s2_rthz=0.0,
                      accel_bias_walk_m_s3_rthz=0.0)
    n = 40_000
    runs = [ImuNoise(cfg, 100.0, rng=np.random.default_rng(seed)) for seed in (0, 1)]
    for imu in runs:
        start = imu.gyro_bias_rad_s.copy()
        a, g = imu.measure(np.zeros((n, 3)), np.zeros((n, 3)))
        np.testing.assert_array_equal(imu.gyro_bias_rad_s, start)  # no walk: constant
        sg, sa = cfg.white_sigmas(100.0)
        # the mean of each half is the same turn-on bias (within 5 standard errors)
        for x, bias, s in ((g, imu.gyro_turn_on_rad_s, sg), (a, imu.accel_turn_on_m_s2, sa)):
            for half in (x[: n // 2], x[n // 2:]):
                assert np.all(np.abs(half.mean(axis=0) - bias) < 5 * s / math.sqrt(n / 2))
    assert not np.allclose(runs[0].gyro_turn_on_rad_s, runs[1].gyro_turn_on_rad_s)
    # over many runs the turn-on bias has the profile's sigma
    draws = np.array([ImuNoise(cfg, 100.0, rng=np.random.default_rng(s)).accel_turn_on_m_s2
                      for s in range(400)])
    assert draws.std() == pytest.approx(cfg.accel_turn_on_bias_m_s2, rel=0.1)
    # with the walk on, the bias moves but the turn-on part stays
    imu = ImuNoise(NoiseConfig(profile="ln200s"), 100.0, rng=np.random.default_rng(0))
    on = imu.gyro_turn_on_rad_s.copy()
    imu.measure(np.zeros((1000, 3)), np.zeros((1000, 3)))
    assert not np.allclose(imu.gyro_bias_rad_s, on)
    np.testing.assert_array_equal(imu.gyro_turn_on_rad_s, on)


def test_imu_noise_is_deterministic() -> None:
    cfg = NoiseConfig(profile="adis16495")

    def run(seed: int) -> np.ndarray:
        imu = ImuNoise(cfg, 100.0, rng=np.random.default_rng(seed))
        rows = [np.concatenate(imu.measure(np.array([0.0, 0.0, 3.72]), np.zeros(3)))
                for _ in range(200)]
        return np.array(rows)

    np.testing.assert_array_equal(run(5), run(5))
    assert not np.array_equal(run(5), run(6))
    assert run(5).shape == (200, 6)


def test_legacy_noise_configs_draw_exactly_as_before() -> None:
    """Without turn-on bias or walk the model draws what ``imu_measure`` drew: old run configs
    replay byte for byte; profile none changes nothing."""
    exact = ImuNoise(NoiseConfig(), 100.0, rng=np.random.default_rng(0))
    acc, gyr = np.full((50, 3), 0.3), np.full((50, 3), -0.1)
    for x, y in zip(exact.measure(acc, gyr), (acc, gyr), strict=True):
        np.testing.assert_array_equal(x, y)
    cfg = NoiseConfig(accel_sigma_m_s2=0.05, gyro_sigma_rad_s=0.01, gyro_bias_rad_s=(0, 0, 1e-3))
    imu = ImuNoise(cfg, 100.0, rng=np.random.default_rng(3))
    old_rng = np.random.default_rng(3)
    for _ in range(20):
        acc, gyr = np.array([0.1, 0.2, 3.7]), np.array([0.0, 0.01, 0.02])
        new = imu.measure(acc, gyr)
        old = imu_measure(acc, gyr, cfg, rng=old_rng)
        np.testing.assert_array_equal(new[0], old[0])
        np.testing.assert_array_equal(new[1], old[1])


def test_bad_profile_names_are_one_line_config_errors(tmp_path: Path, runner) -> None:
    for make in (lambda: NoiseConfig(profile="ln-200"),
                 lambda: NoiseConfig(profile="none").with_profile("bmi088")):
        with pytest.raises(ConfigError) as err:
            make()
        msg = str(err.value)
        assert "\n" not in msg and "unknown" in msg
        assert all(name in msg for name in ("none", "ln200s", "adis16495"))
    p = tmp_path / "run.toml"
    p.write_text('[noise]\nprofile = "mems"\n')
    with pytest.raises(ConfigError, match=r"noise\.profile = 'mems' is unknown; known"):
        RunConfig.from_toml(p)
    from marsscene.cli import main

    res = runner.invoke(main, ["drive", str(tmp_path), "--noise-profile", "mems"])
    assert res.exit_code == 2 and "ln200s" in res.output


def test_run_config_profile_overrides_and_with_profile(tmp_path: Path) -> None:
    p = tmp_path / "run.toml"
    p.write_text('[noise]\nprofile = "ln200s"\nslip_mean = 0.0\naccel_sigma_m_s2 = 0.01\n')
    noise = RunConfig.from_toml(p).noise
    ln = NoiseConfig(profile="ln200s")
    assert noise.profile == "ln200s" and noise.slip_mean == 0.0 and noise.accel_sigma_m_s2 == 0.01
    assert noise.gyro_noise_density_rad_s_rthz == ln.gyro_noise_density_rad_s_rthz
    assert NoiseConfig.from_toml(p) == noise  # a [noise] file reads the same
    moved = noise.with_profile("adis16495")  # overrides kept, the rest from the new profile
    assert moved.slip_mean == 0.0 and moved.accel_sigma_m_s2 == 0.01
    assert moved.gyro_noise_density_rad_s_rthz == NoiseConfig(
        profile="adis16495").gyro_noise_density_rad_s_rthz
    assert NoiseConfig().with_profile("ln200s") == ln
    # sigma per sample = density * sqrt(rate), combined with any legacy per-sample sigma
    g, a = noise.white_sigmas(100.0)
    assert g == pytest.approx(ln.gyro_noise_density_rad_s_rthz * 10.0)
    assert a == pytest.approx(math.hypot(0.01, ln.accel_noise_density_m_s2_rthz * 10.0))


def test_benchmark_specs_use_a_realistic_profile_by_default() -> None:
    from marsscene.benchmark.slam.spec import BENCHMARK_NOISE_PROFILE, SlamSpec

    doc: dict[str, Any] = {"scenes": [{"name": "s", "preset": "mars-base",
                                       "route": {"shape": "loop", "length_m": 40.0}}],
                           "methods": [{"name": "wheel", "kind": "wheel-odometry"}]}
    assert BENCHMARK_NOISE_PROFILE in REALISTIC
    spec = SlamSpec.from_dict(doc)
    assert spec.run_config(lidar=False).noise == NoiseConfig(profile=BENCHMARK_NOISE_PROFILE)
    spec = SlamSpec.from_dict({**doc, "sensors": {"noise_profile": "none"}})
    assert spec.run_config(lidar=False).noise == NoiseConfig()
    spec = SlamSpec.from_dict({**doc, "sensors": {"noise": {"slip_mean": 0.0}}})
    assert spec.run_config(lidar=False).noise == NoiseConfig(profile=BENCHMARK_NOISE_PROFILE,
                                                             slip_mean=0.0)
    with pytest.raises(ConfigError, match="adis"):
        SlamSpec.from_dict({**doc, "sensors": {"noise_profile": "adis"}})


# --- a short drive with a profile: run.json, EuRoC, ORB-SLAM3 and ROS covariances ---------


def _drive(scene: Path, out: Path, profile: str, seed: int, camera: bool = True) -> Path:
    from marsscene.runtime import CameraConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    run = RunConfig(noise=NoiseConfig(profile=profile), camera=CameraConfig(
        width_px=48, height_px=36, rate_hz=5.0, shadows=False) if camera else None)
    drive_sim(RoverSim(scene, run=run), command=(0.3, 0.0), seconds=1.0, out_dir=out,
          rng=stage_rng(seed, "sensors"))
    return out


@pytest.fixture(scope="module")
def ln_runs(gentle_scene: Path, tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    from marsscene.errors import RuntimeSimError

    base = tmp_path_factory.mktemp("noise_runs")
    try:
        # the camera (for the EuRoC export) on the first only: it draws from its own stream
        return [_drive(gentle_scene, base / name, "ln200s", seed, camera=name == "a")
                for name, seed in (("a", 4), ("b", 4), ("c", 5))]
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")


def _yaml_numbers(text: str) -> dict[str, float]:
    out = {}
    for line in text.splitlines():
        key, _, value = line.partition(":")
        try:
            out[key.strip()] = float(value)
        except ValueError:
            continue
    return out


def test_drive_with_a_profile_is_deterministic_and_recorded(ln_runs: list[Path]) -> None:
    a, b, c = ln_runs
    for name in ("imu.csv", "wheels.csv", "odom.tum"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    assert (a / "imu.csv").read_bytes() != (c / "imu.csv").read_bytes()
    meta = json.loads((a / "run.json").read_text())
    assert NoiseConfig(**{k: tuple(v) if isinstance(v, list) else v
                          for k, v in meta["noise"].items()}) == NoiseConfig(profile="ln200s")
    assert meta["noise"]["profile"] == "ln200s"
    bias = meta["summary"]["imu_bias"]
    other = json.loads((c / "run.json").read_text())["summary"]["imu_bias"]
    assert bias["gyro_start_rad_s"] != other["gyro_start_rad_s"]  # per-run, per-seed draw
    assert bias["gyro_start_rad_s"] != bias["gyro_end_rad_s"]  # the bias walked
    imu = np.loadtxt(a / "imu.csv", delimiter=",", skiprows=1)
    true = np.loadtxt(a / "imu_true.csv", delimiter=",", skiprows=1)
    err = imu[:, 4:7] - true[:, 4:7] - np.array(bias["gyro_start_rad_s"])
    sigma = NoiseConfig(profile="ln200s").white_sigmas(100.0)[0]
    assert err.std() == pytest.approx(sigma, rel=0.15)  # white gyro noise at 100 Hz
    # imu_bias.csv: the bias inside every sample; what is left is white noise, mean 0
    walk = np.loadtxt(a / "imu_bias.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(walk[:, 0], imu[:, 0])
    np.testing.assert_allclose(walk[-1, 1:4], bias["gyro_end_rad_s"], rtol=1e-8)  # CSV digits
    np.testing.assert_allclose(walk[-1, 4:7], bias["accel_end_m_s2"], rtol=1e-8)
    step = NoiseConfig(profile="ln200s").gyro_bias_walk_rad_s2_rthz * np.sqrt(0.01)
    np.testing.assert_allclose(np.diff(walk[:, 1:4], axis=0).std(), step, rtol=0.15)
    white = imu[:, 4:7] - true[:, 4:7] - walk[:, 1:4]
    assert white.std() == pytest.approx(sigma, rel=0.15)
    assert np.abs(white.mean(axis=0)).max() < 4 * sigma / np.sqrt(len(white))


def test_exports_declare_the_simulated_noise(ln_runs: list[Path], tmp_path: Path) -> None:
    from marsscene.runs.export.bag_topics import add_state
    from marsscene.runs.export.datasets import export_dataset
    from marsscene.runs.runlog import RunLog

    cfg = NoiseConfig(profile="ln200s")
    out = export_dataset(ln_runs[0], "euroc", tmp_path / "euroc")
    sensor = _yaml_numbers((out / "mav0/imu0/sensor.yaml").read_text())
    want = {"gyroscope_noise_density": cfg.gyro_noise_density_rad_s_rthz,
            "gyroscope_random_walk": cfg.gyro_bias_walk_rad_s2_rthz,
            "accelerometer_noise_density": cfg.accel_noise_density_m_s2_rthz,
            "accelerometer_random_walk": cfg.accel_bias_walk_m_s3_rthz}
    for key, value in want.items():
        assert sensor[key] == pytest.approx(value, rel=1e-8), key
    orb_text = (out / "orbslam3_mono_inertial.yaml").read_text()
    orb = _yaml_numbers(orb_text)
    assert "floor" not in orb_text
    for key, euroc in (("IMU.NoiseGyro", "gyroscope_noise_density"),
                       ("IMU.NoiseAcc", "accelerometer_noise_density"),
                       ("IMU.GyroWalk", "gyroscope_random_walk"),
                       ("IMU.AccWalk", "accelerometer_random_walk")):
        assert orb[key] == pytest.approx(want[euroc], rel=1e-8), key
    # ground-truth bias columns start at the run's turn-on bias
    bias = json.loads((ln_runs[0] / "run.json").read_text())["summary"]["imu_bias"]
    gt = np.loadtxt(out / "mav0/state_groundtruth_estimate0/data.csv", delimiter=",",
                    comments="#")
    walk = np.loadtxt(ln_runs[0] / "imu_bias.csv", delimiter=",", skiprows=1)
    t_gt = gt[:, 0] * 1e-9
    for k in range(6):  # the logged bias at the ground-truth stamps
        np.testing.assert_allclose(gt[:, 11 + k], np.interp(t_gt, walk[:, 0], walk[:, 1 + k]),
                                   rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(gt[0, 11:14], bias["gyro_start_rad_s"],
                               atol=5 * NoiseConfig(profile="ln200s").gyro_bias_walk_rad_s2_rthz)
    # ROS: /rover/imu_noisy covariances are the per-sample white-noise variances
    calls: dict[str, list[tuple[Any, ...]]] = defaultdict(list)

    from marsscene.runs.export.topic_table import ROVER

    class _Bag:
        def __init__(self) -> None:
            self.T: dict[str, Any] = defaultdict(lambda: (lambda *a, **k: None))
            self.names = ROVER

        def add(self, topic: str, t: float, fn: Any, *args: Any) -> None:
            calls[topic].append(args)

        def __getattr__(self, name: str) -> Any:
            return lambda *a, **k: None

    add_state(_Bag(), RunLog(ln_runs[0]), [], False)  # type: ignore[arg-type]
    g_sigma, a_sigma = cfg.white_sigmas(100.0)
    *_, g_var, a_var = calls["/rover/imu_noisy"][0]
    assert g_var == pytest.approx(g_sigma**2, rel=1e-6)
    assert a_var == pytest.approx(a_sigma**2, rel=1e-6)


def test_noise_free_export_floors_orbslam3_and_says_so(bag_run: Path, tmp_path: Path) -> None:
    """``bag_run`` has white IMU noise only (legacy sigma keys, no walk): the random walks are
    0 in imu0/sensor.yaml, and ORB-SLAM3 gets a commented floor instead of 0."""
    from marsscene.runs.export.datasets import export_dataset

    out = export_dataset(bag_run, "euroc", tmp_path / "e")
    sensor = _yaml_numbers((out / "mav0/imu0/sensor.yaml").read_text())
    assert sensor["gyroscope_random_walk"] == 0.0 and sensor["accelerometer_random_walk"] == 0.0
    text = (out / "orbslam3_mono_inertial.yaml").read_text()
    orb = _yaml_numbers(text)
    assert orb["IMU.GyroWalk"] > 0 and orb["IMU.AccWalk"] > 0
    assert text.count("needs > 0, so a small floor is declared") == 2
    assert orb["IMU.NoiseGyro"] == pytest.approx(0.01 / 10.0)  # sigma / sqrt(100 Hz)
