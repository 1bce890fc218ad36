"""Sensor and run-config options of ``marsscene drive`` and ``marsscene serve``, and the
:class:`~marsscene.rover.config.RunConfig` they make.

Each option is declared once here (name, type, default, the drive's help text); a command picks
the ones it offers with :func:`run_option`, in its own order and optionally with its own help
text, and hands the values back to :func:`run_config`. An option a command does not offer takes
its default there.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import click

from marsscene.cli._common import compose
from marsscene.errors import ConfigError
from marsscene.rover.config import (
    CameraConfig,
    LidarConfig,
    NoiseConfig,
    RunConfig,
    noise_profiles,
)
from marsscene.rover.lidar import lidar_models
from marsscene.rover.rates import PHYSICS_HZ
from marsscene.rover.terramechanics import soils

__all__ = ["RUN_OPTION_NAMES", "camera_size", "run_config", "run_option", "run_options"]

_FILE = click.Path(exists=True, dir_okay=False, path_type=Path)
_CAM = CameraConfig()  # the camera defaults live in CameraConfig only
_LIDAR = LidarConfig()  # and the LiDAR's in LidarConfig

#: click parameter -> (option declarations, click.option keywords with the drive's help text)
_SPECS: dict[str, tuple[tuple[str, ...], dict[str, Any]]] = {
    "camera": (("--camera",), dict(
        is_flag=True, help="Log RGB-D mast camera images (docs/camera.md).")),
    "camera_size": (("--camera-size",), dict(
        default=f"{_CAM.width_px}x{_CAM.height_px}", show_default=True, metavar="WxH",
        help="Camera image size in pixels.")),
    "camera_hz": (("--camera-hz",), dict(
        type=float, default=_CAM.rate_hz, show_default=True,
        help=f"Camera rate (must divide {PHYSICS_HZ:g} Hz).")),
    "stereo": (("--stereo",), dict(
        is_flag=True, help="Also log a rectified Navcam-like stereo pair "
        f"({_CAM.stereo_baseline_m} m baseline).")),
    "exposure": (("--exposure",), dict(
        type=click.Choice(["auto", "fixed"]), default=_CAM.exposure, show_default=True,
        help=f"Auto-exposure (mean {_CAM.target_mean}) or a fixed exposure.")),
    "exposure_gain": (("--exposure-gain",), dict(
        type=click.FloatRange(min=0, min_open=True), default=_CAM.exposure_gain,
        show_default=True, help="Gain of --exposure fixed.")),
    "camera_noise": (("--camera-noise",), dict(
        is_flag=True, help="Add seeded shot + read noise to images.")),
    "no_shadows": (("--no-shadows",), dict(
        is_flag=True, help="Turn the sun's shadow map off (faster).")),
    "tau": (("--tau",), dict(
        type=click.FloatRange(0, 10), default=None,
        help="Override the scene's dust optical depth for the camera's lighting.")),
    "sun_elevation": (("--sun-elevation-deg", "sun_elevation"), dict(
        type=click.FloatRange(-10, 90), default=None,
        help="Override the sun elevation (deg) for the camera's lighting.")),
    "lidar": (("--lidar",), dict(
        is_flag=True,
        help=f"Log a spinning 3D LiDAR (default model {_LIDAR.model}: {_LIDAR.spec.channels} x "
        f"{_LIDAR.spec.horizontal_samples} at {_LIDAR.spec.rate_hz:g} Hz; PLY).")),
    "lidar_model": (("--lidar-model",), dict(
        type=click.Choice(tuple(lidar_models())), default=None,
        help="LiDAR model from datasheets (docs/runtime.md); implies --lidar.")),
    "run_config": (("--run-config",), dict(
        type=_FILE, help="TOML/JSON run config: [run], [lidar] (e.g. model = \"vlp16\"), "
        "[camera], [noise] tables; options given on the command line win.")),
    "noise_config": (("--noise-config",), dict(
        type=_FILE, help="TOML/JSON noise config ([noise] table).")),
    "noise_profile": (("--noise-profile",), dict(
        type=click.Choice(tuple(noise_profiles())), default=None,
        help="Named IMU + wheel-odometry noise profile from datasheets (docs/runtime.md); "
        "keys set in --noise-config / --run-config still win. Default: the config's "
        "profile, else none: a noise-free IMU and exact encoders, an optimistic "
        "odometry (the SLAM benchmark uses ln200s).")),
    "soil": (("--soil",), dict(
        type=click.Choice(("rigid", *soils())), default=None,
        help="Deformable soil under the wheels: slip, sinkage and their forces "
        "(docs/science/terramechanics.md). Default: the run config's, else rigid contact.")),
}

#: The click parameters :func:`run_config` reads, in the drive's order.
RUN_OPTION_NAMES = tuple(_SPECS)

#: What :func:`run_config` takes for an option a command does not offer: click's default.
_DEFAULTS = {name: kw.get("default", False if kw.get("is_flag") else None)
             for name, (_, kw) in _SPECS.items()}


def run_option(name: str, help: str | None = None) -> Callable[[Any], Any]:
    """The click option of parameter ``name`` (one of :data:`RUN_OPTION_NAMES`), with the
    command's ``help`` text (default: the drive's)."""
    decls, kw = _SPECS[name]
    return click.option(*decls, **(kw if help is None else {**kw, "help": help}))


def run_options(*names: str) -> Callable[[Any], Any]:
    """:func:`run_option` of each of ``names``, in that order, with the drive's help texts."""
    return compose(*(run_option(name) for name in names))


def camera_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> ``(640, 480)`` pixels (``--camera-size``)."""
    parts = text.lower().split("x")
    try:
        w, h = int(parts[0]), int(parts[1])
        if len(parts) != 2:
            raise ValueError
    except (ValueError, IndexError):
        raise ConfigError(f"--camera-size {text!r} must be WIDTHxHEIGHT, e.g. 640x480") from None
    return w, h


def run_config(values: Mapping[str, Any]) -> RunConfig:
    """The drive's :class:`~marsscene.rover.config.RunConfig`: the run config file (if any),
    then the command-line options over it.

    Parameters
    ----------
    values : mapping
        Click parameter -> value of the options the command offers (a subset of
        :data:`RUN_OPTION_NAMES`; the others take their defaults).

    Raises
    ------
    TypeError
        A key that is not a run option (a command passing what this function does not read).
    ConfigError
        A bad ``--camera-size`` or config file.
    """
    unknown = sorted(set(values) - set(_SPECS))
    if unknown:
        raise TypeError(f"run_config() got values that are not run options: {unknown}")
    v = {**_DEFAULTS, **values}
    run = RunConfig.from_toml(v["run_config"]) if v["run_config"] else RunConfig()
    if v["noise_config"]:
        run = dataclasses.replace(run, noise=NoiseConfig.from_toml(v["noise_config"]))
    if v["noise_profile"]:
        run = dataclasses.replace(run, noise=run.noise.with_profile(v["noise_profile"]))
    if v["soil"]:
        run = dataclasses.replace(run, soil=v["soil"])
    if v["lidar"] or v["lidar_model"]:
        base = run.lidar if run.lidar is not None else LidarConfig()
        lid = dataclasses.replace(base, model=v["lidar_model"]) if v["lidar_model"] else base
        run = dataclasses.replace(run, lidar=lid)
    if v["camera"] or v["stereo"]:
        w, h = camera_size(v["camera_size"])
        run = dataclasses.replace(run, camera=CameraConfig(
            width_px=w, height_px=h, rate_hz=v["camera_hz"], stereo=v["stereo"],
            exposure=v["exposure"], exposure_gain=v["exposure_gain"],
            sensor_noise=v["camera_noise"], shadows=not v["no_shadows"], tau=v["tau"],
            sun_elevation_deg=v["sun_elevation"]))
    return run
