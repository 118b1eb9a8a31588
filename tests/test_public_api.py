"""``import skysh`` exposes only its public names (``__all__``), plus dunders and submodules."""

from __future__ import annotations

import subprocess
import sys
import types

import skysh


def test_public_names_are_all() -> None:
    public = {n for n in dir(skysh) if not n.startswith("_") and not isinstance(getattr(skysh, n), types.ModuleType)}
    assert public == set(skysh.__all__) - {"__version__"}


def test_every_name_in_all_resolves() -> None:
    for name in skysh.__all__:
        assert getattr(skysh, name) is not None


def test_fresh_import_leaks_no_helpers() -> None:
    # In a fresh interpreter (no submodule imported yet by other tests): no typing or __future__ names.
    code = "import skysh, types; print(sorted(n for n in vars(skysh) if not n.startswith('_')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "[]"  # SkySH is lazy (module __getattr__), so nothing public is bound until first use
