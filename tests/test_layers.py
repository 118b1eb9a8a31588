"""
The package's layers, from its source
=====================================

Every ``skysh/*.py`` is parsed with :mod:`ast` (nothing is imported) and its imports of
other ``skysh`` modules are checked against two tables:

-   :data:`LAYERS`: each module's layer. A module may import only modules of strictly
    lower layers, at module level and inside functions alike, so the import graph has no
    cycle and no upward edge (issue 24 removed the last two, which a function-level import
    broke at run time).
-   :data:`ALLOWED`: each module's ``skysh`` imports (module level or inside functions;
    ``if TYPE_CHECKING:`` blocks are not imports at run time and are not counted). A new
    import fails the test until it is added here, where :data:`LAYERS` checks its
    direction.

Also: no library module imports the tools (``tools/``, its studies and report) or
matplotlib at all, and the runtime side (:data:`RUNTIME_SIDE` and everything it imports
at module level) imports neither colour-science nor the tools at module level.
``from skysh import X`` counts as an import of ``skysh/X.py``; ``SkySH`` and
``__version__`` resolve to the modules the package's ``__init__`` takes them from.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path
from typing import NamedTuple

import pytest
from conftest import ROOT, TOOLS

SKYSH: Path = ROOT / "skysh"

LAYERS: dict[str, int] = {
    # 0: foundation (argument checks, version, the npz reader)
    "_version": 0, "_checks": 0, "_npz": 0, "files": 0, "_mitsuba_data": 0, "argtypes": 0,
    # 1: SH mathematics, the fitted parameters' domain (intervals, maps to [-1, 1], term order), the per-frame options
    "sh": 1, "domain": 1, "sun": 1, "options": 1,
    # 2: the Chebyshev basis over the domain
    "poly": 2,
    # 3: the sky model, algorithms on SH coefficients alone, the sun table's form (what the file stores for the sun)
    "preetham": 3, "ground": 3, "shmin": 3, "hazel": 3, "quantize": 3, "sun_table": 3,
    # 4: built on those: the spectral sun model, deringing, the coefficient file
    "solar": 4, "dering": 4, "coefficient_file": 4,
    # 5: the sun's light (from the file's sun table); the Hosek-Wilkie sky (the solar spectrum and the ground)
    "sunlight": 5, "hosek": 5,
    # 6: the offline fit, the per-frame sun and ground, deringing as emitted code
    "fit": 6, "lights": 6, "export_dering": 6,
    # 7: the per-frame runtime
    "runtime": 7, "export_lights": 7,
    # 8: consumers: the irradiance fit, engine conventions, rendering, the JavaScript export's parts
    "irradiance_fit": 8, "engines": 8, "render": 8, "export_js_parts": 8,
    # 9: built on the engines: the numbers every export is written from (with the engines' plans), the engines' sun
    "export_tables": 9, "engine_sun": 9,
    # 10: the JavaScript and JSON exports
    "export_js": 10,
    # 11: the exports by language (C, GLSL, HLSL; js and json from export_js)
    "export": 11,
    # 12: applications and the command line's text
    "viewer": 12, "cli_text": 12,
    # 13: the command line
    "cli": 13,
    # 14: the package and its entry point
    "__init__": 14, "__main__": 14,
}
"""Layer of every module of ``skysh/`` (issue 14's picture: SH mathematics -> sky model -> fit
and file -> runtime -> post-processing -> exports, engines and CLI, as the imports really run;
issue 24: the coefficient file below the sun's light, every export below the language dispatch)."""

ALLOWED: dict[str, frozenset[str]] = {name: frozenset(deps) for name, deps in {
    "_version": (),
    "_checks": (),
    "_npz": (),
    "files": (),
    "_mitsuba_data": (),
    "argtypes": (),
    "sh": ("_checks",),
    "domain": ("_checks",),
    "poly": ("_checks", "domain"),
    "sun": ("_checks",),
    "options": ("_checks",),
    "preetham": ("_checks", "sh", "domain"),
    "ground": ("_checks", "sh"),
    "shmin": ("_checks", "sh"),
    "hazel": ("_checks", "sh"),
    "quantize": ("_checks", "sh"),
    "sun_table": ("domain",),
    "solar": ("_checks", "sh", "preetham", "domain"),
    "dering": ("_checks", "sh", "shmin"),
    "coefficient_file": ("_checks", "_npz", "_version", "files", "poly", "sun_table", "domain"),
    "sunlight": ("_checks", "_npz", "poly", "coefficient_file", "sun_table", "domain"),
    "hosek": ("_checks", "_mitsuba_data", "ground", "preetham", "sh", "solar"),
    "fit": ("_checks", "coefficient_file", "poly", "preetham", "sh", "sun_table", "solar", "domain"),
    "lights": ("_checks", "coefficient_file", "ground", "preetham", "sh", "solar", "domain", "options"),
    "runtime": ("_checks", "coefficient_file", "ground", "lights", "poly", "preetham", "sh", "sunlight", "dering",
                "domain", "options"),
    "export_dering": ("_checks", "dering", "sh", "shmin"),
    "irradiance_fit": ("_checks", "fit", "preetham", "sh", "shmin"),
    "engines": ("_checks", "sh"),
    "render": ("_checks", "files", "ground", "lights", "preetham", "runtime", "sh", "solar"),
    "export_lights": ("_checks", "coefficient_file", "ground", "lights", "preetham", "solar", "sunlight",
                      "export_dering", "domain"),
    "export_js_parts": ("export_lights", "export_dering"),
    "export_tables": ("_checks", "coefficient_file", "engines", "export_lights", "runtime", "sh", "domain"),
    "export_js": ("_checks", "_version", "engines", "export_js_parts", "export_lights", "export_tables", "preetham",
                  "runtime"),
    "export": ("_checks", "_version", "export_js", "export_lights", "export_tables", "preetham", "runtime"),
    "engine_sun": ("_checks", "engines"),
    "viewer": ("_version", "engines", "export", "files", "preetham", "render", "runtime", "sh", "sunlight"),
    "cli_text": ("_checks", "engines", "engine_sun", "export", "sh"),
    "cli": ("_version", "argtypes", "cli_text", "engines", "export", "files", "export_js", "preetham", "render",
            "runtime", "sh", "sun", "viewer", "domain", "options"),
    "__init__": ("_version", "runtime"),
    "__main__": ("cli",),
}.items()}
"""The ``skysh`` imports of every module as of issue 24 (issue 14's, after the studies moved to tools/studies/,
with the sun table's form in sun_table, the exports' shared numbers in export_tables and the per-frame options
in options)."""

RUNTIME_SIDE: tuple[str, ...] = ("runtime", "options", "sunlight", "coefficient_file", "sun_table", "sh", "domain", "poly",
                                "dering", "shmin", "engines")
"""Modules a renderer loads per frame or at start-up: light at import."""

NOT_AT_RUNTIME_IMPORT: frozenset[str] = frozenset({"colour", "matplotlib"})
"""Top-level packages the runtime side must not import at module level (directly or through skysh)."""

NEVER_IN_THE_LIBRARY: frozenset[str] = frozenset(
    {"tools", "matplotlib"} | {p.stem for p in TOOLS.glob("*.py")} | {p.name for p in TOOLS.iterdir() if p.is_dir()}
)
"""Top-level names no ``skysh`` module may import anywhere: the tools (scripts, the studies package,
the report package) and matplotlib."""

FACADE: dict[str, str] = {"SkySH": "runtime", "__version__": "_version"}
"""Names ``from skysh import ...`` takes from a module other than one of the same name."""

MODULES: frozenset[str] = frozenset(p.stem for p in SKYSH.glob("*.py"))


class Import(NamedTuple):
    target: str  # a skysh module name, or "ext:<top-level package>"
    lazy: bool  # inside a function (runs on call, not on import)
    type_only: bool  # inside ``if TYPE_CHECKING:``
    line: int


def _targets(node: ast.AST) -> list[str]:
    if isinstance(node, ast.Import):
        out = []
        for alias in node.names:
            parts = alias.name.split(".")
            out.append((parts[1] if len(parts) > 1 else "__init__") if parts[0] == "skysh" else "ext:" + parts[0])
        return out
    if isinstance(node, ast.ImportFrom):
        module = node.module or ""
        if node.level == 0 and module != "skysh" and not module.startswith("skysh."):
            return ["ext:" + module.split(".")[0]]
        sub = module.split(".")[1] if module.startswith("skysh.") else (module.split(".")[0] if node.level else "")
        if sub:
            return [sub]
        return [a.name if a.name in MODULES else FACADE.get(a.name, "__init__") for a in node.names]
    return []


def _is_type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (
        (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
        or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")
    )


def imports_of(source: str) -> list[Import]:
    """Every import statement of a module's source, with whether it is lazy or type-only."""
    found: list[Import] = []

    def visit(node: ast.AST, lazy: bool, type_only: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner_lazy = lazy or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if _is_type_checking(child):
                assert isinstance(child, ast.If)
                for stmt in child.body:
                    found.extend(Import(t, lazy, True, stmt.lineno) for t in _targets(stmt))
                    visit(stmt, lazy, True)
                for stmt in child.orelse:
                    found.extend(Import(t, lazy, type_only, stmt.lineno) for t in _targets(stmt))
                    visit(stmt, lazy, type_only)
                continue
            found.extend(Import(t, lazy, type_only, getattr(child, "lineno", 0)) for t in _targets(child))
            visit(child, inner_lazy, type_only)

    visit(ast.parse(source), False, False)
    return found


def layer_violations(module: str, source: str) -> list[str]:
    """What is wrong with ``module``'s imports against :data:`ALLOWED` and :data:`LAYERS`."""
    problems = []
    for imp in imports_of(source):
        if imp.type_only or imp.target.startswith("ext:") or imp.target == module:
            continue
        where = f"skysh/{module}.py:{imp.line} imports {imp.target}"
        if imp.target not in ALLOWED.get(module, frozenset()):
            problems.append(f"{where}: not in test_layers.ALLOWED[{module!r}]")
        if imp.target in LAYERS and module in LAYERS and LAYERS[imp.target] >= LAYERS[module]:
            problems.append(f"{where}: layer {LAYERS[imp.target]} from layer {LAYERS[module]}, not a lower layer")
    return problems


def _source(module: str) -> str:
    return (SKYSH / f"{module}.py").read_text(encoding="utf-8")


@functools.cache
def _imports(module: str) -> tuple[Import, ...]:
    """:func:`imports_of` the module's source, parsed once per session (the tests below ask for every module's
    imports several times; the files do not change during a run)."""
    return tuple(imports_of(_source(module)))


def _module_level_closure(module: str) -> set[str]:
    """The skysh modules loaded by importing ``module`` (module-level imports, followed)."""
    seen, todo = set(), [module]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        todo += [i.target for i in _imports(name)
                 if not (i.lazy or i.type_only or i.target.startswith("ext:")) and i.target in MODULES]
    return seen


# --------------------------------------------------------------------------- #
def test_every_module_has_a_layer_and_a_row():
    assert MODULES == set(LAYERS), f"place new modules in LAYERS, drop deleted ones: {MODULES ^ set(LAYERS)}"
    assert MODULES == set(ALLOWED), f"give new modules a row in ALLOWED: {MODULES ^ set(ALLOWED)}"


def test_the_table_points_down():
    """Every allowed import goes to a strictly lower layer (so the allowed graph has no cycle)."""
    upward = [(m, d) for m, deps in ALLOWED.items() for d in deps if LAYERS[d] >= LAYERS[m]]
    assert upward == []


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_follow_the_layers(module):
    assert layer_violations(module, _source(module)) == []


def test_the_studies_are_out_of_the_library():
    """Issue 14: quantize imports neither runtime nor preetham, hazel neither dering, preetham nor quantize."""
    for module, banned in {"quantize": {"runtime", "preetham", "__init__"},
                           "hazel": {"dering", "preetham", "quantize", "__init__"}}.items():
        targets = {i.target for i in _imports(module)}
        assert not targets & banned, (module, targets & banned)
        assert not any(t.startswith("ext:scipy") for t in targets), module  # the sky sampling went with the studies


def test_the_library_never_imports_the_tools():
    for module in sorted(MODULES):
        external = {i.target[4:] for i in _imports(module) if i.target.startswith("ext:")}
        assert not external & NEVER_IN_THE_LIBRARY, (module, external & NEVER_IN_THE_LIBRARY)


@pytest.mark.parametrize("module", RUNTIME_SIDE)
def test_the_runtime_side_is_light_at_import(module):
    closure = _module_level_closure(module)
    assert "fit" not in closure, f"importing skysh.{module} loads the offline fit"
    for name in sorted(closure):
        heavy = {i.target[4:] for i in _imports(name)
                 if i.target.startswith("ext:") and not (i.lazy or i.type_only)} & NOT_AT_RUNTIME_IMPORT
        assert not heavy, f"importing skysh.{module} loads {heavy} at module level through skysh.{name}"


# --------------------------------------------------------------------------- #
# Negative controls: the checker sees what it must
# --------------------------------------------------------------------------- #
def test_negative_control_upward_imports_are_caught():
    lazy_upward = "def f():\n    from skysh.model import preetham\n    return preetham\n"
    assert any("not in test_layers.ALLOWED" in p for p in layer_violations("hazel", lazy_upward))
    assert any("not a lower layer" in p for p in layer_violations("hazel", lazy_upward))
    facade = "from skysh import SkySH\n"
    assert any("imports runtime" in p for p in layer_violations("quantize", facade))
    # Issue 24's two former cycles, written back as lazy imports: refused as upward.
    file_to_sun = "def f():\n    from skysh.lighting.sunlight import SunLight\n    return SunLight\n"
    assert any("not a lower layer" in p for p in layer_violations("coefficient_file", file_to_sun))
    js_to_dispatch = "def f():\n    from skysh.export import c_like as export\n    return export\n"
    assert any("not a lower layer" in p for p in layer_violations("export_js", js_to_dispatch))
    type_only = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from skysh.runtime import SkySH\n"
    assert layer_violations("hazel", type_only) == []


def test_negative_control_heavy_and_tool_imports_are_seen():
    found = imports_of("import matplotlib.pyplot as plt\nfrom studies import hazel_study\n"
                       "def f():\n    import colour\n")
    assert [(i.target, i.lazy) for i in found] == [("ext:matplotlib", False), ("ext:studies", False),
                                                   ("ext:colour", True)]
    assert "studies" in NEVER_IN_THE_LIBRARY and "report" in NEVER_IN_THE_LIBRARY
