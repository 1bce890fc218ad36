"""``benchmark vpr --device cpu``: both traversals in one batch on Warp's CPU device, written
in the layout the CPU path writes (the same readers and ``vpr-eval``), each traversal under its
own lighting and exposure, frames every ``spacing_m`` driven; its traversals are keyed by the
engine, so a CPU run does not resume them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("mujoco_warp")

from marsscene.benchmark.vpr.eval import read_split
from marsscene.cli import main

pytestmark = pytest.mark.slow

SPEC = """
[vpr]
name = "tiny-device"
spacing_m = 0.25
seed = 4
lateral_offset_m = 0.3
radius_m = 2.0
[camera]
width_px = 64
height_px = 48
sensor_noise = true
[scene]
name = "tiny"
route = { shape = "loop", length_m = 8.0 }
[scene.overrides]
terrain = { source = "procedural", size_m = [40, 40], post_m = 0.25, rms_height_m = 0.05 }
craters = { enabled = false }
rocks = { k = 0.02 }
[database]
tau = 0.05
sun_elevation_deg = 50.0
irradiance_of_sun_elevation_deg = 3.0
exposure = "fixed"
[queries]
tau = 0.05
sun_elevation_deg = 50.0
"""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("vprdevice")
    (root / "spec.toml").write_text(SPEC, encoding="utf-8")
    out = root / "ds"
    res = CliRunner().invoke(main, ["benchmark", "vpr", str(root / "spec.toml"), "--out",
                                    str(out), "--device", "cpu", "--no-eval"])
    assert res.exit_code == 0, res.output
    assert "load on device" not in res.output  # Warp's line per module stays off the terminal
    return out


def test_both_traversals_in_the_cpu_layout(dataset: Path) -> None:
    doc = json.loads((dataset / "dataset.json").read_text(encoding="utf-8"))
    assert doc["engine"] == "mujoco_warp"
    t = doc["traversals"]
    db, q = read_split(dataset, "database"), read_split(dataset, "queries")
    assert len(db.files) == t["database"]["frames"] > 20
    assert len(q.files) == t["queries"]["frames"] > 20
    # a frame every 0.25 m driven: the cameras' positions, in time order, step by about that
    rows = [r.split(",") for r in (dataset / "poses.csv").read_text().splitlines()[1:]]
    xy = np.array([[float(r[3]), float(r[4])] for r in sorted(
        (r for r in rows if r[0] == "queries"), key=lambda r: float(r[2]))])
    steps = np.hypot(*np.diff(xy, axis=0).T)
    assert 0.2 < float(np.median(steps)) < 0.32
    assert not list((dataset / "traversals").rglob("*.png"))  # the PNGs became the JPEGs
    run = dataset / "traversals" / "database"
    assert not (run / "camera" / "depth").exists()  # no depth asked, none written
    assert json.loads((run / "run.json").read_text())["batch"]["engine"] == "mujoco_warp"


def test_the_dim_database_is_darker_at_its_fixed_exposure(dataset: Path) -> None:
    from PIL import Image

    def mean(split: str) -> float:
        files = sorted((dataset / split).glob("*.jpg"))[:5]
        return float(np.mean([np.asarray(Image.open(f), dtype=float).mean() for f in files]))

    assert mean("database") < 0.5 * mean("queries")  # dusk's irradiance, the day's exposure


def test_vpr_eval_reads_it_and_its_key_names_the_engine(dataset: Path) -> None:
    res = CliRunner().invoke(main, ["benchmark", "vpr-eval", str(dataset), "--baseline",
                                    "patch-normalised"])
    assert res.exit_code == 0, res.output
    assert (dataset / "results" / "patch-normalised" / "recall.csv").is_file()
    for split in ("database", "queries"):  # a CPU run's key has no engine: it drives again
        key = json.loads((dataset / "traversals" / split / "vpr_key.json").read_text())
        assert key["engine"] == "mujoco_warp" and key["split"] == split
