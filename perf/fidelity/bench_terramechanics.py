"""The rover on deformable soil (issue 46): slip against slope on each soil, a megaripple
crossing, and the physics' speed with the soil model on against off.

Run::

    python perf/run.py terramechanics                  # all four, no figures
    python perf/run.py terramechanics --part slope [--out docs/img/slip_slope.png]
    python perf/run.py terramechanics --part ripple
    python perf/run.py terramechanics --part speed
    python perf/run.py terramechanics --part map [--out docs/img/soil_map.png]

``slope``: the rover climbs straight at 0.2 m/s (rim speed) on a flat scene with gravity tilted
by the slope, for 10 s; its slip ``1 - v / (r omega)`` over the last 5 s beside the
single-wheel theory's (the slip at which a wheel carrying a sixth of the rover's weight pulls a
sixth of the downhill force: sinkage solved for the load, drawbar pull by quadrature; 1 where
no slip pulls enough).
``ripple``: 20 s across sinusoidal sand ripples 0.3 m high and 5 m long (flanks up to 11 deg)
of megaripple sand: the largest slip over 1 s and sinkage. ``speed``: 20 s of driving on the
flat scene, CPU seconds per simulated second and steps per CPU second, at 100 Hz (the
environments') and 500 Hz (the drive's) physics, rigid against dry sand, in one run. ``map``:
the default scene (seed 7) with ``[soil] enabled``: the soil stage's time, each soil's share,
and the map over the terrain's shaded relief.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

import marsscene as ms
from marsscene.rover.config import RoverConfig, RunConfig
from marsscene.rover.terramechanics import sinkage_for_load, soil, soils, wheel_forces
from marsscene.scene import Provenance, Scene
from marsscene.sim.rover_sim import RoverSim
from marsscene.terrain.from_dem import GeoFrame
from marsscene.terrain.heightfield import Heightfield
from perf.suite import Param, optional

ROVER = RoverConfig()
PARAMS = (Param("part", str, "all, slope, ripple, speed or map", quick="speed", full="all",
                choices=("all", "slope", "ripple", "speed", "map")),
          Param("out", optional(Path), "slope, map: the figure (PNG)", quick=None, full=None))
SLOPES_DEG = (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0, 17.5, 20.0, 22.5, 25.0)


def _scene(out: Path, z: np.ndarray) -> Path:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    scene = Scene(heightfield=Heightfield.centered(z.astype(np.float32), 0.25), config=cfg,
                  seed=0, provenance=Provenance(frame=GeoFrame(0.0, None, None, "", 1.0)))
    ms.write_scene(scene, out, formats=("mjcf",))
    return out


def _climb(scene: Path, name: str, slope_deg: float) -> float:
    sim = RoverSim(scene, soil=name, start_xy_m=(-25.0, 0.0))
    g, a = float(np.linalg.norm(sim.model.opt.gravity)), math.radians(slope_deg)
    sim.model.opt.gravity[:] = (-g * math.sin(a), 0.0, -g * math.cos(a))
    sim.reset()
    sim.apply(0.2, 0.0)
    xs = []
    for _ in range(500):
        sim.advance(sim.substeps)
        xs.append(sim.pose()[0][0])
    v = (xs[-1] - xs[249]) / 5.0
    return 1.0 - v / (float(sim.wheel_rates().mean()) * ROVER.wheel_radius_m)


def _theory(name: str, slope_deg: float) -> float:
    from scipy.optimize import brentq

    sl, a = soil(name), math.radians(slope_deg)
    w = ROVER.mass_kg * 3.71 * math.cos(a) / 6
    r, b = ROVER.wheel_radius_m, ROVER.wheel_width_m

    def excess(s: float) -> float:
        dp = wheel_forces(sl, r, b, sinkage_for_load(sl, r, b, w, s), s).drawbar_n
        return float(dp) - w * math.tan(a)

    if excess(0.0) >= 0.0:
        return 0.0  # it rolls free
    return brentq(excess, 0.0, 0.999, xtol=1e-4) if excess(0.999) > 0 else 1.0  # cannot climb


def slope(out: Path | None) -> list[dict[str, object]]:
    with tempfile.TemporaryDirectory() as tmp:
        scene = _scene(Path(tmp) / "flat", np.zeros((81, 241)))
        rows = {}
        print(f"{'soil':16s} " + " ".join(f"{s:>5.1f}" for s in SLOPES_DEG) + "  (deg)")
        for name in soils():
            got = [_climb(scene, name, s) for s in SLOPES_DEG]
            want = [_theory(name, s) for s in SLOPES_DEG]
            rows[name] = (got, want)
            print(f"{name:16s} " + " ".join(f"{g:5.2f}" for g in got) + "  rover")
            print(f"{'':16s} " + " ".join(f"{w:5.2f}" for w in want) + "  one wheel, theory")
    figures: list[dict[str, object]] = [
        {"part": "slope", "soil": name, "slopes_deg": SLOPES_DEG, "rover_slip": got,
         "theory_slip": want} for name, (got, want) in rows.items()]
    if out is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7.0, 4.4), dpi=130)
        for i, (name, (got, want)) in enumerate(rows.items()):
            c = f"C{i}"
            ax.plot(SLOPES_DEG, np.clip(got, 0, 1), "o-", color=c, label=name.replace("_", " "))
            ax.plot(SLOPES_DEG, want, "--", color=c, lw=1)
        ax.set(xlabel="slope (deg)", ylabel="slip 1 - v / (r omega)", ylim=(-0.02, 1.02),
               title="Rover climbing at 0.2 m/s: MuJoCo (dots) and one-wheel theory (dashes)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out)
        print(f"figure: {out}")
    return figures


def ripple() -> dict[str, object]:
    x = (np.arange(481) - 240) * 0.25
    z = np.tile(0.15 * (1 - np.cos(2 * math.pi * x / 5.0)), (81, 1))
    with tempfile.TemporaryDirectory() as tmp:
        scene = _scene(Path(tmp) / "ripples", z)
        sim = RoverSim(scene, soil="megaripple_sand", start_xy_m=(-40.0, 0.0))
        sim.apply(0.2, 0.0)
        xs, slip, sink = [], [], []
        for _ in range(50 * 40):
            sim.advance(sim.substeps)
            xs.append(sim.pose()[0][0])
            slip.append(sim.wheel_soil.slip.mean())
            sink.append(sim.wheel_soil.sinkage_m.max())
        rim = float(sim.wheel_rates().mean()) * ROVER.wheel_radius_m
        v1 = np.diff(xs[::50]) / 1.0
        print(f"megaripple sand ripples 0.30 m x 5 m, 40 s at {rim:.2f} m/s rim speed: "
              f"{xs[-1] - xs[0]:.1f} m driven, slip over 1 s up to "
              f"{1 - v1.min() / rim:.0%}, mean {1 - (xs[-1] - xs[0]) / 40 / rim:.0%}; "
              f"sinkage up to {max(sink) * 100:.1f} cm "
              f"({max(sink) / (2 * ROVER.wheel_radius_m):.0%} of the wheel's diameter)")
    return {"part": "ripple", "driven_m": xs[-1] - xs[0], "rim_m_s": rim,
            "slip_1s_max": 1 - v1.min() / rim, "slip_mean": 1 - (xs[-1] - xs[0]) / 40 / rim,
            "sinkage_max_m": max(sink)}


def _cpu_rate(scene: Path, name: str, hz: float) -> tuple[float, float]:
    sim = RoverSim(scene, soil=name, start_xy_m=(-25.0, 0.0),
                   run=RunConfig(physics_hz=hz, control_hz=10.0 if hz == 100 else 50.0))
    sim.apply(0.2, 0.05)
    steps = round(20.0 / sim.dt_physics_s)
    t0 = time.process_time()
    sim.advance(steps)
    cpu = time.process_time() - t0
    return 20.0 / cpu, steps / cpu


def speed() -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        scene = _scene(Path(tmp) / "flat", np.zeros((81, 241)))
        for hz in (100.0, 500.0):
            for name in ("rigid", "dry_sand"):
                rt, sps = _cpu_rate(scene, name, hz)
                print(f"{hz:5.0f} Hz physics, {name:9s}: {rt:6.1f}x real time per CPU core, "
                      f"{sps:8.0f} steps per CPU s")
                rows.append({"part": "speed", "physics_hz": hz, "soil": name,
                             "real_time_per_cpu": rt, "steps_per_cpu_s": sps})
    return rows


def soil_map(out: Path | None) -> dict[str, object]:
    cfg = ms.SceneConfig.from_dict({"soil": {"enabled": True}})
    scene = ms.build_scene(cfg, seed=7)
    t = scene.provenance.timings_s
    print(f"default scene {scene.heightfield.shape} posts: soil stage {t['soil']:.2f} s of "
          f"{sum(t.values()):.1f} s; "
          + ", ".join(f"{k} {v:.1%}" for k, v in scene.soil.shares().items()))
    figures = {"part": "map", "soil_stage_s": t["soil"], "build_s": sum(t.values()),
               "shares": scene.soil.shares()}
    if out is None:
        return figures
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LightSource, ListedColormap

    hf, m = scene.heightfield, scene.soil
    shade = LightSource(azdeg=315, altdeg=35).hillshade(hf.z_m, dx=hf.cell_size_m,
                                                        dy=hf.cell_size_m, vert_exag=2.0)
    x0, y0, x1, y1 = hf.bounds_xy_m
    colours = {"firm_regolith": "#b07850", "drift_sand": "#f2c14e", "dry_sand": "#e8a33c",
               "megaripple_sand": "#d9480f", "marssim_sand": "#c9a227"}
    fig, ax = plt.subplots(figsize=(6.4, 6.0), dpi=130)
    ax.imshow(shade, cmap="gray", origin="lower", extent=(x0, x1, y0, y1))
    ax.imshow(m.index, cmap=ListedColormap([colours[s.name] for s in m.soils]), alpha=0.45,
              origin="lower", extent=(x0, x1, y0, y1), interpolation="nearest",
              vmin=-0.5, vmax=len(m.soils) - 0.5)
    for s in m.soils:
        ax.plot([], [], "s", color=colours[s.name], label=f"{s.name} ({m.shares()[s.name]:.0%})")
    ax.legend(loc="lower left", fontsize=8)
    ax.set(xlabel="x east (m)", ylabel="y north (m)",
           title="Default scene (seed 7) with [soil] enabled")
    fig.tight_layout()
    fig.savefig(out)
    print(f"figure: {out}")
    return figures


def main(part: str, out: Path | None) -> list[dict[str, object]]:
    runs = {"speed": speed, "ripple": lambda: [ripple()], "slope": lambda: slope(out),
            "map": lambda: [soil_map(out)]}
    figures: list[dict[str, object]] = []
    for name, run in runs.items():
        if part in ("all", name):
            figures += run()
    return figures

