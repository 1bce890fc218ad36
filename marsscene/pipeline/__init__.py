"""The build pipeline: the only code that wires the stages together (one module per stage).

:func:`build_scene` (in :mod:`.build`) runs terrain -> craters -> [focus tiles] -> assets ->
[stitch] -> rocks -> lighting; :func:`~marsscene.pipeline.tile.build_tile` builds one focus
tile of a level-of-detail world alone.
"""

from __future__ import annotations

from marsscene.pipeline.build import build_scene

__all__ = ["build_scene"]
