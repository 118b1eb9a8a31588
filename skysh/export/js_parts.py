"""
The JavaScript and JSON pieces of the exports: the sun, the ground, deringing, the irradiance table
===================================================================================================

:func:`skysh.export.js.module_source` (the ES module) and :func:`skysh.export.js.json_source`
(the JSON export) are built from these, as :mod:`skysh.export.c_like` is from :mod:`skysh.export.lights`:

-   :func:`js_lights`: the sun's and the ground's tables, ``sunRgb``, ``addLights``,
    ``albedoOption`` and ``sunLight``; :func:`lights_json`: the JSON's ``sun`` and ``ground`` blocks.
-   :func:`js_dering`: the runtime's 3-band deringing (:mod:`skysh.export.dering`).
-   :func:`js_irradiance`: the certified irradiance table (``docs/irradiance.md``) and
    ``useTable``, the runtime's ``irradiance_table`` rule; :func:`irradiance_json`: its JSON block.
-   :data:`DECLARATIONS`: the TypeScript declarations' template (:func:`skysh.export.js.declarations`).

What the generated JavaScript computes is :mod:`skysh.export.lights`' list (the sun, the
ground, then the per-band factor) and, with the table, its rows in place of the sky's
(the runtime's order: :meth:`skysh.SkySH.coefficients`).

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: the sun's light.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000).
"""

from __future__ import annotations

from string import Template
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from skysh.export.lights import LightTables, double_literal, embed_table, light_flags

__all__ = ["DECLARATIONS", "js_lights", "lights_json", "js_dering", "js_irradiance", "irradiance_json"]

def js_dering(bands: int) -> tuple[tuple[int, ...], str]:
    """
    (band counts with deringing, JS definitions of ``DERING_BANDS`` and ``deringInPlace(c, n)``).

    The runtime's 3-band deringing (:func:`skysh.export.dering.dering_source`, Sloan 2017) on
    the flat radiance ``c``; other band counts have none (``dering: true`` is refused there).
    """
    if bands < 3:
        return (), (
            "const DERING_BANDS = Object.freeze([]); // deringing: 3 bands only\n"
            "function deringInPlace(c, n) { throw new RangeError(`dering is not available for bands ${n}`); }\n"
        )
    from skysh.export import dering as export_dering

    return (3,), export_dering.dering_source("js", target="irradiance", name="skysh_dering3") + """\
const DERING_BANDS = Object.freeze([3]);
const DERING_C = [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0]];
const DERING_WINDOW = [1, 1, 1];
/** Window the 3-band radiance c (flat, coefficient-major RGB) in place, as the runtime's dering. */
function deringInPlace(c, n) {
  for (let k = 0; k < 27; k++) DERING_C[(k / 3) | 0][k % 3] = c[k];
  skysh_dering3(DERING_C, DERING_WINDOW);
  for (let k = 0; k < 27; k++) c[k] = DERING_C[(k / 3) | 0][k % 3];
}
"""


_JS = Template("""
// The sun and the ground (skysh.export.js_parts): the sun's ln XYZ table, XYZ -> RGB, the sun's SH at
// azimuth 0 as a trigonometric polynomial (unwindowed) and every band count's window, the ground's factors.
const SUN_DX = $sdx, SUN_DY = $sdy, LIGHTS = $flags; // LIGHTS: 1 the sun is available, 2 the ground
const AM_A = $am_a, AM_B = $am_b, AM_NEG_C = $am_neg_c, DEG = $deg; // Kasten 1966
const M0 = $m0, SX_SCALE = $sx_scale, SUN_TMIN = $sun_tmin, SY_SCALE = $sy_scale;
const HF = $hf, INV_PI = $inv_pi, SUN_CLAMP = $clamp;
$tables
const SUN_X = new Float64Array(SUN_DX + 1);
const SUN_Y = new Float64Array(SUN_DY + 1);
const LIGHT_RGB = new Float64Array(3);
const GROUND_L = new Float64Array(3);
const TRIG = new Float64Array(2 * MAX_BANDS);

/** The sun's RGB direct normal illuminance (lux) into rgb (Preetham 1999 appendix, fitted). */
function sunRgb(ts, t, rgb) {
  const m = 1.0 / (Math.cos(ts) + AM_A * Math.pow(AM_B - ts * DEG, AM_NEG_C)); // Kasten 1966
  chebyshev((m - M0) * SX_SCALE - 1.0, (t - SUN_TMIN) * SY_SCALE - 1.0, SUN_X, SUN_Y);
  let l0 = 0.0, l1 = 0.0, l2 = 0.0;
  for (let i = 0, b = 0; i <= SUN_DX; i++) {
    for (let j = 0; j <= SUN_DY; j++, b += 3) {
      const w = SUN_X[i] * SUN_Y[j];
      l0 += w * SUN_TABLE[b];
      l1 += w * SUN_TABLE[b + 1];
      l2 += w * SUN_TABLE[b + 2];
    }
  }
  const e0 = Math.exp(l0), e1 = Math.exp(l1), e2 = Math.exp(l2);
  for (let c = 0; c < 3; c++) rgb[c] = SUN_RGB[3 * c] * e0 + SUN_RGB[3 * c + 1] * e1 + SUN_RGB[3 * c + 2] * e2;
}

/** Add the ground (albedo or null) and the sun to the rotated n-band radiance o; scale: the luminance scale. */
function addLights(ts, t, n, gibbs, sun, albedo, scale, o) {
  LIGHT_RGB.fill(0.0);
  if (sun) sunRgb(ts, t, LIGHT_RGB);
  if (albedo !== null) { // E_sky = sqrt(4 pi / 3) c_10 of the unfiltered sky: C10 x scale
    const ct = Math.cos(ts), g0 = (n * (n - 1)) / 2;
    for (let c = 0; c < 3; c++) GROUND_L[c] = albedo[c] * (HF * scale * C10[c] + ct * LIGHT_RGB[c]) * INV_PI;
    for (let l = 0; l < n; l++) {
      const g = gibbs ? GROUND[l] * GIBBS[g0 + l] : GROUND[l], i3 = l * (l + 1) * 3;
      for (let c = 0; c < 3; c++) o[i3 + c] += g * GROUND_L[c];
    }
  }
  if (!sun) return;
  for (let k = 0; k < n; k++) {
    TRIG[k] = Math.cos(k * ts);
    TRIG[n + k] = Math.sin(k * ts);
  }
  for (let c = 0; c < 3; c++) if (!(LIGHT_RGB[c] > SUN_CLAMP)) LIGHT_RGB[c] = SUN_CLAMP;
  const w0 = (n * (n - 1)) / 2, width = 2 * MAX_BANDS;
  for (let l = 0; l < n; l++) {
    for (let m = -l; m <= l; m++) {
      const k = m < 0 ? -m : m, r = ((l * (l + 1)) / 2 + k) * width;
      let y = 0.0;
      for (let q = 0; q < n; q++) y += SUN_TRIG[r + q] * TRIG[q] + SUN_TRIG[r + MAX_BANDS + q] * TRIG[n + q];
      y *= SUN_WINDOWS[w0 + l] * (m < 0 ? SIN[k] : COS[k]);
      const i3 = (l * (l + 1) + m) * 3;
      for (let c = 0; c < 3; c++) o[i3 + c] += y * LIGHT_RGB[c];
    }
  }
}

/** The groundAlbedo option: null (black) or three numbers in [0, 1]. */
function albedoOption(value) {
  if (value === undefined || value === 0) return null;
  const rgb = typeof value === "number" ? [value, value, value] : value;
  if (!(Array.isArray(rgb) || rgb instanceof Float64Array) || rgb.length !== 3 || rgb.some((v) => typeof v !== "number")) {
    throw new TypeError(`groundAlbedo must be a number or an array of 3 numbers, got $${describe(value)}`);
  }
  if (!rgb.every((v) => v >= 0.0 && v <= 1.0)) {
    throw new RangeError(`groundAlbedo must lie in [0, 1] per channel, got $${Array.from(rgb).join(", ")}`);
  }
  if ((LIGHTS & 2) === 0) throw new RangeError("groundAlbedo needs the sky's c_10: this module's file has 1 band");
  return rgb.every((v) => v === 0.0) ? null : rgb;
}

/**
 * The sun as a directional light (skysh.SkySH.sun_light): direction, the unit vector towards it
 * (Z up), and rgb, its direct normal illuminance in lux per channel (linear sRGB, unclamped).
 */
export function sunLight(sunZenith, turbidity, sunAzimuth = 0) {
  checkFrame(sunZenith, turbidity, sunAzimuth);
  if ((LIGHTS & 1) === 0) throw new RangeError("the sun needs the coefficient file's sun table: this module has none");
  const rgb = [0.0, 0.0, 0.0], phi = sunAzimuth % TWO_PI, s = Math.sin(sunZenith);
  sunRgb(sunZenith, turbidity, rgb);
  return { direction: [s * Math.cos(phi), s * Math.sin(phi), Math.cos(sunZenith)], rgb };
}
""")


def js_lights(tables: LightTables) -> str:
    """The JavaScript of the lights: tables, ``sunRgb``, ``addLights``, ``albedoOption`` and ``sunLight``.

    Uses the module's ``MAX_BANDS``, ``C10``, ``GIBBS``, ``COS``, ``SIN``, ``TWO_PI``, ``describe``,
    ``chebyshev`` and ``checkFrame``; ``MAX_BANDS`` must be ``tables.bands``.
    """
    code = "".join(embed_table("js", name, values) for name, values in (
        ("SUN_TABLE", tables.sun_table), ("SUN_RGB", tables.rgb_from_xyz), ("SUN_TRIG", tables.trig),
        ("SUN_WINDOWS", tables.windows), ("GROUND", tables.ground_zonal),
    ))
    numbers = {key: double_literal(value) for key, value in tables.constants.items()}
    return _JS.substitute(numbers, sdx=tables.sun_degrees[0], sdy=tables.sun_degrees[1], flags=light_flags(tables),
                          tables=code)


def lights_json(tables: LightTables) -> dict[str, Any]:
    """The JSON export's ``sun`` and ``ground`` blocks: float64 tables and the algorithm in words."""
    c = tables.constants
    return {
        "sun": {
            "available": tables.has_sun, "degrees": list(tables.sun_degrees), "table": tables.sun_table.tolist(),
            "table_layout": "[i][j][c]: coefficient of T_i(x) T_j(y) of ln X, ln Y, ln Z (ln lux)",
            "rgb_from_xyz": tables.rgb_from_xyz.tolist(),
            "air_mass": {"a": c["am_a"], "b": c["am_b"], "c": -c["am_neg_c"], "m0": c["m0"], "x_scale": c["sx_scale"]},
            "turbidity": {"min": c["sun_tmin"], "y_scale": c["sy_scale"]},
            "trig": tables.windowed_trig().tolist(),
            "trig_layout": "[r][q]: the sun's windowed SH at azimuth 0 of stored coefficient r (half_layout), over "
            "cos(q ts) for q < N, then sin((q - N) ts)",
            "clamp": c["clamp"],
            "algorithm": [
                "m = 1 / (cos(ts) + a (b - degrees(ts))^-c); x = clamp((m - m0) * x_scale - 1, -1, 1)",
                "y = clamp((turbidity - min) * y_scale - 1, -1, 1)",
                "ln[c] = sum_ij T_i(x) T_j(y) table[i][j][c]; rgb = rgb_from_xyz @ exp(ln): lux (sun_light)",
                "with sun: ybar[r] = sum_q trig[r][q] (cos(q ts), then sin(q ts)); out[l(l+1)+m] += ybar[l(l+1)/2+|m|] "
                "* (cos(m phi) if m >= 0 else sin(|m| phi)) * max(rgb, clamp), after the dering, before the lobe",
            ],
        },
        "ground": {
            "available": tables.has_ground, "zonal": tables.ground_zonal.tolist(),
            "c10_table": tables.c10.tolist(), "horizontal_factor": c["hf"],
            "algorithm": [
                "e_sky = horizontal_factor * luminance_scale * sum_ij T_i(x) T_j(y) c10_table[i][j] (unfiltered)",
                "L = albedo * (e_sky + (rgb * cos(ts) with sun, else 0)) / pi",
                "out[l(l+1)] += zonal[l] * (gibbs[l] if gibbs else 1) * L, after the dering, before the lobe",
            ],
        },
    }


# --------------------------------------------------------------------------- #
# The certified irradiance table (docs/irradiance.md)
# --------------------------------------------------------------------------- #
_USE_TABLE = """
// The certified irradiance table (docs/irradiance.md): the radiance-equivalent E_lm / A_l of 3 bands over the
// luminance scale, m >= 0 rows, laid out as TABLE (at its TERMS); IRRADIANCE_TABLE: whether this module has it.
const IRRADIANCE_TABLE = $available;
$table
/**
 * The irradianceTable option (skysh.SkySH.coefficients' irradiance_table): whether the sky's rows come from the
 * table. null (default): by intent, for diffuse light (irradiance, or an engine) at 3 bands unless gibbs is true or
 * dering false; false: never (the filtered, deringed sky); true: always (refused without the table, at other band
 * counts, or with gibbs: true). gibbs and dering: the options as given (null when absent).
 */
function useTable(choice, bands, diffuse, gibbs, dering) {
  if (choice === null) return IRRADIANCE_TABLE && diffuse && bands === 3 && gibbs !== true && dering !== false;
  if (!flag(choice, "irradianceTable", false)) return false;
  if (!IRRADIANCE_TABLE) {
    throw new RangeError("irradianceTable: true needs the coefficient file's irradiance table: this module has none");
  }
  if (bands !== 3) throw new RangeError(`irradianceTable: true needs bands 3 (the table's), got bands $${bands}`);
  if (gibbs === true) {
    throw new RangeError("irradianceTable: true does not go with gibbs: true (the table is not a filtered sky)");
  }
  return true;
}
"""
"""The JavaScript of the table (``$available``, ``$table``): ``useTable`` and its numbers."""


def js_irradiance(table: ArrayLike | None) -> str:
    """
    The JavaScript of the certified irradiance table: ``IRRADIANCE_TABLE``, ``IRRADIANCE`` and ``useTable``.

    Parameters
    ----------
    table
        (DX + 1, DY + 1, 6, 3): the table's rows at the module's degrees
        (:attr:`skysh.export.tables.ExportTables.irradiance`), or None (a module of fewer than 3
        bands or a file without it: ``irradianceTable: true`` is refused, "by intent" is the sky).

    Uses the module's ``flag``; ``IRRADIANCE[3 (r TERMS + i (DY + 1) + j) + c]`` as ``TABLE``.
    """
    if table is None:
        code = "const IRRADIANCE = new Float64Array(0);\n"
    else:
        rows = np.asarray(table, dtype=np.float64)
        code = embed_table("js", "IRRADIANCE", rows.reshape(-1, rows.shape[2], 3).transpose(1, 0, 2))
    return Template(_USE_TABLE).substitute(available="true" if table is not None else "false", table=code)


def irradiance_json(table: ArrayLike | None) -> dict[str, Any]:
    """The JSON export's ``irradiance_table`` block: the table (float64; None: ``available`` false) and its rule in words."""
    block: dict[str, Any] = {
        "available": table is not None,
        "rule": "irradiance_table as skysh.SkySH.coefficients: null (default) = by intent: the table for diffuse light "
        "(irradiance, or an engine) with bands == 3, gibbs not true and dering not false; false = never; true = always "
        "(refused without the table or with gibbs true)",
    }
    if table is None:
        return {"irradiance_table": block}
    block.update({
        "table": np.asarray(table, dtype=np.float64).tolist(),
        "table_layout": "[i][j][r][c] as table: the certified 3-band irradiance's radiance-equivalent E_lm / A_l over "
        "the luminance scale (docs/irradiance.md), r over half_layout (m >= 0), never negative as irradiance",
        "algorithm": [
            "with the table: acc[r][c] = sum_ij T_i(x) T_j(y) irradiance_table.table[i][j][r][c] in place of table "
            "(the ground's e_sky keeps the sky's c10_table)",
            "no gibbs, no dering; then the luminance scale, the rotation, the sun and the ground and the lobe (or the "
            "engine) as for the sky",
        ],
    })
    return {"irradiance_table": block}


DECLARATIONS: Template = Template('''\
// skysh $version: TypeScript declarations of the ES module written by
// `skysh export --format js$options` (the .mjs beside this file, whose header documents every option).

/** Engine names the engine option takes. */
export type Engine = $engine_union;

export interface CoefficientOptions {
  /** SH bands, an integer in [1, $max_bands]; default $default_bands. */
  bands?: number;
  /** Zonal sinc filter (Habel eq. 5); default !irradiance, false with an engine or the irradiance table. */
  gibbs?: boolean;
  /** Irradiance instead of radiance (clamped-cosine convolution); default false; must be false with an engine. */
  irradiance?: boolean;
  /** Window so the irradiance is never negative; default irradiance (or an engine) where available. */
  dering?: boolean;
  /**
   * The certified 3-band irradiance table (never negative) instead of the filtered, deringed sky: null (default) by
   * intent, for irradiance or an engine at 3 bands unless gibbs is true or dering false; false never; true always.
   */
  irradianceTable?: boolean | null;
  /** Add the sun's disk (a windowed delta, colour clamped at 0); default false. */
  sun?: boolean;
  /** A Lambertian ground below the horizon: a number or [r, g, b] in [0, 1]; default 0 (black). */
  groundAlbedo?: number | readonly [number, number, number] | Float64Array;
  /** Return this engine's numbers (its flat layout, see engineLayout) instead of skysh's. */
  engine?: Engine | null;
  /** Fill and return this array (its length must be the result's) instead of a new one. */
  out?: number[] | Float64Array;
}

/** The sun as a directional light. */
export interface SunLight {
  /** Unit vector towards the sun (Z up). */
  readonly direction: [number, number, number];
  /** Direct normal illuminance, lux per channel (linear sRGB). */
  readonly rgb: [number, number, number];
}

export interface EngineLayout {
  /** The engine's array shape (row-major); the product is the result's length. */
  readonly shape: readonly number[];
  /** The labels of the rows (first axis) of shape, in the engine's vocabulary. */
  readonly labels: readonly string[];
}

export declare const SKYSH_VERSION: string;
export declare const MAX_BANDS: number;
export declare const ENGINES: readonly Engine[];
export declare const SUN_ZENITH_DOMAIN: readonly [number, number];
export declare const TURBIDITY_DOMAIN: readonly [number, number];

/**
 * The sky's SH coefficients for one frame: bands * bands * 3 numbers, coefficient-major RGB
 * (or the engine's values). Radians; turbidity in $turbidity_domain. Throws RangeError / TypeError.
 */
export declare function coefficients<T extends number[] | Float64Array>(
  sunZenith: number, turbidity: number, sunAzimuth: number | undefined, options: CoefficientOptions & { out: T },
): T;
export declare function coefficients(
  sunZenith: number, turbidity: number, sunAzimuth?: number, options?: CoefficientOptions,
): number[];

/** The sun as a directional light (skysh.SkySH.sun_light). Throws RangeError / TypeError. */
export declare function sunLight(sunZenith: number, turbidity: number, sunAzimuth?: number): SunLight;

/** The engine's layout for a band count (default $default_bands). */
export declare function engineLayout(engine: Engine, bands?: number): EngineLayout;
''')
