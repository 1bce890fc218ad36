"""`marsscene benchmark vpr` / `vpr-eval` (issue 22 part 2): distance-triggered capture, the
dataset layout of VPR-methods-evaluation, recall against a brute-force reference."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from marsscene.benchmark.vpr.dataset import generate_vpr, image_name, offset_route
from marsscene.benchmark.vpr.eval import read_split, recall_at, retrieve
from marsscene.benchmark.vpr.spec import PROTOCOLS, VprSpec
from marsscene.cli import main
from marsscene.errors import ConfigError

_TINY = {
    "vpr": {"spacing_m": 0.25, "seed": 4, "lateral_offset_m": 0.3},
    "camera": {"width_px": 64, "height_px": 48},
    "scene": {"name": "tiny", "overrides": {
        "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25,
                    "rms_height_m": 0.05},
        "craters": {"enabled": False}, "rocks": {"enabled": False}},
        "route": {"shape": "loop", "length_m": 8.0}},
    "database": {"tau": 0.6, "sun_elevation_deg": 40.0},
    "queries": {"tau": 0.05, "sun_elevation_deg": 40.0},
}


def test_shipped_protocols_are_the_papers(tmp_path: Path) -> None:
    dust, dark, dim = (VprSpec.from_toml(p) for p in PROTOCOLS)
    assert (dust.queries.tau, dust.database.tau) == (0.05, 0.60)
    assert dark.queries.tau == dark.database.tau == 0.05
    assert dark.database.sun_elevation_deg < 5.0 < dark.queries.sun_elevation_deg
    # Day/Dark's other reading: the day's sun, dimmed to a 3 deg sun's irradiance, with noise
    assert dim.database.sun_elevation_deg == dim.queries.sun_elevation_deg == 50.0
    assert dim.database.irradiance_of_sun_elevation_deg == dark.database.sun_elevation_deg
    assert dim.database.exposure == "fixed" and dim.camera_config(dim.database).sensor_noise
    from marsscene.benchmark.vpr.dataset import irradiance_scale
    from marsscene.lighting import LightingConfig, compute_lighting

    def ghi(el: float) -> float:  # no manifest: the lighting's defaults at that sun
        return compute_lighting(LightingConfig(tau=0.05, sun_azimuth_deg=135.0,
                                               sun_elevation_deg=el),
                                lat_deg=0.0, lon_east_deg=0.0).global_horizontal_w_m2
    scale = irradiance_scale(dim.database, tmp_path)
    assert scale == pytest.approx(ghi(3.0) / ghi(50.0), rel=1e-9) and 0.02 < scale < 0.2
    assert irradiance_scale(dim.queries, tmp_path) == 1.0
    with pytest.raises(ConfigError, match=r"day-low-sun .* or day-dim") as err:
        VprSpec.from_toml("day-dark")  # the former name says what to type
    assert "\n" not in str(err.value)
    for spec in (dust, dark, dim):
        assert spec.spacing_m == 0.1 and spec.radius_m == 2.0
        assert spec.scene.preset == "mars-base"
        cam = spec.camera_config(spec.database)
        assert cam.trigger_distance_m == 0.1 and not cam.depth
    assert dust.with_length(40.0).scene.route.length_m == 40.0
    for spec in (dust, dark, dim):  # the Mars Base route passes the habitat (issue 36)
        assert spec.scene.route.center_asset == spec.landmark_name == "habitat"
        assert spec.scene.route.shape == "out-and-back" and spec.scene.route.width_m >= 20.0


def test_landmark_pixels_in_view_behind_and_hidden() -> None:
    """The landmark's size in a frame: its box ahead (full size), behind the camera (0), at
    the image's edge (a sliver: its width), behind a ridge (0)."""
    from scipy.spatial.transform import Rotation

    from marsscene.benchmark.vpr.landmark import Landmark, landmark_pixels
    from marsscene.terrain.heightfield import Heightfield

    corners = np.array([[i, j, k] for i in (0, 1) for j in (-1, 1) for k in (0, 1)], float)
    mark = Landmark([corners * [2.0, 2.0, 6.0] + [20.0, 0.0, 0.0]])  # 2 x 4 x 6 m, 20 m east
    intr = {"width": 640, "height": 480, "fx": 400.0, "fy": 400.0, "cx": 320.0, "cy": 240.0}
    # optical frames (x right, y down, z forward) looking east, west, and east past the box
    east = Rotation.from_matrix([[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    west = Rotation.from_euler("z", 180, degrees=True) * east
    quats = np.stack([east.as_quat(), west.as_quat(),
                      (Rotation.from_euler("z", 44.0, degrees=True) * east).as_quat()])
    cams = np.array([[0.0, 0.0, 2.0]] * 3)
    flat = Heightfield.centered(np.zeros((81, 81), np.float32), 1.0)
    px = landmark_pixels(mark, cams, quats, intr, flat)
    assert px[0] == pytest.approx(400.0 * 4.0 / 20.0, rel=0.02)  # 4 m wide, its face 20 m off
    assert px[1] == 0.0  # behind the camera
    assert 0.0 < px[2] < 20.0  # a sliver at the left edge
    ridge = np.zeros((81, 81), np.float32)
    ridge[:, 50:52] = 10.0  # a 10 m wall at x = 10 m, between the camera and the box
    assert landmark_pixels(mark, cams[:1], quats[:1], intr,
                           Heightfield.centered(ridge, 1.0))[0] == 0.0
    # the camera draws meshes centred inside its terrain window only
    windows = np.array([[-30.0, -30.0, 30.0, 30.0], [-15.0, -15.0, 15.0, 15.0]])
    drawn = landmark_pixels(mark, cams[[0, 0]], quats[[0, 0]], intr, flat,
                            windows)
    assert drawn[0] == pytest.approx(px[0]) and drawn[1] == 0.0


@pytest.mark.parametrize(("patch", "match"), [
    ({"vpr": {"spacing": 0.1}}, "unknown key vpr.spacing"),
    ({"queries": {"tau": -1.0, "sun_elevation_deg": 30.0}}, "tau"),
    ({"camera": {"width": 64}}, "unknown key camera.width"),
    ({"extra": {}}, "unknown table"),
    ({"vpr": {"spacing_m": 0.0}}, "spacing_m"),
])
def test_spec_errors_are_one_line(patch: dict, match: str) -> None:
    data = {**_TINY, **{k: {**_TINY.get(k, {}), **v} for k, v in patch.items()}}
    with pytest.raises(ConfigError, match=match) as info:
        VprSpec.from_dict(data)
    assert "\n" not in str(info.value)


def test_image_names_round_trip(tmp_path: Path) -> None:
    """The names parse as VPR-methods-evaluation parses them: split('@')[1:3] = east, north."""
    (tmp_path / "database").mkdir()
    pts = [(-12.345, 7.5), (0.0, -0.001), (1234.5, -987.25)]
    for i, (e, n) in enumerate(pts):
        name = image_name(e, n, i, 91.5, -10.0, 0.5, 3.25, 12.0, "database")
        assert name.count("@") == 15 and name.endswith("@.jpg")  # 14 fields
        (tmp_path / "database" / name).write_bytes(b"")
    split = read_split(tmp_path, "database")
    assert sorted(map(tuple, split.xy_m.tolist())) == sorted(pts)


def test_offset_route_is_parallel() -> None:
    xy = np.column_stack([np.linspace(0, 10, 41), np.zeros(41)])
    left = offset_route(xy, 0.4)
    np.testing.assert_allclose(left[:, 1], 0.4)
    np.testing.assert_allclose(left[:, 0], xy[:, 0])


def test_offset_of_a_closed_route_stays_closed() -> None:
    """A loop's seam is shifted like any point: the offset loop ends where it starts, on the
    circle ``offset_m`` inside (left of travel, counter-clockwise)."""
    t = np.linspace(0.0, 2 * np.pi, 81)
    loop = np.column_stack([3 * np.cos(t), 3 * np.sin(t)])
    loop[-1] = loop[0]
    inner = offset_route(loop, 0.4)
    np.testing.assert_array_equal(inner[0], inner[-1])
    np.testing.assert_allclose(np.hypot(*inner.T), 2.6, atol=2e-3)


def test_recall_matches_brute_force() -> None:
    rng = np.random.default_rng(0)
    db_xy, q_xy = rng.uniform(0, 30, (200, 2)), rng.uniform(0, 30, (150, 2))
    db_d, q_d = rng.normal(size=(200, 16)), rng.normal(size=(150, 16))
    q_d[:50] = db_d[:50] + 0.05 * rng.normal(size=(50, 16))  # some findable queries
    q_xy[:50] = db_xy[:50] + 0.5
    ranked = retrieve(db_d, q_d, k=20, block=7)
    res = recall_at(ranked, db_xy, q_xy, radius_m=2.0)
    for n in (1, 5, 10, 20):
        hits = 0
        for i in range(len(q_d)):
            order = np.argsort(((db_d - q_d[i]) ** 2).sum(axis=1), kind="stable")[:n]
            hits += any(np.hypot(*(db_xy[j] - q_xy[i])) <= 2.0 for j in order)
        assert res.recall[n] == pytest.approx(hits / len(q_d))
    assert res.recall[1] >= 50 / 150  # the planted matches are found first
    assert res.without_positive == sum(
        not np.any(np.hypot(*(db_xy - p).T) <= 2.0) for p in q_xy)


def test_distance_triggered_capture_spacing(gentle_scene: Path, tmp_path: Path) -> None:
    """A frame per 0.25 m driven: consecutive frame positions lie 0.25 m (+ at most one
    control step of travel) apart along the path, whatever the speed."""
    from marsscene.runs.runlog import RunLog
    from marsscene.runtime import CameraConfig, RunConfig
    from marsscene.seeding import stage_rng
    from marsscene.sim.driver import drive_sim
    from marsscene.sim.rover_sim import RoverSim

    run = RunConfig(camera=CameraConfig(width_px=32, height_px=24, depth=False,
                                        trigger_distance_m=0.25))
    drive_sim(RoverSim(gentle_scene, run=run), command=lambda t: (0.1 + 0.05 * t, 0.02),
          seconds=6.0, out_dir=tmp_path / "r", rng=stage_rng(0, "sensors"))
    log = RunLog(tmp_path / "r")
    xy = log.gt.xyz_m[:, :2]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    idx = np.searchsorted(log.gt.timestamps_s, log.camera_streams()[0].stamps_s - 1e-7)
    gaps = np.diff(s[idx])
    step = np.diff(s).max()  # the longest distance of one control period
    assert len(idx) == int(s[-1] / 0.25) + 1
    assert np.all(gaps >= 0.25 - step - 1e-9) and np.all(gaps <= 0.25 + step + 1e-9)
    assert s[idx[0]] == 0.0


def test_generate_and_evaluate_end_to_end(tmp_path: Path) -> None:
    spec = VprSpec.from_dict(_TINY)
    out = tmp_path / "ds"
    doc = generate_vpr(spec, out)
    db, q = read_split(out, "database"), read_split(out, "queries")
    t = doc["traversals"]
    assert len(db.files) == t["database"]["frames"] > 20
    assert len(q.files) == t["queries"]["frames"] > 20
    assert t["database"]["offset_m"] != t["queries"]["offset_m"]  # not pixel-identical
    # the coordinates in the names are the camera positions in poses.csv
    rows = (out / "poses.csv").read_text().splitlines()[1:]
    by_file = {r.split(",")[1]: r.split(",") for r in rows}
    f = db.files[3]
    assert float(by_file[f"database/{f.name}"][3]) == pytest.approx(db.xy_m[3, 0], abs=1e-3)
    assert not list((out / "traversals").rglob("*.png"))  # the run's PNGs became the JPEGs
    # two worker processes give the same dataset, byte for byte
    generate_vpr(spec, tmp_path / "ds2", workers=2)
    for split in ("database", "queries"):
        one = {p.name: p.read_bytes() for p in (out / split).iterdir()}
        two = {p.name: p.read_bytes() for p in (tmp_path / "ds2" / split).iterdir()}
        assert one == two
    # resume reuses both traversals (same bytes, no new drive)
    before = {p.name: p.stat().st_mtime_ns for p in (out / "database").iterdir()}
    generate_vpr(spec, out, resume=True)
    assert {p.name: p.stat().st_mtime_ns for p in (out / "database").iterdir()} == before
    with pytest.raises(Exception, match="already holds"):
        generate_vpr(spec, out)
    # any method's descriptors, one .npy per image: perfect "GPS" descriptors -> recall 1
    desc = tmp_path / "gps"
    for split in (db, q):
        (desc / split.name).mkdir(parents=True)
        for file, p in zip(split.files, split.xy_m, strict=True):
            np.save(desc / split.name / f"{file.name}.npy", p.astype(np.float32))
    res = CliRunner().invoke(main, ["benchmark", "vpr-eval", str(out), "--descriptors",
                                    str(desc), "--radius-m", "2", "--radius-m", "0.5"])
    assert res.exit_code == 0, res.output
    lines = (out / "results" / "gps" / "recall.csv").read_text().splitlines()
    assert lines[1].split(",")[2] == "1.000000"  # R@1 at 2 m
    assert (out / "results" / "gps" / "pairs.png").stat().st_size > 10_000
    res = CliRunner().invoke(main, ["benchmark", "vpr-eval", str(out), "--baseline",
                                    "patch-normalised"])
    assert res.exit_code == 0 and "patch-normalised" in res.output
    doc2 = json.loads((out / "dataset.json").read_text())
    assert doc2["traversals"]["queries"]["tau"] == 0.05


def test_vlad_properties() -> None:
    """Unit norm; identical descriptor sets give identical vectors; descriptors sitting on
    their words leave no residual; the order of an image's descriptors does not matter."""
    from marsscene.benchmark.vpr.vlad import vlad

    rng = np.random.default_rng(2)
    centres = rng.normal(size=(8, 128)).astype(np.float32)
    a = rng.normal(size=(40, 128)).astype(np.float32)
    out = vlad([a, a[::-1].copy(), centres.copy(), np.zeros((0, 128), np.float32)], centres)
    assert np.linalg.norm(out[0]) == pytest.approx(1.0, abs=1e-5)
    np.testing.assert_allclose(out[0], out[1], atol=1e-6)
    assert not out[2].any() and not out[3].any()


def test_sift_vlad_finds_the_same_places(tmp_path: Path) -> None:
    """VLAD over RootSIFT on real frames: each query is a database frame re-encoded at a lower
    JPEG quality and brightened, so its nearest database descriptor is its own frame."""
    pytest.importorskip("cv2")
    from PIL import Image, ImageEnhance

    from marsscene.benchmark.vpr.vlad import sift_vlad

    src = Path(__file__).resolve().parents[2] / "docs" / "img"
    frames = [src / f"camera_{n}.png" for n in ("ground_texture", "low_sun_13deg",
                                                 "low_sun_2deg", "low_sun_5deg", "tau_sun")]
    db, q = [], []
    for i, f in enumerate(frames):
        with Image.open(f) as im:
            im = im.convert("RGB")
            im.save(tmp_path / f"db{i}.jpg", quality=95)
            ImageEnhance.Brightness(im).enhance(1.3).save(tmp_path / f"q{i}.jpg", quality=60)
        db.append(tmp_path / f"db{i}.jpg")
        q.append(tmp_path / f"q{i}.jpg")
    d_db, d_q = sift_vlad(tuple(db), tuple(q), words=16)
    ranked = retrieve(d_db, d_q, k=1)
    assert ranked[:, 0].tolist() == list(range(len(frames)))
