"""The physics rate of a built scene, and the rule every control and sensor rate obeys: it
divides the physics rate (a whole number of physics steps per tick)."""

from __future__ import annotations

from marsscene._validate import check_range
from marsscene.errors import ConfigError

__all__ = ["PHYSICS_HZ", "check_rate"]

#: Physics rate of a built scene in Hz: ``scene.xml``'s timestep is ``1 / PHYSICS_HZ`` (2 ms);
#: ``RunConfig.physics_hz`` overrides it for a drive.
PHYSICS_HZ = 500.0


def check_rate(key: str, rate_hz: float, physics_hz: float = PHYSICS_HZ) -> None:
    """Raise a one-line :class:`ConfigError` naming ``key`` unless ``rate_hz`` divides
    ``physics_hz``.

    Examples
    --------
    >>> check_rate("camera.rate_hz", 10.0)
    >>> try:
    ...     check_rate("camera.rate_hz", 7.0)
    ... except ConfigError as err:
    ...     print(str(err).split(" (")[0])
    camera.rate_hz = 7.0 must divide the 500 Hz physics rate
    """
    check_range(key, rate_hz, 0.0, physics_hz, lo_open=True)
    ratio = physics_hz / rate_hz
    if abs(ratio - round(ratio)) > 1e-9:
        examples = ", ".join(f"{physics_hz / n:g}" for n in (50, 10, 5, 2) if physics_hz >= n)
        raise ConfigError(f"{key} = {rate_hz!r} must divide the {physics_hz:g} Hz physics rate "
                          f"(e.g. {examples})")
