"""
The Preetham (1999) sky and its reference SH projection
=======================================================

-   :func:`xyY`: CIE xyY of the sky in a direction (Y in cd/m^2).
-   :func:`luminance`: CIE Y of the sky, cd/m^2.
-   :func:`radiance`: linear RGB of the sky, cd/m^2, zero below the horizon.
-   :func:`sky_sh`: the reference ("truth") SH projection of the sky.
-   :func:`zenith_luminance`, :func:`zenith_chromaticity`, :func:`perez`:
    the model's parts (Preetham et al. 1999, appendix).
-   :func:`rgb_from_xyz_matrix`: XYZ -> linear RGB of a colour-science colourspace.

Model domain: sun zenith angle in [0, pi/2] rad, turbidity in [1.7, 10]. Below a
turbidity of about 2 the model is unreliable (``PREETHAM.md``): B_Y turns
positive near T = 1.2 so exp(B / cos theta) explodes at the horizon, and Zotti
et al. (2007) find the horizon far too bright below T = 2.5, which is why the
fitted runtime only covers [2.5, 6].

Conversions xyY -> XYZ -> RGB go through colour-science, imported on first use
(``import skysh`` does not import it). The XYZ -> RGB matrix is the colourspace's
own ``matrix_XYZ_to_RGB`` with no chromatic adaptation: Preetham's chromaticities
are absolute, so a white of the colourspace's whitepoint maps to R = G = B.

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999). A Practical Analytic Model
    for Daylight. SIGGRAPH 1999, appendix (the formulas and constants below, as
    reproduced in ``PREETHAM.md``).
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: the sky is zero below
    the horizon; its projection is the ground truth.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import sh
from skysh._checks import check_bands, check_choice, check_dirs, check_range

if TYPE_CHECKING:  # pragma: no cover
    pass

__all__ = [
    "SUN_ZENITH_RANGE",
    "TURBIDITY_RANGE",
    "PEREZ_Y",
    "PEREZ_X",
    "PEREZ_YC",
    "ZENITH_X_MATRIX",
    "ZENITH_Y_MATRIX",
    "SKY_SH_THETA_NODES",
    "perez",
    "perez_coefficients",
    "zenith_luminance",
    "zenith_chromaticity",
    "xyY",
    "luminance",
    "radiance",
    "rgb_from_xyz_matrix",
    "sky_quadrature_rule",
    "sky_sh",
    "sky_minimum",
    "luminance_scale",
]

SUN_ZENITH_RANGE: tuple[float, float] = (0.0, math.pi / 2.0)
"""Domain of the sun zenith angle, radians (the model is undefined below the horizon)."""

TURBIDITY_RANGE: tuple[float, float] = (1.7, 10.0)
"""Domain of the turbidity accepted by the model (unreliable below about 2)."""

PEREZ_Y: NDArray[np.float64] = np.array(
    [[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251], [0.1206, -2.5771], [-0.0670, 0.3703]]
)
"""Perez A..E of luminance Y as (slope, intercept) in turbidity, Preetham 1999 appendix."""

PEREZ_X: NDArray[np.float64] = np.array(
    [[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125], [-0.0641, -0.8989], [-0.0033, 0.0452]]
)
"""Perez A..E of chromaticity x as (slope, intercept) in turbidity."""

PEREZ_YC: NDArray[np.float64] = np.array(
    [[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102], [-0.0441, -1.6537], [-0.0109, 0.0529]]
)
"""Perez A..E of chromaticity y as (slope, intercept) in turbidity."""

ZENITH_X_MATRIX: NDArray[np.float64] = np.array(
    [[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394], [0.11693, -0.21196, 0.06052, 0.25886]]
)
"""Zenith chromaticity x = [T^2, T, 1] M_x [ts^3, ts^2, ts, 1]^T."""

ZENITH_Y_MATRIX: NDArray[np.float64] = np.array(
    [[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516], [0.15346, -0.26756, 0.06670, 0.26688]]
)
"""Zenith chromaticity y = [T^2, T, 1] M_y [ts^3, ts^2, ts, 1]^T."""

_PEREZ_Y_SLOPE: tuple[float, ...] = tuple(float(v) for v in PEREZ_Y[:, 0])
_PEREZ_Y_INTERCEPT: tuple[float, ...] = tuple(float(v) for v in PEREZ_Y[:, 1])
_PEREZ_ALL: NDArray[np.float64] = np.stack([PEREZ_X, PEREZ_YC, PEREZ_Y])  # (3 quantities x, y, Y; 5; 2)
for _array in (PEREZ_Y, PEREZ_X, PEREZ_YC, ZENITH_X_MATRIX, ZENITH_Y_MATRIX, _PEREZ_ALL):
    _array.flags.writeable = False

SKY_SH_THETA_NODES: int = 64
"""Gauss-Legendre nodes per zenith panel of :func:`sky_quadrature_rule` used by
:func:`sky_sh` by default (two panels, 128 azimuth nodes: 16,384 directions).
``tests/test_preetham.py`` shows the result agrees with an independent, 50x denser
product rule to better than 1e-7 of the DC term for bands <= 7."""


def _check_sun(sun_zenith: ArrayLike, turbidity: ArrayLike) -> tuple[NDArray, NDArray]:
    ts = check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_range(turbidity, "turbidity", *TURBIDITY_RANGE)
    return ts, t


def perez_coefficients(turbidity: ArrayLike) -> NDArray[np.float64]:
    """Perez A..E for x, y, Y at ``turbidity``: shape (..., 3, 5), quantities ordered (x, y, Y)."""
    t = np.asarray(turbidity, dtype=np.float64)[..., None, None]
    return _PEREZ_ALL[..., 0] * t + _PEREZ_ALL[..., 1]


def perez(cos_theta: ArrayLike, gamma: ArrayLike, cos_gamma: ArrayLike, coefficients: ArrayLike) -> NDArray[np.float64]:
    """
    Perez distribution F = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma).

    ``coefficients`` has A..E on its last axis. ``cos_theta <= 0`` gives
    exp(B / cos theta) = 0 (B < 0 in the model's domain), the horizon limit.
    """
    a, b, c, d, e = np.moveaxis(np.asarray(coefficients, dtype=np.float64), -1, 0)
    ct = np.asarray(cos_theta, dtype=np.float64)
    positive = ct > 0.0
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        horizon = np.where(positive, np.exp(b / np.where(positive, ct, 1.0)), 0.0)
    cg = np.asarray(cos_gamma, dtype=np.float64)
    return (1.0 + a * horizon) * (1.0 + c * np.exp(d * np.asarray(gamma)) + e * cg * cg)


def zenith_luminance(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """Zenith luminance Y_z in cd/m^2 (Preetham's kcd/m^2 times 1000)."""
    ts, t = _check_sun(sun_zenith, turbidity)
    return _zenith_luminance(ts, t, np)


def _zenith_luminance(ts: Any, t: Any, ops: Any = math) -> Any:
    """Y_z in cd/m^2 with ``ops`` = math (floats, the runtime's fast path) or numpy (arrays); unchecked."""
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * ts)
    return 1000.0 * ((4.0453 * t - 4.9710) * ops.tan(chi) - 0.2155 * t + 2.4192)


def _luminance_scale(ts: Any, t: Any, ops: Any = math) -> Any:
    """Y_z / F_Y(0, ts) with ``ops`` = math or numpy; unchecked (see :func:`luminance_scale`)."""
    slope, intercept = _PEREZ_Y_SLOPE, _PEREZ_Y_INTERCEPT
    cos_ts = ops.cos(ts)
    f_zenith = (1.0 + (slope[0] * t + intercept[0]) * ops.exp(slope[1] * t + intercept[1])) * (
        1.0 + (slope[2] * t + intercept[2]) * ops.exp((slope[3] * t + intercept[3]) * ts)
        + (slope[4] * t + intercept[4]) * cos_ts * cos_ts
    )
    return _zenith_luminance(ts, t, ops) / f_zenith


def zenith_chromaticity(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """Zenith chromaticity (x_z, y_z), shape (..., 2)."""
    ts, t = _check_sun(sun_zenith, turbidity)
    tv = np.stack(np.broadcast_arrays(t * t, t, np.ones_like(t)), axis=-1)
    sv = np.stack(np.broadcast_arrays(ts**3, ts**2, ts, np.ones_like(ts)), axis=-1)
    x = np.einsum("...i,ij,...j->...", tv, ZENITH_X_MATRIX, sv)
    y = np.einsum("...i,ij,...j->...", tv, ZENITH_Y_MATRIX, sv)
    return np.stack([x, y], axis=-1)


def luminance_scale(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """
    The sky's luminance scale Y_z / F_Y(0, theta_s), cd/m^2: sky luminance = scale x F_Y(theta, gamma).

    Parameters
    ----------
    sun_zenith, turbidity
        Radians in [0, pi/2] and turbidity in [1.7, 10], broadcasting.

    Notes
    -----
    The fitted tables store the sky's coefficients divided by this factor: it
    carries the fast variation with the sun (tan chi in Y_z) and a pole of
    1 / F_Y(0, theta_s) just below the turbidity domain (1 + A e^B vanishes
    near T = 1.6), both of which a low-degree polynomial fits poorly. It costs
    one tan and two exp per evaluation.
    """
    ts, t = _check_sun(sun_zenith, turbidity)
    return _luminance_scale(ts, t, np)


def _sun_dir(sun_zenith: float, sun_azimuth: float) -> NDArray[np.float64]:
    s = math.sin(sun_zenith)
    return np.array([s * math.cos(sun_azimuth), s * math.sin(sun_azimuth), math.cos(sun_zenith)])


def xyY(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float) -> NDArray[np.float64]:
    """
    CIE xyY of the sky seen in the directions ``dirs``.

    Parameters
    ----------
    dirs
        Unit view vectors (..., 3), Z up.
    sun_zenith
        Sun zenith angle, radians, [0, pi/2].
    sun_azimuth
        Sun azimuth, radians (from +X towards +Y), any finite value.
    turbidity
        Atmospheric turbidity, [1.7, 10].

    Returns
    -------
    ndarray
        (..., 3): chromaticity x, y and luminance Y in cd/m^2. Below the horizon
        (z < 0) Y = 0 and (x, y) is the zenith chromaticity. At the horizon
        (z = 0) Y is the limit of the model, exp(B / cos theta) -> 0.
    """
    d = check_dirs(dirs)
    ts, t = _check_sun(sun_zenith, turbidity)
    phi_s = math.fmod(float(check_range(sun_azimuth, "sun_azimuth", -math.inf, math.inf, unit="rad")), 2.0 * math.pi)
    if ts.ndim or t.ndim:
        raise ValueError("sun_zenith and turbidity must be scalars here (use the runtime for batches)")
    ts, t = float(ts), float(t)
    sun = _sun_dir(ts, phi_s)
    # The zenith rides along as the last direction so F(0, theta_s) is computed on
    # exactly the path of every view, and the zenith value is exactly (x_z, y_z, Y_z).
    flat = np.concatenate([d.reshape(-1, 3), [[0.0, 0.0, 1.0]]])
    cos_theta = flat[:, 2]
    # gamma by atan2(|d x s|, d . s): accurate near the sun, where arccos of the
    # dot product loses half the digits (and the dot product can exceed 1).
    gamma = np.arctan2(np.linalg.norm(np.cross(flat, sun), axis=-1), flat @ sun)
    cos_gamma = np.cos(gamma)
    coeffs = perez_coefficients(t)  # (3, 5): x, y, Y
    f = perez(cos_theta[:, None], gamma[:, None], cos_gamma[:, None], coeffs)
    zenith = np.array([*zenith_chromaticity(ts, t), zenith_luminance(ts, t)])
    values = zenith * (f[:-1] / f[-1])
    values[cos_theta[:-1] < 0.0] = np.array([zenith[0], zenith[1], 0.0])
    return values.reshape(d.shape)


def luminance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float) -> NDArray[np.float64]:
    """Sky luminance Y in cd/m^2 in the directions ``dirs`` (..., 3) -> (...,); zero below the horizon."""
    return xyY(dirs, sun_zenith, sun_azimuth, turbidity)[..., 2]


@lru_cache(maxsize=None)
def rgb_from_xyz_matrix(colourspace: str = "sRGB") -> NDArray[np.float64]:
    """
    The XYZ -> linear RGB matrix of a colour-science colourspace (no chromatic adaptation).

    Parameters
    ----------
    colourspace
        Any key of ``colour.RGB_COLOURSPACES`` ("sRGB", "ITU-R BT.2020", "ACEScg", ...).
    """
    import colour  # heavy (about 1.5 s); imported only when a colour conversion is needed

    if not isinstance(colourspace, str) or colourspace not in colour.RGB_COLOURSPACES:
        raise ValueError(
            f"colourspace must be a colour-science RGB colourspace name (colour.RGB_COLOURSPACES), got {colourspace!r}"
        )
    matrix = np.array(colour.RGB_COLOURSPACES[colourspace].matrix_XYZ_to_RGB, dtype=np.float64)
    matrix.flags.writeable = False
    return matrix


def radiance(
    dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, colourspace: str = "sRGB"
) -> NDArray[np.float64]:
    """
    Linear RGB sky radiance in cd/m^2, zero below the horizon.

    Parameters
    ----------
    dirs
        Unit view vectors (..., 3), Z up.
    sun_zenith, sun_azimuth, turbidity
        As in :func:`xyY`.
    colourspace
        colour-science RGB colourspace name; default linear sRGB (Rec. 709, D65).

    Returns
    -------
    ndarray
        (..., 3) linear RGB; each channel is in cd/m^2 in the sense that
        R = G = B = Y for a white of the colourspace's whitepoint.
    """
    import colour

    matrix = rgb_from_xyz_matrix(colourspace)
    values = xyY(dirs, sun_zenith, sun_azimuth, turbidity)
    xyz = colour.xyY_to_XYZ(values)
    return xyz @ matrix.T


def sky_quadrature_rule(sun_zenith: float, n_theta: int = SKY_SH_THETA_NODES) -> tuple[NDArray, NDArray]:
    """
    Product Gauss rule over the upper hemisphere, adapted to a sky with its sun at azimuth 0.

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    n_theta
        Gauss-Legendre nodes per zenith panel; the azimuth gets ``2 * n_theta``.

    Returns
    -------
    dirs, weights
        (M, 3) and (M,) with M = 4 n_theta^2 (2 n_theta^2 when the sun is at the
        zenith). The nodes cover azimuth [0, pi] only and the weights are doubled:
        exact for integrands even in phi, i.e. the m >= 0 coefficients of a sky
        symmetric about its sun's vertical plane (its m < 0 coefficients are zero).

    Notes
    -----
    The sky has a conical kink at the sun (exp(D gamma) with gamma the angle to
    the sun), which limits the plain product rule in cos(theta) to O(n^-3)
    convergence; the sun at the zenith adds a square-root endpoint singularity
    in cos(theta). This rule is Gauss-Legendre in theta itself (weight
    sin theta), split at theta = sun_zenith, times Gauss-Legendre in phi over
    [0, pi]: the kink sits on a panel corner, where Gauss rules converge
    quickly, and the horizon (where the sky jumps to zero) is a panel edge.
    """
    ts = float(check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad"))
    nodes, weights = sh.gauss_legendre(int(n_theta))
    thetas, theta_weights = [], []
    for low, high in ((0.0, ts), (ts, math.pi / 2.0)):
        if high > low:
            thetas.append(low + (high - low) * 0.5 * (nodes + 1.0))
            theta_weights.append(weights * (high - low) * 0.5)
    theta = np.concatenate(thetas)
    w_theta = np.concatenate(theta_weights) * np.sin(theta)
    phi_nodes, phi_weights = sh.gauss_legendre(2 * int(n_theta))
    phi = 0.5 * math.pi * (phi_nodes + 1.0)
    w_phi = math.pi * phi_weights  # (pi / 2) Jacobian, times 2 for the mirrored half
    st = np.sin(theta)[:, None]
    dirs = np.stack(
        np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1
    ).reshape(-1, 3)
    return dirs, (w_theta[:, None] * w_phi[None, :]).ravel()


def sky_sh(
    sun_zenith: float,
    turbidity: float,
    bands: int = 7,
    sun_azimuth: float = 0.0,
    colourspace: str = "sRGB",
    method: str = "quadrature",
    n: int | None = None,
    seed: int | None = None,
) -> NDArray[np.float64]:
    """
    Reference SH projection of the Preetham sky ("truth").

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    turbidity
        [1.7, 10].
    bands
        Number of bands N, [1, 64].
    sun_azimuth
        Radians. The sky is projected with the sun at azimuth 0 and then turned
        by :func:`skysh.sh.rotate_z`, which is exact (Habel eq. 4).
    colourspace
        colour-science RGB colourspace name.
    method
        ``"quadrature"`` (default): the sun-adapted rule of
        :func:`sky_quadrature_rule`, about ``n`` directions (``n_theta =
        round(sqrt(n / 4))``, default :data:`SKY_SH_THETA_NODES`). ``"mc"``,
        ``"stratified"``, ``"qmc"``: :func:`skysh.sh.project` over the upper
        hemisphere with ``n`` samples and ``seed``.

    Returns
    -------
    ndarray
        (N * N, 3) linear RGB SH coefficients in cd/m^2.
    """
    bands = check_bands(bands)
    check_choice(method, "method", sh.PROJECTION_METHODS)
    ts, t = _check_sun(sun_zenith, turbidity)
    ts, t = float(ts), float(t)
    azimuth = math.fmod(float(check_range(sun_azimuth, "sun_azimuth", -math.inf, math.inf, unit="rad")), 2.0 * math.pi)
    if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1):
        raise ValueError(f"n must be a positive integer, got {n!r}")
    rgb_from_xyz_matrix(colourspace)  # validate the name before the projection
    if method == "quadrature":
        n_theta = SKY_SH_THETA_NODES if n is None else max(bands, round(math.sqrt(n / 4.0)))
        dirs, weights = sky_quadrature_rule(ts, n_theta)
        values = radiance(dirs, ts, 0.0, t, colourspace)
        coeffs = (sh.basis(dirs, bands).T * weights) @ values  # .T is the contiguous (K, M) buffer
        coeffs[[sh.index(*sh.lm(i)) for i in range(bands * bands) if sh.lm(i)[1] < 0]] = 0.0
    else:
        coeffs = sh.project(
            lambda dirs: radiance(dirs, ts, 0.0, t, colourspace), bands, method=method, n=n, seed=seed, hemisphere=True
        )
    return sh.rotate_z(coeffs, azimuth) if azimuth else coeffs


_MIN_GRID_STEP: float = math.radians(2.0)
"""Spacing of the coarse grid that seeds :func:`sky_minimum`, radians."""

_MIN_REFINE: tuple[int, ...] = (20, 20)
"""Each refinement searches a (2k+1)^2 grid spanning +-1 previous step around the best node."""


def sky_minimum(sun_zenith: float, turbidity: float, colourspace: str = "sRGB") -> NDArray[np.float64]:
    """
    Minimum of the sky over the closed upper hemisphere: per RGB channel and of luminance.

    Parameters
    ----------
    sun_zenith, turbidity
        As :func:`xyY`.
    colourspace
        colour-science RGB colourspace name.

    Returns
    -------
    ndarray
        (4,): the minimum R, G, B and Y in cd/m^2 (each minimised on its own).
        This is L_min of the Habel seed's error measures (eqs. 2, 3).

    Notes
    -----
    A 2-degree grid over zenith [0, 90] x azimuth [0, 180] degrees (the sky is
    symmetric about its sun's vertical plane), then two local grids of 41 x 41
    nodes around the best node, each 20 times finer (final spacing 0.005
    degrees; the sky is smooth at its minimum, so the remaining error is
    second order in that spacing). Deterministic and vectorised. An RGB channel can be
    negative: near sunset at low turbidity the sky's chromaticity leaves the
    sRGB gamut (blue about -700 cd/m^2 at sun_zenith = pi/2, turbidity 2.5).
    """
    ts, t = _check_sun(sun_zenith, turbidity)
    ts, t = float(ts), float(t)
    rgb_from_xyz_matrix(colourspace)

    def values(theta: NDArray, phi: NDArray) -> NDArray:
        st = np.sin(theta)
        d = np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], axis=-1)
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        rgb = radiance(d, ts, 0.0, t, colourspace)
        return np.concatenate([rgb, luminance(d, ts, 0.0, t)[..., None]], axis=-1)

    step = _MIN_GRID_STEP
    theta = np.linspace(0.0, math.pi / 2.0, round(math.pi / 2.0 / step) + 1)
    phi = np.linspace(0.0, math.pi, round(math.pi / step) + 1)
    th, ph = (a.ravel() for a in np.meshgrid(theta, phi, indexing="ij"))
    grid = values(th, ph)  # (M, 4)
    best = np.argmin(grid, axis=0)
    centre = np.stack([th[best], ph[best]], axis=-1)  # (4, 2)
    out = grid[best, np.arange(4)]
    for k in _MIN_REFINE:
        offsets = np.linspace(-step, step, 2 * k + 1)
        step = step / k
        oth, oph = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
        cth = np.clip(centre[:, 0, None] + oth, 0.0, math.pi / 2.0)  # (4, M)
        cph = np.clip(centre[:, 1, None] + oph, 0.0, math.pi)
        local = values(cth, cph)[np.arange(4), :, np.arange(4)]  # quantity k on its own grid
        best = np.argmin(local, axis=1)
        centre = np.stack([cth[np.arange(4), best], cph[np.arange(4), best]], axis=-1)
        out = np.minimum(out, local[np.arange(4), best])
    return out
