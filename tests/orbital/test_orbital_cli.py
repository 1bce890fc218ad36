"""``marsscene build --orbital-map`` writes the orbital map beside the scene: the same map
:func:`marsscene.orbital.orbital_map` makes of the same build, on its 1 m posts."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from click.testing import CliRunner

import marsscene as ms
from marsscene.cli import main
from marsscene.orbital import orbital_map, read_orbital_map

CONFIG = """
[terrain]
source = "procedural"
size_m = [40.0, 30.0]
post_m = 0.25
[craters]
enabled = false
[rocks]
k = 0.05
"""


def test_build_writes_the_orbital_map_of_the_scene(tmp_path: Path) -> None:
    (tmp_path / "s.toml").write_text(CONFIG, encoding="utf-8")
    out = tmp_path / "scene"
    res = CliRunner().invoke(main, ["build", "--config", str(tmp_path / "s.toml"), "--seed", "3",
                                    "--format", "mjcf", "--orbital-map", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "orbital: " in res.output and (out / "orbital" / "dem.tif").is_file()
    written = read_orbital_map(out)
    scene = ms.build_scene(ms.SceneConfig.from_toml(tmp_path / "s.toml"), seed=3)
    expected = orbital_map(scene)
    assert written.cell_m == expected.cell_m == 1.0
    np.testing.assert_array_equal(written.dem_m, expected.dem_m)
