"""
Tests of skysh.export_js: the JavaScript runtime module against the Python runtime, run in node.

Every comparison runs ONE node process per test that evaluates a batch of
calls sent as JSON (:func:`run_node`); NaN and infinities travel as
``{"$float": "NaN"}``. Doubles cross JSON exactly (both sides print the
shortest round-trip text).

Error measure (as ``tests/test_export.py``): the largest |js - python| of a
result over |DC| of the same channel, worst channel. For engines the scale is
the largest |DC| of the radiance times the largest absolute row sum of the
engine's map (the most a DC-sized input can become in the engine's numbers).

Skipped without node; the engine tests are skipped while ``skysh.engines`` does
not exist. ``python tests/test_export_js.py`` prints the measured errors.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from skysh import SkySH
from skysh.export import export_source
from skysh.export_js import declarations, declarations_path, module_source

NODE: str | None = shutil.which("node")
pytestmark = pytest.mark.skipif(NODE is None, reason="node is not installed")

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
import { readFileSync } from "node:fs";
import { pathToFileURL } from "node:url";
const request = JSON.parse(readFileSync(0, "utf8"));
const m = await import(pathToFileURL(request.module).href);
const decode = (v) => (v !== null && typeof v === "object" && "$float" in v ? Number(v.$float) : v);
const results = request.calls.map((call) => {
  try {
    const args = call.map((v) => (v !== null && typeof v === "object" && !("$float" in v)
      ? Object.fromEntries(Object.entries(v).map(([k, x]) => [k, decode(x)])) : decode(v)));
    const out = m.coefficients(...args);
    return { values: Array.from(out), plain: Array.isArray(out) };
  } catch (error) {
    return { error: error.constructor.name, message: String(error.message) };
  }
});
process.stdout.write(JSON.stringify({ results, exports: Object.keys(m).sort(), engines: m.ENGINES,
  maxBands: m.MAX_BANDS }));
"""


@pytest.fixture(scope="module")
def sky() -> SkySH:
    return SkySH.load()


@pytest.fixture(scope="module")
def module_dir(sky: SkySH, tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("js")
    (directory / "sky_sh.mjs").write_text(module_source(sky))
    (directory / declarations_path(Path("sky_sh.mjs")).name).write_text(declarations(sky))
    (directory / "runner.mjs").write_text(RUNNER)
    return directory


def encode(value: Any) -> Any:
    """A call argument as JSON: non-finite floats as {"$float": text}."""
    if isinstance(value, float) and not math.isfinite(value):
        return {"$float": str(value).replace("inf", "Infinity").replace("nan", "NaN")}
    if isinstance(value, dict):
        return {k: encode(v) for k, v in value.items()}
    return value


def run_node(directory: Path, calls: list[list[Any]], module: str = "sky_sh.mjs") -> dict[str, Any]:
    """Evaluate every call ``coefficients(*call)`` in one node process."""
    assert NODE is not None
    request = json.dumps({"module": str(directory / module), "calls": [[encode(a) for a in c] for c in calls]})
    done = subprocess.run([NODE, str(directory / "runner.mjs")], input=request, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def dc_relative_error(got: np.ndarray, ref: np.ndarray) -> float:
    """max over channels of max_i |got - ref| / |ref DC|, for (N*N, 3) arrays."""
    return float((np.abs(got - ref).max(axis=-2) / np.abs(ref[..., 0, :])).max())


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


def python_reference(sky: SkySH, ts: float, t: float, phi: float, options: dict[str, Any]) -> np.ndarray:
    """The runtime's result for the same options; the documented JS defaults written out:
    gibbs = !irradiance (the intent), dering as given."""
    irradiance = options.get("irradiance", False)
    gibbs = options.get("gibbs", not irradiance)
    return sky.coefficients(
        ts, t, phi, bands=options["bands"], gibbs=gibbs, dering=options["dering"], irradiance=irradiance
    )


# --------------------------------------------------------------------------- #
class TestAgainstRuntime:
    def test_random_inputs_match_the_python_runtime(self, sky: SkySH, module_dir: Path) -> None:
        calls = random_calls(RANDOM_INPUTS)
        reply = run_node(module_dir, [list(c) for c in calls])
        worst = 0.0
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            assert "values" in result, result
            assert result["plain"]
            got = np.array(result["values"]).reshape(-1, 3)
            worst = max(worst, dc_relative_error(got, python_reference(sky, ts, t, phi, options)))
        assert worst < JS_TOLERANCE

    def test_negative_control_fails(self, sky: SkySH, module_dir: Path) -> None:
        """The same comparison with the Gibbs setting flipped must fail: the test can fail."""
        calls = random_calls(21)
        reply = run_node(module_dir, [list(c) for c in calls])
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            if options["bands"] < 2:
                continue  # the filter is the identity for one band
            flipped = dict(options, gibbs=not options.get("gibbs", not options.get("irradiance", False)))
            got = np.array(result["values"]).reshape(-1, 3)
            assert dc_relative_error(got, python_reference(sky, ts, t, phi, flipped)) > CONTROL_MARGIN * JS_TOLERANCE

    @pytest.mark.parametrize("phi", [-12345.678, 1e6, -1e15, 2.0 * math.pi, -math.pi, 5e-324])
    def test_azimuth_is_reduced_as_the_runtime_does(self, sky: SkySH, module_dir: Path, phi: float) -> None:
        calls = [[0.7, 3.3, phi, {"bands": 7, "gibbs": False}]]
        got = np.array(run_node(module_dir, calls)["results"][0]["values"]).reshape(-1, 3)
        ref = sky.coefficients(0.7, 3.3, phi, bands=7, gibbs=False, dering=False)
        assert dc_relative_error(got, ref) < JS_TOLERANCE

    def test_domain_edges_are_accepted(self, sky: SkySH, module_dir: Path) -> None:
        calls = [[0.0, 2.5, 0.0, {"bands": 3, "dering": False}], [math.pi / 2.0, 6.0, 100.0, {"bands": 3, "dering": False}]]
        for (ts, t, phi, options), result in zip(calls, run_node(module_dir, calls)["results"]):
            got = np.array(result["values"]).reshape(-1, 3)
            assert dc_relative_error(got, python_reference(sky, ts, t, phi, options)) < JS_TOLERANCE

    def test_defaults(self, sky: SkySH, module_dir: Path) -> None:
        """Omitted arguments: azimuth 0, bands 3, gibbs = !irradiance, dering = irradiance where carried;
        the radiance defaults are the Python runtime's (the irradiance ones too where deringing is carried)."""
        carried = 3 in dering_bands(module_dir)
        reply = run_node(module_dir, [
            [0.4, 4.0], [0.4, 4.0, 0.0, {"bands": 3, "gibbs": True, "irradiance": False, "dering": False}],
            [0.4, 4.0, 0.0, {"irradiance": True}],
            [0.4, 4.0, 0.0, {"bands": 3, "gibbs": False, "irradiance": True, "dering": carried}],
        ])
        values = [r["values"] for r in reply["results"]]
        assert values[0] == values[1] and len(values[0]) == 27
        assert values[2] == values[3]
        got = np.array(values[0]).reshape(-1, 3)
        assert dc_relative_error(got, sky.coefficients(0.4, 4.0)) < JS_TOLERANCE
        if carried:
            got = np.array(values[2]).reshape(-1, 3)
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
    def test_dering_matches_the_runtime_window_for_window(self, sky: SkySH, module_dir: Path) -> None:
        rng = np.random.default_rng(SEED + 3)
        calls = [
            [float(rng.uniform(0.0, math.pi / 2.0)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-9.0, 9.0)),
             {"bands": 3, "dering": True, "gibbs": k % 2 == 0, "irradiance": k % 4 < 2}]
            for k in range(DERING_INPUTS)
        ]
        reply = run_node(module_dir, calls)
        worst, windowed = 0.0, 0
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            got = np.array(result["values"]).reshape(-1, 3)
            ref = python_reference(sky, ts, t, phi, options)
            worst = max(worst, dc_relative_error(got, ref))
            plain = python_reference(sky, ts, t, phi, dict(options, dering=False))
            windowed += dc_relative_error(ref, plain) > CONTROL_MARGIN * JS_TOLERANCE
        assert worst < JS_TOLERANCE
        assert windowed > DERING_INPUTS // 10  # the comparison covers real windows, not only identities

    def test_dering_with_engines(self, sky: SkySH, module_dir: Path) -> None:
        engines = pytest.importorskip("skysh.engines")
        names = [name for name, bands in engine_cases() if bands == 3]
        calls = [[0.2 + 0.1 * k, 2.5 + 0.3 * k, 1.0 - k, {"engine": name, "bands": 3}] for name in names for k in range(8)]
        reply = run_node(module_dir, calls)
        for (ts, t, phi, options), result in zip(calls, reply["results"]):
            radiance = sky.coefficients(ts, t, phi, bands=3, gibbs=False, dering=True)  # the engine defaults
            ref = np.asarray(engines.convert(radiance, options["engine"]), dtype=np.float64).reshape(-1)
            gain = float(np.abs(np.asarray(engines.engine_map(options["engine"], 3).matrix)).sum(axis=1).max())
            assert np.abs(np.array(result["values"]) - ref).max() / (gain * np.abs(radiance[0]).max()) < JS_TOLERANCE


def dering_bands(module_dir: Path) -> list[int]:
    """The band counts the module derings (its DERING_BANDS)."""
    source = (module_dir / "sky_sh.mjs").read_text()
    found = re.search(r"^const DERING_BANDS = Object.freeze\(\[([^\]]*)\]\)", source, re.MULTILINE)
    assert found is not None
    return [int(v) for v in found.group(1).split(",") if v.strip()]


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
]


class TestRefusals:
    def test_bad_values_throw_naming_the_parameter(self, sky: SkySH, module_dir: Path) -> None:
        reply = run_node(module_dir, [call for call, _, _ in BAD_CALLS])
        for (call, kind, name), result in zip(BAD_CALLS, reply["results"]):
            assert result.get("error") == kind, (call, result)
            assert result["message"].startswith(name) or f'"{name}"' in result["message"], (call, result)
        for call, _kind, _ in BAD_CALLS[:9]:  # the runtime refuses the same numbers
            with pytest.raises(ValueError):
                sky.coefficients(*call, bands=3)

    def test_unknown_engine_lists_the_valid_ones(self, module_dir: Path) -> None:
        reply = run_node(module_dir, [[0.5, 3.0, 0.0, {"engine": "godot"}]])
        for name in reply["engines"]:
            assert json.dumps(name) in reply["results"][0]["message"]

    def test_dering_refused_where_not_carried(self, module_dir: Path) -> None:
        reply = run_node(module_dir, [[0.5, 3.0, 0.0, {"bands": 7, "dering": True}]])
        if 7 not in dering_bands(module_dir):
            assert reply["results"][0]["error"] == "RangeError"
            assert reply["results"][0]["message"].startswith("dering")

    def test_bands_argument_limits_the_module(self, sky: SkySH, tmp_path: Path) -> None:
        (tmp_path / "sky_sh.mjs").write_text(module_source(sky, bands=2))
        (tmp_path / "runner.mjs").write_text(RUNNER)
        reply = run_node(tmp_path, [[0.5, 3.0, 0.0, {"bands": 3}], [0.5, 3.0, 0.0, {"dering": False}]])
        assert reply["maxBands"] == 2  # and the default bands (3) becomes 2
        assert reply["results"][0]["error"] == "RangeError" and reply["results"][0]["message"].startswith("bands")
        got = np.array(reply["results"][1]["values"]).reshape(-1, 3)
        assert dc_relative_error(got, sky.coefficients(0.5, 3.0, 0.0, bands=2, gibbs=True)) < JS_TOLERANCE


# --------------------------------------------------------------------------- #
def engine_cases() -> list[tuple[str, int]]:
    """(engine, bands) for every band count each engine takes (engine_map accepts)."""
    try:
        from skysh import engines
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


ENGINE_INPUTS: int = 12
"""Random inputs per (engine, bands, gibbs) case."""


def engine_error(sky: SkySH, module_dir: Path, name: str, bands: int) -> tuple[float, float]:
    """(worst error of the engine option, worst error of the unconverted skysh output) against convert(),
    over ENGINE_INPUTS random inputs for each Gibbs setting, in one node process."""
    from skysh import engines

    rng = np.random.default_rng(SEED + bands)
    calls = []
    for k in range(2 * ENGINE_INPUTS):
        options = {"engine": name, "bands": bands, "gibbs": k % 2 == 0, "dering": False}
        calls.append([float(rng.uniform(0, math.pi / 2)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-9, 9)), options])
    plain = [[*c[:3], {"bands": bands, "gibbs": c[3]["gibbs"], "dering": False}] for c in calls]
    reply = run_node(module_dir, calls + plain)
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


def is_padded_identity(name: str, bands: int) -> bool:
    """True when the engine's map is skysh's numbers as they are (zero-padded): no control can fail."""
    from skysh import engines

    emap = engines.engine_map(name, bands)
    matrix = np.asarray(emap.matrix)
    probe = np.random.default_rng(1).standard_normal(matrix.shape[1])
    padded = np.zeros(matrix.shape[0])
    padded[: min(probe.size, padded.size)] = probe[: padded.size]
    return bool(np.allclose(matrix @ probe + np.asarray(emap.offset), padded, rtol=0.0, atol=1e-14))


class TestEngines:
    @pytest.fixture(scope="class")
    def engines(self) -> Any:
        return pytest.importorskip("skysh.engines")

    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_engine_option_matches_convert(self, sky: SkySH, engines: Any, module_dir: Path, name: str, bands: int) -> None:
        worst, control = engine_error(sky, module_dir, name, bands)
        assert worst < JS_TOLERANCE
        if not is_padded_identity(name, bands):  # e.g. one band of a radiance engine is skysh's own DC
            assert control > CONTROL_MARGIN * JS_TOLERANCE  # negative control: skysh's own numbers fail

    def test_every_engine_is_in_the_module(self, engines: Any, module_dir: Path) -> None:
        reply = run_node(module_dir, [])
        assert reply["engines"] == [name for name in engines.ENGINES if any(n == name for n, _ in engine_cases())]

    def test_engine_refuses_irradiance_and_extra_bands(self, engines: Any, module_dir: Path) -> None:
        name = engines.ENGINES[0]
        high = engines.ENGINE_MAX_BANDS[name]
        calls = [[0.5, 3.0, 0.0, {"engine": name, "irradiance": True}]]
        if high < 7:
            calls.append([0.5, 3.0, 0.0, {"engine": name, "bands": high + 1}])
        reply = run_node(module_dir, calls)
        assert reply["results"][0]["error"] == "RangeError" and reply["results"][0]["message"].startswith("irradiance")
        if high < 7:
            message = reply["results"][1]["message"]
            assert reply["results"][1]["error"] == "RangeError" and message.startswith("bands") and name in message


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

    def test_declarations_match_the_module(self, module_dir: Path) -> None:
        """The .d.ts declares exactly what the module exports; tsc checks it when installed."""
        text = (module_dir / "sky_sh.d.mts").read_text()
        reply = run_node(module_dir, [])
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

    def test_declarations_type_check(self, module_dir: Path) -> None:
        local = Path(__file__).parent / "js" / "node_modules" / ".bin" / "tsc"
        tsc = str(local) if local.exists() else shutil.which("tsc")
        if tsc is None:
            pytest.skip("typescript (tsc) is not installed; the declarations are checked structurally")
        usage = module_dir / "usage.ts"
        usage.write_text(
            'import { coefficients, engineLayout, ENGINES, type CoefficientOptions } from "./sky_sh.mjs";\n'
            "const options: CoefficientOptions = { bands: 3, irradiance: true };\n"
            "const c: number[] = coefficients(0.5, 3, 1, options);\n"
            "const t: Float64Array = coefficients(0.5, 3, 1, { ...options, out: new Float64Array(27) });\n"
            "const n: number = c.length + t.length + ENGINES.length;\n"
            "if (ENGINES.length) { const shape: readonly number[] = engineLayout(ENGINES[0]).shape; void shape; }\n"
            "void n;\n"
        )
        bad = module_dir / "bad.ts"  # negative control: a wrong option type must not type-check
        bad.write_text('import { coefficients } from "./sky_sh.mjs";\ncoefficients(0.5, 3, 1, { bands: "3", gibs: true });\n')
        for source, ok in ((usage, True), (bad, False)):
            done = subprocess.run(
                [tsc, "--noEmit", "--strict", "--module", "nodenext", "--moduleResolution", "nodenext",
                 "--target", "es2022", str(source)], capture_output=True, text=True, cwd=module_dir, check=False,
            )
            assert (done.returncode == 0) == ok, done.stdout + done.stderr


def figures() -> list[dict[str, Any]]:
    """The measured worst error of the module against the runtime (``python tests/test_export_js.py``)."""
    import tempfile

    sky = SkySH.load()
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        (directory / "sky_sh.mjs").write_text(module_source(sky))
        (directory / "runner.mjs").write_text(RUNNER)
        calls = random_calls(RANDOM_INPUTS)
        reply = run_node(directory, [list(c) for c in calls])
        errors = [
            dc_relative_error(np.array(r["values"]).reshape(-1, 3), python_reference(sky, *c))
            for c, r in zip(calls, reply["results"])
        ]
        rows = [{"measure": "max |js - runtime| / |DC|, worst channel", "inputs": len(calls), "error": max(errors)}]
        for name, bands in engine_cases():
            worst, control = engine_error(sky, directory, name, bands)
            rows.append({"measure": "max |js engine - engines.convert| / (gain x |DC|)", "engine": name, "bands": bands,
                         "error": worst, "unconverted_control": control})
    return rows


if __name__ == "__main__":
    for row in figures():
        print(json.dumps(row))
    sys.exit(0)
