"""
Input hygiene of every public function and CLI command, from two tables
=======================================================================

One table of *kinds of parameter* (a number in a range, a count, a flag, unit
directions, SH coefficients, a name from a list, a date-time, a seed, ...), each
with the bad values of its kind (a bool where a number is expected, NaN, inf, an
integer beyond float64, text, None, complex, an object, a ragged list, the wrong
shape, an empty array where empty is meaningless, a broadcast view too large for
memory, a flag given as "False", nan or 0, a negative or zero count, ...); one
table of *public functions* with their valid arguments and the kind of each
parameter. Every (function, parameter, bad value) triple becomes a test that
asserts the exception type (ValueError; TypeError for a flag that is not a bool)
and that the message names the parameter as the user spelled it. A new function
gets the whole table by adding one row to :data:`ROWS`; a new command line flag
by adding one row to :data:`CLI_ROWS` (the message must then name the flag,
never an internal name, and no traceback may escape).

Cases of modules owned elsewhere that fail today are marked
``xfail(strict=True)`` in :data:`KNOWN_FAILURES` with the owner in the reason, so
a fix shows up as an unexpected pass that removes the mark.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import math
import re
import resource
import signal
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest

from skysh import domain
from skysh.app import cli, render
from skysh.checks import MAX_ARRAY_ELEMENTS
from skysh.lighting import sun
from skysh.model import preetham
from skysh.post import hazel
from skysh.runtime import SkySH, gibbs_factors
from skysh.sh import basis as sh
from skysh.table import poly

BIG: int = MAX_ARRAY_ELEMENTS + 1
"""A length just past the documented maximum: a zero-stride view of it costs nothing to build."""

FAR: int = 10**12
"""A count far too large for memory (the issue's hang of zonal_half_layout)."""

MEMORY_HEADROOM: int = 4 << 30
"""Address space a refused call may add to the test process (RLIMIT_AS raised by this much over
what the process maps already): a refusal needs a few kilobytes, so a call that would allocate
gigabytes gets a MemoryError (the test fails) instead of exhausting the machine shared with others."""

HANG_SECONDS: int = 20
"""A refused call still running after this long is interrupted (SIGALRM) and fails the test: a
guard against hangs such as the issue's zonal_half_layout(10**12), not a timing assertion: a
refusal does no work, so any limit far above an import of colour-science serves."""


class Hang(Exception):
    """Raised by the SIGALRM guard inside a call that did not return within HANG_SECONDS."""


@contextlib.contextmanager
def guarded() -> Any:
    """Cap the address space and interrupt hangs while one call runs (POSIX)."""
    with open("/proc/self/statm") as statm:
        mapped = int(statm.read().split()[0]) * resource.getpagesize()
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = mapped + MEMORY_HEADROOM
    resource.setrlimit(resource.RLIMIT_AS, (cap if hard == resource.RLIM_INFINITY else min(cap, hard), hard))

    def interrupt(signum: int, frame: Any) -> None:
        raise Hang(f"still running after {HANG_SECONDS} s")

    previous = signal.signal(signal.SIGALRM, interrupt)
    signal.alarm(HANG_SECONDS)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


# --------------------------------------------------------------------------- #
# Kinds of parameter and their bad values
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class Kind:
    """A kind of parameter; :meth:`bad` lists (id, value, exception type) triples."""

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        raise NotImplementedError


_NOT_NUMBERS: tuple[tuple[str, Any], ...] = (
    ("bool", True), ("numpy-bool", np.True_), ("text", "1.0"), ("none", None), ("complex", 1 + 1j),
    ("object", object()), ("huge-int", 10**400), ("huger-int", 10**5000), ("bytes", b"1"),
)
"""Values that are not one real float64. ``huger-int`` has more than the 4300 digits Python turns into text, so a
message that formats it (``f"{value}"``, ``repr``) raises its own ValueError instead of naming the parameter."""


@dataclass(frozen=True)
class Number(Kind):
    """A finite real number in [low, high]; ``array``: arrays of them are accepted too."""

    low: float = -math.inf
    high: float = math.inf
    array: bool = True

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [(k, v, ValueError) for k, v in _NOT_NUMBERS]
        out += [("nan", math.nan, ValueError), ("inf", math.inf, ValueError), ("-inf", -math.inf, ValueError)]
        if math.isfinite(self.low):
            out.append(("below", math.nextafter(self.low, -math.inf) if self.low else -1e-300, ValueError))
        if math.isfinite(self.high):
            out.append(("above", math.nextafter(self.high, math.inf), ValueError))
        if self.array:
            v = float(np.ravel(valid)[0])
            out += [
                ("nan-in-array", np.array([v, math.nan]), ValueError),
                ("ragged", [[v], [v, v]], ValueError),
                ("text-array", ["1", "2"], ValueError),
                ("broadcast-too-large", np.broadcast_to(np.float64(v), (BIG,)), ValueError),
            ]
        else:
            out.append(("array", np.array([float(valid), float(valid)]), ValueError))
        return out


@dataclass(frozen=True)
class Count(Kind):
    """An integer (not a bool, not a float) in [low, high]; ``high`` None: only sizes beyond memory are tested.
    ``none_ok``: None is valid (a default chosen by the function)."""

    low: int = 1
    high: int | None = None
    none_ok: bool = False

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [(k, v, ValueError) for k, v in _NOT_NUMBERS if not (self.none_ok and v is None)]
        out += [
            ("float", float(valid), ValueError), ("fraction", valid + 0.5, ValueError), ("nan", math.nan, ValueError),
            ("inf", math.inf, ValueError), ("below", self.low - 1, ValueError), ("array", np.array([valid]), ValueError),
        ]
        if self.low > 0:
            out.append(("negative", -3, ValueError))
        if self.high is not None:
            out.append(("above", self.high + 1, ValueError))
        if self.high is None or self.high < FAR:
            out.append(("far-too-large", FAR, ValueError))
        return out


@dataclass(frozen=True)
class Flag(Kind):
    """``bool`` or ``numpy.bool_`` only (``none_ok``: None means "by intent")."""

    none_ok: bool = False

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [("text-False", "False"), ("text-True", "True"), ("nan", math.nan), ("zero", 0), ("one", 1),
               ("float-one", np.float64(1.0)), ("array", np.array([True])), ("object", object())]
        if not self.none_ok:
            out.append(("none", None))
        return [(k, v, TypeError) for k, v in out]


@dataclass(frozen=True)
class Dirs(Kind):
    """Unit vectors (..., 3); ``empty_ok``: a batch of zero directions is meaningful."""

    empty_ok: bool = True

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [
            ("bool-array", np.array([[True, False, False]])), ("nan", np.array([[0.0, 0.0, math.nan]])),
            ("inf", np.array([[0.0, 0.0, math.inf]])), ("two-components", np.array([[0.0, 1.0]])),
            ("four-components", np.array([[0.0, 0.0, 1.0, 0.0]])), ("scalar", 1.0), ("text", "up"),
            ("none", None), ("complex", np.array([[0.0, 0.0, 1.0 + 0j]])), ("object", object()),
            ("ragged", [[0.0, 0.0, 1.0], [0.0, 1.0]]), ("not-unit", np.array([[0.0, 0.0, 2.0]])),
            ("zero-vector", np.zeros((1, 3))),
            ("broadcast-too-large", np.broadcast_to(np.array([0.0, 0.0, 1.0]), (BIG // 3 + 1, 3))),
        ]
        if not self.empty_ok:
            out.append(("empty", np.empty((0, 3))))
        return [(k, v, ValueError) for k, v in out]


@dataclass(frozen=True)
class Coeffs(Kind):
    """SH coefficients (K,) / (K, C) / batched (..., K, C); an empty coefficient axis is meaningless."""

    batch: bool = True

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        v = np.asarray(valid, dtype=np.float64)
        nan = v.copy()
        nan.flat[0] = math.nan
        out = [
            ("nan", nan), ("inf", v * math.inf), ("wrong-count", np.ones((5,) + v.shape[1:])), ("scalar", 1.0),
            ("text", "coefficients"), ("none", None), ("complex", v + 0j), ("object", object()),
            ("ragged", [[1.0, 2.0, 3.0], [1.0]]), ("bool-array", v > 0), ("empty", np.empty((0,) + v.shape[1:])),
        ]
        if self.batch:
            out.append(("broadcast-too-large", np.broadcast_to(v, (BIG // v.size + 1,) + v.shape)))
        return [(k, value, ValueError) for k, value in out]


@dataclass(frozen=True)
class Choice(Kind):
    """One name of ``choices`` (a str); the message must list the valid ones. ``none_ok``: None is valid."""

    choices: tuple[str, ...] = ()
    none_ok: bool = False

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [("unknown", "bogus-name"), ("number", 3), ("list", [valid]), ("array", np.array([valid, valid]))]
        if not self.none_ok:
            out.append(("none", None))
        return [(k, v, ValueError) for k, v in out]


@dataclass(frozen=True)
class When(Kind):
    """A timezone-aware datetime or an ISO-8601 string with an offset, within Python's range in UTC."""

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [
            ("garbage", "yesterday"), ("naive-text", "2024-06-21T12:00:00"), ("naive", dt.datetime(2024, 6, 21, 12)),
            ("none", None), ("number", 3.0), ("empty-text", ""), ("bytes", b"2024-06-21T12:00:00Z"),
            ("before-year-1-in-utc", "0001-01-01T00:00:00+05:00"), ("after-9999-in-utc", "9999-12-31T23:59:59-14:00"),
        ]
        return [(k, v, ValueError) for k, v in out]


@dataclass(frozen=True)
class Seed(Kind):
    """None or an integer >= 0."""

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [("negative", -1), ("fraction", 2.5), ("text", "1"), ("bool", True), ("nan", math.nan), ("object", object())]
        return [(k, v, ValueError) for k, v in out]


@dataclass(frozen=True)
class PathKind(Kind):
    """A file to read: the message may name the file itself instead of the parameter."""

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        out = [("number", 3), ("object", object()), ("missing", "/nonexistent/skysh.npz"), ("directory", "/"),
               ("device", "/dev/null")]
        return [(k, v, ValueError) for k, v in out]


@dataclass(frozen=True)
class Values(Kind):
    """Any parameter given an explicit list of (id, bad value) pairs, all ValueError."""

    cases: tuple[tuple[str, Any], ...] = ()

    def bad(self, valid: Any) -> list[tuple[str, Any, type]]:
        return [(k, v, ValueError) for k, v in self.cases]


# --------------------------------------------------------------------------- #
# Public functions and their parameters
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class Row:
    """A public function: its valid keyword arguments and the kind of each parameter tested."""

    name: str
    target: Callable[[], Callable[..., Any]]  # resolved at test time (modules may be edited elsewhere)
    valid: dict[str, Any]
    kinds: dict[str, Kind]
    valid_factory: Callable[[], dict[str, Any]] | None = field(default=None, compare=False)

    def arguments(self) -> dict[str, Any]:
        return dict(self.valid_factory() if self.valid_factory else self.valid)


_SKY: list[SkySH] = []


def the_sky() -> SkySH:
    if not _SKY:
        _SKY.append(SkySH.load())
    return _SKY[0]


Z = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
C9 = np.vstack([np.array([[3.0, 3.0, 3.0]]), np.full((8, 3), 0.1)])  # a positive 3-band radiance
SUN = dict(sun_zenith=0.5, turbidity=3.0)
SUN_KINDS = dict(sun_zenith=Number(0.0, math.pi / 2), turbidity=Number(1.7, 10.0))
RUNTIME_KINDS = dict(sun_zenith=Number(0.0, math.pi / 2), turbidity=Number(2.5, 6.0), sun_azimuth=Number())
SCALAR_RUNTIME_KINDS = dict(sun_zenith=Number(0.0, math.pi / 2, array=False), turbidity=Number(2.5, 6.0, array=False),
                            sun_azimuth=Number(array=False))
WHEN = "2024-06-21T13:00:00+02:00"
TMP_FILE = "<a file in the module's out_dir>"
PAIR = Values((("one", (3,)), ("three", (1, 2, 3)), ("negative", (-1, 2)), ("fraction", (1.5, 2)), ("text", "ab"),
               ("none", None), ("number", 3), ("bool", (True, 1)), ("above", (1, 65)), ("far", (FAR, 1))))
COLOURSPACE = Choice(("sRGB", "ITU-R BT.2020", "ACEScg"))
RGB_TRIPLE = Values((("nan", np.array([[math.nan, 0.0, 0.0]])), ("two-channels", np.array([[1.0, 1.0]])),
                     ("text", "rgb"), ("none", None), ("bool-array", np.array([[True, True, True]])),
                     ("broadcast-too-large", np.broadcast_to(np.ones(3), (BIG // 3 + 1, 3)))))


ALBEDO_TRIPLE = Values((("huge-int", (10**400, 0.1, 0.1)), ("huger-int", [10**5000, 0, 0]), ("above", (0.2, 1.5, 0.1)),
                        ("negative", [-0.1, 0.2, 0.2]), ("two", (0.2, 0.2)), ("nan", (0.2, math.nan, 0.2)),
                        ("bool", (True, 0.2, 0.2)), ("text", ("0.2", "0.2", "0.2"))))
"""Bad RGB albedo triples (lists and tuples: the runtime screens three floats without numpy)."""


class BytesPathLike:
    """An os.PathLike whose ``__fspath__`` returns bytes: a file named by bytes, which skysh does not take."""

    def __fspath__(self) -> bytes:
        return b"data/preetham_sh.npz"


def _sky_row(name: str, method: str, valid: dict[str, Any], kinds: dict[str, Kind]) -> Row:
    return Row(name, lambda: getattr(the_sky(), method), valid, kinds)


ROWS: list[Row] = [
    # skysh.sh.basis
    Row("sh.n_coeffs", lambda: sh.n_coeffs, dict(bands=3), dict(bands=Count(1, 64))),
    Row("sh.index", lambda: sh.index, dict(l=2, m=1), dict(l=Count(0, 63), m=Count(-2, 2))),
    Row("sh.lm", lambda: sh.lm, dict(i=5), dict(i=Count(0, 64 * 64 - 1))),
    Row("sh.basis", lambda: sh.basis, dict(dirs=Z, bands=3), dict(dirs=Dirs(), bands=Count(1, 64))),
    Row("sh.evaluate", lambda: sh.evaluate, dict(coeffs=C9, dirs=Z), dict(coeffs=Coeffs(batch=False), dirs=Dirs())),
    Row("sh.project", lambda: sh.project,
        dict(f=lambda d: d[:, 2], bands=2, method="mc", n=64, seed=1, hemisphere=False),
        dict(f=Values((("number", 3), ("none", None))), bands=Count(1, 64), method=Choice(sh.PROJECTION_METHODS),
             n=Count(1, none_ok=True), seed=Seed(), hemisphere=Flag())),
    Row("sh.project(quadrature)", lambda: sh.project, dict(f=lambda d: d[:, 2], bands=2, n=64),
        dict(n=Count(1, 2 * sh.MAX_GAUSS_NODES**2, none_ok=True))),
    Row("sh.project(f's values)", lambda: sh.project, dict(f=lambda d: d[:, 2], bands=2),
        dict(f=Values((("nan", lambda d: d[:, 2] * math.nan), ("text", lambda d: ["x"] * len(d)),
                       ("wrong-shape", lambda d: d[:3, 2]), ("none", lambda d: None))))),
    Row("sh.gauss_legendre", lambda: sh.gauss_legendre, dict(n=4), dict(n=Count(1, sh.MAX_GAUSS_NODES))),
    Row("sh.quadrature_rule", lambda: sh.quadrature_rule, dict(n_theta=4, hemisphere=False),
        dict(n_theta=Count(1, sh.MAX_GAUSS_NODES), hemisphere=Flag())),
    Row("sh.rotate_z", lambda: sh.rotate_z, dict(coeffs=C9, angle=0.3), dict(coeffs=Coeffs(), angle=Number())),
    Row("sh.rotation_z_matrix", lambda: sh.rotation_z_matrix, dict(angle=0.3), dict(angle=Number(array=False))),
    Row("sh.rotate", lambda: sh.rotate, dict(coeffs=C9, R=sh.Y_UP_MATRIX),
        dict(coeffs=Coeffs(), R=Values((("nan", np.full((3, 3), math.nan)), ("not-a-rotation", 2 * np.eye(3)),
                                        ("reflection", -np.eye(3)), ("shape", np.eye(2)), ("text", "R"),
                                        ("none", None), ("bool", np.eye(3, dtype=bool)))))),
    Row("sh.convolve", lambda: sh.convolve, dict(coeffs=C9, per_band=[1.0, 0.5, 0.25]),
        dict(coeffs=Coeffs(), per_band=Values((("short", [1.0, 0.5]), ("nan", [1.0, math.nan, 1.0]), ("text", "abc"),
                                                ("none", None), ("matrix", np.ones((3, 3))), ("empty", []))))),
    Row("sh.cosine_lobe", lambda: sh.cosine_lobe, dict(bands=3), dict(bands=Count(1, 64))),
    Row("sh.irradiance", lambda: sh.irradiance, dict(coeffs=C9), dict(coeffs=Coeffs())),
    Row("sh.to_y_up", lambda: sh.to_y_up, dict(coeffs=C9), dict(coeffs=Coeffs())),
    Row("sh.from_y_up", lambda: sh.from_y_up, dict(coeffs=C9), dict(coeffs=Coeffs())),
    # skysh.table.poly
    Row("poly.scale", lambda: poly.scale, dict(sun_zenith=0.5, turbidity=3.0, log_turbidity=True),
        dict(sun_zenith=Number(), turbidity=Number(low=5e-324), log_turbidity=Flag())),
    Row("poly.chebyshev", lambda: poly.chebyshev, dict(x=0.3, degree=5), dict(x=Number(), degree=Count(0, domain.MAX_DEGREE))),
    Row("poly.n_terms", lambda: poly.n_terms, dict(degrees=(13, 7)), dict(degrees=PAIR)),
    Row("domain.term_index", lambda: domain.term_index, dict(i=2, j=3, degrees=(13, 7)),
        dict(i=Count(0, 13), j=Count(0, 7), degrees=PAIR)),
    Row("poly.design", lambda: poly.design, dict(sun_zenith=0.5, turbidity=3.0, degrees=(3, 2), log_turbidity=True),
        dict(sun_zenith=Number(), turbidity=Number(low=5e-324), degrees=PAIR, log_turbidity=Flag())),
    # skysh.model.preetham
    Row("preetham.perez_coefficients", lambda: preetham.perez_coefficients, dict(turbidity=3.0),
        dict(turbidity=Number(1.7, 10.0))),
    Row("preetham.perez", lambda: preetham.perez,
        dict(cos_theta=0.5, gamma=0.3, cos_gamma=math.cos(0.3), coefficients=preetham.perez_coefficients(3.0)[2]),
        dict(cos_theta=Number(-1.0, 1.0), gamma=Number(0.0, math.pi), cos_gamma=Number(-1.0, 1.0),
             coefficients=Values((("four", np.ones(4)), ("nan", np.full(5, math.nan)), ("text", "ABCDE"),
                                  ("none", None), ("scalar", 1.0), ("overflow", np.array([1.0, 1.0, 1.0, 3000.0, 1.0])))))),
    Row("preetham.zenith_luminance", lambda: preetham.zenith_luminance, SUN, SUN_KINDS),
    Row("preetham.zenith_chromaticity", lambda: preetham.zenith_chromaticity, SUN, SUN_KINDS),
    Row("preetham.luminance_scale", lambda: preetham.luminance_scale, SUN, SUN_KINDS),
    Row("preetham.xyY", lambda: preetham.xyY, dict(dirs=Z, sun_azimuth=0.2, **SUN),
        dict(dirs=Dirs(), sun_zenith=Number(0.0, math.pi / 2, array=False), turbidity=Number(1.7, 10.0, array=False),
             sun_azimuth=Number(array=False))),
    Row("preetham.luminance", lambda: preetham.luminance, dict(dirs=Z, sun_azimuth=0.2, **SUN),
        dict(dirs=Dirs(), sun_zenith=Number(0.0, math.pi / 2, array=False))),
    Row("preetham.radiance", lambda: preetham.radiance, dict(dirs=Z, sun_azimuth=0.2, colourspace="sRGB", **SUN),
        dict(dirs=Dirs(), turbidity=Number(1.7, 10.0, array=False), colourspace=COLOURSPACE)),
    Row("preetham.rgb_from_xyz_matrix", lambda: preetham.rgb_from_xyz_matrix, dict(colourspace="sRGB"),
        dict(colourspace=COLOURSPACE)),
    Row("preetham.sky_quadrature_rule", lambda: preetham.sky_quadrature_rule, dict(sun_zenith=0.5, n_theta=8),
        dict(sun_zenith=Number(0.0, math.pi / 2, array=False), n_theta=Count(1, preetham.MAX_THETA_NODES))),
    Row("preetham.sky_sh", lambda: preetham.sky_sh, dict(bands=2, sun_azimuth=0.3, n=64, **SUN),
        dict(sun_zenith=Number(0.0, math.pi / 2, array=False), turbidity=Number(1.7, 10.0, array=False),
             bands=Count(1, 64), sun_azimuth=Number(array=False), colourspace=COLOURSPACE,
             method=Choice(sh.PROJECTION_METHODS), n=Count(1, 4 * preetham.MAX_THETA_NODES**2, none_ok=True),
             seed=Seed())),
    Row("preetham.sky_minimum", lambda: preetham.sky_minimum, dict(SUN),
        dict(sun_zenith=Number(0.0, math.pi / 2, array=False), turbidity=Number(1.7, 10.0, array=False),
             colourspace=COLOURSPACE)),
    # skysh.lighting.sun
    Row("sun.position", lambda: sun.position, dict(latitude=48.2, longitude=16.4, when=WHEN, refraction=True),
        dict(latitude=Number(-90.0, 90.0), longitude=Number(-180.0, 180.0), when=When(), refraction=Flag())),
    Row("sun.position_unchecked", lambda: sun.position_unchecked, dict(latitude=48.2, longitude=16.4, when=WHEN),
        dict(latitude=Number(-90.0, 90.0), longitude=Number(-180.0, 180.0), when=When(), refraction=Flag())),
    Row("sun.ephemeris", lambda: sun.ephemeris, dict(when=WHEN), dict(when=When())),
    Row("sun.compass_to_frame", lambda: sun.compass_to_frame, dict(azimuth=1.0), dict(azimuth=Number())),
    Row("sun.frame_to_compass", lambda: sun.frame_to_compass, dict(azimuth=1.0), dict(azimuth=Number())),
    # skysh.post.hazel (library functions)
    Row("hazel.to_normalised", lambda: hazel.to_normalised, dict(coeffs=C9), dict(coeffs=Coeffs())),
    Row("hazel.from_normalised", lambda: hazel.from_normalised,
        dict(R0=np.ones(3), R1=np.zeros((3, 3)), R2=np.zeros((3, 3, 3))),
        dict(R0=Number(), R1=Values((("shape", np.zeros((3, 2))), ("nan", np.full((3, 3), math.nan)), ("text", "r1"))),
             R2=Values((("shape", np.zeros((3, 2, 2))), ("asymmetric", np.tile(np.triu(np.ones((3, 3)), 1), (3, 1, 1))),
                        ("nan", np.full((3, 3, 3), math.nan)), ("text", "r2"))))),
    Row("hazel.radiance", lambda: hazel.radiance, dict(coeffs=C9, dirs=Z), dict(coeffs=Coeffs(), dirs=Dirs())),
    Row("hazel.irradiance", lambda: hazel.irradiance, dict(coeffs=C9, normals=Z), dict(coeffs=Coeffs(), normals=Dirs())),
    Row("hazel.geomerics_parameters", lambda: hazel.geomerics_parameters, dict(coeffs=C9), dict(coeffs=Coeffs())),
    Row("hazel.irradiance_l1_nonlinear", lambda: hazel.irradiance_l1_nonlinear, dict(coeffs=C9, normals=Z),
        dict(coeffs=Coeffs(), normals=Dirs())),
    # skysh.app.render
    Row("render.latlong_dirs", lambda: render.latlong_dirs, dict(width=32), dict(width=Count(2, render.MAX_LATLONG_WIDTH))),
    Row("render.tone_map", lambda: render.tone_map, dict(rgb=np.ones((2, 3)), exposure=1.0),
        dict(rgb=RGB_TRIPLE, exposure=Number(5e-324, array=False))),
    Row("render.draw_text", lambda: render.draw_text,
        dict(image=np.zeros((10, 40, 3), np.uint8), text="HI", x=1, y=1, scale=1, colour=(255, 0, 0)),
        dict(image=Values((("float", np.zeros((10, 40, 3))), ("shape", np.zeros((10, 40), np.uint8)), ("none", None))),
             text=Values((("number", 3), ("none", None))), x=Count(-(1 << 30), 1 << 30), y=Count(-(1 << 30), 1 << 30),
             scale=Count(1, render.MAX_TEXT_SCALE),
             colour=Values((("short", (1, 2)), ("above", (256, 0, 0)), ("negative", (-1, 0, 0)), ("text", "red"))))),
    Row("render.render_image", lambda: render.render_image,
        dict(sky=None, sun_zenith=0.5, turbidity=3.0, sun_azimuth=0.2, bands=2, width=16, gibbs=True),
        dict(sky=Values((("object", object()), ("text", "sky"))), sun_zenith=Number(0.0, math.pi / 2, array=False),
             turbidity=Number(2.5, 6.0, array=False), sun_azimuth=Number(array=False), bands=Count(1, 7),
             width=Count(16, 4096), gibbs=Flag()),
        valid_factory=lambda: dict(sky=the_sky(), sun_zenith=0.5, turbidity=3.0, sun_azimuth=0.2, bands=2, width=16)),
    Row("render.write_png", lambda: render.write_png, dict(path=TMP_FILE, image=np.zeros((2, 2, 3), np.uint8)),
        dict(image=Values((("float", np.zeros((2, 2, 3))), ("above", np.full((2, 2, 3), 300)), ("shape", np.zeros((2, 2))),
                           ("empty", np.zeros((0, 2, 3), np.uint8)), ("none", None), ("text", "png"))),
             path=Values((("number", 3), ("none", None))))),
    # skysh.runtime
    Row("runtime.gibbs_factors", lambda: gibbs_factors, dict(bands=3), dict(bands=Count(1, 64))),
    _sky_row("SkySH.coefficients", "coefficients", dict(sun_azimuth=0.3, **dict(SUN)),
             dict(**RUNTIME_KINDS, bands=Count(1, 7), gibbs=Flag(none_ok=True), dering=Flag(none_ok=True),
                  irradiance=Flag(), colourspace=Choice(("sRGB",), none_ok=True), ground_albedo=Number(0.0, 1.0))),
    _sky_row("SkySH.coefficients(sun)", "coefficients", dict(sun_azimuth=0.3, sun=True, ground_albedo=0.2, **dict(SUN)),
             dict(ground_albedo=Number(0.0, 1.0))),
    _sky_row("SkySH.coefficients(batch)", "coefficients", dict(sun_zenith=np.array([0.5, 0.6]), turbidity=3.0,
                                                               ground_albedo=(0.2, 0.3, 0.1)),
             dict(ground_albedo=ALBEDO_TRIPLE)),
    Row("SkySH.load", lambda: SkySH.load, {}, dict(path=PathKind())),
    Row("SkySH.load(not text)", lambda: SkySH.load, {}, dict(path=Values((("bytes", b"x"), ("zero", 0),
                                                                              ("bytes-path-like", BytesPathLike()))))),
    _sky_row("SkySH.radiance", "radiance", dict(dirs=Z, sun_azimuth=0.3, **SUN),
             dict(dirs=Dirs(), **SCALAR_RUNTIME_KINDS, bands=Count(1, 7), gibbs=Flag(none_ok=True))),
    _sky_row("SkySH.irradiance_at", "irradiance_at", dict(normals=Z, sun_azimuth=0.3, **SUN),
             dict(normals=Dirs(), **SCALAR_RUNTIME_KINDS, bands=Count(1, 7), gibbs=Flag(none_ok=True),
                  dering=Flag(none_ok=True), colourspace=Choice(("sRGB",), none_ok=True))),
]


def _module(name: str) -> Any:
    import importlib

    return importlib.import_module(f"skysh.{name}")


def _other(module: str, function: str) -> Callable[[], Callable[..., Any]]:
    return lambda: getattr(_module(module), function)


OTHER_ROWS: list[Row] = [
    # skysh.post.dering
    Row("dering.sinc4_window", _other("post.dering", "sinc4_window"), dict(cutoff=5.6, bands=3),
        dict(cutoff=Values((("bool", True), ("nan", math.nan), ("zero", 0.0), ("negative", -1.0), ("text", "5"),
                            ("none", None), ("array", np.array([5.6, 5.6])), ("huge-int", 10**400),
                            ("huge-negative-int", -10**400), ("huger-int", 10**5000))), bands=Count(1))),
    Row("solar.sun_window_family", _other("model.solar", "sun_window_family"), dict(cutoff=5.6, attenuation=0.5, bands=3),
        dict(cutoff=Values((("bool", True), ("nan", math.nan), ("zero", 0.0), ("negative", -1.0), ("text", "5"),
                            ("none", None), ("huge-int", 10**400), ("huger-int", 10**5000))),
             attenuation=Values((("nan", math.nan), ("above", 1.5), ("text", "0.5"))), bands=Count(1))),
    Row("dering.delta_minimum", _other("post.dering", "delta_minimum"), dict(scales=[1.0, 0.9, 0.7], target="irradiance"),
        dict(scales=Values((("nan", [1.0, math.nan]), ("text", "abc"), ("none", None), ("empty", []),
                            ("matrix", np.ones((3, 3))), ("bool", [True, True]))),
             target=Choice(("irradiance", "radiance")))),
    Row("dering.linear_attenuation", _other("post.dering", "linear_attenuation"), dict(cutoff=5.6, bands=3),
        dict(cutoff=Values((("nan", math.nan), ("zero", 0.0), ("text", "5"), ("none", None), ("huge-int", 10**400))),
             bands=Count(1, 7),
             target=Choice(("irradiance", "radiance")))),
    Row("dering.window_table", _other("post.dering", "window_table"), dict(bands=3),
        dict(bands=Count(1, 7), target=Choice(("irradiance", "radiance")))),
    # skysh.sh.minimum
    Row("shmin.exact_min", _other("sh.minimum", "exact_min"), dict(coeffs=C9, return_dirs=False),
        dict(coeffs=Coeffs(), return_dirs=Flag())),
    Row("shmin.sphere_quadratic", _other("sh.minimum", "sphere_quadratic"), dict(coeffs=C9[:, 0]), dict(coeffs=Values((
        ("nan", np.full(9, math.nan)), ("wrong-count", np.ones(5)), ("scalar", 1.0), ("text", "c"), ("none", None),
        ("empty", np.empty(0)), ("bool-array", np.ones(9, bool)))))),
    Row("dering.dering", _other("post.dering", "dering"), dict(coeffs=C9),
        dict(coeffs=Coeffs(), target=Choice(("irradiance", "radiance")), method=Choice(("table", "exact", "sinc4")),
             return_failed=Flag())),
    Row("dering.directional_light_sh", _other("post.dering", "directional_light_sh"),
        dict(direction=[0.0, 0.0, 1.0], colour=[1.0, 1.0, 1.0], bands=3),
        dict(direction=Dirs(), colour=Number(), bands=Count(1, 3),  # the default window: 3 factors
             window=Values((("short", [1.0]), ("nan", [1.0, math.nan, 1.0]), ("text", "w"), ("empty", []),
                            ("matrix", np.ones((3, 3))))))),
    Row("dering.directional_light_sh(window of 64)", _other("post.dering", "directional_light_sh"),
        dict(direction=[0.0, 0.0, 1.0], colour=[1.0, 1.0, 1.0], bands=3, window=np.ones(64)),
        dict(bands=Count(1, 64))),
    # skysh.engines.presets
    Row("engines.engine_map", _other("engines.presets", "engine_map"), dict(engine="threejs", bands=3),
        dict(engine=Choice(("threejs", "filament", "unity")), bands=Count(1, 64))),
    Row("engines.convert", _other("engines.presets", "convert"), dict(coeffs=C9, engine="threejs"),
        dict(coeffs=Coeffs(), engine=Choice(("threejs", "filament", "unity")))),
    Row("engines.snippet", _other("engines.presets", "snippet"), dict(coeffs=C9, engine="threejs"),
        dict(coeffs=Coeffs(batch=False), engine=Choice(("threejs", "filament", "unity")))),
    Row("engines.sun_direction", _other("engines.presets", "sun_direction"),
        dict(sun_zenith=0.5, sun_azimuth=0.2, engine="unity"),
        dict(sun_zenith=Number(0.0, math.pi), sun_azimuth=Number(), engine=Choice(("threejs", "filament", "unity")))),
    # skysh.post.quantize
    Row("quantize.words_per_channel", _other("post.quantize", "words_per_channel"), dict(bits=8), dict(bits=Count(2, 32))),
    Row("quantize.bounds", _other("post.quantize", "bounds"), dict(bound="tight", irradiance=False),
        dict(bound=Choice(("tight", "prior")), irradiance=Flag())),
    Row("quantize.ratios", _other("post.quantize", "ratios"), dict(coeffs=C9),
        dict(coeffs=Coeffs(), bound=Choice(("tight", "prior")), irradiance=Flag())),
    Row("quantize.compress", _other("post.quantize", "compress"), dict(coeffs=C9),
        dict(coeffs=Coeffs(), bits=Count(2, 32), bound=Choice(("tight", "prior")), sqrt=Flag(), irradiance=Flag())),
    Row("quantize.decompress", _other("post.quantize", "decompress"), {},
        dict(dc=Number(), bits=Count(2, 32), bound=Choice(("tight", "prior")), sqrt=Flag(), irradiance=Flag(),
             words=Values((("negative", -np.ones((3, 2))), ("too-large", np.full((3, 2), 2**33)), ("text", "w"),
                           ("nan", np.full((3, 2), math.nan)), ("shape", np.zeros((3, 5), np.uint32)),
                           ("ragged", [[1, 2], [3], [4, 5]]), ("huge-int", [[10**400, 0]] * 3)))),
        valid_factory=lambda: dict(zip(("dc", "words"), _module("post.quantize").compress(C9)))),
    Row("quantize.table3_errors", _other("post.quantize", "table3_errors"), dict(coeffs=C9[None], bits=8, n_theta=4),
        dict(bits=Count(2, 32), n_theta=Count(3))),
    # skysh.export.tables, skysh.export.c_like
    Row("export_tables.export_tables", _other("export.tables", "export_tables"), dict(sky=None, bands=3),
        dict(sky=Values((("object", object()), ("none", None))), bands=Count(1, 7)),
        valid_factory=lambda: dict(sky=the_sky(), bands=3)),
    Row("literals.double_literal", _other("literals", "double_literal"), dict(value=0.1),
        dict(value=Number(array=False))),
    Row("literals.float32_literal", _other("literals", "float32_literal"), dict(value=0.1),
        dict(value=Values((("nan", math.nan), ("inf", math.inf), ("beyond-float32", 1e39), ("text", "0.1"),
                           ("none", None), ("bool", True))))),
    Row("export.export_source", _other("export.c_like", "export_source"), dict(sky=None, language="c", bands=3),
        dict(language=Choice(("c", "glsl", "hlsl", "json", "js")), bands=Count(1, 7, none_ok=True),
             real=Choice(("double", "float"))),
        valid_factory=lambda: dict(sky=the_sky(), language="c", bands=3)),
    # skysh.table.coefficient_file
    Row("coefficient_file.zonal_half_layout", _other("table.coefficient_file", "zonal_half_layout"), dict(bands=3),
        dict(bands=Count(1, 64))),
    Row("coefficient_file.read", _other("table.coefficient_file", "read"), {},
        dict(path=PathKind())),
    Row("coefficient_file.write", _other("table.coefficient_file", "write"), dict(path=TMP_FILE, sky_table=None),
        dict(sky_table=Values((("object", object()), ("none", None), ("text", "table"))),
             path=Values((("number", 3), ("none", None)))),
        valid_factory=lambda: dict(path=TMP_FILE, sky_table=the_sky().table)),
    # skysh.table.fit (offline)
    Row("fit.chebyshev_grid", _other("table.fit", "chebyshev_grid"), dict(grid=(8, 6)),
        dict(grid=Values(tuple(kind for kind in PAIR.cases if kind[0] != "above") + (("above", (1, 257)),)))),
    Row("fit.held_out_points", _other("table.fit", "held_out_points"), dict(count=4, seed=0, corners=True),
        dict(count=Count(0), seed=Seed(), corners=Flag())),
    Row("fit.edge_points", _other("table.fit", "edge_points"), dict(per_edge=2, seed=0), dict(per_edge=Count(0), seed=Seed())),
]
"""Public functions of modules other helpers own: included so their gaps are counted (see KNOWN_FAILURES)."""

DERING, SHMIN, ENGINES, QUANTIZE, EXPORT, COEFFICIENT_FILE, FIT = (
    f"owner of skysh/{name}.py" for name in ("dering", "shmin", "engines", "quantize", "export", "coefficient_file", "fit"))
_KNOWN: dict[str, tuple[str, str]] = {
}
"""Gaps of modules other helpers own, as measured on this table: ``"function-parameter"`` ->
(owner, "kind kind: what happens | kind: ..."), written by running the table (``accepted``: no
exception at all; ``not naming it``: the message does not name the parameter)."""

KNOWN_FAILURES: dict[str, tuple[str, dict[str, str]]] = {
    group: (owner, {kind: what for part in text.split(" | ") for what in [part.split(": ", 1)[1]]
                    for kind in part.split(": ", 1)[0].split()})
    for group, (owner, text) in _KNOWN.items()
}
"""``_KNOWN`` as {group: (owner, {kind: what})}. Such a group is marked ``xfail(strict=True,
raises=KnownFailure)``: an expected failure only while exactly these kinds fail; a new failure or a
fixed one fails the test, saying which, so the table is kept exact."""


NOT_RUN: str = "not run: "
"""Prefix of a KNOWN_FAILURES description whose case is not run (it hangs or exhausts memory)."""


class KnownFailure(Exception):
    """Raised by a group whose failures are exactly its KNOWN_FAILURES entry (an expected failure)."""


def _sample(kind: Kind, valid: Any) -> Any:
    """A valid value of ``kind`` for building its bad values, when the row does not give one."""
    if valid is not None:
        return valid
    if isinstance(kind, Count):
        return max(kind.low, min(3, kind.high if kind.high is not None else 3))
    if isinstance(kind, Number):
        return min(max(0.5, kind.low), kind.high)
    if isinstance(kind, Choice):
        return kind.choices[0] if kind.choices else "x"
    return None


def _groups(rows: list[Row]) -> list[Any]:
    """One test per (function, parameter) covering its every bad value (one per value would be slow)."""
    groups = []
    for row in rows:
        for param in row.kinds:
            group_id = f"{row.name}-{param}"
            marks = []
            if group_id in KNOWN_FAILURES:
                owner, kinds = KNOWN_FAILURES[group_id]
                reason = f"{owner}: " + "; ".join(f"{k}: {what}" for k, what in kinds.items())
                marks = [pytest.mark.xfail(strict=True, raises=KnownFailure, reason=reason)]
            groups.append(pytest.param(row, param, id=group_id, marks=marks))
    return groups


@pytest.fixture(scope="module")
def out_dir(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """One directory for the files the calls write."""
    return tmp_path_factory.mktemp("hygiene")


def names(name: str, message: str) -> bool:
    """Whether ``message`` names ``name`` as a word (``sun_zenith``, ``--time``, ``degrees[0]``)."""
    return re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", message) is not None


def _arguments(row: Row, out_dir: Any) -> dict[str, Any]:
    kwargs = row.arguments()
    suffix = ".npz" if row.name.startswith("coefficient_file") else ".png"
    return {key: (out_dir / f"out{suffix}" if value is TMP_FILE else value) for key, value in kwargs.items()}


def refusal_problem(row: Row, param: str, kind: Kind, value: Any, exc: type, out_dir: Any) -> str | None:
    """None if the call refuses ``value`` as it should (type, parameter named, one line); else what happened."""
    kwargs = _arguments(row, out_dir)
    kwargs[param] = value
    function = row.target()
    try:
        with guarded(), np.printoptions(legacy=False):  # a state independent of who imported colour-science first
            function(**kwargs)
    except exc as error:
        message = str(error)
        by_value = isinstance(kind, PathKind) and isinstance(value, str) and value in message
        if not (names(param, message) or by_value):
            return f"{type(error).__name__} not naming {param}: {' '.join(message.split())[:160]!r}"
        if "\n" in message.strip() or len(message) > 2000:
            return f"a message of several lines: {message[:160]!r}"
        if isinstance(kind, Choice) and isinstance(value, str) and value == "bogus-name":
            if not any(choice in message for choice in kind.choices):
                return f"the valid names are not listed: {message[:160]!r}"
        return None
    except Exception as error:
        return f"{type(error).__name__}: {' '.join(str(error).split())[:160]!r}"
    return "accepted (no exception)"


def check_group(row: Row, param: str, out_dir: Any) -> None:
    """Every bad value of ``param`` is refused by name; KNOWN_FAILURES entries must fail exactly as listed."""
    kind = row.kinds[param]
    known = KNOWN_FAILURES.get(f"{row.name}-{param}", ("", {}))[1]
    problems = {}
    for kind_id, value, exc in kind.bad(_sample(kind, row.valid.get(param))):
        if known.get(kind_id, "").startswith(NOT_RUN):  # a known hang or memory blow-up: too costly to repeat
            problems[kind_id] = known[kind_id]
            continue
        problem = refusal_problem(row, param, kind, value, exc, out_dir)
        if problem is not None:
            problems[kind_id] = problem
    new = {k: v for k, v in problems.items() if k not in known}
    fixed = sorted(set(known) - set(problems))
    assert not new, f"{row.name}({param}=...) mishandles: " + "; ".join(f"{k}: {v}" for k, v in new.items())
    assert not fixed, f"{row.name}({param}=...) now refuses {fixed}: remove them from KNOWN_FAILURES"
    if known:
        raise KnownFailure("; ".join(f"{k}: {v}" for k, v in problems.items()))


def _finite(result: Any) -> bool:
    if isinstance(result, dict):
        return all(_finite(v) for v in result.values())
    if isinstance(result, (tuple, list)):
        return all(_finite(v) for v in result)
    array = np.asarray(result) if not isinstance(result, (str, bytes)) else np.zeros(0)
    return array.dtype.kind not in "fc" or bool(np.all(np.isfinite(array)))


class TestLibrary:
    """skysh's own modules: every bad value of every parameter is refused, by name."""

    @pytest.mark.parametrize("row", [pytest.param(r, id=r.name) for r in ROWS])
    def test_valid_arguments_pass(self, row: Row, out_dir: Any) -> None:
        assert _finite(row.target()(**_arguments(row, out_dir)))

    @pytest.mark.parametrize(("row", "param"), _groups(ROWS))
    def test_bad_values_are_refused_by_name(self, row: Row, param: str, out_dir: Any) -> None:
        check_group(row, param, out_dir)


class TestOtherModules:
    """Modules other helpers own, counted by the same table (their gaps: KNOWN_FAILURES)."""

    @pytest.mark.parametrize("row", [pytest.param(r, id=r.name) for r in OTHER_ROWS])
    def test_valid_arguments_pass(self, row: Row, out_dir: Any) -> None:
        assert _finite(row.target()(**_arguments(row, out_dir)))

    @pytest.mark.parametrize(("row", "param"), _groups(OTHER_ROWS))
    def test_bad_values_are_refused_by_name(self, row: Row, param: str, out_dir: Any) -> None:
        check_group(row, param, out_dir)


# --------------------------------------------------------------------------- #
# Empty arrays: meaningful where documented, refused elsewhere
# --------------------------------------------------------------------------- #
EMPTY_RESULTS: list[tuple[str, Callable[[], Any], tuple[int, ...]]] = [
    ("sh.basis", lambda: sh.basis(np.empty((0, 3)), 3), (0, 9)),
    ("sh.evaluate", lambda: sh.evaluate(C9, np.empty((0, 3))), (0, 3)),
    ("sh.rotate_z", lambda: sh.rotate_z(C9, np.empty(0)), (0, 9, 3)),
    ("poly.chebyshev", lambda: poly.chebyshev(np.empty(0), 3), (0, 4)),
    ("preetham.xyY", lambda: preetham.xyY(np.empty((0, 3)), 0.5, 0.0, 3.0), (0, 3)),
    ("sun.compass_to_frame", lambda: sun.compass_to_frame(np.empty(0)), (0,)),
    ("hazel.irradiance", lambda: hazel.irradiance(C9, np.empty((0, 3))), (0, 3)),
    ("SkySH.coefficients", lambda: the_sky().coefficients(np.empty(0), 3.0), (0, 9, 3)),
    ("SkySH.irradiance_at", lambda: the_sky().irradiance_at(np.empty((0, 3)), 0.5, 3.0), (0, 3)),
]
"""Calls whose docstrings say an empty batch is meaningful: a batch of nothing gives nothing."""


@pytest.mark.parametrize(("name", "call", "shape"), EMPTY_RESULTS, ids=[e[0] for e in EMPTY_RESULTS])
def test_documented_empty_batches(name: str, call: Callable[[], Any], shape: tuple[int, ...]) -> None:
    assert np.shape(call()) == shape


# --------------------------------------------------------------------------- #
# The command line
# --------------------------------------------------------------------------- #
COEFFS = ["coeffs", "--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3"]
PLACE = ["coeffs", "--lat", "48.21", "--lon", "16.37", "--time", "2024-06-21T13:00:00+02:00", "--turbidity", "3"]
RENDER = ["render", "--sun-zenith", "30", "--turbidity", "3", "--width", "16", "--out", "OUT"]
NUMBER_TEXTS = ("abc", "nan", "inf", "-inf", "1e999", "", "0x1p3", "1,5")
TIMES = ("yesterday", "2024-06-21T12:00:00", "", "2024-13-01T00:00:00Z", "0001-01-01T00:00:00+05:00",
         "9999-12-31T23:59:59-14:00")


@dataclass(frozen=True)
class CliRow:
    """A command line, a flag of it, and bad texts for that flag (each must be refused naming the flag)."""

    base: tuple[str, ...]
    flag: str
    texts: tuple[str, ...]


CLI_ROWS: list[CliRow] = [
    CliRow(tuple(COEFFS), "--sun-zenith", NUMBER_TEXTS + ("-1", "90.0000001", "True")),
    CliRow(tuple(COEFFS), "--sun-azimuth", NUMBER_TEXTS),
    CliRow(tuple(COEFFS), "--turbidity", NUMBER_TEXTS + ("2.4", "6.0000001")),
    CliRow(tuple(COEFFS), "--bands", ("0", "-1", "2.5", "abc", "8", "99999999999999999999", "nan", "")),
    CliRow(tuple(COEFFS), "--format", ("bogus", "")),
    CliRow(tuple(COEFFS), "--up", ("x", "")),
    CliRow(tuple(COEFFS), "--colourspace", ("bogus", "", "srgb ")),
    CliRow(tuple(COEFFS), "--exposure", NUMBER_TEXTS + ("0", "-1", "1e308", "1e-320")),
    CliRow(tuple(COEFFS), "--engine", ("bogus", "")),
    CliRow(tuple(PLACE), "--lat", NUMBER_TEXTS + ("91", "-90.0000001")),
    CliRow(tuple(PLACE), "--lon", NUMBER_TEXTS + ("181", "-180.5")),
    CliRow(tuple(PLACE), "--time", TIMES),
    CliRow(tuple(RENDER), "--sun-zenith", NUMBER_TEXTS + ("-1", "90.0000001")),
    CliRow(tuple(RENDER), "--turbidity", NUMBER_TEXTS + ("7",)),
    CliRow(tuple(RENDER), "--bands", ("0", "8", "abc")),
    CliRow(tuple(RENDER), "--width", ("8", "5000", "abc", "2.5", "")),
    CliRow(tuple(RENDER), "--out", ("/nonexistent-dir/sky.png",)),
    CliRow(("export", "--format", "c", "--out", "-"), "--bands", ("0", "8", "abc")),
    CliRow(("export", "--out", "-"), "--format", ("bogus",)),
]


def _with(base: tuple[str, ...], flag: str, text: str, out_dir: Any) -> list[str]:
    """``base`` with ``flag`` set to ``text`` (as ``--flag=text``, so texts starting with '-' stay values)."""
    argv = [str(out_dir / "sky.png") if a == "OUT" else a for a in base]
    if flag in argv:
        i = argv.index(flag)
        del argv[i : i + 2]
    return argv + [f"{flag}={text}"]


def run_cli(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = cli.main(argv)  # an exception escaping here would be a traceback for the user
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def cli_problem(argv: list[str], flag: str, capsys: pytest.CaptureFixture) -> str | None:
    """None if the command refuses in one line naming ``flag`` with status 2; else what happened."""
    try:
        code, out, err = run_cli(argv, capsys)
    except BaseException as error:
        return f"{type(error).__name__} escaped (a traceback): {error}"
    lines = err.strip().splitlines()
    if code != 2 or out:
        return f"status {code}, stdout {out[:80]!r}, stderr {err[:160]!r}"
    if len(lines) != 1 or not lines[0].startswith("skysh: error: "):
        return f"not one 'skysh: error:' line: {err[:200]!r}"
    if not names(flag, lines[0]):
        return f"does not name {flag}: {lines[0][:200]!r}"
    if flag == "--colourspace" and not ("ACEScg" in err and "ITU-R BT.2020" in err):
        return "an unknown colourspace does not list the valid names"
    return None


@pytest.fixture(scope="module")
def loaded_once() -> Any:
    """SkySH.load returning one instance for the whole module (loading is tested in test_runtime.py)."""
    sky = the_sky()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(SkySH, "load", classmethod(lambda cls, path=None: sky))
        yield sky


class TestCommandLine:
    @pytest.mark.parametrize("row", [pytest.param(r, id=f"{r.base[0]} {r.flag}") for r in CLI_ROWS])
    def test_bad_texts_are_refused_naming_the_flag(self, row: CliRow, out_dir: Any, loaded_once: Any,
                                                   capsys: pytest.CaptureFixture) -> None:
        problems = {text: cli_problem(_with(row.base, row.flag, text, out_dir), row.flag, capsys) for text in row.texts}
        bad = {text: problem for text, problem in problems.items() if problem is not None}
        assert not bad, f"skysh {row.base[0]} {row.flag}: " + "; ".join(f"{t!r}: {p}" for t, p in bad.items())

    @pytest.mark.parametrize("argv", [["fit", "--bogus"], ["report", "--out", "never-written", "--bogus"]],
                             ids=["fit", "report"])
    def test_tools_refuse_an_unknown_option_in_one_line(self, argv: list[str], capsys: pytest.CaptureFixture) -> None:
        code, out, err = run_cli(argv, capsys)
        assert code == 2 and out == ""
        lines = err.strip().splitlines()
        assert len(lines) == 1 and re.match(r"skysh( \w+)?: error: ", lines[0]) and "--bogus" in lines[0], err
