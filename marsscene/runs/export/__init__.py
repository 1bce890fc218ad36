"""Exporters of run folders, the way :mod:`marsscene.export` exports scenes: ROS 2 bags
(:mod:`.bag`, the only importer of ``rosbags``), TF frames and the rover URDF (:mod:`.frames`),
TUM RGB-D and EuRoC folders (:mod:`.datasets`). They read a run folder and never need MuJoCo."""
