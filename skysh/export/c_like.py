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
-   :data:`EXPORT_FORMATS`, :data:`C_REAL_TYPES`, :data:`DEFAULT_FILE_NAMES`.

C, GLSL and HLSL are one kernel, ``skysh/export/templates/c_like_kernel.h`` (with its
deringing, ``c_like_dering3.h`` or, in C at 5..7 bands, ``c_like_dering_certificate_c.h``), written once over a few words each language defines
(:data:`skysh.export.dering.WORDS`: ``c_like_words_c.h``, ``c_like_words_glsl.glsl`` or
``c_like_words_hlsl.hlsl`` then the shaders' shared ``c_like_words_shader.glsl``, and the math names
of ``c_like_words_math.h``: types, qualifiers, math functions, as sphericart writes one kernel for CPU
and CUDA); the public functions (``skysh_coefficients``, ``skysh_sun_light``,
``skysh_engine_coefficients``) are thin calls of its steps spelled in C (``c_like_api_c.h``) and in
the shaders (``c_like_api_shader.glsl``, its one hole GLSL's ``vec3`` or HLSL's ``float3``: :data:`API`),
their signatures those of the earlier exports. This module writes numbers
only (Filament's cmgen habit): the data section ``c_like_data.h`` (``#define`` lines and tables),
an engine's index-and-factor table ``c_like_engine.h``, the deringing's numbers
(:func:`skysh.export.dering.dering_defines`) and the notice, each by :func:`skysh.export.template.fill`
and the literal writers of :mod:`skysh.literals`.

The C export is a **header** (default name ``sky_sh.h``): an include guard,
``static inline`` functions and ``static const`` tables, so any number of C99
or C++ files may ``#include`` it; link with ``-lm`` (it calls ``tan``, ``exp``,
``log``, ``cos``, ``sin``, ``pow``, ``fmod``, and for deringing ``sqrt``, ``cbrt``,
``frexp``, ``ldexp``).

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
    range(l + 1)]``) and channel c (R, G, B). C, GLSL and HLSL store the table
    term-major (:func:`~skysh.export.tables.term_major`: ``SKYSH_TABLE[(i (SKYSH_DY + 1) + j)
    3 SKYSH_ROWS + 3 r + c]``), so that each term is one pass ``acc[o] += w[q] TABLE[q 3 ROWS + o]``
    over every output o = 3 r + c, a loop compilers vectorise (``benchmarks/bench_c_floor.py``
    measures it against a hand-written floor). With the certified irradiance
    table (3 bands; ``irradiance_table``, by intent for diffuse light, as the
    runtime: ``skysh_use_table`` in ``c_like_kernel.h``) the rows come from
    ``IRRADIANCE`` instead (its radiance-equivalent E_lm / A_l), the ground's c_10
    from ``TABLE``; steps 4 and 6 are then skipped.
4.  Gibbs filter (Habel eq. 5), when asked: zonal rows times ``sinc(pi l / N)``;
    times the luminance scale ``Y_z(ts, T) / F_Y(0, ts)`` (Preetham, cd/m^2).
5.  Rotation about Z (Habel eq. 4) by ``phi = fmod(sun_azimuth, 2 pi)`` as the
    runtime reduces it: coefficient ``l (l + 1) + m`` is ``acc[l (l + 1) / 2 +
    |m|]`` times ``cos(m phi)`` (m >= 0) or ``sin(|m| phi)`` (m < 0), these from one
    ``cos`` and one ``sin`` of phi by the angle-addition recurrence (as the sun's ``cos(k ts)``,
    ``sin(k ts)``; a few ulps from libm's at k <= 6).
6.  Deringing, when asked (:mod:`skysh.export.dering`: the runtime's least
    window, Sloan 2017): C at every band count, GLSL and HLSL at 1..4 bands
    (5..7 need the certificate, C-only: the shaders refuse ``dering`` there).
7.  The sun and the ground, when asked (:mod:`skysh.export.lights`, the order of
    :mod:`skysh.lighting.lights`): the sun's windowed delta (colour clamped at 0) and a
    Lambertian ground lit by the unfiltered sky's c_10 and the sun.
8.  A per-band factor, which commutes with the rotation (one multiplication
    with step 5 when steps 6 and 7 are off): ``A_l`` for irradiance, or an
    engine's folded factor (:func:`skysh.export.tables.engine_plan`).
9.  Engines only: the rest of the engine's linear map (frame change, signs,
    per-coefficient constants, packing) as a table of (output, input, factor)
    terms that one loop reads, plus its constant offsets.

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

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skysh import runtime
from skysh._version import __version__
from skysh.checks import check_choice, interval_text
from skysh.export import dering as export_dering
from skysh.export import js as export_js
from skysh.export import template
from skysh.export.dering import dering_defines, words
from skysh.export.lights import BY_INTENT, light_flags
from skysh.export.tables import EnginePlan, ExportTables, engine_plan, export_tables, term_major
from skysh.literals import float32_literal, number_rows, real_literal
from skysh.model.preetham import PEREZ_Y, ZENITH_LUMINANCE

__all__ = ["EXPORT_FORMATS", "C_REAL_TYPES", "DEFAULT_FILE_NAMES", "export_source"]

EXPORT_FORMATS: tuple[str, ...] = ("c", "glsl", "hlsl", "json", "js")
"""Languages :func:`export_source` writes."""

C_REAL_TYPES: tuple[str, ...] = ("double", "float")
"""Floating-point types of the C export (its tables and arithmetic)."""

DEFAULT_FILE_NAMES: dict[str, str] = {
    "c": "sky_sh.h", "glsl": "sky_sh.glsl", "hlsl": "sky_sh.hlsl", "json": "sky_sh.json", "js": "sky_sh.mjs",
}
"""The file name each export is meant to be saved as (the C export is a header)."""

API: dict[str, tuple[str, dict[str, str]]] = {
    "c": ("c_like_api_c.h", {}), "glsl": ("c_like_api_shader.glsl", {"VEC3": "vec3"}),
    "hlsl": ("c_like_api_shader.glsl", {"VEC3": "float3"}),
}
"""The template of each language's public functions, after the kernel, and its holes' values."""

Literal = Callable[[float], str]
"""A number writer of :mod:`skysh.literals` (the export's precision)."""


def _numbers(values: ArrayLike, literal: Literal, per_line: int = 6) -> str:
    """``values`` flattened row-major, as literals a few a line (a table's body)."""
    return number_rows([literal(v) for v in np.ravel(np.asarray(values, dtype=np.float64))], "    ", per_line)


def _defines(tables: ExportTables, literal: Literal, language: str) -> str:
    """The data section's ``#define`` lines: sizes, switches and the numbers of the domain and the models."""
    lights, k = tables.lights, tables.lights.constants
    sizes = {"BANDS": tables.bands, "COUNT": tables.bands**2, "HALF": len(tables.half_layout),
             "ROWS": len(tables.half_layout) + (tables.bands == 1), "DX": tables.degrees[0], "DY": tables.degrees[1],
             "SUN_DX": lights.sun_degrees[0], "SUN_DY": lights.sun_degrees[1],
             "DERING": int(export_dering.supported(language, tables.bands)),
             "LIGHTS": light_flags(lights), "IRRADIANCE_TABLE": int(tables.bands == 3 and tables.irradiance is not None),
             "BY_INTENT": f"({BY_INTENT})"}
    (zmin, zmax), (tmin, tmax) = tables.sun_zenith_domain, tables.turbidity_domain
    numbers = {"ZMIN": zmin, "ZMAX": zmax, "TMIN": tmin, "TMAX": tmax, "X_SCALE": tables.x_scale,
               "X_SHIFT": tables.x_shift, "Y_SCALE": tables.y_scale, "Y_SHIFT": tables.y_shift, "PI": math.pi,
               "TWO_PI": 2.0 * math.pi, "INV_PI": k["inv_pi"], "ZENITH_CHI": 4.0 / 9.0,
               **dict(zip(("ZENITH_A", "ZENITH_B", "ZENITH_C", "ZENITH_D"), ZENITH_LUMINANCE)),
               "KASTEN_A": k["am_a"], "KASTEN_B": k["am_b"], "KASTEN_NEG_C": k["am_neg_c"], "DEG": k["deg"],
               "SUN_M0": k["m0"], "SUN_X_SCALE": k["sx_scale"], "SUN_TMIN": k["sun_tmin"],
               "SUN_Y_SCALE": k["sy_scale"], "HF": k["hf"], "SUN_CLAMP": k["clamp"]}
    return template.defines({f"SKYSH_{name}": value for name, value in sizes.items()}
                            | {f"SKYSH_{name}": literal(value) for name, value in numbers.items()})


def _data(tables: ExportTables, literal: Literal, language: str) -> str:
    """The data section (``c_like_data.h``) filled with the export's numbers."""
    rows, lights = tables.table, tables.lights
    irradiance = tables.irradiance if tables.bands == 3 else None  # the certified table: 3 bands only
    if tables.bands == 1:  # the unfiltered c_10 (the ground's E_h) as row 1; with 2+ bands it is stored row 1
        rows = np.concatenate([rows, lights.c10[:, :, None, :]], axis=2)
    return template.fill(
        "c_like_data.h", DEFINES=_defines(tables, literal, language), TABLE=_numbers(term_major(rows), literal),
        GIBBS=_numbers(tables.gibbs, literal), LOBE=_numbers(tables.lobe, literal), PEREZ=_numbers(PEREZ_Y, literal),
        IRRADIANCE="" if irradiance is None else _numbers(term_major(irradiance), literal),
        SUN_TABLE=_numbers(lights.sun_table, literal), SUN_RGB=_numbers(lights.rgb_from_xyz, literal),
        SUN_TRIG=_numbers(lights.windowed_trig(), literal), GROUND=_numbers(lights.ground_zonal, literal),
    )


def _engine(plan: EnginePlan, literal: Literal) -> str:
    """An engine's tables (``c_like_engine.h``): the (output, input, factor) terms of its map and its offsets."""
    outputs, inputs = np.nonzero(plan.matrix)  # row-major: each output's terms in column order
    index: Literal = lambda v: str(int(v))  # noqa: E731 (an index writes as a C int)
    return template.fill(
        "c_like_engine.h", NAME=plan.engine, SHAPE=str(plan.shape), COUNT=str(plan.offset.size),
        TERMS=str(outputs.size), BAND=_numbers(plan.band_factor, literal), OUTPUT=_numbers(outputs, index, 16),
        INPUT=_numbers(inputs, index, 16), FACTOR=_numbers(plan.matrix[outputs, inputs], literal),
        OFFSET=_numbers(plan.offset, literal),
    )


def _notice(tables: ExportTables, language: str, precision: str, options: str, plan: EnginePlan | None) -> str:
    """The words at the top of the file: what it reproduces, its conventions and domain."""
    engine = "" if plan is None else template.fill(
        "c_like_notice_engine.txt", ENGINE=plan.engine, COUNT=str(plan.offset.size), SHAPE=str(plan.shape))
    return template.fill(
        "c_like_notice.txt", VERSION=__version__, BANDS=str(tables.bands), LANGUAGE=language,
        OPTIONS=options + ("" if plan is None else f" --engine {plan.engine}"), LAST_L=str(tables.bands - 1),
        SUN_ZENITH_DOMAIN=interval_text(*tables.sun_zenith_domain, pi=True),
        TURBIDITY_DOMAIN=interval_text(*tables.turbidity_domain), PRECISION=precision, ENGINE=engine,
    )


def api_source(language: str) -> str:
    """The public functions of ``language`` (``"c"``, ``"glsl"``, ``"hlsl"``): its :data:`API` template filled."""
    name, values = API[language]
    return template.fill(name, **values)


def _c_like_source(tables: ExportTables, language: str, real: str, plan: EnginePlan | None) -> str:
    """The C header, or the GLSL or HLSL functions: the words, the numbers, the kernel."""
    c = language == "c"
    literal: Literal = (lambda v: real_literal(v, real)) if c else float32_literal
    parts = [words(language), _data(tables, literal, language)]
    if plan is not None:
        parts.append(_engine(plan, literal))
    if export_dering.supported(language, tables.bands):  # the runtime's deringing: double in C, float in the shaders
        parts += [dering_defines("irradiance", "double" if c else "float", bands=tables.bands),
                  template.text(export_dering.dering_file(tables.bands))]
    body = "\n".join([*parts, template.text("c_like_kernel.h"), api_source(language)])
    if not c:
        return template.fill("c_like_frame_shader.glsl", NOTICE=_notice(tables, language, "float32", "", plan), BODY=body)
    notice = _notice(tables, "c", f"{real} (C {real})", "" if real == "double" else " --c-real float", plan)
    return template.fill("c_like_frame_c.h", NOTICE=notice, FLOAT=str(int(real == "float")), BODY=body)


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
    if language == "json":
        return export_js.json_source(tables, plan)
    return _c_like_source(tables, language, real, plan)
