"""
Section 9: what a scene needs
=============================

Irradiance and radiance error against bands and degrees: the runtime's irradiance
against the sky's exact irradiance, the radiance's band-limiting error (Parseval)
against the fit's own error, and the fit's share of the 3-band irradiance error.
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from report import data, studies
from report.common import MAX_BANDS, Context, Section, full_from_half, pareto, pct, sig, style_axes
from skysh.model import preetham
from skysh.post import hazel
from skysh.sh import basis as sh
from skysh.table import fit

NUMBER: int = 9
TITLE: str = "What a scene needs"
POINTS_SEED: int = 1
"""Seed of the sky points (scrambled Halton sequence)."""
PICKED_DEGREES: tuple[tuple[int, int], ...] = ((7, 3), (9, 5))
"""Degrees drawn beside the smallest swept and the shipped ones."""
FIT_SHARE: float = 0.1
"""The fit's share of the 3-band irradiance error is negligible below a tenth of the band-limiting error."""
LEVELS: tuple[float, ...] = (0.05, 0.01)
"""Irradiance error levels (of R0) for the 'fewest bands' statements."""
BANDS: NDArray[np.int64] = np.arange(1, MAX_BANDS + 1)


def fit_irradiance_error(predicted: NDArray, g: dict[str, Any], normals: NDArray, bands: int = 3) -> float:
    """Worst irradiance error (of R0) over the held-out grid and the normals caused by a fit's coefficients."""
    _, _, truth, _ = g["test"]
    k = bands * (bands + 1) // 2
    delta = full_from_half(predicted[:, :k] - truth[:, :k], bands)
    error = np.einsum("mk,pkc->pmc", sh.basis(normals, bands), sh.irradiance(delta)) / math.pi
    r0 = hazel.L0_SCALE * truth[:, 0, :]
    return float(np.max(np.abs(error) / r0[:, None, :]))


def _point(ctx: Context, normals: NDArray, weights: NDArray, sun: tuple[float, float, float]) -> dict[str, Any]:
    """Irradiance errors (worst normal, with and without the filter; sphere average) and band-limiting error by bands."""
    ts, az, tu = sun
    exact = studies.exact_irradiance(ts, tu, normals, sun_azimuth=az)  # I = E / pi, 32 bands
    c7 = preetham.sky_sh(ts, tu, MAX_BANDS, sun_azimuth=az)
    r0 = hazel.L0_SCALE * c7[0]
    dirs, w = preetham.sky_quadrature_rule(ts)
    energy = np.einsum("m,mc->c", w, preetham.radiance(dirs, ts, 0.0, tu) ** 2)  # integral of L^2, (cd/m^2)^2 sr
    lmin = fit.error_denominator(preetham.sky_minimum(ts, tu)[None])[0]
    out: dict[str, Any] = {"worst": {False: [], True: []}, "average": [], "band_limit": []}
    for b in BANDS:
        for gibbs in (False, True):
            rec = ctx.sky.irradiance_at(normals, ts, tu, az, bands=int(b), gibbs=gibbs, dering=False) / math.pi
            out["worst"][gibbs].append(float(np.max(np.abs(rec - exact) / r0)))
            if not gibbs:
                out["average"].append(float(np.max(np.einsum("m,mc->c", weights, np.abs(rec - exact)) / (4 * math.pi) / r0)))
        tail = np.maximum(energy - np.sum(c7[: b * b] ** 2, axis=0), 0.0)
        out["band_limit"].append(float(np.max(np.sqrt(tail) / lmin)))  # band-limiting error in the units of eq. 3
    return out


def compute(ctx: Context) -> dict[str, Any]:
    plan = ctx.plan
    entries = data.sweep(ctx)["entries"]
    g = data.grids(ctx)
    normals, weights = sh.quadrature_rule(studies.COMPARISON_THETA_NODES)
    ts, az, tu = studies.sample_sky_parameters(plan.scene_points, POINTS_SEED)
    points = []
    with ctx.bar(plan.scene_points, "9. bands a scene needs") as bar:
        for sun in zip(ts.tolist(), az.tolist(), tu.tolist()):
            points.append(_point(ctx, normals, weights, sun))
            bar.update(1)
    wanted = {(min(plan.degrees_theta), min(plan.degrees_tau)), *PICKED_DEGREES, tuple(ctx.sky.table.max_degrees)}
    fit_rows = [(e["degrees"], e["terms"], fit_irradiance_error(e["predicted"], g, normals), e["bands"][3]["bytes"])
                for e in sorted(entries, key=lambda e: e["terms"])]
    return {
        "irr": {gibbs: np.array([p["worst"][gibbs] for p in points]) for gibbs in (False, True)},
        "irr_mean": np.array([p["average"] for p in points]),
        "rad": np.array([p["band_limit"] for p in points]),
        "picks": [{"degrees": e["degrees"], "fit_irradiance": fit_irradiance_error(e["predicted"], g, normals),
                   "e_mean": [e["bands"][int(b)]["e_mean"] for b in BANDS]} for e in entries if e["degrees"] in wanted],
        "fit_rows": fit_rows,
        "normals": normals.shape[0],
    }


def _figure(ctx: Context, d: dict[str, Any]) -> str:
    irr, rad = d["irr"], d["rad"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), constrained_layout=True)
    axes[0].plot(BANDS, 100 * irr[False].max(axis=0), "o-", color="tab:blue", label="irradiance, no Gibbs filter: worst normal")
    axes[0].plot(BANDS, 100 * d["irr_mean"].max(axis=0), "o:", color="tab:blue", label="irradiance, no filter: sphere average")
    axes[0].plot(BANDS, 100 * irr[True].max(axis=0), "s-", color="tab:red", label="irradiance, Gibbs filter: worst normal")
    for pick in d["picks"]:
        axes[0].axhline(100 * pick["fit_irradiance"], linestyle="--", linewidth=1, color="gray")
        axes[0].text(MAX_BANDS, 100 * pick["fit_irradiance"], f" fit {pick['degrees']}, 3 bands", fontsize=7,
                     va="bottom", ha="right")
    style_axes(axes[0], "SH bands N (count)", "irradiance error (% of mean irradiance R0, worst sky)",
               "Irradiance error against bands (and the fit's share)", ylog=True, legend={"fontsize": 8, "loc": "lower left"})
    axes[1].plot(BANDS, 100 * rad.max(axis=0), "o-", color="black", label="band-limiting error (worst sky)")
    axes[1].plot(BANDS, 100 * np.median(rad, axis=0), "o:", color="black", label="band-limiting error (median sky)")
    for pick in d["picks"]:
        axes[1].plot(BANDS, 100 * np.array(pick["e_mean"]), "s--", label=f"fit error, degrees {pick['degrees']}")
    style_axes(axes[1], "SH bands N (count)", "radiance error (% of L_min, eq. 3 units)",
               "Radiance: band-limiting against fit error", ylog=True, legend={"fontsize": 8})
    return ctx.save(fig, "s09_bands.png")


def _conclusions(d: dict[str, Any]) -> str:
    irr, trunc3 = d["irr"], float(d["irr"][False][:, 2].max())
    gibbs3 = float(irr[True][:, 2].max())
    enough = next((r for r in d["fit_rows"] if r[2] < FIT_SHARE * trunc3), None)
    text = (f"At 3 bands the irradiance error is {pct(trunc3)} at the worst normal ({pct(d['irr_mean'][:, 2].max())} on "
            "average over the sphere) from band-limiting alone; ")
    text += (f"the fewest-term swept degrees whose fit adds less than a tenth of that are {enough[0]} ({enough[1]} terms, "
             f"{pct(enough[2])}). " if enough else "no swept degree keeps the fit's share below a tenth of it. ")
    text += ("Bands 3 and 4 give the same irradiance (A_3 = 0). With the Gibbs filter the 3-band irradiance error "
             f"is {pct(gibbs3)} instead of {pct(trunc3)}")
    return text + (": for diffuse lighting `gibbs=False` (the runtime's default for irradiance) is the more "
                   "accurate choice; the filter is for what is seen directly (backgrounds, reflections)."
                   if gibbs3 > trunc3 else ".")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, irr, rad = Section(NUMBER, TITLE), d["irr"], d["rad"]
    s.text(f"{ctx.plan.scene_points} skies over the domain (`sample_sky_parameters`). Irradiance: the runtime's "
           "`irradiance_at` (I = E / pi) at N bands, with and without the Gibbs filter and without deringing "
           "(section 5 measures what deringing changes), against `exact_irradiance` (the true sky, 32 bands) on "
           f"{d['normals']:,} normals, as the largest error relative to the mean irradiance R0 (and its sphere "
           "average). Radiance: the band-limiting error sqrt(integral L^2 - sum of the first N^2 c^2) / L_min "
           "(Parseval; the same units as E_mean, eq. 3), against the fit's own E_mean for a few degree choices "
           "(section 3): where the band-limiting error dominates, more polynomial degrees buy nothing.")
    s.figure(_figure(ctx, d), "What a scene needs: irradiance and radiance error against bands and degrees")
    s.table(["bands", "irradiance, worst normal (no filter)", "irradiance, sphere average (no filter)",
             "irradiance, worst normal (Gibbs filter)", "radiance band-limiting, worst sky",
             "radiance band-limiting, median sky"],
            [[b, pct(irr[False][:, b - 1].max()), pct(d["irr_mean"][:, b - 1].max()), pct(irr[True][:, b - 1].max()),
              pct(rad[:, b - 1].max()), pct(np.median(rad[:, b - 1]))] for b in BANDS])
    rows = d["fit_rows"]
    front = pareto(np.array([r[1] for r in rows], dtype=float), np.array([r[2] for r in rows]))
    s.text("Fit-induced 3-band irradiance error (worst normal over the held-out grid, of R0), the swept degrees on "
           "the front of terms against error:")
    s.table(["degrees", "terms", "fit irradiance error, 3 bands", "3-band table size"],
            [[str(rows[i][0]), rows[i][1], pct(rows[i][2]), sig(rows[i][3] / 1000) + " KB"] for i in front])
    worst_irr = irr[False].max(axis=0)
    for level in LEVELS:
        b = next((int(x) for x, v in zip(BANDS, worst_irr) if v <= level), None)
        s.text(f"Fewest bands whose worst irradiance error is below {pct(level, 2)} of R0 (no filter): "
               f"{b if b is not None else f'more than {MAX_BANDS}'}.")
    s.text(_conclusions(d))
    ctx.note("3-band irradiance error against the exact sky, worst normal, Gibbs filter off / on (of R0), no deringing",
             f"{pct(irr[False][:, 2].max())} / {pct(irr[True][:, 2].max())}", "")
    return s
