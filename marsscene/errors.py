"""One error hierarchy for marsscene.

Every error derives from :class:`MarsSceneError` and also from the matching builtin, so callers can
catch either (``except ValueError`` still works for a bad config). Non-fatal conditions are
:class:`Warning` subclasses so users can filter them and tests can assert on them.
"""

from __future__ import annotations

__all__ = [
    "CRSError",
    "ConfigError",
    "DEMReadError",
    "ExportError",
    "ExtrapolationWarning",
    "MarsSceneError",
    "MarsSceneWarning",
    "MemoryBudgetError",
    "MissingDependencyError",
    "NoGeoreferenceWarning",
    "NodataFilledWarning",
    "RuntimeSimError",
    "SweepError",
]


class MarsSceneError(Exception):
    """Root of every error raised by marsscene."""


class ConfigError(MarsSceneError, ValueError):
    """A configuration key or value is invalid (message names key, value and allowed range)."""


class DEMReadError(MarsSceneError, OSError):
    """A DEM or orthoimage cannot be opened, parsed or is inconsistent."""


class CRSError(MarsSceneError, ValueError):
    """A coordinate reference system is unusable (e.g. geographic where metres are needed)."""


class MemoryBudgetError(MarsSceneError, MemoryError):
    """A requested grid would not fit in the memory budget (message gives the estimate)."""


class ExportError(MarsSceneError):
    """Writing USD, MJCF or the manifest failed."""


class MissingDependencyError(MarsSceneError, ImportError):
    """An optional dependency is not installed (message names the extra to install)."""


class RuntimeSimError(MarsSceneError, RuntimeError):
    """The MuJoCo runtime cannot load a scene, a route or a log."""


class SweepError(MarsSceneError, RuntimeError):
    """A sweep cannot run (no scheduler at the address, output folder not shared, ...)."""


class MarsSceneWarning(UserWarning):
    """Root of marsscene warnings."""


class NodataFilledWarning(MarsSceneWarning):
    """Missing DEM posts were filled by interpolation."""


class NoGeoreferenceWarning(MarsSceneWarning):
    """An input raster has no coordinate reference system (no lon/lat, default sun site)."""


class ExtrapolationWarning(MarsSceneWarning):
    """A model is evaluated outside its published validity range."""


def missing_dependency(module: str, extra: str | None) -> MissingDependencyError:
    """Build the error raised when a dependency cannot be imported: one of an ``extra``, or
    (``extra=None``) a core one, missing from an install made before it became core."""
    if extra is None:
        return MissingDependencyError(
            f"{module!r} is not installed, though marsscene needs it; reinstall marsscene "
            "(pip install marsscene, or pip install -e . in a checkout)")
    return MissingDependencyError(
        f"{module!r} is not installed; install it with: pip install \"marsscene[{extra}]\""
    )
