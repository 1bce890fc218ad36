"""ROS 2 services in ``rmw_cyclonedds``'s request/reply form, on the server's participant.

What ``rmw_cyclonedds_cpp`` (``rmw_node.cpp``, ``Serialization.cpp``) puts on the wire, and so
what a ROS 2 client on it sends and waits for:

* the request topic ``rq/<service>Request`` (``/get_entity_state`` ->
  ``rq/get_entity_stateRequest``), type ``<pkg>::srv::dds_::<Srv>_Request_``; the reply topic
  ``rr/<service>Reply``, type ``<pkg>::srv::dds_::<Srv>_Response_``; QoS ROS 2's services
  default (reliable, volatile, keep last 10);
* each sample: the 4-byte CDR encapsulation header, then the request id, the client's request
  writer handle (``uint64``) and a sequence number (``int64``), then the request or reply as
  plain CDR (the 16 bytes keep its alignment); a reply carries its request's id, and the
  client takes only replies with its own handle;
* USER_DATA ``serviceid=<id>;`` on the service's reader and writer (a client waits for a pair
  with the same id: ``wait_for_service``) and ``clientid=<id>;`` on a client's, before the
  type hash of the request or reply type.

A ROS 2 client on another middleware (Fast DDS, Jazzy's default) matches the topics but keeps
the request id elsewhere (RTPS's related-sample identity), so it waits for ever; its request
writer carries no ``clientid=``, and the server says, once, what to do
(:data:`OTHER_MIDDLEWARE`).
"""

from __future__ import annotations

import logging
import struct
import time
from collections.abc import Callable
from typing import Any

from marsscene.ros2.dds import Participant

__all__ = ["OTHER_MIDDLEWARE", "Service"]

log = logging.getLogger("marsscene")

#: The one log line for a client on another middleware.
OTHER_MIDDLEWARE = ("a ROS 2 client on %s calls %s: marsscene's services answer rmw_cyclonedds "
                    "clients only (start it with RMW_IMPLEMENTATION=rmw_cyclonedds_cpp); "
                    "the topics /marsscene/reset, /marsscene/teleport and --pace lockstep's "
                    "/cmd_vel do the same job on any middleware")
_VENDORS = {b"\x01\x0f": "Fast DDS"}  # the vendor id that opens a participant's GUID
_ID = struct.Struct("<Qq")
_said_other = [False]  # the hint is said once a process
_ids = [0]


class Service:
    """One service: ``handle(request) -> reply`` for each request taken by :meth:`poll`.

    Parameters
    ----------
    part : Participant
    store : rosbags typestore
        Holding ``<srvtype>_Request`` and ``<srvtype>_Response``.
    name : str
        The service (``/get_simulation_state``).
    srvtype : str
        ``simulation_interfaces/srv/GetSimulationState``.
    handle : callable
        ``handle(request, reply)``: answer now by returning a reply message, or later
        (``None``): :meth:`reply` with the ``reply`` function it was given.
    """

    def __init__(self, part: Participant, store: Any, name: str, srvtype: str,
                 handle: Callable[[Any, Callable[[Any], None]], Any]) -> None:
        _ids[0] += 1
        sid = ".".join(f"{b:x}" for b in part.guid[:12] + _ids[0].to_bytes(4, "big"))
        self.name, self.store, self.handle = name, store, handle
        self.req_type, self.rep_type = f"{srvtype}_Request", f"{srvtype}_Response"
        ud = f"serviceid={sid};"
        self.reader = part.reader(store, f"rq{name}Request", self.req_type, "default",
                                  ros_topic=False, user_data=ud)
        self.writer = part.writer(store, f"rr{name}Reply", self.rep_type, "default",
                                  ros_topic=False, user_data=ud)
        self._checked: set[int] = set()
        self._checked_at = -1.0  # monotonic time of the last look at the matched clients

    def poll(self) -> int:
        """Answer the requests waiting; the number taken."""
        self._check_clients()
        raws = self.reader.take()
        for raw in raws:
            if len(raw) < 4 + _ID.size:
                continue
            rid = raw[4:4 + _ID.size]
            req = self.store.deserialize_cdr(raw[:4] + raw[4 + _ID.size:], self.req_type)

            def reply(msg: Any, rid: bytes = rid) -> None:
                self._send(rid, msg)

            out = self.handle(req, reply)
            if out is not None:
                reply(out)
        return len(raws)

    def _send(self, rid: bytes, msg: Any) -> None:
        cdr = bytes(self.store.serialize_cdr(msg, self.rep_type))
        t0 = time.monotonic()  # the client's reply reader may match just after its request
        while not self.writer.subscribers and time.monotonic() - t0 < 0.1:
            time.sleep(0.002)
        self.writer.write(cdr[:4] + rid + cdr[4:])

    def _check_clients(self) -> None:
        """Say once when a client's request writer is not an ``rmw_cyclonedds`` one."""
        now = time.monotonic()
        if _said_other[0] or now - self._checked_at < 0.25:  # a look four times a second
            return
        self._checked_at = now
        dr = self.reader.reader
        for handle in dr.get_matched_publications():
            if handle in self._checked:
                continue
            self._checked.add(handle)
            try:
                ep = dr.get_matched_publication_data(handle)
            except Exception:  # it went meanwhile
                continue
            if ep is None:
                continue
            user = ep.qos[_userdata()] if _userdata() in ep.qos else None
            data = bytes(user.data) if user is not None else b""
            if b"clientid=" not in data:
                vendor = _VENDORS.get(ep.participant_key.bytes[:2], "another middleware")
                log.warning(OTHER_MIDDLEWARE, vendor, self.name)
                _said_other[0] = True
                return


def _userdata() -> Any:
    from cyclonedds.qos import Policy

    return Policy.Userdata
