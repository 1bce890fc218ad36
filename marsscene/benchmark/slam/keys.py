"""What the stages of a SLAM benchmark cell are keyed by: a hash of every input of its drive
and of each method's row, so that a resumed benchmark (:mod:`marsscene.benchmark.slam.run`)
redoes only what changed or never finished."""

from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Any

from marsscene._atomic import write_atomic
from marsscene.benchmark.slam.odometry_prior import PRIOR_MODEL
from marsscene.benchmark.slam.spec import MethodSpec, SceneSpec, SlamSpec

__all__ = ["BATCH_ENGINE", "ERROR_FILE", "batch_error", "batch_key", "digest", "drive_key",
           "method_file", "read_json", "write_json"]

#: The engine of a batch drive (``run.json``'s ``batch.engine``), part of its key.
BATCH_ENGINE = "mujoco_warp"
#: In a cell folder: why its batch drive (:mod:`.device`) did not finish.
ERROR_FILE = "drive_error.txt"


def digest(doc: Any) -> str:
    """SHA-256 of ``doc`` as canonical JSON (keys sorted, values by ``str`` where not JSON)."""
    blob = json.dumps(doc, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


def read_json(path: Path) -> dict[str, Any] | None:
    """The JSON object in ``path``; None when it is missing, unreadable or not an object."""
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) else None


def write_json(path: Path, doc: dict[str, Any]) -> None:
    """Write ``doc`` to ``path`` atomically (a reader sees the old file or the new one)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, json.dumps(doc, indent=1, sort_keys=True, default=str) + "\n")


def drive_key(spec: SlamSpec, scene: SceneSpec, lidar: bool, scene_hash: str, camera: bool,
              live: tuple[MethodSpec, ...]) -> tuple[str, bool]:
    """The key of a cell's drive (a hash of everything it depends on), and whether it bags."""
    route_doc: dict[str, Any] = dataclasses.asdict(scene.route)
    if scene.route.file is not None:
        route_doc["file_sha256"] = hashlib.sha256(Path(scene.route.file).read_bytes()).hexdigest()
    run = spec.run_config(lidar=lidar, camera=camera)
    bag = (lidar and spec.needs_bag()) or (bool(spec.sensors.get("bag", False))
                                           and (run.camera is not None or run.lidar is not None))
    key = digest({"scene": scene_hash, "route": route_doc, "seconds": scene.seconds,
                  "sensors": {k: v for k, v in spec.sensors.items()
                              if (lidar or k != "lidar") and (camera or k != "camera")},
                  "noise": dataclasses.asdict(run.noise),  # the profile's values, defaults too
                  "lidar": lidar, "bag": bag,
                  "live": [dataclasses.asdict(m) for m in live],
                  **({"prior": PRIOR_MODEL} if live else {})})
    return key, bag


def method_file(spec: SlamSpec, method: MethodSpec, cell_dir: Path, drive: str
                ) -> tuple[Path, str]:
    """Where a method's row lies, and the key of its inputs (``drive``: the drive's key)."""
    key = digest({"method": dataclasses.asdict(method), "drive": drive,
                  "min_tracked": spec.min_tracked_fraction, "rpe_m": spec.rpe_distance_m,
                  **({"prior": PRIOR_MODEL} if method.options.get("wheel_prior") else {})})
    return cell_dir / "methods" / f"{method.name}.json", key


def batch_key(key: str) -> str:
    """The key of a batch drive (:mod:`.device`) of the inputs whose CPU drive has ``key``:
    its physics differs, so the two are never taken for each other."""
    return digest({"drive": key, "engine": BATCH_ENGINE})


def batch_error(cell_dir: Path, device: str) -> str:
    """The one-line reason the cell has no batch drive on ``device``."""
    try:
        why = (cell_dir / ERROR_FILE).read_text(encoding="utf-8").strip()
    except OSError:
        why = "it was not driven"
    return f"the cell's batch drive on {device} did not finish: {why}"
