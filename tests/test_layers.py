"""
The package graph, from the source and from ``docs/architecture.md``
====================================================================

Every ``skysh`` module is parsed (nothing imported) by ``tools/code_size.py``, which reads
its imports of other ``skysh`` modules, module level and inside functions alike (``if
TYPE_CHECKING:`` bodies are not imports at run time). A module belongs to its sub-package
(``skysh.table.fit`` to ``skysh.table``); a module of ``skysh/``'s root is a package of its own.

-   ``docs/architecture.md``'s table is the graph: its packages are the code's, each row's
    imports are exactly the packages that row's modules import, and a row imports only rows
    above it (so there is no cycle, lazy imports included).
-   No import cycle among modules either.
-   No library module imports the tools (``tools/``, its studies and report) or matplotlib at
    all; the runtime side (:data:`RUNTIME_SIDE` and everything it imports at module level)
    imports neither colour-science nor the offline fit at module level.
"""

from __future__ import annotations

import ast
import functools
import re

import pytest
from conftest import ROOT, TOOLS, load_script

code_size = load_script(TOOLS / "code_size.py", "code_size_of_layers")
"""``tools/code_size.py``, loaded as a module: its import reader and graph are the ones measured here."""

ARCHITECTURE = ROOT / "docs" / "architecture.md"

ROW: re.Pattern[str] = re.compile(r"^\| `(?P<name>skysh[\w.]*)` \| (?P<holds>[^|]+) \| (?P<imports>[^|]+) \|$", re.M)
"""A row of the architecture's package table: the package, what it holds, what it imports."""

RUNTIME_SIDE: tuple[str, ...] = (
    "skysh.runtime", "skysh.options", "skysh.lighting.sunlight", "skysh.table.coefficient_file", "skysh.table.sun_table",
    "skysh.sh.basis", "skysh.domain", "skysh.table.poly", "skysh.post.dering", "skysh.sh.minimum", "skysh.engines.presets",
)
"""Modules a renderer loads per frame or at start-up: light at import."""

NOT_AT_RUNTIME_IMPORT: frozenset[str] = frozenset({"colour", "matplotlib"})
"""Top-level packages the runtime side must not import at module level (directly or through skysh)."""

NEVER_IN_THE_LIBRARY: frozenset[str] = frozenset(
    {"tools", "matplotlib"} | {p.stem for p in TOOLS.glob("*.py")} | {p.name for p in TOOLS.iterdir() if p.is_dir()}
)
"""Top-level names no ``skysh`` module may import anywhere: the tools (scripts, the studies package,
the report package) and matplotlib."""


def documented_graph(text: str) -> dict[str, tuple[str, ...]]:
    """The package table of an architecture document: package -> imported packages, in the table's order."""
    graph: dict[str, tuple[str, ...]] = {}
    for row in ROW.finditer(text):
        listed = row["imports"].strip()
        graph[row["name"]] = () if listed == "nothing" else tuple(re.findall(r"`(skysh[\w.]*)`", listed))
    return graph


def order_violations(graph: dict[str, tuple[str, ...]]) -> list[str]:
    """Rows importing a package not listed above them (the order that makes the graph acyclic)."""
    seen: set[str] = set()
    wrong = []
    for name, deps in graph.items():
        wrong += [f"{name} imports {dep}, which is not above it" for dep in deps if dep not in seen]
        seen.add(name)
    return wrong


@functools.cache
def report() -> code_size.Report:
    return code_size.measure_repository(ROOT)


@functools.cache
def code_graph() -> dict[str, tuple[str, ...]]:
    """The code's package graph: every package with the packages its modules import (sorted)."""
    subpackages = code_size.subpackages_of(ROOT)
    edges = code_size.package_edges(report().imports, subpackages)
    return {p.name: tuple(sorted(b for a, b in edges if a == p.name)) for p in report().packages}


def _external(path: str, module_level_only: bool) -> set[str]:
    """Top-level names of the non-skysh modules a file imports (outside ``if TYPE_CHECKING:``)."""
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    found = set()
    for node, in_function in code_size.import_nodes(tree):
        if module_level_only and in_function:
            continue
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module or ""]
        if isinstance(node, ast.ImportFrom) and node.level:
            continue
        found |= {n.split(".")[0] for n in names if n and n.split(".")[0] != "skysh"}
    return found


def _module_level_closure(module: str) -> set[str]:
    """The skysh modules loaded by importing ``module`` (module-level imports, followed)."""
    edges: dict[str, set[str]] = {}
    for i in report().imports:
        if not i.in_function:
            edges.setdefault(i.source, set()).add(i.target)
    seen, todo = set(), [module]
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo += edges.get(name, set())
    return seen


# --------------------------------------------------------------------------- #
def test_the_document_is_the_code_graph():
    documented, code = documented_graph(ARCHITECTURE.read_text(encoding="utf-8")), code_graph()
    assert sorted(documented) == sorted(code), "packages only in the document / only in the code: " \
        f"{sorted(set(documented) - set(code))} / {sorted(set(code) - set(documented))}"
    wrong = {name: (tuple(sorted(documented[name])), code[name]) for name in code
             if tuple(sorted(documented[name])) != code[name]}
    assert not wrong, "documented imports != the code's (document, code): " + repr(wrong)


def test_the_document_points_down():
    assert order_violations(documented_graph(ARCHITECTURE.read_text(encoding="utf-8"))) == []


def test_no_import_cycles():
    assert report().cycles == [] and report().package_cycles == []


def test_the_studies_are_out_of_the_library():
    """Issue 14: quantize imports neither the runtime nor the model, hazel neither dering, the model nor quantize."""
    banned = {"skysh.post.quantize": {"skysh.runtime", "skysh.model.preetham", "skysh"},
              "skysh.post.hazel": {"skysh.post.dering", "skysh.model.preetham", "skysh.post.quantize", "skysh"}}
    for module, names in banned.items():
        targets = {i.target for i in report().imports if i.source == module}
        assert not targets & names, (module, targets & names)
        path = module.replace(".", "/") + ".py"
        assert "scipy" not in _external(path, module_level_only=False), module  # the sky sampling went with the studies


def test_the_library_never_imports_the_tools():
    for size in report().modules:
        assert not _external(size.path, module_level_only=False) & NEVER_IN_THE_LIBRARY, size.path


@pytest.mark.parametrize("module", RUNTIME_SIDE)
def test_the_runtime_side_is_light_at_import(module):
    closure = _module_level_closure(module)
    assert "skysh.table.fit" not in closure, f"importing {module} loads the offline fit"
    paths = {m.name: m.path for m in report().modules}
    for name in sorted(closure):
        heavy = _external(paths[name], module_level_only=True) & NOT_AT_RUNTIME_IMPORT
        assert not heavy, f"importing {module} loads {heavy} at module level through {name}"


# --------------------------------------------------------------------------- #
# Negative controls: the checks see what they must
# --------------------------------------------------------------------------- #
def test_negative_control_document_rows():
    text = ARCHITECTURE.read_text(encoding="utf-8")
    graph = documented_graph(text)
    assert len(graph) >= 15 and graph["skysh.checks"] == () and "skysh.sh" in graph["skysh.post"]
    # a row moved above what it imports is refused; a missing import is a difference from the code
    swapped = dict(reversed(list(graph.items())))
    assert order_violations(swapped)
    dropped = text.replace("| `skysh.checks`, `skysh.sh` |", "| `skysh.checks` |", 1)
    assert documented_graph(dropped) != graph


def test_negative_control_lazy_upward_import_is_a_cycle(tmp_path):
    """A lazy import from the file up to the sun's light (issue 24's former cycle) is seen by the tool."""
    package = tmp_path / "skysh"
    (package / "table").mkdir(parents=True)
    (package / "lighting").mkdir()
    for folder in (package, package / "table", package / "lighting"):
        (folder / "__init__.py").write_text('"""p."""\n', encoding="utf-8")
    (package / "table" / "file.py").write_text("def f():\n    from skysh.lighting import sunlight\n", encoding="utf-8")
    (package / "lighting" / "sunlight.py").write_text("from skysh.table import file\n", encoding="utf-8")
    found = code_size.measure_repository(tmp_path)
    assert found.package_cycles == [["skysh.lighting", "skysh.table"]]


def test_negative_control_heavy_and_tool_imports_are_seen(tmp_path):
    (tmp_path / "m.py").write_text("import matplotlib.pyplot as plt\nfrom studies import hazel_study\n"
                                   "def f():\n    import colour\n", encoding="utf-8")
    rel = str((tmp_path / "m.py").relative_to(ROOT)) if tmp_path.is_relative_to(ROOT) else None
    source = ast.parse((tmp_path / "m.py").read_text(encoding="utf-8"))
    levels = [(n.names[0].name if isinstance(n, ast.Import) else n.module, lazy)
              for n, lazy in code_size.import_nodes(source)]
    assert levels == [("matplotlib.pyplot", False), ("studies", False), ("colour", True)] and rel is None
    assert "studies" in NEVER_IN_THE_LIBRARY and "report" in NEVER_IN_THE_LIBRARY
