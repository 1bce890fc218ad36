"""Skips that name the install line: a test of an optional part skips with the extra that
brings it, so the README's test command (``pip install -e ".[all,test]"``) passes on a fresh
machine and the skip reason says what to install to run the rest."""

from __future__ import annotations

from types import ModuleType

import pytest

__all__ = ["needs"]


def needs(module: str, extra: str) -> ModuleType:
    """Import ``module`` or skip the test: "needs the [extra] extra (pip install -e ...)"."""
    return pytest.importorskip(
        module, reason=f"needs {module!r} from the [{extra}] extra "
                       f"(python -m pip install -e \".[{extra}]\")")
