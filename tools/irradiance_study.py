#!/usr/bin/env python
"""
Issue 18: the best non-negative 3-band irradiance of the sky, measured.

Prints, from the package's own code (:mod:`skysh.irradiance_fit`):

1.  the convergence of the true irradiance in the projection's bands and nodes;
2.  over 42 skies (sun zenith 0-90 degrees, 1-degree steps near the horizon; turbidity
    2.5, 4, 6) against the true irradiance (64 bands) on 12,168 normals: the worst
    error (over normals and RGB, relative to each channel's mean irradiance; worst
    sky / median sky), the lowest value (exact minimum over the sphere), and the
    chromaticity error (CIE 1976 u'v' distance per normal) of every method;
3.  how well each constrained optimum tabulates: fitted over the 48 x 24 Chebyshev
    grid with the sky table's polynomial (13, 7), its held-out fit error (exact
    optima at held-out points) and its exact minimum at >= 10^4 held-out points;

and writes ``irradiance_error_vs_zenith.png`` (error and chromaticity error against
the sun zenith per method). Expensive results are cached under ``--out``/cache.

    python tools/irradiance_study.py --out build/irradiance_study --workers 2
    python tools/irradiance_study.py --out /tmp/irr --quick        # small grid, few skies
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
from typing import Any

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one BLAS thread per process (see tools/fit_sky.py)

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from skysh import fit, sh  # noqa: E402
from skysh import irradiance_fit as irf  # noqa: E402

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
SEED: int = 2018
"""Seed of the held-out points (different from the sky table's 2008)."""
NEGATIVE_TOL: float = 1e-8
"""A minimum above -1e-8 of the mean counts as non-negative: the solver's feasibility
tolerance (1e-9, on the scaled problem) plus rounding, far below any visible value."""


def progress(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def pct(x: float, digits: int = 3) -> str:
    return f"{100.0 * x:.{digits}g}%"


def cached(path: Path, compute: Callable[[], dict[str, NDArray]]) -> dict[str, NDArray]:
    """Load ``path`` (npz) if it exists, else compute, save and return."""
    if path.exists():
        with np.load(path) as data:
            return {k: data[k] for k in data.files}
    result = compute()
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, **result)
    return result


class Evaluator:
    """The evaluation normals, their 64-band half basis and the study's skies' truth."""

    def __init__(self, cache: Path, skies: list[tuple[float, float]]) -> None:
        self.normals, self.weights = sh.quadrature_rule(EVAL_THETA_NODES)
        self.skies = skies
        self.y9 = sh.basis(self.normals, 3)
        self.rows = np.array([i for i in range(STUDY_TRUTH_BANDS**2) if sh.lm(i)[1] >= 0])
        self.truth = cached(cache / f"skies_{len(skies)}_B{STUDY_TRUTH_BANDS}.npz", self._truth)
        self.mean = irf.Y00 * self.truth["coeffs"][:, 0, :]  # (S, 3) true mean irradiance

    def values(self, coeffs: NDArray) -> NDArray:
        """Any-band coefficients (K, 3) with zero m < 0 rows at the normals (M, 3), in chunks."""
        bands = math.isqrt(coeffs.shape[0])
        rows = np.array([i for i in range(bands * bands) if sh.lm(i)[1] >= 0])
        out = np.empty((self.normals.shape[0], 3))
        for start in range(0, self.normals.shape[0], 2048):
            out[start : start + 2048] = sh.basis(self.normals[start : start + 2048], bands)[:, rows] @ coeffs[rows]
        return out

    def _truth(self) -> dict[str, NDArray]:
        coeffs, values = [], []
        for k, (ts, tu) in enumerate(self.skies):
            progress(f"truth {k + 1}/{len(self.skies)}")
            c = irf.true_irradiance(ts, tu, STUDY_TRUTH_BANDS, None)
            coeffs.append(c)
            values.append(self.values(c))
        return {"coeffs": np.stack(coeffs), "values": np.stack(values)}

    def measure(self, coeffs: NDArray) -> dict[str, NDArray]:
        """Per sky: worst relative error, exact minimum of the mean, worst and median u'v' distance."""
        rec = np.einsum("mk,skc->smc", self.y9, coeffs)
        truth = self.truth["values"]
        error = np.max(np.abs(rec - truth) / self.mean[:, None, :], axis=(1, 2))
        lowest = np.min(irf.sphere_minimum(coeffs) / self.mean, axis=1)
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


def runtime_coefficients(skies: list[tuple[float, float]], gibbs: bool) -> NDArray | None:
    """The runtime's 3-band irradiance (deringed) at the skies, or None (with a note) if the runtime fails."""
    from skysh.runtime import SkySH

    try:
        sky = SkySH.load()
        return np.stack([sky.coefficients(ts, tu, 0.0, bands=3, irradiance=True, gibbs=gibbs, dering=True)
                         for ts, tu in skies])
    except Exception as error:  # (another session may be rebuilding the deringing: say so, keep going)
        print(f"(runtime gibbs={gibbs}, dering=True unavailable: {type(error).__name__}: {error})\n")
        return None


def solve_skies(ev: Evaluator, objective: irf.Objective) -> NDArray:
    return np.stack([irf.constrained_coefficients(truth, objective)[0] for truth in ev.truth["coeffs"]])


def objective_name(obj: irf.Objective) -> str:
    """A short label: method, margin, weight (blend), chroma bound."""
    name = {"l2": "L2-optimal", "minimax": "minimax", "lp": f"L_{irf.LP_EXPONENT}", "minimax_free": "minimax",
            "blend": f"blend (worst + {obj.weight:g} RMS^2)"}[obj.method]
    if obj.method == "minimax_free":
        return name + ", unconstrained (the floor of three bands)"
    name += " subject to non-negative"
    if obj.margin:
        name += f" (margin {pct(obj.margin, 2)})"
    if obj.chroma is not None:
        name += f" and u'v' <= {obj.chroma:g}"
    return name


def objective_tag(obj: irf.Objective) -> str:
    return f"{obj.method}_m{obj.margin:g}_w{obj.weight:g}_c{obj.chroma if obj.chroma is not None else 0:g}_n{obj.normals}"


def study_methods(ev: Evaluator, cache: Path, objectives: list[irf.Objective]) -> dict[str, NDArray]:
    """Coefficients (S, 9, 3) of every method of the table, each objective's solves cached."""
    methods = {"plain projection (L2-optimal, unconstrained)": ev.truth["coeffs"][:, :9]}
    for gibbs in (False, True):
        runtime = runtime_coefficients(ev.skies, gibbs)
        if runtime is not None:
            methods[f"runtime gibbs={gibbs}, dering=True"] = runtime
    for obj in objectives:
        def solve(obj: irf.Objective = obj) -> dict[str, NDArray]:
            progress(f"{len(ev.skies)} skies: {objective_name(obj)}")
            return {"coeffs": solve_skies(ev, obj)}

        methods[objective_name(obj)] = cached(cache / f"skies{len(ev.skies)}_{objective_tag(obj)}.npz", solve)["coeffs"]
    return methods


def table_rows(ev: Evaluator, methods: dict[str, NDArray]) -> dict[str, dict[str, NDArray]]:
    print("| 3-band irradiance | worst error (worst / median sky) | lowest value | u'v' worst normal (worst / median sky) "
          "| u'v' median normal (worst / median sky) |")
    print("|---|---|---|---|---|")
    results = {}
    for name, coeffs in methods.items():
        r = ev.measure(coeffs)
        results[name] = r
        negative = int(np.sum(r["lowest"] < -NEGATIVE_TOL))
        low = (f"negative on {negative} of {len(ev.skies)} skies (down to {pct(r['lowest'].min())} of the mean)"
               if negative else f"non-negative (lowest {pct(r['lowest'].min(), 2)} of the mean)")
        extra = f", {int(r['undefined'].sum())} undefined" if r["undefined"].sum() else ""
        print(f"| {name} | {pct(r['error'].max())} / {pct(np.median(r['error']))} | {low} | "
              f"{r['uv_worst'].max():.4f} / {np.median(r['uv_worst']):.4f}{extra} | "
              f"{r['uv_median'].max():.5f} / {np.median(r['uv_median']):.5f} |")
    return results


# --------------------------------------------------------------------------- #
# Tabulation
# --------------------------------------------------------------------------- #
def grid_axes(grid: tuple[int, int]) -> tuple[NDArray, NDArray]:
    """The 1-D axes of the sky table's Chebyshev grid (:func:`skysh.fit.chebyshev_grid`)."""
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
    return np.max(np.maximum(-irf.sphere_minimum(d), -irf.sphere_minimum(-d)) / mean, axis=1)


def cross_check_minimum(coeffs: NDArray, minimum: NDArray) -> float | None:
    """Largest |difference| (of the mean) to the deringing module's exact minimum, if it has one."""
    try:
        from skysh.dering import exact_min
    except ImportError:
        return None
    other = np.min(exact_min(coeffs) / (irf.Y00 * coeffs[:, 0]), axis=1)
    return float(np.max(np.abs(other - minimum)))


def tabulate(obj: irf.Objective, grid: tuple[int, int], cache: Path, pool: Any, ev: Evaluator,
             solves: int) -> dict[str, Any]:
    """Grid solve (cached, timed), fit, held-out fit error, exact minimum at >= 10^4 points, the study's skies."""
    tag = objective_tag(obj)
    ts_axis, tu_axis = grid_axes(grid)

    def grid_solve() -> dict[str, NDArray]:
        progress(f"grid {grid} {tag}")
        start, cpu = time.perf_counter(), time.process_time()
        def mapper(f: Callable, jobs: Any) -> Any:
            jobs = list(jobs)
            results = pool.map(f, jobs, chunksize=4) if pool is not None else map(f, jobs)
            for k, result in enumerate(results):
                if (k + 1) % 96 == 0:
                    progress(f"  {k + 1} / {len(jobs)}")
                yield result

        coeffs, minimum = irf.constrained_irradiance_grid(ts_axis, tu_axis, obj, mapper)
        return {"coeffs": coeffs, "minimum": minimum, "seconds": np.array(time.perf_counter() - start),
                "cpu": np.array(time.process_time() - cpu if pool is None else np.nan)}

    g = cached(cache / f"grid_{tag}_{grid[0]}x{grid[1]}.npz", grid_solve)
    ts_g, tu_g = fit.chebyshev_grid(grid)
    table, degrees, condition = irf.fit_irradiance_table(ts_g, tu_g, g["coeffs"].reshape(-1, 9, 3), DEGREES)
    hts, htu = held_out(solves, 8, SEED)

    def held_out_solve() -> dict[str, NDArray]:
        progress(f"held-out {hts.size} {tag}")
        return {"coeffs": solve_points(hts, htu, obj, pool)}

    exact = cached(cache / f"heldout_{tag}_{hts.size}.npz", held_out_solve)["coeffs"]
    tab = irf.evaluate_irradiance_table(table, degrees, hts, htu)
    fit_error = max_abs_difference(tab, exact, irf.Y00 * exact[:, 0])
    nts, ntu = held_out(NONNEG_POINTS, 500, SEED + 7)
    dense = irf.evaluate_irradiance_table(table, degrees, nts, ntu)
    minimum = np.min(irf.sphere_minimum(dense) / (irf.Y00 * dense[:, 0]), axis=1)
    agreement = cross_check_minimum(dense, minimum)
    on_skies = irf.evaluate_irradiance_table(table, degrees, *map(np.array, zip(*ev.skies)))
    return {"tag": tag, "seconds": float(g["seconds"]), "cpu": float(g.get("cpu", np.nan)), "condition": condition,
            "fit_error": fit_error, "grid_min": float(g["minimum"].min()), "nonneg_points": int(nts.size), "minimum": minimum,
            "worst_at": (float(nts[np.argmin(minimum)]), float(ntu[np.argmin(minimum)])), "skies": on_skies,
            "table": table, "degrees": degrees, "agreement": agreement}


def section_tabulation(ev: Evaluator, tabulated: dict[irf.Objective, dict[str, Any]], grid: tuple[int, int],
                       solves: int) -> None:
    print(f"## 3. Tabulation: grid {grid[0]} x {grid[1]} (Chebyshev nodes), degrees {DEGREES}, the sky table's form\n")
    print("Fit error: max over the sphere (exact) of |tabulated - exact optimum| / mean, at "
          f"{solves} random held-out points + corners + 32 edge points (seed {SEED}); minimum: exact minimum of the "
          f"tabulated irradiance / its mean at {NONNEG_POINTS} random + 4 corners + 2,000 edge points (seed {SEED + 7}); "
          f"errors of the tabulated result on the {len(ev.skies)} skies as in section 2.\n")
    agreement = [r["agreement"] for r in tabulated.values() if r["agreement"] is not None]
    if agreement:
        print(f"The tabulated minima agree with `skysh.dering.exact_min` to {max(agreement):.1e} of the mean.\n")
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
def chart(ev: Evaluator, results: dict[str, dict[str, NDArray]], path: Path, highlight: str = "") -> None:
    """Worst error and worst u'v' distance over turbidities against the sun zenith, per method (``highlight`` bold)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter

    zen = np.array([math.degrees(ts) for ts, _ in ev.skies])
    axis = np.unique(zen)
    fig, axes = plt.subplots(1, 2, figsize=(15, 7.5))
    colours = plt.get_cmap("tab20").colors
    for k, (name, r) in enumerate(results.items()):
        style = {"color": colours[(2 * k) % 20 + (k // 10) % 2], "marker": "os^vDP*Xh<>p"[k % 12], "markersize": 4,
                 "linewidth": 1.3, "linestyle": "-" if k < 10 else "--"}
        if name == highlight:
            style.update(color="black", linewidth=2.6, linestyle="-")
        axes[0].plot(axis, [100.0 * r["error"][zen == z].max() for z in axis], label=name, **style)
        axes[1].plot(axis, [r["uv_worst"][zen == z].max() for z in axis], **style)
    axes[0].set_ylabel("worst irradiance error over normals and RGB (% of the channel's true mean)")
    axes[1].set_ylabel(f"worst CIE 1976 u'v' distance (unitless; normals lit >= {CHROMA_FLOOR:g} x mean)")
    for ax, title in ((axes[0], "Irradiance error against the sun zenith"),
                      (axes[1], "Chromaticity error against the sun zenith")):
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:.0e}"[0] in "25" else ""))
        ax.set_xlabel("sun zenith angle (degrees); worst over turbidity 2.5, 4, 6")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    fig.legend(loc="lower center", ncol=2, fontsize=8, frameon=False)
    fig.suptitle(f"3-band irradiance against the true sky ({len(ev.skies)} skies, 12,168 normals, truth 64 bands)")
    fig.tight_layout(rect=(0, 0.2, 1, 1))
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
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
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
    args = parse(argv)
    zeniths, grid, solves = SKY_ZENITHS_DEG, GRID, HELD_OUT_SOLVES
    if args.quick:
        zeniths, grid, solves = (0, 60, 89, 90), (12, 6), 16
    skies = [(math.radians(z), t) for z in zeniths for t in SKY_TURBIDITIES]
    cache = args.out / "cache" / ("quick" if args.quick else "full")
    ev = Evaluator(cache, skies)
    methods = study_methods(ev, cache, args.objectives)
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
          f"sphere / the true mean (below -{NEGATIVE_TOL:g} counts as negative).\n")
    results = table_rows(ev, methods)
    print()
    if tabulated:
        section_tabulation(ev, tabulated, grid, solves)
    chart(ev, results, args.out / "irradiance_error_vs_zenith.png", f"tabulated: {objective_name(irf.RECOMMENDED)}")
    print(f"Chart: {args.out / 'irradiance_error_vs_zenith.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
