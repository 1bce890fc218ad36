"""The Perseverance-class rover as MJCF text, written from the link table of
:mod:`marsscene.rover.links` (the USD rover reads the same table). Numbers and sources:
:doc:`/runtime`.
"""

from __future__ import annotations

from marsscene._format import fmt
from marsscene.export.mjcf.common import TORSION_ROLL_FRICTION
from marsscene.rover.config import CameraConfig, RoverConfig
from marsscene.rover.geometry import DRIVE_JOINTS, STEER_JOINTS, navcam_mount, sensor_mounts
from marsscene.rover.links import STEER_ACT_KV_NM_S, Joint, Link, Shape, rover_links

__all__ = ["rover_mjcf"]

_Y_AXIS_QUAT = "0.707107 0.707107 0 0"  # a cylinder's z turned onto y
_AXES = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}


def _joint(j: Joint) -> str:
    lim = f' range="{fmt(j.range_rad)}"' if j.range_rad is not None else ""
    arm = f' armature="{fmt(j.armature_kg_m2)}"' if j.armature_kg_m2 > 0 else ""
    return (f'<joint name="{j.name}" type="hinge" axis="{_AXES[j.axis]}"{lim}{arm} '
            f'damping="{fmt(j.damping_nm_s)}"/>')


def _geom(s: Shape) -> str:
    cls = ("wheel" if s.name.startswith("wheel") else "body") if s.collides else "visual"
    out = f'<geom name="{s.name}" ' if s.name else "<geom "
    out += f'class="{cls}" type="{s.kind}" '
    if s.kind == "capsule":
        out += f'fromto="{fmt(s.fromto_m)}" size="{fmt(s.size_m)}"'
    else:
        out += f'size="{fmt(s.size_m)}"'
        if s.kind in ("box", "cylinder") and s.axis == "z":
            out += f' pos="{fmt(s.pos_m)}"'
        elif s.axis == "y":
            out += f' quat="{_Y_AXIS_QUAT}"'
    if s.rgba is not None:
        out += f' rgba="{fmt(s.rgba)}"'
    return out + f' mass="{fmt(s.mass_kg)}"/>'


def _body(link: Link, children: dict[str, list[Link]], extra: str = "") -> str:
    inner = (_joint(link.joint) if link.joint is not None else "") + "".join(
        _geom(s) for s in link.shapes) + extra
    inner += "".join(_body(c, children) for c in children.get(link.name, []))
    return f'<body name="{link.name}" pos="{fmt(link.pos_m)}">{inner}</body>'


def rover_mjcf(cfg: RoverConfig | None = None, *, camera_fovy_deg: float | None = None) -> str:
    """MJCF text of the rover: root body ``base_link`` (free joint), actuators and sensors.

    Collision: wheels and chassis collide with the terrain and rocks (contype 2 / conaffinity 1,
    so rover parts never collide with each other); links are visual only (group 2).
    ``camera_fovy_deg`` is the navcam's vertical field of view (default: ``CameraConfig``'s).
    """
    cfg = cfg if cfg is not None else RoverConfig()
    if camera_fovy_deg is None:
        camera_fovy_deg = CameraConfig().fovy_deg
    links = rover_links(cfg)
    children: dict[str, list[Link]] = {}
    for link in links[1:]:
        assert link.parent is not None
        children.setdefault(link.parent, []).append(link)
    cam_pos, cam_xyaxes = navcam_mount(cfg)
    mu = fmt((cfg.friction, *TORSION_ROLL_FRICTION))
    sensors = (
        '<site name="imu" pos="0 0 0" size="0.02"/>'
        f'<site name="lidar" pos="{fmt(sensor_mounts(cfg)["lidar"][0])}" '
        'size="0.03"/>'
        f'<camera name="navcam" pos="{fmt(cam_pos)}" xyaxes="{fmt(cam_xyaxes)}" '
        f'fovy="{fmt(camera_fovy_deg)}"/>'
    )
    base = links[0]
    body = _body(base, children, sensors).replace(
        f'<body name="base_link" pos="{fmt(base.pos_m)}">',
        f'<body name="base_link" pos="{fmt(base.pos_m)}"><freejoint name="root"/>', 1)
    lim, tq = cfg.wheel_speed_limit_rad_s, cfg.drive_torque_limit_nm
    acts = "".join(
        f'<velocity name="{j}" joint="{j}" kv="{fmt(cfg.drive_kv_nm_s)}" '
        f'ctrlrange="{fmt((-lim, lim))}" forcerange="{fmt((-tq, tq))}"/>'
        for j in DRIVE_JOINTS
    ) + "".join(
        f'<position name="{j}" joint="{j}" kp="{fmt(cfg.steer_kp_nm)}" '
        f'kv="{fmt(STEER_ACT_KV_NM_S)}" '
        f'ctrlrange="{fmt((-cfg.steer_limit_rad, cfg.steer_limit_rad))}" '
        f'forcerange="{fmt((-cfg.steer_torque_limit_nm, cfg.steer_torque_limit_nm))}"/>'
        for j in STEER_JOINTS
    )
    return (
        '<mujoco model="rover">\n'
        '  <compiler angle="radian" autolimits="true"/>\n'
        "  <default>\n"
        f'    <default class="wheel"><geom contype="2" conaffinity="1" condim="3" group="2" '
        f'friction="{mu}" rgba="0.6 0.6 0.6 1"/></default>\n'
        '    <default class="body"><geom contype="2" conaffinity="1" condim="3" group="2" '
        'rgba="0.85 0.85 0.8 1"/></default>\n'
        '    <default class="visual"><geom contype="0" conaffinity="0" group="2" '
        'rgba="0.4 0.4 0.4 1"/></default>\n'
        "  </default>\n"
        f"  <worldbody>{body}</worldbody>\n"
        '  <equality><joint name="differential" joint1="rocker_left" joint2="rocker_right" '
        'polycoef="0 -1 0 0 0"/></equality>\n'
        f"  <actuator>{acts}</actuator>\n"
        '  <sensor><accelerometer name="imu_accel" site="imu"/><gyro name="imu_gyro" site="imu"/>'
        "</sensor>\n"
        "</mujoco>\n"
    )
