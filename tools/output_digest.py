"""Digest of a scene folder and a run folder: one SHA-256 per file, for comparing outputs across
commits (a refactor must not change a byte).

Timings are the only thing allowed to differ: ``manifest.json`` is hashed without its
``timings_s`` and ``run.json`` without ``wall_s``-like keys.

Usage::

    python tools/output_digest.py build   OUT_DIGEST.json   # builds the default scene + a drive
    python tools/output_digest.py digest  SCENE_DIR RUN_DIR OUT_DIGEST.json   # existing folders
    python tools/output_digest.py compare A.json B.json

``build`` drives 6 s with the camera, the LiDAR, a bag and both dataset exports (TUM RGB-D,
EuRoC).
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
import tempfile
from pathlib import Path

_VOLATILE = {"timings_s", "wall_s", "wall_time_s", "real_time_factor", "elapsed_s", "timings"}


def _strip(doc: object) -> object:
    if isinstance(doc, dict):
        return {k: _strip(v) for k, v in doc.items() if k not in _VOLATILE}
    if isinstance(doc, list):
        return [_strip(v) for v in doc]
    return doc


def _digest(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if not p.is_file():
            continue
        data = p.read_bytes()
        if p.suffix == ".json":
            data = json.dumps(_strip(json.loads(data)), sort_keys=True).encode()
        out[str(p.relative_to(folder))] = hashlib.sha256(data).hexdigest()
    return out


def build(dest: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        (t / "wp.txt").write_text("-5 -5\n5 -5\n5 5\n")
        run = ["marsscene", "build", "--seed", "7", "--out", str(t / "scene")]
        subprocess.run(run, check=True)
        drive = ["marsscene", "drive", str(t / "scene"), "--waypoints", str(t / "wp.txt"),
                 "--seconds", "6", "--camera", "--camera-size", "160x120", "--lidar", "--bag",
                 "--dataset", "tum-rgbd", "--dataset", "euroc", "--out", str(t / "run")]
        subprocess.run(drive, check=True)
        digest(t / "scene", t / "run", dest)


def digest(scene: Path, run: Path, dest: Path) -> None:
    doc = {"scene": _digest(scene), "run": _digest(run)}
    dest.write_text(json.dumps(doc, indent=1, sort_keys=True))


def compare(a: Path, b: Path) -> int:
    da, db = json.loads(a.read_text()), json.loads(b.read_text())
    bad = 0
    for part in ("scene", "run"):
        for name in sorted(set(da[part]) | set(db[part])):
            if da[part].get(name) != db[part].get(name):
                print(f"differs: {part}/{name}")
                bad += 1
    n = sum(len(da[p]) for p in ("scene", "run"))
    print(f"{n - bad} of {n} files identical")
    return 1 if bad else 0


if __name__ == "__main__":
    if sys.argv[1] == "build":
        build(Path(sys.argv[2]))
    elif sys.argv[1] == "digest":
        digest(Path(sys.argv[2]), Path(sys.argv[3]), Path(sys.argv[4]))
    else:
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])))
