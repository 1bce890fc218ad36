"""The array library of a batched environment: PyTorch tensors (on the GPU, or the CPU) or numpy
arrays (Warp's CPU device, where PyTorch is not installed), both as views of MuJoCo Warp's own
arrays -- no copy, no host round trip on the GPU.

The task's arithmetic is written once against the array API (:mod:`marsscene.env.taskmath`);
the few operations it lacks (a seeded random integer draw, a scatter, a stream to run on) are
here.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any

import numpy as np

from marsscene.errors import ConfigError

__all__ = ["Backend"]


class Backend:
    """numpy or PyTorch on one Warp device.

    Parameters
    ----------
    device : str
        A Warp device (``"cuda:0"``, ``"cpu"``).
    library : {"torch", "numpy"}, optional
        Default: PyTorch where it is installed, else numpy (CPU only).
    seed : int
        Seed of the draws (episode starts).
    """

    def __init__(self, device: str, library: str | None, seed: int) -> None:
        import warp as wp

        self.wp, self.device = wp, str(wp.get_device(device))
        cuda = self.device.startswith("cuda")
        if library is None:
            try:
                import torch

                library = "torch"
            except ImportError:
                library = "numpy"
        if library not in ("torch", "numpy"):
            raise ConfigError(f"array library {library!r}; use torch or numpy")
        if cuda and library == "numpy":
            raise ConfigError(f"{self.device}: a GPU batch needs PyTorch (pip install torch)")
        self.library = library
        if library == "torch":
            import torch
            from array_api_compat import torch as xp_torch

            self.xp: Any = xp_torch
            self.torch: Any = torch
            self.tdevice = torch.device(self.device if cuda else "cpu")
            self.generator = torch.Generator(device=self.tdevice)
            self.stream = (torch.cuda.ExternalStream(wp.get_stream(self.device).cuda_stream,
                                                     device=self.tdevice) if cuda else None)
        else:
            from array_api_compat import numpy as xp_numpy

            self.xp, self.torch, self.stream, self.tdevice = xp_numpy, None, None, None
        self.seed(seed)

    def seed(self, seed: int) -> None:
        """Restart the stream of draws from ``seed``."""
        if self.torch is not None:
            self.generator.manual_seed(int(seed))
        else:
            self.rng = np.random.default_rng(int(seed))

    def view(self, array: Any) -> Any:
        """A Warp array as a tensor / ndarray sharing its memory."""
        if self.torch is not None:
            return self.wp.to_torch(array)
        return array.numpy()

    def asarray(self, values: Any, dtype: Any = None) -> Any:
        """``values`` (numpy) copied onto the device."""
        out = self.xp.asarray(np.ascontiguousarray(values), device=self.tdevice)
        return out if dtype is None else self.xp.astype(out, dtype)

    def to_numpy(self, array: Any) -> np.ndarray:
        """A host copy (synchronises with the device)."""
        if self.torch is not None:
            return np.asarray(array.detach().cpu().numpy())
        return np.array(array)

    def randint(self, high: int, n: int) -> Any:
        """``n`` integers drawn uniformly in ``[0, high)`` from the seeded stream."""
        if self.torch is not None:
            return self.torch.randint(0, high, (n,), generator=self.generator,
                                      device=self.tdevice)
        return self.rng.integers(0, high, n)

    def count_per(self, index: Any, flag: Any, n: int) -> Any:
        """``out[i]`` = how many ``flag`` are true where ``index == i``, for ``i < n``
        (out-of-range indices must carry a false flag)."""
        xp = self.xp
        index = xp.clip(index, 0, n - 1)
        if self.torch is not None:
            out = self.torch.zeros(n, dtype=self.torch.int32, device=self.tdevice)
            return out.index_add_(0, index.long(), flag.to(self.torch.int32))
        return np.bincount(np.asarray(index, dtype=np.int64), weights=np.asarray(flag),
                           minlength=n).astype(np.int32)

    @contextlib.contextmanager
    def on_stream(self) -> Iterator[None]:
        """Run PyTorch work on Warp's stream (ordered with the physics), after the caller's
        stream's work, and make the caller's stream wait for it (no host synchronisation)."""
        if self.stream is None:
            yield
            return
        torch = self.torch
        caller = torch.cuda.current_stream(self.tdevice)
        self.stream.wait_stream(caller)
        with torch.cuda.stream(self.stream):
            yield
        caller.wait_stream(self.stream)
