"""The tested path of docs/getting_started.md, checked without running it.

``tools/check_getting_started.py`` runs the page's marked shell blocks in a fresh virtual
environment (``.ci/run`` does, as its own step). Here: its extraction of the blocks and their
checks, and that every ``marsscene`` command line of a marked block parses as click parses it
(options, values, required arguments), with paths not required to exist.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import click
import pytest

from marsscene.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "check_getting_started", ROOT / "tools" / "check_getting_started.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve their module
    spec.loader.exec_module(module)
    return module


tool = _tool()
STEPS = tool.parse_steps((ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8"))

SAMPLE = """\
# A page

```bash
echo not tested
```

<!-- test: first
files: out/a.txt "out/b c.txt"
output: wrote (\\d+) lines in 1..10
output: done
quick: --n 100 => --n 3
timeout: 60
-->

```bash
marsscene build --seed 7 --out out && echo done
python - <<'EOF'
marsscene inside a here-document is Python, not a command
EOF
tool --n 100 | marsscene info out
```

<!-- an ordinary comment -->
<!-- test: second -->
```bash
ls
```
"""


def test_parse_sample() -> None:
    first, second = tool.parse_steps(SAMPLE)
    assert (first.name, second.name) == ("first", "second")
    assert first.line == 7
    assert first.files == ("out/a.txt", "out/b c.txt")
    assert first.output[0] == tool.Expect(r"wrote (\d+) lines", 1.0, 10.0)
    assert first.output[1] == tool.Expect("done")
    assert first.timeout_s == 60.0
    assert "--n 3" in first.script(quick=True) and "--n 100" in first.script(quick=False)
    assert tool.marsscene_commands(first.code) == [
        ["build", "--seed", "7", "--out", "out"], ["info", "out"]]
    assert second.code == "ls" and second.files == () and second.output == ()


def test_expect_checks_numbers() -> None:
    expect = tool.Expect(r"rmse ([\d.]+)", 0.01, 1.0)
    assert expect.check("ATE (m): rmse 0.30 mean 0.2") is None
    assert "outside" in expect.check("ATE (m): rmse 3.5")
    assert "no match" in expect.check("nothing")


@pytest.mark.parametrize("bad", [
    "<!-- test: x\nfiels: a\n-->\n```bash\nls\n```\n",           # unknown key
    "<!-- test: x\nquick: --a 1 => --a 2\n-->\n```bash\nls\n```\n",  # quick text not in block
    "<!-- test: x\noutput: no group in 1..2\n-->\n```bash\nls\n```\n",
    "<!-- test: x -->\nSome prose.\n\n```bash\nls\n```\n",          # not before a block
    "<!-- test: x -->\n```python\nprint()\n```\n",                # not a bash block
    "<!-- test: x -->\n```bash\nls\n```\n<!-- test: x -->\n```bash\nls\n```\n",  # repeated
])
def test_malformed_markers_are_errors(bad: str) -> None:
    with pytest.raises(ValueError):
        tool.parse_steps(bad)


def test_page_walks_the_whole_path() -> None:
    names = [s.name for s in STEPS]
    assert names[:2] == ["install", "build"]
    for step in ("drive", "eval", "benchmark", "controller", "gym", "serve"):
        assert step in names
    install = STEPS[0].code
    # the README's install line, verbatim
    assert 'python -m pip install -e ".[all]"' in install.splitlines()
    # every step checks something: a file or what it printed
    assert all(s.files or s.output for s in STEPS)
    # the quick variant of a step is offered by the page itself
    text = (ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8")
    for step in STEPS:
        for _, new in step.quick:
            for extra in set(new.split()) - set(step.code.split()):
                assert extra in text.replace(step.script(quick=False), ""), (step.name, extra)


def _resolve(args: list[str]) -> tuple[click.Command, str, list[str]]:
    cmd: click.Command = main
    name = "marsscene"
    while isinstance(cmd, click.Group) and args and not args[0].startswith("-"):
        name, args = args[0], args[1:]
        sub = cmd.commands.get(name)
        assert sub is not None, f"no subcommand {name!r}"
        cmd = sub
    return cmd, name, args


COMMANDS = [(s.name, c) for s in STEPS for quick in (False, True)
            for c in tool.marsscene_commands(s.script(quick))]


@pytest.mark.parametrize(("step", "args"), COMMANDS,
                         ids=[f"{s}:{' '.join(a)[:50]}" for s, a in COMMANDS])
def test_marked_commands_parse(step: str, args: list[str], monkeypatch: pytest.MonkeyPatch) -> None:
    # files the earlier steps write need not exist here: paths are taken as given
    monkeypatch.setattr(click.Path, "convert", lambda self, value, param, ctx: value)
    cmd, name, rest = _resolve(list(args))
    if rest == ["--version"] and cmd is main:
        return
    try:
        cmd.make_context(name, rest)
    except click.ClickException as exc:
        pytest.fail(f"step {step}: `marsscene {' '.join(args)}`: {exc.format_message()}")
