"""``evaluate_vpr``: score descriptors (yours, or a classical baseline's) on a VPR dataset.

Writes ``recall.csv``, ``recall.md`` and ``pairs.png`` (query / top-1 pairs) into the results
folder; the recall rules are :mod:`marsscene.benchmark.vpr.eval`'s.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from marsscene.benchmark.vpr.eval import (
    Recall,
    load_descriptors,
    pairs_figure,
    patch_normalised,
    read_split,
    recall_at,
    retrieve,
    write_results,
)
from marsscene.errors import ConfigError

__all__ = ["BASELINES", "evaluate_vpr"]

#: Classical, weight-free baselines: RootSIFT-VLAD and patch-normalised thumbnails.
BASELINES = ("sift-vlad", "patch-normalised")


def evaluate_vpr(
    dataset: str | Path,
    descriptors: str | Path | None = None,
    *,
    radii_m: tuple[float, ...] = (2.0,),
    out_dir: str | Path | None = None,
    method: str | None = None,
    baseline: str = "sift-vlad",
    progress: Callable[[int, int], None] | None = None,
) -> list[Recall]:
    """Recall@1/5/10/20 of ``descriptors`` (or of ``baseline``) on ``dataset``.

    Parameters
    ----------
    dataset : path
        A dataset folder of :func:`~marsscene.benchmark.vpr.dataset.generate_vpr`.
    descriptors : path, optional
        ``database.npy`` + ``queries.npy``, or ``<split>/<image>.npy`` per image; without it
        the classical ``baseline`` computes them.
    radii_m : tuple of float
        Positive radii; one :class:`~marsscene.benchmark.vpr.eval.Recall` each.
    out_dir : path, optional
        Results folder (default ``DATASET/results/<method>``).
    method : str, optional
        Name in the table (default: the descriptor folder's name, or the baseline's).
    baseline : {"sift-vlad", "patch-normalised"}
    progress : callable, optional
        ``progress(done, total)`` per image described by the baseline.
    """
    if baseline not in BASELINES:
        raise ConfigError(f"baseline = {baseline!r}; expected one of {', '.join(BASELINES)}")
    if not radii_m:
        raise ConfigError("radii_m: give at least one radius")
    root = Path(dataset)
    name = method or (Path(descriptors).name if descriptors is not None else baseline)
    out = Path(out_dir) if out_dir is not None else root / "results" / name
    db, q = read_split(root, "database"), read_split(root, "queries")
    n = len(db.files) + len(q.files)
    count = iter(range(1, n + 1))

    def tick() -> None:
        if progress is not None:
            progress(next(count), n)

    if descriptors is not None:
        d_db, d_q = load_descriptors(descriptors, db), load_descriptors(descriptors, q)
    elif baseline == "sift-vlad":
        from marsscene.benchmark.vpr.vlad import sift_vlad

        d_db, d_q = sift_vlad(db.files, q.files, tick=tick)
    else:
        d_db, d_q = patch_normalised(db.files), patch_normalised(q.files)
        if progress is not None:
            progress(n, n)
    ranked = retrieve(d_db, d_q, k=20)
    results = [recall_at(ranked, db.xy_m, q.xy_m, r, name) for r in radii_m]
    write_results(out, results)
    pick, seen = _landmark_queries(root, q)
    pairs_figure(out / "pairs.png", db, q, ranked, radii_m[0], pick=pick,
                 title=f"{root.name}: {name}, top-1 within {radii_m[0]:g} m"
                 + (f" ({seen} in view)" if seen else ""))
    return results


def _landmark_queries(root: Path, queries: Any, count: int = 4, min_px: float = 20.0
                      ) -> tuple[Any, str]:
    """Evenly spaced queries that show the dataset's landmark (``poses.csv`` ``landmark_px``
    >= ``min_px``), or None (evenly spaced queries) when there is none; and its name."""
    import csv
    import json

    import numpy as np

    try:
        with open(root / "poses.csv", encoding="utf-8") as fh:
            px = {r["file"]: float(r["landmark_px"]) for r in csv.DictReader(fh)
                  if r.get("landmark_px")}
        name = json.loads((root / "dataset.json").read_text(encoding="utf-8"))["landmark"]["name"]
    except (OSError, KeyError, ValueError):
        return None, ""
    shown = np.flatnonzero([px.get(f"queries/{f.name}", 0.0) >= min_px for f in queries.files])
    if len(shown) < count:
        return None, ""
    return shown[np.linspace(0, len(shown) - 1, count).round().astype(int)], str(name)
