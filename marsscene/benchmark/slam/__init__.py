"""The SLAM benchmark: scene x tau x seed cells driven with the sensors, localization methods
run on each cell's run folder and bag (:mod:`.methods`, :mod:`.kiss_icp`, :mod:`.mono_vo`),
scored against ground truth (:mod:`.metrics`), tabulated and plotted (:mod:`.table`,
:mod:`.report`). The spec is :class:`~.spec.SlamSpec`; :func:`~.run.run_slam_benchmark` runs
it."""

from marsscene._lazy import lazy_attributes

__all__ = ["SlamBenchmarkResult", "SlamSpec", "run_slam_benchmark", "slam_cells"]

__getattr__ = lazy_attributes(__name__, {
    "SlamSpec": "marsscene.benchmark.slam.spec",
    **dict.fromkeys(("SlamBenchmarkResult", "run_slam_benchmark", "slam_cells"),
                    "marsscene.benchmark.slam.run"),
})
