"""
Start-up: ``import skysh``, ``SkySH.load()`` and ``skysh coeffs`` stay light.

colour-science alone takes about 1.5 s to import. Each check runs a fresh
interpreter (a subprocess), so modules imported by other tests do not count:

-   ``import skysh`` + ``SkySH.load()`` + one coefficients call import neither
    colour-science, matplotlib, the offline fit (``skysh.fit``) nor ``tools``;
-   ``python -X importtime -m skysh coeffs ...`` (default sRGB, every text
    format, the sun from a place and time) imports none of them either;
-   ``skysh render`` works with matplotlib unimportable (colour-science, which
    it needs for the true sky, imports matplotlib itself when installed);
The wall time of ``skysh coeffs`` against ``python -c "import numpy"`` (a speed goal, not a
test) is printed by ``python benchmarks/bench_startup.py``.

The interpreters of the import checks run side by side (conftest.run_concurrently).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from typing import Any

import pytest
from conftest import ROOT, run_concurrently

sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_startup

FORBIDDEN: tuple[str, ...] = ("colour", "matplotlib", "skysh.fit", "tools", "tqdm")
"""Top-level names (and prefixes) that the light paths must not import."""

"""skysh coeffs wall time / import numpy wall time (the issue's 3x)."""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _forbidden(modules: list[str]) -> list[str]:
    return sorted(m for m in modules if any(m == f or m.startswith(f + ".") for f in FORBIDDEN))


LIBRARY_CODE: str = (
    "import sys, json, skysh\n"
    "from skysh import SkySH\n"
    "sky = SkySH.load()\n"
    "sky.coefficients(0.5, 3.0, 1.0)\n"
    "print(json.dumps(sorted(sys.modules)))\n"
)
"""import skysh, load the file, one coefficients call; prints every module imported."""

COEFFS_EXTRAS: dict[str, list[str]] = {
    "text": [], "json": ["--format", "json"], "glsl": ["--format", "glsl", "--irradiance", "--up", "y", "--normalise"],
    "csv": ["--format", "csv"],
}
"""The coeffs formats checked, by name (default sRGB)."""

PLACE_AND_TIME: list[str] = ["--lat", "48.2", "--lon", "16.4", "--time", "2024-06-21T12:00:00Z", "--turbidity", "3"]
"""The sun from a place and time instead of angles."""

RENDER_CODE: str = (
    "import sys, warnings\n"
    "sys.modules['matplotlib'] = None  # import matplotlib now raises ImportError\n"
    "warnings.simplefilter('ignore')  # colour-science warns that its plotting is unavailable\n"
    "from skysh.cli import main\n"
    "sys.exit(main(['render', '--sun-zenith', '40', '--turbidity', '3', '--width', '16', '--out', sys.argv[1]]))\n"
)
"""skysh render with matplotlib made unimportable; the PNG's path is the first argument."""


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Every fresh interpreter of this module, started at once (each mostly imports); results by name."""
    png = tmp_path_factory.mktemp("render") / "r.png"
    coeffs = [sys.executable, "-X", "importtime", "-m", "skysh", "coeffs"]
    commands = {
        "library": [sys.executable, "-c", LIBRARY_CODE],
        **{f"coeffs {name}": [*coeffs, *bench_startup.COEFFS_ARGS[1:], *extra] for name, extra in COEFFS_EXTRAS.items()},
        "place and time": [*coeffs, *PLACE_AND_TIME],
        "render": [sys.executable, "-c", RENDER_CODE, str(png)],
    }
    return {"png": png, **run_concurrently(commands, env=_env(), cwd=ROOT)}


def _imported(result: subprocess.CompletedProcess) -> list[str]:
    """Modules named by ``-X importtime`` on stderr."""
    return [line.rsplit("|", 1)[-1].strip() for line in result.stderr.splitlines() if line.startswith("import time:")]


def test_library_import_is_light(runs: dict[str, Any]) -> None:
    result = runs["library"]
    assert result.returncode == 0, result.stderr[-2000:]
    modules = json.loads(result.stdout)
    assert "skysh.runtime" in modules
    assert _forbidden(modules) == []


@pytest.mark.parametrize("name", list(COEFFS_EXTRAS))
def test_coeffs_command_does_not_import_colour(runs: dict[str, Any], name: str) -> None:
    result = runs[f"coeffs {name}"]
    assert result.returncode == 0, result.stderr[-2000:]
    imported = _imported(result)
    assert "skysh.runtime" in imported
    assert _forbidden(imported) == []


def test_coeffs_from_place_and_time_does_not_import_colour(runs: dict[str, Any]) -> None:
    result = runs["place and time"]
    assert result.returncode == 0, result.stderr[-2000:]
    imported = _imported(result)
    assert "skysh.sun" in imported and _forbidden(imported) == []


def test_render_works_without_matplotlib(runs: dict[str, Any]) -> None:
    # colour-science (which the true sky needs) imports matplotlib itself when it is
    # installed, so the check is that rendering works with matplotlib made unimportable.
    result = runs["render"]
    assert result.returncode == 0, result.stderr[-2000:]
    assert runs["png"].read_bytes().startswith(b"\x89PNG")
