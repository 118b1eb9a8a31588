"""
Section 10: pictures
====================

The sky, its 3- and 7-band reconstructions and the irradiance, by
:func:`skysh.app.render.render_image`, for a few suns.
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from report.common import DPI, MAX_BANDS, Context, Section
from skysh.app.render import render_image

NUMBER: int = 10
TITLE: str = "Pictures"
TITLE_PIXELS: int = 40
"""Height of the title strip above each picture (pixels)."""


def compute(ctx: Context) -> dict[str, Any]:
    """One image per sun: the 3-band render above the 7-band one (uint8 RGB)."""
    plan = ctx.plan
    images = []
    with ctx.bar(len(plan.picture_suns), "10. pictures") as bar:
        for ts, az, tu in plan.picture_suns:
            rows = [render_image(ctx.sky, ts, tu, az, bands=b, width=plan.picture_width) for b in (3, MAX_BANDS)]
            images.append({"sun": (ts, az, tu), "image": np.concatenate(rows, axis=0)})
            bar.update(1)
    return {"images": images}


def render(ctx: Context, d: dict[str, Any]) -> Section:
    s = Section(NUMBER, TITLE)
    s.text("Latitude-longitude renders by `skysh.app.render.render_image` (one exposure per image: Reinhard with key "
           "0.18 on the true sky's log-average; azimuth -180 to 180 deg left to right, zenith at the top, horizon "
           "in the middle; the sun is ringed): the Preetham sky, its SH reconstruction and the SH irradiance E / pi, "
           "at 3 bands (top row) and 7 bands (bottom row), Gibbs filter on (the runtime's default for radiance).")
    for k, item in enumerate(d["images"]):
        (ts, _, tu), image = item["sun"], item["image"]
        h, w = image.shape[:2]
        fig = plt.figure(figsize=(w / DPI, (h + TITLE_PIXELS) / DPI))
        ax = fig.add_axes((0.0, 0.0, 1.0, h / (h + TITLE_PIXELS)))
        ax.imshow(image, interpolation="nearest")
        ax.set_axis_off()
        fig.suptitle(f"Sun {math.degrees(ts):.0f} deg from zenith, T = {tu:g}: 3 bands (top), 7 (bottom)",
                     fontsize=10 if w >= 600 else 8, y=1.0 - 8 / (h + TITLE_PIXELS), va="top")
        name = ctx.save(fig, f"s10_sky_{k + 1}.png")
        s.figure(name, f"Sky, SH reconstruction and irradiance at sun zenith {math.degrees(ts):.0f} deg, T = {tu:g}")
    return s

