"""
The JavaScript and JSON exports, and the engine plans every export shares
========================================================================

-   :func:`module_source`: a self-contained ES module (no dependencies, double
    precision) with the fitted tables and ``coefficients(sunZenith, turbidity,
    sunAzimuth = 0, options = {})``, the per-frame runtime for browser day-night
    cycles (``export.export_source(sky, "js")`` calls it).
-   :func:`declarations`, :func:`declarations_path`: the TypeScript declarations of that
    module and the file name TypeScript finds them under (``sky_sh.d.mts`` beside ``sky_sh.mjs``).
-   :func:`json_source`: the tables and the algorithm in words, for any other language.
-   :func:`engine_plan`, :class:`EnginePlan`: an engine's linear conversion
    (:func:`skysh.engines.engine_map`) split at the Z rotation (per-band factors
    folded before it, the rest after it), for every export.

The module computes what :mod:`skysh.export` documents step by step (the
runtime's algorithm, Habel 2008 eqs. 1, 4, 5) with everything static prepared
at load: the table holds every band the export was asked for (``bands`` is a
run-time option), the Gibbs and clamped-cosine factors of every band count, and
for every engine and band count it takes, the folded per-band factors and the
rest of the map as straight-line code. A call validates, fills preallocated
scratch arrays and allocates its result only (or none, given ``out``).

Options follow the Python runtime's defaults by intent: ``gibbs`` defaults to
``!irradiance`` and ``dering`` to ``irradiance``; ``irradianceTable`` (the runtime's
``irradiance_table``, :func:`skysh.export_js_parts.js_irradiance`) takes the certified
3-band irradiance table for diffuse light unless ``gibbs: true`` or ``dering: false``
is asked for, ``false`` gives the filtered, deringed sky. An engine implies the
diffuse intent (engines light with SH diffusely), so it defaults like irradiance
(the table's radiance-equivalent at 3 bands) and refuses ``irradiance: true`` (its
map already applies the engine's scaling).

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5).
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix.
"""

from __future__ import annotations

import json
import textwrap
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from string import Template
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import runtime, sh
from skysh._checks import interval_text
from skysh._version import __version__
from skysh.export import ExportTables, export_tables
from skysh.export_js_parts import DECLARATIONS, irradiance_json, js_dering, js_irradiance, js_lights, lights_json
from skysh.export_lights import ZENITH_CONSTANTS, double_literal, text_rows
from skysh.preetham import PEREZ_Y

__all__ = ["ENGINE_ZERO", "ENGINE_UNIT", "EnginePlan", "engine_plan", "module_source", "declarations", "declarations_path",
           "json_source"]

ENGINE_ZERO: float = 1e-13
"""Entries of an engine map smaller than this times its largest entry are rounding
residue of the engine's rotation matrices (exact zeros in closed form) and are
dropped; the change to an output is below 1e-13 of the largest term."""

ENGINE_UNIT: float = 1e-14
"""Entries within this of +-1 once the per-band factor is divided out are +-1 in closed form
(the engines' maps are signs, axis permutations, exact 90-degree rotations and band
constants, built numerically): they are written as additions, changing an output by
at most this relative amount."""



@dataclass(frozen=True)
class EnginePlan:
    """
    An engine's conversion (:func:`skysh.engines.engine_map`) arranged for the exports.

    ``engine_flat = matrix @ (band_factor[l] * radiance_flat) + offset``, where
    ``radiance_flat`` is the skysh radiance coefficients (N * N, 3) flattened
    coefficient-major (index 3 i + channel) and l the band of each column.

    Attributes
    ----------
    engine, bands
        The engine's name and N.
    band_factor
        (N,) per-band factors folded before the Z rotation (they commute with it):
        for each band the most common magnitude of its entries in the engine's
        map (for example A_l / pi times a basis constant), so that the most
        entries of ``matrix`` are +-1 (written as additions).
    matrix
        (P, N * N * 3): the rest of the map (frame change, signs, per-coefficient
        constants, packing), applied after the rotation; entries below
        :data:`ENGINE_ZERO` of the largest are exact zeros.
    offset
        (P,) constant terms of the engine's layout (for example a packed 1).
    shape, labels
        The engine's own array shape (row-major, product P) and the labels of its rows (first axis).
    """

    engine: str
    bands: int
    band_factor: NDArray[np.float64]
    matrix: NDArray[np.float64]
    offset: NDArray[np.float64]
    shape: tuple[int, ...]
    labels: tuple[str, ...]

    def terms(self, row: int) -> list[tuple[int, float]]:
        """The nonzero (column, value) pairs of ``matrix[row]``, columns ascending."""
        (columns,) = np.nonzero(self.matrix[row])
        return [(int(q), float(self.matrix[row, q])) for q in columns]

    def expression(self, row: int, value: Callable[[int], str], literal: Callable[[float], str]) -> str:
        """
        ``matrix[row] . v + offset[row]`` as source text: ``value(q)`` names v[q], ``literal`` writes a number.

        Coefficients +-1 become a bare addition or subtraction; zero terms are left out.
        """
        text = ""
        for q, v in self.terms(row):
            term = value(q) if abs(v) == 1.0 else f"{literal(abs(v))} * {value(q)}"
            text = f"{text} {'-' if v < 0.0 else '+'} {term}" if text else ("-" if v < 0.0 else "") + term
        bias = float(self.offset[row])
        if bias != 0.0:
            text = f"{text} {'-' if bias < 0.0 else '+'} {literal(abs(bias))}" if text else literal(bias)
        return text or literal(0.0)


def _most_common_magnitude(values: NDArray[np.float64]) -> float:
    """The magnitude shared by the most entries (12 significant digits decide equality), or 1 for none."""
    magnitudes = np.abs(values[values != 0.0])
    if magnitudes.size == 0:
        return 1.0
    keys = [f"{v:.11e}" for v in magnitudes]
    best, _ = Counter(keys).most_common(1)[0]  # ties: the first met, column order (deterministic)
    return float(magnitudes[keys.index(best)])


def engine_plan(engine: str, bands: int) -> EnginePlan:
    """
    An engine's conversion for ``bands`` bands, split at the Z rotation (see :class:`EnginePlan`).

    Parameters
    ----------
    engine
        One of :data:`skysh.engines.ENGINES`.
    bands
        N in [1, the engine's limit :data:`skysh.engines.ENGINE_MAX_BANDS`].

    Raises
    ------
    ValueError
        From :func:`skysh.engines.engine_map`: unknown engine (the valid names
        listed) or a band count the engine cannot take.
    """
    from skysh import (
        engines,  # imported on first use: exports without an engine never need it
    )

    emap = engines.engine_map(engine, bands)
    matrix = np.array(emap.matrix, dtype=np.float64)
    offset = np.array(emap.offset, dtype=np.float64).reshape(-1)
    n = int(emap.bands)
    if matrix.shape != (offset.size, n * n * 3):
        raise ValueError(f"engine_map({engine!r}, {bands}) has matrix {matrix.shape} and offset {offset.shape}")
    largest = float(np.abs(matrix).max(initial=0.0))
    matrix[np.abs(matrix) <= ENGINE_ZERO * largest] = 0.0
    band_of_column = np.repeat([sh.lm(i)[0] for i in range(n * n)], 3)
    factors = np.ones(n)
    for l in range(n):
        columns = band_of_column == l
        factor = _most_common_magnitude(matrix[:, columns])
        factors[l] = 1.0 if abs(factor - 1.0) <= ENGINE_UNIT else factor
        matrix[:, columns] /= factors[l]
    unit = np.abs(np.abs(matrix) - 1.0) <= ENGINE_UNIT
    matrix[unit] = np.sign(matrix[unit])
    for array in (factors, matrix, offset):
        array.flags.writeable = False
    return EnginePlan(
        engine=str(emap.engine), bands=n, band_factor=factors, matrix=matrix, offset=offset,
        shape=tuple(int(s) for s in emap.shape), labels=tuple(str(s) for s in emap.labels),
    )


_HEADER: str = '''\
/**
 * skysh $version: SH lighting of the Preetham sky (Habel et al. 2008) for the browser and node.
 * Generated by `skysh export --format js$options`; do not edit. A self-contained ES module,
 * double precision; TypeScript declarations in the .d.mts written beside it.
 *
 *   import { coefficients } from "./sky_sh.mjs";
 *   const sh = coefficients(sunZenith, turbidity, sunAzimuth, { irradiance: true });
 *
 * coefficients(sunZenith, turbidity, sunAzimuth = 0, options = {}) returns an array of
 * bands * bands * 3 numbers: coefficient i = l (l + 1) + m, then R, G, B (index 3 i + c).
 * Angles in radians: sun zenith $sun_zenith_domain, any finite azimuth (from +X towards +Y);
 * turbidity $turbidity_domain. Frame: Z up. Real orthonormal SH with the Condon-Shortley phase.
 * Linear sRGB, cd/m^2 (irradiance: cd/m^2 x sr, lux for the luminance). Same numbers as
 * skysh.SkySH.coefficients(sun_zenith, turbidity, sun_azimuth, bands, gibbs, dering, irradiance,
 * sun=..., ground_albedo=..., irradiance_table=...). sunLight(sunZenith, turbidity, sunAzimuth = 0)
 * returns the sun as a directional light, { direction: [x, y, z] towards it, rgb: lux }, as
 * skysh.SkySH.sun_light.
 *
 * options (a plain object, e.g. { irradiance: true }; not an array or a class instance; all optional):
 *   bands       1 .. $max_bands (default $default_bands).
 *   irradiance  false (default): radiance; true: irradiance (clamped-cosine convolution).
 *   gibbs       the zonal sinc filter (Habel eq. 5); default !irradiance, and false with an engine
 *               or the irradiance table.
 *   dering      window so the irradiance is never negative (Sloan 2017); default irradiance (or an
 *               engine) where this module carries deringing (bands: $dering_bands); never with the table.
 *   irradianceTable  the certified 3-band irradiance table (docs/irradiance.md: never negative, no
 *               deringing search) in place of the sky's rows: null (default) by intent, for irradiance
 *               or an engine at 3 bands unless gibbs is true or dering false; false: never (the
 *               filtered, deringed sky); true: always (radiance: its E_lm / A_l), refused with gibbs: true.
 *   sun         true: add the sun's disk, a delta windowed to a non-negative irradiance; default false.
 *   groundAlbedo a number or [r, g, b] in [0, 1]: a Lambertian ground lit by the sky (and sun); default 0.
 *   engine      the numbers the API of that engine takes: $engine_list
 *               (skysh.engines.convert of the radiance), flattened row-major, length from
 *               engineLayout(engine, bands); irradiance must then be false (the engine map
 *               applies the engine's own scaling). Defaults as for irradiance: engines light diffusely.
 *   out         an Array or Float64Array of the result's length to fill and return instead of a
 *               new Array (no allocation per frame).
 * Throws a RangeError naming the parameter for a value outside its domain, NaN or infinity
 * (and an unknown engine, listing the valid ones), a TypeError for a wrong type or option name.
 */
'''

_MODULE = Template('''\
$header
const MAX_BANDS = $max_bands;
const DEFAULT_BANDS = $default_bands;
const DX = $dx; // Chebyshev degree in x (sun zenith)
const DY = $dy; // Chebyshev degree in y (log turbidity)
const HALF3 = $half3; // 3 x table rows: stored (m >= 0) coefficients of MAX_BANDS bands (one band: and c_10)
const TERMS = (DX + 1) * (DY + 1);
const X_SCALE = $x_scale, X_SHIFT = $x_shift, Y_SCALE = $y_scale, Y_SHIFT = $y_shift;
const ZMIN = $zmin, ZMAX = $zmax, TMIN = $tmin, TMAX = $tmax;
const TWO_PI = $two_pi;

// TABLE[3 (r TERMS + i (DY + 1) + j) + c]: coefficient of T_i(x) T_j(y) for stored coefficient r
// (l = 0, 1, 1, 2, 2, 2, ... with m = 0 .. l) and channel c (R, G, B): the terms of one stored
// coefficient are contiguous, so its RGB is three dot products in one pass.
const TABLE = new Float64Array([
  $table
]);
// GIBBS[n (n - 1) / 2 + l] = sinc(pi l / n) (Habel eq. 5); LOBE[l] = A_l (clamped cosine).
const GIBBS = new Float64Array([$gibbs]);
const LOBE = new Float64Array([$lobe]);
// Perez A..E of luminance as (slope, intercept) in turbidity (Preetham 1999).
const PEREZ_Y = new Float64Array([$perez]);

// Engines: band = per-band factor folded before the rotation, apply = the rest of the
// engine's linear map (skysh.export_js.engine_plan), from radiance r into o.
const ENGINE_PLANS = new Map([
$engines
]);

// Scratch space, allocated once: a call allocates its result only.
const TX = new Float64Array(DX + 1);
const TY = new Float64Array(DY + 1);
const W = new Float64Array(TERMS); // T_i(x) T_j(y)
const ACC = new Float64Array(HALF3);
const RADIANCE = new Float64Array(MAX_BANDS * MAX_BANDS * 3);
const COS = new Float64Array(MAX_BANDS);
const SIN = new Float64Array(MAX_BANDS);
const C10 = new Float64Array(3); // the unfiltered sky's c_10 (the ground's E_h), apart from the table's rows
const OPTIONS = new Set(["bands", "gibbs", "irradiance", "dering", "irradianceTable", "sun", "groundAlbedo", "engine", "out"]);
$dering_defs$lights$irradiance
/** skysh's version that wrote this module. */
export const SKYSH_VERSION = $version;
/** Largest band count this module evaluates. */
export { MAX_BANDS };
/** Engine names the engine option takes. */
export const ENGINES = Object.freeze([$engine_names]);
/** Fitted domain: sun zenith [min, max] in radians and turbidity [min, max]. */
export const SUN_ZENITH_DOMAIN = Object.freeze([ZMIN, ZMAX]);
export const TURBIDITY_DOMAIN = Object.freeze([TMIN, TMAX]);

function describe(value) {
  return typeof value === "string" ? JSON.stringify(value) : String(value);
}

function number(value, name) {
  if (typeof value !== "number") throw new TypeError(`$${name} must be a number, got $${describe(value)}`);
  return value;
}

function flag(value, name, fallback) {
  if (value === undefined) return fallback;
  if (typeof value !== "boolean") throw new TypeError(`$${name} must be true or false, got $${describe(value)}`);
  return value;
}

/** Refuse a frame outside the fitted domain, naming the parameter. */
function checkFrame(sunZenith, turbidity, sunAzimuth) {
  if (!(number(sunZenith, "sunZenith") >= ZMIN && sunZenith <= ZMAX)) {
    throw new RangeError(`sunZenith must lie in [$${ZMIN}, $${ZMAX}] rad (the fitted domain), got $${sunZenith}`);
  }
  if (!(number(turbidity, "turbidity") >= TMIN && turbidity <= TMAX)) {
    throw new RangeError(`turbidity must lie in [$${TMIN}, $${TMAX}] (the fitted domain), got $${turbidity}`);
  }
  if (!Number.isFinite(number(sunAzimuth, "sunAzimuth"))) {
    throw new RangeError(`sunAzimuth must be finite (radians), got $${sunAzimuth}`);
  }
}

function enginePlans(engine) {
  const plans = ENGINE_PLANS.get(engine);
  if (plans === undefined) {
    throw new RangeError(`engine must be one of $${ENGINES.map((e) => JSON.stringify(e)).join(", ")}, got $${describe(engine)}`);
  }
  return plans;
}

function checkBands(bands, plans, engine) {
  const high = plans === null ? MAX_BANDS : plans.length - 1;
  if (!Number.isInteger(bands) || bands < 1 || bands > high || (plans !== null && plans[bands] === null)) {
    const which = plans === null ? "" : ` for engine $${JSON.stringify(engine)} (the bands it takes: $${plans.map((p, n) => (p ? n : 0)).filter((n) => n).join(", ")})`;
    throw new RangeError(`bands must be an integer in [1, $${high}]$${which}, got $${describe(bands)}`);
  }
  return bands;
}

/** Y_z / F_Y(0, ts): the sky's luminance scale, cd/m^2 (Preetham 1999, appendix). */
function luminanceScale(ts, t) {
  const chi = ($c4_9 - t / 120.0) * (Math.PI - 2.0 * ts);
  const yz = 1000.0 * (($c40453 * t - $c49710) * Math.tan(chi) - $c02155 * t + $c24192);
  const ct = Math.cos(ts);
  const f = (1.0 + (PEREZ_Y[0] * t + PEREZ_Y[1]) * Math.exp(PEREZ_Y[2] * t + PEREZ_Y[3]))
    * (1.0 + (PEREZ_Y[4] * t + PEREZ_Y[5]) * Math.exp((PEREZ_Y[6] * t + PEREZ_Y[7]) * ts)
      + (PEREZ_Y[8] * t + PEREZ_Y[9]) * ct * ct);
  return yz / f;
}

/** Chebyshev T_0, T_1, ... at x and at y, each clamped to [-1, 1], into the whole of tx and ty. */
function chebyshev(x, y, tx, ty) {
  x = x < -1.0 ? -1.0 : x > 1.0 ? 1.0 : x;
  y = y < -1.0 ? -1.0 : y > 1.0 ? 1.0 : y;
  tx[0] = 1.0;
  ty[0] = 1.0;
  for (let i = 1; i < tx.length; i++) tx[i] = i === 1 ? x : 2.0 * x * tx[i - 1] - tx[i - 2];
  for (let j = 1; j < ty.length; j++) ty[j] = j === 1 ? y : 2.0 * y * ty[j - 1] - ty[j - 2];
}

/** Habel eq. (1) at the frame's W: the first h3 / 3 rows of the table rows (laid out as TABLE) into ACC. */
function rowSums(rows, h3) {
  for (let k = 0, b = 0; k < h3; k += 3) { // six independent sums (latency)
    let r0 = 0.0, g0 = 0.0, b0 = 0.0, r1 = 0.0, g1 = 0.0, b1 = 0.0, q = 0;
    for (; q + 1 < TERMS; q += 2, b += 6) {
      const w0 = W[q], w1 = W[q + 1];
      r0 += w0 * rows[b];
      g0 += w0 * rows[b + 1];
      b0 += w0 * rows[b + 2];
      r1 += w1 * rows[b + 3];
      g1 += w1 * rows[b + 4];
      b1 += w1 * rows[b + 5];
    }
    if (q < TERMS) {
      const w0 = W[q];
      r0 += w0 * rows[b];
      g0 += w0 * rows[b + 1];
      b0 += w0 * rows[b + 2];
      b += 3;
    }
    ACC[k] = r0 + r1;
    ACC[k + 1] = g0 + g1;
    ACC[k + 2] = b0 + b1;
  }
}

/** Radiance coefficients of n bands into o (coefficient-major RGB), band l times factor[l]; returns the
 * luminance scale. The rows from TABLE, or with table the certified IRRADIANCE's; C10 the sky's c_10. */
function evaluate(ts, t, phi, n, gibbs, factor, o, table) {
  chebyshev(ts * X_SCALE - X_SHIFT, Math.log(t) * Y_SCALE - Y_SHIFT, TX, TY);
  for (let i = 0, q = 0; i <= DX; i++) {
    const xi = TX[i];
    for (let j = 0; j <= DY; j++, q++) W[q] = xi * TY[j];
  }
  rowSums(TABLE, n > 1 && !table ? ((n * (n + 1)) / 2) * 3 : 6); // one band or the table: row 1 too (c_10)
  C10[0] = ACC[3];
  C10[1] = ACC[4];
  C10[2] = ACC[5];
  if (table) rowSums(IRRADIANCE, 18); // 3 bands: the table's 6 rows in place of the sky's
  const scale = luminanceScale(ts, t);
  const c1 = Math.cos(phi), s1 = Math.sin(phi);
  COS[0] = 1.0;
  SIN[0] = 0.0;
  for (let m = 1; m < n; m++) { // angle addition
    COS[m] = COS[m - 1] * c1 - SIN[m - 1] * s1;
    SIN[m] = SIN[m - 1] * c1 + COS[m - 1] * s1;
  }
  const g = (n * (n - 1)) / 2;
  for (let l = 0; l < n; l++) {
    const band = factor === null ? scale : scale * factor[l];
    const row = ((l * (l + 1)) / 2) * 3;
    const centre = l * (l + 1) * 3;
    const zonal = gibbs ? band * GIBBS[g + l] : band;
    o[centre] = ACC[row] * zonal;
    o[centre + 1] = ACC[row + 1] * zonal;
    o[centre + 2] = ACC[row + 2] * zonal;
    for (let k = 1; k <= l; k++) { // Habel eq. (4): m = +k takes cos(k phi), m = -k sin(k phi)
      const src = row + 3 * k, plus = centre + 3 * k, minus = centre - 3 * k;
      const cp = COS[k] * band, sp = SIN[k] * band;
      o[plus] = ACC[src] * cp;
      o[plus + 1] = ACC[src + 1] * cp;
      o[plus + 2] = ACC[src + 2] * cp;
      o[minus] = ACC[src] * sp;
      o[minus + 1] = ACC[src + 1] * sp;
      o[minus + 2] = ACC[src + 2] * sp;
    }
  }
  return scale;
}

/** Multiply band l of the n-band coefficients o by factor[l]. */
function scaleBands(o, n, factor) {
  for (let l = 0; l < n; l++) {
    const f = factor[l];
    for (let k = l * l * 3; k < (l + 1) * (l + 1) * 3; k++) o[k] *= f;
  }
}

/**
 * The sky's SH coefficients for one frame (see the header). Throws a RangeError naming
 * the parameter for a value outside its domain, NaN or infinity, a TypeError for a
 * value of the wrong type or an unknown option.
 */
export function coefficients(sunZenith, turbidity, sunAzimuth = 0, options = {}) {
  checkFrame(sunZenith, turbidity, sunAzimuth);
  const proto = options === null || typeof options !== "object" ? undefined : Object.getPrototypeOf(options);
  if (proto === undefined || (proto !== null && Object.getPrototypeOf(proto) !== null)) { // a plain object only
    const what = Array.isArray(options) ? "an array" : proto === undefined ? describe(options) : `an instance of $${proto.constructor?.name ?? "a class"}`;
    throw new TypeError(`options must be a plain object ({ bands, irradiance, ... }), got $${what}`);
  }
  for (const key in options) {
    if (!OPTIONS.has(key)) throw new TypeError(`unknown option $${JSON.stringify(key)}; the options are $${[...OPTIONS].join(", ")}`);
  }
  const engine = options.engine ?? null;
  const plans = engine === null ? null : enginePlans(engine);
  const bands = checkBands(options.bands ?? DEFAULT_BANDS, plans, engine);
  const irradiance = flag(options.irradiance, "irradiance", false);
  if (irradiance && plans !== null) {
    throw new RangeError("irradiance must be false with an engine: the engine map takes radiance and applies the engine's own scaling");
  }
  const diffuse = irradiance || plans !== null; // the intent: diffuse lighting
  const gibbsGiven = flag(options.gibbs, "gibbs", null), deringGiven = flag(options.dering, "dering", null);
  const table = useTable(options.irradianceTable ?? null, bands, diffuse, gibbsGiven, deringGiven);
  const gibbs = gibbsGiven ?? !(diffuse || table);
  const dering = !table && (deringGiven ?? (diffuse && DERING_BANDS.includes(bands))); // the table: never
  if (dering && !DERING_BANDS.includes(bands)) {
    throw new RangeError(`dering is available for bands $${DERING_BANDS.join(", ") || "(none in this module)"}, got bands $${bands}`);
  }
  const sun = flag(options.sun, "sun", false);
  if (sun && (LIGHTS & 1) === 0) throw new RangeError("sun needs the coefficient file's sun table: this module has none");
  const albedo = albedoOption(options.groundAlbedo);
  const post = dering || sun || albedo !== null; // the per-band factor then follows the dering and the lights
  const plan = plans === null ? null : plans[bands];
  const count = plan === null ? bands * bands * 3 : plan.count;
  let out = options.out;
  if (out === undefined) {
    out = new Array(count); // a plain array: a small Float64Array costs more to allocate than the sky
  } else if (!(Array.isArray(out) || out instanceof Float64Array) || out.length !== count) {
    throw new TypeError(`out must be an Array or Float64Array of length $${count}, got $${describe(out)}`);
  }
  const phi = sunAzimuth % TWO_PI; // exact, as the Python runtime's math.fmod
  const factor = plan !== null ? plan.band : irradiance ? LOBE : null;
  const scale = evaluate(sunZenith, turbidity, phi, bands, gibbs, post ? null : factor, RADIANCE, table);
  if (dering) deringInPlace(RADIANCE, bands);
  if (sun || albedo !== null) addLights(sunZenith, turbidity, bands, gibbs, sun, albedo, scale, RADIANCE);
  if (post && factor !== null) scaleBands(RADIANCE, bands, factor);
  if (plan !== null) {
    plan.apply(RADIANCE, out);
  } else {
    for (let k = 0; k < count; k++) out[k] = RADIANCE[k];
  }
  return out;
}

/** The engine's array shape (row-major) and the labels of its rows, for `bands` bands. */
export function engineLayout(engine, bands = DEFAULT_BANDS) {
  const plans = enginePlans(engine);
  const plan = plans[checkBands(bands, plans, engine)];
  return { shape: plan.shape, labels: plan.labels };
}
''')

def json_source(tables: ExportTables, plan: EnginePlan | None = None) -> str:
    """The JSON export: float64 tables, constants and the algorithm in words (and ``plan``, if given)."""
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
            "acc[r][c] = sum_ij T_i(x) T_j(y) table[i][j][r][c] (with the certified irradiance table, by the rule of "
            "the block irradiance_table: its table in place of table)",
            "if gibbs: acc[r] *= gibbs[l] for the rows with m = 0",
            "acc *= luminance_scale(sun_zenith, turbidity)",
            "phi = fmod(sun_azimuth, 2 pi); out[l(l+1)+m] = acc[l(l+1)/2+|m|] * (cos(m phi) if m >= 0 else sin(|m| phi))",
            "if dering (3 bands, not with the irradiance table): the least window of skysh.dering.dering that keeps "
            "the irradiance non-negative, on the radiance",
            "then the sun and the ground when asked (the blocks sun and ground), on the radiance",
            "if irradiance: out[l(l+1)+m] *= lobe[l]",
        ],
        "units": "cd/m^2 (irradiance: cd/m^2*sr)",
        "colourspace": "sRGB (linear, Rec. 709 primaries, D65)",
        "convention": "Z up, azimuth from +X towards +Y, real orthonormal SH with the Condon-Shortley phase, "
        "index l(l+1)+m (docs/conventions.md)",
    }
    payload.update(lights_json(tables.lights))
    payload.update(irradiance_json(tables.irradiance if tables.bands == 3 else None))
    if plan is not None:
        payload["engine"] = {
            "name": plan.engine, "shape": list(plan.shape), "labels": list(plan.labels),
            "band_factor": plan.band_factor.tolist(), "matrix": plan.matrix.tolist(), "offset": plan.offset.tolist(),
            "algorithm": "engine values (flattened row-major to shape) = matrix @ v + offset, v = the radiance "
            "coefficients (no irradiance; by intent from the irradiance table, engines lighting diffusely) with band l "
            "times band_factor[l], flattened coefficient-major (3 i + c)",
        }
    return json.dumps(payload, indent=1) + "\n"


def _engine_plans(bands: int) -> dict[str, list[EnginePlan | None]]:
    """For every engine, its plan for each band count 1 .. ``bands`` it takes (None where it refuses)."""
    from skysh import engines

    plans: dict[str, list[EnginePlan | None]] = {}
    for name in engines.ENGINES:
        row: list[EnginePlan | None] = [None]
        for n in range(1, bands + 1):
            try:
                row.append(engine_plan(name, n))
            except ValueError:
                row.append(None)
        while row[-1] is None and len(row) > 1:
            row.pop()
        if len(row) > 1:
            plans[name] = row
    return plans


def _numbers(values: NDArray[np.float64], indent: str) -> str:
    return text_rows([double_literal(v) for v in np.ravel(values)], indent)


def _js_plan(plan: EnginePlan) -> str:
    """One band count of one engine as a JS object literal: count, shape, labels, band, apply."""
    lines = [f"o[{p}] = {plan.expression(p, lambda q: f'r[{q}]', double_literal)};" for p in range(plan.offset.size)]
    return (
        f"{{ count: {plan.offset.size}, shape: Object.freeze({json.dumps(list(plan.shape))}), "
        f"labels: Object.freeze({json.dumps(list(plan.labels))}),\n"
        f"      band: new Float64Array([{_numbers(plan.band_factor, '')}]),\n"
        "      apply(r, o) {\n        " + "\n        ".join(lines) + "\n      } }"
    )


def _js_engines(plans: dict[str, list[EnginePlan | None]]) -> str:
    entries = []
    for name, row in plans.items():
        items = ",\n    ".join("null" if p is None else _js_plan(p) for p in row)
        entries.append(f"  [{json.dumps(name)}, [\n    {items},\n  ]],")
    return "\n".join(entries)


def _options_text(bands: int, sky: runtime.SkySH) -> str:
    return "" if bands == sky.bands else f" --bands {bands}"


def module_source(sky: runtime.SkySH, bands: int | None = None) -> str:
    """
    The ES module (``sky_sh.mjs``): tables, engine plans and ``coefficients()``.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`.
    bands
        The largest band count the module evaluates, in [1, the file's bands];
        None (default) for all of them (7 in the shipped file). The table
        grows with it (about 200 KB of text for 7 bands).

    Returns JavaScript source ending with a newline (its header documents the API); raises a
    ValueError for ``bands`` out of range (see :func:`skysh.export.export_tables`).
    """
    tables = export_tables(sky, sky.bands if bands is None else bands)
    n = tables.bands
    plans = _engine_plans(n)
    dering = js_dering(n)
    names = textwrap.fill(", ".join(json.dumps(e) for e in plans) or "none in this module", width=90,
                          initial_indent=" " * 60, subsequent_indent=" *               ").strip()
    default = min(3, n)
    header = Template(_HEADER).substitute(
        version=__version__, options=_options_text(n, sky), max_bands=n, default_bands=default,
        dering_bands=", ".join(map(str, dering[0])) or "none", engine_list=names,
        sun_zenith_domain=interval_text(*tables.sun_zenith_domain, pi=True),
        turbidity_domain=interval_text(*tables.turbidity_domain),
    )
    gibbs = np.concatenate([runtime.gibbs_factors(k) for k in range(1, n + 1)])
    constants = {k: double_literal(v) for k, v in ZENITH_CONSTANTS.items()}
    rows = tables.table.reshape(-1, tables.table.shape[2], 3).transpose(1, 0, 2)  # (r, terms, c)
    if n == 1:  # the unfiltered c_10 as row 1, for the ground (stored row 1 from two bands on)
        rows = np.concatenate([rows, tables.lights.c10.reshape(1, -1, 3)])
    return _MODULE.substitute(
        constants,
        header=header, max_bands=n, default_bands=default, dx=tables.degrees[0], dy=tables.degrees[1],
        half3=rows.shape[0] * 3, lights=js_lights(tables.lights), irradiance=js_irradiance(tables.irradiance),
        x_scale=double_literal(tables.x_scale), x_shift=double_literal(tables.x_shift),
        y_scale=double_literal(tables.y_scale), y_shift=double_literal(tables.y_shift),
        zmin=double_literal(tables.sun_zenith_domain[0]), zmax=double_literal(tables.sun_zenith_domain[1]),
        tmin=double_literal(tables.turbidity_domain[0]), tmax=double_literal(tables.turbidity_domain[1]),
        table=_numbers(rows, "  "),
        gibbs=_numbers(gibbs, ""), lobe=_numbers(tables.lobe, ""),
        perez=_numbers(PEREZ_Y, ""), engines=_js_engines(plans), dering_defs=dering[1],
        version=json.dumps(__version__), engine_names=", ".join(json.dumps(e) for e in plans),
    )


def declarations(sky: runtime.SkySH, bands: int | None = None) -> str:
    """
    TypeScript declarations of :func:`module_source` with the same arguments.

    Save them under :func:`declarations_path` of the module's path (``sky_sh.d.mts``
    beside ``sky_sh.mjs``): the name TypeScript looks for.

    Raises
    ------
    ValueError
        ``bands`` out of range.
    """
    tables = export_tables(sky, sky.bands if bands is None else bands)
    n = tables.bands
    names = list(_engine_plans(n))
    return DECLARATIONS.substitute(
        version=__version__, options=_options_text(n, sky), max_bands=n, default_bands=min(3, n),
        engine_union=" | ".join(json.dumps(e) for e in names) or "never",
        turbidity_domain=interval_text(*tables.turbidity_domain),
    )


def declarations_path(module_path: Path) -> Path:
    """Where TypeScript finds the declarations of a module at ``module_path``: ``sky.mjs`` -> ``sky.d.mts``
    (an ``.mjs`` import resolves to ``.d.mts`` only, whatever the module resolution), else ``sky.d.ts``."""
    path = Path(module_path)
    stem = path.name[: -len(path.suffix)] if path.suffix else path.name
    return path.with_name(stem + (".d.mts" if path.suffix == ".mjs" else ".d.ts"))
