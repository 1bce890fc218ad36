"""``marsscene drive --bag``: the bag is the one ``marsscene bag`` makes of the same run folder.

The drive encodes the colour JPEGs from its renders while it drives (a cache the bag reads
instead of decoding the PNGs again), and the chunks are zstd-compressed by a library whose
output does not depend on which ``libzstd`` the process happened to load first (a drive's EGL
renderer loads the system's).
"""

from __future__ import annotations

import ctypes.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("zstandard")

from marsscene.cli import main
from marsscene.runs.export import bag_images


def _drive_with_bag(runner, scene: Path, tmp_path: Path, run: Path, *, seconds: float):
    """``marsscene drive --camera --bag`` for ``seconds`` into ``run`` (skips without GL)."""
    wp = tmp_path / "wp.txt"
    wp.write_text("-5 -5\n-2 -5\n")
    res = runner.invoke(main, ["drive", str(scene), "--waypoints", str(wp),
                               "--seconds", str(seconds), "--camera", "--camera-size", "160x120",
                               "--out", str(run), "--bag"])
    if res.exit_code not in (0, 130) and "OpenGL" in res.output:
        pytest.skip("no headless OpenGL (EGL/OSMesa) here")
    return res


def test_drive_bag_equals_bag_of_the_run_and_reads_the_drives_jpegs(runner, gentle_scene,
                                                                    tmp_path, monkeypatch):
    decoded: list[Path] = []
    real = bag_images.read_image

    def spy(path: Path) -> np.ndarray:
        decoded.append(Path(path))
        return real(path)

    monkeypatch.setattr(bag_images, "read_image", spy)
    monkeypatch.chdir(tmp_path)
    run = Path("run")  # relative, as users type it (the cache once landed in run/run/)
    res = _drive_with_bag(runner, gentle_scene, tmp_path, run, seconds=1.5)
    assert res.exit_code == 0, res.output
    frames = sorted((run / "camera" / "rgb").glob("*.png"))
    assert len(frames) >= 10
    assert not [p for p in decoded if p.parent.name == "rgb"]  # the drive's JPEGs were used
    assert not (run / ".bag-cache").exists()  # and removed with the bag written
    assert sorted(p.name for p in run.iterdir() if p.is_dir()) == ["bag", "camera"]
    again = tmp_path / "again" / "bag"
    res = runner.invoke(main, ["bag", str(run), "--out", str(again)])
    assert res.exit_code == 0, res.output
    assert len([p for p in decoded if p.parent.name == "rgb"]) == len(frames)  # no cache here
    assert (again / "bag.mcap").read_bytes() == (run / "bag" / "bag.mcap").read_bytes()


_CHILD = """
import ctypes, sys
if sys.argv[1] == "system-first":
    ctypes.CDLL(sys.argv[2], mode=ctypes.RTLD_GLOBAL)
from marsscene.runs.export.bag_writer import _compressor
import numpy as np
data = np.random.default_rng(3).integers(0, 6, 3_000_000, dtype=np.uint8).tobytes()
sys.stdout.write(_compressor("zstd", 3)(data).hex())
"""


def test_zstd_chunks_do_not_depend_on_a_libzstd_loaded_before():
    system = ctypes.util.find_library("zstd")
    if system is None:
        pytest.skip("no system libzstd to load first")
    out = [subprocess.run([sys.executable, "-c", _CHILD, mode, system], check=True,
                          capture_output=True, text=True).stdout
           for mode in ("plain", "system-first")]
    assert len(out[0]) > 1000 and out[0] == out[1]


def test_interrupt_while_writing_the_bag_keeps_the_run_and_removes_the_cache(
        runner, gentle_scene, tmp_path, monkeypatch):
    """Ctrl-C or SIGTERM after the drive, while the bag is written: exit 130 with a message,
    the run folder whole, no bag, and no ``.bag-cache`` left behind."""
    import os
    import signal

    from marsscene.runs.export import bag as bag_module

    def killed(run_dir: Path, *args: object, **kwargs: object) -> None:
        assert (Path(run_dir) / ".bag-cache").is_dir()  # the drive filled the cache
        os.kill(os.getpid(), signal.SIGTERM)  # as `kill PID` would, mid-bag

    monkeypatch.setattr(bag_module, "write_bag", killed)
    run = tmp_path / "run"
    before = signal.getsignal(signal.SIGTERM)
    res = _drive_with_bag(runner, gentle_scene, tmp_path, run, seconds=1.0)
    assert res.exit_code == 130, res.output
    assert "interrupted while writing the bag" in res.output
    assert "Traceback" not in res.output
    assert not (run / ".bag-cache").exists() and not (run / "bag").exists()
    assert (run / "gt.tum").is_file() and len(list((run / "camera" / "rgb").glob("*.png"))) >= 5
    assert signal.getsignal(signal.SIGTERM) == before  # the handler is put back


def test_lidar_scans_are_kept_once_in_the_bag_unless_asked(runner, gentle_scene, tmp_path):
    """With --lidar --bag the PLYs go once the bag holds the scans (one copy on disk);
    --keep-lidar-files keeps both, and the bag's bytes do not depend on it."""
    from marsscene.errors import RuntimeSimError
    from marsscene.runs.runlog import LIDAR_IN_BAG, RunLog

    wp = tmp_path / "wp.txt"
    wp.write_text("-5 -5\n-2 -5\n")
    runs = {}
    for keep in (False, True):
        run = tmp_path / f"run_{keep}"
        res = runner.invoke(main, ["drive", str(gentle_scene), "--waypoints", str(wp),
                                   "--seconds", "0.5", "--lidar", "--lidar-model", "vlp16",
                                   "--out", str(run), "--bag",
                                   *(["--keep-lidar-files"] if keep else [])])
        assert res.exit_code == 0, res.output
        runs[keep] = run
    moved, kept = RunLog(runs[False]), RunLog(runs[True])
    assert not list((runs[False] / "lidar").glob("*.ply"))
    assert (runs[False] / "lidar" / LIDAR_IN_BAG).is_file()
    assert kept.lidar is not None and len(kept.lidar[1]) >= 5
    np.testing.assert_array_equal(moved.lidar_stamps_s, kept.lidar[0])
    with pytest.raises(RuntimeSimError, match="moved into the run's bag"):
        _ = moved.lidar
    assert (runs[False] / "bag" / "bag.mcap").read_bytes() == (
        runs[True] / "bag" / "bag.mcap").read_bytes()
