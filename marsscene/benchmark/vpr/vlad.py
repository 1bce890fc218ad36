"""VLAD over RootSIFT: the place-recognition baseline that needs no downloaded weights.

Jégou, Douze, Schmid & Pérez 2010, "Aggregating local descriptors into a compact image
representation", CVPR, doi:10.1109/CVPR.2010.5540039 (VLAD: the sum of residuals to the nearest
visual word); Arandjelović & Zisserman 2012, "Three things everyone should know to improve
object retrieval", CVPR, doi:10.1109/CVPR.2012.6248018 (RootSIFT); Arandjelović & Zisserman
2013, "All about VLAD", CVPR, doi:10.1109/CVPR.2013.207 (intra-normalisation). SIFT: Lowe 2004,
IJCV 60(2) 91-110, doi:10.1023/B:VISI.0000029664.99615.94, as OpenCV implements it.

The vocabulary (``words`` k-means centres, seeded) is learnt from the database images' own
descriptors, so the baseline uses nothing from the queries. Needs ``opencv-python-headless``
(the ``bench`` extra).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import RuntimeSimError, missing_dependency

__all__ = ["rootsift", "sift_vlad", "vlad"]


def rootsift(files: tuple[Path, ...], features: int = 500,
             tick: Callable[[], None] | None = None) -> list[NDArray[np.float32]]:
    """RootSIFT descriptors (n_i, 128) of each image (L1-normalised SIFT, square-rooted)."""
    try:
        import cv2
    except ImportError:
        raise missing_dependency("opencv-python-headless", "bench") from None
    sift = cv2.SIFT_create(nfeatures=features)  # type: ignore[attr-defined]
    out = []
    for f in files:
        grey = cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)
        _, d = sift.detectAndCompute(grey, None)
        d = np.zeros((0, 128), np.float32) if d is None else d.astype(np.float32)
        out.append(np.sqrt(d / (d.sum(axis=1, keepdims=True) + 1e-7)))
        if tick is not None:
            tick()
    return out


def vlad(descs: list[NDArray[np.float32]], centres: NDArray[np.float32]) -> NDArray[np.float32]:
    """Intra-normalised, power-normalised, L2-normalised VLAD (N, words * 128)."""
    k, dim = centres.shape
    c_sq = np.einsum("ij,ij->i", centres, centres)
    out = np.zeros((len(descs), k * dim), dtype=np.float32)
    for i, d in enumerate(descs):
        if not len(d):
            continue
        word = np.argmin(c_sq[None, :] - 2.0 * d @ centres.T, axis=1)
        v = np.zeros((k, dim), dtype=np.float64)
        np.add.at(v, word, d - centres[word])
        v = np.sign(v) * np.sqrt(np.abs(v))
        v /= np.linalg.norm(v, axis=1, keepdims=True) + 1e-12
        flat = v.reshape(-1)
        out[i] = flat / (np.linalg.norm(flat) + 1e-12)
    return out


def sift_vlad(db_files: tuple[Path, ...], query_files: tuple[Path, ...], *, words: int = 64,
              seed: int = 0, tick: Callable[[], None] | None = None
              ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """VLAD descriptors of the database and the queries, vocabulary from the database."""
    from scipy.cluster.vq import kmeans2

    d_db = rootsift(db_files, tick=tick)
    d_q = rootsift(query_files, tick=tick)
    pool = np.concatenate([d for d in d_db if len(d)] or [np.zeros((0, 128), np.float32)])
    if len(pool) < words:
        raise RuntimeSimError(f"only {len(pool)} SIFT features in the database images; need >= "
                         f"{words} for the vocabulary")
    rng = np.random.default_rng(seed)
    sample = pool[rng.choice(len(pool), size=min(len(pool), 50_000), replace=False)]
    centres, _ = kmeans2(sample.astype(np.float64), words, iter=20, minit="++", seed=rng)
    centres = centres.astype(np.float32)
    return vlad(d_db, centres), vlad(d_q, centres)
