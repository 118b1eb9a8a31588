"""
The ``skysh`` command line
==========================

-   :func:`main`: the console script ``skysh`` (and ``python -m skysh``).
-   :func:`build_parser`: its argparse parser.
-   :func:`format_coefficients`: the text of ``skysh coeffs`` in one format.
-   :func:`normalise_factor`: the factor of ``--normalise``.

Commands::

    skysh coeffs  --sun-zenith DEG --sun-azimuth DEG --turbidity T [options]   per-frame coefficients
    skysh coeffs  --lat DEG --lon DEG --time ISO8601 --turbidity T [options]   the same, sun from place and time
    skysh coeffs  ... --engine NAME [--format snippet]                          engine-ready numbers or code
    skysh coeffs  ... [--sun] [--ground-albedo A|R,G,B]                         with the sun's disk and the ground
    skysh coeffs  ... --sun-light [--engine NAME]                               the sun as a directional light
    skysh export  --format c|glsl|hlsl|json|js --out FILE [--bands N] [--engine NAME]   tables + evaluation code
    skysh coeffs|export|render ... --model hosek-wilkie [--albedo A|R,G,B]       the Hosek-Wilkie sky instead
    skysh view    [--out DIR] [--open] [--port N]                                the interactive viewer page
    skysh render  --sun-zenith DEG --sun-azimuth DEG --turbidity T --out FILE.png
    skysh fit     ...   skysh.app.fit_command (the tools extra brings cvxpy)
    skysh report  ...   tools/error_report.py (source checkout only)

Angles are **degrees** on the command line (the library takes radians).
Every refusal (a value out of range, a sun below the horizon, an unknown
colourspace, an unwritable file, a result that overflows) prints one line
``skysh: error: ...`` naming the flag on stderr and exits with status 2; no
traceback. Degrees given on the command line are echoed exactly as given (the
radians are computed from them). The ``table`` format prints values whose
magnitude is below :data:`TABLE_ZERO_BELOW` times the largest |DC| as 0 (they
are rounding noise, e.g. of ``--up y``'s rotation); every other format keeps
full precision.

Start-up: this module imports argparse only; each command imports what it
needs when it runs, so ``skysh coeffs`` in the default colourspace loads numpy
and the runtime, never colour-science or matplotlib
(``tests/test_startup.py``, ``benchmarks/bench_startup.py``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from skysh.app.argtypes import integer, real
from skysh.app.cli_output import (
    TABLE_ZERO_BELOW,
    format_coefficients,
    format_engine,
    format_sun_light,
    normalise_factor,
    number_text,
)

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np
    from numpy.typing import NDArray

__all__ = ["TABLE_ZERO_BELOW", "build_parser", "main"]

COEFF_FORMATS: tuple[str, ...] = ("table", "json", "csv", "glsl", "hlsl", "c", "snippet")
"""Output formats of ``skysh coeffs`` (``snippet``: code for the ``--engine``'s own API)."""

ENGINE_FORMATS: tuple[str, ...] = ("table", "json", "csv", "snippet")
"""The formats that go with ``--engine`` (the constant arrays are skysh's own layout)."""

MODELS: tuple[str, ...] = ("preetham", "hosek-wilkie")
"""``--model``: skysh.options.MODELS, repeated here so that building the parser imports nothing
(tests/test_code_health.py checks they agree)."""

TOOL_COMMANDS: dict[str, str] = {"fit": "skysh.app.fit_command", "report": "error_report.py"}
"""Commands run by another module's ``main(argv)``: a module of the package (``skysh fit``, which works
from an installed wheel), or a script of the source checkout's ``tools/`` folder (``skysh report``)."""

EXIT_USAGE: int = 2
"""Exit status of every refusal (argparse's own convention for bad usage)."""

EXIT_INTERNAL: int = 1
"""Exit status of an unexpected failure (a bug): one line naming it, no traceback."""

RENDER_WIDTH_RANGE: tuple[int, int] = (16, 4096)
"""Accepted ``skysh render --width``, pixels per panel (skysh.app.render.PANEL_WIDTH_RANGE, repeated here
so that building the parser imports nothing; tests/test_code_health.py checks they agree)."""

DEFAULT_RENDER_WIDTH: int = 448
"""Default ``skysh render --width`` (skysh.app.render.DEFAULT_PANEL_WIDTH, repeated here so that
building the parser imports nothing)."""

_SH_CONVENTION: str = "real orthonormal SH with the Condon-Shortley phase; row i = l(l+1)+m, l = 0..N-1"
_CONVENTION: str = "Z up (zenith), azimuth from +X towards +Y; " + _SH_CONVENTION
_CONVENTIONS: dict[str, str] = {"z": _CONVENTION, "y": "Y up (zenith +Y), right-handed as glTF: skysh's +X stays +X "
                                 "and its +Y becomes -Z (skysh.sh.basis.to_y_up); the SH are evaluated at this frame's "
                                 "(x, y, z); " + _SH_CONVENTION}
"""The frame and SH convention of the output, by ``--up``."""


class _UsageError(Exception):
    """A bad command line; :func:`main` prints it on one line and exits with status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block) that :func:`main` turns into status 2."""

    def error(self, message: str) -> NoReturn:
        raise _UsageError(f"{message} (see '{self.prog} --help')")


def _positive(text: str) -> float:
    value = real(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


_bands = integer(1)
"""``--bands``: a positive integer (the coefficient file's bands are checked once it is loaded)."""


def _albedo(text: str) -> float | tuple[float, ...]:
    """``--ground-albedo``: one number or R,G,B, each in [0, 1]."""
    values = tuple(real(part) for part in text.split(","))
    if len(values) not in (1, 3) or not all(0.0 <= v <= 1.0 for v in values):
        raise argparse.ArgumentTypeError(f"expected one number or R,G,B, each in [0, 1], got {text!r}")
    return values[0] if len(values) == 1 else values


_width = integer(*RENDER_WIDTH_RANGE)
"""``skysh render --width``."""

_port = integer(0, 65535)
"""``skysh view --port``: a TCP port (0: a free one)."""


# --------------------------------------------------------------------------- #
# Parser
# --------------------------------------------------------------------------- #
def _add_sun(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("the sun (either its angles, or a place and a time)", "Frame: +X = East, +Y = "
                                      "North, +Z = up; azimuth from +X towards +Y (East 0, North 90, South -90).")
    group.add_argument("--sun-zenith", type=real, metavar="DEG", help=f"sun zenith angle, degrees, {_sun_zenith_range()} (0 = "
                       "overhead, 90 = on the horizon)")
    group.add_argument("--sun-azimuth", type=real, metavar="DEG", help="sun azimuth, degrees, any finite value (default 0)")
    group.add_argument("--lat", type=real, metavar="DEG", help="latitude, degrees, [-90, 90], positive North (with --lon and "
                       "--time)")
    group.add_argument("--lon", type=real, metavar="DEG", help="longitude, degrees, [-180, 180], positive East")
    group.add_argument("--time", metavar="ISO8601", help="time with a UTC offset, e.g. 2024-06-21T12:00:00+02:00 or ...Z; the "
                       "sun must be above the horizon")
    parser.add_argument("--turbidity", type=real, required=True, metavar="T",
                        help=f"atmospheric turbidity, {_turbidity_range()} (the fitted domain; --model hosek-wilkie: "
                        f"{_turbidity_range('hosek-wilkie')})")


def _add_model(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--model", choices=MODELS, default="preetham", help="the sky: preetham (default; the fitted "
                        "table, turbidity [2.5, 6]) or hosek-wilkie (Hosek and Wilkie 2012, projected per frame from its "
                        "exact model; turbidity [1, 10], with --albedo)")
    parser.add_argument("--albedo", type=_albedo, default=None, metavar="A|R,G,B", help="hosek-wilkie only: the ground "
                        "albedo the sky's light sees (one number, or R,G,B for the sRGB dataset's channels), each in "
                        "[0, 1]; default 0")


def _add_lights(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--sun", action="store_true", help="add the sun's disk (Preetham 1999 appendix) as a windowed delta "
                        "(skysh.model.solar.sun_window; never Gibbs-filtered); for engines that light with SH alone")
    parser.add_argument("--ground-albedo", type=_albedo, default=0.0, metavar="A|R,G,B", help="a Lambertian ground of this "
                        "albedo (one number or R,G,B in the output colourspace, each in [0, 1]) below the horizon, lit by the "
                        "sky (and the sun with --sun); default 0, a black ground")


def _add_export_parser(commands: Any) -> None:
    """``skysh export``: the tables and evaluation functions (skysh.export.c_like), the sun and the ground included."""
    export = commands.add_parser(
        "export", help="polynomial tables and an evaluation function in C, GLSL, HLSL, JSON or JavaScript",
        description="Write the fitted polynomial tables and a self-contained function skysh_coefficients"
        "(sun_zenith_rad, turbidity, sun_azimuth_rad, gibbs, dering, irradiance, sun, ground_albedo, out) that "
        f"reproduces the runtime with its sun and ground (radians, turbidity {_turbidity_range()}; output cd/m^2, linear sRGB, "
        + _CONVENTION + "), and skysh_sun_light(sun_zenith_rad, turbidity, sun_azimuth_rad, direction, rgb), the sun "
        "as a directional light (lux); with --engine also skysh_engine_coefficients(...) returning that engine's "
        "numbers. C: a header with double tables (--c-real float for float); GLSL and HLSL: float32 tables and "
        "arithmetic; JSON: float64 tables and the algorithm in words; js: an ES module coefficients(sunZenith, "
        "turbidity, sunAzimuth, options) with options {bands, gibbs, irradiance, dering, sun, groundAlbedo, engine} "
        "and the Python defaults, and sunLight(sunZenith, turbidity, sunAzimuth).")
    export.add_argument("--format", choices=("c", "glsl", "hlsl", "json", "js"), required=True, help="language of the file: c (a "
                        "header, e.g. sky_sh.h: #include it, link with -lm), glsl, hlsl, json, or js (an ES module, the "
                        "per-frame runtime for browsers, with every engine as a per-call option; its TypeScript declarations "
                        "are written beside it: sky.d.mts for sky.mjs)")
    export.add_argument("--out", type=Path, required=True, metavar="FILE", help="file to write ('-' for standard output)")
    export.add_argument("--engine", metavar="NAME", default=None, help="c, glsl, hlsl: the generated function returns that "
                        "engine's numbers (docs/engines.md); js takes the engine as a per-call option instead")
    export.add_argument("--bands", type=_bands, default=None, metavar="N", help="SH bands N, [1, 7]; default 3 (js: all 7, "
                        "chosen per call); deringing needs 3")
    export.add_argument("--c-real", choices=("double", "float"), default="double", help="C only: floating type of the tables and "
                        "arithmetic (default double)")
    export.add_argument("--model", choices=MODELS, default="preetham", help="the sky: preetham (default) or hosek-wilkie "
                        "(--format c or js: the dataset and the per-frame projection, skysh.export.hosek)")
    export.set_defaults(handler=_cmd_export)


def _add_coeffs_parser(commands: Any) -> None:
    """``skysh coeffs``: the sky's SH coefficients for one frame, or the sun as a directional light."""
    coeffs = commands.add_parser(
        "coeffs", help="the sky's SH coefficients for one frame",
        description="The sky's SH coefficients for one sun position and turbidity: (N*N) rows x (R, G, B), "
        "radiance in cd/m^2 (with --irradiance: cd/m^2*sr, lux for the luminance), linear RGB of "
        "--colourspace. " + _CONVENTION + ".")
    _add_sun(coeffs)
    coeffs.add_argument("--bands", type=_bands, default=3, metavar="N", help="SH bands N, [1, 7] (the shipped file's); default 3 "
                        "(9 coefficients)")
    coeffs.add_argument("--irradiance", action="store_true", help="irradiance coefficients E (clamped-cosine convolution), "
                        "cd/m^2*sr (lux for the luminance)")
    coeffs.add_argument("--gibbs", action=argparse.BooleanOptionalAction, default=None, help="the zonal sinc Gibbs filter (Habel "
                        "eq. 5); default: on for radiance, off for irradiance and engine presets (it blurs diffuse light)")
    coeffs.add_argument("--dering", action=argparse.BooleanOptionalAction, default=None, help="window the coefficients so the "
                        "reconstructed irradiance is never negative (Sloan 2017); default: on for irradiance and engine "
                        "presets, off for radiance")
    coeffs.add_argument("--engine", metavar="NAME", default=None, help="engine-ready numbers for that engine's SH API (frame, "
                        "sign convention, pre-scaling; docs/engines.md): threejs, filament, filament-irradiance, unity, "
                        "unity-shader, babylon, unreal. Diffuse intent: the Gibbs filter off and deringing on by default")
    _add_model(coeffs)
    _add_lights(coeffs)
    coeffs.add_argument("--sun-light", action="store_true", help="print the sun as a directional light instead: the unit vector "
                        "towards it (in the --up or --engine frame) and its RGB illuminance at normal incidence, lux (times "
                        "--exposure, or the --normalise factor of the coefficients this command line would print); with "
                        "--engine also the engine's light colour and intensity (--format snippet: code setting the engine's "
                        "light; skysh.engines.sun); light the scene with it and SH without --sun")
    coeffs.add_argument("--up", choices=("z", "y"), default="z", help="frame of the output: z (default, skysh's Z up) or y "
                        "(right-handed Y up as glTF: zenith +Y, +X stays, +Y becomes -Z; skysh.sh.basis.to_y_up)")
    coeffs.add_argument("--format", choices=COEFF_FORMATS, default="table", help="table (default; labelled rows, units), json, "
                        "csv, a constant array for glsl, hlsl (float32) or c (double), or snippet (with --engine: paste-ready "
                        "code that builds the engine's object)")
    coeffs.add_argument("--colourspace", metavar="NAME", default=None, help="colour-science RGB colourspace name, e.g. 'ITU-R "
                        "BT.2020', 'ACEScg'; default linear sRGB (other names load colour-science, about 1.5 s)")
    units = coeffs.add_mutually_exclusive_group()
    units.add_argument("--exposure", type=_positive, metavar="X", help="multiply every coefficient by X > 0 (the units are "
                       "multiplied by X)")
    units.add_argument("--normalise", action="store_true", help="scale so that the irradiance DC coefficient E(0,0) = pi "
                       "L(0,0), averaged over R, G and B, is exactly 1 (then the mean irradiance over all normals, "
                       "E(0,0)/(2 sqrt(pi)), averages 0.2821); radiance output gets the same factor. Applied last, in the "
                       "output colourspace")
    coeffs.set_defaults(handler=_cmd_coeffs)


def _add_render_parser(commands: Any) -> None:
    """``skysh render``: a PNG of the sky, its SH reconstruction and the irradiance."""
    render = commands.add_parser(
        "render", help="PNG of the true sky, its SH reconstruction and the irradiance",
        description="Three latitude-longitude panels side by side: the Preetham sky, its SH reconstruction and "
        "the SH irradiance divided by pi (the radiance of a white Lambertian surface), all with one exposure "
        "(the sky's log-average maps to 0.18), Reinhard tone mapping and the sRGB transfer function. Columns: "
        "azimuth -180 (left) to 180 degrees (right); rows: elevation 90 (top, the zenith) to -90 degrees (bottom), "
        "horizon in the middle; both axes are labelled in degrees; a ring marks the sun. With --sun and "
        "--ground-albedo the scene gains the sun's disk and a Lambertian ground, in all three panels.")
    _add_sun(render)
    render.add_argument("--out", type=Path, required=True, metavar="FILE.png", help="PNG file to write")
    render.add_argument("--bands", type=_bands, default=3, metavar="N", help="SH bands N, [1, 7]; default 3")
    render.add_argument("--width", type=_width, default=DEFAULT_RENDER_WIDTH, metavar="W", help="width of each panel in pixels, "
                        f"[{RENDER_WIDTH_RANGE[0]}, {RENDER_WIDTH_RANGE[1]}]; default {DEFAULT_RENDER_WIDTH} (height W/2; "
                        "the three panels with their axes make an image about 1,660 pixels wide)")
    render.add_argument("--no-gibbs", action="store_true", help="skip the zonal sinc Gibbs filter")
    _add_model(render)
    _add_lights(render)
    render.set_defaults(handler=_cmd_render)


def _add_view_parser(commands: Any) -> None:
    """``skysh view``: the interactive viewer page, served on 127.0.0.1 or written to a folder."""
    view = commands.add_parser(
        "view", help="an interactive page in the browser: the sky, its SH and the irradiance, live",
        description="Serve the viewer page on 127.0.0.1 (only its own files; Ctrl-C stops it), or write it as "
        "static files with --out (they work from any static server and from file://). Nothing is fetched "
        "from the network: the page ships in the package.")
    view.add_argument("--out", type=Path, metavar="DIR", help="write the page's files into DIR instead of serving them")
    view.add_argument("--port", type=_port, metavar="N", help="TCP port on 127.0.0.1, [0, 65535]; default 0 (a free one)")
    view.add_argument("--open", action="store_true", help="open the page in the default browser")
    view.set_defaults(handler=_cmd_view)


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``skysh`` command (subcommands coeffs, export, render, fit, report)."""
    from skysh._version import __version__

    parser = _Parser(prog="skysh", description="Spherical-harmonic lighting of the Preetham sky (Habel et al. 2008). Angles in "
                     "degrees; radiance in cd/m^2, linear sRGB by default.",
                     epilog="Every refusal prints one line 'skysh: error: ...' and exits with status 2.")
    parser.add_argument("--version", action="version", version=f"skysh {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add_parser in (_add_coeffs_parser, _add_export_parser, _add_render_parser, _add_view_parser):
        add_parser(commands)
    for name, script in TOOL_COMMANDS.items():
        commands.add_parser(name, add_help=False, help=f"run tools/{script} with the remaining arguments (source "
                            f"checkout only; 'skysh {name} --help')")
    return parser


# --------------------------------------------------------------------------- #
# Shared steps
# --------------------------------------------------------------------------- #
class _Sun:
    """The sun of a command line: radians for the library, degrees to echo, and the place if given."""

    def __init__(self, zenith_deg: float, azimuth_deg: float, place: dict[str, Any]) -> None:
        self.zenith_deg, self.azimuth_deg = zenith_deg, azimuth_deg  # as typed (echoed exactly), or from the place
        self.zenith, self.azimuth = math.radians(zenith_deg), math.radians(azimuth_deg)
        self.place = place


def _sun_angles(args: argparse.Namespace) -> _Sun:
    """The sun from ``--sun-zenith``/``--sun-azimuth`` or from ``--lat``/``--lon``/``--time``, checked by flag."""
    place = (args.lat, args.lon, args.time)
    if any(v is not None for v in place):
        if args.sun_zenith is not None or args.sun_azimuth is not None:
            raise _UsageError("give either --sun-zenith/--sun-azimuth or --lat/--lon/--time, not both")
        if any(v is None for v in place):
            raise _UsageError("--lat, --lon and --time go together")
        from skysh.lighting import sun

        for flag, value, (low, high) in (("--lat", args.lat, sun.LATITUDE_RANGE), ("--lon", args.lon, sun.LONGITUDE_RANGE)):
            if not low <= value <= high:
                raise _UsageError(f"{flag} must lie in [{low:g}, {high:g}] degrees, got {number_text(value)}")
        utc = sun.as_utc(args.time, name="--time")  # a ValueError naming --time
        zenith, azimuth = (float(v) for v in sun.position_unchecked(args.lat, args.lon, utc))
        if zenith > sun.HORIZON_ZENITH:
            raise _UsageError(f"--time {args.time}: the sun is below the horizon at --lat {number_text(args.lat)} --lon "
                              f"{number_text(args.lon)} (sun zenith {math.degrees(zenith):.2f} deg > 90 deg): the sky "
                              "models are not defined there")
        return _Sun(math.degrees(zenith), math.degrees(azimuth), {"lat": args.lat, "lon": args.lon, "time": args.time})
    if args.sun_zenith is None:
        raise _UsageError("give --sun-zenith (and --sun-azimuth) or --lat/--lon/--time")
    from skysh.domain import SKY

    low, high = (math.degrees(v) for v in SKY.x.interval)
    if not low <= args.sun_zenith <= high:
        raise _UsageError(f"--sun-zenith must lie in {_sun_zenith_range()} degrees, got {number_text(args.sun_zenith)}")
    return _Sun(args.sun_zenith, 0.0 if args.sun_azimuth is None else args.sun_azimuth, {})


def _turbidity_range(model: str = "preetham") -> str:
    """A model's turbidity domain as help text: "[2.5, 6]" (:data:`skysh.domain.SKY`) or "[1, 10]" (Hosek-Wilkie)."""
    if model == "hosek-wilkie":
        from skysh.model import hosek

        return "[{:g}, {:g}]".format(*hosek.TURBIDITY_RANGE)
    from skysh.domain import SKY

    return SKY.y.interval_text()


def _sun_zenith_range() -> str:
    """The fitted sun-zenith domain in degrees as help text, "[0, 90]" (:data:`skysh.domain.SKY`)."""
    from skysh.domain import SKY

    return SKY.x.interval_text(degrees=True)


def _check_turbidity(turbidity: float, model: str = "preetham") -> None:
    from skysh.domain import SKY
    from skysh.model import hosek

    low, high = hosek.TURBIDITY_RANGE if model == "hosek-wilkie" else SKY.y.interval
    if not low <= turbidity <= high:
        domain = "the dataset's" if model == "hosek-wilkie" else "the fitted domain"
        raise _UsageError(f"--turbidity must lie in {_turbidity_range(model)} ({domain}), got {number_text(turbidity)}")


def _load(args: argparse.Namespace) -> Any:
    """The runtime of ``--model`` (a loaded SkySH or HosekWilkieSH), after refusing what that model does not take."""
    from skysh import SkySH

    if args.model == "preetham":
        if getattr(args, "albedo", None) is not None:
            raise _UsageError("--albedo goes with --model hosek-wilkie (the Preetham sky has no ground albedo; "
                              "--ground-albedo adds a lit ground)")
        return SkySH.load()
    for flag, given in (("--sun", getattr(args, "sun", False)), ("--sun-light", getattr(args, "sun_light", False)),
                        ("--ground-albedo", getattr(args, "ground_albedo", 0.0) != 0.0)):
        if given:
            raise _UsageError(f"{flag} does not go with --model hosek-wilkie (its runtime gives the sky alone: the sun's "
                              "disk and a lit ground come with the Preetham table)")
    return SkySH.load(model="hosek-wilkie")


def _check_bands(bands: int, sky: Any) -> None:
    if not 1 <= bands <= sky.bands:
        source = "the coefficient file's" if sky.model == "preetham" else "the model's measured"
        raise _UsageError(f"--bands must lie in [1, {sky.bands}] ({source} bands), got {bands}")


def _check_colourspace(name: str | None, sky: Any) -> None:
    """Refuse an unknown ``--colourspace``, listing the valid names (colour-science loads only for another name)."""
    if name is None or name == sky.colourspace:
        return
    from skysh.model import preetham

    try:
        preetham.rgb_from_xyz_matrix(name)
    except ValueError:
        raise _UsageError(f"--colourspace must be a colour-science RGB colourspace name, got {name!r}; valid names: "
                          + ", ".join(preetham.colourspace_names())) from None


def _scaled(before: NDArray[np.float64], scale: float, flag: str, fmt: str) -> NDArray[np.float64]:
    """``before * scale``; refuse a scale that overflows or flushes coefficients towards zero in the output's precision."""
    import numpy as np

    with np.errstate(over="ignore", under="ignore"):
        after = before * scale
    kind = "float32" if fmt in ("glsl", "hlsl") else "float64"
    limits = np.finfo(kind)  # float64: every finite value fits
    magnitude = np.abs(after)
    if not np.all(np.isfinite(after)) or magnitude.max() > limits.max:
        raise _UsageError(f"{flag} makes the coefficients overflow {kind} (largest |coefficient| before scaling "
                          f"{np.abs(before).max():.6g}); choose a smaller factor")
    if np.any((before != 0.0) & (magnitude < limits.tiny)):
        raise _UsageError(f"{flag} makes coefficients underflow {kind} (to subnormal numbers or zero); choose a larger factor")
    return after


# --------------------------------------------------------------------------- #
# Commands
# --------------------------------------------------------------------------- #
def _cmd_coeffs(args: argparse.Namespace) -> int:
    sun = _sun_angles(args)
    _check_turbidity(args.turbidity, args.model)
    from skysh._version import __version__
    from skysh.options import Options
    from skysh.sh import basis as sh

    sky = _load(args)
    _check_coeffs_options(args, sky)
    hosek = args.model == "hosek-wilkie"
    # the runtime's rules by intent (engines light diffusely: their 3-band presets take the certified irradiance table)
    o = Options.resolve(args.bands, args.gibbs, args.dering, args.irradiance, None, args.sun, args.ground_albedo,
                        args.colourspace, args.engine, has_table=not hosek and sky.has_irradiance_table,
                        max_bands=sky.bands)
    if hosek:
        c = sky.coefficients(sun.zenith, args.turbidity, sun.azimuth, bands=o.bands, gibbs=o.gibbs, dering=o.dering,
                             irradiance=o.irradiance, colourspace=o.colourspace, albedo=args.albedo or 0.0)
    else:
        c = sky.coefficients(sun.zenith, args.turbidity, sun.azimuth, bands=o.bands, gibbs=o.gibbs, dering=o.dering,
                             irradiance=o.irradiance, colourspace=o.colourspace, sun=o.sun,
                             ground_albedo=o.ground_albedo or 0.0, irradiance_table=o.irradiance_table)
    if args.up == "y":
        c = sh.to_y_up(c)
    c, scale, units = _coeffs_scaled(c, args)
    info: dict[str, Any] = {  # sun degrees as given (or computed from the place and time)
        "skysh_version": __version__, "model": args.model, **({"albedo": args.albedo or 0.0} if hosek else {}),
        "quantity": "irradiance" if args.irradiance else "radiance", "bands": args.bands,
        "sun_zenith_deg": sun.zenith_deg, "sun_azimuth_deg": sun.azimuth_deg, "sun_zenith_rad": sun.zenith,
        "sun_azimuth_rad": sun.azimuth, "turbidity": args.turbidity, "gibbs": o.gibbs, "dering": o.dering, "sun": args.sun,
        "ground_albedo": args.ground_albedo, "up": args.up, "units": units, "scale": scale,
        "normalise": args.normalise, "colourspace": args.colourspace or sky.colourspace,
        "convention": _CONVENTIONS[args.up], **({"place": sun.place} if sun.place else {}),
    }
    if args.sun_light:
        print(_sun_light_text(sky, sun, args, scale, info))
    elif args.engine is not None:
        print(format_engine(c, args.engine, args.format, info))
    else:
        print(format_coefficients(c, args.format, info))
    return 0


def _check_coeffs_options(args: argparse.Namespace, sky: Any) -> None:
    """Refuse the options of ``skysh coeffs`` that ``sky`` cannot serve or that do not go together."""
    _check_bands(args.bands, sky)
    _check_colourspace(args.colourspace, sky)
    if args.engine is not None:
        _check_engine_options(args, sky)
    elif args.format == "snippet":
        raise _UsageError("--format snippet needs --engine NAME (the snippet is written in that engine's language)")
    if args.sun_light and args.sun:
        raise _UsageError("--sun-light does not go with --sun: it prints the sun as a directional light, to use with SH "
                          "without the sun (else the sun counts twice)")


def _coeffs_scaled(c: NDArray[np.float64], args: argparse.Namespace) -> tuple[NDArray[np.float64], float, str]:
    """The coefficients times ``--exposure`` or the ``--normalise`` factor, that factor (1 without either) and the units."""
    units = "cd/m^2*sr" if args.irradiance else "cd/m^2"
    scale = 1.0
    if args.exposure is not None:
        scale = args.exposure
        units = f"{units} x {number_text(scale)}"
        c = _scaled(c, scale, f"--exposure {number_text(scale)}", args.format)
    elif args.normalise:
        scale = normalise_factor(c, args.irradiance)
        units = f"relative ({units} x {scale:.9g}: irradiance DC, R+G+B average, = 1)"
        c = _scaled(c, scale, "--normalise", args.format)
    return c, scale, units


def _sun_light_text(sky: Any, sun: _Sun, args: argparse.Namespace, scale: float, info: dict[str, Any]) -> str:
    """The text of ``--sun-light``: the direction in the output frame and the RGB illuminance x ``scale``."""

    direction, rgb = sky.sun_light(sun.zenith, args.turbidity, sun.azimuth, colourspace=args.colourspace)
    keep = ("skysh_version", "sun_zenith_deg", "sun_azimuth_deg", "turbidity", "colourspace", "place")
    record = {key: info[key] for key in keep if key in info}
    record["units"] = "lux" if scale == 1.0 else f"lux x {scale:.9g}" + (" (--normalise)" if args.normalise else "")
    rgb = _scaled(rgb, scale, "--normalise" if args.normalise else "--exposure", args.format)
    return format_sun_light(direction, rgb, args.format, record, engine=args.engine, up=args.up)


def _check_engine_options(args: argparse.Namespace, sky: Any) -> None:
    """Refuse what does not go with ``--engine`` (the preset owns the quantity and the frame)."""
    limit = _engine_bands(args.engine)
    if args.irradiance:
        raise _UsageError("--irradiance does not go with --engine: the preset converts the radiance into the quantity "
                          "the engine takes (radiance, or E/pi pre-scaled)")
    if args.up != "z":
        raise _UsageError("--up does not go with --engine: the preset converts to the engine's own frame")
    if args.format not in ENGINE_FORMATS:
        raise _UsageError(f"--format with --engine must be one of {', '.join(ENGINE_FORMATS)}, got {args.format!r}")
    if args.bands > limit:
        raise _UsageError(f"--bands must be at most {limit} for --engine {args.engine} (the engine holds {limit} bands), got "
                          f"{args.bands}")


def _engine_bands(engine: str) -> int:
    """The bands ``--engine`` holds, after refusing an unknown name."""
    from skysh.engines import presets as engines

    if engine not in engines.ENGINES:
        raise _UsageError(f"--engine must be one of {', '.join(engines.ENGINES)}, got {engine!r}")
    return engines.ENGINE_MAX_BANDS[engine]


def _output(path: Path, flag: str = "--out", folder: bool = False) -> Path:
    """``path`` checked as an output file (or ``folder``; never one of skysh's own files), else a usage error."""
    from skysh import files

    try:
        return files.check_output(path, flag, folder=folder)
    except (TypeError, ValueError) as error:
        raise _UsageError(str(error)) from None


def _write(outputs: dict[Path, bytes], flag: str = "--out") -> None:
    """Write every file whole (temporary files beside them, renamed when all are complete), or none."""
    from skysh import files

    try:
        files.write_together(outputs)
    except OSError as error:  # a full disk, a file-size limit, a missing permission: the targets are as they were
        raise _UsageError(f"{flag} {error.filename or next(iter(outputs))}: cannot write: {error.strerror or error} "
                          "(nothing was written)") from None


def _cmd_export(args: argparse.Namespace) -> int:
    if args.model == "hosek-wilkie":
        return _export_hosek(args)
    from skysh import SkySH
    from skysh.export.c_like import export_source

    sky = SkySH.load()
    if args.bands is not None:
        _check_bands(args.bands, sky)
    if args.engine is not None:
        limit = _engine_bands(args.engine)
        if args.format == "js":
            raise _UsageError("--engine does not go with --format js: the js module takes the engine as a per-call option")
        if args.bands is not None and args.bands > limit:
            raise _UsageError(f"--bands must be at most {limit} for --engine {args.engine}, got {args.bands}")
    from skysh.export.js import declarations, declarations_path

    stdout = str(args.out) == "-"
    paths = [] if stdout else [_output(args.out)]  # checked before the tables are exported
    if args.format == "js" and not stdout:
        paths.append(_output(declarations_path(args.out), "--out (its TypeScript declarations)"))
    text = export_source(sky, args.format, bands=args.bands, real=args.c_real, engine=args.engine)
    if stdout:
        sys.stdout.write(text)
        return 0
    texts = [text] + ([declarations(sky, args.bands)] if args.format == "js" else [])
    _write({path: content.encode("utf-8") for path, content in zip(paths, texts)})
    bands = args.bands if args.bands is not None else ("1-7" if args.format == "js" else 3)
    print(f"wrote {' and '.join(map(str, paths))} ({args.format}, {bands} bands, {len(text) / 1024:.1f} KiB)")
    return 0


def _export_hosek(args: argparse.Namespace) -> int:
    """``skysh export --model hosek-wilkie``: C or JavaScript (skysh.export.hosek), written whole."""
    from skysh.export import hosek as export_hosek

    if args.engine is not None:
        raise _UsageError("--engine does not go with --model hosek-wilkie (its exports give skysh's own convention)")
    if args.bands is not None and not 1 <= args.bands <= 7:
        raise _UsageError(f"--bands must lie in [1, 7], got {args.bands}")
    from skysh.export.js import declarations_path

    stdout = str(args.out) == "-"
    paths = [] if stdout else [_output(args.out)]  # checked before the source is written
    if args.format == "js" and not stdout:
        paths.append(_output(declarations_path(args.out), "--out (its TypeScript declarations)"))
    text = export_hosek.export_source(args.format, bands=args.bands, real=args.c_real)  # refuses other formats
    if stdout:
        sys.stdout.write(text)
        return 0
    texts = [text] + ([export_hosek.declarations(args.bands)] if args.format == "js" else [])
    _write({path: content.encode("utf-8") for path, content in zip(paths, texts)})
    print(f"wrote {' and '.join(map(str, paths))} ({args.format}, hosek-wilkie, {len(text) / 1024:.1f} KiB)")
    return 0


def _cmd_render(args: argparse.Namespace) -> int:
    sun = _sun_angles(args)
    _check_turbidity(args.turbidity, args.model)
    from skysh.app.render import render_image, write_png

    out = _output(args.out)
    sky = _load(args)
    _check_bands(args.bands, sky)
    image = render_image(sky, sun.zenith, args.turbidity, sun.azimuth, bands=args.bands, width=args.width,
                         gibbs=not args.no_gibbs, sun=args.sun, ground_albedo=args.ground_albedo,
                         albedo=args.albedo or 0.0)
    try:
        write_png(out, image)  # whole or not at all (skysh.files)
    except OSError as error:
        raise _UsageError(f"--out {out}: cannot write: {error.strerror or error} (nothing was written)") from None
    print(f"wrote {args.out} ({image.shape[1]} x {image.shape[0]} pixels)")
    return 0


def _cmd_view(args: argparse.Namespace) -> int:
    from skysh.app import viewer

    if args.out is None:
        viewer.serve(host="127.0.0.1", port=0 if args.port is None else args.port, open_browser=args.open)
        return 0
    if args.port is not None:
        raise _UsageError("--port does not go with --out (the page is written, not served)")
    _output(args.out, folder=True)
    try:
        viewer.write_static(args.out)  # every file renamed into place once all are complete (skysh.files)
    except OSError as error:
        raise _UsageError(f"--out {args.out}: cannot write {error.filename or 'the page'}: {error.strerror or error} "
                          "(nothing was written)") from None
    page = (args.out / "index.html").resolve().as_uri()
    print(f"wrote the viewer page: {page}")
    if args.open:
        import webbrowser

        webbrowser.open(page)
    return 0


def _tools_dir() -> Path | None:
    """The source checkout's ``tools/`` folder next to the package, or None for an installed package."""
    root = Path(__file__).resolve().parents[2]  # skysh/app/cli.py -> the checkout
    tools = root / "tools"
    return tools if tools.is_dir() and (root / "pyproject.toml").is_file() else None


def _tool_loader(command: str) -> Any:
    """A function importing ``command``'s module: the package's, or ``tools/<script>`` of the source checkout."""
    import importlib.util  # binds importlib too

    target = TOOL_COMMANDS[command]
    if not target.endswith(".py"):
        return lambda: importlib.import_module(target)
    tools = _tools_dir()
    if tools is None:
        raise _UsageError(f"'skysh {command}' runs tools/{target}, which is only in a source checkout of skysh (this "
                          "skysh is installed without its tools/ folder); clone the repository and run it there")
    path = tools / target
    if not path.is_file():
        raise _UsageError(f"'skysh {command}' runs tools/{target}, which this source checkout lacks ({path})")
    spec = importlib.util.spec_from_file_location(f"skysh_tools_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses (and pickling for process pools) look modules up here

    def load() -> Any:
        spec.loader.exec_module(module)  # type: ignore[union-attr]
        return module

    return load


def _run_tool(command: str, argv: list[str]) -> int:
    """Run ``command``'s ``main(argv)`` (:data:`TOOL_COMMANDS`) with one-line usage errors; refuse clearly where it is missing."""
    load = _tool_loader(command)
    saved, saved_error = sys.argv, argparse.ArgumentParser.error
    sys.argv = [f"skysh {command}"] + argv  # so the tool's --help names the command

    def one_line(parser: argparse.ArgumentParser, message: str) -> NoReturn:  # the tool's usage errors: one line
        raise _UsageError(f"{message} (see 'skysh {command} --help')")

    argparse.ArgumentParser.error = one_line  # type: ignore[assignment]  # one-line errors inside the tools too
    try:
        result = load().main(argv)
    except SystemExit as exit_:  # --help (0), or a tool's own exit
        code = exit_.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except ModuleNotFoundError as error:  # an optional dependency of the tools (matplotlib, tqdm, cvxpy, ...)
        package = (error.name or "").partition(".")[0]
        if package in ("", "skysh", "tools", "report", "studies"):
            raise
        raise _UsageError(f"'skysh {command}' needs the Python package {package!r}, which is not installed: it comes "
                          "with the tools extra, pip install -e \".[tools]\" (in the source checkout)") from None
    finally:
        sys.argv = saved
        argparse.ArgumentParser.error = saved_error  # type: ignore[method-assign]
    return int(result or 0)


def main(argv: Sequence[str] | None = None) -> int:
    """
    Run the ``skysh`` command line.

    Parameters
    ----------
    argv
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success, 2 after a one-line ``skysh: error: ...`` on stderr for any
        bad value (argparse's, the library's ValueError, an unwritable file), 1
        after a one-line ``skysh: internal error: ...`` for anything unexpected
        (a bug to report; never a traceback).
    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    try:
        if args_list and args_list[0] in TOOL_COMMANDS:
            return _run_tool(args_list[0], args_list[1:])
        args = build_parser().parse_args(args_list)
        return int(args.handler(args))
    except (_UsageError, ValueError) as error:  # CoefficientFileError is a ValueError too
        print(f"skysh: error: {' '.join(str(error).split())}", file=sys.stderr)  # on one line
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. piped into head: stop quietly, as other command-line tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as error:  # an unwritable --out
        where = f": {error.filename}" if error.filename else ""
        print(f"skysh: error: {error.strerror or error}{where}", file=sys.stderr)
        return EXIT_USAGE
    except Exception as error:
        message = " ".join(f"{type(error).__name__}: {error}".split())
        print(f"skysh: internal error: {message} (please report it with the command line)", file=sys.stderr)
        return EXIT_INTERNAL
