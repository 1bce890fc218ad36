"""Evaluate place-recognition descriptors on a VPR dataset: Recall@N within a radius.

A query is recognised at N when one of its N nearest database descriptors (L2 distance, as
``gmberton/VPR-methods-evaluation`` ranks with a flat L2 index) was taken within ``radius_m``
of the query (east / north from the file names). Recall@N is the share of all queries
recognised at N (queries with no database image within the radius count as misses, as there).

Descriptors come from any method: one ``.npy`` per split (``database.npy``, ``queries.npy``,
or ``*_descriptors.npy`` as VPR-methods-evaluation saves them: rows in the sorted order of the
split's file names) or one ``.npy`` per image (``<split>/<image
file name>.npy``). Without descriptors the classical baseline runs: patch-normalised
thumbnails (Milford & Wyeth 2012, SeqSLAM, ICRA, doi:10.1109/ICRA.2012.6224623: 64 x 48
grey-level images, each 8 x 8 patch normalised to zero mean and unit variance), which needs no
downloaded weights.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import ConfigError, missing_dependency

__all__ = ["Recall", "VprSplit", "load_descriptors", "patch_normalised", "read_split",
           "recall_at", "retrieve", "write_results"]

RECALL_N = (1, 5, 10, 20)


@dataclass(frozen=True)
class VprSplit:
    """The images of one split, sorted by file name, and their east / north (m)."""

    name: str
    files: tuple[Path, ...]
    xy_m: NDArray[np.float64]


def read_split(dataset: str | Path, split: str) -> VprSplit:
    """The ``.jpg`` images of ``DATASET/split`` and the coordinates in their names."""
    folder = Path(dataset) / split
    files = tuple(sorted(folder.glob("*.jpg")))
    if not files:
        raise ConfigError(f"{folder}: no .jpg images (is {dataset} a VPR dataset folder with "
                          "database/ and queries/?)")
    try:
        xy = np.array([[float(f.name.split("@")[1]), float(f.name.split("@")[2])]
                       for f in files])
    except (IndexError, ValueError):
        raise ConfigError(f"{folder}: image names must start with @east@north@ "
                          f"(e.g. {files[0].name})") from None
    return VprSplit(split, files, xy)


def load_descriptors(folder: str | Path, split: VprSplit) -> NDArray[np.float32]:
    """Descriptors (N, D) of ``split`` from ``folder/<split>.npy`` or per-image files."""
    folder = Path(folder)
    whole = folder / f"{split.name}.npy"
    if not whole.is_file():  # as VPR-methods-evaluation's --save_descriptors names them
        whole = folder / f"{split.name}_descriptors.npy"
    if whole.is_file():
        arr = np.load(whole)
        if arr.ndim != 2 or len(arr) != len(split.files):
            raise ConfigError(f"{whole}: shape {arr.shape}; expected ({len(split.files)}, D), "
                              f"one row per image of {split.name}/ in file-name order")
        return np.asarray(arr, dtype=np.float32)
    per = [folder / split.name / f"{f.name}.npy" for f in split.files]
    missing = [p for p in per if not p.is_file()]
    if missing:
        raise ConfigError(f"{folder}: no {split.name}.npy and {len(missing)} per-image "
                          f"descriptor(s) missing, e.g. {missing[0]}")
    rows = [np.load(p).reshape(-1) for p in per]
    if len({r.shape for r in rows}) != 1:
        raise ConfigError(f"{folder / split.name}: descriptors of different lengths")
    return np.stack(rows).astype(np.float32)


def patch_normalised(files: tuple[Path, ...], size: tuple[int, int] = (64, 48),
                     patch_px: int = 8) -> NDArray[np.float32]:
    """The SeqSLAM-style baseline descriptor of each image, L2-normalised, (N, 64 * 48)."""
    from PIL import Image

    w, h = size
    out = np.zeros((len(files), w * h), dtype=np.float32)
    for i, f in enumerate(files):
        with Image.open(f) as im:
            g = np.asarray(im.convert("L").resize((w, h), Image.Resampling.BOX), np.float32)
        p = g.reshape(h // patch_px, patch_px, w // patch_px, patch_px)
        p = (p - p.mean(axis=(1, 3), keepdims=True)) / (p.std(axis=(1, 3), keepdims=True) + 1e-3)
        v = p.reshape(-1)
        out[i] = v / (np.linalg.norm(v) + 1e-12)
    return out


def retrieve(db: NDArray[np.floating], queries: NDArray[np.floating], k: int,
             block: int = 512) -> NDArray[np.int64]:
    """Indices (Q, k) of each query's k nearest database descriptors (L2), nearest first."""
    if db.shape[1] != queries.shape[1]:
        raise ConfigError(f"descriptor lengths differ: database {db.shape[1]}, queries "
                          f"{queries.shape[1]}")
    k = min(k, len(db))
    d64, q64 = db.astype(np.float64), queries.astype(np.float64)
    db_sq = np.einsum("ij,ij->i", d64, d64)
    out = np.zeros((len(q64), k), dtype=np.int64)
    for a in range(0, len(q64), block):
        q = q64[a:a + block]
        dist = db_sq[None, :] - 2.0 * q @ d64.T  # + |q|^2, the same for every candidate
        part = np.argpartition(dist, k - 1, axis=1)[:, :k]
        order = np.take_along_axis(dist, part, axis=1)
        # ties broken by index, so results do not depend on argpartition's choice
        out[a:a + block] = np.take_along_axis(part, np.lexsort((part, order), axis=1), axis=1)
    return out


@dataclass(frozen=True)
class Recall:
    """Recall@N (fractions) of one method at one radius."""

    method: str
    radius_m: float
    recall: dict[int, float]
    queries: int
    without_positive: int


def recall_at(ranked: NDArray[np.int64], db_xy_m: NDArray[np.float64],
              q_xy_m: NDArray[np.float64], radius_m: float, method: str = "",
              ns: tuple[int, ...] = RECALL_N) -> Recall:
    """Recall@N for each N in ``ns`` from the ranked database indices of each query."""
    from scipy.spatial import cKDTree

    near = cKDTree(db_xy_m).query_ball_point(q_xy_m, r=radius_m)
    top = ranked[:, :max(ns)]
    dist = np.hypot(*(db_xy_m[top] - q_xy_m[:, None, :]).transpose(2, 0, 1))
    hit = dist <= radius_m
    first = np.where(hit.any(axis=1), hit.argmax(axis=1), np.iinfo(np.int64).max)
    rec = {n: float(np.mean(first < n)) for n in ns}
    return Recall(method, radius_m, rec, len(q_xy_m), int(sum(len(p) == 0 for p in near)))


def write_results(out: Path, results: list[Recall]) -> None:
    """``recall.csv`` and ``recall.md`` (Recall@N in %)."""
    out.mkdir(parents=True, exist_ok=True)
    ns = sorted(results[0].recall)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["method", "radius_m", *(f"recall_at_{n}" for n in ns), "queries",
                "queries_without_positive"])
    for r in results:
        w.writerow([r.method, r.radius_m, *(f"{r.recall[n]:.6f}" for n in ns), r.queries,
                    r.without_positive])
    write_atomic(out / "recall.csv", buf.getvalue())
    lines = ["| method | radius | " + " | ".join(f"R@{n}" for n in ns) + " |",
             "|---|---|" + "---|" * len(ns)]
    lines += [f"| {r.method} | {r.radius_m:g} m | "
              + " | ".join(f"{100 * r.recall[n]:.2f}" for n in ns) + " |" for r in results]
    write_atomic(out / "recall.md", "\n".join(lines) + "\n")


def pairs_figure(out_png: Path, db: VprSplit, queries: VprSplit, ranked: NDArray[np.int64],
                 radius_m: float, count: int = 4, title: str = "",
                 pick: NDArray[np.int64] | None = None) -> None:
    """Query / top-1 retrieved pairs (``pick``: query indices; default evenly spaced), like
    the paper's figure."""
    try:
        import matplotlib  # noqa: TID251  (the benchmark's figure is this function's product)

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # noqa: TID251
    except ImportError:
        raise missing_dependency("matplotlib", "bench") from None
    from PIL import Image

    if pick is None:
        pick = np.linspace(0, len(queries.files) - 1, count).round().astype(int)
    count = len(pick)
    fig, axes = plt.subplots(count, 2, figsize=(6.4, 2.4 * count), squeeze=False)
    for row, qi in enumerate(pick):
        di = int(ranked[qi, 0])
        d = float(np.hypot(*(db.xy_m[di] - queries.xy_m[qi])))
        for col, (path, label) in enumerate(((queries.files[qi], f"query {qi}"),
                                             (db.files[di], f"top-1: {d:.1f} m "
                                              + ("correct" if d <= radius_m else "wrong")))):
            ax: Any = axes[row, col]
            with Image.open(path) as im:
                ax.imshow(np.asarray(im.convert("RGB")))
            ax.set_title(label, fontsize=9, color="black" if col == 0 or d <= radius_m
                         else "crimson")
            ax.axis("off")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(out_png, dpi=90)
    plt.close(fig)
