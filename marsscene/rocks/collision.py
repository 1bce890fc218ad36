"""Optional convex decomposition of rock prototypes with coacd (Wei et al. 2022, "Approximate
convex decomposition for 3D meshes with collision-aware concavity and tree search",
doi:10.1145/3528223.3530103).

coacd takes seconds per mesh, so results are cached on disk by a hash of the mesh bytes, the
parameters and the coacd version: ``$MARSSCENE_CACHE_DIR`` or
``$XDG_CACHE_HOME/marsscene/coacd`` (default ``~/.cache/marsscene/coacd``). This module is the
only importer of ``coacd``.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from marsscene._atomic import write_atomic
from marsscene.errors import missing_dependency

if TYPE_CHECKING:
    import trimesh

__all__ = ["cache_dir", "convex_decompose"]


def cache_dir() -> Path:
    """Folder of the coacd result cache."""
    env = os.environ.get("MARSSCENE_CACHE_DIR")
    if env:
        return Path(env) / "coacd"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "marsscene" / "coacd"


def _key(mesh: trimesh.Trimesh, params: dict[str, object], version: str) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(mesh.vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(mesh.faces, dtype="<i8").tobytes())
    h.update(json.dumps({**params, "coacd": version}, sort_keys=True).encode())
    return h.hexdigest()


def convex_decompose(
    mesh: trimesh.Trimesh,
    *,
    threshold: float = 0.08,
    max_hulls: int = 8,
    max_hull_vertices: int = 64,
    resolution: int = 1000,
    seed: int = 0,
    cache: Path | None = None,
) -> tuple[trimesh.Trimesh, ...]:
    """Convex parts of a mesh via coacd, cached on disk.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        Watertight mesh.
    threshold : float
        coacd concavity threshold (smaller = more parts).
    max_hulls : int
        Upper bound on the number of parts.
    max_hull_vertices : int
        Vertices per part (<= 64 suits PhysX and MuJoCo).
    resolution : int
        coacd sampling resolution.
    seed : int
        coacd's internal seed (fixed: reproducible parts).
    cache : Path, optional
        Cache folder (default :func:`cache_dir`).

    Returns
    -------
    tuple of trimesh.Trimesh
        Convex, outward-oriented parts.
    """
    import trimesh

    from marsscene.rocks.hull import convex_hull

    try:
        import coacd
    except ImportError as err:  # pragma: no cover - optional extra
        raise missing_dependency("coacd", "collision") from err
    from importlib import metadata

    params: dict[str, object] = {"threshold": threshold, "max_hulls": max_hulls,
                                 "max_hull_vertices": max_hull_vertices,
                                 "resolution": resolution, "seed": seed}
    folder = cache if cache is not None else cache_dir()
    path = folder / f"{_key(mesh, params, metadata.version('coacd'))}.npz"
    if path.is_file():
        with np.load(path) as data:
            n = int(data["n"])
            raw = [(data[f"v{i}"], data[f"f{i}"]) for i in range(n)]
    else:
        coacd.set_log_level("error")
        raw = coacd.run_coacd(
            coacd.Mesh(np.asarray(mesh.vertices, dtype=np.float64),
                       np.asarray(mesh.faces, dtype=np.int32)),
            threshold=threshold, max_convex_hull=max_hulls, resolution=resolution,
            max_ch_vertex=max_hull_vertices, seed=seed, preprocess_mode="off",
        )
        folder.mkdir(parents=True, exist_ok=True)
        buf = io.BytesIO()
        arrays: dict[str, Any] = {f"v{i}": np.asarray(v) for i, (v, _) in enumerate(raw)}
        arrays |= {f"f{i}": np.asarray(f) for i, (_, f) in enumerate(raw)}
        arrays["n"] = np.array(len(raw))
        np.savez(buf, **arrays)
        write_atomic(path, buf.getvalue())  # concurrent builds never read half a file
    parts = [convex_hull(trimesh.Trimesh(vertices=v, faces=f), max_vertices=max_hull_vertices)
             for v, f in raw]
    return tuple(p for p in parts if p.volume > 0)
