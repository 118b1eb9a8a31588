"""
The wheel built from the repository carries the data file and the type marker
==============================================================================

Builds a wheel (``pip wheel --no-deps --no-build-isolation``, so no network)
from a copy of the source tree, and checks its contents: the shipped
coefficient file as ``skysh/data/preetham_sh.npz`` (byte-identical to
``data/preetham_sh.npz`` and readable), ``skysh/py.typed``, every module of the
package, and nothing outside ``skysh/`` and the dist-info. Installing the
wheel is tested elsewhere (``tests/test_install.py``).

The wheel is conftest's session fixture ``wheel`` (shared with
``tests/test_install.py``): its copy of the tree leaves out ``build/``, ``dist/``
and ``*.egg-info`` so that stale build products of the working tree cannot leak
into the wheel, and so the test writes nothing into the repository.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest
from conftest import ROOT

from skysh.table import coefficient_file

pytestmark = pytest.mark.integration  # builds a wheel with pip and setuptools


def _names(wheel: Path) -> list[str]:
    with zipfile.ZipFile(wheel) as archive:
        return archive.namelist()


class TestWheelContents:
    def test_data_file_and_type_marker(self, wheel: Path) -> None:
        names = _names(wheel)
        assert "skysh/data/preetham_sh.npz" in names
        assert "skysh/py.typed" in names

    def test_data_file_is_the_shipped_file(self, wheel: Path, tmp_path: Path) -> None:
        with zipfile.ZipFile(wheel) as archive:
            payload = archive.read("skysh/data/preetham_sh.npz")
        assert payload == (ROOT / "data" / coefficient_file.DEFAULT_FILE_NAME).read_bytes()
        extracted = tmp_path / "preetham_sh.npz"
        extracted.write_bytes(payload)
        table = coefficient_file.read(extracted)
        assert table.bands == 7 and "errors" in table.metadata

    def test_every_module_is_packaged(self, wheel: Path) -> None:
        """Every module of every sub-package, the viewer's page and the exports' source files."""
        names = set(_names(wheel))
        shipped = [p for pattern in ("**/*.py", "app/web/*", "export/templates/*") for p in (ROOT / "skysh").glob(pattern)
                   if "__pycache__" not in p.parts and p.is_file()]
        files = {p.relative_to(ROOT).as_posix() for p in shipped}
        assert len(files) > 50 and files <= names, sorted(files - names)

    def test_nothing_outside_the_package(self, wheel: Path) -> None:
        tops = {name.split("/")[0] for name in _names(wheel)}
        dist_info = {t for t in tops if t.endswith(".dist-info")}
        assert len(dist_info) == 1
        assert tops - dist_info == {"skysh"}, tops  # no top-level data/, tests/, tools/ or benchmarks/
