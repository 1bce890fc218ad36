"""A SLAM benchmark folder packed down to its results, and the cells a resume reuses from it.

A full-length cell holds gigabytes (its scene, the drive's logs, camera images until scored);
its table row, trajectory plots and report come from a few megabytes: the rows, the estimates
and the ground truth. :func:`pack_benchmark` copies those (:data:`CELL_RESULT_FILES`, and the
benchmark's own table, plots and report) to another folder; ``marsscene benchmark slam SPEC
--out PACK --resume`` on that folder reuses every cell whose rows are all current
(:func:`scored_cell`) and runs the rest, so a long benchmark can move between machines, or
outlive a scratch disk, one finished cell at a time.

A cell with a ``tum-file`` method is never reused this way: its row is scored again on every
resume, from the cell's full logs.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene.benchmark.slam.keys import batch_key, drive_key, method_file, read_json
from marsscene.benchmark.slam.methods import DRIVE_FILE
from marsscene.benchmark.slam.spec import MethodSpec, SceneSpec, SlamSpec
from marsscene.errors import ConfigError, MarsSceneError
from marsscene.sweep.cell import RESULT_FILE, cell_hash, resolve_config
from marsscene.sweep.grid import Cell

__all__ = ["BENCHMARK_RESULT_FILES", "CELL_RESULT_FILES", "Pack", "pack_benchmark",
           "scored_cell"]

#: What a cell's rows, plots and report are made from (globs in ``cells/<cell_id>/``).
CELL_RESULT_FILES = (
    RESULT_FILE, "config.toml", f"drive/{DRIVE_FILE}", "drive/run.json", "drive/gt.tum",
    "drive/tum_rgbd/groundtruth.txt", "drive/images_removed.txt", "estimates/*.tum",
    "methods/*.json",
)
#: The benchmark's own files (globs in its folder); ``benchmark.json`` first.
BENCHMARK_RESULT_FILES = ("benchmark.json", "results.csv", "table.md", "report.md", "*.png",
                          "cells/results.csv")


@dataclass(frozen=True)
class Pack:
    """What :func:`pack_benchmark` wrote: files, their bytes, and the cells they hold."""

    files: int
    bytes: int
    cells: int


def scored_cell(spec: SlamSpec, scene: SceneSpec, cell: Cell, cell_dir: Path,
                methods: list[MethodSpec], *, lidar: bool, camera: bool,
                live: tuple[MethodSpec, ...], device: str | None = None
                ) -> dict[str, Any] | None:
    """The stored row of a cell whose build, drive and every method row are current (read
    from its result files alone), or None when anything must run."""
    if any(m.kind == "tum-file" for m in methods):
        return None
    row = read_json(cell_dir / RESULT_FILE)
    if row is None or row.get("status") not in ("ok", "skipped"):
        return None
    try:
        scene_hash = cell_hash(resolve_config(cell), None)
    except MarsSceneError:
        return None  # the build reports it
    drive = read_json(cell_dir / "drive" / DRIVE_FILE)
    if row.get("config_hash") != scene_hash or drive is None:
        return None
    key, _ = drive_key(spec, scene, lidar, scene_hash, camera, live if lidar else ())
    if device is not None:  # a batch drive (:mod:`.device`)
        key = batch_key(key)
    if drive.get("key") != key:
        return None
    rows = []
    for method in methods:
        path, method_key = method_file(spec, method, cell_dir, key)
        done = read_json(path)
        if done is None or done.get("key") != method_key:
            return None
        rows.append(dict(done["row"]))
    return {**row, "params": dict(cell.params), "status": "skipped",
            "drive": dict(drive["summary"]), "methods": rows}


def _copy(src: Path, dest: Path, patterns: tuple[str, ...]) -> tuple[int, int]:
    files = n_bytes = 0
    for pattern in patterns:
        for path in sorted(src.glob(pattern)):
            if not path.is_file():
                continue
            target = dest / path.relative_to(src)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(path, target)
            files += 1
            n_bytes += target.stat().st_size
    return files, n_bytes


def _poses(path: Path) -> tuple[list[str], list[str], NDArray[np.float64]]:
    """A TUM file's comment lines, pose lines (as written) and stamps (s)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    poses = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    return head, poses, np.array([float(ln.split()[0]) for ln in poses], dtype=np.float64)


def _write_thinned(head: list[str], poses: list[str], target: Path, keep: NDArray[np.bool_],
                   rate_hz: float) -> None:
    note = f"# thinned by marsscene benchmark pack to about {rate_hz:g} pose(s) a second"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text("\n".join([*head, note, *(p for p, k in zip(poses, keep, strict=True)
                                                if k)]) + "\n", encoding="utf-8")


def _thin_cell(cell_dir: Path, dest: Path, rate_hz: float) -> None:
    """Thin the packed cell's trajectories: each estimate to the first pose of every
    1/rate_hz s, the ground truths to as many poses plus the nearest to every pose kept of an
    estimate (what the plots align them by)."""
    kept: list[NDArray[np.float64]] = []
    for est in sorted((cell_dir / "estimates").glob("*.tum")):
        head, poses, t = _poses(est)
        keep = np.r_[True, np.diff(np.floor(t * rate_hz)) != 0] if len(t) else t > 0
        _write_thinned(head, poses, dest / est.relative_to(cell_dir), keep, rate_hz)
        kept.append(t[keep])
    near = np.sort(np.concatenate(kept)) if kept else np.zeros(0)
    for rel in ("drive/gt.tum", "drive/tum_rgbd/groundtruth.txt"):
        if not (cell_dir / rel).is_file():
            continue
        head, poses, t = _poses(cell_dir / rel)
        keep = np.r_[True, np.diff(np.floor(t * rate_hz)) != 0] if len(t) else t > 0
        if len(t) and len(near):
            hi = np.clip(np.searchsorted(t, near), 1, len(t) - 1)
            nearest = np.where(near - t[hi - 1] <= t[hi] - near, hi - 1, hi)
            keep[nearest] = True
        _write_thinned(head, poses, dest / rel, keep, rate_hz)


def pack_benchmark(bench_dir: str | Path, dest: str | Path, *,
                   max_rate_hz: float | None = None) -> Pack:
    """Copy the results of the SLAM benchmark in ``bench_dir`` to ``dest``.

    ``dest`` may be an earlier pack of the same benchmark (its files are updated, cells
    finished since are added); a pack of another spec is an error (:class:`ConfigError`).
    ``max_rate_hz`` thins every trajectory to about that many poses a second (each file says
    so in a comment): the rows are scored already, and a plot of a 400 m route needs no more
    than a pose a second, where the ground truth has 50.
    """
    src, out = Path(bench_dir), Path(dest)
    spec_doc = read_json(src / "benchmark.json")
    if spec_doc is None:
        raise ConfigError(f"{src} is not a SLAM benchmark folder (no readable benchmark.json)")
    if src.resolve() == out.resolve():
        raise ConfigError(f"{out} is the benchmark folder itself; pack to another folder")
    if max_rate_hz is not None and not max_rate_hz > 0.0:
        raise ConfigError(f"max_rate_hz = {max_rate_hz!r}; must be > 0")
    old = read_json(out / "benchmark.json")
    if old is not None and old != spec_doc:
        raise ConfigError(f"{out} holds a pack of another benchmark spec; pack to another "
                          "folder")
    files, n_bytes = _copy(src, out, BENCHMARK_RESULT_FILES)
    cells = 0
    for cell_dir in sorted(p for p in (src / "cells").glob("*") if p.is_dir()):
        if not (cell_dir / RESULT_FILE).is_file():
            continue  # a cell still building
        target = out / "cells" / cell_dir.name
        f, b = _copy(cell_dir, target, CELL_RESULT_FILES)
        if max_rate_hz is not None:
            _thin_cell(cell_dir, target, max_rate_hz)
            b = sum(p.stat().st_size for p in target.rglob("*") if p.is_file())
        files, n_bytes, cells = files + f, n_bytes + b, cells + 1
    return Pack(files, n_bytes, cells)
