"""Warnings that point at the user's line, not at marsscene's own code."""

from __future__ import annotations

import os
import sys
import warnings

_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def warn_external(message: str, category: type[Warning]) -> None:
    """``warnings.warn`` at the first caller outside the marsscene package.

    A warning raised deep inside a build (a DEM fill under ``build_scene``) is then reported at
    the user's call, as ``stacklevel`` would for a direct call, and never names a file of this
    installation.
    """
    level = 2  # the caller of warn_external
    frame = sys._getframe(1)
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame = frame.f_back
        level += 1
    warnings.warn(message, category, stacklevel=level)
