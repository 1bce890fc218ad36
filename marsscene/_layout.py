"""Names of files inside a scene folder that a writer (``export/``) and a reader (``sensors/``,
``sim/``) must agree on. The lowest layer, so neither side imports the other."""

from __future__ import annotations

__all__ = ["MJCF_HFIELD_ASSET", "MJCF_TEXTURE_ASSET"]

#: The MJCF terrain heightfield, relative to ``mjcf/``.
MJCF_HFIELD_ASSET = "assets/terrain.bin"
#: The MJCF terrain albedo texture (orthoimage or regolith albedo), relative to ``mjcf/``.
MJCF_TEXTURE_ASSET = "assets/terrain_albedo.png"
