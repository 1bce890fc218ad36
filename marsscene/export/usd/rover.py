"""The rover as a USD physics asset (``assets/rover.usda``), and its place in a scene.

Written from the link table both rover writers read (:mod:`marsscene.rover.links`), so the
USD rover is the MJCF rover: same links, masses, inertias, wheel size, joint limits and drive
gains. Layout (default prim ``/Rover``; every link prim is a child of ``/Rover`` posed for the
zero configuration, wheels on the ground at z = 0)::

    /Rover                      Xform, kind component, ArticulationRootAPI
      Looks/WheelPhysics        physics materials: wheels (RoverConfig.friction), body (1.0)
      Collision/RoverParts      CollisionGroup filtering itself: rover parts never collide
      base_link                 RigidBodyAPI, MassAPI; chassis Cube (collider), mast, and
        navcam                  Camera (the runtime's mast camera), lidar / imu frames
      rocker_*, bogie_*         RigidBodyAPI, MassAPI, visual Capsule
      steer_**, wheel_**        RigidBodyAPI, MassAPI; wheel Cylinder colliders (axis Y)
      diff_bar, diff_rod_*      the differential (bar on the deck, two rods)
      Joints/                   RevoluteJoints (limits in degrees); wheels: DriveAPI:angular
                                velocity drives; corner steering: position drives; rockers,
                                bogies and the bar free; rod joints SphericalJoint, the two
                                rod-to-rocker joints excludeFromArticulation (loop closures)

Drive gains follow ``UsdPhysics.DriveAPI``'s angular units (per degree): wheel damping
``drive_kv_nm_s * pi / 180`` N m s/deg, stiffness 0, ``maxForce`` the torque limit;
steering stiffness ``steer_kp_nm * pi / 180`` N m/deg and damping of the servo plus the MJCF
joint damping. UsdPhysics has no passive joint damping or armature: the MJCF's 20 N m s/rad on
rockers and bogies and its rotor armatures are not carried (:doc:`/usd_rover`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics, Vt

from marsscene.export.usd.physics import (
    PhysicsMaterial,
    author_physics_material,
    bind_physics_material,
)
from marsscene.export.usd.stage import WORLD, create_asset_stage, set_kind
from marsscene.rover.config import CameraConfig, RoverConfig
from marsscene.rover.geometry import sensor_mounts
from marsscene.rover.links import (
    STEER_ACT_KV_NM_S,
    Link,
    Shape,
    link_inertia,
    loop_joints,
    rover_links,
)

__all__ = ["ROVER_ASSET", "ROVER_PATH", "author_rover", "rover_stage", "usd_links"]

ROVER_ASSET = "assets/rover.usda"
ROVER_PATH = f"{WORLD}/Rover"
_AXIS = {"x": "X", "y": "Y", "z": "Z"}
_COLOUR = {"wheel": (0.6, 0.6, 0.6), "body": (0.85, 0.85, 0.8), "visual": (0.4, 0.4, 0.4)}
#: MuJoCo's default sliding friction, which the MJCF chassis keeps.
BODY_FRICTION = 1.0


def usd_links(cfg: RoverConfig) -> tuple[tuple[Link, tuple[float, float, float]], ...]:
    """The USD rover's links with their origins in the ``/Rover`` frame.

    Massless joint-less MJCF frames (the middle wheels' hubs) are folded into their child:
    a link's parent and ``pos_m`` then refer to the hub's parent.
    """
    links = rover_links(cfg, differential=True)
    by_name = {link.name: link for link in links}
    origin: dict[str, tuple[float, float, float]] = {}
    out = []
    for link in links:
        parent, pos = link.parent, np.asarray(link.pos_m, dtype=np.float64)
        hub = by_name.get(parent) if parent is not None else None
        if hub is not None and hub.joint is None and not hub.shapes and hub.parent is not None:
            parent, pos = hub.parent, pos + np.asarray(hub.pos_m)
        if link.joint is None and not link.shapes and link.parent is not None:
            origin[link.name] = tuple(np.asarray(origin[link.parent]) + link.pos_m)
            continue  # a hub
        base = np.asarray(origin[parent]) if parent is not None else np.zeros(3)
        origin[link.name] = tuple((base + pos).tolist())
        moved = Link(link.name, parent, tuple(pos.tolist()), link.joint, link.shapes)
        out.append((moved, origin[link.name]))
    return tuple(out)


def _extent(gprim: Any) -> None:
    ext = UsdGeom.Boundable.ComputeExtentFromPlugins(gprim, Usd.TimeCode.Default())
    gprim.CreateExtentAttr(ext)


def _shape(stage: Any, path: Sdf.Path, s: Shape, materials: dict[str, Any]) -> None:
    """One gprim: a collider (CollisionAPI, physics material) or a visual shape."""
    xf: Any
    if s.kind == "box":
        xf = UsdGeom.Cube.Define(stage, path)
        xf.CreateSizeAttr(2.0)
        xf.AddTranslateOp().Set(Gf.Vec3d(*s.pos_m))
        xf.AddScaleOp().Set(Gf.Vec3f(*s.size_m))
    elif s.kind == "sphere":
        xf = UsdGeom.Sphere.Define(stage, path)
        xf.CreateRadiusAttr(s.size_m[0])
        xf.AddTranslateOp().Set(Gf.Vec3d(*s.pos_m))
    elif s.kind == "cylinder":
        xf = UsdGeom.Cylinder.Define(stage, path)
        xf.CreateRadiusAttr(s.size_m[0])
        xf.CreateHeightAttr(2.0 * s.size_m[1])
        xf.CreateAxisAttr(_AXIS[s.axis])
        xf.AddTranslateOp().Set(Gf.Vec3d(*s.pos_m))
    else:  # capsule between two points: axis X turned onto the segment
        a, b = np.asarray(s.fromto_m[:3]), np.asarray(s.fromto_m[3:])
        u = (b - a) / np.linalg.norm(b - a)
        xf = UsdGeom.Capsule.Define(stage, path)
        xf.CreateRadiusAttr(s.size_m[0])
        xf.CreateHeightAttr(float(np.linalg.norm(b - a)))
        xf.CreateAxisAttr("X")
        xf.AddTranslateOp().Set(Gf.Vec3d(*((a + b) / 2).tolist()))
        rot = Gf.Rotation(Gf.Vec3d(1.0, 0.0, 0.0), Gf.Vec3d(*u.tolist())).GetQuat()
        xf.AddOrientOp().Set(Gf.Quatf(rot))
    cls = ("wheel" if s.name.startswith("wheel") else "body") if s.collides else "visual"
    rgb = s.rgba[:3] if s.rgba is not None else _COLOUR[cls]
    xf.CreateDisplayColorAttr(Vt.Vec3fArray([Gf.Vec3f(*rgb)]))
    if s.rgba is not None and s.rgba[3] == 0.0:
        xf.CreatePurposeAttr(UsdGeom.Tokens.guide)  # an invisible collider
    _extent(xf)
    if s.collides:
        UsdPhysics.CollisionAPI.Apply(xf.GetPrim())
        bind_physics_material(xf.GetPrim(), materials[cls])


def _principal_axes(tensor: Any) -> tuple[Any, Any]:
    """Eigenvalues and a right-handed eigenvector basis (columns) of an inertia tensor; within
    a degenerate pair (an axisymmetric shape) the basis keeps the link axis closest to the
    plane, so the axes are a small rotation of the link frame, not an arbitrary one."""
    eig, vec = np.linalg.eigh(tensor)
    for a, b in ((0, 1), (1, 2)):
        if abs(eig[a] - eig[b]) <= 1e-9 * max(abs(eig[b]), 1e-12):
            plane = vec[:, [a, b]]
            axis = int(np.argmax(np.linalg.norm(plane.T, axis=0)))  # link axis nearest it
            u = plane @ (plane.T @ np.eye(3)[axis])
            u /= np.linalg.norm(u)
            other = vec[:, 3 - a - b]
            vec[:, a], vec[:, b] = u, np.cross(other, u) if (a, b) == (0, 1) else np.cross(u, other)
    if np.linalg.det(vec) < 0:
        vec[:, 2] *= -1.0
    return eig, vec


def _mass(prim: Any, link: Link) -> None:
    mass, com, tensor = link_inertia(link)
    eig, vec = _principal_axes(tensor)
    q = Gf.Matrix3d(vec.T.tolist()).ExtractRotation().GetQuat()  # rows: the principal axes
    api = UsdPhysics.MassAPI.Apply(prim)
    api.CreateMassAttr(mass)
    api.CreateCenterOfMassAttr(Gf.Vec3f(*com.tolist()))
    api.CreateDiagonalInertiaAttr(Gf.Vec3f(*eig.tolist()))
    api.CreatePrincipalAxesAttr(Gf.Quatf(q))


def _sensors(stage: Any, base: Sdf.Path, cfg: RoverConfig, camera: CameraConfig) -> None:
    from marsscene.export.usd.cameras import FOCAL_LENGTH, navcam_model

    nav = navcam_model(cfg, camera)
    cam = UsdGeom.Camera.Define(stage, base.AppendChild("navcam"))
    m = np.eye(4)
    m[:3, :3] = nav.axes_body.T
    m[3, :3] = nav.mount_xyz_m
    cam.AddTransformOp().Set(Gf.Matrix4d(m.tolist()))
    v = 2.0 * FOCAL_LENGTH * math.tan(math.radians(nav.fovy_deg) / 2.0)
    cam.CreateFocalLengthAttr(FOCAL_LENGTH)
    cam.CreateVerticalApertureAttr(v)
    cam.CreateHorizontalApertureAttr(v * nav.width_px / nav.height_px)
    cam.CreateClippingRangeAttr(Gf.Vec2f(0.05, 1000.0))
    mounts = sensor_mounts(cfg)
    for name in ("lidar", "imu"):
        frame = UsdGeom.Xform.Define(stage, base.AppendChild(name))
        frame.AddTranslateOp().Set(Gf.Vec3d(*mounts[name][0]))


def _joint(stage: Any, path: Sdf.Path, link: Link, cfg: RoverConfig) -> None:
    j = link.joint
    assert j is not None and link.parent is not None
    if j.kind == "ball":
        joint: Any = UsdPhysics.SphericalJoint.Define(stage, path)
    else:
        joint = UsdPhysics.RevoluteJoint.Define(stage, path)
        joint.CreateAxisAttr(_AXIS[j.axis])
        if j.range_rad is not None:
            joint.CreateLowerLimitAttr(math.degrees(j.range_rad[0]))
            joint.CreateUpperLimitAttr(math.degrees(j.range_rad[1]))
    joint.CreateBody0Rel().SetTargets([Sdf.Path(f"/Rover/{link.parent}")])
    joint.CreateBody1Rel().SetTargets([Sdf.Path(f"/Rover/{link.name}")])
    joint.CreateLocalPos0Attr(Gf.Vec3f(*link.pos_m))
    joint.CreateLocalPos1Attr(Gf.Vec3f(0.0, 0.0, 0.0))
    per_deg = math.pi / 180.0
    if j.name.startswith("drive_"):  # velocity drive: stiffness 0, damping > 0
        drive = UsdPhysics.DriveAPI.Apply(joint.GetPrim(), "angular")
        drive.CreateTypeAttr("force")
        drive.CreateTargetVelocityAttr(0.0)
        drive.CreateStiffnessAttr(0.0)
        drive.CreateDampingAttr(cfg.drive_kv_nm_s * per_deg)
        drive.CreateMaxForceAttr(cfg.drive_torque_limit_nm)
    elif j.name.startswith("steer_"):  # position drive
        drive = UsdPhysics.DriveAPI.Apply(joint.GetPrim(), "angular")
        drive.CreateTypeAttr("force")
        drive.CreateTargetPositionAttr(0.0)
        drive.CreateStiffnessAttr(cfg.steer_kp_nm * per_deg)
        drive.CreateDampingAttr((STEER_ACT_KV_NM_S + j.damping_nm_s) * per_deg)
        drive.CreateMaxForceAttr(cfg.steer_torque_limit_nm)


def rover_stage(cfg: RoverConfig | None = None,
                camera: CameraConfig | None = None) -> Usd.Stage:
    """The rover asset as an in-memory stage (default prim ``/Rover``; see the module doc)."""
    cfg = cfg if cfg is not None else RoverConfig()
    camera = camera if camera is not None else CameraConfig()
    stage = create_asset_stage("Rover")
    root = stage.GetPrimAtPath("/Rover")
    UsdPhysics.ArticulationRootAPI.Apply(root)
    looks = Sdf.Path("/Rover/Looks")
    UsdGeom.Scope.Define(stage, looks)
    materials = {
        "wheel": author_physics_material(stage, looks, PhysicsMaterial(
            "WheelPhysics", cfg.friction, cfg.friction, 0.0)),
        "body": author_physics_material(stage, looks, PhysicsMaterial(
            "BodyPhysics", BODY_FRICTION, BODY_FRICTION, 0.0)),
    }
    UsdGeom.Scope.Define(stage, "/Rover/Collision")
    group = UsdPhysics.CollisionGroup.Define(stage, "/Rover/Collision/RoverParts")
    group.GetCollidersCollectionAPI().CreateIncludesRel().SetTargets([Sdf.Path("/Rover")])
    group.CreateFilteredGroupsRel().SetTargets([group.GetPath()])
    UsdGeom.Scope.Define(stage, "/Rover/Joints")
    for link, origin in usd_links(cfg):
        path = Sdf.Path(f"/Rover/{link.name}")
        xform = UsdGeom.Xform.Define(stage, path)
        xform.AddTranslateOp().Set(Gf.Vec3d(*origin))
        UsdPhysics.RigidBodyAPI.Apply(xform.GetPrim())
        _mass(xform.GetPrim(), link)
        for i, shape in enumerate(link.shapes):
            name = "collision" if shape.collides else f"visual_{i}"
            _shape(stage, path.AppendChild(name), shape, materials)
        if link.joint is not None:
            _joint(stage, Sdf.Path(f"/Rover/Joints/{link.joint.name}"), link, cfg)
    for loop in loop_joints(cfg):
        joint = UsdPhysics.SphericalJoint.Define(stage, f"/Rover/Joints/{loop.name}")
        joint.CreateBody0Rel().SetTargets([Sdf.Path(f"/Rover/{loop.parent}")])
        joint.CreateBody1Rel().SetTargets([Sdf.Path(f"/Rover/{loop.child}")])
        joint.CreateLocalPos0Attr(Gf.Vec3f(*loop.parent_pos_m))
        joint.CreateLocalPos1Attr(Gf.Vec3f(*loop.child_pos_m))
        joint.CreateExcludeFromArticulationAttr(True)
    _sensors(stage, Sdf.Path("/Rover/base_link"), cfg, camera)
    return stage


def author_rover(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Write :data:`ROVER_ASSET`; with ``[export] rover = true`` also place it as
    ``/World/Rover`` at the runtime's spawn pose (``rover_xy_m``, default the terrain centre;
    ``rover_yaw_deg``, counter-clockwise from east)."""
    from marsscene.errors import ExportError, RuntimeSimError
    from marsscene.rover.spawn import spawn_pose
    from marsscene.transforms import quat_to_matrix

    cfg = RoverConfig()
    assets[ROVER_ASSET] = rover_stage(cfg)
    export = scene.config.export
    if not export.rover:
        return
    hf = scene.heightfield
    x0, y0, x1, y1 = hf.bounds_xy_m
    xy = export.rover_xy_m if export.rover_xy_m is not None else ((x0 + x1) / 2, (y0 + y1) / 2)
    try:
        pose = spawn_pose(hf, xy, math.radians(export.rover_yaw_deg), cfg)
    except RuntimeSimError as err:
        raise ExportError(f"export.rover_xy_m: {err}") from None
    base = pose[:3] - quat_to_matrix(pose[3:]) @ np.array([0.0, 0.0, cfg.ride_height_m])
    prim = UsdGeom.Xform.Define(stage, Sdf.Path(ROVER_PATH))
    prim.GetPrim().GetPayloads().AddPayload(f"./{ROVER_ASSET}")  # the stage loads none
    prim.AddTranslateOp().Set(Gf.Vec3d(*base.tolist()))
    prim.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Quatd(*pose[3:].tolist()))
    set_kind(prim.GetPrim(), "component")
