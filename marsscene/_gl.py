"""Headless OpenGL default, set before anything imports :mod:`mujoco`.

MuJoCo picks its offscreen backend (GLFW, EGL, OSMesa) from ``MUJOCO_GL`` once, when it is first
imported; on a machine without a display its GLFW default cannot make a context. The package's
``__init__`` imports this module first, so every path into MuJoCo through marsscene (a camera, a
benchmark worker, the Gymnasium env) sees ``MUJOCO_GL=egl`` unless the user set it or a display
exists. A program that imports :mod:`mujoco` before :mod:`marsscene` must set it itself.
"""

from __future__ import annotations

import os


def default_headless_gl(environ: dict[str, str] | None = None) -> str | None:
    """Set ``MUJOCO_GL=egl`` in `environ` (default ``os.environ``) when unset and no display.

    Returns the value in force afterwards (``None`` where a display is used).
    """
    env: dict[str, str] = os.environ if environ is None else environ  # type: ignore[assignment]
    if "MUJOCO_GL" not in env and not env.get("DISPLAY"):
        env["MUJOCO_GL"] = "egl"
    return env.get("MUJOCO_GL")


default_headless_gl()
