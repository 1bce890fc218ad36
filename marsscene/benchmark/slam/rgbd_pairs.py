"""Open3D RGB-D odometry on consecutive frame pairs, in chunks that are saved, resumed and
shared out over processes.

Each pair's result (Open3D's success flag and transform) depends on the two frames and its
initial guess alone, never on another pair's, so :func:`pair_results` splits the pairs into
chunks of ``chunk_pairs``: a chunk is computed in this process, or with ``processes > 1`` in
child processes (``python -m marsscene.benchmark.slam.rgbd_pairs JOB FIRST LAST``: a
subprocess, so it runs inside a daemonic Dask worker too), and each finished chunk is saved in
the ``checkpoint`` folder under the caller's key. A call with the same folder and key computes
only the chunks that are missing, and the results do not depend on how many processes made
them. :mod:`.rgbd_odometry` chains the steps.
"""

from __future__ import annotations

import io
import json
import logging
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import RuntimeSimError, missing_dependency
from marsscene.runs.export.datasets import tum_associations, tum_depth_per_m
from marsscene.runs.runlog import read_image

__all__ = ["PairJob", "halve", "pair_results", "require_open3d"]

log = logging.getLogger("marsscene")

_INIT_FILE = "init.npy"
_JOB_FILE = "job.json"


@dataclass(frozen=True)
class PairJob:
    """What every pair of one run shares: the TUM RGB-D folder, the image halvings, the depth
    cut-off (m), the pinhole intrinsics of the (halved) images and the chunks' key."""

    folder: str
    halvings: int
    depth_trunc_m: float
    intrinsics: tuple[int, int, float, float, float, float]  # width, height, fx, fy, cx, cy
    key: str


def halve(img: NDArray[Any], times: int) -> NDArray[Any]:
    """``img`` averaged over blocks of ``2 ** times`` pixels a side (depth: 0 where any is)."""
    for _ in range(times):
        h, w = img.shape[0] // 2 * 2, img.shape[1] // 2 * 2
        blocks = img[:h, :w].reshape(h // 2, 2, w // 2, 2, *img.shape[2:]).astype(np.float64)
        mean = blocks.mean(axis=(1, 3))
        if img.ndim == 2:  # depth: a block with a missing return has none
            mean = np.where((blocks > 0).all(axis=(1, 3)), mean, 0.0)
        img = np.rint(mean).astype(img.dtype)
    return img


def require_open3d() -> Any:
    """Open3D, or the one-line error that says which extra installs it."""
    try:
        import open3d as o3d
    except ImportError:
        raise missing_dependency("open3d", "bench") from None
    return o3d


def _chunk_pairs(job: PairJob, rows: list[list[str]], first: int, last: int,
                 init: NDArray[np.float64]) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Open3D on pairs ``first .. last - 1`` (pair k: frame k to frame k + 1): success flags
    and transforms (source points into the target), from the initial guesses ``init``."""
    o3d = require_open3d()
    folder = Path(job.folder)
    depth_scale = tum_depth_per_m(folder)
    pin = o3d.camera.PinholeCameraIntrinsic(*job.intrinsics)
    odo = o3d.pipelines.odometry
    jac, opt = odo.RGBDOdometryJacobianFromHybridTerm(), odo.OdometryOption()

    def frame(row: list[str]) -> Any:
        rgb = np.ascontiguousarray(halve(read_image(folder / row[1])[..., :3], job.halvings))
        depth = np.ascontiguousarray(halve(read_image(folder / row[3]).astype(np.uint16),
                                           job.halvings))
        return o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.geometry.Image(rgb), o3d.geometry.Image(depth), depth_scale=depth_scale,
            depth_trunc=job.depth_trunc_m, convert_rgb_to_intensity=True)

    success = np.zeros(last - first, dtype=bool)
    trans = np.tile(np.eye(4), (last - first, 1, 1))
    prev = frame(rows[first])
    for k in range(first, last):
        cur = frame(rows[k + 1])
        ok, t, _ = odo.compute_rgbd_odometry(prev, cur, pin, init[k], jac, opt)
        success[k - first], trans[k - first] = bool(ok), np.asarray(t, dtype=np.float64)
        prev = cur
    return success, trans


def _chunk_file(folder: Path, first: int) -> Path:
    return folder / f"{first:07d}.npz"


def _save_chunk(path: Path, job: PairJob, n_rows: int, first: int,
                result: tuple[NDArray[np.bool_], NDArray[np.float64]]) -> None:
    buf = io.BytesIO()
    np.savez(buf, key=np.array(job.key), n_rows=np.array(n_rows), first=np.array(first),
             success=result[0], trans=result[1])
    write_atomic(path, buf.getvalue())


def _load_chunk(path: Path, job: PairJob, n_rows: int, first: int, last: int
                ) -> tuple[NDArray[np.bool_], NDArray[np.float64]] | None:
    """The chunk saved at ``path``, if it holds these pairs of this key's run."""
    try:
        with np.load(path, allow_pickle=False) as z:
            saved = {k: z[k] for k in ("key", "n_rows", "first", "success", "trans")}
    except (OSError, ValueError, KeyError):
        return None  # none yet, or not one of ours
    if str(saved["key"]) != job.key or int(saved["n_rows"]) != n_rows \
            or int(saved["first"]) != first or len(saved["success"]) != last - first:
        return None
    return saved["success"].astype(bool), saved["trans"].astype(np.float64)


def _child_env() -> dict[str, str]:
    """This process's environment, with this ``marsscene`` first on the child's path (the
    child runs the parent's code whatever its working folder or installed copy)."""
    import marsscene

    root = str(Path(marsscene.__file__).resolve().parent.parent)
    rest = os.environ.get("PYTHONPATH", "")
    return {**os.environ, "PYTHONPATH": root + (os.pathsep + rest if rest else "")}


def _run_child(folder: Path, first: int, last: int) -> None:
    cmd = [sys.executable, "-m", "marsscene.benchmark.slam.rgbd_pairs", str(folder),
           str(first), str(last)]
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          env=_child_env()) as proc:
        try:
            out, _ = proc.communicate()
        except BaseException:  # this process stops: so does the child
            proc.kill()
            raise
    if proc.returncode != 0:
        tail = out.strip().splitlines()[-1:] or [""]
        raise RuntimeSimError(f"open3d-rgbd pairs {first}-{last}: exit code "
                              f"{proc.returncode}: {tail[0][:200]}")


def _in_children(folder: Path, todo: list[tuple[int, int]], processes: int) -> None:
    """The chunks ``todo`` computed by child processes, ``processes`` at a time, each saved in
    ``folder``; the first failure cancels the chunks not yet started."""
    with ThreadPoolExecutor(min(processes, len(todo))) as pool:
        futures = {pool.submit(_run_child, folder, a, b): (a, b) for a, b in todo}
        try:
            for fut in as_completed(futures):
                fut.result()
                log.info("open3d-rgbd: pairs %d-%d done", *futures[fut])
        except BaseException:
            pool.shutdown(wait=True, cancel_futures=True)
            raise


def pair_results(job: PairJob, init: NDArray[np.float64], *, checkpoint: Path | None = None,
                 chunk_pairs: int = 500, processes: int = 1
                 ) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Success flags (N - 1,) and transforms (N - 1, 4, 4) of every consecutive pair of the
    job's N frames, from the initial guesses ``init`` (N - 1, 4, 4).

    Chunks saved in ``checkpoint`` under ``job.key`` are reused and the others saved there as
    they finish; ``processes > 1`` computes the missing chunks in that many child processes
    (in a temporary folder without ``checkpoint``). The caller removes the folder.
    """
    require_open3d()  # missing: the caller's one-line error, not a child's exit code
    rows = tum_associations(job.folder)
    n = len(rows)
    spans = [(a, min(a + chunk_pairs, n - 1)) for a in range(0, n - 1, chunk_pairs)]
    with tempfile.TemporaryDirectory(prefix="marsscene-rgbd-") as tmp:
        folder = Path(tmp) if checkpoint is None else checkpoint
        folder.mkdir(parents=True, exist_ok=True)
        done = {a: _load_chunk(_chunk_file(folder, a), job, n, a, b) for a, b in spans}
        todo = [(a, b) for a, b in spans if done[a] is None]
        if len(todo) < len(spans):
            log.info("open3d-rgbd: %d of %d chunks of pairs saved before, in %s",
                     len(spans) - len(todo), len(spans), folder)
        if processes > 1 and len(todo) > 1:
            buf = io.BytesIO()
            np.save(buf, init)
            write_atomic(folder / _INIT_FILE, buf.getvalue())
            write_atomic(folder / _JOB_FILE, json.dumps(asdict(job)))
            _in_children(folder, todo, processes)
            done.update({a: _load_chunk(_chunk_file(folder, a), job, n, a, b) for a, b in todo})
        else:
            for a, b in todo:
                result = _chunk_pairs(job, rows, a, b, init)
                if checkpoint is not None:
                    _save_chunk(_chunk_file(folder, a), job, n, a, result)
                done[a] = result
                log.info("open3d-rgbd: pairs %d-%d done", a, b)
        chunks = [done[a] for a, _ in spans]
    if any(c is None for c in chunks):
        raise RuntimeSimError(f"open3d-rgbd: a child process left no pairs in {folder}")
    if not chunks:
        return np.zeros(0, dtype=bool), np.zeros((0, 4, 4))
    return (np.concatenate([c[0] for c in chunks if c is not None]),
            np.concatenate([c[1] for c in chunks if c is not None]))


def _child(folder: Path, first: int, last: int) -> None:
    """A child process: one chunk of the job in ``folder``, saved there."""
    raw = json.loads((folder / _JOB_FILE).read_text(encoding="utf-8"))
    job = PairJob(**{**raw, "intrinsics": tuple(raw["intrinsics"])})
    rows = tum_associations(job.folder)
    init = np.load(folder / _INIT_FILE, allow_pickle=False)
    result = _chunk_pairs(job, rows, first, last, init)
    _save_chunk(_chunk_file(folder, first), job, len(rows), first, result)


if __name__ == "__main__":
    _child(Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]))
