"""
Irradiance reconstructions against the sky's exact irradiance
=============================================================

Seed 003 (Hazel, Geomerics) gives the linear L1 and L2 irradiance and, via the
CEDEC 2015 talk, the non-linear L1 of Geomerics (:mod:`skysh.post.hazel`); the
deringing of :mod:`skysh.post.dering` windows the L2 radiance first. This study
measures all four on the Preetham sky:

-   :func:`exact_irradiance`: the irradiance ``I = E / pi`` of the true (not
    band-limited) sky, by a projection to :data:`EXACT_BANDS` bands.
-   :func:`irradiance_comparison`: each reconstruction from the same projection
    against it, over a sphere of normals, with the hand-counted shader cost
    (:data:`COSTS`).
-   :func:`irradiance_experiment`: the comparison over sky points spread over the
    fitted domain.

``tools/quantize_experiment.py`` prints the tables, the truncation estimate of
the exact irradiance and a numpy throughput; ``tests/test_studies.py`` checks
:func:`exact_irradiance` against an independent adaptive quadrature of the sky.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_count
from skysh.model import preetham
from skysh.post import dering, hazel
from skysh.sh import basis as sh
from studies.sky import reference_sh, sample_sky_parameters

__all__ = [
    "EXACT_BANDS",
    "TRUNCATION_STEP",
    "COMPARISON_THETA_NODES",
    "METHODS",
    "COSTS",
    "exact_irradiance",
    "irradiance_comparison",
    "irradiance_experiment",
]

EXACT_BANDS: int = 32
"""Bands of the sky projection behind :func:`exact_irradiance`. The sky jumps to zero at the
horizon, so its coefficients decay slowly and the clamped-cosine series converges only
algebraically: many bands are needed. Its error is bounded in ``tests/test_studies.py`` (against an
adaptive quadrature of the true sky) and estimated by every comparison (``"truncation"``)."""

TRUNCATION_STEP: int = 8
"""The comparison's truncation estimate is ``max |I(exact_bands) - I(exact_bands - TRUNCATION_STEP)| / R0``."""

COMPARISON_THETA_NODES: int = 24
"""Gauss nodes in cos(theta) of the normals of :func:`irradiance_comparison` (2 * 24^2 = 1152
normals, area-weighted)."""

METHODS: tuple[str, ...] = ("L1 linear", "L1 non-linear (Geomerics)", "L2", "L2 deringed")
"""Rows of :func:`irradiance_comparison`."""

COSTS: dict[str, dict[str, Any]] = {
    "L1 linear": {
        "floats_per_channel": 4,
        "alu_per_normal": 3,
        "transcendental_per_normal": 0,
        "per_probe": "fold 2 R1 (3 mul)",
    },
    "L1 non-linear (Geomerics)": {
        "floats_per_channel": 4,
        "alu_per_normal": 6,
        "transcendental_per_normal": 2,
        "per_probe": "|R1|, d, r, p, a, R0 a, R0 (1-a)(1+p): 1 sqrt, 2 div, ~10 ALU",
    },
    "L2": {
        "floats_per_channel": 9,
        "alu_per_normal": 8,
        "transcendental_per_normal": 0,
        "per_probe": "fold the factors into the 9 coefficients (9 mul)",
    },
    "L2 deringed": {
        "floats_per_channel": 9,
        "alu_per_normal": 8,
        "transcendental_per_normal": 0,
        "per_probe": "dering window search (skysh.post.dering), then as L2",
    },
}
"""Hand-counted shader cost per normal and colour channel (multiply-adds; transcendental = sqrt,
log2, exp2), with per-probe work done once; the count is derived in docs/hazel.md ("Shader cost")."""


def exact_irradiance(
    sun_zenith: float,
    turbidity: float,
    normals: ArrayLike,
    sun_azimuth: float = 0.0,
    bands: int = EXACT_BANDS,
) -> NDArray[np.float64]:
    """
    Irradiance ``I = E / pi`` of the true Preetham sky (not band-limited).

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    turbidity
        [1.7, 10] (the model's domain; the runtime covers [2.5, 6]).
    normals
        Unit vectors (..., 3).
    sun_azimuth
        Radians.
    bands
        Bands of the projection, [2, 64]; default :data:`EXACT_BANDS`.

    Returns
    -------
    ndarray
        (..., 3) linear sRGB, cd/m^2.

    Notes
    -----
    ``sum_lm (A_l / pi) L_lm Y_lm(n)`` with ``L_lm`` from :func:`skysh.model.preetham.sky_sh`
    and the clamped-cosine factors A_l of Ramamoorthi and Hanrahan (2001). A direct quadrature of
    ``L max(0, n.w)`` is the other route but needs a rule per normal to resolve the
    kink along n.w = 0 (the tests do that, as the independent reference).
    """
    bands = check_count(bands, "bands", 2, sh.MAX_BANDS)
    c = preetham.sky_sh(sun_zenith, turbidity, bands=bands, sun_azimuth=sun_azimuth)
    return sh.evaluate(sh.irradiance(c) / math.pi, normals)


def _error_row(method: str, value: NDArray, exact: NDArray, scale: NDArray, area: NDArray) -> dict[str, Any]:
    """One row of the comparison: errors of ``value`` (P, M, C) relative to the mean irradiance ``scale``."""
    error = (value - exact) / scale
    return {
        "method": method,
        "mean_abs": float(np.mean(np.einsum("m,pmc->pc", area, np.abs(error)))),
        "rms": float(np.sqrt(np.mean(np.einsum("m,pmc->pc", area, error * error)))),
        "max_abs": float(np.max(np.abs(error))),
        "min": float(np.min(value / scale)),
        "negative_area": float(np.mean(np.einsum("m,pmc->pc", area, (value < 0.0).astype(np.float64)))),
        **COSTS[method],
    }


def _estimates(coeffs: NDArray, normals: NDArray) -> dict[str, NDArray]:
    """Each method's irradiance (P, M, C) from the first 4 or 9 coefficients of the same projections."""
    deringed, _ = dering.dering(coeffs[:, :9], target="irradiance")
    return {
        "L1 linear": hazel.irradiance(coeffs[:, None, :4], normals),
        "L1 non-linear (Geomerics)": hazel.irradiance_l1_nonlinear(coeffs[:, None, :4], normals),
        "L2": hazel.irradiance(coeffs[:, None, :9], normals),
        "L2 deringed": hazel.irradiance(deringed[:, None], normals),
    }


def irradiance_comparison(
    sun_zenith: ArrayLike,
    turbidity: ArrayLike,
    sun_azimuth: ArrayLike = 0.0,
    exact_bands: int = EXACT_BANDS,
    n_theta: int = COMPARISON_THETA_NODES,
) -> dict[str, Any]:
    """
    Accuracy of L1 linear, L1 non-linear, L2 and deringed L2 irradiance against the sky's exact irradiance.

    Parameters
    ----------
    sun_zenith, turbidity, sun_azimuth
        Sky points (radians, turbidity in [1.7, 10], radians), broadcasting to (P,), P >= 1.
    exact_bands
        Bands of the "exact" irradiance (:func:`exact_irradiance`), [10, 64].
    n_theta
        Gauss nodes in cos(theta) of the sphere of normals, [2, :data:`skysh.sh.basis.MAX_GAUSS_NODES`].

    Returns
    -------
    dict
        ``"rows"``: per method (:data:`METHODS`) ``method``, ``mean_abs``, ``rms``,
        ``max_abs`` (errors over the sphere of normals divided by the probe's mean
        irradiance R0, averaged or maximised over points and channels), ``min`` (the
        smallest I / R0: negative means negative irradiance), ``negative_area``
        (fraction of the sphere with I < 0) and the :data:`COSTS` entries.
        ``"notes"``: what the rows were computed from. ``"truncation"``: an upper
        estimate of the exact irradiance's own error (:data:`TRUNCATION_STEP`).
        ``"points"``, ``"exact_bands"``, ``"normals"``.

    Notes
    -----
    All four start from the same projection, so the differences are those of the
    reconstructions, not of a fit. Errors are relative to R0 rather than to I(n)
    because the sky gives zero irradiance to a normal pointing straight down. The
    errors of linear L1 and L2 are even, ``e(n) = e(-n)``: by Hazel's antipodal
    identity their odd part (the L1 term) is exact.
    """
    exact_bands = check_count(exact_bands, "exact_bands", TRUNCATION_STEP + 2, sh.MAX_BANDS)
    n_theta = check_count(n_theta, "n_theta", 2, sh.MAX_GAUSS_NODES)
    ts, t, az = (np.ravel(a) for a in np.broadcast_arrays(
        as_float_array(sun_zenith, "sun_zenith"), as_float_array(turbidity, "turbidity"),
        as_float_array(sun_azimuth, "sun_azimuth")))
    if ts.size == 0:
        raise ValueError("sun_zenith must hold at least one sky point")
    coeffs = reference_sh(ts, t, az, exact_bands)  # (P, B^2, 3), each point validated by sky_sh
    normals, weights = sh.quadrature_rule(n_theta)
    y = sh.basis(normals, exact_bands)  # (M, B^2)
    irr = sh.irradiance(coeffs) / math.pi
    exact = np.einsum("mk,pkc->pmc", y, irr)
    k_low = (exact_bands - TRUNCATION_STEP) ** 2
    truncated = np.einsum("mk,pkc->pmc", y[:, :k_low], irr[:, :k_low])
    r0 = hazel.L0_SCALE * coeffs[:, 0, :]  # (P, C) mean irradiance = mean radiance
    if not np.all(r0 > 0.0):
        raise ValueError("the sky must have a positive mean in every channel")
    scale = r0[:, None, :]
    area = weights / (4.0 * math.pi)
    estimates = _estimates(coeffs, normals)
    return {
        "rows": [_error_row(method, estimates[method], exact, scale, area) for method in METHODS],
        "notes": [f"exact irradiance: {exact_bands}-band projection of the true sky (skysh.model.preetham.sky_sh)",
                  "L2 deringed: skysh.post.dering.dering(coeffs, target='irradiance') (windowed radiance SH), then as L2"],
        "truncation": float(np.max(np.abs(exact - truncated) / scale)),
        "points": int(ts.size),
        "exact_bands": exact_bands,
        "normals": int(normals.shape[0]),
    }


def irradiance_experiment(
    n_points: int = 64,
    seed: int | None = 0,
    exact_bands: int = EXACT_BANDS,
    n_theta: int = COMPARISON_THETA_NODES,
) -> dict[str, Any]:
    """
    :func:`irradiance_comparison` over ``n_points`` sky points spread over the fitted domain.

    The points are :func:`studies.sky.sample_sky_parameters` (``n_points`` and ``seed``
    as its ``n`` and ``seed``). Returns the comparison's dict plus ``"seed"``.
    """
    ts, az, t = sample_sky_parameters(n_points, seed)
    result = irradiance_comparison(ts, t, az, exact_bands=exact_bands, n_theta=n_theta)
    result["seed"] = seed
    return result
