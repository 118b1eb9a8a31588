"""
Section 13: the Hosek-Wilkie sky beside the Preetham sky, and its per-frame rule's accuracy and cost (issue 27)
==============================================================================================================

-   Pictures: for the report's picture suns (turbidity in Preetham's domain [2.5, 6], so both
    models are defined; Hosek albedo :data:`ALBEDO`), the true sky of each model and its 7- and
    3-band SH reconstructions, latitude-longitude, one exposure for all panels of a sun. The SH are
    each model's per-frame path: the shipped Preetham table (``SkySH.coefficients``, Gibbs filter
    off) and :func:`skysh.model.hosek_frame.coefficients` (the exact model on its sun-adapted
    rule, no filter); the luminance errors over the upper hemisphere are printed per model.
-   The accuracy-cost curve of :mod:`skysh.model.hosek_frame`'s rule: worst E_mean (Habel eq. 3,
    m >= 0 coefficients, worst channel, L_min floored as ``tools/hosek_study.py`` does) at 3 and
    7 bands on that study's random and stress point sets, against the rule's points and against
    the median time of one scalar call measured here, for :data:`skysh.model.hosek_frame.ACCURACIES`
    and :data:`EXTRA_ACCURACIES`, with issue 27's targets. The point sets, the reference
    (:func:`skysh.model.hosek.sky_sh` at its default nodes) and the error measure are the study's
    own functions (``hosek_study.rule_sets``, ``rule_reference``, ``rule_errors``), imported.

The quick run thins both point sets (:data:`SIZES`) and times fewer calls.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeVar

import hosek_study as study  # tools/
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import NullFormatter
from numpy.typing import NDArray

from report.common import Context, Section, luminance_row, pct, sig, style_axes
from skysh.app.render import KEY_VALUE, latlong_dirs, tone_map
from skysh.model import hosek, hosek_frame, preetham
from skysh.sh import basis as sh

NUMBER: int = 13
TITLE: str = "Hosek-Wilkie sky per frame"
ALBEDO: float = 0.2
"""Ground albedo of the Hosek-Wilkie skies in the pictures (grey; the Preetham sky has none)."""
SHOWN_BELOW: float = -45.0
"""Lowest elevation of the pictures, degrees: the ringing just below the horizon shows, the rest of the lower
hemisphere is left out (its most negative value is in the table)."""
PICTURE_BANDS: tuple[int, ...] = (7, 3)
"""The reconstructions shown under each true sky, top to bottom."""
TIMED_SUN: tuple[float, float, float, float] = (1.0, 3.0, 0.5, 0.7)
"""(sun zenith rad, turbidity, albedo, sun azimuth rad) of every timed scalar call (``hosek_study --rule``'s)."""

EXTRA_ACCURACIES: dict[str, hosek_frame.Accuracy] = {
    "coarser": hosek_frame.Accuracy((3, 4, 3), 3, 2, 12, 16),
    "cheaper": hosek_frame.Accuracy((4, 6, 4), 4, 3, 16, 20),
    "finer": hosek_frame.Accuracy((12, 14, 12), 12, 7, 32, 40),
    "finest": hosek_frame.Accuracy((14, 16, 14), 14, 8, 36, 44),
}
"""Node counts beyond the offered rules (:class:`skysh.model.hosek_frame.Accuracy`'s fields in order): two
cheaper than "fast", two finer than "fine", each step about 2 nodes more per panel and 4 more in azimuth."""

K = TypeVar("K", bound=Hashable)


@dataclass(frozen=True)
class Sizes:
    """Sizes of the section (``SIZES[plan.name]``)."""

    random: int  # uniform random skies of hosek_study.rule_sets (its 8 corners and 8 horizon suns are added)
    stress_step: int  # every k-th sky of its 96 stress skies
    timing: tuple[int, int]  # (rounds, calls per round) of the median timing


SIZES: dict[str, Sizes] = {
    "quick": Sizes(8, 8, (5, 10)),
    "full": Sizes(study.RULE_RANDOM, 1, (101, 10)),
}
"""Quick: 24 random and 12 stress skies, 5 rounds of 10 calls; full: the study's 272 random and 96 stress skies
(``python tools/hosek_study.py --rule``'s sets), 101 short rounds of 10 calls (many rounds: the median then
ignores bursts of load on a shared machine that spoil up to half of them)."""


# --------------------------------------------------------------------------- #
# The accuracy-cost curve
# --------------------------------------------------------------------------- #
def candidates() -> dict[str, hosek_frame.Accuracy]:
    """Every rule of the curve, ordered by its points (a sun above hosek_frame.LOW_SUN)."""
    rules = {**hosek_frame.ACCURACIES, **EXTRA_ACCURACIES}
    return dict(sorted(rules.items(), key=lambda item: item[1].rings * item[1].azimuth))


def interleaved_median(functions: Mapping[K, Callable[[], Any]], rounds: int, number: int) -> dict[K, float]:
    """Median over ``rounds`` of the mean seconds per call of ``number`` consecutive calls, every function timed
    in turn within a round (one warm-up call each first): a burst of load on a shared machine spoils one round of
    every function, and the median ignores it."""
    for function in functions.values():
        function()
    times: dict[K, list[float]] = {key: [] for key in functions}
    for _ in range(rounds):
        for key, function in functions.items():
            start = time.perf_counter()
            for _ in range(number):
                function()
            times[key].append((time.perf_counter() - start) / number)
    return {key: statistics.median(values) for key, values in times.items()}


def point_sets(sizes: Sizes) -> dict[str, NDArray]:
    """hosek_study's random and stress sets, (P, 3) rows (sun zenith, turbidity, albedo), thinned by ``sizes``."""
    sets = study.rule_sets(sizes.random)
    return {"random": sets["random"], "stress": sets["stress"][:: sizes.stress_step]}


def rule_curve(ctx: Context) -> dict[str, Any]:
    """Worst E_mean per rule, band count and set; median microseconds per scalar call per rule and band count."""
    sizes = SIZES[ctx.plan.name]
    sets = point_sets(sizes)
    rules = candidates()
    with ctx.bar(len(sets) + 1, "13. Hosek-Wilkie rule") as bar:
        refs = {}
        for name, points in sets.items():
            refs[name] = study.rule_reference(points, max(1, ctx.jobs))
            bar.update(1)
        errors = {(rule, bands, name): float(study.rule_errors(acc, sets[name], *refs[name], bands).max())
                  for rule, acc in rules.items() for bands in study.RULE_BANDS for name in sets}
        ts, t, a, phi = TIMED_SUN
        calls = {(rule, bands): partial(hosek_frame.coefficients, ts, t, a, phi, bands=bands, accuracy=acc)
                 for rule, acc in rules.items() for bands in study.RULE_BANDS}
        seconds = interleaved_median(calls, *sizes.timing)
        bar.update(1)
    return {"rules": rules, "errors": errors, "seconds": seconds, "points": {k: len(v) for k, v in sets.items()},
            "timing": sizes.timing, "load": os.getloadavg()[0]}


# --------------------------------------------------------------------------- #
# The pictures
# --------------------------------------------------------------------------- #
def _upper_weights(dirs: NDArray) -> NDArray:
    """Solid-angle weights of the latitude-longitude pixels above the horizon (0 below), summing to 1."""
    w = np.where(dirs[..., 2] > 0.0, np.sqrt(np.maximum(1.0 - dirs[..., 2] ** 2, 0.0)), 0.0)
    return w / w.sum()


def _model_panels(ctx: Context, model: str, dirs: NDArray, ts: float, az: float, tu: float) -> dict[str, NDArray]:
    """One model's true radiance and SH reconstructions (linear sRGB, cd/m^2) at the pixels ``dirs``."""
    if model == "Preetham":
        out = {"true": preetham.radiance(dirs, ts, az, tu)}
        for bands in PICTURE_BANDS:
            out[bands] = sh.evaluate(ctx.sky.coefficients(ts, tu, az, bands=bands, gibbs=False), dirs)
        return out
    out = {"true": hosek.radiance(dirs, ts, az, tu, ALBEDO)}
    for bands in PICTURE_BANDS:
        out[bands] = sh.evaluate(hosek_frame.coefficients(ts, tu, ALBEDO, az, bands=bands), dirs)
    return out


def picture(ctx: Context, ts: float, az: float, tu: float) -> dict[str, Any]:
    """Both models' panels at one sun, the shared exposure and each model's numbers (mean luminance over the upper
    hemisphere, RMS luminance error of each reconstruction there and its most negative luminance below the
    horizon, both / that mean)."""
    dirs = latlong_dirs(ctx.plan.picture_width)
    weights = _upper_weights(dirs)
    y_row = luminance_row()
    panels = {m: _model_panels(ctx, m, dirs, ts, az, tu) for m in ("Preetham", "Hosek-Wilkie")}
    grey = np.maximum(panels["Preetham"]["true"].mean(axis=-1), 1e-6)
    exposure = KEY_VALUE / math.exp(float(np.sum(weights * np.log(grey))))
    numbers = {}
    for model, p in panels.items():
        truth = p["true"] @ y_row
        mean = float(np.sum(weights * truth))
        numbers[model] = {"mean": mean}
        for bands in PICTURE_BANDS:
            rec = p[bands] @ y_row
            numbers[model][bands] = (math.sqrt(float(np.sum(weights * (rec - truth) ** 2))) / mean,
                                     min(float(rec[dirs[..., 2] < 0.0].min()), 0.0) / mean)
    return {"sun": (ts, az, tu), "panels": panels, "exposure": exposure, "numbers": numbers}


def compute(ctx: Context) -> dict[str, Any]:
    """The pictures at the plan's picture suns, then the rule's accuracy-cost curve."""
    with ctx.bar(len(ctx.plan.picture_suns), "13. pictures") as bar:
        pictures = []
        for ts, az, tu in ctx.plan.picture_suns:
            pictures.append(picture(ctx, ts, az, tu))
            bar.update(1)
    return {"pictures": pictures, "curve": rule_curve(ctx)}


# --------------------------------------------------------------------------- #
# Figures
# --------------------------------------------------------------------------- #
def _sun_label(sun: tuple[float, float, float]) -> str:
    ts, az, tu = sun
    return f"sun zenith {math.degrees(ts):.0f} deg, azimuth {math.degrees(az):.0f} deg, T = {tu:g}"


def _pictures_figure(ctx: Context, item: dict[str, Any], k: int) -> str:
    ts, az, _ = item["sun"]
    rows = ("true", *PICTURE_BANDS)
    fig, axes = plt.subplots(len(rows), 2, figsize=(12.5, 8.2), constrained_layout=True, sharex=True, sharey=True)
    shown = round((90.0 - SHOWN_BELOW) / 180.0 * ctx.plan.picture_width / 2)  # the pixel rows down to SHOWN_BELOW
    for col, model in enumerate(("Preetham", "Hosek-Wilkie")):
        name = model + (f" (albedo {ALBEDO:g})" if model == "Hosek-Wilkie" else "")
        for row, what in enumerate(rows):
            ax = axes[row, col]
            ax.imshow(tone_map(item["panels"][model][what][:shown], item["exposure"]),
                      extent=(-180, 180, SHOWN_BELOW, 90), aspect="equal", interpolation="nearest")
            ax.axhline(0.0, color="white", linewidth=0.6, alpha=0.6)
            ax.plot(math.degrees(math.remainder(az, 2.0 * math.pi)), 90.0 - math.degrees(ts), "o", markersize=14,
                    markerfacecolor="none", markeredgecolor="orangered", markeredgewidth=1.5)
            label = "true sky" if what == "true" else f"{what}-band SH reconstruction (no Gibbs filter)"
            ax.set_title(f"{name}: {label}", fontsize=10)
            ax.set_xticks(range(-180, 181, 90))
            ax.set_yticks(range(int(SHOWN_BELOW), 91, 45))
            if row == len(rows) - 1:
                ax.set_xlabel("azimuth (deg, from +X towards +Y)")
            if col == 0:
                ax.set_ylabel("elevation (deg)")
    fig.suptitle(f"Preetham and Hosek-Wilkie skies, {_sun_label(item['sun'])}\none exposure for all six panels: "
                 f"x {sig(item['exposure'])} m^2/cd (key {KEY_VALUE:g} on the Preetham sky's log-average), Reinhard, "
                 "sRGB; black = zero or negative; the sun ringed", fontsize=11)
    return ctx.save(fig, f"s13_skies_{k + 1}.png")


POINT_TICKS: tuple[int, ...] = (100, 200, 300, 500, 1000, 2000, 3000)
"""Tick values of the points axis (log scale), written out."""
BAND_STYLE: dict[int, str] = {3: "tab:blue", 7: "tab:red"}
"""Colour of each band count in the curve."""
SET_STYLE: dict[str, dict[str, Any]] = {"random": {"marker": "o", "linestyle": "-"},
                                        "stress": {"marker": "s", "linestyle": "--"}}
"""Marker and line of each point set in the curve."""


def _curve_axes(ax: plt.Axes, curve: dict[str, Any], x_of: Callable[[str, int], float]) -> None:
    """Worst E_mean against ``x_of(rule, bands)`` per band count and set, the targets, the offered rules named."""
    names = list(curve["rules"])
    for bands in study.RULE_BANDS:
        for name in ("random", "stress"):
            x = [x_of(rule, bands) for rule in names]
            y = [curve["errors"][(rule, bands, name)] for rule in names]
            ax.plot(x, y, color=BAND_STYLE[bands], **SET_STYLE[name],
                    label=f"{bands} bands, {name} ({curve['points'][name]} skies)")
        ax.axhline(study.RULE_TARGETS[bands], color=BAND_STYLE[bands], linestyle=":", linewidth=1.5,
                   label=f"{bands}-band target {study.RULE_TARGETS[bands]:.0e}")
        for rule in hosek_frame.ACCURACIES:
            worst = max(curve["errors"][(rule, bands, name)] for name in ("random", "stress"))
            above = bands == max(study.RULE_BANDS)  # the 7-band names above their points, the 3-band ones below
            ax.annotate(f'"{rule}"', (x_of(rule, bands), worst), textcoords="offset points",
                        xytext=(5, 5) if above else (-10, -14), ha="left" if above else "right", fontsize=8,
                        color=BAND_STYLE[bands])


def _curve_figure(ctx: Context, curve: dict[str, Any]) -> str:
    fig, axes = plt.subplots(1, 2, figsize=(13.5, 5.4), constrained_layout=True, sharey=True)
    rules = curve["rules"]
    _curve_axes(axes[0], curve, lambda rule, bands: rules[rule].rings * rules[rule].azimuth)
    style_axes(axes[0], "points of the rule (rings x azimuth nodes, sun above 80 deg zenith; log scale)",
               "worst E_mean (fraction of L_min, log scale)", "Accuracy against the rule's size", xlog=True, ylog=True)
    axes[0].set_xticks(POINT_TICKS, [str(t) for t in POINT_TICKS])
    axes[0].xaxis.set_minor_formatter(NullFormatter())
    _curve_axes(axes[1], curve, lambda rule, bands: 1e6 * curve["seconds"][(rule, bands)])
    rounds, number = curve["timing"]
    style_axes(axes[1], f"time of one scalar call at that band count (us; median of {rounds} rounds x {number} calls)",
               "", "Accuracy against the time of one call", ylog=True,
               legend={"fontsize": 8, "loc": "upper right"})
    fig.suptitle("skysh.model.hosek_frame: worst E_mean against the converged projection (hosek.sky_sh), "
                 "rules from 'coarser' to 'finest'", fontsize=11)
    return ctx.save(fig, "s13_rule_cost.png")


# --------------------------------------------------------------------------- #
# Text
# --------------------------------------------------------------------------- #
def _rule_rows(curve: dict[str, Any]) -> list[list[str]]:
    rows = []
    for rule, acc in curve["rules"].items():
        errs = [curve["errors"][(rule, b, s)] for b in study.RULE_BANDS for s in ("random", "stress")]
        meets = all(curve["errors"][(rule, b, s)] <= study.RULE_TARGETS[b] for b in study.RULE_BANDS
                    for s in ("random", "stress"))
        rows.append([f'"{rule}"' if rule in hosek_frame.ACCURACIES else rule,
                     f"{acc.zenith} + {acc.sun}, min {acc.minimum}", acc.rings, f"{acc.azimuth} / {acc.low_sun_azimuth}",
                     f"{acc.rings * acc.azimuth} / {acc.rings * acc.low_sun_azimuth}", *(f"{e:.2e}" for e in errs),
                     *(sig(1e6 * curve["seconds"][(rule, b)]) for b in study.RULE_BANDS), "yes" if meets else "no"])
    return rows


def _cheapest_meeting(curve: dict[str, Any]) -> str | None:
    """The rule of fewest points that meets both targets on both sets (None if none does)."""
    for rule in curve["rules"]:
        if all(curve["errors"][(rule, b, s)] <= study.RULE_TARGETS[b] for b in study.RULE_BANDS
               for s in ("random", "stress")):
            return rule
    return None


def _pictures_text(s: Section, d: dict[str, Any]) -> None:
    s.text("Latitude-longitude pictures (azimuth -180 to 180 deg left to right, elevation 90 to "
           f"{SHOWN_BELOW:g} deg top to bottom): the true sky of each model and, under it, its "
           f"{PICTURE_BANDS[0]}- and {PICTURE_BANDS[1]}-band SH reconstruction; the Preetham sky's SH from the "
           "shipped table (`SkySH.coefficients(..., gibbs=False)`), the Hosek-Wilkie sky's from "
           "`skysh.model.hosek_frame.coefficients` (the exact model on its default rule, RGB dataset, ground "
           f"albedo {ALBEDO:g}); both true skies are zero below the horizon. One exposure per sun for all six "
           "panels (in each figure's title), so the two models' brightness compares directly. The table's numbers "
           "are luminance over the pixels (solid-angle weighted), relative to each true sky's mean above the horizon.")
    rows = []
    for item in d["pictures"]:
        ts, _, tu = item["sun"]
        n = item["numbers"]
        for model in ("Preetham", "Hosek-Wilkie"):
            rows.append([f"{math.degrees(ts):.0f}", f"{tu:g}", model, sig(n[model]["mean"]),
                         sig(n[model]["mean"] / n["Preetham"]["mean"]),
                         *(pct(n[model][b][0]) for b in PICTURE_BANDS), *(pct(n[model][b][1]) for b in PICTURE_BANDS)])
    s.table(["sun zenith (deg)", "T", "model", "mean sky luminance above the horizon (cd/m^2)", "/ Preetham's",
             *(f"RMS luminance error above, {b} bands (of the mean)" for b in PICTURE_BANDS),
             *(f"most negative luminance below the horizon, {b} bands (of the mean)" for b in PICTURE_BANDS)], rows)
    ratios = {b: [item["numbers"]["Hosek-Wilkie"][b][0] / item["numbers"]["Preetham"][b][0] for item in d["pictures"]]
              for b in PICTURE_BANDS}
    s.text("The Hosek-Wilkie sky's mean luminance is " + ", ".join(
        f"{sig(item['numbers']['Hosek-Wilkie']['mean'] / item['numbers']['Preetham']['mean'])} x" for item in d["pictures"])
        + " the Preetham sky's at these suns (in the table's order); its SH reconstruction's RMS luminance error, "
        + "; ".join(f"{b} bands: {sig(min(r))} to {sig(max(r))} x Preetham's" for b, r in ratios.items())
        + " (both relative to their own sky's mean).")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s = Section(NUMBER, TITLE)
    _pictures_text(s, d)
    for k, item in enumerate(d["pictures"]):
        s.figure(_pictures_figure(ctx, item, k), f"Preetham and Hosek-Wilkie skies and their 7- and 3-band SH, "
                                                 f"{_sun_label(item['sun'])}")
    curve = d["curve"]
    rounds, number = curve["timing"]
    s.text("The per-frame rule of `skysh.model.hosek_frame` (its module docstring): worst E_mean (Habel eq. 3 over "
           "the m >= 0 coefficients of the first 3 or 7 bands, worst channel, L_min floored as "
           "`tools/hosek_study.py` does) against the converged projection `hosek.sky_sh`, on that study's point sets "
           f"({curve['points']['random']} random skies incl. the domain's corners and horizon suns; "
           f"{curve['points']['stress']} stress skies: low suns, suns on and 1e-7 rad beside every panel edge), for "
           "the offered accuracies (quoted) and four more node counts; time: median over "
           f"{rounds} rounds of {number} scalar calls (sun zenith {TIMED_SUN[0]:g} rad, azimuth {TIMED_SUN[3]:g} rad; "
           f"numpy, this machine, one process; load average {curve['load']:.1f} on {os.cpu_count()} CPUs just after). "
           "Points: rings x azimuth nodes with the sun above / beyond 80 deg.")
    s.table(["rule", "zenith nodes + sun", "rings", "azimuth", "points",
             *(f"{b} bands {n}" for b in study.RULE_BANDS for n in ("random", "stress")),
             *(f"us per call, {b} bands" for b in study.RULE_BANDS), "meets both targets"], _rule_rows(curve))
    s.figure(_curve_figure(ctx, curve), "The rule's worst E_mean against its points and against the time of one call, "
                                        "3 and 7 bands, random and stress skies, with issue 27's targets")
    _curve_summary(ctx, s, curve)
    return s


def _curve_summary(ctx: Context, s: Section, curve: dict[str, Any]) -> None:
    default = {(b, n): curve["errors"][("default", b, n)] for b in study.RULE_BANDS for n in ("random", "stress")}
    margin = min(study.RULE_TARGETS[b] / e for (b, _), e in default.items())
    cheapest = _cheapest_meeting(curve)
    acc = curve["rules"].get(cheapest) if cheapest else None
    cheapest_text = ("no rule measured here meets both targets on both sets" if acc is None else
                     f"the cheapest rule measured here that meets both targets on both sets is \"{cheapest}\" "
                     f"({acc.rings * acc.azimuth} points, {sig(1e6 * curve['seconds'][(cheapest, 7)])} us per 7-band call)")
    s.text(f"\"default\" ({hosek_frame.ACCURACIES['default'].rings} rings): worst E_mean "
           f"{default[(3, 'random')]:.2e} / {default[(3, 'stress')]:.2e} at 3 bands (random / stress) and "
           f"{default[(7, 'random')]:.2e} / {default[(7, 'stress')]:.2e} at 7, within the targets by a factor of "
           f"{sig(margin, 2)} or more; {cheapest_text}. One 7-band call of \"default\" takes "
           f"{sig(1e6 * curve['seconds'][('default', 7)])} us (3 bands: {sig(1e6 * curve['seconds'][('default', 3)])} us).")
    ctx.note("Hosek-Wilkie per frame (default rule): worst E_mean at 3 / 7 bands over random and stress skies",
             f"{max(default[(3, n)] for n in ('random', 'stress')):.2e} / "
             f"{max(default[(7, n)] for n in ('random', 'stress')):.2e} (targets {study.RULE_TARGETS[3]:.0e} / "
             f"{study.RULE_TARGETS[7]:.0e}), "
             f"{sig(1e6 * curve['seconds'][('default', 7)])} us per 7-band call", "")
