"""Rock placement: Poisson counts, area fraction, burial, tilt, ejecta, clusters, masks, slope."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from marsscene.craters.table import CraterTable
from marsscene.errors import ConfigError
from marsscene.rocks import (
    RockConfig,
    cumulative_area_fraction,
    differential_number_density,
    expected_count,
    place_rocks,
)
from marsscene.terrain.heightfield import Heightfield


def flat(size_m: float = 100.0, post_m: float = 0.5) -> Heightfield:
    n = round(size_m / post_m) + 1
    return Heightfield.centered(np.zeros((n, n), np.float32), post_m)


def rough(seed: int = 3, size_m: float = 40.0) -> Heightfield:
    n = int(size_m / 0.25) + 1
    yy, xx = np.mgrid[0:n, 0:n] * 0.25
    rng = np.random.default_rng(seed)
    z = 0.8 * np.sin(xx / 3.0) * np.cos(yy / 4.0) + 0.02 * rng.standard_normal((n, n))
    return Heightfield.centered(z.astype(np.float32), 0.25)


NO_CRATERS = CraterTable.empty()


def test_poisson_counts_over_seeds() -> None:
    hf = flat()
    cfg = RockConfig(placement="uniform", d_min_m=0.2)
    lam = expected_count(hf.area_m2, k=cfg.k, d_min_m=0.2, d_max_m=cfg.d_max_m)
    counts = np.array([len(place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(s)))
                       for s in range(8)])
    assert np.all(np.abs(counts - lam) < 4.5 * np.sqrt(lam))
    # the mean of 8 Poisson draws is within 4 standard errors
    assert abs(counts.mean() - lam) < 4 * np.sqrt(lam / 8)


def test_realised_area_fraction_converges_to_f_difference_not_k() -> None:
    hf = flat()
    cfg = RockConfig(placement="uniform", k=0.05, d_min_m=0.1, d_max_m=3.0)
    target = float(cumulative_area_fraction(0.1, k=0.05) - cumulative_area_fraction(3.0, k=0.05))
    # compound-Poisson standard deviation of the covered fraction
    second, _ = quad(lambda d: float(differential_number_density(d, k=0.05)) * (np.pi * d**2 / 4)
                     ** 2, 0.1, 3.0, limit=200)
    sd = np.sqrt(hf.area_m2 * second) / hf.area_m2
    fracs = []
    for s in range(4):
        r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(s))
        fracs.append(np.sum(np.pi * r.diameter_m**2 / 4) / hf.area_m2)
    assert abs(np.mean(fracs) - target) < 4 * sd / 2
    assert abs(np.mean(fracs) - 0.05) > 10 * sd  # clearly not k


def test_rocks_sit_at_prescribed_burial_and_tilt_limit() -> None:
    hf = rough()
    cfg = RockConfig(placement="uniform", d_min_m=0.1, max_tilt_deg=12.0, tilt_jitter_deg=3.0,
                     burial_fraction=(0.1, 0.4))
    r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(5))
    assert len(r) > 500
    x, y, z = r.position_xyz_m.T
    # base within 1 cm of (surface - burial)
    assert np.max(np.abs(hf.sample(x, y) - r.burial_m - z)) < 0.01
    assert np.all(r.burial_m >= 0) and np.all(r.height_m > 0)
    frac = r.burial_m / (r.burial_m + r.height_m)
    assert frac.min() >= 0.1 - 1e-9 and frac.max() <= 0.4 + 1e-9
    ratio = r.height_m / r.diameter_m
    assert ratio.min() >= 0.35 - 1e-9 and ratio.max() <= 0.65 + 1e-9
    np.testing.assert_allclose(np.linalg.norm(r.orientation_wxyz, axis=1), 1.0, atol=1e-12)
    # the rock's up axis: third column of the rotation = tilt from vertical <= limit
    _, qx, qy, _ = r.orientation_wxyz.T
    up_z = 1.0 - 2.0 * (qx**2 + qy**2)
    assert np.degrees(np.arccos(np.clip(up_z, -1, 1))).max() <= 12.0 + 1e-6
    np.testing.assert_allclose(r.scale_xyz_m[:, 2], r.height_m + r.burial_m)
    np.testing.assert_allclose(np.sqrt(r.scale_xyz_m[:, 0] * r.scale_xyz_m[:, 1]), r.diameter_m)


def test_up_axis_follows_gentle_slope() -> None:
    n = 201
    _, xx = np.mgrid[0:n, 0:n] * 0.25
    hf = Heightfield.centered((0.1 * xx).astype(np.float32), 0.25)  # 5.7 deg slope, uphill +x
    cfg = RockConfig(placement="uniform", tilt_jitter_deg=0.0, max_tilt_deg=30.0)
    r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(2))
    _, qx, qy, _ = r.orientation_wxyz.T
    w = r.orientation_wxyz[:, 0]
    qz = r.orientation_wxyz[:, 3]
    up = np.column_stack([2 * (qx * qz + w * qy), 2 * (qy * qz - w * qx), 1 - 2 * (qx**2 + qy**2)])
    normal = np.array([-0.1, 0.0, 1.0]) / np.sqrt(1.01)
    np.testing.assert_allclose(up, np.broadcast_to(normal, up.shape), atol=1e-6)


def test_ejecta_weighting_raises_density_near_rims_and_fades_with_age() -> None:
    hf = flat(200.0, 0.5)
    crater = CraterTable(np.array([[0.0, 0.0]]), [40.0], [8.0], [1.5], [0.0], [0])
    cfg = RockConfig(placement="ejecta", ejecta_boost=5.0, d_min_m=0.2)

    def ratio(craters: CraterTable) -> float:
        r = place_rocks(hf, craters, cfg, rng=np.random.default_rng(11))
        dist = np.hypot(*r.position_xyz_m[:, :2].T)
        near = np.sum((dist > 16) & (dist < 30)) / (np.pi * (30**2 - 16**2))
        far = np.sum(dist > 60) / (hf.area_m2 - np.pi * 60**2)
        return float(near / far)

    assert ratio(crater) > 3.0  # rim band ~5x, blanket decays from 1 -> ~0.5
    old = CraterTable(np.array([[0.0, 0.0]]), [40.0], [8.0], [1.5], [4.0], [0])
    assert abs(ratio(old) - 1.0) < 0.25  # faded: uniform within Poisson noise


def test_clustered_placement_is_overdispersed() -> None:
    hf = flat()
    cfg = RockConfig(placement="clustered", d_min_m=0.2, cluster_radius_m=1.5,
                     rocks_per_cluster=30)
    r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(4))
    assert hf.contains(r.position_xyz_m[:, 0], r.position_xyz_m[:, 1]).all()
    counts, _, _ = np.histogram2d(*r.position_xyz_m[:, :2].T, bins=20)
    assert counts.var() / counts.mean() > 5.0  # Poisson would give ~1
    uni = place_rocks(hf, NO_CRATERS, RockConfig(placement="uniform", d_min_m=0.2),
                      rng=np.random.default_rng(4))
    c2, _, _ = np.histogram2d(*uni.position_xyz_m[:, :2].T, bins=20)
    assert 0.7 < c2.var() / c2.mean() < 1.4


def test_rock_field_polygon_and_k_map() -> None:
    hf = flat()
    poly = ((-50.0, -50.0), (0.0, -50.0), (0.0, 50.0), (-50.0, 50.0))  # west half
    cfg = RockConfig(placement="uniform", k=0.05, field_k=0.3, field_polygon_xy_m=poly,
                     d_min_m=0.2)
    r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(8))
    west = np.sum(r.position_xyz_m[:, 0] < 0)
    east = len(r) - west
    half = hf.area_m2 / 2
    for n, k in [(west, 0.3), (east, 0.05)]:
        lam = expected_count(half, k=k, d_min_m=0.2, d_max_m=3.0)
        assert abs(n - lam) < 4.5 * np.sqrt(lam)
    kmap = np.where(hf.xy_of(*np.indices(hf.shape))[1] > 0, 0.2, 0.05)  # rows: y, cols: x
    r2 = place_rocks(hf, NO_CRATERS, RockConfig(placement="uniform", d_min_m=0.2),
                     rng=np.random.default_rng(9), k_map=kmap)
    north = np.sum(r2.position_xyz_m[:, 1] > 0)
    lam_n = expected_count(half, k=0.2, d_min_m=0.2, d_max_m=3.0)
    assert abs(north - lam_n) < 4.5 * np.sqrt(lam_n)
    with pytest.raises(ConfigError, match="k_map"):
        place_rocks(hf, NO_CRATERS, RockConfig(), rng=np.random.default_rng(0),
                    k_map=np.zeros(hf.shape))


def test_slope_limit() -> None:
    n = 161
    _, xx = np.mgrid[0:n, 0:n] * 0.25
    z = np.where(xx > 20.0, (xx - 20.0) * 1.5, 0.0)  # east half at 56 deg
    hf = Heightfield.centered(z.astype(np.float32), 0.25)
    cfg = RockConfig(placement="uniform", max_slope_deg=30.0, d_min_m=0.1, d_max_m=0.5)
    r = place_rocks(hf, NO_CRATERS, cfg, rng=np.random.default_rng(1))
    assert len(r) > 100
    assert np.all(r.position_xyz_m[:, 0] < 0.75)  # nothing on the steep half


def test_count_limit_needs_explicit_override() -> None:
    hf = flat(100.0, 0.5)
    with pytest.raises(ConfigError, match="max_rocks"):
        place_rocks(hf, NO_CRATERS, RockConfig(d_min_m=0.001), rng=np.random.default_rng(0))
    small = RockConfig(d_min_m=0.1, max_rocks=1000)
    with pytest.raises(ConfigError, match=r"rocks.max_rocks = 1000"):
        place_rocks(hf, NO_CRATERS, small, rng=np.random.default_rng(0))


def test_deterministic() -> None:
    hf = rough()
    a = place_rocks(hf, NO_CRATERS, RockConfig(), rng=np.random.default_rng(3))
    b = place_rocks(hf, NO_CRATERS, RockConfig(), rng=np.random.default_rng(3))
    for name in ("position_xyz_m", "diameter_m", "orientation_wxyz", "prototype", "scale_xyz_m"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_orientation_is_the_tilt_after_the_yaw_as_rotations_compose() -> None:
    from scipy.spatial.transform import Rotation

    from marsscene.rocks.population import orientations

    rng = np.random.default_rng(11)
    n = 400
    gx, gy = rng.normal(0, 0.4, (2, n))
    gx[:10] = gy[:10] = 0.0  # flat ground: yaw only
    yaw = rng.uniform(0, 2 * np.pi, n)
    jitter = rng.normal(0, 0.05, (n, 2))
    jitter[:5] = 0.0
    q = orientations(gx, gy, yaw, jitter, max_tilt_rad=np.radians(25.0))
    tx = -gx * np.arctan(np.hypot(gx, gy)) / np.where(np.hypot(gx, gy) > 0, np.hypot(gx, gy), 1)
    ty = -gy * np.arctan(np.hypot(gx, gy)) / np.where(np.hypot(gx, gy) > 0, np.hypot(gx, gy), 1)
    tx, ty = tx + jitter[:, 0], ty + jitter[:, 1]
    tilt = np.hypot(tx, ty)
    phi = np.arctan2(ty, tx)
    axis = np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(n)])
    ref = (Rotation.from_rotvec(axis * np.minimum(tilt, np.radians(25.0))[:, None])
           * Rotation.from_rotvec(np.column_stack([np.zeros((n, 2)), yaw])))
    ref_wxyz = np.roll(ref.as_quat(), 1, axis=1)
    same_sign = np.sign(np.sum(ref_wxyz * q, axis=1))[:, None]  # q and -q are one rotation
    np.testing.assert_allclose(q, ref_wxyz * same_sign, atol=1e-12)
