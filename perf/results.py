"""Benchmark results as JSON lines: one record per figure set (benchmark, kind, size, parameters,
figures, git SHA, UTC time, machine), appended to a results file, and Markdown tables made
from such a file for the results pages (``python perf/run.py table FILE``)."""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
from collections.abc import Iterable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def _run(cmd: Sequence[str]) -> str | None:
    try:
        done = subprocess.run(list(cmd), capture_output=True, text=True, timeout=10, cwd=ROOT)
    except (OSError, subprocess.SubprocessError):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


def git_sha() -> dict[str, Any]:
    """The checkout's commit and whether tracked files differ from it."""
    sha = _run(["git", "rev-parse", "HEAD"])
    dirty = _run(["git", "status", "--porcelain", "--untracked-files=no"])
    return {"git_sha": sha, "git_dirty": None if dirty is None else bool(dirty)}


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _memory_gib() -> float | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                return round(int(line.split()[1]) / 2**20, 1)
    except OSError:
        pass
    return None


def machine() -> dict[str, Any]:
    """The machine without its name: CPU model, cores, memory, GPUs, OS and Python."""
    gpus = _run(["nvidia-smi", "--query-gpu=name,memory.total", "--format=csv,noheader"])
    affinity = getattr(os, "sched_getaffinity", None)
    return {"cpu": _cpu_model(), "cores": len(affinity(0)) if affinity else os.cpu_count(),
            "memory_gib": _memory_gib(),
            "gpus": [g.strip() for g in gpus.splitlines()] if gpus else [],
            "os": f"{platform.system()} {platform.release()}",
            "python": platform.python_version()}


def utc_now() -> str:
    return datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def records(name: str, kind: str, size: str, params: dict[str, Any],
            sets: Iterable[dict[str, Any]], *, utc: str | None = None,
            context: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """One record per figure set of one run (the run's records share ``utc``)."""
    ctx = context if context is not None else {**git_sha(), "machine": machine()}
    when = utc or utc_now()
    return [{"benchmark": name, "kind": kind, "size": size, "params": params, "figures": s,
             "utc": when, **ctx} for s in sets]


def _plain(value: Any) -> Any:
    """numpy scalars and arrays, paths and sets as JSON values."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (Path, os.PathLike)):
        return str(value)
    if isinstance(value, (set, frozenset)):
        return sorted(value)
    raise TypeError(f"not JSON: {type(value).__name__}")


def dumps(record: dict[str, Any]) -> str:
    """One JSON line (NaN written as ``null``)."""
    def clean(v: Any) -> Any:
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, dict):
            return {str(k): clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        return v

    return json.dumps(clean(json.loads(json.dumps(record, default=_plain))), sort_keys=False)


def append(path: Path, recs: Iterable[dict[str, Any]]) -> int:
    """Append records to a JSON-lines file (made with its folder); how many were written."""
    lines = [dumps(r) for r in recs]
    if lines:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "a", encoding="utf-8") as fh:
            fh.write("".join(line + "\n" for line in lines))
    return len(lines)


def read(path: Path) -> list[dict[str, Any]]:
    """The records of a JSON-lines file (blank lines skipped)."""
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    return [json.loads(line) for line in lines if line.strip()]


def flat(record: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """A record's values by dotted key (``figures.sample_s``, ``machine.cpu``)."""
    out: dict[str, Any] = {}
    for key, value in record.items():
        if isinstance(value, dict):
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def lookup(row: dict[str, Any], key: str) -> Any:
    """``key`` of a flattened record, trying ``figures.KEY`` and ``params.KEY`` too."""
    for k in (key, f"figures.{key}", f"params.{key}"):
        if k in row:
            return row[k]
    return None


def select(recs: Sequence[dict[str, Any]], *, size: str | None = None,
           where: Sequence[str] = (), latest: bool = False) -> list[dict[str, Any]]:
    """The records of ``size``, matching every ``KEY=VALUE`` (or not matching ``KEY!=VALUE``)
    of ``where``, and (``latest``) of the most recent run only."""
    rows = [r for r in recs if size is None or r.get("size") == size]
    for cond in where:
        key, _, want = cond.partition("=")
        negate = key.endswith("!")
        key = key.removesuffix("!")
        rows = [r for r in rows if (str(lookup(flat(r), key)) == want) != negate]
    if latest and rows:
        last = max(r["utc"] for r in rows)
        rows = [r for r in rows if r["utc"] == last]
    return rows


def _cell(value: Any, fmt: str) -> str:
    if value is None:
        return ""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return str(value) if not isinstance(value, list) else ", ".join(map(str, value))
    return format(value, fmt or (",.3g" if isinstance(value, float) else ","))


def column(spec: str) -> tuple[str, str, str]:
    """``KEY[:FORMAT][=HEADER]`` as ``(key, format, header)`` (``sample_s:.2f=sampling (s)``)."""
    left, _, header = spec.partition("=")
    key, _, fmt = left.partition(":")
    return key, fmt, header or key


def table(recs: Sequence[dict[str, Any]], columns: Sequence[str] = ()) -> str:
    """A Markdown table of records: one row each, the given columns (default: the benchmark,
    the date, the commit and every figure), numbers by their format (default ``,.3g``)."""
    rows = [flat(r) for r in recs]
    if not columns:
        keys = [k for row in rows for k in row if k.startswith("figures.")]
        columns = ["utc", "git_sha", *dict.fromkeys(keys)]
    cols = [column(c) for c in columns]
    out = ["| " + " | ".join(h for _, _, h in cols) + " |", "|" + "---|" * len(cols)]
    for row in rows:
        cells = []
        for key, fmt, _ in cols:
            value = lookup(row, key)
            if key == "git_sha" and isinstance(value, str):
                value = value[:7]
            elif key == "utc" and isinstance(value, str):
                value = value[:10]
            cells.append(_cell(value, fmt))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"
