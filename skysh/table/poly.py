"""
Two-dimensional Chebyshev polynomials over the fitted sky domain
================================================================

The polynomial basis of the fitted tables (Habel 2008, eq. 1), written in
Chebyshev polynomials of variables scaled to [-1, 1] instead of the seed's raw
monomials ``theta^i tau^j`` (whose Vandermonde matrix at degree (13, 7) has a
condition number near 1e15; see the error report's stability section).

-   :func:`scale`: (sun zenith, turbidity) -> (x, y) in [-1, 1]^2 over the fitted domain
    (:data:`skysh.domain.SKY`, which holds the intervals and the term order).
-   :func:`chebyshev`: T_0 .. T_d at x, by the three-term recurrence.
-   :func:`scale_unchecked`, :func:`chebyshev_unchecked`: the same for per-frame paths that checked once;
    :func:`chebyshev_rows`: the batch runtime's layout (a row per degree), built by doubling.
-   :func:`design`: the products T_i(x) T_j(y), i <= d_theta, j <= d_tau.
-   :func:`n_terms`: the number of terms of degrees (d_theta, d_tau).

Term layout (:data:`skysh.domain.TERM_ORDER`, :func:`skysh.domain.term_index`; as a comprehension)::

    [(i, j) for i in range(d_theta + 1) for j in range(d_tau + 1)]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_count, check_flag, check_size
from skysh.domain import MAX_DEGREE, SKY, check_degrees

__all__ = ["scale", "scale_unchecked", "chebyshev_unchecked", "chebyshev_rows", "design", "n_terms"]


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
    The sky's coefficients, once divided by :func:`skysh.model.preetham.luminance_scale`,
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
    # The fit's arithmetic, (2 v - (lo + hi)) / (hi - lo): it differs from the runtime's scalar form
    # v * scale - shift (skysh.domain.Variable) by rounding only, and keeps the fitted tables bit for bit.
    lo_s, hi_s = SKY.x.interval
    x = (2.0 * ts - (lo_s + hi_s)) / (hi_s - lo_s)
    if log_turbidity:
        lo_t, hi_t = SKY.y.fitted
        t = np.log(t)
    else:  # the plain affine map, kept for the comparison in tools/fit_sky.py --compare-scalings
        lo_t, hi_t = SKY.y.interval
    y = (2.0 * t - (lo_t + hi_t)) / (hi_t - lo_t)
    return x, y


def chebyshev(x: ArrayLike, degree: int) -> NDArray[np.float64]:
    """
    Chebyshev polynomials T_0 .. T_degree at ``x``: shape (..., degree + 1).

    ``x`` is finite, any shape (empty gives empty); ``degree`` an integer in
    [0, :data:`skysh.domain.MAX_DEGREE`].
    """
    degree = check_count(degree, "degree", 0, MAX_DEGREE)
    x = as_float_array(x, "x")
    check_size(x.size * (degree + 1), "x", f"T_0 .. T_{degree} at {x.size:,} points")
    return chebyshev_unchecked(x, degree)


def chebyshev_unchecked(x: NDArray, degree: int) -> NDArray[np.float64]:
    """:func:`chebyshev` without its checks: a float64 array and an int ``degree`` in [0, :data:`skysh.domain.MAX_DEGREE`]."""
    out = np.empty(x.shape + (degree + 1,))
    out[..., 0] = 1.0
    if degree >= 1:
        out[..., 1] = x
    for k in range(2, degree + 1):
        out[..., k] = 2.0 * x * out[..., k - 1] - out[..., k - 2]
    return out


def chebyshev_rows(x: NDArray, degree: int) -> NDArray[np.float64]:
    """
    T_0 .. T_degree at the points of a 1-D float64 array ``x`` (unchecked), shape (degree + 1, n): one
    contiguous row per degree, as the batch runtime reads them.

    Built by doubling, T_(k + j) = 2 T_k T_j - T_(k - j) for j = 1 .. k (the product identity
    2 T_a T_b = T_(a + b) + T_|a - b|): three array operations per doubling, about log2(degree) of them,
    instead of a Python step per degree. Agrees with the three-term recurrence to a few eps
    (tests/table/test_poly.py).
    """
    out = np.empty((degree + 1, x.shape[0]))
    out[0] = 1.0
    if degree:
        out[1] = x
    known = 1  # T_0 .. T_known are in place
    while known < degree:
        j = min(known, degree - known)
        new = out[known + 1 : known + j + 1]
        np.multiply(out[1 : j + 1], 2.0 * out[known], out=new)
        new -= out[known - j : known][::-1]  # T_(known - 1) .. T_(known - j)
        known += j
    return out


def n_terms(degrees: tuple[int, int]) -> int:
    """Number of terms of a polynomial of degrees (d_theta, d_tau), integers in [0, :data:`skysh.domain.MAX_DEGREE`]."""
    d_theta, d_tau = check_degrees(degrees)
    return (d_theta + 1) * (d_tau + 1)


def design(sun_zenith: ArrayLike, turbidity: ArrayLike, degrees: tuple[int, int],
           log_turbidity: bool = True) -> NDArray[np.float64]:
    """
    Design matrix of the 2D Chebyshev polynomial at (sun zenith, turbidity).

    Parameters
    ----------
    sun_zenith, turbidity
        Radians and turbidity, broadcasting to (...,). Not range-checked here
        (as :func:`scale`). Empty arrays give an empty design.
    degrees
        (d_theta, d_tau), integers in [0, :data:`skysh.domain.MAX_DEGREE`].
    log_turbidity
        Chebyshev variable affine in log(turbidity) (default, as shipped) or
        in turbidity (a bool).

    Returns
    -------
    ndarray
        (..., (d_theta + 1) (d_tau + 1)), term (i, j) at ``i (d_tau + 1) + j``.
    """
    d_theta, d_tau = check_degrees(degrees)
    x, y = scale(sun_zenith, turbidity, log_turbidity)
    try:
        x, y = np.broadcast_arrays(x, y)
    except ValueError:
        raise ValueError(
            f"sun_zenith and turbidity must broadcast together, got shapes {np.shape(x)} and {np.shape(y)}") from None
    terms = (d_theta + 1) * (d_tau + 1)
    check_size(x.size * terms, "sun_zenith", f"{terms} terms at {x.size:,} points")
    tx, ty = chebyshev_unchecked(x, d_theta), chebyshev_unchecked(y, d_tau)
    return (tx[..., :, None] * ty[..., None, :]).reshape(x.shape + (terms,))
