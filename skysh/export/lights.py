"""
The steps after the sky's rotation in the exports: deringing, the sun and the ground
====================================================================================

The exported functions of :mod:`skysh.export.c_like` (C, GLSL, HLSL) and
:mod:`skysh.export.js` (JavaScript) follow the sky's rotation with the steps of
:meth:`skysh.SkySH.coefficients` (the order of :mod:`skysh.lighting.lights`): the
deringing of the sky, the sun (``sun=True``) and the ground
(``ground_albedo=...``), then the per-band factor; they also give the sun as a
directional light, as :meth:`skysh.SkySH.sun_light`. This module holds those
steps for C, GLSL and HLSL, the certified irradiance table's step, and the pieces
every export shares (:mod:`skysh.export.js_parts` writes the JavaScript and JSON ones):

-   :class:`LightTables`, :func:`light_tables`: the numbers (the file's sun
    table, its XYZ -> RGB matrix, the sun's windowed SH as a trigonometric
    polynomial, the ground's zonal factors, the unfiltered c_10 table) and the
    constants, read through public names only; :func:`light_flags`.
-   :func:`chebyshev_terms`: a file table's Chebyshev terms at an export's degrees
    (the sky's, the irradiance table's, the c_10's).
-   :func:`embed_table`: one named constant table in C, GLSL, HLSL or JavaScript (every table the lights add, and any later one).
-   :func:`c_like_lights`: ``skysh_sun_rgb``, ``skysh_add_lights`` and
    ``skysh_sun_light`` for C, GLSL and HLSL from one template.
-   :func:`dering_parts`: the 3-band deringing of :mod:`skysh.export.dering` wired
    into the C-like functions; :func:`irradiance_parts`: the certified irradiance
    table (``docs/irradiance.md``) and the ``irradiance_table`` rule in them.
-   :func:`double_literal`, :func:`float32_literal`, :func:`real_literal`,
    :func:`text_rows`, :data:`ZENITH_CONSTANTS`: number text and named numbers
    for the generated code.

What the generated code computes (after the sky's rotation and its deringing)
------------------------------------------------------------------------------
1.  The sun's RGB direct normal illuminance (lux): Kasten's air mass
    ``m = 1 / (cos ts + a (b - ts[deg])^-c)``, ``x = clamp(2 (m - m0) / (m1 - m0)
    - 1)``, ``y = clamp(2 (T - 2.5) / 3.5 - 1)`` (:data:`skysh.table.sun_table.SUN_VARIABLES`),
    ``ln XYZ = sum T_i(x) T_j(y) SUN[i][j]``, ``RGB = rgb_from_xyz @ exp(ln XYZ)``.
2.  The ground (when its albedo is not black): ``L_g = albedo (E_sky + cos(ts) RGB_sun)
    / pi`` with ``E_sky = sqrt(4 pi / 3) c_10`` of the *unfiltered* sky
    (:func:`skysh.model.ground.horizontal_irradiance_from_sh`; the sun's term only with
    ``sun``); ``coefficient (l, 0) += GROUND[l] (sinc(pi l / N) with gibbs) L_g``.
3.  The sun (with ``sun``): its colour clamped at :data:`skysh.lighting.lights.SUN_SH_CLAMP`
    per channel; ``coefficient (l, m) += Ybar_l|m|(ts) rot_m(phi) RGB``, with
    ``Ybar_lm(ts) = window_l Y_lm(sin ts, 0, cos ts) = sum_k TRIG[r][k] cos(k ts) +
    TRIG[r][N + k] sin(k ts)`` (:func:`skysh.lighting.lights.sun_trig_matrix`, the window
    :func:`skysh.model.solar.sun_window`) and ``rot_m`` the sky's rotation factors (Habel eq. 4).

Then the per-band factor (``A_l`` for irradiance, an engine's) multiplies the sum.

The certified irradiance table (:func:`irradiance_parts`)
---------------------------------------------------------
``irradiance_table`` follows :meth:`skysh.SkySH.coefficients` (by intent: :data:`BY_INTENT`
in C and the shaders, ``null`` in JavaScript; 0 never; 1 always): the 3-band sky's rows come
from the file's table (E_lm / A_l over the luminance scale, m >= 0), are summed, scaled and
rotated as the sky's (Habel eqs. 1, 4), never filtered or deringed (``docs/irradiance.md``).

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: the sun's light.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (4), (5).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000), section 3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from string import Template
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_bands, check_choice, check_scalar
from skysh.domain import KASTEN_COEFFICIENTS, SUN, term_index
from skysh.lighting import lights, sunlight
from skysh.model import ground, preetham, solar
from skysh.table import coefficient_file

__all__ = [
    "FLOAT32_MAX", "TABLE_LANGUAGES", "ZENITH_CONSTANTS", "BY_INTENT", "LightTables", "light_tables", "light_flags",
    "chebyshev_terms", "embed_table", "dering_parts", "irradiance_parts", "c_like_lights", "c_like_engine", "double_literal",
    "float32_literal", "real_literal", "text_rows",
]

FLOAT32_MAX: float = float(np.finfo(np.float32).max)
"""Largest finite float32: beyond it a float32 literal would read back as inf."""

_FLOAT64_MAX: float = float(np.finfo(np.float64).max)
"""Largest finite double: a double literal's range."""

TABLE_LANGUAGES: tuple[str, ...] = ("c", "glsl", "hlsl", "js")
"""Languages :func:`embed_table` writes."""

ZENITH_CONSTANTS: dict[str, float] = {
    "c4_9": 4.0 / 9.0, "c120": 120.0, "c1000": 1000.0,
    **dict(zip(("c40453", "c49710", "c02155", "c24192"), preetham.ZENITH_LUMINANCE)),
    "pi": math.pi, "two_pi": 2.0 * math.pi, "c0": 0.0, "c1": 1.0, "c2": 2.0,
}
"""Named numbers of every export's code: the zenith luminance's (:data:`skysh.model.preetham.ZENITH_LUMINANCE`,
written ``(c40453 T - c49710) tan chi - c02155 T + c24192``), and pi, 2 pi, 0, 1, 2."""

BY_INTENT: int = -1
"""The C and shader value of ``irradiance_table`` that means the runtime's default (None): by intent."""

_PER_LINE: int = 6
"""Numbers per line of an embedded table."""


_PLAIN_REALS: tuple[type, ...] = (float, np.float64, np.float32)


def _checked_real(value: Any, high: float, unit: str = "") -> float:
    """``value`` in [-high, high]: a float by one comparison (NaN fails it), the rest by ``check_scalar``."""
    if type(value) in _PLAIN_REALS and -high <= value <= high:
        return float(value)
    return check_scalar(value, "value", -high, high, unit=unit)


def double_literal(value: float) -> str:
    """Shortest text that reads back as the same double, always with a '.' or an exponent."""
    text = repr(_checked_real(value, _FLOAT64_MAX))
    return text if any(ch in text for ch in ".en") else text + ".0"


def float32_literal(value: float) -> str:
    """Shortest text that reads back as the same float32 (valid in C, GLSL and HLSL, no suffix)."""
    number = _checked_real(value, FLOAT32_MAX, unit="(the float32 range)")
    return np.format_float_scientific(np.float32(number), unique=True, trim="0")


def real_literal(value: float, real: str) -> str:
    """A C literal of ``real`` (``"double"``: :func:`double_literal`; ``"float"``: float32 text with ``f``)."""
    return double_literal(value) if real == "double" else float32_literal(value) + "f"


def text_rows(items: list[str], indent: str, per_line: int = _PER_LINE) -> str:
    """``items`` joined by commas, ``per_line`` a line, lines joined by a comma, a newline and ``indent``."""
    lines = [", ".join(items[k : k + per_line]) for k in range(0, len(items), per_line)]
    return (",\n" + indent).join(lines)


def chebyshev_terms(table: ArrayLike, max_degrees: tuple[int, int], degrees: tuple[int, int]) -> NDArray[np.float64]:
    """
    A file table's Chebyshev terms at an export's degrees, zero where the table has none.

    Parameters
    ----------
    table
        (n_terms, rows, 3): a :class:`skysh.table.coefficient_file.SkyTable`'s or
        :class:`~skysh.table.coefficient_file.NamedTable`'s ``table``, terms in
        :func:`skysh.domain.term_index` order for ``max_degrees``.
    max_degrees, degrees
        (d_x, d_y) of the table's layout and of the export, each in [0, 31].

    Returns
    -------
    ndarray
        (DX + 1, DY + 1, rows, 3), float64: [i][j] the coefficient of T_i(x) T_j(y).
    """
    values = np.asarray(table, dtype=np.float64)
    out = np.zeros((degrees[0] + 1, degrees[1] + 1) + values.shape[1:])
    for i in range(min(degrees[0], max_degrees[0]) + 1):
        for j in range(min(degrees[1], max_degrees[1]) + 1):
            out[i, j] = values[term_index(i, j, max_degrees)]
    return out


def embed_table(language: str, name: str, values: ArrayLike, real: str = "double", comment: str = "") -> str:
    """
    One named constant table, flattened row-major, as a declaration in ``language``.

    Parameters
    ----------
    language
        One of :data:`TABLE_LANGUAGES`: C (``static const skysh_real NAME[n]``, literals
        of ``real``), GLSL (``const float NAME[n] = float[n](...)``), HLSL (``static const
        float NAME[n] = {...}``), both float32, or JavaScript (``const NAME = new
        Float64Array([...])``, doubles).
    name
        The identifier.
    values
        Any array of finite numbers (float32 range for the shaders and ``real="float"``).
    real
        C only: ``"double"`` or ``"float"``.
    comment
        One line written above the declaration (empty: none).

    Raises
    ------
    ValueError
        An unknown language or ``real``, an empty table, or a value that is not finite
        (or beyond float32 where float32 is written).
    """
    check_choice(language, "language", TABLE_LANGUAGES)
    check_choice(real, "real", ("double", "float"))
    flat = np.ravel(np.asarray(values, dtype=np.float64))
    if flat.size == 0:
        raise ValueError(f"values of table {name} must not be empty")
    if language == "js":
        items = [double_literal(v) for v in flat]
    elif language == "c":
        items = [real_literal(v, real) for v in flat]
    else:
        items = [float32_literal(v) for v in flat]
    body = text_rows(items, "    ")
    n = flat.size
    note = "" if not comment else (f"/* {comment} */\n" if language == "c" else f"// {comment}\n")
    if language == "c":
        return f"{note}static const skysh_real {name}[{n}] = {{\n    {body}\n}};\n"
    if language == "glsl":
        return f"{note}const float {name}[{n}] = float[{n}](\n    {body}\n);\n"
    if language == "hlsl":
        return f"{note}static const float {name}[{n}] = {{\n    {body}\n}};\n"
    return f"{note}const {name} = new Float64Array([\n    {body}\n]);\n"


# --------------------------------------------------------------------------- #
# Step 6: deringing (skysh.export.dering) in the exported functions
# --------------------------------------------------------------------------- #
_DERING_STEP: dict[str, str] = {
    "c": """
    if (dering) { /* skysh.export.dering: windows d in place, returns the window (unused here) */
        double d[SKYSH_COUNT][3], window[3];
        for (i = 0; i < SKYSH_COUNT; ++i)
            for (c = 0; c < 3; ++c)
                d[i][c] = out[i][c];
        (void)skysh_dering3(d, window);
        for (i = 0; i < SKYSH_COUNT; ++i)
            for (c = 0; c < 3; ++c)
                out[i][c] = (skysh_real)d[i][c];
    }""",
    "shader": """
    if (dering) { // skysh.export.dering: windows d in place
        float d[27];
        float window[3];
        for (int n = 0; n < SKYSH_COUNT; ++n) {
            d[3 * n] = coeffs[n].x;
            d[3 * n + 1] = coeffs[n].y;
            d[3 * n + 2] = coeffs[n].z;
        }
        skysh_dering3(d, window);
        for (int n = 0; n < SKYSH_COUNT; ++n)
            coeffs[n] = $vec3(d[3 * n], d[3 * n + 1], d[3 * n + 2]);
    }""",
}
"""Step 6: the deringing of :mod:`skysh.export.dering` on the rotated radiance (steps 7 and 8 follow)."""


def dering_parts(language: str, bands: int, vec3: str = "") -> tuple[str, str]:
    """(definitions, step) of the runtime's 3-band deringing in ``language`` (empty for other N)."""
    if bands != 3:
        return "", ""
    from skysh.export import dering as export_dering

    source = export_dering.dering_source(language, target="irradiance", name="skysh_dering3")
    if language == "c":
        source = source.replace("\nint skysh_dering3(", "\nstatic inline int skysh_dering3(", 1)
    step = Template(_DERING_STEP["c" if language == "c" else "shader"]).substitute(vec3=vec3)
    return "\n" + source, step


# --------------------------------------------------------------------------- #
# Step 3 from the certified irradiance table (docs/irradiance.md)
# --------------------------------------------------------------------------- #
_USE_TABLE: dict[str, str] = {
    "c": """
/*
 * The irradiance_table argument (skysh.SkySH.coefficients' irradiance_table): 1 when the sky's rows come from the
 * certified irradiance table (docs/irradiance.md), 0 when not, -1 when refused. SKYSH_BY_INTENT: the table for
 * diffuse light (mode 1 irradiance, 2 an engine) without the Gibbs filter and with deringing, where this export
 * has it (SKYSH_IRRADIANCE_TABLE); 0: never (the sky's rows, filtered and deringed as asked); 1: always
 * (refused with gibbs or without the table).
 */
static inline int skysh_use_table(int choice, int mode, int gibbs, int dering)
{
    if (choice == SKYSH_BY_INTENT)
        return SKYSH_IRRADIANCE_TABLE && mode != 0 && !gibbs && dering;
    if (choice == 0)
        return 0;
    return choice == 1 && SKYSH_IRRADIANCE_TABLE && !gibbs ? 1 : -1;
}
""",
    "shader": """
// The irradianceTable argument (skysh.SkySH.coefficients' irradiance_table): 1 when the sky's rows come from the
// certified irradiance table (docs/irradiance.md), 0 when not, -1 when refused. SKYSH_BY_INTENT: the table for
// diffuse light (mode 1 irradiance, 2 an engine) without the Gibbs filter and with deringing, where this export
// has it (SKYSH_IRRADIANCE_TABLE); 0: never (the sky's rows, filtered and deringed as asked); 1: always
// (refused with gibbs or without the table).
int skysh_use_table(int choice, int mode, bool gibbs, bool dering)
{
    if (choice == SKYSH_BY_INTENT)
        return (SKYSH_IRRADIANCE_TABLE != 0 && mode != 0 && !gibbs && dering) ? 1 : 0;
    if (choice == 0)
        return 0;
    return (choice == 1 && SKYSH_IRRADIANCE_TABLE != 0 && !gibbs) ? 1 : -1;
}
""",
}
"""``skysh_use_table``: the runtime's ``irradiance_table`` rule (:meth:`skysh.SkySH.coefficients`)."""

_TABLE_STEP: dict[str, str] = {
    "c": """
    if (table) /* step 3 from the certified irradiance table: never filtered, never deringed */
        for (r = 0; r < SKYSH_HALF; ++r)
            skysh_row(SKYSH_IRRADIANCE + r * SKYSH_TERMS * 3, w, acc[r]);""",
    "shader": """
            if (table) // step 3 from the certified irradiance table: never filtered, never deringed
                for (int r = 0; r < SKYSH_HALF; ++r)
                    irr[r] += w * SKYSH_IRRADIANCE[(i * (SKYSH_DY + 1) + j) * SKYSH_HALF + r];""",
}
"""The sums of the irradiance table's rows (C: after the sky's c_10; shaders: in the loop over the terms)."""


def irradiance_parts(language: str, table: ArrayLike | None, real: str = "double") -> dict[str, str]:
    """
    The certified irradiance table in C, GLSL or HLSL: ``irradiance_defs`` and ``irradiance_step``.

    Parameters
    ----------
    language
        ``"c"``, ``"glsl"`` or ``"hlsl"``.
    table
        (DX + 1, DY + 1, 6, 3): the table's rows at the export's degrees
        (:attr:`skysh.export.tables.ExportTables.irradiance`), or None for an export without it
        (``irradiance_table`` 1 is then refused and "by intent" is the sky's pipeline).
    real
        C only: ``"double"`` or ``"float"``.

    Returns
    -------
    dict
        ``irradiance_defs``: ``SKYSH_BY_INTENT``, ``SKYSH_IRRADIANCE_TABLE``, the table
        (C ``SKYSH_IRRADIANCE[3 (r SKYSH_TERMS + i (SKYSH_DY + 1) + j) + c]``; shaders
        ``SKYSH_IRRADIANCE[(i (SKYSH_DY + 1) + j) SKYSH_HALF + r]``, RGB) and ``skysh_use_table``;
        ``irradiance_step``: the sums of its rows (empty without the table).
    """
    check_choice(language, "language", ("c", "glsl", "hlsl"))
    c = language == "c"
    head = (f"\n#define SKYSH_BY_INTENT ({BY_INTENT}) /* irradiance_table: the runtime's default (None) */\n"
            f"#define SKYSH_IRRADIANCE_TABLE {int(table is not None)} /* 1: the certified irradiance table is here */\n")
    if not c:
        head = head.replace("/* ", "// ").replace(" */", "")
    use = _USE_TABLE["c" if c else "shader"]
    if table is None:
        return {"irradiance_defs": head + use, "irradiance_step": ""}
    rows = np.asarray(table, dtype=np.float64)
    what = "E_lm / A_l of the m >= 0 rows over the luminance scale"
    if c:
        comment = f"[3 (r SKYSH_TERMS + i (SKYSH_DY + 1) + j) + c]: {what}, r-major as SKYSH_TABLE"
        text = embed_table("c", "SKYSH_IRRADIANCE", rows.reshape(-1, rows.shape[2], 3).transpose(1, 0, 2), real, comment)
    else:
        vec3 = "vec3" if language == "glsl" else "float3"
        triples = [f"{vec3}(" + ", ".join(float32_literal(v) for v in rgb) + ")" for rgb in rows.reshape(-1, 3)]
        body, n = text_rows(triples, "    ", 4), len(triples)
        comment = f"[(i (SKYSH_DY + 1) + j) SKYSH_HALF + r]: RGB {what}"
        text = (f"// {comment}\nconst vec3 SKYSH_IRRADIANCE[{n}] = vec3[{n}](\n    {body}\n);\n" if language == "glsl"
                else f"// {comment}\nstatic const float3 SKYSH_IRRADIANCE[{n}] = {{\n    {body}\n}};\n")
    return {"irradiance_defs": head + text + use, "irradiance_step": _TABLE_STEP["c" if c else "shader"]}


# --------------------------------------------------------------------------- #
# Step 9: the rest of an engine's map (skysh.export.tables.engine_plan)
# --------------------------------------------------------------------------- #
_ENGINE_TABLES: dict[str, str] = {"c": """
/* Engine "$engine": per-band factors folded before the rotation (skysh.export.tables.engine_plan). */
#define SKYSH_ENGINE_COUNT $count /* values, shape $shape */
static const skysh_real SKYSH_ENGINE_BAND[SKYSH_BANDS] = { $band };
""", "shader": """
// Engine "$engine": per-band factors folded before the rotation (skysh.export.tables.engine_plan).
#define SKYSH_ENGINE_COUNT $count // values, shape $shape
$const float SKYSH_ENGINE_BAND[SKYSH_BANDS] = $band;
"""}
"""Step 9's tables: ``SKYSH_ENGINE_COUNT`` and the per-band factors folded before the rotation."""

_ENGINE_FUNCTION: dict[str, Template] = {"c": Template("""
/*
 * The numbers engine "$engine" takes: skysh.engines.presets.convert(radiance, "$engine")
 * flattened row-major, shape $shape. Arguments as skysh_coefficients (engines light
 * diffusely: SKYSH_BY_INTENT takes the irradiance table's radiance-equivalent as
 * irradiance does); returns 0, or -1 .. -5 (out zeroed) as skysh_coefficients.
 */
static inline int skysh_engine_coefficients(skysh_real sun_zenith, skysh_real turbidity, skysh_real sun_azimuth,
                                            int gibbs, int dering, int sun, const skysh_real *ground_albedo,
                                            int irradiance_table, skysh_real out[SKYSH_ENGINE_COUNT])
{
    skysh_real sh[SKYSH_COUNT][3];
    int p;
    const int rc = skysh_evaluate(sun_zenith, turbidity, sun_azimuth, gibbs, dering, sun, ground_albedo,
                                  irradiance_table, 2, sh);
    if (rc != 0) {
        for (p = 0; p < SKYSH_ENGINE_COUNT; ++p)
            out[p] = $c0;
        return rc;
    }
    $lines
    return 0;
}
"""), "shader": Template("""
// The numbers engine "$engine" takes: skysh.engines.presets.convert(radiance, "$engine")
// flattened row-major, shape $shape (SKYSH_BY_INTENT: the irradiance table, as for irradiance).
// Returns false (values zeroed) as skysh_coefficients.
bool skysh_engine_coefficients(float sunZenith, float turbidity, float sunAzimuth, bool gibbs, bool dering, bool sun,
                               $vec3 groundAlbedo, int irradianceTable, out float values[SKYSH_ENGINE_COUNT])
{
    $vec3 sh[SKYSH_COUNT];
    if (!skysh_evaluate(sunZenith, turbidity, sunAzimuth, gibbs, dering, sun, groundAlbedo, irradianceTable, 2, sh)) {
        for (int p = 0; p < SKYSH_ENGINE_COUNT; ++p)
            values[p] = $c0;
        return false;
    }
    $lines
    return true;
}
""")}
"""Step 9's ``skysh_engine_coefficients``: the rest of the engine's map after the runtime's steps."""


def c_like_engine(language: str, plan: Any, common: dict[str, Any], fmt: Any) -> tuple[str, str]:
    """
    Step 9 in C, GLSL or HLSL: (the engine's tables, ``skysh_engine_coefficients``); empty without ``plan``.

    ``plan``: an :class:`skysh.export.tables.EnginePlan` or None; ``common``: the sky template's
    substitutions; ``fmt``: the export's number literal (float32 text for the shaders).
    """
    check_choice(language, "language", ("c", "glsl", "hlsl"))
    if plan is None:
        return "", ""
    c, glsl = language == "c", language == "glsl"
    bands = [fmt(v) for v in plan.band_factor]
    listed = ", ".join(bands)
    band = listed if c else (f"float[{len(bands)}]({listed})" if glsl else "{ " + listed + " }")
    names = dict(engine=plan.engine, count=plan.offset.size, shape=plan.shape)
    tables = Template(_ENGINE_TABLES["c" if c else "shader"]).substitute(
        names, band=band, const="const" if glsl else "static const")

    def value(q: int) -> str:
        return f"sh[{q // 3}][{q % 3}]" if c else f"sh[{q // 3}].{'xyz'[q % 3]}"

    target = "out" if c else "values"
    lines = [f"{target}[{p}] = {plan.expression(p, value, fmt)};" for p in range(plan.offset.size)]
    function = _ENGINE_FUNCTION["c" if c else "shader"].substitute(
        common, shape=plan.shape, engine=plan.engine, lines="\n    ".join(lines), vec3="vec3" if glsl else "float3")
    return tables, function


# --------------------------------------------------------------------------- #
# The numbers
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class LightTables:
    """
    The sun's and the ground's numbers of an export of ``bands`` bands.

    Attributes
    ----------
    bands
        N.
    has_sun, has_ground
        Whether the file has the sun table (every file since format 3), and the sky's c_10 (>= 2 bands).
        Without them the tables below are zeros and the generated code refuses the option.
    sun_degrees
        (SDX, SDY) of the sun table.
    sun_table
        (SDX + 1, SDY + 1, 3): Chebyshev coefficients of ln X, ln Y, ln Z (ln lux).
    rgb_from_xyz
        (3, 3): the file's XYZ -> linear RGB matrix.
    trig
        (N (N + 1) / 2, 2 N): the sun's SH at azimuth 0 per unit colour, *without* the
        window, as ``[cos(k ts)]_k ++ [sin(k ts)]_k`` (:func:`skysh.lighting.lights.sun_trig_matrix`).
    windows
        The window of every band count n = 1 .. N, concatenated (n entries each).
    ground_zonal
        (N,): :data:`skysh.model.ground.GROUND_ZONAL` (the Gibbs filter is applied in the code).
    c10
        (DX + 1, DY + 1, 3): the unfiltered (1, 0) sky coefficient over the luminance scale,
        at the sky table's degrees.
    constants
        Named scalars of the generated code (:func:`light_tables` lists them).
    """

    bands: int
    has_sun: bool
    has_ground: bool
    sun_degrees: tuple[int, int]
    sun_table: NDArray[np.float64]
    rgb_from_xyz: NDArray[np.float64]
    trig: NDArray[np.float64]
    windows: NDArray[np.float64]
    ground_zonal: NDArray[np.float64]
    c10: NDArray[np.float64]
    constants: dict[str, float]

    def windowed_trig(self) -> NDArray[np.float64]:
        """(N (N + 1) / 2, 2 N): :attr:`trig` with the window of N bands folded into its rows."""
        window = self.windows[-self.bands :]
        rows = [l for l, _ in coefficient_file.zonal_half_layout(self.bands)]
        return self.trig * window[rows][:, None]


def light_tables(sky: Any, bands: int, degrees: tuple[int, int]) -> LightTables:
    """
    The sun's and the ground's numbers for an export of ``bands`` bands.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`: its ``table`` (:class:`skysh.table.coefficient_file.SkyTable`)
        is read through public attributes only.
    bands
        N in [1, the file's bands].
    degrees
        (DX, DY) of the sky table the export embeds (the c_10 table takes the same terms,
        as the runtime's plan of N bands).
    """
    table = sky.table
    bands = check_bands(bands, high=table.bands)
    dx, dy = degrees
    named = table.tables.get("sun")
    has_sun, has_ground = named is not None, table.bands >= 2
    if has_sun:
        sun_table = np.array(named.table[:, 0, :], dtype=np.float64)
        sdx, sdy = named.max_degrees
        rgb = np.array(sunlight.SunLight(table).rgb_from_xyz, dtype=np.float64)
    else:
        sun_table, (sdx, sdy), rgb = np.zeros((1, 3)), (0, 0), np.zeros((3, 3))
    c10 = np.zeros((dx + 1, dy + 1, 3))
    if has_ground:  # the sky's unfiltered (1, 0), at the export's terms
        c10 = chebyshev_terms(table.table[:, 1:2], table.max_degrees, degrees)[:, :, 0]
    a, b, c = KASTEN_COEFFICIENTS  # the sun table's map (skysh.domain.SUN): x = (m - m0) sx_scale - 1, y likewise
    constants = {
        "am_a": a, "am_b": b, "am_neg_c": -c, "deg": 180.0 / math.pi, "m0": SUN.x.origin, "sx_scale": SUN.x.scale,
        "sun_tmin": SUN.y.origin, "sy_scale": SUN.y.scale, "hf": ground.HORIZONTAL_FACTOR, "inv_pi": 1.0 / math.pi,
        "clamp": lights.SUN_SH_CLAMP,
    }
    return LightTables(
        bands=bands, has_sun=has_sun, has_ground=has_ground, sun_degrees=(sdx, sdy),
        sun_table=sun_table.reshape(sdx + 1, sdy + 1, 3), rgb_from_xyz=rgb,
        trig=lights.sun_trig_matrix(bands, np.ones(bands)),
        windows=np.concatenate([solar.sun_window(n) for n in range(1, bands + 1)]),
        ground_zonal=np.array(ground.GROUND_ZONAL[:bands]), c10=c10, constants=constants,
    )


def light_flags(tables: LightTables) -> int:
    """SKYSH_LIGHTS of the generated code: 1 the sun is available, 2 the ground."""
    return int(tables.has_sun) + 2 * int(tables.has_ground)


# --------------------------------------------------------------------------- #
# C, GLSL and HLSL: one template
# --------------------------------------------------------------------------- #
_C_LIKE = Template("""
#define SKYSH_SUN_DX $sdx /* Chebyshev degree of the sun table in x (air mass) */
#define SKYSH_SUN_DY $sdy /* ... and in y (turbidity) */
#define SKYSH_LIGHTS $flags /* 1: the sun is available, 2: the ground (3: both) */
$tables
/* The sun's RGB direct normal illuminance (lux; Preetham 1999 appendix, fitted: skysh.lighting.sunlight). */
${fn}void skysh_sun_rgb($real ts, $real t, $out$rgb rgb$dim)
{
    $real sx[SKYSH_SUN_DX + 1];
    $real sy[SKYSH_SUN_DY + 1];
    $real ln[3];
    $real m = $c1 / ($cos(ts) + $am_a * $pow($am_b - ts * $deg, $am_neg_c)); /* Kasten 1966 */
    $real x = (m - $m0) * $sx_scale - $c1;
    $real y = (t - $sun_tmin) * $sy_scale - $c1;
    x = x < -$c1 ? -$c1 : (x > $c1 ? $c1 : x);
    y = y < -$c1 ? -$c1 : (y > $c1 ? $c1 : y);
    sx[0] = $c1;
    sy[0] = $c1;
    for (int i = 1; i <= SKYSH_SUN_DX; ++i)
        sx[i] = i == 1 ? x : $c2 * x * sx[i - 1] - sx[i - 2];
    for (int j = 1; j <= SKYSH_SUN_DY; ++j)
        sy[j] = j == 1 ? y : $c2 * y * sy[j - 1] - sy[j - 2];
    for (int c = 0; c < 3; ++c)
        ln[c] = $c0;
    for (int i = 0; i <= SKYSH_SUN_DX; ++i)
        for (int j = 0; j <= SKYSH_SUN_DY; ++j) {
            $real w = sx[i] * sy[j];
            int base = 3 * (i * (SKYSH_SUN_DY + 1) + j);
            for (int c = 0; c < 3; ++c)
                ln[c] += w * SKYSH_SUN_TABLE[base + c];
        }
    for (int c = 0; c < 3; ++c)
        ln[c] = $exp(ln[c]);
    for (int c = 0; c < 3; ++c)
        rgb[c] = SKYSH_SUN_RGB[3 * c] * ln[0] + SKYSH_SUN_RGB[3 * c + 1] * ln[1] + SKYSH_SUN_RGB[3 * c + 2] * ln[2];
}

/*
 * The ground (albedo x (E_sky + cos(ts) E_sun) / pi, zonal, Gibbs-filtered with gibbs) and the
 * sun (a delta windowed by skysh.model.solar.sun_window, colour clamped at SKYSH_SUN_CLAMP) added to
 * the rotated radiance coeffs; e_sky = sqrt(4 pi / 3) c_10 of the unfiltered sky (lux).
 */
${fn}void skysh_add_lights($real ts, $real t, $real phi, $flag sun, $flag ground, $flag gibbs, $in$rgb albedo$dim,
                      $in$rgb e_sky$dim, $inout$rgb coeffs[SKYSH_COUNT]$dim)
{
    $rgb rgb$dim;
    for (int c = 0; c < 3; ++c)
        rgb[c] = $c0;
    if (sun)
        skysh_sun_rgb(ts, t, rgb);
    if (ground) {
        $real ct = $cos(ts);
        for (int l = 0; l < SKYSH_BANDS; ++l) {
            $real g = SKYSH_GROUND[l] * (gibbs ? SKYSH_GIBBS[l] : $c1) * $inv_pi;
            for (int c = 0; c < 3; ++c)
                coeffs[l * (l + 1)][c] += g * albedo[c] * (e_sky[c] + ct * rgb[c]);
        }
    }
    if (sun) {
        $real trig[2 * SKYSH_BANDS];
        for (int k = 0; k < SKYSH_BANDS; ++k) {
            trig[k] = $cos(${to_real}(k) * ts);
            trig[SKYSH_BANDS + k] = $sin(${to_real}(k) * ts);
        }
        for (int c = 0; c < 3; ++c)
            rgb[c] = rgb[c] > $clamp ? rgb[c] : $clamp;
        for (int l = 0; l < SKYSH_BANDS; ++l)
            for (int m = -l; m <= l; ++m) {
                int k = m < 0 ? -m : m;
                int r = l * (l + 1) / 2 + k;
                $real y = $c0;
                for (int q = 0; q < 2 * SKYSH_BANDS; ++q)
                    y += SKYSH_SUN_TRIG[r * 2 * SKYSH_BANDS + q] * trig[q];
                y *= m < 0 ? $sin(${to_real}(k) * phi) : $cos(${to_real}(k) * phi);
                for (int c = 0; c < 3; ++c)
                    coeffs[l * (l + 1) + m][c] += y * rgb[c];
            }
    }
}

/*
 * The sun as a directional light (skysh.SkySH.sun_light): the unit vector towards it (Z up) and its
 * RGB direct normal illuminance, lux, unclamped (slightly negative blue near the horizon). Returns
 * $ok; $fail (zeroed) outside the domain$missing_doc.
 */
${fn}$ret skysh_sun_light($real sun_zenith, $real turbidity, $real sun_azimuth, $out$rgb direction$dim,
                     $out$rgb rgb$dim)
{
    for (int c = 0; c < 3; ++c) {
        direction[c] = $c0;
        rgb[c] = $c0;
    }
    if (!(sun_zenith >= $zmin && sun_zenith <= $zmax) || !(turbidity >= $tmin && turbidity <= $tmax)$finite)
        return $fail;
    if (SKYSH_LIGHTS % 2 == 0)
        return $missing;
    $real phi = $fmod(sun_azimuth, $two_pi);
    direction[0] = $sin(sun_zenith) * $cos(phi);
    direction[1] = $sin(sun_zenith) * $sin(phi);
    direction[2] = $cos(sun_zenith);
    skysh_sun_rgb(sun_zenith, turbidity, rgb);
    return $ok;
}
""")


_C_LIKE_WORDS: dict[str, dict[str, str]] = {
    "c": {"fn": "static inline ", "real": "skysh_real", "dim": "[3]", "to_real": "(skysh_real)", "flag": "int",
          "ret": "int", "ok": "0", "fail": "-1", "missing": "-4", "missing_doc": ", -4 without the file's sun table",
          "in": "const ", "out": "", "inout": ""},
    "shader": {"fn": "", "real": "float", "dim": "", "to_real": "float", "flag": "bool", "ret": "bool", "ok": "true",
               "fail": "false", "missing": "false", "missing_doc": ", or without the file's sun table", "in": "",
               "out": "out ", "inout": "inout "},
}
"""The words of :data:`_C_LIKE` that differ between C and the shaders (GLSL and HLSL alike)."""


def _c_like_tables(tables: LightTables, language: str, real: str) -> str:
    """The four tables of the lights in ``language``."""
    return "".join(embed_table(language, name, values, real, comment) for name, values, comment in (
        ("SKYSH_SUN_TABLE", tables.sun_table, "[3 (i (SKYSH_SUN_DY + 1) + j) + c]: ln X, ln Y, ln Z of T_i(x) T_j(y)"),
        ("SKYSH_SUN_RGB", tables.rgb_from_xyz, "XYZ -> linear RGB, row-major"),
        ("SKYSH_SUN_TRIG", tables.windowed_trig(), "[r 2 N + q]: windowed Ybar_r(ts) over cos(q ts), then sin((q - N) ts)"),
        ("SKYSH_GROUND", tables.ground_zonal, "(l, 0) SH of a uniform lower hemisphere of unit radiance"),
    ))


def c_like_lights(tables: LightTables, language: str, real: str = "double", common: dict[str, Any] | None = None) -> str:
    """
    ``skysh_sun_rgb``, ``skysh_add_lights`` and ``skysh_sun_light`` (with their tables) in C, GLSL or HLSL.

    ``common``: the substitutions the sky's template already uses (domain, ``c0``, ``c1``,
    ``c2``, ``two_pi``, written in the same precision); the C code uses ``skysh_real`` of ``real``.
    Needs ``SKYSH_BANDS``, ``SKYSH_COUNT`` and ``SKYSH_GIBBS`` defined before it.
    """
    check_choice(language, "language", ("c", "glsl", "hlsl"))
    c = language == "c"
    suffix = "f" if c and real == "float" else ""

    def fmt(v: float) -> str:
        return real_literal(v, real) if c else float32_literal(v)

    words = dict(_C_LIKE_WORDS["c" if c else "shader"], rgb="skysh_real" if c else ("vec3" if language == "glsl" else "float3"),
                 finite=f" || !(sun_azimuth - sun_azimuth == {fmt(0.0)})" if c else "",
                 fmod="fmod" + suffix if language != "glsl" else "mod",
                 **{name: name + suffix for name in ("cos", "sin", "exp", "pow")})
    numbers = {key: fmt(value) for key, value in tables.constants.items()}
    return _C_LIKE.substitute(
        common or {}, **words, **numbers, sdx=tables.sun_degrees[0], sdy=tables.sun_degrees[1], flags=light_flags(tables),
        tables=_c_like_tables(tables, language, real),
    )
