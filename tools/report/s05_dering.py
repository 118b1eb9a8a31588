"""
Section 5: deringing
====================

:func:`skysh.post.dering.dering` (Sloan 2017) over the domain: the windows chosen, the
target's minimum before and after (:func:`skysh.post.dering.exact_min`), the slack of
the seed's bound :func:`studies.seed_bound.min_bound` against the exact minimum, and the
detail each window removes against the time of a call.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import Normalize
from numpy.typing import NDArray

from report.common import MAX_BANDS, Context, Section, best_time, heatmap, mean_value, pct, sig, style_axes, uniform_grid, us
from report.studies import min_bound
from skysh.post import dering
from skysh.sh import basis as sh

NUMBER: int = 5
TITLE: str = "Deringing"
NEGATIVE_TOL: float = 1e-12
"""A minimum counts as negative below -1e-12 of the function's mean: rounding of the minimum itself is
far below (``exact_min`` is exact to a few ulps of the coefficients for 3 bands)."""
SLACK_FLOOR: float = 1e-17
"""Slack below this (rounding: the bound equals the minimum) is drawn at this value on the log axis."""
LOOSE: float = 1e-3
"""A bound whose slack exceeds 0.1 % of its unit windows visibly more than needed (issue 12's yardstick)."""
BOUND_SEED: int = 2017
"""Seed of the random 3-band functions of the bound study."""
TIMING: dict[int, tuple[int, int]] = {3: (3, 10), MAX_BANDS: (3, 1)}
"""(rounds, calls per round) of one deringing call per band count (7 bands certify: milliseconds)."""

Kernel = Callable[[NDArray], NDArray]
KERNELS: dict[str, Kernel] = {"irradiance": sh.irradiance, "radiance": np.asarray}
"""The function each target makes non-negative, from radiance SH."""


def _relative_min(f: NDArray) -> NDArray:
    """Minimum over the sphere / mean, (P, C)."""
    return dering.exact_min(f) / mean_value(f)


def _windows(target: str, gibbs: bool, c: NDArray) -> dict[str, Any]:
    """The windows chosen for SH ``c`` (P, K, 3) and the target's minimum before and after."""
    kernel = KERNELS[target]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", dering.DeringWarning)
        out, scales, failed = dering.dering(c, target=target, return_failed=True)
    before, after = _relative_min(kernel(c)), _relative_min(kernel(out))
    return {"target": target, "gibbs": gibbs, "bands": math.isqrt(c.shape[-2]), "n": c.shape[0], "scales": scales,
            "windowed": int((scales[:, 1:] < 1.0).any(axis=1).sum()), "last_scale": float(scales[:, -1].min()),
            "min_before": float(before.min()), "negative_before": int((before < 0.0).any(axis=1).sum()),
            "min_after": float(after.min()), "negative_after": int((after < -NEGATIVE_TOL).any(axis=1).sum()),
            "failed": int(failed.sum()),
            "warnings": sum(issubclass(w.category, dering.DeringWarning) for w in caught)}


def _bound_sets(c3: dict[bool, NDArray], count: int) -> dict[str, tuple[NDArray, NDArray]]:
    """(functions (P, 9, C), unit (P, C)) of the bound study: random functions and the skies' irradiance."""
    rng = np.random.default_rng(BOUND_SEED)
    rand = rng.normal(size=(count, 9, 1)) * rng.uniform(0.0, 2.0, (count, 9, 1)) ** 2
    sets = {"random 3-band functions (unit: largest coefficient)": (rand, np.abs(rand).max(axis=-2))}
    for gibbs in (True, False):
        irr = sh.irradiance(c3[gibbs])
        sets[f"sky irradiance, {'Gibbs filter' if gibbs else 'no Gibbs filter'} (unit: mean)"] = (irr, np.abs(mean_value(irr)))
    return sets


def _bound_slack(c3: dict[bool, NDArray], count: int) -> dict[str, dict[str, NDArray]]:
    """``exact_min``, ``min_bound`` and their difference (the bound's slack) per set, in the set's unit."""
    out = {}
    for name, (f, unit) in _bound_sets(c3, count).items():
        exact, bound = dering.exact_min(f) / unit, min_bound(f) / unit
        out[name] = {"exact": exact.ravel(), "bound": bound.ravel(), "slack": (exact - bound).ravel()}
    return out


def _detail(label: str, target: str, c: NDArray, method: str = "window") -> dict[str, Any]:
    """Relative L2 change of the target over the skies that need a window, and the time of one call, by ``method``
    (the least window, the default; or whole rows)."""
    kernel = KERNELS[target]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dering.DeringWarning)  # counted in the windows table
        out, scales = dering.dering(c, target=target, method=method)
        needy = (scales[:, 1:] < 1.0).any(axis=1)
        row: dict[str, Any] = {"label": label, "method": method, "windowed": int(needy.sum()), "n": c.shape[0]}
        if not needy.any():
            return row
        base = kernel(c[needy])
        change = np.sqrt(((kernel(out[needy]) - base) ** 2).sum(axis=-2) / (base**2).sum(axis=-2)).max(axis=-1)
        one = c[np.flatnonzero(needy)[0]]
        seconds = best_time(lambda: dering.dering(one, target=target, method=method), *TIMING[math.isqrt(c.shape[-2])])
    return {**row, "mean": float(change.mean()), "worst": float(change.max()), "seconds": seconds}


def compute(ctx: Context) -> dict[str, Any]:
    """Windows, bound slack and detail against cost on a grid of the domain (3 bands; a few skies at 7)."""
    plan, sky = ctx.plan, ctx.sky
    ts, tu, zen, tur = uniform_grid(plan.dering_grid)
    c3 = {g: sky.coefficients(ts, tu, 0.0, bands=3, gibbs=g) for g in (False, True)}
    idx7 = np.linspace(0, ts.size - 1, min(plan.dering_seven, ts.size)).round().astype(int)
    c7 = sky.coefficients(ts[idx7], tu[idx7], 0.0, bands=MAX_BANDS, gibbs=False)
    with ctx.bar(3, "5. deringing") as bar:
        windows = [_windows("irradiance", False, c3[False]), _windows("irradiance", True, c3[True]),
                   _windows("radiance", True, c3[True]), _windows("irradiance", False, c7)]
        bar.update(1)
        slack = _bound_slack(c3, plan.random_functions)
        bar.update(1)
        detail = [_detail(label, target, c, method) for label, target, c in (
            ("3 bands, irradiance, no filter", "irradiance", c3[False]), ("3 bands, radiance, filter", "radiance", c3[True]),
            ("7 bands, irradiance, no filter", "irradiance", c7)) for method in dering.DERING_METHODS]
        bar.update(1)
    return {"axes": (zen, tur), "windows": windows, "slack": slack, "detail": detail}


def _windows_figure(ctx: Context, d: dict[str, Any]) -> str:
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), constrained_layout=True)
    for ax, w in zip(axes, d["windows"][:3]):
        title = f"{w['target']} target, {'Gibbs filter' if w['gibbs'] else 'no Gibbs filter'}"
        heatmap(ax, d["axes"], w["scales"][:, 2].reshape(ctx.plan.dering_grid), f"Band-2 scale: {title}",
                "window factor of band 2 (1 = none)", norm=Normalize(0.0, 1.0), cmap="magma")
    return ctx.save(fig, "s05_windows.png")


def _slack_figure(ctx: Context, slack: dict[str, dict[str, NDArray]]) -> str:
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    for (name, v), colour in zip(slack.items(), ("tab:gray", "tab:blue", "tab:orange")):
        axes[0].plot(v["exact"], v["bound"], ".", markersize=3, alpha=0.5, color=colour, label=name)
        x = np.sort(np.maximum(v["slack"], SLACK_FLOOR))
        axes[1].plot(x, np.arange(1, x.size + 1) / x.size, "-", color=colour, label=name)
    low = min(float(v["exact"].min()) for v in slack.values())
    high = max(float(v["exact"].max()) for v in slack.values())
    axes[0].plot([low, high], [low, high], "-", color="black", linewidth=1, label="bound = exact minimum")
    axes[1].axvline(LOOSE, color="gray", linestyle=":", label=f"slack {LOOSE:g} of the unit")
    style_axes(axes[0], "exact minimum (exact_min / unit)", "seed's bound (min_bound / unit)",
               "The seed's bound against the exact minimum (below the line: conservative)",
               legend={"fontsize": 7, "loc": "upper left"})
    style_axes(axes[1], f"slack exact_min - min_bound (in the unit; floor {SLACK_FLOOR:g})", "fraction of functions",
               "How loose the seed's bound is (cumulative)", xlog=True, legend={"fontsize": 7, "loc": "lower right"})
    return ctx.save(fig, "s05_bound_slack.png")


def _detail_figure(ctx: Context, detail: list[dict[str, Any]]) -> str:
    fig, ax = plt.subplots(figsize=(9, 5), constrained_layout=True)
    colours = dict(zip(dict.fromkeys(row["label"] for row in detail), ("tab:blue", "tab:orange", "tab:green")))
    shown = [row for row in detail if row["windowed"]]
    for row in shown:
        window = row["method"] == "window"
        ax.plot(1e6 * row["seconds"], 100 * row["mean"], "o" if window else "s", color=colours[row["label"]],
                markersize=9, fillstyle="full" if window else "none",
                label=f"{row['label']}: {'least window (default)' if window else 'whole rows'}")
    if not shown:
        ax.text(0.5, 0.5, "no sky needed a window", transform=ax.transAxes, ha="center")
    style_axes(ax, "time per call (us, one sky)", "mean relative L2 change of the target (%)",
               "Deringing: detail removed against cost (filled: the least window; hollow: whole rows)", xlog=True,
               ylog=True, legend={"fontsize": 7, "loc": "best"})
    return ctx.save(fig, "s05_detail_cost.png")


def _render_windows(ctx: Context, s: Section, d: dict[str, Any]) -> None:
    w = d["windows"]
    s.text("Windows chosen and the minimum (by `dering.exact_min`) of the target function relative to its mean, "
           f"before and after (negative after: below -{NEGATIVE_TOL:g} of the mean):")
    s.table(["target", "Gibbs filter", "bands", "skies windowed", "smallest last-band scale", "min before (of mean)",
             "skies negative before", "min after (of mean)", "skies negative after", "failed (DeringWarning)"],
            [[r["target"], "on" if r["gibbs"] else "off", r["bands"], f"{r['windowed']} / {r['n']}", sig(r["last_scale"]),
              pct(r["min_before"]), r["negative_before"], pct(r["min_after"]), r["negative_after"], r["failed"]]
             for r in w])
    s.text(f"DeringWarnings issued: {sum(r['warnings'] for r in w)}.")
    s.figure(_windows_figure(ctx, d), "Deringing windows chosen across the domain (3 bands, band-2 factor)")
    ctx.note("Deringing: skies whose 3-band irradiance needs a window, Gibbs filter off; on",
             f"{w[0]['windowed']} / {w[0]['n']}; {w[1]['windowed']} / {w[1]['n']}", "")


def _render_slack(ctx: Context, s: Section, slack: dict[str, dict[str, NDArray]]) -> None:
    s.text("**The seed's bound against the exact minimum.** `min_bound` (Sloan 2017, section 2.3: the |m| = 1 and "
           "|m| = 2 pairs at their worst phase) no longer decides the windows; its slack `exact_min - min_bound` "
           "on 3-band functions shows what deciding on it would cost. A violation is a bound above the exact "
           f"minimum (by more than {NEGATIVE_TOL:g} of the unit); 'loose' counts slack above {LOOSE:g} of the unit.")
    rows, violations = [], 0
    for name, v in slack.items():
        gap = v["slack"]
        bad = int((gap < -NEGATIVE_TOL).sum())
        violations += bad
        rows.append([name, gap.size, bad, pct(float(np.mean(gap > LOOSE))), sig(float(gap.mean())),
                     sig(float(np.median(gap))), sig(float(np.quantile(gap, 0.95))), sig(float(gap.max()))])
    s.table(["set", "functions x channels", "violations", "loose", "mean slack", "median slack", "95th percentile",
             "worst slack"], rows)
    s.figure(_slack_figure(ctx, slack), "Slack of the seed's bound (min_bound) against the exact minimum (exact_min)")
    ctx.note("Deringing: seed's bound above the exact minimum (violations); worst slack, random functions",
             f"{violations}; {sig(float(next(iter(slack.values()))['slack'].max()))}", "conservative")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s = Section(NUMBER, TITLE)
    shape = ctx.plan.dering_grid
    s.text(f"3-band sky radiance SH from `SkySH.coefficients` on a {shape[0]} x {shape[1]} grid of the domain "
           "(azimuth 0; the windows do not depend on it), with and without the Gibbs filter, and "
           f"{d['windows'][3]['n']} of those skies at 7 bands, windowed by `skysh.post.dering.dering` (its default, the "
           "least window: the least position along `window_table`, linear between rows, whose target is "
           f"non-negative, to {sig(dering.WINDOW_TOLERANCE)} of a row step where `exact_min` decides (3 bands) and "
           f"{sig(dering.CERTIFIED_TOLERANCE)} where its certified bound does (5..7); the windows table and the "
           "figure below are the default's).")
    _render_windows(ctx, s, d)
    _render_slack(ctx, s, d["slack"])
    s.text("**Detail kept against cost**: relative L2 change of the target (irradiance or radiance) caused by the "
           "window, over the skies that need one, and the time of one call on one (K, 3) sky (best of "
           f"{TIMING[3][0]} rounds):")
    s.table(["skies", "method", "windowed", "mean L2 change", "worst L2 change", "time per call"],
            [[r["label"], r["method"], f"{r['windowed']} / {r['n']}", pct(r["mean"]), pct(r["worst"]), us(r["seconds"])]
             if r["windowed"] else [r["label"], r["method"], f"0 / {r['n']}", "-", "-", "- (no sky needs a window)"]
             for r in d["detail"]])
    by = {(r["label"], r["method"]): r for r in d["detail"] if r["windowed"]}
    first = d["detail"][0]["label"]
    if (first, "window") in by and (first, "table") in by:
        ctx.note("Deringing: mean irradiance change of the windowed 3-band skies, least window (default); whole rows",
                 f"{pct(by[first, 'window']['mean'])}; {pct(by[first, 'table']['mean'])}", "the least window blurs less")
    s.figure(_detail_figure(ctx, d["detail"]), "Deringing: detail removed against time per call")
    return s
