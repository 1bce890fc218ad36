"""The docs and ``marsscene --help`` agree, checked through click's command objects (no command
is run).

* Shell blocks (```bash, ```console, ```sh or unlabelled) of README.md and of every page under
  docs/: each command segment that starts with ``marsscene`` names existing subcommands, and
  options that ``--help`` lists (not hidden, not deprecated); a literal number or choice passes
  the option's click type. Placeholders (``FILE``, ``X Y``, ``[...]``) are fine.
* Prose: every `--option` in inline code is an option of some marsscene command (or of another
  program listed in ``FOREIGN``).
* Defaults: a default a page states for an option, in a sentence ("`--corridor-m` (default
  15 m)"), a table with a default column, a table row about one option ("(default 2)") or a
  copied ``--help`` line ("[default: 15.0; x>=1.0]"), equals click's default, and a unit given
  with it matches the option's (its name's suffix, else its help's "(m)"). The command is the
  nearest one named before it on the page that has the option. Prose defaults ("one per core")
  are not checked.
* A table introduced as "checked against `marsscene X --help`" lists each visible option of X
  with the help text click prints.
"""

from __future__ import annotations

import math
import re
import shlex
from functools import cache
from pathlib import Path

import click
import pytest

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


def _command(path: tuple[str, ...]) -> click.Command:
    cmd: click.Command = main
    for name in path:
        assert isinstance(cmd, click.Group) and name in cmd.commands, path
        cmd = cmd.commands[name]
    return cmd


@cache
def _options(path: tuple[str, ...]) -> dict[str, click.Option]:
    """Option name -> click option of ``marsscene PATH``: what its ``--help`` lists (no hidden
    options), read from click's command objects."""
    cmd = _command(path)
    return {name: p for p in cmd.params if isinstance(p, click.Option) and not p.hidden
            for name in (*p.opts, *p.secondary_opts)}


def _all_paths(cmd: click.Command = main, path: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    out = [path]
    if isinstance(cmd, click.Group):
        for name, sub in cmd.commands.items():
            out += _all_paths(sub, (*path, name))
    return out


PATHS = _all_paths()
HELP = frozenset({"-h", "--help"})
#: types whose literal values in the docs are converted by click (paths may not exist here)
CHECKED_TYPES = (click.Choice, click.types.IntParamType, click.types.FloatParamType)


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
    options = _options(tuple(path))
    for i, token in enumerate(tokens):
        token = token.strip("[]")
        if not token.startswith("-") or token in ("-", "--") or re.fullmatch(r"-[\d.]+", token):
            continue
        name = token.split("=", 1)[0]
        where = f"{page.name}: `marsscene {' '.join(path)}`"
        assert name in options or name in HELP, f"{where} has no option {name}"
        param = options.get(name)
        if param is None or param.is_flag or param.count:
            continue
        assert not (param.help or "").startswith("Deprecated"), (
            f"{where}: {name} is deprecated; the docs teach its replacement")
        values = [token.split("=", 1)[1]] if "=" in token else tokens[i + 1:i + 1 + param.nargs]
        for value in (v.strip("[]") for v in values):
            if _is_placeholder(value) or (value.startswith("-") and not _is_number(value)):
                continue
            if isinstance(param.type, CHECKED_TYPES):
                try:
                    param.type.convert(value, param, None)
                except click.BadParameter as exc:
                    pytest.fail(f"{where} {name} {value}: {exc.message}")


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def test_examples_were_found() -> None:
    pages_with_examples = {p.name for p, _ in EXAMPLES}
    assert len(EXAMPLES) > 60
    assert {"README.md", "getting_started.md", "runtime.md", "benchmark.md"} <= pages_with_examples


# --- defaults and units the prose states --------------------------------------------------------

OPT_SPAN = r"`(--[a-z][\w-]*)((?: [^`\n]+)?)`"  # `--opt` or `--opt VALUE`
#: an option's stated default: `--opt X` (default ...), (`--opt N`, default 4), `--opt` (default)
INLINE_DEFAULT = re.compile(
    OPT_SPAN + r"\**(?:\)? ?[,(] ?)(?:the )?default(?::| is)?([^);:\n]*)[);:]")
#: `--cmd-timeout-s` (0.5 s of sim time by default)
BY_DEFAULT = re.compile(OPT_SPAN + r"\** \(([\d.]+[^)\n]*?) by default\)")
#: "(default 2)" in a table row that documents one option
ROW_DEFAULT = re.compile(r"\((?:the )?default:? ([^);:\n]+)[);:]")
#: options of other programs that the prose names (scripts, the VPR-methods-evaluation CLI)
FOREIGN = {"--cpu-envs", "--collider-min-m", "--save_descriptors", "--obs", "--save-every",
           "--deadline", "--total-minutes"}  # examples/train_batch_ppo.py and outside tools
TABLE_ROW = re.compile(r"^\|(.*)\|\s*$")
UNITS = {"m": "m", "deg": "deg", "°": "deg", "s": "s", "h": "h", "hz": "hz", "px": "px"}
HELP_UNIT = re.compile(r"\((m|deg|s|h|Hz)[);,]")


def _unit(option: click.Option, name: str) -> str | None:
    """The option's unit: its name's suffix (``--lookahead-m``), else its help's ``(m)``."""
    suffix = name.rsplit("-", 1)[-1]
    if suffix in UNITS:
        return UNITS[suffix]
    m = HELP_UNIT.search(option.help or "")
    return UNITS[m.group(1).lower()] if m else None


def _context_paths(text: str, pos: int) -> list[tuple[str, ...]]:
    """The commands named before ``pos`` (`marsscene drive`, ...), nearest first."""
    found: list[tuple[str, ...]] = []
    for m in re.finditer(r"marsscene ([a-z][\w-]*)(?: ([a-z][\w-]*))?", text[:pos]):
        for path in ((m.group(1), m.group(2)), (m.group(1),)):
            if path in PATHS:
                found.append(path)
                break
    return found[::-1]


def _owner(name: str, text: str, pos: int) -> list[tuple[str, ...]]:
    """The command(s) an option mentioned at ``pos`` of a page belongs to: the nearest command
    named before it that has the option, else every command that has it."""
    having = [path for path in PATHS if name in _options(path)]
    for path in _context_paths(text, pos):
        if path in having:
            return [path]
    return having


def _default_claims(text: str) -> list[tuple[int, str, str, str]]:
    """(offset, option, value in the option's span, stated default) for every default a page
    states for a command-line option: in a sentence, in a table with a default column, or in a
    copy of ``--help`` (``[default: 15.0; x>=1.0]``)."""
    claims = [(m.start(), m.group(1), m.group(2).strip(), m.group(3).strip())
              for pattern in (INLINE_DEFAULT, BY_DEFAULT) for m in pattern.finditer(text)]
    column = None
    offset = 0
    for line in text.splitlines(keepends=True):
        row = TABLE_ROW.match(line)
        if not row:
            column = None
        else:
            cells = [c.strip() for c in row.group(1).split(" | ")]
            if set(line) <= set("|-: \n"):
                pass
            elif column is None and any(c.lower() == "default" for c in cells):
                column = [c.lower() for c in cells].index("default")
            else:
                head = re.match(OPT_SPAN, cells[0])
                if head and " / " not in cells[0] and "," not in cells[0]:
                    if column is not None and column < len(cells):
                        claims.append((offset, head.group(1), "", cells[column]))
                    copied = re.search(r"\[default: ([^;\]]+)", line)
                    if copied:
                        claims.append((offset, head.group(1), "", copied.group(1)))
                    rest = INLINE_DEFAULT.sub("", " | ".join(cells[1:]))
                    if not copied and column is None and (said := ROW_DEFAULT.search(rest)):
                        claims.append((offset, head.group(1), "", said.group(1)))
        offset += len(line)
    return claims


def _disagreement(option: click.Option, name: str, span_value: str, stated: str) -> str | None:
    """Why ``stated`` (the default a page gives) disagrees with click's default, or None (it
    agrees, or it is prose that cannot be checked mechanically: 'one per core')."""
    default = option.default
    if isinstance(default, (list, tuple)):
        default = default[0] if len(default) == 1 else None
    stated = stated.replace("×", "x").strip().strip("`").strip()
    if not stated:  # `--pace realtime` (default): the span's value is the default
        stated = span_value
    words = stated.replace("`", "").split()
    if not words or default is None or option.is_flag or default is click.core.UNSET:
        return None
    first = words[0].rstrip(".,")
    if isinstance(default, (int, float)):
        if not _is_number(first):
            return None
        if not math.isclose(float(first), float(default)):
            return f"default {first}, click's is {default}"
        unit = _unit(option, name)
        said = UNITS.get(words[1].rstrip(".,").lower()) if len(words) > 1 else None
        if unit and said and unit != said:
            return f"default in {said}, the option takes {unit}"
        return None
    if isinstance(option.type, click.Choice) and first not in option.type.choices:
        return None  # prose ("only with raw images")
    if len(words) > 1 and not isinstance(option.type, click.Choice):
        return None
    if first != str(default):
        return f"default {first!r}, click's is {default!r}"
    return None


CLAIMS = [(page, *claim) for page in PAGES for claim in
          _default_claims(page.read_text(encoding="utf-8"))]


@pytest.mark.parametrize(("page", "offset", "name", "span_value", "stated"), CLAIMS,
                         ids=[f"{c[0].relative_to(ROOT)}:{c[2]}={c[4][:30]}" for c in CLAIMS])
def test_stated_default_matches_click(page: Path, offset: int, name: str, span_value: str,
                                      stated: str) -> None:
    text = page.read_text(encoding="utf-8")
    owners = _owner(name, text, offset)
    assert owners, f"{page.name}: no command has the option {name}"
    why = [_disagreement(_options(path)[name], name, span_value, stated) for path in owners]
    assert None in why, (f"{page.name}: {name} (of `marsscene {' '.join(owners[0])}`): "
                         f"{'; '.join(w for w in why if w)}")


def test_copied_help_tables_list_every_option() -> None:
    """A table introduced as 'checked against `marsscene X --help`' holds each visible option
    of X once, with the help text click prints for it."""
    checked = 0
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for m in re.finditer(r"checked against `marsscene ([\w -]+?) --help`", text):
            path = tuple(m.group(1).split())
            cmd = _command(path)
            ctx = click.Context(cmd, info_name=path[-1], parent=click.Context(main))
            want = {}
            for param in cmd.get_params(ctx):
                record = param.get_help_record(ctx)
                if isinstance(param, click.Option) and record and "--help" not in param.opts:
                    want[record[0]] = re.sub(r"\s+", " ", record[1])
            rows: dict[str, str] = {}
            table = text[m.end():].split("\n\n", 2)[1]
            for line in table.splitlines()[2:]:
                cells = re.match(r"^\| `([^`]+)` \| (.*) \|$", line)
                assert cells, f"{page.name}: not an option row: {line}"
                rows[cells.group(1).replace("\\|", "|")] = cells.group(2).replace("\\|", "|")
            missing, extra = sorted(set(want) - set(rows)), sorted(set(rows) - set(want))
            assert not missing and not extra, (
                f"{page.name}: `marsscene {m.group(1)} --help` table: missing {missing}, "
                f"not options {extra}")
            for opt, help_text in want.items():
                assert rows[opt] == help_text, f"{page.name}: {opt}: {rows[opt]!r} != {help_text!r}"
            checked += 1
    assert checked >= 1


def _prose_spans(text: str) -> list[tuple[int, str]]:
    """(offset, text) of the inline code spans outside fenced blocks that start with ``--``."""
    spans = []
    fenced = False
    offset = 0
    for line in text.splitlines(keepends=True):
        if re.match(r"^\s*(```|~~~)", line):
            fenced = not fenced
        elif not fenced:
            spans += [(offset + m.start(), m.group(1))
                      for m in re.finditer(r"`(--[a-z][^`\n]*)`", line)]
        offset += len(line)
    return spans


PROSE = [(page, offset, span) for page in PAGES
         for offset, span in _prose_spans(page.read_text(encoding="utf-8"))]


@pytest.mark.parametrize(("page", "offset", "span"), PROSE,
                         ids=[f"{p.relative_to(ROOT)}:{s[:40]}" for p, _, s in PROSE])
def test_prose_option_exists(page: Path, offset: int, span: str) -> None:
    """An option the prose names in `--code` is an option of a marsscene command (or listed
    in FOREIGN); a `--opt VALUE` of a choice option names one of its choices."""
    names = [t for t in span.split() if re.fullmatch(r"--[a-z][\w-]*", t)]
    for name in names:
        if name in FOREIGN:
            return
        if name in HELP:
            continue
        assert _owner(name, page.read_text(encoding="utf-8"), offset), (
            f"{page.name}: `{span}`: no marsscene command has the option {name}")


def test_default_claims_were_found() -> None:
    assert len(CLAIMS) > 20
    assert {"runtime.md", "ros.md", "benchmark.md"} <= {p.name for p, *_ in CLAIMS}
