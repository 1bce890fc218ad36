"""Small validation helpers shared by the stage configs (messages name key, value and range)."""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

from marsscene.errors import ConfigError

T = TypeVar("T")

__all__ = ["check_choice", "check_range", "dataclass_from_mapping", "load_toml", "plain"]


def plain(value: Any) -> Any:
    """``value`` with numpy scalars turned into Python ones, so messages print ``1.0``, not
    ``np.float64(1.0)`` (numpy >= 2 reprs); containers are converted element by element."""
    if hasattr(value, "item") and getattr(value, "ndim", None) == 0:
        return value.item()
    if isinstance(value, list | tuple):
        return type(value)(plain(v) for v in value)
    return value


def check_range(
    key: str,
    value: float,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    lo_open: bool = False,
    hi_open: bool = False,
) -> None:
    """Raise :class:`ConfigError` unless ``lo <= value <= hi`` (open ends with ``*_open``)."""
    ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
    if not ok:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        raise ConfigError(
            f"{key} = {plain(value)!r} is out of range; "
            f"allowed {left}{plain(lo)}, {plain(hi)}{right}"
        )


def check_choice(key: str, value: object, choices: typing.Iterable[object]) -> None:
    """Raise :class:`ConfigError` unless ``value`` is one of ``choices``."""
    allowed = tuple(choices)
    if value not in allowed:
        raise ConfigError(
            f"{key} = {plain(value)!r} is not allowed; choose one of {list(allowed)}"
        )


def _coerce(value: Any, annotation: Any) -> Any:
    """Turn TOML lists into tuples where the field is a tuple (configs are frozen/hashable)."""
    origin = typing.get_origin(annotation)
    if origin in (typing.Union, types.UnionType):
        for arg in typing.get_args(annotation):
            if arg is type(None):
                continue
            if typing.get_origin(arg) is tuple and isinstance(value, list):
                return _coerce(value, arg)
        return value
    if origin is tuple and isinstance(value, list):
        return tuple(value)
    return value


def dataclass_from_mapping(cls: type[T], mapping: Mapping[str, Any], section: str) -> T:
    """Build a frozen config dataclass from a TOML table, rejecting unknown keys.

    Nested dataclass fields are built recursively from nested tables.
    """
    if not isinstance(mapping, Mapping):
        raise ConfigError(f"[{section}] must be a table; got {mapping!r}")
    prefix = f"{section}." if section else ""
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    hints = typing.get_type_hints(cls)
    kwargs: dict[str, Any] = {}
    for key, value in mapping.items():
        if key not in fields:
            raise ConfigError(
                f"unknown key {prefix}{key} = {value!r}; allowed keys: {sorted(fields)}"
            )
        hint = hints[key]
        if dataclasses.is_dataclass(hint) and isinstance(hint, type):
            kwargs[key] = dataclass_from_mapping(hint, value, f"{prefix}{key}")
        else:
            kwargs[key] = _coerce(value, hint)
    try:
        return cls(**kwargs)
    except TypeError as err:
        raise ConfigError(f"[{section or 'config'}]: {err}") from None


def load_toml(path: Any, *, what: str = "config file") -> dict[str, Any]:
    """A TOML file as a mapping; a missing file or bad TOML is a one-line ConfigError."""
    import tomllib
    from pathlib import Path

    p = Path(path)
    try:
        return tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(f"{what} not found: {p}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ConfigError(f"{p}: not valid TOML ({err})") from None
