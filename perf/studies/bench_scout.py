"""The Ingenuity-class scout against the published vehicle, and the speed of a flight (issue 69).

Run: ``python perf/run.py scout --size quick|full [--leg-m M] [--camera-px N]``.

Figures: hover power at the design density (0.0175 kg/m^3) and at the Jezero model's density
against the published ~350 W (Balaram et al. 2018); the energy-limited hover time on the
40 Wh battery against the published flights (90 s planned, ~170 s flown: heating of the
motors, not the battery, bounds them); the thrust-to-weight ratio at 2,900 rpm; and a square
survey flight (four legs of ``LEG_M`` at 10 m) on a built scene: sim seconds, wall seconds,
real-time factor, energy and mean power, waypoints reached, images (CPU, ray-cast camera).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from perf.suite import Param

PARAMS = (Param("leg_m", float, "side of the square survey (m)", quick=10.0, full=30.0),
          Param("camera_px", int, "navigation camera width (px; height 3/4 of it)", quick=64,
                full=160))


def main(leg_m: float, camera_px: int) -> dict[str, Any]:
    import marsscene as ms
    from marsscene.scout import FlightPlan, ScoutConfig, air_density_kg_m3, fly
    from marsscene.scout.aero import endurance_s, hover_power_w, max_thrust_n
    from marsscene.units import MARS_GRAVITY_M_S2

    cfg = ScoutConfig.load()
    rho = air_density_kg_m3()
    out: dict[str, Any] = {
        "hover_power_w_at_0.0175": hover_power_w(cfg, 0.0175),
        "hover_power_w_jezero": hover_power_w(cfg, rho), "density_jezero_kg_m3": rho,
        "published_hover_power_w": cfg.published_hover_power_w,
        "hover_endurance_s": endurance_s(cfg, rho),
        "published_flight_s": cfg.published_flight_s,
        "thrust_to_weight_max": max_thrust_n(cfg, rho) / (cfg.mass_kg * MARS_GRAVITY_M_S2),
    }
    with tempfile.TemporaryDirectory() as tmp:
        size = max(60.0, 2 * leg_m + 20.0)
        scene = ms.SceneConfig.from_dict({"terrain": {"source": "procedural",
                                                      "size_m": [size, size]}})
        t0 = time.perf_counter()
        ms.write_scene(ms.build_scene(scene, seed=1), Path(tmp) / "scene")
        build_s = time.perf_counter() - t0
        h = leg_m / 2
        wps = [[h, -h], [h, h], [-h, h], [-h, -h]]
        plan = FlightPlan(camera_px=(camera_px, camera_px * 3 // 4))
        flight = fly(Path(tmp) / "scene", wps, plan=plan, out_dir=Path(tmp) / "run")
    s = flight.summary
    out.update({"survey_leg_m": leg_m, "sim_s": s["sim_time_s"], "wall_s": flight.wall_s,
                "real_time_factor": flight.realtime_factor, "energy_wh": s["energy_wh"],
                "mean_power_w": s["mean_power_w"], "reached": sum(flight.reached),
                "images": s["images"], "scene_build_s": build_s})
    for key, value in out.items():
        print(f"{key:28s} {value:.4g}" if isinstance(value, float) else f"{key:28s} {value}")
    return out
