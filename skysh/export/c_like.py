"""
Export the fitted sky to C, GLSL, HLSL, JSON and JavaScript
===========================================================

Self-contained source that reproduces :meth:`skysh.SkySH.coefficients` without
Python: the polynomial tables of the shipped coefficient file and an evaluation
function, like the C arrays the Habel seed published, ready to paste.

-   :func:`export_source`: the text for one language (:data:`EXPORT_FORMATS`);
    ``engine=`` makes the generated function return an engine's numbers
    (:mod:`skysh.engines.presets`). C, GLSL and HLSL are written here, ``"js"`` and ``"json"``
    by :mod:`skysh.export.js`; both from the numbers of :mod:`skysh.export.tables`
    (:func:`~skysh.export.tables.export_tables`, :func:`~skysh.export.tables.engine_plan`).
-   :func:`double_literal`, :func:`float32_literal`: shortest round-trip
    number text for the generated code (from :mod:`skysh.export.lights`).
-   :data:`EXPORT_FORMATS`, :data:`C_REAL_TYPES`, :data:`DEFAULT_FILE_NAMES`.

The C export is a **header** (default name ``sky_sh.h``): an include guard,
``static inline`` functions and ``static const`` tables, so any number of C99
or C++ files may ``#include`` it; link with ``-lm`` (it calls ``tan``, ``exp``,
``log``, ``cos``, ``sin``, ``fmod``).

What the exported function computes, step by step (the runtime's steps in its
order; the numbers come from the file's tables as the runtime reads them and
from :mod:`skysh.model.preetham`, never retyped):

1.  Refuse a sun zenith outside [0, pi/2] rad or a turbidity outside [2.5, 6]
    (and, in C, a non-finite azimuth): C returns -1, the shaders ``false``,
    and the output is zeroed; a ground albedo outside [0, 1] (C: -3); an
    ``irradiance_table`` the export cannot honour (C: -5).
2.  ``x = clamp(sun_zenith * X_SCALE - X_SHIFT, -1, 1)``,
    ``y = clamp(log(turbidity) * Y_SCALE - Y_SHIFT, -1, 1)``; Chebyshev
    ``T_0 .. T_DX`` at x and ``T_0 .. T_DY`` at y by ``T_k = 2 t T_(k-1) -
    T_(k-2)`` (the runtime's ``cos(k acos t)``, to a few ulps).
3.  ``acc[r][c] = sum_i sum_j T_i(x) T_j(y) TABLE[i][j][r][c]`` for every stored
    coefficient r (m >= 0, ordered ``[(l, m) for l in range(N) for m in
    range(l + 1)]``) and channel c (R, G, B); C and JS store the table r-major,
    so that each r is a contiguous dot product. With the certified irradiance
    table (3 bands; ``irradiance_table``, by intent for diffuse light, as the
    runtime: :func:`skysh.export.lights.irradiance_parts`) the rows come from
    ``IRRADIANCE`` instead (its radiance-equivalent E_lm / A_l), the ground's c_10
    from ``TABLE``; steps 4 and 6 are then skipped.
4.  Gibbs filter (Habel eq. 5), when asked: zonal rows times ``sinc(pi l / N)``;
    times the luminance scale ``Y_z(ts, T) / F_Y(0, ts)`` (Preetham, cd/m^2).
5.  Rotation about Z (Habel eq. 4) by ``phi = fmod(sun_azimuth, 2 pi)`` as the
    runtime reduces it: coefficient ``l (l + 1) + m`` is ``acc[l (l + 1) / 2 +
    |m|]`` times ``cos(m phi)`` (m >= 0) or ``sin(|m| phi)`` (m < 0).
6.  Deringing, when asked, for 3 bands (:mod:`skysh.export.dering`: the
    runtime's window, Sloan 2017); other band counts refuse it.
7.  The sun and the ground, when asked (:mod:`skysh.export.lights`, the order of
    :mod:`skysh.lighting.lights`): the sun's windowed delta (colour clamped at 0) and a
    Lambertian ground lit by the unfiltered sky's c_10 and the sun.
8.  A per-band factor, which commutes with the rotation (one multiplication
    with step 5 when steps 6 and 7 are off): ``A_l`` for irradiance, or an
    engine's folded factor (:func:`skysh.export.tables.engine_plan`).
9.  Engines only: the rest of the engine's linear map (frame change, signs,
    per-coefficient constants, packing) written out term by term, plus its
    constant offset.

``skysh_sun_light`` (the shaders' too) gives the sun as a directional light, as
:meth:`skysh.SkySH.sun_light`.

Without an engine the result is (N * N) RGB coefficients in cd/m^2 (irradiance
cd/m^2 x sr), linear sRGB, Z up, real SH with the Condon-Shortley phase
(``docs/conventions.md``); with one, ``skysh.engines.presets.convert(radiance,
engine)`` flattened row-major.

Precision
---------
C uses ``double`` (``real="float"``: a float build); GLSL and HLSL are float32.
``python tests/export/test_export.py`` prints each one's agreement with the Python
runtime (largest error over the DC of the same channel, worst channel). GPU
``tan``/``exp`` may be less accurate than the C library's.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5) and
    the C tables of its supplementary material.
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: Y_z and the Perez
    function of luminance.
"""

from __future__ import annotations

from collections.abc import Callable
from string import Template
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import runtime
from skysh.checks import check_choice, interval_text
from skysh.export import js as export_js
from skysh.export.lights import (
    FLOAT32_MAX,
    ZENITH_CONSTANTS,
    c_like_engine,
    c_like_lights,
    dering_parts,
    double_literal,
    float32_literal,
    irradiance_parts,
    real_literal,
    text_rows,
)
from skysh.export.tables import EnginePlan, ExportTables, engine_plan, export_tables
from skysh.model.preetham import PEREZ_Y
from skysh import __version__

__all__ = [
    "EXPORT_FORMATS", "C_REAL_TYPES", "DEFAULT_FILE_NAMES", "export_source", "double_literal", "float32_literal",
    "FLOAT32_MAX",
]

EXPORT_FORMATS: tuple[str, ...] = ("c", "glsl", "hlsl", "json", "js")
"""Languages :func:`export_source` writes."""

C_REAL_TYPES: tuple[str, ...] = ("double", "float")
"""Floating-point types of the C export (its tables and arithmetic)."""

DEFAULT_FILE_NAMES: dict[str, str] = {
    "c": "sky_sh.h", "glsl": "sky_sh.glsl", "hlsl": "sky_sh.hlsl", "json": "sky_sh.json", "js": "sky_sh.mjs",
}
"""The file name each export is meant to be saved as (the C export is a header)."""

_TRIPLES_PER_LINE: int = 4
"""RGB triples per line in the generated tables."""


# Templates: $-placeholders (string.Template), so the languages' braces stay literal.
_HEADER = """\
skysh $version: SH coefficients of the Preetham sky (Habel et al. 2008), $bands band(s).
Generated by `skysh export --format $language$options`; do not edit.
Frame: Z up, azimuth from +X towards +Y. Real SH, orthonormal, Condon-Shortley
phase; coefficient i = l (l + 1) + m, l = 0 .. $last_l. Output: linear sRGB,
cd/m^2 (irradiance: cd/m^2 x sr). Domain: sun zenith $sun_zenith_domain rad,
turbidity $turbidity_domain, any finite azimuth (radians). Tables: $precision.
Reproduces skysh.SkySH.coefficients(sun_zenith, turbidity, sun_azimuth,
bands=$bands, gibbs=..., dering=..., irradiance=..., sun=..., ground_albedo=...,
irradiance_table=...) and skysh.SkySH.sun_light (skysh_sun_light: the sun as a directional light).$engine_text"""

_ENGINE_HEADER = """
Engine $engine ($count values, shape $shape, row-major): skysh_engine_coefficients()
returns skysh.engines.presets.convert(radiance coefficients, "$engine") flattened; it
takes radiance and applies what the engine expects (frame, signs, scaling)."""

_C = Template("""\
/*
$header

A C99 header: #include "sky_sh.h" in any number of C or C++ files and link
with -lm. Every function is static inline and every table static const.
*/
#ifndef SKYSH_SKY_SH_H
#define SKYSH_SKY_SH_H

#include <math.h>

#define SKYSH_BANDS $bands
#define SKYSH_COUNT $count /* SKYSH_BANDS * SKYSH_BANDS */
#define SKYSH_HALF $half /* stored (m >= 0) coefficients */
#define SKYSH_ROWS $rows /* table rows: the stored coefficients (one band: and the unfiltered c_10) */
#define SKYSH_DX $dx /* Chebyshev degree in x (sun zenith) */
#define SKYSH_DY $dy /* Chebyshev degree in y (log turbidity) */
#define SKYSH_DERING $has_dering /* 1: the dering option works (3-band exports) */
#define SKYSH_TERMS ((SKYSH_DX + 1) * (SKYSH_DY + 1))

typedef $real skysh_real;

/*
 * [r][3 (i (SKYSH_DY + 1) + j) + c]: coefficient of T_i(x) T_j(y) for stored coefficient r,
 * channel c (R, G, B); the terms of one stored coefficient are contiguous.
 */
static const skysh_real SKYSH_TABLE[SKYSH_ROWS][SKYSH_TERMS * 3] = {
    $table
};

/* Zonal Gibbs factors sinc(pi l / N) (Habel eq. 5) and clamped-cosine factors A_l. */
static const skysh_real SKYSH_GIBBS[SKYSH_BANDS] = { $gibbs };
static const skysh_real SKYSH_LOBE[SKYSH_BANDS] = { $lobe };

/* Perez A..E of luminance as (slope, intercept) in turbidity (Preetham 1999). */
static const skysh_real SKYSH_PEREZ_Y[5][2] = { $perez };
$engine_tables$dering_defs$lights$irradiance_defs
/* Habel eq. (1) for one stored coefficient: acc[c] = sum_q w[q] p[3 q + c], six independent sums (latency). */
static inline void skysh_row(const skysh_real *p, const skysh_real *w, skysh_real acc[3])
{
    skysh_real r0 = $c0, g0 = $c0, b0 = $c0, r1 = $c0, g1 = $c0, b1 = $c0;
    int i;
    for (i = 0; i + 1 < SKYSH_TERMS; i += 2, p += 6) {
        r0 += w[i] * p[0];
        g0 += w[i] * p[1];
        b0 += w[i] * p[2];
        r1 += w[i + 1] * p[3];
        g1 += w[i + 1] * p[4];
        b1 += w[i + 1] * p[5];
    }
    if (i < SKYSH_TERMS) {
        r0 += w[i] * p[0];
        g0 += w[i] * p[1];
        b0 += w[i] * p[2];
    }
    acc[0] = r0 + r1;
    acc[1] = g0 + g1;
    acc[2] = b0 + b1;
}

/* Y_z / F_Y(0, ts): the sky's luminance scale, cd/m^2. */
static inline skysh_real skysh_luminance_scale(skysh_real ts, skysh_real t)
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
 * The steps of skysh_coefficients; mode selects the per-band factor:
 * 0 none (radiance), 1 the clamped cosine (irradiance)$mode_doc.
 */
static inline int skysh_evaluate(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth, int gibbs,
                                 int dering, int sun, const skysh_real *ground_albedo, int irradiance_table, int mode,
                                 skysh_real out[SKYSH_COUNT][3])
{
    static const skysh_real black[3] = { $c0, $c0, $c0 };
    const skysh_real *albedo = ground_albedo ? ground_albedo : black;
    skysh_real tx[SKYSH_DX + 1], ty[SKYSH_DY + 1], w[SKYSH_TERMS], acc[SKYSH_ROWS][3], e_sky[3];
    skysh_real x, y, phi, scale;
    int i, j, r, c, l, m, ground, post, table;
    for (i = 0; i < SKYSH_COUNT; ++i)
        out[i][0] = out[i][1] = out[i][2] = $c0;
    if (!(sun_zenith >= $zmin && sun_zenith <= $zmax) || !(turbidity >= $tmin && turbidity <= $tmax)
        || !(sun_azimuth - sun_azimuth == $c0))
        return -1;
    if (dering && !SKYSH_DERING)
        return -2;
    for (c = 0; c < 3; ++c)
        if (!(albedo[c] >= $c0 && albedo[c] <= $c1))
            return -3;
    ground = albedo[0] != $c0 || albedo[1] != $c0 || albedo[2] != $c0;
    if ((sun && SKYSH_LIGHTS % 2 == 0) || (ground && SKYSH_LIGHTS / 2 == 0))
        return -4;
    table = skysh_use_table(irradiance_table, mode, gibbs, dering);
    if (table < 0)
        return -5;
    dering = dering && !table; /* the table is certified non-negative: never deringed */
    post = dering || sun || ground; /* then step 8 follows steps 6 and 7 */
    phi = $fmod(sun_azimuth, $two_pi); /* as the runtime: exact, so k * phi stays small */
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
    for (i = 0; i <= SKYSH_DX; ++i)
        for (j = 0; j <= SKYSH_DY; ++j)
            w[i * (SKYSH_DY + 1) + j] = tx[i] * ty[j];
    for (r = 0; r < SKYSH_ROWS; ++r) /* step 3 (with the table: the sky's c_10 only) */
        if (!table || r == 1)
            skysh_row(SKYSH_TABLE[r], w, acc[r]);
    scale = skysh_luminance_scale(sun_zenith, turbidity);
    for (c = 0; c < 3; ++c)
        e_sky[c] = $hf * acc[1][c] * scale; /* E_h of the unfiltered sky (skysh.model.ground) */$irradiance_step
    for (l = 0; l < SKYSH_BANDS; ++l) {
        const skysh_real band = (post ? $c1 : $factor) * scale;
        const int row = l * (l + 1) / 2; /* stored (l, 0) */
        if (gibbs)
            for (c = 0; c < 3; ++c)
                acc[row][c] *= SKYSH_GIBBS[l];
        for (m = -l; m <= l; ++m) {
            const int k = m < 0 ? -m : m;
            const skysh_real rot = m < 0 ? $sin(k * phi) : $cos(k * phi);
            for (c = 0; c < 3; ++c)
                out[l * (l + 1) + m][c] = acc[row + k][c] * rot * band;
        }
    }$dering_step
    if (sun || ground)
        skysh_add_lights(sun_zenith, turbidity, phi, sun, ground, gibbs, albedo, e_sky, out);
    if (post && mode != 0)
        for (l = 0; l < SKYSH_BANDS; ++l)
            for (i = l * l; i < (l + 1) * (l + 1); ++i)
                for (c = 0; c < 3; ++c)
                    out[i][c] *= $factor;
    return 0;
}

/*
 * The sky's SH coefficients. Angles in radians. gibbs: apply the zonal sinc
 * filter; dering: the least window that keeps the irradiance non-negative (Sloan
 * 2017, SKYSH_DERING exports only); irradiance: convolve with the clamped cosine;
 * sun: add the sun's disk (a windowed delta); ground_albedo: NULL, or the RGB
 * albedo in [0, 1] of a Lambertian ground lit by the sky (and the sun with sun);
 * irradiance_table: SKYSH_BY_INTENT (the runtime's default), 0 or 1, as
 * skysh.SkySH.coefficients' None, False, True (skysh_use_table: the certified
 * irradiance table of 3-band exports for diffuse light, never negative).
 * Returns 0, or (out zeroed) -1 for a parameter outside the domain, NaN or inf,
 * -2 for dering without SKYSH_DERING, -3 for a ground albedo outside [0, 1],
 * -4 for the sun or the ground without its table (SKYSH_LIGHTS), -5 for an
 * irradiance_table refused (1 without SKYSH_IRRADIANCE_TABLE or with gibbs).
 */
static inline int skysh_coefficients(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth, int gibbs,
                                     int dering, int irradiance, int sun, const skysh_real *ground_albedo,
                                     int irradiance_table, skysh_real out[SKYSH_COUNT][3])
{
    return skysh_evaluate(sun_zenith, turbidity, sun_azimuth, gibbs, dering, sun, ground_albedo, irradiance_table,
                          irradiance ? 1 : 0, out);
}
$engine_function
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
#define SKYSH_ROWS $rows
#define SKYSH_DX $dx
#define SKYSH_DY $dy
#define SKYSH_DERING $has_dering

// Index ((i * (SKYSH_DY + 1) + j) * SKYSH_ROWS + r): RGB coefficient of T_i(x) T_j(y)
// for stored coefficient r (one band: row 1 is the unfiltered c_10, for the ground).
$const $vec3 SKYSH_TABLE[$n_table] = $open
    $table
$close;
$const float SKYSH_GIBBS[SKYSH_BANDS] = $gibbs;
$const float SKYSH_LOBE[SKYSH_BANDS] = $lobe;
// Perez A..E of luminance as (slope, intercept) in turbidity (Preetham 1999).
$const float SKYSH_PEREZ_Y[10] = $perez;
$engine_tables$dering_defs$lights$irradiance_defs
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

// The steps of skysh_coefficients; mode selects the per-band factor:
// 0 none (radiance), 1 the clamped cosine (irradiance)$mode_doc.
bool skysh_evaluate(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool dering, bool sun,
                    $vec3 groundAlbedo, int irradianceTable, int mode, out $vec3 coeffs[SKYSH_COUNT])
{
    for (int n = 0; n < SKYSH_COUNT; ++n)
        coeffs[n] = $vec3($c0, $c0, $c0);
    bool ground = groundAlbedo.x != $c0 || groundAlbedo.y != $c0 || groundAlbedo.z != $c0;
    int use = skysh_use_table(irradianceTable, mode, gibbs, dering);
    if (!(sunZenith >= $zmin && sunZenith <= $zmax) || !(turbidity >= $tmin && turbidity <= $tmax)
        || (dering && SKYSH_DERING == 0) || !(groundAlbedo.x >= $c0 && groundAlbedo.x <= $c1)
        || !(groundAlbedo.y >= $c0 && groundAlbedo.y <= $c1) || !(groundAlbedo.z >= $c0 && groundAlbedo.z <= $c1)
        || (sun && SKYSH_LIGHTS % 2 == 0) || (ground && SKYSH_LIGHTS / 2 == 0) || use < 0)
        return false;
    bool table = use == 1;
    dering = dering && !table; // the table is certified non-negative: never deringed
    bool post = dering || sun || ground; // then step 8 follows steps 6 and 7
    float phi = $mod(sunAzimuth, $two_pi);
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
    $vec3 acc[SKYSH_ROWS];
    $vec3 irr[SKYSH_ROWS];
    for (int r = 0; r < SKYSH_ROWS; ++r) {
        acc[r] = $vec3($c0, $c0, $c0);
        irr[r] = acc[r];
    }
    for (int i = 0; i <= SKYSH_DX; ++i)
        for (int j = 0; j <= SKYSH_DY; ++j) {
            float w = tx[i] * ty[j];
            int base = (i * (SKYSH_DY + 1) + j) * SKYSH_ROWS;
            for (int r = 0; r < SKYSH_ROWS; ++r) // step 3 (with the table: the sky's c_10 only)
                if (!table || r == 1)
                    acc[r] += w * SKYSH_TABLE[base + r];$irradiance_step
        }
    float scale = skysh_luminance_scale(sunZenith, turbidity);
    $vec3 eSky = acc[1] * ($hf * scale); // E_h of the unfiltered sky (skysh.model.ground)
    for (int r = 0; r < SKYSH_ROWS; ++r)
        if (table)
            acc[r] = irr[r];
    for (int l = 0; l < SKYSH_BANDS; ++l) {
        float band = (post ? $c1 : $factor) * scale;
        int row = l * (l + 1) / 2;
        if (gibbs)
            acc[row] *= SKYSH_GIBBS[l];
        for (int m = -l; m <= l; ++m) {
            int k = abs(m);
            float rot = (m < 0) ? sin(float(k) * phi) : cos(float(k) * phi);
            coeffs[l * (l + 1) + m] = acc[row + k] * (rot * band);
        }
    }$dering_step
    if (sun || ground)
        skysh_add_lights(sunZenith, turbidity, phi, sun, ground, gibbs, groundAlbedo, eSky, coeffs);
    if (post && mode != 0)
        for (int l = 0; l < SKYSH_BANDS; ++l)
            for (int n = l * l; n < (l + 1) * (l + 1); ++n)
                coeffs[n] *= $factor;
    return true;
}

// The sky's SH coefficients. Angles in radians; sun adds the sun's disk, groundAlbedo
// (RGB in [0, 1], vec3(0) for none) a Lambertian ground; irradianceTable SKYSH_BY_INTENT
// (the runtime's default), 0 or 1 as skysh.SkySH.coefficients' irradiance_table None, False,
// True. Returns false (coeffs zeroed) for a parameter outside the domain, dering without
// SKYSH_DERING (3 bands), the sun or the ground without its table (SKYSH_LIGHTS), or an
// irradianceTable refused (1 without SKYSH_IRRADIANCE_TABLE or with gibbs).
bool skysh_coefficients(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool dering, bool irradiance,
                        bool sun, $vec3 groundAlbedo, int irradianceTable, out $vec3 coeffs[SKYSH_COUNT])
{
    return skysh_evaluate(sunZenith, turbidity, sunAzimuth, gibbs, dering, sun, groundAlbedo, irradianceTable,
                          irradiance ? 1 : 0, coeffs);
}
$engine_function""")

def _header(tables: ExportTables, language: str, precision: str, options: str, plan: EnginePlan | None) -> str:
    engine_text = ""
    if plan is not None:
        engine_text = Template(_ENGINE_HEADER).substitute(
            engine=plan.engine, count=plan.offset.size, shape=plan.shape
        )
    return Template(_HEADER).substitute(
        version=__version__, bands=tables.bands, language=language,
        options=options + (f" --engine {plan.engine}" if plan is not None else ""),
        last_l=tables.bands - 1, precision=precision, engine_text=engine_text,
        sun_zenith_domain=interval_text(*tables.sun_zenith_domain, pi=True),
        turbidity_domain=interval_text(*tables.turbidity_domain),
    )


def _common(tables: ExportTables, fmt: Callable[[float], str], plan: EnginePlan | None, language: str,
            vec3: str = "", real: str = "double") -> dict[str, Any]:
    """Substitutions shared by the C and shader templates (and the lights' functions)."""
    one = fmt(1.0)
    factor = f"(mode == 1 ? SKYSH_LOBE[l] : {one})"  # step 8
    if plan is not None:
        factor = f"(mode == 1 ? SKYSH_LOBE[l] : (mode == 2 ? SKYSH_ENGINE_BAND[l] : {one}))"
    defs, step = dering_parts(language, tables.bands, vec3)
    return dict(
        bands=tables.bands, count=tables.bands**2, half=len(tables.half_layout), rows=len(_stored_rows(tables)[0]),
        dx=tables.degrees[0], dy=tables.degrees[1],
        zmin=fmt(tables.sun_zenith_domain[0]), zmax=fmt(tables.sun_zenith_domain[1]),
        tmin=fmt(tables.turbidity_domain[0]), tmax=fmt(tables.turbidity_domain[1]),
        x_scale=fmt(tables.x_scale), x_shift=fmt(tables.x_shift),
        y_scale=fmt(tables.y_scale), y_shift=fmt(tables.y_shift), hf=fmt(tables.lights.constants["hf"]),
        mode_doc=", 2 the engine's folded factor" if plan is not None else "", factor=factor,
        dering_defs=defs, dering_step=step, has_dering=int(bool(step)),
        **irradiance_parts(language, tables.irradiance if tables.bands == 3 else None, real),
        **{k: fmt(v) for k, v in ZENITH_CONSTANTS.items()},
    )


def _stored_rows(tables: ExportTables) -> tuple[list[str], NDArray[np.float64]]:
    """Labels and (rows, terms, 3) of the embedded table: the stored coefficients, and for one band
    the unfiltered c_10 (the ground's E_h; with two or more bands it is stored row 1)."""
    by_row = tables.table.reshape(-1, len(tables.half_layout), 3).transpose(1, 0, 2)  # (r, i (DY + 1) + j, c)
    labels = [f"(l, m) = ({l}, {m})" for l, m in tables.half_layout]
    if tables.bands == 1:
        by_row = np.concatenate([by_row, tables.lights.c10.reshape(1, -1, 3)])
        labels.append("the unfiltered (1, 0), for the ground")
    return labels, by_row


def _c_source(tables: ExportTables, real: str, plan: EnginePlan | None) -> str:
    def fmt(v: float) -> str:
        return real_literal(v, real)

    blocks = []  # one {...} per row r, as the array is declared (no brace elision)
    for label, terms in zip(*_stored_rows(tables)):
        triples = [", ".join(fmt(v) for v in rgb) for rgb in terms]
        blocks.append(f"{{ /* {label} */\n        " + text_rows(triples, "        ", _TRIPLES_PER_LINE) + "\n    }")
    suffix = "" if real == "double" else "f"
    common = _common(tables, fmt, plan, "c", real=real)
    engine_tables, engine_function = c_like_engine("c", plan, common, fmt)
    return _C.substitute(
        common,
        header=_header(tables, "c", f"{real} (C {real})", "" if real == "double" else " --c-real float", plan),
        real=real, table=",\n    ".join(blocks), lights=c_like_lights(tables.lights, "c", real, common),
        gibbs=", ".join(map(fmt, tables.gibbs)), lobe=", ".join(map(fmt, tables.lobe)),
        perez=", ".join("{" + ", ".join(map(fmt, row)) + "}" for row in PEREZ_Y),
        tan="tan" + suffix, exp="exp" + suffix, cos="cos" + suffix, sin="sin" + suffix, log="log" + suffix,
        fmod="fmod" + suffix, engine_tables=engine_tables, engine_function=engine_function,
    )


def _shader_source(tables: ExportTables, language: str, plan: EnginePlan | None) -> str:
    glsl = language == "glsl"
    vec3 = "vec3" if glsl else "float3"
    const = "const" if glsl else "static const"
    fmt = float32_literal

    def array(values: Any, kind: str = "float") -> str:
        items = [fmt(v) for v in values] if kind == "float" else list(values)
        return (f"{kind}[{len(items)}](" + ", ".join(items) + ")") if glsl else "{ " + ", ".join(items) + " }"

    rows = _stored_rows(tables)[1].transpose(1, 0, 2).reshape(-1, 3)  # ((i (DY + 1) + j) ROWS + r, c)
    triples = [f"{vec3}(" + ", ".join(fmt(v) for v in rgb) + ")" for rgb in rows]
    common = _common(tables, fmt, plan, language, vec3)
    engine_tables, engine_function = c_like_engine(language, plan, common, fmt)
    table_open, table_close = (f"{vec3}[{len(triples)}](", ")") if glsl else ("{", "}")
    return _SHADER.substitute(
        common,
        header_lines=_header(tables, language, "float32", "", plan).replace("\n", "\n// "),
        const=const, vec3=vec3, n_table=len(triples), open=table_open, close=table_close,
        table=text_rows(triples, "    ", _TRIPLES_PER_LINE), gibbs=array(tables.gibbs), lobe=array(tables.lobe),
        perez=array(PEREZ_Y.ravel()), mod="mod" if glsl else "fmod", engine_tables=engine_tables,
        engine_function=engine_function, lights=c_like_lights(tables.lights, language, common=common),
    )


def export_source(
    sky: runtime.SkySH, language: str, bands: int | None = None, real: str = "double", engine: str | None = None
) -> str:
    """
    Source text that evaluates the sky's SH coefficients in ``language``.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH` (its default colourspace, linear sRGB).
    language
        One of :data:`EXPORT_FORMATS`: ``"c"`` (a C99 header, ``sky_sh.h``, ``static const``
        tables and ``static inline`` functions, clean under ``-std=c99 -Wall -Wextra
        -pedantic``; link with ``-lm``), ``"glsl"`` / ``"hlsl"`` (float32), ``"json"`` (float64
        tables and the algorithm in words), ``"js"`` (an ES module, :mod:`skysh.export.js`).
    bands
        N in [1, the file's bands]: the export evaluates N bands (default 3). For ``"js"`` the
        most the module holds, a run-time option there (default all the file's).
    real
        C only: ``"double"`` (default) or ``"float"``.
    engine
        None, or one of :data:`skysh.engines.presets.ENGINES`: C, GLSL and HLSL gain
        ``skysh_engine_coefficients()`` returning that engine's numbers
        (:class:`skysh.export.tables.EnginePlan`), JSON the plan. Refused for ``"js"``,
        whose ``coefficients()`` takes every engine as an option.

    Returns
    -------
    str
        The text, ending with a newline.

    Raises
    ------
    ValueError
        Unknown language, ``real`` or engine; ``bands`` out of range or beyond the engine's.
    """
    check_choice(language, "language", EXPORT_FORMATS)
    check_choice(real, "real", C_REAL_TYPES)
    if language == "js":
        if engine is not None:
            raise ValueError("engine must be None for the js export (its coefficients() takes an engine option)")
        return export_js.module_source(sky, bands)
    tables = export_tables(sky, 3 if bands is None else bands)
    plan = None if engine is None else engine_plan(engine, tables.bands)
    if language == "c":
        return _c_source(tables, real, plan)
    if language == "json":
        return export_js.json_source(tables, plan)
    return _shader_source(tables, language, plan)
