"""A distance-triggered camera in a batch: each drive keeps a frame at the first control step at
or past each multiple of its own distance driven (the CPU session's rule), whatever the other
drives of the batch do."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from marsscene.runs.runlog import RunLog
from tests.sim.batch.conftest import WAYPOINTS

pytest.importorskip("mujoco_warp")

pytestmark = pytest.mark.slow

TRIGGER_M = 0.05


@pytest.fixture(scope="module")
def runs(batch_scenes: list[Path], tmp_path_factory: pytest.TempPathFactory) -> Any:
    import marsscene as ms
    from marsscene.sim.batch import BatchDrive, drive_batch

    out = tmp_path_factory.mktemp("trigger")
    config = ms.RunConfig(physics_hz=100.0, control_hz=20.0,
                          camera=ms.CameraConfig(width_px=32, height_px=24,
                                                 trigger_distance_m=TRIGGER_M))
    drives = [BatchDrive(scene=s, waypoints=w, out_dir=out / name, seed=i, seconds=secs)
              for i, (s, w, name, secs) in enumerate(zip(batch_scenes, WAYPOINTS, "ab",
                                                          (1.6, 0.8), strict=True))]
    return drive_batch(drives, config=config, device="cpu", seed=1,
                       options=ms.DriveOptions(settle_s=0.2))


def test_frames_at_each_multiple_of_the_distance_driven(runs: Any) -> None:
    for out, summary in zip(runs.out_dirs, runs.summaries, strict=True):
        run = RunLog(out)
        stamps = run.camera_streams()[0].stamps_s
        assert len(stamps) == summary["camera_frames"] >= 3
        gt = run.gt  # a row per control step: the positions the trigger sums
        travel = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(gt.xyz_m[:, :2], axis=0).T))])
        expect, next_m = [], 0.0
        for t, d in zip(gt.timestamps_s, travel, strict=True):
            if d >= next_m:
                expect.append(t)
                next_m = (np.floor(d / TRIGGER_M) + 1.0) * TRIGGER_M
        np.testing.assert_allclose(stamps, expect, atol=1e-6)
    a, b = (s["camera_frames"] for s in runs.summaries)
    assert a > b  # drive a drives twice as long: its own count, not the batch's
