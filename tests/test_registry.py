"""
One fact in one place, used by identity (issue 24, item 5)
==========================================================

The shared facts (the domains and their maps, Kasten's coefficients, the term order, the basis
constants, the albedo range, the per-frame options, the literal writers, the export languages)
are each defined once. Every ``skysh`` module is imported, and wherever one of them binds a
registered name at module level, the object must *be* the registry's (``is``, not ``==``): a copy,
even an equal one, fails. Each fact must also be used somewhere besides its home, so the test
cannot pass by finding nothing.
"""

from __future__ import annotations

import copy
import importlib
import pkgutil
import re
from pathlib import Path
from types import ModuleType

import pytest

import skysh
from skysh import domain, literals, options
from skysh.sh import basis


def registry() -> dict[str, object]:
    """Name -> the one object every module binding that name must hold."""
    return {
        "SKY": domain.SKY, "SUN": domain.SUN, "KASTEN_COEFFICIENTS": domain.KASTEN_COEFFICIENTS,
        "TERM_ORDER": domain.TERM_ORDER, "MAX_DEGREE": domain.MAX_DEGREE, "check_degrees": domain.check_degrees,
        "term_index": domain.term_index,
        "Y00": basis.Y00, "K_LINEAR": basis.K_LINEAR, "K_PRODUCT": basis.K_PRODUCT, "K_ZONAL": basis.K_ZONAL,
        "K_SECTORAL": basis.K_SECTORAL, "BASIS_CONSTANTS": basis.BASIS_CONSTANTS,
        "ALBEDO_RANGE": options.ALBEDO_RANGE, "check_albedo": options.check_albedo, "Options": options.Options,
        "double_literal": literals.double_literal, "float32_literal": literals.float32_literal,
        "real_literal": literals.real_literal,
    }


HOMES: frozenset[str] = frozenset({"skysh.domain", "skysh.sh.basis", "skysh.options", "skysh.literals"})
"""The modules the facts are defined in."""


def all_modules() -> list[ModuleType]:
    """Every module of the package, imported (the entry point ``__main__`` excepted: it runs the CLI)."""
    names = [m.name for m in pkgutil.walk_packages(skysh.__path__, "skysh.") if not m.name.endswith("__main__")]
    return [importlib.import_module(name) for name in sorted(names)]


def copies(modules: list[ModuleType], facts: dict[str, object]) -> list[str]:
    """Module-level bindings of a registered name to another object."""
    return [f"{m.__name__}.{name}" for m in modules for name, fact in facts.items()
            if name in vars(m) and vars(m)[name] is not fact]


def test_every_binding_is_the_fact_itself():
    assert copies(all_modules(), registry()) == []


@pytest.mark.parametrize("name", sorted(registry()))
def test_each_fact_is_used_beyond_its_home(name):
    """Bound by name (``from skysh.domain import SKY``) or read through its module (``domain.SKY``,
    ``sh.Y00``) in some module other than its home; else the registry entry is stale."""
    fact = registry()[name]
    bound = [m.__name__ for m in all_modules() if m.__name__ not in HOMES and vars(m).get(name) is fact]
    read = [m.__name__ for m in all_modules() if m.__name__ not in HOMES and m.__file__
            and re.search(rf"\b\w+\.{name}\b", Path(m.__file__).read_text(encoding="utf-8"))]
    assert bound or read, f"{name} is used nowhere but its home: the registry entry is stale"


def test_negative_control_an_equal_copy_fails():
    fake = ModuleType("skysh.fake")
    fake.SKY = copy.copy(domain.SKY)  # type: ignore[attr-defined]  # equal, but another object
    fake.Y00 = float(repr(basis.Y00))  # type: ignore[attr-defined]
    fake.KASTEN_COEFFICIENTS = tuple(list(domain.KASTEN_COEFFICIENTS))  # type: ignore[attr-defined]
    fake.double_literal = domain.SKY  # type: ignore[attr-defined]  # a name bound to the wrong fact
    assert fake.SKY == domain.SKY and fake.Y00 == basis.Y00  # type: ignore[attr-defined]
    assert sorted(copies([fake], registry())) == [
        "skysh.fake.KASTEN_COEFFICIENTS", "skysh.fake.SKY", "skysh.fake.Y00", "skysh.fake.double_literal"]
