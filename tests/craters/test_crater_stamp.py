"""Stamping: depth/rim on flat ground, volume, locality, no mutation, order, batch vs slice."""

from __future__ import annotations

import numpy as np
import pytest

from marsscene.craters import (
    CraterConfig,
    CraterTable,
    profile_family,
    sample_craters,
    stamp_craters,
)
from marsscene.craters import stamp as stamp_mod
from marsscene.craters.morphometry import DEFAULT_DEPTH_TO_DIAMETER, RIM_HEIGHT_TO_DIAMETER
from marsscene.terrain.heightfield import Heightfield


def _flat(n: int = 161, cs: float = 0.25, slope: float = 0.0) -> Heightfield:
    z = np.zeros((n, n), np.float32)
    z += (slope * cs * np.arange(n, dtype=np.float32))[None, :]
    return Heightfield.centered(z, cs)


#: Fresh floor depth below the pre-impact surface and rim height over D (default profile).
FLOOR = DEFAULT_DEPTH_TO_DIAMETER - RIM_HEIGHT_TO_DIAMETER
RIM = RIM_HEIGHT_TO_DIAMETER


def _one(x: float, y: float, d: float, age: float = 0.0, depth: float | None = None,
         q: float = 1.0, az: float = 0.0) -> CraterTable:
    depth = FLOOR * d if depth is None else depth
    return CraterTable(np.array([[x, y]]), [d], [depth], [RIM * d], [age], [0], [q], [az])


@pytest.mark.parametrize("d", [4.0, 12.0])  # 4 m: batched boxes; 12 m: slice path
def test_flat_ground_depth_rim_and_volume(d: float) -> None:
    hf = _flat()
    out = stamp_craters(hf, _one(0.0, 0.0, d))
    z = out.z_m.astype(np.float64)
    assert z[80, 80] == pytest.approx(-FLOOR * d, abs=2e-3 * d)
    x, y = hf.grid_xy()
    r = np.hypot(x[None, :], y[:, None])
    rim = z[np.abs(r - d / 2) < 0.13]
    assert rim.max() == pytest.approx(RIM * d, rel=0.05)
    # net volume on the grid = analytic 2 pi R^2 int h/D rho drho * D
    rho = np.linspace(0, 2.5, 250001)
    from marsscene.craters.morphology import profile_over_diameter
    analytic = np.trapezoid(profile_over_diameter(rho) * 2 * np.pi * rho, rho) * d * (d / 2) ** 2
    assert z.sum() * 0.25**2 == pytest.approx(analytic, rel=0.02)


def test_input_not_mutated_and_locality() -> None:
    hf = _flat(slope=0.05)
    before = hf.z_m.copy()
    fam = profile_family("watters-2015")
    d = np.array([2.0, 3.0, 6.0, 2.5, 20.0])
    state = np.array([0, 10, 25, 40, 5])  # fresh ... strongly degraded
    table = CraterTable(np.array([[-12.0, -12.0], [10.0, -8.0], [-6.0, 9.0], [12.0, 12.0],
                                  [-38.0, 0.0]]), d, fam.depth_over_d[state] * d,
                        fam.rim_over_d[state] * d, [3.0, 2.0, 1.0, 0.5, 0.1], np.zeros(5, int))
    out = stamp_craters(hf, table)
    np.testing.assert_array_equal(hf.z_m, before)
    x, y = hf.grid_xy()
    near = np.zeros(hf.shape, bool)
    for (cx, cy), di, si in zip(table.center_xy_m, d, state, strict=True):
        near |= np.hypot(x[None, :] - cx, y[:, None] - cy) <= fam.reach[si] * di / 2
    changed = out.z_m != hf.z_m
    assert changed[np.hypot(x[None, :] + 38, y[:, None]) < 20].any()  # off-grid centre, ejecta in
    assert (~near).sum() > 100
    np.testing.assert_array_equal(out.z_m[~near], hf.z_m[~near])
    assert not np.array_equal(out.z_m, hf.z_m)


def test_young_crater_cuts_old_one() -> None:
    hf = _flat()
    old = _one(-3.0, 0.0, 12.0, age=2.0)
    young = _one(3.0, 0.0, 8.0, age=0.5)
    both = CraterTable(
        np.vstack([old.center_xy_m, young.center_xy_m]), [12.0, 8.0], [FLOOR * 12, FLOOR * 8],
        [RIM * 12, RIM * 8], [2.0, 0.5], [0, 0])
    swapped = CraterTable(both.center_xy_m, both.diameter_m, both.depth_m, both.rim_height_m,
                          [0.5, 2.0], [0, 0])
    a = stamp_craters(hf, both).z_m.astype(np.float64)
    b = stamp_craters(hf, swapped).z_m.astype(np.float64)
    assert not np.allclose(a, b)
    # the young crater's own relief survives: its floor lies one nominal depth below its
    # rim-crest level even though its centre sits on the older crater's rim crest (only the
    # crest's sub-0.2 R kink survives as texture, hence 10 %)
    x, y = hf.grid_xy()
    r = np.hypot(x[None, :] - 3.0, y[:, None])
    crest = np.median(a[np.abs(r - 4.0) < 0.13])
    floor = a[80, 80 + 12]
    assert crest - floor == pytest.approx(DEFAULT_DEPTH_TO_DIAMETER * 8, rel=0.1)
    # and the older crater's rim is cut where the young bowl overlaps it (at x = 3, y = 0)
    single_old = stamp_craters(hf, old).z_m.astype(np.float64)
    assert a[80, 80 + 12] < single_old[80, 80 + 12] - 0.5


def test_batched_boxes_equal_one_at_a_time() -> None:
    hf = _flat(n=401, slope=0.02)
    cfg = CraterConfig(system="hartmann-daubar-2016", d_min_m=1.0, d_max_m=4.0, age_ga=3.5,
                       axis_ratio_min=0.7, degradation="none")
    table, _ = sample_craters(hf.bounds_xy_m, cfg, rng=np.random.default_rng(7))
    assert len(table) > 150
    batched = stamp_craters(hf, table, profile_kwargs=cfg.profile_kwargs())
    serial = hf
    for i in np.argsort(-table.age_ga, kind="stable"):
        serial = stamp_craters(serial, table.take(np.array([i])),
                               profile_kwargs=cfg.profile_kwargs())
    np.testing.assert_allclose(batched.z_m, serial.z_m, atol=1e-5)


def test_slice_and_box_paths_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    hf = _flat(slope=0.03)
    t = _one(0.3, -0.2, 3.0, q=0.75, az=30.0)
    boxed = stamp_craters(hf, t).z_m
    monkeypatch.setattr(stamp_mod, "_SIZES", np.array([2]))  # force the slice path
    sliced = stamp_craters(hf, t).z_m
    np.testing.assert_allclose(boxed, sliced, atol=3e-3 * 3.0)


def test_elliptical_crater_is_elongated_along_azimuth() -> None:
    hf = _flat()
    out = stamp_craters(hf, _one(0.0, 0.0, 10.0, q=0.5, az=0.0)).z_m
    along_x = (out[80, :] < -0.5).sum()
    along_y = (out[:, 80] < -0.5).sum()
    assert along_x > 1.6 * along_y


def test_only_the_profile_families_in_use_are_tabulated() -> None:
    hf = _flat(81, 0.5)
    profile_family.cache_clear()
    stamp_craters(hf, _one(0.0, 0.0, 8.0))  # profile 0 only: one table, not one per model
    assert profile_family.cache_info().currsize == 1
    two = CraterTable(np.array([[-10.0, 0.0], [10.0, 0.0]]), [8.0, 8.0], [FLOOR * 8] * 2,
                      [RIM * 8] * 2, [0.0, 0.0], [0, 2], [1.0, 1.0], [0.0, 0.0])
    mixed = stamp_craters(hf, two)
    assert profile_family.cache_info().currsize == 2  # + profile 2's table
    left, right = mixed.z_m[:, :40], mixed.z_m[:, 41:][:, ::-1]  # mirror images if alike
    assert np.abs(left - right).max() > 1e-3  # each crater got its own profile


@pytest.mark.parametrize("shape", [(2, 2), (5, 7), (70, 66)])
def test_edge_padding_equals_numpy_pad(shape: tuple[int, int]) -> None:
    z = np.random.default_rng(3).normal(size=shape).astype(np.float32)
    for pad in (1, 4, 64):
        expected = np.pad(z.astype(np.float64), pad, mode="edge")
        np.testing.assert_array_equal(stamp_mod._edge_padded(z, pad), expected)


def test_threaded_batches_give_the_same_bytes(monkeypatch: pytest.MonkeyPatch) -> None:
    """A wave's batches of small craters stamped on two threads equal one thread, bit for bit
    (their boxes are disjoint); the threads run on big terrains only."""
    import threading

    import marsscene._threads as threads

    hf = _flat(n=401, slope=0.02)
    cfg = CraterConfig(system="hartmann-daubar-2016", d_min_m=0.5, d_max_m=12.0, age_ga=3.5,
                       axis_ratio_min=0.7)
    table, _ = sample_craters(hf.bounds_xy_m, cfg, rng=np.random.default_rng(3))
    monkeypatch.setattr(stamp_mod, "_BATCH_POSTS", 4096)  # many batches per wave
    names: set[str] = set()
    start = threading.Thread.start

    def spy(self: threading.Thread) -> None:
        names.add(self.name)
        start(self)

    monkeypatch.setattr(threading.Thread, "start", spy)
    one = stamp_craters(hf, table, profile_kwargs=cfg.profile_kwargs()).z_m
    assert not names  # a small terrain: one thread
    monkeypatch.setattr(threads, "THREADED_MIN_POSTS", 1)
    two = stamp_craters(hf, table, profile_kwargs=cfg.profile_kwargs()).z_m
    assert sum(n.startswith("marsscene-craters") for n in names) == 2  # both workers ran
    assert np.array_equal(one, two)
