"""DEM ingest benchmark: a 4000 x 4000 crop of a 6000 x 20000 PDS3 DTM, resampled to 0.5 m.

Writes a synthetic HiRISE-style DTEEC ``.IMG`` (attached, assembled label; 20000 lines x 6000
samples float32, 480 MB, NULL outside the stereo strip and a small hole inside) in row blocks,
then measures in a fresh process: windowed read, Laplace fill, bilinear resampling to 0.5 m
(64 M posts). Target (issue 3): < 5 s and < 2 GB. ``--lines`` and ``--samples`` scale the DTM
(the crop and the hole keep their places in proportion).

Then the whole DTM as a level-of-detail scene (issue 15): ``terrain.lod`` with a 4 m outer
level (the DTM read averaged strip by strip, :mod:`marsscene.pipeline.dem_lod`) and a 1 km focus
at 0.25 m read by window from the DTM's 1 m posts: wall time and peak RSS against the 480 MB
of samples a full read would hold (and its float64 work copies).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from marsscene.testing.pds3 import write_pds3_dtm
from perf._measure import measure
from perf.suite import Param

PARAMS = (Param("lines", int, "DTM lines (rows, 1 m; a multiple of 500)", quick=4_000,
                full=20_000),
          Param("samples", int, "DTM samples (columns, 1 m)", quick=3_000, full=6_000))
_DTM = {"lines": 20_000, "samples": 6_000}  # set by main (forked children inherit it)
_PATH: Path | None = None


def _crop() -> tuple[int, int, int, int]:
    """row_off, col_off, rows, cols: (8000, 1000, 4000, 4000) of the full 20000 x 6000."""
    lines, samples = _DTM["lines"], _DTM["samples"]
    return (2 * lines // 5, samples // 6, lines // 5, 2 * samples // 3)


def dtm_surface(x: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A HiRISE-shaped DTM's elevations (m) at columns ``x`` (samples,) and rows ``y`` (rows, 1):
    30 m swells, a gentle tilt and 0.3 m noise about -2,500 m (float32, rows x samples)."""
    return (-2500.0 + 30.0 * np.sin(x / 700.0) * np.cos(y / 900.0) + 0.002 * y
            + rng.standard_normal((y.shape[0], x.shape[0]), dtype=np.float32) * 0.3)


def _blocks(rows_per_block: int = 500):
    lines, samples = _DTM["lines"], _DTM["samples"]
    rng = np.random.default_rng(7)
    x = np.arange(samples, dtype=np.float32)
    for r0 in range(0, lines, rows_per_block):
        y = np.arange(r0, r0 + rows_per_block, dtype=np.float32)[:, None]
        z = dtm_surface(x, y, rng)
        z[:, :300] = np.nan  # outside the stereo strip (MISSING_CONSTANT)
        z[:, -300:] = np.nan
        if r0 <= lines // 2 < r0 + rows_per_block:
            c = samples // 2
            z[:50, c:c + 50] = np.nan  # a 50 x 50 hole inside the crop
        yield z.astype(np.float32)


def _read_and_resample() -> dict[str, float]:
    import warnings

    from marsscene.dem import ops
    from marsscene.dem.io import read_dem
    from marsscene.errors import NodataFilledWarning

    assert _PATH is not None
    t0 = time.perf_counter()
    dem = read_dem(_PATH, crop=ops.Crop(pixels=_crop()))
    t1 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NodataFilledWarning)
        dem, n_filled = ops.fill_nodata(dem)
    t2 = time.perf_counter()
    out = ops.resample(dem, 0.5)
    t3 = time.perf_counter()
    return {"read_s": t1 - t0, "fill_s": t2 - t1, "resample_s": t3 - t2,
            "filled": float(n_filled), "rows": float(out.shape[0]), "cols": float(out.shape[1]),
            "mean_in": float(dem.elevation_m.mean()), "mean_out": float(out.elevation_m.mean())}


def _whole_dtm_lod() -> dict[str, float]:
    import warnings

    import marsscene as ms

    assert _PATH is not None
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "dem", "dem_path": str(_PATH), "lod": True, "post_m": 4.0,
                    "focus_size_m": 1000.0},
        "craters": {"enabled": False}, "rocks": {"enabled": False}})
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = ms.build_scene(cfg, seed=7)
    assert scene.outer is not None
    return {"build_s": time.perf_counter() - t0,
            "outer_rows": float(scene.outer.heightfield.shape[0]),
            "outer_cols": float(scene.outer.heightfield.shape[1]),
            "focus_posts_M": scene.heightfield.z_m.size / 1e6,
            "terrain_s": float(scene.provenance.timings_s["terrain"]),
            "tiles_s": float(scene.provenance.timings_s["tiles"])}


def main(lines: int, samples: int) -> list[dict[str, float]]:
    global _PATH
    _DTM.update(lines=lines, samples=samples)
    crop = _crop()
    with tempfile.TemporaryDirectory(prefix="bench_dem_") as tmp:
        t0 = time.perf_counter()
        _PATH = write_pds3_dtm(Path(tmp) / "DTEEC_BENCH_U01.IMG", shape=(lines, samples),
                               blocks=_blocks())
        print(f"wrote {lines} x {samples} PDS3 DTM ({_PATH.stat().st_size / 1e6:.0f} MB) "
              f"in {time.perf_counter() - t0:.1f} s")
        wall, peak_mb, extra = measure(_read_and_resample)
        lod_wall, lod_peak_mb, lod = measure(_whole_dtm_lod)
    print(f"crop {crop[2]} x {crop[3]} at 1 m -> {int(extra['rows'])} x {int(extra['cols'])} "
          f"at 0.5 m (bilinear); filled {int(extra['filled'])} posts")
    print(f"  read {extra['read_s']:.2f} s, fill {extra['fill_s']:.2f} s, "
          f"resample {extra['resample_s']:.2f} s")
    print(f"  wall {wall:.2f} s (target < 5 s), peak RSS {peak_mb:.0f} MB (target < 2048 MB)")
    print(f"  mean elevation {extra['mean_in']:.4f} -> {extra['mean_out']:.4f} m")
    print(f"whole DTM, level of detail: outer {int(lod['outer_rows'])} x {int(lod['outer_cols'])}"
          f" at 4 m (read averaged), focus {lod['focus_posts_M']:.1f} M posts at 0.25 m")
    print(f"  terrain {lod['terrain_s']:.2f} s, tiles {lod['tiles_s']:.2f} s, wall "
          f"{lod_wall:.2f} s, peak RSS {lod_peak_mb:.0f} MB (the DTM's samples alone: "
          f"{lines * samples * 4 / 1e6:.0f} MB)")
    return [{"case": "crop at 0.5 m", **extra, "wall_s": wall, "peak_rss_mb": peak_mb},
            {"case": "whole DTM, level of detail", **lod, "wall_s": lod_wall,
             "peak_rss_mb": lod_peak_mb}]

