"""``marsscene serve``: user mistakes are one-line errors (exit 1 or 2), nothing simulated."""

from __future__ import annotations

from marsscene.cli import main


def test_record_needs_a_run_folder(runner, tmp_path):
    (tmp_path / "scene").mkdir()
    res = runner.invoke(main, ["serve", str(tmp_path / "scene"), "--record",
                               "--localhost"])
    assert res.exit_code == 1
    assert res.output.strip().splitlines()[-1] == (
        "Error: exports (a bag, datasets) need a run folder: give out_dir (--out)")


def test_bad_topic_and_missing_scene_are_one_line_errors(runner, tmp_path):
    (tmp_path / "scene").mkdir()
    res = runner.invoke(main, ["serve", str(tmp_path / "scene"), "--cmd-vel-topic", "cmd_vel"])
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert "must be an absolute topic name" in res.output
    res = runner.invoke(main, ["serve", str(tmp_path / "scene"), "--localhost"])
    assert res.exit_code == 1 and "is not a built scene" in res.output
    res = runner.invoke(main, ["serve", str(tmp_path / "nowhere")])
    assert res.exit_code == 2


def test_the_start_heading_is_in_degrees_as_build_takes_it(runner, tmp_path):
    (tmp_path / "scene").mkdir()
    help_text = runner.invoke(main, ["serve", "--help"], terminal_width=200).output
    assert "--yaw-deg" in help_text
    res = runner.invoke(main, ["serve", str(tmp_path / "scene"), "--yaw-deg", "400"])
    assert res.exit_code == 2 and "--yaw-deg" in res.output  # out of -360..360
    res = runner.invoke(main, ["serve", str(tmp_path / "scene"), "--yaw", "1.0"])
    assert res.exit_code == 2 and "No such option '--yaw'" in res.output  # the old alias, gone
