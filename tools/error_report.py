#!/usr/bin/env python
"""
The skysh error report: every accuracy, cost and stability figure in one run
============================================================================

Writes ``DIR/report.md`` with PNG charts (matplotlib, Agg) and the tables
behind them; every number is computed by this tool in the run that writes it.
The logic is the package's (:mod:`skysh.sh`, :mod:`skysh.preetham`,
:mod:`skysh.fit`, :mod:`skysh.runtime`, :mod:`skysh.dering`,
:mod:`skysh.quantize`, :mod:`skysh.hazel`, :mod:`skysh.render`) and the sibling
experiment tools' (``tools/quantize_experiment.py``,
``tools/dering_experiment.py``, ``tools/fit_sky.py``); this file measures,
tabulates and draws.

Sections
--------
1.  Projection methods: error against sample count and wall time (mc,
    stratified, qmc, the sun-adapted and the plain product quadrature) against
    a denser sun-adapted quadrature as truth.
2.  The fit: E_mean and E_max (Habel eqs. 2, 3) of the shipped file over a
    held-out grid of (sun zenith, turbidity), by bands, beside the seed's figures.
3.  Speed against accuracy: degrees and bands swept, cost per call and table
    size against error (Pareto front), and the runtime against projecting the
    sky per frame at equal accuracy.
4.  The Gibbs filter (Habel eq. 5): ringing with and without.
5.  Deringing (Sloan 2017, skysh.dering): windows across the domain, minima
    before and after, the bound against the exact minimum, detail against cost.
6.  Quantization (Wiederien and Sloan 2024, Table 3) on sky data.
7.  Irradiance reconstructions (L1 linear, Geomerics L1, L2, deringed L2)
    against the sky's exact irradiance.
8.  Stability where methods fail: raw monomials, extrapolation, Monte Carlo at
    low sample counts, the sun at the zenith and on the horizon, float32,
    Newton steps of the bound, fuzzing of ``SkySH.coefficients``.
9.  What a scene needs: irradiance and radiance error against bands and degrees.
10. Pictures: the sky, its 3- and 7-band reconstructions and the irradiance.

Run::

    PYTHONPATH=. python tools/error_report.py --out /tmp/report --quick   # about a minute
    PYTHONPATH=. python tools/error_report.py --out docs/report            # the committed report

``--quick`` uses small grids and few samples (for the test suite); the full run
takes several minutes on 2 cores, with progress bars. BLAS is limited to one
thread per process (multi-threaded OpenBLAS on a loaded 2-core machine turns a
0.2 s least-squares fit into 15 s); at most ``--jobs`` (default 2) worker
processes project the sky.
"""

from __future__ import annotations

import os

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")  # before numpy is imported, here and in the workers

import argparse  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
import warnings  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any, Callable, Iterable  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
for _path in (ROOT, ROOT / "tools"):
    if str(_path) not in sys.path:
        sys.path.insert(0, str(_path))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize, SymLogNorm  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from tqdm import tqdm  # noqa: E402

import dering_experiment  # noqa: E402  (tools/)
import fit_sky  # noqa: E402  (tools/)
import quantize_experiment  # noqa: E402  (tools/)
from skysh import coefficient_file, fit, hazel, poly, preetham, quantize, render, runtime, sh  # noqa: E402
from skysh._version import __version__  # noqa: E402
from skysh.runtime import SkySH  # noqa: E402

# --------------------------------------------------------------------------- #
# Constants
# --------------------------------------------------------------------------- #
SEED_E_MEAN_7: float = 0.015
"""Habel 2008, section 3.2: the highest E_mean drops below 1.5% for 7 bands (fraction)."""

SEED_E_MEAN_5: float = 0.00005
"""Habel 2008, section 3.2: E_mean < 0.005% up to 5 bands (fraction)."""

SEED_SIZE_KB_7: float = 131.0
"""Habel 2008, section 4: 131 KB of tables for 7 bands."""

SEED_SIZE_KB_4: float = 28.0
"""Habel 2008, section 4: 28 KB for 4 bands."""

SEED_TIME_US: float = 80.0
"""Habel 2008, section 4: about 80 microseconds per evaluation of 7 bands (Pentium 4, 3.2 GHz)."""

SEED_DEGREES: tuple[int, int] = (13, 7)
"""Habel 2008, section 3.2: polynomial degrees (d_theta, d_tau)."""

MAX_BANDS: int = 7
"""Bands of the shipped file and of every study here."""

RANDOM_METHODS: tuple[str, ...] = ("mc", "stratified", "qmc")
"""The random projection methods of :func:`skysh.sh.project` (via :func:`skysh.preetham.sky_sh`)."""

SUN_QUADRATURE: str = "quadrature (sun-adapted)"
"""Label of :func:`skysh.preetham.sky_sh`'s default rule."""

PLAIN_QUADRATURE: str = "quadrature (plain product)"
"""Label of :func:`skysh.sh.project`'s product Gauss rule over the hemisphere."""

METHOD_STYLE: dict[str, dict[str, Any]] = {
    "mc": {"color": "tab:red", "marker": "o"},
    "stratified": {"color": "tab:orange", "marker": "s"},
    "qmc": {"color": "tab:purple", "marker": "^"},
    SUN_QUADRATURE: {"color": "tab:blue", "marker": "D"},
    PLAIN_QUADRATURE: {"color": "tab:cyan", "marker": "v"},
}
"""Colours and markers of the projection methods in every chart."""

NEWTON_REFERENCE: int = 64
"""Newton steps of the converged reference bound in the Newton study (section 8)."""

DPI: int = 100
"""Resolution of the PNGs (keeps the committed report small)."""

HALF_ROWS: NDArray[np.intp] = np.array(
    [sh.index(l, m) for l, m in coefficient_file.zonal_half_layout(MAX_BANDS)], dtype=np.intp
)
"""Flat SH indices of the stored (m >= 0) rows of 7 bands, in the file's order."""

SECTION_TITLES: dict[int, str] = {
    1: "Projection methods",
    2: "The fit",
    3: "Speed against accuracy",
    4: "Gibbs filter",
    5: "Deringing",
    6: "Quantization",
    7: "Irradiance reconstructions",
    8: "Stability where methods fail",
    9: "What a scene needs",
    10: "Pictures",
}
"""Headings of report.md (``## k. title``); the test checks every one is present."""

FAILED_MARK: str = "**This section failed**"
"""Written in place of a section whose computation raised; the tool then exits with status 1."""


@dataclass(frozen=True)
class Plan:
    """Sizes of every study: :data:`QUICK` for the test suite, :data:`FULL` for the committed report."""

    name: str
    s1_points: tuple[tuple[float, float], ...]
    s1_samples: tuple[int, ...]
    s1_seeds: int
    s1_nodes: tuple[int, ...]
    truth_nodes: int
    test_grid: tuple[int, int]
    fit_grid: tuple[int, int]
    degrees_theta: tuple[int, ...]
    degrees_tau: tuple[int, ...]
    timing: tuple[int, int]
    gibbs_suns: tuple[tuple[float, float], ...]
    dering_grid: tuple[int, int]
    dering_seven: int
    random_functions: int
    table3_points: int
    bits: tuple[int, ...]
    hazel_points: int
    hazel_zeniths: tuple[float, ...]
    stability_degrees: tuple[tuple[int, int], ...]
    extrapolation: tuple[int, tuple[float, ...]]
    mc_counts: tuple[int, ...]
    mc_seeds: int
    mc_points: tuple[tuple[float, float], ...]
    newton_steps: tuple[int, ...]
    fuzz_inputs: int
    scene_points: int
    picture_suns: tuple[tuple[float, float, float], ...]
    picture_width: int


_D = math.radians

QUICK = Plan(
    name="quick",
    s1_points=((_D(40.0), 3.5), (_D(85.0), 5.0)),
    s1_samples=(64, 256, 1024, 4096),
    s1_seeds=3,
    s1_nodes=(8, 16, 32),
    truth_nodes=96,
    test_grid=(10, 6),
    fit_grid=(16, 8),
    degrees_theta=(3, 7, 13),
    degrees_tau=(1, 3, 7),
    timing=(3, 30),
    gibbs_suns=((_D(30.0), 3.0), (_D(80.0), 2.5)),
    dering_grid=(7, 4),
    dering_seven=4,
    random_functions=1000,
    table3_points=64,
    bits=(4, 8, 12),
    hazel_points=4,
    hazel_zeniths=(_D(10.0), _D(60.0), _D(88.0)),
    stability_degrees=((5, 3), (13, 7)),
    extrapolation=(6, (_D(30.0), _D(80.0))),
    mc_counts=(4, 16, 64, 256),
    mc_seeds=20,
    mc_points=((_D(70.0), 3.0),),
    newton_steps=(1, 2, 4),
    fuzz_inputs=300,
    scene_points=3,
    picture_suns=((_D(25.0), _D(30.0), 2.5), (_D(85.0), _D(-60.0), 4.0)),
    picture_width=128,
)
"""Small sizes: the whole report in about a minute."""

FULL = Plan(
    name="full",
    s1_points=((_D(10.0), 2.5), (_D(45.0), 3.5), (_D(75.0), 5.0), (_D(89.0), 6.0)),
    s1_samples=(64, 256, 1024, 4096, 16384, 65536),
    s1_seeds=8,
    s1_nodes=(8, 11, 16, 23, 32, 45, 64, 90),
    truth_nodes=160,
    test_grid=(46, 22),
    fit_grid=(48, 24),
    degrees_theta=(3, 5, 7, 9, 11, 13, 15, 17),
    degrees_tau=(1, 2, 3, 5, 7, 9),
    timing=(5, 200),
    gibbs_suns=((_D(10.0), 2.5), (_D(45.0), 3.5), (_D(75.0), 3.0), (_D(89.0), 2.5)),
    dering_grid=(19, 8),
    dering_seven=24,
    random_functions=20000,
    table3_points=1024,
    bits=(4, 5, 6, 8, 10, 12, 16),
    hazel_points=64,
    hazel_zeniths=tuple(_D(z) for z in (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 90.0)),
    stability_degrees=((3, 1), (5, 3), (7, 3), (9, 5), (11, 5), (13, 7), (15, 7), (17, 9)),
    extrapolation=(25, (_D(30.0), _D(60.0), _D(85.0))),
    mc_counts=(4, 8, 16, 32, 64, 128, 256, 1024, 4096),
    mc_seeds=200,
    mc_points=((_D(30.0), 3.0), (_D(70.0), 3.0), (_D(88.0), 2.5)),
    newton_steps=(1, 2, 3, 4, 6, 8),
    fuzz_inputs=5000,
    scene_points=16,
    picture_suns=((_D(25.0), _D(30.0), 2.5), (_D(65.0), _D(120.0), 4.0), (_D(88.0), _D(-60.0), 6.0)),
    picture_width=256,
)
"""The committed report's sizes: the shipped fitting grid, dense held-out grid, many seeds."""


# --------------------------------------------------------------------------- #
# Formatting and report assembly
# --------------------------------------------------------------------------- #
def sig(value: float, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (plain for moderate sizes, else exponent)."""
    if value is None:
        return "-"
    value = float(value)
    if not math.isfinite(value):
        return str(value)
    if value == 0.0:
        return "0"
    if 1e-3 <= abs(value) < 1e5:
        text = f"{value:.{digits}g}"
        return text
    return f"{value:.{digits - 1}e}"


def pct(fraction: float, digits: int = 3) -> str:
    """A fraction as a percentage with ``digits`` significant digits."""
    return sig(100.0 * float(fraction), digits) + "%"


def us(seconds: float) -> str:
    """Seconds as microseconds, 3 significant digits."""
    return sig(1e6 * seconds) + " us"


def ms(seconds: float) -> str:
    """Seconds as milliseconds, 3 significant digits."""
    return sig(1e3 * seconds) + " ms"


def markdown_table(header: list[str], rows: Iterable[Iterable[Any]]) -> list[str]:
    """A GitHub markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return lines + [""]


class Section:
    """Markdown of one report section, built as the section computes."""

    def __init__(self, number: int) -> None:
        self.number = number
        self.lines: list[str] = [f"## {number}. {SECTION_TITLES[number]}", ""]

    def text(self, *paragraphs: str) -> None:
        for paragraph in paragraphs:
            self.lines += [paragraph, ""]

    def table(self, header: list[str], rows: Iterable[Iterable[Any]]) -> None:
        self.lines += markdown_table(header, rows)

    def figure(self, name: str, caption: str) -> None:
        self.lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]

    def raw(self, lines: Iterable[str]) -> None:
        self.lines += list(lines) + [""]


@dataclass
class Context:
    """What every section shares: settings, the runtime, cached projections and the summary."""

    plan: Plan
    out: Path
    jobs: int
    progress: bool
    sky: SkySH
    summary: list[tuple[str, str, str]] = field(default_factory=list)
    cache: dict[str, Any] = field(default_factory=dict)
    figures: list[str] = field(default_factory=list)

    def bar(self, total: int, desc: str) -> tqdm:
        return tqdm(total=total, desc=desc, unit="step", leave=False, disable=not self.progress, file=sys.stderr)

    def note(self, quantity: str, value: str, seed: str = "") -> None:
        """One row of the summary table at the top of the report."""
        self.summary.append((quantity, value, seed))

    def save(self, fig: plt.Figure, name: str) -> str:
        """Save a figure as PNG in the output directory and close it; returns the file name."""
        fig.savefig(self.out / name, dpi=DPI)
        plt.close(fig)
        self.figures.append(name)
        return name

    def memo(self, key: str, compute: Callable[[], Any]) -> Any:
        if key not in self.cache:
            self.cache[key] = compute()
        return self.cache[key]


def best_time(function: Callable[[], Any], repeats: int, number: int) -> float:
    """Best mean seconds per call of ``number`` calls over ``repeats`` runs, after a warm-up
    (``tools/dering_experiment.py``'s timer)."""
    return dering_experiment.best_time(function, repeats=repeats, number=number)


# --------------------------------------------------------------------------- #
# Small helpers over the package
# --------------------------------------------------------------------------- #
def full_from_half(half: NDArray, bands: int) -> NDArray:
    """(..., bands (bands + 1) / 2, C) m >= 0 rows -> (..., bands^2, C) with zero m < 0 rows (sun at azimuth 0)."""
    k = bands * (bands + 1) // 2
    out = np.zeros(half.shape[:-2] + (bands * bands, half.shape[-1]))
    out[..., HALF_ROWS[:k], :] = half[..., :k, :]
    return out


def error_all(predicted: NDArray, truth: NDArray, denominator: NDArray, bands: int) -> dict[str, NDArray]:
    """:func:`skysh.fit.error_measures` over **all** ``bands^2`` coefficients of full-layout arrays (P, K, 3).

    ``fit.error_measures`` sums the first ``b (b + 1) / 2`` rows of its input (the
    m >= 0 layout of a fit, whose m < 0 rows are zero). A projection by random
    sampling also errs in the m < 0 coefficients, so the full arrays, cut to
    ``bands^2`` rows, are passed with the smallest ``b`` whose ``b (b + 1) / 2``
    covers them: every coefficient of the first ``bands`` bands is summed.
    """
    k = bands * bands
    b = 1
    while b * (b + 1) // 2 < k:
        b += 1
    return fit.error_measures(predicted[:, :k], truth[:, :k], denominator, b)


def gibbs_filter(coeffs: NDArray) -> NDArray:
    """Habel eq. 5 on full-layout SH (..., N^2, C): zonal rows times :func:`skysh.runtime.gibbs_factors` (as the runtime)."""
    bands = math.isqrt(coeffs.shape[-2])
    out = np.array(coeffs, dtype=np.float64)
    for l, factor in enumerate(runtime.gibbs_factors(bands)):  # noqa: E741
        out[..., sh.index(l, 0), :] *= factor
    return out


def mean_value(coeffs: NDArray) -> NDArray:
    """Mean over the sphere of SH (..., K, C): c0 Y00 (``tools/dering_experiment.py``), (..., C)."""
    return dering_experiment.mean_value(coeffs)


def luminance_row() -> NDArray:
    """Y from linear sRGB: the second row of the inverse of the XYZ -> sRGB matrix of skysh.preetham."""
    return np.linalg.inv(preetham.rgb_from_xyz_matrix("sRGB"))[1]


def uniform_grid(shape: tuple[int, int]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Uniform (sun zenith, turbidity) grid over the fitted domain including its edges: flat arrays and axes."""
    zen = np.linspace(*poly.SUN_ZENITH_DOMAIN, shape[0])
    tur = np.linspace(*poly.TURBIDITY_DOMAIN, shape[1])
    a, b = np.meshgrid(zen, tur, indexing="ij")
    return a.ravel(), b.ravel(), zen, tur


def pareto(x: NDArray, y: NDArray) -> NDArray[np.intp]:
    """Indices of the points not dominated in (smaller x, smaller y), sorted by x."""
    order = np.lexsort((y, x))
    keep, best = [], math.inf
    for i in order:
        if y[i] < best:
            keep.append(i)
            best = y[i]
    return np.array(keep, dtype=np.intp)


def cost_to_reach(times: NDArray, errors: NDArray, samples: NDArray, target: float) -> tuple[float, float, bool]:
    """Wall time and samples at which a convergence curve first reaches ``target``.

    Interpolated log-log between the bracketing measurements; beyond the last
    one, extrapolated along the slope of the last two (returned flag True).
    """
    times, errors, samples = (np.asarray(a, dtype=np.float64) for a in (times, errors, samples))
    below = np.flatnonzero(errors <= target)
    if below.size:
        i = int(below[0])
        if i == 0:
            return float(times[0]), float(samples[0]), False
        u = math.log(target / errors[i - 1]) / math.log(errors[i] / errors[i - 1])
        t = math.exp(math.log(times[i - 1]) + u * math.log(times[i] / times[i - 1]))
        n = math.exp(math.log(samples[i - 1]) + u * math.log(samples[i] / samples[i - 1]))
        return t, n, False
    slope_t = math.log(errors[-1] / errors[-2]) / math.log(times[-1] / times[-2])
    slope_n = math.log(errors[-1] / errors[-2]) / math.log(samples[-1] / samples[-2])
    if slope_t >= 0.0 or slope_n >= 0.0:
        return math.inf, math.inf, True
    return (
        float(times[-1] * (target / errors[-1]) ** (1.0 / slope_t)),
        float(samples[-1] * (target / errors[-1]) ** (1.0 / slope_n)),
        True,
    )


def cell_edges(values: NDArray) -> NDArray:
    """Cell edges around uniformly spaced centres (for pcolormesh)."""
    values = np.asarray(values, dtype=np.float64)
    step = values[1] - values[0] if values.size > 1 else 1.0
    return np.concatenate([values - 0.5 * step, values[-1:] + 0.5 * step])


def heatmap(ax: plt.Axes, zen: NDArray, tur: NDArray, values: NDArray, title: str, label: str,
            norm: Any = None, cmap: str = "viridis", marks: NDArray | None = None) -> None:
    """A (sun zenith, turbidity) heatmap with a colour bar; ``marks`` flags cells with an x."""
    mesh = ax.pcolormesh(cell_edges(np.degrees(zen)), cell_edges(tur), values.T, norm=norm, cmap=cmap, shading="flat")
    plt.colorbar(mesh, ax=ax, label=label)
    if marks is not None and marks.any():
        a, b = np.meshgrid(np.degrees(zen), tur, indexing="ij")
        ax.plot(a[marks], b[marks], "x", color="white", markersize=5, label="L_min floored")
        ax.legend(loc="upper left", fontsize=8, framealpha=0.6)
    ax.set_xlabel("sun zenith angle (deg)")
    ax.set_ylabel("turbidity (dimensionless)")
    ax.set_title(title)


# --------------------------------------------------------------------------- #
# Shared computations (memoised in the context)
# --------------------------------------------------------------------------- #
def projection_study(ctx: Context) -> dict[str, Any]:
    """Section 1's measurements: every method at every sample count, seed and sky point, timed serially."""
    plan, sky = ctx.plan, ctx.sky
    total = len(plan.s1_points) * (len(RANDOM_METHODS) * len(plan.s1_samples) * plan.s1_seeds + 2 * len(plan.s1_nodes) + 1)
    records: list[dict[str, Any]] = []
    points: list[dict[str, Any]] = []
    repeats, number = plan.timing
    for method in RANDOM_METHODS:  # warm-up: first-call imports (scipy.stats.qmc) are not a per-frame cost
        preetham.sky_sh(*plan.s1_points[0], MAX_BANDS, method=method, n=64, seed=0)
    with ctx.bar(total, "1. projection methods") as bar:
        for p, (ts, tu) in enumerate(plan.s1_points):
            truth = preetham.sky_sh(ts, tu, MAX_BANDS, n=4 * plan.truth_nodes**2)[None]
            lmin = preetham.sky_minimum(ts, tu)[None]
            denom = fit.error_denominator(lmin)

            def measure(c: NDArray) -> tuple[float, float, float]:
                e7 = error_all(c[None], truth, denom, MAX_BANDS)
                e3 = error_all(c[None], truth, denom, 3)
                return float(e7["e_mean"][0]), float(e3["e_mean"][0]), float(e7["dc"][0])

            default = preetham.sky_sh(ts, tu, MAX_BANDS)
            d7, _, ddc = measure(default)
            rt7, rt3, _ = measure(sky.coefficients(ts, tu, 0.0, bands=MAX_BANDS, gibbs=False))
            points.append({
                "point": p, "sun_zenith": ts, "turbidity": tu, "default_e7": d7, "default_dc": ddc,
                "runtime_e7": rt7, "runtime_e3": rt3,
                "runtime_s3": best_time(lambda: sky.coefficients(ts, tu, 0.3, bands=3), repeats, number),
                "runtime_s7": best_time(lambda: sky.coefficients(ts, tu, 0.3, bands=MAX_BANDS), repeats, number),
                "default_s": best_time(lambda: preetham.sky_sh(ts, tu, MAX_BANDS), 3, 1),
                "default_samples": int(preetham.sky_quadrature_rule(ts)[0].shape[0]),
            })
            bar.update(1)
            for method in RANDOM_METHODS:
                for n in plan.s1_samples:
                    for seed in range(plan.s1_seeds):
                        start = time.perf_counter()
                        c = preetham.sky_sh(ts, tu, MAX_BANDS, method=method, n=n, seed=1000 * p + seed)
                        seconds = time.perf_counter() - start
                        e7, e3, dc = measure(c)
                        records.append({"method": method, "point": p, "seed": seed, "samples": n, "seconds": seconds,
                                        "e7": e7, "e3": e3, "dc": dc})
                        bar.update(1)
            for nodes in plan.s1_nodes:
                count = int(preetham.sky_quadrature_rule(ts, nodes)[0].shape[0])
                c = preetham.sky_sh(ts, tu, MAX_BANDS, n=4 * nodes * nodes)
                seconds = best_time(lambda: preetham.sky_sh(ts, tu, MAX_BANDS, n=4 * nodes * nodes), 3, 1)
                e7, e3, dc = measure(c)
                records.append({"method": SUN_QUADRATURE, "point": p, "seed": 0, "samples": count, "seconds": seconds,
                                "e7": e7, "e3": e3, "dc": dc})
                bar.update(1)
                counted: list[int] = []

                def sky_radiance(dirs: NDArray) -> NDArray:
                    counted.append(dirs.shape[0])
                    return preetham.radiance(dirs, ts, 0.0, tu)

                plain = 4 * nodes * nodes  # about as many directions as the sun-adapted rule
                c = sh.project(sky_radiance, MAX_BANDS, "quadrature", n=plain, hemisphere=True)
                seconds = best_time(lambda: sh.project(sky_radiance, MAX_BANDS, "quadrature", n=plain, hemisphere=True), 3, 1)
                e7, e3, dc = measure(c)
                records.append({"method": PLAIN_QUADRATURE, "point": p, "seed": 0, "samples": counted[0],
                                "seconds": seconds, "e7": e7, "e3": e3, "dc": dc})
                bar.update(1)
    return {"records": records, "points": points}


def curves(study: dict[str, Any], method: str, point: int | None = None, key: str = "e7") -> dict[str, NDArray]:
    """Median error and time per sample count of one method (one point or all), with 10/90 percentiles."""
    rows = [r for r in study["records"] if r["method"] == method and (point is None or r["point"] == point)]
    counts = sorted({r["samples"] for r in rows})
    if point is None and method in (SUN_QUADRATURE, PLAIN_QUADRATURE):
        # node counts differ slightly between points (the sun at the zenith halves the sun-adapted rule): group by rank
        per_point: dict[int, list[dict[str, Any]]] = {}
        for r in rows:
            per_point.setdefault(r["point"], []).append(r)
        groups = list(zip(*[sorted(v, key=lambda r: r["samples"]) for v in per_point.values()]))
    else:
        groups = [[r for r in rows if r["samples"] == n] for n in counts]
    samples = np.array([np.median([r["samples"] for r in g]) for g in groups])
    err = [np.array([r[key] for r in g]) for g in groups]
    return {
        "samples": samples,
        "seconds": np.array([np.median([r["seconds"] for r in g]) for g in groups]),
        "median": np.array([np.median(e) for e in err]),
        "low": np.array([np.quantile(e, 0.1) for e in err]),
        "high": np.array([np.quantile(e, 0.9) for e in err]),
        "worst": np.array([np.max(e) for e in err]),
    }


def grids(ctx: Context) -> dict[str, Any]:
    """Truth (m >= 0 rows) and sky minima on the held-out test grid and on the fitting grid, in parallel."""
    plan = ctx.plan
    test_ts, test_tu, zen, tur = uniform_grid(plan.test_grid)
    fit_ts, fit_tu = fit.chebyshev_grid(plan.fit_grid)
    all_ts, all_tu = np.concatenate([test_ts, fit_ts]), np.concatenate([test_tu, fit_tu])
    settings = fit.FitSettings(bands=MAX_BANDS, grid=plan.fit_grid)
    start = time.perf_counter()
    with ProcessPoolExecutor(max(1, ctx.jobs)) as pool, ctx.bar(all_ts.size, "projecting the sky (grids)") as bar:

        def mapper(function: Callable, jobs: Iterable) -> Iterable:
            for result in pool.map(function, jobs, chunksize=8):
                bar.update(1)
                yield result

        coeffs, lmin = fit.project_points(all_ts, all_tu, settings, mapper)
    n = test_ts.size
    # distance of the test grid from the fitting nodes, in the Chebyshev variables of the shipped form
    tx, ty = poly.scale(test_ts, test_tu)
    fx, fy = poly.scale(fit_ts, fit_tu)
    gap = np.sqrt((tx[:, None] - fx[None]) ** 2 + (ty[:, None] - fy[None]) ** 2).min()
    return {
        "test": (test_ts, test_tu, coeffs[:n], lmin[:n]),
        "axes": (zen, tur),
        "fit": (fit_ts, fit_tu, coeffs[n:], lmin[n:]),
        "seconds": time.perf_counter() - start,
        "points": int(all_ts.size),
        "nearest_fit_node": float(gap),
    }


def sweep(ctx: Context) -> dict[str, Any]:
    """Section 3's fits: every (d_theta, d_tau), measured on the test grid and timed in the runtime."""
    plan = ctx.plan
    g = ctx.memo("grids", lambda: grids(ctx))
    fts, ftu, fc, fl = g["fit"]
    tts, ttu, tc, tl = g["test"]
    fd, td = fit.error_denominator(fl), fit.error_denominator(tl)
    repeats, number = plan.timing
    entries: list[dict[str, Any]] = []
    pairs = [(a, b) for a in plan.degrees_theta for b in plan.degrees_tau]
    with ctx.bar(len(pairs) + 1, "3. degrees swept") as bar:
        for degrees in pairs:
            per_band = np.tile(np.asarray(degrees, dtype=np.int64), (MAX_BANDS, 1))
            table, condition = fit.fit_table(fts, ftu, fc, fd, per_band)
            predicted = fit.evaluate_table(table, per_band, tts, ttu)
            model = SkySH(coefficient_file.SkyTable(table=table, degrees=per_band, metadata={"colourspace": "sRGB"}))
            entry: dict[str, Any] = {"degrees": degrees, "terms": poly.n_terms(degrees), "condition": condition,
                                     "predicted": predicted, "table": table, "model": model, "bands": {}}
            for bands in range(1, MAX_BANDS + 1):
                m = fit.error_measures(predicted, tc, td, bands)
                entry["bands"][bands] = {
                    "e_mean": float(m["e_mean"].max()), "e_max": float(m["e_max"].max()), "dc": float(m["dc"].max()),
                    "seconds": math.inf, "bytes": poly.n_terms(degrees) * bands * (bands + 1) // 2 * 3 * 8,
                }
            entries.append(entry)
            bar.update(1)
        seed_degrees = np.tile(np.asarray(SEED_DEGREES, dtype=np.int64), (MAX_BANDS, 1))
        seed_table, seed_condition = fit.fit_table(fts, ftu, fc, fd, seed_degrees, variant=fit.VARIANTS["plain (seed)"])
        seed_predicted = fit.evaluate_table(seed_table, seed_degrees, tts, ttu, variant=fit.VARIANTS["plain (seed)"])
        seed_form = {"condition": seed_condition, "table": seed_table, "predicted": seed_predicted, "bands": {}}
        for bands in range(1, MAX_BANDS + 1):
            m = fit.error_measures(seed_predicted, tc, td, bands)
            seed_form["bands"][bands] = {"e_mean": float(m["e_mean"].max()), "e_max": float(m["e_max"].max()),
                                         "dc": float(m["dc"].max())}
        bar.update(1)
    # Cost per call: rounds over every (degrees, bands), keeping each one's best round, so that a burst
    # of load on the shared machine spoils one round of every configuration rather than some configurations.
    with ctx.bar(repeats, "3. timing the runtime") as bar:
        for _ in range(repeats):
            for entry in entries:
                model = entry["model"]
                for bands in range(1, MAX_BANDS + 1):
                    seconds = best_time(lambda: model.coefficients(0.7, 3.3, 0.4, bands=bands), 1, number)
                    entry["bands"][bands]["seconds"] = min(entry["bands"][bands]["seconds"], seconds)
            bar.update(1)
    return {"entries": entries, "seed_form": seed_form}


# --------------------------------------------------------------------------- #
# Section 1
# --------------------------------------------------------------------------- #
def section_projection(ctx: Context) -> Section:
    s = Section(1)
    plan = ctx.plan
    study = ctx.memo("projection", lambda: projection_study(ctx))
    methods = [*RANDOM_METHODS, SUN_QUADRATURE, PLAIN_QUADRATURE]
    s.text(
        f"The sky at {len(plan.s1_points)} (sun zenith, turbidity) points, projected to {MAX_BANDS} bands by each "
        "method of `skysh.preetham.sky_sh` (`mc`, `stratified`, `qmc`: uniform directions over the upper "
        "hemisphere through `skysh.sh.project`; the default sun-adapted Gauss rule of `sky_quadrature_rule`) and "
        "by `skysh.sh.project(..., 'quadrature', hemisphere=True)` (a plain product Gauss rule, not adapted to the "
        f"sun). Truth: `sky_sh(n=4 * {plan.truth_nodes}^2)`, the sun-adapted rule with {plan.truth_nodes} nodes "
        "per panel. Error: E_mean of Habel eq. 3 over all 49 coefficients (the random methods also err in the "
        "m < 0 ones), worst channel, with L_min = `fit.error_denominator(sky_minimum)`. Random methods: "
        f"{plan.s1_seeds} seeds per sample count; lines are medians over seeds and points, bands the 10-90% "
        "range. Wall time: one call on one core, including the sky's evaluation (the random methods' single "
        "call; quadrature best of 3, so `sh.project`'s cached basis is reused as a renderer would).")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    for method in methods:
        cv = curves(study, method)
        style = METHOD_STYLE[method]
        for ax, x in ((axes[0], cv["samples"]), (axes[1], 1e3 * cv["seconds"])):
            ax.plot(x, cv["median"], label=method, linestyle="-", markersize=5, **style)
            ax.fill_between(x, cv["low"], cv["high"], color=style["color"], alpha=0.15, linewidth=0)
    rt = max(p["runtime_e7"] for p in study["points"])
    for ax in axes:
        ax.axhline(rt, color="black", linestyle="--", linewidth=1, label=f"shipped runtime, worst of these points ({pct(rt, 2)})")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("E_mean, 7 bands (fraction of L_min)")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_xlabel("directions evaluated per projection (count)")
    axes[1].set_xlabel("wall time per projection (ms, one core)")
    axes[0].set_title("Projection error against sample count")
    axes[1].set_title("Projection error against wall time")
    axes[0].legend(fontsize=8, loc="lower left")
    s.figure(ctx.save(fig, "s01_projection.png"), "Projection error of the sky (7 bands) against sample count and wall time, per method")
    rows = []
    for method in methods:
        cv = curves(study, method)
        cv3 = curves(study, method, key="e3")
        for i in range(cv["samples"].size):
            rows.append([method, f"{cv['samples'][i]:.0f}", ms(cv["seconds"][i]), pct(cv["median"][i]),
                         pct(cv["worst"][i]), pct(cv3["median"][i])])
    s.table(["method", "directions", "median time", "median E_mean (7 bands)", "worst E_mean (7 bands)",
             "median E_mean (3 bands)"], rows)
    prow = [[f"{math.degrees(p['sun_zenith']):.0f}", f"{p['turbidity']:g}", f"{p['default_samples']}",
             ms(p["default_s"]), pct(p["default_e7"]), sig(p["default_dc"]), pct(p["runtime_e7"]), pct(p["runtime_e3"])]
            for p in study["points"]]
    s.text("The default `sky_sh` (64 nodes per panel) against the truth, and the shipped runtime at the same points:")
    s.table(["sun zenith (deg)", "turbidity", "default directions", "default time", "default E_mean (7 bands)",
             "default DC error (relative)", "runtime E_mean (7 bands)", "runtime E_mean (3 bands)"], prow)
    worst_default = max(p["default_dc"] for p in study["points"])
    orders = []
    for method in methods:
        cv = curves(study, method)
        slope = np.polyfit(np.log(cv["samples"]), np.log(cv["median"]), 1)[0]
        orders.append(f"{method} n^{slope:.2f}")
    s.text(f"The default quadrature against the denser rule: worst DC error {sig(worst_default)} (relative), worst "
           f"E_mean {pct(max(p['default_e7'] for p in study['points']))}. Observed convergence of the median E_mean "
           f"(least-squares slope in log-log over the sample counts tried): {', '.join(orders)}. Section 3 compares "
           "the time each method needs to reach the runtime's accuracy.")
    ctx.note("Default reference projection (sky_sh) against a denser rule, worst DC error", sig(worst_default), "converged (sec. 3.1)")
    return s


# --------------------------------------------------------------------------- #
# Section 2
# --------------------------------------------------------------------------- #
def shipped_errors(ctx: Context) -> dict[str, Any]:
    """The shipped runtime against the truth on the test grid, per band count."""
    g = ctx.memo("grids", lambda: grids(ctx))
    ts, tu, truth, lmin = g["test"]
    denom = fit.error_denominator(lmin)
    predicted = ctx.sky.coefficients(ts, tu, 0.0, bands=MAX_BANDS, gibbs=False)[:, HALF_ROWS, :]
    by = {b: fit.error_measures(predicted, truth, denom, b) for b in range(1, MAX_BANDS + 1)}
    floored = (lmin[:, :3] < fit.LMIN_FLOOR * lmin[:, 3:4]).any(axis=1)
    return {"by": by, "floored": floored, "predicted": predicted}


def section_fit(ctx: Context) -> Section:
    s = Section(2)
    plan = ctx.plan
    g = ctx.memo("grids", lambda: grids(ctx))
    sw = ctx.memo("sweep", lambda: sweep(ctx))
    errs = ctx.memo("shipped", lambda: shipped_errors(ctx))
    ts, tu = g["test"][:2]
    zen, tur = g["axes"]
    shape = plan.test_grid
    by, floored = errs["by"], errs["floored"]
    meta = ctx.sky.metadata
    s.text(
        f"The shipped file (`SkySH.load()`: degrees {ctx.sky.table.max_degrees}, grid {meta['grid']['shape']}, "
        f"form: {meta['basis'].split(';')[0]}) against `sky_sh` (the converged quadrature) on a held-out "
        f"{shape[0]} x {shape[1]} uniform grid of sun zenith [0, 90] deg x turbidity [2.5, 6], edges and corners "
        f"included ({ts.size} points, projected in {sig(g['seconds'])} s with {ctx.jobs} processes; the nearest "
        f"fitting node is {sig(g['nearest_fit_node'])} away in the Chebyshev variables, so none is a fitting "
        "node). Errors: `fit.error_measures` (Habel eqs. 2 and 3, worst channel) with "
        "`fit.error_denominator(sky_minimum)`, no Gibbs filter, sun at azimuth 0 (E_mean is invariant under "
        f"the rotation). Cells marked x had a channel's L_min floored at {fit.LMIN_FLOOR:g} x the darkest "
        f"luminance (the sky leaves the sRGB gamut): {int(floored.sum())} of {ts.size}.")
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5), constrained_layout=True)
    panels = [
        (by[3]["e_mean"], "E_mean, 3 bands (eq. 3)", "E_mean (% of L_min)"),
        (by[MAX_BANDS]["e_mean"], "E_mean, 7 bands (eq. 3)", "E_mean (% of L_min)"),
        (by[MAX_BANDS]["e_max"], "E_max, 7 bands (eq. 2)", "E_max (% of L_min)"),
        (by[MAX_BANDS]["dc"], "DC coefficient error", "relative DC error (%)"),
    ]
    for ax, (values, title, label) in zip(axes.ravel(), panels):
        v = 100.0 * np.maximum(values, 1e-12).reshape(shape)
        heatmap(ax, zen, tur, v, f"Shipped fit: {title}", label, norm=LogNorm(vmin=v.min(), vmax=v.max()),
                marks=floored.reshape(shape))
    s.figure(ctx.save(fig, "s02_heatmaps.png"), "Fit error of the shipped file over (sun zenith, turbidity), held-out grid")
    seed_form = sw["seed_form"]["bands"]
    bands = np.arange(1, MAX_BANDS + 1)
    fig, ax = plt.subplots(figsize=(12, 5.2), constrained_layout=True)
    ax.plot(bands, [100 * by[b]["e_mean"].max() for b in bands], "o-", color="tab:blue", label="shipped: worst E_mean")
    ax.plot(bands, [100 * by[b]["e_mean"].mean() for b in bands], "o:", color="tab:blue", label="shipped: mean E_mean")
    ax.plot(bands, [100 * by[b]["e_max"].max() for b in bands], "s-", color="tab:green", label="shipped: worst E_max")
    ax.plot(bands, [100 * by[b]["dc"].max() for b in bands], "^-", color="tab:gray", label="shipped: worst DC error")
    ax.plot(bands, [100 * seed_form[b]["e_mean"] for b in bands], "o-", color="tab:red",
            label=f"seed's form {SEED_DEGREES}, refit here: worst E_mean")
    ax.plot(bands, [100 * seed_form[b]["e_max"] for b in bands], "s--", color="tab:red",
            label=f"seed's form {SEED_DEGREES}, refit here: worst E_max")
    ax.plot([7], [100 * SEED_E_MEAN_7], "*", color="black", markersize=14, label="seed (published): E_mean < 1.5% at 7 bands")
    ax.plot([1, 5], [100 * SEED_E_MEAN_5] * 2, "-", color="black", linewidth=3, alpha=0.6,
            label="seed (published): E_mean < 0.005% up to 5 bands")
    ax.set_yscale("log")
    ax.set_xlabel("SH bands N (count)")
    ax.set_ylabel("error (% of L_min, worst channel)")
    ax.set_title("Fit error by number of bands: shipped file, the seed's form refit, the seed's published figures")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    s.figure(ctx.save(fig, "s02_by_bands.png"), "Worst and mean error by bands (held-out grid) beside the seed's figures")
    rows = []
    for b in bands:
        worst = int(np.argmax(by[b]["e_mean"]))
        rows.append([b, pct(by[b]["e_mean"].max()), pct(by[b]["e_mean"].mean()), pct(by[b]["e_max"].max()),
                     pct(by[b]["dc"].max()), f"({math.degrees(ts[worst]):.1f} deg, {tu[worst]:.2f})",
                     pct(seed_form[b]["e_mean"]), pct(seed_form[b]["e_max"])])
    s.table(["bands", "worst E_mean", "mean E_mean", "worst E_max", "worst DC error", "worst at (zenith, T)",
             f"seed's form {SEED_DEGREES}: worst E_mean", "seed's form: worst E_max"], rows)
    stored = meta["errors"]["by_bands"]
    s.text(
        "Seed (Habel 2008, sec. 3.2 and Fig. 3): E_mean below 1.5% at 7 bands and below 0.005% up to 5 bands at "
        f"degree {SEED_DEGREES}. The seed's form refit here (plain polynomial in (theta, T), same grid, same "
        f"weights, `fit.VARIANTS['plain (seed)']`) measures {pct(seed_form[7]['e_mean'])} at 7 bands (seed: < 1.5%) "
        f"and {pct(seed_form[5]['e_mean'])} at 5 (seed: < 0.005%); the shipped form {pct(by[7]['e_mean'].max())} and "
        f"{pct(by[5]['e_mean'].max())}. For comparison, the file's own metadata (256 random held-out points and the corners) "
        f"reports a worst E_mean of {pct(stored['7']['e_mean_worst'])} at 7 bands and "
        f"{pct(stored['3']['e_mean_worst'])} at 3.")
    ctx.note("Worst E_mean, 7 bands (held-out grid)", pct(by[MAX_BANDS]["e_mean"].max()), "< 1.5%")
    ctx.note("Worst E_mean, 5 bands", pct(by[5]["e_mean"].max()), "< 0.005%")
    ctx.note("Worst E_mean, 3 bands", pct(by[3]["e_mean"].max()), "")
    ctx.note("Worst E_max, 7 bands", pct(by[MAX_BANDS]["e_max"].max()), "(Fig. 3, not quoted)")
    ctx.note("Worst DC error (relative)", sig(by[MAX_BANDS]["dc"].max()), "")
    ctx.note(f"Seed's form {SEED_DEGREES} refit here: worst E_mean 7 / 5 bands",
             f"{pct(seed_form[7]['e_mean'])} / {pct(seed_form[5]['e_mean'])}", "< 1.5% / < 0.005%")
    return s


# --------------------------------------------------------------------------- #
# Section 3
# --------------------------------------------------------------------------- #
def section_speed(ctx: Context) -> Section:
    s = Section(3)
    plan = ctx.plan
    sw = ctx.memo("sweep", lambda: sweep(ctx))
    study = ctx.memo("projection", lambda: projection_study(ctx))
    entries = sw["entries"]
    shipped_degrees = ctx.sky.table.max_degrees
    s.text(
        f"Tables fitted in-process (`fit.fit_table`, shipped form) on the {plan.fit_grid[0]} x {plan.fit_grid[1]} "
        f"Chebyshev grid projected once, for d_theta in {list(plan.degrees_theta)} and d_tau in "
        f"{list(plan.degrees_tau)}; errors on the held-out grid of section 2. Cost per call: a `SkySH` built from "
        "an in-memory `coefficient_file.SkyTable` of those degrees, `coefficients(0.7, 3.3, 0.4, bands=N)` "
        f"(scalar fast path, Gibbs filter and rotation included), best of {plan.timing[0]} x {plan.timing[1]} "
        "calls on a shared machine. Table size: float64, the m >= 0 rows that the file stores "
        "(n_terms x N (N + 1) / 2 x 3 x 8 bytes).")
    shipped_entry = next((e for e in entries if e["degrees"] == tuple(shipped_degrees)), None)
    if shipped_entry is not None and plan.fit_grid == tuple(ctx.sky.metadata["grid"]["shape"]):
        ref = np.asarray(ctx.sky.table.table)
        diff = np.abs(shipped_entry["table"] - ref).max() / np.abs(ref).max()
        s.text(f"Reproducibility: the refit at {shipped_degrees} on the shipped grid differs from the shipped table "
               f"by {sig(diff)} of its largest entry.")
        ctx.note("Refit on the shipped grid against the shipped table (max relative difference)", sig(diff), "")
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
    colours = {3: "tab:blue", MAX_BANDS: "tab:red"}
    for bands in (3, MAX_BANDS):
        cost = np.array([1e6 * e["bands"][bands]["seconds"] for e in entries])
        size = np.array([e["bands"][bands]["bytes"] / 1000 for e in entries])
        err = np.array([100 * e["bands"][bands]["e_mean"] for e in entries])
        for ax, x in ((axes[0], cost), (axes[1], size)):
            ax.scatter(x, err, s=14, color=colours[bands], alpha=0.45, label=f"{bands} bands: swept degrees")
            front = pareto(x, err)
            ax.plot(x[front], err[front], "-", color=colours[bands], linewidth=1.5, label=f"{bands} bands: Pareto front")
            if shipped_entry is not None:
                i = entries.index(shipped_entry)
                ax.plot(x[i], err[i], "*", color=colours[bands], markersize=16, markeredgecolor="black",
                        label=f"{bands} bands: shipped {tuple(shipped_degrees)}")
            seed_err = 100 * sw["seed_form"]["bands"][bands]["e_mean"]
            seed_entry = next((e for e in entries if e["degrees"] == SEED_DEGREES), None)
            if seed_entry is not None:
                j = entries.index(seed_entry)
                ax.plot(x[j], seed_err, "P", color=colours[bands], markersize=11, markeredgecolor="black",
                        label=f"{bands} bands: seed's form {SEED_DEGREES}")
    for ax in axes:
        ax.set_yscale("log")
        ax.set_ylabel("worst E_mean (% of L_min)")
        ax.grid(True, which="major", alpha=0.3)
    axes[1].set_xscale("log")
    axes[0].set_xlabel("runtime cost per call (us, Python scalar path)")
    axes[1].set_xlabel("table size (KB = 1000 bytes, float64, m >= 0 rows)")
    axes[0].set_title("Error against cost per call")
    axes[1].set_title("Error against table size")
    axes[1].plot([SEED_SIZE_KB_7], [100 * SEED_E_MEAN_7], "*", color="black", markersize=14,
                 label="seed (published): 131 KB, E_mean < 1.5% (7 bands)")
    axes[1].legend(fontsize=7, loc="lower left")
    s.figure(ctx.save(fig, "s03_pareto.png"), "Speed and size against accuracy over the swept degrees (3 and 7 bands)")
    # error over the degree grid
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    for ax, bands in zip(axes, (3, MAX_BANDS)):
        grid_err = np.array([[100 * next(e for e in entries if e["degrees"] == (a, b))["bands"][bands]["e_mean"]
                              for b in plan.degrees_tau] for a in plan.degrees_theta])
        mesh = ax.pcolormesh(np.arange(len(plan.degrees_tau) + 1), np.arange(len(plan.degrees_theta) + 1), grid_err,
                             norm=LogNorm(vmin=grid_err.min(), vmax=grid_err.max()), cmap="viridis")
        plt.colorbar(mesh, ax=ax, label="worst E_mean (% of L_min)")
        for i in range(len(plan.degrees_theta)):
            for j in range(len(plan.degrees_tau)):
                ax.text(j + 0.5, i + 0.5, sig(grid_err[i, j], 2), ha="center", va="center", fontsize=7, color="white")
        ax.set_xticks(np.arange(len(plan.degrees_tau)) + 0.5, [str(d) for d in plan.degrees_tau])
        ax.set_yticks(np.arange(len(plan.degrees_theta)) + 0.5, [str(d) for d in plan.degrees_theta])
        ax.set_xlabel("d_tau, degree in log turbidity (count)")
        ax.set_ylabel("d_theta, degree in sun zenith (count)")
        ax.set_title(f"Worst E_mean by degrees, {bands} bands")
    s.figure(ctx.save(fig, "s03_degrees.png"), "Worst held-out E_mean over the swept degrees")
    rows = []
    for bands in (3, MAX_BANDS):
        cost = np.array([e["bands"][bands]["seconds"] for e in entries])
        err = np.array([e["bands"][bands]["e_mean"] for e in entries])
        for i in pareto(cost, err):
            e = entries[i]
            rows.append([bands, str(e["degrees"]), e["terms"], us(e["bands"][bands]["seconds"]),
                         sig(e["bands"][bands]["bytes"] / 1000) + " KB", pct(e["bands"][bands]["e_mean"]),
                         pct(e["bands"][bands]["e_max"]), sig(e["condition"])])
    s.text("The Pareto front (cost per call against worst E_mean) for 3 and 7 bands:")
    s.table(["bands", "degrees", "terms", "cost per call", "table size", "worst E_mean", "worst E_max",
             "condition (weighted)"], rows)
    costs = np.array([e["bands"][MAX_BANDS]["seconds"] for e in entries])
    terms = np.array([e["terms"] for e in entries])
    small, large = entries[int(np.argmin(terms))], entries[int(np.argmax(terms))]
    s.text(f"Cost per call at 7 bands: {us(costs.min())} to {us(costs.max())} over the sweep; "
           f"{us(small['bands'][MAX_BANDS]['seconds'])} for the fewest terms {small['degrees']} against "
           f"{us(large['bands'][MAX_BANDS]['seconds'])} for the most {large['degrees']} "
           f"({sig(large['terms'] / small['terms'])} times the terms): the Python scalar path's fixed cost of numpy "
           "calls dominates the arithmetic, so the degrees trade accuracy against table size far more than against time.")
    if shipped_entry is not None:
        sb = shipped_entry["bands"]
        ctx.note("Runtime cost per call, 3 / 7 bands (shipped degrees)", f"{us(sb[3]['seconds'])} / {us(sb[MAX_BANDS]['seconds'])}",
                 "80 us (7 bands, P4 3.2 GHz, C)")
        ctx.note("Table size, 7 / 4 bands (float64, m >= 0 rows)",
                 f"{sig(sb[MAX_BANDS]['bytes'] / 1000)} KB / {sig(sb[4]['bytes'] / 1000)} KB", "131 KB / 28 KB")
    # the runtime against projecting per frame at equal accuracy
    rows, bars = [], []
    for bands, key in ((MAX_BANDS, "e7"), (3, "e3")):
        target_key = "runtime_e7" if bands == MAX_BANDS else "runtime_e3"
        time_key = "runtime_s7" if bands == MAX_BANDS else "runtime_s3"
        runtime_s = max(p[time_key] for p in study["points"])
        bars.append((f"runtime, {bands} bands", runtime_s, False, "black"))
        for method in [*RANDOM_METHODS, SUN_QUADRATURE, PLAIN_QUADRATURE]:
            worst = (0.0, 0.0, False)
            for p in study["points"]:
                cv = curves(study, method, point=p["point"], key=key)
                target = max(p[target_key], 1e-12)
                t, n, extrapolated = cost_to_reach(cv["seconds"], cv["median"], cv["samples"], target)
                if t > worst[0]:
                    worst = (t, n, extrapolated)
            t, n, extrapolated = worst
            rows.append([bands, method, ("~" if extrapolated else "") + (ms(t) if math.isfinite(t) else "never"),
                         ("~" if extrapolated else "") + (sig(n) if math.isfinite(n) else "-"),
                         sig(t / runtime_s) + "x" if math.isfinite(t) else "-", "extrapolated" if extrapolated else "measured"])
            bars.append((f"{method}, {bands} bands", t, extrapolated, METHOD_STYLE[method]["color"]))
    s.text("Projecting the sky every frame instead, at the runtime's own accuracy at each section-1 point "
           "(E_mean of the runtime against the dense truth; the time a method needs to reach it, by log-log "
           "interpolation of its median convergence curve, worst point; '~' marks an extrapolation along the "
           "curve's last slope because no sample count tried was enough):")
    s.table(["bands", "method", "time per frame at equal accuracy", "directions needed", "ratio to the runtime",
             "how"], rows)
    fig, ax = plt.subplots(figsize=(10, 5.5), constrained_layout=True)
    labels = [b[0] for b in bars]
    values = [b[1] * 1e3 if math.isfinite(b[1]) else np.nan for b in bars]
    ax.barh(labels, values, color=[b[3] for b in bars], hatch=None)
    for k, b in enumerate(bars):
        if b[2]:
            ax.barh([labels[k]], [values[k]], color="none", edgecolor="black", hatch="//")
    for k, v in enumerate(values):
        if np.isfinite(v):
            ax.text(v * 1.15, k, ms(v / 1e3), va="center", fontsize=8)
    ax.axvline(1000.0 / 60.0, color="gray", linestyle="--", linewidth=1, label="a whole 60 Hz frame (16.7 ms)")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_xscale("log")
    ax.set_xlim(right=max(v for v in values if np.isfinite(v)) * 30)
    ax.invert_yaxis()
    ax.set_xlabel("time per frame (ms, one core); hatched = extrapolated")
    ax.set_title("Sky SH per frame: the fitted runtime against projecting at the same accuracy")
    ax.grid(True, axis="x", which="major", alpha=0.3)
    s.figure(ctx.save(fig, "s03_per_frame.png"), "Time per frame of the runtime and of each projection method at equal accuracy")
    best = min((r for r in rows if r[0] == 3 and r[4] != "-"), key=lambda r: float(r[4][:-1]), default=None)
    if best is not None:
        ctx.note("Cheapest per-frame projection at the runtime's 3-band accuracy", f"{best[1]}: {best[2]} ({best[4]} the runtime)", "")
    return s


# --------------------------------------------------------------------------- #
# Section 4
# --------------------------------------------------------------------------- #
def section_gibbs(ctx: Context) -> Section:
    s = Section(4)
    plan, sky = ctx.plan, ctx.sky
    dirs, weights = sh.quadrature_rule(48)
    upper, lower = dirs[:, 2] > 0.0, dirs[:, 2] < 0.0
    y_row = luminance_row()
    rows, worst = [], {False: 0.0, True: 0.0}
    with ctx.bar(len(plan.gibbs_suns), "4. Gibbs filter") as bar:
        for ts, tu in plan.gibbs_suns:
            truth_y = preetham.luminance(dirs, ts, 0.0, tu)
            mean_up = float(np.sum(weights[upper] * truth_y[upper]) / np.sum(weights[upper]))
            for bands in (3, 5, MAX_BANDS):
                cells = [f"{math.degrees(ts):.0f}", f"{tu:g}", bands]
                for gibbs in (False, True):
                    rec = sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=bands, gibbs=gibbs), dirs) @ y_row
                    below = float(rec[lower].min()) / mean_up
                    over = float(np.max(rec[upper] - truth_y[upper])) / mean_up
                    rms = math.sqrt(float(np.sum(weights[upper] * (rec[upper] - truth_y[upper]) ** 2) / np.sum(weights[upper]))) / mean_up
                    cells += [pct(below), pct(over), pct(rms)]
                    if bands == MAX_BANDS:
                        worst[gibbs] = min(worst[gibbs], below)
                rows.append(cells)
            bar.update(1)
    s.text("Luminance of the reconstructed sky (`SkySH.coefficients(..., gibbs=False/True)`, azimuth 0) on a "
           "4,608-direction Gauss sphere, relative to the true sky's mean luminance over the upper hemisphere: "
           "the most negative value below the horizon (ringing; the true sky is 0 there), the largest overshoot "
           "above the truth in the upper hemisphere, and the RMS error over the upper hemisphere (the filter's "
           "smoothing cost).")
    s.table(["sun zenith (deg)", "T", "bands", "min below horizon, no filter", "overshoot above, no filter",
             "RMS above, no filter", "min below horizon, filter", "overshoot above, filter", "RMS above, filter"], rows)
    ctx.note("Gibbs filter: most negative luminance below the horizon, 7 bands, without / with (of the mean sky)",
             f"{pct(worst[False])} / {pct(worst[True])}", "strongly reduced (Fig. 4)")
    # profiles along the sun's vertical plane
    ts, tu = plan.gibbs_suns[-1]
    theta = np.linspace(0.0, math.pi, 721)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True, sharey=True)
    for ax, phi, side in ((axes[0], 0.0, "towards the sun"), (axes[1], math.pi, "away from the sun")):
        d = np.stack([np.sin(theta) * math.cos(phi), np.sin(theta) * math.sin(phi), np.cos(theta)], axis=-1)
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        truth_y = preetham.luminance(d, ts, 0.0, tu)
        dense, dw = sh.quadrature_rule(48)
        mean_up = float(np.sum(dw[dense[:, 2] > 0] * preetham.luminance(dense[dense[:, 2] > 0], ts, 0.0, tu)) / np.sum(dw[dense[:, 2] > 0]))
        ax.plot(np.degrees(theta), truth_y / mean_up, color="black", linewidth=2, label="Preetham sky")
        for bands, colour in ((3, "tab:blue"), (MAX_BANDS, "tab:red")):
            for gibbs, style in ((False, ":"), (True, "-")):
                rec = sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=bands, gibbs=gibbs), d) @ luminance_row()
                ax.plot(np.degrees(theta), rec / mean_up, style, color=colour,
                        label=f"{bands} bands, {'Gibbs filter' if gibbs else 'no filter'}")
        ax.axvline(90.0, color="gray", linewidth=1)
        ax.axhline(0.0, color="gray", linewidth=0.8)
        ax.set_yscale("symlog", linthresh=0.05)
        ax.set_xlabel("zenith angle of the view direction (deg); horizon at 90")
        ax.set_title(f"Luminance in the sun's vertical plane, {side}")
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("luminance / mean sky luminance (symlog)")
    axes[0].legend(fontsize=8, loc="lower left")
    fig.suptitle(f"Ringing with and without the Gibbs filter (sun zenith {math.degrees(ts):.0f} deg, T = {tu:g})")
    s.figure(ctx.save(fig, "s04_profiles.png"), "Reconstructed luminance along the sun's vertical plane, with and without the filter")
    # pictures: tone-mapped (skysh.render) and signed luminance
    width = plan.picture_width
    ll = render.latlong_dirs(width)
    dense, dw = sh.quadrature_rule(48)
    up = dense[:, 2] > 0
    mean_up = float(np.sum(dw[up] * preetham.luminance(dense[up], ts, 0.0, tu)) / np.sum(dw[up]))
    images = [render.render_image(sky, ts, tu, 0.0, bands=MAX_BANDS, width=width, gibbs=g) for g in (False, True)]
    fig = plt.figure(figsize=(12, 9.5), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, height_ratios=[images[0].shape[0] / images[0].shape[1] * 2, images[0].shape[0] / images[0].shape[1] * 2, 1.0])
    for row, (gibbs, image) in enumerate(zip((False, True), images)):
        ax = fig.add_subplot(grid[row, :])
        ax.imshow(image, interpolation="nearest")
        ax.set_axis_off()
        ax.set_title(f"7 bands, {'Gibbs filter' if gibbs else 'no filter'}: sky, reconstruction, irradiance (skysh.render, tone-mapped)")
    for col, gibbs in enumerate((False, True)):
        ax = fig.add_subplot(grid[2, col])
        rec = sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=MAX_BANDS, gibbs=gibbs), ll) @ luminance_row()
        im = ax.imshow(rec / mean_up, cmap="RdBu_r", norm=SymLogNorm(linthresh=0.02, vmin=-3, vmax=3),
                       extent=(-180, 180, 180, 0), aspect="auto", interpolation="nearest")
        ax.axhline(90.0, color="black", linewidth=0.8)
        ax.set_xlabel("azimuth (deg, from +X towards +Y)")
        ax.set_ylabel("zenith angle (deg)")
        ax.set_title(f"signed luminance / mean, {'Gibbs filter' if gibbs else 'no filter'} (blue = negative)")
        plt.colorbar(im, ax=ax, label="luminance / mean sky luminance")
    fig.suptitle(f"The 7-band reconstruction with and without the Gibbs filter (sun zenith {math.degrees(ts):.0f} deg, T = {tu:g})")
    s.figure(ctx.save(fig, "s04_pictures.png"), "Reconstructed sky with and without the Gibbs filter: tone-mapped and signed")
    s.text(f"At 7 bands the most negative luminance below the horizon over these suns is {pct(worst[False])} of the "
           f"mean sky without the filter (Habel eq. 5, zonal rows times sinc(pi l / N)) and {pct(worst[True])} with "
           "it; the RMS columns show what the smoothing costs above the horizon.")
    return s


# --------------------------------------------------------------------------- #
# Section 5
# --------------------------------------------------------------------------- #
class Missing(Exception):
    """A package function a sub-study needs is not there (yet)."""


def need(module: Any, *names: str) -> list[Any]:
    """The named attributes of ``module``, or :class:`Missing` naming the absent ones."""
    absent = [n for n in names if not hasattr(module, n)]
    if absent:
        raise Missing(f"{module.__name__} lacks {', '.join(absent)}")
    return [getattr(module, n) for n in names]


def part(s: Section, title: str, body: Callable[[], None]) -> None:
    """Run a sub-study; a missing or incompatible package function is reported in the section, not raised."""
    try:
        body()
    except (Missing, ImportError, NotImplementedError, TypeError, AttributeError) as error:
        s.text(f"*{title}: not measured, because the package does not provide it yet: "
               f"{type(error).__name__}: {error}.*")


def section_dering(ctx: Context) -> Section:
    s = Section(5)
    plan, sky = ctx.plan, ctx.sky
    try:
        from skysh import dering
    except ImportError as error:
        s.text(f"*skysh.dering cannot be imported ({error}); nothing measured.*")
        return s
    ts, tu, zen, tur = uniform_grid(plan.dering_grid)
    shape = plan.dering_grid
    c3 = {g: sky.coefficients(ts, tu, 0.0, bands=3, gibbs=g) for g in (False, True)}
    s.text(f"3-band sky radiance SH from `SkySH.coefficients` on a {shape[0]} x {shape[1]} grid of the domain "
           "(azimuth 0; the windows do not depend on it), with and without the Gibbs filter, windowed by "
           "`skysh.dering.dering` (default method: Table rows with the seed's bound for 3 bands, `exact_min` "
           "above).")

    def windows() -> None:
        (dering_fn,) = need(dering, "dering")
        configs = [("irradiance", False, 3, c3[False]), ("irradiance", True, 3, c3[True]), ("radiance", True, 3, c3[True])]
        idx7 = np.linspace(0, ts.size - 1, min(plan.dering_seven, ts.size)).round().astype(int)
        c7 = sky.coefficients(ts[idx7], tu[idx7], 0.0, bands=MAX_BANDS, gibbs=False)
        results = {}
        rows = []
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            for target, gibbs, bands, c in configs:
                out, scales, failed = dering_fn(c, target=target, return_failed=True)
                results[(target, gibbs)] = (out, scales)
                kernel = sh.irradiance if target == "irradiance" else (lambda x: x)
                before = dering.exact_min(kernel(c)) / (kernel(c)[:, 0, :] * 0.5 / math.sqrt(math.pi))
                after = dering.exact_min(kernel(out)) / (kernel(out)[:, 0, :] * 0.5 / math.sqrt(math.pi))
                rows.append([target, "on" if gibbs else "off", bands, f"{int((scales[:, 1:] < 1).any(axis=1).sum())} / {c.shape[0]}",
                             sig(scales[:, -1].min()), pct(before.min()), int((before < 0).any(axis=1).sum()),
                             pct(after.min()), int((after < -1e-12).any(axis=1).sum()), int(failed.sum())])
            out7, scales7, failed7 = dering_fn(c7, target="irradiance", return_failed=True)
            irr7 = sh.irradiance(c7)
            before7 = dering.exact_min(irr7) / (irr7[:, 0, :] * 0.5 / math.sqrt(math.pi))
            after7 = dering.exact_min(sh.irradiance(out7)) / (sh.irradiance(out7)[:, 0, :] * 0.5 / math.sqrt(math.pi))
            rows.append(["irradiance", "off", MAX_BANDS, f"{int((scales7[:, 1:] < 1).any(axis=1).sum())} / {c7.shape[0]}",
                         sig(scales7[:, -1].min()), pct(before7.min()), int((before7 < 0).any(axis=1).sum()),
                         pct(after7.min()), int((after7 < -1e-12).any(axis=1).sum()), int(failed7.sum())])
        s.text("Windows chosen and the minimum (by `dering.exact_min`) of the target function relative to its mean, "
               "before and after:")
        s.table(["target", "Gibbs filter", "bands", "skies windowed", "smallest last-band scale",
                 "min before (of mean)", "skies negative before", "min after (of mean)", "skies negative after",
                 "failed (DeringWarning)"], rows)
        if caught:
            s.text(f"Warnings during deringing: {len(caught)} ({', '.join(sorted({type(w.message).__name__ for w in caught}))}).")
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), constrained_layout=True)
        for ax, (target, gibbs), title in zip(
                axes, [("irradiance", False), ("irradiance", True), ("radiance", True)],
                ["irradiance target, no Gibbs filter", "irradiance target, Gibbs filter", "radiance target, Gibbs filter"]):
            heatmap(ax, zen, tur, results[(target, gibbs)][1][:, 2].reshape(shape), f"Band-2 scale: {title}",
                    "window factor of band 2 (1 = none)", norm=Normalize(0.0, 1.0), cmap="magma")
        s.figure(ctx.save(fig, "s05_windows.png"), "Deringing windows chosen across the domain (3 bands, band-2 factor)")
        ctx.note("Deringing: skies whose 3-band irradiance needs a window, Gibbs filter off; on",
                 f"{rows[0][3]}; {rows[1][3]}", "")

    def bound() -> None:
        need(dering, "min_bound", "exact_min")
        sets = {"sky, Gibbs filter": c3[True], "sky, no Gibbs filter": c3[False]}
        rows = dering_experiment.bound_conservativeness(sets, np.random.default_rng(2017), plan.random_functions)
        s.text("Conservative against exact: `exact_min - min_bound` of the 3-band irradiance (units: the "
               "function's mean, or its largest coefficient for random functions); a violation is a bound above the "
               "exact minimum (`tools/dering_experiment.py`'s `bound_conservativeness`):")
        s.table(["set", "n", "violations", "mean gap", "95th percentile", "worst gap"],
                [[r["set"], r["n"], r["violations"], sig(r["mean"]), sig(r["p95"]), sig(r["worst"])] for r in rows])
        ctx.note("Deringing bound: violations (bound above the exact minimum)", str(sum(r["violations"] for r in rows)), "conservative")

    def detail() -> None:
        (dering_fn,) = need(dering, "dering")
        methods = need(dering, "DERING_METHODS")[0]
        idx7 = np.linspace(0, ts.size - 1, min(plan.dering_seven, ts.size)).round().astype(int)
        configs = [("3 bands, irradiance, no filter", "irradiance", c3[False]),
                   ("3 bands, radiance, filter", "radiance", c3[True]),
                   ("7 bands, irradiance, no filter", "irradiance",
                    sky.coefficients(ts[idx7], tu[idx7], 0.0, bands=MAX_BANDS, gibbs=False))]
        rows, points = [], []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for label, target, c in configs:
                kernel = sh.irradiance if target == "irradiance" else (lambda x: x)
                base = kernel(c)
                _, ref = dering_fn(c, target=target)
                needy = (ref[:, 1:] < 1).any(axis=1)
                if not needy.any():
                    continue
                one = c[np.flatnonzero(needy)[0]]
                for method in methods:
                    out, _ = dering_fn(c[needy], target=target, method=method)
                    change = np.sqrt(((kernel(out) - base[needy]) ** 2).sum(axis=-2) / (base[needy] ** 2).sum(axis=-2)).max(axis=-1)
                    number = 1 if (method == "exact" or c.shape[-2] > 9) else 10
                    seconds = best_time(lambda: dering_fn(one, target=target, method=method), 3, number)
                    rows.append([label, method, int(needy.sum()), pct(change.mean()), pct(change.max()), us(seconds)])
                    points.append((label, method, seconds, change.mean()))
        s.text("Detail kept against cost: relative L2 change of the target (irradiance or radiance) caused by the "
               "window, over the skies that need one, and the time of one call on one (K, 3) sky:")
        s.table(["skies", "method", "windowed", "mean L2 change", "worst L2 change", "time per call"], rows)
        fig, ax = plt.subplots(figsize=(9, 5), constrained_layout=True)
        markers = {"table": "o", "exact": "s", "sinc4": "^"}
        colours = {c[0]: col for c, col in zip(configs, ("tab:blue", "tab:orange", "tab:green"))}
        for label, method, seconds, change in points:
            ax.plot(1e6 * seconds, 100 * change, markers.get(method, "o"), color=colours[label], markersize=9,
                    label=f"{label}: {method}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time per call (us, one sky)")
        ax.set_ylabel("mean relative L2 change of the target (%)")
        ax.set_title("Deringing: detail removed against cost, per method")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        s.figure(ctx.save(fig, "s05_detail_cost.png"), "Deringing methods: detail removed against time per call")

    for title, body in (("Windows across the domain", windows), ("Bound against exact minimum", bound),
                        ("Detail against cost", detail)):
        part(s, title, body)
    return s


# --------------------------------------------------------------------------- #
# Section 6
# --------------------------------------------------------------------------- #
def section_quantization(ctx: Context) -> Section:
    s = Section(6)
    plan = ctx.plan
    result = quantize.table3_experiment(plan.table3_points, seed=0)
    s.text(f"`skysh.quantize.table3_experiment({plan.table3_points})`: the seed's Table 3 (Wiederien and Sloan "
           "2024) on 3-band sky SH over the domain (sun zenith, azimuth, turbidity by a scrambled Halton sequence), "
           "8-bit codec, prior bound sqrt(5) against the tight bound sqrt(15)/2, errors relative to each probe's "
           "mean (`tools/quantize_experiment.py`'s table layout).")
    s.raw(quantize_experiment.table3_markdown(result).splitlines())
    ts, az, tu = quantize.sample_sky_parameters(plan.table3_points, 0)
    coeffs, source = quantize.sky_coefficients(ts, tu, az)
    by_bits = {bits: quantize.table3_errors(coeffs, bits=bits) for bits in plan.bits}
    fig, axes = plt.subplots(1, 2, figsize=(14, 4.8), constrained_layout=True, gridspec_kw={"width_ratios": [1.5, 1.0]})
    labels, prior, tight = [], [], []
    for row in result["rows"]:
        if row["bound"] == "prior":
            twin = next(r for r in result["rows"] if r["bound"] == "tight" and r["quantity"] == row["quantity"] and r["sqrt"] == row["sqrt"])
            for metric in ("L1", "L2"):
                labels.append(f"{row['quantity']}\n{'sqrt, ' if row['sqrt'] else ''}{metric}")
                prior.append(row[metric])
                tight.append(twin[metric])
    x = np.arange(len(labels))
    axes[0].bar(x - 0.2, prior, 0.4, label="prior bound sqrt(5)", color="tab:gray")
    axes[0].bar(x + 0.2, tight, 0.4, label="tight bound sqrt(15)/2", color="tab:blue")
    axes[0].set_xticks(x, labels, fontsize=7)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("summed error over probes and channels (relative to mean)")
    axes[0].set_title(f"Table 3 on sky data ({result['probes']} probes, 8 bits)")
    axes[0].legend(fontsize=8)
    for bound, colour in (("prior", "tab:gray"), ("tight", "tab:blue")):
        for quantity, style in (("radiance", "-"), ("irradiance", "--")):
            rmse = [next(r for r in by_bits[b]["rows"] if r["bound"] == bound and r["quantity"] == quantity and not r["sqrt"])["RMSE"]
                    for b in plan.bits]
            axes[1].plot(plan.bits, rmse, style, marker="o", color=colour, label=f"{quantity}, {bound} bound")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("bits per coefficient (count)")
    axes[1].set_ylabel("RMSE (relative to the probe's mean)")
    axes[1].set_title("Quantization error against bit depth (no square root)")
    axes[1].grid(True, which="major", alpha=0.3)
    axes[1].legend(fontsize=8)
    s.figure(ctx.save(fig, "s06_quantization.png"), "Quantization of sky SH: Table 3 and the error against bit depth")
    change = next(c for c in result["changes"] if c["quantity"] == "radiance" and not c["sqrt"] and c["metric"] == "L2")
    s.text(f"Sky data for the bit-depth sweep: {source}. The tight bound lowers the radiance L2 error by "
           f"{sig(change['change_percent'])}% at 8 bits.")
    ctx.note("Quantization (8 bits): radiance L2 error change, tight against prior bound", f"{sig(change['change_percent'])}%",
             "5.361% (PBR_White_Box, seed 002)")
    return s


# --------------------------------------------------------------------------- #
# Section 7
# --------------------------------------------------------------------------- #
def section_irradiance(ctx: Context) -> Section:
    s = Section(7)
    plan = ctx.plan
    with ctx.bar(1 + len(plan.hazel_zeniths), "7. irradiance") as bar:
        result = hazel.irradiance_experiment(plan.hazel_points, seed=0)
        bar.update(1)
        timings = quantize_experiment.reconstruction_timings(0)
        sweep_rows = {}
        for z in plan.hazel_zeniths:
            r = hazel.irradiance_comparison(z, 3.0, 0.0)
            sweep_rows[z] = {row["method"]: row for row in r["rows"]}
            bar.update(1)
    s.text(f"`skysh.hazel.irradiance_experiment({plan.hazel_points})`: each reconstruction from the same "
           "projection against the exact irradiance of the true sky (a 32-band projection), I = E / pi, errors "
           "relative to the mean irradiance R0, over a Gauss sphere of normals; hand-counted shader costs and a "
           "numpy throughput (`tools/quantize_experiment.py`).")
    s.raw(quantize_experiment.hazel_markdown(result, timings).splitlines())
    methods = [r["method"] for r in result["rows"]]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True)
    x = np.arange(len(methods))
    for k, (key, label) in enumerate((("mean_abs", "mean |error|"), ("rms", "RMS error"), ("max_abs", "max |error|"))):
        axes[0].bar(x + (k - 1) * 0.27, [100 * r[key] for r in result["rows"]], 0.27, label=label)
    axes[0].set_xticks(x, [m.replace(" (Geomerics)", "\n(Geomerics)") for m in methods], fontsize=8)
    axes[0].set_yscale("log")
    axes[0].set_ylabel("irradiance error (% of mean irradiance R0)")
    axes[0].set_title(f"Irradiance reconstructions against the exact sky ({result['points']} skies)")
    axes[0].legend(fontsize=8)
    for method in methods:
        axes[1].plot(np.degrees(plan.hazel_zeniths), [100 * sweep_rows[z][method]["max_abs"] for z in plan.hazel_zeniths],
                     "o-", label=method)
    axes[1].set_yscale("log")
    axes[1].set_xlabel("sun zenith angle (deg), turbidity 3")
    axes[1].set_ylabel("max |error| over normals (% of R0)")
    axes[1].set_title("Worst irradiance error against the sun's position")
    axes[1].grid(True, which="major", alpha=0.3)
    axes[1].legend(fontsize=8)
    s.figure(ctx.save(fig, "s07_irradiance.png"), "Irradiance reconstructions against the sky's exact irradiance")
    by = {r["method"]: r for r in result["rows"]}
    if "L2" in by:
        ctx.note("Irradiance, L2 (3 bands) against the exact sky: mean / max error (of R0)",
                 f"{pct(by['L2']['mean_abs'])} / {pct(by['L2']['max_abs'])}", "")
    if "L1 non-linear (Geomerics)" in by:
        ctx.note("Irradiance, Geomerics L1: mean / max error (of R0)",
                 f"{pct(by['L1 non-linear (Geomerics)']['mean_abs'])} / {pct(by['L1 non-linear (Geomerics)']['max_abs'])}", "")
    return s


# --------------------------------------------------------------------------- #
# Section 8
# --------------------------------------------------------------------------- #
def evaluate_float32(table: NDArray, degrees: NDArray, sun_zenith: NDArray, turbidity: NDArray,
                     variant: tuple[bool, bool] = (True, True)) -> NDArray:
    """:func:`skysh.fit.evaluate_table` with the table, the design terms, the scale and the sum in float32."""
    degrees = np.asarray(degrees)
    within = (int(degrees[:, 0].max()), int(degrees[:, 1].max()))
    design = poly.design(sun_zenith, turbidity, within, variant[0]).astype(np.float32)
    scale = (preetham.luminance_scale(sun_zenith, turbidity) if variant[1] else np.ones(np.shape(sun_zenith))).astype(np.float32)
    return np.einsum("pt,tkc->pkc", design, table.astype(np.float32)) * scale[:, None, None]


def monomial_design(sun_zenith: NDArray, turbidity: NDArray, degrees: tuple[int, int]) -> NDArray:
    """The seed's raw monomials theta^i tau^j (eq. 1), term (i, j) at i (d_tau + 1) + j like skysh.poly."""
    return np.polynomial.polynomial.polyvander2d(sun_zenith, turbidity, degrees)


def fuzz(sky: SkySH, count: int, rng: np.random.Generator) -> dict[str, Any]:
    """Random and adversarial calls of ``SkySH.coefficients``: what comes back, by category."""
    import colour  # the names the runtime accepts (colour-science is a dependency)

    colour_spaces = colour.RGB_COLOURSPACES
    half_pi = math.pi / 2.0
    just_outside_z = [np.nextafter(0.0, -1.0), np.nextafter(half_pi, 4.0), -1e-300, half_pi + 1e-12, 3.2, -5.0, 1e300]
    just_outside_t = [np.nextafter(2.5, 0.0), np.nextafter(6.0, 7.0), 0.0, -1.0, 1.7, 10.0, 1e300]
    weird = [None, "0.5", complex(0.5, 0.0), [0.5], (0.5,), np.float32(0.5), np.float16(0.5), np.int64(0), True,
             np.array(0.5), object(), b"1", {"a": 1}]
    azimuths_huge = [1e17, -1e17, 1e300, 1e308, -1.7e308, 2.0**1000, np.finfo(np.float64).max]
    bands_odd = [0, -1, 8, 100, 3.0, True, None, "3", np.int64(3), np.int32(7), 2**64, 7.5]
    spaces = ["sRGB", "ITU-R BT.2020", "ACEScg", "srgb", "", None, 5, "not a colourspace"]

    def in_domain() -> tuple[float, float, float]:
        return float(rng.uniform(0.0, half_pi)), float(rng.uniform(2.5, 6.0)), float(rng.uniform(-10.0, 10.0))

    def expect_domain(z: Any, t: Any, a: Any) -> str:
        if any(isinstance(v, (str, bytes, bool, np.bool_)) for v in (z, t, a)):
            return "ValueError"  # text and truth values are not angles or turbidities
        try:
            zz, tt, aa = (np.asarray(v, dtype=np.float64) for v in (z, t, a))
            np.broadcast_shapes(zz.shape, tt.shape, aa.shape)
        except (TypeError, ValueError):
            return "ValueError"
        if not (np.all(np.isfinite(zz)) and np.all(np.isfinite(tt)) and np.all(np.isfinite(aa))):
            return "ValueError"
        if zz.size and (zz.min() < 0.0 or zz.max() > half_pi):
            return "ValueError"
        if tt.size and (tt.min() < 2.5 or tt.max() > 6.0):
            return "ValueError"
        return "finite"

    categories = ["in domain", "domain edges", "just outside", "non-finite", "huge azimuth", "arrays", "other types",
                  "bands", "flags and colourspace"]
    stats = {c: {"tried": 0, "finite": 0, "nan_inf": 0, "ValueError": 0, "other": 0, "lenient": 0, "unexpected": 0}
             for c in categories}
    examples: list[str] = []
    warning_count = 0
    for i in range(count):
        category = categories[i % len(categories)]
        z, t, a = in_domain()
        kwargs: dict[str, Any] = {"bands": int(rng.integers(1, MAX_BANDS + 1)), "gibbs": bool(rng.integers(2)),
                                  "irradiance": bool(rng.integers(2))}
        if category == "domain edges":
            z = float(rng.choice([0.0, -0.0, half_pi, np.nextafter(half_pi, 0.0), np.nextafter(0.0, 1.0)]))
            t = float(rng.choice([2.5, 6.0, np.nextafter(2.5, 3.0), np.nextafter(6.0, 5.0)]))
        elif category == "just outside":
            if rng.integers(2):
                z = float(rng.choice(just_outside_z))
            else:
                t = float(rng.choice(just_outside_t))
        elif category == "non-finite":
            bad = float(rng.choice([math.nan, math.inf, -math.inf]))
            which = int(rng.integers(3))
            z, t, a = [bad if k == which else v for k, v in enumerate((z, t, a))]
        elif category == "huge azimuth":
            a = float(rng.choice(azimuths_huge))
        elif category == "arrays":
            n = int(rng.integers(0, 5))
            z = rng.uniform(0.0, half_pi, n)
            t = rng.uniform(2.5, 6.0, n) if rng.integers(2) else float(rng.uniform(2.5, 6.0))
            a = rng.uniform(-4.0, 4.0, (1, n)) if rng.integers(2) else rng.uniform(-4.0, 4.0, n)
            if n and rng.integers(4) == 0:
                z[int(rng.integers(n))] = float(rng.choice([math.nan, -0.1, 2.0]))
            if rng.integers(6) == 0:
                t = rng.uniform(2.5, 6.0, n + 1)  # shapes that do not broadcast
        elif category == "other types":
            value = weird[int(rng.integers(len(weird)))]
            which = int(rng.integers(3))
            z, t, a = [value if k == which else v for k, v in enumerate((z, t, a))]
        elif category == "bands":
            kwargs["bands"] = bands_odd[int(rng.integers(len(bands_odd)))]
        elif category == "flags and colourspace":
            kwargs["colourspace"] = spaces[int(rng.integers(len(spaces)))]
            kwargs["dering"] = bool(rng.integers(8) == 0)
            kwargs["bands"] = int(rng.integers(1, 4)) if kwargs["dering"] else kwargs["bands"]
        expected = expect_domain(z, t, a)
        b = kwargs["bands"]
        if expected == "finite" and not (type(b) in (int, np.int64, np.int32) and 1 <= int(b) <= MAX_BANDS):
            expected = "ValueError"
        cs = kwargs.get("colourspace")
        if expected == "finite" and cs is not None and not (isinstance(cs, str) and cs in colour_spaces):
            expected = "ValueError"  # colour-science's names are case-insensitive
        entry = stats[category]
        entry["tried"] += 1
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                out = sky.coefficients(z, t, a, **kwargs)
                finite = bool(np.all(np.isfinite(out)))
                outcome = "finite" if finite else "nan_inf"
            except ValueError:
                outcome = "ValueError"
            except Exception as error:  # noqa: BLE001 - the fuzzer records every kind of failure
                outcome = "other"
                if sum(e.startswith(category) for e in examples) < 3:
                    examples.append(f"{category}: coefficients({z!r}, {t!r}, {a!r}, {kwargs}) raised {type(error).__name__}: {error}")
        warning_count += sum(1 for w in caught if issubclass(w.category, RuntimeWarning))
        entry[outcome] += 1
        if outcome != expected:
            entry["unexpected"] += 1
            if outcome == "finite" and any(isinstance(v, (str, bytes, bool, np.bool_)) for v in (z, t, a)):
                entry["lenient"] += 1
            if outcome != "other" and sum(e.startswith(category) for e in examples) < 3:
                examples.append(f"{category}: coefficients({z!r}, {t!r}, {a!r}, {kwargs}) gave {outcome}, expected {expected}")
    return {"stats": stats, "examples": examples, "runtime_warnings": warning_count}


def section_stability(ctx: Context) -> Section:
    s = Section(8)
    plan, sky = ctx.plan, ctx.sky
    g = ctx.memo("grids", lambda: grids(ctx))
    fts, ftu, fc, fl = g["fit"]
    tts, ttu, tc, tl = g["test"]
    fd, td = fit.error_denominator(fl), fit.error_denominator(tl)

    # (a) raw monomials against Chebyshev
    rows, cond_points = [], []
    with ctx.bar(len(plan.stability_degrees), "8a. monomials") as bar:
        for degrees in plan.stability_degrees:
            per_band = np.tile(np.asarray(degrees, dtype=np.int64), (MAX_BANDS, 1))
            mono = monomial_design(fts, ftu, degrees)
            mono_table, mono_cond = fit._solve(mono, fc, fd)  # the package's weighted least squares, raw monomials
            mono_pred = monomial_design(tts, ttu, degrees) @ mono_table.reshape(mono_table.shape[0], -1)
            mono_pred = mono_pred.reshape(tts.size, *mono_table.shape[1:])
            mono32 = (monomial_design(tts, ttu, degrees).astype(np.float32)
                      @ mono_table.reshape(mono_table.shape[0], -1).astype(np.float32)).reshape(mono_pred.shape)
            plain_table, plain_cond = fit.fit_table(fts, ftu, fc, fd, per_band, variant=fit.VARIANTS["plain (seed)"])
            plain_pred = fit.evaluate_table(plain_table, per_band, tts, ttu, variant=fit.VARIANTS["plain (seed)"])
            ship_table, ship_cond = fit.fit_table(fts, ftu, fc, fd, per_band)
            ship_pred = fit.evaluate_table(ship_table, per_band, tts, ttu)
            ship32 = evaluate_float32(ship_table, per_band, tts, ttu)
            # the naive route: normal equations of the weighted monomial design
            normal = np.empty_like(mono_table)
            try:
                for ch in range(3):
                    w = 1.0 / fd[:, ch, None]
                    a = mono * w
                    normal[:, :, ch] = np.linalg.solve(a.T @ a, a.T @ (fc[:, :, ch] * w))
                normal_pred = (monomial_design(tts, ttu, degrees) @ normal.reshape(normal.shape[0], -1)).reshape(mono_pred.shape)
                normal_err = pct(fit.error_measures(normal_pred, tc, td, MAX_BANDS)["e_mean"].max())
            except np.linalg.LinAlgError as error:
                normal_err = f"failed ({error})"

            def e(pred: NDArray) -> float:
                return float(fit.error_measures(np.asarray(pred, dtype=np.float64), tc, td, MAX_BANDS)["e_mean"].max())

            cond_mono_raw = float(np.linalg.cond(mono))
            cond_cheb_raw = float(np.linalg.cond(poly.design(fts, ftu, degrees)))
            rows.append([str(degrees), poly.n_terms(degrees), sig(cond_mono_raw), sig(mono_cond), sig(cond_cheb_raw),
                         sig(plain_cond), pct(e(mono_pred)), normal_err, pct(e(plain_pred)), pct(e(mono32)),
                         pct(e(ship_pred)), pct(e(ship32))])
            cond_points.append((poly.n_terms(degrees), cond_mono_raw, mono_cond, cond_cheb_raw, plain_cond, ship_cond,
                                e(mono_pred), e(plain_pred), e(mono32), e(ship_pred), e(ship32)))
            bar.update(1)
    s.text("**Raw monomials against the well-conditioned basis.** The seed's eq. 1 (theta^i tau^j, radians and "
           "turbidity) fitted by the package's own weighted least squares (`fit._solve`, SVD-based) on the same grid "
           "and weights as the Chebyshev forms; condition numbers of the design matrix alone and weighted by 1/L_min "
           "(the matrix actually solved); worst held-out E_mean at 7 bands in float64 and with the table, the design "
           "terms and the sum in float32 (an engine's float evaluation). 'normal equations' solves the weighted "
           "monomial problem the naive way (A^T A x = A^T b). Condition numbers above about 1e16 are themselves "
           "inexact in float64 (the smallest singular value is at rounding level): they mean 'singular to working "
           "precision'; there the SVD solver drops directions (its rcond) and the fit degrades.")
    s.table(["degrees", "terms", "cond, monomials", "cond, monomials weighted", "cond, Chebyshev (plain)",
             "cond, Chebyshev weighted", "E_mean monomials (SVD)", "E_mean monomials (normal eq.)",
             "E_mean Chebyshev plain", "E_mean monomials float32", "E_mean shipped form", "E_mean shipped form float32"], rows)
    cp = np.array(cond_points)
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True)
    axes[0].plot(cp[:, 0], cp[:, 1], "o-", color="tab:red", label="monomials theta^i T^j")
    axes[0].plot(cp[:, 0], cp[:, 2], "o--", color="tab:red", label="monomials, weighted 1/L_min")
    axes[0].plot(cp[:, 0], cp[:, 3], "s-", color="tab:blue", label="Chebyshev (plain variables)")
    axes[0].plot(cp[:, 0], cp[:, 4], "s--", color="tab:blue", label="Chebyshev plain, weighted")
    axes[0].plot(cp[:, 0], cp[:, 5], "^--", color="tab:green", label="shipped form, weighted")
    axes[0].axhline(1.0 / np.finfo(np.float64).eps, color="gray", linestyle=":", label="1 / float64 epsilon")
    axes[0].set_yscale("log")
    axes[0].set_xlabel("polynomial terms (d_theta + 1)(d_tau + 1) (count)")
    axes[0].set_ylabel("condition number (dimensionless)")
    axes[0].set_title("Conditioning of the fit's design matrix")
    axes[0].legend(fontsize=8)
    axes[0].grid(True, which="major", alpha=0.3)
    for col, label, style in ((6, "monomials, float64", "o-"), (7, "Chebyshev plain, float64", "s-"),
                              (8, "monomials, float32", "o:"), (9, "shipped form, float64", "^-"),
                              (10, "shipped form, float32", "^:")):
        axes[1].plot(cp[:, 0], 100 * cp[:, col], style, label=label)
    axes[1].set_yscale("log")
    axes[1].set_xlabel("polynomial terms (count)")
    axes[1].set_ylabel("worst held-out E_mean, 7 bands (% of L_min)")
    axes[1].set_title("Fit error by basis and precision")
    axes[1].legend(fontsize=8)
    axes[1].grid(True, which="major", alpha=0.3)
    s.figure(ctx.save(fig, "s08_conditioning.png"), "Raw monomials against Chebyshev: condition numbers and error, float64 and float32")
    seed_row = next((r for r in cond_points if r[0] == poly.n_terms(SEED_DEGREES)), cond_points[-1])
    ctx.note(f"Condition number of the raw monomial design at {SEED_DEGREES} (unweighted)", sig(seed_row[1]), "(not given)")
    ctx.note("float32 evaluation of the shipped form: worst E_mean 7 bands (float64 in brackets)",
             f"{pct(seed_row[10])} ({pct(seed_row[9])})", "")

    # (b) extrapolation
    count, zeniths = plan.extrapolation
    refusals = []
    for z, t in ((np.nextafter(math.pi / 2, 4.0), 4.0), (math.pi / 2 + 0.01, 4.0), (-1e-9, 4.0), (0.5, 2.49), (0.5, 6.01), (0.5, 1.7)):
        try:
            sky.coefficients(float(z), float(t), 0.0)
            refusals.append([sig(z, 17), sig(t), "**accepted (silent extrapolation)**"])
        except ValueError as error:
            refusals.append([sig(z, 17), sig(t), f"ValueError: {error}"])
    s.text("**Extrapolation just outside the domain.** What the runtime does:")
    s.table(["sun_zenith (rad)", "turbidity", "SkySH.coefficients"], refusals)
    turbidities = np.linspace(1.8, 8.0, count)
    extr = {}
    with ctx.bar(len(zeniths) * count, "8b. extrapolation") as bar:
        for z in zeniths:
            zz = np.full(count, z)
            truth, lmin = [], []
            for t in turbidities:
                c, m = fit._project_one((float(z), float(t), MAX_BANDS, "sRGB", "quadrature", None, 0))
                truth.append(c)
                lmin.append(m)
                bar.update(1)
            predicted = fit.evaluate_table(np.asarray(sky.table.table), sky.table.degrees, zz, turbidities)
            denom = fit.error_denominator(np.array(lmin))
            extr[z] = {b: fit.error_measures(predicted, np.array(truth), denom, b)["e_mean"] for b in (3, MAX_BANDS)}
    fig, ax = plt.subplots(figsize=(9, 4.8), constrained_layout=True)
    for z in zeniths:
        line = ax.plot(turbidities, 100 * extr[z][MAX_BANDS], "o-", markersize=3, label=f"sun zenith {math.degrees(z):.0f} deg, 7 bands")
        ax.plot(turbidities, 100 * extr[z][3], "--", color=line[0].get_color(), label=f"sun zenith {math.degrees(z):.0f} deg, 3 bands")
    ax.axvspan(*poly.TURBIDITY_DOMAIN, color="tab:green", alpha=0.1, label="fitted domain (runtime accepts)")
    ax.set_yscale("log")
    ax.set_xlabel("turbidity (dimensionless)")
    ax.set_ylabel("E_mean of the polynomial (% of L_min)")
    ax.set_title("What the polynomial would give outside the domain (the runtime refuses)")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    s.figure(ctx.save(fig, "s08_extrapolation.png"), "Error of the shipped polynomial evaluated outside its turbidity domain")
    inside = np.array([extr[z][MAX_BANDS][(turbidities >= 2.5) & (turbidities <= 6.0)].max() for z in zeniths]).max()
    low = np.array([extr[z][MAX_BANDS][turbidities <= 2.0].max() for z in zeniths]).max() if (turbidities <= 2.0).any() else math.nan
    high = np.array([extr[z][MAX_BANDS][turbidities >= 7.5].max() for z in zeniths]).max() if (turbidities >= 7.5).any() else math.nan
    s.text(f"Inside the domain the worst E_mean on this line is {pct(inside)}; at T <= 2 it reaches {pct(low)}, at "
           f"T >= 7.5 {pct(high)} (`fit.evaluate_table`, which does not check the domain; the sun below the "
           "horizon is undefined in Preetham's model, so there is no truth to compare with).")
    ctx.note("Extrapolation: runtime refuses outside the domain; polynomial error at T <= 2 / T >= 7.5 (7 bands)",
             f"refused; {pct(low)} / {pct(high)}", "")

    # (c) Monte Carlo at low sample counts
    from skysh import dering

    methods = RANDOM_METHODS
    neg = {(m, g): [] for m in methods for g in (False, True)}
    low = {m: [] for m in methods}
    err = {m: [] for m in methods}
    truths, true_min, true_min_raw = [], [], []
    for ts_, tu_ in plan.mc_points:
        truth3 = preetham.sky_sh(ts_, tu_, 3)
        truths.append((truth3, fit.error_denominator(preetham.sky_minimum(ts_, tu_)[None])))
        true_min.append(float((dering.exact_min(sh.irradiance(gibbs_filter(truth3))) / mean_value(sh.irradiance(truth3))).min()))
        true_min_raw.append(float((dering.exact_min(sh.irradiance(truth3)) / mean_value(sh.irradiance(truth3))).min()))
    with ctx.bar(len(methods) * len(plan.mc_counts) * len(plan.mc_points), "8c. Monte Carlo") as bar:
        for method in methods:
            for n in plan.mc_counts:
                negative = {False: 0, True: 0}
                errors, lowest = [], []
                for (ts_, tu_), (truth3, denom) in zip(plan.mc_points, truths):
                    c = np.stack([preetham.sky_sh(ts_, tu_, 3, method=method, n=n, seed=seed) for seed in range(plan.mc_seeds)])
                    for gibbs in (False, True):
                        irr = sh.irradiance(gibbs_filter(c) if gibbs else c)
                        relative = dering.exact_min(irr) / np.abs(mean_value(irr))  # (S, 3)
                        negative[gibbs] += int((relative < 0.0).any(axis=1).sum())
                        if gibbs:
                            lowest.append(relative.min(axis=1))
                    errors.append(error_all(c, np.broadcast_to(truth3, c.shape), np.broadcast_to(denom, (c.shape[0], 3)), 3)["e_mean"])
                    bar.update(1)
                for gibbs in (False, True):
                    neg[(method, gibbs)].append(negative[gibbs] / (plan.mc_seeds * len(plan.mc_points)))
                low[method].append(np.concatenate(lowest))
                err[method].append(float(np.median(np.concatenate(errors))))
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), constrained_layout=True)
    for method in methods:
        style = METHOD_STYLE[method]
        axes[0].plot(plan.mc_counts, 100 * np.array(neg[(method, True)]), "-", label=f"{method}, Gibbs filter", **style)
        axes[0].plot(plan.mc_counts, 100 * np.array(neg[(method, False)]), ":", label=f"{method}, no filter", **style)
        axes[1].plot(plan.mc_counts, [100 * np.quantile(v, 0.01) for v in low[method]], "-", label=f"{method}: 1st percentile", **style)
        axes[1].plot(plan.mc_counts, [100 * np.median(v) for v in low[method]], "--", label=f"{method}: median", **style)
        axes[2].plot(plan.mc_counts, 100 * np.array(err[method]), "-", label=method, **style)
    axes[1].axhline(100 * min(true_min), color="black", linewidth=1.5, label="converged projection (worst sun)")
    axes[1].axhline(0.0, color="gray", linewidth=0.8)
    axes[0].set_ylim(-3, 103)
    axes[0].set_ylabel("projections with negative 3-band irradiance (%)")
    axes[0].set_title(f"Irradiance goes negative ({plan.mc_seeds} seeds x {len(plan.mc_points)} suns)")
    axes[1].set_yscale("symlog", linthresh=1.0)
    axes[1].set_ylabel("min irradiance / mean irradiance (%, symlog)")
    axes[1].set_title("Lowest irradiance, Gibbs filter on")
    axes[2].set_yscale("log")
    axes[2].set_ylabel("median E_mean, 3 bands (% of L_min)")
    axes[2].set_title("Error of low-sample projections")
    for ax in axes:
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks(plan.mc_counts, [str(n) for n in plan.mc_counts], fontsize=8)
        ax.set_xlabel("directions per projection (count)")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    s.figure(ctx.save(fig, "s08_monte_carlo.png"), "Monte Carlo at low sample counts: negative irradiance and error")
    s.text("**Monte Carlo at low sample counts.** 3-band projections by `sky_sh(method=..., n=..., seed=...)` at "
           + ", ".join(f"({math.degrees(a):.0f} deg, T = {b:g})" for a, b in plan.mc_points)
           + ", without and with the runtime's Gibbs filter (`runtime.gibbs_factors` on the zonal rows, as a "
           "renderer projecting per frame would apply it); a projection counts as negative when `dering.exact_min` "
           "of its irradiance is below zero in any channel. Without the filter the converged 3-band irradiance is "
           f"itself negative (minimum {', '.join(pct(v) for v in true_min_raw)} of the mean: the horizon's ringing, "
           "section 5), so negatives there are not the sampling's fault; with it the converged minimum is "
           f"{', '.join(pct(v) for v in true_min)} of the mean, and every negative is the sampling's. E_mean: all 9 "
           "coefficients against the converged projection, unfiltered.")
    s.table(["directions", *[f"{m}: negative, filter" for m in methods], *[f"{m}: negative, no filter" for m in methods],
             *[f"{m}: median E_mean" for m in methods]],
            [[n, *[pct(neg[(m, True)][i]) for m in methods], *[pct(neg[(m, False)][i]) for m in methods],
              *[pct(err[m][i]) for m in methods]] for i, n in enumerate(plan.mc_counts)])
    worst_n = max((n for i, n in enumerate(plan.mc_counts) if neg[("mc", True)][i] > 0.0), default=None)
    ctx.note("Monte Carlo, Gibbs filter on: largest sample count with a negative 3-band irradiance "
             f"({plan.mc_seeds} seeds x {len(plan.mc_points)} suns)", "none" if worst_n is None else f"{worst_n} directions", "")

    # (d) the sun at the zenith and on the horizon
    rows = []
    for z, label in ((0.0, "0"), (1e-9, "1e-9"), (math.pi / 2 - 1e-9, "pi/2 - 1e-9"), (math.pi / 2, "pi/2")):
        for t in (2.5, 4.25, 6.0):
            c, m = fit._project_one((z, t, MAX_BANDS, "sRGB", "quadrature", None, 0))
            denom = fit.error_denominator(m[None])
            pred = sky.coefficients(z, t, 0.0, bands=MAX_BANDS, gibbs=False)
            e = {b: fit.error_measures(pred[HALF_ROWS][None], c[None], denom, b) for b in (3, MAX_BANDS)}
            twist = np.abs(sky.coefficients(z, t, 2.0, bands=MAX_BANDS) - sky.coefficients(z, t, 0.0, bands=MAX_BANDS)).max()
            rows.append([label, t, pct(e[3]["e_mean"][0]), pct(e[MAX_BANDS]["e_mean"][0]), sig(e[MAX_BANDS]["dc"][0]),
                         sig(twist / np.abs(pred[0]).max()), "yes" if np.all(np.isfinite(pred)) else "**no**",
                         "yes" if (m[:3] < fit.LMIN_FLOOR * m[3]).any() else "no"])
    s.text("**The sun at the zenith and on the horizon** (the domain's edges, where the sky's quadrature has its "
           "singular cases): runtime against `sky_sh`; 'azimuth change' is the largest coefficient change when the "
           "sun's azimuth goes from 0 to 2 rad, relative to DC (the true sky's is zero at the zenith by symmetry; what "
           "remains there is the fit's error in the m != 0 coefficients).")
    s.table(["sun_zenith (rad)", "T", "E_mean 3 bands", "E_mean 7 bands", "DC error", "azimuth change (of DC)",
             "finite", "L_min floored"], rows)

    # (e) float32 is in (a); (f) Newton iterations in the bound
    def newton() -> None:
        need(dering, "min_bound", "exact_min", "_NEWTON_STEPS")
        rng = np.random.default_rng(7)
        rand = rng.normal(size=(plan.random_functions, 9, 1)) * rng.uniform(0.0, 2.0, (plan.random_functions, 9, 1)) ** 2
        unit = np.abs(rand).max(axis=-2)
        ts_, tu_, _, _ = uniform_grid(plan.dering_grid)
        skies = sh.irradiance(sky.coefficients(ts_, tu_, 0.0, bands=3, gibbs=False))
        sky_unit = skies[:, 0, :] * 0.5 / math.sqrt(math.pi)
        exact_r, exact_s = dering.exact_min(rand), dering.exact_min(skies)
        original = dering._NEWTON_STEPS
        rows, curve = [], []
        try:
            dering._NEWTON_STEPS = NEWTON_REFERENCE
            converged_r, converged_s = dering.min_bound(rand), dering.min_bound(skies)
            for steps in plan.newton_steps:
                dering._NEWTON_STEPS = steps
                bound_r, bound_s = dering.min_bound(rand), dering.min_bound(skies)
                short_r = (converged_r - bound_r) / unit  # what stopping early costs
                short_s = (converged_s - bound_s) / sky_unit
                gap_r = (exact_r - bound_r) / unit  # the bound's total looseness
                seconds = best_time(lambda: dering.min_bound(skies[0]), 3, 20)
                viol = int((gap_r < -1e-12).sum() + ((exact_s - bound_s) / sky_unit < -1e-12).sum())
                rows.append([steps, sig(short_r.mean()), sig(np.quantile(short_r, 0.99)), sig(short_r.max()),
                             sig(short_s.max()), sig(gap_r.mean()), viol, us(seconds)])
                curve.append((steps, short_r.mean(), np.quantile(short_r, 0.99), short_r.max(), short_s.max(), gap_r.mean()))
        finally:
            dering._NEWTON_STEPS = original
        s.text(f"**Newton iterations in the bound** (`dering._NEWTON_STEPS`, shipped {original}; set temporarily): "
               f"the shortfall of `min_bound` against the same bound with {NEWTON_REFERENCE} steps (what stopping early "
               f"costs), for {plan.random_functions} random 3-band functions (unit: largest coefficient) and the "
               f"{skies.shape[0]} skies' irradiance without the Gibbs filter (unit: mean), beside the bound's total gap "
               "to `exact_min` (its looseness, from the worst-phase assumption of the |m| = 1 pair); a violation is a "
               "bound above the exact minimum. Fewer steps can only loosen the bound: duality keeps it valid.")
        s.table(["Newton steps", "shortfall mean (random)", "shortfall 99th pct (random)", "shortfall worst (random)",
                 "shortfall worst (skies)", "gap to exact_min, mean (random)", "violations", "min_bound, one sky"], rows)
        cv = np.array(curve)
        fig, ax = plt.subplots(figsize=(9, 4.8), constrained_layout=True)
        for col, label, style in ((1, "shortfall, random: mean", "o-"), (2, "shortfall, random: 99th percentile", "o--"),
                                  (3, "shortfall, random: worst", "o:"), (4, "shortfall, skies: worst", "s-"),
                                  (5, "total gap to exact_min, random: mean", "k^-")):
            ax.plot(cv[:, 0], np.maximum(cv[:, col], 1e-17), style, label=label)
        ax.axvline(original, color="gray", linestyle=":", label=f"shipped: {original} steps")
        ax.set_xticks(list(plan.newton_steps))
        ax.set_yscale("log")
        ax.set_xlabel("Newton steps (count)")
        ax.set_ylabel("bound shortfall or gap (function units; floor 1e-17)")
        ax.set_title("The deringing bound against Newton steps")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
        s.figure(ctx.save(fig, "s08_newton.png"), "Gap of the conservative bound to the exact minimum against Newton steps")

    part(s, "Newton iterations in the bound", newton)

    # (g) fuzzing
    with ctx.bar(1, "8g. fuzzing") as bar:
        start = time.perf_counter()
        result = fuzz(sky, plan.fuzz_inputs, np.random.default_rng(99))
        seconds = time.perf_counter() - start
        bar.update(1)
    stats = result["stats"]
    s.text(f"**Fuzzing `SkySH.coefficients`**: {plan.fuzz_inputs} calls in {sig(seconds)} s, random and adversarial "
           "inputs in 9 categories; 'expected' is a finite result for an in-domain call and a ValueError otherwise; "
           "'unexpected' counts calls that did anything else (NaN/inf, another exception, a refusal of a valid call "
           f"or silent extrapolation). RuntimeWarnings raised by numpy during the calls: {result['runtime_warnings']}.")
    s.table(["category", "tried", "finite result", "NaN or inf", "ValueError", "other exception",
             "text or bool taken as a number", "unexpected (all kinds)"],
            [[c, v["tried"], v["finite"], v["nan_inf"], v["ValueError"], v["other"], v["lenient"], v["unexpected"]]
             for c, v in stats.items()])
    if result["examples"]:
        s.text("Unexpected outcomes (at most three per category):")
        s.raw([f"- `{e}`" for e in result["examples"]])
    total = {k: sum(v[k] for v in stats.values()) for k in ("tried", "nan_inf", "other", "lenient")}
    ctx.note("Fuzzing SkySH.coefficients: inputs tried / NaN-inf results / exceptions other than ValueError / "
             "text or bool accepted as numbers", f"{total['tried']} / {total['nan_inf']} / {total['other']} / {total['lenient']}", "")
    nan_cases = [e for e in result["examples"] if "nan_inf" in e]
    if nan_cases:
        s.text("NaN or inf came only from huge finite azimuths: the runtime multiplies the azimuth by m before "
               "taking cos and sin, which overflows to inf for |sun_azimuth| above about 1.8e308 / (N - 1); "
               "`sun_azimuth` is documented as 'any finite value'." if all("huge azimuth" in e for e in nan_cases)
               else "NaN or inf came from the calls listed above.")
    return s


# --------------------------------------------------------------------------- #
# Section 9
# --------------------------------------------------------------------------- #
def section_scene(ctx: Context) -> Section:
    s = Section(9)
    plan, sky = ctx.plan, ctx.sky
    sw = ctx.memo("sweep", lambda: sweep(ctx))
    g = ctx.memo("grids", lambda: grids(ctx))
    normals, nw = sh.quadrature_rule(hazel.COMPARISON_THETA_NODES)
    ts, az, tu = quantize.sample_sky_parameters(plan.scene_points, 1)
    bands = np.arange(1, MAX_BANDS + 1)
    irr = {False: np.zeros((plan.scene_points, MAX_BANDS)), True: np.zeros((plan.scene_points, MAX_BANDS))}
    irr_mean = np.zeros((plan.scene_points, MAX_BANDS))
    rad = np.zeros((plan.scene_points, MAX_BANDS))
    with ctx.bar(plan.scene_points, "9. bands a scene needs") as bar:
        for p in range(plan.scene_points):
            exact = hazel.exact_irradiance(ts[p], tu[p], normals, sun_azimuth=az[p])  # I = E / pi, 32 bands
            c7 = preetham.sky_sh(ts[p], tu[p], MAX_BANDS, sun_azimuth=az[p])
            r0 = hazel.L0_SCALE * c7[0]
            dirs, w = preetham.sky_quadrature_rule(ts[p])
            energy = np.einsum("m,mc->c", w, preetham.radiance(dirs, ts[p], 0.0, tu[p]) ** 2)  # integral of L^2 (cd/m^2)^2 sr
            lmin = fit.error_denominator(preetham.sky_minimum(ts[p], tu[p])[None])[0]
            for b in bands:
                for gibbs in (False, True):
                    rec = sky.irradiance_at(normals, float(ts[p]), float(tu[p]), float(az[p]), bands=int(b), gibbs=gibbs) / math.pi
                    irr[gibbs][p, b - 1] = float(np.max(np.abs(rec - exact) / r0))
                    if not gibbs:
                        irr_mean[p, b - 1] = float(np.max(np.einsum("m,mc->c", nw, np.abs(rec - exact)) / (4 * math.pi) / r0))
                tail = np.maximum(energy - np.sum(c7[: b * b] ** 2, axis=0), 0.0)
                rad[p, b - 1] = float(np.max(np.sqrt(tail) / lmin))  # band-limiting error in the units of eq. 3
            bar.update(1)
    entries = sw["entries"]
    picks = [e for e in entries if e["degrees"] in {(min(ctx.plan.degrees_theta), min(ctx.plan.degrees_tau)),
                                                   (7, 3), (9, 5), tuple(ctx.sky.table.max_degrees)}]
    s.text(f"{plan.scene_points} skies over the domain (`quantize.sample_sky_parameters`). Irradiance: the runtime's "
           "`irradiance_at` (I = E / pi) at N bands, with and without the Gibbs filter, against "
           "`hazel.exact_irradiance` (the true sky, 32 bands) on 1,152 normals, as the largest error relative to "
           "the mean irradiance R0 (and its sphere average). Radiance: the band-limiting error "
           "sqrt(integral L^2 - sum of the first N^2 c^2) / L_min (Parseval; the same units as E_mean, eq. 3), "
           "against the fit's own E_mean for a few degree choices (section 3): where the band-limiting error "
           "dominates, more polynomial degrees buy nothing.")
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    axes[0].plot(bands, 100 * irr[False].max(axis=0), "o-", color="tab:blue", label="irradiance, no Gibbs filter: worst normal")
    axes[0].plot(bands, 100 * irr_mean.max(axis=0), "o:", color="tab:blue", label="irradiance, no filter: sphere average")
    axes[0].plot(bands, 100 * irr[True].max(axis=0), "s-", color="tab:red", label="irradiance, Gibbs filter (runtime default): worst normal")
    for e in picks:
        fit_irr = fit_irradiance_error(e["predicted"], g, normals)
        axes[0].axhline(100 * fit_irr, linestyle="--", linewidth=1, color="gray")
        axes[0].text(MAX_BANDS, 100 * fit_irr, f" fit {e['degrees']}, 3 bands", fontsize=7, va="bottom", ha="right")
    axes[0].set_yscale("log")
    axes[0].set_xlabel("SH bands N (count)")
    axes[0].set_ylabel("irradiance error (% of mean irradiance R0, worst sky)")
    axes[0].set_title("Irradiance error against bands (and the fit's share)")
    axes[0].legend(fontsize=8, loc="lower left")
    axes[0].grid(True, which="major", alpha=0.3)
    axes[1].plot(bands, 100 * rad.max(axis=0), "o-", color="black", label="band-limiting error (worst sky)")
    axes[1].plot(bands, 100 * np.median(rad, axis=0), "o:", color="black", label="band-limiting error (median sky)")
    for e in picks:
        axes[1].plot(bands, [100 * e["bands"][b]["e_mean"] for b in bands], "s--", label=f"fit error, degrees {e['degrees']}")
    axes[1].set_yscale("log")
    axes[1].set_xlabel("SH bands N (count)")
    axes[1].set_ylabel("radiance error (% of L_min, eq. 3 units)")
    axes[1].set_title("Radiance: band-limiting against fit error")
    axes[1].legend(fontsize=8)
    axes[1].grid(True, which="major", alpha=0.3)
    s.figure(ctx.save(fig, "s09_bands.png"), "What a scene needs: irradiance and radiance error against bands and degrees")
    rows = [[b, pct(irr[False][:, b - 1].max()), pct(irr_mean[:, b - 1].max()), pct(irr[True][:, b - 1].max()),
             pct(rad[:, b - 1].max()), pct(np.median(rad[:, b - 1]))] for b in bands]
    s.table(["bands", "irradiance, worst normal (no filter)", "irradiance, sphere average (no filter)",
             "irradiance, worst normal (Gibbs filter)", "radiance band-limiting, worst sky", "radiance band-limiting, median sky"], rows)
    fit_rows = []
    for e in sorted(entries, key=lambda e: e["terms"]):
        fit_rows.append((e["degrees"], e["terms"], fit_irradiance_error(e["predicted"], g, normals), e["bands"][3]["bytes"]))
    trunc3 = irr[False][:, 2].max()
    enough = next((r for r in fit_rows if r[2] < 0.1 * trunc3), None)
    front = pareto(np.array([r[1] for r in fit_rows], dtype=float), np.array([r[2] for r in fit_rows]))
    front_rows = [fit_rows[i] for i in front]
    s.text("Fit-induced 3-band irradiance error (worst normal over the held-out grid, of R0), the swept degrees on "
           "the front of terms against error:")
    s.table(["degrees", "terms", "fit irradiance error, 3 bands", "3-band table size"],
            [[str(r[0]), r[1], pct(r[2]), sig(r[3] / 1000) + " KB"] for r in front_rows])
    worst_irr = irr[False].max(axis=0)
    for level in (0.05, 0.01):
        b = next((int(x) for x, v in zip(bands, worst_irr) if v <= level), None)
        s.text(f"Fewest bands whose worst irradiance error is below {pct(level, 2)} of R0 (no filter): "
               f"{b if b is not None else f'more than {MAX_BANDS}'}.")
    gibbs3 = irr[True][:, 2].max()
    s.text(f"At 3 bands the irradiance error is {pct(trunc3)} at the worst normal ({pct(irr_mean[:, 2].max())} on "
           "average over the sphere) from band-limiting alone; "
           + (f"the fewest-term swept degrees whose fit adds less than a tenth of that are {enough[0]} ({enough[1]} terms, "
              f"{pct(enough[2])}). " if enough else "no swept degree keeps the fit's share below a tenth of it. ")
           + "Bands 3 and 4 give the same irradiance (A_3 = 0). With the Gibbs filter (the runtime's default) the "
           f"3-band irradiance error is {pct(gibbs3)} instead of {pct(trunc3)}"
           + (": for diffuse lighting `gibbs=False` is the more accurate choice; the filter is for what is seen "
              "directly (backgrounds, reflections)." if gibbs3 > trunc3 else "."))
    ctx.note("3-band irradiance error against the exact sky, worst normal, Gibbs filter off / on (of R0)",
             f"{pct(irr[False][:, 2].max())} / {pct(irr[True][:, 2].max())}", "")
    return s


def fit_irradiance_error(predicted: NDArray, g: dict[str, Any], normals: NDArray, bands: int = 3) -> float:
    """Worst irradiance error (of R0) over the held-out grid and the normals caused by a fit's coefficients."""
    _, _, truth, _ = g["test"]
    k = bands * (bands + 1) // 2
    delta = full_from_half(predicted[:, :k] - truth[:, :k], bands)
    error = np.einsum("mk,pkc->pmc", sh.basis(normals, bands), sh.irradiance(delta)) / math.pi
    r0 = hazel.L0_SCALE * truth[:, 0, :]
    return float(np.max(np.abs(error) / r0[:, None, :]))


# --------------------------------------------------------------------------- #
# Section 10
# --------------------------------------------------------------------------- #
def section_pictures(ctx: Context) -> Section:
    s = Section(10)
    plan, sky = ctx.plan, ctx.sky
    s.text("Latitude-longitude renders by `skysh.render.render_image` (one exposure per image: Reinhard with key "
           "0.18 on the true sky's log-average; azimuth -180 to 180 deg left to right, zenith at the top, horizon "
           "in the middle; the sun is ringed): the Preetham sky, its SH reconstruction and the SH irradiance E / pi, "
           "at 3 bands (top row) and 7 bands (bottom row), Gibbs filter on (the runtime's default).")
    with ctx.bar(len(plan.picture_suns), "10. pictures") as bar:
        for k, (ts, az, tu) in enumerate(plan.picture_suns):
            images = [render.render_image(sky, ts, tu, az, bands=b, width=plan.picture_width) for b in (3, MAX_BANDS)]
            image = np.concatenate(images, axis=0)
            h, w = image.shape[:2]
            fig = plt.figure(figsize=(w / DPI, (h + 40) / DPI))
            ax = fig.add_axes((0.0, 0.0, 1.0, h / (h + 40)))
            ax.imshow(image, interpolation="nearest")
            ax.set_axis_off()
            fig.suptitle(f"Sun {math.degrees(ts):.0f} deg from zenith, T = {tu:g}: 3 bands (top), 7 (bottom)",
                         fontsize=10 if w >= 600 else 8, y=1.0 - 8 / (h + 40), va="top")
            name = ctx.save(fig, f"s10_sky_{k + 1}.png")
            s.figure(name, f"Sky, SH reconstruction and irradiance at sun zenith {math.degrees(ts):.0f} deg, T = {tu:g}")
            bar.update(1)
    return s


SECTIONS: dict[int, Callable[[Context], Section]] = {
    1: section_projection,
    2: section_fit,
    3: section_speed,
    4: section_gibbs,
    5: section_dering,
    6: section_quantization,
    7: section_irradiance,
    8: section_stability,
    9: section_scene,
    10: section_pictures,
}
"""Report sections in order; each computes its numbers and returns its markdown."""


# --------------------------------------------------------------------------- #
# Command line
# --------------------------------------------------------------------------- #
def parse_sections(text: str) -> list[int]:
    try:
        chosen = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected section numbers like '1,3,8', got {text!r}") from None
    if not chosen or any(k not in SECTIONS for k in chosen):
        raise argparse.ArgumentTypeError(f"sections must be among 1..{len(SECTIONS)}, got {text!r}")
    return chosen


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].strip().splitlines()[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True, help="output directory (report.md and PNGs)")
    parser.add_argument("--quick", action="store_true", help="small sizes: about a minute (for the test suite)")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes for the sky projections (default 2)")
    parser.add_argument("--sections", type=parse_sections, default=list(SECTIONS), help="only these sections, e.g. '1,3'")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error("--jobs must be >= 1")
    plan = QUICK if args.quick else FULL
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("s[0-9][0-9]_*.png"):
        old.unlink()  # stale charts of an earlier run
    start = time.perf_counter()
    ctx = Context(plan=plan, out=out, jobs=args.jobs, progress=not args.no_progress, sky=SkySH.load())
    sections: list[Section] = []
    failures = 0
    timings: list[tuple[int, float]] = []
    for number in tqdm(args.sections, desc="error report", unit="section", disable=not ctx.progress, file=sys.stderr):
        t0 = time.perf_counter()
        try:
            sections.append(SECTIONS[number](ctx))
        except Exception:  # noqa: BLE001 - one failing study must not lose the others; reported and exit 1
            failures += 1
            failed = Section(number)
            failed.text(f"{FAILED_MARK}: the tool raised while computing it (a bug in the tool or the package):")
            failed.raw(["```", traceback.format_exc().rstrip(), "```"])
            sections.append(failed)
            traceback.print_exc()
        timings.append((number, time.perf_counter() - t0))
    elapsed = time.perf_counter() - start
    ctx.note("Report run time (this run)", f"{sig(elapsed)} s ({plan.name}, {ctx.jobs} processes)", "")
    header = [
        "# skysh error report",
        "",
        f"Generated by `python tools/error_report.py --out {out.as_posix()}{' --quick' if args.quick else ''}` "
        f"({plan.name} run) in {sig(elapsed)} s: skysh {__version__}, commit {fit_sky.git_commit()}, Python "
        f"{platform.python_version()}, numpy {np.__version__}, {os.cpu_count()} CPUs, {ctx.jobs} worker processes. "
        "Every number below was computed in this run; quoted figures of the seed papers are labelled as such. "
        "Timings come from a shared machine (best of several runs) and vary between runs. Errors are fractions "
        "shown as percentages; E_mean and E_max are Habel 2008's eqs. 3 and 2 (sum over the coefficients of the "
        "bands used, divided by L_min, the sky's minimum over the upper hemisphere per channel, worst channel).",
        "",
        "## Summary",
        "",
        *markdown_table(["quantity", "this run", "seed (Habel et al. 2008 unless noted)"], ctx.summary),
        "Sections: " + ", ".join(f"[{k}. {SECTION_TITLES[k]}](#{k}-{SECTION_TITLES[k].lower().replace(' ', '-')})"
                                  for k in args.sections),
        "",
        "Time per section: " + ", ".join(f"{k}: {sig(t)} s" for k, t in timings),
        "",
    ]
    body = [line for sec in sections for line in sec.lines]
    (out / "report.md").write_text("\n".join(header + body).rstrip() + "\n", encoding="utf-8")
    size = sum((out / name).stat().st_size for name in ctx.figures)
    print(f"wrote {out / 'report.md'} and {len(ctx.figures)} PNGs ({size / 1e6:.2f} MB) in {elapsed:.1f} s"
          + (f"; {failures} section(s) FAILED" if failures else ""))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
