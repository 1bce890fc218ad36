"""Export a :class:`~marsscene.Scene`: USD, MJCF and ``manifest.json``, written atomically.

Everything is first written into a temporary sibling folder; only when every writer succeeded is
it renamed into place, so a failed build never leaves a half-written scene.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from functools import partial
from pathlib import Path
from typing import Any

from marsscene._atomic import probe_writable, replacing_dir
from marsscene._threads import worth_a_thread
from marsscene.errors import ExportError, MarsSceneError

__all__ = ["WRITERS", "check_export_dependencies", "check_output_dir", "write_scene"]


def _write_usd(scene: Any, out: Path, textures: Future[Any] | None = None) -> list[Path]:
    from marsscene.export.usd import write_usd

    return write_usd(scene, out, usd_format=scene.config.export.usd_format, textures=textures)


def _write_mjcf(scene: Any, out: Path) -> list[Path]:
    from marsscene.export.mjcf import write_mjcf

    return write_mjcf(scene, out)


def _write_catalogs(scene: Any, out: Path) -> list[Path]:
    from marsscene.export.catalog_craters import write_crater_catalog
    from marsscene.export.catalog_rocks import write_rock_catalog
    from marsscene.soil import write_soil_map

    soil = write_soil_map(scene.soil, out) if getattr(scene, "soil", None) is not None else []
    return write_crater_catalog(scene, out) + write_rock_catalog(scene, out) + soil


def _timed(fn: Callable[[Any, Path], list[Path]], scene: Any,
           out: Path) -> tuple[list[Path], float]:
    t0 = time.perf_counter()
    paths = fn(scene, out)
    return paths, round(time.perf_counter() - t0, 4)


#: Format name -> writer(scene, out_dir) -> written paths. Extend to add a format.
WRITERS: dict[str, Callable[[Any, Path], list[Path]]] = {"usd": _write_usd, "mjcf": _write_mjcf}


def check_output_dir(out_dir: str | os.PathLike[str]) -> Path:
    """Fail early (before a long build) if ``out_dir`` cannot be written; returns its full path.

    Creates the parent folder if needed and probes it with a temporary folder, removed again.
    """
    final = Path(out_dir).resolve()
    probe_writable(final)
    return final


def check_export_dependencies(export: Any) -> None:
    """Fail early (before a long build) when an optional writer the ``[export]`` config asks
    for is not installed (pyarrow for a Parquet rock catalogue)."""
    if export.rock_catalogue in ("parquet", "both"):
        from marsscene._optional import require_pyarrow

        require_pyarrow()


def write_scene(
    scene: Any,
    out_dir: str | os.PathLike[str],
    *,
    formats: Iterable[str] | None = None,
    overwrite: bool = True,
) -> dict[str, list[Path]]:
    """Write a scene folder: ``scene.usda`` (+assets), ``mjcf/scene.xml`` (+assets), manifest.

    Everything is written into a temporary sibling folder first and renamed into place only
    when every writer succeeded, so a failed export never leaves a half-written scene. The
    crater and rock catalogues and ``manifest.json`` are always written.

    Parameters
    ----------
    scene : Scene
        A built scene (:func:`marsscene.build_scene`).
    out_dir : path-like
        Output folder; replaced as a whole if it exists and ``overwrite`` is true.
    formats : iterable of str, optional
        Keys of :data:`WRITERS` (``"usd"``: OpenUSD for Isaac Sim and Omniverse, needs
        ``usd-core``; ``"mjcf"``: MuJoCo); default ``scene.config.export.formats``.
    overwrite : bool
        Replace an existing ``out_dir`` (else :class:`~marsscene.errors.ExportError`).

    Returns
    -------
    dict of str to list of Path
        Format -> final paths written (plus ``"catalogs"`` and ``"manifest"``).

    Raises
    ------
    ExportError
        An unknown format, an existing ``out_dir`` without ``overwrite``, a writer that failed.

    Examples
    --------
    >>> import tempfile
    >>> import marsscene as ms
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    >>> scene = ms.build_scene(cfg, seed=7)
    >>> out = tempfile.mkdtemp()
    >>> written = ms.write_scene(scene, out, formats=["mjcf"])
    >>> sorted(written)
    ['catalogs', 'manifest', 'mjcf']
    >>> written["mjcf"][-1].relative_to(out).as_posix()
    'mjcf/scene.xml'

    The MJCF loads in MuJoCo as it is:

    >>> import mujoco
    >>> model = mujoco.MjModel.from_xml_path(str(written["mjcf"][-1]))
    """
    from marsscene.export.manifest import manifest_bytes

    fmts = tuple(formats) if formats is not None else tuple(scene.config.export.formats)
    unknown = [f for f in fmts if f not in WRITERS]
    if unknown:
        raise ExportError(f"unknown export format(s) {unknown}; known: {sorted(WRITERS)}")
    check_export_dependencies(scene.config.export)
    final = Path(out_dir).resolve()
    written: dict[str, list[Path]] = {}
    try:
        with (replacing_dir(final, overwrite=overwrite) as tmp,
              ThreadPoolExecutor(max_workers=1, thread_name_prefix="marsscene-textures") as pool):
            timings = dict(scene.provenance.timings_s)
            writers = {fmt: WRITERS[fmt] for fmt in fmts}
            if writers.get("usd") is _write_usd and worth_a_thread(scene.heightfield.z_m.size):
                # The USD material's textures (numpy + Pillow) are encoded on a background
                # thread while the catalogues, the MJCF and the terrain tiles are written; the
                # USD writer itself (pxr) runs on this thread, last (see docs/usd.md).
                from marsscene.export.usd import start_textures

                writers["usd"] = partial(_write_usd, textures=start_textures(scene, pool))
            catalogs, _ = _timed(_write_catalogs, scene, tmp)
            for fmt in sorted(fmts, key=lambda f: f == "usd"):
                written[fmt], timings[f"export_{fmt}"] = _timed(writers[fmt], scene, tmp)
            written = {fmt: written[fmt] for fmt in fmts}  # manifest order: formats as asked
            written["catalogs"] = catalogs
            rel = [p.relative_to(tmp).as_posix() for paths in written.values() for p in paths]
            (tmp / "manifest.json").write_bytes(manifest_bytes(scene, rel, timings_s=timings))
            written["manifest"] = [tmp / "manifest.json"]
    except MarsSceneError:
        raise
    except Exception as err:
        raise ExportError(f"writing {final} failed: {err}") from err
    return {k: [final / p.relative_to(tmp) for p in v] for k, v in written.items()}
