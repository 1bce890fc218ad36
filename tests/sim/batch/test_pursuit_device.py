"""Pure pursuit on the Warp device gives sim/pursuit.py's commands, progress and stop on the
same states (Warp's CPU device)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("warp")

from marsscene.sim.pursuit import PurePursuit, PursuitConfig
from marsscene.sim.route import Route


@pytest.mark.parametrize(("config", "lookaheads"), [
    (PursuitConfig(), None), (PursuitConfig(lookahead_m=2.0, slow_down_m=0.0), None),
    (PursuitConfig(), (1.2, None, 3.5, 2.0)),  # each drive's own lookahead where given
])
def test_device_pursuit_matches_cpu(config: PursuitConfig, lookaheads: tuple | None) -> None:
    import dataclasses

    import warp as wp

    from marsscene.sim.batch.pursuit import DevicePursuit

    wp.config.quiet = True
    t = np.linspace(0.0, 1.0, 200)
    routes = [Route(np.column_stack([20 * t, 3 * np.sin(4 * t)])),
              Route(np.column_stack([10 * np.cos(3 * t), 10 * np.sin(3 * t)])),
              Route(np.column_stack([5 * t[:50], 0 * t[:50]])),  # a shorter route: padding
              # a closed loop shorter than 3 lookaheads + 1 m: the window stops half way round
              Route(np.column_stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)]))]
    own = lookaheads or (None,) * len(routes)
    cpu = [PurePursuit(r, config if look is None else dataclasses.replace(config,
                                                                        lookahead_m=look))
           for r, look in zip(routes, own, strict=True)]
    dev = DevicePursuit(routes, config, lookaheads_m=lookaheads, device="cpu")
    rng = np.random.default_rng(0)
    turns = 0
    for step in range(420):
        poses = np.array([(*(r.xy_m[min(len(r.xy_m) - 1, step // 2)] + rng.normal(0, 0.3, 2)),
                           rng.uniform(-3.2, 3.2)) for r in routes])
        ref = np.array([p.command(*q) for p, q in zip(cpu, poses, strict=True)])
        v, w = dev.command(*poses.T)
        np.testing.assert_allclose(np.column_stack([v.numpy(), w.numpy()]), ref, rtol=0,
                                   atol=1e-12)
        assert list(dev.index.numpy()) == [p.index for p in cpu]
        turns += int(np.sum((ref[:, 0] == 0) & (ref[:, 1] != 0)))
    assert turns > 10  # turns in place were exercised
    assert list(dev.done.numpy()) == [1, 1, 1, 1] == [int(p.done) for p in cpu]
