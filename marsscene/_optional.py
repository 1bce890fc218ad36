"""Imports of optional dependencies with one clear error each (the lowest layer)."""

from __future__ import annotations

from typing import Any

from marsscene.errors import missing_dependency

__all__ = ["quiet_warp", "require_pyarrow"]


def quiet_warp(wp: Any) -> Any:
    """``wp`` (the imported ``warp``) with its info messages off (the banner at ``wp.init()``,
    a line per module loaded: dozens on a user's terminal), its warnings kept; returns it."""
    wp.config.log_level = wp.LOG_WARNING
    return wp


def require_pyarrow() -> Any:
    """Import pyarrow (raising :class:`~marsscene.errors.MissingDependencyError` if absent)."""
    try:
        import pyarrow
    except ImportError:
        raise missing_dependency("pyarrow", "parquet") from None
    return pyarrow
