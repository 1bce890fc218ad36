"""Cameras in USD: ``/World/Cameras`` (a ``group``) with ``Navcam`` and ``Overview``.

* ``Navcam``: the runtime's mast camera. Its intrinsics (image size, vertical field of view)
  come from :class:`marsscene.rover.config.CameraConfig` and its mount (position and axes on
  the rover body) from :func:`marsscene.rover.geometry.navcam_mount` (the numbers the rover
  MJCF carries), read by :func:`navcam_model`. It is placed at the nominal spawn pose: terrain
  centre, yaw 0 (facing east), body z along the mean terrain normal under the footprint,
  ``ride_height_m`` above ground (the runtime then settles the rover by a few centimetres).
  MuJoCo and USD cameras both look along their local -Z with +Y up, so the MJCF ``xyaxes``
  are the USD camera axes.
* ``Overview``: looks at the terrain centre from the south-south-west, 35 deg above the
  horizon, far enough to see the whole footprint.

Apertures and focal length are in tenths of a scene unit (UsdGeom convention): focal length
10 and ``verticalAperture = 2 f tan(fovy / 2)``, ``horizontalAperture = verticalAperture *
width / height`` (square pixels).

Exposure: ``exposure:time`` is chosen (f/8, ISO 100) so that UsdGeom's linear exposure scale
``time * iso / 100 / fStop^2`` equals ``pi / E``, with ``E`` the global horizontal illuminance in
the light's units (lux by default; see ``marsscene/lighting/usd_units.py``). A renderer applying
that scale shows a grey card of albedo 0.18 lying on the ground at linear 0.18 (middle grey).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pxr import Gf, Sdf, UsdGeom

from marsscene.export.usd.stage import WORLD, set_kind
from marsscene.lighting.usd_units import usd_light_intensity

__all__ = ["CAMERAS_PATH", "CameraModel", "author_cameras", "exposure_time_s", "navcam_model"]

CAMERAS_PATH = f"{WORLD}/Cameras"
FOCAL_LENGTH = 10.0
F_STOP = 8.0
ISO = 100.0


@dataclass(frozen=True, slots=True)
class CameraModel:
    """A pinhole camera mounted on the rover body (metres, body frame x forward, z up)."""

    width_px: int
    height_px: int
    fovy_deg: float
    mount_xyz_m: tuple[float, float, float]
    axes_body: NDArray[np.float64]
    """(3, 3): columns are the camera's x, y, z axes in the body frame (z = backwards)."""


def navcam_model(rover: Any = None, camera: Any = None) -> CameraModel:
    """The mast camera as the runtime builds it (defaults: ``RoverConfig()``,
    ``CameraConfig()``)."""
    from marsscene._format import fmt
    from marsscene.rover.config import CameraConfig, RoverConfig
    from marsscene.rover.geometry import navcam_mount

    cam = camera if camera is not None else CameraConfig()
    mount, xyaxes = navcam_mount(rover if rover is not None else RoverConfig())
    # the numbers the rover MJCF carries (fixed significant digits), so both agree exactly
    pos = tuple(float(v) for v in fmt(mount).split())
    xy = np.array([float(v) for v in fmt(xyaxes).split()]).reshape(2, 3)
    x = xy[0] / np.linalg.norm(xy[0])
    y = xy[1] - x * float(xy[1] @ x)
    y /= np.linalg.norm(y)
    axes = np.column_stack([x, y, np.cross(x, y)])
    return CameraModel(int(cam.width_px), int(cam.height_px), float(fmt(cam.fovy_deg)),
                       (pos[0], pos[1], pos[2]), axes)


def exposure_time_s(illuminance: float, *, f_stop: float = F_STOP, iso: float = ISO) -> float:
    """Shutter time giving a linear exposure scale ``pi / illuminance`` (middle grey).

    Examples
    --------
    >>> round(exposure_time_s(math.pi * 64 * 100.0), 6)  # scale 1/6400 at f/8
    0.01
    """
    return math.pi / illuminance * f_stop**2 / (iso / 100.0)


def _matrix(axes_world: NDArray[np.float64], origin: NDArray[np.float64]) -> Gf.Matrix4d:
    """USD (row-vector) transform whose rows are the local axes and the origin."""
    m = np.eye(4)
    m[:3, :3] = axes_world.T
    m[3, :3] = origin
    return Gf.Matrix4d(m.tolist())


def _camera(stage: Any, name: str, width_px: int, height_px: int, fovy_deg: float,
            xform: Gf.Matrix4d, far_m: float, exposure: float | None) -> UsdGeom.Camera:
    cam = UsdGeom.Camera.Define(stage, Sdf.Path(f"{CAMERAS_PATH}/{name}"))
    cam.AddTransformOp().Set(xform)
    v = 2.0 * FOCAL_LENGTH * math.tan(math.radians(fovy_deg) / 2.0)
    cam.CreateProjectionAttr(UsdGeom.Tokens.perspective)
    cam.CreateFocalLengthAttr(FOCAL_LENGTH)
    cam.CreateVerticalApertureAttr(v)
    cam.CreateHorizontalApertureAttr(v * width_px / height_px)
    cam.CreateClippingRangeAttr(Gf.Vec2f(0.05, far_m))
    if exposure is not None:
        cam.CreateExposureFStopAttr(F_STOP)
        cam.CreateExposureIsoAttr(ISO)
        cam.CreateExposureTimeAttr(exposure_time_s(exposure))
    prim = cam.GetPrim()
    prim.CreateAttribute("marsscene:camera:resolution_px", Sdf.ValueTypeNames.Int2,
                         custom=True).Set(Gf.Vec2i(width_px, height_px))
    return cam


def _look_at(eye: NDArray[np.float64], target: NDArray[np.float64]) -> NDArray[np.float64]:
    f = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(f, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(x, f), -f])


def author_cameras(stage: Any, scene: Any, assets: dict[str, Any]) -> None:
    """Author ``/World/Cameras/Navcam`` and ``/World/Cameras/Overview``."""
    from marsscene.rover.config import RoverConfig
    from marsscene.transforms import quat_from_yaw_normal, quat_to_matrix

    hf = scene.heightfield
    x0, y0, x1, y1 = hf.bounds_xy_m
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    diag = math.hypot(x1 - x0, y1 - y0)
    lt = scene.lighting
    lux = None
    if lt is not None and lt.global_horizontal_w_m2 > 0:
        lux = usd_light_intensity(lt.global_horizontal_w_m2, units=lt.usd_units,
                                  luminous_efficacy_lm_per_w=lt.luminous_efficacy_lm_per_w)
    group = UsdGeom.Xform.Define(stage, Sdf.Path(CAMERAS_PATH)).GetPrim()
    set_kind(group, "group")

    rover = RoverConfig()
    nav = navcam_model(rover)
    # body z: the mean terrain normal under the rover footprint (the runtime fits a plane)
    half = max(rover.wheelbase_front_m, rover.wheelbase_rear_m) + 0.6
    g = np.linspace(-half, half, 9)
    gx, gy = np.meshgrid(centre[0] + g, centre[1] + g)
    normal = np.asarray(hf.normal(gx, gy), dtype=np.float64).reshape(-1, 3).mean(axis=0)
    normal /= np.linalg.norm(normal)
    body = quat_to_matrix(quat_from_yaw_normal(0.0, normal))
    ground = np.array([centre[0], centre[1], float(hf.sample(centre[0], centre[1]))])
    base = ground + normal * rover.ride_height_m
    eye = base + body @ np.asarray(nav.mount_xyz_m)
    _camera(stage, "Navcam", nav.width_px, nav.height_px, nav.fovy_deg,
            _matrix(body @ nav.axes_body, eye), max(diag, 100.0), lux)

    z_c = float(hf.sample(centre[0], centre[1]))
    az, el = math.radians(200.0), math.radians(35.0)  # from the south-south-west
    dist = 0.5 * diag / math.sin(math.radians(45.0) / 2)  # the footprint's circle fits in view
    eye = np.array([centre[0] + dist * math.cos(el) * math.sin(az),
                    centre[1] + dist * math.cos(el) * math.cos(az),
                    z_c + dist * math.sin(el)])
    target = np.array([centre[0], centre[1], z_c])
    _camera(stage, "Overview", 1280, 720, 45.0, _matrix(_look_at(eye, target), eye),
            4.0 * diag, lux)
