"""Benchmark protocols and baselines: the MarsLab paper's experiments on marsscene's worlds.

* :mod:`.slam`: localization methods (wheel odometry, KISS-ICP, Open3D RGB-D, monocular VO, your
  own) run on the runs and bags of scene x tau x seed cells and scored against ground truth;
* :mod:`.vpr`: place-recognition datasets (two traversals of one route under two lightings) and
  their recall@N evaluation;
* :mod:`.routes`: the automatic routes both use.

Above the run side and sweeps: cells drive with :func:`marsscene.drive` like any user.

Examples
--------
>>> from marsscene.benchmark import SlamSpec, slam_cells
>>> spec = SlamSpec.from_dict({
...     "benchmark": {"tau": [0.5, 6.0]},
...     "scenes": [{"name": "plain", "route": {"shape": "loop", "length_m": 20.0}}],
...     "methods": [{"name": "wheel-odom", "kind": "wheel-odometry"}]})
>>> [c.cell_id for c in slam_cells(spec)]
['scene=plain__tau=0.5__seed=0', 'scene=plain__tau=6.0__seed=0']
"""

from marsscene._lazy import lazy_attributes

__all__ = ["SlamSpec", "VprSpec", "evaluate_vpr", "generate_vpr", "run_slam_benchmark",
           "slam_cells"]

__getattr__ = lazy_attributes(__name__, {
    "SlamSpec": "marsscene.benchmark.slam.spec", "VprSpec": "marsscene.benchmark.vpr.spec",
    "run_slam_benchmark": "marsscene.benchmark.slam.run",
    "generate_vpr": "marsscene.benchmark.vpr.dataset",
    "evaluate_vpr": "marsscene.benchmark.vpr.score",
    "slam_cells": "marsscene.benchmark.slam.run",
})
