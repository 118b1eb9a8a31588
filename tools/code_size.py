"""
Code size of skysh, measured (issue 24: "One algorithm, one place")
====================================================================

Prints, per module of ``skysh/`` (and of ``tools/`` with ``--tools``), a markdown table sorted by
code lines, the totals of each group (all of ``skysh/``; the export modules, :data:`EXPORT_MODULES`)
against issue 24's budgets (:data:`BUDGETS`), and the import cycles among ``skysh`` modules.
The files are parsed with :mod:`ast` and :mod:`tokenize`, never imported or run.

Run::

    python tools/code_size.py            # the markdown report
    python tools/code_size.py --tools    # tools/ measured too (a group of its own)
    python tools/code_size.py --json     # the same numbers, machine-readable

What is counted, per file:

physical lines
    Every line of the file (as ``tokenize`` numbers them).
code lines
    The lines holding at least one token that is not a comment, ``NL``/``NEWLINE``,
    ``INDENT``/``DEDENT`` or part of a docstring. A docstring is a string expression statement
    that is the first statement of a module, class or function, or that follows an assignment
    there (an attribute's docstring, as Sphinx and PEP 257 read it: every constant of this
    project carries one, and it is prose).
    A token spanning several lines makes each of them a code line, so every line inside a
    non-docstring multi-line string literal, blank or not, is a code line: generated C, GLSL,
    HLSL or JavaScript held in Python strings is code the module carries. Prose (docstrings,
    comments) and blank lines are never counted, so they are never squeezed to pay for code.
code-string lines
    The lines spanned, first and last included, by string literals that look like generated
    target-language code: a literal (implicitly concatenated pieces are one literal, as in the
    :mod:`ast`; an f-string's text is its literal parts) that spans more than one line, is no
    docstring and contains ``;`` or ``{``. Each such line is also a code line.
``__all__`` names
    The entries of the module's ``__all__`` list or tuple (``=``, ``: list[str] =`` and ``+=``).

Imports among ``skysh`` modules are read everywhere in a file, module level and inside
functions alike, except in ``if TYPE_CHECKING:`` blocks (their ``else`` branches are read).
``import skysh.X``, ``from skysh.X import name`` and ``from skysh import X`` (``X`` a module) are
imports of ``skysh/X.py``; ``from skysh import name`` (not a module) is an import of
``skysh/__init__.py``; relative imports are resolved. A cycle is a strongly connected component of
that graph with more than one module, or a module importing itself.
"""

from __future__ import annotations

import argparse
import ast
import io
import json
import sys
import tokenize
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

ROOT: Path = Path(__file__).resolve().parent.parent
"""The repository root (the folder holding ``skysh/`` and ``tools/``)."""

PACKAGE: str = "skysh"
"""The package measured, and the one whose import graph is drawn."""

EXPORT_PACKAGE: str = f"{PACKAGE}.export"
"""The export package: issue 24's second group (its template files are not Python and are counted apart)."""

PACKAGE_BUDGETS: dict[str, int] = {
    "skysh": 15, "skysh.__main__": 5, "skysh._version": 1, "skysh.checks": 162, "skysh.domain": 110,
    "skysh.options": 90, "skysh.files": 65, "skysh.literals": 30,
    "skysh.sh": 440, "skysh.post": 660, "skysh.model": 995, "skysh.table": 1225, "skysh.lighting": 440,
    "skysh.runtime": 415, "skysh.hosek_runtime": 70, "skysh.engines": 395, "skysh.export": 700, "skysh.app": 1450,
}
"""Code lines each package (a sub-package, or a module of the package's root) may hold (issue 24, item 5):
a ceiling a change must argue with, counted in code lines so that prose is never squeezed to pay for code.
Issue 25 raised ``skysh.post`` from 505 to 650: the least window's search (the exact fraction by tangents and
chords, the certificate's start and gallop, ``least_window``, ``window_at``) is 136 code lines. Issue 26 raised
``skysh.runtime`` (350 to 370: chunked batches, the few-frames route), ``skysh.table`` (1210 to 1225: Chebyshev rows by
doubling), ``skysh.checks`` (145 to 155: range checks in two reductions) and ``skysh.post`` (650 to 660: deringing
a chunk of functions at a time); issue 27 ``skysh.model`` (900 to 980: the Hosek-Wilkie per-frame rule, 175 lines,
with the dataset's reader shrunk by 90; to 995: an albedo per RGB channel), ``skysh.hosek_runtime`` (new, 70: the
Hosek-Wilkie runtime object), ``skysh.runtime`` (to 375: ``SkySH.load(model=)``) and ``skysh.app`` (1360 to 1450:
``--model`` and ``--albedo`` on three commands, the Hosek-Wilkie render panel and the viewer's model switch, 84 lines).
Issue 26 (item 3) raised ``skysh.runtime`` (375 to 415: ``out=``, the composed paths in chunks into the result, the
coefficients call split into its route and its finish to stay within the complexity limit) and ``skysh.checks``
(155 to 162: ``check_out``)."""

BUDGETS: dict[str, int] = {"skysh code lines": 7165, "export code lines": 700, "skysh __all__ names": 260,
                           "import cycles": 0}
"""Issue 24's targets, printed beside the measured numbers (the total raised from 6,500 by issue 25's least
window: 136 lines in ``skysh.post``, 33 in ``skysh.export``; to 6,850 by issues 26 and 27, as the packages' budgets;
to 7,100 and 260 names by issue 27's Hosek-Wilkie runtime, exports, command line and viewer; to 7,165 by issue 26's
``out=`` and composed chunks, as ``skysh.runtime``'s and ``skysh.checks``' budgets)."""

NOT_CODE: frozenset[int] = frozenset({tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT,
                                      tokenize.DEDENT, tokenize.ENDMARKER, tokenize.ENCODING})
"""Token types that never make a line a code line."""

CODE_MARKS: tuple[str, ...] = (";", "{")
"""Characters that make a multi-line string literal look like generated C/GLSL/HLSL/JavaScript."""

COLUMNS: tuple[str, ...] = ("physical", "code", "code_strings", "all_names")
"""The counted columns, in the table's order."""


class Size(NamedTuple):
    """The counts of one module, or of a group of modules (``name`` is then the group's)."""

    name: str
    path: str = ""
    physical: int = 0
    code: int = 0
    code_strings: int = 0
    all_names: int = 0
    modules: int = 1


class Import(NamedTuple):
    """One import of a ``skysh`` module by another: ``source`` imports ``target`` at ``path:line``."""

    source: str
    target: str
    path: str
    line: int
    in_function: bool


class Report(NamedTuple):
    """Everything the tool prints."""

    modules: list[Size]
    groups: list[Size]
    imports: list[Import]
    cycles: list[list[str]]
    packages: list[Size]
    package_cycles: list[list[str]]

    def as_json(self) -> dict[str, object]:
        """The report as JSON values (each module, group and import an object of named fields)."""
        return {"modules": [s._asdict() for s in self.modules], "groups": [g._asdict() for g in self.groups],
                "imports": [i._asdict() for i in self.imports], "cycles": self.cycles,
                "packages": [p._asdict() for p in self.packages], "package_cycles": self.package_cycles}


# --------------------------------------------------------------------------- #
# Counting one file
# --------------------------------------------------------------------------- #
def _is_string(statement: ast.stmt) -> bool:
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant) and \
        isinstance(statement.value.value, str)


def docstrings(tree: ast.AST) -> Iterator[ast.Constant]:
    """The docstring nodes of ``tree``: a string expression first in a module, class or function body, or
    right after an assignment there (an attribute docstring, as Sphinx and PEP 257 read it: this project
    documents every constant so)."""
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            body = node.body
            for k, statement in enumerate(body):
                after_assignment = k > 0 and isinstance(body[k - 1], (ast.Assign, ast.AnnAssign))
                if _is_string(statement) and (k == 0 or after_assignment):
                    yield statement.value  # type: ignore[attr-defined,misc]


def _char_position(lines: Sequence[str], line: int, byte_column: int) -> tuple[int, int]:
    """An :mod:`ast` position (UTF-8 byte column) as a :mod:`tokenize` one (character column)."""
    return line, len(lines[line - 1].encode("utf-8")[:byte_column].decode("utf-8", errors="ignore"))


def code_lines(source: str, tree: ast.AST) -> set[int]:
    """
    The code lines of one module.

    Parameters
    ----------
    source
        The module's text.
    tree
        ``source`` parsed (:func:`ast.parse`): where its docstrings are.

    Returns
    -------
    set of int
        The 1-based numbers of the lines holding a token that is no comment, newline, indentation
        or docstring; every line a multi-line token spans (a string literal) is one of them.
    """
    lines = source.splitlines(keepends=True) or [""]
    spans = [(_char_position(lines, d.lineno, d.col_offset), _char_position(lines, d.end_lineno or d.lineno,
                                                                           d.end_col_offset or 0))
             for d in docstrings(tree)]
    found: set[int] = set()
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type in NOT_CODE or any(start <= token.start and token.end <= end for start, end in spans):
            continue
        found.update(range(token.start[0], token.end[0] + 1))
    return found


def _literal_text(node: ast.expr) -> str:
    if isinstance(node, ast.JoinedStr):
        return "".join(part.value for part in node.values if isinstance(part, ast.Constant) and isinstance(part.value, str))
    return node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else ""


def code_string_lines(tree: ast.AST) -> set[int]:
    """
    The lines of string literals that look like generated target-language code.

    Parameters
    ----------
    tree
        A parsed module.

    Returns
    -------
    set of int
        Every line spanned by a literal (implicit concatenation and f-strings whole) that spans more
        than one line, is no docstring and holds one of :data:`CODE_MARKS`.
    """
    skipped = {id(d) for d in docstrings(tree)}
    skipped |= {id(part) for node in ast.walk(tree) if isinstance(node, ast.JoinedStr) for part in ast.walk(node)
                if part is not node}  # an f-string is judged whole
    found: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Constant, ast.JoinedStr)) and id(node) not in skipped:
            end = node.end_lineno or node.lineno
            if end > node.lineno and any(mark in _literal_text(node) for mark in CODE_MARKS):
                found.update(range(node.lineno, end + 1))
    return found


def all_names(tree: ast.Module) -> int:
    """The number of entries of the module-level ``__all__`` (0 without one)."""
    count = 0
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            value: ast.expr | None = node.value
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)) and isinstance(node.target, ast.Name) \
                and node.target.id == "__all__":
            value = node.value
        else:
            continue
        entries = len(value.elts) if isinstance(value, (ast.List, ast.Tuple)) else 0
        count = count + entries if isinstance(node, ast.AugAssign) else entries
    return count


def measure(source: str, name: str, path: str = "") -> tuple[Size, ast.Module]:
    """
    Count one module.

    Parameters
    ----------
    source
        The module's text.
    name
        Its dotted name (``skysh.table.fit``).
    path
        Its path relative to the repository root, for the table.

    Returns
    -------
    (Size, ast.Module)
        Its counts, and ``source`` parsed (for :func:`imports`).
    """
    tree = ast.parse(source, filename=path or name)
    physical = len(io.StringIO(source).readlines())
    return Size(name, path, physical, len(code_lines(source, tree)), len(code_string_lines(tree)), all_names(tree)), tree


# --------------------------------------------------------------------------- #
# Imports among the package's modules
# --------------------------------------------------------------------------- #
def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def import_nodes(node: ast.AST, in_function: bool = False) -> Iterator[tuple[ast.Import | ast.ImportFrom, bool]]:
    """Every import statement below ``node`` outside ``if TYPE_CHECKING:`` bodies, and whether inside a function."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, (ast.Import, ast.ImportFrom)):
            yield child, in_function
        elif isinstance(child, ast.If) and _is_type_checking(child.test):
            for branch in child.orelse:
                yield from import_nodes(ast.Module(body=[branch], type_ignores=[]), in_function)
        else:
            yield from import_nodes(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)))


def _known(dotted: str, modules: frozenset[str]) -> str | None:
    """The longest prefix of ``dotted`` that is one of ``modules`` (``skysh.table.fit.solve`` -> ``skysh.table.fit``)."""
    parts = dotted.split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in modules:
            return ".".join(parts[:end])
    return None


def _targets(node: ast.Import | ast.ImportFrom, own: str, is_package: bool, modules: frozenset[str]) -> Iterator[str]:
    if isinstance(node, ast.Import):
        yield from filter(None, (_known(alias.name, modules) for alias in node.names))
        return
    origin = node.module or ""
    if node.level:
        base = own.split(".") if is_package else own.split(".")[:-1]
        origin = ".".join(base[: len(base) - (node.level - 1)] + ([origin] if origin else []))
    for alias in node.names:
        target = f"{origin}.{alias.name}" if f"{origin}.{alias.name}" in modules else _known(origin, modules)
        if target is not None:
            yield target


def imports(tree: ast.AST, own: str, modules: frozenset[str], path: str = "", is_package: bool = False) -> list[Import]:
    """
    The imports of the package's modules by one of them.

    Parameters
    ----------
    tree
        The importing module, parsed.
    own
        Its dotted name (relative imports are resolved against it).
    modules
        The dotted names of every module of the package (``skysh``, ``skysh.table.fit``, ...).
    path
        Its path, recorded in each :class:`Import`.
    is_package
        True if ``tree`` is a package's ``__init__.py``.

    Returns
    -------
    list of Import
        One per imported module and statement, module level and inside functions, none from an
        ``if TYPE_CHECKING:`` body.
    """
    found: dict[tuple[str, int], Import] = {}
    for node, in_function in import_nodes(tree):
        for target in _targets(node, own, is_package, modules):
            found.setdefault((target, node.lineno), Import(own, target, path, node.lineno, in_function))
    return list(found.values())


def _reachable(graph: dict[str, set[str]], start: str) -> set[str]:
    """The modules ``start`` imports, directly or through others (``start`` itself only round a cycle)."""
    seen: set[str] = set()
    todo = [start]
    while todo:
        for successor in graph[todo.pop()] - seen:
            seen.add(successor)
            todo.append(successor)
    return seen


def cycles(edges: Iterable[tuple[str, str]]) -> list[list[str]]:
    """
    The import cycles of a graph.

    Parameters
    ----------
    edges
        (importer, imported) pairs.

    Returns
    -------
    list of list of str
        Each strongly connected component of more than one module, or a module importing itself,
        as its sorted names; the components sorted.
    """
    graph: dict[str, set[str]] = {}
    for source, target in edges:
        graph.setdefault(source, set()).add(target)
        graph.setdefault(target, set())
    reach = {node: _reachable(graph, node) for node in graph}
    components = {tuple(sorted(m for m in reach[node] if node in reach[m])) for node in graph if node in reach[node]}
    return [list(c) for c in sorted(components)]


# --------------------------------------------------------------------------- #
# The repository
# --------------------------------------------------------------------------- #
def module_names(folder: Path, prefix: str) -> dict[str, Path]:
    """Every ``.py`` file below ``folder`` by dotted name (``prefix.sub.mod``; a package's ``__init__`` is ``prefix.sub``)."""
    found = {}
    for path in sorted(p for p in folder.rglob("*.py") if "__pycache__" not in p.parts):
        parts = [prefix, *path.relative_to(folder).with_suffix("").parts]
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts).strip(".")] = path
    return found


def package_of(module: str, subpackages: frozenset[str]) -> str:
    """The package a module belongs to: its sub-package (``skysh.table.fit`` -> ``skysh.table``), else itself
    (a module of the package's root, ``skysh.domain``, is a package of its own)."""
    parts = module.split(".")
    return ".".join(parts[:2]) if len(parts) > 1 and ".".join(parts[:2]) in subpackages else module


def package_edges(imports_: Iterable[Import], subpackages: frozenset[str]) -> set[tuple[str, str]]:
    """The (importer, imported) pairs of packages (imports inside a package left out)."""
    pairs = {(package_of(i.source, subpackages), package_of(i.target, subpackages)) for i in imports_}
    return {(a, b) for a, b in pairs if a != b}


def subpackages_of(root: Path) -> frozenset[str]:
    """The dotted names of the package's sub-packages (folders of ``skysh/`` with an ``__init__.py``)."""
    return frozenset(f"{PACKAGE}.{p.parent.name}" for p in (root / PACKAGE).glob("*/__init__.py"))


def total(name: str, sizes: Sequence[Size]) -> Size:
    """The sum of ``sizes`` under ``name``."""
    sums = {column: sum(getattr(s, column) for s in sizes) for column in COLUMNS}
    return Size(name, modules=len(sizes), **sums)


def measure_repository(root: Path = ROOT, with_tools: bool = False) -> Report:
    """
    Measure a repository.

    Parameters
    ----------
    root
        The folder holding ``skysh/`` (and ``tools/``).
    with_tools
        Measure ``tools/`` too: its modules join the table, a group of their own (not the graph).

    Returns
    -------
    Report
        The modules by code lines (most first), the groups (``skysh/``, the export modules, then
        ``tools/``), the package's imports and its cycles.
    """
    package = module_names(root / PACKAGE, PACKAGE)
    known = frozenset(package)
    sizes: list[Size] = []
    edges: list[Import] = []
    for name, path in package.items():
        size, tree = measure(path.read_text(encoding="utf-8"), name, str(path.relative_to(root)))
        sizes.append(size)
        edges += imports(tree, name, known, size.path, path.name == "__init__.py")
    subpackages = subpackages_of(root)
    exports = [s for s in sizes if package_of(s.name, subpackages) == EXPORT_PACKAGE]
    groups = [total(f"all of {PACKAGE}/", sizes), total("export package", exports)]
    by_package: dict[str, list[Size]] = {}
    for size in sizes:
        by_package.setdefault(package_of(size.name, subpackages), []).append(size)
    packages = sorted((total(name, members) for name, members in by_package.items()), key=lambda g: (-g.code, g.name))
    if with_tools:
        tools = [measure(p.read_text(encoding="utf-8"), name, str(p.relative_to(root)))[0]
                 for name, p in module_names(root / "tools", "").items()]
        sizes += tools
        groups.append(total("tools/", tools))
    sizes.sort(key=lambda s: (-s.code, s.name))
    return Report(sizes, groups, edges, cycles((e.source, e.target) for e in edges), packages,
                  cycles(package_edges(edges, subpackages)))


# --------------------------------------------------------------------------- #
# Output
# --------------------------------------------------------------------------- #
def _row(cells: Iterable[object]) -> str:
    return "| " + " | ".join(f"{c:,}" if isinstance(c, int) else str(c) for c in cells) + " |"


def _budgets(report: Report) -> list[str]:
    package, export = report.groups[0], report.groups[1]
    measured = {"skysh code lines": package.code, "export code lines": export.code,
                "skysh __all__ names": package.all_names, "import cycles": len(report.cycles) + len(report.package_cycles)}
    return ["| measure | today | target |", "|---|--:|--:|",
            *(_row((what, measured[what], target)) for what, target in BUDGETS.items())]


def _package_lines(report: Report) -> list[str]:
    lines = ["| package | modules | code | budget | `__all__` |", "|---|--:|--:|--:|--:|"]
    return lines + [_row((p.name, p.modules, p.code, PACKAGE_BUDGETS.get(p.name, "none"), p.all_names))
                     for p in report.packages]


def _cycle_lines(report: Report) -> list[str]:
    if not report.cycles:
        return ["None."]
    lines = []
    for members in report.cycles:
        inside = sorted((e for e in report.imports if e.source in members and e.target in members),
                        key=lambda e: (e.path, e.line))
        lines.append("-   " + " <-> ".join(members) + ": " + "; ".join(
            f"{e.path}:{e.line} imports {e.target}{' (in a function)' if e.in_function else ''}" for e in inside))
    return lines


def markdown(report: Report) -> str:
    """The report as markdown: the modules by code lines, the totals, the budgets, the cycles."""
    header = "| {} | physical | code | code in strings | `__all__` |"
    lines = ["# Code size (tools/code_size.py)", "", header.format("module"), "|---|--:|--:|--:|--:|"]
    lines += [_row((s.path, *(getattr(s, c) for c in COLUMNS))) for s in report.modules]
    lines += ["", "## Totals", "", header.format("group | modules"), "|---|--:|--:|--:|--:|--:|"]
    lines += [_row((g.name, g.modules, *(getattr(g, c) for c in COLUMNS))) for g in report.groups]
    lines += ["", "## Packages (code lines against PACKAGE_BUDGETS)", "", *_package_lines(report)]
    lines += ["", "## Issue 24's budgets", "", *_budgets(report)]
    lines += ["", f"## Import cycles among {PACKAGE} modules (imports inside functions included)", "", *_cycle_lines(report)]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """The command line: print the report (markdown, or JSON with ``--json``)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].strip() if __doc__ else None,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tools", action="store_true", help="measure tools/ too (a group of its own)")
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    parser.add_argument("--root", type=Path, default=ROOT, help="the repository measured (default: this one)")
    args = parser.parse_args(argv)
    report = measure_repository(args.root, args.tools)
    sys.stdout.write(json.dumps(report.as_json(), indent=1) + "\n" if args.json else markdown(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
