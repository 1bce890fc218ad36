"""Scene-variant sweeps: a grid of configs (seeds x tau x sun x rocks ...) built, driven and
evaluated serially or on Dask, with a ``results.csv`` row per cell.

Spec parsing, the grid and cell ids are pure (:mod:`~marsscene.sweep.spec`,
:mod:`~marsscene.sweep.grid`); one cell runs in :mod:`~marsscene.sweep.cell`; Dask is imported
only by :mod:`~marsscene.sweep.run`, when :func:`run_sweep` is called.

Examples
--------
>>> from marsscene.sweep import expand_grid, SweepSpec
>>> spec = SweepSpec.from_dict({"sweep": {"seed": [1, 2], "lighting.tau": [0.3, 3.0]}})
>>> for cell in expand_grid(spec):
...     print(cell.cell_id)
seed=1__lighting.tau=0.3
seed=1__lighting.tau=3.0
seed=2__lighting.tau=0.3
seed=2__lighting.tau=3.0
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from marsscene._lazy import lazy_attributes
from marsscene.sweep.cell import run_cell
from marsscene.sweep.grid import Cell, cell_id, expand_grid
from marsscene.sweep.spec import DriveSpec, SweepSpec

if TYPE_CHECKING:
    from marsscene.sweep.run import Progress, SweepResult, run_sweep

__all__ = [
    "Cell",
    "DriveSpec",
    "Progress",
    "SweepResult",
    "SweepSpec",
    "cell_id",
    "expand_grid",
    "run_cell",
    "run_sweep",
]


#: dask is imported when a sweep is run
__getattr__ = lazy_attributes(__name__, dict.fromkeys(("Progress", "SweepResult", "run_sweep"),
                                                      "marsscene.sweep.run"))
