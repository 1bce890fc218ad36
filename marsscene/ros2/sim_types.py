"""The ``simulation_interfaces`` types, from their own ``.msg`` / ``.srv`` / ``.action`` files.

The definitions travel with the package (``interfaces/``, with their licence) and are
registered into the session's ``rosbags`` typestore as ROS 2's ``rosidl`` makes them:

* a service ``pkg/srv/Foo`` is two messages, ``pkg/srv/Foo_Request`` and
  ``pkg/srv/Foo_Response`` (the parts before and after ``---``);
* an action ``pkg/action/Foo`` is ``Foo_Goal``, ``Foo_Result``, ``Foo_Feedback`` and the types
  of its services and topics: ``Foo_SendGoal`` (request ``goal_id`` + ``goal``, response
  ``accepted`` + ``stamp``), ``Foo_GetResult`` (request ``goal_id``, response ``status`` +
  ``result``) and ``Foo_FeedbackMessage`` (``goal_id`` + ``feedback``).

So each one's RIHS01 type hash (REP-2016) is ``rosbags``'s, computed as the topics' are, and its
DDS type is :func:`marsscene.ros2.dds.dds_type`'s.
"""

from __future__ import annotations

from importlib import resources
from typing import Any

__all__ = ["ACTION", "SERVICES", "register"]

#: The services served (the interface's names; ``--sim-namespace`` goes in front).
SERVICES = {
    "get_simulator_features": "GetSimulatorFeatures",
    "get_simulation_state": "GetSimulationState",
    "set_simulation_state": "SetSimulationState",
    "reset_simulation": "ResetSimulation",
    "step_simulation": "StepSimulation",
    "get_entities": "GetEntities",
    "get_entity_state": "GetEntityState",
    "set_entity_state": "SetEntityState",
    "get_entity_info": "GetEntityInfo",
    "get_spawnables": "GetSpawnables",
    "spawn_entity": "SpawnEntity",
    "delete_entity": "DeleteEntity",
}
#: The action served: its name and type.
ACTION = ("simulate_steps", "SimulateSteps")

_PKG = "simulation_interfaces"
_ACTION_PARTS = {
    "SendGoal_Request": "unique_identifier_msgs/UUID goal_id\n{a}_Goal goal\n",
    "SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp\n",
    "GetResult_Request": "unique_identifier_msgs/UUID goal_id\n",
    "GetResult_Response": "int8 status\n{a}_Result result\n",
    "FeedbackMessage": "unique_identifier_msgs/UUID goal_id\n{a}_Feedback feedback\n",
}


def _text(*parts: str) -> str:
    return resources.files("marsscene.ros2").joinpath("interfaces", *parts).read_text("utf-8")


def _split(text: str) -> list[str]:
    """The parts of a ``.srv`` / ``.action`` file between its ``---`` lines."""
    parts: list[str] = []
    cur: list[str] = []
    for line in text.splitlines():
        if line.strip() == "---":
            parts.append("\n".join(cur) + "\n")
            cur = []
        else:
            cur.append(line)
    return [*parts, "\n".join(cur) + "\n"]


def definitions() -> dict[str, str]:
    """Every message type the services and the action need: name -> ``.msg`` text."""
    root = resources.files("marsscene.ros2").joinpath("interfaces", _PKG)
    out = {f"{_PKG}/msg/{f.name[:-4]}": f.read_text("utf-8")
           for f in root.joinpath("msg").iterdir() if f.name.endswith(".msg")}
    for srv in [*SERVICES.values()]:
        req, rep = _split(_text(_PKG, "srv", f"{srv}.srv"))
        out[f"{_PKG}/srv/{srv}_Request"], out[f"{_PKG}/srv/{srv}_Response"] = req, rep
    req, rep = _split(_text("action_msgs", "srv", "CancelGoal.srv"))
    out["action_msgs/srv/CancelGoal_Request"], out["action_msgs/srv/CancelGoal_Response"] = \
        req, rep
    act = ACTION[1]
    goal, result, feedback = _split(_text(_PKG, "action", f"{act}.action"))
    base = f"{_PKG}/action/{act}"
    out.update({f"{base}_Goal": goal, f"{base}_Result": result, f"{base}_Feedback": feedback})
    for part, text in _ACTION_PARTS.items():
        out[f"{base}_{part}"] = text.format(a=act)
    return out


def register(store: Any) -> None:
    """Add the types to ``store`` (a ``rosbags`` typestore); a second call does nothing."""
    if f"{_PKG}/srv/StepSimulation_Request" in store.fielddefs:
        return
    from rosbags.typesys import get_types_from_msg

    # rosbags parses every definition as a message (``pkg/msg/Name``, references to the
    # package's types resolved there); the services' and the action's types are renamed after
    defs = definitions()
    real = {_as_msg(name): name for name in defs}
    types: dict[str, Any] = {}
    for name, text in defs.items():
        for key, (consts, fields) in get_types_from_msg(text, _as_msg(name)).items():
            types[real.get(key, key)] = (consts, [(f, _renamed(d, real)) for f, d in fields])
    store.register(types)


def _as_msg(name: str) -> str:
    pkg, _, tail = name.split("/")
    return f"{pkg}/msg/{tail}"


def _renamed(desc: Any, real: dict[str, str]) -> Any:
    node, spec = desc
    if node == 2:  # NAME
        return node, real.get(spec, spec)
    if node in (3, 4):  # ARRAY, SEQUENCE
        return node, (_renamed(spec[0], real), spec[1])
    return desc
