"""Exporters of run folders, the way :mod:`marsscene.export` exports scenes: ROS 2 bags
(:mod:`.bag`, the only importer of ``rosbags``), TF frames and the rover URDF (:mod:`.frames`),
TUM RGB-D and EuRoC folders (:mod:`.datasets`), and their options (:mod:`.options`). They read
a run folder and never need MuJoCo."""

from marsscene._lazy import lazy_attributes
from marsscene.runs.export.options import BagOptions, ExportOptions

__all__ = ["BagOptions", "BagSummary", "ExportOptions", "export_dataset", "write_bag"]

__getattr__ = lazy_attributes(__name__, {
    "BagSummary": "marsscene.runs.export.bag", "write_bag": "marsscene.runs.export.bag",
    "export_dataset": "marsscene.runs.export.datasets",
})
