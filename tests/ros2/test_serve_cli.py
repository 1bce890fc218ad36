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


def test_serve_team_mistakes_are_one_line_and_a_team_serves(runner, tmp_path, gentle_scene):
    """``serve --team``: a served robot with a route, ``--record`` without ``--out`` and a start
    option are one-line errors; a team file serves each robot under its name and writes its
    run folder and bag."""
    team = tmp_path / "team.toml"
    team.write_text('[[robots]]\nname = "a"\nstart_xy_m = [-6.0, -3.0]\n'
                    '[[robots]]\nname = "b"\nrover = "mer"\nstart_xy_m = [-6.0, 3.0]\n')
    bad = tmp_path / "bad.toml"
    bad.write_text('[[robots]]\nname = "a"\nwaypoints = [[0.0, 0.0], [5.0, 0.0]]\n')
    res = runner.invoke(main, ["serve", str(gentle_scene), "--team", str(bad), "--localhost"])
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert res.output.strip().splitlines()[-1].startswith("Error: robot 'a': a served robot")
    res = runner.invoke(main, ["serve", str(gentle_scene), "--team", str(team), "--record"])
    assert res.exit_code == 2 and "--record needs --out" in res.output
    res = runner.invoke(main, ["serve", str(gentle_scene), "--team", str(team),
                               "--start-xy", "0", "0"])
    assert res.exit_code == 2 and "no --start-xy" in res.output
    out = tmp_path / "served"
    res = runner.invoke(main, ["serve", str(gentle_scene), "--team", str(team), "--localhost",
                               "--domain-id", "219", "--pace", "max", "--seconds", "1",
                               "--out", str(out), "--record"])
    assert res.exit_code == 0, res.output
    assert "served: 2 robots" in res.output
    for name in ("a", "b"):
        assert f"  {name}: 1.0 sim s" in res.output
        assert (out / name / "gt.tum").is_file() and (out / name / "bag").is_dir()
