"""
argparse types shared by the ``skysh`` command line and the tools
=================================================================

-   :func:`integer`: an argparse ``type`` accepting the text of an integer in [low, high].
-   :func:`real`: an argparse ``type`` accepting the text of a finite real number.

Both read ASCII decimal text only (``[+-]digits``, and for :func:`real` a point and an
exponent): Python's ``int`` and ``float`` would also take other scripts' digits (fullwidth
or Arabic-Indic ones), underscores (``'1_0'``) and surrounding spaces, which a command line should refuse
rather than guess. A real number whose text is not zero but whose value underflows to 0 or
to a subnormal float64 (``1e-400``, ``1e-310``), or overflows (``1e400``), is refused too.

This module imports argparse only: :mod:`skysh.app.cli` builds its parser with it before any
command runs, and a command line that never reaches a command loads nothing else.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable

__all__ = ["integer"]

FLOAT64_TINY: float = 2.2250738585072014e-308
"""Smallest positive normal float64 (numpy.finfo(float).tiny): a smaller non-zero value has lost precision."""

_INTEGER: re.Pattern[str] = re.compile(r"[+-]?[0-9]+")
_REAL: re.Pattern[str] = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NONZERO_DIGIT: re.Pattern[str] = re.compile(r"^[^eE]*[1-9]")


def integer(low: int = 1, high: int | None = None) -> Callable[[str], int]:
    """
    An argparse ``type`` for an integer in [low, high] (``high`` None: no upper bound).

    Parameters
    ----------
    low, high
        The closed interval of accepted values; default 1 and no bound: a positive integer.

    Returns
    -------
    callable
        ``parse(text) -> int``; any other text or value raises :class:`argparse.ArgumentTypeError`
        ``"expected <what>, got '<text>'"``, where <what> is ``"a positive integer"`` (low 1, no
        high), ``"an integer >= <low>"`` or ``"an integer in [<low>, <high>]"``; argparse prints
        it after the option's name.

    Examples
    --------
    >>> jobs = integer()
    >>> jobs("3")
    3
    >>> integer(16, 4096)("8")
    Traceback (most recent call last):
    argparse.ArgumentTypeError: expected an integer in [16, 4096], got '8'
    """
    if high is None:
        wanted = "a positive integer" if low == 1 else f"an integer >= {low}"
    else:
        wanted = f"an integer in [{low}, {high}]"

    def parse(text: str) -> int:
        if _INTEGER.fullmatch(text) is None:
            raise argparse.ArgumentTypeError(f"expected {wanted} (ASCII digits), got {text!r}")
        try:
            value = int(text)
        except ValueError:  # beyond sys.get_int_max_str_digits(): far outside any range
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {len(text)} digits") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {text!r}")
        return value

    parse.__name__ = "integer"  # argparse names a type by it in some messages
    return parse


def real(text: str) -> float:
    """
    An argparse ``type`` for a finite real number written in ASCII decimal.

    Parameters
    ----------
    text
        ``[+-]`` digits with an optional point and ``e``/``E`` exponent, e.g. ``30``, ``-0.5``, ``1e-3``.

    Returns
    -------
    float
        The value.

    Raises
    ------
    argparse.ArgumentTypeError
        For any other text (other scripts' digits, underscores, spaces, ``inf``, ``nan``), and
        for a value that overflows float64 or whose non-zero text underflows to 0 or to a
        subnormal number (below :data:`FLOAT64_TINY` in magnitude).

    Examples
    --------
    >>> real("2.5")
    2.5
    >>> real("1e-400")
    Traceback (most recent call last):
    argparse.ArgumentTypeError: expected a number within float64's normal range, got '1e-400' (it underflows)
    """
    if _REAL.fullmatch(text) is None:
        raise argparse.ArgumentTypeError(f"expected a finite number in ASCII decimal, got {text!r}")
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r} (it overflows float64)")
    if abs(value) < FLOAT64_TINY and _NONZERO_DIGIT.match(text) is not None:
        raise argparse.ArgumentTypeError(f"expected a number within float64's normal range, got {text!r} (it underflows)")
    return value
