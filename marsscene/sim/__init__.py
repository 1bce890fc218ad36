"""The MuJoCo simulation: the rover's MJCF (:mod:`.rover_model`), the simulator
(:mod:`.rover_sim`), routes (:mod:`.route`, :mod:`.corridor`), pure pursuit (:mod:`.pursuit`),
the drive loop (:mod:`.driver`) and missions (:mod:`.mission`). ``mujoco`` is imported on use."""
