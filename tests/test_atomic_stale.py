"""Temporary folders left by killed writers are swept by the next write of the same output,
and only those: live writers, other outputs and odd entries are left alone (issue 24)."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from marsscene import _atomic
from marsscene._atomic import probe_writable, replacing_dir

# A writer that enters replacing_dir(target), writes a part of its output, says so, and waits.
WRITER = """
import sys, time
from pathlib import Path
from marsscene._atomic import replacing_dir
target, ready = Path(sys.argv[1]), Path(sys.argv[2])
with replacing_dir(target) as out:
    (out / "half.bin").write_bytes(b"x" * 1000)
    if len(sys.argv) > 3:
        target.rename(out.parent.parent / "old")  # as if killed between the two renames
    ready.write_text("in")
    time.sleep(600)
"""


def _temps(parent: Path, name: str) -> list[Path]:
    return sorted(parent.glob(f".{name}.*.tmp"))


def _start_writer(target: Path, *extra: str) -> subprocess.Popen[bytes]:
    ready = target.parent / f"ready-{target.name}-{len(extra)}"
    ready.unlink(missing_ok=True)
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(target), str(ready), *extra])
    deadline = time.monotonic() + 60
    while not ready.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"the writer did not start (exit {proc.poll()})")
        time.sleep(0.02)
    return proc


def _kill(proc: subprocess.Popen[bytes]) -> None:
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=30)


def _write(target: Path, payload: bytes = b"complete") -> None:
    with replacing_dir(target) as out:
        (out / "data.bin").write_bytes(payload)
        (out / "sub").mkdir()
        (out / "sub" / "more.txt").write_text("more")


def _assert_complete(target: Path, payload: bytes = b"complete") -> None:
    assert sorted(p.relative_to(target).as_posix() for p in target.rglob("*")) == [
        "data.bin", "sub", "sub/more.txt"]
    assert (target / "data.bin").read_bytes() == payload


def test_a_killed_writers_temp_folder_is_removed_by_the_next_write(tmp_path: Path) -> None:
    target = tmp_path / "s"
    _write(target, b"first")
    proc = _start_writer(target)
    _kill(proc)
    stale = _temps(tmp_path, "s")
    assert len(stale) == 1 and (stale[0] / "new" / "s" / "half.bin").exists()
    assert json.loads((stale[0] / "owner.json").read_text())["pid"] == proc.pid
    _assert_complete(target, b"first")  # the killed write did not touch the output

    _write(target, b"second")
    assert _temps(tmp_path, "s") == []
    _assert_complete(target, b"second")


def test_probe_writable_also_sweeps(tmp_path: Path) -> None:
    target = tmp_path / "s"
    _kill(_start_writer(target))
    assert len(_temps(tmp_path, "s")) == 1
    probe_writable(target)
    assert _temps(tmp_path, "s") == [] and not target.exists()


def test_the_pid_check_alone_finds_a_dead_owner(tmp_path: Path, monkeypatch) -> None:
    target = tmp_path / "s"
    _kill(_start_writer(target))
    monkeypatch.setattr(_atomic, "fcntl", None)  # as where fcntl is missing
    _write(target)
    assert _temps(tmp_path, "s") == []
    _assert_complete(target)


def test_a_reused_pid_is_not_taken_for_the_owner(tmp_path: Path, monkeypatch) -> None:
    target = tmp_path / "s"
    _kill(_start_writer(target))
    (stale,) = _temps(tmp_path, "s")
    owner = json.loads((stale / "owner.json").read_text())
    assert isinstance(owner["start"], int)  # Linux: /proc/<pid>/stat field 22
    owner["pid"], owner["start"] = os.getpid(), owner["start"] + 1  # a live pid, reused
    (stale / "owner.json").write_text(json.dumps(owner))
    monkeypatch.setattr(_atomic, "fcntl", None)
    _write(target)
    assert _temps(tmp_path, "s") == []


def test_a_write_killed_between_the_renames_restores_the_old_output(tmp_path: Path) -> None:
    target = tmp_path / "s"
    _write(target, b"previous")
    _kill(_start_writer(target, "between-renames"))
    assert not target.exists()
    probe_writable(target)
    _assert_complete(target, b"previous")
    assert _temps(tmp_path, "s") == []


def test_a_live_writers_temp_folder_is_kept(tmp_path: Path, monkeypatch) -> None:
    target = tmp_path / "s"
    proc = _start_writer(target)
    try:
        (live,) = _temps(tmp_path, "s")
        _write(target)
        _assert_complete(target)
        monkeypatch.setattr(_atomic, "fcntl", None)  # the pid check agrees
        _write(target)
        assert _temps(tmp_path, "s") == [live]
        assert (live / "new" / "s" / "half.bin").exists()
        assert proc.poll() is None
    finally:
        _kill(proc)


def test_an_enclosing_write_of_the_same_output_is_kept(tmp_path: Path) -> None:
    target = tmp_path / "s"
    with replacing_dir(target) as outer:
        (outer / "a.txt").write_text("outer")
        _write(target)  # a nested write in the same process (a separate lock)
        assert (outer / "a.txt").read_text() == "outer"
        assert len(_temps(tmp_path, "s")) == 1
    assert (target / "a.txt").read_text() == "outer"
    assert _temps(tmp_path, "s") == []


def test_other_outputs_and_foreign_hosts_are_left_alone(tmp_path: Path) -> None:
    target = tmp_path / "s"
    for name in ("s2", "s.x", "sx"):  # other outputs, some with names starting like "s"
        _kill(_start_writer(tmp_path / name))
    others = {n: _temps(tmp_path, n) for n in ("s2", "s.x", "sx")}
    assert all(len(v) == 1 for v in others.values())
    lookalike = tmp_path / ".s.abcdefgh.x.tmp"  # the random part is 8 chars without dots
    lookalike.mkdir()
    legacy = tmp_path / ".s.legacy00.tmp"  # an older version's: no owner information
    (legacy / "new" / "s").mkdir(parents=True)
    foreign = tmp_path / ".s.foreign0.tmp"  # another host on a shared filesystem
    (foreign / "new").mkdir(parents=True)
    (foreign / "owner.json").write_text(json.dumps({"pid": 999999, "host": "elsewhere-1"}))
    _write(target)
    _assert_complete(target)
    assert all(v[0].is_dir() for v in others.values())
    assert lookalike.is_dir() and legacy.is_dir() and foreign.is_dir()

    old = time.time() - _atomic.STALE_AFTER_S - 60  # idle for longer than a day: removed
    for p in (legacy, legacy / "new", legacy / "new" / "s", foreign, foreign / "new"):
        os.utime(p, (old, old))
    _write(target)
    assert not legacy.exists() and not foreign.exists()
    assert lookalike.is_dir() and all(v[0].is_dir() for v in others.values())


def test_odd_entries_do_not_fail_the_write(tmp_path: Path, monkeypatch) -> None:
    target = tmp_path / "s"
    (tmp_path / ".s.aaaaaaaa.tmp").write_text("a file, not a folder")
    elsewhere = tmp_path / "elsewhere"  # looks like a dead writer's folder, with an "old"
    (elsewhere / "owner.lock").mkdir(parents=True)
    (elsewhere / "old").mkdir()
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait(timeout=60)
    (elsewhere / "owner.json").write_text(
        json.dumps({"pid": dead.pid, "host": socket.gethostname(), "start": None}))
    (tmp_path / ".s.bbbbbbbb.tmp").symlink_to(elsewhere)  # a link: never followed
    fifo = tmp_path / ".s.cccccccc.tmp"  # fifos where the owner files should be: no hang
    fifo.mkdir()
    os.mkfifo(fifo / "owner.json")
    os.mkfifo(fifo / "owner.lock")
    junk = tmp_path / ".s.dddddddd.tmp"
    junk.mkdir()
    (junk / "owner.json").write_text('{"pid": "not a number"')
    (junk / "owner.lock").symlink_to(elsewhere / "owner.lock")
    _write(target)
    _assert_complete(target)
    assert (tmp_path / ".s.aaaaaaaa.tmp").is_file() and (elsewhere / "owner.lock").is_dir()
    assert (elsewhere / "old").is_dir()
    assert fifo.is_dir() and junk.is_dir()

    _kill(_start_writer(target))  # a stale folder that cannot be removed
    (stale,) = [p for p in _temps(tmp_path, "s") if (p / "new").is_dir()]

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(_atomic, "_reap", refuse)
    _write(target, b"again")
    _assert_complete(target, b"again")
    assert stale.is_dir()


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores modes")
def test_an_unremovable_stale_folder_does_not_fail_the_write(tmp_path: Path) -> None:
    target = tmp_path / "s"
    _kill(_start_writer(target))
    (stale,) = _temps(tmp_path, "s")
    os.chmod(stale / "new" / "s", 0o500)  # its file cannot be deleted
    try:
        _write(target)
        _assert_complete(target)
        assert (stale / "new" / "s" / "half.bin").exists()
    finally:
        os.chmod(stale / "new" / "s", 0o700)
