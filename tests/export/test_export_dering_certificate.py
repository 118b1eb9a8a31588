"""
Tests of the C deringing at 5..7 bands (``c_like_dering_certificate_c.h``: the certificate)
==========================================================================================

The C function (gcc, double) against :func:`skysh.post.dering.least_window` window for window on
HDR delta lights, skies and random functions at 5, 6 and 7 bands (position within one lattice step
of the certificate's search, :data:`skysh.post.dering.CERTIFIED_TOLERANCE`, where a decision may
flip at a rounding tie; measured identical), with a negative control (a covering radius too small
for the grid: the certificate then passes too early and the comparison must catch it); and the
default call of the C export (``skysh_coefficients`` with ``dering``, irradiance, by intent) never
negative over 1,000 random skies per band count 1..7 (:func:`skysh.sh.minimum.exact_min`: exact at
1..3 bands, the certified minimum at 4..7).

``python tests/export/test_export_dering_certificate.py`` prints the certificate's cost per call in
C (time and SH evaluations, function-direction pairs) on skies, lights and random functions.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

if __name__ == "__main__":  # run as a script: conftest and skysh as pytest would find them
    sys.path[:0] = [str(Path(__file__).resolve().parents[1]), str(Path(__file__).resolve().parents[2])]

from background import ToolRuns
from conftest import Exported
from test_export import NO_LIGHTS
from test_export_dering import GCC, compare, compile_c, inputs, not_finite, run
from test_export_lights import CC, compile_harness

from skysh.export import dering as export_dering
from skysh.export.lights import BY_INTENT
from skysh.post import dering
from skysh.sh import minimum as shmin

CERTIFIED_BANDS: list[int] = [5, 6, 7]
"""Band counts whose deringing is the certificate's (C only)."""

NONNEGATIVE_SKIES: int = 1000
"""Random frames per band count at which the C export's default irradiance is checked (the issue's 1,000)."""

NONNEGATIVE_SLACK: float = 1e-9
"""The checked minimum may dip this far below 0, over the channel's largest |coefficient|: exact_min's own slack at
4..7 bands (12 levels, K (COVER_RADIUS / 2^12)^2, about 1e-10 of the size) and the C output's rounding."""

C_MAIN = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <math.h>
#include <time.h>
static long tally = 0;
#define SKYSH_DERING_TALLY(n) (tally += (n))
%s
int main(void) {
  double c[SKYSH_DERING_COUNT][3], s[SKYSH_DERING_BANDS], p[1];
  for (;;) {
    for (int k = 0; k < SKYSH_DERING_COUNT; k++) for (int ch = 0; ch < 3; ch++) if (scanf("%%lf", &c[k][ch]) != 1) return 0;
    struct timespec t0, t1;
    tally = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int failed = skysh_dering(c, s, p);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("%%d %%.17g", failed, p[0]);
    for (int l = 0; l < SKYSH_DERING_BANDS; l++) printf(" %%.17g", s[l]);
    for (int k = 0; k < SKYSH_DERING_COUNT; k++) for (int ch = 0; ch < 3; ch++) printf(" %%.17g", c[k][ch]);
    printf(" %%ld %%.3f\n", tally, (t1.tv_sec - t0.tv_sec) * 1e6 + (t1.tv_nsec - t0.tv_nsec) * 1e-3);
  }
}
"""
"""As test_export_dering.C_MAIN, then the SH evaluations and the microseconds of the call."""


def source(bands: int, cover: float = shmin.COVER_RADIUS) -> str:
    text = C_MAIN % export_dering.dering_source("c", bands=bands)
    return text.replace(f"#define SKYSH_DERING_COVER {cover!r}", "#define SKYSH_DERING_COVER 0.01")  # the control


def sample(bands: int) -> np.ndarray:
    """A small set (Python's certificate costs about a millisecond per function): lights, skies, random functions."""
    return inputs(bands, lights=40, skies=12, rand=20)[:72]


def results(bands: int, runs: ToolRuns, corrupt: bool = False) -> tuple[np.ndarray, np.ndarray]:
    data = sample(bands)
    text = source(bands) if corrupt else C_MAIN % export_dering.dering_source("c", bands=bands)
    return data, run([str(compile_c(text, runs, f"cert{bands}{'_bad' if corrupt else ''}"))], data)


@pytest.mark.integration
@pytest.mark.parametrize("bands", CERTIFIED_BANDS)
def test_c_matches_python(bands: int, tool_runs: ToolRuns) -> None:
    data, res = results(bands, tool_runs)
    compare(res[:, :-2], data, tolerance=dering.CERTIFIED_TOLERANCE)
    assert (res[:, 1] % 1.0 > 0.0).any() and res[:, -2].min() > 0  # fractions exercised, evaluations counted


@pytest.mark.integration
def test_not_finite_fails_at_once(tool_runs: ToolRuns) -> None:
    """The precondition, checked as at 1..4 bands: a NaN or an inf returns 1, c untouched, factors 1, position 0."""
    bad = not_finite(sample(5))
    res = run([str(compile_c(C_MAIN % export_dering.dering_source("c", bands=5), tool_runs, "cert5"))], bad)
    assert np.all(res[:, 0] == 1) and np.all(res[:, 1] == 0.0) and np.all(res[:, 2:7] == 1.0) and np.all(res[:, -2] == 0)
    np.testing.assert_array_equal(res[:, 7:-2].reshape(bad.shape), bad)


@pytest.mark.integration
def test_negative_control_small_cover(tool_runs: ToolRuns) -> None:
    """A covering radius of 0.01 rad (the grid's is 0.0427): the slack is too small, windows pass too early."""
    assert source(7) != C_MAIN % export_dering.dering_source("c", bands=7)
    data, res = results(7, tool_runs, corrupt=True)
    with pytest.raises(AssertionError):
        compare(res[:, :-2], data, tolerance=dering.CERTIFIED_TOLERANCE)


def frames(count: int, seed: int) -> list[tuple[float, float, float]]:
    rng = np.random.default_rng(seed)
    return [(float(z), float(t), float(a)) for z, t, a in zip(rng.uniform(0.0, math.pi / 2, count),
                                                             rng.uniform(2.5, 6.0, count), rng.uniform(-7.0, 7.0, count))]


@pytest.mark.integration
@pytest.mark.skipif(CC is None, reason="no C compiler")
@pytest.mark.parametrize("bands", [1, 2, 3, 4, 5, 6, 7])
def test_default_irradiance_is_never_negative(bands: int, exported: Exported, tool_runs: ToolRuns) -> None:
    """skysh_coefficients(..., gibbs 0, dering 1, irradiance 1, no sun, no ground, SKYSH_BY_INTENT): the runtime's
    defaults for irradiance (3 bands: the certified table; else the deringed sky)."""
    binary = compile_harness(exported("c", bands=bands), tool_runs)
    text = "".join(f"0 {z!r} {t!r} {a!r} 0 1 1 {NO_LIGHTS} {BY_INTENT}\n" for z, t, a in frames(NONNEGATIVE_SKIES, bands))
    out = subprocess.run([str(binary)], input=text, capture_output=True, text=True, check=True).stdout.splitlines()
    rows = np.array([line.split() for line in out], dtype=np.float64)
    assert np.all(rows[:, 0] == 0)
    irr = rows[:, 8:].reshape(len(rows), bands * bands, 3)
    lowest = shmin.exact_min(irr) / np.abs(irr).max(axis=1)
    assert lowest.min() >= -NONNEGATIVE_SLACK


def figures() -> list[dict[str, object]]:
    """The certificate's cost per call in C (gcc -O2, this machine) by band count and kind of input."""
    if GCC is None:
        return []
    rows = []
    with tempfile.TemporaryDirectory() as name:
        runs = ToolRuns(Path(name))
        for bands in CERTIFIED_BANDS:
            data = inputs(bands, lights=100, skies=60, rand=50)
            res = run([str(compile_c(C_MAIN % export_dering.dering_source("c", bands=bands), runs, f"cert{bands}"))],
                      data)[1:]  # the first call builds the grid
            kinds = {"lights": slice(0, 99), "skies": slice(99, 159), "random": slice(159, 209)}
            for kind, part in kinds.items():
                rows.append({"bands": bands, "inputs": kind, "calls": int(res[part].shape[0]),
                             "median_us": float(np.median(res[part, -1])), "max_us": float(res[part, -1].max()),
                             "median_sh_evaluations": float(np.median(res[part, -2])),
                             "max_sh_evaluations": float(res[part, -2].max())})
        runs.close()
    return rows


if __name__ == "__main__":
    for row in figures():
        print(json.dumps(row))
    sys.exit(0)
