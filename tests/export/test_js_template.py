"""
Tests of the JavaScript export's source files as they stand: ``skysh/export/templates/js_module.mjs``, ``.d.mts``
=================================================================================================================

The module is fixed source with one data object, ``DATA``, that :func:`skysh.export.js.module_source` fills.
Here the template is filled with a SMALL hand-made data object instead (:data:`FIXTURE`: a synthetic sky table of
Chebyshev degrees (2, 1), a synthetic irradiance table and sun table, a made-up engine ``"small"`` whose plans
skip a band count; the Perez, zenith-luminance, Kasten and deringing constants are skysh's own,
:meth:`TestFixture.test_constants_are_skyshs`), run under node, and compared with an independent evaluation of
the same numbers written here from the algorithm's description (the header of the module and
:mod:`skysh.export.lights`): Chebyshev terms as ``cos(k acos x)``, the sums by :func:`numpy.einsum`, the luminance
scale by :func:`skysh.model.preetham.luminance_scale_unchecked` (so the module's zenith luminance is Python's),
the deringing by :func:`skysh.post.dering.dering`, the engine map as a dense matrix.

The TypeScript declarations, filled with the same words, are type-checked by the pinned ``tsc`` of
``tests/js/node_modules`` (skipped naming ``npm ci --prefix tests/js`` without it) with a usage that must pass and
a negative control that must not.

Also (no node): the templates' holes are the ones :mod:`skysh.export.js` fills, the real module's data object is
JSON whose numbers are :func:`skysh.export.tables.export_tables`' exactly, and the zenith luminance and Kasten's air
mass are written once in the package's JavaScript (the viewer's page takes the module's).

Error measure: the largest |js - reference| of a call over the largest |reference| of that call.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import subprocess
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import SKIP_NO_NODE, SKIP_NO_TSC

from skysh import SkySH
from skysh.app import viewer
from skysh.export import dering as export_dering
from skysh.export import template
from skysh.export.js import DECLARATIONS_TEMPLATE, DERING_TEMPLATE, MODULE_TEMPLATE, module_source
from skysh.export.tables import engine_plan, export_tables
from skysh.model import preetham
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

NODE: str | None = shutil.which("node")
TSC: Path = Path(__file__).parents[1] / "js" / "node_modules" / ".bin" / "tsc"
"""The pinned TypeScript (tests/js/package-lock.json)."""

FIXTURE: Path = Path(__file__).with_name("data") / "js_small_data.json"
"""The small data object the template is run with (JSON: also the JavaScript literal the template takes)."""

WORDS: dict[str, str] = {
    "VERSION": "0.0.0-small", "COMMAND_OPTIONS": " --bands 3", "MAX_BANDS": "3", "DEFAULT_BANDS": "3",
    "ENGINE_LIST": '"small"', "SUN_ZENITH_DOMAIN": "[0, pi/2]", "TURBIDITY_DOMAIN": "[2.5, 6]",
}
"""The header's words for the small module (the module's holes but DATA)."""

DECLARATION_WORDS: dict[str, str] = {
    "VERSION": "0.0.0-small", "COMMAND_OPTIONS": " --bands 3", "MAX_BANDS": "3", "DEFAULT_BANDS": "3",
    "ENGINE_UNION": '"small"', "TURBIDITY_DOMAIN": "[2.5, 6]",
}
"""The declarations' holes for the small module."""

TOLERANCE: float = 1e-13
"""Module against the reference, relative to the call's largest value: the same doubles, summed in another order,
the Chebyshev recurrence against cos(k acos x), Math.tan/exp/pow against numpy's (measured 6e-16 for the sky, 9e-15
with the sun, whose exp of ~11.4 (ln lux) the rounding of its argument scales)."""

CONTROL_MARGIN: float = 1e3
"""A negative control misses by this factor times the tolerance."""

SEED: int = 20251202

RUNNER: str = r"""
import { pathToFileURL } from "node:url";
import { readFileSync } from "node:fs";
const request = JSON.parse(readFileSync(0, "utf8"));
const m = await import(pathToFileURL(request.module).href);
const decode = (v) => (v !== null && typeof v === "object" && "$float" in v ? Number(v.$float) : v);
const results = request.calls.map(([name, ...args]) => {
  try {
    const value = m[name](...args.map(decode));
    return { value: name === "sunLight" ? [...value.direction, ...value.rgb] : value };
  } catch (error) {
    return { error: error.constructor.name, message: String(error.message) };
  }
});
process.stdout.write(JSON.stringify({ results, exports: Object.keys(m).sort(), engines: m.ENGINES,
  maxBands: m.MAX_BANDS, version: m.SKYSH_VERSION, domains: [m.SUN_ZENITH_DOMAIN, m.TURBIDITY_DOMAIN] }));
"""
"""Runs the calls ``[name, ...args]`` of stdin's {module, calls} on that module's exports; prints the results (a
thrown error as its class and message), the module's exports, ENGINES, MAX_BANDS, SKYSH_VERSION and domains."""

NODE_TIMEOUT_S: float = 120.0
"""Hang guard of a node run (well under a second normally)."""

integration = pytest.mark.integration
needs_node = pytest.mark.skipif(NODE is None, reason=SKIP_NO_NODE)


@pytest.fixture(scope="module")
def data() -> dict[str, Any]:
    return json.loads(FIXTURE.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def small_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder with the template filled with the fixture (small.mjs), its declarations (small.d.mts) and the runner."""
    folder = tmp_path_factory.mktemp("js_template")
    (folder / "small.mjs").write_text(template.fill(MODULE_TEMPLATE, **WORDS, DATA=FIXTURE.read_text(encoding="utf-8"),
                                                     DERING=template.text(DERING_TEMPLATE)))
    (folder / "small.d.mts").write_text(template.fill(DECLARATIONS_TEMPLATE, **DECLARATION_WORDS))
    (folder / "runner.mjs").write_text(RUNNER)
    return folder


def run(folder: Path, calls: list[list[Any]], module: str = "small.mjs") -> dict[str, Any]:
    """Run ``calls`` on ``folder / module`` in one node process (non-finite floats travel as {"$float": text})."""
    assert NODE is not None
    encoded = [[{"$float": repr(a).replace("inf", "Infinity").replace("nan", "NaN")}
                if isinstance(a, float) and not math.isfinite(a) else a for a in call] for call in calls]
    done = subprocess.run([NODE, str(folder / "runner.mjs")], input=json.dumps({"module": str(folder / module),
                          "calls": encoded}), capture_output=True, text=True, timeout=NODE_TIMEOUT_S, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


# --------------------------------------------------------------------------- #
# The reference: the fixture's numbers evaluated as the algorithm is described
# --------------------------------------------------------------------------- #
def chebyshev(v: float, degree: int) -> np.ndarray:
    """T_0 .. T_degree at v clamped to [-1, 1], as cos(k acos v) (not the module's recurrence)."""
    return np.cos(np.arange(degree + 1) * math.acos(min(max(v, -1.0), 1.0)))


def rows_at(data: dict[str, Any], ts: float, t: float, key: str = "table") -> np.ndarray:
    """(rows, 3): sum_ij T_i(x) T_j(y) of a table of the data object laid out as TABLE."""
    (dx, dy), (xs, xo), (ys, yo) = data["degrees"], data["x"], data["y"]
    w = np.outer(chebyshev(ts * xs - xo, dx), chebyshev(math.log(t) * ys - yo, dy)).ravel()
    return np.einsum("q,rqc->rc", w, np.array(data[key]).reshape(-1, w.size, 3))


def rotated(acc: np.ndarray, n: int, phi: float, zonal: np.ndarray) -> np.ndarray:
    """(n^2, 3): Habel eq. (4), the stored m >= 0 rows turned to azimuth phi, the m = 0 ones times zonal[l]."""
    out = np.zeros((n * n, 3))
    for l in range(n):
        for m in range(-l, l + 1):
            factor = math.cos(m * phi) if m >= 0 else math.sin(-m * phi)
            out[l * (l + 1) + m] = acc[l * (l + 1) // 2 + abs(m)] * factor * (zonal[l] if m == 0 else 1.0)
    return out


def sun_rgb(data: dict[str, Any], ts: float, t: float) -> np.ndarray:
    """The sun's RGB (lux): Kasten's air mass, the sun table's Chebyshev sum of ln XYZ, the XYZ -> RGB matrix."""
    lights, c = data["lights"], data["lights"]["constants"]
    m = 1.0 / (math.cos(ts) + c["am_a"] * (c["am_b"] - math.degrees(ts)) ** c["am_neg_c"])
    sdx, sdy = lights["sunDegrees"]
    w = np.outer(chebyshev((m - c["m0"]) * c["sx_scale"] - 1.0, sdx),
                 chebyshev((t - c["sun_tmin"]) * c["sy_scale"] - 1.0, sdy)).ravel()
    return np.array(lights["rgbFromXyz"]).reshape(3, 3) @ np.exp(w @ np.array(lights["sunTable"]).reshape(-1, 3))


def add_lights(data: dict[str, Any], frame: tuple[float, float, float], n: int, zonal: np.ndarray, sun: bool,
               albedo: np.ndarray | None, e_sky: np.ndarray, out: np.ndarray) -> None:
    """The ground (L = albedo (E_sky + cos ts RGB_sun) / pi, zonal, Gibbs-filtered) and the windowed sun, into out."""
    ts, t, phi = frame
    lights = data["lights"]
    rgb = sun_rgb(data, ts, t) if sun else np.zeros(3)
    if albedo is not None:
        light = albedo * (e_sky + math.cos(ts) * rgb) / math.pi
        for l in range(n):
            out[l * (l + 1)] += lights["ground"][l] * zonal[l] * light
    if not sun:
        return
    width = 2 * data["maxBands"]
    trig = np.array(lights["trig"]).reshape(-1, width)
    window = lights["windows"][n * (n - 1) // 2 : n * (n + 1) // 2]
    q = np.arange(n)
    for l in range(n):
        for m in range(-l, l + 1):
            r = l * (l + 1) // 2 + abs(m)
            y = trig[r, :n] @ np.cos(q * ts) + trig[r, width // 2 : width // 2 + n] @ np.sin(q * ts)
            rot = math.cos(m * phi) if m >= 0 else math.sin(-m * phi)
            out[l * (l + 1) + m] += y * window[l] * rot * np.maximum(rgb, lights["constants"]["clamp"])


def settings(data: dict[str, Any], options: dict[str, Any]) -> tuple[int, bool, bool, bool]:
    """(bands, gibbs, dering, table) of options by the header's rules (defaults by intent)."""
    n, diffuse = options.get("bands", data["defaultBands"]), options.get("irradiance", False) or "engine" in options
    gibbs, deringing, table = options.get("gibbs"), options.get("dering"), options.get("irradianceTable")
    if table is None:
        table = data["irradiance"] is not None and diffuse and n == 3 and gibbs is not True and deringing is not False
    gibbs = not (diffuse or table) if gibbs is None else gibbs
    deringing = not table and (diffuse if deringing is None else deringing)
    return n, gibbs, deringing, table


def reference(data: dict[str, Any], ts: float, t: float, phi: float, options: dict[str, Any]) -> np.ndarray:
    """The module's result for one call, flat: the sky (or the irradiance table), dering, lights, factor, engine."""
    n, gibbs, deringing, table = settings(data, options)
    phi = math.fmod(phi, 2.0 * math.pi)
    zonal = np.array(data["gibbs"][n * (n - 1) // 2 : n * (n + 1) // 2]) if gibbs else np.ones(n)
    scale = preetham.luminance_scale_unchecked(ts, t)
    out = rotated(rows_at(data, ts, t, "irradiance" if table else "table"), n, phi, zonal) * scale
    if deringing:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out = dering.dering(out, "irradiance")[0]
    albedo = options.get("groundAlbedo", 0.0)
    albedo = None if np.all(np.asarray(albedo) == 0.0) else np.broadcast_to(np.asarray(albedo, dtype=float), (3,))
    e_sky = data["lights"]["constants"]["hf"] * scale * rows_at(data, ts, t)[1]  # the unfiltered sky's c_10
    add_lights(data, (ts, t, phi), n, zonal, options.get("sun", False), albedo, e_sky, out)
    plan = dict(data["engines"])[options["engine"]][n] if "engine" in options else None
    factor = plan["band"] if plan else data["lobe"] if options.get("irradiance") else np.ones(n)
    flat = (out * np.asarray(factor)[sh.band_of_index(n)][:, None]).ravel()
    if plan is None:
        return flat
    matrix = np.zeros((len(plan["offset"]), flat.size))
    for p in range(len(plan["offset"])):
        for k in range(plan["start"][p], plan["start"][p + 1]):
            matrix[p, plan["index"][k]] = plan["factor"][k]
    return matrix @ flat + np.array(plan["offset"])


def random_calls(rng: np.random.Generator, count: int, choose: Any) -> list[tuple[float, float, float, dict]]:
    """count frames over the domain (azimuths far outside [0, 2 pi] too) with options from choose(k)."""
    return [(float(rng.uniform(0.0, math.pi / 2.0)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-40.0, 40.0)),
             choose(k)) for k in range(count)]


def worst_error(data: dict[str, Any], folder: Path, calls: list[tuple[float, float, float, dict]],
                reference_options: Any = None) -> float:
    """The worst error of the module's calls against the reference (of reference_options(options) if given)."""
    reply = run(folder, [["coefficients", *call] for call in calls])
    worst = 0.0
    for (ts, t, phi, options), result in zip(calls, reply["results"], strict=True):
        assert "value" in result, (options, result)
        ref = reference(data, ts, t, phi, reference_options(options) if reference_options else options)
        worst = max(worst, float(np.abs(np.array(result["value"]) - ref).max() / np.abs(ref).max()))
    return worst


# --------------------------------------------------------------------------- #
class TestFixture:
    def test_constants_are_skyshs(self, data: dict[str, Any]) -> None:
        """The fixture's model constants are skysh's: the comparisons with skysh's Python then mean something."""
        np.testing.assert_array_equal(data["perezY"], preetham.PEREZ_Y.ravel())
        assert data["zenithLuminance"] == list(preetham.ZENITH_LUMINANCE)
        block = data["dering"]
        assert block["windows"] == [dering.window_table(n, "irradiance").ravel().tolist() for n in (1, 2, 3)]
        assert block["rows"] == 7 and block["certificate"] is None  # 3 bands: no certificate
        assert block["exact"] == [dering.exact_target(n) for n in (1, 2, 3)]
        assert block["lattice"] == [1 / dering.tolerance(n) for n in (1, 2, 3)]
        assert block["kernel"] == sh.cosine_lobe(3).tolist()
        assert block["basis"] == [sh.Y00, sh.K_LINEAR, sh.K_PRODUCT, sh.K_ZONAL, sh.K_SECTORAL]
        assert block["guards"] == [shmin.TINY, shmin.FLOOR, shmin.POLE, shmin.ALLOWANCE]
        assert block["steps"] == shmin.NEWTON_STEPS and block["subnormal"] == dering.SUBNORMAL_EXPONENT

    def test_holes_are_the_ones_filled(self) -> None:
        assert template.holes(MODULE_TEMPLATE) == set(WORDS) | {"DATA", "DERING"}
        assert not template.holes(DERING_TEMPLATE)  # fixed code, embedded whole
        assert template.holes(DECLARATIONS_TEMPLATE) == set(DECLARATION_WORDS)
        assert max(len(template.holes(MODULE_TEMPLATE)), len(template.holes(DECLARATIONS_TEMPLATE))) <= template.MAX_HOLES

    def test_the_real_module_data_is_export_tables(self, sky: SkySH) -> None:
        """The data object of module_source is JSON; its tables are export_tables' exactly (shortest round-trip
        doubles), laid out as the module reads them; the rest of the module is the template's text."""
        source, tables = module_source(sky, bands=3), export_tables(sky, 3)
        found = re.search(r"^const DATA = (\{\n.*?\n\});$", source, re.MULTILINE | re.DOTALL)
        assert found is not None
        real = json.loads(found.group(1))
        rows = tables.table.reshape(-1, tables.table.shape[2], 3).transpose(1, 0, 2).ravel()
        assert real["table"] == rows.tolist() and real["degrees"] == list(tables.degrees)
        assert real["lights"]["sunTable"] == tables.lights.sun_table.ravel().tolist()
        assert tables.irradiance is not None
        assert real["irradiance"] == tables.irradiance.reshape(-1, 6, 3).transpose(1, 0, 2).ravel().tolist()
        name, plans = real["engines"][0]
        plan = engine_plan(name, 3)
        assert plans[3]["index"] == [q for p in range(plan.offset.size) for q, _ in plan.terms(p)]
        assert plans[3]["factor"] == [v for p in range(plan.offset.size) for _, v in plan.terms(p)]
        assert plans[3]["offset"] == plan.offset.tolist() and plans[3]["band"] == plan.band_factor.tolist()
        code = template.text(MODULE_TEMPLATE).split("{{DATA}}")[1].replace("{{DERING}}", template.text(DERING_TEMPLATE))
        assert source.endswith(code)  # the code: the template's text, its deringing file embedded whole

    def test_the_certificate_numbers_are_python_s(self, sky: SkySH) -> None:
        """At 7 bands the module's certificate constants are Python's (skysh.sh.minimum, skysh.post.dering), passed, not
        recomputed in JavaScript: the final slack, the Fibonacci angle, the band norms and the recurrence's factors."""
        source = module_source(sky, bands=7)
        found = re.search(r"^const DATA = (\{\n.*?\n\});$", source, re.MULTILINE | re.DOTALL)
        assert found is not None
        block = json.loads(found.group(1))["dering"]
        cert, lists = block["certificate"], export_dering.certificate_lists(7)
        assert block["subnormal"] == dering.SUBNORMAL_EXPONENT and block["lattice"][4:] == [32, 32, 32]
        assert cert["final"] == (shmin.COVER_RADIUS / shmin.SPLIT**shmin.LEVELS) ** 2
        assert cert["golden"] == 3.0 - math.sqrt(5.0) and cert["directions"] == shmin.DIRECTIONS
        assert cert["bandNorm"] == [math.sqrt((2 * l + 1) / (4 * math.pi)) for l in range(7)] == lists["BAND_NORM"]
        assert cert["next"] == lists["NEXT"] and cert["diag"] == lists["DIAG"] and cert["a"] == lists["RA"]
        code = template.text(MODULE_TEMPLATE)
        assert "-1022" not in code and "Math.sqrt(5" not in code and "4.0 * Math.PI" not in code

    def test_formulas_written_once_in_javascript(self) -> None:
        """The zenith luminance (the only tan) and Kasten's air mass are written once in the package's JavaScript:
        the module's; the viewer's page (sky.js) takes the zenith luminance from the module it inlines."""
        sources = {path.name: path.read_text(encoding="utf-8") for path in
                   [*template.TEMPLATE_DIR.glob("*.mjs"), *viewer.WEB_DIR.glob("*.js")]}
        assert sum(text.count("Math.tan(") for text in sources.values()) == 1
        assert sum(text.count("Math.pow(AM_B - ts * DEG, AM_NEG_C)") for text in sources.values()) == 1
        assert "zenithLuminance(ts, t)" in sources["sky.js"] and "Math.tan(" in sources[MODULE_TEMPLATE]


# --------------------------------------------------------------------------- #
@integration
@needs_node
class TestUnderNode:
    def test_exports_and_constants(self, data: dict[str, Any], small_dir: Path) -> None:
        reply = run(small_dir, [["engineLayout", "small", 3], ["engineLayout", "small"], ["engineLayout", "small", 1]])
        assert reply["exports"] == sorted(["coefficients", "sunLight", "engineLayout", "SKYSH_VERSION", "MAX_BANDS",
                                           "ENGINES", "SUN_ZENITH_DOMAIN", "TURBIDITY_DOMAIN"])
        assert (reply["engines"], reply["maxBands"], reply["version"]) == (["small"], 3, "0.0.0-small")
        assert reply["domains"] == [data["sunZenithDomain"], data["turbidityDomain"]]
        layouts = [r["value"] for r in reply["results"]]
        assert layouts[0] == layouts[1] == {"shape": [2, 2], "labels": ["p", "q"]}
        assert layouts[2] == {"shape": [2], "labels": ["a", "b"]}

    def test_the_sky_matches_the_reference(self, data: dict[str, Any], small_dir: Path) -> None:
        rng = np.random.default_rng(SEED)
        calls = random_calls(rng, 180, lambda k: {"bands": 1 + k % 3, "gibbs": k % 2 == 0, "irradiance": k % 4 < 2,
                                                  "dering": False, "irradianceTable": False})
        assert worst_error(data, small_dir, calls) < TOLERANCE

    def test_negative_control_the_other_gibbs_setting(self, data: dict[str, Any], small_dir: Path) -> None:
        rng = np.random.default_rng(SEED + 1)
        calls = random_calls(rng, 20, lambda k: {"bands": 3, "gibbs": True, "dering": False})
        assert worst_error(data, small_dir, calls, lambda o: dict(o, gibbs=False)) > CONTROL_MARGIN * TOLERANCE

    def test_the_irradiance_table_by_intent(self, data: dict[str, Any], small_dir: Path) -> None:
        """3-band irradiance and engines take the table by default, true takes it for radiance too."""
        rng = np.random.default_rng(SEED + 2)
        choices = [{"irradiance": True}, {"irradianceTable": True}, {"engine": "small"}, {"irradiance": True, "gibbs": True},
                   {"irradiance": True, "dering": False}, {"irradiance": True, "irradianceTable": False}]
        calls = random_calls(rng, 60, lambda k: {"bands": 3, **choices[k % len(choices)]})
        assert worst_error(data, small_dir, calls) < TOLERANCE
        assert worst_error(data, small_dir, calls[:6], lambda o: dict(o, irradianceTable=False)) > CONTROL_MARGIN * TOLERANCE

    def test_deringing_matches_the_runtimes(self, data: dict[str, Any], small_dir: Path) -> None:
        """The module's deringing at 1..3 bands picks skysh.post.dering.dering's window (the fixture's sky rings)."""
        rng = np.random.default_rng(SEED + 3)
        calls = random_calls(rng, 120, lambda k: {"bands": 1 + k % 3, "dering": True, "irradianceTable": False,
                                                  "gibbs": k % 2 == 0, "irradiance": k % 4 < 2})
        assert worst_error(data, small_dir, calls) < TOLERANCE
        windowed = 0
        for ts, t, phi, options in calls:
            got, plain = reference(data, ts, t, phi, options), reference(data, ts, t, phi, dict(options, dering=False))
            windowed += float(np.abs(got - plain).max()) > CONTROL_MARGIN * TOLERANCE * float(np.abs(got).max())
        assert windowed > len(calls) // 10  # real windows are compared, not only the identity (measured: 61 of 120)

    def test_the_sun_and_the_ground(self, data: dict[str, Any], small_dir: Path) -> None:
        rng = np.random.default_rng(SEED + 4)

        def choose(k: int) -> dict[str, Any]:
            options: dict[str, Any] = {"bands": 1 + k % 3, "gibbs": k % 2 == 0, "sun": k % 3 != 1,
                                       "irradiance": k % 4 < 2, "dering": k % 3 == 2, "irradianceTable": False}
            if k % 5:
                options["groundAlbedo"] = 0.3 if k % 5 == 1 else [float(v) for v in rng.uniform(0.0, 1.0, 3)]
            if k % 7 == 0:
                options.update(engine="small", bands=1 + 2 * (k % 2), irradiance=False, dering=False)
            return options

        calls = random_calls(rng, 150, choose)
        assert worst_error(data, small_dir, calls) < TOLERANCE

    def test_sun_light(self, data: dict[str, Any], small_dir: Path) -> None:
        rng = np.random.default_rng(SEED + 5)
        frames = [(float(z), float(t), float(a)) for z, t, a in
                  zip(rng.uniform(0.0, math.pi / 2.0, 30), rng.uniform(2.5, 6.0, 30), rng.uniform(-50.0, 50.0, 30))]
        reply = run(small_dir, [["sunLight", *frame] for frame in frames])
        for (ts, t, phi), result in zip(frames, reply["results"], strict=True):
            phi = math.fmod(phi, 2.0 * math.pi)
            direction = [math.sin(ts) * math.cos(phi), math.sin(ts) * math.sin(phi), math.cos(ts)]
            np.testing.assert_allclose(result["value"][:3], direction, rtol=0.0, atol=TOLERANCE)
            rgb = sun_rgb(data, ts, t)
            assert np.abs(np.array(result["value"][3:]) - rgb).max() < TOLERANCE * np.abs(rgb).max()

    def test_engine_map_is_the_sparse_table(self, data: dict[str, Any], small_dir: Path) -> None:
        rng = np.random.default_rng(SEED + 6)
        calls = random_calls(rng, 40, lambda k: {"engine": "small", "bands": 1 + 2 * (k % 2), "gibbs": k % 4 < 2})
        assert worst_error(data, small_dir, calls) < TOLERANCE

    @pytest.mark.parametrize(("call", "kind", "start"), [
        ([0.5, 3.0, 0.0, {"engine": "small", "bands": 2}], "RangeError", "bands must be an integer in [1, 3] for engine "
                                                                         '"small" (the bands it takes: 1, 3)'),
        ([0.5, 3.0, 0.0, {"engine": "big"}], "RangeError", 'engine must be one of "small", got "big"'),
        ([0.5, 3.0, 0.0, {"bands": 2, "dering": 1}], "TypeError", "dering must be true or false"),
        ([0.5, 3.0, 0.0, {"bands": 2, "irradianceTable": True}], "RangeError", "irradianceTable: true needs bands 3"),
        ([0.5, 3.0, 0.0, {"engine": "small", "irradiance": True}], "RangeError", "irradiance must be false"),
        ([0.5, 6.5, 0.0], "RangeError", "turbidity must lie in [2.5, 6]"),
        ([0.5, 3.0, float("nan")], "RangeError", "sunAzimuth must be finite"),
        ([0.5, 3.0, 0.0, {"bands": 4}], "RangeError", "bands must be an integer in [1, 3]"),
        ([0.5, 3.0, 0.0, {"sun": "yes"}], "TypeError", "sun must be true or false"),
        ([0.5, 3.0, 0.0, {"out": [0.0]}], "TypeError", "out must be an Array or Float64Array of length 27"),
        ([0.5, 3.0, 0.0, [1]], "TypeError", "options must be a plain object"),
    ])
    def test_refusals_name_the_parameter(self, small_dir: Path, call: list[Any], kind: str, start: str) -> None:
        result = run(small_dir, [["coefficients", *call]])["results"][0]
        assert result.get("error") == kind and result["message"].startswith(start), result

    def test_declarations_type_check(self, small_dir: Path) -> None:
        """The declarations, filled for the small module, type-check a usage under --strict; a wrong option does not."""
        if not TSC.exists():
            pytest.skip(SKIP_NO_TSC)
        (small_dir / "usage.ts").write_text(
            'import { coefficients, engineLayout, sunLight, ENGINES, MAX_BANDS, type Engine } from "./small.mjs";\n'
            'const engine: Engine = "small";\n'
            "const c: number[] = coefficients(0.5, 3, 1, { bands: 3, irradiance: true, groundAlbedo: [0.1, 0.2, 0.3] });\n"
            "const t: Float64Array = coefficients(0.5, 3, 1, { engine, out: new Float64Array(4) });\n"
            "const n: number = c.length + t.length + ENGINES.length + MAX_BANDS + engineLayout(engine, 1).shape[0];\n"
            "void n; void sunLight(0.5, 3).rgb[0];\n")
        (small_dir / "bad.ts").write_text('import { coefficients } from "./small.mjs";\n'
                                          'coefficients(0.5, 3, 1, { engine: "big" });\n')
        done = subprocess.run([str(TSC), "--noEmit", "--pretty", "false", "--strict", "--module", "nodenext",
                               "--moduleResolution", "nodenext", "--target", "es2022", "--skipDefaultLibCheck", "usage.ts",
                               "bad.ts"], cwd=small_dir, capture_output=True, text=True, timeout=NODE_TIMEOUT_S, check=False)
        located = re.findall(r"^(\S+?)\(\d+,\d+\): error TS\d+", done.stdout + done.stderr, re.MULTILINE)
        assert done.returncode != 0 and located and set(located) == {"bad.ts"}, done.stdout + done.stderr
