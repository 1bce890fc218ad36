"""The test tiers stay true: every entry of the slow table names a real folder, file or test,
and a plain run leaves exactly those out (``tests/conftest.py``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.conftest import SLOW_TESTS, _slow_entry

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("key", sorted(SLOW_TESTS))
def test_every_slow_entry_names_a_real_test(key: str) -> None:
    path, _, name = key.partition("::")
    name = name.split("[", 1)[0]
    target = ROOT / path
    assert target.exists(), f"{key}: no such folder or file"
    if name:
        assert re.search(rf"^def {re.escape(name)}\(", target.read_text(encoding="utf-8"),
                         flags=re.M), f"{key}: no such test"


def test_slow_entries_match_folders_files_and_every_parameter() -> None:
    assert _slow_entry("tests/ros2/test_live.py::test_x")  # a folder
    assert _slow_entry("tests/benchmark/test_kiss_icp.py::test_anything")  # a file
    key = "tests/export/test_lod_export.py::test_lod_stage_passes_the_omniverse_asset_validator"
    assert _slow_entry(f"{key}[usdz]") and _slow_entry(key)  # a test, any parameter
    assert not _slow_entry(f"{key}_too")  # not a prefix of a longer name
    assert not _slow_entry("tests/export/test_lod_export.py::test_lod_outputs_are_reproducible")
    assert not _slow_entry("tests/ros2x/test_live.py::test_x")  # not a prefix of a folder name
    checker = "tests/env/test_nav_env.py::test_every_registered_id_passes_gymnasiums_checker"
    assert _slow_entry(f"{checker}[marsscene/RoverNavCamera-v0]")  # one case
    assert not _slow_entry(f"{checker}[marsscene/RoverNav-v0]")
