"""
Sky points over the fitted domain and their SH
==============================================

-   :func:`sample_sky_parameters`: (sun zenith, sun azimuth, turbidity) points,
    low-discrepancy over the fitted domain (:data:`skysh.domain.SKY`,
    :data:`skysh.domain.SKY`).
-   :func:`reference_sh`: the reference projection :func:`skysh.model.preetham.sky_sh`
    at many points, any band count.
-   :func:`sky_coefficients`: 9-coefficient RGB SH at many points from a *named*
    source, the shipped runtime or the reference.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import (
    MAX_ARRAY_ELEMENTS,
    as_float_array,
    check_choice,
    check_count,
    check_range,
    check_seed,
)
from skysh.domain import SKY
from skysh.model import preetham

__all__ = ["SKY_SOURCES", "SKY_PARAMETERS", "sample_sky_parameters", "reference_sh", "sky_coefficients"]

SKY_SOURCES: tuple[str, ...] = ("runtime", "reference")
"""Sky data sources of :func:`sky_coefficients`: the shipped runtime (:class:`skysh.SkySH`, its
polynomial fit) or the reference projection (:func:`skysh.model.preetham.sky_sh`). There is no automatic
choice: a study says which data it measures."""

SKY_PARAMETERS: int = 3
"""Parameters per sky point: sun zenith, sun azimuth, turbidity."""

MAX_SKY_POINTS: int = MAX_ARRAY_ELEMENTS // SKY_PARAMETERS
"""Largest ``n`` of :func:`sample_sky_parameters`: its (n, 3) sample stays within the package's array limit."""

_RGB: int = 3
_QUADRATIC: int = 9  # coefficients of bands l <= 2


def sample_sky_parameters(n: int, seed: int | None = 0) -> tuple[NDArray, NDArray, NDArray]:
    """
    Spread ``n`` (sun zenith, sun azimuth, turbidity) points over the fitted sky domain.

    Parameters
    ----------
    n
        Number of points, in [1, :data:`MAX_SKY_POINTS`].
    seed
        Seed of the scrambled Halton sequence, None or an integer in [0, 2^64 - 1]
        (same seed, same points).

    Returns
    -------
    sun_zenith, sun_azimuth, turbidity
        Shapes (n,) each: radians in :data:`skysh.domain.SKY`, radians
        in [0, 2 pi), and turbidity in :data:`skysh.domain.SKY`, uniform
        in each parameter (low-discrepancy, so small ``n`` still covers the domain).
    """
    n = check_count(n, "n", 1, MAX_SKY_POINTS)
    seed = check_seed(seed)
    from scipy.stats import qmc  # imported on first use: scipy is heavy

    u = qmc.Halton(d=SKY_PARAMETERS, scramble=True, rng=np.random.default_rng(seed)).random(n)
    (z0, z1), (t0, t1) = SKY.x.interval, SKY.y.interval
    return z0 + (z1 - z0) * u[:, 0], 2.0 * math.pi * u[:, 1], t0 + (t1 - t0) * u[:, 2]


def reference_sh(sun_zenith: NDArray, turbidity: NDArray, sun_azimuth: NDArray, bands: int) -> NDArray[np.float64]:
    """
    (P, bands^2, 3) reference projections :func:`skysh.model.preetham.sky_sh` of P sky points.

    Parameters
    ----------
    sun_zenith, turbidity, sun_azimuth
        Shape (P,) each: radians, [1.7, 10] (the model's domain), radians; each
        point is validated by :func:`skysh.model.preetham.sky_sh`.
    bands
        Bands of the projection, [1, 64].

    Returns
    -------
    ndarray
        Linear-sRGB SH in cd/m^2; (0, bands^2, 3) for no points. A Python loop over
        the points: the reference takes scalars.
    """
    if sun_zenith.size == 0:
        return np.zeros((0, bands * bands, _RGB))
    return np.stack([preetham.sky_sh(float(a), float(b), bands=bands, sun_azimuth=float(g))
                     for a, b, g in zip(sun_zenith, turbidity, sun_azimuth, strict=True)])


def sky_coefficients(
    sun_zenith: ArrayLike,
    turbidity: ArrayLike,
    sun_azimuth: ArrayLike = 0.0,
    source: str = "runtime",
) -> tuple[NDArray[np.float64], str]:
    """
    9-coefficient RGB SH of the Preetham sky at many points, from the runtime or the reference.

    Parameters
    ----------
    sun_zenith
        Radians, in :data:`skysh.domain.SKY`, shape (P,) (or scalar).
    turbidity
        In :data:`skysh.domain.SKY`, broadcasting with ``sun_zenith``.
    sun_azimuth
        Radians, broadcasting with ``sun_zenith``.
    source
        One of :data:`SKY_SOURCES`. ``"runtime"``: ``skysh.SkySH.load().coefficients(...,
        bands=3, gibbs=False, dering=False)``, vectorised. ``"reference"``:
        :func:`reference_sh` with 3 bands, point by point.

    Returns
    -------
    coeffs, source
        (P, 9, 3) linear-sRGB SH in cd/m^2, and the name of the source.

    Notes
    -----
    The runtime is asked for ``gibbs=False`` and ``dering=False`` so that both sources
    give the same quantity: the unfiltered projection (the runtime's being its fit).
    A runtime that cannot load raises its own error; it is never replaced by the reference.
    """
    check_choice(source, "source", SKY_SOURCES)
    ts = check_range(sun_zenith, "sun_zenith", *SKY.x.interval, unit="rad")
    t = check_range(turbidity, "turbidity", *SKY.y.interval)
    az = as_float_array(sun_azimuth, "sun_azimuth")
    ts, t, az = (np.ravel(a) for a in np.broadcast_arrays(ts, t, az))
    if source == "reference":
        return reference_sh(ts, t, az, 3), source
    from skysh import SkySH

    coeffs = SkySH.load().coefficients(ts, t, sun_azimuth=az, bands=3, gibbs=False, dering=False, irradiance=False)
    return np.asarray(coeffs, dtype=np.float64).reshape(ts.shape + (_QUADRATIC, _RGB)), source
