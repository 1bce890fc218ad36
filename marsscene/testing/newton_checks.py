"""Worlds and checks for the USD rover in Newton (``marsscene.sim.newton_rover``): a 15 deg slope,
small and large rocks in the path, a sphere dropped on a rock, and the same ``cmd_vel`` plan in
MuJoCo's runtime and in Newton. ``tests/usd_clients/test_newton_rover.py`` asserts on them and
``perf/interop/bench_newton.py`` prints them. Needs the extra ``newton`` (and ``sim`` for
MuJoCo), imported on first use (:class:`~marsscene.sim.newton_rover.NewtonRover` raises
:func:`marsscene.errors.missing_dependency` naming the extra)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["CELL_M", "check_rock", "check_slope", "check_sphere", "compare_drive", "flat",
           "gentle_scene", "slope", "write_world"]

CELL_M = 0.25
V_M_S, TURN_RAD_S = 0.3, 0.1


def _tilt_deg(q_wxyz: Any) -> float:
    """Angle between the body z axis and the world z axis (deg)."""
    _, x, y, _ = q_wxyz
    return math.degrees(math.acos(min(1.0, max(-1.0, 1 - 2 * (x * x + y * y)))))


def _roll_pitch_deg(q_wxyz: Any) -> tuple[float, float]:
    w, x, y, z = q_wxyz
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return math.degrees(roll), math.degrees(pitch)


def rock_prototype() -> Any:
    """The largest-class prototype of the default rock config (a real, irregular rock)."""
    from marsscene.rocks.config import RockConfig
    from marsscene.rocks.shapes import make_prototypes
    from marsscene.seeding import stage_rng

    protos = make_prototypes(RockConfig(), rng=stage_rng(0, "rock_shapes"))
    return max(protos, key=lambda p: p.size_class)


def block_prototype() -> Any:
    """A flat-topped block rock (unit frame: x, y in [-0.5, 0.5], z in [0, 1])."""
    import trimesh

    from marsscene.rocks.shapes import RockPrototype

    box = trimesh.creation.box(extents=(1.0, 1.0, 1.0))
    box.apply_translation((0.0, 0.0, 0.5))
    return RockPrototype("rock_00", 2, box, (box,))


def rock_top_m(proto: Any, scale_xyz: Any, x: float, y: float) -> float:
    """Top of a rock's convex collision hull above its base at (x, y) (rock frame,
    unrotated): the lowest of the upward faces' planes there."""
    hull = proto.collision[0]
    v = np.asarray(hull.vertices) * np.asarray(scale_xyz)
    tri = v[np.asarray(hull.faces)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    up = n[:, 2] > 1e-12
    d = np.einsum("ij,ij->i", n[up], tri[up, 0])
    return float(np.min((d - n[up, 0] * x - n[up, 1] * y) / n[up, 2]))


def write_world(out: Path, z: Any, *, rocks: Sequence[tuple[tuple[float, float], Any]] = (),
                rover_xy_m: tuple[float, float], rover_yaw_deg: float = 0.0,
                prototype: Any = None) -> Path:
    """A scene folder (USD with the rover placed, MJCF) over heightfield ``z`` (0.25 m posts,
    centred) with ``rocks``: ``((x, y), scale_xyz_m)`` of ``prototype`` (default: the
    :func:`rock_prototype`)."""
    import marsscene as ms
    from marsscene.rocks.table import RockTable
    from marsscene.scene import Provenance, Scene
    from marsscene.terrain.from_dem import GeoFrame
    from marsscene.terrain.heightfield import Heightfield

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [10, 10]},
        "export": {"rover": True, "rover_xy_m": list(rover_xy_m),
                   "rover_yaw_deg": rover_yaw_deg}})
    hf = Heightfield.centered(np.asarray(z, dtype=np.float32), CELL_M)
    table = None
    if rocks:
        xy = np.array([r[0] for r in rocks], dtype=np.float64)
        scale = np.array([r[1] for r in rocks], dtype=np.float64)
        ground = hf.sample(xy[:, 0], xy[:, 1])
        table = RockTable(np.column_stack([xy, ground]), scale[:, 0], scale[:, 2],
                          np.zeros(len(rocks)), np.tile([1.0, 0, 0, 0], (len(rocks), 1)),
                          np.zeros(len(rocks), dtype=np.int64), scale_xyz_m=scale)
    scene = Scene(heightfield=hf, config=cfg, seed=0,
                  provenance=Provenance(frame=GeoFrame(0.0, None, None, "", 1.0)),
                  rocks=table,
                  rock_prototypes=((prototype or rock_prototype()),) if rocks else None)
    ms.write_scene(scene, out, formats=("usd", "mjcf"))
    return out


def flat(n: int = 121) -> Any:
    return np.zeros((n, n), np.float32)


def slope(deg: float = 15.0) -> Any:
    x = (np.arange(161) - 80) * CELL_M
    return np.tile(math.tan(math.radians(deg)) * x, (81, 1)).astype(np.float32)


def _rover(scene: Path, **kw: Any) -> Any:
    from marsscene.sim.newton_rover import NewtonRover

    return NewtonRover(scene / "scene.usda", **kw)


def check_slope(tmp: Path) -> dict[str, Any]:
    """Parked across a 15 deg slope for 5 s, then driven up it for 20 s at 0.3 m/s."""
    across = _rover(write_world(tmp / "across", slope(), rover_xy_m=(0.0, 0.0),
                                rover_yaw_deg=90.0))
    across.advance(1000)
    settled = across.pose()[0]
    across.advance(1500)
    roll, pitch = _roll_pitch_deg(across.pose()[1])
    up = _rover(write_world(tmp / "up", slope(), rover_xy_m=(-12.0, 0.0)))
    up.advance(1000)
    p0 = up.pose()[0]
    tilt_max = 0.0
    for _ in range(1000):
        up.step(V_M_S, 0.0)
        tilt_max = max(tilt_max, _tilt_deg(up.pose()[1]))
    p1 = up.pose()[0]
    return {"across_roll_deg": round(roll, 2), "across_pitch_deg": round(pitch, 2),
            "across_settle_shift_m": round(float(np.hypot(*settled[:2])), 3),
            "across_creep_m_s": round(float(np.hypot(*(across.pose()[0][:2] - settled[:2])))
                                      / 3.0, 4),
            "up_travelled_m": round(float(np.linalg.norm(p1 - p0)), 3),
            "up_grade": round(float((p1[2] - p0[2]) / (p1[0] - p0[0])), 4),
            "tan15": round(math.tan(math.radians(15)), 4), "up_tilt_max_deg": round(tilt_max, 2)}


def _drive_into(scene: Path, seconds: float) -> dict[str, Any]:
    sim = _rover(scene)
    sim.advance(1000)
    p0 = sim.pose()[0]
    z_max, roll_max = p0[2], 0.0
    for _ in range(round(seconds * 50)):
        sim.step(V_M_S, float(np.clip(-sim.yaw_rad(), -0.2, 0.2)))  # heading hold
        z_max = max(z_max, sim.pose()[0][2])
        roll_max = max(roll_max, abs(_roll_pitch_deg(sim.pose()[1])[0]))
    p1 = sim.pose()[0]
    return {"x0": round(float(p0[0]), 3), "x1": round(float(p1[0]), 3),
            "lift_m": round(float(z_max - p0[2]), 3), "roll_max_deg": round(roll_max, 2)}


def check_rock(tmp: Path) -> dict[str, Any]:
    """A 0.35 m rock under the left wheels, and a 1.2 m rock across the path."""
    small = write_world(tmp / "small_rock", flat(), rover_xy_m=(-4.0, 0.0),
                        rocks=[((-1.0, 1.0), (0.7, 0.7, 0.35))])
    big = write_world(tmp / "big_rock", flat(), rover_xy_m=(-4.0, 0.0),
                      rocks=[((0.5, 0.0), (2.4, 2.4, 1.2))])
    return {"small": _drive_into(small, 25.0), "big": _drive_into(big, 20.0),
            "big_rock_x_m": [0.5 - 1.2, 0.5 + 1.2], "commanded_m": round(V_M_S * 20.0, 2)}


def check_sphere(tmp: Path) -> dict[str, Any]:
    """A 0.3 m sphere dropped from 1.5 m above a 1.2 m flat-topped rock (a block: on a real
    rock's rounded top a sphere rolls off) rests on the rock's top."""
    from marsscene.sim.newton_rover import _newton

    _, wp = _newton()
    scale = (2.4, 2.4, 1.2)
    scene = write_world(tmp / "sphere", flat(), rover_xy_m=(-8.0, 0.0),
                        rocks=[((0.0, 0.0), scale)], prototype=block_prototype())
    top = rock_top_m(block_prototype(), scale, 0.3, -0.2)
    ids: list[int] = []

    def add_sphere(builder: Any) -> None:
        body = builder.add_body(xform=wp.transform(wp.vec3(0.3, -0.2, top + 1.5),
                                                   wp.quat_identity()))
        builder.add_shape_sphere(body, radius=0.3)
        ids.append(body)

    sim = _rover(scene, edit_builder=add_sphere)
    sim.advance(1500)
    z = float(sim.state.body_q.numpy()[ids[0]][2])
    speed = float(np.linalg.norm(sim.state.body_qd.numpy()[ids[0]]))
    return {"rock_top_m": round(top, 3), "sphere_centre_z_m": round(z, 3),
            "sphere_speed_after_3s": round(speed, 4),
            "expected_z_m": round(top + 0.3, 3), "ground_rest_z_m": 0.3}


def _mujoco_run(scene: Path, plan: list[tuple[float, float, int]]) -> Any:
    from marsscene.sim.rover_sim import RoverSim

    sim = RoverSim(scene)
    out = [np.r_[sim.pose()[0], sim.yaw_rad()]]
    for v, w, n in plan:
        for _ in range(n):
            sim.apply(v, w)  # one control period of cmd_vel, as a drive session makes it
            sim.advance(sim.substeps)
            out.append(np.r_[sim.pose()[0], sim.yaw_rad()])
    return np.array(out)


def _newton_run(scene: Path, plan: list[tuple[float, float, int]],
                **kw: Any) -> tuple[Any, dict[str, Any]]:
    t0 = time.perf_counter()
    sim = _rover(scene, **kw)
    load_s = time.perf_counter() - t0
    sim.advance(1500)  # settle 3 s, wheels braked (MuJoCo: up to 3 s)
    out = [np.r_[sim.pose()[0], sim.yaw_rad()]]
    t0 = time.perf_counter()
    for v, w, n in plan:
        for _ in range(n):
            sim.step(v, w)
            out.append(np.r_[sim.pose()[0], sim.yaw_rad()])
    steps = sum(n for _, _, n in plan)
    info = {"load_s": round(load_s, 1), "rocks_loaded": sim.load_info["rocks_loaded"],
            "sim_s_per_wall_s": round(steps / 50 / (time.perf_counter() - t0), 3)}
    return np.array(out), info


def _summary(track: Any, n_straight: int) -> dict[str, float]:
    """Start-relative figures: straight distance, speed, lateral drift, heading changes."""
    p, yaw = track[:, :3] - track[0, :3], np.unwrap(track[:, 3])
    c, s = math.cos(yaw[0]), math.sin(yaw[0])
    fwd = p[:, 0] * c + p[:, 1] * s
    lat = -p[:, 0] * s + p[:, 1] * c
    seg = np.linalg.norm(np.diff(track[: n_straight + 1, :2], axis=0), axis=1).sum()
    return {"straight_m": round(float(fwd[n_straight]), 3),
            "straight_speed_m_s": round(float(seg / (n_straight / 50)), 4),
            "straight_lateral_m": round(float(lat[n_straight]), 3),
            "straight_yaw_deg": round(math.degrees(yaw[n_straight] - yaw[0]), 2),
            "turn_deg": round(math.degrees(yaw[-1] - yaw[n_straight]), 2),
            "end_fwd_m": round(float(fwd[-1]), 3), "end_lat_m": round(float(lat[-1]), 3)}


def mjcf_rock_rows(scene: Path) -> set[int]:
    """Rows of the rock table that the MJCF scene simulates (geoms ``rock_<row>_<part>``)."""
    import re

    text = (scene / "mjcf" / "scene.xml").read_text()
    return {int(m) for m in re.findall(r'<geom name="rock_(\d+)_\d+"', text)}


def compare_drive(scene: Path, *, straight_m: float = 10.0, turn_deg: float = 90.0,
                  same_rocks: bool = True, **kw: Any) -> dict[str, Any]:
    """The same cmd_vel plan in MuJoCo (RoverSim on mjcf/scene.xml) and Newton (the USD
    rover on scene.usda): ``straight_m`` at 0.3 m/s, then an arc of ``turn_deg`` (0.3 m/s,
    0.1 rad/s). ``same_rocks``: Newton loads only the rocks the MJCF has (the largest 1000 by
    default), else every USD rock within 30 m."""
    n_straight = round(straight_m / V_M_S * 50)
    n_turn = round(math.radians(turn_deg) / TURN_RAD_S * 50)
    plan = [(V_M_S, 0.0, n_straight), (V_M_S, TURN_RAD_S, n_turn)]
    mj = _mujoco_run(scene, plan)
    if same_rocks:
        kw["rock_rows"] = mjcf_rock_rows(scene)
    nt, info = _newton_run(scene, plan, **kw)
    a, b = _summary(mj, n_straight), _summary(nt, n_straight)
    # path: each track in its own start frame (x along the start heading), sample by sample
    def local(tr: Any) -> Any:
        c, s = math.cos(tr[0, 3]), math.sin(tr[0, 3])
        d = tr[:, :2] - tr[0, :2]
        return np.column_stack([d[:, 0] * c + d[:, 1] * s, -d[:, 0] * s + d[:, 1] * c])

    gap = np.linalg.norm(local(mj) - local(nt), axis=1)
    return {"mujoco": a, "newton": b, "newton_run": info,
            "path_gap_max_m": round(float(gap.max()), 3),
            "path_gap_end_m": round(float(gap[-1]), 3),
            "path_length_m": round(float(np.linalg.norm(np.diff(mj[:, :2], axis=0),
                                                        axis=1).sum()), 2)}


def gentle_scene(tmp: Path) -> Path:
    """40 m procedural terrain (0.05 m RMS) with rocks from 0.5 m, the rover at the centre."""
    import marsscene as ms

    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [40, 40], "post_m": 0.25,
                    "rms_height_m": 0.05},
        "craters": {"enabled": False}, "rocks": {"k": 0.05, "d_min_m": 0.5},
        "export": {"rover": True}})
    ms.write_scene(ms.build_scene(cfg, seed=3), tmp / "gentle")
    return tmp / "gentle"
