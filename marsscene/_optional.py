"""Imports of optional dependencies with one clear error each (the lowest layer)."""

from __future__ import annotations

from typing import Any

from marsscene.errors import missing_dependency

__all__ = ["require_pyarrow"]


def require_pyarrow() -> Any:
    """Import pyarrow (raising :class:`~marsscene.errors.MissingDependencyError` if absent)."""
    try:
        import pyarrow
    except ImportError:
        raise missing_dependency("pyarrow", "parquet") from None
    return pyarrow
