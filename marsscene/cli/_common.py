"""Helpers shared by the commands."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

import click

from marsscene.errors import MarsSceneError

F = TypeVar("F", bound=Callable[..., Any])


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn library errors into one-line click errors (exit 1, no traceback)."""
    try:
        yield
    except MarsSceneError as err:
        raise click.ClickException(str(err)) from err
    except MemoryError as err:
        raise click.ClickException(f"out of memory: {err}") from err


@contextmanager
def sigterm_interrupts() -> Iterator[None]:
    """SIGTERM raises KeyboardInterrupt inside the block (a no-op off the main thread)."""

    def terminate(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:  # only the main thread may set handlers
        previous: Any = signal.signal(signal.SIGTERM, terminate)
    except ValueError:
        previous = None
    try:
        yield
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def compose(*decorators: Callable[[F], F]) -> Callable[[F], F]:
    """Apply several click option decorators in order."""

    def wrap(func: F) -> F:
        for dec in reversed(decorators):
            func = dec(func)
        return func

    return wrap


#: ``--workers`` / ``--scheduler`` / ``--serial``: where the cells of a sweep or a benchmark run.
dask_options = compose(
    click.option("--workers", type=click.IntRange(min=1), default=None,
                 help="LocalCluster worker processes (default: one per CPU core)."),
    click.option("--scheduler", default=None, metavar="ADDRESS",
                 help="Running Dask scheduler (e.g. tcp://10.0.0.5:8786) instead of a "
                 "LocalCluster; its workers must see --out on a shared filesystem."),
    click.option("--serial", is_flag=True,
                 help="Run the cells one by one in this process (no Dask)."),
)


def dask_where(workers: int | None, scheduler: str | None, serial: bool) -> str:
    """Check the :data:`dask_options` together and say where the cells will run."""
    if scheduler is not None and (workers is not None or serial):
        raise click.UsageError("--scheduler excludes --workers and --serial")
    if serial and workers is not None:
        raise click.UsageError("--serial excludes --workers")
    return ("serially" if serial else f"on {scheduler}" if scheduler
            else f"on a LocalCluster ({workers or 'one worker per core'})")
