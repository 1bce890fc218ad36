"""The run folder: its writers (:mod:`.logs`), its reader (:mod:`.runlog`), TUM trajectories
(:mod:`.tum`) and trajectory evaluation (:mod:`.evaluation`). Pure numpy/scipy, no MuJoCo.
Exporters of run folders (ROS 2 bags, TUM RGB-D / EuRoC) are :mod:`marsscene.runs.export`."""
