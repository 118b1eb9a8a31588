"""
Tests of the sun and the ground in the C, GLSL, HLSL and JSON exports (skysh.export.lights).

The C header is compiled once per build (a module fixture) with a harness that calls
``skysh_coefficients(..., sun, ground_albedo, out)`` and ``skysh_sun_light`` for every
input line; its numbers are compared with :meth:`skysh.SkySH.coefficients` (``sun=``,
``ground_albedo=``) and :meth:`skysh.SkySH.sun_light` over random inputs, the horizon and
the zenith included, every band count the tests build and every flag. The shaders are
compiled with glslangValidator when installed and their embedded tables read back; the
JSON's sun and ground blocks are evaluated independently (numpy's Chebyshev module) from
their own description. Every point also sets ``irradiance_table`` (by intent, 0, 1: the
certified irradiance table of 3-band exports, issue 18), so the table's sky is checked with
the sun and the ground too; the irradiance of the table (or the deringed sky) plus the sun
and the ground is never negative by its exact minimum (:func:`skysh.sh.minimum.exact_min`).
Negative controls: a header whose ground skips the Gibbs filter, one whose sun skips the
clamp of its colour, and one whose ground takes the table's c_10 instead of the sky's, must
fail the same comparisons; without deringing the sum dips below 0.

Error measure: as ``tests/export/test_export.py`` (largest |export - runtime| over |DC| of the same
channel, worst channel); the sun's light: |direction| difference, and the RGB difference over
the largest channel. ``python tests/export/test_export_lights.py`` prints the measured figures.

Compiles and validations go through the session's :class:`background.ToolRuns` (each distinct
one once: the harness, :data:`C_HARNESS`, is also tests/export/test_export.py's, so the builds of the
same headers are shared in one process); the module queues them all when it starts (:func:`_prefetch`).
The tests that compile or validate carry the ``integration`` marker.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import re
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from background import GLSLANG, RUN_DIR, ToolJob, ToolRuns, glslang_job, selected_names
from conftest import PLAIN_DIP, SKIP_NO_CC, SKIP_NO_GLSLANG, Exported, dc_relative_error

from skysh import SkySH
from skysh.export.c_like import export_source
from skysh.export.lights import BY_INTENT, light_tables
from skysh.export.tables import export_tables
from skysh.model import preetham
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

DOUBLE_TOLERANCE: float = 1e-12
"""The double C build against the runtime: the same arithmetic up to the Chebyshev recurrence, the order of
summation, pow and exp of the C library (measured 3.3e-14 of the DC, worst channel, with the sun)."""

FLOAT32_SUN_TOLERANCE: float = 1e-4
"""The float C build (standing in for a shader) with the sun: the sun's ln XYZ is a 91-term float32 sum of
magnitude about 12 near the horizon, then exp; measured 7.3e-6 of the DC, 1.7e-5 of the sun's largest channel."""

SUN_DIRECTION_TOLERANCE: float = 1e-15
"""The sun's unit vector: sin, cos and fmod of the same doubles (measured 0 to 1 ulp)."""

CONTROL_MARGIN: float = 1e3
"""A negative control must miss by this factor times the tolerance."""

NONNEGATIVE_FLOOR: float = -1e-9
"""Sun + dering: the irradiance over the sphere must stay above this times the irradiance DC (rounding of
a sum that touches 0 where the window is tight)."""

WINDOWED_TRIG_TOL: float = 1e-14
"""The exported trig matrix against sh.basis times the window, absolute: values below 1 (the largest is about
0.6) formed as an 8-term sum of cos(k ts), sin(k ts) times matrix entries whose absolute row sums are below 1,
so a few roundings of unit-size terms (eps 2.2e-16 each)."""

RANDOM_POINTS: int = 240
"""Random frames per build (each with its own flags and albedo)."""

CC: str | None = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
"""The machine's C compiler, or None: the C export tests skip without it."""

C_HARNESS: str = r"""
#include <stdio.h>
#include SKYSH_HEADER
int main(void) {
    double ts, t, phi, a[3];
    int engine, gibbs, dering, irradiance, sun, null_albedo, table, i, c;
    skysh_real out[SKYSH_COUNT][3], albedo[3], direction[3], rgb[3];
#ifdef SKYSH_ENGINE_COUNT
    skysh_real values[SKYSH_ENGINE_COUNT];
#endif
    while (scanf("%d %lf %lf %lf %d %d %d %d %d %lf %lf %lf %d", &engine, &ts, &t, &phi, &gibbs, &dering, &irradiance,
                 &sun, &null_albedo, a, a + 1, a + 2, &table) == 13) {
        int rc, rs;
        for (c = 0; c < 3; ++c)
            albedo[c] = (skysh_real)a[c];
        if (engine) {
#ifdef SKYSH_ENGINE_COUNT
            rc = skysh_engine_coefficients((skysh_real)ts, (skysh_real)t, (skysh_real)phi, gibbs, dering, sun,
                                           null_albedo ? NULL : albedo, table, values);
            printf("%d", rc);
            for (i = 0; i < SKYSH_ENGINE_COUNT; ++i)
                printf(" %.17g", (double)values[i]);
            printf("\n");
            continue;
#else
            return 2; /* an engine line for a header without an engine */
#endif
        }
        rc = skysh_coefficients((skysh_real)ts, (skysh_real)t, (skysh_real)phi, gibbs, dering, irradiance, sun,
                                null_albedo ? NULL : albedo, table, out);
        rs = skysh_sun_light((skysh_real)ts, (skysh_real)t, (skysh_real)phi, direction, rgb);
        printf("%d %d", rc, rs);
        for (c = 0; c < 3; ++c)
            printf(" %.17g", (double)direction[c]);
        for (c = 0; c < 3; ++c)
            printf(" %.17g", (double)rgb[c]);
        for (i = 0; i < SKYSH_COUNT; ++i)
            for (c = 0; c < 3; ++c)
                printf(" %.17g", (double)out[i][c]);
        printf("\n");
    }
    return 0;
}
"""
"""The C export tests' program around a header (here and in tests/export/test_export.py): each input line
``engine ts t phi gibbs dering irradiance sun null_albedo a_r a_g a_b irradiance_table`` calls, for engine 0,
skysh_coefficients (ground albedo NULL when null_albedo) and skysh_sun_light, printing both return codes, the sun's
direction and RGB and the SKYSH_COUNT x 3 coefficients (8 + 3 SKYSH_COUNT numbers); for engine 1 (a header with an
engine) skysh_engine_coefficients (irradiance unused), printing its code and the SKYSH_ENGINE_COUNT values."""


def c_harness_job(source: str) -> ToolJob:
    """The build of :data:`C_HARNESS` around the header ``source`` with :data:`CC`: C99, -O2, every warning an error."""
    assert CC is not None
    return ([CC, "-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", '-DSKYSH_HEADER="sky_sh.h"', "-o",
             f"{RUN_DIR}/harness", f"{RUN_DIR}/harness.c", "-lm"], {"sky_sh.h": source, "harness.c": C_HARNESS})


def compile_harness(source: str, runs: ToolRuns) -> Path:
    """The :data:`C_HARNESS` program of the header ``source`` (built once per session by ``runs``)."""
    done = runs.run(*c_harness_job(source))
    assert done.result.returncode == 0, done.result.stderr
    return done.directory / "harness"


BUILDS: dict[str, tuple[int, str]] = {"1": (1, "double"), "3": (3, "double"), "7": (7, "double"), "3f": (3, "float")}
"""Header builds compiled once per module: name -> (bands, C real type)."""

Point = tuple  # (ts, t, azimuth, gibbs, dering, irradiance, sun, NULL albedo, albedo[, irradiance_table])
"""(sun zenith, turbidity, azimuth, gibbs, dering, irradiance, sun, NULL albedo, albedo (r, g, b)[, irradiance_table:
BY_INTENT (absent), 0 or 1])."""

TABLE_CHOICES: dict[int, bool | None] = {BY_INTENT: None, 0: False, 1: True}
"""The exports' irradiance_table argument -> the runtime's."""


def table_of(p: Point) -> int:
    return p[9] if len(p) > 9 else BY_INTENT


@pytest.fixture(scope="module")
def binaries(exported: Exported, tool_runs: ToolRuns) -> dict[str, Path]:
    if CC is None:
        pytest.skip(SKIP_NO_CC)
    return {name: compile_harness(exported("c", bands=bands, real=real), tool_runs) for name, (bands, real) in BUILDS.items()}


def run(binary: Path, pts: list[Point]) -> list[np.ndarray]:
    """The harness ``binary`` (:data:`C_HARNESS`) at ``pts``: per point (rc, sun rc, sun direction (3), sun RGB (3),
    coefficients (SKYSH_COUNT x 3, flat))."""
    lines = [f"0 {p[0]!r} {p[1]!r} {p[2]!r} {p[3]} {p[4]} {p[5]} {p[6]} {p[7]} " + " ".join(map(repr, p[8]))
             + f" {table_of(p)}" for p in pts]
    out = subprocess.run([str(binary)], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True)
    return [np.array(line.split(), dtype=np.float64) for line in out.stdout.splitlines()]


def random_points(bands: int, count: int = RANDOM_POINTS, seed: int = 7) -> list[Point]:
    """Random frames over the domain; every tenth on the horizon, every 25th at the zenith; the flags cycle;
    the albedo is black, grey or random RGB (and NULL for black every other time); irradiance_table by intent,
    0, or 1 (3 bands, without the Gibbs filter) in turn."""
    rng = np.random.default_rng(seed + bands)
    pts: list[Point] = []
    for k in range(count):
        ts = math.pi / 2.0 if k % 10 == 0 else (0.0 if k % 25 == 1 else float(rng.uniform(0.0, math.pi / 2.0)))
        kind = k % 3
        albedo = (0.0, 0.0, 0.0) if kind == 0 else ((0.3,) * 3 if kind == 1 else tuple(rng.uniform(0.0, 1.0, 3)))
        table = (BY_INTENT, 0, 1)[k % 3 if bands == 3 else k % 2]
        pts.append((ts, float(rng.uniform(2.5, 6.0)), float(rng.uniform(-20.0, 20.0)), (k // 3) % 2 if table != 1 else 0,
                    int(bands == 3 and (k // 6) % 2), (k // 12) % 2, (k // 24) % 2 if k % 10 else 1,
                    int(kind == 0 and k % 2 == 1), tuple(float(v) for v in albedo), table))
    return pts


def reference(sky: SkySH, p: Point, bands: int) -> np.ndarray:
    return sky.coefficients(p[0], p[1], p[2], bands=bands, gibbs=bool(p[3]), dering=bool(p[4]), irradiance=bool(p[5]),
                            sun=bool(p[6]), ground_albedo=p[8], irradiance_table=TABLE_CHOICES[table_of(p)])


def errors(sky: SkySH, binary: Path, bands: int, pts: list[Point]) -> tuple[float, float, float]:
    """(coefficients, sun direction, sun RGB) worst errors of one build at ``pts``."""
    worst = direction_error = rgb_error = 0.0
    for p, row in zip(pts, run(binary, pts)):
        assert row[0] == 0 and row[1] == 0, (p, row[:2])
        worst = max(worst, dc_relative_error(row[8:].reshape(-1, 3), reference(sky, p, bands)))
        d, rgb = sky.sun_light(p[0], p[1], p[2])
        direction_error = max(direction_error, float(np.abs(row[2:5] - d).max()))
        rgb_error = max(rgb_error, float(np.abs(row[5:8] - rgb).max() / np.abs(rgb).max()))
    return worst, direction_error, rgb_error


MUTATIONS: list[str] = ["ground without the Gibbs filter", "sun colour not clamped", "ground lit by the table's c_10"]
"""The negative controls' changes to the 3-band header (:func:`mutate`)."""


def mutate(source: str, mutation: str) -> str:
    """The C header ``source`` with one of :data:`MUTATIONS` (unchanged if its code is not found)."""
    if mutation.startswith("ground without"):
        return source.replace("(gibbs ? SKYSH_GIBBS[l] : 1.0f)", "(gibbs ? 1.0f : 1.0f)")
    if mutation.startswith("ground lit"):  # the table's rows summed before the sky's E_h is taken from row 1
        start = source.index("\n#if SKYSH_IRRADIANCE_TABLE\n    if (table == 1) /* step 3 from the certified")
        step = source[start:source.index("\n#endif", start) + len("\n#endif")]
        e_sky = "\n    for (int c = 0; c < 3; ++c)\n        e_sky[c] ="
        return source.replace(step, "").replace(e_sky, step + e_sky)
    return source.replace("rgb[c] = rgb[c] > SKYSH_SUN_CLAMP ? rgb[c] : SKYSH_SUN_CLAMP;", "")


def without(sky: SkySH, table: str) -> SkySH:
    """An in-memory copy of ``sky`` without its table ``table`` ("sun", "irradiance"), in the data and the metadata."""
    metadata = copy.deepcopy(sky.table.metadata)
    metadata.get("tables", {}).pop(table, None)
    return SkySH(dataclasses.replace(sky.table, metadata=metadata,
                                     tables={k: v for k, v in sky.table.tables.items() if k != table}))


@pytest.fixture(scope="module")
def sunless(sky: SkySH) -> tuple[SkySH, str]:
    """The sky without the sun table, and its 3-band C export."""
    reduced = without(sky, "sun")
    return reduced, export_source(reduced, "c", bands=3)


@pytest.fixture(scope="module")
def bare(sky: SkySH) -> tuple[SkySH, str]:
    """The sky without the irradiance table, and its 3-band C export."""
    reduced = without(sky, "irradiance")
    return reduced, export_source(reduced, "c", bands=3)


def shader(exported: Exported, version: str, bands: int) -> tuple[str, str]:
    """(language, fragment shader) calling skysh_coefficients with the sun and the ground and skysh_sun_light of the
    ``bands``-band export, for GLSL ``version`` or "hlsl"."""
    if version == "hlsl":
        return "hlsl", exported("hlsl", bands=bands) + SHADER_MAIN["hlsl"]
    precision = "precision highp float;\n" if version.endswith("es") else ""
    return "glsl", f"#version {version}\n{precision}" + exported("glsl", bands=bands) + SHADER_MAIN["glsl"]


SHADER_VERSIONS: list[str] = ["330", "300 es", "hlsl"]
"""The shader targets compiled (GLSL desktop and ES, HLSL)."""

SHADER_BANDS: list[int] = [1, 3]
"""Band counts of the shader exports tested (one band: the unfiltered c_10 row; three: dering and the table)."""


def jobs(request: pytest.FixtureRequest, exported: Exported) -> Iterator[ToolJob]:
    """The compiles and validations of the module's selected tests, in the order the tests run."""
    wanted = selected_names(request)
    if CC is not None:
        if "TestC" in wanted:
            yield from (c_harness_job(exported("c", bands=bands, real=real)) for bands, real in BUILDS.values())
        if "test_negative_controls_fail" in wanted:
            yield from (c_harness_job(mutate(exported("c", bands=3), mutation)) for mutation in MUTATIONS)
        if "test_without_the_sun_table_the_sun_is_refused" in wanted:
            yield c_harness_job(request.getfixturevalue("sunless")[1])
        if "test_without_the_irradiance_table" in wanted:
            yield c_harness_job(request.getfixturevalue("bare")[1])
    if GLSLANG is not None and "test_compiles_with_the_sun_and_the_ground" in wanted:
        for bands in SHADER_BANDS:
            for version in SHADER_VERSIONS:
                language, text = shader(exported, version, bands)
                yield glslang_job(text, language)


@pytest.fixture(scope="module", autouse=True)
def _prefetch(request: pytest.FixtureRequest, exported: Exported, tool_runs: ToolRuns) -> None:
    """Queue the module's compiles and validations when it starts (background.ToolRuns): they run in the background
    while the tests compare numbers; each test takes its own when it needs it (or builds it then)."""
    tool_runs.prefetch(jobs(request, exported))


# --------------------------------------------------------------------------- #
@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestC:
    @pytest.mark.parametrize("name", ["1", "3", "7"])
    def test_random_inputs_match_the_runtime(self, sky: SkySH, binaries: dict[str, Path], name: str) -> None:
        bands = BUILDS[name][0]
        worst, direction_error, rgb_error = errors(sky, binaries[name], bands, random_points(bands))
        assert worst < DOUBLE_TOLERANCE
        assert direction_error < SUN_DIRECTION_TOLERANCE and rgb_error < DOUBLE_TOLERANCE

    @pytest.mark.parametrize("name", ["3", "7"])
    def test_large_azimuths_with_the_sun_match_the_runtime(self, sky: SkySH, binaries: dict[str, Path], name: str) -> None:
        """Issue 23: the sun sits where the sky turns at any finite azimuth (both reduce it by fmod(phi, 2 pi))."""
        bands = BUILDS[name][0]
        rng = np.random.default_rng(23)
        pts = [(p[0], p[1], float(10.0 ** rng.uniform(4, 300) * rng.choice([-1.0, 1.0])), *p[3:6], 1, *p[7:])
               for p in random_points(bands, 60)]
        worst, direction_error, rgb_error = errors(sky, binaries[name], bands, pts)
        assert worst < DOUBLE_TOLERANCE
        assert direction_error < SUN_DIRECTION_TOLERANCE and rgb_error < DOUBLE_TOLERANCE

    def test_float_build(self, sky: SkySH, binaries: dict[str, Path]) -> None:
        pts = [p for p in random_points(3, 120) if abs(p[2]) < 10.0]  # a float32 azimuth of 20 rad is off by 1e-6
        worst, _, rgb_error = errors(sky, binaries["3f"], 3, pts)
        assert worst < FLOAT32_SUN_TOLERANCE and rgb_error < FLOAT32_SUN_TOLERANCE

    def test_sun_and_the_ground_keep_the_irradiance_non_negative(self, binaries: dict[str, Path]) -> None:
        """Irradiance of the exported sky (the certified table by intent; the deringed old pipeline) + the windowed
        sun (+ a ground), exact minimum over the sphere; the old pipeline without deringing (negative control) dips
        below 0 at the same frames, so the check can fail."""
        rng = np.random.default_rng(3)
        frames = list(zip(np.linspace(0.0, math.pi / 2.0, 40), rng.uniform(2.5, 6.0, 40), rng.uniform(-3.0, 3.0, 40)))
        lowest = {}
        for dering, table, albedo in ((1, BY_INTENT, (0.0,) * 3), (1, BY_INTENT, (0.2, 0.3, 0.1)), (1, 0, (0.0,) * 3),
                                      (1, 0, (0.2, 0.3, 0.1)), (0, 0, (0.0,) * 3)):
            pts: list[Point] = [(float(ts), float(t), float(phi), 0, dering, 1, 1, 0, albedo, table) for ts, t, phi in frames]
            rows = np.array([row[8:].reshape(-1, 3) for row in run(binaries["3"], pts)])
            lowest[dering, table, albedo] = float((shmin.exact_min(rows) / rows[:, 0, :]).min())
        assert min(value for key, value in lowest.items() if key[0]) >= NONNEGATIVE_FLOOR
        assert lowest[0, 0, (0.0,) * 3] < PLAIN_DIP  # measured -7.3e-3 of the DC without deringing

    def test_refusals(self, binaries: dict[str, Path]) -> None:
        bad: list[Point] = [
            (0.5, 3.0, 0.0, 0, 0, 0, 0, 0, (-0.01, 0.0, 0.0)), (0.5, 3.0, 0.0, 0, 0, 0, 1, 0, (0.2, 1.01, 0.2)),
            (0.5, 3.0, 0.0, 0, 0, 0, 0, 0, (0.2, 0.2, float("nan"))),
        ]
        for row in run(binaries["3"], bad):
            assert row[0] == -3 and np.all(row[8:] == 0.0)  # the ground albedo named by its code
        outside: list[Point] = [(1.6, 3.0, 0.0, 0, 0, 0, 1, 0, (0.0,) * 3), (0.5, 6.5, 0.0, 0, 0, 0, 1, 0, (0.0,) * 3),
                                (0.5, 3.0, float("inf"), 0, 0, 0, 1, 0, (0.0,) * 3)]
        for row in run(binaries["3"], outside):
            assert row[0] == -1 and row[1] == -1 and np.all(row[2:] == 0.0)

    def test_null_albedo_is_a_black_ground(self, binaries: dict[str, Path]) -> None:
        pts: list[Point] = [(0.7, 3.3, 1.0, 1, 0, 1, 1, null, (0.0,) * 3) for null in (0, 1)]
        black, null = run(binaries["3"], pts)
        np.testing.assert_array_equal(black, null)

    @pytest.mark.parametrize("mutation", MUTATIONS)
    def test_negative_controls_fail(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns, mutation: str) -> None:
        source = exported("c", bands=3)
        mutated = mutate(source, mutation)
        if mutation.startswith("ground without"):
            pts: list[Point] = [(0.3 + 0.1 * k, 3.0 + 0.2 * k, 0.5 * k, 1, 0, 0, 0, 0, (0.5, 0.4, 0.3)) for k in range(8)]
        elif mutation.startswith("ground lit"):
            pts = [(0.3 + 0.1 * k, 3.0 + 0.2 * k, 0.5 * k, 0, 1, 1, 0, 0, (0.5, 0.4, 0.3), BY_INTENT) for k in range(8)]
        else:
            pts = [(math.pi / 2.0 - 0.002 * k, 2.5 + 0.5 * k, 0.5 * k, 0, 0, 0, 1, 0, (0.0,) * 3) for k in range(8)]
        assert mutated != source
        binary = compile_harness(mutated, tool_runs)
        worst = max(dc_relative_error(row[8:].reshape(-1, 3), reference(sky, p, 3)) for p, row in zip(pts, run(binary, pts)))
        assert worst > CONTROL_MARGIN * DOUBLE_TOLERANCE, mutation


# --------------------------------------------------------------------------- #
def parse_table(source: str, name: str, dtype: type = np.float32) -> np.ndarray:
    """The numbers of the table ``name`` of a C, GLSL or HLSL export, flat (``dtype``: float32 for the shaders, float64
    for a double C header): its declaration ``SKYSH_CONST type NAME[size] = SKYSH_ARRAY(type, size) ... SKYSH_END;``
    (skysh/export/templates/c_like_data.h), the numbers between the array's opening and SKYSH_END."""
    declaration = re.search(rf"^SKYSH_CONST \w+ {name}\[[^\]]*\] =\s*SKYSH_ARRAY\((?:[^()]|\([^()]*\))*\)(.*?)SKYSH_END;",
                            source, re.MULTILINE | re.DOTALL)
    assert declaration is not None, name
    numbers = re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?", declaration.group(1))
    return np.array([dtype(v) for v in numbers], dtype=dtype)


SHADER_MAIN: dict[str, str] = {
    "glsl": "uniform vec4 params;\nuniform vec3 albedo;\nout vec4 colour;\nvoid main() {\n    vec3 c[SKYSH_COUNT];\n"
            "    vec3 d;\n    vec3 rgb;\n    bool ok = skysh_coefficients(params.x, params.y, params.z, true, false, true, "
            "params.w > 0.0, albedo, SKYSH_BY_INTENT, c);\n"
            "    bool lit = skysh_sun_light(params.x, params.y, params.z, d, rgb);\n"
            "    colour = vec4(c[0] + c[SKYSH_COUNT - 1] + d + rgb, ok && lit ? 1.0 : 0.0);\n}\n",
    "hlsl": "float4 params;\nfloat3 albedo;\nfloat4 main() : SV_Target {\n    float3 c[SKYSH_COUNT];\n    float3 d;\n"
            "    float3 rgb;\n    bool ok = skysh_coefficients(params.x, params.y, params.z, true, false, true, "
            "params.w > 0.0, albedo, SKYSH_BY_INTENT, c);\n"
            "    bool lit = skysh_sun_light(params.x, params.y, params.z, d, rgb);\n"
            "    return float4(c[0] + c[SKYSH_COUNT - 1] + d + rgb, ok && lit ? 1.0 : 0.0);\n}\n",
}


class TestShaders:
    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    @pytest.mark.parametrize("bands", SHADER_BANDS)
    def test_tables_round_trip_in_float32(self, sky: SkySH, exported: Exported, language: str, bands: int) -> None:
        source = exported(language, bands=bands)
        lights = export_tables(sky, bands).lights
        for name, values in (("SKYSH_SUN_TABLE", lights.sun_table), ("SKYSH_SUN_RGB", lights.rgb_from_xyz),
                             ("SKYSH_SUN_TRIG", lights.windowed_trig()), ("SKYSH_GROUND", lights.ground_zonal)):
            np.testing.assert_array_equal(parse_table(source, name), np.ravel(values).astype(np.float32), err_msg=name)
        assert "skysh_sun_light(" in source and "#define SKYSH_LIGHTS 3" in source

    @pytest.mark.integration
    @pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
    @pytest.mark.parametrize("version", SHADER_VERSIONS)
    @pytest.mark.parametrize("bands", SHADER_BANDS)
    def test_compiles_with_the_sun_and_the_ground(self, exported: Exported, tool_runs: ToolRuns, version: str,
                                                  bands: int) -> None:
        language, text = shader(exported, version, bands)
        done = tool_runs.run(*glslang_job(text, language)).result
        assert done.returncode == 0, done.stdout + done.stderr


# --------------------------------------------------------------------------- #
def json_lights(payload: dict[str, Any], p: Point) -> tuple[np.ndarray, np.ndarray]:
    """The JSON export's sky + sun + ground (no dering, no irradiance) and the sun's RGB, evaluated as its
    blocks' algorithm lists say, with numpy's Chebyshev module; irradiance_table 1: the block irradiance_table's
    table in place of the sky's (the ground keeps the sky's c10_table)."""
    ts, t, phi = p[0], p[1], math.fmod(p[2], 2.0 * math.pi)
    bands, gibbs = payload["bands"], bool(p[3])
    x = min(1.0, max(-1.0, ts * payload["x"]["scale"] - payload["x"]["shift"]))
    y = min(1.0, max(-1.0, math.log(t) * payload["y"]["scale"] - payload["y"]["shift"]))
    cheb = np.polynomial.chebyshev
    table = np.array(payload["irradiance_table"]["table"] if table_of(p) == 1 else payload["table"])
    tx, ty = cheb.chebvander([x], table.shape[0] - 1)[0], cheb.chebvander([y], table.shape[1] - 1)[0]
    acc = np.einsum("i,j,ijrc->rc", tx, ty, table)
    lum = float(preetham.luminance_scale(ts, t))
    c10 = np.array(payload["ground"]["c10_table"])
    e_sky = payload["ground"]["horizontal_factor"] * lum * np.einsum(
        "i,j,ijc->c", cheb.chebvander([x], c10.shape[0] - 1)[0], cheb.chebvander([y], c10.shape[1] - 1)[0], c10)
    sun = payload["sun"]
    air = sun["air_mass"]
    m = 1.0 / (math.cos(ts) + air["a"] * (air["b"] - math.degrees(ts)) ** -air["c"])
    xs = min(1.0, max(-1.0, (m - air["m0"]) * air["x_scale"] - 1.0))
    ys = min(1.0, max(-1.0, (t - sun["turbidity"]["min"]) * sun["turbidity"]["y_scale"] - 1.0))
    ln_table = np.array(sun["table"])
    ln = np.einsum("i,j,ijc->c", cheb.chebvander([xs], ln_table.shape[0] - 1)[0], cheb.chebvander([ys], ln_table.shape[1] - 1)[0],
                   ln_table)
    rgb = np.array(sun["rgb_from_xyz"]) @ np.exp(ln)
    trig = np.array(sun["trig"]) @ np.concatenate([np.cos(np.arange(bands) * ts), np.sin(np.arange(bands) * ts)])
    out = np.empty((bands * bands, 3))
    for l in range(bands):
        row = l * (l + 1) // 2
        for m_ in range(-l, l + 1):
            rot = math.sin(-m_ * phi) if m_ < 0 else math.cos(m_ * phi)
            zonal = payload["gibbs"][l] if gibbs and m_ == 0 else 1.0
            out[l * (l + 1) + m_] = acc[row + abs(m_)] * zonal * rot * lum
            if p[6]:
                out[l * (l + 1) + m_] += trig[row + abs(m_)] * rot * np.maximum(rgb, sun["clamp"])
        ground = payload["ground"]["zonal"][l] * (payload["gibbs"][l] if gibbs else 1.0)
        light = np.array(p[8]) * (e_sky + (math.cos(ts) * rgb if p[6] else 0.0)) / math.pi
        out[l * (l + 1)] += ground * light
    return out, rgb


class TestJson:
    @pytest.mark.parametrize("bands", [1, 3])
    def test_independent_evaluation_matches_the_runtime(self, sky: SkySH, exported: Exported, bands: int) -> None:
        payload = json.loads(exported("json", bands=bands))
        assert payload["sun"]["available"] and payload["ground"]["available"]
        pts = [q for q in random_points(bands, 60) if not q[4] and not q[5]]  # by intent: the sky's rows
        assert sum(table_of(q) == 1 for q in pts) > 3 or bands != 3  # the table's radiance-equivalent with the lights
        for p in pts:
            got, rgb = json_lights(payload, p)
            assert dc_relative_error(got, reference(sky, p, bands)) < DOUBLE_TOLERANCE, p
            assert np.abs(rgb - sky.sun_light(p[0], p[1])[1]).max() / np.abs(rgb).max() < DOUBLE_TOLERANCE


# --------------------------------------------------------------------------- #
class TestGenerator:
    def test_light_tables_are_the_public_pieces(self, sky: SkySH) -> None:
        """The trig matrix reproduces the windowed SH of the sun's direction (an independent sh.basis)."""
        from skysh.model.solar import sun_window

        lights = export_tables(sky, 4).lights
        ts = np.linspace(0.0, math.pi / 2.0, 9)
        trig = np.concatenate([np.cos(np.outer(ts, np.arange(4))), np.sin(np.outer(ts, np.arange(4)))], axis=1)
        y = sh.basis(np.stack([np.sin(ts), 0.0 * ts, np.cos(ts)], axis=-1), 4)
        half = [l * (l + 1) + m for l in range(4) for m in range(l + 1)]
        expected = y[:, half] * sun_window(4)[[l for l in range(4) for _ in range(l + 1)]]
        np.testing.assert_allclose(trig @ lights.windowed_trig().T, expected, rtol=0, atol=WINDOWED_TRIG_TOL)
        np.testing.assert_array_equal(lights.c10, export_tables(sky, 4).table[:, :, 1, :])  # stored row (1, 0)

    @pytest.mark.parametrize("language", ["c", "glsl", "hlsl"])
    def test_tables_are_written_from_the_light_tables(self, sky: SkySH, exported: Exported, language: str) -> None:
        """Each lights table of the data section (skysh/export/templates/c_like_data.h) is the LightTables' numbers,
        float32 in the shaders and double in C, every value read back exactly."""
        source, lights = exported(language, bands=3), export_tables(sky, 3).lights
        dtype = np.float64 if language == "c" else np.float32
        for name, values in (("SKYSH_SUN_TABLE", lights.sun_table), ("SKYSH_SUN_RGB", lights.rgb_from_xyz),
                             ("SKYSH_SUN_TRIG", lights.windowed_trig()), ("SKYSH_GROUND", lights.ground_zonal)):
            np.testing.assert_array_equal(parse_table(source, name, dtype), np.ravel(values).astype(dtype), err_msg=name)
        defines = dict(re.findall(r"^#define (SKYSH_\w+) (.+)$", source, re.MULTILINE))
        assert int(defines["SKYSH_SUN_DX"]) == lights.sun_degrees[0] and int(defines["SKYSH_SUN_DY"]) == lights.sun_degrees[1]
        for name, key in (("SKYSH_KASTEN_A", "am_a"), ("SKYSH_KASTEN_NEG_C", "am_neg_c"), ("SKYSH_SUN_M0", "m0"),
                          ("SKYSH_HF", "hf"), ("SKYSH_SUN_CLAMP", "clamp")):
            assert dtype(defines[name]) == dtype(lights.constants[key]), name

    @pytest.mark.integration
    @pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
    def test_without_the_sun_table_the_sun_is_refused(self, sunless: tuple[SkySH, str], tool_runs: ToolRuns) -> None:
        """An in-memory SkyTable without the sun table exports; the sun is refused (-4), the ground still works."""
        reduced, source = sunless
        assert "#define SKYSH_LIGHTS 2" in source
        pts: list[Point] = [(0.5, 3.0, 0.0, 0, 0, 0, 1, 0, (0.0,) * 3), (0.5, 3.0, 0.4, 1, 0, 0, 0, 0, (0.2, 0.3, 0.4))]
        refused, ground = run(compile_harness(source, tool_runs), pts)
        assert refused[0] == -4 and refused[1] == -4 and np.all(refused[2:] == 0.0)
        assert ground[0] == 0 and dc_relative_error(ground[8:].reshape(-1, 3), reference(reduced, pts[1], 3)) < DOUBLE_TOLERANCE

    @pytest.mark.integration
    @pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
    def test_without_the_irradiance_table(self, sky: SkySH, bare: tuple[SkySH, str], tool_runs: ToolRuns) -> None:
        """An in-memory SkyTable without the irradiance table exports: by intent the old pipeline (as the runtime's
        default then), irradiance_table 1 refused (-5) as the runtime refuses it."""
        reduced, source = bare
        assert "#define SKYSH_IRRADIANCE_TABLE 0" in source and export_tables(reduced, 3).irradiance is None
        pts: list[Point] = [(0.5, 3.0, 0.4, 0, 1, 1, 1, 0, (0.2, 0.3, 0.4), BY_INTENT),
                            (0.5, 3.0, 0.4, 0, 1, 1, 0, 0, (0.0,) * 3, 1)]
        intent, refused = run(compile_harness(source, tool_runs), pts)
        assert intent[0] == 0 and dc_relative_error(intent[8:].reshape(-1, 3), reference(reduced, pts[0], 3)) < DOUBLE_TOLERANCE
        assert dc_relative_error(intent[8:].reshape(-1, 3), reference(sky, pts[0], 3)) > CONTROL_MARGIN * DOUBLE_TOLERANCE
        assert refused[0] == -5 and np.all(refused[8:] == 0.0)
        with pytest.raises(ValueError, match="irradiance_table"):
            reference(reduced, pts[1], 3)

    def test_light_tables_refuses_bad_bands(self, sky: SkySH) -> None:
        for bands in (0, 8, 2.5):
            with pytest.raises(ValueError, match="bands"):
                light_tables(sky, bands, (1, 1))  # type: ignore[arg-type]


def figures() -> list[dict[str, Any]]:
    """The measured errors printed by ``python tests/export/test_export_lights.py``."""
    import tempfile

    sky = SkySH.load()
    rows = []
    if CC is None:
        return rows
    with tempfile.TemporaryDirectory() as name:
        runs = ToolRuns(Path(name))
        for bands, real in BUILDS.values():
            binary = compile_harness(export_source(sky, "c", bands=bands, real=real), runs)
            pts = random_points(bands) if real == "double" else [p for p in random_points(bands, 120) if abs(p[2]) < 10]
            worst, direction, rgb = errors(sky, binary, bands, pts)
            rows.append({"export": f"c ({real})", "bands": bands, "points": len(pts), "coefficients_over_dc": worst,
                         "sun_direction": direction, "sun_rgb_over_max": rgb})
        runs.close()
    return rows


if __name__ == "__main__":
    for row in figures():
        print(json.dumps({"measure": "max |export - runtime|, sun and ground on", **row}))
    sys.exit(0)
