"""Sensor models of the rover: the RGB-D camera (:mod:`.camera` and its world, ground, exposure
and offscreen-render modules), the ray-cast LiDAR (:mod:`.lidar`, :mod:`.raycast`), the IMU
(:mod:`.imu`) and wheel odometry (:mod:`.odometry`). Noise is drawn from a Generator passed in."""
