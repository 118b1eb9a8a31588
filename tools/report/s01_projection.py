"""
Section 1: projection methods
=============================

Error of the sky's SH against sample count and wall time for every projection
method (mc, stratified, qmc, the sun-adapted and the plain product quadrature),
against a denser sun-adapted quadrature as truth. Section 3 reuses the study
(:func:`compute` is memoised).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from report.common import (
    ALL_METHODS,
    MAX_BANDS,
    METHOD_STYLE,
    PLAIN_QUADRATURE,
    RANDOM_METHODS,
    SUN_QUADRATURE,
    Context,
    Section,
    best_time,
    error_all,
    interleaved_best,
    ms,
    pct,
    sig,
    style_axes,
    timed,
)
from skysh.model import preetham
from skysh.sh import basis as sh
from skysh.table import fit

NUMBER: int = 1
TITLE: str = "Projection methods"
DEFAULT_REPEATS: int = 3
"""Timing rounds of one default-quadrature call (each call takes milliseconds)."""

Measure = Callable[[NDArray], tuple[float, float, float]]


def _measurer(sun_zenith: float, turbidity: float, truth_nodes: int) -> Measure:
    """(E_mean 7 bands, E_mean 3 bands, relative DC error) of full-layout SH against the dense truth."""
    truth = preetham.sky_sh(sun_zenith, turbidity, MAX_BANDS, n=4 * truth_nodes**2)[None]
    denom = fit.error_denominator(preetham.sky_minimum(sun_zenith, turbidity)[None])

    def measure(c: NDArray) -> tuple[float, float, float]:
        e7 = error_all(c[None], truth, denom, MAX_BANDS)
        e3 = error_all(c[None], truth, denom, 3)
        return float(e7["e_mean"][0]), float(e3["e_mean"][0]), float(e7["dc"][0])

    return measure


def _record(method: str, point: int, seed: int, samples: int, seconds: float, measured: tuple) -> dict[str, Any]:
    e7, e3, dc = measured
    return {"method": method, "point": point, "seed": seed, "samples": samples, "seconds": seconds,
            "e7": e7, "e3": e3, "dc": dc}


def _point_row(ctx: Context, point: int, ts: float, tu: float, measure: Measure) -> dict[str, Any]:
    """The default ``sky_sh`` and the shipped runtime at one point: errors and times."""
    sky, (repeats, number) = ctx.sky, ctx.plan.timing
    d7, _, ddc = measure(preetham.sky_sh(ts, tu, MAX_BANDS))
    rt7, rt3, _ = measure(sky.coefficients(ts, tu, 0.0, bands=MAX_BANDS, gibbs=False))
    times = interleaved_best({b: partial(sky.coefficients, ts, tu, 0.3, bands=b) for b in (3, MAX_BANDS)}, repeats, number)
    return {
        "point": point, "sun_zenith": ts, "turbidity": tu, "default_e7": d7, "default_dc": ddc,
        "runtime_e7": rt7, "runtime_e3": rt3, "runtime_s3": times[3], "runtime_s7": times[MAX_BANDS],
        "default_s": best_time(lambda: preetham.sky_sh(ts, tu, MAX_BANDS), DEFAULT_REPEATS, 1),
        "default_samples": int(preetham.sky_quadrature_rule(ts)[0].shape[0]),
    }


def _plain_projection(ts: float, tu: float, n: int) -> tuple[NDArray, int, float]:
    """The plain product Gauss rule over the hemisphere: coefficients, directions evaluated, best time."""
    counted: list[int] = []

    def radiance(dirs: NDArray) -> NDArray:
        counted.append(dirs.shape[0])
        return preetham.radiance(dirs, ts, 0.0, tu)

    def run() -> NDArray:
        return sh.project(radiance, MAX_BANDS, "quadrature", n=n, hemisphere=True)

    c = run()
    return c, counted[0], best_time(run, DEFAULT_REPEATS, 1)


def _point_records(ctx: Context, point: int, ts: float, tu: float, measure: Measure, bar: Any) -> list[dict[str, Any]]:
    """Every method at every sample count (and seed) at one point."""
    plan, records = ctx.plan, []
    for method in RANDOM_METHODS:
        for n in plan.s1_samples:
            for seed in range(plan.s1_seeds):
                c, seconds = timed(partial(preetham.sky_sh, ts, tu, MAX_BANDS, method=method, n=n, seed=1000 * point + seed))
                records.append(_record(method, point, seed, n, seconds, measure(c)))
                bar.update(1)
    for nodes in plan.s1_nodes:
        n = 4 * nodes * nodes  # about as many directions for both rules
        count = int(preetham.sky_quadrature_rule(ts, nodes)[0].shape[0])
        c = preetham.sky_sh(ts, tu, MAX_BANDS, n=n)
        seconds = best_time(partial(preetham.sky_sh, ts, tu, MAX_BANDS, n=n), DEFAULT_REPEATS, 1)
        records.append(_record(SUN_QUADRATURE, point, 0, count, seconds, measure(c)))
        c, count, seconds = _plain_projection(ts, tu, n)
        records.append(_record(PLAIN_QUADRATURE, point, 0, count, seconds, measure(c)))
        bar.update(2)
    return records


def compute(ctx: Context) -> dict[str, Any]:
    """Every method at every sample count, seed and sky point, timed serially (memoised: section 3 reads it)."""

    def study() -> dict[str, Any]:
        plan = ctx.plan
        per_point = len(RANDOM_METHODS) * len(plan.s1_samples) * plan.s1_seeds + 2 * len(plan.s1_nodes) + 1
        for method in RANDOM_METHODS:  # warm-up: first-call imports (scipy.stats.qmc) are not a per-frame cost
            preetham.sky_sh(*plan.s1_points[0], MAX_BANDS, method=method, n=64, seed=0)
        records: list[dict[str, Any]] = []
        points = []
        with ctx.bar(len(plan.s1_points) * per_point, "1. projection methods") as bar:
            for p, (ts, tu) in enumerate(plan.s1_points):
                measure = _measurer(ts, tu, plan.truth_nodes)
                points.append(_point_row(ctx, p, ts, tu, measure))
                bar.update(1)
                records += _point_records(ctx, p, ts, tu, measure, bar)
        return {"records": records, "points": points}

    return ctx.memo("projection", study)


def _groups(rows: list[dict[str, Any]], method: str, point: int | None) -> list[list[dict[str, Any]]]:
    """Records grouped by sample count; the quadratures over all points by rank (their counts differ per point)."""
    if point is None and method in (SUN_QUADRATURE, PLAIN_QUADRATURE):
        per_point: dict[int, list[dict[str, Any]]] = {}
        for r in rows:
            per_point.setdefault(r["point"], []).append(r)
        return [list(g) for g in zip(*[sorted(v, key=lambda r: r["samples"]) for v in per_point.values()])]
    return [[r for r in rows if r["samples"] == n] for n in sorted({r["samples"] for r in rows})]


def _group_stats(group: list[dict[str, Any]], key: str) -> tuple[float, ...]:
    """(samples, seconds, median, 10th percentile, 90th percentile, worst) of one group of records."""
    err = np.array([r[key] for r in group])
    low, median, high = np.quantile(err, [0.1, 0.5, 0.9])
    return (float(np.median([r["samples"] for r in group])), float(np.median([r["seconds"] for r in group])),
            float(median), float(low), float(high), float(err.max()))


def curves(study: dict[str, Any], method: str, point: int | None = None, key: str = "e7") -> dict[str, NDArray]:
    """Median error and time per sample count of one method (one point or all), with 10/90 percentiles and worst."""
    rows = [r for r in study["records"] if r["method"] == method and (point is None or r["point"] == point)]
    stats = np.array([_group_stats(g, key) for g in _groups(rows, method, point)])
    return dict(zip(("samples", "seconds", "median", "low", "high", "worst"), stats.T))


def _figure(ctx: Context, study: dict[str, Any]) -> str:
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    for method in ALL_METHODS:
        cv = curves(study, method)
        style = METHOD_STYLE[method]
        for ax, x in ((axes[0], cv["samples"]), (axes[1], 1e3 * cv["seconds"])):
            ax.plot(x, cv["median"], label=method, linestyle="-", markersize=5, **style)
            ax.fill_between(x, cv["low"], cv["high"], color=style["color"], alpha=0.15, linewidth=0)
    rt = max(p["runtime_e7"] for p in study["points"])
    for ax in axes:
        ax.axhline(rt, color="black", linestyle="--", linewidth=1, label=f"shipped runtime, worst of these points ({pct(rt, 2)})")
    style_axes(axes[0], "directions evaluated per projection (count)", "E_mean, 7 bands (fraction of L_min)",
               "Projection error against sample count", xlog=True, ylog=True, legend={"fontsize": 8, "loc": "lower left"})
    style_axes(axes[1], "wall time per projection (ms, one core)", "E_mean, 7 bands (fraction of L_min)",
               "Projection error against wall time", xlog=True, ylog=True)
    return ctx.save(fig, "s01_projection.png")


def _method_rows(study: dict[str, Any]) -> list[list[str]]:
    rows = []
    for method in ALL_METHODS:
        cv, cv3 = curves(study, method), curves(study, method, key="e3")
        for i in range(cv["samples"].size):
            rows.append([method, f"{cv['samples'][i]:.0f}", ms(cv["seconds"][i]), pct(cv["median"][i]),
                         pct(cv["worst"][i]), pct(cv3["median"][i])])
    return rows


def render(ctx: Context, study: dict[str, Any]) -> Section:
    s, plan = Section(NUMBER, TITLE), ctx.plan
    s.text(
        f"The sky at {len(plan.s1_points)} (sun zenith, turbidity) points, projected to {MAX_BANDS} bands by each "
        "method of `skysh.model.preetham.sky_sh` (`mc`, `stratified`, `qmc`: uniform directions over the upper "
        "hemisphere through `skysh.sh.basis.project`; the default sun-adapted Gauss rule of `sky_quadrature_rule`) and "
        "by `skysh.sh.basis.project(..., 'quadrature', hemisphere=True)` (a plain product Gauss rule, not adapted to the "
        f"sun). Truth: `sky_sh(n=4 * {plan.truth_nodes}^2)`, the sun-adapted rule with {plan.truth_nodes} nodes "
        "per panel. Error: E_mean of Habel eq. 3 over all 49 coefficients (the random methods also err in the "
        "m < 0 ones), worst channel, with L_min = `fit.error_denominator(sky_minimum)`. Random methods: "
        f"{plan.s1_seeds} seeds per sample count; lines are medians over seeds and points, bands the 10-90% "
        "range. Wall time: one call on one core, including the sky's evaluation (the random methods' single "
        f"call; quadrature best of {DEFAULT_REPEATS}, so `sh.project`'s cached basis is reused as a renderer would).")
    s.figure(_figure(ctx, study), "Projection error of the sky (7 bands) against sample count and wall time, per method")
    s.table(["method", "directions", "median time", "median E_mean (7 bands)", "worst E_mean (7 bands)",
             "median E_mean (3 bands)"], _method_rows(study))
    points = study["points"]
    s.text("The default `sky_sh` (64 nodes per panel) against the truth, and the shipped runtime at the same points:")
    s.table(["sun zenith (deg)", "turbidity", "default directions", "default time", "default E_mean (7 bands)",
             "default DC error (relative)", "runtime E_mean (7 bands)", "runtime E_mean (3 bands)"],
            [[f"{math.degrees(p['sun_zenith']):.0f}", f"{p['turbidity']:g}", f"{p['default_samples']}",
              ms(p["default_s"]), pct(p["default_e7"]), sig(p["default_dc"]), pct(p["runtime_e7"]),
              pct(p["runtime_e3"])] for p in points])
    worst_default = max(p["default_dc"] for p in points)
    orders = []
    for method in ALL_METHODS:
        cv = curves(study, method)
        orders.append(f"{method} n^{np.polyfit(np.log(cv['samples']), np.log(cv['median']), 1)[0]:.2f}")
    s.text(f"The default quadrature against the denser rule: worst DC error {sig(worst_default)} (relative), worst "
           f"E_mean {pct(max(p['default_e7'] for p in points))}. Observed convergence of the median E_mean "
           f"(least-squares slope in log-log over the sample counts tried): {', '.join(orders)}. Section 3 compares "
           "the time each method needs to reach the runtime's accuracy.")
    ctx.note("Default reference projection (sky_sh) against a denser rule, worst DC error", sig(worst_default),
             "converged (sec. 3.1)")
    return s
