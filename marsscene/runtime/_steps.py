"""The steps of :func:`marsscene.runtime.api.drive` around the drive itself: the checks before
it, the scene folder, ``route.tum``, the controller made from the prepared simulator, the bag's
JPEG cache, and the exports after it (private: ``drive`` is the one caller)."""

from __future__ import annotations

import inspect
import logging
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from marsscene.errors import ExportError, RuntimeSimError
from marsscene.rover.config import RunConfig
from marsscene.runs.export.options import ExportOptions
from marsscene.runs.tum import write_tum
from marsscene.sim.control import OnStart
from marsscene.sim.mission import DriveOptions
from marsscene.sim.route import Route

if TYPE_CHECKING:
    from marsscene.scene import Scene

__all__ = ["ROUTE_NOTE", "ExportProgress", "check_exports", "export_run", "jpeg_cache", "scene_dir",
           "started", "write_route"]

log = logging.getLogger("marsscene")
#: Header of ``route.tum`` unless ``DriveOptions.route_note`` says otherwise.
ROUTE_NOTE = "authored route (x, y on the terrain; stamps at 0.5 m/s)"


@dataclass(frozen=True)
class ExportProgress:
    """Where an export stands, passed to ``drive(progress=...)``: ``stage`` is ``"bag"`` (done
    / total messages) or a dataset format (done / total images)."""

    stage: str
    done: int
    total: int


def check_exports(export: ExportOptions, config: RunConfig, out: Path | None) -> None:
    """Refuse, before driving, exports that cannot be written."""
    if out is None and (export.bag is not None or export.datasets):
        raise RuntimeSimError("exports (a bag, datasets) need a run folder: give out_dir (--out)")
    if export.datasets and config.camera is None:
        raise RuntimeSimError(f"datasets {', '.join(export.datasets)} need the camera: "
                              "drive with RunConfig(camera=CameraConfig(...)) (--camera)")
    if out is not None and not export.overwrite:
        for name in export.folders:
            if (out / name).exists():
                raise ExportError(f"{out / name} exists; pass overwrite=True (--overwrite) "
                                  "to replace it")
    if export.bag is not None:
        from marsscene.runs.export.bag_writer import require_backends

        require_backends(export.bag.compression)


@contextmanager
def scene_dir(scene: str | os.PathLike[str] | Scene, out: Path | None) -> Iterator[Path]:
    """A scene folder: the one given, or a built :class:`~marsscene.Scene` written as MJCF into
    ``out/scene`` (into a temporary folder without ``out``)."""
    if isinstance(scene, str | os.PathLike):
        yield Path(scene)
        return
    from marsscene.export import write_scene

    if out is not None:
        write_scene(scene, out / "scene", formats=("mjcf",), overwrite=True)
        yield out / "scene"
        return
    with tempfile.TemporaryDirectory(prefix="marsscene-scene-") as tmp:
        write_scene(scene, Path(tmp) / "scene", formats=("mjcf",))
        yield Path(tmp) / "scene"


def write_route(out: Path | None, sim: Any, path: Route | None, options: DriveOptions) -> None:
    """``route.tum`` of a drive along a route, into its run folder."""
    if path is not None and sim.rocks_kept[1]:
        log.info("rocks: %d of %d MJCF rocks lie near the route and are simulated",
                 *sim.rocks_kept)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        if path is not None:
            write_tum(out / "route.tum", path.to_trajectory(sim.heightfield),
                      header=(options.route_note or ROUTE_NOTE).format(length_m=path.length_m))


def started(controller: Any, sim: Any, route: Route | None) -> tuple[Any, tuple[Any, ...]]:
    """The drive's controller (made now from an :class:`OnStart`: ``make(sim)``, or
    ``make(sim, route=route)`` when ``make`` takes a ``route``, the drive's authored or given
    route) and the listeners it adds."""
    if not isinstance(controller, OnStart):
        return controller, ()
    make: Any = controller.make
    made = make(sim, route=route) if "route" in inspect.signature(make).parameters else make(sim)
    return made, ((made,) if controller.listen else ())


@contextmanager
def jpeg_cache(out: Path | None, export: ExportOptions, config: RunConfig) -> Iterator[Any]:
    """The bag's JPEG cache, filled while driving (None when no bag wants JPEG frames)."""
    if out is None or export.bag is None or config.camera is None or not export.bag.wants_jpeg:
        yield None
        return
    from marsscene.runs.export.bag_images import JpegCache  # no rosbags import

    cache = JpegCache.fresh(out, export.bag.jpeg_quality)
    try:
        yield cache
    finally:
        cache.remove()


def export_run(out: Path | None, export: ExportOptions, cache: Any,
            progress: Callable[[Any], None] | None) -> tuple[Any, dict[str, Path]]:
    """Write the bag and the dataset folders of the finished run folder ``out``."""
    def tell(stage: str) -> Callable[[int, int], None] | None:
        if progress is None:
            return None
        return lambda done, total: progress(ExportProgress(stage, done, total))

    bag = None
    if out is not None and export.bag is not None:
        from marsscene.runs.export.bag import write_bag

        bag = write_bag(out, options=export.bag, overwrite=export.overwrite, jpeg_cache=cache,
                        progress=tell("bag"))
        if export.lidar_into_bag() and not export.keep_lidar_files:
            from marsscene.runs.runlog import move_lidar_into_bag

            move_lidar_into_bag(out)
    datasets: dict[str, Path] = {}
    if out is not None:
        from marsscene.runs.export.datasets import export_dataset

        for fmt in export.datasets:
            datasets[fmt] = export_dataset(out, fmt, overwrite=export.overwrite,
                                           progress=tell(fmt), images=export.dataset_images)
    return bag, datasets
