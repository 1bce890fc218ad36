"""Sensor models of the rover: the RGB-D camera (:mod:`.camera` and its world, ground, exposure
and offscreen-render modules), the ray-cast LiDAR (:mod:`.lidar`, :mod:`.raycast`), the IMU
(:mod:`.imu`) and wheel odometry (:mod:`.odometry`). Noise is drawn from a Generator passed in."""

from marsscene._lazy import lazy_attributes

__all__ = ["ImuNoise", "Lidar", "MastCamera", "WheelOdometry", "measure_wheels"]

__getattr__ = lazy_attributes(__name__, {
    "ImuNoise": "marsscene.sensors.imu", "Lidar": "marsscene.sensors.lidar",
    "MastCamera": "marsscene.sensors.camera", "WheelOdometry": "marsscene.sensors.odometry",
    "measure_wheels": "marsscene.sensors.odometry",
})
