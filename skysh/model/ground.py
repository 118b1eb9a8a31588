"""
The ground: a Lambertian lower hemisphere lit by the sky and the sun
===================================================================

The Preetham sky is zero below the horizon (the Habel seed's setting). A
Lambertian ground of albedo rho under a horizontal irradiance E_h reflects a
uniform radiance ``L_g = rho E_h / pi`` into every upward direction, so seen from
a point above it the lower hemisphere has the uniform radiance L_g. Its SH are
zonal with a closed form.

-   :func:`ground_radiance`: ``L_g = albedo x E_h / pi`` per channel, with checks.
-   :func:`ground_sh`: the SH of a uniform lower hemisphere (closed form).
-   :data:`GROUND_ZONAL`: the per-band factors of that closed form.
-   :func:`ground_irradiance`: its exact irradiance ``pi L_g (1 - n_z) / 2``.
-   :func:`horizontal_irradiance_from_sh`: the exact horizontal irradiance of any
    light that is zero below the horizon, from its band-1 zonal coefficient.

Closed form
-----------
For m != 0 the azimuthal integral vanishes. For m = 0, with
``Y_l0 = K_l P_l(z)``, ``K_l = sqrt((2 l + 1) / (4 pi))`` and Bonnet's
``(2 l + 1) P_l = P'_{l+1} - P'_{l-1}`` (and ``P_n(-1) = (-1)^n``)::

    c_l0 = L_g 2 pi K_l int_{-1}^{0} P_l(z) dz
         = L_g 2 pi K_l (P_{l+1}(0) - P_{l-1}(0)) / (2 l + 1)     (l >= 1)
    c_00 = L_g 2 pi K_0 = L_g sqrt(pi)

with ``P_{2k}(0) = (-1)^k C(2k, k) / 4^k`` and ``P_odd(0) = 0``: only l = 0 and
odd l are non-zero; c_10 = -L_g sqrt(3 pi) / 2.

Irradiance, and why the ground needs no Gibbs filter
----------------------------------------------------
The irradiance SH are ``A_l c_l0``: A_l vanishes for odd l >= 3 and c_l0 for
even l >= 2, so only bands 0 and 1 survive and any N >= 2 bands give the
ground's irradiance *exactly*: ``E(n) = (pi L_g / 2)(1 - n_z)`` (the view factor
of a uniform hemisphere). The zonal sinc filter (Habel eq. 5) would scale band
1 by sinc(pi / N) and make it wrong by up to ``(1 - sinc(pi / N)) / 2`` of
``pi L_g`` (8.7 % at N = 3); only the radiance reconstruction rings.
``tools/sun_study.py`` prints both.

Exact horizontal irradiance
---------------------------
For any radiance L that is zero below the horizon, ``E_h = int L(w) max(0, w_z)
dw = int L(w) w_z dw = sqrt(4 pi / 3) c_10``: exact, without truncation, from the
unfiltered, unwindowed band-1 zonal coefficient (the sky's true projection or
its fit, and the sun's delta: ``E_sun cos theta_s``).

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: the sky is zero below
    the horizon; ground colour named as future work; eq. (5), the Gibbs filter.
-   Ramamoorthi, R., Hanrahan, P. (2001): the clamped-cosine factors A_l.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_bands, check_dirs
from skysh.sh import basis as sh

__all__ = ["GROUND_ZONAL", "HORIZONTAL_FACTOR", "ground_radiance", "horizontal_irradiance_from_sh"]


def _legendre_at_zero(n: int) -> float:
    """P_n(0): 0 for odd n, (-1)^k C(2k, k) / 4^k for n = 2k (exact rational, rounded once)."""
    if n % 2:
        return 0.0
    k = n // 2
    return (-1.0) ** k * (math.comb(2 * k, k) / 4.0**k)


def _ground_zonal(bands: int) -> NDArray[np.float64]:
    out = np.zeros(bands)
    for l in range(bands):
        k = math.sqrt((2 * l + 1) / (4.0 * math.pi))
        integral = 1.0 if l == 0 else (_legendre_at_zero(l + 1) - _legendre_at_zero(l - 1)) / (2 * l + 1)
        out[l] = 2.0 * math.pi * k * integral
    out.flags.writeable = False
    return out


GROUND_ZONAL: NDArray[np.float64] = _ground_zonal(sh.MAX_BANDS)
"""(64,) ``c_l0 / L_g`` of a uniform lower hemisphere of unit radiance, sr^(1/2) units of the SH:
sqrt(pi), -sqrt(3 pi)/2, 0, ... (non-zero for l = 0 and odd l only)."""

HORIZONTAL_FACTOR: float = math.sqrt(4.0 * math.pi / 3.0)
"""E_h / c_10 = 1 / Y_10(+Z) for a light zero below the horizon (see the module docstring)."""

_ZONAL_INDEX: NDArray[np.intp] = np.array([l * (l + 1) for l in range(sh.MAX_BANDS)], dtype=np.intp)
"""Flat index of (l, 0)."""


def ground_radiance(ground_albedo: ArrayLike, horizontal_irradiance: ArrayLike) -> NDArray[np.float64]:
    """
    Uniform radiance of a Lambertian ground, ``albedo x E_h / pi``.

    Parameters
    ----------
    ground_albedo
        A number or one value per channel (an RGB triple), each in [0, 1].
    horizontal_irradiance
        The irradiance of the horizontal ground per channel, (C,) or (..., C),
        lux (cd/m^2 x sr) for luminance-scaled RGB; finite.

    Returns
    -------
    ndarray
        (..., C), cd/m^2: the radiance reflected upward in every direction,
        i.e. the ground's exitance ``pi L_g = albedo x E_h`` divided by pi.
    """
    albedo = as_float_array(ground_albedo, "ground_albedo")
    e = as_float_array(horizontal_irradiance, "horizontal_irradiance")
    if e.ndim == 0:
        raise ValueError(f"horizontal_irradiance must have shape (C,) or (..., C), got {e.shape}")
    if albedo.ndim > 1 or (albedo.ndim == 1 and albedo.shape[0] != e.shape[-1]):
        raise ValueError(f"ground_albedo must be a number or one value per channel ({e.shape[-1]}), "
                         f"got shape {albedo.shape}")
    if albedo.size and (albedo.min() < 0.0 or albedo.max() > 1.0):
        raise ValueError(f"ground_albedo must lie in [0, 1], got {albedo.tolist()}")
    return albedo * e / math.pi


def ground_sh(radiance: ArrayLike, bands: int = 3) -> NDArray[np.float64]:
    """
    SH of a uniform lower hemisphere (z < 0) of radiance ``radiance``.

    Parameters
    ----------
    radiance
        L_g per channel, (C,) or (..., C), e.g. from :func:`ground_radiance`.
    bands
        Number of bands N in [1, 64].

    Returns
    -------
    ndarray
        (..., N * N, C): zonal, ``c_l0 = GROUND_ZONAL[l] x L_g``, every m != 0
        coefficient exactly 0. Add it to sky SH after the Gibbs filter (see the
        module docstring) and before any irradiance convolution.
    """
    bands = check_bands(bands, high=sh.MAX_BANDS)
    lg = as_float_array(radiance, "radiance")
    if lg.ndim == 0:
        raise ValueError(f"radiance must have shape (C,) or (..., C), got {lg.shape}")
    out = np.zeros(lg.shape[:-1] + (bands * bands, lg.shape[-1]))
    out[..., _ZONAL_INDEX[:bands], :] = GROUND_ZONAL[:bands, None] * lg[..., None, :]
    return out


def ground_irradiance(radiance: ArrayLike, normals: ArrayLike) -> NDArray[np.float64]:
    """
    Exact irradiance from a uniform lower hemisphere: ``pi L_g (1 - n_z) / 2``.

    Parameters
    ----------
    radiance
        L_g per channel, (C,).
    normals
        Unit normals (..., 3), Z up.

    Returns
    -------
    ndarray
        (..., C): ``L_g int_{z<0} max(0, n.w) dw`` (0 facing up, pi L_g facing down).
    """
    lg = as_float_array(radiance, "radiance")
    n = check_dirs(normals, "normals")
    return (0.5 * math.pi * (1.0 - n[..., 2]))[..., None] * lg


def horizontal_irradiance_from_sh(coeffs: ArrayLike) -> NDArray[np.float64]:
    """
    Exact irradiance of the horizontal ground from the SH of a light that is zero below the horizon.

    Parameters
    ----------
    coeffs
        Radiance SH with at least 2 bands, (K,) or (..., K, C), K = N * N >= 4:
        the *unfiltered, unwindowed* projection (the truth or its fit; not
        after the Gibbs filter or deringing, which scale c_10).

    Returns
    -------
    ndarray
        ``sqrt(4 pi / 3) c_10``: (...,) or (..., C), lux for luminance-scaled SH.
        Exact for any radiance zero for z < 0 (sky, sun above the horizon),
        whatever its bands beyond 1: ``int L max(0, w_z) dw = int L w_z dw``.
    """
    c = as_float_array(coeffs, "coeffs")
    axis = 0 if c.ndim == 1 else -2
    if c.ndim == 0 or c.shape[axis] < 4 or math.isqrt(c.shape[axis]) ** 2 != c.shape[axis]:
        raise ValueError(f"coeffs must have shape (N*N,) or (..., N*N, C) with N >= 2, got {c.shape}")
    return HORIZONTAL_FACTOR * (c[2] if c.ndim == 1 else c[..., 2, :])
