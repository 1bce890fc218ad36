"""The README's copy-paste material stays true: the two commands and the config example."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import marsscene as ms

README = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")


def test_two_fresh_machine_commands_near_the_top() -> None:
    top = README[: README.index("## What you get")]
    commands = re.findall(r"```bash\n(.+?)\n```", top)
    assert commands == [
        'python -m pip install -e ".[all]" && marsscene build --seed 7 --out scenes/demo',
        'python -m pip install -e ".[all,test]" && python -m pytest',
    ]


def test_config_example_is_a_valid_scene_config() -> None:
    block = re.search(r"```toml\n(.+?)```", README, flags=re.S)
    assert block is not None
    cfg = ms.SceneConfig.from_dict(tomllib.loads(block.group(1)))
    assert cfg.seed == 7 and cfg.terrain.source == "procedural"
    assert cfg.lighting.tau == 0.5 and cfg.rocks.k == 0.05
