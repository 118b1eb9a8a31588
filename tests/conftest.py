"""
Shared test helpers
===================

What more than one test file needs, written once (issue 14: "tests share what they
share"). Plain helpers are imported by name (``from conftest import scipy_real_sh``:
``tests/`` is on ``sys.path`` in pytest's default import mode, which is also how
``test_dering_adversarial`` imports ``test_dering``); fixtures are found by pytest.

Paths and numbers
    :data:`ROOT`, :data:`TOOLS`, :data:`EPS`, :data:`L_OF`.
Independent references (none of them calls the function a test checks)
    :func:`scipy_real_sh` (real SH from scipy's complex ``sph_harm_y``),
    :func:`chebyshev_variables` (the coefficient file's fit variables typed from its
    'basis' text), :func:`reference_min` / :func:`channel_min` (minimum of an SH function
    over the sphere by grid search and Newton steps).
Inputs
    :func:`unit`, :func:`random_unit_vectors`, :func:`fibonacci_sphere`, :func:`light`,
    :func:`random_functions`, :func:`sky_samples`.
Measures and options
    :func:`dc_relative_error`, :data:`PLAIN_DIP`, :func:`old_pipeline`, :func:`canonical_json`,
    :func:`engine_cases`, :func:`is_padded_identity`.
Running code
    :func:`load_script`, :func:`tools_on_path`, :func:`python_without_matplotlib`,
    :func:`pythons_without_matplotlib`, :func:`run_concurrently`, :func:`environment_without_pythonpath`,
    :func:`script_without_cvxpy`; the marker :data:`needs_cvxpy`.
    Work run ahead in the background (tool runs, a module's named jobs) is in ``tests/background.py``.
Hooks
    The ``late`` marker (a test so marked runs after the other tests of its module);
    :func:`pytest_configure_node` (the distribution mode, for ``background.modules_stay_whole``).
Fixtures
    :func:`sky` (the shipped :class:`skysh.SkySH`, loaded once per session), :func:`exported` (its
    ``export_source`` texts, each made once; type :data:`Exported`), :func:`tool_runs` (the session's
    ``background.ToolRuns``), :func:`wheel` (the package's wheel, built once per session from a clean copy
    of the tree).

Tolerances stay in the test files, next to what they bound: their size follows from
what each test compares (see each file's constants).
"""

from __future__ import annotations

import functools
import importlib.util
import inspect
import json
import math
import os
import shutil
import subprocess
import sys
import types
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pytest
from background import ToolRuns, modules_stay_whole
from scipy.special import sph_harm_y

from skysh.sh import basis as sh
from skysh.table import irradiance_fit

if TYPE_CHECKING:  # the runtime is imported by the fixture that loads it, not by collecting the tests
    from skysh.runtime import SkySH

ROOT: Path = Path(__file__).resolve().parent.parent
"""The repository root (the folder holding ``skysh/``, ``tools/`` and ``tests/``)."""

TOOLS: Path = ROOT / "tools"
"""The command-line tools and studies (not part of the installed package)."""

EPS: float = float(np.finfo(np.float64).eps)
"""Machine epsilon of float64, 2.2e-16: the unit of the rounding allowances."""

L_OF: np.ndarray = np.repeat(np.arange(64), 2 * np.arange(64) + 1)
"""Band l of every flat SH index i = l (l + 1) + m, for all 64 bands skysh.sh.basis takes (4,096
entries); ``L_OF[: bands * bands]`` is the table of a smaller band count."""
L_OF.flags.writeable = False

WHEEL_SOURCE_IGNORED = shutil.ignore_patterns(
    ".git", "build", "dist", "*.egg-info", "__pycache__", ".pytest_cache", ".hypothesis", "*.pyc", "out", "report*",
    "node_modules",
)
"""What the :func:`wheel` fixture's copy of the tree leaves out: build products of the working tree (they
could leak into the wheel), caches, and the JavaScript test dependencies (a wheel holds none of them)."""

WHEEL_BUILD_TIMEOUT_S: float = 300.0
"""Hang guard of the wheel build (pip without network; a few seconds normally)."""

NO_MATPLOTLIB: str = "import sys; sys.modules['matplotlib'] = None  # a plain install: colour-science without matplotlib\n"
"""Python source that makes ``import matplotlib`` fail, as on a machine without it."""

NO_CVXPY: str = f"import sys; sys.modules.update(dict.fromkeys({irradiance_fit.SOLVER_PACKAGES!r}))  # no tools extra\n"
"""Python source that makes the solver's packages unimportable (and unfound), whether or not they are installed."""

SKIP_NO_GLSLANG: str = "glslangValidator is not installed: apt-get install glslang-tools (.ci/run installs it)"
SKIP_NO_NODE: str = "node is not installed: install Node.js >= 18, e.g. apt-get install nodejs"
SKIP_NO_CC: str = "no C compiler on this machine: apt-get install gcc"
SKIP_NO_TSC: str = "typescript (tsc) is not installed: npm ci --prefix tests/js (the declarations are checked structurally)"
"""Skip reasons of the tests that drive an optional tool, each naming the command that brings it."""

needs_cvxpy = pytest.mark.skipif(not irradiance_fit.solver_available(),
                                 reason=irradiance_fit.solver_missing_message("this test"))
"""Skips a test that solves (cvxpy and Clarabel: the tools extra), saying what to install."""


# --------------------------------------------------------------------------- #
# Inputs
# --------------------------------------------------------------------------- #
def unit(v: Any) -> np.ndarray:
    """``v`` (..., 3) scaled to unit length along the last axis, as float64."""
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_unit_vectors(n: int, seed: int = 0) -> np.ndarray:
    """``n`` unit vectors (n, 3) uniform on the sphere: normalised Gaussians from ``default_rng(seed)``."""
    return unit(np.random.default_rng(seed).normal(size=(n, 3)))


def fibonacci_sphere(n: int) -> np.ndarray:
    """``n`` quasi-uniform unit vectors (n, 3) on the golden-angle spiral, z from +1 down to -1.

    Independent of every constant of skysh (point k: z = 1 - 2 (k + 1/2) / n, azimuth
    pi (3 - sqrt 5) (k + 1/2)).
    """
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def light(rng: np.random.Generator, bands: int, channels: int = 3) -> np.ndarray:
    """A random non-negative light (bands**2, channels): HDR deltas, an arc (linear light) and maybe ambient."""
    c = np.zeros((bands * bands, channels))
    k = int(rng.integers(1, 4))
    c += sh.basis(unit(rng.normal(size=(k, 3))), bands).T @ (10.0 ** rng.uniform(-1.0, 3.0, (k, channels)))
    if rng.random() < 0.6:
        a, b = unit(rng.normal(size=(2, 3)))
        b = unit(b - a * (a @ b))
        t = np.linspace(0.0, rng.uniform(0.1, 1.5), 48)
        arc = np.cos(t)[:, None] * a + np.sin(t)[:, None] * b
        c += sh.basis(arc, bands).sum(axis=0)[:, None] * (10.0 ** rng.uniform(0.0, 2.0, channels) / 48)
    if rng.random() < 0.4:
        c[0] += 10.0 ** rng.uniform(-2.0, 1.0, channels) * 2.0 * math.sqrt(math.pi)
    return c


def random_functions(rng: np.random.Generator, n: int, bands: int) -> np.ndarray:
    """(n, bands**2) random SH functions with a wide spread of coefficient sizes."""
    k = bands * bands
    return rng.normal(size=(n, k)) * rng.uniform(0.0, 2.0, (n, k)) ** 2


def sky_samples(n: int, bands: int = 3, gibbs: bool = True) -> np.ndarray:
    """(n, bands**2, 3) sky radiance SH across the fitted domain, its 4 corners first.

    The reference projection ``preetham.sky_sh`` (independent of the runtime's fitted file),
    with the runtime's zonal Gibbs filter ``c(l, 0) *= sinc(l / N)`` (Habel eq. 5) when ``gibbs``.
    """
    from skysh.model import preetham

    rng = np.random.default_rng(44)
    zen = np.concatenate([[0.0, math.pi / 2, 0.0, math.pi / 2], rng.uniform(0, math.pi / 2, n - 4)])
    tur = np.concatenate([[2.5, 2.5, 6.0, 6.0], rng.uniform(2.5, 6.0, n - 4)])
    azi = rng.uniform(0.0, 2 * math.pi, n)
    out = np.stack([preetham.sky_sh(float(z), float(t), bands, sun_azimuth=float(a), n=2000)
                    for z, t, a in zip(zen, tur, azi)])
    if gibbs:
        zonal = [l * (l + 1) for l in range(bands)]
        out[:, zonal] *= np.sinc(np.arange(bands) / bands)[:, None]
    return out


# --------------------------------------------------------------------------- #
# Independent references
# --------------------------------------------------------------------------- #
def scipy_real_sh(dirs: np.ndarray, bands: int) -> np.ndarray:
    """Real orthonormal SH with the Condon-Shortley phase via scipy, (M, bands**2) for dirs (M, 3).

    scipy's complex Y_l^m already includes the (-1)^m phase, so Y(l, 0) = Re Y_l^0,
    Y(l, m > 0) = sqrt(2) Re Y_l^m, Y(l, -m) = sqrt(2) Im Y_l^m (docs/conventions.md's
    index l (l + 1) + m). The polar angle comes from atan2, accurate at the poles, unlike arccos(z).
    """
    theta = np.arctan2(np.hypot(dirs[:, 0], dirs[:, 1]), dirs[:, 2])
    phi = np.arctan2(dirs[:, 1], dirs[:, 0])
    out = np.empty((dirs.shape[0], bands * bands))
    for l in range(bands):
        for m in range(l + 1):
            y = sph_harm_y(l, m, theta, phi)
            if m == 0:
                out[:, l * l + l] = y.real
            else:
                out[:, l * l + l + m] = math.sqrt(2.0) * y.real
                out[:, l * l + l - m] = math.sqrt(2.0) * y.imag
    return out


def chebyshev_variables(ts: Any, t: Any) -> tuple[np.ndarray, np.ndarray]:
    """The sky table's fit variables, typed from the coefficient file's 'basis' text.

    x affine in the sun zenith (0 .. pi/4 .. pi/2 -> -1 .. 0 .. 1 is x = 4 ts / pi - 1), y affine in
    log(turbidity) onto [-1, 1] over the fitted turbidities [2.5, 6].
    """
    x = 4.0 * np.asarray(ts, dtype=float) / math.pi - 1.0
    y = (2.0 * np.log(t) - math.log(2.5) - math.log(6.0)) / (math.log(6.0) - math.log(2.5))
    return x, y


REF_THETA: dict[int, int] = {1: 8, 2: 8, 3: 16, 4: 16, 5: 20, 6: 24, 7: 28}
"""Gauss nodes in z of :func:`reference_min`'s grid per band count (about 4 nodes per lobe)."""

REF_STARTS: dict[int, int] = {1: 1, 2: 1, 3: 3, 4: 4, 5: 4, 6: 4, 7: 4}
"""Newton runs per function in :func:`reference_min` (a 3-band function has at most 2 local minima on
the sphere; a third start covers two grid minima in one basin)."""

_REF_GRIDS: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}


def tangents(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangents by a cross product with the least-aligned axis (not skysh's frame)."""
    helper = np.where(np.abs(p[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(p, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(p, e1)


def _ref_grid(bands: int, nt: int) -> tuple[np.ndarray, np.ndarray]:
    """Product-grid nodes (M, 3) and their basis (K, M), cached: ``sh.quadrature_rule(nt)``'s nodes, row by row
    (nt rows of constant z, from the south pole up), each row M / nt equal steps in azimuth."""
    if (bands, nt) not in _REF_GRIDS:
        dirs, _ = sh.quadrature_rule(nt)
        _REF_GRIDS[(bands, nt)] = (dirs, np.ascontiguousarray(sh.basis(dirs, bands).T))
    return _REF_GRIDS[(bands, nt)]


def _neighbour_min(vals: np.ndarray, nt: int) -> np.ndarray:
    """Least of the 8 grid neighbours of every node's value (F, M) on :func:`_ref_grid`'s (nt, M / nt) grid: rows
    clipped at the poles (a pole row is its own neighbour), columns wrapped in azimuth; by shifted views."""
    v = vals.reshape(len(vals), nt, vals.shape[1] // nt)
    padded = np.concatenate([v[:, :1], v, v[:, -1:]], axis=1)
    padded = np.concatenate([padded[:, :, -1:], padded, padded[:, :, :1]], axis=2)
    out = np.full_like(v, np.inf)
    for a in range(3):
        for b in range(3):
            if a != 1 or b != 1:
                np.minimum(out, padded[:, a : a + nt, b : b + v.shape[2]], out=out)
    return out.reshape(vals.shape)


def reference_min(f: np.ndarray, iters: int = 12, dense: int = 1) -> np.ndarray:
    """Minimum over the sphere of SH functions f (F, K), (F,).

    Grid, then a trust-region Newton method (finite differences, step 1e-3 shrinking to
    2e-6 rad) from the lowest discrete local minima. ``dense`` multiplies the grid's
    resolution and the starts (for functions with two nearly equal minima close together).
    A value of the function at a point: never below the true minimum beyond rounding.
    """
    f = np.asarray(f, dtype=np.float64)
    size = np.abs(f).max(axis=1, keepdims=True)
    size = np.where(size > 0.0, size, 1.0)
    f = f / size  # values of order one: no overflow in the differences at 1e300
    n_f, k_c = f.shape
    bands = math.isqrt(k_c)
    nt = REF_THETA[bands] * dense
    dirs, y = _ref_grid(bands, nt)
    vals = f @ y
    key = np.where(vals <= _neighbour_min(vals, nt), vals, np.inf)
    k = REF_STARTS[bands] * dense
    start = np.argpartition(key, k - 1, axis=1)[:, :k]
    start = np.where(np.isfinite(np.take_along_axis(key, start, 1)), start, np.argmin(vals, 1)[:, None])
    p, fr = dirs[start].reshape(-1, 3), np.repeat(f, k, 0)
    best = np.take_along_axis(vals, start, 1).reshape(-1)
    o = np.array([(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1)], dtype=np.float64)
    h, radius = 1e-3, np.full(len(p), 0.3)
    for _ in range(iters):
        e1, e2 = tangents(p)
        q = p[:, None] + h * (o[None, :, :1] * e1[:, None] + o[None, :, 1:] * e2[:, None])
        fq = np.einsum("pk,pjk->pj", fr, sh.basis(q / np.linalg.norm(q, axis=-1, keepdims=True), bands))
        gu, gv = (fq[:, 7] - fq[:, 1]) / (2 * h), (fq[:, 5] - fq[:, 3]) / (2 * h)
        huu, hvv = (fq[:, 7] - 2 * fq[:, 4] + fq[:, 1]) / h**2, (fq[:, 5] - 2 * fq[:, 4] + fq[:, 3]) / h**2
        huv = (fq[:, 8] - fq[:, 6] - fq[:, 2] + fq[:, 0]) / (4 * h * h)
        low = 0.5 * (huu + hvv) - np.sqrt(0.25 * (huu - hvv) ** 2 + huv**2)
        mu = np.maximum(0.0, 1e-6 * (np.abs(huu) + np.abs(hvv) + np.abs(huv) + 1e-300) - low)
        a11, a22 = huu + mu, hvv + mu
        det = a11 * a22 - huv * huv
        det = np.where(det > 0.0, det, np.inf)
        du, dv = -(a22 * gu - huv * gv) / det, -(a11 * gv - huv * gu) / det
        cap = np.minimum(1.0, radius / np.maximum(np.hypot(du, dv), 1e-300))
        cand = p + (cap * du)[:, None] * e1 + (cap * dv)[:, None] * e2
        cand /= np.linalg.norm(cand, axis=-1, keepdims=True)
        cv = np.einsum("pk,pk->p", fr, sh.basis(cand, bands))
        better = cv < best
        p, best = np.where(better[:, None], cand, p), np.where(better, cv, best)
        radius = np.where(better, np.minimum(2.0 * radius, 0.3), 0.25 * radius)  # a trust region
        h = max(h / 4.0, 2e-6)
    return np.minimum(best.reshape(n_f, k).min(1), vals.min(1)) * size[:, 0]


def channel_min(c: np.ndarray, dense: int = 1) -> np.ndarray:
    """:func:`reference_min` of SH (..., K, C) per channel, (..., C)."""
    flat = np.moveaxis(c, -1, -2).reshape(-1, c.shape[-2])
    return reference_min(flat, dense=dense).reshape(c.shape[:-2] + c.shape[-1:])


# --------------------------------------------------------------------------- #
# Measures and options
# --------------------------------------------------------------------------- #
def dc_relative_error(got: np.ndarray, ref: np.ndarray) -> float:
    """Worst channel of max_i |got_i - ref_i| / |ref_DC| for SH arrays (..., K, C): the error
    relative to the DC term, the scale of every coefficient of a non-negative function."""
    return float((np.abs(got - ref).max(axis=-2) / np.abs(ref[..., 0, :])).max())


PLAIN_DIP: float = -1e-3
"""Negative control of the exports' non-negativity checks (tests/test_export*.py): the un-deringed old pipeline's
irradiance, minimum over the sphere divided by its mean (test_export, test_export_js) or by its DC coefficient
(test_export_lights: 2 sqrt(pi) times the mean, so a deeper dip), must fall below this for the check to be able
to fail. Its size is the irradiance table's own margin (1e-3 of the mean) with the sign flipped: a dip that deep
is a real ring, not rounding (each use states the dip it measured)."""


def old_pipeline(sky: SkySH) -> dict[str, bool]:
    """Options giving the runtime's filtered and deringed sky (which the exports carry):
    ``irradiance_table=False`` where the runtime has the certified irradiance table's option
    (its default for 3-band irradiance is the table), nothing where it does not."""
    return {"irradiance_table": False} if "irradiance_table" in inspect.signature(sky.coefficients).parameters else {}


PADDED_IDENTITY_ATOL: float = 1e-14
"""An engine map that passes skysh's numbers on as they are (zero-padded) reproduces a standard-normal
probe exactly (one-entry sums); any real change of convention moves it by O(1), so 1e-14 separates them."""


def engine_cases() -> list[tuple[str, int]]:
    """(engine, bands) for every band count each engine of skysh.engines.presets takes (engine_map accepts it);
    none while skysh.engines.presets does not exist."""
    try:
        from skysh.engines import presets as engines
    except ModuleNotFoundError:
        return []
    cases = []
    for name in engines.ENGINES:
        for n in range(1, engines.ENGINE_MAX_BANDS[name] + 1):
            try:
                engines.engine_map(name, n)
            except ValueError:
                continue
            cases.append((name, n))
    return cases


def is_padded_identity(name: str, bands: int) -> bool:
    """True when the engine's map is skysh's numbers as they are (zero-padded): no negative control can fail."""
    from skysh.engines import presets as engines

    emap = engines.engine_map(name, bands)
    matrix = np.asarray(emap.matrix)
    probe = np.random.default_rng(1).standard_normal(matrix.shape[1])
    padded = np.zeros(matrix.shape[0])
    padded[: min(probe.size, padded.size)] = probe[: padded.size]
    return bool(np.allclose(matrix @ probe + np.asarray(emap.offset), padded, rtol=0.0, atol=PADDED_IDENTITY_ATOL))


def canonical_json(value: Any) -> bytes:
    """Canonical JSON as skysh.table.coefficient_file's docstring defines it, typed here (sorted keys, no
    spaces, ASCII, no NaN)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode("ascii")


# --------------------------------------------------------------------------- #
# Running code
# --------------------------------------------------------------------------- #
def load_script(path: Path, name: str) -> types.ModuleType:
    """The Python file ``path`` imported as a module called ``name`` (tools and scripts are not packages)."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None, path
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def tools_on_path() -> None:
    """Put :data:`TOOLS` first on ``sys.path`` (once), so ``import studies`` finds ``tools/studies``."""
    if str(TOOLS) not in sys.path:
        sys.path.insert(0, str(TOOLS))


def python_without_matplotlib(code: str, *python_args: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter (flags ``python_args``, e.g. ``"-W", "default"``) in which
    ``import matplotlib`` fails; output captured as text, run from :data:`ROOT`."""
    return pythons_without_matplotlib({"code": code}, *python_args)["code"]


def pythons_without_matplotlib(codes: dict[str, str], *python_args: str) -> dict[str, subprocess.CompletedProcess]:
    """:func:`python_without_matplotlib` of every value of ``codes``, all at once (:func:`run_concurrently`),
    by the same keys."""
    return run_concurrently({key: [sys.executable, *python_args, "-c", NO_MATPLOTLIB + code]
                             for key, code in codes.items()}, cwd=ROOT)


def script_without_cvxpy(script: Path, *argv: str) -> list[str]:
    """The command running the Python file ``script`` with ``argv`` as ``python script ...`` does, in an interpreter
    without the solver's packages (:data:`NO_CVXPY`)."""
    code = (f"import runpy; sys.argv = {[str(script), *argv]!r}; sys.path[0] = {str(script.parent)!r}; "
            "runpy.run_path(sys.argv[0], run_name='__main__')")
    return [sys.executable, "-c", NO_CVXPY + code]


def run_concurrently(commands: dict[str, list[str]], **popen: Any) -> dict[str, subprocess.CompletedProcess]:
    """Run every command of ``commands`` at the same time (output captured as text; ``popen``: more
    ``subprocess.Popen`` arguments such as ``cwd`` and ``env``); their results by the same keys.

    For fresh interpreters that mostly import (skysh, colour-science): one after another they leave the
    other cores idle while the test process waits.
    """
    started = {key: subprocess.Popen(argv, text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **popen)
               for key, argv in commands.items()}
    done = {}
    for key, process in started.items():
        out, err = process.communicate()
        done[key] = subprocess.CompletedProcess(process.args, process.returncode, out, err)
    return done


# --------------------------------------------------------------------------- #
# Hooks: order, xdist
# --------------------------------------------------------------------------- #
def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "late: runs after the other tests of its module (it waits for work started in the background "
        "when the module began, which the module's other tests overlap)",
    )


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Within each module, the tests marked ``late`` after the others; every other order is kept."""
    modules: dict[Any, int] = {}
    for item in items:
        modules.setdefault(item.module, len(modules))
    items.sort(key=lambda item: (modules[item.module], item.get_closest_marker("late") is not None))


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node: Any) -> None:
    """pytest-xdist (controller side): pass the distribution mode on to each worker, whose own options say "no"."""
    node.workerinput["skysh_dist"] = node.config.getoption("dist", "no")


# --------------------------------------------------------------------------- #
# Fixtures
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="session")
def sky() -> SkySH:
    """The shipped coefficient file's runtime, loaded once per session.

    Shared by every test that asks for ``sky``: a test that changes it must do so through
    ``monkeypatch`` (undone after the test). A module's own ``sky`` fixture takes precedence.
    """
    from skysh.runtime import SkySH

    return SkySH.load()


Exported = Callable[..., str]
"""The type of the :func:`exported` fixture: ``exported(language, **options)`` -> the export's text."""


@pytest.fixture(scope="session")
def exported(sky: SkySH) -> Exported:
    """``export_source(sky, language, **options)`` of the session's :func:`sky`, each distinct call made once (the
    texts are immutable; a test of ``export_source`` itself calls it directly)."""
    from skysh.export.c_like import export_source

    return functools.lru_cache(maxsize=None)(functools.partial(export_source, sky))


@pytest.fixture(scope="session")
def tool_runs(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[ToolRuns]:
    """The session's ``background.ToolRuns``, in its own temporary folder; eager when modules stay whole
    (``background.modules_stay_whole``)."""
    runs = ToolRuns(tmp_path_factory.mktemp("tool_runs"), eager=modules_stay_whole(request.config))
    yield runs
    runs.close()


def environment_without_pythonpath() -> dict[str, str]:
    """``os.environ`` without ``PYTHONPATH``: a subprocess then imports skysh only from where it is installed."""
    return {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}


@pytest.fixture(scope="session")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The skysh wheel, built once per session (``pip wheel --no-deps --no-build-isolation --no-index``: no
    network) from a copy of the source tree without :data:`WHEEL_SOURCE_IGNORED`, so that nothing is
    written into the repository and no stale build product can leak in."""
    base = tmp_path_factory.mktemp("wheel")
    source = base / "src"
    shutil.copytree(ROOT, source, ignore=WHEEL_SOURCE_IGNORED)
    out = base / "dist"
    result = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "--no-build-isolation", "--no-index",
         "-q", "-w", str(out)],
        capture_output=True, text=True, timeout=WHEEL_BUILD_TIMEOUT_S, env=environment_without_pythonpath(),
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    wheels = sorted(out.glob("skysh-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]
