"""Array namespaces (the Python array API through ``array-api-compat``) for code that runs on
numpy or PyTorch arrays alike, with numpy's found without a lookup: on one rover's arrays the
lookup and the compat wrappers cost more than the arithmetic (tens of microseconds a step)."""

from __future__ import annotations

import types
from typing import Any

import numpy as np
from array_api_compat import array_namespace
from array_api_compat import numpy as _compat_numpy

__all__ = ["clip", "namespace"]


def _astype(x: Any, dtype: Any, /, *, copy: bool = True, device: Any = None) -> Any:
    return x.astype(dtype, copy=copy)


def _on_cpu(make: Any) -> Any:
    """numpy's ``make`` taking (and ignoring) the array API's ``device`` keyword."""
    def made(*args: Any, device: Any = None, **kwargs: Any) -> Any:
        return make(*args, **kwargs)
    return made


#: array-api-compat's numpy namespace with ``astype`` and the array makers as numpy's own (its
#: wrappers check the device on every call: a third of the task's arithmetic on one rover).
numpy_namespace = types.ModuleType("marsscene._xp.numpy")
numpy_namespace.__dict__.update(
    {k: v for k, v in vars(_compat_numpy).items() if not k.startswith("__")})
numpy_namespace.astype = _astype  # type: ignore[attr-defined]
for _name in ("zeros", "ones", "empty", "full", "zeros_like", "ones_like", "empty_like",
              "full_like"):
    setattr(numpy_namespace, _name, _on_cpu(getattr(np, _name)))


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
