"""
Offline fit of the sky's SH coefficients (Habel 2008, section 3.1)
==================================================================

Projects the Preetham sky over a grid of (sun zenith, turbidity), fits every
coefficient of every channel with a 2D Chebyshev polynomial by weighted least
squares, and measures the result on held-out points. Used by
``tools/fit_sky.py``; the runtime never imports this module.

-   :class:`FitSettings`: grid, degrees, projection settings.
-   :func:`chebyshev_grid`: the (sun zenith, turbidity) fitting grid.
-   :func:`held_out_points`: random points plus the domain corners.
-   :func:`project_points`: the truth (m >= 0 coefficients) and L_min at points.
-   :func:`error_denominator`: L_min of the seed's eqs. (2, 3), with a floor.
-   :func:`fit_table`: weighted least squares per band and channel.
-   :func:`evaluate_table`: the polynomial tables at points (no rotation).
-   :func:`error_measures`: E_mean (eq. 3), E_max (eq. 2) and the DC error.
-   :func:`choose_degrees`: the smallest degrees per band meeting a budget.
-   :func:`build`: all of the above and the sun's table, returning a :class:`~skysh.table.coefficient_file.SkyTable`.
-   :func:`zenith_of_air_mass`, :func:`sun_grid`, :func:`sun_held_out_points`,
    :func:`fit_sun_table`, :func:`evaluate_sun_table`, :func:`sun_errors`,
    :func:`build_sun`: the sun's direct illuminance (:mod:`skysh.model.solar`) as the
    file's sun table (:mod:`skysh.table.sun_table`; :mod:`skysh.lighting.sunlight` evaluates it): ln XYZ in Chebyshev
    polynomials of the air-mass variable x and the turbidity variable y.

The sun's table is fitted by plain least squares of ln XYZ (equal weights,
so relative errors) on Chebyshev-Gauss nodes of (x, y), and measured on
held-out points uniform in the sun zenith and, separately, uniform in the air
mass (three quarters of m's range lie within 5 degrees of the horizon), plus
the domain's edges and corners (:data:`SUN_ERROR_DEFINITION`).

The sky's fit minimises the seed's error measure: each grid point's residuals are
divided by that point's L_min (per channel), so the least-squares objective is
the sum over grid points of E_mean(theta, tau)^2 (eq. 3).

Beyond the seed, the polynomial models the coefficients divided by the sky's
luminance scale Y_z / F_Y(0, theta_s) (:func:`skysh.model.preetham.luminance_scale`,
one tan and two exp at run time), in Chebyshev variables of sun zenith and
log(turbidity) (:func:`skysh.table.poly.scale`). Both remove near singularities
that a raw polynomial fits poorly: at degree (13, 7) the worst held-out
E_mean at 7 bands drops from about 2% (neither, as in the seed) to below
0.01% (``tools/fit_sky.py --compare-scalings`` prints the comparison).

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1)-(3).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh.checks import MAX_ARRAY_ELEMENTS, check_count, check_flag, check_seed
from skysh.domain import SKY, SUN
from skysh.model import preetham
from skysh.sh import basis as sh
from skysh.table import coefficient_file, poly
from skysh.table.coefficient_file import NamedTable, SkyTable, zonal_half_layout
from skysh.table.sun_table import air_mass, sun_variables

__all__ = ["LMIN_FLOOR", "FitSettings", "held_out_points", "error_denominator", "fit_table", "evaluate_table",
    "error_measures", "build", "VARIANTS", "compare_variants", "SUN_ERROR_DEFINITION", "build_sun"]

LMIN_FLOOR: float = 0.05
"""Floor of a channel's L_min as a fraction of the sky's darkest luminance.

Near sunset at low turbidity the sky leaves the sRGB gamut and its blue channel
reaches zero or below (about -700 cd/m^2 at sun_zenith = pi/2, T = 2.5); an
error relative to such an L_min is meaningless, so that channel is measured
against 5% of the darkest luminance instead (the error report counts how often)."""


@dataclass(frozen=True)
class FitSettings:
    """Everything that determines a fit (recorded in the file's metadata)."""

    bands: int = 7
    degrees: tuple[int, int] = (13, 7)
    grid: tuple[int, int] = (40, 20)
    colourspace: str = "sRGB"
    method: str = "quadrature"
    samples: int | None = None
    seed: int = 2008
    held_out: int = 256
    validation: int = 128
    sun_degrees: tuple[int, int] = (12, 6)
    sun_grid: tuple[int, int] = (48, 16)
    sun_held_out: int = 512


MAX_GRID_NODES: int = 256
"""Largest fitting grid in either variable (256 x 256 projections already take hours)."""


def _check_grid(grid: Any) -> tuple[int, int]:
    """``grid`` as (points in sun zenith, points in turbidity), each an integer in [1, MAX_GRID_NODES]."""
    if not isinstance(grid, (tuple, list)) or len(grid) != 2:
        raise ValueError(f"grid must be a pair (points in sun zenith, points in turbidity), got {grid!r:.80}")
    return check_count(grid[0], "grid[0]", 1, MAX_GRID_NODES), check_count(grid[1], "grid[1]", 1, MAX_GRID_NODES)


def _gauss_nodes(n: int) -> NDArray[np.float64]:
    """The ``n`` Chebyshev-Gauss nodes in (-1, 1), increasing: ``-cos((2 k + 1) pi / (2 n))``, k = 0 .. n - 1."""
    return -np.cos((2 * np.arange(n) + 1) * math.pi / (2 * n))


def chebyshev_grid(grid: tuple[int, int]) -> tuple[NDArray, NDArray]:
    """
    The fitting grid: Chebyshev-Gauss nodes (interior, endpoints excluded) in each variable.

    Returns flat arrays (sun_zenith, turbidity) of ``grid[0] * grid[1]`` points.
    Nodes cluster towards the domain edges, where a polynomial fit is least
    constrained; the corners themselves stay free for held-out testing.
    """
    grid = _check_grid(grid)

    def nodes(n: int, lo: float, hi: float) -> NDArray:
        return lo + (hi - lo) * 0.5 * (_gauss_nodes(n) + 1.0)

    a, b = np.meshgrid(nodes(grid[0], *SKY.x.interval), nodes(grid[1], *SKY.y.interval), indexing="ij")
    return a.ravel(), b.ravel()


def held_out_points(count: int, seed: int, corners: bool = True) -> tuple[NDArray, NDArray]:
    """``count`` uniform random points of the domain (seeded) followed by its 4 corners."""
    count = check_count(count, "count", 0, MAX_ARRAY_ELEMENTS)
    rng = np.random.default_rng(check_seed(seed, "seed"))
    corners = check_flag(corners, "corners")
    ts = rng.uniform(*SKY.x.interval, size=count)
    tu = rng.uniform(*SKY.y.interval, size=count)
    if corners:
        ts = np.concatenate([ts, np.repeat(SKY.x.interval, 2)])
        tu = np.concatenate([tu, np.tile(SKY.y.interval, 2)])
    return ts, tu


def edge_points(per_edge: int, seed: int) -> tuple[NDArray, NDArray]:
    """``per_edge`` uniform random points on each of the domain's four edges (seeded)."""
    per_edge = check_count(per_edge, "per_edge", 0, MAX_ARRAY_ELEMENTS // 4)
    u = np.random.default_rng(check_seed(seed, "seed")).uniform(0.0, 1.0, (4, per_edge))
    (lo_s, hi_s), (lo_t, hi_t) = SKY.x.interval, SKY.y.interval
    ts = np.concatenate([lo_s + (hi_s - lo_s) * u[0], lo_s + (hi_s - lo_s) * u[1],
                         np.full(per_edge, lo_s), np.full(per_edge, hi_s)])
    tu = np.concatenate([np.full(per_edge, lo_t), np.full(per_edge, hi_t),
                         lo_t + (hi_t - lo_t) * u[2], lo_t + (hi_t - lo_t) * u[3]])
    return ts, tu


def _held_out(counts: tuple[int, int], seed: int) -> tuple[NDArray, NDArray]:
    """:func:`held_out_points` (``counts[0]`` and the 4 corners) plus :func:`edge_points` (``counts[1]`` per edge, seed + 1)."""
    ts, tu = held_out_points(counts[0], seed)
    ets, etu = edge_points(counts[1], seed + 1)
    return np.concatenate([ts, ets]), np.concatenate([tu, etu])


def _project_one(args: tuple) -> tuple[NDArray, NDArray]:
    """Truth (m >= 0 rows) and L_min at one point; top level so process pools can pickle it."""
    ts, tu, bands, colourspace, method, samples, seed = args
    coeffs = preetham.sky_sh(ts, tu, bands, colourspace=colourspace, method=method, n=samples, seed=seed)
    return coeffs[[sh.index(l, m) for l, m in zonal_half_layout(bands)]], preetham.sky_minimum(ts, tu, colourspace)


def project_points(sun_zenith: NDArray, turbidity: NDArray, settings: FitSettings,
                   mapper: Callable[[Callable, Iterable], Iterable] = map) -> tuple[NDArray, NDArray]:
    """
    Project the sky at every point.

    Parameters
    ----------
    sun_zenith, turbidity
        Flat arrays of points.
    settings
        Bands, colourspace and projection method / samples / seed.
    mapper
        ``map``-like callable (e.g. a process pool's ``map`` wrapped in a
        progress bar); results must come back in order (determinism).

    Returns
    -------
    coeffs, lmin
        (P, bands (bands + 1) / 2, 3) m >= 0 coefficients in cd/m^2, and (P, 4)
        sky minima (R, G, B, Y) in cd/m^2.
    """
    jobs = [(float(a), float(b), settings.bands, settings.colourspace, settings.method, settings.samples, settings.seed + i)
            for i, (a, b) in enumerate(zip(sun_zenith, turbidity))]
    results = list(mapper(_project_one, jobs))
    return np.stack([r[0] for r in results]), np.stack([r[1] for r in results])


def error_denominator(lmin: NDArray) -> NDArray[np.float64]:
    """L_min per channel (..., 3) from sky minima (..., 4), floored at LMIN_FLOOR x the luminance minimum."""
    return np.maximum(lmin[..., :3], LMIN_FLOOR * lmin[..., 3:4])


def _band_rows(bands: int) -> list[NDArray[np.intp]]:
    """Rows of the m >= 0 layout that belong to each band."""
    layout = zonal_half_layout(bands)
    return [np.array([k for k, (l, _) in enumerate(layout) if l == band], dtype=np.intp) for band in range(bands)]


def fit_table(sun_zenith: NDArray, turbidity: NDArray, coeffs: NDArray, denominator: NDArray, degrees: NDArray,
              variant: tuple[bool, bool] = (True, True)) -> tuple[NDArray, float]:
    """
    Weighted least-squares fit of every coefficient of every channel.

    Parameters
    ----------
    sun_zenith, turbidity
        (P,) grid points.
    coeffs
        (P, K_half, 3) m >= 0 coefficients at the points.
    denominator
        (P, 3) L_min per point and channel: residuals are divided by it.
    degrees
        (bands, 2) per-band (d_theta, d_tau).
    variant
        (log_turbidity, luminance_scale): the shipped form is (True, True);
        (False, False) is the seed's plain polynomial (in Chebyshev form).

    Returns
    -------
    table, condition
        (n_terms(max degrees), K_half, 3) Chebyshev coefficients, and the
        largest condition number of any weighted design matrix solved.
    """
    degrees = np.asarray(degrees, dtype=np.int64)
    within = coefficient_file._max_degrees(degrees)
    full = poly.design(sun_zenith, turbidity, within, variant[0])  # (P, T)
    scale = _scale(sun_zenith, turbidity, variant)[:, None]
    coeffs, denominator = coeffs / scale[:, :, None], denominator / scale
    table = np.zeros((full.shape[1], coeffs.shape[1], 3))
    condition = 1.0
    for band, rows in enumerate(_band_rows(degrees.shape[0])):
        mask = coefficient_file._term_mask(degrees[band], within)
        solution, cond = _solve(full[:, mask], coeffs[:, rows], denominator)
        table[np.ix_(mask, rows)] = solution
        condition = max(condition, cond)
    return table, condition


def _solve(design: NDArray, values: NDArray, denominator: NDArray) -> tuple[NDArray, float]:
    """Weighted least squares per channel: design (P, T), values (P, R, 3) -> (T, R, 3), condition."""
    solution = np.empty((design.shape[1], values.shape[1], 3))
    condition = 1.0
    for channel in range(3):
        weight = 1.0 / denominator[:, channel, None]
        x, _, _, singular = np.linalg.lstsq(design * weight, values[:, :, channel] * weight, rcond=None)
        solution[:, :, channel] = x
        condition = max(condition, float(singular[0] / singular[-1]))
    return solution, condition


def _scale(sun_zenith: NDArray, turbidity: NDArray, variant: tuple[bool, bool]) -> NDArray:
    if variant[1]:
        return preetham.luminance_scale(sun_zenith, turbidity)
    return np.ones(np.broadcast_shapes(np.shape(sun_zenith), np.shape(turbidity)))


def evaluate_table(table: NDArray, degrees: NDArray, sun_zenith: NDArray, turbidity: NDArray,
                   variant: tuple[bool, bool] = (True, True)) -> NDArray:
    """The fitted m >= 0 coefficients at points: (P, K_half, 3) in cd/m^2, no Gibbs filter, no rotation."""
    within = coefficient_file._max_degrees(np.asarray(degrees))
    scale = _scale(sun_zenith, turbidity, variant)[:, None, None]
    return np.einsum("pt,tkc->pkc", poly.design(sun_zenith, turbidity, within, variant[0]), table) * scale


def error_measures(predicted: NDArray, truth: NDArray, denominator: NDArray, bands: int) -> dict[str, NDArray]:
    """
    The seed's error measures over the first ``bands`` bands, worst channel per point.

    Parameters
    ----------
    predicted, truth
        (P, K_half, 3) m >= 0 coefficients (the m < 0 ones are zero in both).
    denominator
        (P, 3) L_min per channel (:func:`error_denominator`).
    bands
        Bands included.

    Returns
    -------
    dict
        ``e_mean`` (eq. 3) and ``e_max`` (eq. 2) as fractions, ``dc`` the
        relative error of the DC term; each (P,), the worst channel. With the
        sun at azimuth 0; E_mean is invariant under the runtime's rotation,
        E_max (an L1 sum) is not.
    """
    k = bands * (bands + 1) // 2
    diff = predicted[:, :k] - truth[:, :k]
    e_mean = np.sqrt(np.sum(diff**2, axis=1)) / denominator
    e_max = np.sum(np.abs(diff), axis=1) / denominator
    dc = np.abs(diff[:, 0]) / np.abs(truth[:, 0])
    return {"e_mean": e_mean.max(axis=1), "e_max": e_max.max(axis=1), "dc": dc.max(axis=1)}


def choose_degrees(tolerance: float, bands: int, max_degrees: tuple[int, int], grid: tuple[NDArray, NDArray, NDArray, NDArray],
                   validation: tuple[NDArray, NDArray, NDArray, NDArray]) -> NDArray[np.int64]:
    """
    Smallest degrees per band whose fit meets an E_mean budget on validation points.

    Each band gets the budget ``tolerance / sqrt(bands)`` (so the total E_mean
    over all bands is at most ``tolerance``); among the degrees (d_theta <=
    max, d_tau <= max) meeting it, the one with the fewest terms wins (ties:
    lower d_theta). A band that cannot meet it gets ``max_degrees``.

    Parameters
    ----------
    grid, validation
        (sun_zenith, turbidity, coeffs, denominator) of the fitting grid and of
        separate validation points (never the held-out test points).
    """
    budget = tolerance / math.sqrt(bands)
    candidates = sorted(itertools.product(range(max_degrees[0] + 1), range(max_degrees[1] + 1)),
                        key=lambda d: (poly.n_terms(d), d[0]))
    chosen = np.tile(np.asarray(max_degrees, dtype=np.int64), (bands, 1))
    grid_scale = preetham.luminance_scale(grid[0], grid[1])[:, None]
    val_scale = preetham.luminance_scale(validation[0], validation[1])[:, None, None]
    for band, rows in enumerate(_band_rows(bands)):
        values = grid[2][:, rows] / grid_scale[:, :, None]
        for degrees in candidates:
            fitted, _ = _solve(poly.design(grid[0], grid[1], degrees), values, grid[3] / grid_scale)
            predicted = np.einsum("pt,trc->prc", poly.design(validation[0], validation[1], degrees), fitted) * val_scale
            diff = predicted - validation[2][:, rows]
            if (np.sqrt(np.sum(diff**2, axis=1)) / validation[3]).max() <= budget:
                chosen[band] = degrees
                break
    return chosen


def _report(predicted: NDArray, truth: NDArray, denominator: NDArray, lmin: NDArray, points: tuple[NDArray, NDArray],
            bands: int) -> dict[str, Any]:
    """The sky's held-out error report: E_mean, E_max and DC error per band count, and the floored channels."""
    report: dict[str, Any] = {"held_out_points": int(truth.shape[0]), "by_bands": {}}
    for n in range(1, bands + 1):
        measures = error_measures(predicted, truth, denominator, n)
        worst = int(np.argmax(measures["e_mean"]))
        report["by_bands"][str(n)] = {
            "e_mean_worst": float(measures["e_mean"].max()),
            "e_mean_mean": float(measures["e_mean"].mean()),
            "e_max_worst": float(measures["e_max"].max()),
            "dc_worst": float(measures["dc"].max()),
            "worst_at": [float(points[0][worst]), float(points[1][worst])],
        }
    report["floored_channels"] = int(np.sum(lmin[:, :3] < LMIN_FLOOR * lmin[:, 3:4]))
    return report


def _sky_metadata(settings: FitSettings, degrees: NDArray, tolerance: float | None, condition: float,
                  report: dict[str, Any]) -> dict[str, Any]:
    """The file's metadata for the sky: conventions, the runtime fields, settings and the held-out report."""
    return {
        "description": "Chebyshev fit of the SH projection of the Preetham (1999) sky (Habel et al. 2008)",
        "conventions": {
            "sh": "real orthonormal, Condon-Shortley phase, index l(l+1)+m; stored rows m >= 0 only",
            "frame": "right-handed, Z up; sun at azimuth 0 (+X); runtime rotates about Z (Habel eq. 4)",
            "units": "cd/m^2 (linear RGB; R = G = B = Y for the colourspace's white)",
        },
        # The fields the runtime relies on (coefficient_file.RUNTIME_FIELDS), checked when the file is read.
        "colourspace": settings.colourspace,
        **coefficient_file._runtime_values(degrees),  # domain, basis, term_order, degrees, bands
        "requested_degrees": list(settings.degrees),
        "tolerance": tolerance,
        "weighting": "residuals divided by L_min per point and channel (seed eq. 3); floor "
        f"{LMIN_FLOOR} x min luminance",
        "condition_number": condition,
        "grid": {"kind": "Chebyshev-Gauss nodes", "shape": list(settings.grid)},
        "projection": {
            "method": settings.method,
            "samples": settings.samples,
            "seed": settings.seed,
            "quadrature_theta_nodes": preetham.SKY_SH_THETA_NODES if settings.samples is None else None,
        },
        "held_out": {"count": settings.held_out, "seed": settings.seed, "corners": True},
        "settings": asdict(settings),
        "errors": report,
    }


def build(settings: FitSettings, tolerance: float | None = None, mapper: Callable[[Callable, Iterable], Iterable] = map,
          provenance: dict[str, Any] | None = None) -> tuple[SkyTable, dict[str, Any], dict[str, tuple[NDArray, ...]]]:
    """
    Project, fit, measure: the whole offline pipeline.

    Parameters
    ----------
    settings
        :class:`FitSettings`.
    tolerance
        If given, choose per-band degrees (at most ``settings.degrees``) so the
        worst validation E_mean over all bands stays within it (a fraction,
        e.g. 1e-3 for 0.1%); else every band gets ``settings.degrees``.
    mapper
        ``map``-like callable for the projections (parallelism, progress).
    provenance
        Extra metadata (package version, git commit, command line).

    Returns
    -------
    table, report, samples
        The :class:`SkyTable` (with metadata, and the sun's table of
        :func:`build_sun` under ``tables["sun"]``, its block under the
        metadata's ``"tables"``), the sky's held-out error report (also
        stored in the metadata under ``"errors"``), and the projected samples
        (``grid`` and ``test`` tuples of sun_zenith, turbidity, coeffs,
        denominator) for further study (:func:`compare_variants`).

    Raises
    ------
    ValueError
        If ``settings.colourspace`` is not one of
        :data:`skysh.table.coefficient_file.FILE_COLOURSPACES` (checked before any
        projection: the file could not record it).
    """
    if settings.colourspace not in coefficient_file.FILE_COLOURSPACES:  # the file could not record it
        raise ValueError(
            f"settings.colourspace must be one of {', '.join(coefficient_file.FILE_COLOURSPACES)} "
            f"(coefficient_file.FILE_COLOURSPACES), got {settings.colourspace!r}")
    points = {"grid": chebyshev_grid(settings.grid), "test": held_out_points(settings.held_out, settings.seed)}
    if tolerance is not None:
        # Validation: random interior points, the corners and random points on the
        # four edges, since the worst errors sit on the boundary (sun on the horizon).
        points["validation"] = _held_out((settings.validation, 6), settings.seed + 1)
    every_ts, every_tu = (np.concatenate(group) for group in zip(*points.values()))
    coeffs, lmin = project_points(every_ts, every_tu, settings, mapper)
    denominator = error_denominator(lmin)
    starts = np.cumsum([0] + [ts.size for ts, _ in points.values()])
    spans = {name: slice(start, end) for name, start, end in zip(points, starts, starts[1:])}
    samples: dict[str, tuple[NDArray, NDArray, NDArray, NDArray]] = {
        name: (ts, tu, coeffs[spans[name]], denominator[spans[name]]) for name, (ts, tu) in points.items()}
    if tolerance is None:
        degrees = np.tile(np.asarray(settings.degrees, dtype=np.int64), (settings.bands, 1))
    else:
        degrees = choose_degrees(tolerance, settings.bands, settings.degrees, samples["grid"], samples["validation"])
    table, condition = fit_table(*samples["grid"], degrees)
    test_ts, test_tu, test_coeffs, test_denominator = samples["test"]
    predicted = evaluate_table(table, degrees, test_ts, test_tu)
    report = _report(predicted, test_coeffs, test_denominator, lmin[spans["test"]], (test_ts, test_tu), settings.bands)
    metadata = _sky_metadata(settings, degrees, tolerance, condition, report)
    metadata.update(provenance or {})
    sun, sun_block = build_sun(settings, preetham.rgb_from_xyz_matrix(settings.colourspace))
    metadata["tables"] = {"sun": sun_block}
    sky_table = SkyTable(table=table, degrees=degrees, metadata=metadata, tables={"sun": sun})
    return sky_table, report, {"grid": samples["grid"], "test": samples["test"]}


VARIANTS: dict[str, tuple[bool, bool]] = {
    "plain (seed)": (False, False),
    "log turbidity": (True, False),
    "luminance scale": (False, True),
    "both (shipped)": (True, True),
}
"""Forms of the fit compared by :func:`compare_variants`: (log_turbidity, luminance_scale)."""


def compare_variants(samples: dict[str, tuple], degrees: tuple[int, int], bands: int) -> list[dict[str, Any]]:
    """Held-out worst and mean E_mean at 3 and ``bands`` bands for every form in :data:`VARIANTS`."""
    gts, gtu, gc, gd = samples["grid"]
    hts, htu, hc, hd = samples["test"]
    per_band = np.tile(np.asarray(degrees, dtype=np.int64), (bands, 1))
    rows = []
    for name, variant in VARIANTS.items():
        table, condition = fit_table(gts, gtu, gc, gd, per_band, variant)
        predicted = evaluate_table(table, per_band, hts, htu, variant)
        row: dict[str, Any] = {"variant": name, "degrees": list(degrees), "condition": condition}
        for n in sorted({min(3, bands), bands}):
            e = error_measures(predicted, hc, hd, n)["e_mean"]
            row[f"e_mean_worst_{n}"] = float(e.max())
            row[f"e_mean_mean_{n}"] = float(e.mean())
        rows.append(row)
    return rows


# --------------------------------------------------------------------------- #
# The sun's table (format version 3)
# --------------------------------------------------------------------------- #
SUN_ERROR_DEFINITION: str = (
    "held out, worst over points: xyz = max |XYZ_fit,c / XYZ_c - 1| per channel (strict: XYZ > 0); "
    "rgb = max |RGB_fit,c - RGB_c| / max(|RGB_c|, Y) per channel in the file's colourspace, floored at the "
    "point's luminance Y because near the horizon a channel outside the gamut crosses zero"
)
"""How the sun table's held-out errors in the file's metadata are defined."""


def zenith_of_air_mass(m: NDArray) -> NDArray[np.float64]:
    """
    Sun zeniths (radians) whose Kasten air mass (:func:`skysh.table.sun_table.air_mass`) is ``m``, in [m0, m1].

    Bisection on [0, pi/2] to float precision (64 halvings of pi/2 reach 8.5e-20).
    Kasten's m dips slightly (< 1e-7) below m0 just above the zenith; for m in
    that range the largest solution is returned (the air mass, all that matters, is ``m``).
    """
    m = np.asarray(m, dtype=np.float64)
    lo, hi = np.zeros_like(m), np.full_like(m, SKY.x.interval[1])
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        below = air_mass(mid) < m
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def _from_variables(x: NDArray, y: NDArray) -> tuple[NDArray, NDArray]:
    """(sun zenith, turbidity) of the sun table's variables x, y in [-1, 1]."""
    (m0, m1), (t0, t1) = SUN.x.fitted, SUN.y.interval
    return zenith_of_air_mass(m0 + 0.5 * (x + 1.0) * (m1 - m0)), t0 + 0.5 * (y + 1.0) * (t1 - t0)


def sun_grid(grid: tuple[int, int]) -> tuple[NDArray, NDArray]:
    """The sun table's fitting grid: ``grid[0] x grid[1]`` Chebyshev-Gauss nodes of (x, y) as (sun zenith, turbidity)."""
    x, y = np.meshgrid(_gauss_nodes(grid[0]), _gauss_nodes(grid[1]), indexing="ij")
    return _from_variables(x.ravel(), y.ravel())


def sun_held_out_points(count: int, seed: int) -> tuple[NDArray, NDArray]:
    """
    Held-out points of the sun table (seeded): ``count`` uniform in (sun zenith, T), ``count`` uniform in
    (air mass, T), ``count // 8`` uniform on each of the four edges, and the four corners.
    """
    ts, tu = held_out_points(count, seed, corners=False)
    rng = np.random.default_rng(seed + 3)  # another stream: not the zeniths above in another variable
    mx, mt = _from_variables(rng.uniform(-1.0, 1.0, count), rng.uniform(-1.0, 1.0, count))
    es, et = edge_points(count // 8, seed + 1)
    cs, ct = np.repeat(SKY.x.interval, 2), np.tile(SKY.y.interval, 2)
    return np.concatenate([ts, mx, es, cs]), np.concatenate([tu, mt, et, ct])


def _sun_design(sun_zenith: NDArray, turbidity: NDArray, degrees: tuple[int, int]) -> NDArray:
    """(P, (d_x + 1)(d_y + 1)) products T_i(x) T_j(y) of the sun table's variables, term i (d_y + 1) + j."""
    x, y = sun_variables(sun_zenith, turbidity)
    tx, ty = poly.chebyshev(x, degrees[0]), poly.chebyshev(y, degrees[1])
    return (tx[:, :, None] * ty[:, None, :]).reshape(x.shape[0], -1)


def fit_sun_table(sun_zenith: NDArray, turbidity: NDArray, xyz: NDArray, degrees: tuple[int, int]) -> tuple[NDArray, float]:
    """
    Least-squares fit of ln XYZ (equal weights: relative errors) in the sun table's form.

    Parameters
    ----------
    sun_zenith, turbidity
        (P,) points (radians; turbidity).
    xyz
        (P, 3) CIE XYZ of the direct normal illuminance at the points, lux (> 0).
    degrees
        (d_x, d_y).

    Returns
    -------
    table, condition
        ((d_x + 1)(d_y + 1), 1, 3) Chebyshev coefficients of ln XYZ
        (:data:`skysh.table.sun_table.SUN_BASIS`), and the design's condition number.
    """
    solution, _, _, singular = np.linalg.lstsq(_sun_design(sun_zenith, turbidity, degrees), np.log(xyz), rcond=None)
    return solution[:, None, :], float(singular[0] / singular[-1])


def evaluate_sun_table(table: NDArray, degrees: tuple[int, int], sun_zenith: NDArray, turbidity: NDArray) -> NDArray:
    """The fitted XYZ (P, 3), lux, at points (the offline twin of :meth:`skysh.lighting.sunlight.SunLight.xyz`)."""
    return np.exp(_sun_design(sun_zenith, turbidity, degrees) @ np.asarray(table)[:, 0, :])


def sun_errors(fitted: NDArray, truth: NDArray, rgb_from_xyz: NDArray, points: tuple[NDArray, NDArray]) -> dict[str, Any]:
    """
    Held-out errors of the sun table (:data:`SUN_ERROR_DEFINITION`).

    Parameters
    ----------
    fitted, truth
        (P, 3) XYZ, lux.
    rgb_from_xyz
        (3, 3) XYZ -> RGB of the file's colourspace.
    points
        (sun zenith, turbidity), (P,) each: where the worst error sits.
    """
    xyz = np.abs(fitted / truth - 1.0)
    rgb = np.abs((fitted - truth) @ rgb_from_xyz.T) / np.maximum(np.abs(truth @ rgb_from_xyz.T), truth[:, 1:2])
    worst = int(np.argmax(np.maximum(xyz.max(axis=1), rgb.max(axis=1))))
    return {
        "held_out_points": int(truth.shape[0]),
        "xyz_relative_worst": xyz.max(axis=0).tolist(),
        "xyz_relative_mean": xyz.mean(axis=0).tolist(),
        "rgb_relative_worst": rgb.max(axis=0).tolist(),
        "worst": float(max(xyz.max(), rgb.max())),
        "worst_at": [float(points[0][worst]), float(points[1][worst])],
        "definition": SUN_ERROR_DEFINITION,
    }


def build_sun(settings: FitSettings, rgb_from_xyz: NDArray) -> tuple[NamedTable, dict[str, Any]]:
    """
    The sun's table and its metadata block (deterministic: no random projection involved).

    Evaluates :func:`skysh.model.solar.illuminance_xyz` (the spectral model) on
    :func:`sun_grid` ``(settings.sun_grid)``, fits :func:`fit_sun_table` of
    ``settings.sun_degrees`` and measures it on :func:`sun_held_out_points`
    ``(settings.sun_held_out, settings.seed)`` (:func:`sun_errors`).

    Returns
    -------
    table, block
        The :class:`~skysh.table.coefficient_file.NamedTable` and the ``tables.sun``
        metadata block (``rgb_from_xyz``, degrees, fit settings, condition
        number, largest channel sum of |coefficients| and the held-out errors).
    """
    from skysh.model import solar

    degrees = (int(settings.sun_degrees[0]), int(settings.sun_degrees[1]))
    ts, tu = sun_grid(settings.sun_grid)
    table, condition = fit_sun_table(ts, tu, solar.illuminance_xyz(ts, tu), degrees)
    hs, hu = sun_held_out_points(settings.sun_held_out, settings.seed)
    errors = sun_errors(evaluate_sun_table(table, degrees, hs, hu), solar.illuminance_xyz(hs, hu), rgb_from_xyz, (hs, hu))
    block = {
        "description": "ln CIE XYZ (lux) of the sun's direct normal illuminance (Preetham et al. 1999 appendix, "
        "skysh.model.solar), 2D Chebyshev in the air-mass and turbidity variables",
        "rgb_from_xyz": np.asarray(rgb_from_xyz, dtype=np.float64).tolist(),
        "degrees": [list(degrees)],
        "fit": "least squares of ln XYZ, equal weights (relative errors)",
        "grid": {"kind": "Chebyshev-Gauss nodes of (x, y)", "shape": list(settings.sun_grid)},
        "held_out": {"count": int(hs.size), "seed": settings.seed,
                     "kinds": "uniform in (sun zenith, T); uniform in (air mass, T); the four edges; the corners"},
        "condition_number": condition,
        "largest_abs_sum": float(np.abs(table).sum(axis=0).max()),
        "errors": errors,
    }
    return NamedTable(table=table, degrees=np.array([degrees], dtype=np.int64)), block
