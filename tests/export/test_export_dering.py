"""
Tests of :mod:`skysh.export.dering`: the generated deringing runs as Python does
================================================================================

The deringing is one hand-written kernel, ``skysh/export/templates/c_like_dering3.h``, over
the words of each language. The C source is compiled with gcc, on lights, skies, random
(mostly impossible) functions and extreme magnitudes; it must pick Python's row, failure
flag and windowed coefficients exactly (double precision, the same table, start and Newton
steps). The HLSL text, compiled as C in float (``-fsingle-precision-constant``, HLSL's
qualifiers defined away), must never window less than Python and match it except near a
tie; GLSL and HLSL must pass ``glslangValidator`` (skipped where the tool is missing). A
corrupted table is the negative control: the comparison must catch it. (The JavaScript
export's deringing is its own, tested with it: ``tests/export/test_export_js.py``.)

Compiles and validations go through the session's :class:`background.ToolRuns` (each
distinct one once), queued when the module starts (:func:`_prefetch`); those tests carry
the ``integration`` marker.
``python tests/export/test_export_dering.py`` prints the float build's agreement with Python.
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from background import GLSLANG, RUN_DIR, ToolJob, ToolRuns
from conftest import L_OF, SKIP_NO_CC, SKIP_NO_GLSLANG, light, random_functions, sky_samples

from skysh.export import dering as export_dering
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

FLOAT_TIE_RTOL: float = 1e-4
"""Float (GLSL / HLSL) may window one row more than Python where Python's minimum at
its row is within 1e-4 of the target's largest |coefficient|: the float allowance
(256 float eps = 3e-5 of the same size) plus float rounding of the eigenvalues."""

FLOAT_SAME_ROW_MIN: float = 0.95
"""At least this fraction of the inputs must get exactly Python's row from the float build. The tie allowance
(:data:`FLOAT_TIE_RTOL`) covers a large share of the inputs (``python tests/export/test_export_dering.py`` prints it, with
the fraction that agrees): without this floor a float build that windowed one row more at every near-tie would
pass; 0.95 leaves room for the rare true ties."""

FLOAT32_INPUT_LIMIT: float = 1e30
"""The float build is compared on the inputs whose largest |coefficient| is below this. Cast to float32 they stay
finite (float32's largest is 3.4e38), and the function's power-of-two normaliser 2^-(floor(log2 m) + 1) stays a
normal float32 (m below 2^125, 4.3e37; a GPU flushes subnormals to zero); 1e30 keeps 7 decades from both. The
inputs beyond it (up to 1e300) are for the double builds."""

RUN_TIMEOUT_S: float = 300.0
"""Hang guard of one run of a built program over all the inputs (well under a second normally)."""

GCC: str | None = shutil.which("gcc")

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
    done = subprocess.run(cmd, input=text, capture_output=True, text=True, check=True, timeout=RUN_TIMEOUT_S)
    return np.array([[float(v) for v in line.split()] for line in done.stdout.splitlines() if line.strip()])


def python_result(data: np.ndarray, target: str = "irradiance") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dering.DeringWarning)
        return dering.dering(data, target=target, return_failed=True)


def c_job(source: str, name: str, flags: tuple[str, ...] = ()) -> ToolJob:
    """gcc -O2 (C99, every warning an error, ``flags``) on ``source``, making the program ``name``."""
    assert GCC is not None
    return (["gcc", "-O2", "-std=c99", "-Wall", "-Werror", *flags, "-o", f"{RUN_DIR}/{name}", f"{RUN_DIR}/{name}.c", "-lm"],
            {f"{name}.c": source})


def compile_c(source: str, runs: ToolRuns, name: str, flags: tuple[str, ...] = ()) -> Path:
    """The program ``name`` built from ``source`` (once per session); skips without gcc."""
    if GCC is None:
        pytest.skip(SKIP_NO_CC)
    done = runs.run(*c_job(source, name, flags))
    assert done.result.returncode == 0, done.result.stderr
    return done.directory / name


def corrupted_source() -> str:
    """The C source with the table's second row's band-2 factor replaced by the third's (the negative control)."""
    source = export_dering.dering_source("c")
    table = dering.WINDOW_TABLE
    return source.replace(repr(float(table[1, 2])), repr(float(table[2, 2])), 1)


def float_source() -> str:
    """:data:`FLOAT_MAIN` around the HLSL text made C: its qualifiers ``inout`` and ``out`` defined away (HLSL's
    abs/max/min mapped by macros; ``static const`` is C too)."""
    return FLOAT_MAIN % ("#define inout\n#define out\n" + export_dering.dering_source("hlsl"))


FLOAT_FLAGS: tuple[str, ...] = ("-fsingle-precision-constant",)
"""The float build's extra flag: unsuffixed constants are float, as in HLSL."""


def shader_job(language: str) -> ToolJob:
    """glslangValidator compiling a compute shader around the GLSL (ES 3.10) or HLSL text to SPIR-V."""
    assert GLSLANG is not None
    source = export_dering.dering_source(language, name="dering_sky")
    if language == "glsl":
        text = ("#version 310 es\nlayout(local_size_x = 1) in;\n"
                "layout(std430, binding = 0) buffer B { float data[]; };\n" + source
                + "void main() { float c[27]; for (int i = 0; i < 27; i++) { c[i] = data[i]; }"
                  " float s[3]; int f = dering_sky(c, s); data[0] = float(f) + s[1] + s[2]; }\n")
        return [GLSLANG, "-V", f"{RUN_DIR}/t.comp", "-o", f"{RUN_DIR}/t.spv"], {"t.comp": text}
    text = ("RWStructuredBuffer<float> data : register(u0);\n" + source
            + "[numthreads(1, 1, 1)] void main() { float c[27]; for (int i = 0; i < 27; i++) "
              "{ c[i] = data[i]; } float s[3]; int f = dering_sky(c, s); data[0] = float(f) + s[1]; }\n")
    return [GLSLANG, "-V", "-D", "-e", "main", "-S", "comp", f"{RUN_DIR}/t.hlsl", "-o", f"{RUN_DIR}/t.spv"], {"t.hlsl": text}


def jobs() -> Iterator[ToolJob]:
    """Every compile and validation of the module, in the order the tests run."""
    if GCC is not None:
        yield from (c_job(C_MAIN % export_dering.dering_source("c", target), "dering_c") for target in dering.DERING_TARGETS)
        yield c_job(C_MAIN % corrupted_source(), "dering_bad")
        yield c_job(float_source(), "dering_f", FLOAT_FLAGS)
    if GLSLANG is not None:
        yield from (shader_job(language) for language in ("glsl", "hlsl"))


@pytest.fixture(scope="module", autouse=True)
def _prefetch(tool_runs: ToolRuns) -> None:
    """Queue the module's compiles and validations when it starts (background.ToolRuns): they run in the background
    while the inputs are made and compared; each test takes its own when it needs it."""
    tool_runs.prefetch(jobs())


@pytest.fixture(scope="module")
def data() -> np.ndarray:
    return inputs()


def float_rows(data: np.ndarray, exe: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The float build ``exe`` on the inputs below :data:`FLOAT32_INPUT_LIMIT` (cast to float32): (Python's row,
    the float build's row, Python's failure flags, the float build's failure flags, near-tie flags), one per input."""
    small = data[np.abs(data).max(axis=(1, 2)) < FLOAT32_INPUT_LIMIT].astype(np.float32).astype(np.float64)
    res = run([str(exe)], small)
    _, scales, failed = python_result(small)
    table = dering.WINDOW_TABLE
    row_py = np.argmin(np.abs(scales[:, None, :] - table).max(-1), -1)
    row_f = np.argmin(np.abs(res[:, None, 1:4] - table).max(-1), -1)
    irr = sh.irradiance(small * table[row_py][:, L_OF[:9], None])
    near = (dering.exact_min(irr) <= FLOAT_TIE_RTOL * np.abs(irr).max(axis=-2)).any(-1)
    return row_py, row_f, failed, res[:, 0].astype(bool), near


@pytest.mark.integration
class TestDouble:
    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    def test_c_matches_python(self, data: np.ndarray, target: str, tool_runs: ToolRuns) -> None:
        exe = compile_c(C_MAIN % export_dering.dering_source("c", target), tool_runs, "dering_c")
        res = run([str(exe)], data)
        out, scales, failed = python_result(data, target)
        assert failed.any() and not failed.all()  # both outcomes exercised
        np.testing.assert_array_equal(res[:, 0].astype(bool), failed)
        np.testing.assert_array_equal(res[:, 1:4], scales)
        np.testing.assert_array_equal(res[:, 4:].reshape(-1, 9, 3), out)

    def test_negative_control_corrupted_table(self, data: np.ndarray, tool_runs: ToolRuns) -> None:
        """A table whose second row is the third: the comparison must see the difference."""
        bad = corrupted_source()
        assert bad != export_dering.dering_source("c")
        res = run([str(compile_c(C_MAIN % bad, tool_runs, "dering_bad"))], data)
        assert np.any(res[:, 1:4] != python_result(data)[1])


@pytest.mark.integration
class TestFloat:
    def test_hlsl_as_float_c_is_python_or_more_conservative(self, data: np.ndarray, tool_runs: ToolRuns) -> None:
        row_py, row_f, failed, failed_f, near = float_rows(data, compile_c(float_source(), tool_runs, "dering_f",
                                                                           FLOAT_FLAGS))
        assert np.all(row_f >= row_py)
        assert np.all((row_f == row_py) | near) and (row_f == row_py).mean() > FLOAT_SAME_ROW_MIN
        assert np.all(failed_f >= failed)  # float fails wherever Python does

    @pytest.mark.parametrize("language", ["glsl", "hlsl"])
    def test_shader_compiles(self, language: str, tool_runs: ToolRuns) -> None:
        if GLSLANG is None:
            pytest.skip(SKIP_NO_GLSLANG)
        done = tool_runs.run(*shader_job(language)).result
        assert done.returncode == 0, done.stdout + done.stderr


class TestSource:
    def test_interface(self) -> None:
        """The function is the kernel's, over each language's words: C int name(double c[9][3], double scales_out[3]),
        GLSL and HLSL int name(inout float c[27], out float scales_out[3]) (tests/export/test_templates.py checks the
        preprocessed signatures with the compiler and glslangValidator)."""
        head = "int SKYSH_DERING_NAME(SKYSH_INOUT SKYSH_DERING_COEFFS(c), SKYSH_OUT SKYSH_DREAL scales_out[3])"
        words = {"c": ("#define SKYSH_DERING_COEFFS(name) double name[9][3]", "#define SKYSH_DREAL double"),
                 "glsl": ("#define SKYSH_DERING_COEFFS(name) float name[27]", "#define SKYSH_INOUT inout"),
                 "hlsl": ("#define SKYSH_DERING_COEFFS(name) float name[27]", "#define SKYSH_OUT out")}
        for language, defined in words.items():
            source = export_dering.dering_source(language)
            assert head in source and all(w in source for w in defined) and source.count("{") == source.count("}")
            assert "#define SKYSH_DERING_NAME skysh_dering3\n" in source
        assert "#define SKYSH_DERING_NAME sky\n" in export_dering.dering_source("c", name="sky")
        assert math.isclose(float(repr(float(dering.WINDOW_TABLE[-1, 1]))), dering.WINDOW_TABLE[-1, 1])

    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    def test_numbers_are_python_s(self, target: str) -> None:
        """The #defines the kernel reads: the window table, the kernel, the basis constants, the steps and the guards of
        skysh.post.dering and skysh.sh.minimum, read back exactly (double for C, float32 for the shaders)."""
        table = dering.window_table(3, target)
        for precision, dtype in (("double", np.float64), ("float", np.float32)):
            defines = dict(line.split(" ", 2)[1:] for line in export_dering.dering_defines(target, precision).splitlines())
            numbers = {name: np.array(text.split(", "), dtype=np.float64).astype(dtype) for name, text in defines.items()
                       if name not in ("SKYSH_DERING_NAME", "SKYSH_DERING_ROWS", "SKYSH_DERING_STEPS")}
            np.testing.assert_array_equal(numbers["SKYSH_DERING_TAB1"], table[:, 1].astype(dtype))
            np.testing.assert_array_equal(numbers["SKYSH_DERING_TAB2"], table[:, 2].astype(dtype))
            np.testing.assert_array_equal(numbers["SKYSH_DERING_KERNEL"],
                                          dering.KERNELS[target][sh.band_of_index(3)].astype(dtype))
            assert numbers["SKYSH_K_ZONAL"] == dtype(sh.K_ZONAL) and numbers["SKYSH_Y00"] == dtype(sh.Y00)
            assert int(defines["SKYSH_DERING_ROWS"]) == len(table) and int(defines["SKYSH_DERING_STEPS"]) == shmin.NEWTON_STEPS
            guards = export_dering.GUARDS[precision]
            assert [numbers[f"SKYSH_DERING_{k}"] for k in ("TINY", "FLOOR", "POLE", "ROUND")] == [dtype(g) for g in guards]

    def test_bad_input(self) -> None:
        for language in ("rust", "js"):  # the JavaScript export writes its own deringing
            with pytest.raises(ValueError, match="language"):
                export_dering.dering_source(language)
        with pytest.raises(ValueError, match="target"):
            export_dering.dering_source("c", target="luminance")
        with pytest.raises(ValueError, match="name"):
            export_dering.dering_source("c", name="2fast")


def figures() -> list[dict[str, object]]:
    """The float build's agreement with Python, printed by ``python tests/export/test_export_dering.py``."""
    import tempfile

    if GCC is None:
        return []
    with tempfile.TemporaryDirectory() as name:
        runs = ToolRuns(Path(name))
        row_py, row_f, _, _, near = float_rows(inputs(), compile_c(float_source(), runs, "dering_f", FLOAT_FLAGS))
        runs.close()
    return [{"measure": "float (HLSL as C) build against Python, inputs below FLOAT32_INPUT_LIMIT", "inputs": len(row_py),
             "same_row": float((row_f == row_py).mean()), "near_tie": float(near.mean()),
             "rows_differing": int((row_f != row_py).sum())}]


if __name__ == "__main__":
    for row in figures():
        print(json.dumps(row))
    sys.exit(0)
