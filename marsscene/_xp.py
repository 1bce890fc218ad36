"""Array namespaces (the Python array API through ``array-api-compat``) for code that runs on
numpy or PyTorch arrays alike, with numpy's found without a lookup: on one rover's arrays the
lookup and the compat wrappers cost more than the arithmetic (tens of microseconds a step)."""

from __future__ import annotations

from typing import Any

import numpy as np
from array_api_compat import array_namespace
from array_api_compat import numpy as numpy_namespace

__all__ = ["clip", "namespace"]


def namespace(*arrays: Any) -> Any:
    """The array-API namespace of ``arrays`` (array-api-compat's numpy one for numpy arrays)."""
    if all(isinstance(a, np.ndarray | np.generic) for a in arrays):
        return numpy_namespace
    return array_namespace(*arrays)


def clip(xp: Any, x: Any, lo: float | None, hi: float | None) -> Any:
    """``xp.clip(x, lo, hi)``; numpy ufuncs for numpy arrays (the same values, a fraction of
    the wrapper's cost)."""
    if not isinstance(x, np.ndarray | np.generic):
        return xp.clip(x, lo, hi)
    if lo is not None:
        x = np.maximum(x, lo)
    return x if hi is None else np.minimum(x, hi)
