"""TUM trajectories: ``timestamp tx ty tz qx qy qz qw`` per line (Sturm et al. 2012, TUM RGB-D).

Timestamps in s, positions in m, unit quaternions in Hamilton convention with the scalar
**last** (the TUM order). Lines starting with ``#`` and blank lines are ignored.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from marsscene._atomic import write_atomic
from marsscene._validate import plain
from marsscene.errors import RuntimeSimError

__all__ = ["Trajectory", "read_tum", "write_tum"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Time-stamped poses.

    Attributes
    ----------
    timestamps_s : ndarray of shape (N,)
        Strictly increasing stamps (in s).
    xyz_m : ndarray of shape (N, 3)
        Positions (in m).
    quat_xyzw : ndarray of shape (N, 4)
        Unit quaternions, scalar last (TUM order).
    """

    timestamps_s: NDArray[np.float64]
    xyz_m: NDArray[np.float64]
    quat_xyzw: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = np.asarray(self.timestamps_s, dtype=np.float64).reshape(-1)
        n = len(t)
        xyz = np.asarray(self.xyz_m, dtype=np.float64).reshape(n, 3)
        q = np.asarray(self.quat_xyzw, dtype=np.float64).reshape(n, 4)
        norm = np.linalg.norm(q, axis=1)
        if n and (not np.all(np.isfinite(norm)) or np.any(np.abs(norm - 1.0) > 1e-3)):
            i = int(np.argmax(~np.isfinite(norm) | (np.abs(norm - 1.0) > 1e-3)))
            raise RuntimeSimError(f"pose {i}: quaternion norm {plain(norm[i])!r} is not 1 (+-1e-3)")
        if n > 1 and np.any(np.diff(t) <= 0):
            i = int(np.argmax(np.diff(t) <= 0)) + 1
            raise RuntimeSimError(
                f"pose {i}: timestamp {plain(t[i])!r} s does not increase "
                f"(previous {plain(t[i - 1])!r} s)"
            )
        object.__setattr__(self, "timestamps_s", t)
        object.__setattr__(self, "xyz_m", xyz)
        object.__setattr__(self, "quat_xyzw", q / np.where(norm > 0, norm, 1.0)[:, None])

    def __len__(self) -> int:
        return len(self.timestamps_s)

    @property
    def quat_wxyz(self) -> NDArray[np.float64]:
        return self.quat_xyzw[:, [3, 0, 1, 2]]

    @classmethod
    def from_wxyz(
        cls,
        timestamps_s: NDArray[np.float64],
        xyz_m: NDArray[np.float64],
        quat_wxyz: NDArray[np.float64],
    ) -> Trajectory:
        q = np.asarray(quat_wxyz, dtype=np.float64).reshape(-1, 4)
        return cls(timestamps_s, xyz_m, q[:, [1, 2, 3, 0]])

    def head(self, n: int) -> Trajectory:
        """The first ``n`` poses."""
        return self if len(self) == n else Trajectory(
            self.timestamps_s[:n], self.xyz_m[:n], self.quat_xyzw[:n])

    def path_length_m(self) -> float:
        return float(np.linalg.norm(np.diff(self.xyz_m, axis=0), axis=1).sum())


def read_tum(path: str | os.PathLike[str], *, complete_lines: bool = False) -> Trajectory:
    """Read a TUM file; malformed lines raise :class:`RuntimeSimError` naming the line.

    ``complete_lines=True`` ignores a last line without its newline (a file whose writer was
    killed mid-line).
    """
    p = Path(path)
    try:
        text_all = p.read_text(encoding="utf-8")
    except OSError as err:
        raise RuntimeSimError(f"cannot read TUM file {p}: {err.strerror or err}") from None
    if complete_lines and not text_all.endswith("\n"):
        text_all = text_all[: text_all.rfind("\n") + 1]
    lines = text_all.splitlines()
    rows = []
    for lineno, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        parts = text.replace(",", " ").split()
        if len(parts) != 8:
            raise RuntimeSimError(
                f"{p}:{lineno}: expected 8 numbers 'timestamp tx ty tz qx qy qz qw', "
                f"got {len(parts)}: {text[:80]!r}"
            )
        try:
            rows.append([float(v) for v in parts])
        except ValueError:
            raise RuntimeSimError(f"{p}:{lineno}: not a number in {text[:80]!r}") from None
    if not rows:
        raise RuntimeSimError(f"{p}: no poses (empty TUM file)")
    a = np.asarray(rows)
    if not np.isfinite(a).all():
        raise RuntimeSimError(f"{p}: NaN or inf in poses")
    try:
        return Trajectory(a[:, 0], a[:, 1:4], a[:, 4:8])
    except RuntimeSimError as err:
        raise RuntimeSimError(f"{p}: {err}") from None


def format_tum(traj: Trajectory) -> str:
    """TUM text with fixed precision (1 us stamps, 0.1 mm positions... 1e-6; quats 1e-9)."""
    a = np.column_stack([traj.timestamps_s, traj.xyz_m, traj.quat_xyzw])
    fmt = "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f"
    lines = [fmt % tuple(row) for row in a]
    return "\n".join(lines).replace("-0.000000000 ", "0.000000000 ") + ("\n" if lines else "")


def write_tum(path: str | os.PathLike[str], traj: Trajectory, *, header: str | None = None) -> Path:
    """Write a TUM file (deterministic formatting); returns the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    head = "".join(f"# {h}\n" for h in header.splitlines()) if header else ""
    return write_atomic(p, head + format_tum(traj))
