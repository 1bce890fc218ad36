"""``marsscene drive --device`` / ``--batch``: the one-line user errors (no simulation)."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from marsscene.cli import main


@pytest.mark.parametrize(("args", "message"), [
    (["--device", "cpu", "--bag"], "--device/--batch drive with pure pursuit"),
    (["--device", "cpu"], "give SCENE_DIR and --route or --waypoints"),
])
def test_device_usage_errors(runner: CliRunner, args: list[str], message: str) -> None:
    res = runner.invoke(main, ["drive", *args])
    assert res.exit_code == 2 and message in res.output


def test_batch_file_error_is_one_line(runner: CliRunner, tmp_path: Path) -> None:
    f = tmp_path / "drives.toml"
    f.write_text('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\nspeed = 2\n')
    res = runner.invoke(main, ["drive", "--batch", str(f), "--device", "cpu"])
    assert res.exit_code != 0 and "unknown key 'speed'" in res.output
    assert "Traceback" not in res.output and len(res.output.strip().splitlines()) == 1


def test_batch_with_scene_is_a_usage_error(runner: CliRunner, tmp_path: Path) -> None:
    f = tmp_path / "drives.toml"
    f.write_text('[[drive]]\nscene = "a"\nwaypoints = [[0, 0], [1, 1]]\n')
    res = runner.invoke(main, ["drive", str(tmp_path), "--batch", str(f)])
    assert res.exit_code == 2 and "--batch lists the drives" in res.output
