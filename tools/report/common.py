"""
What every section of the error report shares
=============================================

Constants, number formatting, markdown, the run's :class:`Context` (figures,
summary, memoised data), the one timing helper :func:`interleaved_best`, and small
computations over the package's public API (error measures over full-layout SH,
the Gibbs filter, grids, Pareto fronts, heatmaps).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Hashable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from report.plans import Plan
from skysh import runtime
from skysh.domain import SKY
from skysh.model import preetham
from skysh.runtime import SkySH
from skysh.sh import basis as sh
from skysh.table import coefficient_file, fit

matplotlib.use("Agg")  # PNGs only, no display (no figure exists yet, so the switch is free)

K = TypeVar("K", bound=Hashable)

# --------------------------------------------------------------------------- #
# Constants
# --------------------------------------------------------------------------- #
SEED_E_MEAN_7: float = 0.015
"""Habel 2008, section 3.2: the highest E_mean drops below 1.5% for 7 bands (fraction)."""

SEED_E_MEAN_5: float = 0.00005
"""Habel 2008, section 3.2: E_mean < 0.005% up to 5 bands (fraction)."""

SEED_SIZE_KB_7: float = 131.0
"""Habel 2008, section 4: 131 KB of tables for 7 bands."""

SEED_DEGREES: tuple[int, int] = (13, 7)
"""Habel 2008, section 3.2: polynomial degrees (d_theta, d_tau)."""

MAX_BANDS: int = 7
"""Bands of the shipped file and of every study here."""

RANDOM_METHODS: tuple[str, ...] = ("mc", "stratified", "qmc")
"""The random projection methods of :func:`skysh.sh.basis.project` (via :func:`skysh.model.preetham.sky_sh`)."""

SUN_QUADRATURE: str = "quadrature (sun-adapted)"
"""Label of :func:`skysh.model.preetham.sky_sh`'s default rule."""

PLAIN_QUADRATURE: str = "quadrature (plain product)"
"""Label of :func:`skysh.sh.basis.project`'s product Gauss rule over the hemisphere."""

ALL_METHODS: tuple[str, ...] = (*RANDOM_METHODS, SUN_QUADRATURE, PLAIN_QUADRATURE)
"""Every projection method of section 1, in the order of its charts and tables."""

METHOD_STYLE: dict[str, dict[str, Any]] = {
    "mc": {"color": "tab:red", "marker": "o"},
    "stratified": {"color": "tab:orange", "marker": "s"},
    "qmc": {"color": "tab:purple", "marker": "^"},
    SUN_QUADRATURE: {"color": "tab:blue", "marker": "D"},
    PLAIN_QUADRATURE: {"color": "tab:cyan", "marker": "v"},
}
"""Colours and markers of the projection methods in every chart."""

DPI: int = 100
"""Resolution of the PNGs (keeps the committed report small)."""

Y00: float = sh.Y00
"""The constant SH basis function (:data:`skysh.sh.basis.Y00`): the mean over the sphere of SH c is ``c_0 * Y00``."""

HALF_ROWS: NDArray[np.intp] = np.array(
    [sh.index(degree, m) for degree, m in coefficient_file.zonal_half_layout(MAX_BANDS)], dtype=np.intp
)
"""Flat SH indices of the stored (m >= 0) rows of 7 bands, in the file's order."""

GAUSS_SPHERE_NODES: int = 48
"""Gauss nodes in z of the check sphere of section 4 (2 * 48^2 = 4,608 directions)."""


# --------------------------------------------------------------------------- #
# Formatting and markdown
# --------------------------------------------------------------------------- #
def sig(value: float | None, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (plain for moderate sizes, else exponent)."""
    if value is None:
        return "-"
    value = float(value)
    if not math.isfinite(value):
        return str(value)
    if value == 0.0:
        return "0"
    if 1e-3 <= abs(value) < 1e5:
        return f"{value:.{digits}g}"
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
    """A GitHub markdown table, one string a line, with a blank line after it."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return lines + [""]


class Section:
    """Markdown of one report section (``## number. title``), built by its render function."""

    def __init__(self, number: int, title: str) -> None:
        self.number = number
        self.title = title
        self.lines: list[str] = [f"## {number}. {title}", ""]

    def text(self, *paragraphs: str) -> None:
        for paragraph in paragraphs:
            self.lines += [paragraph, ""]

    def table(self, header: list[str], rows: Iterable[Iterable[Any]]) -> None:
        self.lines += markdown_table(header, rows)

    def figure(self, name: str, caption: str) -> None:
        self.lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]

    def raw(self, lines: Iterable[str]) -> None:
        self.lines += list(lines) + [""]


# --------------------------------------------------------------------------- #
# The run's context
# --------------------------------------------------------------------------- #
@dataclass
class Context:
    """What every section shares: settings, the runtime, memoised data, figures and the summary."""

    plan: Plan
    out: Path
    jobs: int
    progress: bool
    sky: SkySH
    summary: list[tuple[str, str, str]] = field(default_factory=list)
    cache: dict[str, Any] = field(default_factory=dict)
    figures: list[str] = field(default_factory=list)

    def bar(self, total: int, desc: str) -> tqdm:
        """A progress bar on stderr (silent with ``--no-progress``)."""
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
        """``compute()`` once per run; later calls with the same key get the same object."""
        if key not in self.cache:
            self.cache[key] = compute()
        return self.cache[key]


# --------------------------------------------------------------------------- #
# Timing
# --------------------------------------------------------------------------- #
def interleaved_best(functions: Mapping[K, Callable[[], Any]], repeats: int, number: int) -> dict[K, float]:
    """Best mean seconds per call of every function, timed in interleaved rounds.

    One warm-up call each, then ``repeats`` rounds; a round times ``number``
    consecutive calls of every function in turn. Each function keeps its best
    round, so a burst of load on a shared machine spoils one round of every
    function rather than every round of some.
    """
    for function in functions.values():
        function()
    best = {key: math.inf for key in functions}
    for _ in range(repeats):
        for key, function in functions.items():
            start = time.perf_counter()
            for _ in range(number):
                function()
            best[key] = min(best[key], (time.perf_counter() - start) / number)
    return best


def best_time(function: Callable[[], Any], repeats: int, number: int) -> float:
    """Best mean seconds per call of one function (:func:`interleaved_best` of one)."""
    return interleaved_best({0: function}, repeats, number)[0]


def timed(function: Callable[[], Any]) -> tuple[Any, float]:
    """The result of one call and its wall time in seconds (no warm-up: a cold single call)."""
    start = time.perf_counter()
    result = function()
    return result, time.perf_counter() - start


# --------------------------------------------------------------------------- #
# Small computations over the package's public API
# --------------------------------------------------------------------------- #
def full_from_half(half: NDArray, bands: int) -> NDArray:
    """(..., bands (bands + 1) / 2, C) m >= 0 rows -> (..., bands^2, C) with zero m < 0 rows (sun at azimuth 0)."""
    k = bands * (bands + 1) // 2
    out = np.zeros(half.shape[:-2] + (bands * bands, half.shape[-1]))
    out[..., HALF_ROWS[:k], :] = half[..., :k, :]
    return out


def error_all(predicted: NDArray, truth: NDArray, denominator: NDArray, bands: int) -> dict[str, NDArray]:
    """:func:`skysh.table.fit.error_measures` over **all** ``bands^2`` coefficients of full-layout arrays (P, K, 3).

    ``fit.error_measures`` sums the first ``b (b + 1) / 2`` rows of its input (the
    m >= 0 layout of a fit, whose m < 0 rows are zero). A projection by random
    sampling also errs in the m < 0 coefficients, so the full arrays, cut to
    ``bands^2`` rows, are passed with the smallest ``b`` whose ``b (b + 1) / 2``
    covers them: every coefficient of the first ``bands`` bands is summed.
    """
    k = bands * bands
    b = math.ceil((math.sqrt(8 * k + 1) - 1) / 2)
    return fit.error_measures(predicted[:, :k], truth[:, :k], denominator, b)


def gibbs_filter(coeffs: NDArray) -> NDArray:
    """Habel eq. 5 on full-layout SH (..., N^2, C): zonal rows times :func:`skysh.runtime.gibbs_factors` (as the runtime)."""
    bands = math.isqrt(coeffs.shape[-2])
    out = np.array(coeffs, dtype=np.float64)
    for degree, factor in enumerate(runtime.gibbs_factors(bands)):
        out[..., sh.index(degree, 0), :] *= factor
    return out


def mean_value(coeffs: NDArray) -> NDArray:
    """Mean over the sphere of SH (..., K, C): ``c_0 * Y00``, shape (..., C)."""
    return coeffs[..., 0, :] * Y00


def luminance_row() -> NDArray:
    """Y from linear sRGB: the second row of the inverse of the XYZ -> sRGB matrix of skysh.model.preetham."""
    return np.linalg.inv(preetham.rgb_from_xyz_matrix("sRGB"))[1]


def uniform_grid(shape: tuple[int, int]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Uniform (sun zenith, turbidity) grid over the fitted domain including its edges: flat arrays and axes."""
    zen = np.linspace(*SKY.x.interval, shape[0])
    tur = np.linspace(*SKY.y.interval, shape[1])
    a, b = np.meshgrid(zen, tur, indexing="ij")
    return a.ravel(), b.ravel(), zen, tur


def mean_upper_luminance(sun_zenith: float, turbidity: float) -> float:
    """The true sky's mean luminance over the upper hemisphere (cd/m^2), on the Gauss check sphere."""
    dirs, weights = sh.quadrature_rule(GAUSS_SPHERE_NODES)
    up = dirs[:, 2] > 0.0
    values = preetham.luminance(dirs[up], sun_zenith, 0.0, turbidity)
    return float(np.sum(weights[up] * values) / np.sum(weights[up]))


def pareto(x: NDArray, y: NDArray) -> NDArray[np.intp]:
    """Indices of the points not dominated in (smaller x, smaller y), sorted by x."""
    order = np.lexsort((y, x))
    running = np.minimum.accumulate(np.asarray(y, dtype=np.float64)[order])
    improves = np.concatenate([[True], running[1:] < running[:-1]])
    return order[improves].astype(np.intp)


def _log_interpolate(a0: float, a1: float, u: float) -> float:
    return math.exp(math.log(a0) + u * math.log(a1 / a0))


def cost_to_reach(times: NDArray, errors: NDArray, samples: NDArray, target: float) -> tuple[float, float, bool]:
    """Wall time and samples at which a convergence curve first reaches ``target``.

    Interpolated log-log between the bracketing measurements; beyond the last
    one, extrapolated along the slope of the last two (returned flag True);
    ``inf`` when that slope does not fall.
    """
    times, errors, samples = (np.asarray(a, dtype=np.float64) for a in (times, errors, samples))
    below = np.flatnonzero(errors <= target)
    if below.size and below[0] == 0:
        return float(times[0]), float(samples[0]), False
    if below.size:
        i = int(below[0])
        u = math.log(target / errors[i - 1]) / math.log(errors[i] / errors[i - 1])
        return _log_interpolate(times[i - 1], times[i], u), _log_interpolate(samples[i - 1], samples[i], u), False
    slope_t = math.log(errors[-1] / errors[-2]) / math.log(times[-1] / times[-2])
    slope_n = math.log(errors[-1] / errors[-2]) / math.log(samples[-1] / samples[-2])
    if slope_t >= 0.0 or slope_n >= 0.0:
        return math.inf, math.inf, True
    ratio = target / errors[-1]
    return float(times[-1] * ratio ** (1.0 / slope_t)), float(samples[-1] * ratio ** (1.0 / slope_n)), True


# --------------------------------------------------------------------------- #
# Figures
# --------------------------------------------------------------------------- #
def style_axes(ax: plt.Axes, xlabel: str, ylabel: str, title: str, *, xlog: bool = False, ylog: bool = False,
               legend: dict[str, Any] | None = None) -> None:
    """Labels, title, log scales, a light major grid and (with ``legend`` keyword arguments) a legend."""
    if xlog:
        ax.set_xscale("log")
    if ylog:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="major", alpha=0.3)
    if legend is not None:
        ax.legend(**legend)


def cell_edges(values: NDArray) -> NDArray:
    """Cell edges around uniformly spaced centres (for pcolormesh)."""
    values = np.asarray(values, dtype=np.float64)
    step = values[1] - values[0] if values.size > 1 else 1.0
    return np.concatenate([values - 0.5 * step, values[-1:] + 0.5 * step])


def heatmap(ax: plt.Axes, axes: tuple[NDArray, NDArray], values: NDArray, title: str, label: str,
            norm: Any = None, cmap: str = "viridis", marks: NDArray | None = None) -> None:
    """A (sun zenith, turbidity) heatmap with a colour bar; ``marks`` flags cells with an x."""
    zen, tur = axes
    mesh = ax.pcolormesh(cell_edges(np.degrees(zen)), cell_edges(tur), values.T, norm=norm, cmap=cmap, shading="flat")
    plt.colorbar(mesh, ax=ax, label=label)
    if marks is not None and marks.any():
        a, b = np.meshgrid(np.degrees(zen), tur, indexing="ij")
        ax.plot(a[marks], b[marks], "x", color="white", markersize=5, label="L_min floored")
        ax.legend(loc="upper left", fontsize=8, framealpha=0.6)
    ax.set_xlabel("sun zenith angle (deg)")
    ax.set_ylabel("turbidity (dimensionless)")
    ax.set_title(title)
