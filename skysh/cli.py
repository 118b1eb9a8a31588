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
    skysh export  --format c|glsl|hlsl|json --out FILE [--bands N]            tables + evaluation code
    skysh render  --sun-zenith DEG --sun-azimuth DEG --turbidity T --out FILE.png
    skysh fit     ...   tools/fit_sky.py (source checkout only)
    skysh report  ...   tools/error_report.py (source checkout only)

Angles are **degrees** on the command line (the library takes radians).
Every refusal (a value out of range, a sun below the horizon, an unknown
colourspace, an unwritable file) prints one line ``skysh: error: ...`` on
stderr and exits with status 2; no traceback.

Start-up: this module imports argparse only; each command imports what it
needs when it runs, so ``skysh coeffs`` in the default colourspace loads numpy
and the runtime, never colour-science or matplotlib
(``tests/test_startup.py``, ``benchmarks/bench_startup.py``).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn, Sequence

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np
    from numpy.typing import NDArray

__all__ = ["COEFF_FORMATS", "TOOL_COMMANDS", "build_parser", "format_coefficients", "normalise_factor", "main"]

COEFF_FORMATS: tuple[str, ...] = ("table", "json", "csv", "glsl", "hlsl", "c")
"""Output formats of ``skysh coeffs``."""

TOOL_COMMANDS: dict[str, str] = {"fit": "fit_sky.py", "report": "error_report.py"}
"""Commands that run a script of the source checkout's ``tools/`` folder."""

EXIT_USAGE: int = 2
"""Exit status of every refusal (argparse's own convention for bad usage)."""

_CONVENTION: str = (
    "Z up (zenith), azimuth from +X towards +Y; real orthonormal SH with the Condon-Shortley phase; "
    "row i = l(l+1)+m, l = 0..N-1"
)
_NORMALISE_HELP: str = (
    "scale so that the irradiance DC coefficient E(0,0) = pi L(0,0), averaged over R, G and B, is exactly 1 "
    "(then the mean irradiance over all normals, E(0,0)/(2 sqrt(pi)), averages 0.2821); radiance output "
    "gets the same factor. Applied last, in the output colourspace"
)


_NUMBER_LIST = re.compile(r"\[\s*(-?[0-9.eE+-]+(?:,\s*-?[0-9.eE+-]+)*)\s*\]")
"""An innermost JSON list of numbers, to print on one line."""


class _UsageError(Exception):
    """A bad command line; :func:`main` prints it on one line and exits with status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block) that :func:`main` turns into status 2."""

    def error(self, message: str) -> NoReturn:
        raise _UsageError(f"{message} (see '{self.prog} --help')")


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _positive(text: str) -> float:
    value = _finite(text)
    if value <= 0.0:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def _bands(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


def _width(text: str) -> int:
    value = _bands(text)
    if not 16 <= value <= 4096:
        raise argparse.ArgumentTypeError(f"expected an integer in [16, 4096], got {text!r}")
    return value


# --------------------------------------------------------------------------- #
# Parser
# --------------------------------------------------------------------------- #
def _add_sun(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group(
        "the sun (either its angles, or a place and a time)",
        "Frame: +X = East, +Y = North, +Z = up; azimuth from +X towards +Y (East 0, North 90, South -90).",
    )
    group.add_argument("--sun-zenith", type=_finite, metavar="DEG", help="sun zenith angle, degrees, [0, 90] (0 = overhead, 90 = on the horizon)")
    group.add_argument("--sun-azimuth", type=_finite, metavar="DEG", help="sun azimuth, degrees, any finite value (default 0)")
    group.add_argument("--lat", type=_finite, metavar="DEG", help="latitude, degrees, [-90, 90], positive North (with --lon and --time)")
    group.add_argument("--lon", type=_finite, metavar="DEG", help="longitude, degrees, [-180, 180], positive East")
    group.add_argument("--time", metavar="ISO8601", help="time with a UTC offset, e.g. 2024-06-21T12:00:00+02:00 or ...Z; the sun must be above the horizon")
    parser.add_argument("--turbidity", type=_finite, required=True, metavar="T", help="atmospheric turbidity, [2.5, 6] (the fitted domain)")


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``skysh`` command (subcommands coeffs, export, render, fit, report)."""
    from skysh._version import __version__

    parser = _Parser(
        prog="skysh",
        description="Spherical-harmonic lighting of the Preetham sky (Habel et al. 2008). Angles in degrees; "
        "radiance in cd/m^2, linear sRGB by default.",
        epilog="Every refusal prints one line 'skysh: error: ...' and exits with status 2.",
    )
    parser.add_argument("--version", action="version", version=f"skysh {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    coeffs = commands.add_parser(
        "coeffs", help="the sky's SH coefficients for one frame",
        description="The sky's SH coefficients for one sun position and turbidity: (N*N) rows x (R, G, B), "
        "radiance in cd/m^2 (with --irradiance: cd/m^2*sr, lux for the luminance), linear RGB of "
        "--colourspace. " + _CONVENTION + ".",
    )
    _add_sun(coeffs)
    coeffs.add_argument("--bands", type=_bands, default=3, metavar="N", help="SH bands N, [1, 7] (the shipped file's); default 3 (9 coefficients)")
    coeffs.add_argument("--irradiance", action="store_true", help="irradiance coefficients E (clamped-cosine convolution), cd/m^2*sr (lux for the luminance)")
    coeffs.add_argument("--gibbs", action=argparse.BooleanOptionalAction, default=None, help="the zonal sinc Gibbs filter (Habel eq. 5); default: on for radiance, off for irradiance and engine presets (it blurs diffuse light)")
    coeffs.add_argument("--dering", action=argparse.BooleanOptionalAction, default=None, help="window the coefficients so the reconstructed irradiance is never negative (Sloan 2017); default: on for irradiance and engine presets, off for radiance")
    coeffs.add_argument("--up", choices=("z", "y"), default="z", help="frame of the output: z (default, skysh's Z up) or y (right-handed Y up as glTF: zenith +Y, +X stays, +Y becomes -Z; skysh.sh.to_y_up)")
    coeffs.add_argument("--format", choices=COEFF_FORMATS, default="table", help="table (default; labelled rows, units), json, csv, or a constant array for glsl, hlsl (float32) or c (double)")
    coeffs.add_argument("--colourspace", metavar="NAME", default=None, help="colour-science RGB colourspace name, e.g. 'ITU-R BT.2020', 'ACEScg'; default linear sRGB (other names load colour-science, about 1.5 s)")
    units = coeffs.add_mutually_exclusive_group()
    units.add_argument("--exposure", type=_positive, metavar="X", help="multiply every coefficient by X > 0 (the units are multiplied by X)")
    units.add_argument("--normalise", action="store_true", help=_NORMALISE_HELP)
    coeffs.set_defaults(handler=_cmd_coeffs)

    export = commands.add_parser(
        "export", help="polynomial tables and an evaluation function in C, GLSL, HLSL or JSON",
        description="Write the fitted polynomial tables and a self-contained function skysh_coefficients"
        "(sun_zenith_rad, turbidity, sun_azimuth_rad, gibbs, irradiance, out) that reproduces the runtime "
        "(radians, turbidity [2.5, 6]; output cd/m^2, linear sRGB, " + _CONVENTION + "). C: double tables "
        "(--c-real float for float); GLSL and HLSL: float32 tables and arithmetic; JSON: float64 tables and "
        "the algorithm in words.",
    )
    export.add_argument("--format", choices=("c", "glsl", "hlsl", "json"), required=True, help="language of the file")
    export.add_argument("--out", type=Path, required=True, metavar="FILE", help="file to write ('-' for standard output)")
    export.add_argument("--bands", type=_bands, default=3, metavar="N", help="SH bands N, [1, 7]; default 3")
    export.add_argument("--c-real", choices=("double", "float"), default="double", help="C only: floating type of the tables and arithmetic (default double)")
    export.set_defaults(handler=_cmd_export)

    render = commands.add_parser(
        "render", help="PNG of the true sky, its SH reconstruction and the irradiance",
        description="Three latitude-longitude panels side by side: the Preetham sky, its SH reconstruction and "
        "the SH irradiance divided by pi (the radiance of a white Lambertian surface), all with one exposure "
        "(the sky's log-average maps to 0.18), Reinhard tone mapping and the sRGB transfer function. Columns: "
        "azimuth -180 (left) to 180 degrees (right); rows: zenith angle 0 (top) to 180 (bottom), horizon in the "
        "middle; a ring marks the sun.",
    )
    _add_sun(render)
    render.add_argument("--out", type=Path, required=True, metavar="FILE.png", help="PNG file to write")
    render.add_argument("--bands", type=_bands, default=3, metavar="N", help="SH bands N, [1, 7]; default 3")
    render.add_argument("--width", type=_width, default=256, metavar="W", help="width of each panel in pixels, [16, 4096]; default 256 (height W/2)")
    render.add_argument("--no-gibbs", action="store_true", help="skip the zonal sinc Gibbs filter")
    render.set_defaults(handler=_cmd_render)

    for name, script in TOOL_COMMANDS.items():
        commands.add_parser(
            name, add_help=False,
            help=f"run tools/{script} with the remaining arguments (source checkout only; 'skysh {name} --help')",
        )
    return parser


# --------------------------------------------------------------------------- #
# Shared steps
# --------------------------------------------------------------------------- #
def _sun_angles(args: argparse.Namespace) -> tuple[float, float, dict[str, Any]]:
    """(sun_zenith, sun_azimuth) in radians from the sun options, and what to record about them."""
    place = (args.lat, args.lon, args.time)
    if any(v is not None for v in place):
        if args.sun_zenith is not None or args.sun_azimuth is not None:
            raise _UsageError("give either --sun-zenith/--sun-azimuth or --lat/--lon/--time, not both")
        if any(v is None for v in place):
            raise _UsageError("--lat, --lon and --time go together")
        from skysh import sun

        zenith, azimuth = sun.position(args.lat, args.lon, args.time)  # degrees in, radians out
        return float(zenith), float(azimuth), {"lat": args.lat, "lon": args.lon, "time": args.time}
    if args.sun_zenith is None:
        raise _UsageError("give --sun-zenith (and --sun-azimuth) or --lat/--lon/--time")
    from skysh.poly import SUN_ZENITH_DOMAIN

    low, high = (math.degrees(v) for v in SUN_ZENITH_DOMAIN)
    if not low <= args.sun_zenith <= high:
        raise _UsageError(f"--sun-zenith must lie in [{low:g}, {high:g}] degrees, got {args.sun_zenith:g}")
    azimuth = 0.0 if args.sun_azimuth is None else args.sun_azimuth
    return math.radians(args.sun_zenith), math.radians(azimuth), {}


def _check_turbidity(turbidity: float) -> None:
    from skysh.poly import TURBIDITY_DOMAIN

    low, high = TURBIDITY_DOMAIN
    if not low <= turbidity <= high:
        raise _UsageError(f"--turbidity must lie in [{low:g}, {high:g}] (the fitted domain), got {turbidity:g}")


def _check_bands(bands: int, sky: Any) -> None:
    if not 1 <= bands <= sky.bands:
        raise _UsageError(f"--bands must lie in [1, {sky.bands}] (the coefficient file's bands), got {bands}")


def normalise_factor(coefficients: NDArray[np.float64], irradiance: bool) -> float:
    """
    The factor of ``--normalise``: 1 / (irradiance DC coefficient averaged over R, G, B).

    Parameters
    ----------
    coefficients
        (N * N, 3) radiance (``irradiance=False``) or irradiance coefficients.
    irradiance
        Whether ``coefficients`` already are irradiance.

    Returns
    -------
    float
        k such that ``k * mean_c E(0, 0)_c = 1`` with ``E(0, 0) = A_0 L(0, 0) = pi L(0, 0)``.

    Raises
    ------
    ValueError
        If that average is not positive (never for the Preetham sky).
    """
    from skysh import sh

    dc = float(coefficients[0].mean())
    if not irradiance:
        dc *= float(sh.cosine_lobe(1)[0])
    if not dc > 0.0:
        raise ValueError(f"--normalise needs a positive irradiance DC (R+G+B average), got {dc:g}")
    return 1.0 / dc


def _lm_rows(bands: int) -> list[tuple[int, int]]:
    from skysh import sh

    return [sh.lm(i) for i in range(bands * bands)]


def format_coefficients(coefficients: NDArray[np.float64], fmt: str, info: dict[str, Any]) -> str:
    """
    The text of ``skysh coeffs`` in the format ``fmt`` (one of :data:`COEFF_FORMATS`).

    Parameters
    ----------
    coefficients
        (N * N, 3) RGB coefficients.
    fmt
        ``"table"``: a header (parameters, units, convention) and one row per
        coefficient labelled i, l, m with R, G, B (7 significant digits).
        ``"json"``: an object with ``"coefficients"`` (the (N*N, 3) list, full
        precision) and the parameters, units, colourspace and convention.
        ``"csv"``: ``i,l,m,R,G,B`` rows (full precision). ``"glsl"``,
        ``"hlsl"``: a float32 constant array ``SKY_SH``; ``"c"``: a double
        array ``SKY_SH[N*N][3]``.
    info
        The parameters to record (keys as in the JSON output).
    """
    import json

    rows = _lm_rows(math.isqrt(len(coefficients)))
    values = [[float(v) for v in row] for row in coefficients]
    n = len(values)
    if fmt == "json":
        text = json.dumps({"coefficients": values, "lm": [list(lm) for lm in rows], **info}, indent=1)
        return _NUMBER_LIST.sub(lambda match: "[" + " ".join(match.group(1).split()) + "]", text)  # a row per line
    if fmt == "csv":
        lines = ["i,l,m,R,G,B"] + [f"{i},{l},{m}," + ",".join(map(repr, v)) for i, ((l, m), v) in enumerate(zip(rows, values))]
        return "\n".join(lines)
    summary = (
        f"skysh {info['skysh_version']}: {info['quantity']} SH of the Preetham sky, {info['bands']} bands; "
        f"sun zenith {info['sun_zenith_deg']:.6g} deg, azimuth {info['sun_azimuth_deg']:.6g} deg, "
        f"turbidity {info['turbidity']:g}; gibbs {'on' if info['gibbs'] else 'off'}, dering {'on' if info['dering'] else 'off'}"
    )
    context = [
        summary,
        f"units: {info['units']}; colourspace: {info['colourspace']} (linear); {info['up'].upper()} up",
        info["convention"],
    ]
    if fmt == "table":
        header = f"{'i':>3} {'l':>2} {'m':>3} {'R':>15} {'G':>15} {'B':>15}"
        body = [
            f"{i:>3} {l:>2} {m:>3} " + " ".join(f"{x:>15.7g}" for x in v) for i, ((l, m), v) in enumerate(zip(rows, values))
        ]
        return "\n".join(["# " + line for line in context] + [header] + body)
    if fmt == "c":
        body = [f"    {{{', '.join(map(repr, v))}}}, /* {i}: l={l}, m={m} */" for i, ((l, m), v) in enumerate(zip(rows, values))]
        comment = ["/* " + line + " */" for line in context]
        return "\n".join(comment + [f"static const double SKY_SH[{n}][3] = {{"] + body + ["};"])
    # glsl / hlsl: float32, shortest round-trip text
    from skysh.export import float32_literal

    vec3 = "vec3" if fmt == "glsl" else "float3"
    items = [f"    {vec3}({', '.join(float32_literal(x) for x in v)})" for v in values]
    labels = [f" // {i}: l={l}, m={m}" for i, (l, m) in enumerate(rows)]
    body = [item + ("," if k < n - 1 else "") + label for k, (item, label) in enumerate(zip(items, labels))]
    comment = ["// " + line for line in context]
    if fmt == "glsl":
        return "\n".join(comment + [f"const vec3 SKY_SH[{n}] = vec3[{n}]("] + body + [");"])
    return "\n".join(comment + [f"static const float3 SKY_SH[{n}] = {{"] + body + ["};"])


# --------------------------------------------------------------------------- #
# Commands
# --------------------------------------------------------------------------- #
def _cmd_coeffs(args: argparse.Namespace) -> int:
    sun_zenith, sun_azimuth, place = _sun_angles(args)
    _check_turbidity(args.turbidity)
    from skysh import SkySH, sh
    from skysh._version import __version__

    sky = SkySH.load()
    _check_bands(args.bands, sky)
    diffuse = args.irradiance
    gibbs = not diffuse if args.gibbs is None else args.gibbs
    dering = diffuse if args.dering is None else args.dering
    c = sky.coefficients(
        sun_zenith, args.turbidity, sun_azimuth, bands=args.bands, gibbs=gibbs, dering=dering,
        irradiance=args.irradiance, colourspace=args.colourspace,
    )
    if args.up == "y":
        c = sh.to_y_up(c)
    units = "cd/m^2*sr" if args.irradiance else "cd/m^2"
    scale = 1.0
    if args.exposure is not None:
        scale = args.exposure
        units = f"{units} x {scale:g}"
    elif args.normalise:
        scale = normalise_factor(c, args.irradiance)
        units = f"relative ({units} x {scale:.9g}: irradiance DC, R+G+B average, = 1)"
    c = c * scale
    info: dict[str, Any] = {
        "skysh_version": __version__,
        "quantity": "irradiance" if args.irradiance else "radiance",
        "bands": args.bands,
        "sun_zenith_deg": math.degrees(sun_zenith),
        "sun_azimuth_deg": math.degrees(sun_azimuth),
        "sun_zenith_rad": sun_zenith,
        "sun_azimuth_rad": sun_azimuth,
        "turbidity": args.turbidity,
        "gibbs": gibbs,
        "dering": dering,
        "up": args.up,
        "units": units,
        "scale": scale,
        "normalise": args.normalise,
        "colourspace": args.colourspace or sky.colourspace,
        "convention": _CONVENTION + ("; Y-up frame (skysh.sh.to_y_up)" if args.up == "y" else ""),
    }
    if place:
        info["place"] = place
    print(format_coefficients(c, args.format, info))
    return 0


def _write_text(path: Path, text: str) -> None:
    if str(path) == "-":
        sys.stdout.write(text)
    else:
        path.write_text(text)


def _cmd_export(args: argparse.Namespace) -> int:
    from skysh import SkySH
    from skysh.export import export_source

    sky = SkySH.load()
    _check_bands(args.bands, sky)
    text = export_source(sky, args.format, bands=args.bands, real=args.c_real)
    _write_text(args.out, text)
    if str(args.out) != "-":
        print(f"wrote {args.out} ({args.format}, {args.bands} bands, {len(text) / 1024:.1f} KiB)")
    return 0


def _cmd_render(args: argparse.Namespace) -> int:
    sun_zenith, sun_azimuth, _ = _sun_angles(args)
    _check_turbidity(args.turbidity)
    from skysh import SkySH
    from skysh.render import render_image, write_png

    sky = SkySH.load()
    _check_bands(args.bands, sky)
    image = render_image(
        sky, sun_zenith, args.turbidity, sun_azimuth, bands=args.bands, width=args.width, gibbs=not args.no_gibbs
    )
    write_png(args.out, image)
    print(f"wrote {args.out} ({image.shape[1]} x {image.shape[0]} pixels)")
    return 0


def _tools_dir() -> Path | None:
    """The source checkout's ``tools/`` folder next to the package, or None for an installed package."""
    root = Path(__file__).resolve().parent.parent
    tools = root / "tools"
    return tools if tools.is_dir() and (root / "pyproject.toml").is_file() else None


def _run_tool(command: str, argv: list[str]) -> int:
    """Run ``tools/<script>``'s ``main(argv)`` from the source checkout; refuse clearly elsewhere."""
    import importlib.util

    script = TOOL_COMMANDS[command]
    tools = _tools_dir()
    path = None if tools is None else tools / script
    if path is None:
        raise _UsageError(
            f"'skysh {command}' runs tools/{script}, which is only in a source checkout of skysh "
            "(this skysh is installed without its tools/ folder); clone the repository and run it there"
        )
    if not path.is_file():
        raise _UsageError(f"'skysh {command}' runs tools/{script}, which this source checkout lacks ({path})")
    spec = importlib.util.spec_from_file_location(f"skysh_tools_{path.stem}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses (and pickling for process pools) look modules up here
    saved = sys.argv
    sys.argv = [f"skysh {command}"] + argv  # so the tool's --help names the command
    try:
        spec.loader.exec_module(module)
        result = module.main(argv)
    except SystemExit as exit_:  # argparse inside the tool: --help (0) or its own usage error (2)
        code = exit_.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    finally:
        sys.argv = saved
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
        bad value (argparse's, the library's ValueError, an unwritable file).
    """
    args_list = list(sys.argv[1:] if argv is None else argv)
    try:
        if args_list and args_list[0] in TOOL_COMMANDS:
            return _run_tool(args_list[0], args_list[1:])
        args = build_parser().parse_args(args_list)
        return int(args.handler(args))
    except (_UsageError, ValueError) as error:  # CoefficientFileError is a ValueError too
        message = " ".join(str(error).split())
        print(f"skysh: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. piped into head: stop quietly, as other command-line tools do
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as error:  # an unwritable --out
        where = f": {error.filename}" if error.filename else ""
        print(f"skysh: error: {error.strerror or error}{where}", file=sys.stderr)
        return EXIT_USAGE
