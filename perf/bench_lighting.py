"""Lighting benchmark: vectorised Mars24, irradiance models, one compute_lighting, sky texture."""

from __future__ import annotations

import time

import numpy as np
from _measure import measure

N = 1_000_000


def _mars24() -> float:
    from marsscene.lighting import sun_track

    t0 = time.perf_counter()
    sun_track("2021-02-18T00:00Z", hours=N / 60.0, step_min=1.0, lat_deg=18.4447,
              lon_east_deg=77.4508)
    return time.perf_counter() - t0


def _irradiance(model: str) -> float:
    from marsscene.lighting import diffuse_irradiance_w_m2

    rng = np.random.default_rng(0)
    z = rng.uniform(0.0, 89.0, N)
    tau = rng.uniform(0.1, 6.0, N)
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


def main() -> None:
    for name, fn in (("Mars24 sun track, 1e6 instants", _mars24),
                     ("A&F table diffuse, 1e6 (z, tau)", _table),
                     ("A&F polynomial diffuse, 1e6", _polynomial),
                     ("delta-Eddington diffuse, 1e6", _delta_eddington),
                     ("compute_lighting + sky texture (per call)", _compute_and_sky)):
        wall, peak_mb, inner = measure(fn)
        print(f"{name:45s} inner {inner * 1000:9.2f} ms  process {wall:6.2f} s  "
              f"peak RSS {peak_mb:7.1f} MB")


if __name__ == "__main__":
    main()
