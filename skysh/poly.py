"""
Two-dimensional Chebyshev polynomials over the fitted sky domain
================================================================

The polynomial basis of the fitted tables (Habel 2008, eq. 1), written in
Chebyshev polynomials of variables scaled to [-1, 1] instead of the seed's raw
monomials ``theta^i tau^j`` (whose Vandermonde matrix at degree (13, 7) has a
condition number near 1e15; see the error report's stability section).

-   :data:`SUN_ZENITH_DOMAIN`, :data:`TURBIDITY_DOMAIN`: the fitted domain.
-   :func:`scale`: (sun zenith, turbidity) -> (x, y) in [-1, 1]^2.
-   :func:`chebyshev`: T_0 .. T_d at x, by the three-term recurrence.
-   :func:`design`: the products T_i(x) T_j(y), i <= d_theta, j <= d_tau.
-   :func:`term_index`: flat index of the term (i, j) of degrees (d_theta, d_tau).

Term layout (as a comprehension)::

    [(i, j) for i in range(d_theta + 1) for j in range(d_tau + 1)]
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["SUN_ZENITH_DOMAIN", "TURBIDITY_DOMAIN", "scale", "chebyshev", "design", "term_index", "n_terms"]

SUN_ZENITH_DOMAIN: tuple[float, float] = (0.0, math.pi / 2.0)
"""Fitted sun zenith angles, radians (sun at the zenith to sun on the horizon)."""

TURBIDITY_DOMAIN: tuple[float, float] = (2.5, 6.0)
"""Fitted turbidities (Habel 2008 after Zotti et al. 2007: the model is unusable below 2.5)."""


_LOG_TURBIDITY: tuple[float, float] = (math.log(TURBIDITY_DOMAIN[0]), math.log(TURBIDITY_DOMAIN[1]))


def scale(sun_zenith: ArrayLike, turbidity: ArrayLike, log_turbidity: bool = True) -> tuple[NDArray, NDArray]:
    """
    Map the domain onto [-1, 1]^2: x affine in sun zenith, y affine in log(turbidity).

    Notes
    -----
    The sky's coefficients, once divided by :func:`skysh.preetham.luminance_scale`,
    still have a singularity at turbidities just below the domain; the log moves
    it further from [-1, 1] in the Chebyshev variable, so the coefficients of the
    fit decay faster (with the luminance scale, worst held-out E_mean at 3 bands
    1.25e-3 -> 4.1e-5 at degree (13, 7), printed by ``tools/fit_sky.py
    --compare-scalings``).
    """
    lo_s, hi_s = SUN_ZENITH_DOMAIN
    x = (2.0 * np.asarray(sun_zenith, dtype=np.float64) - (lo_s + hi_s)) / (hi_s - lo_s)
    t = np.asarray(turbidity, dtype=np.float64)
    if log_turbidity:
        lo_t, hi_t = _LOG_TURBIDITY
        t = np.log(t)
    else:  # the plain affine map, kept for the comparison in tools/fit_sky.py --compare-scalings
        lo_t, hi_t = TURBIDITY_DOMAIN
    y = (2.0 * t - (lo_t + hi_t)) / (hi_t - lo_t)
    return x, y


def chebyshev(x: ArrayLike, degree: int) -> NDArray[np.float64]:
    """Chebyshev polynomials T_0 .. T_degree at ``x``: shape (..., degree + 1)."""
    x = np.asarray(x, dtype=np.float64)
    out = np.empty(x.shape + (degree + 1,))
    out[..., 0] = 1.0
    if degree >= 1:
        out[..., 1] = x
    for k in range(2, degree + 1):
        out[..., k] = 2.0 * x * out[..., k - 1] - out[..., k - 2]
    return out


def n_terms(degrees: tuple[int, int]) -> int:
    """Number of terms of a polynomial of degrees (d_theta, d_tau)."""
    return (degrees[0] + 1) * (degrees[1] + 1)


def term_index(i: int, j: int, degrees: tuple[int, int]) -> int:
    """Flat index of the term T_i(x) T_j(y) in a design of degrees (d_theta, d_tau)."""
    return i * (degrees[1] + 1) + j


def design(
    sun_zenith: ArrayLike, turbidity: ArrayLike, degrees: tuple[int, int], log_turbidity: bool = True
) -> NDArray[np.float64]:
    """
    Design matrix of the 2D Chebyshev polynomial at (sun zenith, turbidity).

    Parameters
    ----------
    sun_zenith, turbidity
        Radians and turbidity, broadcasting to (...,). Not range-checked here.
    degrees
        (d_theta, d_tau).
    log_turbidity
        Chebyshev variable affine in log(turbidity) (default, as shipped) or in turbidity.

    Returns
    -------
    ndarray
        (..., (d_theta + 1) (d_tau + 1)), term (i, j) at ``i (d_tau + 1) + j``.
    """
    x, y = scale(sun_zenith, turbidity, log_turbidity)
    x, y = np.broadcast_arrays(x, y)
    tx = chebyshev(x, degrees[0])
    ty = chebyshev(y, degrees[1])
    return (tx[..., :, None] * ty[..., None, :]).reshape(x.shape + (n_terms(degrees),))
