"""MuJoCo MJCF export: ``mjcf/scene.xml`` with its assets (``mjcf/assets/``).

:func:`to_mjcf` builds the XML text and a dict of assets in memory; :func:`write_mjcf` writes
them. The XML is assembled with :mod:`xml.etree.ElementTree` and numbers are formatted with a
fixed precision, so the same scene always gives the same bytes. :func:`validate_mjcf` (the only
``mujoco`` import outside ``sim/`` and ``sensors/``) compiles the file and steps it.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from marsscene.errors import ExportError, missing_dependency
from marsscene.export.mjcf.build import build_mjcf

__all__ = ["to_mjcf", "validate_mjcf", "write_mjcf"]


def to_mjcf(scene: Any) -> tuple[str, dict[str, bytes]]:
    """Return ``(scene.xml text, {relative asset path: bytes})``."""
    root, assets = build_mjcf(scene)
    ET.indent(root, space="  ")
    xml = ET.tostring(root, encoding="unicode", short_empty_elements=True)
    return xml + "\n", assets


def write_mjcf(scene: Any, out_dir: str | Path) -> list[Path]:
    """Write ``out_dir/mjcf/scene.xml`` and its assets; return the written paths.

    The MJCF writer of :func:`marsscene.write_scene`, which most users call instead (it writes
    atomically and adds the manifest); this one writes into ``out_dir`` as it is.

    Parameters
    ----------
    scene : Scene
        A built scene (:func:`marsscene.build_scene`).
    out_dir : path-like
        Folder in which the ``mjcf/`` folder is written.

    Returns
    -------
    list of Path
        Every file written (meshes, heightfield): ``mjcf/scene.xml`` is the last.

    Examples
    --------
    >>> import tempfile
    >>> import mujoco
    >>> import marsscene as ms
    >>> from marsscene.export.mjcf import write_mjcf
    >>> cfg = ms.SceneConfig.from_dict({"terrain": {"source": "procedural", "size_m": [10, 10]}})
    >>> paths = write_mjcf(ms.build_scene(cfg, seed=7), tempfile.mkdtemp())
    >>> paths[-1].name
    'scene.xml'
    >>> model = mujoco.MjModel.from_xml_path(str(paths[-1]))
    >>> model.nhfield
    1
    """
    xml, assets = to_mjcf(scene)
    base = Path(out_dir) / "mjcf"
    written = []
    for rel, blob in sorted(assets.items()):
        p = base / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(blob)
        written.append(p)
    target = base / "scene.xml"
    target.write_text(xml, encoding="utf-8")
    written.append(target)
    return written


def validate_mjcf(path: str | Path, *, seconds: float = 1.0) -> Any:
    """Compile ``path`` with MuJoCo, step it ``seconds`` and fail on any MuJoCo warning.

    Returns the ``(model, data)`` pair after stepping.
    """
    try:
        import mujoco
    except ImportError as err:
        raise missing_dependency("mujoco", None) from err
    try:
        model = mujoco.MjModel.from_xml_path(str(path))
    except ValueError as err:
        raise ExportError(f"{path}: MuJoCo cannot compile it: {err}") from None
    data = mujoco.MjData(model)
    steps = round(seconds / model.opt.timestep)
    for _ in range(steps):
        mujoco.mj_step(model, data)
    warnings = [(i, int(w.number)) for i, w in enumerate(data.warning) if w.number]
    if warnings:
        names = [mujoco.mjtWarning(i).name for i, _ in warnings]
        raise ExportError(f"{path}: MuJoCo warnings while stepping: {names}")
    return model, data
