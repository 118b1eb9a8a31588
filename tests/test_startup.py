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
-   ``skysh coeffs`` end to end is within 3x ``python -c "import numpy"``
    (best of a few runs, the benchmark's own function).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_startup  # noqa: E402

FORBIDDEN: tuple[str, ...] = ("colour", "matplotlib", "skysh.fit", "tools", "tqdm")
"""Top-level names (and prefixes) that the light paths must not import."""

STARTUP_BUDGET: float = bench_startup.BUDGET
"""skysh coeffs wall time / import numpy wall time (the issue's 3x)."""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _forbidden(modules: list[str]) -> list[str]:
    return sorted(m for m in modules if any(m == f or m.startswith(f + ".") for f in FORBIDDEN))


def test_library_import_is_light() -> None:
    code = (
        "import sys, json, skysh\n"
        "from skysh import SkySH\n"
        "sky = SkySH.load()\n"
        "sky.coefficients(0.5, 3.0, 1.0)\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), cwd=ROOT, check=True)
    modules = json.loads(result.stdout)
    assert "skysh.runtime" in modules
    assert _forbidden(modules) == []


@pytest.mark.parametrize(
    "extra",
    [[], ["--format", "json"], ["--format", "glsl", "--irradiance", "--up", "y", "--normalise"], ["--format", "csv"]],
)
def test_coeffs_command_does_not_import_colour(extra: list[str]) -> None:
    argv = [sys.executable, "-X", "importtime", "-m", "skysh", "coeffs", *bench_startup.COEFFS_ARGS[1:], *extra]
    result = subprocess.run(argv, capture_output=True, text=True, env=_env(), cwd=ROOT)
    assert result.returncode == 0, result.stderr[-2000:]
    imported = [line.rsplit("|", 1)[-1].strip() for line in result.stderr.splitlines() if line.startswith("import time:")]
    assert "skysh.runtime" in imported
    assert _forbidden(imported) == []


def test_coeffs_from_place_and_time_does_not_import_colour() -> None:
    argv = [sys.executable, "-X", "importtime", "-m", "skysh", "coeffs", "--lat", "48.2", "--lon", "16.4",
            "--time", "2024-06-21T12:00:00Z", "--turbidity", "3"]
    result = subprocess.run(argv, capture_output=True, text=True, env=_env(), cwd=ROOT)
    assert result.returncode == 0, result.stderr[-2000:]
    imported = [line.rsplit("|", 1)[-1].strip() for line in result.stderr.splitlines() if line.startswith("import time:")]
    assert "skysh.sun" in imported and _forbidden(imported) == []


def test_render_works_without_matplotlib(tmp_path: Path) -> None:
    # colour-science (which the true sky needs) imports matplotlib itself when it is
    # installed, so the check is that rendering works with matplotlib made unimportable.
    out = tmp_path / "r.png"
    code = (
        "import sys, warnings\n"
        "sys.modules['matplotlib'] = None  # import matplotlib now raises ImportError\n"
        "warnings.simplefilter('ignore')  # colour-science warns that its plotting is unavailable\n"
        "from skysh.cli import main\n"
        f"sys.exit(main(['render', '--sun-zenith', '40', '--turbidity', '3', '--width', '16', '--out', {str(out)!r}]))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=_env(), cwd=ROOT)
    assert result.returncode == 0, result.stderr[-2000:]
    assert out.read_bytes().startswith(b"\x89PNG")


def test_coeffs_within_3x_import_numpy() -> None:
    cases = bench_startup.commands()
    timed = {name: cases[name] for name in ("numpy", "skysh coeffs (python -m)")}
    best = bench_startup.best_times(timed, repeats=3)
    ratio = best["skysh coeffs (python -m)"] / best["numpy"]
    assert ratio < STARTUP_BUDGET, f"skysh coeffs takes {ratio:.2f}x import numpy ({best})"
