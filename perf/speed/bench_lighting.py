"""Lighting benchmark: vectorised Mars24, irradiance models, one compute_lighting, sky texture.

Run: ``python perf/run.py lighting``."""

from __future__ import annotations

import time

import numpy as np

from perf._measure import measure
from perf.suite import Param

PARAMS = (Param("n", int, "instants and (z, tau) pairs per vectorised call", quick=10_000,
                full=1_000_000),)
_N = {"n": 1_000_000}  # set by main before the measured calls (forked children inherit it)


def _mars24() -> float:
    from marsscene.lighting import sun_track

    t0 = time.perf_counter()
    sun_track("2021-02-18T00:00Z", hours=_N["n"] / 60.0, step_min=1.0, lat_deg=18.4447,
              lon_east_deg=77.4508)
    return time.perf_counter() - t0


def _irradiance(model: str) -> float:
    from marsscene.lighting import diffuse_irradiance_w_m2

    rng = np.random.default_rng(0)
    z = rng.uniform(0.0, 89.0, _N["n"])
    tau = rng.uniform(0.1, 6.0, _N["n"])
    t0 = time.perf_counter()
    diffuse_irradiance_w_m2(z, tau=tau, model=model)  # type: ignore[arg-type]
    return time.perf_counter() - t0


def _table() -> float:
    return _irradiance("table")


def _polynomial() -> float:
    return _irradiance("polynomial")


def _delta_eddington() -> float:
    return _irradiance("delta_eddington")


def _compute_and_sky() -> float:
    from marsscene.export.usd.lighting import sky_texture
    from marsscene.lighting import LightingConfig, compute_lighting

    t0 = time.perf_counter()
    for _ in range(100):
        lt = compute_lighting(LightingConfig(utc="2021-02-18T20:55Z", tau=0.5), lat_deg=18.4447,
                              lon_east_deg=77.4508)
        sky_texture(lt)
    return (time.perf_counter() - t0) / 100


def main(n: int) -> list[dict[str, object]]:
    _N["n"] = n
    figures: list[dict[str, object]] = []
    for name, fn in ((f"Mars24 sun track, {n:.0e} instants", _mars24),
                     (f"A&F table diffuse, {n:.0e} (z, tau)", _table),
                     (f"A&F polynomial diffuse, {n:.0e}", _polynomial),
                     (f"delta-Eddington diffuse, {n:.0e}", _delta_eddington),
                     ("compute_lighting + sky texture (per call)", _compute_and_sky)):
        wall, peak_mb, inner = measure(fn)
        print(f"{name:45s} inner {inner * 1000:9.2f} ms  process {wall:6.2f} s  "
              f"peak RSS {peak_mb:7.1f} MB")
        figures.append({"case": name, "inner_ms": inner * 1000, "process_s": wall,
                        "peak_rss_mb": peak_mb})
    return figures

