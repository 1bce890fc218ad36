"""Every ``marsscene`` command shown in the docs exists, with the options it uses.

Reads the shell blocks (```bash, ```console, ```sh or unlabelled) of README.md and of every page
under docs/, takes each command segment that starts with ``marsscene``, walks its subcommands
and checks every option against the options the command's ``--help`` lists (and a literal value
of a choice option against its choices). Placeholders (``FILE``, ``X Y``, ``[...]``) are fine.
"""

from __future__ import annotations

import re
import shlex
from functools import cache
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from marsscene.cli import main

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted(
    p for p in (ROOT / "docs").rglob("*.md")
    if "_build" not in p.parts and "generated" not in p.parts and "notebooks" not in p.parts
)]
SHELL = ("bash", "console", "sh", "shell", "")


def _shell_blocks(text: str) -> list[str]:
    """The bodies of the fenced shell blocks (and unlabelled ones) of a Markdown page."""
    blocks: list[str] = []
    fence: str | None = None
    lang = ""
    body: list[str] = []
    for line in text.splitlines():
        m = re.match(r"^(\s*)(`{3,}|~{3,})(.*)$", line)
        if fence is None:
            if m:
                fence, lang, body = m.group(2), m.group(3).strip(), []
        elif m and m.group(2).startswith(fence) and not m.group(3).strip():
            if lang in SHELL:
                blocks.append("\n".join(body))
            fence = None
        else:
            body.append(line)
    return blocks


def _commands(text: str) -> list[str]:
    """The ``marsscene ...`` segments of the shell blocks of ``text``."""
    out: list[str] = []
    for body in _shell_blocks(text):
        joined = re.sub(r"\\\n\s*", " ", body)
        for line in joined.splitlines():
            line = line.strip().removeprefix("$ ")
            for segment in re.split(r"&&|\|\||;|\|(?=\s)", line):
                segment = segment.strip()
                if re.match(r"marsscene( +(-|[a-z][\w-]*( |$))|$)", segment):
                    out.append(segment)
    return out


EXAMPLES = [(page, cmd) for page in PAGES for cmd in _commands(page.read_text(encoding="utf-8"))]


@cache
def _help_options(path: tuple[str, ...]) -> frozenset[str]:
    result = CliRunner().invoke(main, [*path, "--help"], terminal_width=200)
    assert result.exit_code == 0, (path, result.output)
    options = result.output.split("Options:")[-1]
    return frozenset(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", options))


def _tokens(command: str) -> list[str]:
    command = re.sub(r"\s#.*$", "", command)  # a trailing comment
    try:
        return shlex.split(command)
    except ValueError:
        return command.split()


def _is_placeholder(token: str) -> bool:
    return (not token or token.isupper() or any(c in token for c in "[]|<>{}…")
            or token.startswith(("$", "...")) or token.endswith("..."))


@pytest.mark.parametrize(("page", "command"), EXAMPLES,
                         ids=[f"{p.relative_to(ROOT)}:{c[:60]}" for p, c in EXAMPLES])
def test_cli_example_matches_help(page: Path, command: str) -> None:
    tokens = _tokens(command)[1:]
    group: click.Command = main
    path: list[str] = []
    while tokens and isinstance(group, click.Group) and not tokens[0].startswith("-"):
        name = tokens.pop(0)
        assert name in group.commands, (
            f"{page.name}: no subcommand {name!r} in `marsscene {' '.join(path)}`")
        group = group.commands[name]
        path.append(name)
    known = _help_options(tuple(path))
    params = {opt: p for p in group.params for opt in (*p.opts, *p.secondary_opts)}
    for i, token in enumerate(tokens):
        token = token.strip("[]")
        if not token.startswith("-") or token in ("-", "--") or re.fullmatch(r"-[\d.]+", token):
            continue
        name = token.split("=", 1)[0]
        assert name in known, f"{page.name}: `marsscene {' '.join(path)}` has no option {name}"
        param = params.get(name)
        if isinstance(param, click.Option) and isinstance(param.type, click.Choice):
            value = token.split("=", 1)[1] if "=" in token else (
                tokens[i + 1] if i + 1 < len(tokens) else "")
            if not _is_placeholder(value) and not value.startswith("-"):
                assert value in param.type.choices, (
                    f"{page.name}: {name} {value!r} is not one of {list(param.type.choices)}")


def test_examples_were_found() -> None:
    pages_with_examples = {p.name for p, _ in EXAMPLES}
    assert len(EXAMPLES) > 60
    assert {"README.md", "getting_started.md", "runtime.md", "benchmark.md"} <= pages_with_examples
