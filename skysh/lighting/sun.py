"""
The sun's position from a place and a time (NOAA solar calculator)
==================================================================

-   :func:`position`: ``(sun_zenith, sun_azimuth)`` in radians in skysh's frame,
    refusing times when the sun is below the horizon (the Preetham sky is not
    defined there).
-   :func:`position_unchecked`: the same angles for any time, sun up or down.
-   :func:`ephemeris`: the sun's apparent longitude, right ascension,
    declination and the equation of time (the place-independent part).
-   :func:`compass_to_frame`, :func:`frame_to_compass`: convert azimuths between
    the compass (clockwise from North) and skysh's frame (from +X towards +Y).

Frame
-----
skysh's frame is right-handed with Z up and the azimuth phi measured from +X
towards +Y (``docs/conventions.md``). On the ground this module fixes

    **+X = East, +Y = North, +Z = up** (the local East-North-Up frame).

So a direction with East, North and up components (e, n, u) has
``phi = atan2(n, e)``, and a compass azimuth A (clockwise from North, N = 0,
E = pi/2, S = pi, W = 3 pi/2) converts as

    ``phi = pi/2 - A``  and  ``A = pi/2 - phi`` (modulo 2 pi).

Due East is phi = 0 (+X), North pi/2 (+Y), South -pi/2 (-Y), West pi. Frame
azimuths are returned in (-pi, pi], compass azimuths in [0, 2 pi). A renderer
whose +X is not East rotates the SH about Z by its own offset
(:func:`skysh.sh.basis.rotate_z`).

Units
-----
The output angles are radians, like the rest of the library API. ``latitude``
and ``longitude`` are the one exception: they are **degrees, as on every map**
(and as the command line takes them, so the CLI passes them through): latitude
positive North in [-90, 90], longitude positive East in [-180, 180]. A latitude
given in radians would be silently wrong rather than out of range, so the unit
is stated in every docstring here.

``when`` is a timezone-aware :class:`datetime.datetime` (any tzinfo, e.g.
``datetime.timezone.utc`` or a ``zoneinfo.ZoneInfo``) or an ISO-8601 string
with an offset (``"2024-06-21T12:00:00+02:00"``, ``"...Z"``). Naive datetimes
are refused: a local clock time without its offset is ambiguous by hours.

Algorithm
---------
The equations of NOAA's Solar Calculator spreadsheets (after Meeus,
*Astronomical Algorithms*, ch. 25 "low accuracy" solar coordinates and
eq. 28.3 for the equation of time): Julian century, geometric mean longitude
and anomaly, eccentricity, equation of centre, apparent longitude, corrected
obliquity, declination, equation of time, true solar time, hour angle, zenith.
Two departures, neither changing the result beyond rounding:

-   the Julian day is computed exactly from the UTC instant (Python's proleptic
    Gregorian calendar) instead of the spreadsheet's Excel-date shortcut, which
    is what limits the spreadsheets to the years 1901-2099;
-   the azimuth is ``atan2`` of the East and North components of the sun
    direction instead of the spreadsheet's ``acos`` with a branch on the hour
    angle (same angle, no loss of precision near the zenith, defined at the
    poles, where it is taken relative to the meridian of ``longitude``).

Like NOAA, no Delta T (TT - UT, about 69 s in 2024) is applied and the position
is geocentric (no parallax, at most 0.0024 deg). NOAA's web page states the
accuracy only for sunrise and sunset times (within one minute between +/- 72
deg latitude); it gives no angular figure. Measured here
(``tests/lighting/test_sun.py``): Meeus's example 25.a declination and right ascension
agree to 1e-5 deg, and the NREL SPA reference example's zenith and azimuth to
0.003 deg (its declination to 0.0015 deg), far below what the sky model can
resolve.

Atmospheric refraction is applied by default (``refraction=True``), with
NOAA's piecewise formula for a standard atmosphere: the returned zenith is then
the *apparent* one, as seen and as NOAA's calculator reports it (it raises the
sun by 0.57 deg at the horizon, 0.016 deg at 45 deg elevation, 0 above 85 deg).
``refraction=False`` gives the geometric (airless) zenith. The below-horizon
check of :func:`position` uses the zenith that is returned.

References
----------
-   NOAA Global Monitoring Laboratory, Solar Calculator and its spreadsheets
    ``NOAA_Solar_Calculations_day.xls`` (calculation details page:
    gml.noaa.gov/grad/solcalc/calcdetails.html).
-   Meeus, J. (1998). *Astronomical Algorithms*, 2nd ed., Willmann-Bell:
    ch. 7 (Julian day), ch. 22 eq. 22.2 (obliquity), ch. 25 (solar coordinates,
    example 25.a), ch. 28 eq. 28.3 (equation of time, example 28.b).
-   Reda, I., Andreas, A. (2004). Solar position algorithm for solar radiation
    applications. *Solar Energy* 76(5), 577-589; NREL/TP-560-34302 (the SPA
    example used as an independent check in the tests).
"""

from __future__ import annotations

import datetime as _dt
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_flag, check_range, check_size, short_repr

__all__ = ["LATITUDE_RANGE", "LONGITUDE_RANGE", "HORIZON_ZENITH", "position", "position_unchecked", "as_utc"]

LATITUDE_RANGE: tuple[float, float] = (-90.0, 90.0)
"""Valid geographic latitude, degrees, positive North."""

LONGITUDE_RANGE: tuple[float, float] = (-180.0, 180.0)
"""Valid geographic longitude, degrees, positive East."""

J2000: _dt.datetime = _dt.datetime(2000, 1, 1, 12, 0, 0, tzinfo=_dt.timezone.utc)
"""The epoch J2000.0 (JD 2451545.0). NOAA applies no Delta T, so UTC stands in for TT."""

DAYS_PER_JULIAN_CENTURY: float = 36525.0
"""Days in a Julian century, the time unit T of Meeus's series."""

HORIZON_ZENITH: float = math.pi / 2.0
"""Largest sun zenith angle, radians, for which the Preetham sky is defined."""

_REFRACTION_MAX_ELEVATION: float = 85.0
"""NOAA: no refraction correction above this elevation, degrees."""

_REFRACTION_TAN_ELEVATION: float = 5.0
"""NOAA: the tangent series is used above this elevation, degrees."""

_REFRACTION_POLY_ELEVATION: float = -0.575
"""NOAA: the horizon polynomial is used above this elevation, degrees."""

_ARCSEC_PER_DEG: float = 3600.0


class SunPosition(NamedTuple):
    """The sun's direction in skysh's frame (+X East, +Y North, +Z up), radians."""

    sun_zenith: NDArray[np.float64] | np.float64
    """Angle from the zenith, [0, pi] (apparent when refraction is applied)."""
    sun_azimuth: NDArray[np.float64] | np.float64
    """Azimuth from +X (East) towards +Y (North), (-pi, pi]."""


class SolarEphemeris(NamedTuple):
    """The place-independent solar quantities of the NOAA / Meeus ch. 25 series (radians)."""

    julian_century: float
    """T: Julian centuries from J2000.0 (UTC taken as TT, as NOAA does)."""
    apparent_longitude: float
    """Apparent ecliptic longitude lambda of the sun, radians, [0, 2 pi)."""
    obliquity: float
    """Obliquity of the ecliptic corrected for nutation (Meeus's epsilon), radians."""
    right_ascension: float
    """Apparent right ascension alpha, radians, (-pi, pi]."""
    declination: float
    """Apparent declination delta, radians."""
    equation_of_time: float
    """Apparent minus mean solar time as an hour angle, radians (times 720/pi: minutes)."""


# --------------------------------------------------------------------------- time


_UTC_RANGE_TEXT: str = "0001-01-01T00:00:00Z .. 9999-12-31T23:59:59.999999Z"
"""The instants a ``when`` may name: Python's datetime range, in UTC."""


def as_utc(when: _dt.datetime | str, name: str = "when") -> _dt.datetime:
    """Return ``when`` (an aware datetime or an ISO-8601 string with an offset) as an aware UTC datetime;
    refuse naive datetimes, other types and instants outside Python's datetime range in UTC with a
    ValueError naming ``name`` (the parameter, or a command-line flag)."""
    if isinstance(when, str):
        text = when.strip()
        if text[-1:] in ("Z", "z"):  # Python 3.10's fromisoformat does not read "Z"
            text = text[:-1] + "+00:00"
        try:
            parsed = _dt.datetime.fromisoformat(text)
        except ValueError as error:
            raise ValueError(
                f"{name} must be an ISO-8601 date-time with an offset, e.g. '2024-06-21T12:00:00+02:00', got {short_repr(when)}"
            ) from error
        if parsed.tzinfo is None or parsed.utcoffset() is None:
            raise ValueError(
                f"{name} must carry a UTC offset (e.g. '+02:00' or 'Z'), got {short_repr(when)}: a local time alone is ambiguous"
            )
        when = parsed
    if not isinstance(when, _dt.datetime):
        raise ValueError(
            f"{name} must be a timezone-aware datetime.datetime or an ISO-8601 string with an offset, got {short_repr(when)}"
        )
    try:
        offset = when.utcoffset()
    except (TypeError, ValueError) as error:  # a tzinfo whose utcoffset() misbehaves
        raise ValueError(f"{name} has a tzinfo whose utcoffset() fails: {error}") from error
    if when.tzinfo is None or offset is None:
        raise ValueError(
            f"{name} must be timezone-aware: give it a tzinfo, e.g. datetime.timezone.utc or "
            f"zoneinfo.ZoneInfo('Europe/Vienna'), got the naive {when.isoformat()}"
        )
    try:
        return when.astimezone(_dt.timezone.utc)
    except OverflowError:  # e.g. 0001-01-01T00:00:00+05:00 is still year 0 in UTC
        raise ValueError(
            f"{name} must lie in {_UTC_RANGE_TEXT} once converted to UTC (Python's datetime range), got {when.isoformat()}"
        ) from None




def _julian_century(utc: _dt.datetime) -> float:
    """Julian centuries since J2000.0 of an aware UTC datetime (exact to the microsecond)."""
    return (utc - J2000).total_seconds() / 86400.0 / DAYS_PER_JULIAN_CENTURY


# --------------------------------------------------------------------------- ephemeris


def _ephemeris_deg(t: float) -> tuple[float, float, float, float, float]:
    """
    NOAA's spreadsheet columns I..V for Julian century ``t``, in degrees (EoT in minutes).

    Returns (apparent longitude, corrected obliquity, right ascension,
    declination, equation of time in minutes).
    """
    # Meeus 25.2-25.4 (NOAA columns I, J, K).
    mean_longitude = (280.46646 + t * (36000.76983 + t * 0.0003032)) % 360.0
    mean_anomaly = 357.52911 + t * (35999.05029 - 0.0001537 * t)
    e = 0.016708634 - t * (0.000042037 + 0.0000001267 * t)  # eccentricity of the earth's orbit
    m = math.radians(mean_anomaly)
    # Equation of centre (column L) and true longitude (column M).
    centre = (
        math.sin(m) * (1.914602 - t * (0.004817 + 0.000014 * t))
        + math.sin(2.0 * m) * (0.019993 - 0.000101 * t)
        + math.sin(3.0 * m) * 0.000289
    )
    true_longitude = mean_longitude + centre
    # Apparent longitude (column P), with the nutation/aberration term in Omega.
    omega = math.radians(125.04 - 1934.136 * t)
    apparent_longitude = (true_longitude - 0.00569 - 0.00478 * math.sin(omega)) % 360.0
    # Mean obliquity, Meeus 22.2 (column Q), corrected (column R).
    mean_obliquity = 23.0 + (26.0 + (21.448 - t * (46.815 + t * (0.00059 - t * 0.001813))) / 60.0) / 60.0
    obliquity = mean_obliquity + 0.00256 * math.cos(omega)
    lam = math.radians(apparent_longitude)
    eps = math.radians(obliquity)
    # Right ascension and declination (columns S, T).
    right_ascension = math.degrees(math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam)))
    declination = math.degrees(math.asin(math.sin(eps) * math.sin(lam)))
    # Equation of time, Meeus 28.3 (columns U, V), in minutes of time.
    y = math.tan(eps / 2.0) ** 2
    l0 = math.radians(mean_longitude)
    eot_rad = (
        y * math.sin(2.0 * l0)
        - 2.0 * e * math.sin(m)
        + 4.0 * e * y * math.sin(m) * math.cos(2.0 * l0)
        - 0.5 * y * y * math.sin(4.0 * l0)
        - 1.25 * e * e * math.sin(2.0 * m)
    )
    return apparent_longitude, obliquity, right_ascension, declination, 4.0 * math.degrees(eot_rad)


def ephemeris(when: _dt.datetime | str) -> SolarEphemeris:
    """
    The sun's apparent equatorial coordinates and the equation of time at ``when``.

    Parameters
    ----------
    when
        Timezone-aware :class:`datetime.datetime`, or an ISO-8601 string with a
        UTC offset. Taken as UT and, as in NOAA's calculator, also as TT (no
        Delta T).

    Returns
    -------
    SolarEphemeris
        Julian century and the angles in radians; ``equation_of_time`` is an
        hour angle in radians (multiply by 720/pi for minutes of time).

    Notes
    -----
    NOAA spreadsheet columns G..V, which are Meeus ch. 25's low-accuracy solar
    coordinates (apparent longitude corrected for nutation and aberration,
    obliquity corrected by 0.00256 cos Omega) and Meeus eq. 28.3 for the
    equation of time.

    References
    ----------
    Meeus (1998), example 25.a: 1992 October 13.0 gives declination
    -7.78507 deg and right ascension 198.38083 deg.

    Examples
    --------
    >>> import math
    >>> e = ephemeris("1992-10-13T00:00:00Z")
    >>> round(math.degrees(e.declination), 5)
    -7.78507
    """
    t = _julian_century(as_utc(when))
    lam, eps, alpha, delta, eot_minutes = _ephemeris_deg(t)
    # every angle in radians; the equation of time as an hour angle (1 degree per 4 minutes of time)
    return SolarEphemeris(t, *(math.radians(v) for v in (lam, eps, alpha, delta, eot_minutes / 4.0)))


# --------------------------------------------------------------------------- horizon


def _refraction_deg(e: NDArray[np.float64]) -> NDArray[np.float64]:
    """NOAA's atmospheric refraction correction, degrees, for the geometric elevation ``e`` in degrees."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        tan_e = np.tan(np.radians(e))
        high = 58.1 / tan_e - 0.07 / tan_e**3 + 0.000086 / tan_e**5
        near = 1735.0 + e * (-518.2 + e * (103.4 + e * (-12.79 + e * 0.711)))
        below = -20.772 / tan_e
    arcsec = np.select(
        [e > _REFRACTION_MAX_ELEVATION, e > _REFRACTION_TAN_ELEVATION, e > _REFRACTION_POLY_ELEVATION],
        [0.0, high, near],
        default=below,
    )
    return arcsec / _ARCSEC_PER_DEG


def _scalar_or_array(value: NDArray[np.float64]) -> NDArray[np.float64] | np.float64:
    return value[()] if value.ndim == 0 else value


def position_unchecked(
    latitude: ArrayLike, longitude: ArrayLike, when: _dt.datetime | str, refraction: bool = True
) -> SunPosition:
    """
    The sun's zenith angle and azimuth at any time, with the sun up or down.

    Parameters
    ----------
    latitude
        Geographic latitude in **degrees** (as on a map), positive North,
        [-90, 90]. Any array shape, broadcast against ``longitude``.
    longitude
        Geographic longitude in **degrees**, positive East, [-180, 180].
    when
        Timezone-aware :class:`datetime.datetime`, or an ISO-8601 string with a
        UTC offset. Naive datetimes are refused.
    refraction
        Apply NOAA's standard-atmosphere refraction (default): the zenith is
        then the apparent one. ``False``: the geometric zenith. A bool.

    Returns
    -------
    SunPosition
        ``(sun_zenith, sun_azimuth)`` in radians: zenith in [0, pi], azimuth in
        (-pi, pi] from +X = East towards +Y = North. Scalars (numpy float64)
        for scalar inputs, else arrays of the broadcast shape (empty arrays
        give empty results).

    Raises
    ------
    ValueError
        Latitude or longitude out of range, NaN or inf, not numbers, or too
        many places (``skysh.checks.MAX_ARRAY_ELEMENTS``); ``when`` naive,
        not a date-time, or outside Python's datetime range once in UTC.
    TypeError
        ``refraction`` not a bool.

    Examples
    --------
    >>> import math
    >>> z, phi = position_unchecked(40.0, -105.0, "2024-03-20T00:00:00-07:00")
    >>> bool(z > math.pi / 2)  # midnight in Colorado: the sun is down
    True
    """
    refraction = check_flag(refraction, "refraction")
    lat_deg = check_range(latitude, "latitude", *LATITUDE_RANGE, unit="deg")
    lon_deg = check_range(longitude, "longitude", *LONGITUDE_RANGE, unit="deg")
    try:
        lat_deg, lon_deg = np.broadcast_arrays(lat_deg, lon_deg)
    except ValueError as error:
        raise ValueError(
            f"latitude and longitude must broadcast together, got shapes {np.shape(lat_deg)} and {np.shape(lon_deg)}"
        ) from error
    check_size(8 * lat_deg.size, "latitude" if np.size(latitude) >= np.size(longitude) else "longitude",
               f"{lat_deg.size:,} places")
    utc = as_utc(when)
    _, _, _, declination_deg, eot_minutes = _ephemeris_deg(_julian_century(utc))

    # True solar time (minutes) and hour angle (NOAA columns AB, AC), positive West.
    minutes_utc = utc.hour * 60.0 + utc.minute + (utc.second + utc.microsecond * 1e-6) / 60.0
    true_solar_time = minutes_utc + eot_minutes + 4.0 * lon_deg
    hour_angle = np.radians(true_solar_time / 4.0 - 180.0)

    lat = np.radians(lat_deg)
    dec = math.radians(declination_deg)
    sin_dec, cos_dec = math.sin(dec), math.cos(dec)
    east = -cos_dec * np.sin(hour_angle)
    north = np.cos(lat) * sin_dec - np.sin(lat) * cos_dec * np.cos(hour_angle)
    up = np.sin(lat) * sin_dec + np.cos(lat) * cos_dec * np.cos(hour_angle)

    zenith = np.arctan2(np.hypot(east, north), up)
    if refraction:
        elevation_deg = 90.0 - np.degrees(zenith)
        zenith = np.clip(np.radians(90.0 - (elevation_deg + _refraction_deg(elevation_deg))), 0.0, math.pi)
    azimuth = np.arctan2(north, east)
    azimuth = np.where(azimuth == -math.pi, math.pi, azimuth)  # (-pi, pi]
    return SunPosition(_scalar_or_array(np.asarray(zenith, dtype=np.float64)), _scalar_or_array(azimuth))


def position(
    latitude: ArrayLike, longitude: ArrayLike, when: _dt.datetime | str, refraction: bool = True
) -> SunPosition:
    """
    The sun's zenith angle and azimuth in skysh's frame, for the sky model.

    Parameters
    ----------
    latitude, longitude, when
        As :func:`position_unchecked`: degrees (as on a map) and an aware time,
        e.g. ``"2024-06-21T12:00:00+02:00"``.
    refraction
        Apply NOAA's standard-atmosphere refraction (default; the apparent
        sun, as seen). ``False``: the geometric zenith.

    Returns
    -------
    SunPosition
        ``(sun_zenith, sun_azimuth)`` in radians: zenith in [0, pi/2], azimuth
        in (-pi, pi] from +X = East towards +Y = North, ready for
        ``SkySH.coefficients(sun_zenith, turbidity, sun_azimuth)``.

    Raises
    ------
    ValueError
        As :func:`position_unchecked`, and when the sun is below the horizon
        (zenith > pi/2) at any of the places: the Preetham sky model is not
        defined there. :func:`position_unchecked` returns the angles anyway.

    Examples
    --------
    >>> import math
    >>> z, phi = position(48.21, 16.37, "2024-06-21T13:00:00+02:00")  # Vienna, midsummer
    >>> round(math.degrees(z), 1), round(math.degrees(phi), 1)  # just past noon: high, South (-Y) a little West
    (24.8, -92.0)
    """
    zenith, azimuth = position_unchecked(latitude, longitude, when, refraction=refraction)
    z = np.asarray(zenith)
    below = z > HORIZON_ZENITH
    if np.any(below):
        lat_b, lon_b, z_b = np.broadcast_arrays(np.asarray(latitude, float), np.asarray(longitude, float), z)
        k = np.flatnonzero(below.ravel())[0]
        raise ValueError(
            f"the sun is below the horizon at {as_utc(when).isoformat()} for latitude {lat_b.ravel()[k]:g} deg, "
            f"longitude {lon_b.ravel()[k]:g} deg (sun zenith {math.degrees(z_b.ravel()[k]):.2f} deg > 90 deg): "
            "the Preetham sky model is not defined there; skysh.lighting.sun.position_unchecked returns the raw angles"
        )
    return SunPosition(zenith, azimuth)


# --------------------------------------------------------------------------- azimuths


def _mod_2pi(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Wrap radians to [0, 2 pi)."""
    r = np.mod(angle, 2.0 * math.pi)
    return np.where(r >= 2.0 * math.pi, 0.0, r)  # np.mod can round up to exactly 2 pi


def compass_to_frame(azimuth: ArrayLike) -> NDArray[np.float64] | np.float64:
    """
    Convert a compass azimuth (clockwise from North) to skysh's frame azimuth.

    Parameters
    ----------
    azimuth
        Compass azimuth A, radians: North 0, East pi/2, South pi, West 3 pi/2.
        Any finite value, any shape (empty gives empty).

    Returns
    -------
    ndarray or numpy.float64
        ``phi = pi/2 - A`` wrapped to (-pi, pi]: the azimuth from +X = East
        towards +Y = North.

    Examples
    --------
    >>> import math
    >>> float(compass_to_frame(math.pi))  # South is -Y
    -1.5707963267948966
    """
    a = as_float_array(azimuth, "azimuth")
    return _scalar_or_array(math.pi - _mod_2pi(math.pi - (math.pi / 2.0 - a)))  # wrapped to (-pi, pi]


def frame_to_compass(azimuth: ArrayLike) -> NDArray[np.float64] | np.float64:
    """
    Convert skysh's frame azimuth (from +X = East towards +Y = North) to a compass azimuth.

    Parameters
    ----------
    azimuth
        Frame azimuth phi, radians, any finite value, any shape (empty gives empty).

    Returns
    -------
    ndarray or numpy.float64
        ``A = pi/2 - phi`` wrapped to [0, 2 pi): clockwise from North.

    Examples
    --------
    >>> float(frame_to_compass(0.0))  # +X is East
    1.5707963267948966
    """
    phi = as_float_array(azimuth, "azimuth")
    return _scalar_or_array(_mod_2pi(math.pi / 2.0 - phi))
