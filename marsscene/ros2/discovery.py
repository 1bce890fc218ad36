"""``ros_discovery_info``: how a DDS participant tells ROS 2 tools which nodes it hosts.

ROS 2's graph (``ros2 node list``, ``ros2 node info``) comes from ``rmw_dds_common``'s
``ParticipantEntitiesInfo`` messages on the DDS topic ``ros_discovery_info`` (reliable,
transient local, depth 1): the participant's GID and, per node, its name, namespace and the GIDs
of its readers and writers. A GID is the entity's 16-byte DDS GUID (Humble pads it to 24
bytes). Topics are visible in ``ros2 topic list`` from DDS discovery alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from marsscene.ros2.dds import Participant, RawWriter

__all__ = ["publish_discovery_info"]

_TOPIC = "ros_discovery_info"
_TYPE = "rmw_dds_common/msg/ParticipantEntitiesInfo"


def _gid(store: Any, guid: bytes) -> Any:
    (_, (_, (_, size))), = store.fielddefs["rmw_dds_common/msg/Gid"][1]  # char[16] or [24]
    data = np.zeros(size, dtype=np.uint8)
    data[:16] = np.frombuffer(guid, dtype=np.uint8)
    return store.types["rmw_dds_common/msg/Gid"](data=data)


def publish_discovery_info(part: Participant, store: Any, node_name: str,
                           namespace: str = "/") -> RawWriter:
    """Announce node ``namespace/node_name`` with every reader and writer of ``part``.

    Returns the writer (keep it: the message is transient local, served to late joiners
    while the writer lives).
    """
    writer = part.writer(store, _TOPIC, _TYPE, "latched", ros_topic=False)
    node = store.types["rmw_dds_common/msg/NodeEntitiesInfo"](
        node_namespace=namespace, node_name=node_name,
        reader_gid_seq=[_gid(store, r.guid) for r in part.readers],
        writer_gid_seq=[_gid(store, w.guid) for w in part.writers if w is not writer])
    msg = store.types[_TYPE](gid=_gid(store, part.guid), node_entities_info_seq=[node])
    writer.write(store.serialize_cdr(msg, _TYPE))
    return writer
