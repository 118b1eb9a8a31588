"""
Tests of skysh.export.c_like: the C, GLSL, HLSL and JSON exports against the Python runtime.

Also: the C export is a header (included twice and unused, it compiles as C99
and C++ with -Wunused-function -Werror); large azimuths are reduced as the
runtime reduces them; with ``engine=`` the generated
``skysh_engine_coefficients()`` (C compiled and run, GLSL/HLSL compiled, JSON
evaluated from its own description) matches ``skysh.engines.presets.convert`` of the
runtime's radiance for every engine and band count, and a negative control (the
unconverted coefficients) fails the same comparison.

The certified irradiance table (issue 18): the ``irradiance_table`` argument (C
``SKYSH_BY_INTENT``/0/1, the runtime's None/False/True) at random frames, the domain's
corners and edges, every (gibbs, irradiance, dering, irradiance_table) setting, against
the runtime (refused together: -5 and a ``ValueError``), for the 3-band double and float
headers, the 7-band one (no table) and every engine at 3 bands (by intent the table's
radiance-equivalent); the exported table's irradiance never negative by its exact minimum
(:func:`skysh.sh.minimum.exact_min`) at 3,000 random frames and the edges; negative controls:
a header whose rotation turns the other way, the old pipeline in place of the default,
the sky's own rows in place of the table (shaders, JSON), and the un-deringed old pipeline
(it dips below 0). The shaders' and the JSON's tables are evaluated as documented.

Error measure (:func:`dc_relative_error`): the largest |export - runtime| over
all coefficients of a channel, divided by |DC| of the same channel, worst
channel, worst point. Relative error per coefficient is meaningless (the m < 0
coefficients are exactly 0 at azimuth 0 and high bands are small); the DC
coefficient is the channel's mean radiance times 2 sqrt(pi), the scale that
lighting errors are seen against, and the worst channel (blue at a low sun and
low turbidity has the smallest DC relative to its other coefficients) is the
demanding one.

The C export is compiled with the machine's C compiler (skipped without one);
GLSL and HLSL are validated with glslangValidator when it is installed
(Debian's ``glslang-tools``; skipped otherwise) and always checked structurally.
The tests that compile C or run glslangValidator carry the ``integration`` marker.
Compiles and validations go through the session's :class:`background.ToolRuns`: each
distinct one (command, header and harness text) is made once and shared by the tests
that need it (one harness, test_export_lights.C_HARNESS, serves ``skysh_coefficients`` and
``skysh_engine_coefficients`` of a header, here and in tests/export/test_export_lights.py),
and the module queues them all when it starts (:func:`_prefetch`), so they overlap
each other and the Python comparisons.

``python tests/export/test_export.py`` prints the measured figures as JSON lines.
"""

from __future__ import annotations

import itertools
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
from conftest import PLAIN_DIP, SKIP_NO_CC, SKIP_NO_GLSLANG, Exported, dc_relative_error, engine_cases, is_padded_identity
from test_export_lights import CC, c_harness_job, compile_harness, parse_table

from skysh import SkySH
from skysh.app import cli
from skysh.export.c_like import (
    DEFAULT_FILE_NAMES,
    EXPORT_FORMATS,
    export_source,
)
from skysh.export.lights import BY_INTENT
from skysh.export.tables import engine_plan, export_tables
from skysh.model import preetham
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

REQUIRED_TOLERANCE: float = 1e-6
"""The issue's requirement for the C export (relative to the worst channel's DC)."""

DOUBLE_TOLERANCE: float = 1e-12
"""The double C build and the JSON tables: the same arithmetic as the runtime
(measured 1.5e-15; a few ulps of the Chebyshev recurrence against cos(k acos x))."""

FLOAT32_TOLERANCE: float = 5e-6
"""A float32 evaluation (tables, inputs and arithmetic: the float C build,
standing in for a shader); measured 1.0e-6."""

FLOAT32_TABLE_TOLERANCE: float = 1e-6
"""Float32 tables alone, evaluated in double (the GLSL/HLSL tables as
written); measured about 1e-7."""

Job = ToolJob
"""A tool run for :class:`background.ToolRuns`: (argv, files written to its directory first)."""

NO_LIGHTS: str = "0 1 0 0 0"
"""The harness fields (sun, null_albedo, albedo r g b) of a line without the sun and the ground (test_export_lights.C_HARNESS)."""

AZIMUTH_TOLERANCE: float = 1e-14
"""Large azimuths, reduced by an exact fmod in both the export and the runtime: the
same rounding as azimuth 0 (the unreduced export was 1.3e-13 off at -12345.678)."""

CONTROL_MARGIN: float = 1e3
"""A negative control must miss by this factor times the tolerance."""

ENGINE_SNAP_TOL: float = 1e-13
"""export_tables' engine plan against the engine's map, over the largest entry: the fold snaps entries to 1 within
export_tables.ENGINE_UNIT (1e-14) and to 0 within ENGINE_ZERO (1e-13) of the largest, and otherwise only divides and
multiplies by the band factor (a few ulps): ENGINE_ZERO bounds both."""

CXX: str | None = shutil.which("c++") or shutil.which("g++") or shutil.which("clang++")

DERING_POINT_STRIDE: int = 6
"""5..7-band deringing against the runtime at every this many of :func:`points` (the certificate costs about a
millisecond per frame in either)."""


def points() -> list[tuple[float, float, float, int, int]]:
    """A grid of the domain with its corners and edges; both Gibbs and irradiance settings."""
    return [
        (float(ts), float(t), phi, gibbs, irradiance)
        for ts in np.linspace(0.0, math.pi / 2.0, 7)
        for t in (2.5, 3.1, 4.4, 6.0)
        for phi in (0.0, 0.9, -2.7)
        for gibbs in (0, 1)
        for irradiance in (0, 1)
    ]


TABLE_CHOICES: dict[int, bool | None] = {BY_INTENT: None, 0: False, 1: True}
"""The exports' irradiance_table argument -> the runtime's irradiance_table."""


def table_of(p: tuple) -> int:
    """The irradiance_table argument of a point (ts, t, phi, gibbs, irradiance[, dering[, table]]): by intent when absent."""
    return p[6] if len(p) > 6 else BY_INTENT


def runtime_values(sky: SkySH, pts: list, bands: int) -> np.ndarray:
    """The runtime at points (ts, t, phi, gibbs, irradiance[, dering[, table]]) (dering 0 when absent)."""
    return np.array([
        sky.coefficients(p[0], p[1], p[2], bands=bands, gibbs=bool(p[3]), dering=bool(p[5:] and p[5]),
                         irradiance=bool(p[4]), irradiance_table=TABLE_CHOICES[table_of(p)])
        for p in pts
    ])


def run_c(binary: Path, pts: list) -> tuple[np.ndarray, np.ndarray]:
    """skysh_coefficients of the harness ``binary`` at points (ts, t, phi, gibbs, irradiance[, dering[, table]]), without
    the sun and the ground: (return codes, coefficients (n, SKYSH_COUNT, 3))."""
    text = "\n".join(f"0 {p[0]!r} {p[1]!r} {p[2]!r} {p[3]} {p[5] if p[5:] else 0} {p[4]} {NO_LIGHTS} {table_of(p)}"
                     for p in pts) + "\n"
    out = subprocess.run([str(binary)], input=text, capture_output=True, text=True, check=True).stdout.splitlines()
    rows = [np.array(line.split(), dtype=np.float64) for line in out]
    codes = np.array([row[0] for row in rows])
    return codes, np.array([row[8:].reshape(-1, 3) for row in rows])


def c_error(sky: SkySH, source: str, bands: int, runs: ToolRuns) -> float:
    """The C export ``source`` (``bands`` bands) at :func:`points` against the runtime."""
    pts = points()
    codes, got = run_c(compile_harness(source, runs), pts)
    assert np.all(codes == 0)
    return dc_relative_error(got, runtime_values(sky, pts, bands))


# --------------------------------------------------------------------------- #
# An independent evaluator of the exported numbers (numpy's Chebyshev module)
# --------------------------------------------------------------------------- #
def evaluate_tables(
    table: np.ndarray, gibbs_factors: np.ndarray, lobe: np.ndarray, x_map: tuple[float, float],
    y_map: tuple[float, float], bands: int, ts: float, t: float, phi: float, gibbs: bool, irradiance: bool,
) -> np.ndarray:
    """Coefficients from exported tables (DX+1, DY+1, K_half, 3), written from the export's documentation."""
    x = min(1.0, max(-1.0, ts * x_map[0] - x_map[1]))
    y = min(1.0, max(-1.0, math.log(t) * y_map[0] - y_map[1]))
    tx = np.polynomial.chebyshev.chebvander([x], table.shape[0] - 1)[0]
    ty = np.polynomial.chebyshev.chebvander([y], table.shape[1] - 1)[0]
    acc = np.einsum("i,j,ijrc->rc", tx, ty, table)
    out = np.empty((bands * bands, 3))
    for l in range(bands):
        row = l * (l + 1) // 2
        if gibbs:
            acc[row] *= gibbs_factors[l]
        for m in range(-l, l + 1):
            rot = math.sin(-m * phi) if m < 0 else math.cos(m * phi)
            out[l * (l + 1) + m] = acc[row + abs(m)] * rot * (lobe[l] if irradiance else 1.0)
    return out * float(preetham.luminance_scale(ts, t))


def parse_shader_table(source: str, name: str = "SKYSH_TABLE") -> np.ndarray:
    """The numbers of an RGB table (SKYSH_TABLE, SKYSH_IRRADIANCE) of a GLSL or HLSL export, (n, 3) float32, in its
    order: term-major, [(i (SKYSH_DY + 1) + j) 3 rows + 3 r + c] (skysh/export/templates/c_like_data.h)."""
    return parse_table(source, name).reshape(-1, 3)


def terms_major(rows: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """A table as the exports store it (term-major), (terms x rows, 3), as ``shape`` (DX + 1, DY + 1, rows, 3)."""
    return rows.reshape(shape[0], shape[1], shape[2], 3)


def as_stored(table: np.ndarray) -> np.ndarray:
    """(DX + 1, DY + 1, rows, 3) in the exports' order, (terms x rows, 3): the inverse of :func:`terms_major`."""
    return table.reshape(-1, 3)


def shader_float32_table_error(sky: SkySH, source: str, bands: int) -> float:
    """The float32 table of the shader export ``source`` (``bands`` bands), evaluated in double, against the runtime."""
    tables = export_tables(sky, bands)
    table32 = parse_shader_table(source)
    rows = tables.table.shape[2] + (bands == 1)  # one band: the unfiltered c_10 follows (not evaluated here)
    table = terms_major(table32.astype(np.float64), tables.table.shape[:2] + (rows,))[:, :, : tables.table.shape[2]]
    pts = points()
    got = np.array([
        evaluate_tables(
            table, tables.gibbs, tables.lobe, (tables.x_scale, tables.x_shift), (tables.y_scale, tables.y_shift),
            bands, ts, t, phi, bool(g), bool(e),
        )
        for ts, t, phi, g, e in pts
    ])
    return dc_relative_error(got, runtime_values(sky, pts, bands))


# --------------------------------------------------------------------------- #
# The module's compiles and validations (background.ToolRuns: each distinct one once)
# --------------------------------------------------------------------------- #
SHADER_BANDS: list[int] = [1, 3, 7]
"""Band counts of the plain shader exports compiled by glslangValidator."""

GLSL_VERSIONS: list[str] = ["330", "300 es"]
"""GLSL versions the shader exports are compiled for (desktop and ES)."""

CHOICE_VERSIONS: list[str] = ["330", "300 es", "hlsl"]
"""The shader targets of TestShaderIrradianceTable.test_compiles_with_every_choice."""

CHOICE_ENGINES: list[str | None] = [None, "unity"]
"""Without and with an engine, in the same test."""


def unit_job(source: str, compiler: str) -> Job:
    """A translation unit that includes the header ``source`` twice and uses none of it, compiled (not linked) as
    C99 (``compiler`` "c") or C++11 ("c++") with unused-function warnings as errors."""
    tool = CC if compiler == "c" else CXX
    assert tool is not None
    standard = ["-std=c99", "-pedantic"] if compiler == "c" else ["-x", "c++", "-std=c++11"]
    return ([tool, *standard, "-Wall", "-Wextra", "-Wunused-function", "-Werror", "-c", "-o", f"{RUN_DIR}/unit.o",
             f"{RUN_DIR}/unit.c"],
            {"sky_sh.h": source, "unit.c": '#include "sky_sh.h"\n#include "sky_sh.h"\nint unit(void) { return SKYSH_COUNT; }\n'})


def sky_shader(source: str, version: str) -> str:
    """A fragment shader calling skysh_coefficients of the export ``source`` (GLSL ``version``, or "hlsl")."""
    if version == "hlsl":
        return (source + "float4 params;\nfloat4 main() : SV_Target {\n    float3 c[SKYSH_COUNT];\n"
                "    bool ok = skysh_coefficients(params.x, params.y, params.z, true, params.w > 0.0, false, false,\n"
                "        float3(0.0, 0.0, 0.0), SKYSH_BY_INTENT, c);\n"
                "    return float4(c[0] + c[SKYSH_COUNT - 1], ok ? 1.0 : 0.0);\n}\n")
    precision = "precision highp float;\n" if version.endswith("es") else ""
    return (f"#version {version}\n{precision}" + source
            + "uniform vec4 params;\nout vec4 colour;\nvoid main() {\n    vec3 c[SKYSH_COUNT];\n"
            "    bool ok = skysh_coefficients(params.x, params.y, params.z, true, params.w > 0.0, false, false, vec3(0.0),\n"
            "        SKYSH_BY_INTENT, c);\n"
            "    colour = vec4(c[0] + c[SKYSH_COUNT - 1], ok ? 1.0 : 0.0);\n}\n")


def engine_shader(source: str, language: str) -> str:
    """A fragment shader calling skysh_engine_coefficients of the engine export ``source`` (GLSL 330 or HLSL)."""
    if language == "glsl":
        return ("#version 330\n" + source + "uniform vec4 params;\nout vec4 colour;\nvoid main() {\n"
                "    float v[SKYSH_ENGINE_COUNT];\n    bool ok = skysh_engine_coefficients(params.x, params.y, params.z, "
                "false, params.w > 0.0, true, vec3(0.2), SKYSH_BY_INTENT, v);\n"
                "    colour = vec4(v[0], v[SKYSH_ENGINE_COUNT - 1], 0.0, ok ? 1.0 : 0.0);\n}\n")
    return (source + "float4 params;\nfloat4 main() : SV_Target {\n    float v[SKYSH_ENGINE_COUNT];\n"
            "    bool ok = skysh_engine_coefficients(params.x, params.y, params.z, false, params.w > 0.0, true,\n"
            "        float3(0.2, 0.2, 0.2), SKYSH_BY_INTENT, v);\n"
            "    return float4(v[0], v[SKYSH_ENGINE_COUNT - 1], 0.0, ok ? 1.0 : 0.0);\n}\n")


def choice_shader(source: str, version: str, engine: str | None) -> str:
    """A fragment shader (GLSL ``version`` or "hlsl") passing irradianceTable from a uniform, so that every value
    reaches the code, to skysh_coefficients or (with ``engine``) skysh_engine_coefficients of ``source``."""
    glsl = version != "hlsl"
    vec3, args = ("vec3" if glsl else "float3"), "params.x, params.y, params.z, false, true"
    call = (f"skysh_engine_coefficients({args}, false, {vec3}(0.2, 0.2, 0.2), int(params.w) - 1, v)" if engine
            else f"skysh_coefficients({args}, true, false, {vec3}(0.2, 0.2, 0.2), int(params.w) - 1, c)")
    decl = "float v[SKYSH_ENGINE_COUNT];" if engine else f"{vec3} c[SKYSH_COUNT];"
    use = "v[0]" if engine else "c[0].x"
    if glsl:
        precision = "precision highp float;\n" if version.endswith("es") else ""
        return (f"#version {version}\n{precision}{source}uniform vec4 params;\nout vec4 colour;\n"
                f"void main() {{\n    {decl}\n    bool ok = {call};\n"
                f"    colour = vec4({use}, 0.0, 0.0, ok ? 1.0 : 0.0);\n}}\n")
    return (f"{source}float4 params;\nfloat4 main() : SV_Target {{\n    {decl}\n    bool ok = {call};\n"
            f"    return float4({use}, 0.0, 0.0, ok ? 1.0 : 0.0);\n}}\n")


def turned_the_other_way(source: str) -> str:
    """The C header ``source`` with its rotation (Habel eq. 4) turning the other way (a negative control)."""
    return source.replace("SKYSH_REAL rot = m < 0 ? rs[k] : rc[k];", "SKYSH_REAL rot = m < 0 ? -rs[k] : rc[k];")


def c_jobs(exported: Exported, wanted: set[str]) -> Iterator[Job]:
    """The C builds of the tests (and classes) named in ``wanted``, in the order the tests run."""
    if CC is None:
        return
    engines = engine_cases()
    if wanted & {"TestCExport", "TestCHeader", "TestCDering", "TestCIrradianceTable"}:
        yield from (c_harness_job(exported("c", bands=bands, real=real)) for bands, real in (
            (1, "double"), (3, "double"), (7, "double"), (3, "float"), (7, "float"), (2, "double"), (4, "double"),
            (5, "double"), (6, "double")))
    if "test_included_twice_and_unused_compiles_without_warnings" in wanted:
        yield from (unit_job(exported("c", bands=3), compiler) for compiler in ("c", "c++") if compiler == "c" or CXX)
    if "test_negative_control_wrong_rotation_sign" in wanted:
        yield c_harness_job(turned_the_other_way(exported("c", bands=3)))
    if wanted & {"test_matches_convert", "test_negative_control_unconverted_fails", "test_engine_with_dering",
                 "test_engines_take_the_table_by_intent"}:
        yield from (c_harness_job(exported("c", bands=bands, engine=name)) for name, bands in engines)
    if engines and "test_float_build" in wanted:
        yield c_harness_job(exported("c", bands=engines[-1][1], engine=engines[-1][0], real="float"))


def shader_jobs(exported: Exported, wanted: set[str]) -> Iterator[Job]:
    """The glslangValidator runs of the tests named in ``wanted``."""
    if GLSLANG is None:
        return
    if "test_shader_compiles" in wanted:
        yield from (glslang_job(engine_shader(exported(language, bands=bands, engine=name), language), language)
                    for name, bands in engine_cases() for language in ("glsl", "hlsl"))
    if "test_glsl_compiles" in wanted:
        yield from (glslang_job(sky_shader(exported("glsl", bands=bands), version), "glsl")
                    for bands in SHADER_BANDS for version in GLSL_VERSIONS)
    if "test_hlsl_compiles" in wanted:
        yield from (glslang_job(sky_shader(exported("hlsl", bands=bands), "hlsl"), "hlsl") for bands in SHADER_BANDS)
    if "test_compiles_with_every_choice" in wanted:
        for engine in CHOICE_ENGINES:
            for version in CHOICE_VERSIONS:
                language = "hlsl" if version == "hlsl" else "glsl"
                yield glslang_job(choice_shader(exported(language, bands=3, engine=engine), version, engine), language)


@pytest.fixture(scope="module", autouse=True)
def _prefetch(request: pytest.FixtureRequest, exported: Exported, tool_runs: ToolRuns) -> None:
    """Queue the compiles and validations of the module's selected tests when the module starts: they run in the
    background (background.ToolRuns) while the tests compare numbers, and each test takes its own when it needs it.
    The lists above only decide what is queued early; a test builds whatever it needs itself."""
    wanted = selected_names(request)
    tool_runs.prefetch(itertools.chain(c_jobs(exported, wanted), shader_jobs(exported, wanted)))


# --------------------------------------------------------------------------- #
@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestCExport:
    @pytest.mark.parametrize("bands", [1, 3, 7])
    def test_double_matches_runtime(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns, bands: int) -> None:
        error = c_error(sky, exported("c", bands=bands, real="double"), bands, tool_runs)
        assert error < REQUIRED_TOLERANCE
        assert error < DOUBLE_TOLERANCE

    @pytest.mark.parametrize("bands", [3, 7])
    def test_float_build_is_within_float32_error(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns, bands: int) -> None:
        assert c_error(sky, exported("c", bands=bands, real="float"), bands, tool_runs) < FLOAT32_TOLERANCE

    def test_refuses_outside_the_domain(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        binary = compile_harness(exported("c", bands=2), tool_runs)
        bad = [(-0.01, 3.0, 0.0, 1, 0), (1.5708, 3.0, 0.0, 1, 0), (0.5, 2.49, 0.0, 1, 0), (0.5, 6.01, 0.0, 1, 0),
               (float("nan"), 3.0, 0.0, 1, 0), (0.5, 3.0, float("inf"), 1, 0)]
        codes, values = run_c(binary, bad)
        assert np.all(codes == -1) and np.all(values == 0.0)
        for ts, t, phi, _, _ in bad:  # the runtime refuses the same points
            with pytest.raises(ValueError):
                sky.coefficients(ts, t, phi, bands=2)

    def test_domain_edges_are_accepted(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        binary = compile_harness(exported("c", bands=2), tool_runs)
        edges = [(0.0, 2.5, 0.0, 1, 0), (math.pi / 2.0, 6.0, 100.0, 0, 1)]
        codes, got = run_c(binary, edges)
        assert np.all(codes == 0)
        assert dc_relative_error(got, runtime_values(sky, edges, 2)) < DOUBLE_TOLERANCE


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestCHeader:
    """Issue 13: the C export is a header; the azimuth is reduced as the runtime does."""

    def test_names_itself_a_header(self, exported: Exported) -> None:
        source = exported("c", bands=2)
        assert DEFAULT_FILE_NAMES["c"] == "sky_sh.h"
        assert '#include "sky_sh.h"' in source and "-lm" in source
        assert "static int" not in source and "static skysh_real skysh" not in source  # every function static inline

    @pytest.mark.parametrize("compiler", ["c", "c++"])
    def test_included_twice_and_unused_compiles_without_warnings(self, exported: Exported, tool_runs: ToolRuns,
                                                                  compiler: str) -> None:
        if (CC if compiler == "c" else CXX) is None:
            pytest.skip(f"no {compiler} compiler")
        result = tool_runs.run(*unit_job(exported("c", bands=3), compiler)).result
        assert result.returncode == 0, result.stderr

    @pytest.mark.parametrize("phi", [-12345.678, 1e6, -1e15, 1e300, 2.0 * math.pi])
    def test_azimuth_is_reduced_as_the_runtime_does(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns,
                                                    phi: float) -> None:
        binary = compile_harness(exported("c", bands=7), tool_runs)
        pts = [(0.7, 3.3, phi, 0, 0), (1.2, 5.0, phi, 1, 1)]
        codes, got = run_c(binary, pts)
        assert np.all(codes == 0)
        assert dc_relative_error(got, runtime_values(sky, pts, 7)) < AZIMUTH_TOLERANCE


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestCDering:
    """The deringing step (skysh.export.dering) against the runtime's dering, window for window: at 3 bands (also the
    float build and an engine) and at every other band count 1..7."""

    def test_matches_the_runtime(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        binary = compile_harness(exported("c", bands=3), tool_runs)
        pts = [(*p, 1, 0) for p in points()]  # the old pipeline (irradiance_table 0): its deringing
        codes, got = run_c(binary, pts)
        ref = runtime_values(sky, pts, 3)
        assert np.all(codes == 0)
        assert dc_relative_error(got, ref) < DOUBLE_TOLERANCE
        plain = runtime_values(sky, [p[:5] for p in pts], 3)
        windowed = sum(dc_relative_error(r[None], q[None]) > CONTROL_MARGIN * DOUBLE_TOLERANCE for r, q in zip(ref, plain))
        assert windowed > len(pts) // 10  # real windows are compared, not only identities

    def test_float_build(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        binary = compile_harness(exported("c", bands=3, real="float"), tool_runs)
        pts = [(*p, 1, 0) for p in points()]
        codes, got = run_c(binary, pts)
        assert np.all(codes == 0)
        assert dc_relative_error(got, runtime_values(sky, pts, 3)) < FLOAT32_TOLERANCE

    @pytest.mark.parametrize("bands", [1, 2, 4, 5, 6, 7])
    def test_every_band_count_matches_the_runtime(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns,
                                                  bands: int) -> None:
        """Issue 25: the least window at every band count (1..4 exact, 5..7 the certificate), as the runtime's."""
        source = exported("c", bands=bands)
        assert "#define SKYSH_DERING 1" in source
        pts = [(*p, 1, 0) for p in points()[:: 1 if bands <= 4 else DERING_POINT_STRIDE]]
        codes, got = run_c(compile_harness(source, tool_runs), pts)
        assert np.all(codes == 0)
        assert dc_relative_error(got, runtime_values(sky, pts, bands)) < DOUBLE_TOLERANCE

    def test_engine_with_dering(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        cases = [case for case in engine_cases() if case[1] == 3]
        if not cases:
            pytest.skip("skysh.engines.presets does not exist yet")
        name = cases[-1][0]
        pts = [(*p, 1) for p in engine_points()]
        codes, got = run_engine_c(exported("c", bands=3, engine=name), tool_runs, pts)
        ref, scale = engine_reference(sky, pts, name, 3)
        assert np.all(codes == 0)
        assert float(np.abs(got - ref).max()) / scale < DOUBLE_TOLERANCE


# --------------------------------------------------------------------------- #
# The certified irradiance table (issue 18): irradiance_table as the runtime's
# --------------------------------------------------------------------------- #
TABLE_POINTS: int = 480
"""Random frames of the table tests: the 24 (gibbs, irradiance, dering, irradiance_table) settings in turn, the
four corners of the domain with each (96), one in ten of the rest on an edge."""

NONNEGATIVE_POINTS: int = 3000
"""Random frames at which the exported tabulated irradiance's exact minimum over the sphere is checked (the
file's certificate: 12,004 points by its own fit tool, tests/table/test_irradiance_table.py 12,004 others)."""


def table_points(count: int = TABLE_POINTS, seed: int = 18) -> list[tuple]:
    """(ts, t, phi, gibbs, irradiance, dering, irradiance_table) over the domain; see :data:`TABLE_POINTS`."""
    rng = np.random.default_rng(seed)
    corners = [(z, t) for z in (0.0, math.pi / 2.0) for t in (2.5, 6.0)]
    pts = []
    for k in range(count):
        setting = (k % 2, (k // 2) % 2, (k // 4) % 2, (BY_INTENT, 0, 1)[(k // 8) % 3])
        if k < 4 * 24:
            ts, t = corners[k // 24]
        else:
            ts, t = float(rng.uniform(0.0, math.pi / 2.0)), float(rng.uniform(2.5, 6.0))
            if k % 10 == 0:  # an edge: one variable at an end of its range
                ts, t = ((0.0, math.pi / 2.0)[k % 20 // 10], t) if k % 40 < 20 else (ts, (2.5, 6.0)[k % 20 // 10])
        pts.append((ts, t, float(rng.uniform(-20.0, 20.0)), *setting))
    return pts


def table_error(sky: SkySH, binary: Path, pts: list, bands: int) -> tuple[float, int]:
    """(worst error against the runtime, points both refuse): where the runtime raises a ValueError the export
    must return -5 with a zeroed output."""
    codes, got = run_c(binary, pts)
    worst, refused = 0.0, 0
    for p, code, values in zip(pts, codes, got):
        try:
            ref = runtime_values(sky, [p], bands)[0]
        except ValueError:
            assert code == -5 and np.all(values == 0.0), p
            refused += 1
            continue
        assert code == 0, p
        worst = max(worst, dc_relative_error(values, ref))
    return worst, refused


def relative_minimum(coeffs: np.ndarray) -> np.ndarray:
    """skysh.sh.minimum.exact_min over the sphere of 3-band irradiance (..., 9, 3), over its mean (Y00 c_0), per channel."""
    return shmin.exact_min(coeffs) / (coeffs[..., 0, :] / (2.0 * math.sqrt(math.pi)))


@pytest.fixture(scope="module")
def builds(exported: Exported, tool_runs: ToolRuns) -> dict[str, Path]:
    """The headers of the table tests, compiled once: 3 bands (double, float), 7 bands (no table)."""
    if CC is None:
        pytest.skip(SKIP_NO_CC)
    return {name: compile_harness(exported("c", bands=bands, real=real), tool_runs)
            for name, bands, real in (("3", 3, "double"), ("3f", 3, "float"), ("7", 7, "double"))}


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestCIrradianceTable:
    @pytest.mark.parametrize(("name", "bands", "tolerance"), [("3", 3, DOUBLE_TOLERANCE), ("3f", 3, FLOAT32_TOLERANCE),
                                                              ("7", 7, DOUBLE_TOLERANCE)])
    def test_every_setting_matches_the_runtime(self, sky: SkySH, builds: dict[str, Path], name: str, bands: int,
                                               tolerance: float) -> None:
        # dering at 3 bands only here (7: the certificate's cost; TestCDering covers it)
        pts = [p for p in table_points() if (name != "3f" or abs(p[2]) < 10.0) and (bands == 3 or not p[5])]
        worst, refused = table_error(sky, builds[name], pts, bands)
        assert worst < tolerance
        assert refused > 0  # irradiance_table 1 with gibbs (and at 7 bands): refused on both sides

    def test_the_default_takes_the_table(self, sky: SkySH, builds: dict[str, Path]) -> None:
        """Negative control: 3-band irradiance by intent is not the old pipeline (irradiance_table=False), which
        misses at every point by far more than the tolerance (measured: 2.3e-3 of the DC at the least)."""
        pts = [p[:3] + (0, 1, 1, BY_INTENT) for p in table_points()]
        _, got = run_c(builds["3"], pts)
        old = runtime_values(sky, [p[:6] + (0,) for p in pts], 3)
        assert min(dc_relative_error(g[None], r[None]) for g, r in zip(got, old)) > CONTROL_MARGIN * DOUBLE_TOLERANCE

    @pytest.mark.parametrize("name", ["3", "3f"])
    def test_tabulated_irradiance_is_never_negative(self, builds: dict[str, Path], name: str) -> None:
        """The exported table's irradiance, exact minimum over the sphere (skysh.sh.minimum.exact_min), at random frames,
        the corners and the edges; the un-deringed old pipeline at the same frames dips below 0 (the check can fail)."""
        rng = np.random.default_rng(1802)
        frames = [(float(z), float(t), float(a)) for z, t, a in zip(rng.uniform(0.0, math.pi / 2.0, NONNEGATIVE_POINTS),
                                                                 rng.uniform(2.5, 6.0, NONNEGATIVE_POINTS),
                                                                 rng.uniform(-3.0, 3.0, NONNEGATIVE_POINTS))]
        frames += [(z, t, 0.5) for z in (0.0, math.pi / 2.0) for t in (2.5, 6.0)]
        frames += [(z, t, 1.0) for z in np.linspace(0.0, math.pi / 2.0, 25) for t in (2.5, 6.0)]
        frames += [(z, t, -1.0) for z in (0.0, math.pi / 2.0) for t in np.linspace(2.5, 6.0, 25)]
        codes, table = run_c(builds[name], [f + (0, 1, 1, BY_INTENT) for f in frames])
        assert np.all(codes == 0)
        assert relative_minimum(table).min() >= 0.0
        _, plain = run_c(builds[name], [f + (0, 1, 0, 0) for f in frames])
        assert relative_minimum(plain).min() < PLAIN_DIP  # measured -2.6e-2 of the mean

    def test_negative_control_wrong_rotation_sign(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        """A header whose rotation (Habel eq. 4) turns the other way must fail the comparison with the runtime."""
        source = exported("c", bands=3)
        mutated = turned_the_other_way(source)
        assert mutated != source
        pts = [p[:3] + (0, 1, 1, BY_INTENT) for p in table_points(40)]
        worst, _ = table_error(sky, compile_harness(mutated, tool_runs), pts, 3)
        assert worst > CONTROL_MARGIN * DOUBLE_TOLERANCE

    def test_refusals(self, sky: SkySH, builds: dict[str, Path]) -> None:
        """-5 (zeroed) for irradiance_table 1 with gibbs, at 7 bands, or a value other than -1, 0, 1."""
        frame = (0.6, 3.2, 0.7)
        bad = [frame + (1, 1, 1, 1), frame + (0, 1, 1, 2), frame + (0, 1, 1, -2)]
        codes, got = run_c(builds["3"], bad)
        assert np.all(codes == -5) and np.all(got == 0.0)
        codes, got = run_c(builds["7"], [frame + (0, 1, 0, 1)])
        assert codes[0] == -5 and np.all(got == 0.0)
        for bands, gibbs in ((3, True), (7, False)):  # the runtime refuses the same
            with pytest.raises(ValueError, match="irradiance_table"):
                sky.coefficients(*frame, bands=bands, gibbs=gibbs, irradiance=True, irradiance_table=True)

    def test_engines_take_the_table_by_intent(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        """skysh_engine_coefficients at 3 bands: engines.convert of the runtime's radiance, the table's
        radiance-equivalent by intent (no Gibbs filter, deringing on), and with irradiance_table 0 and 1."""
        cases = [name for name, bands in engine_cases() if bands == 3]
        pts = [(ts, t, phi, g, 1, choice) for ts, t, phi, g in engine_points()[::3] for choice in (BY_INTENT, 0, 1)
               if not (g and choice == 1)]
        for name in cases:
            codes, got = run_engine_c(exported("c", bands=3, engine=name), tool_runs, pts)
            ref, scale = engine_reference(sky, pts, name, 3)
            assert np.all(codes == 0) and float(np.abs(got - ref).max()) / scale < DOUBLE_TOLERANCE, name
        assert sum(engine_table(p, 3) for p in pts) > len(pts) // 3  # the table is in the comparison


# --------------------------------------------------------------------------- #
# Engines: the generated skysh_engine_coefficients() against skysh.engines.presets.convert
# --------------------------------------------------------------------------- #
def engine_table(p: tuple, bands: int) -> bool:
    """The runtime's irradiance_table for an engine at (ts, t, phi, gibbs[, dering[, table]]): engines light diffusely,
    so by intent the table at 3 bands without the Gibbs filter and with deringing (docs/engines.md)."""
    choice = p[5] if len(p) > 5 else BY_INTENT
    return bool(choice == 1 or (choice == BY_INTENT and bands == 3 and not p[3] and p[4:] and p[4]))


def engine_reference(sky: SkySH, pts: list, name: str, bands: int) -> tuple[np.ndarray, float]:
    """engines.convert of the runtime's radiance at points (ts, t, phi, gibbs[, dering[, table]]), flattened, and the
    error scale: the largest |DC| times the largest absolute row sum of the engine's map."""
    from skysh.engines import presets as engines

    radiance = np.array([
        sky.coefficients(p[0], p[1], p[2], bands=bands, gibbs=bool(p[3]), dering=bool(p[4:] and p[4]),
                         irradiance_table=engine_table(p, bands)) for p in pts
    ])
    ref = np.asarray(engines.convert(radiance, name), dtype=np.float64).reshape(len(pts), -1)
    gain = float(np.abs(np.asarray(engines.engine_map(name, bands).matrix)).sum(axis=1).max())
    return ref, gain * float(np.abs(radiance[:, 0]).max())


def engine_points() -> list[tuple[float, float, float, int]]:
    return [(float(ts), t, phi, g) for ts in np.linspace(0.0, math.pi / 2.0, 4) for t in (2.5, 4.4, 6.0)
            for phi in (0.0, 0.9, -2.7, -12345.678) for g in (0, 1)]


def run_engine_c(source: str, runs: ToolRuns, pts: list) -> tuple[np.ndarray, np.ndarray]:
    """skysh_engine_coefficients of the header ``source`` at points (ts, t, phi, gibbs[, dering[, table]]):
    (return codes, values)."""
    binary = compile_harness(source, runs)
    text = "\n".join(f"1 {p[0]!r} {p[1]!r} {p[2]!r} {p[3]} {p[4] if p[4:] else 0} 0 {NO_LIGHTS} "
                     f"{p[5] if p[5:] else BY_INTENT}" for p in pts) + "\n"
    out = subprocess.run([str(binary)], input=text, capture_output=True, text=True, check=True).stdout.splitlines()
    rows = np.array([line.split() for line in out], dtype=np.float64)
    return rows[:, 0], rows[:, 1:]


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
class TestCEngineExport:
    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_matches_convert(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns, name: str, bands: int) -> None:
        pts = engine_points()
        codes, got = run_engine_c(exported("c", bands=bands, engine=name), tool_runs, pts)
        ref, scale = engine_reference(sky, pts, name, bands)
        assert np.all(codes == 0) and got.shape == ref.shape
        assert float(np.abs(got - ref).max()) / scale < DOUBLE_TOLERANCE

    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_negative_control_unconverted_fails(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns, name: str,
                                                bands: int) -> None:
        """skysh's own radiance (the non-engine function of the same header and build) must fail the comparison."""
        if is_padded_identity(name, bands):
            pytest.skip(f"{name} at {bands} band(s) takes skysh's numbers as they are")
        pts = engine_points()[:8]
        binary = compile_harness(exported("c", bands=bands, engine=name), tool_runs)
        codes, radiance = run_c(binary, [(ts, t, phi, g, 0) for ts, t, phi, g in pts])
        ref, scale = engine_reference(sky, pts, name, bands)
        assert np.all(codes == 0)
        pasted = np.zeros(ref.shape)  # skysh's numbers pasted as they are (zero-padded to the layout)
        flat = radiance.reshape(len(pts), -1)[:, : ref.shape[1]]
        pasted[:, : flat.shape[1]] = flat
        assert float(np.abs(pasted - ref).max()) / scale > CONTROL_MARGIN * DOUBLE_TOLERANCE

    def test_refuses_outside_the_domain(self, exported: Exported, tool_runs: ToolRuns) -> None:
        if not engine_cases():
            pytest.skip("skysh.engines.presets does not exist yet")
        name, bands = engine_cases()[-1]
        pts = [(-0.01, 3.0, 0.0, 1), (0.5, 6.01, 0.0, 1), (float("nan"), 3.0, 0.0, 0), (0.5, 3.0, float("inf"), 0)]
        codes, got = run_engine_c(exported("c", bands=bands, engine=name), tool_runs, pts)
        assert np.all(codes == -1) and np.all(got == 0.0)

    def test_float_build(self, sky: SkySH, exported: Exported, tool_runs: ToolRuns) -> None:
        if not engine_cases():
            pytest.skip("skysh.engines.presets does not exist yet")
        name, bands = engine_cases()[-1]
        pts = [p for p in engine_points() if abs(p[2]) < 10.0]  # a float32 azimuth of 12345.678 is off by 1e-4 rad
        codes, got = run_engine_c(exported("c", bands=bands, engine=name, real="float"), tool_runs, pts)
        ref, scale = engine_reference(sky, pts, name, bands)
        assert np.all(codes == 0)
        assert float(np.abs(got - ref).max()) / scale < FLOAT32_TOLERANCE

    def test_unknown_engine_lists_the_valid_ones(self, sky: SkySH) -> None:
        engines = pytest.importorskip("skysh.engines.presets")
        with pytest.raises(ValueError) as error:
            export_source(sky, "c", engine="godot")
        assert all(name in str(error.value) for name in engines.ENGINES)


class TestEngineOtherLanguages:
    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_plan_refactors_the_engine_map(self, name: str, bands: int) -> None:
        """matrix x (band factor of each column) is the engine's map: the fold changes no number beyond
        the snapping of export_tables.ENGINE_UNIT and ENGINE_ZERO (1e-13 of the largest entry bounds both)."""
        from skysh.engines import presets as engines

        plan, emap = engine_plan(name, bands), engines.engine_map(name, bands)
        band_of_column = np.repeat([sh.lm(i)[0] for i in range(bands * bands)], 3)
        rebuilt = plan.matrix * plan.band_factor[band_of_column]
        assert np.abs(rebuilt - emap.matrix).max() <= ENGINE_SNAP_TOL * np.abs(emap.matrix).max()
        np.testing.assert_array_equal(plan.offset, emap.offset)
        assert plan.shape == tuple(emap.shape) and plan.offset.size == np.prod(plan.shape)

    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_json_plan_reproduces_convert(self, sky: SkySH, exported: Exported, name: str, bands: int) -> None:
        """The JSON's engine block, applied as its text says, to an independent evaluation of its tables."""
        payload = json.loads(exported("json", bands=bands, engine=name))
        engine = payload["engine"]
        pts = engine_points()[::7]
        got = []
        for ts, t, phi, g in pts:
            c = evaluate_tables(
                np.array(payload["table"]), np.array(payload["gibbs"]), np.array(payload["lobe"]),
                (payload["x"]["scale"], payload["x"]["shift"]), (payload["y"]["scale"], payload["y"]["shift"]),
                bands, ts, t, math.fmod(phi, 2.0 * math.pi), bool(g), False,
            )
            c *= np.array(engine["band_factor"])[[sh.lm(i)[0] for i in range(bands * bands)]][:, None]
            got.append(np.array(engine["matrix"]) @ c.reshape(-1) + np.array(engine["offset"]))
        ref, scale = engine_reference(sky, pts, name, bands)
        assert engine["shape"] == list(np.asarray(ref[0]).reshape(engine["shape"]).shape)
        assert float(np.abs(np.array(got) - ref).max()) / scale < DOUBLE_TOLERANCE

    @pytest.mark.parametrize("language", ["c", "glsl", "hlsl"])
    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_engine_table_is_the_plan(self, exported: Exported, language: str, name: str, bands: int) -> None:
        """The (output, input, factor) terms and the offsets of skysh/export/templates/c_like_engine.h rebuild the
        plan's matrix and offset (double in C, float32 in the shaders, exactly), each output's terms in column order."""
        source, plan = exported(language, bands=bands, engine=name), engine_plan(name, bands)
        dtype = np.float64 if language == "c" else np.float32
        count = plan.offset.size
        assert f"#define SKYSH_ENGINE_COUNT {count}" in source
        assert ("int" if language == "c" else "bool") + " skysh_engine_coefficients(" in source
        outputs, inputs = (parse_table(source, f"SKYSH_ENGINE_{part}", np.float64).astype(int) for part in ("OUTPUT", "INPUT"))
        factors = parse_table(source, "SKYSH_ENGINE_FACTOR", dtype)
        assert f"#define SKYSH_ENGINE_TERMS {factors.size}" in source and outputs.size == inputs.size == factors.size
        rebuilt = np.zeros(plan.matrix.shape, dtype=dtype)
        rebuilt[outputs, inputs] = factors
        np.testing.assert_array_equal(rebuilt, plan.matrix.astype(dtype))
        assert np.all(np.diff(outputs * plan.matrix.shape[1] + inputs) > 0)  # row-major, no repeated term
        np.testing.assert_array_equal(parse_table(source, "SKYSH_ENGINE_OFFSET", dtype), plan.offset.astype(dtype))
        np.testing.assert_array_equal(parse_table(source, "SKYSH_ENGINE_BAND", dtype), plan.band_factor.astype(dtype))
        for open_, close in ("()", "{}", "[]"):
            assert source.count(open_) == source.count(close)

    @pytest.mark.integration
    @pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    @pytest.mark.parametrize(("name", "bands"), engine_cases())
    def test_shader_compiles(self, exported: Exported, tool_runs: ToolRuns, language: str, name: str, bands: int) -> None:
        source = exported(language, bands=bands, engine=name)
        result = tool_runs.run(*glslang_job(engine_shader(source, language), language)).result
        assert result.returncode == 0, result.stdout + result.stderr


class TestShaderExport:
    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    @pytest.mark.parametrize("bands", [1, 3, 7])
    def test_structure(self, sky: SkySH, exported: Exported, language: str, bands: int) -> None:
        source = exported(language, bands=bands)
        tables = export_tables(sky, bands)
        table = parse_shader_table(source)
        stored = tables.table  # one band: the unfiltered c_10 follows as row 1 (the ground's E_h)
        if bands == 1:
            stored = np.concatenate([stored, tables.lights.c10[:, :, None, :]], axis=2)
        assert table.shape == (stored[..., 0].size, 3)
        np.testing.assert_array_equal(table, as_stored(stored).astype(np.float32))  # exact float32 round trip
        for open_, close in ("()", "{}", "[]"):
            assert source.count(open_) == source.count(close)
        assert f"#define SKYSH_COUNT {bands * bands}" in source
        vec3 = "vec3" if language == "glsl" else "float3"
        assert f"out {vec3} coeffs[SKYSH_COUNT]" in source and "bool skysh_coefficients(" in source
        assert not re.search(r"\bdouble\b", source) and not re.search(r"^#version", source, re.MULTILINE)

    @pytest.mark.parametrize("bands", [1, 3, 7])
    def test_float32_tables(self, sky: SkySH, exported: Exported, bands: int) -> None:
        assert shader_float32_table_error(sky, exported("glsl", bands=bands), bands) < FLOAT32_TABLE_TOLERANCE

    @pytest.mark.integration
    @pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
    @pytest.mark.parametrize("version", GLSL_VERSIONS)
    @pytest.mark.parametrize("bands", SHADER_BANDS)
    def test_glsl_compiles(self, exported: Exported, tool_runs: ToolRuns, bands: int, version: str) -> None:
        result = tool_runs.run(*glslang_job(sky_shader(exported("glsl", bands=bands), version), "glsl")).result
        assert result.returncode == 0, result.stdout + result.stderr

    @pytest.mark.integration
    @pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
    @pytest.mark.parametrize("bands", SHADER_BANDS)
    def test_hlsl_compiles(self, exported: Exported, tool_runs: ToolRuns, bands: int) -> None:
        result = tool_runs.run(*glslang_job(sky_shader(exported("hlsl", bands=bands), "hlsl"), "hlsl")).result
        assert result.returncode == 0, result.stdout + result.stderr


def evaluate_table(table: np.ndarray, source: Any, p: tuple, irradiance: bool) -> np.ndarray:
    """3-band coefficients from a table (DX+1, DY+1, 6, 3) as the exports document it (no Gibbs filter); ``source``
    gives the maps and factors: the JSON payload or :func:`skysh.export.tables.export_tables`' numbers."""
    if isinstance(source, dict):
        x_map, y_map = (source["x"]["scale"], source["x"]["shift"]), (source["y"]["scale"], source["y"]["shift"])
        gibbs, lobe = np.array(source["gibbs"]), np.array(source["lobe"])
    else:
        x_map, y_map, gibbs, lobe = (source.x_scale, source.x_shift), (source.y_scale, source.y_shift), source.gibbs, source.lobe
    return evaluate_tables(table, gibbs, lobe, x_map, y_map, 3, p[0], p[1], math.fmod(p[2], 2.0 * math.pi), False, irradiance)


class TestShaderIrradianceTable:
    """The shaders' SKYSH_IRRADIANCE (float32, evaluated in double as documented) against the runtime's table."""

    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    def test_round_trip_and_presence(self, sky: SkySH, exported: Exported, language: str) -> None:
        source = exported(language, bands=3)
        table = parse_shader_table(source, "SKYSH_IRRADIANCE")
        np.testing.assert_array_equal(table, as_stored(export_tables(sky, 3).irradiance).astype(np.float32))
        assert "#define SKYSH_IRRADIANCE_TABLE 1" in source
        for bands in (1, 7):  # no table: irradianceTable 1 is refused, by intent is the sky's pipeline
            other = exported(language, bands=bands)  # (its declaration, empty, is skipped by #if SKYSH_IRRADIANCE_TABLE)
            assert "#define SKYSH_IRRADIANCE_TABLE 0" in other and parse_shader_table(other, "SKYSH_IRRADIANCE").size == 0

    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    def test_float32_table_matches_the_runtime(self, sky: SkySH, exported: Exported, language: str) -> None:
        """Radiance-equivalent and irradiance at the table points; the sky's own rows (SKYSH_TABLE) evaluated the
        same way miss the runtime's table (negative control)."""
        source, tables = exported(language, bands=3), export_tables(sky, 3)
        shape = tables.irradiance.shape
        table = terms_major(parse_shader_table(source, "SKYSH_IRRADIANCE").astype(np.float64), shape)
        sky_rows = terms_major(parse_shader_table(source).astype(np.float64), shape)
        worst = control = 0.0
        for p in table_points()[::4]:
            ref = sky.coefficients(*p[:3], bands=3, irradiance=bool(p[4]), irradiance_table=True)
            worst = max(worst, dc_relative_error(evaluate_table(table, tables, p, bool(p[4])), ref))
            control = max(control, dc_relative_error(evaluate_table(sky_rows, tables, p, bool(p[4])), ref))
        assert worst < FLOAT32_TABLE_TOLERANCE < CONTROL_MARGIN * FLOAT32_TABLE_TOLERANCE < control

    def test_float32_table_is_never_negative(self, sky: SkySH, exported: Exported) -> None:
        tables = export_tables(sky, 3)
        table = terms_major(parse_shader_table(exported("glsl", bands=3), "SKYSH_IRRADIANCE").astype(np.float64),
                            tables.irradiance.shape)
        rng = np.random.default_rng(1803)
        got = np.array([evaluate_table(table, tables, (z, t, a), True) for z, t, a in
                        zip(rng.uniform(0.0, math.pi / 2.0, 1000), rng.uniform(2.5, 6.0, 1000), rng.uniform(-3.0, 3.0, 1000))])
        assert relative_minimum(got).min() >= 0.0

    @pytest.mark.integration
    @pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
    @pytest.mark.parametrize("version", CHOICE_VERSIONS)
    @pytest.mark.parametrize("engine", CHOICE_ENGINES)
    def test_compiles_with_every_choice(self, exported: Exported, tool_runs: ToolRuns, version: str, engine: str | None) -> None:
        """irradianceTable from a uniform (every value reaches the code), with and without an engine."""
        language = "hlsl" if version == "hlsl" else "glsl"
        shader = choice_shader(exported(language, bands=3, engine=engine), version, engine)
        result = tool_runs.run(*glslang_job(shader, language)).result
        assert result.returncode == 0, result.stdout + result.stderr


class TestJsonIrradianceTable:
    def test_block_matches_the_runtime(self, sky: SkySH, exported: Exported) -> None:
        """The block's table evaluated as its text says (radiance-equivalent and irradiance) against the runtime's
        irradiance_table=True; the sky's own table in its place misses (negative control)."""
        payload = json.loads(exported("json", bands=3))
        block = payload["irradiance_table"]
        assert block["available"] and "by intent" in block["rule"]
        table, sky_rows = np.array(block["table"]), np.array(payload["table"])
        worst = control = 0.0
        for p in table_points()[::5]:
            ref = sky.coefficients(*p[:3], bands=3, irradiance=bool(p[4]), irradiance_table=True)
            worst = max(worst, dc_relative_error(evaluate_table(table, payload, p, bool(p[4])), ref))
            control = max(control, dc_relative_error(evaluate_table(sky_rows, payload, p, bool(p[4])), ref))
        assert worst < DOUBLE_TOLERANCE < CONTROL_MARGIN * DOUBLE_TOLERANCE < control

    @pytest.mark.parametrize("bands", [1, 7])
    def test_other_band_counts_have_none(self, exported: Exported, bands: int) -> None:
        block = json.loads(exported("json", bands=bands))["irradiance_table"]
        assert not block["available"] and "table" not in block

    @pytest.mark.parametrize("name", [name for name, bands in engine_cases() if bands == 3])
    def test_engine_plan_on_the_table(self, sky: SkySH, exported: Exported, name: str) -> None:
        """The JSON engine block applied to the table's radiance-equivalent: engines.convert of the runtime's."""
        payload = json.loads(exported("json", bands=3, engine=name))
        engine, table = payload["engine"], np.array(payload["irradiance_table"]["table"])
        pts = [p for p in engine_points() if not p[3]][::3]
        factor = np.array(engine["band_factor"])[sh.band_of_index(3)][:, None]
        got = [np.array(engine["matrix"]) @ (factor * evaluate_table(table, payload, p, False)).reshape(-1)
               + np.array(engine["offset"]) for p in pts]
        ref, scale = engine_reference(sky, [(*p, 1, 1) for p in pts], name, 3)
        assert float(np.abs(np.array(got) - ref).max()) / scale < DOUBLE_TOLERANCE


class TestJsonExport:
    @pytest.mark.parametrize("bands", [1, 4, 7])
    def test_independent_evaluation_matches_runtime(self, sky: SkySH, exported: Exported, bands: int) -> None:
        payload = json.loads(exported("json", bands=bands))
        assert payload["bands"] == bands and payload["format"] == "skysh-export"
        table = np.array(payload["table"])
        assert table.shape == (payload["degrees"][0] + 1, payload["degrees"][1] + 1, bands * (bands + 1) // 2, 3)
        assert payload["half_layout"] == [[l, m] for l in range(bands) for m in range(l + 1)]
        pts = points()[::5]
        got = np.array([
            evaluate_tables(
                table, np.array(payload["gibbs"]), np.array(payload["lobe"]),
                (payload["x"]["scale"], payload["x"]["shift"]), (payload["y"]["scale"], payload["y"]["shift"]),
                bands, ts, t, phi, bool(g), bool(e),
            )
            for ts, t, phi, g, e in pts
        ])
        assert dc_relative_error(got, runtime_values(sky, pts, bands)) < DOUBLE_TOLERANCE


class TestExportSource:
    def test_tables_come_from_the_runtime_plan(self, sky: SkySH) -> None:
        tables = export_tables(sky, 3)
        plan = sky.plan(3, False)
        np.testing.assert_array_equal(tables.table.reshape(plan.half_table.shape), plan.half_table)
        assert tables.degrees == plan.degrees
        from skysh.domain import SKY  # the variables' maps: the same doubles as the runtime's

        assert (tables.x_scale, tables.x_shift, tables.y_scale, tables.y_shift) == (
            SKY.x.scale, SKY.x.shift, SKY.y.scale, SKY.y.shift)
        radiance_equivalent = sky._table_plans[False]  # the runtime's plan of the irradiance table (no lobe)
        assert tables.degrees == radiance_equivalent.degrees  # the shipped file: the same degrees as the sky's
        np.testing.assert_array_equal(tables.irradiance.reshape(radiance_equivalent.half_table.shape),
                                      radiance_equivalent.half_table)

    @pytest.mark.parametrize("kwargs", [{"language": "wgsl"}, {"language": "c", "bands": 8},
                                        {"language": "c", "bands": 0}, {"language": "c", "real": "half"}])
    def test_refuses_bad_arguments(self, sky: SkySH, kwargs: dict) -> None:
        with pytest.raises(ValueError):
            export_source(sky, **kwargs)

    def test_every_format_ends_with_a_newline(self, sky: SkySH) -> None:
        for language in EXPORT_FORMATS:
            assert export_source(sky, language, bands=2).endswith("\n")


class TestExportCommand:
    def test_writes_the_file(self, sky: SkySH, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        out = tmp_path / "sky.glsl"
        assert cli.main(["export", "--format", "glsl", "--bands", "2", "--out", str(out)]) == 0
        assert out.read_text() == export_source(sky, "glsl", bands=2)
        assert "wrote" in capsys.readouterr().out

    def test_standard_output(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        assert cli.main(["export", "--format", "c", "--c-real", "float", "--out", "-"]) == 0
        assert capsys.readouterr().out == export_source(sky, "c", bands=3, real="float")

    @pytest.mark.parametrize("argv", [["--format", "c", "--bands", "8"], ["--format", "wgsl"], ["--format", "c"]])
    def test_bad_values_exit_2(self, argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        extra = [] if "--out" in argv or argv == ["--format", "c"] else ["--out", str(tmp_path / "x")]
        assert cli.main(["export", *argv, *extra]) == 2
        err = capsys.readouterr().err
        assert err.startswith("skysh: error: ") and err.count("\n") == 1


def figures() -> list[dict]:
    """The measured errors (relative to the worst channel's DC) printed by ``python tests/export/test_export.py``."""
    import tempfile

    sky = SkySH.load()
    rows = []
    with tempfile.TemporaryDirectory() as directory:
        runs = ToolRuns(Path(directory))
        for bands in (1, 3, 7):
            if CC is not None:
                for real in ("double", "float"):
                    error = c_error(sky, export_source(sky, "c", bands=bands, real=real), bands, runs)
                    rows.append({"export": f"c ({real})", "bands": bands, "error": error})
            rows.append({"export": "glsl/hlsl float32 tables, double arithmetic", "bands": bands,
                         "error": shader_float32_table_error(sky, export_source(sky, "glsl", bands=bands), bands)})
        rows += table_figures(sky, runs)
        runs.close()
    return rows


def table_figures(sky: SkySH, runs: ToolRuns) -> list[dict]:
    """The irradiance table's figures: every setting of irradiance_table against the runtime (C), the shaders'
    float32 table in double arithmetic, and the least exact minimum over the mean of the exported table."""
    rows = []
    pts = table_points()
    if CC is not None:
        for real in ("double", "float"):
            binary = compile_harness(export_source(sky, "c", bands=3, real=real), runs)
            chosen = [p for p in pts if real == "double" or abs(p[2]) < 10.0]
            rows.append({"export": f"c ({real}), every irradiance_table setting", "bands": 3, "points": len(chosen),
                         "error": table_error(sky, binary, chosen, 3)[0]})
            rng = np.random.default_rng(1802)
            frames = zip(rng.uniform(0.0, math.pi / 2.0, NONNEGATIVE_POINTS), rng.uniform(2.5, 6.0, NONNEGATIVE_POINTS))
            _, table = run_c(binary, [(float(z), float(t), 0.3, 0, 1, 1, BY_INTENT) for z, t in frames])
            rows.append({"export": f"c ({real}) tabulated irradiance", "measure": "least exact minimum / mean",
                         "points": NONNEGATIVE_POINTS, "value": float(relative_minimum(table).min())})
    tables = export_tables(sky, 3)
    table = terms_major(parse_shader_table(export_source(sky, "glsl", bands=3), "SKYSH_IRRADIANCE").astype(np.float64),
                        tables.irradiance.shape)
    worst = max(dc_relative_error(evaluate_table(table, tables, p, bool(p[4])),
                                  sky.coefficients(*p[:3], irradiance=bool(p[4]), irradiance_table=True)) for p in pts)
    rows.append({"export": "glsl/hlsl float32 irradiance table, double arithmetic", "bands": 3, "error": worst})
    return rows


if __name__ == "__main__":
    for row in figures():
        print(json.dumps({"measure": "max |export - runtime| / |DC|, worst channel, worst point", **row}))
    sys.exit(0)
