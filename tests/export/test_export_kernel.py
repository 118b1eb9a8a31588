"""
Tests of the C export's per-frame kernel as laid out for the machine (issue 26).

The kernel (``skysh/export/templates/c_like_kernel.h``) reads its tables term-major
(:func:`skysh.export.tables.term_major`) and rotates by one cos, one sin and the angle-addition
recurrence (``skysh_turns``). Here:

-   the double C header against an independent reference, the Python runtime
    (:meth:`skysh.SkySH.coefficients`), in the cases ``benchmarks/bench_c_floor.py`` times (radiance
    with the Gibbs filter; irradiance without it and without deringing; the same by the defaults,
    deringing asked; lit: the sun and a 0.2 grey ground) at 3 and 7 bands, over random frames and the
    domain's corners, to :data:`KERNEL_TOLERANCE` of the DC (lit: :data:`LIT_TOLERANCE`, the sun's exp);
-   the generated tables: ``SKYSH_TABLE`` and ``SKYSH_IRRADIANCE`` are the export tables term-major, to the bit;
-   ``skysh_turns`` of a real header against cos(k phi), sin(k phi) in long double (cosl, sinl), for k up
    to 6 over phi in [0, 2 pi) (hypothesis), to :data:`TURNS_TOLERANCE`.

The harness is tests/export/test_export_lights.py's (:data:`test_export_lights.C_HARNESS`, built through the
session's :class:`background.ToolRuns`); the error measure is :func:`conftest.dc_relative_error`. Tests that
compile carry the ``integration`` marker. Timings are benchmarks/bench_c_floor.py's, never a test's.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from background import RUN_DIR, ToolRuns
from conftest import SKIP_NO_CC, Exported, dc_relative_error
from hypothesis import given, settings
from hypothesis import strategies as st
from test_export_lights import CC, Point, compile_harness, parse_table, reference, run

from skysh import SkySH
from skysh.export.tables import export_tables, term_major

KERNEL_TOLERANCE: float = 1e-14
"""The double header against the runtime, over |DC| of the worst channel: the same arithmetic up to the order of
the 112-term sums (eight terms a pass), the Chebyshev recurrence against cos(k acos x), the rotation's and the
sun's angle-addition recurrence against libm (a few ulps each, :data:`TURNS_TOLERANCE`) and the C library's tan,
exp against numpy's (measured below 2e-15 without the sun)."""

TURNS_TOLERANCE: float = 16.0 * float(np.finfo(np.float64).eps)
"""|skysh_turns - cos(k phi)|, |... - sin(k phi)| absolute, k <= 6, phi in [0, 2 pi): each step of the recurrence
adds the rounding of two products and a sum of unit-size values (about 1.5 ulp of 1) to the error it carries,
so six steps stay below 10 ulps of 1, and libm's cos and sin of phi start it within 1 ulp; 16 ulps (3.6e-15)
leave room (measured 1.3e-15)."""

LIT_TOLERANCE: float = 1e-13
"""The lit case against the runtime: the sun's colour is exp of a 91-term sum of ln XYZ of magnitude about 12, whose
rounding (a few ulps of 12) exp turns into a relative error of about 1e-15 of the sun, itself up to tens of times the
sky's DC; measured 3.0e-14 at 3 and 7 bands, the same to the digit for the r-major kernel before issue 26, so the
libraries' exp and pow, not the kernel, set it."""

BANDS: tuple[int, ...] = (3, 7)
"""The band counts of the cases (the benchmark's)."""

GREY: tuple[float, float, float] = (0.2, 0.2, 0.2)
"""The lit case's ground albedo."""

BLACK: tuple[float, float, float] = (0.0, 0.0, 0.0)

CASES: dict[str, tuple[int, int, int, int, int]] = {
    "radiance": (1, 0, 0, 0, 1), "irradiance": (0, 0, 1, 0, 1), "irradiance-default": (0, 1, 1, 0, 1),
    "lit": (1, 0, 0, 1, 0),
}
"""Case -> (gibbs, dering, irradiance, sun, NULL albedo) of test_export_lights.Point (lit: the grey albedo)."""

FRAMES: int = 24
"""Random frames per case (the 7-band default deringing costs about a millisecond a frame in the runtime)."""


TURNS_HARNESS: str = r"""
#include <stdio.h>
#include "sky_sh.h"
int main(void) {
    double phi, c[SKYSH_BANDS], s[SKYSH_BANDS];
    while (scanf("%lf", &phi) == 1) {
        skysh_turns(cos(phi), sin(phi), c, s);
        for (int k = 0; k < SKYSH_BANDS; ++k)
            printf("%.17g %.17g ", c[k], s[k]);
        printf("\n");
    }
    return 0;
}
"""
"""Prints skysh_turns(cos phi, sin phi) of a header, (cos(k phi), sin(k phi)) for k < SKYSH_BANDS, a line per phi."""


def frames(case: str, bands: int) -> list[Point]:
    """The domain's corners and random frames (azimuths beyond 2 pi included) of ``case``."""
    gibbs, dering, irradiance, sun, null = CASES[case]
    rng = np.random.default_rng(2600 + bands)
    corners = [(ts, t, phi) for ts in (0.0, math.pi / 2.0) for t in (2.5, 6.0) for phi in (0.0, 4.0)]
    inside = zip(rng.uniform(0.0, math.pi / 2.0, FRAMES), rng.uniform(2.5, 6.0, FRAMES), rng.uniform(-9.0, 9.0, FRAMES))
    albedo = BLACK if null else GREY
    return [(float(ts), float(t), float(phi), gibbs, dering, irradiance, sun, null, albedo)
            for ts, t, phi in [*corners, *inside]]


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason=SKIP_NO_CC)
@pytest.mark.parametrize("bands", BANDS)
@pytest.mark.parametrize("case", list(CASES))
def test_the_kernel_matches_the_runtime(sky: SkySH, exported: Exported, tool_runs: ToolRuns, case: str,
                                        bands: int) -> None:
    binary = compile_harness(exported("c", bands=bands), tool_runs)
    pts = frames(case, bands)
    rows = run(binary, pts)
    assert all(row[0] == 0 for row in rows)
    got = np.array([row[8:].reshape(-1, 3) for row in rows])
    want = np.array([reference(sky, p, bands) for p in pts])
    assert dc_relative_error(got, want) < (LIT_TOLERANCE if case == "lit" else KERNEL_TOLERANCE)


@pytest.mark.parametrize("bands", [1, 3, 7])
def test_the_tables_are_term_major(sky: SkySH, exported: Exported, bands: int) -> None:
    """SKYSH_TABLE[q 3 ROWS + 3 r + c] (one band: the unfiltered c_10 as row 1) and, at 3 bands,
    SKYSH_IRRADIANCE[q 3 HALF + 3 r + c], every double literal read back exactly."""
    tables, source = export_tables(sky, bands), exported("c", bands=bands)
    stored = tables.table
    if bands == 1:
        stored = np.concatenate([stored, tables.lights.c10[:, :, None, :]], axis=2)
    np.testing.assert_array_equal(parse_table(source, "SKYSH_TABLE", np.float64), term_major(stored).ravel())
    if bands == 3 and tables.irradiance is not None:
        np.testing.assert_array_equal(parse_table(source, "SKYSH_IRRADIANCE", np.float64),
                                      term_major(tables.irradiance).ravel())


@pytest.fixture(scope="module")
def turns_binary(exported: Exported, tool_runs: ToolRuns) -> Path:
    """:data:`TURNS_HARNESS` around the 7-band double header (k up to 6)."""
    if CC is None:
        pytest.skip(SKIP_NO_CC)
    done = tool_runs.run([CC, "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-o", f"{RUN_DIR}/turns",
                          f"{RUN_DIR}/turns.c", "-lm"], {"sky_sh.h": exported("c", bands=7), "turns.c": TURNS_HARNESS})
    assert done.result.returncode == 0, done.result.stderr
    return done.directory / "turns"


def turns_error(binary: Path, phis: list[float]) -> float:
    """The largest |skysh_turns - exact| over ``phis`` and k = 0 .. 6, cos and sin alike."""
    out = subprocess.run([str(binary)], input="\n".join(map(repr, phis)) + "\n", capture_output=True, text=True,
                         check=True).stdout.splitlines()
    worst = 0.0
    for phi, line in zip(phis, out, strict=True):
        values = [float(v) for v in line.split()]
        for k in range(7):
            angle = np.longdouble(k) * np.longdouble(phi)  # phi a double, k <= 6: exact in the 64-bit significand
            worst = max(worst, abs(values[2 * k] - float(np.cos(angle))), abs(values[2 * k + 1] - float(np.sin(angle))))
    return worst


@pytest.mark.integration
@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0.0, 2.0 * math.pi, exclude_max=True), min_size=1, max_size=40))
def test_the_rotation_recurrence_matches_cos_and_sin(turns_binary: Path, phis: list[float]) -> None:
    assert turns_error(turns_binary, phis) <= TURNS_TOLERANCE


@pytest.mark.integration
def test_the_rotation_recurrence_on_a_grid(turns_binary: Path) -> None:
    """4,096 evenly spaced azimuths of [0, 2 pi), the quarter turns included."""
    assert turns_error(turns_binary, [2.0 * math.pi * i / 4096 for i in range(4096)]) <= TURNS_TOLERANCE
