"""TUM I/O and ATE/RPE: known transforms, injected errors, and agreement with evo."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from marsscene.errors import RuntimeSimError
from marsscene.runs.evaluation import associate, ate, rpe, umeyama
from marsscene.runs.tum import Trajectory, read_tum, write_tum
from marsscene.transforms import matrix_to_quat, quat_to_matrix


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def _gt(n: int = 300) -> Trajectory:
    t = np.arange(n) * 0.1
    xyz = np.c_[5 * np.cos(0.05 * t) + 0.1 * t, 3 * np.sin(0.07 * t), 0.2 * np.sin(0.3 * t)]
    yaw = 0.05 * t
    q = np.c_[np.cos(yaw / 2), 0 * t, 0 * t, np.sin(yaw / 2)]
    return Trajectory.from_wxyz(t, xyz, q)


def _transform(
    tr: Trajectory, rot: np.ndarray, trans: np.ndarray, scale: float = 1.0
) -> Trajectory:
    xyz = scale * tr.xyz_m @ rot.T + trans
    q = matrix_to_quat(rot @ quat_to_matrix(tr.quat_wxyz))
    return Trajectory.from_wxyz(tr.timestamps_s, xyz, q)


def test_tum_roundtrip(tmp_path: Path) -> None:
    gt = _gt()
    p = write_tum(tmp_path / "gt.tum", gt, header="test")
    back = read_tum(p)
    np.testing.assert_allclose(back.timestamps_s, gt.timestamps_s, atol=1e-6)
    np.testing.assert_allclose(back.xyz_m, gt.xyz_m, atol=1e-6)
    np.testing.assert_allclose(back.quat_xyzw, gt.quat_xyzw, atol=1e-8)
    assert p.read_text().startswith("# test\n")
    assert write_tum(tmp_path / "c.tum", gt, header="test").read_bytes() == p.read_bytes()


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("0 1 2 3 0 0 0 1\n1 1 2 3 0 0 0\n", r"b\.tum:2: expected 8 numbers"),
        ("0 1 2 3 0 0 0 1\n1 1 x 3 0 0 0 1\n", r"b\.tum:2: not a number"),
        ("# only a comment\n", "no poses"),
        ("0 1 2 3 0 0 0 1\n0 1 2 3 0 0 0 1\n", "does not increase"),
        ("0 1 2 3 0 0 0 2\n", "quaternion norm"),
    ],
)
def test_malformed_tum_errors(tmp_path: Path, text: str, match: str) -> None:
    p = tmp_path / "b.tum"
    p.write_text(text)
    with pytest.raises(RuntimeSimError, match=match):
        read_tum(p)


def test_ate_zero_after_alignment_of_known_transform() -> None:
    gt = _gt()
    rot = _rot(np.array([0.2, -0.3, 1.0]), 0.7)
    est = _transform(gt, rot, np.array([3.0, -2.0, 0.5]))
    assert ate(est, gt, align="none").stats.rmse > 1.0
    res = ate(est, gt)
    assert res.stats.rmse < 1e-9
    np.testing.assert_allclose(res.rotation, rot.T, atol=1e-9)
    # monocular: a scaled copy needs Sim(3)
    est_s = _transform(gt, rot, np.array([1.0, 0.0, 0.0]), scale=0.37)
    assert ate(est_s, gt, align="se3").stats.rmse > 0.5
    sim3 = ate(est_s, gt, align="sim3")
    assert sim3.stats.rmse < 1e-9 and sim3.scale == pytest.approx(1 / 0.37)
    assert rpe(est, gt).translation.rmse < 1e-9  # RPE is invariant to a rigid transform


def test_ate_equals_injected_error() -> None:
    gt = _gt()
    offset = np.array([0.3, -0.4, 0.0])  # |offset| = 0.5 m
    est = Trajectory(gt.timestamps_s, gt.xyz_m + offset, gt.quat_xyzw)
    res = ate(est, gt, align="none").stats
    assert res.rmse == pytest.approx(0.5) and res.std == pytest.approx(0.0, abs=1e-12)
    # per-pose errors of known size perpendicular to nothing in particular
    rng = np.random.default_rng(0)
    d = rng.normal(size=(len(gt), 3))
    d *= (0.05 + 0.1 * rng.random(len(gt)))[:, None] / np.linalg.norm(d, axis=1, keepdims=True)
    est = Trajectory(gt.timestamps_s, gt.xyz_m + d, gt.quat_xyzw)
    np.testing.assert_allclose(ate(est, gt, align="none").stats.errors, np.linalg.norm(d, axis=1))


def test_association_with_different_rates_and_offsets() -> None:
    gt = _gt(300)  # 10 Hz
    est = Trajectory(gt.timestamps_s[::3] + 0.004, gt.xyz_m[::3], gt.quat_xyzw[::3])
    ie, ig = associate(est, gt, max_dt_s=0.01)
    np.testing.assert_array_equal(ig, np.arange(0, 300, 3))
    np.testing.assert_array_equal(ie, np.arange(100))
    assert ate(est, gt).stats.n == 100
    with pytest.raises(RuntimeSimError, match="no matching timestamps"):
        associate(Trajectory(gt.timestamps_s + 100, gt.xyz_m, gt.quat_xyzw), gt)


def test_umeyama_needs_points() -> None:
    with pytest.raises(RuntimeSimError, match=">= 3 paired points"):
        umeyama(np.zeros((2, 3)), np.zeros((2, 3)))


@pytest.mark.parametrize("align", ["se3", "sim3", "none"])
def test_ate_rpe_equal_evo(tmp_path: Path, align: str) -> None:
    pytest.importorskip("evo")
    from evo.core import metrics, sync
    from evo.tools import file_interface

    gt = _gt(400)
    rng = np.random.default_rng(11)
    drift = np.cumsum(rng.normal(scale=0.01, size=(len(gt), 3)), axis=0)
    rot = _rot(np.array([0.0, 0.1, 1.0]), 0.3)
    wobble = [_rot(a, 0.01) for a in rng.normal(size=(len(gt), 3))]  # 0.57 deg per pose
    q = matrix_to_quat(np.array(wobble) @ quat_to_matrix(gt.quat_wxyz))
    noisy = Trajectory.from_wxyz(gt.timestamps_s, gt.xyz_m + drift, q)
    est = _transform(noisy, rot, np.array([1.0, 2.0, 0.0]), scale=0.8 if align == "sim3" else 1.0)
    # estimate at other stamps: every other pose, shifted by 3 ms
    est = Trajectory(est.timestamps_s[::2] + 0.003, est.xyz_m[::2], est.quat_xyzw[::2])
    pe, pg = write_tum(tmp_path / "est.tum", est), write_tum(tmp_path / "gt.tum", gt)

    ours = ate(read_tum(pe), read_tum(pg), align=align)
    ref, e = sync.associate_trajectories(
        file_interface.read_tum_trajectory_file(str(pg)),
        file_interface.read_tum_trajectory_file(str(pe)),
        max_diff=0.01,
    )
    if align != "none":
        e.align(ref, correct_scale=align == "sim3")
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, e))
    stats = ape.get_all_statistics()
    assert ours.stats.n == ref.num_poses == 200
    for key in ("rmse", "mean", "median", "std", "min", "max"):
        assert getattr(ours.stats, key) == pytest.approx(stats[key], rel=1e-6, abs=1e-9), key

    ref, e = sync.associate_trajectories(
        file_interface.read_tum_trajectory_file(str(pg)),
        file_interface.read_tum_trajectory_file(str(pe)),
        max_diff=0.01,
    )
    for relation, ours_stats in (
        (metrics.PoseRelation.translation_part, rpe(read_tum(pe), read_tum(pg)).translation),
        (metrics.PoseRelation.rotation_angle_deg, rpe(read_tum(pe), read_tum(pg)).rotation_deg),
    ):
        m = metrics.RPE(relation, delta=1, delta_unit=metrics.Unit.frames, all_pairs=False)
        m.process_data((ref, e))
        assert ours_stats.rmse == pytest.approx(
            m.get_statistic(metrics.StatisticsType.rmse), rel=1e-6, abs=1e-9
        )
        assert ours_stats.max == pytest.approx(
            m.get_statistic(metrics.StatisticsType.max), rel=1e-6, abs=1e-9
        )
