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


_ZERO, _MINUS, _DOT = ord("0"), ord("-"), ord(".")
_CHUNK_ROWS = 1 << 15  # rows formatted at a time: the byte matrix stays in the CPU cache


class _Field:
    """One column as fixed-point text: ``[sign slot][int digits][.decimals]`` then ``sep``,
    right-aligned in a fixed width with 0 bytes as padding (dropped at the end)."""

    def __init__(self, values: NDArray[Any], decimals: int, sep: str) -> None:
        v = np.asarray(values, dtype=np.float64)
        self.scaled = np.rint(np.abs(v) * 10**decimals).astype(np.int64)
        if len(v) and self.scaled.max() < 2**31:  # int32 digit arithmetic is faster
            self.scaled = self.scaled.astype(np.int32)
        self.neg = (v < 0) & (self.scaled > 0)
        self.decimals = decimals
        top = int(self.scaled.max()) // 10**decimals if len(v) else 0
        self.int_width = len(str(top))
        self.sep = ord(sep)
        self.width = 1 + self.int_width + (1 + decimals if decimals else 0) + 1

    def write(self, out: NDArray[np.uint8], rows: slice) -> None:
        """Write rows ``rows`` of the field into ``out`` (its own columns, 0-padded)."""
        scaled = self.scaled[rows]
        whole = scaled // 10**self.decimals if self.decimals else scaled
        q = whole.copy()
        lead = self.int_width  # column of the units digit; column 0 is the sign slot
        for p in range(self.int_width):
            digit = (q % 10).astype(np.uint8)
            q //= 10
            digit += _ZERO
            if p:  # blank leading zeros, keep the units digit
                digit[whole < 10**p] = 0
            out[:, lead - p] = digit
        neg = np.flatnonzero(self.neg[rows])
        if len(neg):  # the sign sits just before the first digit
            n_digits = np.searchsorted(10 ** np.arange(1, self.int_width + 1, dtype=np.int64),
                                       whole[neg], side="right") + 1
            out[neg, lead - n_digits] = _MINUS
        col = lead + 1
        if self.decimals:
            out[:, col] = _DOT
            frac = scaled % 10**self.decimals
            for p in range(self.decimals):
                out[:, col + self.decimals - p] = (frac % 10).astype(np.uint8) + _ZERO
                frac //= 10
            col += self.decimals + 1
        out[:, col] = self.sep


def _text_rows(fields: list[_Field], n: int) -> bytes:
    """The rows' text: formatted in cache-sized chunks, padding dropped."""
    widths = [f.width for f in fields]
    offsets = np.concatenate([[0], np.cumsum(widths)])
    parts = []
    for start in range(0, n, _CHUNK_ROWS):
        rows = slice(start, min(start + _CHUNK_ROWS, n))
        block = np.zeros((rows.stop - rows.start, int(offsets[-1])), dtype=np.uint8)
        for f, lo, hi in zip(fields, offsets[:-1], offsets[1:], strict=True):
            f.write(block[:, lo:hi], rows)
        flat = block.ravel()
        parts.append(flat[flat != 0].tobytes())
    return b"".join(parts)


def rock_catalog_columns(scene: Any) -> dict[str, NDArray[Any]]:
    """The catalogue's columns (:data:`COLUMNS`, in order) as arrays (no copies of the rocks)."""
    from marsscene.rocks.report import mjcf_focus, mjcf_rock_selection

    rocks = scene.rocks
    n = len(rocks)
    in_mjcf = np.zeros(n, dtype=bool)
    in_mjcf[mjcf_rock_selection(rocks, scene.config.rocks, within=mjcf_focus(scene))] = True
    pos = rocks.position_xyz_m
    return {"id": np.arange(n, dtype=np.int64), "x_m": pos[:, 0], "y_m": pos[:, 1],
            "z_m": pos[:, 2], "diameter_m": rocks.diameter_m, "height_m": rocks.height_m,
            "burial_m": rocks.burial_m, "prototype": rocks.prototype, "in_mjcf": in_mjcf}


def _csv_bytes(columns: dict[str, NDArray[Any]]) -> bytes:
    header = (",".join(COLUMNS) + "\n").encode("ascii")
    n = len(columns["id"])
    if n == 0:
        return header
    fields = [_Field(columns[name], 4 if name.endswith("_m") else 0,
                     "\n" if i == len(COLUMNS) - 1 else ",")
              for i, name in enumerate(COLUMNS)]
    return header + _text_rows(fields, n)


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
