#!/usr/bin/env python
"""
Issue 18: the best non-negative 3-band irradiance of the sky, measured.

Prints, from the package's own code (:mod:`skysh.table.irradiance_fit`):

1.  the convergence of the true irradiance in the projection's bands and nodes;
2.  over 42 skies (sun zenith 0-90 degrees, 1-degree steps near the horizon; turbidity
    2.5, 4, 6) against the true irradiance (64 bands) on 12,168 normals: the worst
    error (over normals and RGB, relative to each channel's mean irradiance; worst
    sky / median sky), the lowest value (exact minimum over the sphere,
    :func:`skysh.post.dering.exact_min`), and the chromaticity error (CIE 1976 u'v'
    distance per normal) of every method;
3.  how well each constrained optimum tabulates: fitted over the 48 x 24 Chebyshev
    grid with the sky table's polynomial (13, 7), its held-out fit error (exact
    optima at held-out points) and its exact minimum at >= 10^4 held-out points;

and writes ``irradiance_error_vs_zenith.png`` (error and chromaticity error against
the sun zenith per method). Expensive results are cached under ``--out``/cache.

    python tools/irradiance_study.py --out build/irradiance_study --workers 2
    python tools/irradiance_study.py --out /tmp/irr --quick        # small grid, few skies

The functions are also the error report's section 11 (``tools/report/s11_irradiance_table.py``):
:func:`sky_points`, :class:`Evaluator` (truth and measures), :func:`method_coefficients`
(every method of the issue's table), :func:`continuous_dering`, :func:`grid_solution`,
:func:`fit_grid`, :func:`nonnegative_check`, :func:`runtime_has_irradiance_table`,
:func:`row_cells` and :func:`chart_figure`.
"""

from __future__ import annotations

import argparse
import inspect
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one BLAS thread per process (see tools/fit_sky.py)

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from skysh.post.dering import LINEAR_ATTENUATION, SEED_WINDOW_SIZES, dering, exact_min, sinc4_window  # noqa: E402
from skysh.sh import basis as sh  # noqa: E402
from skysh.sh import minimum as shmin  # noqa: E402
from skysh.table import fit  # noqa: E402
from skysh.table import irradiance_fit as irf  # noqa: E402

Log = Callable[[str], None]
Mapper = Callable[[Callable, Iterable], Iterable]

SKY_ZENITHS_DEG: tuple[float, ...] = (0, 15, 30, 45, 60, 70, 75, 80, 85, 86, 87, 88, 89, 90)
"""Sun zenith angles of the study's skies, degrees: 1-degree steps next to the horizon."""
SKY_TURBIDITIES: tuple[float, ...] = (2.5, 4.0, 6.0)
"""Turbidities of the study's skies (the fitted domain's ends and its middle)."""
STUDY_TRUTH_BANDS: int = 64
"""Bands of the truth the study measures against (convergence table: section 1)."""
EVAL_THETA_NODES: int = 78
"""Gauss nodes in z of the evaluation normals: 2 x 78^2 = 12,168 normals (sh.quadrature_rule)."""
CHROMA_FLOOR: float = irf.CHROMA_FLOOR
"""u'v' is measured where the true luminance irradiance is at least this fraction of its
mean (the colour constraint's floor)."""
DEGREES: tuple[int, int] = (13, 7)
"""Polynomial degrees of the tabulation: the sky table's (data/preetham_sh.npz)."""
GRID: tuple[int, int] = (48, 24)
"""Chebyshev grid of the tabulation: the sky table's."""
HELD_OUT_SOLVES: int = 128
"""Random held-out points (plus corners and 8 per edge) solved exactly for the fit error."""
NONNEG_POINTS: int = 10_000
"""Random held-out points (plus corners and 500 per edge) for the exact-minimum check."""
NONNEG_PER_EDGE: int = 500
"""Held-out points per domain edge of the exact-minimum check."""
SEED: int = 2018
"""Seed of the held-out points (different from the sky table's 2008)."""
NONNEG_SEED: int = SEED + 7
"""Seed of the exact-minimum check's points."""
NEGATIVE_TOL: float = 1e-8
"""A minimum above -1e-8 of the mean counts as non-negative: the solver's feasibility
tolerance (1e-9, on the scaled problem) plus rounding, far below any visible value."""
DEFAULT_CACHE: Path = ROOT / "build" / "irradiance_study" / "cache"
"""The study's cache directory (``--out build/irradiance_study``); ``full`` and ``quick`` below it."""
BASIS_CHUNK: int = 2048
"""Normals per block when the 64-band basis is evaluated (2048 x 4096 floats: 64 MB)."""
ISSUE_OBJECTIVES: tuple[irf.Objective, ...] = (
    irf.Objective("l2"), irf.Objective("minimax"), irf.Objective("minimax_free"), irf.RECOMMENDED,
)
"""The optima of issue 18's table (L2 and minimax subject to f >= 0, minimax unconstrained) and the
recommended objective (blend with u'v' <= 0.01 and a 0.1% margin)."""
PLAIN: str = "plain projection (L2-optimal, unconstrained)"
"""Name of the first 9 coefficients of the truth (the L2-optimal 3-band irradiance)."""
RUNTIME_TABLE_OPTION: str = "irradiance_table"
"""The runtime's keyword choosing the tabulated irradiance (True) or the windowed pipeline (False)."""
FILE_TABLE: str = "irradiance"
"""Name of the tabulated irradiance in the coefficient file's tables."""
DERING_BISECTION_STEPS: int = 60
"""Bisection steps in log w over [5.6, 1e4] of :func:`continuous_dering`: the bracket ends
7.4 / 2^60 apart in log w, far below any change of the window."""
LARGEST_WINDOW: float = 1e4
"""Upper end of the window sizes bisected by :func:`continuous_dering` (sinc^4 at l = 2 is 1 - 5e-7)."""
_L_OF: NDArray[np.intp] = np.repeat(np.arange(3), 2 * np.arange(3) + 1)
"""Band l of each of the 9 coefficients."""


def progress(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def pct(x: float, digits: int = 3) -> str:
    return f"{100.0 * x:.{digits}g}%"


def cached(path: Path | None, compute: Callable[[], dict[str, NDArray]]) -> dict[str, NDArray]:
    """Load ``path`` (npz) if it exists, else compute, save (unless ``path`` is None) and return."""
    if path is not None and path.exists():
        with np.load(path) as data:
            return {k: data[k] for k in data.files}
    result = compute()
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(path, **result)  # type: ignore[arg-type]  # numpy stub: the first keyword is allow_pickle
    return result


def sky_points(zeniths_deg: Iterable[float] = SKY_ZENITHS_DEG,
               turbidities: Iterable[float] = SKY_TURBIDITIES) -> list[tuple[float, float]]:
    """(sun zenith in radians, turbidity) of every study sky, zenith-major."""
    tu = tuple(turbidities)
    return [(math.radians(z), t) for z in zeniths_deg for t in tu]


def sky_arrays(skies: list[tuple[float, float]]) -> tuple[NDArray, NDArray]:
    """The skies as two (S,) arrays: sun zenith (radians) and turbidity."""
    ts, tu = zip(*skies)
    return np.array(ts, dtype=np.float64), np.array(tu, dtype=np.float64)


def truth_point(job: tuple[float, float, int, int | None]) -> NDArray:
    """The true irradiance (bands^2, 3) of one (sun zenith, turbidity, bands, zenith nodes per panel or None for
    the projection's default); top level, for process pools."""
    ts, tu, bands, nodes = job
    return irf.true_irradiance(ts, tu, bands, nodes)


def m_nonnegative_rows(bands: int) -> NDArray[np.intp]:
    """Flat indices of the m >= 0 coefficients of ``bands`` bands (the others are zero: sun at azimuth 0)."""
    return np.array([i for i in range(bands * bands) if sh.lm(i)[1] >= 0], dtype=np.intp)


class Evaluator:
    """The evaluation normals, the skies' true irradiance (coefficients and values) and the measures."""

    def __init__(self, skies: list[tuple[float, float]], cache: Path | None = None, truth_bands: int = STUDY_TRUTH_BANDS,
                 theta_nodes: int = EVAL_THETA_NODES, mapper: Mapper = map, log: Log = progress,
                 truth_nodes: int | None = None) -> None:
        self.normals, self.weights = sh.quadrature_rule(theta_nodes)
        self.skies = list(skies)
        self.truth_bands, self.truth_nodes = truth_bands, truth_nodes
        self.y9 = sh.basis(self.normals, 3)
        suffix = "" if theta_nodes == EVAL_THETA_NODES else f"_N{theta_nodes}"
        suffix += "" if truth_nodes is None else f"_Q{truth_nodes}"
        path = None if cache is None else cache / f"skies_{len(skies)}_B{truth_bands}{suffix}.npz"
        self.truth = cached(path, lambda: self.compute_truth(mapper, log))
        self.mean = irf.Y00 * self.truth["coeffs"][:, 0, :]  # (S, 3) true mean irradiance

    def values(self, coeffs: NDArray) -> NDArray:
        """Any-band coefficients (K, 3) or (S, K, 3) with zero m < 0 rows at the normals: (M, 3) or (S, M, 3)."""
        c = np.asarray(coeffs, dtype=np.float64)
        single = c.ndim == 2
        c = c[None] if single else c
        bands = math.isqrt(c.shape[1])
        rows = m_nonnegative_rows(bands)
        flat = np.moveaxis(c[:, rows], 1, 0).reshape(rows.size, -1)  # (K', S * 3)
        out = np.empty((self.normals.shape[0], flat.shape[1]))
        for start in range(0, self.normals.shape[0], BASIS_CHUNK):
            block = self.normals[start : start + BASIS_CHUNK]
            out[start : start + BASIS_CHUNK] = sh.basis(block, bands)[:, rows] @ flat
        out = out.reshape(-1, c.shape[0], 3).transpose(1, 0, 2)
        return out[0] if single else out

    def compute_truth(self, mapper: Mapper, log: Log) -> dict[str, NDArray]:
        """The skies' true irradiance coefficients (S, B^2, 3) and values at the normals (S, M, 3)."""
        coeffs = []
        jobs = [(ts, tu, self.truth_bands, self.truth_nodes) for ts, tu in self.skies]
        for k, c in enumerate(mapper(truth_point, jobs)):
            log(f"truth {k + 1}/{len(self.skies)}")
            coeffs.append(c)
        stacked = np.stack(coeffs)
        return {"coeffs": stacked, "values": self.values(stacked)}

    def measure(self, coeffs: NDArray) -> dict[str, NDArray]:
        """Per sky: worst relative error, exact minimum of the mean, worst and median u'v' distance."""
        rec = np.einsum("mk,skc->smc", self.y9, coeffs)
        truth = self.truth["values"]
        error = np.max(np.abs(rec - truth) / self.mean[:, None, :], axis=(1, 2))
        lowest = np.min(exact_min(coeffs) / self.mean, axis=1)
        uv_worst, uv_median, undefined = chroma(rec, truth, self.mean)
        return {"error": error, "lowest": lowest, "uv_worst": uv_worst, "uv_median": uv_median, "undefined": undefined}


def chroma(rec: NDArray, truth: NDArray, mean: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Per sky: worst and median CIE 1976 u'v' distance over normals lit above CHROMA_FLOOR, undefined count."""
    import colour

    space = colour.RGB_COLOURSPACES["sRGB"]

    def uv(rgb: NDArray) -> tuple[NDArray, NDArray]:
        xyz = colour.RGB_to_XYZ(rgb, space, illuminant=None, chromatic_adaptation_transform=None)
        return colour.xy_to_Luv_uv(colour.XYZ_to_xy(xyz)), np.sum(xyz, axis=-1) > 0.0

    y_row = np.asarray(space.matrix_RGB_to_XYZ)[1]
    lit = (truth @ y_row) >= CHROMA_FLOOR * (mean @ y_row)[:, None]
    uv_true, _ = uv(truth)
    uv_rec, defined = uv(rec)
    distance = np.linalg.norm(uv_rec - uv_true, axis=-1)
    distance = np.where(defined, distance, np.inf)
    worst = np.array([d[m].max() for d, m in zip(distance, lit)])
    median = np.array([np.median(d[m]) for d, m in zip(distance, lit)])
    undefined = np.sum(lit & ~defined, axis=1)
    return worst, median, undefined


def section_convergence(ev: Evaluator) -> None:
    """Section 1: max |E_B - E_64| / mean over the normals, the tail beyond 64 bands, and the quadrature nodes."""
    print("## 1. Convergence of the true irradiance\n")
    print("max over the 12,168 normals and RGB of |E_B - E_64| / mean (E_64: 64 bands, 64 nodes per panel):\n")
    bands = (16, 24, 32, 48)
    print("| sun zenith | T | " + " | ".join(f"B = {b}" for b in bands)
          + " | rate p (16 -> 24) | tail beyond 64 (extrapolated) | B = 32, 40 nodes vs 64 | B = 64, 96 nodes vs 64 |")
    print("|---|---|" + "---|" * (len(bands) + 4))
    for zen, tu in ((0, 2.5), (60, 4.0), (85, 2.5), (90, 2.5), (90, 6.0)):
        ts = math.radians(zen)
        ref = irf.true_irradiance(ts, tu, 64, None)
        ref_v = ev.values(ref)
        mean = irf.Y00 * ref[0]
        diffs = [float(np.max(np.abs(ev.values(ref[: b * b]) - ref_v) / mean)) for b in bands]
        rate = math.log(diffs[0] / diffs[1]) / math.log(24 / 16)  # e(B) ~ B^-p, e(64) small against e(16), e(24)
        tail = diffs[1] * (24 / 64) ** rate
        nodes32 = np.max(np.abs(ev.values(irf.true_irradiance(ts, tu, 32, 40)) - ev.values(ref[:1024])) / mean)
        nodes64 = np.max(np.abs(ev.values(irf.true_irradiance(ts, tu, 64, 96)) - ref_v) / mean)
        print(f"| {zen} | {tu:g} | " + " | ".join(pct(d) for d in diffs)
              + f" | {rate:.2f} | {pct(tail, 2)} | {nodes32:.1e} | {nodes64:.1e} |")
    print("\nE_B is the 64-band projection truncated at B bands; the worst normal is next to the nadir. The tail "
          "beyond 64 bands is e(24) (24 / 64)^p with the rate p of the 16 -> 24 step.\n")


# --------------------------------------------------------------------------- #
# The methods
# --------------------------------------------------------------------------- #
def runtime_has_option(sky: Any) -> bool:
    """Whether ``sky.coefficients`` takes :data:`RUNTIME_TABLE_OPTION` (a runtime that knows the tabulated irradiance)."""
    return RUNTIME_TABLE_OPTION in inspect.signature(sky.coefficients).parameters


def runtime_has_irradiance_table(sky: Any) -> bool:
    """Whether ``sky`` (a :class:`skysh.SkySH`) evaluates the tabulated irradiance: the option and the file's table."""
    return runtime_has_option(sky) and FILE_TABLE in sky.table.tables


def runtime_coefficients(sky: Any, skies: list[tuple[float, float]], gibbs: bool) -> NDArray:
    """The runtime's windowed 3-band irradiance (deringed; never the table) at the skies: (S, 9, 3)."""
    ts, tu = sky_arrays(skies)
    options = {RUNTIME_TABLE_OPTION: False} if runtime_has_option(sky) else {}
    return sky.coefficients(ts, tu, 0.0, bands=3, irradiance=True, gibbs=gibbs, dering=True, **options)


def runtime_tabulated(sky: Any, sun_zenith: NDArray, turbidity: NDArray) -> NDArray:
    """The runtime's tabulated 3-band irradiance at (P,) points: (P, 9, 3) (needs :func:`runtime_has_irradiance_table`)."""
    return sky.coefficients(sun_zenith, turbidity, 0.0, bands=3, irradiance=True, **{RUNTIME_TABLE_OPTION: True})


def continuous_window(size: NDArray) -> NDArray:
    """(S, 3) factors of eq. (6) at window sizes (S,) with the linear ramp of :func:`skysh.post.dering.window_table`.

    Band 1 is scaled by ``1 - (1 - a) (1 - s2(w)) / (1 - s2(5.6))`` with ``a`` =
    :data:`skysh.post.dering.LINEAR_ATTENUATION`: the table's rows for w in its sizes, any w in between.
    """
    x = np.arange(3) / np.asarray(size, dtype=np.float64)[:, None]
    rows = np.where(x < 1.0, np.sinc(x) ** 4, 0.0)
    last = sinc4_window(SEED_WINDOW_SIZES[-1], 3)
    rows[:, 1] *= 1.0 - (1.0 - LINEAR_ATTENUATION) * (1.0 - rows[:, 2]) / (1.0 - last[2])
    return rows


def continuous_dering(sky: Any, skies: list[tuple[float, float]], steps: int = DERING_BISECTION_STEPS) -> NDArray:
    """The runtime's sky (gibbs=False) deringed with the least window of a *continuous* size: irradiance (S, 9, 3).

    The runtime takes the least position along the table's 7 rows (linear between them) that
    makes the irradiance non-negative; here the size w is bisected in [5.6, 1e4] on the
    exact minimum (one window for all channels, as the runtime): a search over the
    window's size instead of the table's path.
    """
    ts, tu = sky_arrays(skies)
    raw = sky.coefficients(ts, tu, 0.0, bands=3, gibbs=False, dering=False)

    def irradiance(size: NDArray) -> NDArray:
        return raw * continuous_window(size)[:, _L_OF, None] * irf.LOBE[:, None]

    def nonnegative(size: NDArray) -> NDArray:
        return np.min(exact_min(irradiance(size)), axis=-1) >= 0.0

    lo, hi = np.full(len(skies), SEED_WINDOW_SIZES[-1]), np.full(len(skies), LARGEST_WINDOW)
    for _ in range(steps):
        mid = np.sqrt(lo * hi)
        good = nonnegative(mid)
        lo, hi = np.where(good, mid, lo), np.where(good, hi, mid)
    return irradiance(np.where(nonnegative(np.full(len(skies), np.inf)), np.inf, lo))


def row_dering(sky: Any, skies: list[tuple[float, float]]) -> NDArray:
    """The runtime's sky (gibbs=False) deringed with the least whole row of the table
    (``dering(method="table")``, the default until issue 25): irradiance (S, 9, 3)."""
    ts, tu = sky_arrays(skies)
    return dering(sky.coefficients(ts, tu, 0.0, bands=3, gibbs=False, dering=False), method="table")[0] * irf.LOBE[:, None]


def solve_job(job: tuple[NDArray, irf.Objective]) -> NDArray:
    """One sky's constrained optimum (9, 3) from its truth; top level, for process pools."""
    truth, objective = job
    return irf.constrained_coefficients(truth, objective)[0]


def solve_skies(ev: Evaluator, objective: irf.Objective, mapper: Mapper = map) -> NDArray:
    """The optimum of ``objective`` at every sky of ``ev`` against its truth: (S, 9, 3)."""
    return np.stack(list(mapper(solve_job, [(truth, objective) for truth in ev.truth["coeffs"]])))


def objective_name(obj: irf.Objective) -> str:
    """A short label: method, margin, weight (blend), chroma bound (and the optimisation sphere if not the default)."""
    name = {"l2": "L2-optimal", "minimax": "minimax", "lp": f"L_{irf.LP_EXPONENT}", "minimax_free": "minimax",
            "blend": f"blend (worst + {obj.weight:g} RMS^2)"}[obj.method]
    if obj.method == "minimax_free":
        name += ", unconstrained (the floor of three bands)"
    else:
        name += " subject to non-negative"
        if obj.margin:
            name += f" (margin {pct(obj.margin, 2)})"
        if obj.chroma is not None:
            name += f" and u'v' <= {obj.chroma:g}"
    if obj.normals != irf.OPTIMISATION_NORMALS and obj.needs_normals:
        name += f" [{obj.normals}-point sphere]"
    return name


def objective_tag(obj: irf.Objective) -> str:
    return f"{obj.method}_m{obj.margin:g}_w{obj.weight:g}_c{obj.chroma if obj.chroma is not None else 0:g}_n{obj.normals}"


def runtime_name(gibbs: bool) -> str:
    return f"runtime gibbs={gibbs}, dering=True"


def method_coefficients(ev: Evaluator, objectives: Iterable[irf.Objective], sky: Any, cache: Path | None = None,
                        mapper: Mapper = map, log: Log = progress) -> dict[str, NDArray]:
    """Coefficients (S, 9, 3) of every method: the plain projection, the runtime's pipeline (gibbs off, on), the optima.

    Each objective's solves are cached under ``cache`` (None: not cached).
    """
    methods = {PLAIN: ev.truth["coeffs"][:, :9]}
    for gibbs in (False, True):
        methods[runtime_name(gibbs)] = runtime_coefficients(sky, ev.skies, gibbs)
    for obj in objectives:
        def solve(obj: irf.Objective = obj) -> dict[str, NDArray]:
            log(f"{len(ev.skies)} skies: {objective_name(obj)}")
            return {"coeffs": solve_skies(ev, obj, mapper)}

        path = None if cache is None else cache / f"skies{len(ev.skies)}_{objective_tag(obj)}.npz"
        methods[objective_name(obj)] = cached(path, solve)["coeffs"]
    return methods


def measure_methods(ev: Evaluator, methods: dict[str, NDArray]) -> dict[str, dict[str, NDArray]]:
    """:meth:`Evaluator.measure` of every method."""
    return {name: ev.measure(coeffs) for name, coeffs in methods.items()}


TABLE_HEADER: tuple[str, ...] = ("worst error (worst / median sky)", "lowest value",
                                 "u'v' worst normal (worst / median sky)", "u'v' median normal (worst / median sky)")
"""Columns of :func:`row_cells`."""


def row_cells(r: dict[str, NDArray]) -> list[str]:
    """The table cells of one method's measures (:meth:`Evaluator.measure`), as :data:`TABLE_HEADER`."""
    negative = int(np.sum(r["lowest"] < -NEGATIVE_TOL))
    low = (f"negative on {negative} of {r['lowest'].size} skies (down to {pct(r['lowest'].min())} of the mean)"
           if negative else f"non-negative (lowest {pct(r['lowest'].min(), 2)} of the mean)")
    extra = f", {int(r['undefined'].sum())} undefined" if r["undefined"].sum() else ""
    return [f"{pct(r['error'].max())} / {pct(np.median(r['error']))}", low,
            f"{r['uv_worst'].max():.4f} / {np.median(r['uv_worst']):.4f}{extra}",
            f"{r['uv_median'].max():.5f} / {np.median(r['uv_median']):.5f}"]


def table_rows(ev: Evaluator, methods: dict[str, NDArray]) -> dict[str, dict[str, NDArray]]:
    """Measure every method and print the markdown table; returns the measures."""
    results = measure_methods(ev, methods)
    print("| 3-band irradiance | " + " | ".join(TABLE_HEADER) + " |")
    print("|---|---|---|---|---|")
    for name, r in results.items():
        print(f"| {name} | " + " | ".join(row_cells(r)) + " |")
    return results


# --------------------------------------------------------------------------- #
# Tabulation
# --------------------------------------------------------------------------- #
def grid_axes(grid: tuple[int, int]) -> tuple[NDArray, NDArray]:
    """The 1-D axes of the sky table's Chebyshev grid (:func:`skysh.table.fit.chebyshev_grid`)."""
    ts, tu = fit.chebyshev_grid(grid)
    return ts.reshape(grid)[:, 0], tu.reshape(grid)[0]


def held_out(count: int, per_edge: int, seed: int) -> tuple[NDArray, NDArray]:
    ts, tu = fit.held_out_points(count, seed)
    ets, etu = fit.edge_points(per_edge, seed + 1)
    return np.concatenate([ts, ets]), np.concatenate([tu, etu])


def solve_points(ts: NDArray, tu: NDArray, objective: irf.Objective, pool: Any) -> NDArray:
    jobs = [(float(a), float(b), objective) for a, b in zip(ts, tu)]
    results = pool.map(irf.constrained_point, jobs, chunksize=4) if pool is not None else map(irf.constrained_point, jobs)
    return np.stack([r[0] for r in results])


def max_abs_difference(a: NDArray, b: NDArray, mean: NDArray) -> NDArray:
    """max over the sphere of |f_a - f_b| / mean, exactly (two exact minima), per point: (P, 9, 3) -> (P,)."""
    d = a - b
    return np.max(np.maximum(-exact_min(d), -exact_min(-d)) / mean, axis=1)


def grid_path(obj: irf.Objective, grid: tuple[int, int], cache: Path) -> Path:
    """The cache file of the grid solve of ``obj`` over ``grid``."""
    return cache / f"grid_{objective_tag(obj)}_{grid[0]}x{grid[1]}.npz"


def grid_solution(obj: irf.Objective, grid: tuple[int, int], cache: Path | None, mapper: Mapper = map,
                  log: Log = progress) -> dict[str, NDArray]:
    """The optimum over the Chebyshev ``grid`` (cached under ``cache`` unless None): coeffs (n_ts, n_t, 9, 3),
    minimum (n_ts, n_t, 3), wall seconds and CPU seconds (NaN when solved in worker processes)."""
    ts_axis, tu_axis = grid_axes(grid)

    def solve() -> dict[str, NDArray]:
        log(f"grid {grid} {objective_tag(obj)}")
        start, cpu = time.perf_counter(), time.process_time()

        def counted(f: Callable, jobs: Iterable) -> Iterator:
            jobs = list(jobs)
            for k, result in enumerate(mapper(f, jobs)):
                if (k + 1) % 96 == 0:
                    log(f"  {k + 1} / {len(jobs)}")
                yield result

        coeffs, minimum = irf.constrained_irradiance_grid(ts_axis, tu_axis, obj, counted)
        return {"coeffs": coeffs, "minimum": minimum, "seconds": np.array(time.perf_counter() - start),
                "cpu": np.array(time.process_time() - cpu if mapper is map else np.nan)}

    return cached(None if cache is None else grid_path(obj, grid, cache), solve)


def fit_grid(g: dict[str, NDArray], grid: tuple[int, int], degrees: tuple[int, int] = DEGREES) -> tuple[NDArray, NDArray, float]:
    """The grid solve ``g`` (:func:`grid_solution`) fitted as the sky table: (table, degrees, condition)."""
    ts_g, tu_g = fit.chebyshev_grid(grid)
    return irf.fit_irradiance_table(ts_g, tu_g, g["coeffs"].reshape(-1, 9, 3), degrees)


def nonnegative_check(evaluate: Callable[[NDArray, NDArray], NDArray], count: int = NONNEG_POINTS,
                      per_edge: int = NONNEG_PER_EDGE, seed: int = NONNEG_SEED) -> dict[str, Any]:
    """Exact minimum / mean of tabulated irradiance ``evaluate(ts, tu) -> (P, 9, 3)`` at held-out points.

    ``count`` random points, the 4 corners and ``per_edge`` points per edge (seeded);
    returns the points, the coefficients there and the minimum per point (worst channel).
    """
    ts, tu = held_out(count, per_edge, seed)
    dense = evaluate(ts, tu)
    minimum = np.min(exact_min(dense) / (irf.Y00 * dense[:, 0]), axis=1)
    return {"ts": ts, "tu": tu, "coeffs": dense, "minimum": minimum}


CROSS_CHECK_DIRECTIONS: int = 4096
"""Fibonacci directions of the sampled minimum that :func:`cross_check_minimum` sets against the exact one."""


def cross_check_minimum(coeffs: NDArray, minimum: NDArray) -> tuple[float, float]:
    """(lowest, largest) of (sampled minimum - exact minimum) / mean over the points, the sampled minimum over
    :data:`CROSS_CHECK_DIRECTIONS` directions: never negative if ``minimum`` (:func:`skysh.sh.minimum.exact_min`) is
    a true lower bound, and small (the sample's covering radius, squared) if it is tight."""
    dense = np.einsum("dk,nkc->ndc", sh.basis(shmin.fibonacci(CROSS_CHECK_DIRECTIONS), 3), coeffs)
    sampled = np.min(np.min(dense, axis=1) / (irf.Y00 * coeffs[:, 0]), axis=1)
    return float(np.min(sampled - minimum)), float(np.max(sampled - minimum))


def tabulate(obj: irf.Objective, grid: tuple[int, int], cache: Path, pool: Any, ev: Evaluator,
             solves: int) -> dict[str, Any]:
    """Grid solve (cached, timed), fit, held-out fit error, exact minimum at >= 10^4 points, the study's skies."""
    tag = objective_tag(obj)
    g = grid_solution(obj, grid, cache, map if pool is None else lambda f, jobs: pool.map(f, jobs, chunksize=4))
    table, degrees, condition = fit_grid(g, grid)
    hts, htu = held_out(solves, 8, SEED)

    def held_out_solve() -> dict[str, NDArray]:
        progress(f"held-out {hts.size} {tag}")
        return {"coeffs": solve_points(hts, htu, obj, pool)}

    exact = cached(cache / f"heldout_{tag}_{hts.size}.npz", held_out_solve)["coeffs"]
    tab = irf.evaluate_irradiance_table(table, degrees, hts, htu)
    fit_error = max_abs_difference(tab, exact, irf.Y00 * exact[:, 0])
    check = nonnegative_check(lambda ts, tu: irf.evaluate_irradiance_table(table, degrees, ts, tu))
    worst = int(np.argmin(check["minimum"]))
    on_skies = irf.evaluate_irradiance_table(table, degrees, *sky_arrays(ev.skies))
    return {"tag": tag, "seconds": float(g["seconds"]), "cpu": float(g.get("cpu", np.nan)), "condition": condition,
            "fit_error": fit_error, "grid_min": float(g["minimum"].min()), "nonneg_points": int(check["ts"].size),
            "minimum": check["minimum"], "worst_at": (float(check["ts"][worst]), float(check["tu"][worst])),
            "skies": on_skies, "table": table, "degrees": degrees,
            "agreement": cross_check_minimum(check["coeffs"], check["minimum"])}


def section_tabulation(ev: Evaluator, tabulated: dict[irf.Objective, dict[str, Any]], grid: tuple[int, int],
                       solves: int) -> None:
    print(f"## 3. Tabulation: grid {grid[0]} x {grid[1]} (Chebyshev nodes), degrees {DEGREES}, the sky table's form\n")
    print("Fit error: max over the sphere (exact) of |tabulated - exact optimum| / mean, at "
          f"{solves} random held-out points + corners + 32 edge points (seed {SEED}); minimum: exact minimum of the "
          f"tabulated irradiance / its mean at {NONNEG_POINTS} random + 4 corners + 2,000 edge points (seed {NONNEG_SEED}); "
          f"errors of the tabulated result on the {len(ev.skies)} skies as in section 2.\n")
    agreement = [r["agreement"] for r in tabulated.values()]
    if agreement:
        print(f"The tabulated minima (`skysh.sh.minimum.exact_min`) lie below a {CROSS_CHECK_DIRECTIONS}-direction sampled "
              f"minimum by {min(a[0] for a in agreement):.1e} to {max(a[1] for a in agreement):.1e} of the mean "
              "(never above it: a true lower bound).\n")
    print("| objective | grid solve: wall / CPU (1 process) | fit error worst / median | tabulated minimum (at) "
          "| points negative | worst error (worst / median sky) | u'v' worst normal (worst / median sky) |")
    print("|---|---|---|---|---|---|---|")
    for obj, r in tabulated.items():
        m = ev.measure(r["skies"])
        negative = int(np.sum(r["minimum"] < -NEGATIVE_TOL))
        cpu = f"{r['cpu']:.0f} s" if np.isfinite(r["cpu"]) else "not recorded"
        print(f"| {objective_name(obj)} | {r['seconds']:.0f} s / {cpu} | {pct(r['fit_error'].max())} / "
              f"{pct(np.median(r['fit_error']))} | {pct(r['minimum'].min())} ({math.degrees(r['worst_at'][0]):.2f} deg, "
              f"T {r['worst_at'][1]:.3f}) | {negative} of {r['nonneg_points']} | {pct(m['error'].max())} / "
              f"{pct(np.median(m['error']))} | {m['uv_worst'].max():.4f} / {np.median(m['uv_worst']):.4f} |")
    print()


# --------------------------------------------------------------------------- #
# Chart and command line
# --------------------------------------------------------------------------- #
def chart_figure(skies: list[tuple[float, float]], results: dict[str, dict[str, NDArray]], highlight: str = "",
                 title: str = "", bound: float | None = None) -> Any:
    """Figure: worst error and worst u'v' distance over turbidities against the sun zenith, per method (``highlight``
    bold; ``bound``, a fraction, drawn as a dotted line on the error panel)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter

    zen = np.array([math.degrees(ts) for ts, _ in skies])
    axis = np.unique(zen)
    turbidities = ", ".join(f"{t:g}" for t in sorted({t for _, t in skies}))
    fig, axes = plt.subplots(1, 2, figsize=(15, 7.5))
    colours = plt.get_cmap("tab20").colors  # type: ignore[attr-defined]  # a ListedColormap
    for k, (name, r) in enumerate(results.items()):
        style = {"color": colours[(2 * k) % 20 + (k // 10) % 2], "marker": "os^vDP*Xh<>p"[k % 12], "markersize": 4,
                 "linewidth": 1.3, "linestyle": "-" if k < 10 else "--"}
        if name == highlight:
            style.update(color="black", linewidth=2.6, linestyle="-")
        axes[0].plot(axis, [100.0 * r["error"][zen == z].max() for z in axis], label=name, **style)
        axes[1].plot(axis, [r["uv_worst"][zen == z].max() for z in axis], **style)
    if bound is not None:
        axes[0].axhline(100.0 * bound, color="grey", linestyle=":", linewidth=1.5, label=f"bound {pct(bound)}")
    axes[0].set_ylabel("worst irradiance error over normals and RGB (% of the channel's true mean)")
    axes[1].set_ylabel(f"worst CIE 1976 u'v' distance (unitless; normals lit >= {CHROMA_FLOOR:g} x mean)")
    for ax, name in ((axes[0], "Irradiance error against the sun zenith"),
                     (axes[1], "Chromaticity error against the sun zenith")):
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
        ax.set_xlabel(f"sun zenith angle (degrees); worst over turbidity {turbidities}")
        ax.set_title(name)
        ax.grid(True, which="both", alpha=0.3)
    fig.legend(loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(title or f"3-band irradiance against the true sky ({len(skies)} skies)")
    fig.tight_layout(rect=(0, 0.2, 1, 1))
    return fig


def chart(ev: Evaluator, results: dict[str, dict[str, NDArray]], path: Path, highlight: str = "") -> None:
    """:func:`chart_figure` of the study, saved as PNG."""
    import matplotlib.pyplot as plt

    fig = chart_figure(ev.skies, results, highlight, f"3-band irradiance against the true sky ({len(ev.skies)} skies, "
                       f"{ev.normals.shape[0]:,} normals, truth {ev.truth_bands} bands)")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


DEFAULT_OBJECTIVES: tuple[str, ...] = (
    "l2", "minimax", "lp", "blend:0:100", "l2:0:0:0.01", "minimax:0:0:0.01", "blend:0:100:0.01", "minimax_free",
)
"""The constrained (and unconstrained) optima of the study's table, as method[:margin[:weight[:chroma]]]."""

DEFAULT_TABULATE: tuple[str, ...] = ("l2", "l2:0.001", "minimax", "blend:0:100:0.01", "blend:0.001:100:0.01")
"""The optima tabulated by default."""


def parse_objective(text: str) -> irf.Objective:
    """method[:margin[:weight[:chroma]]] -> Objective (chroma 0 means none)."""
    parts = text.split(":")
    values = [float(p) for p in parts[1:]] + [0.0, irf.BLEND_WEIGHT, 0.0][len(parts) - 1 :]
    return irf.Objective(parts[0], values[0], values[1], values[2] or None)


def parse(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, required=True, help="directory of the chart and the cache")
    p.add_argument("--workers", type=int, default=1, help="processes for the grid solves (default 1)")
    p.add_argument("--quick", action="store_true", help="12 skies, a 12 x 6 grid, 16 held-out solves")
    p.add_argument("--objectives", nargs="*", default=list(DEFAULT_OBJECTIVES),
                   help="method[:margin[:weight[:chroma]]] optima for the table")
    p.add_argument("--tabulate", nargs="*", default=list(DEFAULT_TABULATE),
                   help="method[:margin[:weight[:chroma]]] optima to tabulate")
    p.add_argument("--skip-convergence", action="store_true")
    args = p.parse_args(argv)
    if not 1 <= args.workers <= 64:
        p.error(f"--workers must be in [1, 64], got {args.workers}")
    try:
        args.objectives = [parse_objective(t) for t in args.objectives]
        args.tabulate = [parse_objective(t) for t in args.tabulate]
    except ValueError as error:
        p.error(str(error))
    return args


def main(argv: list[str] | None = None) -> int:
    from skysh.runtime import SkySH

    args = parse(argv)
    zeniths, grid, solves = SKY_ZENITHS_DEG, GRID, HELD_OUT_SOLVES
    if args.quick:
        zeniths, grid, solves = (0, 60, 89, 90), (12, 6), 16
    skies = sky_points(zeniths)
    cache = args.out / "cache" / ("quick" if args.quick else "full")
    ev = Evaluator(skies, cache)
    methods = method_coefficients(ev, args.objectives, SkySH.load(), cache)
    pool = ProcessPoolExecutor(args.workers) if args.workers > 1 else None
    try:
        tabulated = {obj: tabulate(obj, grid, cache, pool, ev, solves) for obj in args.tabulate}
    finally:
        if pool is not None:
            pool.shutdown()
    for obj, r in tabulated.items():
        methods[f"tabulated: {objective_name(obj)}"] = r["skies"]
    if not args.skip_convergence:
        section_convergence(ev)
    print(f"## 2. {len(skies)} skies (sun zenith {', '.join(map(str, zeniths))} deg x turbidity "
          f"{', '.join(map(str, SKY_TURBIDITIES))}), 12,168 normals, truth 64 bands\n")
    print(f"u'v': distance to the truth's chromaticity per normal where the true luminance irradiance is >= "
          f"{CHROMA_FLOOR:g} x its mean; worst normal and median normal per sky. Lowest value: exact minimum over the "
          f"sphere (`skysh.post.dering.exact_min`) / the true mean (below -{NEGATIVE_TOL:g} counts as negative).\n")
    results = table_rows(ev, methods)
    print()
    if tabulated:
        section_tabulation(ev, tabulated, grid, solves)
    chart(ev, results, args.out / "irradiance_error_vs_zenith.png", f"tabulated: {objective_name(irf.RECOMMENDED)}")
    print(f"Chart: {args.out / 'irradiance_error_vs_zenith.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
