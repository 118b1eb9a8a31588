"""
Tests of skysh.lighting.sun: the NOAA solar position in skysh's frame (+X East, +Y North, +Z up).

Reference values are published numbers, each cited where it is used:

-   Meeus, J. (1998). Astronomical Algorithms, 2nd ed.: example 25.a (the sun
    on 1992 October 13.0 TD with the low-accuracy series NOAA uses) and
    example 28.b (the equation of time by eq. 28.3, same date).
-   Reda, I., Andreas, A. (2004/2008). Solar Position Algorithm for Solar
    Radiation Applications, NREL/TP-560-34302, appendix A.5 example (also the
    printed output of NREL's ``spa_tester.c``): an independent, more accurate
    algorithm (+/- 0.0003 deg).
-   US Naval Observatory, "Earth's Seasons": 2024 March equinox at 03:06 UTC on
    March 20 and June solstice at 20:51 UTC on June 20.
-   IAU 2006 precession (Capitaine et al. 2003): mean obliquity
    eps_A = 84381.406" - 46.836769" T.

The SPA and USNO numbers were checked (2026-11-23) against the expected output
printed in the comments of NREL's ``spa_tester.c`` (zenith 50.111622 deg,
azimuth 194.340241 deg) and against the USNO 2024 table as quoted in several
independent public code bases.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable
from typing import ClassVar

import numpy as np
import pytest

from skysh.lighting import sun

UTC = dt.timezone.utc

SERIES_TOL_DEG: float = 1e-5
"""Meeus prints the example-25.a angles to 5 decimals (rounding 5e-6 deg) and
rounds his intermediate values; NOAA's columns are the same formulas."""

EOT_TOL_RAD: float = 1.5e-6
"""Meeus prints E to 6 decimals of a radian (5e-7), and his example takes
y = tan^2(eps/2) with the mean obliquity where NOAA uses the corrected one (a
further 6e-7 rad on that date): 1.5e-6 rad is 0.02 s of time."""

LOW_ACCURACY_TOL_DEG: float = 0.01
"""Meeus ch. 25: the low-accuracy solar series NOAA uses is good to 0.01 deg."""

SPA_TOL_DEG: float = 0.01
"""NOAA vs the SPA example: low-accuracy series (0.01 deg, Meeus ch. 25) while the
other terms are smaller: SPA is topocentric (parallax 0.002 deg at z = 50 deg) and
refracts for 820 hPa and 11 C where NOAA assumes a standard atmosphere (about
0.003 deg at 40 deg elevation); SPA's Delta T = 67 s moves the sun by < 0.001 deg."""

SEARCH_TOL_S: float = 1e-3
"""Precision of the golden-section search for local solar noon, seconds of time."""

MEEUS_T_ATOL: float = 5e-10
"""Meeus prints the example's Julian century T = -0.072183436 to 9 decimals: half a unit."""

EOT_PRINTED_S: float = 0.05
"""Meeus prints E also as 13m 42.7s: half a tenth of a second of time (added to EOT_TOL_RAD in time)."""

REFRACTION_ATOL_DEG: float = 2e-4
"""Refraction at the solstice noon at 40 N (elevation 73.4 deg): NOAA's 58.1"/tan h - 0.07"/tan^3 h
= 17.3" = 0.00481 deg, quoted as 0.0048; the elevation, known here to 0.1 deg, moves it by 0.11"
(3e-5 deg) per 0.1 deg."""

NOON_AZIMUTH_ATOL: float = 1e-4
"""Radians: the highest sun near the June solstice is < 1e-5 rad off the meridian (the declination
moves < 1e-4 rad/day), and the noon search's 1e-3 s moves the azimuth by ~2e-7 rad; mirrored times an
hour either side share the same bound."""

MIRROR_ZENITH_ATOL: float = 1e-5
"""Radians: the zenith an hour before and after the highest sun differs only by the declination's
drift over those 2 h (< 1e-4 rad/day near the solstice: < 1e-5 rad)."""

SUNRISE_ZENITH_ATOL_DEG: float = 1e-3
"""The sunrise search stops within 0.01 s; the sun climbs at most 15 deg/h = 0.0042 deg/s, so the
apparent zenith is 90 deg within 4e-5 deg; the bound leaves room for the refraction's kink there."""

SUNRISE_AZIMUTH_ATOL_DEG: float = 0.27
"""The sun rises 0.575 / tan 50 = 0.48 deg North of East on the equinox day at 40 N; its declination,
|delta| < 0.2 deg that day, moves the rising point by < 0.2 / cos 40 = 0.26 deg."""

HORIZON_DEPRESSION_ATOL_DEG: float = 0.01
"""Geometric zenith at apparent sunrise, 90.575 deg: NOAA's horizon refraction at h = -0.575 deg is
2069.7" = 0.5749 deg, so 90.575 holds to 1e-4 deg; 0.01 deg leaves room for the search's instant."""

REFRACTION_FORMULA_RTOL: float = 1e-9
"""NOAA's three-term refraction typed here vs skysh.lighting.sun's, from the same geometric elevation: the same
terms in degrees and radians, rounding only (relative to 69.4")."""

ANGLE_ATOL: float = 1e-15
"""compass_to_frame / frame_to_compass of one angle (the table's multiples of pi/4, one round trip of
a sun azimuth): pi/2 - a reduced into its range, one or two roundings of values <= 2 pi (ulp(2 pi) =
8.9e-16)."""

ROUND_TRIP_ATOL: float = 1e-12
"""frame_to_compass(compass_to_frame(a)) against a mod 2 pi, for |a| <= 4 pi: two subtractions and two
reductions, a few ulp of 4 pi (1.8e-15 each); compared through exp(1j x) to ignore whole turns."""


def _min_zenith_time(lat: float, lon: float, start: dt.datetime, end: dt.datetime) -> dt.datetime:
    """Time of the smallest geometric zenith in [start, end] (solar noon), by golden-section search."""

    def zenith(seconds: float) -> float:
        when = start + dt.timedelta(seconds=seconds)
        return float(sun.position_unchecked(lat, lon, when, refraction=False).sun_zenith)

    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = 0.0, (end - start).total_seconds()
    while b - a > SEARCH_TOL_S:
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        if zenith(c) < zenith(d):
            b = d
        else:
            a = c
    return start + dt.timedelta(seconds=(a + b) / 2.0)


def _first_time(predicate: Callable[[dt.datetime], bool], start: dt.datetime, end: dt.datetime) -> dt.datetime:
    """First instant (to 0.01 s) in [start, end] where a monotone ``predicate`` becomes true, by bisection."""
    a, b = 0.0, (end - start).total_seconds()
    assert not predicate(start) and predicate(end)
    while b - a > 0.01:
        m = (a + b) / 2.0
        if predicate(start + dt.timedelta(seconds=m)):
            b = m
        else:
            a = m
    return start + dt.timedelta(seconds=b)


class TestEphemeris:
    """The place-independent series (NOAA columns G..V) against Meeus's worked examples."""

    # Meeus (1998), example 25.a: 1992 October 13.0 TD = JDE 2448908.5. NOAA takes its
    # input time as TD (no Delta T), so 1992-10-13T00:00Z is exactly that instant.
    WHEN = "1992-10-13T00:00:00Z"

    def test_julian_century(self) -> None:
        # Meeus example 25.a: T = -0.072183436.
        assert sun.ephemeris(self.WHEN).julian_century == pytest.approx(-0.072183436, abs=MEEUS_T_ATOL)

    def test_meeus_25a(self) -> None:
        e = sun.ephemeris(self.WHEN)
        # Meeus example 25.a: apparent longitude lambda = 199.90895 deg.
        assert math.degrees(e.apparent_longitude) == pytest.approx(199.90895, abs=SERIES_TOL_DEG)
        # Meeus example 25.a: corrected obliquity eps = 23.43999 deg.
        assert math.degrees(e.obliquity) == pytest.approx(23.43999, abs=SERIES_TOL_DEG)
        # Meeus example 25.a: apparent right ascension alpha = -161.61918 deg (198.38082 deg, 13h13m31.4s).
        assert math.degrees(e.right_ascension) == pytest.approx(-161.61918, abs=SERIES_TOL_DEG)
        # Meeus example 25.a: apparent declination delta = -7.78507 deg (-7 deg 47' 06").
        assert math.degrees(e.declination) == pytest.approx(-7.78507, abs=SERIES_TOL_DEG)

    def test_equation_of_time_meeus_28b(self) -> None:
        e = sun.ephemeris(self.WHEN)
        # Meeus example 28.b (eq. 28.3, same date): E = +0.059825 rad = 13m 42.7s.
        assert e.equation_of_time == pytest.approx(0.059825, abs=EOT_TOL_RAD)
        minutes = e.equation_of_time * 720.0 / math.pi
        assert minutes == pytest.approx(13.0 + 42.7 / 60.0, abs=EOT_PRINTED_S / 60.0 + EOT_TOL_RAD * 720.0 / math.pi)

    def test_spa_example_declination(self) -> None:
        # Reda & Andreas, NREL/TP-560-34302, A.5: 2003-10-17 12:30:30 at UTC-7 gives the
        # geocentric declination -9.31434 deg and right ascension 202.22741 deg.
        e = sun.ephemeris(dt.datetime(2003, 10, 17, 12, 30, 30, tzinfo=dt.timezone(dt.timedelta(hours=-7))))
        assert math.degrees(e.declination) == pytest.approx(-9.31434, abs=LOW_ACCURACY_TOL_DEG)
        assert math.degrees(e.right_ascension) % 360.0 == pytest.approx(202.22741, abs=LOW_ACCURACY_TOL_DEG)


class TestPosition:
    """Zenith and azimuth at a place and time."""

    # Reda & Andreas, NREL/TP-560-34302, appendix A.5 example (and spa_tester.c's output).
    SPA_LAT, SPA_LON = 39.742476, -105.1786
    SPA_WHEN = dt.datetime(2003, 10, 17, 12, 30, 30, tzinfo=dt.timezone(dt.timedelta(hours=-7)))
    SPA_ZENITH_DEG = 50.11162  # topocentric zenith, refraction for 820 hPa, 11 C
    SPA_AZIMUTH_DEG = 194.34024  # topocentric azimuth, eastward from North

    def test_spa_example(self) -> None:
        zenith, azimuth = sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN)
        assert math.degrees(zenith) == pytest.approx(self.SPA_ZENITH_DEG, abs=SPA_TOL_DEG)
        assert math.degrees(sun.frame_to_compass(azimuth)) == pytest.approx(self.SPA_AZIMUTH_DEG, abs=SPA_TOL_DEG)
        # The same azimuth in the frame: 194.34 deg compass is 14.34 deg West of South.
        assert math.degrees(azimuth) == pytest.approx(90.0 - self.SPA_AZIMUTH_DEG, abs=SPA_TOL_DEG)

    def test_equator_equinox_noon(self) -> None:
        # USNO: March equinox 2024-03-20 03:06 UTC. At (0, 0) solar noon is about 9 h later,
        # when the declination is delta = asin(sin eps sin(d lambda)), d lambda at the mean
        # rate 0.9856 deg/day (the true rate in March is 1% faster: 0.0015 deg in delta).
        equinox = dt.datetime(2024, 3, 20, 3, 6, tzinfo=UTC)
        day = dt.datetime(2024, 3, 20, tzinfo=UTC)
        noon = _min_zenith_time(0.0, 0.0, day + dt.timedelta(hours=11), day + dt.timedelta(hours=13))
        days = (noon - equinox).total_seconds() / 86400.0
        obliquity = 23.4361  # 2024, IAU 2006 formula (see test_solstice_noon_elevation_40n)
        expected = math.degrees(math.asin(math.sin(math.radians(obliquity)) * math.sin(math.radians(0.9856 * days))))
        zenith = math.degrees(sun.position(0.0, 0.0, noon, refraction=False).sun_zenith)
        assert zenith == pytest.approx(expected, abs=LOW_ACCURACY_TOL_DEG)
        assert zenith < 0.2  # elevation ~ 90 deg: the sun overhead at the equator on an equinox

    def test_solstice_noon_elevation_40n(self) -> None:
        # USNO: June solstice 2024-06-20 20:51 UTC; the declination is then the obliquity
        # (IAU 2006: eps_A = 84381.406" - 46.836769" T; nutation adds at most 9.2" = 0.0026 deg).
        # Noon at 105 W falls ~2 h before the solstice: the declination is short by < 1e-5 deg.
        t = (dt.datetime(2024, 6, 20, 20, 51, tzinfo=UTC) - sun.J2000).total_seconds() / 86400.0 / 36525.0
        obliquity = (84381.406 - 46.836769 * t) / 3600.0
        day = dt.datetime(2024, 6, 20, tzinfo=UTC)
        noon = _min_zenith_time(40.0, -105.0, day + dt.timedelta(hours=18), day + dt.timedelta(hours=20))
        zenith, _azimuth = sun.position(40.0, -105.0, noon, refraction=False)
        assert 90.0 - math.degrees(zenith) == pytest.approx(90.0 - 40.0 + obliquity, abs=LOW_ACCURACY_TOL_DEG)
        # Refraction at 73.4 deg elevation: NOAA's 58.1"/tan(h) - ... = 17.4" = 0.0048 deg.
        refracted = sun.position(40.0, -105.0, noon).sun_zenith
        assert math.degrees(zenith - refracted) == pytest.approx(0.0048, abs=REFRACTION_ATOL_DEG)

    @pytest.mark.parametrize(("lat", "lon", "expected"), [(40.0, -105.0, -math.pi / 2), (-33.87, 151.21, math.pi / 2)])
    def test_noon_due_south_or_north(self, lat: float, lon: float, expected: float) -> None:
        # At local solar noon the sun is due South (-Y) in the northern mid-latitudes and
        # due North (+Y) in the southern ones (Sydney), by symmetry of the meridian. Noon is
        # found as the highest sun, which is the meridian transit only while the declination
        # stands still: near the June solstice (USNO: 2024-06-20 20:51 UTC) it moves < 1e-4
        # rad/day, which puts the highest sun < 1e-5 rad off the meridian. (In October it
        # falls 0.39 deg/day and the highest sun comes 13 s after transit, 0.08 deg West.)
        day = dt.datetime(2024, 6, 20, tzinfo=UTC)
        utc_noon = day + dt.timedelta(hours=12.0 - lon / 15.0)
        noon = _min_zenith_time(lat, lon, utc_noon - dt.timedelta(hours=1), utc_noon + dt.timedelta(hours=1))
        _, azimuth = sun.position(lat, lon, noon)
        assert float(azimuth) == pytest.approx(expected, abs=NOON_AZIMUTH_ATOL)
        # Symmetric times around noon mirror the azimuth about the meridian and keep the zenith.
        morning = sun.position(lat, lon, noon - dt.timedelta(hours=1))
        afternoon = sun.position(lat, lon, noon + dt.timedelta(hours=1))
        assert float(morning.sun_azimuth - expected) == pytest.approx(-(afternoon.sun_azimuth - expected), abs=NOON_AZIMUTH_ATOL)
        assert float(morning.sun_zenith) == pytest.approx(float(afternoon.sun_zenith), abs=MIRROR_ZENITH_ATOL)
        if lat > 0:  # morning: South-East, between +X (0) and -Y (-pi/2); afternoon South-West
            assert -math.pi / 2 < morning.sun_azimuth < 0.0
            assert afternoon.sun_azimuth < -math.pi / 2
        else:  # morning: North-East, between +X (0) and +Y (pi/2); afternoon North-West
            assert 0.0 < morning.sun_azimuth < math.pi / 2
            assert afternoon.sun_azimuth > math.pi / 2

    def test_sunrise_equinox_is_east(self) -> None:
        # On an equinox (delta ~ 0) the sun rises due East: frame azimuth 0 (+X). The apparent
        # sun clears the horizon while still 0.575 deg under it geometrically (NOAA's horizon
        # refraction); below the horizon its path, the celestial equator, runs on towards the
        # North at 90 - 40 = 50 deg to the horizon, so the sun is 0.575 / tan 50 = 0.48 deg
        # North of East (positive frame azimuth). |delta| < 0.2 deg that day adds < 0.27 deg.
        lat, lon = 40.0, 0.0
        day = dt.datetime(2024, 3, 20, tzinfo=UTC)

        def risen(when: dt.datetime) -> bool:
            return bool(sun.position_unchecked(lat, lon, when).sun_zenith <= sun.HORIZON_ZENITH)

        sunrise = _first_time(risen, day + dt.timedelta(hours=5), day + dt.timedelta(hours=7))
        zenith, azimuth = sun.position(lat, lon, sunrise)
        assert math.degrees(zenith) == pytest.approx(90.0, abs=SUNRISE_ZENITH_ATOL_DEG)
        shift = 0.575 / math.tan(math.radians(50.0))
        assert math.degrees(azimuth) == pytest.approx(shift, abs=SUNRISE_AZIMUTH_ATOL_DEG)
        # Geometrically the sun is then 0.575 deg below the horizon.
        geometric = sun.position_unchecked(lat, lon, sunrise, refraction=False)
        assert math.degrees(geometric.sun_zenith) == pytest.approx(90.575, abs=HORIZON_DEPRESSION_ATOL_DEG)
        # An hour later it is higher and further round towards the South (-Y).
        later = sun.position(lat, lon, sunrise + dt.timedelta(hours=1))
        assert later.sun_zenith < zenith and later.sun_azimuth < 0.0

    def test_same_instant_any_offset(self) -> None:
        a = sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN)
        b = sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN.astimezone(UTC))
        c = sun.position(self.SPA_LAT, self.SPA_LON, "2003-10-17T19:30:30Z")
        d = sun.position(self.SPA_LAT, self.SPA_LON, "2003-10-17T21:30:30+02:00")
        for other in (b, c, d):
            assert other == a

    def test_refraction_parameter(self) -> None:
        apparent = sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN)
        geometric = sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN, refraction=False)
        # NOAA: 58.1"/tan h - 0.07"/tan^3 h + 0.000086"/tan^5 h at h = 39.87 deg = 69.4" = 0.0193 deg.
        h = math.radians(90.0 - math.degrees(geometric.sun_zenith))
        expected = (58.1 / math.tan(h) - 0.07 / math.tan(h) ** 3 + 0.000086 / math.tan(h) ** 5) / 3600.0
        assert math.degrees(geometric.sun_zenith - apparent.sun_zenith) == pytest.approx(expected, rel=REFRACTION_FORMULA_RTOL)
        assert apparent.sun_azimuth == geometric.sun_azimuth
        with pytest.raises(TypeError, match="refraction"):
            sun.position(self.SPA_LAT, self.SPA_LON, self.SPA_WHEN, refraction="yes")  # type: ignore[arg-type]

    def test_n_dimensional(self) -> None:
        lat = np.array([[10.0, 20.0, 30.0], [40.0, 50.0, 60.0]])
        lon = np.array([-10.0, 0.0, 10.0])
        when = "2024-06-21T12:00:00Z"
        zenith, azimuth = sun.position(lat, lon, when)
        assert zenith.shape == azimuth.shape == (2, 3)
        for i, j in np.ndindex(2, 3):
            z, a = sun.position(float(lat[i, j]), float(lon[j]), when)
            assert zenith[i, j] == z and azimuth[i, j] == a
        assert isinstance(sun.position(10.0, 0.0, when).sun_zenith, float)  # scalars stay scalars

    def test_below_horizon_refused(self) -> None:
        midnight = "2024-03-20T00:00:00-07:00"
        with pytest.raises(ValueError, match=r"below the horizon"):
            sun.position(40.0, -105.0, midnight)
        # position_unchecked reports the sun under the horizon instead.
        zenith, _ = sun.position_unchecked(40.0, -105.0, midnight)
        assert zenith > math.pi / 2
        # One place of a batch in the night is enough to refuse, and it is named.
        with pytest.raises(ValueError, match="longitude 75 deg"):
            sun.position([40.0, 40.0], [-105.0, 75.0], "2024-03-20T12:00:00-07:00")

    @pytest.mark.parametrize(
        "when",
        [
            dt.datetime(2024, 6, 21, 12, 0),  # naive
            "2024-06-21T12:00:00",  # no offset
            "21/06/2024 12:00",  # not ISO-8601
            dt.date(2024, 6, 21),  # a date, not a date-time
            1718971200,  # a POSIX time
        ],
    )
    def test_bad_time_refused(self, when: object) -> None:
        with pytest.raises(ValueError, match="when must"):
            sun.position(40.0, -105.0, when)  # type: ignore[arg-type]

    def test_naive_message_says_how(self) -> None:
        with pytest.raises(ValueError, match=r"tzinfo.*datetime\.timezone\.utc"):
            sun.position(40.0, -105.0, dt.datetime(2024, 6, 21, 12, 0))

    @pytest.mark.parametrize(
        ("lat", "lon", "name"),
        [
            (90.5, 0.0, "latitude"),
            (-91.0, 0.0, "latitude"),
            (0.0, 180.5, "longitude"),
            (0.0, -181.0, "longitude"),
            (math.nan, 0.0, "latitude"),
            (0.0, math.inf, "longitude"),
            ([0.0, math.nan], 0.0, "latitude"),
        ],
    )
    def test_bad_place_refused(self, lat: object, lon: object, name: str) -> None:
        with pytest.raises(ValueError, match=name):
            sun.position_unchecked(lat, lon, "2024-06-21T12:00:00Z")  # type: ignore[arg-type]

    def test_poles_and_date_line_accepted(self) -> None:
        # The closed ranges' ends are valid places; at a pole the azimuth is still defined.
        for lat, lon in [(90.0, 0.0), (-90.0, 180.0), (0.0, -180.0)]:
            zenith, azimuth = sun.position_unchecked(lat, lon, "2024-06-21T12:00:00Z")
            assert np.isfinite(zenith) and -math.pi < azimuth <= math.pi
        # North Pole at midsummer: elevation = declination (23.44 deg, + refraction 0.04 deg).
        zenith, _ = sun.position(90.0, 0.0, "2024-06-21T12:00:00Z", refraction=False)
        assert 90.0 - math.degrees(zenith) == pytest.approx(23.44, abs=LOW_ACCURACY_TOL_DEG)


class TestAzimuthConversion:
    """compass_to_frame / frame_to_compass with +X = East, +Y = North."""

    # (compass azimuth clockwise from North, frame azimuth from +X towards +Y), radians.
    TABLE: ClassVar[list[tuple[float, float]]] = [
        (0.0, math.pi / 2),  # North = +Y
        (math.pi / 2, 0.0),  # East = +X
        (math.pi, -math.pi / 2),  # South = -Y
        (3 * math.pi / 2, math.pi),  # West = -X
        (math.pi / 4, math.pi / 4),  # North-East
        (5 * math.pi / 4, -3 * math.pi / 4),  # South-West
    ]

    def test_table(self) -> None:
        for compass, frame in self.TABLE:
            assert float(sun.compass_to_frame(compass)) == pytest.approx(frame, abs=ANGLE_ATOL)
            assert float(sun.frame_to_compass(frame)) == pytest.approx(compass, abs=ANGLE_ATOL)

    def test_ranges_and_round_trip(self) -> None:
        angles = np.linspace(-4 * math.pi, 4 * math.pi, 1001).reshape(7, 11, 13)
        frame = sun.compass_to_frame(angles)
        compass = sun.frame_to_compass(angles)
        assert frame.shape == compass.shape == angles.shape
        assert np.all((frame > -math.pi) & (frame <= math.pi))
        assert np.all((compass >= 0.0) & (compass < 2 * math.pi))
        back = sun.frame_to_compass(sun.compass_to_frame(angles))
        assert np.allclose(np.angle(np.exp(1j * (back - angles))), 0.0, rtol=0, atol=ROUND_TRIP_ATOL)
        assert float(sun.compass_to_frame(-math.pi / 2)) == math.pi  # West: +pi, never -pi

    def test_matches_position(self) -> None:
        # The frame azimuth is atan2(North, East) of the sun direction.
        _zenith, azimuth = sun.position(40.0, -105.0, "2024-06-21T09:00:00-06:00")
        compass = sun.frame_to_compass(azimuth)
        assert 0.0 < compass < math.pi  # a summer morning: the sun is in the East
        assert float(sun.compass_to_frame(compass)) == pytest.approx(float(azimuth), abs=ANGLE_ATOL)

    @pytest.mark.parametrize("bad", [math.nan, math.inf, "north"])
    def test_non_finite_refused(self, bad: object) -> None:
        with pytest.raises(ValueError, match="azimuth"):
            sun.compass_to_frame(bad)  # type: ignore[arg-type]
        with pytest.raises(ValueError, match="azimuth"):
            sun.frame_to_compass(bad)  # type: ignore[arg-type]
