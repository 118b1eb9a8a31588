"""
Tests of :mod:`skysh.export_dering`: the generated deringing runs as Python does
================================================================================

The C source is compiled with gcc and the JavaScript run with node, on lights,
skies, random (mostly impossible) functions and extreme magnitudes; both must pick
Python's row, failure flag and windowed coefficients exactly (double precision,
the same table, start and Newton steps). The HLSL text, compiled as C in float
(``-fsingle-precision-constant``), must never window less than Python and match it
except near a tie; GLSL and HLSL must pass ``glslangValidator`` (skipped where the
tool is missing). A corrupted table is the negative control: the comparison must
catch it.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import L_OF, light, random_functions, sky_samples

from skysh import dering, export_dering, sh

FLOAT_TIE_RTOL: float = 1e-4
"""Float (GLSL / HLSL) may window one row more than Python where Python's minimum at
its row is within 1e-4 of the target's largest |coefficient|: the float allowance
(256 float eps = 3e-5 of the same size) plus float rounding of the eigenvalues."""

C_MAIN = r"""
#include <stdio.h>
#include <math.h>
%s
int main(void) {
  double c[9][3], s[3];
  for (;;) {
    for (int k = 0; k < 9; k++) for (int ch = 0; ch < 3; ch++) if (scanf("%%lf", &c[k][ch]) != 1) return 0;
    int failed = skysh_dering3(c, s);
    printf("%%d %%.17g %%.17g %%.17g", failed, s[0], s[1], s[2]);
    for (int k = 0; k < 9; k++) for (int ch = 0; ch < 3; ch++) printf(" %%.17g", c[k][ch]);
    printf("\n");
  }
}
"""
"""Reads 27 numbers per line (c[k][ch]), prints failed, the scales and the windowed c."""

FLOAT_MAIN = r"""
#include <stdio.h>
#include <tgmath.h>
#define abs(x) fabsf(x)
#define max(a, b) fmaxf(a, b)
#define min(a, b) fminf(a, b)
%s
int main(void) {
  float c[27], s[3]; double v;
  for (;;) {
    for (int k = 0; k < 27; k++) { if (scanf("%%lf", &v) != 1) return 0; c[k] = (float) v; }
    int failed = skysh_dering3(c, s);
    printf("%%d %%.9g %%.9g %%.9g\n", failed, s[0], s[1], s[2]);
  }
}
"""
"""The HLSL function as C in float: qualifiers removed, HLSL's abs/max/min mapped."""

JS_MAIN = """
%s
const out = [];
for (const line of require("fs").readFileSync(0, "utf8").trim().split("\\n")) {
  const v = line.split(" ").map(Number);
  const c = [];
  for (let k = 0; k < 9; k++) c.push([v[3 * k], v[3 * k + 1], v[3 * k + 2]]);
  const s = [0, 0, 0];
  const failed = skysh_dering3(c, s);
  out.push([failed, ...s, ...c.flat()].join(" "));
}
console.log(out.join("\\n"));
"""


def inputs() -> np.ndarray:
    """(n, 9, 3) radiance SH: lights, skies without the Gibbs filter, random functions,
    lights at 1e-300 .. 1e300 per channel, a zero channel, the zero function."""
    rng = np.random.default_rng(61)
    lights = np.stack([light(rng, 3) for _ in range(400)])
    rand = random_functions(rng, 600, 3).reshape(200, 3, 9).swapaxes(1, 2)
    extreme = lights[:60] * 10.0 ** rng.uniform(-300, 300, (60, 1, 3))
    zero = lights[:3].copy()
    zero[0, :, 1] = 0.0
    zero[1] = 0.0
    return np.concatenate([lights, sky_samples(30, 3, gibbs=False), rand, extreme, zero])


def run(cmd: list[str], data: np.ndarray) -> np.ndarray:
    text = "\n".join(" ".join(repr(float(v)) for v in x.ravel()) for x in data)
    done = subprocess.run(cmd, input=text, capture_output=True, text=True, check=True, timeout=300)
    return np.array([[float(v) for v in line.split()] for line in done.stdout.splitlines() if line.strip()])


def python_result(data: np.ndarray, target: str = "irradiance") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dering.DeringWarning)
        return dering.dering(data, target=target, return_failed=True)


def compile_c(source: str, directory: Path, name: str, flags: tuple[str, ...] = ()) -> Path:
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    src = directory / f"{name}.c"
    src.write_text(source)
    exe = directory / name
    subprocess.run(["gcc", "-O2", "-std=c99", "-Wall", "-Werror", *flags, "-o", str(exe), str(src), "-lm"],
                   check=True, capture_output=True, text=True)
    return exe


@pytest.fixture(scope="module")
def data() -> np.ndarray:
    return inputs()


class TestDouble:
    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    def test_c_matches_python(self, data: np.ndarray, target: str, tmp_path: Path) -> None:
        exe = compile_c(C_MAIN % export_dering.dering_source("c", target), tmp_path, "dering_c")
        res = run([str(exe)], data)
        out, scales, failed = python_result(data, target)
        assert failed.any() and not failed.all()  # both outcomes exercised
        np.testing.assert_array_equal(res[:, 0].astype(bool), failed)
        np.testing.assert_array_equal(res[:, 1:4], scales)
        np.testing.assert_array_equal(res[:, 4:].reshape(-1, 9, 3), out)

    def test_js_matches_python(self, data: np.ndarray, tmp_path: Path) -> None:
        if shutil.which("node") is None:
            pytest.skip("node is not installed")
        script = tmp_path / "dering.js"
        script.write_text(JS_MAIN % export_dering.dering_source("js"))
        res = run(["node", str(script)], data)
        out, scales, failed = python_result(data)
        np.testing.assert_array_equal(res[:, 0].astype(bool), failed)
        np.testing.assert_array_equal(res[:, 1:4], scales)
        np.testing.assert_array_equal(res[:, 4:].reshape(-1, 9, 3), out)

    def test_negative_control_corrupted_table(self, data: np.ndarray, tmp_path: Path) -> None:
        """A table whose second row is the third: the comparison must see the difference."""
        source = export_dering.dering_source("c")
        table = dering.WINDOW_TABLE
        bad = source.replace(repr(float(table[1, 2])), repr(float(table[2, 2])), 1)
        assert bad != source
        res = run([str(compile_c(C_MAIN % bad, tmp_path, "dering_bad"))], data)
        assert np.any(res[:, 1:4] != python_result(data)[1])


class TestFloat:
    def test_hlsl_as_float_c_is_python_or_more_conservative(self, data: np.ndarray, tmp_path: Path) -> None:
        hlsl = export_dering.dering_source("hlsl").replace("inout float c[27]", "float c[27]")
        hlsl = hlsl.replace("out float scales_out[3]", "float scales_out[3]").replace("static const", "const")
        exe = compile_c(FLOAT_MAIN % hlsl, tmp_path, "dering_f", ("-fsingle-precision-constant",))
        small = data[np.abs(data).max(axis=(1, 2)) < 1e30].astype(np.float32).astype(np.float64)
        res = run([str(exe)], small)
        _, scales, failed = python_result(small)
        table = dering.WINDOW_TABLE
        row_py = np.argmin(np.abs(scales[:, None, :] - table).max(-1), -1)
        row_f = np.argmin(np.abs(res[:, None, 1:4] - table).max(-1), -1)
        assert np.all(row_f >= row_py)
        irr = sh.irradiance(small * table[row_py][:, L_OF[:9], None])
        near = (dering.exact_min(irr) <= FLOAT_TIE_RTOL * np.abs(irr).max(axis=-2)).any(-1)
        assert np.all((row_f == row_py) | near) and (row_f == row_py).mean() > 0.95
        assert np.all(res[:, 0].astype(bool) >= failed)  # float fails wherever Python does

    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    def test_shader_compiles(self, language: str, tmp_path: Path) -> None:
        tool = shutil.which("glslangValidator")
        if tool is None:
            pytest.skip("glslangValidator is not installed (Debian: glslang-tools)")
        source = export_dering.dering_source(language, name="dering_sky")
        if language == "glsl":
            path = tmp_path / "t.comp"
            path.write_text("#version 310 es\nlayout(local_size_x = 1) in;\n"
                            "layout(std430, binding = 0) buffer B { float data[]; };\n" + source
                            + "void main() { float c[27]; for (int i = 0; i < 27; i++) { c[i] = data[i]; }"
                              " float s[3]; int f = dering_sky(c, s); data[0] = float(f) + s[1] + s[2]; }\n")
            cmd = [tool, "-V", str(path), "-o", str(tmp_path / "t.spv")]
        else:
            path = tmp_path / "t.hlsl"
            path.write_text("RWStructuredBuffer<float> data : register(u0);\n" + source
                            + "[numthreads(1, 1, 1)] void main() { float c[27]; for (int i = 0; i < 27; i++) "
                              "{ c[i] = data[i]; } float s[3]; int f = dering_sky(c, s); data[0] = float(f) + s[1]; }\n")
            cmd = [tool, "-V", "-D", "-e", "main", "-S", "comp", str(path), "-o", str(tmp_path / "t.spv")]
        done = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stdout + done.stderr


class TestSource:
    def test_interface(self) -> None:
        heads = {"c": "int skysh_dering3(double c[9][3], double scales_out[3])",
                 "glsl": "int skysh_dering3(inout float c[27], out float scales_out[3])",
                 "hlsl": "int skysh_dering3(inout float c[27], out float scales_out[3])",
                 "js": "function skysh_dering3(c, scales_out)"}
        for language, head in heads.items():
            source = export_dering.dering_source(language)
            assert head in source and source.count("{") == source.count("}")
        assert "function sky(" in export_dering.dering_source("js", name="sky")
        assert math.isclose(float(repr(float(dering.WINDOW_TABLE[-1, 1]))), dering.WINDOW_TABLE[-1, 1])

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="language"):
            export_dering.dering_source("rust")
        with pytest.raises(ValueError, match="target"):
            export_dering.dering_source("c", target="luminance")
        with pytest.raises(ValueError, match="name"):
            export_dering.dering_source("c", name="2fast")
