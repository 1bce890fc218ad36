"""The MuJoCo simulation: the rover's MJCF (:mod:`.rover_model`), the simulator
(:mod:`.rover_sim`), the scene without the rover (:mod:`.world`), routes (:mod:`.route`,
:mod:`.corridor`), pure pursuit (:mod:`.pursuit`), the controller seam (:mod:`.control`), the
drive loop (:mod:`.session`, :mod:`.driver`) and its setup (:mod:`.mission`).
``mujoco`` is imported on first use of a name that simulates."""

from marsscene._lazy import lazy_attributes

__all__ = [
    "Controller",
    "DriveOptions",
    "DriveResult",
    "DriveSession",
    "Observation",
    "PurePursuit",
    "PursuitConfig",
    "Route",
    "RoverSim",
    "author_route",
    "drive_sim",
    "load_world",
    "prepare_drive",
]

__getattr__ = lazy_attributes(__name__, {
    "Controller": "marsscene.sim.control", "Observation": "marsscene.sim.control",
    "DriveOptions": "marsscene.sim.mission", "prepare_drive": "marsscene.sim.mission",
    "DriveResult": "marsscene.sim.driver", "drive_sim": "marsscene.sim.driver",
    "DriveSession": "marsscene.sim.session", "RoverSim": "marsscene.sim.rover_sim",
    "PurePursuit": "marsscene.sim.pursuit", "PursuitConfig": "marsscene.sim.pursuit",
    "Route": "marsscene.sim.route", "author_route": "marsscene.sim.route",
    "load_world": "marsscene.sim.world",
})
