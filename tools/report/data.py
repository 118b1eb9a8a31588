"""
Data several sections share, computed once per run
==================================================

-   :func:`project`: the sky's truth (m >= 0 rows) and minima at many points, through
    :func:`skysh.table.fit.project_points`, optionally in worker processes.
-   :func:`grids`: the held-out test grid and the Chebyshev fitting grid (sections 2,
    3, 8, 9).
-   :func:`sweep`: tables fitted at every swept (d_theta, d_tau), their held-out errors
    and their runtime cost (sections 2, 3, 9).

Each is memoised in the run's :class:`report.common.Context` under its own name.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from report.common import MAX_BANDS, SEED_DEGREES, Context, interleaved_best, uniform_grid
from skysh.runtime import SkySH
from skysh.table import coefficient_file, fit, poly

SWEEP_SUN: tuple[float, float, float] = (0.7, 3.3, 0.4)
"""(sun zenith rad, turbidity, sun azimuth rad) of every timed runtime call (scalar fast path)."""


def project(ctx: Context, sun_zenith: NDArray, turbidity: NDArray, desc: str, processes: int = 1) -> tuple[NDArray, NDArray]:
    """Truth (P, 28, 3) m >= 0 coefficients and sky minima (P, 4) at the points, 7 bands, sun-adapted quadrature.

    :func:`skysh.table.fit.project_points` with the shipped fit's settings (``plan.grid_nodes``
    nodes per panel; None: ``sky_sh``'s default, the shipped fit's); with ``processes``
    > 1 the points are spread over a process pool, in order.
    """
    nodes = ctx.plan.grid_nodes
    settings = fit.FitSettings(bands=MAX_BANDS, samples=None if nodes is None else 4 * nodes * nodes)
    ts, tu = np.atleast_1d(np.asarray(sun_zenith, dtype=np.float64)), np.atleast_1d(np.asarray(turbidity, dtype=np.float64))
    with ctx.bar(ts.size, desc) as bar:

        def counted(results: Iterable) -> Iterable:
            for result in results:
                bar.update(1)
                yield result

        if processes <= 1:
            return fit.project_points(ts, tu, settings, lambda f, jobs: counted(map(f, jobs)))
        with ProcessPoolExecutor(processes) as pool:

            def mapper(function: Callable, jobs: Iterable) -> Iterable:
                return counted(pool.map(function, jobs, chunksize=8))

            return fit.project_points(ts, tu, settings, mapper)


def grids(ctx: Context) -> dict[str, Any]:
    """Truth and sky minima on the held-out test grid and on the fitting grid, projected in parallel."""

    def compute() -> dict[str, Any]:
        test_ts, test_tu, zen, tur = uniform_grid(ctx.plan.test_grid)
        fit_ts, fit_tu = fit.chebyshev_grid(ctx.plan.fit_grid)
        start = time.perf_counter()
        coeffs, lmin = project(ctx, np.concatenate([test_ts, fit_ts]), np.concatenate([test_tu, fit_tu]),
                               "projecting the sky (grids)", max(1, ctx.jobs))
        n = test_ts.size
        # distance of the test grid from the fitting nodes, in the Chebyshev variables of the shipped form
        tx, ty = poly.scale(test_ts, test_tu)
        fx, fy = poly.scale(fit_ts, fit_tu)
        gap = np.sqrt((tx[:, None] - fx[None]) ** 2 + (ty[:, None] - fy[None]) ** 2).min()
        return {
            "test": (test_ts, test_tu, coeffs[:n], lmin[:n]),
            "axes": (zen, tur),
            "fit": (fit_ts, fit_tu, coeffs[n:], lmin[n:]),
            "seconds": time.perf_counter() - start,
            "points": int(coeffs.shape[0]),
            "nearest_fit_node": float(gap),
        }

    return ctx.memo("grids", compute)


def band_errors(predicted: NDArray, truth: NDArray, denominator: NDArray) -> dict[int, dict[str, float]]:
    """Worst E_mean, E_max and DC error over the points, for every band count 1..7."""
    out = {}
    for bands in range(1, MAX_BANDS + 1):
        m = fit.error_measures(predicted, truth, denominator, bands)
        out[bands] = {"e_mean": float(m["e_mean"].max()), "e_max": float(m["e_max"].max()), "dc": float(m["dc"].max())}
    return out


def _fit_entry(g: dict[str, Any], degrees: tuple[int, int]) -> dict[str, Any]:
    """One swept fit in the shipped form: table, held-out errors by bands, table size, a runtime over it."""
    fts, ftu, fc, fl = g["fit"]
    tts, ttu, tc, tl = g["test"]
    per_band = np.tile(np.asarray(degrees, dtype=np.int64), (MAX_BANDS, 1))
    table, condition = fit.fit_table(fts, ftu, fc, fit.error_denominator(fl), per_band)
    predicted = fit.evaluate_table(table, per_band, tts, ttu)
    model = SkySH(coefficient_file.SkyTable(table=table, degrees=per_band, metadata={"colourspace": "sRGB"}))
    bands = band_errors(predicted, tc, fit.error_denominator(tl))
    for b, entry in bands.items():
        entry["bytes"] = poly.n_terms(degrees) * b * (b + 1) // 2 * 3 * 8
        entry["seconds"] = math.inf
    return {"degrees": degrees, "terms": poly.n_terms(degrees), "condition": condition, "predicted": predicted,
            "table": table, "model": model, "bands": bands}


def _seed_form(g: dict[str, Any]) -> dict[str, Any]:
    """The seed's plain polynomial form at its degrees, refit on the same grid and weights."""
    fts, ftu, fc, fl = g["fit"]
    tts, ttu, tc, tl = g["test"]
    degrees = np.tile(np.asarray(SEED_DEGREES, dtype=np.int64), (MAX_BANDS, 1))
    variant = fit.VARIANTS["plain (seed)"]
    table, condition = fit.fit_table(fts, ftu, fc, fit.error_denominator(fl), degrees, variant=variant)
    predicted = fit.evaluate_table(table, degrees, tts, ttu, variant=variant)
    return {"condition": condition, "table": table, "predicted": predicted,
            "bands": band_errors(predicted, tc, fit.error_denominator(tl))}


def sweep(ctx: Context) -> dict[str, Any]:
    """Section 3's fits: every (d_theta, d_tau), measured on the test grid and timed in the runtime."""

    def compute() -> dict[str, Any]:
        plan = ctx.plan
        g = grids(ctx)
        pairs = [(a, b) for a in plan.degrees_theta for b in plan.degrees_tau]
        entries = []
        with ctx.bar(len(pairs) + 1, "3. degrees swept") as bar:
            for degrees in pairs:
                entries.append(_fit_entry(g, degrees))
                bar.update(1)
            seed_form = _seed_form(g)
            bar.update(1)
        calls = {(k, bands): partial(entry["model"].coefficients, *SWEEP_SUN, bands=bands)
                 for k, entry in enumerate(entries) for bands in range(1, MAX_BANDS + 1)}
        for (k, bands), seconds in interleaved_best(calls, *plan.timing).items():
            entries[k]["bands"][bands]["seconds"] = seconds
        return {"entries": entries, "seed_form": seed_form}

    return ctx.memo("sweep", compute)
