"""A rover drive and a helicopter scout flight over one place: the rover's and the scout's run
folders share the scene's map frame (ground and aerial views for cross-view localization).

Run: ``python examples/scout_flight.py OUT_DIR`` (about a minute on a 2-core CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

import marsscene as ms
from marsscene.scout import FlightPlan, fly


def main(out: Path) -> None:
    cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [60, 60]}})
    ms.write_scene(ms.build_scene(cfg, seed=1), out / "scene")
    route = [[-8.0, 0.0], [8.0, 0.0]]
    rover = ms.drive(out / "scene", waypoints=route, seconds=20.0, out_dir=out / "rover", seed=1)
    scout = fly(out / "scene", [[-8.0, 0.0], [8.0, 0.0]], plan=FlightPlan(altitude_m=8.0),
                out_dir=out / "scout", seed=1)
    print(f"rover: {rover.summary['status']}, {len(rover.gt.timestamps_s)} poses in "
          f"{out / 'rover' / 'gt.tum'}")
    print(f"scout: reached {scout.reached}, landed at {scout.touchdown_s:.1f} s, "
          f"{scout.summary['images']} images in {out / 'scout' / 'images'}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "scout_example"))
