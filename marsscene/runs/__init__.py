"""The run folder: its writers (:mod:`.logs`), its reader (:mod:`.runlog`), TUM trajectories
(:mod:`.tum`) and trajectory evaluation (:mod:`.evaluation`). Pure numpy/scipy, no MuJoCo.
Exporters of run folders (ROS 2 bags, TUM RGB-D / EuRoC) are :mod:`marsscene.runs.export`."""

from marsscene.runs.evaluation import ate, rpe
from marsscene.runs.runlog import RunLog
from marsscene.runs.tum import Trajectory, read_tum, write_tum

__all__ = ["RunLog", "Trajectory", "ate", "read_tum", "rpe", "write_tum"]
