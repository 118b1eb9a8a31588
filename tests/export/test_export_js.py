"""
Tests of skysh.export.js: the JavaScript runtime module against the Python runtime, run in node.

Every comparison sends its batch of calls as one JSON line to ONE node process
per module (:class:`NodeServer`, the :func:`node` fixture), which imports the module
named in the request and answers with one JSON line; NaN and infinities travel as
``{"$float": "NaN"}``. Doubles cross JSON exactly (both sides print the shortest
round-trip text). The TypeScript check of the declarations (one ``tsc`` run for the
usage and its negative control) starts in the background with the module.

Error measure (as ``tests/export/test_export.py``): the largest |js - python| of a
result over |DC| of the same channel, worst channel. For engines the scale is
the largest |DC| of the radiance times the largest absolute row sum of the
engine's map (the most a DC-sized input can become in the engine's numbers).

The certified irradiance table (issue 18): the ``irradianceTable`` option against the
runtime's ``irradiance_table`` (every option absent or set, engines, the sun and the
ground, the domain's corners and edges; refusals on both sides), the module's tabulated
irradiance never negative by its exact minimum (:func:`skysh.sh.minimum.exact_min`), and
negative controls (a module whose rotation turns the other way; the old pipeline in
place of the default; the un-deringed old pipeline dips below 0).

Skipped without node; the engine tests are skipped while ``skysh.engines.presets`` does
not exist. ``python tests/export/test_export_js.py`` prints the measured errors.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

import numpy as np
import pytest
from background import selected_names
from conftest import PLAIN_DIP, SKIP_NO_NODE, SKIP_NO_TSC, dc_relative_error, engine_cases, is_padded_identity

from skysh import SkySH
from skysh.export.c_like import export_source
from skysh.export.js import declarations, declarations_path, module_source
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

NODE: str | None = shutil.which("node")
pytestmark = [pytest.mark.skipif(NODE is None, reason=SKIP_NO_NODE), pytest.mark.integration]

JS_TOLERANCE: float = 1e-12
"""The issue's requirement: double arithmetic in both languages, the same algorithm
up to the Chebyshev recurrence against cos(k acos x) and the order of summation
(a few ulps of each of ~100 terms; measured about 1e-15)."""

CONTROL_MARGIN: float = 1e3
"""A negative control must miss by this factor times the tolerance: a wrong answer
is wrong by far more than rounding."""

RANDOM_INPUTS: int = 560
"""Random (sun, turbidity, azimuth, options) calls compared with the runtime (>= 500):
every band count 1-7 with every gibbs/irradiance setting, 20 times each."""

SEED: int = 20241130

RUNNER: str = r"""
import { pathToFileURL } from "node:url";
const decode = (v) => (v !== null && typeof v === "object" && "$float" in v ? Number(v.$float) : v);
async function answer(request) {
  const m = await import(pathToFileURL(request.module).href);
  const results = request.calls.map((call) => {
    try {
      const args = call.map((v) => (v !== null && typeof v === "object" && !("$float" in v)
        ? Object.fromEntries(Object.entries(v).map(([k, x]) => [k, decode(x)])) : decode(v)));
      if (args[0] === "sunLight") {
        const light = m.sunLight(...args.slice(1));
        return { values: [...light.direction, ...light.rgb], plain: true };
      }
      const out = m.coefficients(...args);
      return { values: Array.from(out), plain: Array.isArray(out) };
    } catch (error) {
      return { error: error.constructor.name, message: String(error.message) };
    }
  });
  process.stdout.write(JSON.stringify({ results, exports: Object.keys(m).sort(), engines: m.ENGINES,
    maxBands: m.MAX_BANDS }) + "\n");
}
let pending = "";
let chain = Promise.resolve();
process.stdin.setEncoding("utf8");
process.stdin.on("data", (chunk) => {
  pending += chunk;
  for (let cut = pending.indexOf("\n"); cut >= 0; cut = pending.indexOf("\n")) {
    const line = pending.slice(0, cut);
    pending = pending.slice(cut + 1);
    if (line.trim()) chain = chain.then(() => answer(JSON.parse(line)));
  }
});
"""
"""A node server: each stdin line {"module": path, "calls": [...]} is answered, in order, by one stdout line
{"results", "exports", "engines", "maxBands"} from that module (imported once per path); ends with its stdin."""

NODE_TIMEOUT_S: float = 120.0
"""Hang guard of the node server at the end of the module (it ends when its stdin closes, at once normally)."""


class NodeServer:
    """One node process running :data:`RUNNER`: :meth:`run` sends a request and reads its answer.

    The module imported by a request is cached by its path for the server's life, so a test writes a changed module
    (a negative control) under a new name.
    """

    def __init__(self, directory: Path) -> None:
        assert NODE is not None
        (directory / "runner.mjs").write_text(RUNNER)
        self._stderr: IO[str] = tempfile.TemporaryFile(mode="w+")
        self._process = subprocess.Popen([NODE, str(directory / "runner.mjs")], stdin=subprocess.PIPE,
                                         stdout=subprocess.PIPE, stderr=self._stderr, text=True)

    def run(self, directory: Path, calls: list[list[Any]], module: str = "sky_sh.mjs") -> dict[str, Any]:
        """Evaluate every call ``coefficients(*call)`` (or ``sunLight(*call[1:])`` for a call starting "sunLight") of
        the module ``directory / module``: the results in order, the module's exports, ENGINES and MAX_BANDS."""
        assert self._process.stdin is not None and self._process.stdout is not None
        request = json.dumps({"module": str(directory / module), "calls": [[encode(a) for a in c] for c in calls]})
        self._process.stdin.write(request + "\n")
        self._process.stdin.flush()
        line = self._process.stdout.readline()
        if not line:
            self._stderr.seek(0)
            raise AssertionError(f"node ended ({self._process.wait()}): {self._stderr.read()}")
        return json.loads(line)

    def close(self) -> None:
        """End the process (closing its stdin) and check it ended cleanly."""
        assert self._process.stdin is not None
        self._process.stdin.close()
        code = self._process.wait(timeout=NODE_TIMEOUT_S)
        self._stderr.seek(0)
        errors = self._stderr.read()
        self._stderr.close()
        assert code == 0, errors


@pytest.fixture(scope="module")
def module_dir(sky: SkySH, tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("js")
    (directory / "sky_sh.mjs").write_text(module_source(sky))
    (directory / declarations_path(Path("sky_sh.mjs")).name).write_text(declarations(sky))
    return directory


@pytest.fixture(scope="module")
def node(tmp_path_factory: pytest.TempPathFactory) -> Iterator[NodeServer]:
    """The module's node server."""
    server = NodeServer(tmp_path_factory.mktemp("node"))
    yield server
    server.close()


TSC_TIMEOUT_S: float = 300.0
"""Hang guard of the TypeScript check (a few seconds normally: tsc parses its standard library)."""

USAGE_TS: str = (
    'import { coefficients, engineLayout, ENGINES, type CoefficientOptions } from "./sky_sh.mjs";\n'
    "const options: CoefficientOptions = { bands: 3, irradiance: true, sun: true, groundAlbedo: [0.2, 0.3, 0.1],\n"
    "  irradianceTable: null };\n"
    "const old: number[] = coefficients(0.5, 3, 1, { ...options, irradianceTable: false });\n"
    "const c: number[] = coefficients(0.5, 3, 1, options);\n"
    "const t: Float64Array = coefficients(0.5, 3, 1, { ...options, out: new Float64Array(27) });\n"
    "const n: number = c.length + t.length + ENGINES.length + old.length;\n"
    "if (ENGINES.length) { const shape: readonly number[] = engineLayout(ENGINES[0]).shape; void shape; }\n"
    'import { sunLight } from "./sky_sh.mjs";\n'
    "const light = sunLight(0.5, 3); const lux: number = light.rgb[0] + light.direction[2];\n"
    "void n; void lux;\n"
)
"""TypeScript using the declarations as documented: must type-check under --strict."""

BAD_TS: str = 'import { coefficients } from "./sky_sh.mjs";\ncoefficients(0.5, 3, 1, { bands: "3", gibs: true });\n'
"""The negative control: a wrong option type and an unknown option must not type-check."""


@pytest.fixture(scope="module")
def type_check(module_dir: Path) -> Iterator[subprocess.Popen | None]:
    """tsc (tests/js's pinned TypeScript, else one on PATH; None without) checking usage.ts and bad.ts next to the
    module and its declarations in one run, started in the background; killed if left running."""
    local = Path(__file__).parents[1] / "js" / "node_modules" / ".bin" / "tsc"
    tsc = str(local) if local.exists() else shutil.which("tsc")
    if tsc is None:
        yield None
        return
    (module_dir / "usage.ts").write_text(USAGE_TS)
    (module_dir / "bad.ts").write_text(BAD_TS)
    process = subprocess.Popen(
        [tsc, "--noEmit", "--pretty", "false", "--strict", "--module", "nodenext", "--moduleResolution", "nodenext",
         "--target", "es2022", "--skipDefaultLibCheck", "usage.ts", "bad.ts"], cwd=module_dir, stdout=subprocess.PIPE,
        stderr=subprocess.PIPE, text=True)  # skipDefaultLibCheck: TypeScript's own lib.*.d.ts are used, not re-checked
    yield process
    if process.poll() is None:
        process.kill()
    process.communicate()


@pytest.fixture(scope="module", autouse=True)
def _start_the_type_check(request: pytest.FixtureRequest) -> None:
    """Start the TypeScript check with the module's first test when test_declarations_type_check is selected: tsc
    then works in its own process while the other tests run, and the test (marked ``late``) waits for it."""
    if NODE is not None and "test_declarations_type_check" in selected_names(request):
        request.getfixturevalue("type_check")


def encode(value: Any) -> Any:
    """A call argument as JSON: non-finite floats as {"$float": text}."""
    if isinstance(value, float) and not math.isfinite(value):
        return {"$float": str(value).replace("inf", "Infinity").replace("nan", "NaN")}
    if isinstance(value, dict):
        return {k: encode(v) for k, v in value.items()}
    return value


def random_calls(count: int, seed: int = SEED) -> list[tuple[float, float, float, dict[str, Any]]]:
    """Random inputs over the domain (and azimuths well outside [0, 2 pi]); options cycle through
    bands 1-7 x gibbs {absent, true, false} x irradiance {absent, true, false}."""
    rng = np.random.default_rng(seed)
    calls = []
    for k in range(count):
        bands = 1 + k % 7
        gibbs = (None, True, False)[(k // 7) % 3]
        irradiance = (None, True, False)[(k // 21) % 3]
        options: dict[str, Any] = {"bands": bands, "dering": False}
        if gibbs is not None:
            options["gibbs"] = gibbs
        if irradiance is not None:
            options["irradiance"] = irradiance
        ts = float(rng.uniform(0.0, math.pi / 2.0))
        t = float(rng.uniform(2.5, 6.0))
        phi = float(rng.uniform(-50.0, 50.0))
        calls.append((ts, t, phi, options))
    return calls


def runtime_options(options: dict[str, Any]) -> dict[str, Any]:
    """The runtime's keyword arguments for a module call's options (the radiance for an engine), the module's
    documented defaults written out: absent gibbs and dering are the runtime's None (its rule by intent) except
    that an engine lights diffusely (gibbs false, dering true, and the irradiance table by the irradiance rule)."""
    bands = options.get("bands", 3)
    gibbs, dering, table = options.get("gibbs"), options.get("dering"), options.get("irradianceTable")
    if "engine" in options:
        if table is None:  # the runtime's rule for irradiance, as engines light diffusely
            table = bands == 3 and gibbs is not True and dering is not False
        gibbs = False if gibbs is None else gibbs
        dering = True if dering is None else dering
    return dict(bands=bands, gibbs=gibbs, dering=dering, irradiance=options.get("irradiance", False),
                sun=options.get("sun", False), ground_albedo=options.get("groundAlbedo", 0.0), irradiance_table=table)


def python_reference(sky: SkySH, ts: float, t: float, phi: float, options: dict[str, Any]) -> np.ndarray:
    """The runtime's result for the same options (:func:`runtime_options`; for an engine, its radiance)."""
    return sky.coefficients(ts, t, phi, **runtime_options(options))


# --------------------------------------------------------------------------- #
class TestAgainstRuntime:
    def test_random_inputs_match_the_python_runtime(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        calls = random_calls(RANDOM_INPUTS)
        reply = node.run(module_dir, [list(c) for c in calls])
        worst = 0.0
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            assert "values" in result, result
            assert result["plain"]
            got = np.array(result["values"]).reshape(-1, 3)
            worst = max(worst, dc_relative_error(got, python_reference(sky, ts, t, phi, options)))
        assert worst < JS_TOLERANCE

    def test_negative_control_fails(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """The same comparison with the Gibbs setting flipped must fail: the test can fail."""
        calls = random_calls(21)
        reply = node.run(module_dir, [list(c) for c in calls])
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            if options["bands"] < 2:
                continue  # the filter is the identity for one band
            flipped = dict(options, gibbs=not options.get("gibbs", not options.get("irradiance", False)))
            got = np.array(result["values"]).reshape(-1, 3)
            assert dc_relative_error(got, python_reference(sky, ts, t, phi, flipped)) > CONTROL_MARGIN * JS_TOLERANCE

    @pytest.mark.parametrize("phi", [-12345.678, 1e6, -1e15, 2.0 * math.pi, -math.pi, 5e-324])
    def test_azimuth_is_reduced_as_the_runtime_does(self, sky: SkySH, module_dir: Path, phi: float, node: NodeServer) -> None:
        calls = [[0.7, 3.3, phi, {"bands": 7, "gibbs": False}]]
        got = np.array(node.run(module_dir, calls)["results"][0]["values"]).reshape(-1, 3)
        ref = sky.coefficients(0.7, 3.3, phi, bands=7, gibbs=False, dering=False)
        assert dc_relative_error(got, ref) < JS_TOLERANCE

    def test_domain_edges_are_accepted(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        calls = [[0.0, 2.5, 0.0, {"bands": 3, "dering": False}], [math.pi / 2.0, 6.0, 100.0, {"bands": 3, "dering": False}]]
        for (ts, t, phi, options), result in zip(calls, node.run(module_dir, calls)["results"]):
            got = np.array(result["values"]).reshape(-1, 3)
            assert dc_relative_error(got, python_reference(sky, ts, t, phi, options)) < JS_TOLERANCE

    def test_defaults(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """Omitted arguments: azimuth 0, bands 3, gibbs = !irradiance, dering = irradiance; the Python runtime's
        defaults (every band count's irradiance default: tests/export/test_export_js_dering.py)."""
        reply = node.run(module_dir, [
            [0.4, 4.0], [0.4, 4.0, 0.0, {"bands": 3, "gibbs": True, "irradiance": False, "dering": False}],
            [0.4, 4.0, 0.0, {"irradiance": True}],
            [0.4, 4.0, 0.0, {"bands": 3, "gibbs": False, "irradiance": True, "dering": True}],
        ])
        values = [r["values"] for r in reply["results"]]
        assert values[0] == values[1] and len(values[0]) == 27
        assert values[2] == values[3]
        got = np.array(values[0]).reshape(-1, 3)
        assert dc_relative_error(got, sky.coefficients(0.4, 4.0)) < JS_TOLERANCE
        got = np.array(values[2]).reshape(-1, 3)  # the runtime's default for 3-band irradiance: the certified table
        assert dc_relative_error(got, sky.coefficients(0.4, 4.0, irradiance=True)) < JS_TOLERANCE

    def test_out_is_filled_in_place(self, module_dir: Path) -> None:
        script = (
            f"import {{ coefficients }} from {json.dumps((module_dir / 'sky_sh.mjs').as_uri())};\n"
            "const typed = new Float64Array(12), plain = new Array(12);\n"
            "const fresh = coefficients(0.5, 3, 1, { bands: 2 });\n"
            "const same = coefficients(0.5, 3, 1, { bands: 2, out: typed }) === typed\n"
            "  && coefficients(0.5, 3, 1, { bands: 2, out: plain }) === plain;\n"
            "let wrong = '';\n"
            "try { coefficients(0.5, 3, 1, { bands: 3, out: typed }); } "
            "catch (e) { wrong = e.constructor.name + ' ' + e.message; }\n"
            "console.log(JSON.stringify({ same, equal: fresh.every((v, i) => v === typed[i] && v === plain[i]), wrong }));\n"
        )
        done = subprocess.run([NODE, "--input-type=module", "-e", script], capture_output=True, text=True, check=True)
        reply = json.loads(done.stdout)
        assert reply["same"] and reply["equal"]
        assert reply["wrong"].startswith("TypeError out must be an Array or Float64Array of length 27")


DERING_INPUTS: int = 240
"""Random 3-band calls with deringing (every gibbs/irradiance setting); about half need a window."""


class TestDering:
    def test_dering_matches_the_runtime_window_for_window(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        rng = np.random.default_rng(SEED + 3)
        calls = [
            [float(rng.uniform(0.0, math.pi / 2.0)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-9.0, 9.0)),
             {"bands": 3, "dering": True, "gibbs": k % 2 == 0, "irradiance": k % 4 < 2, "irradianceTable": False}]
            for k in range(DERING_INPUTS)
        ]
        reply = node.run(module_dir, calls)
        worst, windowed = 0.0, 0
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            got = np.array(result["values"]).reshape(-1, 3)
            ref = python_reference(sky, ts, t, phi, options)
            worst = max(worst, dc_relative_error(got, ref))
            plain = python_reference(sky, ts, t, phi, dict(options, dering=False))
            windowed += dc_relative_error(ref, plain) > CONTROL_MARGIN * JS_TOLERANCE
        assert worst < JS_TOLERANCE
        assert windowed > DERING_INPUTS // 10  # the comparison covers real windows, not only identities

    def test_dering_with_engines(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """The engine option's defaults at 3 bands (by intent: the irradiance table's radiance-equivalent) and the
        deringed old pipeline one option away."""
        engines = pytest.importorskip("skysh.engines.presets")
        names = [name for name, bands in engine_cases() if bands == 3]
        calls = [[0.2 + 0.1 * k, 2.5 + 0.3 * k, 1.0 - k, {"engine": name, "bands": 3, **({"irradianceTable": False} if k % 2
                                                                                            else {})}]
                 for name in names for k in range(8)]
        reply = node.run(module_dir, calls)
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            table = "irradianceTable" not in options
            radiance = sky.coefficients(ts, t, phi, bands=3, gibbs=False, dering=True, irradiance_table=table)
            ref = np.asarray(engines.convert(radiance, options["engine"]), dtype=np.float64).reshape(-1)
            gain = float(np.abs(np.asarray(engines.engine_map(options["engine"], 3).matrix)).sum(axis=1).max())
            assert np.abs(np.array(result["values"]) - ref).max() / (gain * np.abs(radiance[0]).max()) < JS_TOLERANCE


TABLE_INPUTS: int = 600
"""Random calls of the irradiance-table tests: every option absent or set, engines at 3 bands."""

NONNEGATIVE_INPUTS: int = 2000
"""Random frames (and the domain's corners and edges) at which the module's tabulated irradiance is checked by its
exact minimum over the sphere."""


def table_calls(count: int = TABLE_INPUTS, seed: int = SEED + 18) -> list[tuple[float, float, float, dict[str, Any]]]:
    """Random calls: bands 3 two times in three (else 1-7), gibbs/dering/irradiance absent, true or false,
    irradianceTable absent, null, true or false, an engine every
    fifth 3-band call, the sun and a ground now and then; the domain's corners first, one in ten on an edge."""
    rng = np.random.default_rng(seed)
    names = [name for name, bands in engine_cases() if bands == 3]
    corners = [(z, t) for z in (0.0, math.pi / 2.0) for t in (2.5, 6.0)]
    calls = []
    for k in range(count):
        bands = 3 if k % 3 else int(rng.integers(1, 8))
        options: dict[str, Any] = {"bands": bands}
        for key, values, pick in (("gibbs", (True, False), k // 3), ("dering", (True, False), k // 9),
                                  ("irradiance", (True, False), k // 27), ("irradianceTable", (None, True, False), k // 81)):
            choice = pick % (len(values) + 1)
            if choice < len(values):
                options[key] = values[choice]
        if names and bands == 3 and k % 5 == 0 and not options.get("irradiance"):
            options["engine"] = names[k // 5 % len(names)]
        if k % 7 == 0:
            options.update(sun=True, groundAlbedo=0.3)
        ts, t = corners[k % 4] if k < 40 else (float(rng.uniform(0.0, math.pi / 2.0)), float(rng.uniform(2.5, 6.0)))
        if k >= 40 and k % 10 == 0:
            ts = (0.0, math.pi / 2.0)[k % 20 // 10]
        calls.append((ts, t, float(rng.uniform(-20.0, 20.0)), options))
    return calls


def table_errors(sky: SkySH, calls: list, results: list) -> tuple[float, int, int]:
    """(worst error against the runtime, calls both refuse, calls that take the table); a ValueError of the runtime
    must be a RangeError of the module naming irradianceTable."""
    worst, refused, tables = 0.0, 0, 0
    for (ts, t, phi, options), result in zip(calls, results):
        try:
            ref, scale = light_reference(sky, ts, t, phi, options)
        except ValueError:
            assert result.get("error") == "RangeError" and result["message"].startswith("irradianceTable"), (options, result)
            refused += 1
            continue
        assert "values" in result, (options, result)
        got = np.array(result["values"])
        error = float(np.abs(got - ref.reshape(-1)).max()) / scale if scale else dc_relative_error(got.reshape(-1, 3), ref)
        worst = max(worst, error)
        kwargs = runtime_options(options)
        if kwargs["bands"] == 3 and kwargs["gibbs"] is not True and kwargs["irradiance_table"] is not False:
            tables += np.array_equal(sky.coefficients(ts, t, phi, **kwargs),
                                     sky.coefficients(ts, t, phi, **{**kwargs, "irradiance_table": True}))
    return worst, refused, tables


class TestIrradianceTable:
    """The certified irradiance table (issue 18): the irradianceTable option as the runtime's irradiance_table."""

    def test_every_setting_matches_the_runtime(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        calls = table_calls()
        worst, refused, tables = table_errors(sky, calls, node.run(module_dir, [list(c) for c in calls])["results"])
        assert worst < JS_TOLERANCE
        assert refused > 10 and tables > TABLE_INPUTS // 10  # refusals and the table are in the comparison

    def test_the_default_takes_the_table(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """Negative control: the default 3-band irradiance misses the old pipeline (irradiance_table=False)."""
        calls = [c[:3] + ({"irradiance": True},) for c in table_calls(60)]
        reply = node.run(module_dir, [list(c) for c in calls])
        for (ts, t, phi, _), result in zip(calls, reply["results"]):
            old = sky.coefficients(ts, t, phi, irradiance=True, irradiance_table=False)
            assert dc_relative_error(np.array(result["values"]).reshape(-1, 3), old) > CONTROL_MARGIN * JS_TOLERANCE

    def test_tabulated_irradiance_is_never_negative(self, module_dir: Path, node: NodeServer) -> None:
        """The module's default 3-band irradiance, exact minimum over the sphere (skysh.sh.minimum.exact_min), at random
        frames, the corners and the edges; with irradianceTable: false and dering: false it dips below 0."""
        rng = np.random.default_rng(SEED + 19)
        frames = [[float(z), float(t), float(a)] for z, t, a in zip(rng.uniform(0.0, math.pi / 2.0, NONNEGATIVE_INPUTS),
                                                                 rng.uniform(2.5, 6.0, NONNEGATIVE_INPUTS),
                                                                 rng.uniform(-3.0, 3.0, NONNEGATIVE_INPUTS))]
        frames += [[z, t, 0.5] for z in (0.0, math.pi / 2.0) for t in (2.5, 6.0)]
        frames += [[z, t, 1.0] for z in np.linspace(0.0, math.pi / 2.0, 25).tolist() for t in (2.5, 6.0)]
        frames += [[z, t, -1.0] for z in (0.0, math.pi / 2.0) for t in np.linspace(2.5, 6.0, 25).tolist()]
        plain = {"irradiance": True, "irradianceTable": False, "dering": False}
        reply = node.run(module_dir, [f + [{"irradiance": True}] for f in frames] + [f + [plain] for f in frames])
        values = np.array([r["values"] for r in reply["results"]]).reshape(2, len(frames), 9, 3)
        mean = values[:, :, 0, :] / (2.0 * math.sqrt(math.pi))
        lowest = (shmin.exact_min(values) / mean).min(axis=(1, 2))
        assert lowest[0] >= 0.0 and lowest[1] < PLAIN_DIP  # measured 6.8e-4 and -2.6e-2 of the mean

    def test_negative_control_wrong_rotation_sign(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """A module whose rotation (Habel eq. 4) turns the other way must fail the comparison with the runtime."""
        source = (module_dir / "sky_sh.mjs").read_text()
        mutated = source.replace("sp = SIN[k] * band;", "sp = -SIN[k] * band;")
        assert mutated != source
        (module_dir / "turned.mjs").write_text(mutated)
        calls = [c[:3] + ({"irradiance": True},) for c in table_calls(20)]
        worst, _, tables = table_errors(sky, calls, node.run(module_dir, [list(c) for c in calls], "turned.mjs")["results"])
        assert tables == len(calls) and worst > CONTROL_MARGIN * JS_TOLERANCE

    def test_a_module_without_the_table(self, sky: SkySH, tmp_path: Path, node: NodeServer) -> None:
        """Two bands: no table; irradianceTable: true is refused, the default irradiance is the runtime's (no table)."""
        (tmp_path / "two.mjs").write_text(module_source(sky, bands=2))
        reply = node.run(tmp_path, [[0.5, 3.0, 0.2, {"bands": 2, "irradianceTable": True}],
                                    [0.5, 3.0, 0.2, {"bands": 2, "irradiance": True}]], module="two.mjs")
        assert reply["results"][0]["error"] == "RangeError"
        assert reply["results"][0]["message"].startswith("irradianceTable: true needs the coefficient file's")
        got = np.array(reply["results"][1]["values"]).reshape(-1, 3)
        assert dc_relative_error(got, sky.coefficients(0.5, 3.0, 0.2, bands=2, irradiance=True, dering=False)) < JS_TOLERANCE


# --------------------------------------------------------------------------- #
BAD_CALLS: list[tuple[list[Any], str, str]] = [
    ([-0.01, 3.0, 0.0], "RangeError", "sunZenith"),
    ([1.5708, 3.0, 0.0], "RangeError", "sunZenith"),
    ([float("nan"), 3.0, 0.0], "RangeError", "sunZenith"),
    ([0.5, 2.49, 0.0], "RangeError", "turbidity"),
    ([0.5, 6.01, 0.0], "RangeError", "turbidity"),
    ([0.5, float("inf"), 0.0], "RangeError", "turbidity"),
    ([0.5, 3.0, float("inf")], "RangeError", "sunAzimuth"),
    ([0.5, 3.0, float("-inf")], "RangeError", "sunAzimuth"),
    ([0.5, 3.0, float("nan")], "RangeError", "sunAzimuth"),
    ([0.5, 3.0, 0.0, {"bands": 0}], "RangeError", "bands"),
    ([0.5, 3.0, 0.0, {"bands": 8}], "RangeError", "bands"),
    ([0.5, 3.0, 0.0, {"bands": 2.5}], "RangeError", "bands"),
    ([0.5, 3.0, 0.0, {"bands": float("nan")}], "RangeError", "bands"),
    ([0.5, 3.0, 0.0, {"engine": "godot"}], "RangeError", "engine"),
    ([0.5, 3.0, 0.0, {"engine": ""}], "RangeError", "engine"),
    (["0.5", 3.0, 0.0], "TypeError", "sunZenith"),
    ([0.5, None, 0.0], "TypeError", "turbidity"),
    ([0.5, 3.0, "0"], "TypeError", "sunAzimuth"),
    ([0.5, 3.0, 0.0, {"gibbs": 1}], "TypeError", "gibbs"),
    ([0.5, 3.0, 0.0, {"irradiance": "false"}], "TypeError", "irradiance"),
    ([0.5, 3.0, 0.0, {"dering": 0}], "TypeError", "dering"),
    ([0.5, 3.0, 0.0, {"gibs": True}], "TypeError", "gibs"),
    ([0.5, 3.0, 0.0, 7], "TypeError", "options"),
    ([0.5, 3.0, 0.0, {"irradianceTable": 1}], "TypeError", "irradianceTable"),
    ([0.5, 3.0, 0.0, {"irradianceTable": True, "bands": 2}], "RangeError", "irradianceTable"),
    ([0.5, 3.0, 0.0, {"irradianceTable": True, "gibbs": True}], "RangeError", "irradianceTable"),
]


class TestRefusals:
    def test_bad_values_throw_naming_the_parameter(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        reply = node.run(module_dir, [call for call, _, _ in BAD_CALLS])
        for (call, kind, name), result in zip(BAD_CALLS, reply["results"]):
            assert result.get("error") == kind, (call, result)
            assert result["message"].startswith(name) or f'"{name}"' in result["message"], (call, result)
        for call, _kind, _ in BAD_CALLS[:9]:  # the runtime refuses the same numbers
            with pytest.raises(ValueError):
                sky.coefficients(*call, bands=3)

    def test_options_must_be_a_plain_object(self, module_dir: Path) -> None:
        """Issue 23: an array (once taken as no options), a Map, a Date or a class instance as ``options`` is a
        TypeError naming options; plain objects pass, from this realm, another (node:vm) or without a prototype."""
        script = (
            "import vm from 'node:vm';\n"
            f"import {{ coefficients }} from {json.dumps((module_dir / 'sky_sh.mjs').as_uri())};\n"
            "class Options { constructor() { this.bands = 2; } }\n"
            "const bad = [[], [2], new Map([['bands', 2]]), new Date(0), new Options(), new Float64Array(2)];\n"
            "const refused = bad.map((options) => {\n"
            "  try { coefficients(0.5, 3, 1, options); return 'accepted'; }\n"
            "  catch (e) { return e.constructor.name + ' ' + e.message; }\n"
            "});\n"
            "const bare = Object.create(null); bare.bands = 2;\n"
            "const good = [{ bands: 2 }, bare, vm.runInNewContext('({ bands: 2 })'), undefined];\n"
            "const accepted = good.map((options) => coefficients(0.5, 3, 1, options).length);\n"
            "console.log(JSON.stringify({ refused, accepted }));\n"
        )
        done = subprocess.run([NODE, "--input-type=module", "-e", script], capture_output=True, text=True, check=True)
        reply = json.loads(done.stdout)
        for message in reply["refused"]:
            assert message.startswith("TypeError options must be a plain object"), reply
        assert reply["refused"][0].endswith("got an array") and "Options" in reply["refused"][4]
        assert reply["accepted"] == [12, 12, 12, 27]  # bands 2 (4 x 3 numbers); no options: the default 3 bands

    def test_unknown_engine_lists_the_valid_ones(self, module_dir: Path, node: NodeServer) -> None:
        reply = node.run(module_dir, [[0.5, 3.0, 0.0, {"engine": "godot"}]])
        for name in reply["engines"]:
            assert json.dumps(name) in reply["results"][0]["message"]

    def test_bands_argument_limits_the_module(self, sky: SkySH, tmp_path: Path, node: NodeServer) -> None:
        (tmp_path / "sky_sh.mjs").write_text(module_source(sky, bands=2))
        reply = node.run(tmp_path, [[0.5, 3.0, 0.0, {"bands": 3}], [0.5, 3.0, 0.0, {"dering": False}]])
        assert reply["maxBands"] == 2  # and the default bands (3) becomes 2
        assert reply["results"][0]["error"] == "RangeError" and reply["results"][0]["message"].startswith("bands")
        got = np.array(reply["results"][1]["values"]).reshape(-1, 3)
        assert dc_relative_error(got, sky.coefficients(0.5, 3.0, 0.0, bands=2, gibbs=True)) < JS_TOLERANCE


# --------------------------------------------------------------------------- #
ENGINE_INPUTS: int = 12
"""Random inputs per (engine, bands, gibbs) case."""


def engine_error(sky: SkySH, node: NodeServer, module_dir: Path, name: str, bands: int) -> tuple[float, float]:
    """(worst error of the engine option, worst error of the unconverted skysh output) against convert(),
    over ENGINE_INPUTS random inputs for each Gibbs setting, in one node process."""
    from skysh.engines import presets as engines

    rng = np.random.default_rng(SEED + bands)
    calls = []
    for k in range(2 * ENGINE_INPUTS):
        options = {"engine": name, "bands": bands, "gibbs": k % 2 == 0, "dering": False}
        calls.append([float(rng.uniform(0, math.pi / 2)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-9, 9)), options])
    plain = [[*c[:3], {"bands": bands, "gibbs": c[3]["gibbs"], "dering": False}] for c in calls]
    reply = node.run(module_dir, calls + plain)
    emap = engines.engine_map(name, bands)
    gain = float(np.abs(np.asarray(emap.matrix)).sum(axis=1).max())
    worst = control = 0.0
    for k, (ts, t, phi, options) in enumerate(calls):
        radiance = sky.coefficients(ts, t, phi, bands=bands, gibbs=options["gibbs"], dering=False)
        ref = np.asarray(engines.convert(radiance, name), dtype=np.float64).reshape(-1)
        scale = gain * float(np.abs(radiance[0]).max())
        got = np.array(reply["results"][k]["values"])
        worst = max(worst, float(np.abs(got - ref).max()) / scale)
        unconverted = np.zeros(ref.size)  # skysh's numbers pasted as they are (zero-padded to the layout)
        plain_values = np.array(reply["results"][len(calls) + k]["values"])[: ref.size]
        unconverted[: plain_values.size] = plain_values
        control = max(control, float(np.abs(unconverted - ref).max()) / scale)
    return worst, control


class TestEngines:
    @pytest.fixture(scope="class")
    @classmethod
    def engines(cls) -> Any:
        return pytest.importorskip("skysh.engines.presets")

    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_engine_option_matches_convert(self, sky: SkySH, engines: Any, module_dir: Path, name: str, bands: int,
                                           node: NodeServer) -> None:
        worst, control = engine_error(sky, node, module_dir, name, bands)
        assert worst < JS_TOLERANCE
        if not is_padded_identity(name, bands):  # e.g. one band of a radiance engine is skysh's own DC
            assert control > CONTROL_MARGIN * JS_TOLERANCE  # negative control: skysh's own numbers fail

    def test_every_engine_is_in_the_module(self, engines: Any, module_dir: Path, node: NodeServer) -> None:
        reply = node.run(module_dir, [])
        assert reply["engines"] == [name for name in engines.ENGINES if any(n == name for n, _ in engine_cases())]

    def test_engine_refuses_irradiance_and_extra_bands(self, engines: Any, module_dir: Path, node: NodeServer) -> None:
        name = engines.ENGINES[0]
        high = engines.ENGINE_MAX_BANDS[name]
        calls = [[0.5, 3.0, 0.0, {"engine": name, "irradiance": True}]]
        if high < 7:
            calls.append([0.5, 3.0, 0.0, {"engine": name, "bands": high + 1}])
        reply = node.run(module_dir, calls)
        assert reply["results"][0]["error"] == "RangeError" and reply["results"][0]["message"].startswith("irradiance")
        if high < 7:
            message = reply["results"][1]["message"]
            assert reply["results"][1]["error"] == "RangeError" and message.startswith("bands") and name in message


# --------------------------------------------------------------------------- #
# The sun and the ground (skysh.export.lights)
# --------------------------------------------------------------------------- #
LIGHT_INPUTS: int = 350
"""Random calls with the sun and the ground: every band count, flag and (for 3 bands) engine, the horizon every
tenth call."""

NONNEGATIVE_FLOOR: float = -1e-9
"""Sun + dering: irradiance over the sphere above this times its DC (rounding of a sum touching 0)."""


def light_calls(count: int, seed: int = SEED + 11) -> list[tuple[float, float, float, dict[str, Any]]]:
    rng = np.random.default_rng(seed)
    names = [name for name, bands in engine_cases() if bands == 3]
    calls = []
    for k in range(count):
        bands = 1 + k % 7
        options: dict[str, Any] = {"bands": bands, "gibbs": (k // 7) % 2 == 0, "irradiance": (k // 14) % 2 == 0,
                                   "dering": (k // 28) % 2 == 0, "sun": (k // 3) % 2 == 0 or k % 10 == 0}
        if k % 4:
            options["groundAlbedo"] = [float(v) for v in rng.uniform(0.0, 1.0, 3)] if k % 4 > 1 else 0.25
        if bands == 3 and names and k % 5 == 0:
            options.update(engine=names[k % len(names)], irradiance=False)
        ts = math.pi / 2.0 if k % 10 == 0 else float(rng.uniform(0.0, math.pi / 2.0))
        calls.append((ts, float(rng.uniform(2.5, 6.0)), float(rng.uniform(-30.0, 30.0)), options))
    return calls


def light_reference(sky: SkySH, ts: float, t: float, phi: float, options: dict[str, Any]) -> tuple[np.ndarray, float]:
    """The runtime's numbers for a call (engines: convert of the radiance) and the error scale (|DC| per channel,
    or the engine's gain times the largest |DC|)."""
    radiance = python_reference(sky, ts, t, phi, options)
    if "engine" not in options:
        return radiance, 0.0
    from skysh.engines import presets as engines

    gain = float(np.abs(np.asarray(engines.engine_map(options["engine"], 3).matrix)).sum(axis=1).max())
    return np.asarray(engines.convert(radiance, options["engine"])).reshape(-1), gain * float(np.abs(radiance[0]).max())


def light_error(sky: SkySH, calls: list, results: list) -> float:
    worst = 0.0
    for (ts, t, phi, options), result in zip(calls, results):
        assert "values" in result, (options, result)
        ref, scale = light_reference(sky, ts, t, phi, options)
        got = np.array(result["values"])
        error = float(np.abs(got - ref.reshape(-1)).max()) / scale if scale else dc_relative_error(got.reshape(-1, 3), ref)
        worst = max(worst, error)
    return worst


class TestLights:
    def test_random_inputs_match_the_python_runtime(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        calls = light_calls(LIGHT_INPUTS)
        assert light_error(sky, calls, node.run(module_dir, [list(c) for c in calls])["results"]) < JS_TOLERANCE

    def test_large_azimuths_with_the_sun_match_the_python_runtime(self, sky: SkySH, module_dir: Path,
                                                                   node: NodeServer) -> None:
        """Issue 23: the sun sits where the sky turns at any finite azimuth (both reduce it by sunAzimuth % 2 pi,
        exact as Python's math.fmod)."""
        rng = np.random.default_rng(SEED + 23)
        calls = [(ts, t, float(10.0 ** rng.uniform(4, 300) * rng.choice([-1.0, 1.0])), {**options, "sun": True})
                 for ts, t, _, options in light_calls(60)]
        assert light_error(sky, calls, node.run(module_dir, [list(c) for c in calls])["results"]) < JS_TOLERANCE

    def test_sun_light_matches_the_runtime(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        rng = np.random.default_rng(SEED + 12)
        frames = [(float(ts), float(t), float(phi)) for ts, t, phi in
                  zip(rng.uniform(0.0, math.pi / 2.0, 60), rng.uniform(2.5, 6.0, 60), rng.uniform(-99.0, 99.0, 60))]
        frames += [(math.pi / 2.0, 6.0, 1.0), (0.0, 2.5, 0.0), (math.pi / 2.0, 2.5, -4.0)]
        reply = node.run(module_dir, [["sunLight", *f] for f in frames])
        for frame, result in zip(frames, reply["results"]):
            direction, rgb = sky.sun_light(*frame)
            values = np.array(result["values"])
            assert np.abs(values[:3] - direction).max() < JS_TOLERANCE
            assert np.abs(values[3:] - rgb).max() / np.abs(rgb).max() < JS_TOLERANCE

    def test_sun_and_dering_keep_the_irradiance_non_negative(self, module_dir: Path, node: NodeServer) -> None:
        calls = [[float(ts), 2.5 + 0.08 * k, 0.3 * k, {"bands": 3, "irradiance": True, "sun": True,
                                                      "groundAlbedo": [0.3, 0.2, 0.1] if k % 2 else 0}]
                 for k, ts in enumerate(np.linspace(0.0, math.pi / 2.0, 40))]  # black ground: the sky's ring shows
        normals = np.random.default_rng(4).standard_normal((4000, 3))
        basis = sh.basis(normals / np.linalg.norm(normals, axis=1, keepdims=True), 3)
        for call, result in zip(calls, node.run(module_dir, calls)["results"]):
            coefficients = np.array(result["values"]).reshape(-1, 3)
            assert (basis @ coefficients).min() >= NONNEGATIVE_FLOOR * coefficients[0].max(), call

    @pytest.mark.parametrize(("options", "kind", "name"), [
        ({"groundAlbedo": -0.1}, "RangeError", "groundAlbedo"),
        ({"groundAlbedo": [0.1, 1.5, 0.1]}, "RangeError", "groundAlbedo"),
        ({"groundAlbedo": float("nan")}, "RangeError", "groundAlbedo"),
        ({"groundAlbedo": [0.2, 0.2]}, "TypeError", "groundAlbedo"),
        ({"groundAlbedo": "0.2"}, "TypeError", "groundAlbedo"), ({"sun": 1}, "TypeError", "sun"),
    ])
    def test_bad_options_throw_naming_the_parameter(self, module_dir: Path, options: dict, kind: str, name: str,
                                                    node: NodeServer) -> None:
        result = node.run(module_dir, [[0.5, 3.0, 0.0, options]])["results"][0]
        assert result.get("error") == kind and result["message"].startswith(name), result

    def test_sun_light_refuses_bad_frames(self, module_dir: Path, node: NodeServer) -> None:
        reply = node.run(module_dir, [["sunLight", 1.6, 3.0], ["sunLight", 0.5, 7.0], ["sunLight", "0.5", 3.0],
                                      ["sunLight", 0.5, 3.0, float("nan")]])
        expected = [("RangeError", "sunZenith"), ("RangeError", "turbidity"), ("TypeError", "sunZenith"),
                    ("RangeError", "sunAzimuth")]
        for (kind, name), result in zip(expected, reply["results"]):
            assert result.get("error") == kind and result["message"].startswith(name), result

    def test_negative_control_unfiltered_ground_fails(self, sky: SkySH, module_dir: Path, node: NodeServer) -> None:
        """A module whose ground skips the Gibbs filter must fail the comparison with the runtime."""
        source = (module_dir / "sky_sh.mjs").read_text()
        mutated = source.replace("gibbs ? GROUND[l] * GIBBS[g0 + l] : GROUND[l]", "GROUND[l]")
        assert mutated != source
        (module_dir / "mutated.mjs").write_text(mutated)
        calls = [(0.3 + 0.1 * k, 3.0 + 0.3 * k, 0.4 * k, {"bands": 3, "gibbs": True, "dering": False,
                                                           "groundAlbedo": [0.5, 0.4, 0.3]}) for k in range(6)]
        reply = node.run(module_dir, [list(c) for c in calls], module="mutated.mjs")
        assert light_error(sky, calls, reply["results"]) > CONTROL_MARGIN * JS_TOLERANCE


# --------------------------------------------------------------------------- #
class TestModuleText:
    def test_self_contained(self, module_dir: Path) -> None:
        source = (module_dir / "sky_sh.mjs").read_text()
        assert not re.search(r"^\s*import\b|\brequire\(|\bfetch\(", source, re.MULTILINE)
        assert source.endswith("\n")

    def test_export_source_writes_the_module(self, sky: SkySH, module_dir: Path) -> None:
        assert export_source(sky, "js") == (module_dir / "sky_sh.mjs").read_text()  # all the file's bands
        with pytest.raises(ValueError, match="engine"):
            export_source(sky, "js", engine="threejs")
        with pytest.raises(ValueError, match="bands"):
            module_source(sky, bands=8)

    def test_declarations_match_the_module(self, module_dir: Path, node: NodeServer) -> None:
        """The .d.ts declares exactly what the module exports; tsc checks it when installed."""
        text = (module_dir / "sky_sh.d.mts").read_text()
        reply = node.run(module_dir, [])
        declared = sorted(set(re.findall(r"^export declare (?:const|function) (\w+)", text, re.MULTILINE)))
        assert declared == reply["exports"]
        union = re.search(r"^export type Engine = (.*);$", text, re.MULTILINE).group(1)
        assert union == (" | ".join(json.dumps(e) for e in reply["engines"]) or "never")
        for open_, close in ("()", "{}", "[]", "<>"):
            assert text.count(open_) == text.count(close)
        statements = [line for line in text.splitlines() if line and not line.startswith((" ", "//", "/**", " *", "}", ")"))]
        assert all(line.startswith("export ") for line in statements), statements

    def test_declarations_file_name(self) -> None:
        """TypeScript resolves an .mjs import to .d.mts only (checked by test_declarations_type_check)."""
        assert declarations_path(Path("out/sky.mjs")) == Path("out/sky.d.mts")
        assert declarations_path(Path("sky.js")) == Path("sky.d.ts")

    @pytest.mark.late  # waits for the tsc run started in the background when the module began
    def test_declarations_type_check(self, type_check: subprocess.Popen | None) -> None:
        """The usage type-checks and its negative control (a wrong option type) does not: one tsc run of both files,
        every error located in bad.ts (none in usage.ts or the declarations, none unlocated), at least one there."""
        if type_check is None:
            pytest.skip(SKIP_NO_TSC)
        out, err = type_check.communicate(timeout=TSC_TIMEOUT_S)
        text = out + err
        located = [Path(name).name for name in re.findall(r"^(\S+?)\(\d+,\d+\): error TS\d+", text, re.MULTILINE)]
        assert type_check.returncode != 0 and located, text  # the negative control fails
        assert set(located) == {"bad.ts"} and len(located) == len(re.findall(r"error TS\d+", text)), text


def figures() -> list[dict[str, Any]]:
    """The measured worst error of the module against the runtime (``python tests/export/test_export_js.py``)."""
    sky = SkySH.load()
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        (directory / "sky_sh.mjs").write_text(module_source(sky))
        node = NodeServer(directory)
        calls = random_calls(RANDOM_INPUTS)
        reply = node.run(directory, [list(c) for c in calls])
        errors = [
            dc_relative_error(np.array(r["values"]).reshape(-1, 3), python_reference(sky, *c))
            for c, r in zip(calls, reply["results"])
        ]
        rows = [{"measure": "max |js - runtime| / |DC|, worst channel", "inputs": len(calls), "error": max(errors)}]
        lit = light_calls(LIGHT_INPUTS)
        rows.append({"measure": "the same with the sun and the ground (engines: over gain x |DC|)", "inputs": len(lit),
                     "error": light_error(sky, lit, node.run(directory, [list(c) for c in lit])["results"])})
        table = table_calls()
        worst, refused, tables = table_errors(sky, table, node.run(directory, [list(c) for c in table])["results"])
        rows.append({"measure": "every irradianceTable setting against irradiance_table (engines: over gain x |DC|)",
                     "inputs": len(table), "refused_by_both": refused, "taking_the_table": tables, "error": worst})
        for name, bands in engine_cases():
            worst, control = engine_error(sky, node, directory, name, bands)
            rows.append({"measure": "max |js engine - engines.convert| / (gain x |DC|)", "engine": name, "bands": bands,
                         "error": worst, "unconverted_control": control})
        node.close()
    return rows


if __name__ == "__main__":
    for row in figures():
        print(json.dumps(row))
    sys.exit(0)
