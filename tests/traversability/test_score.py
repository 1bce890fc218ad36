"""Hazard IoU and cost AUROC on known cases, against a brute-force pair count."""

from __future__ import annotations

import math

import numpy as np
import pytest

from marsscene.errors import ConfigError
from marsscene.traversability.score import cost_auroc, hazard_iou


def test_iou_known_cases() -> None:
    truth = np.array([[1, 1, 0], [0, 0, 0]], bool)
    assert hazard_iou(truth, truth) == 1.0
    assert hazard_iou(~truth, truth) == 0.0
    assert hazard_iou([[1, 0, 0], [0, 0, 1]], truth) == pytest.approx(1 / 3)
    assert math.isnan(hazard_iou(np.zeros((2, 3)), np.zeros((2, 3))))
    valid = np.array([[1, 1, 1], [1, 1, 0]], bool)  # the false alarm unobserved
    assert hazard_iou([[1, 0, 0], [0, 0, 1]], truth, valid) == pytest.approx(1 / 2)


def test_auroc_matches_pair_counting() -> None:
    rng = np.random.default_rng(4)
    truth = rng.random(400) < 0.2
    cost = np.round(rng.random(400) * 0.5 + 0.3 * truth, 2)  # informative, with ties
    pos, neg = cost[truth], cost[~truth]
    brute = ((pos[:, None] > neg[None, :]).sum() + 0.5 * (pos[:, None] == neg[None, :]).sum()
             ) / (pos.size * neg.size)
    assert cost_auroc(cost, truth) == pytest.approx(brute, abs=1e-12)
    assert cost_auroc(truth.astype(float), truth) == 1.0
    assert cost_auroc(np.zeros(400), truth) == 0.5
    assert math.isnan(cost_auroc(cost, np.zeros(400, bool)))


def test_shape_mismatch_is_one_line() -> None:
    with pytest.raises(ConfigError, match=r"predicted map \(2,\) and ground truth \(3,\)"):
        hazard_iou([1, 0], [1, 0, 0])
