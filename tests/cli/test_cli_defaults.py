"""Each default is stated once, in its dataclass: the command line's options show what the
dataclass says (a changed default changes ``--help``), and the sweep's ``[drive]`` table takes
the drive's own defaults and bounds."""

from __future__ import annotations

import importlib
from collections.abc import Iterator
from types import ModuleType
from typing import Any

import pytest
from click.testing import CliRunner

from marsscene.errors import ConfigError
from marsscene.ros2.options import Ros2Options
from marsscene.rover.config import CameraConfig, LidarConfig
from marsscene.runs.export.options import ExportOptions
from marsscene.sim.mission import DriveOptions
from marsscene.sim.pursuit import PursuitConfig
from marsscene.sweep import SweepSpec
from marsscene.terrain.config import TerrainConfig

_RUN, _DRIVE = "marsscene.cli.options_run", "marsscene.cli.drive"
#: (modules that read the defaults, the command's last; command; dataclass; field; option;
#:  a value no default has; what the option's help line then says)
_CASES = [
    ((_DRIVE,), "drive", DriveOptions, "max_slope_deg", "--max-slope-deg", 27.5,
     "default: 27.5"),
    ((_DRIVE,), "drive", DriveOptions, "corridor_m", "--corridor-m", 23.25, "default: 23.25"),
    ((_DRIVE,), "drive", PursuitConfig, "lookahead_m", "--lookahead-m", 1.75, "default: 1.75"),
    ((_DRIVE,), "drive", ExportOptions, "dataset_images", "--dataset-images", "convert",
     "default: convert"),
    ((_RUN, _DRIVE), "drive", CameraConfig, "rate_hz", "--camera-hz", 12.5, "default: 12.5"),
    ((_RUN, _DRIVE), "drive", LidarConfig, "model", "--lidar ", "vlp16",
     "default model vlp16: 16 x 1800 at 10 Hz"),
    (("marsscene.cli.serve",), "serve", Ros2Options, "cmd_timeout_s", "--cmd-timeout-s", 4.5,
     "default: 4.5"),
    (("marsscene.cli.options_dem", "marsscene.cli.build"), "build", TerrainConfig,
     "focus_post_m", "--focus-post-m", 0.375, "default 0.375"),
]


@pytest.fixture
def reloaded(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[ModuleType]]:
    """Modules to reload once the test's monkeypatches are undone (module defaults back)."""
    modules: list[ModuleType] = []
    yield modules
    monkeypatch.undo()
    for module in modules:
        importlib.reload(module)


@pytest.mark.parametrize(("modules", "command", "cls", "field", "option", "value", "shown"),
                         _CASES, ids=[f"{c[1]} {c[4].strip()}" for c in _CASES])
def test_a_changed_dataclass_default_changes_the_help(
    monkeypatch: pytest.MonkeyPatch, reloaded: list[ModuleType], modules: tuple[str, ...],
    command: str, cls: type, field: str, option: str, value: Any, shown: str,
) -> None:
    def help_line() -> str:
        cmd = getattr(importlib.import_module(modules[-1]), command)
        lines = CliRunner().invoke(cmd, ["--help"], terminal_width=300).output.splitlines()
        i = next(i for i, ln in enumerate(lines) if ln.lstrip().startswith(option))
        j = next((j for j in range(i + 1, len(lines)) if lines[j].lstrip().startswith("-")),
                 len(lines))
        return " ".join(ln.strip() for ln in lines[i:j])  # the option's help, one line

    assert shown not in help_line()
    monkeypatch.setitem(cls.__init__.__kwdefaults__, field, value)  # type: ignore[misc]
    reloaded += [importlib.import_module(name) for name in modules]
    for module in reloaded:
        importlib.reload(module)  # the option tables read the dataclasses again
    assert shown in help_line()


def test_the_drive_options_bounds_are_the_dataclasses() -> None:
    """The command line and the sweep refuse what DriveOptions / PursuitConfig refuse, in the
    dataclasses' words (lookahead up to 50 m, not the sweep's old 100)."""
    from marsscene.cli import main

    res = CliRunner().invoke(main, ["drive", ".", "--waypoints", __file__, "--lookahead-m", "60"])
    assert res.exit_code == 1 and "pursuit.lookahead_m = 60.0 is out of range" in res.output
    base = {"sweep": {"seed": [1]}}
    with pytest.raises(ConfigError, match=r"pursuit\.lookahead_m = 60 is out of range; "
                                          r"allowed \[0\.05, 50\.0\]"):
        SweepSpec.from_dict({**base, "drive": {"waypoints": [[0, 0], [1, 1]],
                                               "pursuit": {"lookahead_m": 60}}})


def test_the_sweep_drive_table_is_drive_options() -> None:
    base = {"sweep": {"seed": [1]}}
    wp = {"waypoints": [[0, 0], [1, 1]]}
    spec = SweepSpec.from_dict({**base, "drive": wp}).drive
    assert spec is not None and spec.options == DriveOptions()
    spec = SweepSpec.from_dict({**base, "drive": {**wp, "corridor_m": 30.0, "settle_s": 1.0,
                                                  "pursuit": {"lookahead_m": 2.0}}}).drive
    assert spec is not None
    assert spec.options == DriveOptions(corridor_m=30.0, settle_s=1.0,
                                        pursuit=PursuitConfig(lookahead_m=2.0))
    doc = spec.to_dict()  # the cell's hash: the old flat keys, then what else differs
    assert (doc["lookahead_m"], doc["corridor_m"], doc["options"]) == (2.0, 30.0,
                                                                       {"settle_s": 1.0})
    with pytest.raises(ConfigError, match=r"drive\.lookahead_m = 2\.0: now "
                                          r"drive\.pursuit\.lookahead_m"):
        SweepSpec.from_dict({**base, "drive": {**wp, "lookahead_m": 2.0}})
    with pytest.raises(ConfigError, match=r"unknown key drive\.speed = 1; allowed keys: .*"
                                          r"'corridor_m'.*'noise_seed'"):
        SweepSpec.from_dict({**base, "drive": {**wp, "speed": 1}})
