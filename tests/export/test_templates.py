"""
The C, GLSL and HLSL exports' source files as they stand (skysh/export/templates/c_like_*)
==========================================================================================

The exports are one C-like kernel (``c_like_kernel.h`` and its deringing ``c_like_dering3.h``, in C at 5..7
bands ``c_like_dering_certificate_c.h``) over the words
of each language (``c_like_words_c.h``, ``c_like_words_glsl.glsl``, ``c_like_words_hlsl.hlsl``, the shaders'
shared ``c_like_words_shader.glsl`` and the math names ``c_like_words_math.h``:
:data:`skysh.export.dering.WORDS`), the public functions in C's and in the shaders' spelling
(``c_like_api_c.h``, ``c_like_api_shader.glsl`` with GLSL's or HLSL's RGB type:
:data:`skysh.export.c_like.API`) and a data section that :mod:`skysh.export.c_like` fills with numbers. Here
the shipped files are checked as they are, against ``tests/export/data/c_like_small.h``, a small data section
written by hand in the data section's layout (four Chebyshev terms, short made-up tables, the real constants
of the domain, the models and the deringing, and a four-value engine):

-   C: the files compiled as C99 in double and in float (``SKYSH_FLOAT``) and as C++11, every warning an
    error, inside the export tests' harness (:data:`test_export_lights.C_HARNESS`); the double build's
    numbers against an independent numpy evaluation of the small data, written from the documented
    steps (the sky with the Gibbs filter; the irradiance table with the clamped cosine; the deringed
    irradiance, against :func:`skysh.post.dering.dering`; the engine's terms; the sun's light), and its
    refusals (-1, -3, -5).
-   GLSL 3.30 and ES 3.00 and HLSL: the same files validated by glslangValidator, every public function
    called.
-   The public functions of real exports after the preprocessor (``cc -E``, ``glslangValidator -E``):
    today's return and parameter types in today's order, in C, GLSL and HLSL.
-   The templates' holes (none in a code file, the data files' listed) and :mod:`skysh.export.template`'s
    refusals.

Tests that run a compiler or glslangValidator carry the ``integration`` marker.
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from background import GLSLANG, RUN_DIR, ToolJob, ToolRuns, glslang_job
from conftest import SKIP_NO_CC, SKIP_NO_GLSLANG, Exported
from test_export_lights import C_HARNESS, CC, parse_table

from skysh.export import c_like, template
from skysh.export import dering as export_dering
from skysh.model import preetham
from skysh.post import dering

DATA: Path = Path(__file__).resolve().parent / "data"
"""The small data section (``c_like_small.h``) and the header that puts it before the kernel."""

CXX: str | None = shutil.which("c++") or shutil.which("g++") or shutil.which("clang++")
"""The machine's C++ compiler, or None (the C++ build then skips)."""

KERNEL_FILES: tuple[str, ...] = ("c_like_words_c.h", "c_like_dering3.h", "c_like_kernel.h", "c_like_api_c.h")
"""The C build's templates, in the order ``c_like_small_kernel.h`` includes them (around the data); its
``c_like_words_c.h`` stands for all the C words (:data:`skysh.export.dering.WORDS`, one after another)."""

HOLES: dict[str, frozenset[str]] = {name: frozenset(holes) for name, holes in {
    "c_like_words_c.h": (), "c_like_words_glsl.glsl": (), "c_like_words_hlsl.hlsl": (), "c_like_words_shader.glsl": (),
    "c_like_words_math.h": (), "c_like_dering3.h": (), "c_like_dering_certificate_c.h": (), "c_like_kernel.h": (),
    "c_like_api_c.h": (),
    "c_like_api_shader.glsl": ("VEC3",),
    "c_like_data.h": ("DEFINES", "TABLE", "GIBBS", "LOBE", "PEREZ", "IRRADIANCE", "SUN_TABLE", "SUN_RGB", "SUN_TRIG",
                      "GROUND"),
    "c_like_engine.h": ("NAME", "SHAPE", "COUNT", "TERMS", "BAND", "OUTPUT", "INPUT", "FACTOR", "OFFSET"),
    "c_like_notice.txt": ("VERSION", "BANDS", "LANGUAGE", "OPTIONS", "LAST_L", "SUN_ZENITH_DOMAIN", "TURBIDITY_DOMAIN",
                          "PRECISION", "ENGINE"),
    "c_like_notice_engine.txt": ("ENGINE", "COUNT", "SHAPE"),
    "c_like_frame_c.h": ("NOTICE", "FLOAT", "BODY"), "c_like_frame_shader.glsl": ("NOTICE", "BODY"),
}.items()}
"""Every C-like template and its holes: the code files have none but the shaders' RGB type, the data files numbers
and switches only."""

TOLERANCE: float = 1e-12
"""The double build against numpy on the same numbers, over the largest |value| of the case: a few roundings of
sums of a handful of terms, the luminance scale's tan and exp, and the sun's pow and exp (measured about 1e-15)."""

FLOAT_TOLERANCE: float = 1e-5
"""The float build (SKYSH_FLOAT 1) against the double one on the small data, over the largest |value|."""

SUN_DIRECTION_TOLERANCE: float = 1e-15
"""The sun's unit vector: sin, cos and fmod of the same doubles."""

BUILDS: dict[str, list[str]] = {"double": ["-std=c99", "-pedantic", "-DSKYSH_FLOAT=0"],
                                "float": ["-std=c99", "-pedantic", "-DSKYSH_FLOAT=1"],
                                "c++": ["-x", "c++", "-std=c++11", "-DSKYSH_FLOAT=0"]}
"""The builds of the kernel as it stands: C99 in double and in float, C++11."""

Line = tuple  # (engine, ts, t, phi, gibbs, dering, irradiance, sun, null_albedo, (r, g, b), irradiance_table)
"""One call of the harness (its input line, test_export_lights.C_HARNESS)."""


def small_files() -> dict[str, str]:
    """The files of the C build, each as it stands: the templates (the C words joined), the small data, the harness."""
    files = {name: template.text(name) for name in KERNEL_FILES} | {"c_like_words_c.h": export_dering.words("c")}
    files.update({p.name: p.read_text(encoding="utf-8") for p in (DATA / "c_like_small.h", DATA / "c_like_small_kernel.h")})
    return files | {"harness.c": C_HARNESS}


def small_job(build: str) -> ToolJob:
    """The harness around the small kernel (:data:`BUILDS`), C99 or C++, -O2 -Wall -Wextra -Werror."""
    tool = CXX if build == "c++" else CC
    assert tool is not None
    return ([tool, *BUILDS[build], "-O2", "-Wall", "-Wextra", "-Werror", '-DSKYSH_HEADER="c_like_small_kernel.h"',
             f"-I{RUN_DIR}", "-o", f"{RUN_DIR}/harness", f"{RUN_DIR}/harness.c", "-lm"], small_files())


def run_small(runs: ToolRuns, build: str, lines: list[Line]) -> list[np.ndarray]:
    """The harness of ``build`` at ``lines``: per line its printed numbers (test_export_lights.C_HARNESS)."""
    if (CXX if build == "c++" else CC) is None:
        pytest.skip(SKIP_NO_CC)
    done = runs.run(*small_job(build))
    assert done.result.returncode == 0, done.result.stderr
    text = "".join(f"{p[0]} {p[1]!r} {p[2]!r} {p[3]!r} {p[4]} {p[5]} {p[6]} {p[7]} {p[8]} "
                   + " ".join(map(repr, p[9])) + f" {p[10]}\n" for p in lines)
    out = subprocess.run([str(done.directory / "harness")], input=text, capture_output=True, text=True, check=True)
    return [np.array(line.split(), dtype=np.float64) for line in out.stdout.splitlines()]


# --------------------------------------------------------------------------- #
# An independent evaluation of the small data, from the documented steps
# --------------------------------------------------------------------------- #
class Small:
    """The numbers of ``c_like_small.h`` (its double branch) and the steps the kernel documents, in numpy."""

    def __init__(self) -> None:
        text = (DATA / "c_like_small.h").read_text(encoding="utf-8")
        self.defines = {k: v for k, v in re.findall(r"^#define (SKYSH_\w+) (.+)$", text, re.MULTILINE)}
        self.tables = {name: parse_table(text, name, np.float64) for name in re.findall(r"^SKYSH_CONST \w+ (\w+)\[",
                                                                                        text, re.MULTILINE)}

    def number(self, name: str) -> float:
        return float(self.defines[f"SKYSH_{name}"])

    def sky(self, ts: float, t: float, phi: float, gibbs: bool, table: bool, band: np.ndarray) -> np.ndarray:
        """Steps 2 to 5 and the per-band factor ``band``: (9, 3)."""
        x = min(1.0, max(-1.0, ts * self.number("X_SCALE") - self.number("X_SHIFT")))
        y = min(1.0, max(-1.0, math.log(t) * self.number("Y_SCALE") - self.number("Y_SHIFT")))
        rows = self.tables["SKYSH_IRRADIANCE" if table else "SKYSH_TABLE"].reshape(4, 6, 3)  # term-major
        acc = np.einsum("q,qrc->rc", np.outer([1.0, x], [1.0, y]).ravel(), rows)  # term q = i (DY + 1) + j
        scale = float(preetham.luminance_scale(ts, t))
        out = np.zeros((9, 3))
        for l in range(3):
            row = l * (l + 1) // 2
            if gibbs:
                acc[row] *= self.tables["SKYSH_GIBBS"][l]
            for m in range(-l, l + 1):
                rot = math.sin(-m * phi) if m < 0 else math.cos(m * phi)
                out[l * (l + 1) + m] = acc[row + abs(m)] * rot * band[l] * scale
        return out

    def engine(self, sh: np.ndarray) -> np.ndarray:
        """Step 9: the (output, input, factor) terms and the offsets."""
        values = self.tables["SKYSH_ENGINE_OFFSET"].copy()
        for p, q, f in zip(self.tables["SKYSH_ENGINE_OUTPUT"].astype(int), self.tables["SKYSH_ENGINE_INPUT"].astype(int),
                           self.tables["SKYSH_ENGINE_FACTOR"]):
            values[p] += f * sh.reshape(-1)[q]
        return values

    def sun_rgb(self, ts: float, t: float) -> np.ndarray:
        """The sun's RGB: Kasten's air mass, the sun table's Chebyshev sum of ln XYZ, exp, XYZ -> RGB."""
        m = 1.0 / (math.cos(ts) + self.number("KASTEN_A") * (self.number("KASTEN_B") - math.degrees(ts)) ** self.number(
            "KASTEN_NEG_C"))
        x = min(1.0, max(-1.0, (m - self.number("SUN_M0")) * self.number("SUN_X_SCALE") - 1.0))
        y = min(1.0, max(-1.0, (t - self.number("SUN_TMIN")) * self.number("SUN_Y_SCALE") - 1.0))
        ln = np.einsum("q,qc->c", np.outer([1.0, x], [1.0, y]).ravel(), self.tables["SKYSH_SUN_TABLE"].reshape(4, 3))
        return self.tables["SKYSH_SUN_RGB"].reshape(3, 3) @ np.exp(ln)


FRAMES: list[tuple[float, float, float]] = [(0.0, 2.5, 0.0), (0.6, 3.2, 0.7), (1.2, 5.1, -20.0), (math.pi / 2.0, 6.0, 3.0)]
"""Frames of the small checks: the domain's corners and two inside it, azimuths beyond 2 pi included."""


def relative(got: np.ndarray, want: np.ndarray) -> float:
    return float(np.abs(got - want).max() / np.abs(want).max())


@pytest.fixture(scope="module")
def small() -> Small:
    return Small()


@pytest.mark.integration
class TestSmallKernelInC:
    def test_the_sky_matches_numpy(self, small: Small, tool_runs: ToolRuns) -> None:
        """Radiance with the Gibbs filter (the sky's rows), and irradiance from the certified table (irradiance_table
        1: its rows, the clamped cosine A_l)."""
        lobe, ones = small.tables["SKYSH_LOBE"], np.ones(3)
        lines = [(0, *f, 1, 0, 0, 0, 1, (0.0,) * 3, 0) for f in FRAMES] + [(0, *f, 0, 0, 1, 0, 1, (0.0,) * 3, 1) for f in FRAMES]
        rows = run_small(tool_runs, "double", lines)
        for line, row in zip(lines, rows):
            assert row[0] == 0, line
            table = line[10] == 1
            want = small.sky(*line[1:4], gibbs=bool(line[4]), table=table, band=lobe if table else ones)
            assert relative(row[8:].reshape(9, 3), want) < TOLERANCE, line

    def test_the_deringing_is_python_s(self, small: Small, tool_runs: ToolRuns) -> None:
        """Irradiance from the sky's rows, deringed (skysh.post.dering.dering of the same radiance), then A_l."""
        lobe = small.tables["SKYSH_LOBE"]
        lines = [(0, *f, 0, 1, 1, 0, 1, (0.0,) * 3, 0) for f in FRAMES]
        for line, row in zip(lines, run_small(tool_runs, "double", lines)):
            radiance = small.sky(*line[1:4], gibbs=False, table=False, band=np.ones(3))
            want = dering.dering(radiance, target="irradiance")[0] * lobe[[0, 1, 1, 1, 2, 2, 2, 2, 2]][:, None]
            assert row[0] == 0 and relative(row[8:].reshape(9, 3), want) < TOLERANCE, line

    def test_the_engine_terms(self, small: Small, tool_runs: ToolRuns) -> None:
        band = small.tables["SKYSH_ENGINE_BAND"]
        lines = [(1, *f, g, 0, 0, 0, 1, (0.0,) * 3, 0) for f in FRAMES for g in (0, 1)]
        for line, row in zip(lines, run_small(tool_runs, "double", lines)):
            want = small.engine(small.sky(*line[1:4], gibbs=bool(line[4]), table=False, band=band))
            assert row[0] == 0 and row.size == 5 and relative(row[1:], want) < TOLERANCE, line

    def test_the_sun_light(self, small: Small, tool_runs: ToolRuns) -> None:
        lines = [(0, *f, 0, 0, 0, 1, 1, (0.0,) * 3, 0) for f in FRAMES]
        for (_, ts, t, phi, *_), row in zip(lines, run_small(tool_runs, "double", lines)):
            phi = math.fmod(phi, 2.0 * math.pi)
            direction = [math.sin(ts) * math.cos(phi), math.sin(ts) * math.sin(phi), math.cos(ts)]
            assert row[1] == 0 and np.abs(row[2:5] - direction).max() <= SUN_DIRECTION_TOLERANCE
            assert relative(row[5:8], small.sun_rgb(ts, t)) < TOLERANCE

    def test_refusals(self, tool_runs: ToolRuns) -> None:
        """-1 outside the domain (the sun's light too), -3 an albedo beyond 1, -5 the table with the Gibbs filter;
        every output zeroed."""
        lines = [(0, 1.6, 3.0, 0.0, 0, 0, 0, 1, 0, (0.0,) * 3, -1), (0, 0.5, 3.0, math.inf, 0, 0, 0, 0, 0, (0.0,) * 3, -1),
                 (0, 0.5, 3.0, 0.0, 0, 0, 0, 0, 0, (0.2, 1.5, 0.2), -1), (0, 0.5, 3.0, 0.0, 1, 0, 1, 0, 0, (0.0,) * 3, 1),
                 (1, 0.5, 7.0, 0.0, 0, 0, 0, 0, 0, (0.0,) * 3, -1)]
        rows = run_small(tool_runs, "double", lines)
        assert [row[0] for row in rows] == [-1, -1, -3, -5, -1]
        assert rows[0][1] == -1 and rows[1][1] == -1 and all(np.all(row[2:] == 0.0) for row in rows[:2])
        assert all(np.all(row[8:] == 0.0) for row in rows[2:4]) and np.all(rows[4][1:] == 0.0)

    @pytest.mark.parametrize("build", ["float", "c++"])
    def test_other_builds(self, tool_runs: ToolRuns, build: str) -> None:
        """The float build (skysh_real float, float arithmetic) and C++11 compile cleanly and agree with the double
        build, with the sun, a ground, deringing and the engine (inside the domain: the small data's edges are
        double literals, which a float frame rounded up at pi / 2 would exceed)."""
        lines = [(e, *f, 0, 1, 1, 1, 0, (0.2, 0.3, 0.1), -1) for f in FRAMES[1:3] for e in (0, 1)]
        tolerance = FLOAT_TOLERANCE if build == "float" else 0.0
        for line, got, want in zip(lines, run_small(tool_runs, build, lines), run_small(tool_runs, "double", lines)):
            assert got[0] == want[0] == 0 and relative(got, want) <= tolerance, line


SHADER_MAIN: dict[str, str] = {
    "glsl": "uniform vec4 params;\nuniform vec3 albedo;\nout vec4 colour;\nvoid main() {\n    vec3 c[SKYSH_COUNT];\n"
            "    float v[SKYSH_ENGINE_COUNT];\n    vec3 d;\n    vec3 rgb;\n"
            "    bool ok = skysh_coefficients(params.x, params.y, params.z, true, params.w > 0.0, true, true, albedo,\n"
            "                                 SKYSH_BY_INTENT, c);\n"
            "    bool engine = skysh_engine_coefficients(params.x, params.y, params.z, false, true, true, albedo, 1, v);\n"
            "    bool lit = skysh_sun_light(params.x, params.y, params.z, d, rgb);\n"
            "    colour = vec4(c[0] + c[SKYSH_COUNT - 1] + d + rgb, v[3] + (ok && lit && engine ? 1.0 : 0.0));\n}\n",
    "hlsl": "float4 params;\nfloat3 albedo;\nfloat4 main() : SV_Target {\n    float3 c[SKYSH_COUNT];\n"
            "    float v[SKYSH_ENGINE_COUNT];\n    float3 d;\n    float3 rgb;\n"
            "    bool ok = skysh_coefficients(params.x, params.y, params.z, true, params.w > 0.0, true, true, albedo,\n"
            "                                 SKYSH_BY_INTENT, c);\n"
            "    bool engine = skysh_engine_coefficients(params.x, params.y, params.z, false, true, true, albedo, 1, v);\n"
            "    bool lit = skysh_sun_light(params.x, params.y, params.z, d, rgb);\n"
            "    return float4(c[0] + c[SKYSH_COUNT - 1] + d + rgb, v[3] + (ok && lit && engine ? 1.0 : 0.0));\n}\n",
}
"""Fragment shaders calling every public function of the small kernel."""


def small_shader(version: str) -> tuple[str, str]:
    """(language, shader): the words of ``version``'s language, the small data, the deringing, the kernel and the
    language's public functions, each file as it stands, and a main calling every one of them."""
    language = "hlsl" if version == "hlsl" else "glsl"
    body = "\n".join([export_dering.words(language), (DATA / "c_like_small.h").read_text(encoding="utf-8"),
                      template.text("c_like_dering3.h"), template.text("c_like_kernel.h"), c_like.api_source(language),
                      SHADER_MAIN[language]])
    if language == "hlsl":
        return language, body
    return language, f"#version {version}\n" + ("precision highp float;\n" if version.endswith("es") else "") + body


@pytest.mark.integration
@pytest.mark.skipif(GLSLANG is None, reason=SKIP_NO_GLSLANG)
@pytest.mark.parametrize("version", ["330", "300 es", "hlsl"])
def test_the_small_kernel_validates_as_a_shader(tool_runs: ToolRuns, version: str) -> None:
    result = tool_runs.run(*glslang_job(*reversed(small_shader(version)))).result
    assert result.returncode == 0, result.stdout + result.stderr


# --------------------------------------------------------------------------- #
# The public functions of real exports, after the preprocessor
# --------------------------------------------------------------------------- #
SIGNATURES: dict[str, dict[str, tuple[str, ...]]] = {
    "c": {"skysh_coefficients": ("int", "skysh_real", "skysh_real", "skysh_real", "int", "int", "int", "int",
                                 "const skysh_real *", "int", "skysh_real [9][3]"),
          "skysh_engine_coefficients": ("int", "skysh_real", "skysh_real", "skysh_real", "int", "int", "int",
                                        "const skysh_real *", "int", "skysh_real [27]"),
          "skysh_sun_light": ("int", "skysh_real", "skysh_real", "skysh_real", "skysh_real [3]", "skysh_real [3]"),
          "skysh_dering": ("int", "double [9][3]", "double [3]", "double [1]")},
    "glsl": {"skysh_coefficients": ("bool", "float", "float", "float", "bool", "bool", "bool", "bool", "vec3", "int",
                                    "out vec3 [9]"),
             "skysh_engine_coefficients": ("bool", "float", "float", "float", "bool", "bool", "bool", "vec3", "int",
                                           "out float [27]"),
             "skysh_sun_light": ("bool", "float", "float", "float", "out vec3", "out vec3"),
             "skysh_dering": ("int", "inout float [3 * 9]", "out float [3]", "out float [1]")},
}
"""The public functions' (return type, parameter types...) as before the kernel (3 bands, engine "unity": 27 values);
HLSL's are GLSL's with float3."""
SIGNATURES["hlsl"] = {name: tuple(t.replace("vec3", "float3") for t in types) for name, types in SIGNATURES["glsl"].items()}


def signature(text: str, name: str) -> tuple[str, ...]:
    """(return type, parameter types...) of the definition of ``name`` in preprocessed ``text``, names left out."""
    found = re.search(rf"(\w+)\s+{name}\s*\(([^)]*)\)\s*\{{", text)
    assert found is not None, name
    types = [re.sub(r"\s*\b\w+\s*((?:\[[^\]]*\]\s*)*)$", r" \1", p.strip()) for p in found.group(2).split(",")]
    return (found.group(1), *(" ".join(t.replace("[", " [").replace("] [", "][").split()) for t in types))


def preprocessed(source: str, language: str, directory: Path) -> str:
    """``source`` after the preprocessor: cc -E for C, glslangValidator -E for the shaders."""
    path = directory / {"c": "sky_sh.h", "glsl": "sky.frag", "hlsl": "sky.hlsl"}[language]
    path.write_text(source if language != "glsl" else "#version 330\n" + source)
    command = {"c": [str(CC), "-E", "-P", "-x", "c", str(path)], "glsl": [str(GLSLANG), "-E", str(path)],
               "hlsl": [str(GLSLANG), "-D", "-E", "-S", "frag", "-e", "main", str(path)]}[language]
    return subprocess.run(command, capture_output=True, text=True, check=True).stdout


@pytest.mark.integration
@pytest.mark.parametrize("language", ["c", "glsl", "hlsl"])
def test_public_signatures_are_today_s(exported: Exported, tmp_path: Path, language: str) -> None:
    if (CC if language == "c" else GLSLANG) is None:
        pytest.skip(SKIP_NO_CC if language == "c" else SKIP_NO_GLSLANG)
    text = preprocessed(exported(language, bands=3, engine="unity"), language, tmp_path)
    for name, types in SIGNATURES[language].items():
        assert signature(text, name) == types, name
    assert "skysh_engine_coefficients" not in preprocessed(exported(language, bands=3), language, tmp_path)


# --------------------------------------------------------------------------- #
# The templates and their holes
# --------------------------------------------------------------------------- #
def test_every_c_like_template_is_listed_with_its_holes() -> None:
    shipped = {p.name for p in template.TEMPLATE_DIR.glob("c_like_*")}
    assert shipped == set(HOLES)
    for name, holes in HOLES.items():
        assert template.holes(name) == holes, name


def test_the_code_files_are_the_same_for_every_language(exported: Exported) -> None:
    """Each export holds the kernel and its deringing verbatim (c_like_dering3.h where the exact minimum decides, in C at
    5..7 bands c_like_dering_certificate_c.h; the shaders refuse those), and its own words and functions (those the
    shaders share included), not another language's."""
    for language in export_dering.LANGUAGES:
        source = exported(language, bands=3)
        assert template.text("c_like_kernel.h") in source and template.text("c_like_dering3.h") in source
        assert export_dering.words(language) in source and c_like.api_source(language) in source
        others = [other for other in export_dering.LANGUAGES if other != language]
        assert all(c_like.api_source(other) not in source for other in others)
        own = set(export_dering.WORDS[language])
        assert all(template.text(name) not in source for other in others for name in export_dering.WORDS[other]
                   if name not in own)
    assert template.text("c_like_dering3.h") in exported("c", bands=2)  # every band count derings (issue 25)
    certificate = template.text("c_like_dering_certificate_c.h")
    assert certificate in exported("c", bands=7) and template.text("c_like_dering3.h") not in exported("c", bands=7)
    assert all(certificate not in exported(language, bands=7) for language in ("glsl", "hlsl"))  # C only
    for language in ("glsl", "hlsl"):  # the shaders refuse the certificate's band counts
        assert "#define SKYSH_DERING 0\n" in exported(language, bands=5) and "skysh_dering(" not in exported(language, bands=5)


def test_dering_source_is_the_kernel_s() -> None:
    for language in export_dering.LANGUAGES:
        source = export_dering.dering_source(language, name="sky")
        assert source.startswith(export_dering.words(language)) and source.endswith(template.text("c_like_dering3.h"))
    assert export_dering.dering_source("c", bands=6).endswith(template.text("c_like_dering_certificate_c.h"))


class TestTemplateModule:
    def test_fill_refuses_missing_unused_and_non_text(self) -> None:
        values = {hole: "x" for hole in HOLES["c_like_frame_shader.glsl"]}
        assert template.fill("c_like_frame_shader.glsl", **values).startswith("/*\nx\n")
        for bad in ({"NOTICE": "x"}, {**values, "EXTRA": "x"}, {**values, "BODY": 1}):
            with pytest.raises(ValueError, match=r"c_like_frame_shader\.glsl"):
                template.fill("c_like_frame_shader.glsl", **bad)  # type: ignore[arg-type]

    def test_text_refuses_other_paths(self) -> None:
        for name in ("../template.py", "missing.h"):
            with pytest.raises(ValueError, match="name"):
                template.text(name)

    def test_defines(self) -> None:
        assert template.defines({"SKYSH_A": 1, "SKYSH_B_2": "0.5, -1.0"}) == "#define SKYSH_A 1\n#define SKYSH_B_2 0.5, -1.0\n"
        for bad in ({"A": 1}, {"SKYSH_a": 1}, {"SKYSH_A": "1\n2"}):
            with pytest.raises(ValueError, match="define"):
                template.defines(bad)
