"""Run one sweep cell: resolve its config, build, write, optionally drive, record a result row.

A cell folder ``DIR/<cell_id>/`` holds::

    config.toml     fully resolved scene config (seed included): `marsscene build --config`
                    reproduces scene/ byte for byte (manifest.json differs only in timings)
    scene/          the scene (write_scene layout)
    drive/          drive logs (gt.tum, odom.tum, ...) when the sweep has a [drive] table
    result.json     the cell's results row; written last, it marks the cell finished

The folder is assembled in a hidden temporary sibling and renamed into place, so a cell is
either complete or absent. Errors never escape :func:`run_cell`: they become a ``failed`` row.
This module does not import Dask; the same function runs serially or on any Dask worker.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import time
import traceback
from pathlib import Path
from typing import Any

from marsscene._atomic import replacing_dir, write_atomic
from marsscene.errors import ConfigError, MarsSceneError, missing_dependency
from marsscene.sweep.grid import Cell
from marsscene.sweep.spec import DriveSpec

__all__ = ["RESULT_FILE", "cell_hash", "resolve_config", "run_cell", "toml_text"]

log = logging.getLogger("marsscene")

RESULT_FILE = "result.json"


def _drop_none(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _drop_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list | tuple):
        return [_drop_none(v) for v in value]
    return value


def resolve_config(cell: Cell) -> Any:
    """The cell's :class:`~marsscene.SceneConfig` with its seed set (``ConfigError`` if invalid)."""
    from marsscene.config import SceneConfig

    cfg = SceneConfig.from_dict(cell.config)
    return cfg.replace(seed=cfg.seed if cfg.seed is not None else 0)


def toml_text(cfg: Any) -> str:
    """TOML of a resolved config that reads back to the same config (checked)."""
    from marsscene.config import SceneConfig

    try:
        import tomli_w
    except ImportError:
        raise missing_dependency("tomli_w", "sweep") from None
    text = tomli_w.dumps(_drop_none(cfg.to_dict()))
    import tomllib

    back = SceneConfig.from_dict(tomllib.loads(text))
    if back.config_hash() != cfg.config_hash():
        raise ConfigError("the resolved config does not round-trip through TOML")
    return text


def cell_hash(cfg: Any, drive: DriveSpec | None) -> str:
    """SHA-256 of the cell's resolved scene config and drive spec (a finished cell's key)."""
    doc = {"scene": cfg.to_dict(), "drive": drive.to_dict() if drive is not None else None}
    blob = json.dumps(doc, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


def _finished(final: Path, digest: str) -> dict[str, Any] | None:
    try:
        row = json.loads((final / RESULT_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if row.get("status") not in ("ok", "skipped") or row.get("config_hash") != digest:
        return None
    if not all((final / rel).is_file() for rel in row.get("outputs", ())):
        return None
    return row


def _scene_row(scene: Any) -> dict[str, Any]:
    row: dict[str, Any] = {
        "n_craters": len(scene.craters) if scene.craters is not None else 0,
        "n_rocks": len(scene.rocks) if scene.rocks is not None else 0,
    }
    for stage, dt in scene.provenance.timings_s.items():
        row[f"t_{stage}_s"] = dt
    lit = scene.lighting
    for key in ("tau", "sun_azimuth_deg", "sun_elevation_deg", "direct_normal_w_m2",
                "diffuse_horizontal_w_m2", "visibility_m"):
        row[key] = round(float(getattr(lit, key)), 9) if lit is not None else None
    return row


def _write_json(path: Path, doc: dict[str, Any]) -> None:
    write_atomic(path, json.dumps(doc, indent=1, sort_keys=True, default=str) + "\n")


def run_cell(
    cell: Cell, out_dir: str | os.PathLike[str], drive: DriveSpec | None = None, *,
    force: bool = False,
) -> dict[str, Any]:
    """Build (and drive) one cell into ``out_dir/<cell_id>/``; return its results row.

    The row has ``cell_id``, the swept ``params``, ``status`` (``ok`` / ``failed`` /
    ``skipped``), ``error``, timings (``t_*_s``), crater/rock counts, lighting values and, with
    a drive, its metrics. A cell already finished with the same config hash is ``skipped``
    (its stored row is returned) unless ``force``.
    """
    from marsscene import build_scene, write_scene

    root = Path(out_dir).resolve()
    final = root / cell.cell_id
    row: dict[str, Any] = {"cell_id": cell.cell_id, "params": dict(cell.params),
                           "status": "failed", "error": ""}
    t_start = time.perf_counter()
    try:
        cfg = resolve_config(cell)
        row["seed"] = cfg.seed
        digest = cell_hash(cfg, drive)
        done = None if force else _finished(final, digest)
        if done is not None:
            return {**done, "params": dict(cell.params), "status": "skipped"}
        with replacing_dir(final) as tmp:  # the cell folder is complete or absent
            (tmp / "config.toml").write_text(toml_text(cfg), encoding="utf-8")
            t0 = time.perf_counter()
            scene = build_scene(cfg, seed=cfg.seed)
            row["t_build_s"] = round(time.perf_counter() - t0, 4)
            t0 = time.perf_counter()
            written = write_scene(scene, tmp / "scene")
            row["t_write_s"] = round(time.perf_counter() - t0, 4)
            row.update(_scene_row(scene))
            outputs = ["config.toml"] + [
                p.relative_to(tmp).as_posix() for ps in written.values() for p in ps
            ]
            if drive is not None:
                from marsscene.sweep.drive import drive_cell

                t0 = time.perf_counter()
                row.update(drive_cell(tmp / "scene", drive, tmp / "drive"))
                row["t_drive_s"] = round(time.perf_counter() - t0, 4)
                outputs += ["drive/gt.tum", "drive/odom.tum"]
            row.update(status="ok", config_hash=digest, outputs=outputs)
            row["t_total_s"] = round(time.perf_counter() - t_start, 4)
            _write_json(tmp / RESULT_FILE, row)
    except MarsSceneError as err:
        row["status"] = "failed"
        row["error"] = f"{type(err).__name__}: {err}"
    except Exception as err:  # one failing cell never stops the sweep
        row["status"] = "failed"
        last = traceback.extract_tb(err.__traceback__)[-1]
        row["error"] = f"{type(err).__name__}: {err} ({Path(last.filename).name}:{last.lineno})"
    if row["status"] == "failed":
        row["error"] = " ".join(row["error"].split())  # one line in results.csv
        row["t_total_s"] = round(time.perf_counter() - t_start, 4)
        log.warning("cell %s failed: %s", cell.cell_id, row["error"])
        try:  # leave only the failure record (and no stale outputs) in the cell folder
            shutil.rmtree(final, ignore_errors=True)
            final.mkdir(parents=True, exist_ok=True)
            _write_json(final / RESULT_FILE, row)
        except OSError:
            pass
    return row
