"""Small rotation helpers (quaternions are (w, x, y, z) unless a name says ``xyzw``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from array_api_compat import is_array_api_obj
from numpy.typing import ArrayLike, NDArray

from marsscene._xp import namespace

__all__ = ["quat_from_yaw_normal", "quat_to_matrix", "yaw_of_quat"]


def quat_to_matrix(q_wxyz: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrices of unit quaternions, shape (..., 3, 3)."""
    q = np.asarray(q_wxyz, dtype=np.float64)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    r = np.stack(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - w * z),
            2 * (x * z + w * y),
            2 * (x * y + w * z),
            1 - 2 * (x * x + z * z),
            2 * (y * z - w * x),
            2 * (x * z - w * y),
            2 * (y * z + w * x),
            1 - 2 * (x * x + y * y),
        ],
        axis=-1,
    )
    return r.reshape(*q.shape[:-1], 3, 3)


def matrix_to_quat(r: ArrayLike) -> NDArray[np.float64]:
    """Quaternion (w, x, y, z) with w >= 0 of rotation matrices (..., 3, 3)."""
    m = np.asarray(r, dtype=np.float64)
    a = m.reshape(-1, 3, 3)
    t = np.trace(a, axis1=1, axis2=2)
    k = (
        np.stack(
            [
                t,
                a[:, 2, 1] - a[:, 1, 2],
                a[:, 0, 2] - a[:, 2, 0],
                a[:, 1, 0] - a[:, 0, 1],
                a[:, 2, 1] - a[:, 1, 2],
                2 * a[:, 0, 0] - t,
                a[:, 0, 1] + a[:, 1, 0],
                a[:, 0, 2] + a[:, 2, 0],
                a[:, 0, 2] - a[:, 2, 0],
                a[:, 0, 1] + a[:, 1, 0],
                2 * a[:, 1, 1] - t,
                a[:, 1, 2] + a[:, 2, 1],
                a[:, 1, 0] - a[:, 0, 1],
                a[:, 0, 2] + a[:, 2, 0],
                a[:, 1, 2] + a[:, 2, 1],
                2 * a[:, 2, 2] - t,
            ],
            axis=-1,
        ).reshape(-1, 4, 4)
        / 3.0
    )
    _, vecs = np.linalg.eigh(k)  # Bar-Itzhack (2000): largest eigenvector of K
    out = vecs[:, :, -1]
    out = np.where(out[:, :1] < 0, -out, out)
    return out.reshape(*m.shape[:-2], 4)


def yaw_of_quat(q_wxyz: Any) -> Any:
    """Heading (rad, counter-clockwise from +x) of quaternions (..., 4): numpy (or anything
    ``np.asarray`` takes) or PyTorch arrays, returned as the same kind; one quaternion (4,)
    gives a Python float (the C library's ``atan2``, as the simulators have always used)."""
    q = q_wxyz if is_array_api_obj(q_wxyz) else np.asarray(q_wxyz, dtype=np.float64)
    atan2 = math.atan2 if isinstance(q, np.ndarray) and q.shape == (4,) else namespace(q).atan2
    w, x, y, z = (q[..., i] for i in range(4))
    return atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def quat_from_yaw_normal(yaw_rad: float, normal: ArrayLike) -> NDArray[np.float64]:
    """Orientation whose z axis is ``normal`` and whose x axis points along ``yaw`` (projected)."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    heading = np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    x = heading - n * float(heading @ n)
    x /= np.linalg.norm(x)
    y = np.cross(n, x)
    return matrix_to_quat(np.column_stack([x, y, n]))
