"""
Deringing of 1..7-band SH in C, and of 1..4-band SH in GLSL and HLSL
=====================================================================

The function that windows RGB radiance SH in place as :func:`skysh.post.dering.dering` does
(method ``"window"``: the least window position, :func:`skysh.post.dering.least_window`) is
written once, by hand, in two templates over the words of the C-like kernel (:data:`WORDS`,
:func:`words`); this module writes the numbers they read:

-   ``c_like_dering3.h`` (C, GLSL, HLSL): targets that are 3-band functions (1..3 bands, and
    4-band irradiance, whose band 3 the kernel zeroes), on their exact minimum;
-   ``c_like_dering_certificate_c.h`` (C only): the others (5..7 bands, 4-band radiance), on the
    sampling certificate of :mod:`skysh.sh.minimum`. The shaders refuse them
    (:data:`SHADER_REFUSAL`: its cost per call, measured in C).

-   :func:`dering_defines`: the ``#define`` lines, the same table, kernel, basis constants,
    Newton steps, certificate constants and guards as Python's (:data:`GUARDS` per precision).
-   :func:`dering_source`: the self-contained function in one language (the words, the numbers,
    the function), as the C, GLSL and HLSL exports embed it (:mod:`skysh.export.c_like`):

    -   C: ``int name(double c[K][3], double scales_out[N], double position_out[1])``, ``static inline``;
    -   GLSL, HLSL: ``int name(inout float c[3 K], out float scales_out[N], out float position_out[1])``,
        c[3 k + ch].

    ``name`` is the macro ``SKYSH_DERING_NAME``, which the function's definition expands.
-   :func:`certificate_lists`, :data:`FINAL_SLACK`, :data:`GOLDEN`: the certificate's numbers C and the
    JavaScript export both take (as #defines, in its ``DATA``); :data:`NORMAL`, :data:`HALVINGS`,
    :data:`CERTIFICATE_COST`.
-   :func:`dering_file`, :func:`supported`, :data:`LANGUAGES`, :data:`WORDS`.

Each returns 1 when no row is non-negative (the last row is then applied), else 0, writes the
factors applied and the window's position along :func:`skysh.post.dering.window_table`. Its
coefficients must be finite (as every skysh output is); C returns 1 at once for a NaN or an inf,
c untouched (factors 1, position 0). C (double) returns Python's position (to one lattice step of
:func:`skysh.post.dering.tolerance` at a rounding tie: 2^-10 of a row for exact targets, 1/32 for
certified ones); GLSL and HLSL (float, with float guards and a 256-ulp allowance) may window more
near a tie and report failure for lights whose last-row margin (1e-9 of the mean) is below float's
resolution. C needs ``<math.h>``; GLSL 3.10 ES / 4.0+. The JavaScript export writes its own
(:mod:`skysh.export.js`).
"""

from __future__ import annotations

import math

import numpy as np

from skysh.checks import check_bands, check_choice
from skysh.export import template
from skysh.literals import double_literal, float32_literal
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

__all__ = ["dering_source"]

LANGUAGES: tuple[str, ...] = ("c", "glsl", "hlsl")
"""Languages of :func:`dering_source`."""

WORDS: dict[str, tuple[str, ...]] = {
    "c": ("c_like_words_c.h", "c_like_words_math.h"),
    "glsl": ("c_like_words_glsl.glsl", "c_like_words_shader.glsl", "c_like_words_math.h"),
    "hlsl": ("c_like_words_hlsl.hlsl", "c_like_words_shader.glsl", "c_like_words_math.h"),
}
"""The templates defining the C-like kernel's words (types, qualifiers, functions) in each language, in order:
the language's own, those GLSL and HLSL share, then the math names C's double build and the shaders share (a
language naming them otherwise defines them first)."""

GUARDS: dict[str, tuple[float, float, float, float]] = {
    "double": (shmin.TINY, shmin.FLOOR, shmin.POLE, shmin.ALLOWANCE),
    "float": (1e-30, 1e-18, 1e-12, shmin.ALLOWANCE / 2.0**-52 * 2.0**-23)}
"""(tiny, floor, pole, allowance) per precision: Python's in double; in float the same roles
within float's range (floor^2 and a / pole^3 normal and finite for |f| <= pi)."""

NORMAL: dict[str, float] = {"double": float(np.finfo(np.float64).smallest_normal),
                           "float": float(np.finfo(np.float32).smallest_normal)}
"""The least normal number per precision (2^-1022, 2^-126): the shaders' power-of-two normaliser takes max |c| at
least this (``SKYSH_DERING_NORMAL``; C normalises by frexp)."""

HALVINGS: int = round(-math.log2(dering.WINDOW_TOLERANCE))
"""10: the bisection's halvings of a row step (its lattice, 2^HALVINGS points, is exact in float too)."""

SHADER_REFUSAL: str = ("the certificate of 5..7-band deringing (and 4-band radiance) is C-only: its cost in C per call, "
                       "%s, is too much for a shader")
"""Why GLSL and HLSL refuse the deringing that needs the certificate (:func:`dering_source`'s message, ``%s``:
:data:`CERTIFICATE_COST`)."""

CERTIFICATE_COST: str = ("0.34 to 0.68 ms and 2.5e4 SH evaluations on skies (5 to 7 bands, median), 0.95 to 2.1 ms and "
                         "6.3e4 to 6.6e4 on lights (up to 9.3 ms and 1.2e5), measured by python "
                         "tests/export/test_export_dering_certificate.py (gcc -O2) on the 2-core CI machine")
"""The C certificate's cost per call, as measured by the command it names on the project's 2-core CI machine (times
depend on the machine; the evaluations, function-direction pairs, do not). The templates name this constant rather
than repeat its figures."""


def supported(language: str, bands: int, target: str = "irradiance") -> bool:
    """Whether ``language``'s export derings ``bands`` bands: C always, the shaders on the exact minimum only."""
    return language == "c" or dering.exact_target(bands, target)


def dering_file(bands: int, target: str = "irradiance") -> str:
    """The template of the deringing of ``bands`` bands and ``target``."""
    return "c_like_dering3.h" if dering.exact_target(bands, target) else "c_like_dering_certificate_c.h"


def words(language: str) -> str:
    """The C-like kernel's words in ``language`` (:data:`WORDS`): its templates as shipped, one after another."""
    return "\n".join(template.text(name) for name in WORDS[language])


def _certificate(literal) -> dict[str, object]:
    """The certificate's #define values (C, double): sizes, grid, refinement and the basis recurrence."""
    return {"DIRECTIONS": shmin.DIRECTIONS, "SPLIT": shmin.SPLIT, "LEVELS": shmin.LEVELS, "BUDGET": shmin.CELL_BUDGET,
            "COVER": literal(shmin.COVER_RADIUS), "FINAL": literal(FINAL_SLACK),
            "SAMPLE_ROUNDING": literal(shmin.SAMPLE_ROUNDING), "PI": literal(math.pi), "GOLDEN": literal(GOLDEN)}


def certificate_lists(bands: int) -> dict[str, list[float]]:
    """The certificate's per-band numbers at ``bands``: the basis recurrence's constants (skysh.sh.basis.basis_recurrence:
    DIAG, NEXT = sqrt(2l + 1) DIAG[l - 1], RA, RB row-major) and the per-band norms sqrt((2l + 1) / (4 pi)) of the
    curvature (skysh.sh.minimum.curvature); C takes them as #defines, JavaScript in its DATA."""
    rec = sh.basis_recurrence(bands)
    nxt = [0.0] + [math.sqrt(2 * l + 1) * rec.diag[l - 1] for l in range(1, bands)]
    norm = [math.sqrt((2 * l + 1) / (4 * math.pi)) for l in range(bands)]
    return {"DIAG": [float(v) for v in rec.diag], "NEXT": nxt, "RA": rec.a.ravel().tolist(), "RB": rec.b.ravel().tolist(),
            "BAND_NORM": norm}


FINAL_SLACK: float = (shmin.COVER_RADIUS / shmin.SPLIT**shmin.LEVELS) ** 2
"""The certificate's last level's slack per unit curvature, (COVER_RADIUS / SPLIT^LEVELS)^2 (skysh.post.dering._fraction's
``final``): its hopeless test and the certified search's start."""

GOLDEN: float = 3.0 - math.sqrt(5.0)
"""The Fibonacci grid's angle step over pi (skysh.sh.minimum.fibonacci: phi_i = i pi (3 - sqrt 5))."""


def _recurrence(bands: int, literal) -> dict[str, str]:
    """:func:`certificate_lists` as #define values."""
    return {key: ", ".join(map(literal, values)) for key, values in certificate_lists(bands).items()}


def dering_defines(target: str = "irradiance", precision: str = "double", name: str = "skysh_dering",
                   bands: int = 3) -> str:
    """
    The ``#define`` lines the deringing of ``bands`` (in [1, 7]) reads (:func:`dering_file`), for ``target``
    (``"irradiance"`` or ``"radiance"``: what must be non-negative) in ``precision`` (``"double"``: C;
    ``"float"``: the shaders, exact targets only), the function named ``name`` (an ASCII identifier).
    """
    check_choice(target, "target", dering.DERING_TARGETS)
    check_choice(precision, "precision", tuple(GUARDS))
    bands = check_bands(bands, high=dering.MAX_DERING_BANDS)
    if not (name.isidentifier() and name.isascii()):
        raise ValueError(f"name must be an ASCII identifier, got {name!r}")
    if precision == "float" and not dering.exact_target(bands, target):
        raise ValueError(f"precision must be double for {bands}-band {target} deringing: "
                         + SHADER_REFUSAL % CERTIFICATE_COST)
    literal = double_literal if precision == "double" else float32_literal
    table = dering.window_table(bands, target)
    numbers = dict(zip(("TINY", "FLOOR", "POLE", "ROUND", "NORMAL"), (*GUARDS[precision], NORMAL[precision])))
    lists = {"TABLE": table.ravel(), "KERNEL": dering.KERNELS[target][sh.band_of_index(bands)]}
    basis = {"Y00": sh.Y00, "K_LINEAR": sh.K_LINEAR, "K_PRODUCT": sh.K_PRODUCT, "K_ZONAL": sh.K_ZONAL,
             "K_SECTORAL": sh.K_SECTORAL}
    extra = {**_certificate(literal), **_recurrence(bands, literal)} if not dering.exact_target(bands, target) else {
        "STEPS": shmin.NEWTON_STEPS, "USED": min(bands, 3) ** 2}
    return template.defines({
        "SKYSH_DERING_NAME": name, "SKYSH_DERING_BANDS": bands, "SKYSH_DERING_COUNT": bands * bands,
        "SKYSH_DERING_ROWS": len(table), "SKYSH_DERING_HALVINGS": HALVINGS,
        "SKYSH_DERING_LATTICE": literal(1.0 / dering.tolerance(bands, target)),
        "SKYSH_DERING_SUBNORMAL": f"({dering.SUBNORMAL_EXPONENT})",
        **{f"SKYSH_DERING_{key}": ", ".join(map(literal, values)) for key, values in lists.items()},
        **{f"SKYSH_DERING_{key}": literal(value) for key, value in numbers.items()},
        **{f"SKYSH_DERING_{key}": value for key, value in extra.items()},
        **({f"SKYSH_{key}": literal(value) for key, value in basis.items()} if dering.exact_target(bands, target) else {}),
    })


def dering_source(language: str, target: str = "irradiance", name: str = "skysh_dering", bands: int = 3) -> str:
    """
    Source text of a function that derings one RGB radiance SH of ``bands`` bands in place.

    Parameters
    ----------
    language
        One of :data:`LANGUAGES`: ``"c"`` (double), ``"glsl"``, ``"hlsl"`` (float).
    target
        ``"irradiance"`` or ``"radiance"``: what must be non-negative (table and kernel baked in).
    name
        The function's name, an ASCII identifier.
    bands
        N in [1, 7]; GLSL and HLSL: the exact targets only (:func:`supported`).

    Returns
    -------
    str
        The language's words, the numbers and the function (signatures in the module
        docstring), no includes.

    Raises
    ------
    ValueError
        Unknown language or target, a bad name or band count, or a shader asked for the certificate
        (:data:`SHADER_REFUSAL`).
    """
    check_choice(language, "language", LANGUAGES)
    defines = dering_defines(target, "double" if language == "c" else "float", name, bands)
    return "\n".join((words(language), defines, template.text(dering_file(bands, target))))
