"""
Export the fitted sky to C, GLSL, HLSL and JSON
===============================================

Self-contained source that reproduces :meth:`skysh.SkySH.coefficients` without
Python: the polynomial tables of the shipped coefficient file and an evaluation
function, like the C arrays the Habel seed published, ready to paste.

-   :func:`export_source`: the text for one language (``"c"``, ``"glsl"``,
    ``"hlsl"``, ``"json"``).
-   :func:`export_tables`: the numbers every export is generated from.
-   :func:`double_literal`, :func:`float32_literal`: shortest round-trip
    number text for the generated code.
-   :data:`EXPORT_FORMATS`, :data:`C_REAL_TYPES`: the accepted names.

What the exported function computes, step by step (each step is the
runtime's, in the same order; the numbers come from :class:`skysh.SkySH`'s
plan and :mod:`skysh.preetham`, never retyped):

1.  Refuse a sun zenith outside [0, pi/2] rad or a turbidity outside
    [2.5, 6] (and, in C, a non-finite azimuth): the C function returns -1, the
    shader functions ``false``, and the output is zeroed.
2.  ``x = clamp(sun_zenith * X_SCALE - X_SHIFT, -1, 1)`` and
    ``y = clamp(log(turbidity) * Y_SCALE - Y_SHIFT, -1, 1)``.
3.  Chebyshev polynomials ``T_0 .. T_DX`` at x and ``T_0 .. T_DY`` at y by the
    three-term recurrence ``T_k = 2 t T_(k-1) - T_(k-2)`` (the runtime uses
    ``cos(k acos t)``: the same values to a few ulps).
4.  ``acc[r][c] = sum_i sum_j T_i(x) T_j(y) TABLE[i][j][r][c]`` for every stored
    coefficient r (the m >= 0 ones, ordered ``[(l, m) for l in range(N) for m
    in range(l + 1)]``) and channel c (R, G, B).
5.  Gibbs filter (Habel eq. 5), when asked: the zonal rows (m = 0) times
    ``GIBBS[l] = sinc(pi l / N)``.
6.  Times the luminance scale ``Y_z(ts, T) / F_Y(0, ts)`` of Preetham's model
    (zenith luminance in cd/m^2 over the Perez function of the zenith).
7.  Rotation about Z by the sun azimuth (Habel eq. 4): coefficient
    ``i = l (l + 1) + m`` is ``acc[l (l + 1) / 2 + |m|]`` times ``cos(m phi)``
    for m >= 0 and ``sin(|m| phi)`` for m < 0.
8.  Irradiance, when asked: band l times the clamped-cosine factor ``LOBE[l]``.

The result is (N * N) RGB coefficients in cd/m^2 (irradiance in cd/m^2 x sr),
linear sRGB, Z up, real SH with the Condon-Shortley phase (``CONVENTIONS.md``).

Precision
---------
C uses ``double`` by default (``real="float"`` gives a float build). GLSL and
HLSL tables and arithmetic are **float32** (``float``): the shader languages'
default precision. Measured against the Python runtime in
``tests/test_export.py`` over a grid of the domain, as the largest coefficient
error over the DC coefficient of the same channel, worst channel
(``python tests/test_export.py`` prints the figures): the double C build
agrees to 1.4e-15; float32 tables alone (the GLSL/HLSL tables, evaluated in
double) cost 9e-8; a whole float32 evaluation (inputs, tables and arithmetic:
the float C build, standing in for a shader) 1.0e-6. GPU ``tan``/``exp`` may be less
accurate than the C library's.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5) and
    the C tables of its supplementary material.
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: Y_z and the Perez
    function of luminance.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from string import Template
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import coefficient_file, runtime, sh
from skysh._checks import check_bands, check_choice
from skysh._version import __version__
from skysh.preetham import PEREZ_Y

__all__ = [
    "EXPORT_FORMATS", "C_REAL_TYPES", "ExportTables", "export_tables", "export_source", "double_literal",
    "float32_literal",
]

EXPORT_FORMATS: tuple[str, ...] = ("c", "glsl", "hlsl", "json")
"""Languages :func:`export_source` writes."""

C_REAL_TYPES: tuple[str, ...] = ("double", "float")
"""Floating-point types of the C export (its tables and arithmetic)."""

_VALUES_PER_LINE: int = 4
"""RGB triples per line in the generated tables."""


@dataclass(frozen=True)
class ExportTables:
    """
    Everything an export is generated from, for one band count.

    Attributes
    ----------
    bands
        N: the export evaluates l = 0 .. N - 1.
    degrees
        (DX, DY): Chebyshev degrees in x (sun zenith) and y (log turbidity).
    table
        (DX + 1, DY + 1, N (N + 1) / 2, 3) Chebyshev coefficients, no Gibbs
        filter folded in, of the stored (m >= 0) SH coefficients divided by the
        luminance scale (dimensionless: the scale carries cd/m^2).
    half_layout
        The (l, m) of the third axis of ``table``.
    gibbs
        (N,) zonal Gibbs factors sinc(pi l / N).
    lobe
        (N,) clamped-cosine factors A_l.
    x_scale, x_shift, y_scale, y_shift
        The Chebyshev variables' affine maps (see the module docstring, step 2).
    sun_zenith_domain, turbidity_domain
        The fitted domain, radians and turbidity.
    """

    bands: int
    degrees: tuple[int, int]
    table: NDArray[np.float64]
    half_layout: list[tuple[int, int]]
    gibbs: NDArray[np.float64]
    lobe: NDArray[np.float64]
    x_scale: float
    x_shift: float
    y_scale: float
    y_shift: float
    sun_zenith_domain: tuple[float, float]
    turbidity_domain: tuple[float, float]


def export_tables(sky: runtime.SkySH, bands: int = 3) -> ExportTables:
    """
    The numbers of an export: the runtime's plan for (``bands``, no Gibbs) and its constants.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`.
    bands
        N in [1, the file's bands].
    """
    bands = check_bands(bands, high=sky.bands)
    plan = sky._plans[(bands, False)]  # the runtime's own table: one source for the numbers
    dx, dy = plan.degrees
    layout = coefficient_file.zonal_half_layout(bands)
    table = np.array(plan.half_table).reshape(dx + 1, dy + 1, len(layout), 3)
    return ExportTables(
        bands=bands,
        degrees=(dx, dy),
        table=table,
        half_layout=layout,
        gibbs=runtime.gibbs_factors(bands),
        lobe=sh.cosine_lobe(bands),
        x_scale=runtime._X_SCALE,
        x_shift=runtime._X_SHIFT,
        y_scale=runtime._Y_SCALE,
        y_shift=runtime._Y_SHIFT,
        sun_zenith_domain=(runtime._ZMIN, runtime._ZMAX),
        turbidity_domain=(runtime._TMIN, runtime._TMAX),
    )


# --------------------------------------------------------------------------- #
# Number formatting
# --------------------------------------------------------------------------- #
def double_literal(value: float) -> str:
    """Shortest text that reads back as the same double, always with a '.' or an exponent."""
    text = repr(float(value))
    return text if any(ch in text for ch in ".en") else text + ".0"


def float32_literal(value: float) -> str:
    """Shortest text that reads back as the same float32 (valid in C, GLSL and HLSL, no suffix)."""
    return np.format_float_scientific(np.float32(value), unique=True, trim="0")


def _real(value: float, real: str) -> str:
    return double_literal(value) if real == "double" else float32_literal(value) + "f"


def _rows(items: list[str], indent: str) -> str:
    lines = [", ".join(items[k : k + _VALUES_PER_LINE]) for k in range(0, len(items), _VALUES_PER_LINE)]
    return (",\n" + indent).join(lines)


# --------------------------------------------------------------------------- #
# Templates. $-placeholders (string.Template) so the languages' braces stay literal.
# --------------------------------------------------------------------------- #
_HEADER = """\
skysh $version: SH coefficients of the Preetham sky (Habel et al. 2008), $bands band(s).
Generated by `skysh export --format $language$options`; do not edit.
Frame: Z up, azimuth from +X towards +Y. Real SH, orthonormal, Condon-Shortley
phase; coefficient i = l (l + 1) + m, l = 0 .. $last_l. Output: linear sRGB,
cd/m^2 (irradiance: cd/m^2 x sr). Domain: sun zenith [0, pi/2] rad,
turbidity [2.5, 6], any finite azimuth (radians). Tables: $precision.
Reproduces skysh.SkySH.coefficients(sun_zenith, turbidity, sun_azimuth,
bands=$bands, gibbs=..., irradiance=...)."""

_C = Template("""\
/*
$header
*/
#ifndef SKYSH_SKY_SH_H
#define SKYSH_SKY_SH_H

#include <math.h>

#define SKYSH_BANDS $bands
#define SKYSH_COUNT $count /* SKYSH_BANDS * SKYSH_BANDS */
#define SKYSH_HALF $half /* stored (m >= 0) coefficients */
#define SKYSH_DX $dx /* Chebyshev degree in x (sun zenith) */
#define SKYSH_DY $dy /* Chebyshev degree in y (log turbidity) */

typedef $real skysh_real;

/* [i][j][r][c]: coefficient of T_i(x) T_j(y) for stored coefficient r, channel c (R, G, B). */
static const skysh_real SKYSH_TABLE[SKYSH_DX + 1][SKYSH_DY + 1][SKYSH_HALF][3] = {
    $table
};

/* Zonal Gibbs factors sinc(pi l / N) (Habel eq. 5) and clamped-cosine factors A_l. */
static const skysh_real SKYSH_GIBBS[SKYSH_BANDS] = { $gibbs };
static const skysh_real SKYSH_LOBE[SKYSH_BANDS] = { $lobe };

/* Perez A..E of luminance as (slope, intercept) in turbidity (Preetham 1999). */
static const skysh_real SKYSH_PEREZ_Y[5][2] = { $perez };

/* Y_z / F_Y(0, ts): the sky's luminance scale, cd/m^2. */
static skysh_real skysh_luminance_scale(skysh_real ts, skysh_real t)
{
    const skysh_real chi = ($c4_9 - t / $c120) * ($pi - $c2 * ts);
    const skysh_real yz = $c1000 * (($c40453 * t - $c49710) * $tan(chi) - $c02155 * t + $c24192);
    const skysh_real ct = $cos(ts);
    const skysh_real f = ($c1 + (SKYSH_PEREZ_Y[0][0] * t + SKYSH_PEREZ_Y[0][1]) * $exp(SKYSH_PEREZ_Y[1][0] * t + SKYSH_PEREZ_Y[1][1]))
        * ($c1 + (SKYSH_PEREZ_Y[2][0] * t + SKYSH_PEREZ_Y[2][1]) * $exp((SKYSH_PEREZ_Y[3][0] * t + SKYSH_PEREZ_Y[3][1]) * ts)
           + (SKYSH_PEREZ_Y[4][0] * t + SKYSH_PEREZ_Y[4][1]) * ct * ct);
    return yz / f;
}

/*
 * The sky's SH coefficients. Angles in radians. gibbs: apply the zonal sinc
 * filter; irradiance: convolve with the clamped cosine. Returns 0, or -1
 * (out zeroed) for a parameter outside the domain, NaN or inf.
 */
static int skysh_coefficients(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth,
                              int gibbs, int irradiance, skysh_real out[SKYSH_COUNT][3])
{
    skysh_real tx[SKYSH_DX + 1], ty[SKYSH_DY + 1], acc[SKYSH_HALF][3];
    skysh_real x, y, scale;
    int i, j, r, c, l, m;
    for (i = 0; i < SKYSH_COUNT; ++i)
        out[i][0] = out[i][1] = out[i][2] = $c0;
    if (!(sun_zenith >= $zmin && sun_zenith <= $zmax) || !(turbidity >= $tmin && turbidity <= $tmax)
        || !(sun_azimuth - sun_azimuth == $c0))
        return -1;
    x = sun_zenith * $x_scale - $x_shift;
    y = $log(turbidity) * $y_scale - $y_shift;
    x = x < -$c1 ? -$c1 : (x > $c1 ? $c1 : x);
    y = y < -$c1 ? -$c1 : (y > $c1 ? $c1 : y);
    tx[0] = $c1;
    ty[0] = $c1;
    for (i = 1; i <= SKYSH_DX; ++i)
        tx[i] = i == 1 ? x : $c2 * x * tx[i - 1] - tx[i - 2];
    for (j = 1; j <= SKYSH_DY; ++j)
        ty[j] = j == 1 ? y : $c2 * y * ty[j - 1] - ty[j - 2];
    for (r = 0; r < SKYSH_HALF; ++r)
        acc[r][0] = acc[r][1] = acc[r][2] = $c0;
    for (i = 0; i <= SKYSH_DX; ++i)
        for (j = 0; j <= SKYSH_DY; ++j) {
            const skysh_real w = tx[i] * ty[j];
            for (r = 0; r < SKYSH_HALF; ++r)
                for (c = 0; c < 3; ++c)
                    acc[r][c] += w * SKYSH_TABLE[i][j][r][c];
        }
    scale = skysh_luminance_scale(sun_zenith, turbidity);
    for (l = 0; l < SKYSH_BANDS; ++l) {
        const skysh_real band = (irradiance ? SKYSH_LOBE[l] : $c1) * scale;
        const int row = l * (l + 1) / 2; /* stored (l, 0) */
        if (gibbs)
            for (c = 0; c < 3; ++c)
                acc[row][c] *= SKYSH_GIBBS[l];
        for (m = -l; m <= l; ++m) {
            const int k = m < 0 ? -m : m;
            const skysh_real rot = m < 0 ? $sin(k * sun_azimuth) : $cos(k * sun_azimuth);
            for (c = 0; c < 3; ++c)
                out[l * (l + 1) + m][c] = acc[row + k][c] * rot * band;
        }
    }
    return 0;
}

#endif /* SKYSH_SKY_SH_H */
""")

_SHADER = Template("""\
// $header_lines
// Paste into a shader (no #version line; GLSL 3.30 / ES 3.00 or later, or HLSL
// SM 4+). For 4 or more bands the table is large for a constant array: move it
// to a uniform or storage buffer with the same layout if the compiler balks.

#define SKYSH_BANDS $bands
#define SKYSH_COUNT $count
#define SKYSH_HALF $half
#define SKYSH_DX $dx
#define SKYSH_DY $dy

// Index ((i * (SKYSH_DY + 1) + j) * SKYSH_HALF + r): RGB coefficient of T_i(x) T_j(y)
// for stored coefficient r.
$const $vec3 SKYSH_TABLE[$n_table] = $open
    $table
$close;
$const float SKYSH_GIBBS[SKYSH_BANDS] = $gibbs_open$gibbs$gibbs_close;
$const float SKYSH_LOBE[SKYSH_BANDS] = $lobe_open$lobe$lobe_close;
// Perez A..E of luminance as (slope, intercept) in turbidity (Preetham 1999).
$const float SKYSH_PEREZ_Y[10] = $perez_open$perez$perez_close;

// Y_z / F_Y(0, ts): the sky's luminance scale, cd/m^2.
float skysh_luminance_scale(float ts, float t)
{
    float chi = ($c4_9 - t / $c120) * ($pi - $c2 * ts);
    float yz = $c1000 * (($c40453 * t - $c49710) * tan(chi) - $c02155 * t + $c24192);
    float ct = cos(ts);
    float f = ($c1 + (SKYSH_PEREZ_Y[0] * t + SKYSH_PEREZ_Y[1]) * exp(SKYSH_PEREZ_Y[2] * t + SKYSH_PEREZ_Y[3]))
        * ($c1 + (SKYSH_PEREZ_Y[4] * t + SKYSH_PEREZ_Y[5]) * exp((SKYSH_PEREZ_Y[6] * t + SKYSH_PEREZ_Y[7]) * ts)
           + (SKYSH_PEREZ_Y[8] * t + SKYSH_PEREZ_Y[9]) * ct * ct);
    return yz / f;
}

// The sky's SH coefficients. Angles in radians. Returns false (coeffs zeroed)
// for a parameter outside the domain.
bool skysh_coefficients(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool irradiance,
                        out $vec3 coeffs[SKYSH_COUNT])
{
    for (int n = 0; n < SKYSH_COUNT; ++n)
        coeffs[n] = $vec3($c0, $c0, $c0);
    if (!(sunZenith >= $zmin && sunZenith <= $zmax) || !(turbidity >= $tmin && turbidity <= $tmax))
        return false;
    float x = clamp(sunZenith * $x_scale - $x_shift, -$c1, $c1);
    float y = clamp(log(turbidity) * $y_scale - $y_shift, -$c1, $c1);
    float tx[SKYSH_DX + 1];
    float ty[SKYSH_DY + 1];
    tx[0] = $c1;
    ty[0] = $c1;
    for (int i = 1; i <= SKYSH_DX; ++i)
        tx[i] = (i == 1) ? x : $c2 * x * tx[i - 1] - tx[i - 2];
    for (int j = 1; j <= SKYSH_DY; ++j)
        ty[j] = (j == 1) ? y : $c2 * y * ty[j - 1] - ty[j - 2];
    $vec3 acc[SKYSH_HALF];
    for (int r = 0; r < SKYSH_HALF; ++r)
        acc[r] = $vec3($c0, $c0, $c0);
    for (int i = 0; i <= SKYSH_DX; ++i)
        for (int j = 0; j <= SKYSH_DY; ++j) {
            float w = tx[i] * ty[j];
            int base = (i * (SKYSH_DY + 1) + j) * SKYSH_HALF;
            for (int r = 0; r < SKYSH_HALF; ++r)
                acc[r] += w * SKYSH_TABLE[base + r];
        }
    float scale = skysh_luminance_scale(sunZenith, turbidity);
    for (int l = 0; l < SKYSH_BANDS; ++l) {
        float band = (irradiance ? SKYSH_LOBE[l] : $c1) * scale;
        int row = l * (l + 1) / 2;
        if (gibbs)
            acc[row] *= SKYSH_GIBBS[l];
        for (int m = -l; m <= l; ++m) {
            int k = abs(m);
            float rot = (m < 0) ? sin(float(k) * sunAzimuth) : cos(float(k) * sunAzimuth);
            coeffs[l * (l + 1) + m] = acc[row + k] * (rot * band);
        }
    }
    return true;
}
""")

# The zenith luminance of skysh.preetham._zenith_luminance (Preetham 1999, appendix):
# Y_z = 1000 ((4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192), chi = (4/9 - T/120)(pi - 2 ts).
# preetham.py keeps these inline, so they are repeated here once; the tests compare
# every export with the runtime, which would catch a difference.
_ZENITH_CONSTANTS: dict[str, float] = {
    "c4_9": 4.0 / 9.0, "c120": 120.0, "c1000": 1000.0,
    "c40453": 4.0453, "c49710": 4.9710, "c02155": 0.2155, "c24192": 2.4192,
    "pi": math.pi, "c0": 0.0, "c1": 1.0, "c2": 2.0,
}


def _header(tables: ExportTables, language: str, precision: str, options: str) -> str:
    return Template(_HEADER).substitute(
        version=__version__, bands=tables.bands, language=language, options=options,
        last_l=tables.bands - 1, precision=precision,
    )


def _c_source(tables: ExportTables, real: str) -> str:
    fmt = lambda v: _real(v, real)  # noqa: E731
    blocks = []  # one {...} per (i, j), nested as the array is declared (no brace elision)
    for i, plane in enumerate(tables.table):
        rows = []
        for j, block in enumerate(plane):
            triples = ["{" + ", ".join(fmt(v) for v in rgb) + "}" for rgb in block]
            rows.append(f"{{ /* T_{i}(x) T_{j}(y) */\n            " + _rows(triples, "            ") + "\n        }")
        blocks.append("{\n        " + ",\n        ".join(rows) + "\n    }")
    suffix = "" if real == "double" else "f"
    header = _header(
        tables, "c", f"{real} (C {real})", "" if real == "double" else " --c-real float"
    )
    return _C.substitute(
        header=header,
        bands=tables.bands, count=tables.bands**2, half=len(tables.half_layout),
        dx=tables.degrees[0], dy=tables.degrees[1], real=real,
        table=",\n    ".join(blocks),
        gibbs=", ".join(map(fmt, tables.gibbs)), lobe=", ".join(map(fmt, tables.lobe)),
        perez=", ".join("{" + ", ".join(map(fmt, row)) + "}" for row in PEREZ_Y),
        zmin=fmt(tables.sun_zenith_domain[0]), zmax=fmt(tables.sun_zenith_domain[1]),
        tmin=fmt(tables.turbidity_domain[0]), tmax=fmt(tables.turbidity_domain[1]),
        x_scale=fmt(tables.x_scale), x_shift=fmt(tables.x_shift),
        y_scale=fmt(tables.y_scale), y_shift=fmt(tables.y_shift),
        tan="tan" + suffix, exp="exp" + suffix, cos="cos" + suffix, sin="sin" + suffix, log="log" + suffix,
        **{k: fmt(v) for k, v in _ZENITH_CONSTANTS.items()},
    )


def _shader_source(tables: ExportTables, language: str) -> str:
    glsl = language == "glsl"
    vec3 = "vec3" if glsl else "float3"
    fmt = float32_literal

    def brackets(n: int) -> tuple[str, str]:
        return (f"float[{n}](", ")") if glsl else ("{ ", " }")

    triples = [f"{vec3}(" + ", ".join(fmt(v) for v in rgb) + ")" for rgb in tables.table.reshape(-1, 3)]
    n_table = len(triples)
    open_, close = (f"{vec3}[{n_table}](", ")") if glsl else ("{", "}")
    gibbs = [fmt(v) for v in tables.gibbs]
    lobe = [fmt(v) for v in tables.lobe]
    perez = [fmt(v) for v in PEREZ_Y.ravel()]
    g_open, g_close = brackets(tables.bands)
    p_open, p_close = brackets(len(perez))
    header = _header(tables, language, "float32", "").replace("\n", "\n// ")
    return _SHADER.substitute(
        header_lines=header,
        const="const" if glsl else "static const", vec3=vec3,
        bands=tables.bands, count=tables.bands**2, half=len(tables.half_layout),
        dx=tables.degrees[0], dy=tables.degrees[1], n_table=n_table,
        open=open_, close=close, table=_rows(triples, "    "),
        gibbs_open=g_open, gibbs=", ".join(gibbs), gibbs_close=g_close,
        lobe_open=g_open, lobe=", ".join(lobe), lobe_close=g_close,
        perez_open=p_open, perez=", ".join(perez), perez_close=p_close,
        zmin=fmt(tables.sun_zenith_domain[0]), zmax=fmt(tables.sun_zenith_domain[1]),
        tmin=fmt(tables.turbidity_domain[0]), tmax=fmt(tables.turbidity_domain[1]),
        x_scale=fmt(tables.x_scale), x_shift=fmt(tables.x_shift),
        y_scale=fmt(tables.y_scale), y_shift=fmt(tables.y_shift),
        **{k: fmt(v) for k, v in _ZENITH_CONSTANTS.items()},
    )


def _json_source(tables: ExportTables) -> str:
    payload: dict[str, Any] = {
        "format": "skysh-export",
        "skysh_version": __version__,
        "bands": tables.bands,
        "degrees": list(tables.degrees),
        "table": tables.table.tolist(),
        "table_layout": "[i][j][r][c]: coefficient of T_i(x) T_j(y) for stored coefficient r "
        "(half_layout[r] = (l, m), m >= 0) and channel c (R, G, B); float64",
        "half_layout": [list(lm) for lm in tables.half_layout],
        "gibbs": tables.gibbs.tolist(),
        "lobe": tables.lobe.tolist(),
        "x": {"scale": tables.x_scale, "shift": tables.x_shift, "of": "sun_zenith (rad)"},
        "y": {"scale": tables.y_scale, "shift": tables.y_shift, "of": "log(turbidity)"},
        "domain": {"sun_zenith": list(tables.sun_zenith_domain), "turbidity": list(tables.turbidity_domain)},
        "perez_Y": PEREZ_Y.tolist(),
        "luminance_scale": "Y_z / F_Y(0, ts) with Y_z = 1000 ((4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192), "
        "chi = (4/9 - T/120)(pi - 2 ts), F_Y(0, ts) = (1 + A e^B)(1 + C e^(D ts) + E cos^2 ts), "
        "(A..E) = perez_Y[:, 0] T + perez_Y[:, 1]",
        "algorithm": [
            "refuse sun_zenith outside domain.sun_zenith, turbidity outside domain.turbidity, non-finite azimuth",
            "x = clamp(sun_zenith * x.scale - x.shift, -1, 1); y = clamp(log(turbidity) * y.scale - y.shift, -1, 1)",
            "T_0..T_DX at x and T_0..T_DY at y (Chebyshev: T_0 = 1, T_1 = t, T_k = 2 t T_(k-1) - T_(k-2))",
            "acc[r][c] = sum_ij T_i(x) T_j(y) table[i][j][r][c]",
            "if gibbs: acc[r] *= gibbs[l] for the rows with m = 0",
            "acc *= luminance_scale(sun_zenith, turbidity)",
            "out[l(l+1)+m] = acc[l(l+1)/2+|m|] * (cos(m phi) if m >= 0 else sin(|m| phi))",
            "if irradiance: out[l(l+1)+m] *= lobe[l]",
        ],
        "units": "cd/m^2 (irradiance: cd/m^2*sr)",
        "colourspace": "sRGB (linear, Rec. 709 primaries, D65)",
        "convention": "Z up, azimuth from +X towards +Y, real orthonormal SH with the Condon-Shortley phase, "
        "index l(l+1)+m",
    }
    return json.dumps(payload, indent=1) + "\n"


def export_source(sky: runtime.SkySH, language: str, bands: int = 3, real: str = "double") -> str:
    """
    Source text that evaluates the sky's SH coefficients in ``language``.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH` (its default colourspace, linear sRGB).
    language
        One of :data:`EXPORT_FORMATS`: ``"c"`` (a header with ``static``
        tables and ``skysh_coefficients()``; C99, compiles cleanly with
        ``-std=c99 -Wall -Wextra -pedantic``), ``"glsl"`` / ``"hlsl"`` (float32 constant arrays and
        ``skysh_coefficients()``), ``"json"`` (the float64 tables and the
        algorithm in words).
    bands
        N in [1, the file's bands]: the export evaluates N bands only.
    real
        C only: ``"double"`` (default) or ``"float"``.

    Returns
    -------
    str
        The text, ending with a newline.

    Raises
    ------
    ValueError
        For an unknown language or ``real``, or ``bands`` out of range.
    """
    check_choice(language, "language", EXPORT_FORMATS)
    check_choice(real, "real", C_REAL_TYPES)
    tables = export_tables(sky, bands)
    if language == "c":
        return _c_source(tables, real)
    if language == "json":
        return _json_source(tables)
    return _shader_source(tables, language)
