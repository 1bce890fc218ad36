"""The rover's own shadow in the camera (issue 25 follow-up): a straight strip, no saw-tooth.

On the flat scene with the sun behind the rover and to its left (elevation 30 deg, azimuth
250 deg; the rover faces east), the mast's shadow is a strip running up the bottom of the
image. A frame is rendered twice, with the rover casting and without (its geoms'
``castshadow`` off); per image row the strip's two edges are found to a sub-pixel (where the
darkening crosses half its depth) and fitted with straight lines. A mast's shadow on a plane
is straight; the shadow map draws it in texel steps. With the old 1024² map (3.9 cm texels:
~7 px at 3 m) the edges strayed from their lines by 4.3 px at most, 1.8 px RMS; with 3072²
(1.3 cm) by 1.5-1.8 px, 0.6-0.7 px RMS.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from marsscene.errors import RuntimeSimError
from marsscene.runtime import CameraConfig, RunConfig
from marsscene.sensors.camera import shadow_light_position
from marsscene.sim.rover_sim import RoverSim

_CAMERA = CameraConfig(sun_elevation_deg=30.0, sun_azimuth_deg=250.0, tau=0.3,
                       exposure="fixed", exposure_gain=1.0)


def _renderer(scene: Path):
    sim = RoverSim(scene, run=RunConfig(camera=_CAMERA), settle_s=0.3)
    try:
        return sim, sim.make_renderer()
    except RuntimeSimError as err:
        pytest.skip(f"no headless OpenGL (EGL/OSMesa) here: {err}")


@pytest.fixture(scope="module")
def frames(flat_scene: Path) -> tuple[np.ndarray, np.ndarray]:
    """Linear renders with the rover's shadow and without it."""
    sim, cam = _renderer(flat_scene)
    try:
        cam._sync(sim)
        lit = cam._render(cam.camera_id, False)[0]
        rover = np.flatnonzero(cam.model.geom_bodyid != 0)
        cam.model.geom_castshadow[rover] = 0
        ref = cam._render(cam.camera_id, False)[0]
    finally:
        cam.close()
    return lit, ref


def _cross(d: np.ndarray, half: float, out: int, inside: int) -> float:
    """Where ``d`` crosses ``half`` between pixel ``out`` (lit) and ``inside`` (dark)."""
    return out + (half - d[out]) / (d[inside] - d[out]) * (inside - out)


def _strip_edges(lit: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """(row, left edge, right edge) in px of the mast's strip: rows whose darkened run is
    narrow (not the chassis' shadow), within half of the median width."""
    dark = 1.0 - lit.mean(-1) / np.maximum(ref.mean(-1), 1e-6)
    half = 0.5 * np.percentile(dark[dark > 0.1], 90)
    rows = []
    for y, d in enumerate(dark):
        idx = np.flatnonzero(d > half)
        if idx.size == 0:
            continue
        runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
        run = max(runs, key=len)
        a, b = int(run[0]), int(run[-1])
        if a == 0 or b == d.size - 1:
            continue
        rows.append((y, _cross(d, half, a - 1, a), _cross(d, half, b + 1, b), b - a + 1))
    e = np.array(rows, dtype=np.float64)
    e = e[e[:, 3] < 40]
    med = np.median(e[:, 3])
    return e[np.abs(e[:, 3] - med) < 0.5 * med][3:-3, :3]


def test_the_mast_shadow_is_a_straight_strip(frames) -> None:
    lit, ref = frames
    e = _strip_edges(lit, ref)
    assert len(e) >= 100, "the mast's shadow should run > 100 rows up the image"
    assert 150 < e[:, 0].min() and e[:, 0].max() > 400  # from the bottom toward the horizon
    for k in (1, 2):
        fit = np.polyfit(e[:, 0], e[:, k], 1)
        resid = e[:, k] - np.polyval(fit, e[:, 0])
        # 1024² map: 4.3 px max, 1.8 px RMS (saw-tooth); 3072²: <= 1.8 px, <= 0.7 px RMS
        assert np.abs(resid).max() < 2.5
        assert np.sqrt(np.mean(resid**2)) < 1.0
    width = e[:, 2] - e[:, 1]
    assert 3.0 < np.median(width) < 30.0  # a 12 cm mast a few metres away


def test_shadow_texels_are_fixed_to_the_world(flat_scene: Path) -> None:
    """The light's position falls on the map's texel lattice (across the sun), as MuJoCo's
    light view builds it: a whole-texel shift of the light leaves the frame as it was, half a
    texel moves the shadow edges."""
    import marsscene.sensors.camera as camera

    sim, cam = _renderer(flat_scene)
    try:
        cam._sync(sim)
        sun = np.asarray(cam.lighting.sun_direction_enu)
        eye = cam.model.light_pos[cam.sun_id].copy()
        texel = 2.0 * camera._SHADOW_CLIP_M / (camera._SHADOW_MAP_PX - 2)
        f = -sun / np.linalg.norm(sun)
        side = np.cross(f, np.cross(f, [-1.0, 0.0, 0.0]))
        side /= np.linalg.norm(side)
        up = np.cross(side, f)
        for axis in (side, up):
            k = axis @ eye / texel
            assert abs(k - round(k)) < 1e-6
        # the camera moved by 1 cm: the light follows, still on the lattice
        moved = shadow_light_position(cam.data.cam_xpos[cam.camera_id] + [0.01, 0.004, 0.0],
                                      cam.data.cam_xmat[cam.camera_id], sun)
        assert np.abs(moved - eye).max() < 0.03
        k = side @ moved / texel
        assert abs(k - round(k)) < 1e-6

        def frame(pos: np.ndarray) -> np.ndarray:
            cam.model.light_pos[cam.sun_id] = pos
            mujoco.mj_camlight(cam.model, cam.data)
            return cam._render(cam.camera_id, False)[0]

        base = frame(eye)
        whole = np.abs(frame(eye + texel * side) - base).max(-1)
        halfway = np.abs(frame(eye + 0.5 * texel * side) - base).max(-1)
        assert (whole > 0.02).sum() <= 5
        assert (halfway > 0.02).sum() >= 20 * max((whole > 0.02).sum(), 1)
    finally:
        cam.close()
