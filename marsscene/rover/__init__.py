"""The rover and its sensor suite as data: run configuration (:mod:`.config`), geometry and
wheel kinematics (:mod:`.geometry`), LiDAR models (:mod:`.lidar`). Pure numpy; no MuJoCo, no
files."""

from marsscene.rover.config import CameraConfig, LidarConfig, NoiseConfig, RoverConfig, RunConfig
from marsscene.rover.geometry import wheel_commands

__all__ = ["CameraConfig", "LidarConfig", "NoiseConfig", "RoverConfig", "RunConfig",
           "wheel_commands"]
