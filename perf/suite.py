"""The benchmark suite's declarations: each benchmark states its parameters once (name, type,
help, a ``quick`` and a ``full`` value) and the runner builds its command line from them.

A registered benchmark is a module ``perf/<kind>/bench_<name>.py`` (kinds: :data:`KINDS`) with

* ``PARAMS``: a tuple of :class:`Param` (empty when it takes none), and
* ``main(**params)``: prints its figures as before and returns them, as one figure set (a dict)
  or several (a list of dicts), or ``None`` when it prints only.

``python perf/run.py NAME --size quick|full [--param value ...]`` runs one; the ``full`` values
are the measured configuration the results pages quote, the ``quick`` ones a smoke size.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

KINDS = ("speed", "fidelity", "interop", "studies")
"""The folders of ``perf/``: speed and memory; fidelity against a truth; interoperability with
other tools; studies (parameter sweeps and one-off investigations)."""

SIZES = ("quick", "full")
PERF = Path(__file__).resolve().parent


def names(text: str) -> tuple[str, ...]:
    """A comma-separated list of names (``"os1-64,os1-128"``; ``none`` or empty: no names)."""
    items = tuple(v.strip() for v in text.split(",") if v.strip())
    return () if items == ("none",) else items


def floats(text: str) -> tuple[float, ...]:
    """A comma-separated list of numbers (``"13,5,2,-3"``; ``none`` or empty: no numbers)."""
    return tuple(float(v) for v in names(text))


def ints(text: str) -> tuple[int, ...]:
    """A comma-separated list of whole numbers (``"256,1024,4096"``; ``none``: none)."""
    return tuple(int(v) for v in names(text))


def optional(kind: Callable[[str], Any]) -> Callable[[str], Any]:
    """``kind``, or ``None`` for an empty string or ``none``."""
    def parse(text: str) -> Any:
        return None if text.strip().lower() in ("", "none") else kind(text)

    parse.__name__ = f"optional {getattr(kind, '__name__', 'value')}"
    return parse


@dataclass(frozen=True)
class Param:
    """One parameter of a benchmark: its option ``--name`` (underscores as dashes) parsed by
    ``type`` (``bool`` makes a ``--name/--no-name`` flag), a help text, and its value at each
    size. ``choices`` limits the values."""

    name: str
    type: Callable[[str], Any]
    help: str
    quick: Any
    full: Any
    choices: tuple[Any, ...] | None = None

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    def value(self, size: str) -> Any:
        """The value at ``size`` (``quick`` or ``full``)."""
        return self.quick if size == "quick" else self.full


@dataclass(frozen=True)
class Registered:
    """A benchmark found in a kind folder: its name (the module's without ``bench_``), kind,
    module path, parameters and ``main``."""

    name: str
    kind: str
    module: str
    params: tuple[Param, ...]
    main: Callable[..., Any]
    summary: str


def summary(module: ModuleType, width: int = 76) -> str:
    """The first paragraph of a module's docstring on one line, cut to ``width`` characters."""
    first = " ".join((module.__doc__ or "").strip().split("\n\n", 1)[0].split())
    return first if len(first) <= width else first[: width - 1].rstrip() + "…"


def declared(module: ModuleType, kind: str) -> Registered:
    """The declaration of a benchmark module (raises ``TypeError`` when it has none)."""
    params = getattr(module, "PARAMS", None)
    if not isinstance(params, tuple) or not callable(getattr(module, "main", None)):
        raise TypeError(f"{module.__name__} declares no PARAMS tuple and main()")
    stem = module.__name__.rsplit(".", 1)[-1]
    return Registered(stem.removeprefix("bench_"), kind, module.__name__, params, module.main,
                      summary(module))


def modules() -> list[tuple[str, str]]:
    """``(kind, dotted module)`` of every script in the kind folders, sorted."""
    out = []
    for kind in KINDS:
        for path in sorted((PERF / kind).glob("*.py")):
            if not path.name.startswith("_"):
                out.append((kind, f"perf.{kind}.{path.stem}"))
    return out


def registry() -> dict[str, Registered]:
    """Every registered benchmark by name (importing each module: imports there are light)."""
    found = {}
    for kind, dotted in modules():
        bench = declared(importlib.import_module(dotted), kind)
        if bench.name in found:
            raise ValueError(f"two benchmarks named {bench.name!r}")
        found[bench.name] = bench
    return found


def problems(bench: Registered) -> list[str]:
    """What is wrong with a declaration: names, types, sizes and ``main``'s signature."""
    out = []
    seen: set[str] = set()
    for p in bench.params:
        where = f"{bench.name}.{p.name}"
        if not p.name.isidentifier() or p.name in seen or p.name in ("size", "json"):
            out.append(f"{where}: not a fresh identifier")
        seen.add(p.name)
        if not p.help.strip():
            out.append(f"{where}: no help text")
        for size in SIZES:
            v = p.value(size)
            if p.choices is not None and v not in p.choices:
                out.append(f"{where}: {size} value {v!r} not in {p.choices}")
            if p.type in (int, float, str, bool) and v is not None and \
                    not isinstance(v, p.type):
                out.append(f"{where}: {size} value {v!r} is not {p.type.__name__}")
    sig = inspect.signature(bench.main).parameters
    if set(sig) != seen:
        out.append(f"{bench.name}: main takes {sorted(sig)}, PARAMS declare {sorted(seen)}")
    return out


def parser(bench: Registered) -> argparse.ArgumentParser:
    """The command line of one benchmark, built from its declaration."""
    ap = argparse.ArgumentParser(prog=f"perf/run.py {bench.name}", description=bench.summary)
    ap.add_argument("--size", choices=SIZES, default="full",
                    help="the declared values to start from (default: full)")
    ap.add_argument("--json", type=Path, default=None,
                    help=f"results file to append to (default: perf/results/{bench.name}.jsonl)")
    ap.add_argument("--no-json", action="store_true", help="print only; write no record")
    for p in bench.params:
        kw: dict[str, Any] = {"dest": p.name, "default": None,
                              "help": f"{_escaped(p.help)} (quick: {_shown(p.quick)}; "
                                      f"full: {_shown(p.full)})"}
        if p.type is bool:
            ap.add_argument(p.flag, action=argparse.BooleanOptionalAction, **kw)
        else:
            ap.add_argument(p.flag, type=p.type, choices=p.choices, metavar=p.name.upper(),
                            **kw)
    return ap


def _escaped(text: str) -> str:
    """``text`` as argparse prints it (its help strings are %-format templates)."""
    return text.replace("%", "%%")


def _shown(value: Any) -> str:
    if isinstance(value, tuple):
        return _escaped(",".join(str(v) for v in value) or "none")
    return _escaped(str(value))


def resolve(bench: Registered, argv: Sequence[str]) -> tuple[argparse.Namespace, dict[str, Any]]:
    """Parse ``argv`` for ``bench``: the options and the parameter values (the size's declared
    value where no option was given)."""
    args = parser(bench).parse_args(list(argv))
    values = {}
    for p in bench.params:
        given = getattr(args, p.name)
        values[p.name] = p.value(args.size) if given is None else given
    return args, values


def figure_sets(returned: Any) -> list[dict[str, Any]]:
    """A ``main``'s return value as a list of figure sets."""
    if returned is None:
        return []
    if isinstance(returned, dict):
        return [returned]
    if isinstance(returned, list) and all(isinstance(r, dict) for r in returned):
        return returned
    raise TypeError(f"main returned {type(returned).__name__}: a dict, a list of dicts or None")
