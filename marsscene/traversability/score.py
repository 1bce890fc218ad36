"""Scores of a predicted traversability map against the ground truth (pure numpy): the
intersection over union of the hazard masks and the area under the ROC curve of a predicted
cost as a detector of ground-truth hazards.

The AUROC is the Mann--Whitney statistic: the probability that a random hazard cell gets a
higher predicted cost than a random free cell, ties counting one half (Hanley, J. A., McNeil,
B. J. (1982), The meaning and use of the area under a receiver operating characteristic (ROC)
curve, Radiology 143(1), 29-36). Cells outside ``valid`` (unobserved by the method) are left
out of both scores.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.stats import rankdata

from marsscene.errors import ConfigError

__all__ = ["cost_auroc", "hazard_iou"]


def _masks(pred: ArrayLike, truth: ArrayLike, valid: ArrayLike | None
           ) -> tuple[np.ndarray, np.ndarray]:
    p, t = np.asarray(pred), np.asarray(truth, dtype=bool)
    if p.shape != t.shape:
        raise ConfigError(f"predicted map {p.shape} and ground truth {t.shape} differ in shape")
    v = np.ones(t.shape, bool) if valid is None else np.asarray(valid, dtype=bool)
    if v.shape != t.shape:
        raise ConfigError(f"valid mask {v.shape} and ground truth {t.shape} differ in shape")
    return p[v], t[v]


def hazard_iou(pred_hazard: ArrayLike, true_hazard: ArrayLike, valid: ArrayLike | None = None
               ) -> float:
    """|pred AND truth| / |pred OR truth| over the valid cells (NaN when both are empty).

    >>> hazard_iou([[1, 1, 0, 0]], [[0, 1, 1, 0]])
    0.3333333333333333
    """
    p, t = _masks(pred_hazard, true_hazard, valid)
    p = p.astype(bool)
    union = int(np.count_nonzero(p | t))
    return math.nan if union == 0 else int(np.count_nonzero(p & t)) / union


def cost_auroc(pred_cost: ArrayLike, true_hazard: ArrayLike, valid: ArrayLike | None = None
               ) -> float:
    """AUROC of ``pred_cost`` separating ground-truth hazard cells from free ones (NaN when
    either class is empty; 1 perfect, 0.5 chance).

    >>> cost_auroc([0.1, 0.4, 0.35, 0.8], [0, 0, 1, 1])
    0.75
    """
    p, t = _masks(pred_cost, true_hazard, valid)
    p = p.astype(np.float64)
    n_pos, n_neg = int(t.sum()), int((~t).sum())
    if n_pos == 0 or n_neg == 0:
        return math.nan
    ranks = rankdata(p)
    return float((ranks[t].sum() - n_pos * (n_pos + 1) / 2.0) / (n_pos * n_neg))
