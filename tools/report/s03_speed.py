"""
Section 3: speed against accuracy
=================================

Degrees and bands swept: cost per call and table size against error (Pareto
front), and the runtime against projecting the sky per frame at equal accuracy
(from section 1's convergence curves).
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LogNorm

from report import data, s01_projection
from report.common import (
    ALL_METHODS,
    MAX_BANDS,
    METHOD_STYLE,
    SEED_DEGREES,
    SEED_E_MEAN_7,
    SEED_SIZE_KB_7,
    Context,
    Section,
    cost_to_reach,
    ms,
    pareto,
    pct,
    sig,
    style_axes,
    us,
)

NUMBER: int = 3
TITLE: str = "Speed against accuracy"
FRAME_60HZ_MS: float = 1000.0 / 60.0
"""A whole frame at 60 Hz (ms)."""
SHOWN_BANDS: tuple[int, int] = (3, MAX_BANDS)
"""Band counts of the charts: diffuse lighting and the whole file."""


def _per_frame(study: dict[str, Any], bands: int) -> dict[str, Any]:
    """Worst time (over section 1's points) each method needs to reach the runtime's accuracy at ``bands``."""
    key = "e7" if bands == MAX_BANDS else "e3"
    runtime_s = max(p[f"runtime_s{bands}"] for p in study["points"])
    methods = {}
    for method in ALL_METHODS:
        worst = (0.0, 0.0, False)
        for p in study["points"]:
            cv = s01_projection.curves(study, method, point=p["point"], key=key)
            reach = cost_to_reach(cv["seconds"], cv["median"], cv["samples"], max(p[f"runtime_{key}"], 1e-12))
            worst = max(worst, reach, key=lambda r: r[0])
        methods[method] = worst
    return {"runtime_s": runtime_s, "methods": methods}


def compute(ctx: Context) -> dict[str, Any]:
    """The sweep (shared with sections 2, 9), the shipped degrees in it, and the per-frame comparison."""
    sw = data.sweep(ctx)
    study = s01_projection.compute(ctx)
    shipped = tuple(ctx.sky.table.max_degrees)
    entries = sw["entries"]
    shipped_entry = next((e for e in entries if e["degrees"] == shipped), None)
    same_grid = ctx.plan.fit_grid == tuple(ctx.sky.metadata["grid"]["shape"])
    diff = None
    if shipped_entry is not None and same_grid:
        ref = np.asarray(ctx.sky.table.table)
        diff = float(np.abs(shipped_entry["table"] - ref).max() / np.abs(ref).max())
    return {"entries": entries, "seed_form": sw["seed_form"], "shipped": shipped, "shipped_entry": shipped_entry,
            "refit_difference": diff, "per_frame": {b: _per_frame(study, b) for b in (MAX_BANDS, 3)}}


def _pareto_figure(ctx: Context, d: dict[str, Any]) -> str:
    entries, shipped_entry = d["entries"], d["shipped_entry"]
    seed_index = next((k for k, e in enumerate(entries) if e["degrees"] == SEED_DEGREES), None)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
    colours = {3: "tab:blue", MAX_BANDS: "tab:red"}
    for bands in SHOWN_BANDS:
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
                        label=f"{bands} bands: shipped {d['shipped']}")
            if seed_index is not None:
                ax.plot(x[seed_index], 100 * d["seed_form"]["bands"][bands]["e_mean"], "P", color=colours[bands],
                        markersize=11, markeredgecolor="black", label=f"{bands} bands: seed's form {SEED_DEGREES}")
    axes[1].plot([SEED_SIZE_KB_7], [100 * SEED_E_MEAN_7], "*", color="black", markersize=14,
                 label="seed (published): 131 KB, E_mean < 1.5% (7 bands)")
    style_axes(axes[0], "runtime cost per call (us, Python scalar path)", "worst E_mean (% of L_min)",
               "Error against cost per call", ylog=True)
    style_axes(axes[1], "table size (KB = 1000 bytes, float64, m >= 0 rows)", "worst E_mean (% of L_min)",
               "Error against table size", xlog=True, ylog=True, legend={"fontsize": 7, "loc": "lower left"})
    return ctx.save(fig, "s03_pareto.png")


def _degrees_figure(ctx: Context, d: dict[str, Any]) -> str:
    plan = ctx.plan
    by_degrees = {e["degrees"]: e for e in d["entries"]}
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    for ax, bands in zip(axes, SHOWN_BANDS):
        grid_err = np.array([[100 * by_degrees[(a, b)]["bands"][bands]["e_mean"] for b in plan.degrees_tau]
                             for a in plan.degrees_theta])
        mesh = ax.pcolormesh(np.arange(len(plan.degrees_tau) + 1), np.arange(len(plan.degrees_theta) + 1), grid_err,
                             norm=LogNorm(vmin=grid_err.min(), vmax=grid_err.max()), cmap="viridis")
        plt.colorbar(mesh, ax=ax, label="worst E_mean (% of L_min)")
        for (i, j), value in np.ndenumerate(grid_err):
            ax.text(j + 0.5, i + 0.5, sig(value, 2), ha="center", va="center", fontsize=7, color="white")
        ax.set_xticks(np.arange(len(plan.degrees_tau)) + 0.5, [str(v) for v in plan.degrees_tau])
        ax.set_yticks(np.arange(len(plan.degrees_theta)) + 0.5, [str(v) for v in plan.degrees_theta])
        ax.set_xlabel("d_tau, degree in log turbidity (count)")
        ax.set_ylabel("d_theta, degree in sun zenith (count)")
        ax.set_title(f"Worst E_mean by degrees, {bands} bands")
    return ctx.save(fig, "s03_degrees.png")


def _front_rows(entries: list[dict[str, Any]]) -> list[list[Any]]:
    rows = []
    for bands in SHOWN_BANDS:
        cost = np.array([e["bands"][bands]["seconds"] for e in entries])
        err = np.array([e["bands"][bands]["e_mean"] for e in entries])
        for i in pareto(cost, err):
            e, b = entries[i], entries[i]["bands"][bands]
            rows.append([bands, str(e["degrees"]), e["terms"], us(b["seconds"]), sig(b["bytes"] / 1000) + " KB",
                         pct(b["e_mean"]), pct(b["e_max"]), sig(e["condition"])])
    return rows


def _per_frame_rows(d: dict[str, Any]) -> tuple[list[list[Any]], list[tuple[str, float, bool, str]]]:
    """Table rows and chart bars of the per-frame comparison."""
    rows, bars = [], []
    for bands, pf in d["per_frame"].items():
        bars.append((f"runtime, {bands} bands", pf["runtime_s"], False, "black"))
        for method, (t, n, extrapolated) in pf["methods"].items():
            mark = "~" if extrapolated else ""
            finite = math.isfinite(t)
            rows.append([bands, method, mark + (ms(t) if finite else "never"), mark + (sig(n) if math.isfinite(n) else "-"),
                         sig(t / pf["runtime_s"]) + "x" if finite else "-", "extrapolated" if extrapolated else "measured"])
            bars.append((f"{method}, {bands} bands", t, extrapolated, METHOD_STYLE[method]["color"]))
    return rows, bars


def _per_frame_figure(ctx: Context, bars: list[tuple[str, float, bool, str]]) -> str:
    fig, ax = plt.subplots(figsize=(10, 5.5), constrained_layout=True)
    labels = [b[0] for b in bars]
    values = np.array([b[1] * 1e3 if math.isfinite(b[1]) else np.nan for b in bars])
    ax.barh(labels, values, color=[b[3] for b in bars])
    hatched = [k for k, b in enumerate(bars) if b[2]]
    ax.barh([labels[k] for k in hatched], values[hatched], color="none", edgecolor="black", hatch="//")
    for k, v in enumerate(values):
        if np.isfinite(v):
            ax.text(v * 1.15, k, ms(v / 1e3), va="center", fontsize=8)
    ax.axvline(FRAME_60HZ_MS, color="gray", linestyle="--", linewidth=1, label="a whole 60 Hz frame (16.7 ms)")
    style_axes(ax, "time per frame (ms, one core); hatched = extrapolated", "",
               "Sky SH per frame: the fitted runtime against projecting at the same accuracy", xlog=True,
               legend={"fontsize": 8, "loc": "lower right"})
    ax.set_xlim(right=np.nanmax(values) * 30)  # room for the labels, on the log scale
    ax.invert_yaxis()
    return ctx.save(fig, "s03_per_frame.png")


def _notes(ctx: Context, d: dict[str, Any], rows: list[list[Any]]) -> None:
    if d["refit_difference"] is not None:
        ctx.note("Refit on the shipped grid against the shipped table (max relative difference)", sig(d["refit_difference"]), "")
    if d["shipped_entry"] is not None:
        sb = d["shipped_entry"]["bands"]
        ctx.note("Runtime cost per call, 3 / 7 bands (shipped degrees)",
                 f"{us(sb[3]['seconds'])} / {us(sb[MAX_BANDS]['seconds'])}",
                 "80 us (7 bands, P4 3.2 GHz, C)")
        ctx.note("Table size, 7 / 4 bands (float64, m >= 0 rows)",
                 f"{sig(sb[MAX_BANDS]['bytes'] / 1000)} KB / {sig(sb[4]['bytes'] / 1000)} KB", "131 KB / 28 KB")
    best = min((r for r in rows if r[0] == 3 and r[4] != "-"), key=lambda r: float(r[4][:-1]), default=None)
    if best is not None:
        ctx.note("Cheapest per-frame projection at the runtime's 3-band accuracy",
                 f"{best[1]}: {best[2]} ({best[4]} the runtime)", "")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, plan, entries = Section(NUMBER, TITLE), ctx.plan, d["entries"]
    s.text(
        f"Tables fitted in-process (`fit.fit_table`, shipped form) on the {plan.fit_grid[0]} x {plan.fit_grid[1]} "
        f"Chebyshev grid projected once, for d_theta in {list(plan.degrees_theta)} and d_tau in "
        f"{list(plan.degrees_tau)}; errors on the held-out grid of section 2. Cost per call: a `SkySH` built from "
        "an in-memory `coefficient_file.SkyTable` of those degrees, `coefficients(0.7, 3.3, 0.4, bands=N)` "
        f"(scalar fast path, Gibbs filter and rotation included), best of {plan.timing[0]} interleaved rounds of "
        f"{plan.timing[1]} calls on a shared machine. Table size: float64, the m >= 0 rows that the file stores "
        "(n_terms x N (N + 1) / 2 x 3 x 8 bytes).")
    if d["refit_difference"] is not None:
        s.text(f"Reproducibility: the refit at {d['shipped']} on the shipped grid differs from the shipped table "
               f"by {sig(d['refit_difference'])} of its largest entry.")
    s.figure(_pareto_figure(ctx, d), "Speed and size against accuracy over the swept degrees (3 and 7 bands)")
    s.figure(_degrees_figure(ctx, d), "Worst held-out E_mean over the swept degrees")
    s.text("The Pareto front (cost per call against worst E_mean) for 3 and 7 bands:")
    s.table(["bands", "degrees", "terms", "cost per call", "table size", "worst E_mean", "worst E_max",
             "condition (weighted)"], _front_rows(entries))
    costs = np.array([e["bands"][MAX_BANDS]["seconds"] for e in entries])
    terms = np.array([e["terms"] for e in entries])
    small, large = entries[int(np.argmin(terms))], entries[int(np.argmax(terms))]
    s.text(f"Cost per call at 7 bands: {us(costs.min())} to {us(costs.max())} over the sweep; "
           f"{us(small['bands'][MAX_BANDS]['seconds'])} for the fewest terms {small['degrees']} against "
           f"{us(large['bands'][MAX_BANDS]['seconds'])} for the most {large['degrees']} "
           f"({sig(large['terms'] / small['terms'])} times the terms): the Python scalar path's fixed cost of numpy "
           "calls dominates the arithmetic, so the degrees trade accuracy against table size far more than against time.")
    rows, bars = _per_frame_rows(d)
    s.text("Projecting the sky every frame instead, at the runtime's own accuracy at each section-1 point "
           "(E_mean of the runtime against the dense truth; the time a method needs to reach it, by log-log "
           "interpolation of its median convergence curve, worst point; '~' marks an extrapolation along the "
           "curve's last slope because no sample count tried was enough):")
    s.table(["bands", "method", "time per frame at equal accuracy", "directions needed", "ratio to the runtime",
             "how"], rows)
    s.figure(_per_frame_figure(ctx, bars), "Time per frame of the runtime and of each projection method at equal accuracy")
    _notes(ctx, d, rows)
    return s
