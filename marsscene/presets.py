"""Reference-scene presets (the MarsLab paper's four scenes) as data: ``data/presets.toml``.

A preset is a partial scene config. :func:`apply_preset` merges it *under* a user mapping, so
every key the user gives (config file or command line) wins over the preset's value.
"""

from __future__ import annotations

import copy
import tomllib
from functools import cache
from importlib import resources
from typing import Any

from marsscene.errors import ConfigError

__all__ = ["PRESET_NAMES", "apply_preset", "preset_info"]


@cache
def _presets() -> dict[str, Any]:
    text = resources.files("marsscene").joinpath("data/presets.toml").read_text(encoding="utf-8")
    return tomllib.loads(text)


PRESET_NAMES: tuple[str, ...] = tuple(_presets())


def preset_info(name: str) -> dict[str, Any]:
    """The preset table ``name`` (``summary``, ``target_use``, ``config``); a deep copy."""
    if name not in _presets():
        raise ConfigError(f"preset = {name!r} is not known; choose one of {list(PRESET_NAMES)}")
    return copy.deepcopy(_presets()[name])


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def apply_preset(mapping: dict[str, Any]) -> dict[str, Any]:
    """``mapping`` with its ``preset`` (if any) expanded underneath it (a new dict).

    Examples
    --------
    >>> m = apply_preset({"preset": "main-crater", "terrain": {"post_m": 2.0}})
    >>> m["terrain"]["size_m"], m["terrain"]["post_m"], m["terrain"]["landform"]
    ([3600.0, 3600.0], 2.0, 'crater')
    """
    name = mapping.get("preset")
    if name is None:
        return dict(mapping)
    if not isinstance(name, str):
        raise ConfigError(f"preset = {name!r}; need one of {list(PRESET_NAMES)}")
    return _merge(preset_info(name)["config"], mapping)
