"""SWEEP.toml parsing, the grid and cell ids (pure; no Dask)."""

from __future__ import annotations

from pathlib import Path

import pytest

from marsscene.cli import main
from marsscene.errors import ConfigError
from marsscene.sweep import SweepSpec, expand_grid
from marsscene.sweep.cell import resolve_config, toml_text


def test_grid_is_the_cartesian_product_in_axis_order() -> None:
    spec = SweepSpec.from_dict({
        "terrain": {"source": "procedural", "size_m": [40.0, 40.0]},
        "sweep": {"seed": [1, 2], "lighting.tau": [0.3, 3.0], "rocks.k": [0.02, 0.08]},
    })
    cells = expand_grid(spec)
    assert len(cells) == 8
    assert cells[0].cell_id == "seed=1__lighting.tau=0.3__rocks.k=0.02"
    assert cells[-1].cell_id == "seed=2__lighting.tau=3.0__rocks.k=0.08"
    assert [c.params["rocks.k"] for c in cells[:2]] == [0.02, 0.08]  # last axis fastest
    assert cells[5].config["lighting"]["tau"] == 0.3 and cells[5].config["rocks"]["k"] == 0.08
    assert cells[5].config["terrain"]["size_m"] == [40.0, 40.0] and cells[5].seed == 2
    assert spec.base == {"terrain": {"source": "procedural", "size_m": [40.0, 40.0]}}  # unchanged
    assert len({c.cell_id for c in cells}) == 8


def test_cell_ids_are_sanitised_and_stable() -> None:
    spec = SweepSpec.from_dict({"sweep": {"lighting.utc": ["2021-02-18T20:55:00Z"],
                                      "terrain.size_m": [[50, 50.5]], "craters.enabled": [False]}})
    (cell,) = expand_grid(spec)
    assert cell.cell_id == (
        "lighting.utc=2021-02-18T20-55-00Z__terrain.size_m=50x50.5__craters.enabled=false"
    )
    assert expand_grid(spec)[0].cell_id == cell.cell_id


def test_resolved_config_round_trips_through_toml() -> None:
    import tomllib

    import marsscene as ms

    spec = SweepSpec.from_dict({"seed": 9, "terrain": {"source": "procedural", "size_m": [30, 20]},
                            "lighting": {"sun_azimuth_deg": 90.0},
                            "sweep": {"lighting.sun_elevation_deg": [25.0]}})
    cfg = resolve_config(expand_grid(spec)[0])
    text = toml_text(cfg)
    back = ms.SceneConfig.from_dict(tomllib.loads(text))
    assert back == cfg and back.seed == 9 and back.lighting.sun_elevation_deg == 25.0


@pytest.mark.parametrize(
    ("sweep", "message"),
    [
        ({"lighting.tauu": [1.0]}, "unknown sweep key 'lighting.tauu': no 'tauu' in lighting"),
        ({"light.tau": [1.0]}, "unknown sweep key 'light.tau'"),
        ({"lighting": {"tau": [1.0]}}, "quote dotted keys"),
        ({"lighting.tau": []}, "sweep.lighting.tau = []; give at least one value"),
        ({"lighting.tau": 0.5}, "sweep.lighting.tau = 0.5; must be a list of values"),
        ({"seed": [1, 1]}, "repeats a value"),
        ({"terrain": [1]}, "is a whole table"),
        ({}, "non-empty [sweep] table"),
    ],
)
def test_bad_sweep_tables_give_one_line_errors(sweep: dict, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        SweepSpec.from_dict({"sweep": sweep})
    assert message in str(info.value) and "\n" not in str(info.value)


def test_bad_base_config_and_drive_are_rejected() -> None:
    with pytest.raises(ConfigError, match=r"unknown key rocks\.kk"):
        SweepSpec.from_dict({"rocks": {"kk": 1}, "sweep": {"seed": [1]}})
    with pytest.raises(ConfigError, match="exactly one of waypoints or route"):
        SweepSpec.from_dict({"sweep": {"seed": [1]}, "drive": {"seconds": 3.0}})
    with pytest.raises(ConfigError, match=r"drive\.waypoints"):
        SweepSpec.from_dict({"sweep": {"seed": [1]}, "drive": {"waypoints": [[0, 0]]}})
    with pytest.raises(ConfigError, match=r"drive\.bag = 'yes'; must be true or false"):
        SweepSpec.from_dict({"sweep": {"seed": [1]}, "drive": {"waypoints": [[0, 0], [1, 1]],
                                                          "bag": "yes"}})


def test_route_path_resolves_against_the_sweep_file(tmp_path: Path) -> None:
    (tmp_path / "s.toml").write_text('[sweep]\nseed = [1]\n[drive]\nroute = "r.tum"\n')
    spec = SweepSpec.from_toml(tmp_path / "s.toml")
    assert spec.drive is not None and spec.drive.route == str((tmp_path / "r.tum").resolve())


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('[sweep]\n"rocks.kk" = [1.0]\n', "unknown sweep key 'rocks.kk'"),
        ('[sweep]\n"rocks.k" = []\n', "give at least one value"),
        ('[sweep]\n"rocks.k" = 0.05\n', "must be a list of values"),
        ("[sweep\n", "not valid TOML"),
    ],
)
def test_cli_reports_bad_sweep_files_in_one_line(runner, tmp_path: Path, text: str,
                                                 message: str) -> None:
    path = tmp_path / "sweep.toml"
    path.write_text(text)
    res = runner.invoke(main, ["sweep", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 1
    lines = [ln for ln in res.output.splitlines() if ln.startswith("Error")]
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in res.output
    assert not (tmp_path / "out").exists()


def test_example_sweep_file_is_valid() -> None:
    path = Path(__file__).resolve().parents[2] / "examples" / "sweep_tau_sun.toml"
    spec = SweepSpec.from_toml(path)
    cells = expand_grid(spec)
    assert len(cells) == 12 and spec.drive is not None and spec.drive.seconds == 40.0
    cfg = resolve_config(cells[-1])
    assert (cfg.seed, cfg.lighting.tau, cfg.lighting.sun_elevation_deg) == (2, 3.0, 45.0)


def test_cells_of_one_seed_prefer_one_worker() -> None:
    """Seed groups are dealt out to the workers in turn (the seed-only textures are then made
    once per worker and seed); every cell gets exactly one preferred worker."""
    from marsscene.sweep.grid import Cell
    from marsscene.sweep.run import _seed_affinity

    cells = [Cell(f"s{s}_t{t}", {"seed": s, "lighting.tau": t}, {}, s)
             for s in (7, 3, 9, 5) for t in (0.3, 1.0, 3.0)]
    prefer = _seed_affinity(cells, ["tcp://a", "tcp://b"])
    by_seed: dict[int | None, set[str]] = {}
    for c in cells:
        assert len(prefer[c.cell_id]) == 1
        by_seed.setdefault(c.seed, set()).update(prefer[c.cell_id])
    assert all(len(w) == 1 for w in by_seed.values())
    assert [by_seed[s].pop() for s in (7, 3, 9, 5)] == ["tcp://a", "tcp://b", "tcp://a", "tcp://b"]
    assert _seed_affinity(cells, []) == {c.cell_id: [] for c in cells}


def test_drive_noise_profile_is_checked_and_reaches_the_drive(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import marsscene as ms
    from marsscene.sweep.drive import drive_cell

    base = {"sweep": {"seed": [1]}, "drive": {"waypoints": [[0, 0], [1, 1]]}}
    default = SweepSpec.from_dict(base).drive
    assert default is not None and default.run_config().noise == ms.NoiseConfig()
    assert "noise_profile" not in default.to_dict()  # older sweeps keep their config hashes
    with pytest.raises(ConfigError, match=r"drive\.noise_profile: noise\.profile = 'ln200' is"):
        SweepSpec.from_dict({**base, "drive": {**base["drive"], "noise_profile": "ln200"}})
    spec = SweepSpec.from_dict({**base, "drive": {**base["drive"], "noise_profile": "ln200s"}})
    assert spec.drive is not None and spec.drive.to_dict()["noise_profile"] == "ln200s"

    seen: dict = {}

    class _Stop(Exception):
        pass

    def fake_drive(scene, **kwargs):
        seen.update(kwargs)
        raise _Stop

    monkeypatch.setattr(ms, "drive", fake_drive)
    with pytest.raises(_Stop):
        drive_cell(tmp_path, spec.drive, tmp_path / "drive")
    assert seen["config"].noise.profile == "ln200s"
    assert seen["config"].noise == ms.NoiseConfig(profile="ln200s")
