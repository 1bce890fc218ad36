"""Batch files and one-line errors of batched drives (no simulation)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.sim.batch import BatchDrive, read_batch_file


def test_batch_file_paths_relative_to_it(tmp_path: Path) -> None:
    f = tmp_path / "drives.toml"
    f.write_text('[[drive]]\nscene = "s/a"\nwaypoints = [[0, 0], [5, 1]]\nout = "r/a"\n'
                 'seed = 3\n\n[[drive]]\nscene = "s/b"\nroute = "b.tum"\nout = "r/b"\n'
                 "seconds = 12.5\n")
    a, b = read_batch_file(f)
    assert a.scene == tmp_path / "s/a" and a.out_dir == tmp_path / "r/a" and a.seed == 3
    np.testing.assert_array_equal(a.waypoints, [[0, 0], [5, 1]])
    assert b.route == tmp_path / "b.tum" and b.seconds == 12.5 and b.seed == 0


@pytest.mark.parametrize(("text", "message"), [
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\nspeed = 1\n', "unknown key 'speed'"),
    ('[[drive]]\nwaypoints = [[0, 0], [1, 1]]\n', "drive 0 has no scene"),
    ('[[drive]]\nscene = "a"\n', "give a route or waypoints"),
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0]]\n', "two or more"),
    ("x = 1\n", "no [[drive]] tables"),
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\nsun_elevation_deg = 95\n',
     "sun_elevation_deg = 95"),
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\ntau = 11\n', "camera.tau = 11"),
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\nexposure = "long"\n',
     "camera.exposure"),
    ('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\nlookahead_m = 0\n',
     "pursuit.lookahead_m"),
])
def test_batch_file_errors(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "drives.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")):
        read_batch_file(f)


def test_a_drives_sun_and_dust_replace_the_cameras(tmp_path: Path) -> None:
    from marsscene.rover.config import CameraConfig

    f = tmp_path / "drives.toml"
    f.write_text('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\ntau = 3.0\n'
                 'sun_elevation_deg = 12.5\nsun_azimuth_deg = 270\nirradiance_scale = 0.1\n'
                 'exposure = "fixed"\nlookahead_m = 2.5\n')
    (drive,) = read_batch_file(f)
    base = CameraConfig(width_px=64, height_px=48, tau=0.5, sun_elevation_deg=40.0)
    lit = drive.lighting_of(base)
    assert (lit.tau, lit.sun_elevation_deg, lit.sun_azimuth_deg) == (3.0, 12.5, 270.0)
    assert (lit.irradiance_scale, lit.exposure, drive.lookahead_m) == (0.1, "fixed", 2.5)
    assert (lit.width_px, lit.height_px) == (64, 48)
    plain = BatchDrive(scene="a", waypoints=[[0, 0], [1, 1]]).lighting_of(base)
    assert (plain.tau, plain.sun_elevation_deg, plain.sun_azimuth_deg) == (0.5, 40.0, None)


def test_drive_without_a_folder_is_one_line(tmp_path: Path) -> None:
    pytest.importorskip("mujoco_warp")
    from marsscene.sim.batch import drive_batch

    with pytest.raises(ConfigError, match="needs a run folder"):
        drive_batch([BatchDrive(scene=tmp_path, waypoints=[[0, 0], [1, 0]])], device="cpu")
