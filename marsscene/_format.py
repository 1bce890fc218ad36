"""Deterministic number formatting for text outputs (MJCF, URDF): the lowest layer, so the
scene exporters and the rover model share one rule."""

from __future__ import annotations

from collections.abc import Iterable

__all__ = ["fmt"]


def fmt(values: float | Iterable[float], digits: int = 6) -> str:
    """Format numbers deterministically (fixed significant digits, no ``-0``).

    Examples
    --------
    >>> fmt((0.1, -0.0, 1 / 3))
    '0.1 0 0.333333'
    """
    vals = [values] if isinstance(values, int | float) else list(values)
    out = []
    for v in vals:
        s = f"{float(v):.{digits}g}"
        out.append("0" if s in ("-0", "0") else s)
    return " ".join(out)
