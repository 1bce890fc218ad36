"""terrain.lod = "auto" (the default): a procedural terrain too large for one grid gets two
levels, says so, and records it; --no-lod keeps today's refusal, naming what would work."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

import marsscene as ms
from marsscene.cli import main
from marsscene.errors import ConfigError
from marsscene.pipeline.terrain import resolve_lod
from marsscene.terrain.synth import MAX_POSTS


def _cfg(**terrain):
    return ms.SceneConfig.from_dict({"terrain": {"source": "procedural", **terrain}})


def test_auto_chooses_two_levels_only_past_the_post_budget():
    assert ms.SceneConfig().terrain.lod == "auto"
    small, note = resolve_lod(_cfg(size_m=[300, 300]))
    assert small.terrain.lod is False and note is None
    big, note = resolve_lod(_cfg(size_m=[3600, 3600]))
    t = big.terrain
    assert t.lod is True and t.focus_post_m == 0.25 and t.post_m == 1.0
    assert t.focus_size_m == 1000.0
    outer_posts = (3600 / t.post_m + 1) ** 2
    assert outer_posts < MAX_POSTS and (3600 / (t.post_m / 2) + 1) ** 2 > 16e6  # smallest k
    assert note is not None and "207,388,801 posts" in note and "--no-lod" in note
    # an explicit choice is kept; DEMs (size unknown before reading) keep one grid
    assert resolve_lod(_cfg(size_m=[3600, 3600], lod=False))[0].terrain.lod is False
    assert resolve_lod(ms.SceneConfig())[0].terrain.lod is False
    fine, _ = resolve_lod(_cfg(size_m=[2000, 2000], post_m=0.1))
    assert fine.terrain.lod is True and fine.terrain.focus_size_m == pytest.approx(400.0)


def test_lod_values_are_validated():
    with pytest.raises(ConfigError, match='true, false or "auto"'):
        _cfg(lod="maybe")


def test_no_lod_refusal_names_the_options_that_work(tmp_path):
    res = CliRunner().invoke(main, ["build", "--procedural", "--size-m", "3600", "3600",
                                    "--seed", "7", "--no-lod", "--out", str(tmp_path / "s")])
    assert res.exit_code != 0
    assert "Traceback" not in res.output
    for hint in ("--lod", "--focus-size-m", "--post-m", "main-crater", '"auto"'):
        assert hint in res.output
    assert not (tmp_path / "s").exists()
