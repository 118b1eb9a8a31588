"""
Section 7: irradiance reconstructions
=====================================

L1 linear, Geomerics L1, L2 and deringed L2 irradiance against the sky's exact
irradiance (``irradiance_experiment``), over the domain and against the sun's
position.
"""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from report import studies
from report.common import Context, Section, pct, style_axes

NUMBER: int = 7
TITLE: str = "Irradiance reconstructions"
SWEEP_TURBIDITY: float = 3.0
"""Turbidity of the sweep over the sun's zenith."""
STUDY_SEED: int = 0
"""Seed of the sky points and of the timing inputs."""
NOTED: tuple[tuple[str, str], ...] = (("L2", "Irradiance, L2 (3 bands)"),
                                      ("L1 non-linear (Geomerics)", "Irradiance, Geomerics L1"))
"""(method, summary label) of the methods whose errors go into the summary table."""


def compute(ctx: Context) -> dict[str, Any]:
    """The comparison over the domain, numpy timings, and the worst error per method against the sun's zenith."""
    plan = ctx.plan
    with ctx.bar(1 + len(plan.hazel_zeniths), "7. irradiance") as bar:
        result = studies.irradiance_experiment(plan.hazel_points, seed=STUDY_SEED)
        bar.update(1)
        timings = studies.reconstruction_timings(STUDY_SEED)
        sweep = {}
        for z in plan.hazel_zeniths:
            rows = studies.irradiance_comparison(z, SWEEP_TURBIDITY, 0.0)["rows"]
            sweep[z] = {row["method"]: row for row in rows}
            bar.update(1)
    return {"result": result, "timings": timings, "sweep": sweep}


def _figure(ctx: Context, d: dict[str, Any]) -> str:
    result, zeniths = d["result"], ctx.plan.hazel_zeniths
    methods = [r["method"] for r in result["rows"]]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True)
    x = np.arange(len(methods))
    for k, (key, label) in enumerate((("mean_abs", "mean |error|"), ("rms", "RMS error"), ("max_abs", "max |error|"))):
        axes[0].bar(x + (k - 1) * 0.27, [100 * r[key] for r in result["rows"]], 0.27, label=label)
    axes[0].set_xticks(x, [m.replace(" (Geomerics)", "\n(Geomerics)") for m in methods], fontsize=8)
    style_axes(axes[0], "", "irradiance error (% of mean irradiance R0)",
               f"Irradiance reconstructions against the exact sky ({result['points']} skies)", ylog=True,
               legend={"fontsize": 8})
    for method in methods:
        axes[1].plot(np.degrees(zeniths), [100 * d["sweep"][z][method]["max_abs"] for z in zeniths], "o-", label=method)
    style_axes(axes[1], f"sun zenith angle (deg), turbidity {SWEEP_TURBIDITY:g}", "max |error| over normals (% of R0)",
               "Worst irradiance error against the sun's position", ylog=True, legend={"fontsize": 8})
    return ctx.save(fig, "s07_irradiance.png")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, result = Section(NUMBER, TITLE), d["result"]
    s.text(f"`irradiance_experiment({ctx.plan.hazel_points})`: each reconstruction from the same projection against "
           "the exact irradiance of the true sky (a 32-band projection), I = E / pi, errors relative to the mean "
           "irradiance R0, over a Gauss sphere of normals; hand-counted shader costs and a numpy throughput "
           "(`tools/quantize_experiment.py`).")
    s.raw(studies.hazel_markdown(result, d["timings"]).splitlines())
    s.figure(_figure(ctx, d), "Irradiance reconstructions against the sky's exact irradiance")
    by = {r["method"]: r for r in result["rows"]}
    for method, label in NOTED:
        ctx.note(f"{label} against the exact sky: mean / max error (of R0)",
                 f"{pct(by[method]['mean_abs'])} / {pct(by[method]['max_abs'])}", "")
    return s
