"""
Section 8: stability where methods fail
=======================================

(a) Raw monomials against the Chebyshev forms (conditioning, float64 and float32),
(b) extrapolation outside the domain, (c) Monte Carlo at low sample counts, (d) the
sun at the zenith and on the horizon, (e) fuzzing of ``SkySH.coefficients``
(:mod:`report.fuzz`).
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from report import data, fuzz
from report.common import (
    HALF_ROWS,
    MAX_BANDS,
    METHOD_STYLE,
    RANDOM_METHODS,
    SEED_DEGREES,
    Context,
    Section,
    error_all,
    gibbs_filter,
    mean_value,
    pct,
    sig,
    style_axes,
)
from skysh.domain import SKY
from skysh.model import preetham
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.table import fit, poly

NUMBER: int = 8
TITLE: str = "Stability where methods fail"
EXTRAPOLATION_TURBIDITY: tuple[float, float] = (1.8, 8.0)
"""Turbidities of the extrapolation study (inside Preetham's model, around the fitted turbidity [2.5, 6])."""
EXTRAPOLATION_REPORTED: tuple[float, float] = (2.0, 7.5)
"""The summary reports the worst error at turbidities at most the first and at least the second."""
REFUSAL_PROBES: tuple[tuple[float, float], ...] = (
    (float(np.nextafter(math.pi / 2, 4.0)), 4.0), (math.pi / 2 + 0.01, 4.0), (-1e-9, 4.0), (0.5, 2.49), (0.5, 6.01),
    (0.5, 1.7))
"""(sun zenith rad, turbidity) just outside the domain, given to the runtime."""
EDGE_ZENITHS: tuple[tuple[float, str], ...] = ((0.0, "0"), (1e-9, "1e-9"), (math.pi / 2 - 1e-9, "pi/2 - 1e-9"),
                                              (math.pi / 2, "pi/2"))
"""Sun zeniths at and next to the domain's edges, with their labels."""
EDGE_TURBIDITIES: tuple[float, ...] = (2.5, 4.25, 6.0)
EDGE_AZIMUTH: float = 2.0
"""Azimuth (rad) of the twist test: at the zenith the true sky does not change with it."""


# --------------------------------------------------------------------------- #
# (a) conditioning
# --------------------------------------------------------------------------- #
def monomial_design(sun_zenith: NDArray, turbidity: NDArray, degrees: tuple[int, int]) -> NDArray:
    """The seed's raw monomials theta^i tau^j (eq. 1), term (i, j) at i (d_tau + 1) + j like skysh.table.poly."""
    return np.polynomial.polynomial.polyvander2d(sun_zenith, turbidity, degrees)


def _channel_lstsq(design: NDArray, values: NDArray, weight: NDArray) -> tuple[NDArray, float]:
    x, _, _, singular = np.linalg.lstsq(design * weight[:, None], values * weight[:, None], rcond=None)
    return x, float(singular[0] / singular[-1])


def weighted_lstsq(design: NDArray, values: NDArray, denominator: NDArray) -> tuple[NDArray, float]:
    """Least squares of ``design`` (P, T) against ``values`` (P, R, 3) with rows divided by ``denominator`` (P, 3).

    The weighting of :func:`skysh.table.fit.fit_table` (residuals relative to L_min),
    per channel by ``numpy.linalg.lstsq`` (SVD, default rcond); returns the
    (T, R, 3) solution and the largest condition number of a weighted design.
    """
    parts = [_channel_lstsq(design, values[..., c], 1.0 / denominator[:, c]) for c in range(values.shape[-1])]
    return np.stack([p[0] for p in parts], axis=-1), max(p[1] for p in parts)


def normal_equations(design: NDArray, values: NDArray, denominator: NDArray) -> NDArray | str:
    """The naive route to the same fit: ``A^T A x = A^T b`` per channel; the error text when A^T A is singular."""
    out = np.empty((design.shape[1],) + values.shape[1:])
    try:
        for c in range(values.shape[-1]):
            a = design / denominator[:, c, None]
            out[..., c] = np.linalg.solve(a.T @ a, a.T @ (values[..., c] / denominator[:, c, None]))
    except np.linalg.LinAlgError as error:
        return f"failed ({error})"
    return out


def evaluate_float32(table: NDArray, degrees: NDArray, sun_zenith: NDArray, turbidity: NDArray) -> NDArray:
    """:func:`skysh.table.fit.evaluate_table` (shipped form), table, terms, scale and sum in float32."""
    within = (int(degrees[:, 0].max()), int(degrees[:, 1].max()))
    design = poly.design(sun_zenith, turbidity, within, True).astype(np.float32)
    scale = preetham.luminance_scale(sun_zenith, turbidity).astype(np.float32)
    return np.einsum("pt,tkc->pkc", design, table.astype(np.float32)) * scale[:, None, None]


def _predictions(g: dict[str, Any], degrees: tuple[int, int]) -> dict[str, Any]:
    """Held-out predictions of every basis and precision at ``degrees``, with the condition numbers."""
    fts, ftu, fc, fl = g["fit"]
    tts, ttu = g["test"][:2]
    fd = fit.error_denominator(fl)
    per_band = np.tile(np.asarray(degrees, dtype=np.int64), (MAX_BANDS, 1))
    mono = monomial_design(fts, ftu, degrees)
    mono_table, mono_cond = weighted_lstsq(mono, fc, fd)
    test_design = monomial_design(tts, ttu, degrees)
    flat = mono_table.reshape(mono_table.shape[0], -1)
    shape = (tts.size,) + mono_table.shape[1:]
    normal = normal_equations(mono, fc, fd)
    plain = fit.VARIANTS["plain (seed)"]
    plain_table, plain_cond = fit.fit_table(fts, ftu, fc, fd, per_band, variant=plain)
    ship_table, ship_cond = fit.fit_table(fts, ftu, fc, fd, per_band)
    return {
        "cond": (float(np.linalg.cond(mono)), mono_cond, float(np.linalg.cond(poly.design(fts, ftu, degrees))),
                 plain_cond, ship_cond),
        "mono": (test_design @ flat).reshape(shape),
        "normal": normal if isinstance(normal, str) else (test_design @ normal.reshape(flat.shape)).reshape(shape),
        "plain": fit.evaluate_table(plain_table, per_band, tts, ttu, variant=plain),
        "mono32": (test_design.astype(np.float32) @ flat.astype(np.float32)).reshape(shape),
        "ship": fit.evaluate_table(ship_table, per_band, tts, ttu),
        "ship32": evaluate_float32(ship_table, per_band, tts, ttu),
    }


def _conditioning(ctx: Context) -> list[dict[str, Any]]:
    g = data.grids(ctx)
    _, _, tc, tl = g["test"]
    td = fit.error_denominator(tl)

    def worst(pred: NDArray | str) -> float | str:
        if isinstance(pred, str):
            return pred
        return float(fit.error_measures(np.asarray(pred, dtype=np.float64), tc, td, MAX_BANDS)["e_mean"].max())

    rows = []
    with ctx.bar(len(ctx.plan.stability_degrees), "8a. monomials") as bar:
        for degrees in ctx.plan.stability_degrees:
            p = _predictions(g, degrees)
            errors = {k: worst(p[k]) for k in ("mono", "normal", "plain", "mono32", "ship", "ship32")}
            rows.append({"degrees": degrees, "terms": poly.n_terms(degrees), "cond": p["cond"], "e": errors})
            bar.update(1)
    return rows


# --------------------------------------------------------------------------- #
# (b) extrapolation, (d) edges
# --------------------------------------------------------------------------- #
def _refusals(sky: Any) -> list[list[str]]:
    rows = []
    for z, t in REFUSAL_PROBES:
        try:
            sky.coefficients(z, t, 0.0)
            rows.append([sig(z, 17), sig(t), "**accepted (silent extrapolation)**"])
        except ValueError as error:
            rows.append([sig(z, 17), sig(t), f"ValueError: {error}"])
    return rows


def _extrapolation(ctx: Context) -> dict[str, Any]:
    """The shipped polynomial (``fit.evaluate_table``, no domain check) along turbidity, beyond the domain."""
    count, zeniths = ctx.plan.extrapolation
    turbidities = np.linspace(*EXTRAPOLATION_TURBIDITY, count)
    ts, tu = np.repeat(zeniths, count), np.tile(turbidities, len(zeniths))
    truth, lmin = data.project(ctx, ts, tu, "8b. extrapolation", ctx.jobs)
    predicted = fit.evaluate_table(np.asarray(ctx.sky.table.table), ctx.sky.table.degrees, ts, tu)
    denom = fit.error_denominator(lmin)
    errors = {b: fit.error_measures(predicted, truth, denom, b)["e_mean"].reshape(len(zeniths), count) for b in (3, MAX_BANDS)}
    return {"refusals": _refusals(ctx.sky), "turbidities": turbidities, "zeniths": zeniths, "errors": errors}


def _edges(ctx: Context) -> list[list[Any]]:
    sky = ctx.sky
    pairs = [(z, label, t) for z, label in EDGE_ZENITHS for t in EDGE_TURBIDITIES]
    truth, lmin = data.project(ctx, np.array([p[0] for p in pairs]), np.array([p[2] for p in pairs]), "8d. edges")
    rows = []
    for k, (z, label, t) in enumerate(pairs):
        denom = fit.error_denominator(lmin[k : k + 1])
        pred = sky.coefficients(z, t, 0.0, bands=MAX_BANDS, gibbs=False)
        e = {b: fit.error_measures(pred[HALF_ROWS][None], truth[k : k + 1], denom, b) for b in (3, MAX_BANDS)}
        twist = np.abs(sky.coefficients(z, t, EDGE_AZIMUTH, bands=MAX_BANDS) - sky.coefficients(z, t, 0.0, bands=MAX_BANDS)).max()
        rows.append([label, t, pct(e[3]["e_mean"][0]), pct(e[MAX_BANDS]["e_mean"][0]), sig(e[MAX_BANDS]["dc"][0]),
                     sig(twist / np.abs(pred[0]).max()), "yes" if np.all(np.isfinite(pred)) else "**no**",
                     "yes" if (lmin[k, :3] < fit.LMIN_FLOOR * lmin[k, 3]).any() else "no"])
    return rows


# --------------------------------------------------------------------------- #
# (c) Monte Carlo at low sample counts
# --------------------------------------------------------------------------- #
def _mc_truths(points: tuple[tuple[float, float], ...]) -> list[dict[str, Any]]:
    """Converged 3-band projections, their error denominators and irradiance minima / mean (raw and filtered)."""
    out = []
    for ts, tu in points:
        truth = preetham.sky_sh(ts, tu, 3)
        irr = sh.irradiance(truth)
        out.append({"sun": (ts, tu), "truth": truth, "denom": fit.error_denominator(preetham.sky_minimum(ts, tu)[None]),
                    "min_raw": float((dering.exact_min(irr) / mean_value(irr)).min()),
                    "min_filtered": float((dering.exact_min(sh.irradiance(gibbs_filter(truth))) / mean_value(irr)).min())})
    return out


def _mc_count(ctx: Context, method: str, n: int, truths: list[dict[str, Any]]) -> dict[str, Any]:
    """Negative irradiance rates (with and without the filter), lowest minima and median error at one sample count."""
    seeds = ctx.plan.mc_seeds
    negative = {False: 0, True: 0}
    lowest, errors = [], []
    for t in truths:
        ts, tu = t["sun"]
        c = np.stack([preetham.sky_sh(ts, tu, 3, method=method, n=n, seed=seed) for seed in range(seeds)])
        for gibbs in (False, True):
            irr = sh.irradiance(gibbs_filter(c) if gibbs else c)
            relative = dering.exact_min(irr) / np.abs(mean_value(irr))  # (S, 3)
            negative[gibbs] += int((relative < 0.0).any(axis=1).sum())
            if gibbs:
                lowest.append(relative.min(axis=1))
        errors.append(error_all(c, np.broadcast_to(t["truth"], c.shape), np.broadcast_to(t["denom"], (seeds, 3)), 3)["e_mean"])
    total = seeds * len(truths)
    return {"negative": {g: v / total for g, v in negative.items()}, "lowest": np.concatenate(lowest),
            "median_error": float(np.median(np.concatenate(errors)))}


def _monte_carlo(ctx: Context) -> dict[str, Any]:
    plan = ctx.plan
    truths = _mc_truths(plan.mc_points)
    out: dict[str, list[dict[str, Any]]] = {}
    with ctx.bar(len(RANDOM_METHODS) * len(plan.mc_counts), "8c. Monte Carlo") as bar:
        for method in RANDOM_METHODS:
            out[method] = []
            for n in plan.mc_counts:
                out[method].append(_mc_count(ctx, method, n, truths))
                bar.update(1)
    return {"by_method": out, "min_raw": [t["min_raw"] for t in truths], "min_filtered": [t["min_filtered"] for t in truths]}


def compute(ctx: Context) -> dict[str, Any]:
    """Every sub-study's plain data."""
    return {"conditioning": _conditioning(ctx), "extrapolation": _extrapolation(ctx), "monte_carlo": _monte_carlo(ctx),
            "edges": _edges(ctx), "fuzz": fuzz.compute(ctx)}


# --------------------------------------------------------------------------- #
# Rendering
# --------------------------------------------------------------------------- #
def _conditioning_figure(ctx: Context, rows: list[dict[str, Any]]) -> str:
    terms = [r["terms"] for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True)
    for k, (label, style, colour) in enumerate((
            ("monomials theta^i T^j", "o-", "tab:red"), ("monomials, weighted 1/L_min", "o--", "tab:red"),
            ("Chebyshev (plain variables)", "s-", "tab:blue"), ("Chebyshev plain, weighted", "s--", "tab:blue"),
            ("shipped form, weighted", "^--", "tab:green"))):
        axes[0].plot(terms, [r["cond"][k] for r in rows], style, color=colour, label=label)
    axes[0].axhline(1.0 / np.finfo(np.float64).eps, color="gray", linestyle=":", label="1 / float64 epsilon")
    style_axes(axes[0], "polynomial terms (d_theta + 1)(d_tau + 1) (count)", "condition number (dimensionless)",
               "Conditioning of the fit's design matrix", ylog=True, legend={"fontsize": 8})
    for key, label, style in (("mono", "monomials, float64", "o-"), ("plain", "Chebyshev plain, float64", "s-"),
                              ("mono32", "monomials, float32", "o:"), ("ship", "shipped form, float64", "^-"),
                              ("ship32", "shipped form, float32", "^:")):
        axes[1].plot(terms, [100 * r["e"][key] for r in rows], style, label=label)
    style_axes(axes[1], "polynomial terms (count)", "worst held-out E_mean, 7 bands (% of L_min)",
               "Fit error by basis and precision", ylog=True, legend={"fontsize": 8})
    return ctx.save(fig, "s08_conditioning.png")


def _render_conditioning(ctx: Context, s: Section, rows: list[dict[str, Any]]) -> None:
    s.text("**Raw monomials against the well-conditioned basis.** The seed's eq. 1 (theta^i tau^j, radians and "
           "turbidity) fitted by the weighted least squares of `fit.fit_table` (rows divided by L_min, per channel "
           "by `numpy.linalg.lstsq`, SVD-based; written in the report because `skysh.table.fit` has no public solver for "
           "an arbitrary design) on the same grid and weights as the Chebyshev forms; condition numbers of the "
           "design matrix alone and weighted by 1/L_min (the matrix actually solved); worst held-out E_mean at 7 "
           "bands in float64 and with the table, the design terms and the sum in float32 (an engine's float "
           "evaluation). 'normal equations' solves the weighted monomial problem the naive way (A^T A x = A^T b). "
           "Condition numbers above about 1e16 are themselves inexact in float64 (the smallest singular value is "
           "at rounding level): they mean 'singular to working precision'; there the SVD solver drops directions "
           "(its rcond) and the fit degrades.")
    s.table(["degrees", "terms", "cond, monomials", "cond, monomials weighted", "cond, Chebyshev (plain)",
             "cond, Chebyshev weighted", "E_mean monomials (SVD)", "E_mean monomials (normal eq.)",
             "E_mean Chebyshev plain", "E_mean monomials float32", "E_mean shipped form", "E_mean shipped form float32"],
            [[str(r["degrees"]), r["terms"], *map(sig, r["cond"][:4]),
              *[v if isinstance(v, str) else pct(v) for v in r["e"].values()]] for r in rows])
    s.figure(_conditioning_figure(ctx, rows), "Raw monomials against Chebyshev: condition numbers and error, float64 and float32")
    seed_row = next((r for r in rows if r["terms"] == poly.n_terms(SEED_DEGREES)), rows[-1])
    ctx.note(f"Condition number of the raw monomial design at {SEED_DEGREES} (unweighted)", sig(seed_row["cond"][0]),
             "(not given)")
    ctx.note("float32 evaluation of the shipped form: worst E_mean 7 bands (float64 in brackets)",
             f"{pct(seed_row['e']['ship32'])} ({pct(seed_row['e']['ship'])})", "")


def _render_extrapolation(ctx: Context, s: Section, d: dict[str, Any]) -> None:
    tur, errors = d["turbidities"], d["errors"]
    s.text("**Extrapolation just outside the domain.** What the runtime does:")
    s.table(["sun_zenith (rad)", "turbidity", "SkySH.coefficients"], d["refusals"])
    fig, ax = plt.subplots(figsize=(9, 4.8), constrained_layout=True)
    for k, z in enumerate(d["zeniths"]):
        label = f"sun zenith {math.degrees(z):.0f} deg"
        line = ax.plot(tur, 100 * errors[MAX_BANDS][k], "o-", markersize=3, label=f"{label}, 7 bands")
        ax.plot(tur, 100 * errors[3][k], "--", color=line[0].get_color(), label=f"{label}, 3 bands")
    ax.axvspan(*SKY.y.interval, color="tab:green", alpha=0.1, label="fitted domain (runtime accepts)")
    style_axes(ax, "turbidity (dimensionless)", "E_mean of the polynomial (% of L_min)",
               "What the polynomial would give outside the domain (the runtime refuses)", ylog=True, legend={"fontsize": 8})
    s.figure(ctx.save(fig, "s08_extrapolation.png"), "Error of the shipped polynomial evaluated outside its turbidity domain")
    e7 = errors[MAX_BANDS]
    inside = e7[:, (tur >= SKY.y.interval[0]) & (tur <= SKY.y.interval[1])].max()
    below, above = EXTRAPOLATION_REPORTED
    low = e7[:, tur <= below].max() if (tur <= below).any() else math.nan
    high = e7[:, tur >= above].max() if (tur >= above).any() else math.nan
    s.text(f"Inside the domain the worst E_mean on this line is {pct(inside)}; at T <= {below:g} it reaches {pct(low)}, "
           f"at T >= {above:g} {pct(high)} (`fit.evaluate_table`, which does not check the domain; the sun below the "
           "horizon is undefined in Preetham's model, so there is no truth to compare with).")
    ctx.note(f"Extrapolation: runtime refuses outside the domain; polynomial error at T <= {below:g} / T >= {above:g} "
             "(7 bands)",
             f"refused; {pct(low)} / {pct(high)}", "")


def _mc_figure(ctx: Context, d: dict[str, Any]) -> str:
    plan, by = ctx.plan, d["by_method"]
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), constrained_layout=True)
    for method, counts in by.items():
        style = METHOD_STYLE[method]
        axes[0].plot(plan.mc_counts, [100 * c["negative"][True] for c in counts], "-", label=f"{method}, Gibbs filter", **style)
        axes[0].plot(plan.mc_counts, [100 * c["negative"][False] for c in counts], ":", label=f"{method}, no filter", **style)
        axes[1].plot(plan.mc_counts, [100 * np.quantile(c["lowest"], 0.01) for c in counts], "-",
                     label=f"{method}: 1st percentile", **style)
        axes[1].plot(plan.mc_counts, [100 * np.median(c["lowest"]) for c in counts], "--", label=f"{method}: median", **style)
        axes[2].plot(plan.mc_counts, [100 * c["median_error"] for c in counts], "-", label=method, **style)
    axes[1].axhline(100 * min(d["min_filtered"]), color="black", linewidth=1.5, label="converged projection (worst sun)")
    axes[1].axhline(0.0, color="gray", linewidth=0.8)
    axes[0].set_ylim(-3, 103)
    axes[1].set_yscale("symlog", linthresh=1.0)
    titles = ((f"Irradiance goes negative ({plan.mc_seeds} seeds x {len(plan.mc_points)} suns)",
               "projections with negative 3-band irradiance (%)", False),
              ("Lowest irradiance, Gibbs filter on", "min irradiance / mean irradiance (%, symlog)", False),
              ("Error of low-sample projections", "median E_mean, 3 bands (% of L_min)", True))
    for ax, (title, ylabel, ylog) in zip(axes, titles):
        style_axes(ax, "directions per projection (count)", ylabel, title, xlog=True, ylog=ylog, legend={"fontsize": 7})
        ax.minorticks_off()
        ax.set_xticks(plan.mc_counts, [str(n) for n in plan.mc_counts], fontsize=8)
    return ctx.save(fig, "s08_monte_carlo.png")


MC_COLUMNS: tuple[tuple[str, Any], ...] = (("negative, filter", lambda c: c["negative"][True]),
                                           ("negative, no filter", lambda c: c["negative"][False]),
                                           ("median E_mean", lambda c: c["median_error"]))
"""Columns of the Monte Carlo table, per method: heading and value of one sample count's results."""


def _mc_table(counts: tuple[int, ...], by: dict[str, list[dict[str, Any]]]) -> tuple[list[str], list[list[Any]]]:
    header = ["directions"] + [f"{m}: {name}" for name, _ in MC_COLUMNS for m in by]
    return header, [[n] + [pct(value(by[m][i])) for _, value in MC_COLUMNS for m in by] for i, n in enumerate(counts)]


def _render_monte_carlo(ctx: Context, s: Section, d: dict[str, Any]) -> None:
    plan, by = ctx.plan, d["by_method"]
    s.figure(_mc_figure(ctx, d), "Monte Carlo at low sample counts: negative irradiance and error")
    s.text("**Monte Carlo at low sample counts.** 3-band projections by `sky_sh(method=..., n=..., seed=...)` at "
           + ", ".join(f"({math.degrees(a):.0f} deg, T = {b:g})" for a, b in plan.mc_points)
           + ", without and with the runtime's Gibbs filter (`runtime.gibbs_factors` on the zonal rows, as a "
           "renderer projecting per frame would apply it); a projection counts as negative when `dering.exact_min` "
           "of its irradiance is below zero in any channel. Without the filter the converged 3-band irradiance is "
           f"itself negative (minimum {', '.join(pct(v) for v in d['min_raw'])} of the mean: the horizon's ringing, "
           "section 5), so negatives there are not the sampling's fault; with it the converged minimum is "
           f"{', '.join(pct(v) for v in d['min_filtered'])} of the mean, and every negative is the sampling's. "
           "E_mean: all 9 coefficients against the converged projection, unfiltered.")
    s.table(*_mc_table(plan.mc_counts, by))
    negative = [n for n, c in zip(plan.mc_counts, by["mc"]) if c["negative"][True] > 0.0]
    worst_n = max(negative) if negative else None
    ctx.note("Monte Carlo, Gibbs filter on: largest sample count with a negative 3-band irradiance "
             f"({plan.mc_seeds} seeds x {len(plan.mc_points)} suns)", "none" if worst_n is None else f"{worst_n} directions", "")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s = Section(NUMBER, TITLE)
    _render_conditioning(ctx, s, d["conditioning"])
    _render_extrapolation(ctx, s, d["extrapolation"])
    _render_monte_carlo(ctx, s, d["monte_carlo"])
    s.text("**The sun at the zenith and on the horizon** (the domain's edges, where the sky's quadrature has its "
           "singular cases): runtime against `sky_sh`; 'azimuth change' is the largest coefficient change when the "
           f"sun's azimuth goes from 0 to {EDGE_AZIMUTH:g} rad, relative to DC (the true sky's is zero at the zenith "
           "by symmetry; what remains there is the fit's error in the m != 0 coefficients).")
    s.table(["sun_zenith (rad)", "T", "E_mean 3 bands", "E_mean 7 bands", "DC error", "azimuth change (of DC)",
             "finite", "L_min floored"], d["edges"])
    fuzz.render(ctx, s, d["fuzz"])
    return s
