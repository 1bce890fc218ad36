"""Rock catalogue written beside the scene: ``rocks.csv`` (one row per rock), and/or
``rocks.parquet`` (``[export] rock_catalogue``; :mod:`marsscene.export.catalog_parquet`).

Columns: ``id, x_m, y_m, z_m, diameter_m, height_m, burial_m, prototype, in_mjcf`` —
``(x, y, z)`` is the rock's base centre in the scene frame (z = surface - burial), ``height_m``
the exposed height, ``prototype`` the index into the USD prototypes (``rock_NN``), ``in_mjcf``
1 if the rock is a MuJoCo collision geom. Numbers are fixed-point (4 decimals, 0.1 mm), formatted
by a vectorised writer so a million rows take well under a second and bytes are reproducible.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["ROCK_CATALOG", "rock_catalog_bytes", "rock_catalog_columns", "write_rock_catalog"]

ROCK_CATALOG = "rocks.csv"
COLUMNS = ("id", "x_m", "y_m", "z_m", "diameter_m", "height_m", "burial_m", "prototype",
           "in_mjcf")


#: ASCII digits of 0000..9999, shape (10000, 4): numbers are formatted 4 digits per gather.
_DIGITS4 = (
    (np.arange(10000)[:, None] // 10 ** np.arange(3, -1, -1)[None, :]) % 10 + ord("0")
).astype(np.uint8)


def _chunks4(values: NDArray[np.int64], groups: int) -> NDArray[np.uint8]:
    """Zero-padded decimal digits of non-negative ints, ``4 * groups`` chars per row."""
    out = []
    for g in range(groups - 1, -1, -1):
        out.append(_DIGITS4[(values // 10 ** (4 * g)) % 10000])
    return np.concatenate(out, axis=1)


def _fixed(values: NDArray[np.float64], decimals: int) -> NDArray[np.uint8]:
    """ASCII fixed-point text of each value as a (N, W) byte matrix, 0 = padding.

    ``decimals`` is 0 or 4.
    """
    scaled = np.rint(np.abs(values) * 10**decimals).astype(np.int64)
    neg = (values < 0) & (scaled > 0)
    whole = scaled // 10**decimals
    top = int(whole.max()) if len(whole) else 0
    groups = max(1, (len(str(top)) + 3) // 4)
    int_chars = _chunks4(whole, groups)
    width = int_chars.shape[1]
    # blank leading zeros of the integer part (keep the units digit)
    n_digits = np.searchsorted(10 ** np.arange(1, width, dtype=np.int64), whole, side="right") + 1
    first = width - n_digits
    significant = np.arange(width)[None, :] >= first[:, None]
    body = np.zeros((len(values), width + 1), dtype=np.uint8)
    body[:, 1:] = np.where(significant, int_chars, 0)
    rows = np.flatnonzero(neg)
    body[rows, first[rows]] = ord("-")  # the slot just before the first digit
    parts = [body]
    if decimals:
        parts += [np.full((len(values), 1), ord("."), np.uint8),
                  _DIGITS4[scaled % 10**decimals]]
    return np.concatenate(parts, axis=1)


def rock_catalog_columns(scene: Any) -> dict[str, NDArray[Any]]:
    """The catalogue's columns (:data:`COLUMNS`, in order) as arrays (no copies of the rocks)."""
    from marsscene.rocks.report import mjcf_rock_selection

    rocks = scene.rocks
    n = len(rocks)
    in_mjcf = np.zeros(n, dtype=bool)
    in_mjcf[mjcf_rock_selection(rocks, scene.config.rocks)] = True
    pos = rocks.position_xyz_m
    return {"id": np.arange(n, dtype=np.int64), "x_m": pos[:, 0], "y_m": pos[:, 1],
            "z_m": pos[:, 2], "diameter_m": rocks.diameter_m, "height_m": rocks.height_m,
            "burial_m": rocks.burial_m, "prototype": rocks.prototype, "in_mjcf": in_mjcf}


def _csv_bytes(columns: dict[str, NDArray[Any]]) -> bytes:
    header = (",".join(COLUMNS) + "\n").encode("ascii")
    n = len(columns["id"])
    if n == 0:
        return header
    blocks = []
    for i, name in enumerate(COLUMNS):
        decimals = 4 if name.endswith("_m") else 0
        blocks.append(_fixed(np.asarray(columns[name], dtype=np.float64), decimals))
        sep = "\n" if i == len(COLUMNS) - 1 else ","
        blocks.append(np.full((n, 1), ord(sep), np.uint8))
    table = np.concatenate(blocks, axis=1).ravel()
    return header + table[table != 0].tobytes()


def rock_catalog_bytes(scene: Any) -> bytes:
    """The CSV text of the scene's rock catalogue."""
    return _csv_bytes(rock_catalog_columns(scene))


def write_rock_catalog(scene: Any, out_dir: Path) -> list[Path]:
    """Write ``rocks.csv`` and/or ``rocks.parquet`` beside the scene, as
    ``scene.config.export.rock_catalogue`` says; nothing when the stage is disabled."""
    if scene.rocks is None:
        return []
    kind = scene.config.export.rock_catalogue
    columns = rock_catalog_columns(scene)
    written = []
    if kind in ("csv", "both"):
        path = Path(out_dir) / ROCK_CATALOG
        path.write_bytes(_csv_bytes(columns))
        written.append(path)
    if kind in ("parquet", "both"):
        from marsscene.export.catalog_parquet import ROCK_PARQUET, write_rock_parquet

        written.append(write_rock_parquet(columns, Path(out_dir) / ROCK_PARQUET))
    return written
