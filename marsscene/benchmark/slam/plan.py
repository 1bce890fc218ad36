"""What a SLAM benchmark cell runs (:class:`CellPlan`): its scene, tau, seed and methods, and
the sensors its drive logs; the same for a cell driven on the CPU (:mod:`.cell`) and in a batch
(:mod:`.device`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from marsscene.benchmark.slam.spec import MethodSpec, SceneSpec, SlamSpec
from marsscene.sweep.grid import Cell

__all__ = ["CellPlan", "cell_plan", "is_lidar_cell"]


def is_lidar_cell(spec: SlamSpec, tau: float) -> bool:
    """The cell of each scene and seed that logs the LiDAR and runs the tau-free methods."""
    return math.isclose(tau, float(spec.lidar_tau or spec.tau[0]))



@dataclass(frozen=True)
class CellPlan:
    """What a cell runs: its scene, tau, seed and methods, and which sensors its drive logs
    (the main seeds' cells log every sensor of the spec; an extra seed's only what its methods
    need, e.g. none for the wheel odometry); ``live``: the methods fed during the drive."""

    scene: SceneSpec
    tau: float
    seed: int
    methods: tuple[MethodSpec, ...]
    lidar: bool
    camera: bool
    live: tuple[MethodSpec, ...]


def cell_plan(spec: SlamSpec, cell: Cell) -> CellPlan:
    """The :class:`CellPlan` of ``cell``."""
    scene = next(s for s in spec.scenes if s.name == cell.params["scene"])
    tau, seed = float(cell.params["tau"]), int(cell.params["seed"])
    methods = tuple(spec.methods_for(tau, seed))
    main = seed in spec.seeds
    lidar = is_lidar_cell(spec, tau) and (main or any(m.sensor == "lidar" for m in methods))
    camera = main or any(m.sensor == "camera" for m in methods)
    live = tuple(m for m in methods if m.kind == "kiss-icp") if lidar else ()
    return CellPlan(scene, tau, seed, methods, lidar, camera, live)
