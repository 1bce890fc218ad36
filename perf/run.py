"""The benchmark suite's one entry point.

Usage::

    python perf/run.py list                              # registered benchmarks, by kind
    python perf/run.py NAME --help                       # its parameters, quick and full values
    python perf/run.py NAME [--size quick|full] [--PARAM VALUE ...] [--json FILE | --no-json]
    python perf/run.py all --size quick                  # every registered benchmark
    python perf/run.py table FILE [-c KEY[:FMT][=HEADER] ...] [--size full] [--latest]

``NAME`` is a module's name without ``bench_`` (``craters`` is ``perf/speed/bench_craters.py``).
A run prints its figures and appends one JSON line per figure set to ``--json`` (default
``perf/results/NAME.jsonl``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

PERF = Path(__file__).resolve().parent
if str(PERF.parent) not in sys.path:  # ``python perf/run.py``: the ``perf`` package's root
    sys.path.insert(0, str(PERF.parent))

from perf import results, suite  # noqa: E402


def run_registered(bench: suite.Registered, argv: Sequence[str]) -> int:
    """Run one benchmark with its parsed parameters; append its records."""
    args, values = suite.resolve(bench, argv)
    print(f"== {bench.name} ({bench.kind}, {args.size}) ==", flush=True)
    utc = results.utc_now()
    sets = suite.figure_sets(bench.main(**values))
    if args.no_json or not sets:
        return 0
    path = args.json or PERF / "results" / f"{bench.name}.jsonl"
    recs = results.records(bench.name, bench.kind, args.size, values, sets, utc=utc)
    print(f"{bench.name}: {results.append(path, recs)} record(s) appended to {path}")
    return 0


def list_benchmarks() -> str:
    """The registered benchmarks by kind, with their one-line summaries."""
    lines = []
    reg = suite.registry()
    for kind in suite.KINDS:
        lines.append(f"{kind}:")
        lines += [f"  {b.name:22s} {b.summary}" for b in reg.values() if b.kind == kind]
    return "\n".join(lines)


def table_command(argv: Sequence[str]) -> str:
    ap = argparse.ArgumentParser(prog="perf/run.py table",
                                 description="A Markdown table from a results file.")
    ap.add_argument("file", type=Path)
    ap.add_argument("-c", "--column", action="append", default=[], dest="columns",
                    help="KEY[:FORMAT][=HEADER], repeatable, in order (keys: figures.*, "
                         "params.*, machine.*, utc, git_sha; a bare KEY tries figures. then "
                         "params.; FORMAT as in format(), e.g. .2f)")
    ap.add_argument("--size", choices=suite.SIZES, default=None)
    ap.add_argument("--where", action="append", default=[],
                    help="KEY=VALUE or KEY!=VALUE (repeatable)")
    ap.add_argument("--latest", action="store_true", help="the most recent run's records only")
    args = ap.parse_args(list(argv))
    recs = results.select(results.read(args.file), size=args.size, where=args.where,
                          latest=args.latest)
    return results.table(recs, args.columns)


def main(argv: Sequence[str]) -> int:
    argv = list(argv)
    if not argv or argv[0] in ("list", "-h", "--help"):
        print(__doc__ if argv[:1] in (["-h"], ["--help"]) else list_benchmarks())
        return 0
    command, rest = argv[0], argv[1:]
    if command == "table":
        print(table_command(rest), end="")
        return 0
    reg = suite.registry()
    if command == "all":
        for bench in reg.values():
            run_registered(bench, rest)
        return 0
    if command in reg:
        return run_registered(reg[command], rest)
    print(f"perf/run.py: no benchmark {command!r}; `python perf/run.py list` lists them",
          file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
