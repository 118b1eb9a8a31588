"""
Section 4: the Gibbs filter
===========================

Habel eq. 5 (zonal rows times sinc(pi l / N)): the reconstructed sky's ringing
below the horizon, overshoot and RMS error with and without the filter, profiles
along the sun's vertical plane and pictures.
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import SymLogNorm
from numpy.typing import NDArray

from report.common import GAUSS_SPHERE_NODES, MAX_BANDS, Context, Section, luminance_row, mean_upper_luminance, pct, style_axes
from skysh.app.render import latlong_dirs, render_image
from skysh.model import preetham
from skysh.sh import basis as sh

NUMBER: int = 4
TITLE: str = "Gibbs filter"
TABLE_BANDS: tuple[int, ...] = (3, 5, MAX_BANDS)
"""Band counts of the ringing table."""
PROFILE_ZENITHS: int = 721
"""View zenith angles of the profiles, 0 to 180 deg in steps of 0.25 deg."""


def _ringing(sky: Any, ts: float, tu: float, bands: int, gibbs: bool) -> tuple[float, float, float]:
    """(most negative below the horizon, largest overshoot above, RMS above), each / the true mean above."""
    dirs, weights = sh.quadrature_rule(GAUSS_SPHERE_NODES)
    upper, lower = dirs[:, 2] > 0.0, dirs[:, 2] < 0.0
    truth = preetham.luminance(dirs, ts, 0.0, tu)
    mean_up = mean_upper_luminance(ts, tu)
    rec = sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=bands, gibbs=gibbs), dirs) @ luminance_row()
    diff = rec[upper] - truth[upper]
    rms = math.sqrt(float(np.sum(weights[upper] * diff**2) / np.sum(weights[upper])))
    return float(rec[lower].min()) / mean_up, float(np.max(diff)) / mean_up, rms / mean_up


def _profile(sky: Any, ts: float, tu: float, phi: float) -> dict[str, NDArray]:
    """Luminance / mean along the vertical plane at azimuth ``phi``: the truth and 3, 7 bands with and without the filter."""
    theta = np.linspace(0.0, math.pi, PROFILE_ZENITHS)
    d = np.stack([np.sin(theta) * math.cos(phi), np.sin(theta) * math.sin(phi), np.cos(theta)], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    mean_up = mean_upper_luminance(ts, tu)
    out = {"theta": theta, "truth": preetham.luminance(d, ts, 0.0, tu) / mean_up}
    for bands in (3, MAX_BANDS):
        for gibbs in (False, True):
            rec = sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=bands, gibbs=gibbs), d) @ luminance_row()
            out[f"{bands} {gibbs}"] = rec / mean_up
    return out


def compute(ctx: Context) -> dict[str, Any]:
    """Ringing per sun, bands and filter; profiles and signed pictures at the last sun."""
    plan, sky = ctx.plan, ctx.sky
    rows: list[dict[str, Any]] = []
    with ctx.bar(len(plan.gibbs_suns), "4. Gibbs filter") as bar:
        for ts, tu in plan.gibbs_suns:
            for bands in TABLE_BANDS:
                rows.append({"sun": (ts, tu), "bands": bands, "off": _ringing(sky, ts, tu, bands, False),
                             "on": _ringing(sky, ts, tu, bands, True)})
            bar.update(1)
    ts, tu = plan.gibbs_suns[-1]
    ll = latlong_dirs(plan.picture_width)
    mean_up = mean_upper_luminance(ts, tu)
    signed = {g: sh.evaluate(sky.coefficients(ts, tu, 0.0, bands=MAX_BANDS, gibbs=g), ll) @ luminance_row() / mean_up
              for g in (False, True)}
    return {
        "rows": rows,
        "worst": {g: min(min(r[g][0] for r in rows if r["bands"] == MAX_BANDS), 0.0) for g in ("off", "on")},
        "sun": (ts, tu),
        "profiles": {phi: _profile(sky, ts, tu, phi) for phi in (0.0, math.pi)},
        "images": {g: render_image(sky, ts, tu, 0.0, bands=MAX_BANDS, width=plan.picture_width, gibbs=g)
                   for g in (False, True)},
        "signed": signed,
    }


def _profiles_figure(ctx: Context, d: dict[str, Any]) -> str:
    ts, tu = d["sun"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True, sharey=True)
    for ax, phi, side in ((axes[0], 0.0, "towards the sun"), (axes[1], math.pi, "away from the sun")):
        p = d["profiles"][phi]
        deg = np.degrees(p["theta"])
        ax.plot(deg, p["truth"], color="black", linewidth=2, label="Preetham sky")
        for bands, colour in ((3, "tab:blue"), (MAX_BANDS, "tab:red")):
            for gibbs, style in ((False, ":"), (True, "-")):
                ax.plot(deg, p[f"{bands} {gibbs}"], style, color=colour,
                        label=f"{bands} bands, {'Gibbs filter' if gibbs else 'no filter'}")
        ax.axvline(90.0, color="gray", linewidth=1)
        ax.axhline(0.0, color="gray", linewidth=0.8)
        ax.set_yscale("symlog", linthresh=0.05)
        style_axes(ax, "zenith angle of the view direction (deg); horizon at 90", "",
                   f"Luminance in the sun's vertical plane, {side}")
    axes[0].set_ylabel("luminance / mean sky luminance (symlog)")
    axes[0].legend(fontsize=8, loc="lower left")
    fig.suptitle(f"Ringing with and without the Gibbs filter (sun zenith {math.degrees(ts):.0f} deg, T = {tu:g})")
    return ctx.save(fig, "s04_profiles.png")


def _pictures_figure(ctx: Context, d: dict[str, Any]) -> str:
    ts, tu = d["sun"]
    images = d["images"]
    aspect = images[False].shape[0] / images[False].shape[1] * 2
    fig = plt.figure(figsize=(12, 9.5), constrained_layout=True)
    grid = fig.add_gridspec(3, 2, height_ratios=[aspect, aspect, 1.0])
    for row, gibbs in enumerate((False, True)):
        ax = fig.add_subplot(grid[row, :])
        ax.imshow(images[gibbs], interpolation="nearest")
        ax.set_axis_off()
        ax.set_title(f"7 bands, {'Gibbs filter' if gibbs else 'no filter'}: sky, reconstruction, irradiance "
                     "(skysh.app.render, tone-mapped)")
    for col, gibbs in enumerate((False, True)):
        ax = fig.add_subplot(grid[2, col])
        im = ax.imshow(d["signed"][gibbs], cmap="RdBu_r", norm=SymLogNorm(linthresh=0.02, vmin=-3, vmax=3),
                       extent=(-180, 180, 180, 0), aspect="auto", interpolation="nearest")
        ax.axhline(90.0, color="black", linewidth=0.8)
        ax.set_xlabel("azimuth (deg, from +X towards +Y)")
        ax.set_ylabel("zenith angle (deg)")
        ax.set_title(f"signed luminance / mean, {'Gibbs filter' if gibbs else 'no filter'} (blue = negative)")
        plt.colorbar(im, ax=ax, label="luminance / mean sky luminance")
    fig.suptitle(f"The 7-band reconstruction with and without the Gibbs filter (sun zenith {math.degrees(ts):.0f} deg, "
                 f"T = {tu:g})")
    return ctx.save(fig, "s04_pictures.png")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, worst = Section(NUMBER, TITLE), d["worst"]
    s.text("Luminance of the reconstructed sky (`SkySH.coefficients(..., gibbs=False/True)`, azimuth 0) on a "
           f"{2 * GAUSS_SPHERE_NODES**2:,}-direction Gauss sphere, relative to the true sky's mean luminance over "
           "the upper hemisphere: the most negative value below the horizon (ringing; the true sky is 0 there), "
           "the largest overshoot above the truth in the upper hemisphere, and the RMS error over the upper "
           "hemisphere (the filter's smoothing cost).")
    s.table(["sun zenith (deg)", "T", "bands", "min below horizon, no filter", "overshoot above, no filter",
             "RMS above, no filter", "min below horizon, filter", "overshoot above, filter", "RMS above, filter"],
            [[f"{math.degrees(r['sun'][0]):.0f}", f"{r['sun'][1]:g}", r["bands"], *map(pct, r["off"]), *map(pct, r["on"])]
             for r in d["rows"]])
    ctx.note("Gibbs filter: most negative luminance below the horizon, 7 bands, without / with (of the mean sky)",
             f"{pct(worst['off'])} / {pct(worst['on'])}", "strongly reduced (Fig. 4)")
    s.figure(_profiles_figure(ctx, d), "Reconstructed luminance along the sun's vertical plane, with and without the filter")
    s.figure(_pictures_figure(ctx, d), "Reconstructed sky with and without the Gibbs filter: tone-mapped and signed")
    s.text(f"At 7 bands the most negative luminance below the horizon over these suns is {pct(worst['off'])} of the "
           f"mean sky without the filter (Habel eq. 5, zonal rows times sinc(pi l / N)) and {pct(worst['on'])} with "
           "it; the RMS columns show what the smoothing costs above the horizon.")
    return s
