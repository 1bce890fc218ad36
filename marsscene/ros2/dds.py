"""ROS 2 on DDS without ROS: Eclipse Cyclone DDS (``cyclonedds``) as ROS 2's middlewares use it.

The only importer of ``cyclonedds``. What makes a DDS endpoint a ROS 2 one:

* topic ``rt/<name>`` (``/rover/odom`` -> ``rt/rover/odom``); type
  ``<pkg>::msg::dds_::<Type>_``; ``@final`` structs without a key, sent as plain
  (XCDR1, little-endian) CDR;
* the types here are made from the ``rosbags`` typestore's definitions of the ROS 2 messages
  (:func:`dds_type`), so they carry the XTypes type information of those IDL structs; the
  payloads are **not** serialised by ``cyclonedds-python`` (whose pure-Python path for large
  sequences costs tens of milliseconds per image): :class:`RawWriter` hands the ``rosbags``
  CDR bytes, the bag's very bytes, to Cyclone's C writer, and :class:`RawReader` takes raw
  samples for ``rosbags`` to decode;
* QoS as ROS 2 sets it (:data:`QOS`, built from the topic table's profiles), participant
  USER_DATA ``enclave=/;`` and the ``ros_discovery_info`` topic (:mod:`.discovery`);
* each endpoint's USER_DATA ``typehash=RIHS01_...;``: its type's description hash (REP-2016,
  computed by ``rosbags``), which Jazzy's graph reports (``ros2 topic info --verbose``; without
  it a Jazzy node shows ``INVALID``) and which Fast DDS's and Cyclone's ROS 2 middlewares
  put on theirs.

Localhost mode (:func:`cyclone_config`) binds to 127.0.0.1, turns multicast off and discovers
peers by unicast on 127.0.0.1 only; a ``CYCLONEDDS_URI`` of the user's comes first, ours last
(later settings win), and a user's own choice of the loopback interface is kept.
"""

from __future__ import annotations

import os
import re
import threading
import warnings
from pathlib import Path
from typing import Any

from marsscene.errors import MarsSceneWarning, RuntimeSimError, missing_dependency
from marsscene.runs.export.topic_table import QOS_PROFILES, QosProfile

__all__ = ["QOS", "Participant", "RawReader", "RawWriter", "cyclone_config", "dds_topic",
           "dds_type", "user_interfaces"]

try:
    from cyclonedds import qos as _qos
    from cyclonedds._clayer import ddspy_take, ddspy_write
    from cyclonedds.core import DDSException, InstanceState, Listener, SampleState, ViewState
    from cyclonedds.domain import Domain, DomainParticipant
    from cyclonedds.idl import annotations as _ann
    from cyclonedds.idl import make_idl_struct
    from cyclonedds.idl import types as _types
    from cyclonedds.pub import DataWriter
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
except ImportError:  # pragma: no cover - exercised without the extra only
    raise missing_dependency("cyclonedds", "ros2") from None

_P = _qos.Policy
_t: Any = _types  # its generic aliases (array[...], sequence[...]) are not typed


def _qos_of(p: QosProfile) -> Any:
    rel = _P.Reliability.Reliable(max_blocking_time=100_000_000) if p.reliable \
        else _P.Reliability.BestEffort
    dur = _P.Durability.TransientLocal if p.transient_local else _P.Durability.Volatile
    return _qos.Qos(rel, dur, _P.History.KeepLast(p.depth))


#: Cyclone DDS QoS of each named profile of :data:`~marsscene.runs.export.topic_table.
#: QOS_PROFILES` (ROS 2's conventions).
QOS: dict[str, Any] = {name: _qos_of(p) for name, p in QOS_PROFILES.items()}

_BASE = {"bool": bool, "int8": _t.int8, "uint8": _t.uint8, "byte": _t.byte, "char": _t.uint8,
         "int16": _t.int16, "uint16": _t.uint16, "int32": _t.int32, "uint32": _t.uint32,
         "int64": _t.int64, "uint64": _t.uint64, "float32": _t.float32,
         "float64": _t.float64}
_TYPES: dict[tuple[int, str, bool], Any] = {}
_DOMAINS: dict[int, tuple[str, Any]] = {}


def dds_type(store: Any, msgtype: str, request_header: bool = False) -> Any:
    """The Cyclone DDS type of a ROS 2 message (``sensor_msgs/msg/Imu`` ->
    ``sensor_msgs::msg::dds_::Imu_``), built from ``store``'s (a ``rosbags`` typestore)
    definition: ``@final``, no key, an empty message holding ``uint8
    structure_needs_at_least_one_member`` as ROS 2's IDL does. ``request_header``: a service
    request's or reply's type as ``rmw_cyclonedds`` sends it, the request's id first (the
    client's ``uint64`` writer handle and the ``int64`` sequence number)."""
    key = (id(store), msgtype, request_header)
    if key in _TYPES:
        return _TYPES[key]
    _, fields = store.fielddefs[msgtype]
    pkg, kind, name = msgtype.split("/")
    members = {fname: _field(store, node, spec) for fname, (node, spec) in fields}
    if not members:
        members = {"structure_needs_at_least_one_member": _t.uint8}
    if request_header:
        members = {"client_guid": _t.uint64, "sequence_number": _t.int64, **members}
    cls = make_idl_struct(f"{name}_", f"{pkg}::{kind}::dds_::{name}_", members)
    _TYPES[key] = _ann.final(cls)
    return _TYPES[key]


def _field(store: Any, node: int, spec: Any) -> Any:
    if node == 1:  # BASE
        base, bound = spec
        if base == "string":
            return _t.bounded_str[bound] if bound else str
        return _BASE[base]
    if node == 2:  # NAME
        return dds_type(store, spec)
    (sub_node, sub_spec), size = spec
    sub = _field(store, sub_node, sub_spec)
    if node == 3:  # ARRAY
        return _t.array[sub, size]
    return _t.sequence[sub, size] if size else _t.sequence[sub]


#: Interface selections of a Cyclone configuration: ``<NetworkInterface name=... address=...>``
#: (Cyclone 0.10 and later) or ``<NetworkInterfaceAddress>`` (older).
_IFACE = re.compile(r"<NetworkInterface\b([^>]*)>|<NetworkInterfaceAddress>([^<]*)<", re.I)
_LOOPBACK = ("lo", "lo0", "loopback", "localhost", "::1")


def user_interfaces(uri: str) -> list[str] | None:
    """The network interfaces a ``CYCLONEDDS_URI`` selects (its inline XML and the files it
    names; names or addresses, empty: none selected), None where a file cannot be read."""
    text = []
    for part in (p.strip() for p in uri.split(",") if p.strip()):
        if part.startswith("<"):
            text.append(part)
            continue
        path = Path(part[len("file://"):] if part.startswith("file://") else part)
        try:
            text.append(path.read_text(encoding="utf-8"))
        except OSError:
            return None
    found = []
    for attrs, old in _IFACE.findall(" ".join(text)):
        if old:
            found.append(old.strip())
        for key in ("name", "address"):
            m = re.search(rf'{key}\s*=\s*"([^"]*)"', attrs)
            if m:
                found.append(m.group(1))
    return found


def _loopback(iface: str) -> bool:
    return iface.lower() in _LOOPBACK or iface.startswith("127.")


def cyclone_config(localhost: bool, env: dict[str, str] | None = None) -> str | None:
    """The configuration the participant's domain is created with (None: Cyclone's own,
    i.e. ``CYCLONEDDS_URI`` or its defaults).

    Localhost: the 127.0.0.1 interface, no multicast, unicast discovery of participants 0..31
    on 127.0.0.1 and 64 kB UDP messages (loopback's MTU), after a user's ``CYCLONEDDS_URI``
    (later settings win). Where the user's configuration selects the loopback interface itself
    (``<NetworkInterface name="lo"/>``, as many ROS 2 set-ups do), ours selects none: Cyclone
    refuses an interface selected twice. Where it selects another interface, the two cannot
    both hold: localhost mode was asked for (``--localhost``, ``ROS_LOCALHOST_ONLY``,
    ``ROS_AUTOMATIC_DISCOVERY_RANGE``), so it wins, the user's URI is left out and a
    :class:`~marsscene.errors.MarsSceneWarning` says so.
    """
    env = dict(os.environ) if env is None else env
    user = env.get("CYCLONEDDS_URI", "").strip()
    if not localhost:
        return None
    general = ("<AllowMulticast>false</AllowMulticast><MaxMessageSize>65000B</MaxMessageSize>"
               "</General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
               "<MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
               '<Peers><Peer Address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>')
    ours = ('<CycloneDDS><Domain Id="any"><General><Interfaces>'
            '<NetworkInterface address="127.0.0.1"/></Interfaces>' + general)
    if not user:
        return ours
    chosen = user_interfaces(user) or []
    if chosen and all(_loopback(i) for i in chosen):
        return f"{user},<CycloneDDS><Domain Id=\"any\"><General>{general}"
    if chosen:
        warnings.warn(f"CYCLONEDDS_URI selects {', '.join(chosen)}; localhost mode keeps DDS on "
                      "127.0.0.1, so that URI is not used (drop --localhost, "
                      "ROS_LOCALHOST_ONLY and ROS_AUTOMATIC_DISCOVERY_RANGE to use it)",
                      MarsSceneWarning, stacklevel=2)
        return ours
    return f"{user},{ours}"


class Participant:
    """A DDS domain participant that hosts one ROS 2 node's endpoints.

    Parameters
    ----------
    domain_id : int
    localhost : bool
        Loopback only (:func:`cyclone_config`).
    """

    def __init__(self, domain_id: int, localhost: bool) -> None:
        config = cyclone_config(localhost)
        try:
            if config is not None and domain_id not in _DOMAINS:  # one configuration a process
                _DOMAINS[domain_id] = (config, Domain(domain_id, config))
            if config is not None and _DOMAINS[domain_id][0] != config:
                raise RuntimeSimError(f"DDS domain {domain_id} is already configured "
                                      "differently in this process")
            self.dp = DomainParticipant(domain_id, qos=_qos.Qos(_P.Userdata(b"enclave=/;")))
        except DDSException as err:  # e.g. a bad CYCLONEDDS_URI, no usable interface
            uri = os.environ.get("CYCLONEDDS_URI", "")
            raise RuntimeSimError(f"cannot start Cyclone DDS on domain {domain_id}: {err}"
                                  + (f" (CYCLONEDDS_URI={uri!r})" if uri else "")) from None
        self.writers: list[RawWriter] = []
        self.readers: list[RawReader] = []

    @property
    def guid(self) -> bytes:
        return bytes(self.dp.guid.bytes)

    def writer(self, store: Any, topic: str, msgtype: str, qos: str, *,
               ros_topic: bool = True, user_data: str = "") -> RawWriter:
        """A writer of ``topic`` (a ROS topic, ``rt/`` on DDS, unless ``ros_topic`` is false)
        with the QoS profile named ``qos`` (:data:`QOS`); ``user_data`` goes before the type
        hash in the endpoint's USER_DATA (a service's reply writer: its header, its
        ``serviceid=``)."""
        w = RawWriter(self, dds_type(store, msgtype, not ros_topic and bool(user_data)),
                      dds_topic(topic) if ros_topic else topic,
                      QOS[qos] + _type_hash(store, msgtype, user_data))
        w.topic = topic
        self.writers.append(w)
        return w

    def reader(self, store: Any, topic: str, msgtype: str, qos: str, *,
               ros_topic: bool = True, user_data: str = "") -> RawReader:
        """A reader of the ROS topic ``topic`` with the QoS profile named ``qos`` (``ros_topic``
        and ``user_data`` as for :meth:`writer`: a service's request reader)."""
        r = RawReader(self, dds_type(store, msgtype, not ros_topic and bool(user_data)),
                      dds_topic(topic) if ros_topic else topic,
                      QOS[qos] + _type_hash(store, msgtype, user_data))
        r.topic = topic
        self.readers.append(r)
        return r

    def close(self) -> None:
        """Delete the participant and everything in it (peers see the endpoints go)."""
        self.dp.__del__()  # cyclonedds deletes an entity (and its children) this way


def _type_hash(store: Any, msgtype: str, before: str = "") -> Any:
    """The endpoint USER_DATA that carries the type's RIHS01 hash, as ROS 2 Jazzy writes it."""
    return _qos.Qos(_P.Userdata(f"{before}typehash={store.hash_rihs01(msgtype)};".encode()))


def dds_topic(topic: str) -> str:
    """``/rover/odom`` -> ``rt/rover/odom`` (ROS 2's topic prefix on DDS)."""
    return "rt" + topic if topic.startswith("/") else "rt/" + topic


class RawWriter:
    """A DDS writer of already serialised CDR messages (the 4-byte encapsulation header first).

    ``subscribers`` counts the matched readers; ``write`` pads to a multiple of 4 bytes as ROS
    2's middlewares do and hands the bytes to Cyclone's C writer.
    """

    def __init__(self, part: Participant, dtype: Any, dds_name: str, qos: Any) -> None:
        self.topic = dds_name
        self.subscribers = 0
        self._lock = threading.Lock()
        self.writer = DataWriter(part.dp, Topic(part.dp, dds_name, dtype), qos,
                                 listener=Listener(on_publication_matched=self._matched))

    def _matched(self, _writer: Any, status: Any) -> None:
        with self._lock:
            self.subscribers = int(status.current_count)

    @property
    def guid(self) -> bytes:
        return bytes(self.writer.guid.bytes)

    def write(self, cdr: bytes | memoryview, timestamp_ns: int | None = None) -> None:
        data = bytes(cdr)
        pad = -len(data) % 4
        if pad:
            data += b"\0" * pad
        ret = ddspy_write(self.writer._ref, data)  # the C writer: no Python CDR
        if ret < 0:
            raise RuntimeError(f"DDS write on {self.topic} failed ({ret})")


class RawReader:
    """A DDS reader whose samples come back as CDR bytes (decode with ``rosbags``)."""

    def __init__(self, part: Participant, dtype: Any, dds_name: str, qos: Any) -> None:
        self.topic = dds_name
        self.reader = DataReader(part.dp, Topic(part.dp, dds_name, dtype), qos)
        self.mask = SampleState.Any | ViewState.Any | InstanceState.Any

    @property
    def guid(self) -> bytes:
        return bytes(self.reader.guid.bytes)

    def take(self, n: int = 64) -> list[bytes]:
        """Up to ``n`` waiting samples, oldest first (empty when none)."""
        got = ddspy_take(self.reader._ref, self.mask, n)
        if isinstance(got, int):
            raise RuntimeError(f"DDS take on {self.topic} failed ({got})")
        return [bytes(data) for data, info in got if info.valid_data]
