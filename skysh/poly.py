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
-   :func:`scale_unchecked`, :func:`chebyshev_unchecked`: the same for per-frame paths that checked once.
-   :func:`design`: the products T_i(x) T_j(y), i <= d_theta, j <= d_tau.
-   :func:`term_index`: flat index of the term (i, j) of degrees (d_theta, d_tau).

Term layout (as a comprehension)::

    [(i, j) for i in range(d_theta + 1) for j in range(d_tau + 1)]
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh._checks import as_float_array, check_count, check_flag, check_size, short_repr

__all__ = [
    "SUN_ZENITH_DOMAIN",
    "TURBIDITY_DOMAIN",
    "MAX_DEGREE",
    "scale",
    "scale_unchecked",
    "chebyshev",
    "chebyshev_unchecked",
    "design",
    "term_index",
    "n_terms",
]

SUN_ZENITH_DOMAIN: tuple[float, float] = (0.0, math.pi / 2.0)
"""Fitted sun zenith angles, radians (sun at the zenith to sun on the horizon)."""

TURBIDITY_DOMAIN: tuple[float, float] = (2.5, 6.0)
"""Fitted turbidities (Habel 2008 after Zotti et al. 2007: the model is unusable below 2.5)."""


MAX_DEGREE: int = 64
"""Largest polynomial degree accepted in either variable (the shipped file uses (13, 7); the
coefficient file format allows 31)."""

_LOG_TURBIDITY: tuple[float, float] = (math.log(TURBIDITY_DOMAIN[0]), math.log(TURBIDITY_DOMAIN[1]))


def scale(sun_zenith: ArrayLike, turbidity: ArrayLike, log_turbidity: bool = True) -> tuple[NDArray, NDArray]:
    """
    Map the domain onto [-1, 1]^2: x affine in sun zenith, y affine in log(turbidity).

    Parameters
    ----------
    sun_zenith, turbidity
        Radians and turbidity, finite, broadcasting; not range-checked (points
        outside the domain map outside [-1, 1]). ``turbidity > 0`` when
        ``log_turbidity``. Empty arrays give empty results.
    log_turbidity
        y affine in log(turbidity) (default, as shipped) or in turbidity (a bool).

    Returns
    -------
    x, y
        Arrays of the shapes of ``sun_zenith`` and ``turbidity``.

    Notes
    -----
    The sky's coefficients, once divided by :func:`skysh.preetham.luminance_scale`,
    still have a singularity at turbidities just below the domain; the log moves
    it further from [-1, 1] in the Chebyshev variable, so the coefficients of the
    fit decay faster (with the luminance scale, worst held-out E_mean at 3 bands
    1.25e-3 -> 4.1e-5 at degree (13, 7), printed by ``tools/fit_sky.py
    --compare-scalings``).
    """
    log_turbidity = check_flag(log_turbidity, "log_turbidity")
    ts = as_float_array(sun_zenith, "sun_zenith")
    t = as_float_array(turbidity, "turbidity")
    if log_turbidity and t.size and t.min() <= 0.0:
        raise ValueError(f"turbidity must be > 0 (its log is taken), got {float(t.min())!r}")
    return scale_unchecked(ts, t, log_turbidity)


def scale_unchecked(ts: NDArray, t: NDArray, log_turbidity: bool = True) -> tuple[NDArray, NDArray]:
    """:func:`scale` without its checks: float64 arrays (``t > 0`` when ``log_turbidity``), a bool."""
    lo_s, hi_s = SUN_ZENITH_DOMAIN
    x = (2.0 * ts - (lo_s + hi_s)) / (hi_s - lo_s)
    if log_turbidity:
        lo_t, hi_t = _LOG_TURBIDITY
        t = np.log(t)
    else:  # the plain affine map, kept for the comparison in tools/fit_sky.py --compare-scalings
        lo_t, hi_t = TURBIDITY_DOMAIN
    y = (2.0 * t - (lo_t + hi_t)) / (hi_t - lo_t)
    return x, y


def chebyshev(x: ArrayLike, degree: int) -> NDArray[np.float64]:
    """
    Chebyshev polynomials T_0 .. T_degree at ``x``: shape (..., degree + 1).

    ``x`` is finite, any shape (empty gives empty); ``degree`` an integer in
    [0, :data:`MAX_DEGREE`].
    """
    degree = check_count(degree, "degree", 0, MAX_DEGREE)
    x = as_float_array(x, "x")
    check_size(x.size * (degree + 1), "x", f"T_0 .. T_{degree} at {x.size:,} points")
    return chebyshev_unchecked(x, degree)


def chebyshev_unchecked(x: NDArray, degree: int) -> NDArray[np.float64]:
    """:func:`chebyshev` without its checks: a float64 array and an int ``degree`` in [0, :data:`MAX_DEGREE`]."""
    out = np.empty(x.shape + (degree + 1,))
    out[..., 0] = 1.0
    if degree >= 1:
        out[..., 1] = x
    for k in range(2, degree + 1):
        out[..., k] = 2.0 * x * out[..., k - 1] - out[..., k - 2]
    return out


# the names skysh/runtime.py still reads (issue 14: to go once it reads scale_unchecked and chebyshev_unchecked)


def _degrees(degrees: Any, name: str = "degrees") -> tuple[int, int]:
    """(d_theta, d_tau) as ints, each in [0, MAX_DEGREE]."""
    try:
        d_theta, d_tau = degrees
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be a pair of integers (d_theta, d_tau) in [0, {MAX_DEGREE}], got {short_repr(degrees)}"
        ) from None
    return check_count(d_theta, f"{name}[0]", 0, MAX_DEGREE), check_count(d_tau, f"{name}[1]", 0, MAX_DEGREE)


def n_terms(degrees: tuple[int, int]) -> int:
    """Number of terms of a polynomial of degrees (d_theta, d_tau), integers in [0, :data:`MAX_DEGREE`]."""
    d_theta, d_tau = _degrees(degrees)
    return (d_theta + 1) * (d_tau + 1)


def term_index(i: int, j: int, degrees: tuple[int, int]) -> int:
    """Flat index of the term T_i(x) T_j(y) in a design of degrees (d_theta, d_tau); 0 <= i <= d_theta, 0 <= j <= d_tau."""
    d_theta, d_tau = _degrees(degrees)
    i, j = check_count(i, "i", 0, d_theta), check_count(j, "j", 0, d_tau)
    return i * (d_tau + 1) + j


def design(
    sun_zenith: ArrayLike, turbidity: ArrayLike, degrees: tuple[int, int], log_turbidity: bool = True
) -> NDArray[np.float64]:
    """
    Design matrix of the 2D Chebyshev polynomial at (sun zenith, turbidity).

    Parameters
    ----------
    sun_zenith, turbidity
        Radians and turbidity, broadcasting to (...,). Not range-checked here
        (as :func:`scale`). Empty arrays give an empty design.
    degrees
        (d_theta, d_tau), integers in [0, :data:`MAX_DEGREE`].
    log_turbidity
        Chebyshev variable affine in log(turbidity) (default, as shipped) or
        in turbidity (a bool).

    Returns
    -------
    ndarray
        (..., (d_theta + 1) (d_tau + 1)), term (i, j) at ``i (d_tau + 1) + j``.
    """
    d_theta, d_tau = _degrees(degrees)
    x, y = scale(sun_zenith, turbidity, log_turbidity)
    try:
        x, y = np.broadcast_arrays(x, y)
    except ValueError:
        raise ValueError(
            f"sun_zenith and turbidity must broadcast together, got shapes {np.shape(x)} and {np.shape(y)}"
        ) from None
    terms = (d_theta + 1) * (d_tau + 1)
    check_size(x.size * terms, "sun_zenith", f"{terms} terms at {x.size:,} points")
    tx = chebyshev_unchecked(x, d_theta)
    ty = chebyshev_unchecked(y, d_tau)
    return (tx[..., :, None] * ty[..., None, :]).reshape(x.shape + (terms,))
