"""
Number text for generated source: one writer per language and precision
========================================================================

Every number skysh writes into C, C++, C#, GLSL, HLSL or JavaScript goes through
one of these, so a constant reads back as exactly the value it was written from:

-   :func:`double_literal`: the shortest text that reads back as the same double
    (C ``double``, JavaScript ``number``), always with a ``.`` or an exponent.
-   :func:`float32_literal`: the shortest text that reads back as the same float32
    (C ``float`` with ``f`` added, GLSL and HLSL as written).
-   :func:`real_literal`: a C literal of ``double`` or ``float``.
-   :func:`suffixed_literal`: the double's text with the C++/C# ``f`` suffix (the
    engines' snippets: the compiler rounds it once, to the float nearest the double).
-   :func:`number_rows`: literals laid out a few per line.
-   :data:`FLOAT32_MAX`, :data:`FLOAT64_MAX`: the ranges a literal may take.
"""

from __future__ import annotations

import numpy as np

from skysh.checks import check_choice, check_scalar

__all__ = ["double_literal", "float32_literal", "real_literal", "suffixed_literal", "number_rows"]

FLOAT32_MAX: float = float(np.finfo(np.float32).max)
"""Largest finite float32: beyond it a float32 literal would read back as inf."""

FLOAT64_MAX: float = float(np.finfo(np.float64).max)
"""Largest finite double: a double literal's range."""

_PLAIN_REALS: tuple[type, ...] = (float, np.float64, np.float32)


def _checked(value: object, high: float, unit: str = "") -> float:
    """``value`` in [-high, high]: a plain float by one comparison (NaN fails it), the rest by ``check_scalar``."""
    if type(value) in _PLAIN_REALS and -high <= value <= high:  # type: ignore[operator]
        return float(value)  # type: ignore[arg-type]
    return check_scalar(value, "value", -high, high, unit=unit)


def double_literal(value: float) -> str:
    """Shortest text that reads back as the same double, always with a '.' or an exponent."""
    text = repr(_checked(value, FLOAT64_MAX))
    return text if any(ch in text for ch in ".en") else text + ".0"


def float32_literal(value: float) -> str:
    """Shortest text that reads back as the same float32 (valid in C, GLSL and HLSL, no suffix)."""
    number = _checked(value, FLOAT32_MAX, unit="(the float32 range)")
    return np.format_float_scientific(np.float32(number), unique=True, trim="0")


def real_literal(value: float, real: str) -> str:
    """A C literal of ``real`` (``"double"``: :func:`double_literal`; ``"float"``: float32 text with ``f``)."""
    check_choice(real, "real", ("double", "float"))
    return double_literal(value) if real == "double" else float32_literal(value) + "f"


def suffixed_literal(value: float) -> str:
    """:func:`double_literal` with the C++/C# float suffix ``f`` (the compiler rounds it once)."""
    return double_literal(value) + "f"


def number_rows(items: list[str], indent: str, per_line: int = 6) -> str:
    """``items`` joined by commas, ``per_line`` a line, lines joined by a comma, a newline and ``indent``."""
    lines = [", ".join(items[k : k + per_line]) for k in range(0, len(items), per_line)]
    return (",\n" + indent).join(lines)
