"""Write the ROS 2 messages the Fast DDS peer uses as DDS IDL, in ROS 2's ``dds_`` form.

ROS 2 builds its Fast DDS types from IDL of this shape (``rosidl_generator_dds_idl``): module
``<pkg>::msg::dds_``, struct ``<Type>_``, ROS field types as IDL types. The definitions are the
ROS 2 Jazzy messages as ``rosbags`` ships them. Usage: ``python gen_idl.py OUT.idl``.
"""

from __future__ import annotations

import sys

from rosbags.typesys import Stores, get_typestore

ROOTS = ("sensor_msgs/msg/Imu", "nav_msgs/msg/Odometry", "sensor_msgs/msg/Image",
         "sensor_msgs/msg/PointCloud2", "geometry_msgs/msg/Twist", "rosgraph_msgs/msg/Clock")
BASE = {"bool": "boolean", "byte": "octet", "char": "uint8", "uint8": "uint8", "int8": "int8",
        "int16": "short", "uint16": "unsigned short", "int32": "long",
        "uint32": "unsigned long", "int64": "long long", "uint64": "unsigned long long",
        "float32": "float", "float64": "double"}
STORE = get_typestore(Stores.ROS2_JAZZY)


def scoped(msgtype: str) -> str:
    pkg, kind, name = msgtype.split("/")
    return f"{pkg}::{kind}::dds_::{name}_"


def idl_type(node: int, spec) -> tuple[str, str]:
    """(type, declarator suffix) of a field."""
    if node == 1:
        base, bound = spec
        if base == "string":
            return (f"string<{bound}>" if bound else "string"), ""
        return BASE[base], ""
    if node == 2:
        return scoped(spec), ""
    (sub_node, sub_spec), size = spec
    sub, _ = idl_type(sub_node, sub_spec)
    if node == 3:
        return sub, f"[{size}]"
    return (f"sequence<{sub}, {size}>" if size else f"sequence<{sub}>"), ""


def deps(msgtype: str, order: list[str]) -> None:
    for _, (node, spec) in STORE.fielddefs[msgtype][1]:
        inner = spec if node == 2 else (spec[0][1] if node in (3, 4) and spec[0][0] == 2
                                        else None)
        if inner is not None:
            deps(inner, order)
    if msgtype not in order:
        order.append(msgtype)


def main(out: str) -> None:
    order: list[str] = []
    for root in ROOTS:
        deps(root, order)
    lines = []
    for mt in order:
        pkg, kind, name = mt.split("/")
        fields = [f"      {t} {fname}{suffix};" for fname, (node, spec) in STORE.fielddefs[mt][1]
                  for t, suffix in [idl_type(node, spec)]]
        fields = fields or ["      uint8 structure_needs_at_least_one_member;"]
        lines += [f"module {pkg} {{ module {kind} {{ module dds_ {{",
                  f"    @final struct {name}_ {{", *fields, "    };", "}; }; };", ""]
    with open(out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1])
