"""The benchmark suite's runner (``perf/run.py``): parsers built from declarations, quick and
full values, the JSON lines it appends, the Markdown tables made from them, and every
registered benchmark's declaration. Nothing here runs a benchmark."""

from __future__ import annotations

import ast
import json
import re
import shlex
import socket
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from perf import results, suite
from perf import run as runner

ROOT = Path(__file__).resolve().parents[1]


def _bench(main: Any = None, params: tuple[suite.Param, ...] | None = None) -> suite.Registered:
    if params is None:
        params = (
            suite.Param("seconds", float, "drive length (s)", quick=2.0, full=34.0),
            suite.Param("models", suite.names, "LiDAR models", quick=("simple",),
                        full=("os1-64", "os1-128")),
            suite.Param("quality", bool, "image quality pass", quick=False, full=True),
            suite.Param("mode", str, "what to run", quick="cast", full="all",
                        choices=("all", "cast", "drive")),
            suite.Param("scene", suite.optional(Path), "a built scene", quick=None, full=None),
        )

    def fake(seconds: float, models: tuple[str, ...], quality: bool, mode: str,
             scene: Path | None) -> list[dict[str, Any]]:
        return [{"case": m, "wall_s": seconds, "quality": quality} for m in models]

    return suite.Registered("fake", "speed", "tests.fake", params, main or fake, "A fake.")


def test_the_parser_is_built_from_the_declaration_with_each_sizes_values() -> None:
    bench = _bench()
    text = suite.parser(bench).format_help()
    for flag in ("--seconds", "--models", "--quality", "--no-quality", "--mode", "--scene",
                 "--size", "--json", "--no-json"):
        assert flag in text
    assert "quick: 2.0; full: 34.0" in text and "full: os1-64,os1-128" in text

    _, full = suite.resolve(bench, [])
    assert full == {"seconds": 34.0, "models": ("os1-64", "os1-128"), "quality": True,
                    "mode": "all", "scene": None}
    _, quick = suite.resolve(bench, ["--size", "quick"])
    assert quick == {"seconds": 2.0, "models": ("simple",), "quality": False, "mode": "cast",
                     "scene": None}
    _, given = suite.resolve(bench, ["--size", "quick", "--seconds", "5", "--models",
                                     "vlp16,os1-64", "--quality", "--scene", "/tmp/s"])
    assert given == {"seconds": 5.0, "models": ("vlp16", "os1-64"), "quality": True,
                     "mode": "cast", "scene": Path("/tmp/s")}
    assert suite.resolve(bench, ["--no-quality"])[1]["quality"] is False


@pytest.mark.parametrize("argv", [["--mode", "fly"], ["--seconds", "soon"], ["--bogus", "1"],
                                  ["--size", "huge"]])
def test_bad_options_are_refused(argv: list[str]) -> None:
    with pytest.raises(SystemExit):
        suite.resolve(_bench(), argv)


def test_list_parsers_and_optional_values() -> None:
    assert suite.floats("13,5,2,-3") == (13.0, 5.0, 2.0, -3.0)
    assert suite.floats("") == () and suite.floats("none") == () and suite.names("none") == ()
    assert suite.names(" os1-64, os1-128 ,") == ("os1-64", "os1-128")
    assert suite.ints("256,1024") == (256, 1024)
    assert suite.optional(float)("none") is None and suite.optional(float)("0.5") == 0.5


def test_a_declaration_that_disagrees_with_main_is_reported() -> None:
    assert suite.problems(_bench()) == []

    def main(seconds: float, extra: int) -> None:
        return None

    bad = _bench(main=main, params=(
        suite.Param("seconds", float, "s", quick=1, full=2.0),  # quick is an int
        suite.Param("seconds", float, "", quick=1.0, full=2.0),  # twice, and no help
        suite.Param("mode", str, "m", quick="x", full="all", choices=("all",)),
    ))
    found = "\n".join(suite.problems(bad))
    assert "quick value 1 is not float" in found
    assert "not a fresh identifier" in found and "no help text" in found
    assert "quick value 'x' not in" in found
    assert "main takes ['extra', 'seconds']" in found


def test_a_record_has_the_runs_fields_and_no_hostname() -> None:
    (rec,) = results.records("fake", "speed", "quick", {"seconds": 2.0, "models": ("a",)},
                             [{"wall_s": np.float32(1.5), "n": np.int64(3),
                               "bad": float("nan"), "where": Path("/tmp/x")}])
    line = results.dumps(rec)
    back = json.loads(line)
    assert set(back) == {"benchmark", "kind", "size", "params", "figures", "utc", "git_sha",
                         "git_dirty", "machine"}
    assert back["benchmark"] == "fake" and back["kind"] == "speed" and back["size"] == "quick"
    assert back["params"] == {"seconds": 2.0, "models": ["a"]}
    assert back["figures"] == {"wall_s": 1.5, "n": 3, "bad": None, "where": "/tmp/x"}
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", back["utc"])
    assert re.fullmatch(r"[0-9a-f]{40}", back["git_sha"])  # the suite runs in a checkout
    assert isinstance(back["git_dirty"], bool)
    machine = back["machine"]
    assert set(machine) == {"cpu", "cores", "memory_gib", "gpus", "os", "python"}
    assert machine["cores"] >= 1 and machine["memory_gib"] > 0 and machine["cpu"]
    host = socket.gethostname()
    assert len(host) < 4 or host not in line
    assert "\n" not in line


def test_records_append_and_read_back(tmp_path: Path) -> None:
    ctx = {"git_sha": "0" * 40, "git_dirty": False, "machine": {"cores": 2}}
    path = tmp_path / "deep" / "fake.jsonl"
    one = results.records("fake", "speed", "full", {}, [{"a": 1}, {"a": 2}],
                          utc="2026-01-01T00:00:00Z", context=ctx)
    two = results.records("fake", "speed", "full", {}, [{"a": 3}], utc="2026-01-02T00:00:00Z",
                          context=ctx)
    assert results.append(path, one) == 2 and results.append(path, two) == 1
    assert results.append(path, []) == 0
    assert results.read(path) == one + two
    assert len(path.read_text().splitlines()) == 3


def _records() -> list[dict[str, Any]]:
    ctx = {"git_sha": "abcdef0123456789" + "0" * 24, "git_dirty": False,
           "machine": {"cpu": "X", "cores": 2}}
    old = results.records("craters", "speed", "full", {"posts": 4001},
                          [{"case": "fresh", "n": 22689, "stamp_s": 1.2149},
                           {"case": "default", "n": 22689, "stamp_s": 1.5351}],
                          utc="2026-11-23T10:00:00Z", context=ctx)
    new = results.records("craters", "speed", "full", {"posts": 4001},
                          [{"case": "fresh", "n": 22689, "stamp_s": 1.1}],
                          utc="2026-11-30T10:00:00Z", context=ctx)
    quick = results.records("craters", "speed", "quick", {"posts": 1001},
                            [{"case": "fresh", "n": 1477, "stamp_s": 0.25}],
                            utc="2026-12-01T10:00:00Z", context=ctx)
    return old + new + quick


def test_the_table_renders_the_chosen_columns_with_their_formats() -> None:
    rows = results.select(_records(), size="full", where=["utc=2026-11-23T10:00:00Z"])
    text = results.table(rows, ["case=case", "n=craters", "stamp_s:.2f=stamping (s)",
                                "params.posts", "machine.cores=cores", "git_sha", "utc=date"])
    assert text == (
        "| case | craters | stamping (s) | params.posts | cores | git_sha | date |\n"
        "|---|---|---|---|---|---|---|\n"
        "| fresh | 22,689 | 1.21 | 4,001 | 2 | abcdef0 | 2026-11-23 |\n"
        "| default | 22,689 | 1.54 | 4,001 | 2 | abcdef0 | 2026-11-23 |\n")


def test_select_keeps_a_size_a_match_and_the_latest_run() -> None:
    recs = _records()
    assert [r["figures"]["stamp_s"] for r in results.select(recs, size="full", latest=True)] \
        == [1.1]
    assert [r["size"] for r in results.select(recs, latest=True)] == ["quick"]
    assert len(results.select(recs, where=["case=fresh"])) == 3
    assert [r["figures"]["case"] for r in results.select(recs, where=["case!=fresh"])] == \
        ["default"]
    assert results.select(recs, where=["params.posts=1001"])[0]["size"] == "quick"
    default = results.table(results.select(recs, size="quick"))
    assert default.splitlines()[0] == \
        "| utc | git_sha | figures.case | figures.n | figures.stamp_s |"
    assert "| 2026-12-01 | abcdef0 | fresh | 1,477 | 0.25 |" in default


def test_a_run_prints_and_appends_one_record_per_figure_set(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
    monkeypatch.setattr(results, "machine", lambda: {"cores": 1})
    out = tmp_path / "fake.jsonl"
    assert runner.run_registered(_bench(), ["--size", "quick", "--models", "a,b", "--json",
                                            str(out)]) == 0
    recs = results.read(out)
    assert [r["figures"]["case"] for r in recs] == ["a", "b"]
    assert {r["size"] for r in recs} == {"quick"} and len({r["utc"] for r in recs}) == 1
    assert recs[0]["params"] == {"seconds": 2.0, "models": ["a", "b"], "quality": False,
                                 "mode": "cast", "scene": None}
    assert "2 record(s) appended" in capsys.readouterr().out
    runner.run_registered(_bench(), ["--no-json", "--json", str(out)])
    assert len(results.read(out)) == 2


def test_the_table_command_prints_markdown(tmp_path: Path) -> None:
    path = tmp_path / "c.jsonl"
    results.append(path, _records())
    text = runner.table_command([str(path), "--size", "full", "--latest", "-c", "case",
                                 "--column", "stamp_s:.1f=s"])
    assert text == "| case | s |\n|---|---|\n| fresh | 1.1 |\n"


def test_no_benchmark_is_left_at_the_top_of_perf() -> None:
    """Every benchmark is registered in a kind folder; the runner has no other way to run one."""
    assert sorted(p.name for p in (ROOT / "perf").glob("bench_*.py")) == []
    assert not hasattr(runner, "run_legacy") and not hasattr(runner, "legacy_scripts")


def test_an_unknown_benchmark_is_refused(capsys: pytest.CaptureFixture) -> None:
    assert runner.main(["no_such_bench"]) == 2
    assert "no benchmark 'no_such_bench'" in capsys.readouterr().err


def test_a_percent_sign_in_a_help_text_is_printed_as_is() -> None:
    bench = _bench(main=lambda share: None, params=(
        suite.Param("share", suite.optional(float), "a policy's success (%)", quick=None,
                    full=50.0),))
    assert "a policy's success (%) (quick: None; full: 50.0)" in \
        " ".join(suite.parser(bench).format_help().split())


@pytest.mark.parametrize(("name", "argv", "message"), [
    ("batch_env", ["--what", "sim2sim"], "needs --path"),
    ("batch_env", ["--what", "run", "--path", "/nonexistent/worlds.npz"], "--what pack"),
    ("mjwarp", ["--what", "run", "--path", "/nonexistent/rover.mjb"], "--what export"),
])
def test_a_missing_input_is_one_config_error(name: str, argv: list[str], message: str) -> None:
    from marsscene.errors import ConfigError

    bench = suite.registry()[name]
    _, values = suite.resolve(bench, argv)
    with pytest.raises(ConfigError, match=message):
        bench.main(**values)


def test_env_sections_are_checked_by_the_parser() -> None:
    bench = suite.registry()["env"]
    assert suite.resolve(bench, ["--sections", "physics,reset"])[1]["sections"] == \
        ("physics", "reset")
    assert suite.resolve(bench, ["--size", "quick"])[1]["sections"] == ("steps",)
    with pytest.raises(SystemExit):
        suite.resolve(bench, ["--sections", "steps,warp"])


def _perf_commands(text: str) -> list[str]:
    """What follows ``python perf/run.py`` in a page's code: its fenced blocks' lines and its
    inline code spans (which may wrap), up to a comment or the next command."""
    code: list[str] = []
    prose: list[str] = []
    fenced = False
    for line in text.splitlines():
        if re.match(r"^\s*(```|~~~)", line):
            fenced = not fenced
        else:
            (code if fenced else prose).append(line)
    spans = code + re.findall(r"`([^`]+)`", "\n".join(prose))
    out = []
    for span in spans:
        for m in re.finditer(r"python perf/run\.py\s+(.+?)(?=\s#|&&|;|\|\||$)",
                             span.replace("\\\n", " "), re.S):
            out.append(" ".join(m.group(1).split()))
    return out


def test_the_docs_perf_commands_name_benchmarks_and_their_options() -> None:
    """Every ``python perf/run.py NAME --option`` in README.md and docs/ names a registered
    benchmark (or list, all, table) and options of its command line."""
    reg = suite.registry()
    found: dict[str, set[str]] = {}
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        if "_build" in page.parts:
            continue
        for command in _perf_commands(page.read_text(encoding="utf-8")):
            name, *rest = command.split()
            if name in ("list", "all", "table", "NAME") or name.startswith("-"):
                continue
            assert name in reg, f"{page.name}: `python perf/run.py {command}`: no {name!r}"
            options = suite.parser(reg[name])._option_string_actions
            for token in rest:
                token = token.strip("[](),;:'\"")
                if re.fullmatch(r"--[a-z][\w-]*", token):
                    assert token in options, f"{page.name}: {name} has no option {token}"
                    found.setdefault(name, set()).add(token)
    assert {"--what", "--path", "--envs", "--folders", "--posts"} <= found["batch_env"]
    assert found["env"] == {"--sections"} and "--what" in found["mjwarp"]


def test_every_registered_benchmark_imports_and_its_declaration_is_valid() -> None:
    reg = suite.registry()
    assert len(reg) >= 29
    for kind, dotted in suite.modules():
        path = ROOT / Path(*dotted.split(".")).with_suffix(".py")
        assert path.parent.name == kind
    for bench in reg.values():
        assert suite.problems(bench) == [], bench.name
        assert bench.summary, bench.name
        assert "--size" in suite.parser(bench).format_help()
        for size in suite.SIZES:
            _, values = suite.resolve(bench, ["--size", size])
            assert set(values) == {p.name for p in bench.params}
            json.dumps(values, default=str)  # a record's parameters
    assert {"craters", "camera", "newton", "kiss_start", "fastdds_check", "env", "batch_env",
            "mjwarp"} <= set(reg)
    assert {reg[n].kind for n in ("craters", "camera", "newton", "kiss_start")} == \
        set(suite.KINDS)
    listing = runner.list_benchmarks()
    for bench in reg.values():
        assert f"  {bench.name} " in listing


def test_the_suite_imports_nothing_from_tests_and_leaves_sys_path_alone() -> None:
    for kind in suite.KINDS:
        for path in (ROOT / "perf" / kind).rglob("*.py"):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and node.module:
                    assert node.module.split(".")[0] != "tests", path
                    assert node.module.split(".")[0] not in ("_measure", "bench_camera"), path
                elif isinstance(node, ast.Import):
                    assert all(a.name.split(".")[0] != "tests" for a in node.names), path
                elif isinstance(node, ast.Attribute) and node.attr == "path" and \
                        isinstance(node.value, ast.Name) and node.value.id == "sys":
                    raise AssertionError(f"{path} touches sys.path")


def test_the_craters_results_table_is_made_from_its_results_file() -> None:
    page = (ROOT / "docs" / "results" / "craters.md").read_text(encoding="utf-8")
    match = re.search(r"<!-- table: python perf/run.py table (\S+) (.+?) -->\n(.+?\n)\n",
                      page, re.S)
    assert match, "the craters page names the command that makes its table"
    file, options, table = match.groups()
    rendered = runner.table_command([str(ROOT / file), *shlex.split(options)])
    assert rendered == table
    assert {r["benchmark"] for r in results.read(ROOT / file)} == {"craters"}
