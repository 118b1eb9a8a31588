"""
Start-up: ``import skysh``, ``SkySH.load()`` and ``skysh coeffs`` stay light.

colour-science alone takes about 1.5 s to import. The checks run in a fresh
interpreter (a subprocess), so modules imported by other tests do not count: one
interpreter, ``python -X importtime``, runs every step below in turn (issue 14: one
interpreter start instead of seven), and each test asserts on its own step:

-   ``import skysh`` + ``SkySH.load()`` + one coefficients call, first, while the
    interpreter is fresh (``sys.modules`` right after it): import neither
    colour-science, matplotlib, the offline fit (``skysh.table.fit``) nor ``tools``;
-   ``python -m skysh coeffs ...`` (default sRGB, every text format, the sun from a
    place and time), each run as ``python -m`` runs it (``runpy``, ``__main__``):
    none of them imported by that step or any step before it (the union of the
    ``-X importtime`` lines so far: a step's own imports plus what the steps before
    it loaded, at least what a fresh ``python -m skysh coeffs`` would import);
-   last, ``skysh render`` works with matplotlib unimportable (colour-science, which
    it needs for the true sky, imports matplotlib itself when installed).

The wall time of ``skysh coeffs`` against ``python -c "import numpy"`` (a speed goal, not a
test) is printed by ``python benchmarks/bench_startup.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_startup

FORBIDDEN: tuple[str, ...] = ("colour", "matplotlib", "skysh.table.fit", "tools", "tqdm")
"""Top-level names (and prefixes) that the light paths must not import."""

STEP_MARK: str = "test_startup step done: "
"""Written to stderr after each step of :data:`PROBE` (followed by the step's name): splits the
``-X importtime`` lines by step."""

PROBE_TIMEOUT_S: float = 300.0
"""Hang guard of the probe interpreter (its time is mostly colour-science's import, in the render step)."""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def _forbidden(modules: list[str]) -> list[str]:
    return sorted(m for m in modules if any(m == f or m.startswith(f + ".") for f in FORBIDDEN))


COEFFS_EXTRAS: dict[str, list[str]] = {
    "text": [], "json": ["--format", "json"], "glsl": ["--format", "glsl", "--irradiance", "--up", "y", "--normalise"],
    "csv": ["--format", "csv"],
}
"""The coeffs formats checked, by name (default sRGB)."""

PLACE_AND_TIME: list[str] = ["--lat", "48.2", "--lon", "16.4", "--time", "2024-06-21T12:00:00Z", "--turbidity", "3"]
"""The sun from a place and time instead of angles."""

COEFFS_STEPS: dict[str, list[str]] = {
    **{f"coeffs {name}": [*bench_startup.COEFFS_ARGS, *extra] for name, extra in COEFFS_EXTRAS.items()},
    "place and time": ["coeffs", *PLACE_AND_TIME],
}
"""The ``python -m skysh`` command lines the probe runs after the library step, by step name."""

PROBE: str = r"""
import contextlib, io, json, runpy, sys, warnings

def done(step):
    print(STEP_MARK + step, file=sys.stderr, flush=True)

steps, png = json.loads(sys.argv[1]), sys.argv[2]

# the library, in the fresh interpreter: import skysh, load the file, one coefficients call
import skysh
from skysh import SkySH
SkySH.load().coefficients(0.5, 3.0, 1.0)
library = sorted(sys.modules)
done("library")

codes = {}
for step, argv in steps.items():  # as `python -m skysh ARGV` runs skysh/__main__.py
    sys.argv = ["skysh", *argv]
    with contextlib.redirect_stdout(io.StringIO()) as out:
        try:
            runpy.run_module("skysh", run_name="__main__", alter_sys=True)
            codes[step] = 0
        except SystemExit as exit_:
            codes[step] = 0 if exit_.code is None else exit_.code
        except Exception as error:  # the step's test fails, naming it; the others still run
            codes[step] = repr(error)
    codes[step] = [codes[step], out.getvalue()]
    done(step)

# last: skysh render with matplotlib made unimportable; the PNG's path is the second argument
sys.modules["matplotlib"] = None  # import matplotlib now raises ImportError
warnings.simplefilter("ignore")  # colour-science warns that its plotting is unavailable
try:
    from skysh.app.cli import main
    with contextlib.redirect_stdout(io.StringIO()):
        codes["render"] = [main(["render", "--sun-zenith", "40", "--turbidity", "3", "--width", "16", "--out", png]), ""]
except Exception as error:
    codes["render"] = [repr(error), ""]
done("render")
print(json.dumps({"library": library, "codes": codes}))
""".replace("STEP_MARK", repr(STEP_MARK))
"""One interpreter for every check: the library step, then each of :data:`COEFFS_STEPS`, then render."""


@pytest.fixture(scope="module")
def probe(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The probe's results: ``library`` (modules after the library step), ``codes`` (step -> [exit status,
    stdout]), ``imported`` (step -> every module ``-X importtime`` saw up to the end of that step), ``png``."""
    png = tmp_path_factory.mktemp("render") / "r.png"
    argv = [sys.executable, "-X", "importtime", "-c", PROBE, json.dumps(COEFFS_STEPS), str(png)]
    result = subprocess.run(argv, env=_env(), cwd=ROOT, capture_output=True, text=True, timeout=PROBE_TIMEOUT_S,
                            check=False)
    assert result.returncode == 0, result.stderr[-3000:]
    imported, so_far = {}, []
    for line in result.stderr.splitlines():
        if line.startswith("import time:"):
            so_far.append(line.rsplit("|", 1)[-1].strip())
        elif line.startswith(STEP_MARK):
            imported[line[len(STEP_MARK):]] = list(so_far)
    return {**json.loads(result.stdout.splitlines()[-1]), "imported": imported, "png": png}


def test_library_import_is_light(probe: dict[str, Any]) -> None:
    modules = probe["library"]
    assert "skysh.runtime" in modules
    assert _forbidden(modules) == []


def _light_step(probe: dict[str, Any], step: str) -> list[str]:
    code, out = probe["codes"][step]
    assert code == 0 and out, (step, code)
    return probe["imported"][step]


@pytest.mark.parametrize("name", list(COEFFS_EXTRAS))
def test_coeffs_command_does_not_import_colour(probe: dict[str, Any], name: str) -> None:
    imported = _light_step(probe, f"coeffs {name}")
    assert "skysh.runtime" in imported and "skysh.app.cli" in imported
    assert _forbidden(imported) == []


def test_coeffs_from_place_and_time_does_not_import_colour(probe: dict[str, Any]) -> None:
    imported = _light_step(probe, "place and time")
    assert "skysh.lighting.sun" in imported and _forbidden(imported) == []


def test_render_works_without_matplotlib(probe: dict[str, Any]) -> None:
    # colour-science (which the true sky needs) imports matplotlib itself when it is
    # installed, so the check is that rendering works with matplotlib made unimportable.
    assert probe["codes"]["render"][0] == 0, probe["codes"]["render"]
    assert Path(probe["png"]).read_bytes().startswith(b"\x89PNG")
