"""The sweep grid: Cartesian product of the axes -> cells with stable, readable ids (pure)."""

from __future__ import annotations

import hashlib
import itertools
import json
import re
from dataclasses import dataclass
from typing import Any

from marsscene.errors import ConfigError
from marsscene.sweep.spec import SweepSpec, set_dotted

__all__ = ["Cell", "cell_id", "expand_grid"]

_UNSAFE = re.compile(r"[^A-Za-z0-9.+-]+")
_MAX_ID_CHARS = 200


@dataclass(frozen=True)
class Cell:
    """One grid point: its id, the swept values and the resolved scene config mapping."""

    cell_id: str
    params: dict[str, Any]
    """Dotted key -> value, in axis order."""
    config: dict[str, Any]
    """Base config with the swept values set (validated when the cell is built)."""
    seed: int | None
    """The cell's seed (swept ``seed``, else the base config's, else 0 at build time)."""


def _value_text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return f"{value:.1f}"
    if isinstance(value, list | tuple):
        return "x".join(_value_text(v) for v in value)
    return _UNSAFE.sub("-", str(value)).strip("-") or "empty"


def cell_id(params: dict[str, Any]) -> str:
    """Readable folder name of a cell, e.g. ``seed=1__lighting.tau=0.3__rocks.k=0.02``.

    Characters outside ``[A-Za-z0-9.+-]`` in values become ``-``; very long ids are cut and
    end in a hash of the parameters so they stay unique.
    """
    text = "__".join(f"{k}={_value_text(v)}" for k, v in params.items())
    if len(text) > _MAX_ID_CHARS:
        digest = hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:10]
        text = f"{text[: _MAX_ID_CHARS - 12]}__{digest}"
    return text


def expand_grid(spec: SweepSpec) -> list[Cell]:
    """All cells of ``spec`` (first axis varies slowest), ids checked unique."""
    keys = [k for k, _ in spec.axes]
    cells: list[Cell] = []
    for combo in itertools.product(*(values for _, values in spec.axes)):
        params = dict(zip(keys, combo, strict=True))
        config = spec.base
        for key, value in params.items():
            config = set_dotted(config, key, value)
        seed = config.get("seed")
        cells.append(Cell(cell_id(params), params, config, seed if isinstance(seed, int) else None))
    ids = [c.cell_id for c in cells]
    dupes = sorted({i for i in ids if ids.count(i) > 1})
    if dupes:
        raise ConfigError(f"sweep values give the same cell id {dupes[0]!r}; make them distinct")
    return cells
