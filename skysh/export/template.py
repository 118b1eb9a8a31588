"""
The exports' source files and their holes
==========================================

The C, GLSL, HLSL and JavaScript that the exports write live as real files in
``skysh/export/templates/``, each checked as it stands by its own compiler,
validator or runtime. Python fills in numbers and a few switches, never
statements (Filament's cmgen and pygfx's shader files work the same way):

-   :func:`fill`: a template's text with every hole ``{{NAME}}`` replaced; a
    missing or an unused name is an error, as is a template with more than
    :data:`MAX_HOLES` distinct names.
-   :func:`holes`: the names a template asks for; :func:`text`: a file as shipped.
-   :func:`defines`: ``#define NAME value`` lines, the numbers and switches of a C-like
    data section (the one form of C, GLSL and HLSL that Python writes).
-   :data:`TEMPLATE_DIR`, :data:`HOLE`, :data:`MAX_HOLES`, :data:`MACRO`.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

__all__ = ["text"]

TEMPLATE_DIR: Path = Path(__file__).with_name("templates")
"""The folder of the exports' source files (shipped as package data)."""

HOLE: re.Pattern[str] = re.compile(r"\{\{([A-Z][A-Z0-9_]*)\}\}")
"""A hole: ``{{NAME}}``, the name upper case (``{{`` followed by anything else is source text)."""

MAX_HOLES: int = 10
"""Issue 24: at most about ten names per template; numbers and switches only."""

MACRO: re.Pattern[str] = re.compile(r"SKYSH_[A-Z0-9_]+")
"""A name :func:`defines` writes: the exports' own upper-case ``SKYSH_`` prefix."""


@cache
def text(name: str) -> str:
    """The template file ``name`` (inside :data:`TEMPLATE_DIR`) as shipped."""
    path = TEMPLATE_DIR / name
    if path.parent != TEMPLATE_DIR or not path.is_file():
        raise ValueError(f"name must be a file of {TEMPLATE_DIR}, got {name!r}")
    return path.read_text(encoding="utf-8")


@cache
def holes(name: str) -> frozenset[str]:
    """The distinct hole names of template ``name``; more than :data:`MAX_HOLES` is an error."""
    found = frozenset(HOLE.findall(text(name)))
    if len(found) > MAX_HOLES:
        raise ValueError(f"template {name} has {len(found)} holes, more than {MAX_HOLES}: {sorted(found)}")
    return found


def fill(name: str, **values: str) -> str:
    """
    Template ``name`` with each ``{{NAME}}`` replaced by ``values[NAME]``.

    Raises
    ------
    ValueError
        A hole without a value, a value without a hole, or a value that is not a str.
    """
    wanted = holes(name)
    missing, unused = sorted(wanted - values.keys()), sorted(values.keys() - wanted)
    if missing or unused:
        raise ValueError(f"template {name}: missing {missing}, unused {unused}")
    for key, value in values.items():
        if not isinstance(value, str):
            raise ValueError(f"template {name}: {key} must be a str, got {type(value).__name__}")
    return HOLE.sub(lambda match: values[match.group(1)], text(name))


def defines(values: dict[str, object]) -> str:
    """
    ``#define NAME value`` lines, one per entry in order, each ending with a newline.

    ``values`` maps a :data:`MACRO` name to its text (``str(value)``: a literal already written,
    an integer, or a comma-separated list of literals). Raises ValueError for another name or a
    value spanning lines.
    """
    lines = []
    for name, value in values.items():
        text = str(value)
        if not MACRO.fullmatch(name) or "\n" in text:
            raise ValueError(f"#define {name!r}: the name must match {MACRO.pattern} and the value be one line")
        lines.append(f"#define {name} {text}\n")
    return "".join(lines)
