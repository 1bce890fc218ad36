"""Run every benchmark (``perf/bench_*.py``) and print its figures.

Usage: ``python perf/run.py [name ...]`` (names without ``bench_``/``.py``).
Each module defines ``main() -> None`` that prints its own figures.
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
from pathlib import Path


def main(argv: list[str]) -> int:
    here = Path(__file__).resolve().parent
    sys.path.insert(0, str(here))  # the scripts import _measure and each other
    paths = sorted(here.glob("bench_*.py"))
    if argv:
        paths = [p for p in paths if p.stem.removeprefix("bench_") in argv]
    for path in paths:
        print(f"== {path.stem} ==", flush=True)
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec and spec.loader
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.main(*([[]] if inspect.signature(module.main).parameters else []))  # defaults
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
