#!/usr/bin/env python
"""
Measurements for fitting the Hosek-Wilkie sky's SH (issue 17): which variables and degrees.

The model's dataset ships with skysh; only ``--mitsuba`` needs the optional extra
(``pip install 'skysh[hosek]'``). Each section prints a table; the numbers quoted in
``skysh/model/hosek.py``, ``tests/model/test_hosek.py`` and ``docs/hosek.md`` come from here.

    python tools/hosek_study.py --minima        # where the model's radiance goes negative
    python tools/hosek_study.py --albedo        # is the SH linear in the albedo? (two tables?)
    python tools/hosek_study.py --turbidity     # one polynomial in T, or one per integer interval?
    python tools/hosek_study.py --fit           # per-interval (u, s, albedo) fits: degrees, errors, size
    python tools/hosek_study.py --datasets      # RGB vs spectral dataset, DC per channel
    python tools/hosek_study.py --mitsuba       # float32 agreement with Mitsuba's sunsky (needs mitsuba)
    python tools/hosek_study.py --rule --jobs 2 # issue 27: the per-frame rule's accuracy and cost (hosek_frame)

Error measure: E_mean of the Habel seed (eq. 3) over the m >= 0 coefficients of 7
bands, worst channel, relative to L_min (skysh.table.fit.error_measures). L_min is the
sky's minimum per channel (:func:`skysh.model.hosek.sky_minimum`) floored as
skysh.table.fit.error_denominator does (5 % of the minimum luminance) and, because the
model's radiance reaches zero and below near the horizon for a low sun, also at
:data:`MEAN_FLOOR` of the hemisphere's mean luminance (the count of points where
that floor decides is printed).

Variables: u = (elevation / (pi/2))^(1/3) (the model's own Bezier variable; the sun
at the zenith is u = 1), the turbidity's interval k = floor(T) and s = T - k in
[0, 1] (the dataset interpolates linearly between integer turbidities, so the sky
has a kink in T at every integer), and the albedo a.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from skysh.model import hosek, hosek_frame  # noqa: E402
from skysh.sh import basis as sh  # noqa: E402
from skysh.table import fit, poly  # noqa: E402
from skysh.table.coefficient_file import zonal_half_layout  # noqa: E402

BANDS: int = 7
GOAL: float = 1e-4
"""Issue 17's goal: worst held-out E_mean at 7 bands."""
N_THETA: int = 24
"""sky_sh nodes per panel for the truth here (half the default, 4x faster); ``--fit`` prints its
difference from the default nodes at the interval's corners, relative to L_min."""
MEAN_FLOOR: float = 0.01
"""Floor of L_min as a fraction of the hemisphere's mean luminance (see the module docstring)."""
ROWS: np.ndarray = np.array([sh.index(l, m) for l, m in zonal_half_layout(BANDS)])
BAND_OF_ROW: np.ndarray = np.array([l for l, _ in zonal_half_layout(BANDS)])


# --------------------------------------------------------------------------- #
# Truth
# --------------------------------------------------------------------------- #
def zenith_of_u(u: np.ndarray) -> np.ndarray:
    """Sun zenith angle (radians) of u = (elevation / (pi/2))^(1/3)."""
    return 0.5 * math.pi * (1.0 - np.asarray(u) ** 3)


def _one(args: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    ts, t, a = args
    coeffs = hosek.sky_sh(ts, t, a, BANDS, n_theta=N_THETA)[ROWS]
    return coeffs, hosek.sky_minimum(ts, t, a)


def project_skies(one: Callable[[tuple[float, float, float]], tuple[np.ndarray, np.ndarray]],
                  points: list[tuple[float, float, float]], jobs: int) -> tuple[np.ndarray, np.ndarray]:
    """``one`` (a picklable ``(sun zenith, turbidity, albedo) -> (coefficients, minima)``) at every point, in order,
    over ``jobs`` worker processes when ``jobs`` > 1: the stacked (P, ...) coefficients and (P, 4) sky minima."""
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            results = list(pool.map(one, points, chunksize=8))
    else:
        results = [one(p) for p in points]
    return np.stack([r[0] for r in results]), np.stack([r[1] for r in results])


def truth(ts: np.ndarray, t: np.ndarray, a: np.ndarray, jobs: int) -> tuple[np.ndarray, np.ndarray, int]:
    """(P, 28, 3) m >= 0 coefficients (cd/m^2), (P, 3) E_mean denominators, and how many MEAN_FLOOR set."""
    coeffs, lmin = project_skies(_one, [(float(x), float(y), float(z)) for x, y, z in zip(ts, t, a)], jobs)
    den = denominator(lmin, coeffs)
    return coeffs, den, int(np.sum(den > fit.error_denominator(lmin)))


def denominator(lmin: np.ndarray, coeffs: np.ndarray) -> np.ndarray:
    """L_min per channel: skysh.table.fit's floor, then MEAN_FLOOR x the hemisphere's mean luminance."""
    mean_y = (coeffs[:, 0] @ hosek.luminance_row("sRGB")) / math.sqrt(math.pi)  # DC = sqrt(pi) x mean
    return np.maximum(fit.error_denominator(lmin), MEAN_FLOOR * mean_y[:, None])


def e_mean(predicted: np.ndarray, actual: np.ndarray, den: np.ndarray) -> np.ndarray:
    return fit.error_measures(predicted, actual, den, BANDS)["e_mean"]


# --------------------------------------------------------------------------- #
# Sections
# --------------------------------------------------------------------------- #
def section_minima() -> None:
    print("Smallest sun zenith (degrees) at which the sky's minimum over the hemisphere is negative")
    print("(any RGB channel / the luminance), per turbidity; albedo 0 and 1; 1-degree steps from 60 to 90.")
    zeniths = np.radians(np.arange(60.0, 90.5, 1.0))
    print(f"{'T':>5} {'a=0 RGB':>8} {'a=0 Y':>7} {'a=1 RGB':>8} {'a=1 Y':>7}")
    for t in (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0):
        cells = []
        for a in (0.0, 1.0):
            mins = np.array([hosek.sky_minimum(ts, t, a) for ts in zeniths])
            for negative in (np.any(mins[:, :3] < 0.0, axis=1), mins[:, 3] < 0.0):
                cells.append(f"{np.degrees(zeniths[np.argmax(negative)]):.0f}" if negative.any() else "-")
        print(f"{t:5.1f} {cells[0]:>8} {cells[1]:>7} {cells[2]:>8} {cells[3]:>7}")


def section_albedo(jobs: int) -> None:
    print("Two tables (albedo 0 and 1) interpolated linearly vs the model at albedo a:")
    print("worst E_mean at 7 bands over 24 sun zeniths (u uniform) x 9 turbidities, per a.")
    u = np.linspace(0.0, 1.0, 24)
    t = np.array([1.0, 1.5, 2.0, 3.0, 4.5, 6.0, 7.5, 9.0, 10.0])
    uu, tt = (x.ravel() for x in np.meshgrid(u, t, indexing="ij"))
    ts = zenith_of_u(uu)
    ends = [truth(ts, tt, np.full(ts.size, a), jobs)[0] for a in (0.0, 1.0)]
    print(f"{'a':>5} {'worst E_mean':>13} {'median':>9}  worst at (sun zenith deg, T)")
    for a in (0.1, 0.3, 0.5, 0.7, 0.9):
        actual, den, _ = truth(ts, tt, np.full(ts.size, a), jobs)
        e = e_mean((1.0 - a) * ends[0] + a * ends[1], actual, den)
        k = int(np.argmax(e))
        print(f"{a:5.1f} {e.max():13.2e} {np.median(e):9.2e}  ({np.degrees(ts[k]):.1f}, {tt[k]:.1f})")


def _chebyshev_fit(x: np.ndarray, values: np.ndarray, den: np.ndarray, degree: int) -> np.ndarray:
    """Weighted least squares of values (P, 28, 3) in T_0..T_degree of x; returns the fitted values."""
    design = poly.chebyshev(x, degree)
    out = np.empty_like(values)
    for c in range(3):
        w = 1.0 / den[:, c, None]
        coef = np.linalg.lstsq(design * w, values[:, :, c] * w, rcond=None)[0]
        out[:, :, c] = design @ coef
    return out


def section_turbidity(jobs: int) -> None:
    print("1-D fits in turbidity at fixed (sun zenith, albedo): worst E_mean at 7 bands on 181 turbidities.")
    print("'global': one Chebyshev polynomial over [1, 10]; 'interval': one per [k, k+1] (here [2, 3]).")
    t = np.linspace(1.0, 10.0, 181)
    print(f"{'zenith':>7} {'a':>4} " + " ".join(f"{'global ' + str(d):>10}" for d in (6, 10, 20, 30))
          + " " + " ".join(f"{'interval ' + str(d):>11}" for d in (2, 3, 4)))
    for ts, a in ((0.3, 0.5), (1.2, 0.2), (1.5, 0.8)):
        values, den, _ = truth(np.full(t.size, ts), t, np.full(t.size, a), jobs)
        cells = [e_mean(_chebyshev_fit((2.0 * t - 11.0) / 9.0, values, den, d), values, den).max() for d in (6, 10, 20, 30)]
        inside = (t >= 2.0) & (t <= 3.0)
        for d in (2, 3, 4):
            fitted = _chebyshev_fit(2.0 * (t[inside] - 2.5), values[inside], den[inside], d)
            cells.append(e_mean(fitted, values[inside], den[inside]).max())
        print(f"{np.degrees(ts):7.1f} {a:4.1f} " + " ".join(f"{c:10.2e}" for c in cells[:4]) + " "
              + " ".join(f"{c:11.2e}" for c in cells[4:]))


def lobatto(n: int) -> np.ndarray:
    """n Chebyshev-Lobatto nodes on [-1, 1] (endpoints included)."""
    return -np.cos(np.pi * np.arange(n) / (n - 1))


def design3(x: np.ndarray, y: np.ndarray, z: np.ndarray, degrees: tuple[int, int, int]) -> np.ndarray:
    """Tensor Chebyshev design T_i(x) T_j(y) T_k(z), term (i, j, k) at (i (dy+1) + j)(dz+1) + k."""
    tx, ty, tz = poly.chebyshev(x, degrees[0]), poly.chebyshev(y, degrees[1]), poly.chebyshev(z, degrees[2])
    return (tx[:, :, None, None] * ty[:, None, :, None] * tz[:, None, None, :]).reshape(x.size, -1)


def _variables(ts: np.ndarray, t: np.ndarray, a: np.ndarray, interval: int, variable: str) -> tuple[np.ndarray, ...]:
    x = 2.0 * np.cbrt(np.clip(1.0 - ts / (0.5 * math.pi), 0.0, 1.0)) - 1.0 if variable == "u" \
        else 4.0 * ts / math.pi - 1.0
    return x, 2.0 * (t - interval) - 1.0, 2.0 * a - 1.0


def interval_data(interval: int, nodes: tuple[int, int, int], held_out: int, variable: str, jobs: int) -> dict:
    """Truth on a Lobatto grid of one turbidity interval [k, k+1] and at random held-out points."""
    gx, gs, ga = (x.ravel() for x in np.meshgrid(*(lobatto(n) for n in nodes), indexing="ij"))
    ts = 0.5 * math.pi * (1.0 - ((gx + 1.0) / 2.0) ** 3) if variable == "u" else (gx + 1.0) * math.pi / 4.0
    grid = (ts, interval + (gs + 1.0) / 2.0, (ga + 1.0) / 2.0)
    rng = np.random.default_rng(1700 + interval)
    ho = (rng.uniform(0.0, 0.5 * math.pi, held_out), rng.uniform(interval, interval + 1.0, held_out),
          rng.uniform(0.0, 1.0, held_out))
    corners = np.array([(z, interval + s, a) for z in (0.0, 0.5 * math.pi) for s in (0.0, 1.0) for a in (0.0, 1.0)])
    ho = tuple(np.concatenate([h, corners[:, i]]) for i, h in enumerate(ho))
    grid_truth, held_truth = truth(*grid, jobs), truth(*ho, jobs)
    return {"grid": grid + grid_truth[:2], "held_out": ho + held_truth[:2], "floored": held_truth[2]}


def fit_interval(data: dict, interval: int, degrees: tuple[int, int, int], variable: str) -> np.ndarray:
    """Weighted least squares (residuals / L_min, as skysh.table.fit) on the grid; the held-out predictions (P, 28, 3)."""
    ts, t, a, values, den = data["grid"]
    design = design3(*_variables(ts, t, a, interval, variable), degrees)
    hts, ht, ha = data["held_out"][:3]
    held = design3(*_variables(hts, ht, ha, interval, variable), degrees)
    out = np.empty(data["held_out"][3].shape)
    for c in range(3):
        w = 1.0 / den[:, c, None]
        out[:, :, c] = held @ np.linalg.lstsq(design * w, values[:, :, c] * w, rcond=None)[0]
    return out


def _truth_check(data: dict, interval: int) -> float:
    """Worst |truth at N_THETA - truth at the default nodes| / L_min over the held-out corners (the last 8)."""
    ts, t, a, values, den = (x[-8:] for x in data["held_out"])
    default = np.stack([hosek.sky_sh(*p, BANDS)[ROWS] for p in zip(ts, t, a)])
    return float(np.max(np.abs(values - default) / den[:, None, :]))


PREETHAM_TABLE_NUMBERS: int = 112 * 28 * 3
"""The shipped Preetham file's sky table: (13 + 1)(7 + 1) terms x 28 rows x 3 channels (data/preetham_sh.npz)."""


def section_fit(intervals: list[int], candidates: list[tuple[int, int, int]], variable: str, jobs: int) -> None:
    within = tuple(max(d[i] for d in candidates) for i in range(3))
    nodes = (within[0] + 4, within[1] + 4, within[2] + 4)
    print(f"Per-interval tensor Chebyshev fits in ({variable}, s, albedo); grid Lobatto {nodes}; held-out: 150 random "
          "+ 8 corners per interval. Worst held-out E_mean at 7 bands (and per band), numbers stored for all 9 "
          f"intervals and their ratio to the Preetham file's sky table ({PREETHAM_TABLE_NUMBERS}).")
    for k in intervals:
        start = time.perf_counter()
        data = interval_data(k, nodes, 150, variable, jobs)
        actual, den = data["held_out"][3], data["held_out"][4]
        print(f"T in [{k}, {k + 1}] ({data['floored']} held-out denominators set by the mean floor; "
              f"truth at {N_THETA} vs {hosek.SKY_SH_THETA_NODES} nodes: {_truth_check(data, k):.1e} of L_min):")
        for degrees in candidates:
            predicted = fit_interval(data, k, degrees, variable)
            worst = e_mean(predicted, actual, den).max()
            per_band = [(np.sqrt(np.sum((predicted[:, r] - actual[:, r]) ** 2, axis=1)) / den).max()
                        for r in (np.flatnonzero(BAND_OF_ROW == b) for b in range(BANDS))]
            numbers = 9 * (degrees[0] + 1) * (degrees[1] + 1) * (degrees[2] + 1) * ROWS.size * 3
            print(f"  {degrees!s:>12}: E_mean {worst:.2e} (bands 0..6: " + " ".join(f"{e:.0e}" for e in per_band)
                  + f"); {numbers} numbers = {numbers / PREETHAM_TABLE_NUMBERS:.1f} x")
        print(f"  ({time.perf_counter() - start:.0f} s)")


def section_datasets(jobs: int) -> None:
    print("DC of the RGB dataset / DC of the spectral dataset (sRGB, cd/m^2), 300 random skies:")
    rng = np.random.default_rng(3)
    ratios = []
    for _ in range(300):
        ts, t, a = rng.uniform(0.0, 0.5 * math.pi), rng.uniform(1.0, 10.0), rng.uniform(0.0, 1.0)
        rgb = hosek.sky_sh(ts, t, a, 1, dataset="rgb", n_theta=16)[0]
        ratios.append(rgb / hosek.sky_sh(ts, t, a, 1, dataset="spectral", n_theta=16)[0])
    r = np.array(ratios)
    for c, name in enumerate("RGB"):
        print(f"  {name}: {r[:, c].min():.3f} to {r[:, c].max():.3f}")


def section_mitsuba() -> None:
    sys.path[:0] = [str(ROOT / "tests" / "model"), str(ROOT / "tests")]  # test_hosek, and the conftest it imports
    import mitsuba as mi
    import test_hosek as t  # the test's own comparison: the same skies, directions and budget

    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(7)
    worst = []
    scale = hosek.LUMINOUS_EFFICACY / mi.MI_CIE_Y_NORMALIZATION
    for sky in t._skies(rng, 300):
        d = t._upper_dirs(rng, 50)
        diff = np.abs(hosek.radiance(d, *sky) - t._mitsuba_eval(mi, sky, d) * scale)
        worst.append(float(np.max(diff / (t.EPS32 * t._float32_budget(d, *sky)))))
    print(f"|skysh - Mitsuba| / (EPS32 x budget) over {50 * 300} directions (300 skies): max {max(worst):.1f}, "
          f"median of the per-sky maxima {np.median(worst):.2f} (tests/model/test_hosek.py allows {t.MITSUBA_ULPS:.0f})")
    compare = t.TestAgainstMitsuba()._compare  # in units of the test's tolerance (MITSUBA_ULPS budgets)
    print(f"the test's comparison: {compare(mi):.2f} of its tolerance; negative controls: albedo a -> 1 - a "
          f"{compare(mi, lambda ts, phi, tu, a: (ts, phi, tu, 1.0 - a)):.1e}, azimuth from +Y "
          f"{compare(mi, lambda ts, phi, tu, a: (ts, 0.5 * math.pi - phi, tu, a)):.1e} x the tolerance")


# --------------------------------------------------------------------------- #
# Issue 27: the per-frame rule (skysh.model.hosek_frame)
# --------------------------------------------------------------------------- #
RULE_BANDS: tuple[int, ...] = (3, 7)
"""The band counts of issue 27's targets."""
RULE_TARGETS: dict[int, float] = {3: 3e-5, 7: 1e-4}
"""Issue 27's targets: worst E_mean at 3 and 7 bands, on both point sets."""
RULE_RANDOM: int = 256
"""Uniform random skies (sun zenith, turbidity, albedo) of the held-out set, before its corners and horizon suns."""


def rule_sets(random: int = RULE_RANDOM, seed: int = 2027) -> dict[str, np.ndarray]:
    """Issue 27's point sets, (P, 3) rows (sun zenith, turbidity, albedo).

    "random": uniform skies, the domain's 8 corners, 8 random skies with the sun on the horizon.
    "stress": 48 suns uniform in [80, 90] degrees; the sun exactly on and 1e-7 rad either side of every
    panel edge of hosek_frame.ZENITH_EDGES, each at the four (turbidity, albedo) corners; the corners.
    """
    rng = np.random.default_rng(seed)
    half = 0.5 * math.pi
    corners = np.array([(z, t, a) for z in (0.0, half) for t in (1.0, 10.0) for a in (0.0, 1.0)])
    uniform = np.column_stack([rng.uniform(0.0, half, random), rng.uniform(1.0, 10.0, random), rng.uniform(0.0, 1.0, random)])
    horizon = np.column_stack([np.full(8, half), rng.uniform(1.0, 10.0, 8), rng.uniform(0.0, 1.0, 8)])
    low = np.column_stack([rng.uniform(math.radians(80.0), half, 48), rng.uniform(1.0, 10.0, 48), rng.uniform(0.0, 1.0, 48)])
    zeniths = sorted({min(max(e + d, 0.0), half) for e in hosek_frame.ZENITH_EDGES for d in (-1e-7, 0.0, 1e-7)})
    edges = np.array([(z, t, a) for z in zeniths for t in (1.0, 10.0) for a in (0.0, 1.0)])
    return {"random": np.concatenate([uniform, corners, horizon]), "stress": np.concatenate([low, edges, corners])}


def _reference(point: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """The converged projection (hosek.sky_sh at its default nodes: doubling them moves it < 1e-8 of L_min) and minima."""
    return hosek.sky_sh(*point, max(RULE_BANDS))[ROWS], hosek.sky_minimum(*point)


def rule_reference(points: np.ndarray, jobs: int) -> tuple[np.ndarray, np.ndarray]:
    """(P, 28, 3) m >= 0 reference coefficients and (P, 3) L_min (floored as :func:`denominator`)."""
    coeffs, lmin = project_skies(_reference, [(float(z), float(t), float(a)) for z, t, a in points], jobs)
    return coeffs, denominator(lmin, coeffs)


def rule_errors(accuracy: str | hosek_frame.Accuracy, points: np.ndarray, truth: np.ndarray, den: np.ndarray,
                bands: int) -> np.ndarray:
    """(P,) E_mean of hosek_frame.coefficients (batched, sun at azimuth 0) at ``bands`` against the reference."""
    got = hosek_frame.coefficients(points[:, 0], points[:, 1], points[:, 2], bands=max(RULE_BANDS), accuracy=accuracy)
    return fit.error_measures(got[:, ROWS], truth, den, bands)["e_mean"]


def _best(call, repeat: int = 200) -> float:
    """Mean time of ``repeat`` calls, seconds."""
    start = time.perf_counter()
    for _ in range(repeat):
        call()
    return (time.perf_counter() - start) / repeat


def _call_time(accuracy: str | hosek_frame.Accuracy, bands: int = 7) -> float:
    """Best-of-5 mean time of one scalar call (sun azimuth 0.7), seconds."""
    return min(_best(lambda: hosek_frame.coefficients(1.0, 3.0, 0.5, 0.7, bands=bands, accuracy=accuracy))
               for _ in range(5))


def rule_candidates() -> dict[str, hosek_frame.Accuracy]:
    """The offered accuracies and the variants tried: without the two ideas of issue 27, and the issue's rules."""
    acc = hosek_frame.Accuracy
    out: dict[str, hosek_frame.Accuracy] = dict(hosek_frame.ACCURACIES)
    for name in ("fast", "default"):
        a = out[name]
        out[f"{name}, halves"] = acc(a.zenith, a.sun, a.minimum, a.azimuth, a.low_sun_azimuth, by_width=False)
        out[f"{name}, minimum 2"] = acc(a.zenith, a.sun, 2, a.azimuth, a.low_sun_azimuth)
        out[f"{name}, one azimuth"] = acc(a.zenith, a.sun, a.minimum, a.azimuth, a.azimuth)
    out["issue (6,6,8,6)x20"] = acc((6, 8, 6), 6, 6, 20, 20, by_width=False)
    out["issue (8,8,8,8)x24"] = acc((8, 8, 8), 8, 8, 24, 24, by_width=False)
    out["issue (10,10,10,8)x24"] = acc((10, 10, 8), 10, 10, 24, 24, by_width=False)
    return out


def section_rule(jobs: int) -> None:
    sets = rule_sets()
    print("Per-frame SH of the Hosek-Wilkie sky (skysh.model.hosek_frame) against hosek.sky_sh at its default nodes:")
    print(f"worst E_mean (m >= 0, worst channel, L_min floored as --fit) on {len(sets['random'])} random and "
          f"{len(sets['stress'])} stress skies; targets {RULE_TARGETS[3]:.0e} (3 bands), {RULE_TARGETS[7]:.0e} (7 bands).")
    refs = {name: rule_reference(points, jobs) for name, points in sets.items()}
    print(f"{'rule':>24} {'rings':>5} {'az':>7} {'points':>9} {'3 random':>9} {'3 stress':>9} {'7 random':>9} "
          f"{'7 stress':>9} {'us/call':>8}")
    for name, accuracy in rule_candidates().items():
        cells = [rule_errors(accuracy, sets[s], *refs[s], b).max() for b in RULE_BANDS for s in ("random", "stress")]
        az = f"{accuracy.azimuth}/{accuracy.low_sun_azimuth}"
        points = f"{accuracy.rings * accuracy.azimuth}/{accuracy.rings * accuracy.low_sun_azimuth}"
        print(f"{name:>24} {accuracy.rings:5d} {az:>7} {points:>9} " + " ".join(f"{c:9.1e}" for c in cells)
              + f" {_call_time(accuracy) * 1e6:8.0f}")
    from skysh import SkySH

    sky = SkySH.load()
    preetham_call = min(_best(lambda: sky.coefficients(1.0, 3.0, 0.5, bands=7)) for _ in range(5))
    print(f"Preetham table, 7 bands (SkySH.load().coefficients(1.0, 3.0, 0.5, bands=7)): {preetham_call * 1e6:.1f} us; "
          f"default / Preetham: {_call_time('default') / preetham_call:.0f}x")
    worst = rule_errors("default", sets["stress"], *refs["stress"], 7)
    k = int(np.argmax(worst))
    z, t, a = sets["stress"][k]
    print(f"default's worst stress sky at 7 bands: sun zenith {math.degrees(z):.7f} deg, T {t:.2f}, albedo {a:.2f}")


def build_parser() -> argparse.ArgumentParser:
    """The command line: a flag per section, and the ``--fit`` section's settings."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1], formatter_class=argparse.RawTextHelpFormatter)
    for name in ("minima", "albedo", "turbidity", "fit", "datasets", "mitsuba", "rule"):
        parser.add_argument(f"--{name}", action="store_true", help=f"print the {name} section")
    parser.add_argument("--intervals", default="2", help="--fit: turbidity intervals k of [k, k+1] (1..9), comma-separated")
    parser.add_argument("--degrees", default="8,1,1;12,2,2;16,3,3;20,3,4;24,3,4;24,4,5",
                        help="--fit: degree triples (sun variable, s, albedo), ';'-separated")
    parser.add_argument("--variable", choices=("u", "zenith"), default="u", help="--fit: the sun's variable")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes for the projections")
    return parser


def fit_settings(parser: argparse.ArgumentParser, args: argparse.Namespace) -> tuple[list[int], list[tuple[int, ...]]]:
    """``--intervals`` and ``--degrees`` parsed and checked (one line, exit 2)."""
    intervals = [int(k) for k in args.intervals.split(",")]
    candidates = [tuple(int(d) for d in triple.split(",")) for triple in args.degrees.split(";")]
    if any(not 1 <= k <= 9 for k in intervals) or any(len(c) != 3 or min(c) < 0 for c in candidates):
        parser.error("--intervals are integers in 1..9; --degrees triples of integers >= 0")
    return intervals, candidates


def main(argv: list[str] | None = None) -> None:
    parser = build_parser()
    args = parser.parse_args(argv)
    intervals, candidates = fit_settings(parser, args)
    chosen = [n for n in ("minima", "albedo", "turbidity", "fit", "datasets", "mitsuba", "rule") if getattr(args, n)]
    for name in chosen or ["minima", "albedo", "turbidity", "datasets"]:
        if name == "fit":
            section_fit(intervals, candidates, args.variable, args.jobs)
        elif name in ("minima", "mitsuba"):
            globals()[f"section_{name}"]()
        else:
            globals()[f"section_{name}"](args.jobs)
        print()


if __name__ == "__main__":
    main()
