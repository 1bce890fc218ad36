"""The localization benchmark: seeded query places along routes on scene x tau cells, each with
the rover's local data after a short drive (a LiDAR elevation map, camera images with depth)
and a dead-reckoning prior, localized against the scene's orbital map by ``dem-correlation``,
``ortho-match``, the ``prior`` floor or your method (:mod:`.methods`), scored and tabulated
(:mod:`.table`, :mod:`.report`). The spec is :class:`~.spec.LocSpec`;
:func:`~.run.run_loc_benchmark` runs it; docs/benchmark_loc.md documents the query folder."""

from marsscene._lazy import lazy_attributes

__all__ = ["LocBenchmarkResult", "LocSpec", "loc_cells", "run_loc_benchmark"]

__getattr__ = lazy_attributes(__name__, {
    "LocSpec": "marsscene.benchmark.loc.spec",
    **dict.fromkeys(("LocBenchmarkResult", "run_loc_benchmark", "loc_cells"),
                    "marsscene.benchmark.loc.run"),
})
