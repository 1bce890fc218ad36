"""The ``marsscene`` command line (click; this subpackage is the only importer of click).

Commands are thin: they parse options into a :class:`~marsscene.SceneConfig` and call one
library function. Library errors (:class:`~marsscene.MarsSceneError`) become one-line messages
with exit code 1; bad option values exit with code 2 (click's usage errors).
"""

from __future__ import annotations

import logging
import sys
import warnings

import click

from marsscene._version import __version__

__all__ = ["main"]


class _StderrFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        return f"marsscene: {record.getMessage()}"


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: object = None,
    line: str | None = None,
) -> None:
    """Print library warnings as one line (no source excerpt) for command-line users."""
    click.echo(f"marsscene: warning: {message}", err=True)


def configure_logging(verbosity: int) -> None:
    """Attach a stderr handler to the ``marsscene`` logger (the library adds only NullHandler)."""
    level = logging.WARNING if verbosity < 0 else logging.INFO if verbosity == 0 else logging.DEBUG
    logger = logging.getLogger("marsscene")
    for h in list(logger.handlers):
        if getattr(h, "_marsscene_cli", False):
            logger.removeHandler(h)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_StderrFormatter())
    handler._marsscene_cli = True  # type: ignore[attr-defined]
    logger.addHandler(handler)
    logger.setLevel(level)
    warnings.showwarning = _show_warning


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="marsscene")
@click.option("-v", "--verbose", count=True, help="More output (repeatable).")
@click.option("-q", "--quiet", count=True, help="Less output (warnings and errors only).")
def main(verbose: int, quiet: int) -> None:
    """Author seeded, reproducible Mars worlds (USD + MuJoCo MJCF)."""
    configure_logging(verbose - quiet)


def _register() -> None:
    from marsscene.cli.bag import bag
    from marsscene.cli.benchmark import benchmark
    from marsscene.cli.benchmark_loc import loc
    from marsscene.cli.benchmark_nav import nav
    from marsscene.cli.benchmark_vpr import vpr, vpr_eval
    from marsscene.cli.build import build
    from marsscene.cli.drive import drive
    from marsscene.cli.eval import eval_cmd
    from marsscene.cli.export import export_cmd
    from marsscene.cli.fly import fly
    from marsscene.cli.info import info
    from marsscene.cli.serve import serve
    from marsscene.cli.sun import sun
    from marsscene.cli.sweep import sweep
    from marsscene.cli.traversability import traversability

    main.add_command(build)
    main.add_command(info)
    main.add_command(sun)
    main.add_command(drive)
    main.add_command(fly)
    main.add_command(serve)
    main.add_command(eval_cmd)
    main.add_command(bag)
    main.add_command(export_cmd)
    main.add_command(sweep)
    main.add_command(traversability)
    main.add_command(benchmark)
    benchmark.add_command(vpr)
    benchmark.add_command(vpr_eval)
    benchmark.add_command(loc)
    benchmark.add_command(nav)


_register()
