"""Build a scene with a Parquet rock catalogue and query it with pyarrow.

    python examples/rock_catalogue_parquet.py [OUT_DIR]

Writes a 200 m x 200 m procedural scene (MJCF only, to keep it quick) with
``[export] rock_catalogue = "parquet"``, then reads ``rocks.parquet`` back: the column units
stored in the file, the rock count, the cumulative number of rocks larger than a few
diameters, and the rocks that are MuJoCo collision geoms.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq

import marsscene as ms


def main(out: Path) -> dict[str, float]:
    cfg = ms.SceneConfig.from_dict({
        "terrain": {"source": "procedural", "size_m": [200.0, 200.0], "post_m": 0.5},
        "rocks": {"k": 0.05, "d_min_m": 0.1},
        "export": {"formats": ["mjcf"], "rock_catalogue": "parquet"},
    })
    ms.write_scene(ms.build_scene(cfg, seed=7), out)
    table = pq.read_table(out / "rocks.parquet")
    units = {f.name: f.metadata[b"unit"].decode() for f in table.schema}
    print("columns:", ", ".join(f"{name} [{unit}]" for name, unit in units.items()))
    d = table.column("diameter_m").to_numpy()
    print(f"{table.num_rows:,} rocks on {200 * 200:,} m^2")
    for d_min in (0.1, 0.3, 1.0):
        print(f"  D >= {d_min:3.1f} m: {int((d >= d_min).sum()):7,d}")
    contact = table.filter(pc.field("in_mjcf"))
    print(f"{contact.num_rows} rocks are MuJoCo geoms; the largest is "
          f"{pc.max(contact.column('diameter_m')).as_py():.2f} m across")
    return {"rocks": float(table.num_rows), "d_max_m": float(np.max(d)),
            "mjcf_rocks": float(contact.num_rows)}


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "scenes/parquet_demo"))
