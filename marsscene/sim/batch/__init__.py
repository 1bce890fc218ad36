"""Many drives at once on one MuJoCo Warp model (``pip install "marsscene[gpu]"``), each
written as a CPU drive writes its run folder (:func:`drive_batch`; docs: :doc:`/gpu_drives`).

- :mod:`.spec`: one drive of a batch (:class:`BatchDrive`) and batch files (TOML).
- :mod:`.setup`: the drives' worlds, routes and starts, tiled into one model.
- :mod:`.pursuit`: pure pursuit of every drive on the Warp device.
- :mod:`.loop`: the batch's clock (control, IMU, LiDAR, camera ticks).
- :mod:`.sink`: each drive's noise, odometry and run folder, written by worker threads.
"""

from __future__ import annotations

from marsscene._lazy import lazy_attributes

__all__ = ["BatchDrive", "BatchRun", "drive_batch", "read_batch_file"]

__getattr__ = lazy_attributes(__name__, {
    "BatchDrive": "marsscene.sim.batch.spec",
    "read_batch_file": "marsscene.sim.batch.spec",
    "BatchRun": "marsscene.sim.batch.api",
    "drive_batch": "marsscene.sim.batch.api",
})
