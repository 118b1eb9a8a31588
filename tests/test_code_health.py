"""
Code health, measured (issue 14)
================================

Every ``.py`` file below ``skysh/`` and ``tools/`` (recursively) is parsed, nothing is
imported or run, and held to:

-   :data:`MAX_FUNCTION_LINES` lines per function or method, from its ``def`` line to its last
    line (decorators not counted; a nested function counts in its parent and on its own);
-   :data:`MAX_COMPLEXITY`, McCabe's cyclomatic complexity as radon computes it
    (:func:`radon.complexity.cc_visit`; a closure or method is its own block, as radon reports it).

The package, the tools and ``benchmarks/`` are also held to the "no reach-ins" rules:

-   no ``from M import _name`` where ``M`` is another first-party module (``skysh``, its
    modules, the tools' modules and packages, the benchmarks' modules) and ``_name`` is not
    itself a module (``from skysh import checks as _checks`` imports a module and is fine);
-   no ``M._name`` (nor ``getattr``/``setattr``/``delattr`` with ``"_name"``) where ``M`` is a
    name bound by an import of another first-party module, or of an object taken from one
    (``SkySH._x``); dunders (``__name__``) are public;
-   no ``obj._name`` for the instance privates other modules are known to have been read
    through: :data:`KNOWN_INSTANCE_PRIVATES` (issue 14's list), and every ``self._name`` a class
    of another ``skysh`` module assigns or private method it defines (``def _one(self, ...)``:
    :func:`instance_privates`), unless the file defines that name for its own objects. An
    instance's type cannot be known without running the code, so this is a name-level check; a
    reach-in under a fresh name would pass it.

One source for every fact: the turbidity and sun-zenith domains are constants of the modules
that own them (:func:`prose_domains`); where prose repeats them (numpy-style docstrings state
the valid range; comments; help and message texts) every interval ``[a, b]`` written next to the
word *turbidity*, or next to *zenith* in radians (an end in pi) or degrees (``deg`` beside
it), must equal one of those constants (:func:`prose_ranges`). Intervals whose ends are not
numbers (``[{low:g}, {high:g}]``, ``$turbidity_domain``) are derived from the constants in code.

Module size: issue 24 ("One algorithm, one place") retired the cap of 700 physical lines per module
(it bred squeezed prose and modules cut by size rather than by concept) in favour of budgets of code
lines (physical lines less docstrings, comments and blank lines), measured by ``tools/code_size.py``
with the package's import cycles and ``__all__`` names. The tests here hold that tool's counting to
small sources with known answers and its run over ``skysh/`` to basic sanity.

Every violation is listed in the failure message as ``path:line: what (measured > limit)``.
The negative controls feed small synthetic sources to the same checkers. The checked files are
parsed, never imported; the domains are read from the modules that own them.
"""

from __future__ import annotations

import ast
import io
import json
import math
import re
import textwrap
import tokenize
from collections.abc import Iterable, Iterator
from functools import cache
from pathlib import Path
from typing import NamedTuple

import pytest
from conftest import TOOLS, load_script
from radon.complexity import cc_visit
from radon.visitors import Class, Function

ROOT: Path = Path(__file__).resolve().parent.parent

code_size = load_script(TOOLS / "code_size.py", "code_size_under_test")
"""``tools/code_size.py`` (issue 24's code-line measure), loaded as a module."""

MAX_FUNCTION_LINES: int = 60
"""Issue 24: code lines per function (``tools/code_size.py``'s count: docstrings, comments and blank
lines are free, so prose is never squeezed to pay for code)."""
MAX_COMPLEXITY: int = 15
"""Issue 24: radon's grade C ends at 20; 15 keeps a function's paths few enough to test each."""

SIZE_SCOPE: tuple[str, ...] = ("skysh", "tools")
"""Folders held to the size and complexity limits."""
PRIVACY_SCOPE: tuple[str, ...] = ("skysh", "tools", "benchmarks")
"""Folders held to the no-reach-in rules (tests may look inside the modules they test)."""

KNOWN_INSTANCE_PRIVATES: dict[str, str] = {
    "_plans": "SkySH's fitted tables (export.py read sky._plans)",
    "_NEWTON_STEPS": "dering's iteration count (the report monkeypatched it)",
    "_X_SCALE": "runtime's domain scale (export.py read it)",
    "_TMAX": "runtime's turbidity bound (export.py read it)",
    "_solve": "fit's solver (the report called fit._solve)",
    "_project_one": "fit's projection (the report called fit._project_one)",
    "_luminance_scale": "preetham's luminance scale (runtime imported it)",
}
"""Private names issue 14 found read from outside their module, with where."""


class Violation(NamedTuple):
    path: str  # relative to the repository root
    line: int
    what: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.what}"


# --------------------------------------------------------------------------- #
# Files and first-party modules
# --------------------------------------------------------------------------- #
def python_files(folders: Iterable[str]) -> list[Path]:
    """Every ``.py`` file below the given folders of the repository, sorted."""
    return sorted(p for folder in folders for p in (ROOT / folder).rglob("*.py") if "__pycache__" not in p.parts)


def module_name(path: Path) -> str:
    """The dotted name a file is imported under: ``skysh.table.fit``, ``report.common``, ``bench_runtime``."""
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[0] in ("tools", "benchmarks"):  # both folders are put on sys.path, not imported as packages
        parts = parts[1:]
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


@cache
def first_party() -> frozenset[str]:
    """Dotted names of every first-party module and package (``skysh``, the tools, the benchmarks)."""
    names = {module_name(p) for p in python_files(PRIVACY_SCOPE)}
    return frozenset(names | {n.rsplit(".", i)[0] for n in names for i in range(n.count(".") + 1)})


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _is_first_party(dotted: str, modules: frozenset[str]) -> bool:
    return dotted.split(".")[0] in {m.split(".")[0] for m in modules}


# --------------------------------------------------------------------------- #
# Size and complexity
# --------------------------------------------------------------------------- #
def _functions(tree: ast.AST, prefix: str = "") -> Iterator[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield prefix + node.name, node
            yield from _functions(node, prefix + node.name + ".")
        elif isinstance(node, ast.ClassDef):
            yield from _functions(node, prefix + node.name + ".")
        else:
            yield from _functions(node, prefix)


def function_lengths(path: str, source: str) -> list[Violation]:
    """Functions of more than :data:`MAX_FUNCTION_LINES` code lines (a nested function counts in its parent too)."""
    tree = ast.parse(source)
    code = sorted(code_size.code_lines(source, tree))
    found = []
    for name, node in _functions(tree):
        length = sum(node.lineno <= line <= (node.end_lineno or node.lineno) for line in code)
        if length > MAX_FUNCTION_LINES:
            found.append(Violation(path, node.lineno, f"function {name} of {length} code lines > {MAX_FUNCTION_LINES}"))
    return found


def _blocks(blocks: Iterable[Function | Class], prefix: str = "") -> Iterator[tuple[str, Function]]:
    for block in blocks:
        if isinstance(block, Class):
            yield from _blocks(block.methods, prefix + block.name + ".")
            yield from _blocks(block.inner_classes, prefix + block.name + ".")
        else:
            yield prefix + block.name, block
            yield from _blocks(block.closures, prefix + block.name + ".")


def complexities(path: str, source: str) -> list[Violation]:
    top = [b for b in cc_visit(source) if not (isinstance(b, Function) and b.is_method)]  # methods come with their class
    return [Violation(path, block.lineno, f"function {name} of cyclomatic complexity {block.complexity} > {MAX_COMPLEXITY}")
            for name, block in _blocks(top) if block.complexity > MAX_COMPLEXITY]


# --------------------------------------------------------------------------- #
# Reach-ins
# --------------------------------------------------------------------------- #
def _resolve_from(node: ast.ImportFrom, own: str, is_package: bool) -> str:
    """The absolute dotted module of ``from ... import``, relative imports resolved against ``own``."""
    if not node.level:
        return node.module or ""
    base = own.split(".") if is_package else own.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def package_of(dotted: str) -> str:
    """The package privacy is shared in (issue 24): a ``skysh`` sub-package (``skysh.export.js`` ->
    ``skysh.export``), a module of ``skysh/``'s root on its own (``skysh.domain``), the tools' first name
    (``report.common`` -> ``report``). An object's dotted origin maps to its module's package."""
    parts = dotted.split(".")
    return ".".join(parts[:2]) if parts[0] == "skysh" else parts[0]


def _bindings(tree: ast.AST, own: str, is_package: bool, modules: frozenset[str]) -> tuple[dict[str, str], list[Violation]]:
    """Names bound to other first-party modules or their objects (name -> dotted origin),
    and the ``from M import _name`` violations met on the way (path left blank)."""
    bound: dict[str, str] = {}
    found: list[Violation] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if _is_first_party(alias.name, modules) and package_of(alias.name) != package_of(own):
                    if alias.asname:
                        bound[alias.asname] = alias.name
                    else:
                        bound[alias.name.split(".")[0]] = alias.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom):
            origin = _resolve_from(node, own, is_package)
            if not _is_first_party(origin, modules) or package_of(origin) == package_of(own):
                continue
            for alias in node.names:
                target = f"{origin}.{alias.name}"
                if _is_private(alias.name) and target not in modules:
                    found.append(Violation("", node.lineno, f"from {origin} import {alias.name}: another package's private name"))
                bound[alias.asname or alias.name] = target
    return bound, found


def _dotted(node: ast.expr, bound: dict[str, str]) -> str | None:
    """The first-party origin an expression names (``sky`` -> None, ``skysh.table.fit`` -> ``skysh.table.fit``)."""
    if isinstance(node, ast.Name):
        return bound.get(node.id)
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value, bound)
        return None if base is None else f"{base}.{node.attr}"
    return None


def _self_privates(tree: ast.AST) -> set[str]:
    """Private attribute names a module's classes give their instances (``self._x = ...``, ``__slots__``,
    private methods ``def _x(self, ...)``)."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            names |= {item.name for item in node.body
                      if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)) and _is_private(item.name)}
        if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) and _is_private(node.attr) \
                and isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
            names.add(node.attr)
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__slots__" for t in node.targets):
            names |= {e.value for e in ast.walk(node.value)
                      if isinstance(e, ast.Constant) and isinstance(e.value, str) and _is_private(e.value)}
    return names


@cache
def instance_privates() -> dict[str, str]:
    """Every instance-private name a ``skysh`` class assigns or defines as a method, with the module that owns it."""
    owners: dict[str, str] = {}
    for path in python_files(("skysh",)):
        for name in _self_privates(ast.parse(path.read_text(encoding="utf-8"))):
            owners.setdefault(name, module_name(path))
    return owners


def reach_ins(path: str, tree: ast.AST, own: str, is_package: bool = False,
              modules: frozenset[str] | None = None, instance_names: dict[str, str] | None = None) -> list[Violation]:
    """Every reach-in of ``tree`` (the module ``own``) into another first-party module's privates."""
    modules = first_party() if modules is None else modules
    instance_names = instance_privates() if instance_names is None else instance_names
    bound, found = _bindings(tree, own, is_package, modules)
    found = [v._replace(path=path) for v in found]
    mine = _self_privates(tree)
    foreign = {name: f"{owner}'s instance attribute" for name, owner in instance_names.items()
               if package_of(owner) != package_of(own)}
    foreign |= {name: why for name, why in KNOWN_INSTANCE_PRIVATES.items()}
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _is_private(node.attr):
            origin = _dotted(node.value, bound)
            if origin is not None and package_of(origin) != package_of(own):
                found.append(Violation(path, node.lineno, f"{ast.unparse(node)}: private {node.attr} of {origin}"))
            elif origin is not None:
                continue
            elif node.attr in foreign and node.attr not in mine and not (
                    isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
                found.append(Violation(path, node.lineno, f"{ast.unparse(node)}: {foreign[node.attr]}"))
        elif isinstance(node, ast.Call) and isinstance(node.func, (ast.Name, ast.Attribute)) and len(node.args) >= 2:
            verb = node.func.id if isinstance(node.func, ast.Name) else node.func.attr
            name = node.args[1]
            if verb in ("getattr", "setattr", "delattr") and isinstance(name, ast.Constant) \
                    and isinstance(name.value, str) and _is_private(name.value):
                origin = _dotted(node.args[0], bound)
                if origin is not None and package_of(origin) != package_of(own):
                    found.append(Violation(path, node.lineno, f"{verb}({origin}, {name.value!r}): private of another package"))
    return found


# --------------------------------------------------------------------------- #
# Facts written as prose
# --------------------------------------------------------------------------- #
_INTERVAL: str = r"\[\s*(?P<low>[^\[\],\n]{1,24}?)\s*,\s*(?P<high>[^\[\],\n]{1,24}?)\s*\]"
TURBIDITY_PROSE: re.Pattern[str] = re.compile(r"\bturbidit(?:y|ies)\b(?=(?P<gap>[^\[\]]{0,50}?)" + _INTERVAL + ")", re.I)
"""The first interval within 50 characters after the word turbidity (across a docstring's line break);
a lookahead, so every occurrence of the word is tried, also one inside another's gap."""
ZENITH_PROSE: re.Pattern[str] = re.compile(
    r"(?<![a-z])zenith\b(?=(?P<gap>[^\[\]]{0,50}?)" + _INTERVAL + r"(?P<after>[^\[\]\n]{0,12}))", re.I)
"""The first interval within 50 characters after the word zenith (also in ``sun_zenith``), and what
follows it on its line (a lookahead, as :data:`TURBIDITY_PROSE`)."""
NOT_TURBIDITY: re.Pattern[str] = re.compile(r"zenith|azimuth|albedo|radian|interval|variable|->", re.I)
"""Words between *turbidity* and an interval that make it another quantity's (``sun_zenith, turbidity,
albedo: Radians in [0, pi/2]``, ``(sun zenith, turbidity) -> (x, y) in [-1, 1]``, ``the table's
variables x, y in [-1, 1]``)."""
NOT_ZENITH: re.Pattern[str] = re.compile(r"turbidity|azimuth|albedo|cos|variable|->", re.I)
"""Likewise for *zenith* (``zenith ... azimuth [0, pi]``, ``cosine of the zenith angle, [0, 1]``)."""


def prose_domains() -> dict[str, dict[tuple[float, float], str]]:
    """The domains prose may state, by quantity: each from the constant that owns it."""
    from skysh.domain import SKY
    from skysh.model import hosek, preetham

    zenith = {SKY.x.interval: "skysh.domain.SKY.x (also preetham's and hosek's SUN_ZENITH_RANGE)",
              (0.0, math.pi): "a zenith angle's whole range (skysh.lighting.sun: the sun may be below the horizon)"}
    return {
        "turbidity": {SKY.y.interval: "skysh.domain.SKY.y (the fitted domain)",
                      preetham.TURBIDITY_RANGE: "skysh.model.preetham.TURBIDITY_RANGE (Preetham's model)",
                      hosek.TURBIDITY_RANGE: "skysh.model.hosek.TURBIDITY_RANGE (Hosek-Wilkie's model)"},
        "zenith": zenith,
        "zenith in degrees": {(math.degrees(a), math.degrees(b)): f"{why}, in degrees" for (a, b), why in zenith.items()},
    }


def _end_value(text: str) -> float | None:
    """An interval's end: a number, or a multiple of pi (``pi/2``, ``3 pi/4``, ``pi / 2``); None for a name."""
    compact = text.replace(" ", "")
    multiple = re.fullmatch(r"(-?)(\d*)pi(?:/(\d+))?", compact)
    if multiple:
        return (-1.0 if multiple[1] else 1.0) * int(multiple[2] or 1) * math.pi / int(multiple[3] or 1)
    try:
        return float(compact)
    except ValueError:
        return None


def _prose(source: str) -> Iterator[tuple[str, int]]:
    """Every string literal and comment of ``source`` with its first line."""
    kinds = {tokenize.STRING, tokenize.COMMENT} | ({tokenize.FSTRING_MIDDLE} if hasattr(tokenize, "FSTRING_MIDDLE") else set())
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type in kinds:
            yield token.string, token.start[0]


def _stated(match: re.Match[str], quantity: str, domains: dict[str, dict[tuple[float, float], str]]) -> str | None:
    """What is wrong with one stated interval, or None (right, or not a statement of ``quantity``'s domain)."""
    low, high = _end_value(match["low"]), _end_value(match["high"])
    if low is None or high is None:  # a name or a placeholder: derived in code
        return None
    if quantity == "turbidity":
        if NOT_TURBIDITY.search(match["gap"]) or "pi" in match["low"] + match["high"]:
            return None
    else:
        in_pi = "pi" in match["low"] + match["high"]
        in_degrees = "deg" in (match["gap"] + match["after"]).lower()
        if NOT_ZENITH.search(match["gap"]) or not (in_pi or in_degrees):
            return None
        quantity = "zenith" if in_pi else "zenith in degrees"
    known = domains[quantity]
    if any(abs(low - a) <= 1e-12 * max(1.0, abs(a)) and abs(high - b) <= 1e-12 * max(1.0, abs(b)) for a, b in known):
        return None
    return (f"{quantity} [{match['low']}, {match['high']}] is none of: "
            + "; ".join(f"[{a:g}, {b:g}] {why}" for (a, b), why in known.items()))


def prose_ranges(path: str, source: str, domains: dict[str, dict[tuple[float, float], str]] | None = None) -> list[Violation]:
    """Every turbidity or sun-zenith interval written in a string or comment of ``source`` that is no known domain."""
    domains = prose_domains() if domains is None else domains
    found = []
    for text, line in _prose(source):
        for quantity, pattern in (("turbidity", TURBIDITY_PROSE), ("zenith", ZENITH_PROSE)):
            for match in pattern.finditer(text):
                wrong = _stated(match, quantity, domains)
                if wrong is not None:
                    found.append(Violation(path, line + text.count("\n", 0, match.start("low")), wrong))
    return found


# --------------------------------------------------------------------------- #
# The repository's files, measured once
# --------------------------------------------------------------------------- #
@cache
def _parsed(path: Path) -> tuple[str, ast.Module]:
    source = path.read_text(encoding="utf-8")
    return source, ast.parse(source, filename=str(path))


@cache
def _measured() -> object:
    """``tools/code_size.py`` over the repository, once per session (the files do not change during a run)."""
    return code_size.measure_repository(ROOT)


def _rel(path: Path) -> str:
    return str(path.relative_to(ROOT))


def _check(found: list[Violation], rule: str) -> None:
    """Fail listing every violation, one ``path:line: what (measured > limit)`` a line."""
    if found:
        pytest.fail(f"{len(found)} {rule} violation(s):\n" + "\n".join(map(str, sorted(found))), pytrace=False)


def test_scope_is_not_empty():
    files = python_files(SIZE_SCOPE)
    assert any(p.name == "basis.py" for p in files) and any("report" in p.parts for p in files)


def test_function_length():
    found = [v for p in python_files(SIZE_SCOPE) for v in function_lengths(_rel(p), _parsed(p)[0])]
    _check(found, "function length")


def test_cyclomatic_complexity():
    found = [v for p in python_files(SIZE_SCOPE) for v in complexities(_rel(p), _parsed(p)[0])]
    _check(found, "cyclomatic complexity")


def test_no_reach_ins():
    found = [v for p in python_files(PRIVACY_SCOPE)
             for v in reach_ins(_rel(p), _parsed(p)[1], module_name(p), p.name == "__init__.py")]
    _check(found, "private reach-in")


def test_prose_domains_match_their_source():
    found = [v for p in python_files(SIZE_SCOPE) for v in prose_ranges(_rel(p), _parsed(p)[0])]
    _check(found, "domain written as prose")


def test_prose_scan_finds_the_written_domains():
    """The scan sees the ranges the docstrings state (else a pattern that matches nothing would pass)."""
    seen = {quantity: 0 for quantity in ("turbidity", "zenith")}
    for p in python_files(SIZE_SCOPE):
        for text, _ in _prose(_parsed(p)[0]):
            seen["turbidity"] += sum(_end_value(m["low"]) == 2.5 for m in TURBIDITY_PROSE.finditer(text))
            seen["zenith"] += sum("pi/2" in m["high"] for m in ZENITH_PROSE.finditer(text))
    assert seen["turbidity"] >= 5 and seen["zenith"] >= 5, seen


def test_startup_copies_match_their_source():
    """Values :mod:`skysh.app.cli` repeats so that building its parser imports nothing equal their source."""
    from skysh import options
    from skysh.app import cli, render

    assert cli.MODELS == options.MODELS
    assert cli.RENDER_WIDTH_RANGE == render.PANEL_WIDTH_RANGE
    assert cli.DEFAULT_RENDER_WIDTH == render.DEFAULT_PANEL_WIDTH


# --------------------------------------------------------------------------- #
# Negative controls: the same checkers flag synthetic offenders
# --------------------------------------------------------------------------- #
def _branchy(n: int) -> str:
    return "def branchy(x):\n" + "".join(f"    if x == {i}:\n        return {i}\n" for i in range(n)) + "    return -1\n"


def test_negative_control_sizes():
    long_body = "".join(f"        y{i} = {i}\n" for i in range(MAX_FUNCTION_LINES))  # def line + 60 = 61 code lines
    source = f"class A:\n    def long(self):\n{long_body}\n"
    found = function_lengths("m.py", source)
    assert [v.what for v in found] == [f"function A.long of {MAX_FUNCTION_LINES + 1} code lines > {MAX_FUNCTION_LINES}"]
    at_limit = "def short():\n" + "".join(f"    y{i} = {i}\n" for i in range(MAX_FUNCTION_LINES - 1))
    assert not function_lengths("m.py", at_limit)
    prose = '    """\n' + "    Prose.\n" * 100 + '    """\n    # a comment\n\n'
    assert not function_lengths("m.py", "def documented():\n" + prose + at_limit.split("\n", 1)[1])  # prose is free


def test_negative_control_complexity():
    # complexity = 1 + one per `if`: MAX_COMPLEXITY ifs give MAX_COMPLEXITY + 1
    found = complexities("m.py", _branchy(MAX_COMPLEXITY))
    assert [v.what for v in found] == [f"function branchy of cyclomatic complexity {MAX_COMPLEXITY + 1} > {MAX_COMPLEXITY}"]
    assert not complexities("m.py", _branchy(MAX_COMPLEXITY - 1))
    nested = "class A:\n    def f(self):\n" + textwrap.indent(_branchy(MAX_COMPLEXITY), "        ") + "        return branchy\n"
    assert [v.what.split(" of ")[0] for v in complexities("m.py", nested)] == ["function A.f.branchy"]


SYNTHETIC_OFFENDER: str = """
import skysh.post.dering
import skysh.table.fit as fitting
from skysh import runtime; from skysh.sh import basis as sh; from skysh import checks as _checks
from skysh.model.preetham import _luminance_scale, luminance
from skysh.runtime import SkySH
from report.common import _helper

def f(sky, obj, monkeypatch):
    a = fitting._solve(1)                       # module private through an alias
    b = skysh.post.dering._NEWTON_STEPS              # through the dotted package path
    c = runtime._X_SCALE, SkySH._private        # module and class privates
    d = sky._plans                              # a known instance private
    e = obj._lmax                               # an instance private a skysh class assigns
    monkeypatch.setattr(skysh.post.dering, "_NEWTON_STEPS", 3)
    ok = sh.__name__, checks.check_positive_int, luminance, sh.eval_basis
    return a, b, c, d, e, ok
"""
"""A module that reaches into other modules' privates in every way the checker knows (and a few ways it must allow)."""


def test_negative_control_reach_ins():
    modules = frozenset({"skysh", "skysh.post.dering", "skysh.table.fit", "skysh.runtime", "skysh.sh.basis", "skysh.checks",
                         "skysh.model.preetham", "report", "report.common", "tools_module"})
    found = reach_ins("m.py", ast.parse(SYNTHETIC_OFFENDER), "tools_module", modules=modules,
                      instance_names={"_lmax": "skysh.runtime"})
    whats = sorted(v.what for v in found)
    expected = [
        "from report.common import _helper", "from skysh.model.preetham import _luminance_scale",
        "fitting._solve", "skysh.post.dering._NEWTON_STEPS", "runtime._X_SCALE", "SkySH._private",
        "sky._plans", "obj._lmax", "setattr(skysh.post.dering, '_NEWTON_STEPS')",
    ]
    for needle in expected:
        assert any(w.startswith(needle) for w in whats), (needle, whats)
    assert len(found) == len(expected), whats  # nothing else: dunders, public names, `from skysh import checks as _checks`
    # a module's own privates, and a name it assigns to its own objects, are its business
    own = "import skysh.table.fit as me\nclass K:\n    def __init__(self):\n        self._plans = 1\n" \
          "    def g(self, other):\n        return other._plans, self._plans\n"
    assert reach_ins("m.py", ast.parse(own), "skysh.table.fit", modules=modules, instance_names={}) == []


def test_negative_control_private_methods():
    """A benchmark calling a skysh class's private methods (``sky._one``, ``plan._evaluate``) is flagged."""
    library = ("class SkySH:\n    def _one(self, ts):\n        return ts\n    def coefficients(self, ts):\n"
               "        return self._one(ts)\n"
               "class LitPlan:\n    def _evaluate(self, ts):\n        return ts\n    def fused(self, ts):\n"
               "        return self._evaluate(ts)\n")
    assert _self_privates(ast.parse(library)) == {"_one", "_evaluate"}  # the methods, not the public ones
    owners = {name: "skysh.runtime" for name in _self_privates(ast.parse(library))}
    bench = ("from skysh.runtime import SkySH\nsky = SkySH.load()\nplan = sky.plan(3)\n"
             "t = (sky._one(0.5), plan._evaluate(0.5), sky.coefficients(0.5))\n")
    modules = frozenset({"skysh", "skysh.runtime", "bench_lights"})
    found = reach_ins("bench.py", ast.parse(bench), "bench_lights", modules=modules, instance_names=owners)
    assert sorted(v.what.split(":")[0] for v in found) == ["plan._evaluate", "sky._one"], found
    # the module that defines them calls them freely, on itself and on its other objects
    assert reach_ins("m.py", ast.parse(library + "def g(sky):\n    return sky._one(1)\n"), "skysh.runtime",
                     modules=modules, instance_names=owners) == []


@pytest.mark.parametrize(("source", "own", "flagged"), [
    ("from . import _x", "report.run", False),  # inside its package: shared (issue 24's package privacy)
    ("from .common import _y", "report.run", False),
    ("from studies.sky import _z", "report.run", True),  # another package's private
    ("from skysh.export.lights import _x", "skysh.export.js", False),
    ("from skysh.export.lights import _x", "skysh.app.cli", True),
    ("from skysh.checks import _x", "skysh.domain", True),  # root modules are packages of their own
])
def test_negative_control_package_privacy(source, own, flagged):
    modules = frozenset({"report", "report.common", "report.run", "studies", "studies.sky", "skysh", "skysh.export",
                         "skysh.export.lights", "skysh.export.js", "skysh.app", "skysh.app.cli", "skysh.checks",
                         "skysh.domain"})
    assert bool(reach_ins("m.py", ast.parse(source), own, modules=modules, instance_names={})) == flagged


PROSE_CASES: list[tuple[str, bool]] = [
    ('"""Turbidity in [2.5, 7]."""', True),  # the example: a typo of the fitted domain
    ("# turbidity [2.5, 6], the fitted domain", False),
    ('"""\n    turbidity\n        (n_t,) in [1.7, 10]."""', False),  # a numpy-style parameter, across a line
    ('"""\n    turbidity\n        (n_t,) in [1.7, 11]."""', True),
    ('"""sun zenith [0, pi/3] rad"""', True),
    ('"""Radians: sun zenith [0, pi / 2], any azimuth."""', False),
    ('"""\n    sun_zenith\n        Radians, [0, pi/2]."""', False),
    ('"""\n    sun_zenith\n        Radians, [0, 3 pi/2]."""', True),
    ('"""(sun_zenith, sun_azimuth) in radians: zenith in [0, pi/3], azimuth any."""', True),  # the 2nd zenith
    ('help="sun zenith angle, degrees, [0, 95]"', True),
    ('"""zenith [0, 90] deg x turbidity [2.5, 6]"""', False),
    ('f"--turbidity must lie in [{low:g}, {high:g}], got {t}"', False),  # derived in code
    ('"""Domain: turbidity $turbidity_domain."""', False),  # a template placeholder
    ('"""sun_zenith, turbidity, albedo\n        Radians in [0, pi/2]; turbidity in [1, 10]."""', False),
    ('"""Cosine of the view\'s zenith angle, [0, 1]."""', False),  # not an angle's range
    ('"""(sun zenith, turbidity) of the table\'s variables x, y in [-1, 1]."""', False),
]
"""Synthetic sources and whether the prose check must flag them."""


@pytest.mark.parametrize("source, flagged", PROSE_CASES)
def test_negative_control_prose_ranges(source, flagged):
    found = prose_ranges("m.py", source + "\n")
    assert bool(found) == flagged, found


# --------------------------------------------------------------------------- #
# Code size (issue 24): tools/code_size.py's counting, on sources with known answers
# --------------------------------------------------------------------------- #
COUNTED_SOURCE: str = """\
\"\"\"The module's docstring,
over two lines.\"\"\"

import os  # a trailing comment: a code line

# a comment line, then two blank lines


class K:
    \"\"\"The class's docstring.\"\"\"

    x = 1
    \"\"\"An attribute's docstring: prose, as Sphinx and PEP 257 read it.\"\"\"

    def f(self):
        \"\"\"
        The function's docstring.
        \"\"\"
        return \"\"\"
void main() {

    gl_FragColor = vec4(1.0);
}
\"\"\"


def g(n):
    prose = \"\"\"two lines
of prose\"\"\"
    joined = ("const a = 1;\\n"
              "const b = 2;\\n")
    return prose, joined, f\"\"\"
float k{n}() {{ return 1.0; }}
\"\"\", os.sep
"""
"""Every kind of line: docstrings (module, class, function), comments, blank lines, an attribute's
docstring, a GLSL string with a blank line in it, multi-line prose, implicitly joined code, an f-string."""

COUNTED_CODE: set[int] = {4, 9, 12, 15, *range(19, 25), *range(27, 35)}
"""The code lines of :data:`COUNTED_SOURCE` (by hand): the statements and every line of its
non-docstring strings (the blank line 21 inside the GLSL too)."""

COUNTED_CODE_STRINGS: set[int] = {*range(19, 25), 30, 31, *range(32, 35)}
"""Its lines of generated-code-like strings: the GLSL (19-24), the joined JavaScript (30-31), the
f-string (32-34); not the two lines of prose (28-29), which hold neither ``;`` nor ``{``."""


def test_code_size_counts_lines():
    size, tree = code_size.measure(COUNTED_SOURCE, "m")
    assert size.physical == 34 == len(COUNTED_SOURCE.splitlines())
    assert code_size.code_lines(COUNTED_SOURCE, tree) == COUNTED_CODE
    assert code_size.code_string_lines(tree) == COUNTED_CODE_STRINGS
    assert (size.code, size.code_strings, size.all_names) == (len(COUNTED_CODE), len(COUNTED_CODE_STRINGS), 0)


@pytest.mark.parametrize("source, physical, code", [
    ("", 0, 0),
    ("x = 1", 1, 1),  # no final newline
    ('"""Only a docstring."""\n\n# and a comment\n', 3, 0),
    ('x = "caf\u00e9"; """not a docstring"""\n', 1, 1),
    ('def f():\n    """\u00e9t\u00e9"""; return 1\n', 2, 2),  # a non-ASCII docstring, then code on its line
    ("x = (1 +\n     2)  # a comment\n", 2, 2),
])
def test_code_size_edge_cases(source, physical, code):
    size, _ = code_size.measure(source, "m")
    assert (size.physical, size.code) == (physical, code)


def test_code_size_all_names():
    assert code_size.measure("__all__ = ['a', 'b']\n__all__ += ('c',)\n", "m")[0].all_names == 3
    assert code_size.measure("__all__: list[str] = ['a']\nx = ['b', 'c']\n", "m")[0].all_names == 1
    assert code_size.measure("def f():\n    __all__ = ['a']\n", "m")[0].all_names == 0  # module level only


IMPORTING_SOURCE: str = """\
import typing
from typing import TYPE_CHECKING

import numpy
import skysh.b
from skysh import SkySH, c
from . import d
from .e import thing

if TYPE_CHECKING:
    from skysh.f import Only
if typing.TYPE_CHECKING:
    import skysh.f
else:
    from skysh.g import fallback


def lazy():
    from skysh.h import helper
    import skysh.h.deep
    return helper
"""
"""A module ``skysh.a`` importing its package's modules in every way :func:`code_size.imports` reads."""

PACKAGE_MODULES: frozenset[str] = frozenset({"skysh", *(f"skysh.{m}" for m in "abcdefgh")})


def test_code_size_imports():
    found = code_size.imports(ast.parse(IMPORTING_SOURCE), "skysh.a", PACKAGE_MODULES)
    assert sorted((i.target, i.line, i.in_function) for i in found) == [
        ("skysh", 6, False),  # SkySH is no module: an import of skysh/__init__.py
        ("skysh.b", 5, False), ("skysh.c", 6, False), ("skysh.d", 7, False), ("skysh.e", 8, False),
        ("skysh.g", 15, False),  # the else branch of TYPE_CHECKING is read, its body (skysh.f) is not
        ("skysh.h", 19, True), ("skysh.h", 20, True),
    ]
    assert code_size.imports(ast.parse("from . import b\n"), "skysh", PACKAGE_MODULES, is_package=True)[0].target \
        == "skysh.b"


@pytest.mark.parametrize("edges, expected", [
    ([("a", "b"), ("b", "c")], []),
    ([("a", "b"), ("b", "a"), ("b", "c")], [["a", "b"]]),
    ([("a", "b"), ("b", "c"), ("c", "a"), ("d", "e"), ("e", "d"), ("c", "d")], [["a", "b", "c"], ["d", "e"]]),
    ([("a", "a"), ("a", "b")], [["a"]]),
])
def test_code_size_cycles(edges, expected):
    assert code_size.cycles(edges) == expected


def test_code_size_command(tmp_path, capsys):
    """The command over a small tree: a lazy import closing a cycle, and a module outside it."""
    package = tmp_path / "skysh"
    package.mkdir()
    (package / "__init__.py").write_text('"""The package."""\n', encoding="utf-8")
    (package / "a.py").write_text("from skysh import b\n\n__all__ = ['x']\nx = b\n", encoding="utf-8")
    (package / "b.py").write_text("def f():\n    from skysh.a import x\n    return x\n", encoding="utf-8")
    (package / "c.py").write_text("import skysh.a\n", encoding="utf-8")
    assert code_size.main(["--json", "--root", str(tmp_path)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [m["path"] for m in report["modules"]] == ["skysh/a.py", "skysh/b.py", "skysh/c.py", "skysh/__init__.py"]
    assert report["groups"][0] | {"name": ""} == {"name": "", "path": "", "physical": 9, "code": 7, "code_strings": 0,
                                                "all_names": 1, "modules": 4}
    assert report["cycles"] == [["skysh.a", "skysh.b"]]
    assert code_size.main(["--root", str(tmp_path)]) == 0
    assert "skysh.a <-> skysh.b: skysh/a.py:1 imports skysh.b; skysh/b.py:2 imports skysh.a (in a function)" \
        in capsys.readouterr().out


def test_code_size_of_skysh():
    """The tool over the real package: every module counted, the totals the sums, the cycles inside skysh."""
    report = _measured()
    assert sorted(m.path for m in report.modules) == [_rel(p) for p in python_files(("skysh",))]
    for m in report.modules:
        assert 0 <= m.code_strings <= m.code < m.physical, m
    package, export = report.groups
    exports = [m for m in report.modules if m.name.startswith(code_size.EXPORT_PACKAGE + ".")
               or m.name == code_size.EXPORT_PACKAGE]
    for group, members in ((package, report.modules), (export, exports)):
        assert group.modules == len(members) and group.physical == sum(m.physical for m in members)
        assert (group.code, group.code_strings, group.all_names) == tuple(
            sum(getattr(m, c) for m in members) for c in ("code", "code_strings", "all_names"))
    assert export.modules == len(exports) > 1 and export.code < package.code
    assert [m.code for m in report.modules] == sorted((m.code for m in report.modules), reverse=True)
    assert any(i.in_function for i in report.imports) and any(not i.in_function for i in report.imports)
    names = {m.name for m in report.modules}
    assert all(set(cycle) <= names and len(cycle) > 1 for cycle in report.cycles)



# --------------------------------------------------------------------------- #
# Issue 24's rules over the real package
# --------------------------------------------------------------------------- #
def test_every_package_within_its_budget():
    """Each package's code lines at most its budget (``tools/code_size.py``'s PACKAGE_BUDGETS), every package budgeted."""
    report = _measured()
    names = {p.name for p in report.packages}
    assert names == set(code_size.PACKAGE_BUDGETS), names ^ set(code_size.PACKAGE_BUDGETS)
    over = [f"{p.name}: {p.code} code lines > {code_size.PACKAGE_BUDGETS[p.name]}" for p in report.packages
            if p.code > code_size.PACKAGE_BUDGETS[p.name]]
    assert not over, over
    total = sum(p.code for p in report.packages)
    assert total <= code_size.BUDGETS["skysh code lines"], f"skysh holds {total} code lines"


def test_the_export_package_writes_no_statements():
    """No multi-line string holding ``;`` or ``{`` in the export package's Python: the code lives in its templates."""
    report = _measured()
    found = [f"{m.path}: {m.code_strings} lines" for m in report.modules
             if m.name.startswith(code_size.EXPORT_PACKAGE) and m.code_strings]
    assert not found, found
