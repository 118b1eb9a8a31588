"""
argparse types shared by the ``skysh`` command line and the tools
=================================================================

-   :func:`integer`: an argparse ``type`` accepting the text of an integer in [low, high].

This module imports argparse only: :mod:`skysh.cli` builds its parser with it before any
command runs, and a command line that never reaches a command loads nothing else.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

__all__ = ["integer"]


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
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {text!r}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {text!r}")
        return value

    parse.__name__ = "integer"  # argparse names a type by it in some messages
    return parse
