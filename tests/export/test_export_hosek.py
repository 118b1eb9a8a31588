"""
Tests of skysh.export.hosek: the Hosek-Wilkie per-frame runtime in C (gcc) and in JavaScript (node)
against the Python pipeline.

The Python pipeline is composed here from public functions: :func:`skysh.model.hosek_frame.coefficients`
(grey albedo; an RGB albedo by one grey call per channel, each channel's parameters depending on its own
albedo only), then the runtime's post steps in its order: the zonal Gibbs filter
(:func:`skysh.runtime.gibbs_factors`), :func:`skysh.post.dering.dering` (target irradiance), the lobe
:func:`skysh.sh.basis.cosine_lobe`. Suns: random, on and 1e-7 rad either side of every panel edge and of
the low-sun switch, the domain's corners, the sun on the horizon; bands 1..7; azimuths up to 1e12.

Run as a script, it prints the largest differences (fractions of the call's largest |DC|) per language and
band count: ``python tests/export/test_export_hosek.py``. Skipped without gcc (the C tests) or node (the JS
tests), saying why.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from skysh import runtime
from skysh.export import hosek as export_hosek
from skysh.model import hosek, hosek_frame
from skysh.post import dering
from skysh.sh import basis as sh

TOLERANCE: float = 1e-12
"""Largest |difference| allowed, as a fraction of the call's largest |DC| over the channels: the exports sum the
~900 rule terms (34 rings x 24 or 28 azimuth nodes) in another order than numpy's matmul and einsum, and their
exp, pow, cbrt, asin and Gauss nodes differ from numpy's by an ulp or so; in double that leaves ~1e-14 of the DC
(measured: the module's ``__main__``), 1e-12 keeps a 10x-100x margin while a perturbed table entry or a wrong
node count misses it by 1e4 or more."""

PARAMETER_TOLERANCE: float = 1e-13
"""The model's parameters (:func:`skysh.model.hosek.configuration`), as a fraction of max(1, |value|): a sum of six
Bezier terms of dataset values up to ~20 in magnitude, which cancel for the smallest parameters (measured 1.1e-14)."""

GCC: str | None = shutil.which("gcc")
NODE: str | None = shutil.which("node")
TSC: Path = Path(__file__).parents[1] / "js" / "node_modules" / ".bin" / "tsc"
CFLAGS: tuple[str, ...] = ("-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2")
BANDS: tuple[int, ...] = tuple(range(1, 8))
GIBBS, DERING, IRRADIANCE = 1, 2, 4
"""The C flags (SKYSH_HW_GIBBS, SKYSH_HW_DERING, SKYSH_HW_IRRADIANCE)."""
SETTINGS: tuple[tuple[int, bool], ...] = ((0, False), (GIBBS, False), (IRRADIANCE | DERING, False), (DERING, False),
                                          (GIBBS, True), (IRRADIANCE | DERING, True))
"""(flags, RGB albedo) of every sun: the bare projection, the runtime's radiance and irradiance defaults (grey and
RGB albedo) and a deringed radiance."""

DRIVER = r"""
#include <stdio.h>
#include "hosek_wilkie.h"
static skysh_hw_state states[SKYSH_HW_BANDS + 1]; /* states[0] is never initialised */
int main(void)
{
    for (int b = 1; b <= SKYSH_HW_BANDS; b++) { if (skysh_hw_init(&states[b], b) != 0) { return 2; } }
    char kind[4];
    while (scanf("%3s", kind) == 1) {
        double v[8], out[3 * SKYSH_HW_COUNT > 30 ? 3 * SKYSH_HW_COUNT : 30];
        int b = 0, flags = 0, rc = 0, size = 0;
        if (kind[0] == 'c') { /* bands ts t phi a0 a1 a2 flags */
            if (scanf("%d %lf %lf %lf %lf %lf %lf %d", &b, v, v + 1, v + 2, v + 3, v + 4, v + 5, &flags) != 8) { return 3; }
            for (int k = 0; k < 3 * SKYSH_HW_COUNT; k++) { out[k] = 99.0; }
            rc = skysh_hw_coefficients(&states[b], v[0], v[1], v[2], v + 3, flags, out);
            size = 3 * (b ? b * b : 1);
        } else if (kind[0] == 'r') { /* x y z ts t phi a0 a1 a2: radiance */
            for (int k = 0; k < 9; k++) { if (scanf("%lf", k < 8 ? v + k : out + 29) != 1) { return 3; } }
            double a[3] = {v[6], v[7], out[29]};
            rc = skysh_hw_radiance(v, v[3], v[4], v[5], a, out);
            size = 3;
        } else { /* ts t a0 a1 a2: configuration */
            if (scanf("%lf %lf %lf %lf %lf", v, v + 1, v + 2, v + 3, v + 4) != 5) { return 3; }
            rc = skysh_hw_configuration(v[0], v[1], v + 2, out);
            size = 30;
        }
        printf("%d", rc);
        for (int k = 0; k < size; k++) { printf(" %.17g", out[k]); }
        printf("\n");
    }
    return 0;
}
"""
"""Reads one call a line (c: coefficients, r: radiance, p: configuration), writes the code and the numbers (%.17g:
every double exactly)."""

RUNNER = r"""
import { readFileSync } from "node:fs";
import { pathToFileURL } from "node:url";
const request = JSON.parse(readFileSync(0, "utf8"));
const mod = await import(pathToFileURL(request.module).href);
const skies = new Map();
const num = (v) => (v === "NaN" ? NaN : v === "Infinity" ? Infinity : v === "-Infinity" ? -Infinity : v);
const results = request.calls.map(([kind, ...args]) => {
  try {
    args = args.map(num);
    if (kind === "c") {
      const [bands, ts, t, phi, options] = args;
      if (!skies.has(bands)) skies.set(bands, mod.createSky(bands));
      const sky = skies.get(bands);
      return { values: sky.coefficients(ts, t, phi, options), failed: sky.deringFailed };
    }
    if (kind === "r") return { values: mod.radiance(...args) };
    if (kind === "p") return { values: mod.configuration(...args) };
    if (kind === "new") return { values: mod.createSky(...args).bands };
    throw new Error(`unknown call ${kind}`);
  } catch (error) {
    return { error: error.constructor.name, message: error.message };
  }
});
process.stdout.write(JSON.stringify(results));
"""
"""Runs a batch of calls of one module: stdin {"module": path, "calls": [[kind, ...args]]}, stdout the results."""

needs_gcc = pytest.mark.skipif(GCC is None, reason="gcc is not on PATH: the C header cannot be compiled")
needs_node = pytest.mark.skipif(NODE is None, reason="node is not on PATH: the ES module cannot be run")


# ---------------------------------------------------------------------------------------------------------------
# The suns and the Python pipeline
# ---------------------------------------------------------------------------------------------------------------
def suns() -> list[tuple[float, float, float, float, tuple[float, float, float]]]:
    """(sun zenith, turbidity, azimuth, grey albedo, RGB albedo) of every test sky."""
    rng = np.random.default_rng(27)
    out = []
    azimuths = [1e3, -1e5, 1e8, 1e12, -7.5, 2.0 * math.pi, -math.pi]

    def rgb() -> tuple[float, float, float]:
        r, g, b = (float(v) for v in rng.choice([0.0, 1.0, rng.uniform(), rng.uniform()], 3))
        return r, g, b

    for _ in range(36):
        out.append((float(rng.uniform(0.0, 0.5 * math.pi)), float(rng.uniform(1.0, 10.0)),
                    float(rng.uniform(-4.0 * math.pi, 4.0 * math.pi)), float(rng.uniform()), rgb()))
    edges = [*hosek_frame.ZENITH_EDGES, hosek_frame.LOW_SUN]
    for k, edge in enumerate(edges):
        for step in (-1e-7, 0.0, 1e-7):
            ts = min(max(edge + step, 0.0), 0.5 * math.pi)
            out.append((ts, float(rng.uniform(1.0, 10.0)), azimuths[(3 * k + int(step * 1e7)) % len(azimuths)],
                        float(rng.uniform()), rgb()))
    for ts in (0.0, 0.5 * math.pi):
        for t in (1.0, 10.0):
            for a in (0.0, 1.0):
                out.append((ts, t, float(rng.uniform(-10.0, 10.0)), a, (a, 1.0 - a, a)))
    for t in (2.0, 4.5, 9.0):  # the sun on the horizon, integer and other turbidities
        out.append((0.5 * math.pi, t, float(rng.uniform(-10.0, 10.0)), float(rng.uniform()), rgb()))
    return sorted(set(out))


def post(radiance: np.ndarray, bands: int, flags: int) -> np.ndarray:
    """The runtime's steps after hosek_frame: Gibbs (zonal), deringing (irradiance target), lobe; (S, N^2, 3)."""
    c = np.array(radiance, dtype=np.float64)
    if flags & GIBBS:
        for l, g in enumerate(runtime.gibbs_factors(bands)):
            c[:, l * (l + 1)] *= g
    if flags & DERING:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            c = dering.dering(c, "irradiance")[0]
    if flags & IRRADIANCE:
        c = c * sh.cosine_lobe(bands)[sh.band_of_index(bands)][None, :, None]
    return c


def radiance_sh(skies: list, bands: int, rgb: bool) -> np.ndarray:
    """hosek_frame's radiance SH (S, N^2, 3) of the skies: grey albedo, or each channel from a grey call at its albedo."""
    ts, t, phi = (np.array([s[k] for s in skies]) for k in range(3))
    if not rgb:
        return hosek_frame.coefficients(ts, t, np.array([s[3] for s in skies]), phi, bands)
    out = np.empty((len(skies), bands * bands, 3))
    for c in range(3):
        out[..., c] = hosek_frame.coefficients(ts, t, np.array([s[4][c] for s in skies]), phi, bands)[..., c]
    return out


_REFERENCE: dict[int, dict[tuple[int, bool], np.ndarray]] = {}


def reference(bands: int) -> dict[tuple[int, bool], np.ndarray]:
    """The Python pipeline of every setting at ``bands`` bands (computed once)."""
    if bands not in _REFERENCE:
        skies = suns()
        raw = {rgb: radiance_sh(skies, bands, rgb) for rgb in (False, True)}
        _REFERENCE[bands] = {(flags, rgb): post(raw[rgb], bands, flags) for flags, rgb in SETTINGS}
    return _REFERENCE[bands]


def worst(got: np.ndarray, want: np.ndarray) -> float:
    """Largest |got - want| of each call over its largest |DC|, the worst call: (S, N^2, 3) each."""
    scale = np.max(np.abs(want[:, 0, :]), axis=-1)
    return float(np.max(np.max(np.abs(got - want), axis=(1, 2)) / scale))


# ---------------------------------------------------------------------------------------------------------------
# C
# ---------------------------------------------------------------------------------------------------------------
def build_c(directory: Path, source: str) -> Path:
    """The driver compiled against ``source`` (the header) in ``directory``; gcc's messages on failure."""
    assert GCC is not None
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "hosek_wilkie.h").write_text(source, encoding="utf-8")
    (directory / "driver.c").write_text(DRIVER, encoding="utf-8")
    done = subprocess.run([GCC, *CFLAGS, "driver.c", "-o", "driver", "-lm"], cwd=directory, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    return directory / "driver"


def run_c(driver: Path, lines: list[str]) -> list[tuple[int, np.ndarray]]:
    """Each line's (return code, numbers)."""
    done = subprocess.run([str(driver)], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True)
    rows = [line.split() for line in done.stdout.splitlines()]
    assert len(rows) == len(lines)
    return [(int(row[0]), np.array([float(v) for v in row[1:]])) for row in rows]


def c_calls(bands: int, skies: list) -> list[str]:
    """The driver's lines of every sky and setting, setting-major (the order of :data:`SETTINGS`)."""
    return [f"c {bands} {ts!r} {t!r} {phi!r} " + " ".join(repr(v) for v in (rgb_a if rgb else (a, a, a))) + f" {flags}"
            for flags, rgb in SETTINGS for ts, t, phi, a, rgb_a in skies]


def c_results(driver: Path, bands: int) -> dict[tuple[int, bool], np.ndarray]:
    skies = suns()
    results = run_c(driver, c_calls(bands, skies))
    assert {rc for rc, _ in results} <= {0, 1}
    values = np.array([v for _, v in results]).reshape(len(SETTINGS), len(skies), bands * bands, 3)
    return {setting: values[k] for k, setting in enumerate(SETTINGS)}


@pytest.fixture(scope="module")
def c_drivers(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The driver of every band count (two compilers at a time)."""
    if GCC is None:
        pytest.skip("gcc is not on PATH: the C header cannot be compiled")
    root = tmp_path_factory.mktemp("hosek_c")
    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = {n: pool.submit(build_c, root / f"b{n}", export_hosek.export_source("c", n)) for n in BANDS}
        return {n: f.result() for n, f in futures.items()}


@needs_gcc
class TestC:
    @pytest.mark.parametrize("bands", BANDS)
    def test_matches_the_python_pipeline(self, c_drivers: dict[int, Path], bands: int) -> None:
        got, want = c_results(c_drivers[bands], bands), reference(bands)
        for setting in SETTINGS:
            assert worst(got[setting], want[setting]) <= TOLERANCE, setting

    @pytest.mark.parametrize("bands", [1, 3, 6])
    def test_a_state_of_fewer_bands_matches(self, c_drivers: dict[int, Path], bands: int) -> None:
        """A 7-band header's state initialised for fewer bands (no deringing there: its tables are per band count)."""
        skies, settings = suns(), [s for s in SETTINGS if not s[0] & DERING]
        lines = [line for line in c_calls(bands, skies) if not int(line.split()[-1]) & DERING]
        values = np.array([v for _, v in run_c(c_drivers[7], lines)]).reshape(len(settings), len(skies), bands * bands, 3)
        for k, setting in enumerate(settings):
            assert worst(values[k], reference(bands)[setting]) <= TOLERANCE, setting

    @pytest.mark.skipif(shutil.which("g++") is None, reason="g++ is not on PATH")
    def test_header_compiles_as_cpp_in_two_units(self, tmp_path: Path) -> None:
        (tmp_path / "hosek_wilkie.h").write_text(export_hosek.export_source("c", 5), encoding="utf-8")
        (tmp_path / "main.cpp").write_text(DRIVER, encoding="utf-8")
        (tmp_path / "other.cpp").write_text('#include "hosek_wilkie.h"\nint other() { return SKYSH_HW_BANDS; }\n',
                                            encoding="utf-8")
        done = subprocess.run(["g++", "-std=c++11", "-Wall", "-Wextra", "-pedantic", "-Werror", "main.cpp", "other.cpp",
                               "-o", "driver", "-lm"], cwd=tmp_path, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr

    def test_domain_is_refused_with_zeroed_output(self, c_drivers: dict[int, Path]) -> None:
        edge = "0.5 3.0 0.0"
        lines = ["c 3 -1e-300 3.0 0.0 0.2 0.2 0.2 1", "c 3 1.5707963267948968 3.0 0.0 0.2 0.2 0.2 1",
                 "c 3 nan 3.0 0.0 0.2 0.2 0.2 1", "c 3 0.5 0.999 0.0 0.2 0.2 0.2 1", "c 3 0.5 10.001 0.0 0.2 0.2 0.2 1",
                 f"c 3 {edge} 0.2 -0.001 0.2 1", f"c 3 {edge} 0.2 0.2 1.001 1", f"c 3 {edge} 0.2 nan 0.2 1",
                 "c 3 0.5 3.0 inf 0.2 0.2 0.2 1", "c 3 0.5 3.0 nan 0.2 0.2 0.2 1", f"c 2 {edge} 0.2 0.2 0.2 2",
                 f"c 3 {edge} 0.2 0.2 0.2 8"]
        codes = [-1, -1, -1, -2, -2, -3, -3, -3, -4, -4, -5, -6]
        for (rc, values), code in zip(run_c(c_drivers[3], lines), codes):
            assert rc == code and not np.any(values)
        rc, values = run_c(c_drivers[3], [f"c 0 {edge} 0.2 0.2 0.2 1"])[0]  # a state never initialised
        assert rc == -7 and np.all(values == 99.0)  # untouched

    def test_configuration_and_radiance(self, c_drivers: dict[int, Path]) -> None:
        ts, t, a, phi = 1.2, 4.5, 0.35, -2.0
        (rc, p), = run_c(c_drivers[1], [f"p {ts} {t} {a} {a} {a}"])
        params, mean = hosek.configuration(ts, t, a)
        want = np.concatenate([params, mean[:, None]], axis=1).ravel()
        assert rc == 0 and np.all(np.abs(p - want) <= PARAMETER_TOLERANCE * np.maximum(1.0, np.abs(want)))
        dirs = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0], [0.3, 0.4, -math.sqrt(0.75)],
                         [math.sin(ts) * math.cos(phi), math.sin(ts) * math.sin(phi), math.cos(ts)]])
        got = np.array([v for _, v in run_c(c_drivers[1], [
            "r " + " ".join(repr(float(x)) for x in (*d, ts, t, phi, a, a, a)) for d in dirs])])
        want = hosek.radiance(dirs, ts, phi, t, a)
        assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))

    @pytest.mark.parametrize("change", ["table entry", "azimuth nodes", "sun nodes"])
    def test_negative_controls_fail(self, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, change: str) -> None:
        params, radiances = export_hosek._dataset()
        if change == "table entry":  # parameter D of green at turbidity 1, albedo 0, control point 0: relatively 1e-6
            perturbed = params.copy()
            perturbed[0, 0, 0, 1, 3] *= 1.0 + 1e-6
            monkeypatch.setattr(export_hosek, "_dataset", lambda: (perturbed, radiances))
        else:
            numbers = export_hosek._accuracy_numbers

            def wrong(accuracy: str) -> dict[str, int]:
                out = dict(numbers(accuracy))
                out["AZIMUTH" if change == "azimuth nodes" else "SUN"] += 1
                out["RINGS"] += change == "sun nodes"
                out["MAX_NODES"] += 1
                return out
            monkeypatch.setattr(export_hosek, "_accuracy_numbers", wrong)
        driver = build_c(tmp_path, export_hosek.export_source("c", 3))
        got = c_results(driver, 3)[(GIBBS, False)]
        skies = suns()
        keep = [k for k, s in enumerate(skies) if s[1] < 2.0] if change == "table entry" else slice(None)
        assert worst(got[keep], reference(3)[(GIBBS, False)][keep]) > 1e4 * TOLERANCE


# ---------------------------------------------------------------------------------------------------------------
# JavaScript
# ---------------------------------------------------------------------------------------------------------------
def run_js(module: Path, calls: list[list]) -> list[dict]:
    assert NODE is not None
    done = subprocess.run([NODE, "--input-type=module", "-e", RUNNER], input=json.dumps({"module": str(module), "calls": calls}),
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def js_calls(bands: int, skies: list) -> list[list]:
    calls = []
    for flags, rgb in SETTINGS:
        for ts, t, phi, a, rgb_a in skies:
            options = {"gibbs": bool(flags & GIBBS), "dering": bool(flags & DERING),
                       "irradiance": bool(flags & IRRADIANCE), "albedo": list(rgb_a) if rgb else a}
            calls.append(["c", bands, ts, t, phi, options])
    return calls


def js_results(module: Path, bands_list: tuple[int, ...]) -> dict[int, dict[tuple[int, bool], np.ndarray]]:
    skies = suns()
    calls = [call for n in bands_list for call in js_calls(n, skies)]
    replies = run_js(module, calls)
    out, k = {}, 0
    for n in bands_list:
        size = len(SETTINGS) * len(skies)
        chunk = replies[k : k + size]
        k += size
        assert all("values" in r for r in chunk), chunk[0]
        values = np.array([r["values"] for r in chunk]).reshape(len(SETTINGS), len(skies), n * n, 3)
        out[n] = {setting: values[j] for j, setting in enumerate(SETTINGS)}
    return out


@pytest.fixture(scope="module")
def js_module(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if NODE is None:
        pytest.skip("node is not on PATH: the ES module cannot be run")
    directory = tmp_path_factory.mktemp("hosek_js")
    (directory / "hosek_wilkie.mjs").write_text(export_hosek.export_source("js"), encoding="utf-8")
    (directory / "hosek_wilkie.d.mts").write_text(export_hosek.declarations(), encoding="utf-8")
    return directory / "hosek_wilkie.mjs"


@pytest.fixture(scope="module")
def js_all(js_module: Path) -> dict[int, dict[tuple[int, bool], np.ndarray]]:
    return js_results(js_module, BANDS)


@needs_node
class TestJavaScript:
    @pytest.mark.parametrize("bands", BANDS)
    def test_matches_the_python_pipeline(self, js_all: dict, bands: int) -> None:
        want = reference(bands)
        for setting in SETTINGS:
            assert worst(js_all[bands][setting], want[setting]) <= TOLERANCE, setting

    def test_defaults_are_the_runtime_intent(self, js_module: Path) -> None:
        ts, t, phi, a = 1.3, 2.5, 0.7, 0.25
        replies = run_js(js_module, [["c", 3, ts, t, phi, {"albedo": a}], ["c", 3, ts, t, phi, {"albedo": a, "irradiance": True}],
                                     ["c", 3, ts, t, phi, {}]])
        raw = hosek_frame.coefficients(ts, t, a, phi, 3)[None]
        for reply, flags in zip(replies[:2], (GIBBS, IRRADIANCE | DERING)):
            assert worst(np.array(reply["values"]).reshape(1, 9, 3), post(raw, 3, flags)) <= TOLERANCE
        zero = post(hosek_frame.coefficients(ts, t, 0.0, phi, 3)[None], 3, GIBBS)
        assert worst(np.array(replies[2]["values"]).reshape(1, 9, 3), zero) <= TOLERANCE

    def test_configuration_and_radiance(self, js_module: Path) -> None:
        ts, t, a, phi = 0.3, 7.25, 0.6, 1e4
        dirs = [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0], [0.3, 0.4, -math.sqrt(0.75)],
                [math.sin(ts) * math.cos(phi), math.sin(ts) * math.sin(phi), math.cos(ts)]]
        replies = run_js(js_module, [["p", ts, t, a], *[["r", d, ts, t, phi, a] for d in dirs]])
        params, mean = hosek.configuration(ts, t, a)
        got = replies[0]["values"]
        for name, want in [*zip(hosek.PARAMETER_NAMES, params.T), ("LM", mean)]:
            assert np.all(np.abs(np.array(got[name]) - want) <= PARAMETER_TOLERANCE * np.maximum(1.0, np.abs(want))), name
        assert got["efficacy"] == hosek.LUMINOUS_EFFICACY
        rgb = np.array([r["values"] for r in replies[1:]])
        want = hosek.radiance(np.array(dirs), ts, phi, t, a)
        assert np.max(np.abs(rgb - want)) <= 1e-12 * np.max(np.abs(want))

    def test_refusals_name_the_parameter(self, js_module: Path) -> None:
        calls = [["c", 3, -1e-9, 3.0, 0.0, {}], ["c", 3, "NaN", 3.0, 0.0, {}], ["c", 3, 0.5, 10.5, 0.0, {}],
                 ["c", 3, 0.5, 3.0, "Infinity", {}], ["c", 3, 0.5, 3.0, 0.0, {"albedo": [0.1, 1.5, 0.2]}],
                 ["c", 3, 0.5, 3.0, 0.0, {"albedo": [0.1, 0.2]}], ["c", 3, 0.5, 3.0, 0.0, {"engine": "three"}],
                 ["c", 3, 0.5, 3.0, 0.0, {"gibbs": 1}], ["new", 8], ["new", 0], ["p", 0.5, 0.5, 0.0],
                 ["r", [0, 0, 1], 0.5, 3.0, 0.0, -0.5]]
        expected = [("RangeError", "sunZenith"), ("RangeError", "sunZenith"), ("RangeError", "turbidity"),
                    ("RangeError", "sunAzimuth"), ("RangeError", "albedo"), ("TypeError", "albedo"),
                    ("TypeError", "engine"), ("TypeError", "gibbs"), ("RangeError", "bands"), ("RangeError", "bands"),
                    ("RangeError", "turbidity"), ("RangeError", "albedo")]
        for reply, (error, name) in zip(run_js(js_module, calls), expected):
            assert reply.get("error") == error and name in reply["message"], reply

    def test_negative_control_fails(self, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
        params, radiances = export_hosek._dataset()
        perturbed = params.copy()
        perturbed[0, 0, 0, 1, 3] *= 1.0 + 1e-6
        monkeypatch.setattr(export_hosek, "_dataset", lambda: (perturbed, radiances))
        module = tmp_path / "hosek_wilkie.mjs"
        module.write_text(export_hosek.export_source("js", 3), encoding="utf-8")
        got = js_results(module, (3,))[3][(GIBBS, False)]
        keep = [k for k, s in enumerate(suns()) if s[1] < 2.0]
        assert worst(got[keep], reference(3)[(GIBBS, False)][keep]) > 1e4 * TOLERANCE

    @pytest.mark.skipif(not TSC.is_file(), reason="TypeScript is not installed in tests/js (npm ci there)")
    def test_declarations_type_check(self, js_module: Path) -> None:
        usage = js_module.with_name("usage.ts")
        usage.write_text(
            'import { createSky, configuration, radiance, MAX_BANDS } from "./hosek_wilkie.mjs";\n'
            "const sky = createSky(3);\n"
            "const out: Float64Array = sky.coefficients(0.5, 3, 0, { irradiance: true, albedo: [0.1, 0.2, 0.3], "
            "out: new Float64Array(27) });\n"
            "const c: number[] = sky.coefficients(0.5, 3);\n"
            "const p: number = configuration(0.5, 3, 0.2).H[0] + radiance([0, 0, 1], 0.5, 3)[1] + MAX_BANDS;\n"
            "const f: boolean = sky.deringFailed;\n"
            "export { out, c, p, f };\n", encoding="utf-8")
        done = subprocess.run([str(TSC), "--noEmit", "--strict", "--module", "nodenext", "--moduleResolution", "nodenext",
                               "--target", "es2022", "--skipDefaultLibCheck", "usage.ts"], cwd=js_module.parent,
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stdout + done.stderr


# ---------------------------------------------------------------------------------------------------------------
# The runtime object (skysh.SkySH.load(model="hosek-wilkie")), where it exists
# ---------------------------------------------------------------------------------------------------------------
RUNTIME_SETTINGS: tuple[tuple[int, bool], ...] = ((GIBBS, False), (IRRADIANCE | DERING, False), (GIBBS, True),
                                                  (IRRADIANCE | DERING, True))
"""The runtime's defaults (radiance, irradiance) with grey and RGB albedo."""


_RUNTIME: dict[int, dict[tuple[int, bool], np.ndarray]] = {}


def runtime_results(bands: int) -> dict[tuple[int, bool], np.ndarray]:
    """``SkySH.load(model="hosek-wilkie").coefficients`` of every sky with its defaults (computed once); skipped where
    the runtime object is missing."""
    if bands in _RUNTIME:
        return _RUNTIME[bands]
    try:
        from skysh import SkySH

        sky = SkySH.load(model="hosek-wilkie")
    except (ImportError, TypeError, ValueError) as error:  # pragma: no cover - before the runtime object lands
        pytest.skip(f"the Hosek-Wilkie runtime object is not available: {error}")
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dering.DeringWarning)
        for flags, rgb in RUNTIME_SETTINGS:
            out[(flags, rgb)] = np.array([
                sky.coefficients(ts, t, phi, bands, irradiance=bool(flags & IRRADIANCE), albedo=list(rgb_a) if rgb else a)
                for ts, t, phi, a, rgb_a in suns()])
    _RUNTIME[bands] = out
    return out


class TestRuntime:
    @pytest.mark.parametrize("bands", [1, 3, 7])
    def test_the_pipeline_composed_here_is_the_runtime(self, bands: int) -> None:
        got = runtime_results(bands)
        for setting in RUNTIME_SETTINGS:
            assert worst(got[setting], reference(bands)[setting]) <= TOLERANCE, setting

    @needs_gcc
    @pytest.mark.parametrize("bands", [3, 7])
    def test_c_matches_the_runtime(self, c_drivers: dict[int, Path], bands: int) -> None:
        got, want = c_results(c_drivers[bands], bands), runtime_results(bands)
        for setting in RUNTIME_SETTINGS:
            assert worst(got[setting], want[setting]) <= TOLERANCE, setting

    @needs_node
    def test_js_matches_the_runtime(self, js_all: dict) -> None:
        for bands in (3, 7):
            want = runtime_results(bands)
            for setting in RUNTIME_SETTINGS:
                assert worst(js_all[bands][setting], want[setting]) <= TOLERANCE, (bands, setting)


# ---------------------------------------------------------------------------------------------------------------
# Python
# ---------------------------------------------------------------------------------------------------------------
class TestExportSource:
    @pytest.mark.parametrize("language", ["glsl", "hlsl", "json"])
    def test_shader_languages_are_refused_saying_why(self, language: str) -> None:
        with pytest.raises(ValueError, match=f"does not write {language}"):
            export_hosek.export_source(language)

    @pytest.mark.parametrize("kwargs", [{"language": "rust"}, {"language": "c", "bands": 8}, {"language": "js", "bands": 0},
                                        {"language": "c", "accuracy": "best"}, {"language": "c", "real": "half"}])
    def test_bad_arguments_are_refused(self, kwargs: dict) -> None:
        with pytest.raises(ValueError):
            export_hosek.export_source(**kwargs)

    def test_float_is_refused_saying_why(self) -> None:
        with pytest.raises(ValueError, match="double only"):
            export_hosek.export_source("c", real="float")

    def test_numbers_round_trip_and_license(self) -> None:
        source = export_hosek.export_source("c", 2, accuracy="fast")
        params, _ = export_hosek._dataset()
        body = source.split("SKYSH_HW_PARAMS[10 * 2 * 6 * 3 * 9] = {", 1)[1].split("};", 1)[0]
        assert np.array_equal(np.array([float(v) for v in body.replace("\n", " ").split(",")]), params.ravel())
        assert "Lukas Hosek and Alexander Wilkie" in source and "#define SKYSH_HW_AZIMUTH 20" in source
        assert export_hosek.export_source("js", 2).count("Lukas Hosek and Alexander Wilkie") == 1


if __name__ == "__main__":  # print the measured agreement
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        if GCC:
            for n in BANDS:
                got = c_results(build_c(root / f"b{n}", export_hosek.export_source("c", n)), n)
                print(f"C  {n} bands: " + ", ".join(f"{s}: {worst(got[s], reference(n)[s]):.2e}" for s in SETTINGS))
        if NODE:
            module = root / "hosek_wilkie.mjs"
            module.write_text(export_hosek.export_source("js"), encoding="utf-8")
            for n, got in js_results(module, BANDS).items():
                print(f"JS {n} bands: " + ", ".join(f"{s}: {worst(got[s], reference(n)[s]):.2e}" for s in SETTINGS))
