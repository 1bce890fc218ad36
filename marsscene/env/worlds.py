"""The worlds of a navigation environment: scene folders, or scenes drawn and built on demand.

A :class:`WorldSampler` is domain randomisation over scene configs: a base config (a mapping,
as in a TOML file) and, per world, a seed plus draws of the keys named in ``vary`` (terrain seed,
landform, rock abundance k, dust opacity tau, sun elevation, ...). World ``i`` is the same scene
for the same sampler, whoever asks; it is built once into ``cache_dir`` (a folder keyed by the
hash of its config and seed) and reused by every later episode, environment and process.

:data:`WORLD_KINDS` names three small world types used by the benchmark (``plain``,
``craters``, ``rocks``: k = 0.2).
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from marsscene._atomic import replacing_dir
from marsscene.errors import ConfigError

__all__ = ["WORLD_KINDS", "WorldSampler", "world_paths"]

#: Small (60 m x 60 m, 0.25 m posts) worlds for navigation. MJCF rocks of 0.3 m and more
#: (the rover rolls over smaller ones; fewer static geoms keep the physics fast).
_SMALL: dict[str, Any] = {
    "terrain": {"source": "procedural", "size_m": [60.0, 60.0], "post_m": 0.25,
                "rms_height_m": 0.15},
    "rocks": {"mjcf_min_diameter_m": 0.3},
}
WORLD_KINDS: dict[str, dict[str, Any]] = {
    "plain": {**_SMALL, "terrain": {**_SMALL["terrain"], "landform": "plain"},
              "craters": {"enabled": False}},
    "craters": {**_SMALL, "craters": {"age_ga": 3.8, "d_min_m": 2.0, "d_max_m": 20.0}},
    "rocks": {**_SMALL, "craters": {"enabled": False}, "rocks": {**_SMALL["rocks"], "k": 0.2}},
}


def _set(doc: dict[str, Any], dotted: str, value: Any) -> None:
    *head, leaf = dotted.split(".")
    for key in head:
        doc = doc.setdefault(key, {})
    doc[leaf] = value


@dataclass(frozen=True, kw_only=True)
class WorldSampler:
    """Scenes drawn from ``base`` with ``vary`` applied, ``count`` of them, built on demand.

    Parameters
    ----------
    base : mapping or str
        A scene config mapping, or a name of :data:`WORLD_KINDS`.
    vary : mapping
        Dotted config key -> ``[lo, hi]`` (a float drawn uniformly) or a list of choices (one
        drawn), e.g. ``{"rocks.k": [0.02, 0.2], "terrain.landform": ["plain", "crater"],
        "lighting.tau": [0.3, 3.0]}``.
    count : int
        Number of distinct worlds; world ``i`` has scene seed ``seed + i``.
    seed : int
        Seed of the scene seeds and of the draws.
    cache_dir : path, optional
        Where built worlds are kept (default ``$MARSSCENE_CACHE`` or
        ``<tmp>/marsscene-worlds``).
    """

    base: Mapping[str, Any] | str = "plain"
    vary: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    count: int = 8
    seed: int = 0
    cache_dir: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.base, str) and self.base not in WORLD_KINDS:
            raise ConfigError(f"world kind {self.base!r} is unknown; known: "
                              f"{', '.join(WORLD_KINDS)}")
        if not isinstance(self.count, int) or self.count < 1:
            raise ConfigError(f"count = {self.count!r}; give at least one world")
        for key, spec in self.vary.items():
            if not isinstance(spec, Sequence) or isinstance(spec, str) or not len(spec):
                raise ConfigError(f"vary[{key!r}] = {spec!r}; give [lo, hi] or a list of "
                                  "choices")
        self.config(0)  # a bad key or value fails here, before any world is built

    def config(self, index: int) -> dict[str, Any]:
        """The scene config mapping of world ``index`` (seed included)."""
        doc = copy.deepcopy(WORLD_KINDS[self.base] if isinstance(self.base, str)
                            else dict(self.base))
        rng = np.random.default_rng([self.seed, index])
        for key, spec in sorted(self.vary.items()):
            numeric = len(spec) == 2 and all(isinstance(v, int | float) and not isinstance(
                v, bool) for v in spec)
            value = (float(rng.uniform(float(spec[0]), float(spec[1]))) if numeric
                     else spec[int(rng.integers(len(spec)))])
            _set(doc, key, value)
        doc["seed"] = self.seed + index
        from marsscene.config import SceneConfig

        try:
            SceneConfig.from_dict(doc)
        except ConfigError as err:
            raise ConfigError(f"world {index}: {err}") from None
        return doc

    def path(self, index: int) -> Path:
        """World ``index``'s scene folder, built into the cache the first time it is asked."""
        import marsscene as ms

        doc = self.config(index)
        blob = json.dumps(doc, sort_keys=True, default=str).encode()
        key = hashlib.sha256(blob + ms.__version__.encode()).hexdigest()[:16]
        root = Path(self.cache_dir or os.environ.get("MARSSCENE_CACHE")
                    or Path(tempfile.gettempdir()) / "marsscene-worlds")
        folder = root / f"world-{key}"
        if (folder / "mjcf" / "scene.xml").is_file():
            return folder
        root.mkdir(parents=True, exist_ok=True)
        cfg = ms.SceneConfig.from_dict(doc)
        scene = ms.build_scene(cfg, seed=int(doc["seed"]))
        with replacing_dir(folder, overwrite=True) as tmp:  # parallel builders: one wins
            ms.write_scene(scene, tmp, formats=("mjcf",))
        return folder


def world_paths(worlds: Any) -> tuple[int, Any]:
    """``(number of worlds, index -> scene folder)`` of a folder, a list of folders or a
    :class:`WorldSampler`."""
    if isinstance(worlds, WorldSampler):
        return worlds.count, worlds.path
    paths = [Path(worlds)] if isinstance(worlds, str | os.PathLike) else [Path(p) for p in worlds]
    if not paths:
        raise ConfigError("worlds: give a scene folder, a list of them, or a WorldSampler")
    for p in paths:
        if not (p / "mjcf" / "scene.xml").is_file():
            raise ConfigError(f"{p} is not a built scene (no mjcf/scene.xml); build one with "
                              "`marsscene build` or pass a WorldSampler")
    return len(paths), paths.__getitem__
