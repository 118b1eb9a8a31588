"""
Deringing of 3-band SH in C, GLSL and HLSL
==========================================

The function that windows 3-band radiance SH in place as :func:`skysh.post.dering.dering`
does is written once, by hand, in ``skysh/export/templates/c_like_dering3.h`` over the words
of the C-like kernel (:data:`WORDS`, :func:`words`); this module writes the numbers it reads:

-   :func:`dering_defines`: its ``#define`` lines, the same table, kernel, basis constants,
    Newton steps and guards as Python's (:data:`GUARDS` per precision).
-   :func:`dering_source`: the self-contained function in one language (the words, the numbers,
    the function), as the C, GLSL and HLSL exports embed it (:mod:`skysh.export.c_like`):

    -   C: ``int name(double c[9][3], double scales_out[3])``, ``static inline``;
    -   GLSL, HLSL: ``int name(inout float c[27], out float scales_out[3])``, c[3 k + ch].

    ``name`` is the macro ``SKYSH_DERING_NAME``, which the function's definition expands.
-   :data:`LANGUAGES`, :data:`WORDS`, :func:`words`.

Each returns 1 when no row is non-negative (the last row is then applied), else 0. C (double)
picks Python's row; GLSL and HLSL (float, with float guards and a 256-ulp allowance) may pick a
later row near a tie and report failure for lights whose last-row margin (1e-9 of the mean) is
below float's resolution. C needs ``<math.h>``; GLSL 3.10 ES / 4.0+. The JavaScript export
writes its own (:mod:`skysh.export.js`).
"""

from __future__ import annotations

from skysh.checks import check_choice
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


def words(language: str) -> str:
    """The C-like kernel's words in ``language`` (:data:`WORDS`): its templates as shipped, one after another."""
    return "\n".join(template.text(name) for name in WORDS[language])


def dering_defines(target: str = "irradiance", precision: str = "double", name: str = "skysh_dering3") -> str:
    """
    The ``#define`` lines ``c_like_dering3.h`` reads, for ``target`` (``"irradiance"`` or
    ``"radiance"``: what must be non-negative) in ``precision`` (``"double"``: C; ``"float"``: the
    shaders), the function named ``name`` (an ASCII identifier).
    """
    check_choice(target, "target", dering.DERING_TARGETS)
    check_choice(precision, "precision", tuple(GUARDS))
    if not (name.isidentifier() and name.isascii()):
        raise ValueError(f"name must be an ASCII identifier, got {name!r}")
    literal = double_literal if precision == "double" else float32_literal
    table = dering.window_table(3, target)
    numbers = dict(zip(("TINY", "FLOOR", "POLE", "ROUND"), GUARDS[precision]))
    lists = {"TAB1": table[:, 1], "TAB2": table[:, 2], "KERNEL": dering.KERNELS[target][sh.band_of_index(3)]}
    basis = {"Y00": sh.Y00, "K_LINEAR": sh.K_LINEAR, "K_PRODUCT": sh.K_PRODUCT, "K_ZONAL": sh.K_ZONAL,
             "K_SECTORAL": sh.K_SECTORAL}
    return template.defines({
        "SKYSH_DERING_NAME": name, "SKYSH_DERING_ROWS": len(table), "SKYSH_DERING_STEPS": shmin.NEWTON_STEPS,
        **{f"SKYSH_DERING_{key}": ", ".join(map(literal, values)) for key, values in lists.items()},
        **{f"SKYSH_DERING_{key}": literal(value) for key, value in numbers.items()},
        **{f"SKYSH_{key}": literal(value) for key, value in basis.items()},
    })


def dering_source(language: str, target: str = "irradiance", name: str = "skysh_dering3") -> str:
    """
    Source text of a function that derings one 3-band RGB radiance SH in place.

    Parameters
    ----------
    language
        One of :data:`LANGUAGES`: ``"c"`` (double), ``"glsl"``, ``"hlsl"`` (float).
    target
        ``"irradiance"`` or ``"radiance"``: what must be non-negative (table and kernel baked in).
    name
        The function's name, an ASCII identifier.

    Returns
    -------
    str
        The language's words, the numbers and the function (signatures in the module
        docstring), no includes.
    """
    check_choice(language, "language", LANGUAGES)
    defines = dering_defines(target, "double" if language == "c" else "float", name)
    return "\n".join((words(language), defines, template.text("c_like_dering3.h")))
