"""The planning and navigation benchmark (``marsscene benchmark nav``): seeded start-goal pairs
on connected traversable ground of a scene's ground-truth traversability, methods from straight
pure pursuit to a user's controller, each driven with :func:`marsscene.drive` and scored
(success, SPL, path ratio, time, slip, hazard entries, tip-over, stuck, planning time).
docs/benchmark_nav.md is the guide."""

from marsscene.benchmark.nav.metrics import episode_scores, spl
from marsscene.benchmark.nav.run import NavBenchmarkResult, nav_cells, run_nav_benchmark
from marsscene.benchmark.nav.spec import METHOD_KINDS, NavMethodSpec, NavSceneSpec, NavSpec

__all__ = ["METHOD_KINDS", "NavBenchmarkResult", "NavMethodSpec", "NavSceneSpec", "NavSpec",
           "episode_scores", "nav_cells", "run_nav_benchmark", "spl"]
