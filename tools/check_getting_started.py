"""Run the tested shell blocks of docs/getting_started.md in a fresh virtual environment.

A shell block is tested when an HTML comment that starts with ``test:`` comes right before its
fence (MyST drops the comment from the page). The comment names the step and says what to check
after it, one ``key: value`` a line::

    <!-- test: drive
    files: runs/r1/gt.tum runs/r1/bag/metadata.yaml
    output: goal reached: True
    output: drove: ([\\d.]+) m in 20..40
    quick: --workers 2 => --workers 2 --length-m 10
    -->
    ```bash
    marsscene drive scenes/demo --waypoints wp.txt --out runs/r1
    ```

* ``files``: paths (relative to the checkout) that must exist afterwards, files not empty;
* ``output``: a regular expression searched in what the block printed (stdout and stderr); with
  ``in LO..HI``, its first group is a number that must lie in [LO, HI];
* ``quick``: ``OLD => NEW``, a text replacement made with ``--quick`` (the default): the page's
  own smaller variant of a long step (it must say so in its prose);
* ``timeout``: seconds for the block (default 1800).

Blocks without the comment (system packages, the clone, a ROS 2 machine's commands) are shown,
not run. The run stands in for the clone: it copies this checkout's files (tracked and
untracked, not ignored: ``git ls-files``) into a temporary folder and runs every tested block
there, in order, each with ``bash -euo pipefail``, as one terminal would: a block that creates
``.venv`` leaves it activated for the next ones. The environment is this one's without any
active virtual environment, ``PYTHONPATH`` or ``MUJOCO_GL`` (the page says ``import marsscene``
sets it). Only the package index is contacted (``pip install``).

    python tools/check_getting_started.py             # quick sizes, temporary folder removed
    python tools/check_getting_started.py --full --keep /tmp/gs

Exit status 0 when every step ran and passed its checks.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "getting_started.md"
MARKER = re.compile(r"<!--\s*test:\s*(?P<name>[\w.-]+)\s*\n?(?P<body>.*?)-->\s*\n", re.S)
FENCE = re.compile(r"(?P<fence>`{3,})bash[ \t]*\n(?P<code>.*?)\n(?P=fence)[ \t]*(\n|$)", re.S)
RANGE = re.compile(r"^(?P<regex>.*?)\s+in\s+(?P<lo>-?[\d.]+)\.\.(?P<hi>-?[\d.]+)\s*$")
KEYS = ("files", "output", "quick", "timeout")


@dataclass(frozen=True)
class Expect:
    """A regular expression to find in a step's output; its group 1 in [lo, hi] when given."""

    regex: str
    lo: float | None = None
    hi: float | None = None

    def check(self, output: str) -> str | None:
        """None when ``output`` passes, else why not (one line)."""
        m = re.search(self.regex, output)
        if m is None:
            return f"no match for {self.regex!r}"
        if self.lo is None or self.hi is None:
            return None
        value = float(m.group(1))
        if not self.lo <= value <= self.hi:
            return f"{self.regex!r}: {value:g} is outside [{self.lo:g}, {self.hi:g}]"
        return None


@dataclass(frozen=True)
class Step:
    """A tested shell block of the page and what to check after it."""

    name: str
    code: str
    line: int
    files: tuple[str, ...] = ()
    output: tuple[Expect, ...] = ()
    quick: tuple[tuple[str, str], ...] = ()
    timeout_s: float = 1800.0
    notes: list[str] = field(default_factory=list, compare=False)

    def script(self, quick: bool) -> str:
        """The block's commands, with the ``quick`` replacements when ``quick``."""
        code = self.code
        if quick:
            for old, new in self.quick:
                if old not in code:
                    raise ValueError(f"step {self.name!r}: quick text {old!r} is not in its block")
                code = code.replace(old, new)
        return code


def _parse_marker(name: str, body: str, code: str, line: int) -> Step:
    files: list[str] = []
    output: list[Expect] = []
    quick: list[tuple[str, str]] = []
    timeout_s = 1800.0
    for raw in body.strip().splitlines():
        if not raw.strip():
            continue
        key, sep, value = raw.partition(":")
        key, value = key.strip(), value.strip()
        if not sep or key not in KEYS or not value:
            raise ValueError(f"line {line}: step {name!r}: {raw.strip()!r} is not "
                             f"'key: value' with a key of {list(KEYS)}")
        if key == "files":
            files += shlex.split(value)
        elif key == "output":
            m = RANGE.match(value)
            expect = (Expect(m["regex"], float(m["lo"]), float(m["hi"])) if m
                      else Expect(value))
            re.compile(expect.regex)
            if expect.lo is not None and re.compile(expect.regex).groups < 1:
                raise ValueError(f"line {line}: step {name!r}: {expect.regex!r} needs a group")
            output.append(expect)
        elif key == "quick":
            old, arrow, new = value.partition("=>")
            if not arrow or not old.strip():
                raise ValueError(f"line {line}: step {name!r}: quick is 'OLD => NEW'")
            quick.append((old.strip(), new.strip()))
        else:
            timeout_s = float(value)
    step = Step(name, code, line, tuple(files), tuple(output), tuple(quick), timeout_s)
    step.script(quick=True)  # every quick replacement applies
    return step


def parse_steps(text: str) -> list[Step]:
    """The tested steps of a Markdown page, in page order.

    A marker must be followed (after blank lines only) by a ```bash fence; step names are
    unique. Raises ``ValueError`` naming the line of a malformed marker.
    """
    steps: list[Step] = []
    for m in MARKER.finditer(text):
        line = text.count("\n", 0, m.start()) + 1
        rest = text[m.end():]
        fence = FENCE.match(rest.lstrip("\n"))
        if fence is None:
            raise ValueError(f"line {line}: the test marker {m['name']!r} is not followed by a "
                             "```bash block")
        steps.append(_parse_marker(m["name"], m["body"], fence["code"], line))
    names = [s.name for s in steps]
    if len(set(names)) != len(names):
        raise ValueError(f"step names repeat: {names}")
    return steps


def marsscene_commands(code: str) -> list[list[str]]:
    """The ``marsscene ...`` command lines of a block's shell code, as argument lists.

    Here-documents are skipped, continuation lines joined, and a line split at ``&&``, ``||``,
    ``;`` and ``|``; the leading ``marsscene`` is dropped.
    """
    out: list[list[str]] = []
    lines = re.sub(r"\\\n\s*", " ", code).splitlines()
    heredoc: str | None = None
    for line in lines:
        if heredoc is not None:
            if line.strip() == heredoc:
                heredoc = None
            continue
        m = re.search(r"<<-?\s*(['\"]?)(\w+)\1", line)
        if m:
            heredoc = m.group(2)
        for segment in re.split(r"&&|\|\||;|\|", line):
            tokens = shlex.split(segment, comments=True)
            if tokens and tokens[0] == "marsscene":
                out.append(tokens[1:])
    return out


def _clean_env() -> dict[str, str]:
    env = dict(os.environ)
    venv = env.pop("VIRTUAL_ENV", None)
    for key in ("PYTHONPATH", "MUJOCO_GL", "PYTHONHOME", "CONDA_PREFIX", "MARSSCENE_SITE"):
        env.pop(key, None)
    if venv:
        bin_dir = str(Path(venv) / "bin")
        env["PATH"] = os.pathsep.join(p for p in env["PATH"].split(os.pathsep) if p != bin_dir)
    return env


def copy_checkout(dest: Path) -> int:
    """Copy the checkout's tracked and untracked (not ignored) files to ``dest``; the count."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT, check=True, capture_output=True).stdout.decode().split("\0")
    n = 0
    for rel in filter(None, listed):
        src = ROOT / rel
        if not src.is_file():  # deleted in the work tree, or a submodule
            continue
        (dest / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dest / rel)
        n += 1
    return n


def run_step(step: Step, cwd: Path, env: dict[str, str], quick: bool) -> tuple[bool, str]:
    """Run one step in ``cwd``; (passed, its output). Prints what it runs and checks."""
    script = step.script(quick)
    prelude = "if [ -f .venv/bin/activate ]; then . .venv/bin/activate; fi\n"
    t0 = time.monotonic()
    print(f"\n== step {step.name} (docs/getting_started.md line {step.line})", flush=True)
    print("\n".join(f"   $ {line}" for line in script.splitlines()), flush=True)
    try:
        proc = subprocess.run(["bash", "-euo", "pipefail", "-c", prelude + script], cwd=cwd,
                              env=env, capture_output=True, text=True, timeout=step.timeout_s)
        output, rc = proc.stdout + proc.stderr, proc.returncode
    except subprocess.TimeoutExpired as exc:
        parts = (exc.stdout, exc.stderr)
        output = "".join(p.decode(errors="replace") if isinstance(p, bytes) else (p or "")
                         for p in parts) + f"\n(timed out after {step.timeout_s:g} s)"
        rc = 124
    took = time.monotonic() - t0
    tail = "\n".join(output.rstrip().splitlines()[-8:])
    print("\n".join(f"   | {line}" for line in tail.splitlines()), flush=True)
    problems = [] if rc == 0 else [f"exit status {rc}"]
    for rel in step.files:
        path = cwd / rel
        if not path.exists() or (path.is_file() and path.stat().st_size == 0):
            problems.append(f"missing or empty: {rel}")
        else:
            print(f"   ok: {rel} exists", flush=True)
    for expect in step.output:
        why = expect.check(output)
        if why:
            problems.append(why)
        else:
            m = re.search(expect.regex, output)
            shown = m.group(0) if m else expect.regex
            print(f"   ok: output has {shown!r}"
                  + (f" in [{expect.lo:g}, {expect.hi:g}]" if expect.lo is not None else ""),
                  flush=True)
    for p in problems:
        print(f"   FAIL: {p}", flush=True)
    print(f"   {'passed' if not problems else 'FAILED'} in {took:.0f} s", flush=True)
    if problems and rc != 0:
        print(output[-6000:], file=sys.stderr)
    return not problems, output


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--page", type=Path, default=PAGE, help="Markdown page (default: %(default)s)")
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--quick", dest="quick", action="store_true", default=True,
                      help="the page's smaller variants of long steps (default)")
    size.add_argument("--full", dest="quick", action="store_false", help="the page as written")
    ap.add_argument("--keep", type=Path, help="run in this (new or empty) folder and keep it")
    ap.add_argument("--only", nargs="*", help="run only these steps (and stop after the last)")
    args = ap.parse_args(argv)

    steps = parse_steps(args.page.read_text(encoding="utf-8"))
    if args.only:
        unknown = set(args.only) - {s.name for s in steps}
        if unknown:
            ap.error(f"no steps {sorted(unknown)}; the page has {[s.name for s in steps]}")
        steps = [s for s in steps if s.name in args.only]
    print(f"{args.page.name}: {len(steps)} tested steps: {', '.join(s.name for s in steps)}"
          f" ({'quick' if args.quick else 'full'} sizes)")
    if args.keep:
        args.keep.mkdir(parents=True, exist_ok=True)
        if any(args.keep.iterdir()):
            ap.error(f"--keep {args.keep} is not empty")
        base, cleanup = args.keep, None
    else:
        cleanup = tempfile.TemporaryDirectory(prefix="marsscene-getting-started-")
        base = Path(cleanup.name)
    t0 = time.monotonic()
    try:
        work = base / "marsscene"
        work.mkdir()
        print(f"copied {copy_checkout(work)} files of {ROOT} to {work} (stands in for the clone)")
        env = _clean_env()
        for step in steps:
            ok, _ = run_step(step, work, env, args.quick)
            if not ok:
                print(f"\nFAILED at step {step.name} after {time.monotonic() - t0:.0f} s"
                      + (f"; the folder is kept: {work}" if args.keep else ""))
                return 1
    finally:
        if cleanup is not None:
            cleanup.cleanup()
    print(f"\nall {len(steps)} steps passed in {time.monotonic() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
