"""Each default is stated once, in its dataclass: the command line's options show what the
dataclass says (a changed default changes ``--help``), and the sweep's ``[drive]`` table takes
the drive's own defaults and bounds."""

from __future__ import annotations

import importlib
from collections.abc import Iterator
from types import ModuleType

import click
import pytest
from click.testing import CliRunner

from marsscene.errors import ConfigError
from marsscene.ros2.options import Ros2Options
from marsscene.rover.config import CameraConfig
from marsscene.sim.mission import DriveOptions
from marsscene.sim.pursuit import PursuitConfig
from marsscene.sweep import SweepSpec

#: (module of the command, its name, dataclass, field, option, a value no default has)
_CASES = [
    ("marsscene.cli.drive", "drive", DriveOptions, "max_slope_deg", "--max-slope-deg", 27.5),
    ("marsscene.cli.drive", "drive", DriveOptions, "corridor_m", "--corridor-m", 23.25),
    ("marsscene.cli.drive", "drive", PursuitConfig, "lookahead_m", "--lookahead-m", 1.75),
    ("marsscene.cli.serve", "serve", Ros2Options, "cmd_timeout_s", "--cmd-timeout-s", 4.5),
    ("marsscene.cli.drive", "drive", CameraConfig, "rate_hz", "--camera-hz", 12.5),
]


@pytest.fixture
def reloaded(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[ModuleType]]:
    """Modules to reload once the test's monkeypatches are undone (module defaults back)."""
    modules: list[ModuleType] = []
    yield modules
    monkeypatch.undo()
    for module in modules:
        importlib.reload(module)


def _reload(name: str) -> ModuleType:
    """``name`` re-imported (its option tables read the dataclasses again), after
    ``cli.options_run`` (the run options' table)."""
    importlib.reload(importlib.import_module("marsscene.cli.options_run"))
    return importlib.reload(importlib.import_module(name))


@pytest.mark.parametrize(("module", "command", "cls", "field", "option", "value"), _CASES,
                         ids=[f"{c[1]} {c[4]}" for c in _CASES])
def test_a_changed_dataclass_default_changes_the_help(
    monkeypatch: pytest.MonkeyPatch, reloaded: list[ModuleType], module: str, command: str,
    cls: type, field: str, option: str, value: float,
) -> None:
    old = cls.__init__.__kwdefaults__[field]  # type: ignore[misc]
    cmd: click.Command = getattr(importlib.import_module(module), command)
    assert _option(cmd, option).default == old  # the dataclass's default today
    monkeypatch.setitem(cls.__init__.__kwdefaults__, field, value)  # type: ignore[misc]
    reloaded += [importlib.import_module("marsscene.cli.options_run"),
                 importlib.import_module(module)]
    cmd = getattr(_reload(module), command)
    assert _option(cmd, option).default == value
    text = CliRunner().invoke(cmd, ["--help"], terminal_width=200).output
    line = next(ln for ln in text.splitlines() if ln.lstrip().startswith(option))
    assert f"default: {value:g}" in line, line


def _option(cmd: click.Command, flag: str) -> click.Option:
    return next(p for p in cmd.params if isinstance(p, click.Option) and flag in p.opts)


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
