"""A client that is not on ``rmw_cyclonedds`` is told, once, in one line: its request writer
carries no ``clientid=`` (here a plain Cyclone DDS writer, as a Fast DDS client's is)."""

from __future__ import annotations

import logging
import time

from cyclonedds.pub import DataWriter
from cyclonedds.qos import Policy, Qos
from cyclonedds.topic import Topic

from marsscene.ros2 import dds
from marsscene.ros2.services import Service
from marsscene.ros2.sim_types import register
from marsscene.runs.export.bag_messages import MessageBuilder

SRV = "simulation_interfaces/srv/GetSimulationState"


def test_a_foreign_client_gets_the_hint_once(caplog):
    from marsscene.ros2 import services

    services._said_other[0] = False
    store = MessageBuilder().store
    register(store)
    part = dds.Participant(212, localhost=True)
    try:
        srv = Service(part, store, "/get_simulation_state", SRV, lambda req, reply: None)
        dtype = dds.dds_type(store, f"{SRV}_Request", True)
        writers = [DataWriter(part.dp, Topic(part.dp, "rq/get_simulation_stateRequest", dtype),
                              Qos(Policy.Reliability.Reliable(10**8)))
                   for _ in range(2)]
        with caplog.at_level(logging.WARNING, logger="marsscene"):
            t0 = time.monotonic()
            while not caplog.records and time.monotonic() - t0 < 5.0:
                srv.poll()
                time.sleep(0.01)
            for _ in range(20):
                srv.poll()
    finally:
        del writers
        part.close()
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "\n" not in lines[0]
    assert "RMW_IMPLEMENTATION=rmw_cyclonedds_cpp" in lines[0]
    assert "/marsscene/reset" in lines[0] and "/get_simulation_state" in lines[0]
