"""
Section 6: quantization
=======================

The seed's Table 3 (Wiederien and Sloan 2024) on 3-band sky SH, and the codec's
error against bit depth for the prior and the tight bound.
"""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from report import studies
from report.common import Context, Section, sig, style_axes
from skysh.post import quantize

NUMBER: int = 6
TITLE: str = "Quantization"
POINTS_SEED: int = 0
"""Seed of the sky points (scrambled Halton sequence)."""


def compute(ctx: Context) -> dict[str, Any]:
    """Table 3 at 8 bits, and :func:`skysh.post.quantize.table3_errors` at every bit depth of the plan."""
    plan = ctx.plan
    result = studies.table3_experiment(plan.table3_points, seed=POINTS_SEED, source=studies.SKY_SOURCE)
    ts, az, tu = studies.sample_sky_parameters(plan.table3_points, POINTS_SEED)
    coeffs, source = studies.sky_coefficients(ts, tu, az, source=studies.SKY_SOURCE)
    by_bits = {bits: quantize.table3_errors(coeffs, bits=bits) for bits in plan.bits}
    return {"table3": result, "by_bits": by_bits, "source": source}


def _row(rows: list[dict[str, Any]], bound: str, quantity: str, use_sqrt: bool) -> dict[str, Any]:
    return next(r for r in rows if r["bound"] == bound and r["quantity"] == quantity and r["sqrt"] == use_sqrt)


def _figure(ctx: Context, d: dict[str, Any]) -> str:
    result, bits = d["table3"], ctx.plan.bits
    fig, axes = plt.subplots(1, 2, figsize=(14, 4.8), constrained_layout=True, gridspec_kw={"width_ratios": [1.5, 1.0]})
    labels, prior, tight = [], [], []
    for row in (r for r in result["rows"] if r["bound"] == "prior"):
        twin = _row(result["rows"], "tight", row["quantity"], row["sqrt"])
        for metric in ("L1", "L2"):
            labels.append(f"{row['quantity']}\n{'sqrt, ' if row['sqrt'] else ''}{metric}")
            prior.append(row[metric])
            tight.append(twin[metric])
    x = np.arange(len(labels))
    axes[0].bar(x - 0.2, prior, 0.4, label="prior bound sqrt(5)", color="tab:gray")
    axes[0].bar(x + 0.2, tight, 0.4, label="tight bound sqrt(15)/2", color="tab:blue")
    axes[0].set_xticks(x, labels, fontsize=7)
    style_axes(axes[0], "", "summed error over probes and channels (relative to mean)",
               f"Table 3 on sky data ({result['probes']} probes, 8 bits)", ylog=True, legend={"fontsize": 8})
    for bound, colour in (("prior", "tab:gray"), ("tight", "tab:blue")):
        for quantity, style in (("radiance", "-"), ("irradiance", "--")):
            rmse = [_row(d["by_bits"][b]["rows"], bound, quantity, False)["RMSE"] for b in bits]
            axes[1].plot(bits, rmse, style, marker="o", color=colour, label=f"{quantity}, {bound} bound")
    style_axes(axes[1], "bits per coefficient (count)", "RMSE (relative to the probe's mean)",
               "Quantization error against bit depth (no square root)", ylog=True, legend={"fontsize": 8})
    return ctx.save(fig, "s06_quantization.png")


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s, result = Section(NUMBER, TITLE), d["table3"]
    change = next(c for c in result["changes"] if c["quantity"] == "radiance" and not c["sqrt"] and c["metric"] == "L2")
    s.text(f"`table3_experiment({ctx.plan.table3_points}, source={studies.SKY_SOURCE!r})`: the seed's Table 3 "
           "(Wiederien and Sloan 2024) on 3-band sky SH over the domain (sun zenith, azimuth, turbidity by a "
           "scrambled Halton sequence), 8-bit codec, prior bound sqrt(5) against the tight bound sqrt(15)/2, errors "
           "relative to each probe's mean (`tools/quantize_experiment.py`'s table layout).")
    s.raw(studies.table3_markdown(result).splitlines())
    s.figure(_figure(ctx, d), "Quantization of sky SH: Table 3 and the error against bit depth")
    s.text(f"Sky data for the bit-depth sweep: {d['source']}. The tight bound lowers the radiance L2 error by "
           f"{sig(change['change_percent'])}% at 8 bits.")
    ctx.note("Quantization (8 bits): radiance L2 error change, tight against prior bound", f"{sig(change['change_percent'])}%",
             "5.361% (PBR_White_Box, seed 002)")
    return s
