"""A soil map: which soil lies at each post of a grid over the terrain, and its files in a
scene folder (``soil/soil_map.png``, ``soil/soils.json``)."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene.errors import ConfigError
from marsscene.rover.terramechanics import Soil

__all__ = ["SOIL_DIR", "SoilMap", "read_soil_map", "write_soil_map"]

#: The scene folder's soil files: ``soil_map.png`` (8-bit soil indices, row 0 = north, image
#: order) and ``soils.json`` (the soils by index with their parameters and sources, the grid's
#: bounds).
SOIL_DIR = "soil"


@dataclass(frozen=True, eq=False)
class SoilMap:
    """Which soil lies where: ``index`` (rows along y from ``y0``, columns along x from ``x0``,
    as the heightfield's posts) picks one of ``soils`` at each post of a grid over
    ``bounds_xy_m = (x0, y0, x1, y1)``. One soil everywhere: ``SoilMap.uniform(soil)``.
    """

    soils: tuple[Soil, ...]
    index: NDArray[np.uint8]
    bounds_xy_m: tuple[float, float, float, float]

    def __post_init__(self) -> None:
        if self.index.ndim != 2 or not len(self.soils) or int(self.index.max()) >= len(
                self.soils):
            raise ConfigError(f"a soil map needs a 2-D index below its {len(self.soils)} soils")

    @classmethod
    def uniform(cls, soil: Soil) -> SoilMap:
        return cls((soil,), np.zeros((1, 1), np.uint8), (0.0, 0.0, 1.0, 1.0))

    def at(self, xy_m: NDArray[np.float64]) -> NDArray[np.intp]:
        """The soil index under points ``xy_m`` (N, 2) (nearest post; edges extend)."""
        rows, cols = self.index.shape
        x0, y0, x1, y1 = self.bounds_xy_m
        c = np.rint((xy_m[:, 0] - x0) / max(x1 - x0, 1e-9) * (cols - 1)).astype(np.intp)
        r = np.rint((xy_m[:, 1] - y0) / max(y1 - y0, 1e-9) * (rows - 1)).astype(np.intp)
        return self.index[np.clip(r, 0, rows - 1), np.clip(c, 0, cols - 1)].astype(np.intp)

    def shares(self) -> dict[str, float]:
        """Each soil's share of the map's posts."""
        counts = np.bincount(self.index.ravel(), minlength=len(self.soils)) / self.index.size
        return {s.name: float(c) for s, c in zip(self.soils, counts, strict=True)}


def write_soil_map(soil_map: SoilMap, scene_dir: Path) -> list[Path]:
    """Write ``SOIL_DIR/soil_map.png`` and ``SOIL_DIR/soils.json`` under ``scene_dir``."""
    from PIL import Image

    out = Path(scene_dir) / SOIL_DIR
    out.mkdir(parents=True, exist_ok=True)
    png, meta = out / "soil_map.png", out / "soils.json"
    Image.fromarray(np.ascontiguousarray(soil_map.index[::-1]), mode="L").save(png)
    doc = {
        "map": png.name,
        "map_rows": "north first (image order); pixel value = index into soils",
        "bounds_xy_m": [round(float(v), 6) for v in soil_map.bounds_xy_m],
        "soils": [dataclasses.asdict(s) for s in soil_map.soils],
        "shares": {k: round(v, 6) for k, v in soil_map.shares().items()},
    }
    meta.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return [png, meta]


def read_soil_map(scene_dir: str | Path) -> SoilMap | None:
    """The soil map of a scene folder (None: the scene has none)."""
    from PIL import Image

    meta = Path(scene_dir) / SOIL_DIR / "soils.json"
    if not meta.is_file():
        return None
    try:
        doc = json.loads(meta.read_text(encoding="utf-8"))
        with Image.open(meta.parent / doc["map"]) as im:
            index = np.asarray(im, dtype=np.uint8)[::-1].copy()
        soils = tuple(Soil(**s) for s in doc["soils"])
        return SoilMap(soils, index, tuple(float(v) for v in doc["bounds_xy_m"]))  # type: ignore[arg-type]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise ConfigError(f"{meta}: not a readable soil map ({err})") from None
