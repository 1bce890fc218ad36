"""UTC parsing and the UTC -> TT time scale (leap seconds) used by the Mars24 sun position.

``TT - UTC = (TAI - UTC) + 32.184 s`` with TAI - UTC from the bundled leap-second table
(``data/leap_seconds.csv``, IERS Bulletin C). Mars24 step A-4 (Allison & McEwen 2000).
"""

from __future__ import annotations

import csv
import datetime as dt
from functools import lru_cache
from importlib import resources

import numpy as np

from marsscene.errors import ConfigError

__all__ = [
    "jd_tt_from_utc",
    "parse_utc",
    "tt_minus_utc_s",
    "utc_from_jd_tt",
]

_UNIX_EPOCH_JD = 2440587.5
_TT_MINUS_TAI_S = 32.184
_EPOCH = dt.datetime(1970, 1, 1, tzinfo=dt.UTC)


@lru_cache(maxsize=1)
def _leap_table() -> tuple[tuple[dt.datetime, ...], tuple[float, ...]]:
    text = resources.files("marsscene.lighting").joinpath("data/leap_seconds.csv").read_text(
        encoding="utf-8"
    )
    rows = [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]
    reader = csv.DictReader(rows)
    dates, values = [], []
    for row in reader:
        dates.append(dt.datetime.fromisoformat(row["utc_date"]).replace(tzinfo=dt.UTC))
        values.append(float(row["tai_minus_utc_s"]))
    return tuple(dates), tuple(values)


def parse_utc(utc: dt.datetime | str) -> dt.datetime:
    """Return ``utc`` as a timezone-aware UTC :class:`~datetime.datetime`.

    Parameters
    ----------
    utc : datetime or str
        A timezone-aware datetime, or an ISO 8601 string with a ``Z`` or ``+hh:mm`` suffix
        (e.g. ``"2021-02-18T20:55Z"``). Naive datetimes and strings without a zone are rejected:
        a Mars sun position an hour off is a silent, large error.

    Raises
    ------
    ConfigError
        For naive datetimes, unparsable strings or other types.
    """
    if isinstance(utc, str):
        text = utc.strip()
        if text.endswith(("Z", "z")):
            text = text[:-1] + "+00:00"
        try:
            value = dt.datetime.fromisoformat(text)
        except ValueError:
            raise ConfigError(
                f"utc = {utc!r} is not an ISO 8601 time; use e.g. '2021-02-18T20:55:00Z'"
            ) from None
    elif isinstance(utc, dt.datetime):
        value = utc
    else:
        raise ConfigError(f"utc = {utc!r} must be a timezone-aware datetime or an ISO string")
    if value.tzinfo is None or value.utcoffset() is None:
        raise ConfigError(
            f"utc = {utc!r} has no time zone; give a timezone-aware datetime "
            "(datetime(..., tzinfo=timezone.utc)) or a string ending in 'Z' or '+00:00'"
        )
    return value.astimezone(dt.UTC)


def tt_minus_utc_s(utc: dt.datetime | str) -> float:
    """TT - UTC in seconds at ``utc`` (69.184 s since 2017-01-01; 64.184 s in 1999-2005)."""
    when = parse_utc(utc)
    dates, values = _leap_table()
    tai_utc = values[0]
    for d, v in zip(dates, values, strict=True):
        if when >= d:
            tai_utc = v
        else:
            break
    return tai_utc + _TT_MINUS_TAI_S


def jd_tt_from_utc(utc: dt.datetime | str) -> float:
    """Julian date in Terrestrial Time (Mars24 A-1..A-5)."""
    when = parse_utc(utc)
    millis = (when - _EPOCH) / dt.timedelta(milliseconds=1)
    jd_ut = _UNIX_EPOCH_JD + millis / 8.64e7
    return jd_ut + tt_minus_utc_s(when) / 86400.0


def utc_from_jd_tt(jd_tt: float) -> dt.datetime:
    """Inverse of :func:`jd_tt_from_utc` (to the microsecond)."""
    guess = _EPOCH + dt.timedelta(days=float(jd_tt) - _UNIX_EPOCH_JD)
    for _ in range(2):  # TT - UTC depends on the UTC date
        offset = tt_minus_utc_s(guess)
        days = float(jd_tt) - _UNIX_EPOCH_JD - offset / 86400.0
        micros = int(np.round(days * 86400e6))
        guess = _EPOCH + dt.timedelta(microseconds=micros)
    return guess
