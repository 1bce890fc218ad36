"""A run folder replayed into KISS-ICP (``replay_run``) gives the estimate KISS-ICP gave fed
live during the drive: the same poses to 1e-9 m (KISS-ICP's own threaded sums differ in the
last bits from run to run); with the wheel prior to 1e-5 m (the prior then reads ``odom.tum``'s
micrometres, not the live odometry's doubles)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco")

from tests.support.extras import needs


@pytest.mark.parametrize("wheel_prior", [False, True])
def test_replay_equals_live(wheel_prior: bool, tmp_path: Path, gentle_scene: Path) -> None:
    needs("kiss_icp", "bench")
    import marsscene as ms
    from marsscene.benchmark.slam.kiss_icp import LiveKissIcp, lidar_mount
    from marsscene.benchmark.slam.replay import replay_run
    from marsscene.rover.config import RoverConfig

    mount = lidar_mount(RoverConfig())
    live = LiveKissIcp(lidar_mount=mount, wheel_prior=wheel_prior)
    run = ms.RunConfig(lidar=ms.LidarConfig(model="vlp16"),
                       noise=ms.NoiseConfig(profile="ln200s"))
    ms.drive(gentle_scene, command=(0.3, 0.05), seconds=3.0, config=run,
             out_dir=tmp_path / "r", listeners=[live])
    again = LiveKissIcp(lidar_mount=mount, wheel_prior=wheel_prior)
    assert replay_run(tmp_path / "r", [again]) == len(live.poses) > 10
    third = LiveKissIcp(lidar_mount=mount, wheel_prior=wheel_prior)
    replay_run(tmp_path / "r", [third])
    # KISS-ICP's threaded sums differ run to run in the last bits (1e-15): so do two replays
    spread = np.abs(np.stack(third.poses) - np.stack(again.poses)).max()
    assert spread < 1e-12
    # the wheel prior reads odom.tum, whose positions are rounded to the micrometre
    atol = 1e-5 if wheel_prior else 1e-9
    np.testing.assert_allclose(np.stack(again.poses), np.stack(live.poses), rtol=0, atol=atol)
    assert again.icp_steps_kept == live.icp_steps_kept
