"""
Start-up: ``import skysh``, ``SkySH.load()`` and ``skysh coeffs`` stay light.

colour-science alone takes about 1.5 s to import. The checks run in a fresh
interpreter (a subprocess), so modules imported by other tests do not count: one
interpreter, ``python -X importtime``, runs every step below in turn (issue 14: one
interpreter start instead of seven), and each test asserts on its own step:

-   ``import skysh`` + ``SkySH.load()`` + one coefficients call, first, while the
    interpreter is fresh (``sys.modules`` right after it): import neither
    colour-science, matplotlib, the offline fit (``skysh.fit``) nor ``tools``;
-   ``python -m skysh coeffs ...`` (default sRGB, every text format, the sun from a
    place and time), each run as ``python -m`` runs it (``runpy``, ``__main__``):
    none of them imported by that step or any step before it (the union of the
    ``-X importtime`` lines so far: a step's own imports plus what the steps before
    it loaded, at least what a fresh ``python -m skysh coeffs`` would import);
-   last, ``skysh render`` works with matplotlib unimportable (colour-science, which
    it needs for the true sky, imports matplotlib itself when installed).

The wall time of ``skysh coeffs`` against ``python -c "import numpy"`` (a speed goal, not a
test) is printed by ``python benchmarks/bench_startup.py``.

:class:`Prefetched` (jobs started when a module begins, awaited by its tests) is shared with
the other subprocess-bound test files (test_cli, test_preetham, test_sunlight, test_viewer,
test_engines).
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import urllib.request
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any, Generic, TypeVar

import pytest
from conftest import ROOT, modules_stay_whole

sys.path.insert(0, str(ROOT / "benchmarks"))

import bench_startup

T = TypeVar("T")

FORBIDDEN: tuple[str, ...] = ("colour", "matplotlib", "skysh.fit", "tools", "tqdm")
"""Top-level names (and prefixes) that the light paths must not import."""

STEP_MARK: str = "test_startup step done: "
"""Written to stderr after each step of :data:`PROBE` (followed by the step's name): splits the
``-X importtime`` lines by step."""

PROBE_TIMEOUT_S: float = 300.0
"""Hang guard of the probe interpreter (its time is mostly colour-science's import, in the render step)."""


class Prefetched(Generic[T]):
    """Jobs (name -> function of no arguments) started on background threads when a module begins, so that
    the module's other tests overlap them; :meth:`result` waits for one (issue 14).

    ``eager`` False (pytest-xdist sharing a module between processes: conftest.modules_stay_whole) starts
    nothing ahead: :meth:`result` then runs a job the first time a test asks for it. Each job runs once; its
    exception is raised in every test that asks for its result, so each test fails for itself. Jobs run
    subprocesses, or compute from fixed inputs (numpy releases the interpreter lock in its array loops); they
    change nothing, read nothing that the module's tests change, and leave process-wide state alone (no
    import that changes warning filters: warnings.catch_warnings is not thread-safe).
    """

    def __init__(self, jobs: Mapping[str, Callable[[], T]], eager: bool) -> None:
        self._jobs = dict(jobs)
        self._pool = ThreadPoolExecutor(max_workers=max(1, len(self._jobs)), thread_name_prefix="prefetched")
        self._futures: dict[str, Future[T]] = {}
        self._lock = threading.Lock()
        if eager:
            for name in self._jobs:
                self._start(name)

    def _start(self, name: str) -> Future[T]:
        with self._lock:
            if name not in self._futures:
                self._futures[name] = self._pool.submit(self._jobs[name])
            return self._futures[name]

    def result(self, name: str) -> T:
        """The job's return value, waiting for it (started now if it was not)."""
        return self._start(name).result()

    def close(self) -> None:
        """Wait for the running jobs (each has its own hang guard); drop those never started."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def prefetched(request: pytest.FixtureRequest, jobs: Mapping[str, Callable[[], T]]) -> Iterator[Prefetched[T]]:
    """Body of a module fixture (``yield from``): ``jobs`` as a :class:`Prefetched`, eager when the module stays in
    this process (conftest.modules_stay_whole; True without pytest-xdist), closed at the module's end."""
    jobs_ = Prefetched(jobs, eager=modules_stay_whole(request.config))
    try:
        yield jobs_
    finally:
        jobs_.close()


def start_early(request: pytest.FixtureRequest, *fixtures: str) -> None:
    """In a module's autouse fixture: set up the module fixtures ``fixtures`` now, at the module's first test, when
    the module stays in this process and a test of it selected in this session asks for one of them (so their
    background jobs overlap the module's other tests; a run of other tests of the module starts nothing)."""
    if modules_stay_whole(request.config):
        for name in fixtures:
            if asked_for(request, name):
                request.getfixturevalue(name)


def asked_for(request: pytest.FixtureRequest, fixture: str) -> bool:
    """Whether a test of the requesting module selected in this session asks for ``fixture`` (directly or not)."""
    return any(getattr(item, "module", None) is request.module and fixture in getattr(item, "fixturenames", ())
               for item in request.session.items)


SERVER_START_TIMEOUT_S: float = 180.0
"""Hang guard of a server subprocess's start (imports, the coefficient file and colour-science on a shared
machine), and of each step after it."""


def server_session(argv: list[str], cwd: Path = ROOT) -> dict[str, Any]:
    """Run a server command (``python -m skysh view``, ``serve()``): the first line it prints, one GET of the
    loopback address in it (status and body), then Ctrl-C (SIGINT): its exit status, stdout and stderr. None
    (b"" for the body) where a step was not reached."""
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd)
    timer = threading.Timer(SERVER_START_TIMEOUT_S, process.kill)
    timer.start()
    session: dict[str, Any] = {"line": "", "status": None, "body": b"", "code": None, "out": None, "err": None}
    try:
        session["line"] = process.stdout.readline() if process.stdout else ""
        address = re.search(r"http://127\.0\.0\.1:\d+/", session["line"])
        if address:
            with urllib.request.urlopen(address.group(0), timeout=SERVER_START_TIMEOUT_S) as response:
                session["status"], session["body"] = response.status, response.read()
            process.send_signal(signal.SIGINT)
            session["out"], session["err"] = process.communicate(timeout=SERVER_START_TIMEOUT_S)
            session["code"] = process.returncode
    finally:
        timer.cancel()
        if process.poll() is None:
            process.kill()
            process.communicate()
    return session


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
    from skysh.cli import main
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
    assert "skysh.runtime" in imported and "skysh.cli" in imported
    assert _forbidden(imported) == []


def test_coeffs_from_place_and_time_does_not_import_colour(probe: dict[str, Any]) -> None:
    imported = _light_step(probe, "place and time")
    assert "skysh.sun" in imported and _forbidden(imported) == []


def test_render_works_without_matplotlib(probe: dict[str, Any]) -> None:
    # colour-science (which the true sky needs) imports matplotlib itself when it is
    # installed, so the check is that rendering works with matplotlib made unimportable.
    assert probe["codes"]["render"][0] == 0, probe["codes"]["render"]
    assert Path(probe["png"]).read_bytes().startswith(b"\x89PNG")
