"""A scout flight on a built scene: take-off from the terrain, a straight leg to each waypoint
at ``altitude_m`` above the ground below it, a hover there, and a landing; logged as a run
folder beside a rover's, in the same map frame (the scene's world frame, metres):

    gt.tum          the body's ground-truth pose at the control rate (TUM, scalar last)
    altimeter.csv   t_s, range_m (noisy), true_m
    images/         NNNNNN.png: the navigation camera looking down (8-bit grey)
    images.tum      the camera's pose at each image (optical frame: x right, y down, z ahead)
    run.json        the vehicle, the air density, waypoints reached, hover power, energy

The same seed gives the same bytes (the altimeter noise is ``default_rng([seed, 0x5C0])``).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from marsscene._atomic import write_atomic
from marsscene.errors import ConfigError
from marsscene.runs.tum import Trajectory, write_tum
from marsscene.scout.aero import hover_power_w, rotor_power_w
from marsscene.scout.config import ScoutConfig, air_density_kg_m3
from marsscene.scout.control import FlightGains, flight_command
from marsscene.scout.sensors import BODY_TO_CAMERA, altimeter_m, nadir_image, pixel_rays
from marsscene.scout.vehicle import ScoutSim
from marsscene.transforms import matrix_to_quat

__all__ = ["Flight", "FlightPlan", "fly"]

#: The scout's noise stream: ``default_rng([seed, _SCOUT_STREAM])``, apart from the rover's.
_SCOUT_STREAM = 0x5C0
#: The reference slows to each waypoint at this deceleration (m/s^2), half the 20 deg tilt's.
_BRAKE_M_S2 = 0.6


@dataclass(frozen=True, kw_only=True)
class FlightPlan:
    """How the scout flies its waypoints (m, m/s, s, Hz)."""

    altitude_m: float = 10.0
    speed_m_s: float = 3.0
    climb_m_s: float = 1.0
    tolerance_m: float = 0.5
    """A waypoint is reached within this distance (3-D) of its point."""
    hover_s: float = 1.0
    control_hz: float = 100.0
    camera_hz: float = 2.0
    camera_px: tuple[int, int] = (160, 120)
    altimeter_hz: float = 50.0
    max_s: float = 600.0
    gains: FlightGains = field(default_factory=FlightGains)


@dataclass
class Flight:
    """A flown flight: ``gt`` poses, the waypoints reached, energy and the run folder."""

    gt: Trajectory
    reached: list[bool]
    touchdown_s: float | None
    summary: dict[str, Any]
    out_dir: Path | None
    wall_s: float

    @property
    def realtime_factor(self) -> float:
        return float(self.summary["sim_time_s"]) / self.wall_s if self.wall_s > 0 else math.nan


def _legs(sim: ScoutSim, waypoints: NDArray[np.float64], plan: FlightPlan
          ) -> list[NDArray[np.float64]]:
    """Reference points: above the start, each waypoint at altitude, the last one's ground."""
    hf = sim.heightfield
    p0 = sim.data.qpos[:3].copy()
    pts = [np.array([p0[0], p0[1], hf.sample(p0[0], p0[1]) + plan.altitude_m])]
    pts += [np.array([x, y, hf.sample(x, y) + plan.altitude_m]) for x, y in waypoints]
    return pts


def fly(scene_dir: str | Path, waypoints: ArrayLike, *, plan: FlightPlan | None = None,
        scout: ScoutConfig | None = None, density_kg_m3: float | None = None,
        out_dir: str | Path | None = None, seed: int = 0,
        start_xy_m: tuple[float, float] | None = None,
        rng: np.random.Generator | None = None) -> Flight:
    """Fly the scout through ``waypoints`` ((N, 2) map x, y in m) and land at the last.

    ``density_kg_m3``: the air density (default :func:`air_density_kg_m3` at Jezero);
    ``rng``: the altimeter's noise stream (default ``default_rng([seed, 0x5C0])``; a team's
    scout has its own, keyed by its name).
    """
    plan = plan if plan is not None else FlightPlan()
    cfg = scout if scout is not None else ScoutConfig.load()
    rho = density_kg_m3 if density_kg_m3 is not None else air_density_kg_m3()
    wp = np.asarray(waypoints, dtype=np.float64).reshape(-1, 2)
    if len(wp) == 0:
        raise ConfigError("fly: give at least one waypoint")
    sim = ScoutSim(scene_dir, cfg, density_kg_m3=rho, start_xy_m=start_xy_m)
    (x0, y0, x1, y1) = sim.heightfield.bounds_xy_m
    if ((wp[:, 0] < x0) | (wp[:, 0] > x1) | (wp[:, 1] < y0) | (wp[:, 1] > y1)).any():
        raise ConfigError(f"fly: waypoints outside the terrain [{x0}, {x1}] x [{y0}, {y1}] m")
    t0 = time.perf_counter()
    log = _fly(sim, wp, plan, rho,
               rng if rng is not None else np.random.default_rng([seed, _SCOUT_STREAM]))
    wall = time.perf_counter() - t0
    gt = Trajectory(np.asarray(log["t"]), np.asarray(log["p"]), np.asarray(log["q"]))
    summary = {
        "scout": {k: v for k, v in asdict(cfg).items() if k != "sources"},
        "air_density_kg_m3": rho, "plan": asdict(plan), "seed": seed,
        "waypoints_xy_m": wp.tolist(), "reached": log["reached"],
        "touchdown_s": log["touchdown_s"], "sim_time_s": log["t"][-1],
        "energy_wh": log["energy_j"] / 3600.0, "hover_power_w": hover_power_w(cfg, rho),
        "mean_power_w": log["energy_j"] / max(log["t"][-1], 1e-9),
        "images": len(log["images"]),
    }
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        _write(out, gt, log, summary)
    return Flight(gt, log["reached"], log["touchdown_s"], summary, out, wall)


def _fly(sim: ScoutSim, wp: NDArray[np.float64], plan: FlightPlan, rho: float,
         rng: np.random.Generator) -> dict[str, Any]:
    cfg, hf = sim.cfg, sim.heightfield
    n_sub = max(1, round(1.0 / (plan.control_hz * sim.dt_s)))
    dt = n_sub * sim.dt_s
    cam_every = max(1, round(plan.control_hz / plan.camera_hz))
    alt_every = max(1, round(plan.control_hz / plan.altimeter_hz))
    w, h = plan.camera_px
    rays = pixel_rays(w, h, cfg.camera_fov_diag_deg)
    sun = np.array([0.5, 0.3, 0.81])
    sun /= np.linalg.norm(sun)
    pts = _legs(sim, wp, plan)
    log: dict[str, Any] = {"t": [], "p": [], "q": [], "alt": [], "images": [],
                           "reached": [False] * len(wp), "touchdown_s": None, "energy_j": 0.0}
    ref = sim.data.qpos[:3].copy()
    yaw = 0.0
    leg, hold, landing, k, airborne = 0, 0.0, False, 0, False
    while k * dt <= plan.max_s:
        t = k * dt
        state = sim.state()
        p = state[0]
        target = pts[leg] if not landing else np.array([ref[0], ref[1], -1e9])
        d = target - ref
        dist = float(np.linalg.norm(d))
        speed = plan.climb_m_s if leg == 0 or landing else plan.speed_m_s
        step = min(speed, math.sqrt(2.0 * _BRAKE_M_S2 * dist)) * dt  # slowing to each point
        if landing:
            ref = ref + np.array([0.0, 0.0, -0.5 * dt])
            v_ref = np.array([0.0, 0.0, -0.5])
        else:
            ref = target.copy() if dist <= step else ref + d / dist * step
            v_ref = np.zeros(3) if dist <= step else d / dist * step / dt
        ctrl = flight_command(cfg, plan.gains, ref, v_ref, yaw, state)
        contacts = sim.feet_in_contact()
        airborne = airborne or contacts == 0
        if landing and airborne and contacts >= 3 and log["touchdown_s"] is None:
            log["touchdown_s"] = t
        if log["touchdown_s"] is not None:
            ctrl = np.zeros(4)
        _record(log, t, state, k, cam_every, alt_every, hf, cfg, rays, (h, w), sun, rng)
        if not landing and np.linalg.norm(pts[leg] - p) < plan.tolerance_m:
            hold += dt
            if hold >= plan.hover_s:
                if leg > 0:
                    log["reached"][leg - 1] = True
                leg, hold = leg + 1, 0.0
                landing = leg == len(pts)
        log["energy_j"] += rotor_power_w(cfg, float(ctrl[0]), rho) * dt if ctrl[0] > 0 else 0.0
        if log["touchdown_s"] is not None and t - log["touchdown_s"] >= 1.0:
            break
        sim.step(ctrl, n_sub)
        k += 1
    return log


def _record(log: dict[str, Any], t: float, state: Sequence[Any], k: int, cam_every: int,
            alt_every: int, hf: Any, cfg: ScoutConfig, rays: NDArray[np.float64],
            shape: tuple[int, int], sun: NDArray[np.float64], rng: np.random.Generator) -> None:
    p, _, rot, _ = state
    q = matrix_to_quat(rot)  # w, x, y, z
    log["t"].append(t)
    log["p"].append(p.copy())
    log["q"].append(np.array([q[1], q[2], q[3], q[0]]))
    if k % alt_every == 0:
        true = altimeter_m(hf, p, rot, cfg.altimeter_range_m)
        noisy = true + rng.normal(0.0, cfg.altimeter_sigma_m) if math.isfinite(true) else true
        log["alt"].append((t, noisy, true))
    if k % cam_every == 0:
        img = nadir_image(hf, p, rot, rays, shape, sun)
        qc = matrix_to_quat(rot @ BODY_TO_CAMERA)
        log["images"].append((t, p.copy(), np.array([qc[1], qc[2], qc[3], qc[0]]), img))


def _write(out: Path, gt: Trajectory, log: dict[str, Any], summary: dict[str, Any]) -> None:
    import cv2

    out.mkdir(parents=True, exist_ok=True)
    write_tum(out / "gt.tum", gt, header="scout body pose in the map (scene world) frame")
    rows = "".join(f"{t:.6f},{r:.6f},{tr:.6f}\n" for t, r, tr in log["alt"])
    write_atomic(out / "altimeter.csv", "t_s,range_m,true_m\n" + rows)
    (out / "images").mkdir(exist_ok=True)
    for i, (_, _, _, img) in enumerate(log["images"]):
        _, png = cv2.imencode(".png", img)
        write_atomic(out / "images" / f"{i:06d}.png", png.tobytes())
    ts = np.array([im[0] for im in log["images"]])
    cams = Trajectory(ts, np.array([im[1] for im in log["images"]]),
                      np.array([im[2] for im in log["images"]]))
    write_tum(out / "images.tum", cams, header="navcam optical frame in the map frame")
    write_atomic(out / "run.json", json.dumps(summary, indent=2, sort_keys=True) + "\n")
