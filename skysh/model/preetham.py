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
fitted runtime only covers turbidity [2.5, 6].

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

import itertools
import math
import warnings
from collections.abc import Callable
from functools import cache
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import (
    MAX_ARRAY_ELEMENTS,
    as_float_array,
    check_bands,
    check_choice,
    check_count,
    check_dirs,
    check_range,
    check_scalar,
    check_seed,
    check_size,
    read_only,
    short_repr,
)
from skysh.domain import SKY
from skysh.sh import basis as sh

__all__ = ["SUN_ZENITH_RANGE", "TURBIDITY_RANGE", "PEREZ_Y", "PEREZ_X", "PEREZ_YC", "ZENITH_X_MATRIX",
    "ZENITH_Y_MATRIX", "SKY_SH_THETA_NODES", "perez", "luminance", "radiance", "rgb_from_xyz_matrix",
    "sky_quadrature_rule", "sky_sh", "sky_minimum", "luminance_scale", "luminance_scale_unchecked"]

SUN_ZENITH_RANGE: tuple[float, float] = SKY.x.interval
"""Domain of the sun zenith angle, radians (the model is undefined below the horizon): the
interval the fit covers too, written once in :data:`skysh.domain.SKY`."""

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

ZENITH_LUMINANCE: tuple[float, float, float, float] = (4.0453, 4.9710, 0.2155, 2.4192)
"""(a, b, c, d) of the zenith luminance Y_z = 1000 ((a T - b) tan chi - c T + d) cd/m^2 with
chi = (4/9 - T/120)(pi - 2 ts) (Preetham 1999, appendix; the exports write these same numbers)."""

_PEREZ_Y_SLOPE: tuple[float, ...] = tuple(float(v) for v in PEREZ_Y[:, 0])
_PEREZ_Y_INTERCEPT: tuple[float, ...] = tuple(float(v) for v in PEREZ_Y[:, 1])
_PEREZ_ALL: NDArray[np.float64] = np.stack([PEREZ_X, PEREZ_YC, PEREZ_Y])  # (3 quantities x, y, Y; 5; 2)
read_only(PEREZ_Y, PEREZ_X, PEREZ_YC, ZENITH_X_MATRIX, ZENITH_Y_MATRIX, _PEREZ_ALL)

SKY_SH_THETA_NODES: int = 64
"""Gauss-Legendre nodes per zenith panel of :func:`sky_quadrature_rule` used by
:func:`sky_sh` by default (two panels, 128 azimuth nodes: 16,384 directions).
``tests/model/test_preetham.py`` shows the result agrees with an independent, 50x denser
product rule to better than 1e-7 of the DC term for bands <= 7."""


_COLOUR_MATPLOTLIB_WARNING: str = r'"Matplotlib" related API features are not available'
"""Start of the message colour-science emits on import when matplotlib is absent: skysh
plots nothing, so the warning is noise to its users and is filtered around the import."""


def import_colour() -> ModuleType:
    """colour-science, imported on first use without its side effects on the user's session.

    Its "matplotlib not available" warning is filtered (skysh plots nothing), and numpy's
    print options, which colour-science's import switches to the 1.13 legacy mode for the
    whole process, are put back as they were.
    """
    options = np.get_printoptions()
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=_COLOUR_MATPLOTLIB_WARNING)
        import colour  # heavy (about 1.5 s); imported only when a colour conversion is needed
    np.set_printoptions(**options)
    return colour


def _broadcast_shape(names: str, *shapes: tuple[int, ...]) -> tuple[int, ...]:
    """The broadcast shape of ``shapes``, else a ValueError naming the arrays and their shapes:
    "<names> must broadcast together, got shapes (2,) and (3,)"."""
    try:
        return np.broadcast_shapes(*shapes)
    except ValueError:
        listed = ", ".join(map(str, shapes[:-1])) + f" and {shapes[-1]}"
        raise ValueError(f"{names} must broadcast together, got shapes {listed}") from None


def _check_sun(sun_zenith: ArrayLike, turbidity: ArrayLike) -> tuple[NDArray, NDArray]:
    ts = check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_range(turbidity, "turbidity", *TURBIDITY_RANGE)
    shape = _broadcast_shape("sun_zenith and turbidity", ts.shape, t.shape)
    check_size(4 * math.prod(shape), "sun_zenith" if ts.size >= t.size else "turbidity", "the broadcast sky points")
    return ts, t


def perez_coefficients(turbidity: ArrayLike) -> NDArray[np.float64]:
    """Perez A..E for x, y, Y at ``turbidity`` in [1.7, 10]: shape (..., 3, 5), quantities ordered (x, y, Y)."""
    t = check_range(turbidity, "turbidity", *TURBIDITY_RANGE)
    check_size(15 * t.size, "turbidity")
    return _PEREZ_ALL[..., 0] * t[..., None, None] + _PEREZ_ALL[..., 1]


def perez(cos_theta: ArrayLike, gamma: ArrayLike, cos_gamma: ArrayLike, coefficients: ArrayLike) -> NDArray[np.float64]:
    """
    Perez distribution F = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma).

    ``cos_theta`` and ``cos_gamma`` in [-1, 1], ``gamma`` in [0, pi] radians and
    ``coefficients`` (A..E on its last axis, shape (..., 5)) broadcast together;
    empty arrays give an empty result. ``cos_theta <= 0`` gives exp(B / cos theta)
    = 0 (B < 0 in the model's domain), the horizon limit. A result that is not
    finite (coefficients far outside the model's) is refused.
    """
    k = as_float_array(coefficients, "coefficients")
    if k.ndim == 0 or k.shape[-1] != 5:
        raise ValueError(f"coefficients must have shape (..., 5) (Perez A..E), got {k.shape}")
    ct = check_range(cos_theta, "cos_theta", -1.0, 1.0)
    g = check_range(gamma, "gamma", 0.0, math.pi, unit="rad")
    cg = check_range(cos_gamma, "cos_gamma", -1.0, 1.0)
    shape = _broadcast_shape("cos_theta, gamma, cos_gamma and coefficients[..., 0]", ct.shape, g.shape, cg.shape,
                             k.shape[:-1])
    check_size(math.prod(shape), "cos_theta")
    with np.errstate(over="ignore", invalid="ignore"):
        out = _perez(ct, g, cg, k)
    if not np.all(np.isfinite(out)):
        raise ValueError("coefficients give a Perez value that is not finite (exp overflows): use the model's A..E")
    return out


def _perez(ct: NDArray, gamma: NDArray, cg: NDArray, coefficients: NDArray) -> NDArray[np.float64]:
    """:func:`perez` of checked float64 arrays."""
    a, b, c, d, e = np.moveaxis(coefficients, -1, 0)
    positive = ct > 0.0
    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
        horizon = np.where(positive, np.exp(b / np.where(positive, ct, 1.0)), 0.0)
    return (1.0 + a * horizon) * (1.0 + c * np.exp(d * gamma) + e * cg * cg)


def zenith_luminance(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """Zenith luminance Y_z in cd/m^2 (Preetham's kcd/m^2 times 1000)."""
    ts, t = _check_sun(sun_zenith, turbidity)
    return zenith_luminance_unchecked(ts, t, np)


def zenith_luminance_unchecked(ts: Any, t: Any, ops: Any = math) -> Any:
    """:func:`zenith_luminance` without its checks, for per-frame paths that checked once: floats with
    ``ops = math`` or arrays with ``ops = numpy`` (any namespace with ``tan``), in the model's domain."""
    a, b, c, d = ZENITH_LUMINANCE
    chi = (4.0 / 9.0 - t / 120.0) * (math.pi - 2.0 * ts)
    return 1000.0 * ((a * t - b) * ops.tan(chi) - c * t + d)


def luminance_scale_unchecked(ts: Any, t: Any, ops: Any = math) -> Any:
    """:func:`luminance_scale` without its checks: floats with ``ops = math`` or arrays with
    ``ops = numpy`` (any namespace with ``cos``, ``exp`` and ``tan``), in the model's domain."""
    slope, intercept = _PEREZ_Y_SLOPE, _PEREZ_Y_INTERCEPT
    cos_ts = ops.cos(ts)
    f_zenith = (1.0 + (slope[0] * t + intercept[0]) * ops.exp(slope[1] * t + intercept[1])) * (
        1.0 + (slope[2] * t + intercept[2]) * ops.exp((slope[3] * t + intercept[3]) * ts)
        + (slope[4] * t + intercept[4]) * cos_ts * cos_ts
    )
    return zenith_luminance_unchecked(ts, t, ops) / f_zenith




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
    return luminance_scale_unchecked(ts, t, np)


def _sun_angle(flat: NDArray, sun_zenith: float, sun_azimuth: float) -> NDArray[np.float64]:
    """(M,) angle gamma between unit directions (M, 3) and the sun, radians: atan2(|d x s|, d . s), accurate
    near the sun, where arccos of the dot product loses half the digits (and the dot product can exceed 1)."""
    s = math.sin(sun_zenith)
    sun = np.array([s * math.cos(sun_azimuth), s * math.sin(sun_azimuth), math.cos(sun_zenith)])
    return np.arctan2(np.linalg.norm(np.cross(flat, sun), axis=-1), flat @ sun)


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
        (..., 3): chromaticity x, y and luminance Y in cd/m^2 (an empty batch of
        directions gives an empty result). Below the horizon
        (z < 0) Y = 0 and (x, y) is the zenith chromaticity. At the horizon
        (z = 0) Y is the limit of the model, exp(B / cos theta) -> 0.
    """
    d = check_dirs(dirs, per_point=16)
    ts = check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_scalar(turbidity, "turbidity", *TURBIDITY_RANGE)
    phi_s = math.fmod(check_scalar(sun_azimuth, "sun_azimuth", unit="rad"), 2.0 * math.pi)
    # The zenith rides along as the last direction so F(0, theta_s) is computed on
    # exactly the path of every view, and the zenith value is exactly (x_z, y_z, Y_z).
    flat = np.concatenate([d.reshape(-1, 3), [[0.0, 0.0, 1.0]]])
    cos_theta = flat[:, 2]
    gamma = _sun_angle(flat, ts, phi_s)
    coeffs = _PEREZ_ALL[..., 0] * t + _PEREZ_ALL[..., 1]  # (3, 5): x, y, Y; as perez_coefficients(t)
    f = _perez(cos_theta[:, None], gamma[:, None], np.cos(gamma)[:, None], coeffs)
    zenith = np.array([*zenith_chromaticity(ts, t), zenith_luminance(ts, t)])
    values = zenith * (f[:-1] / f[-1])
    values[cos_theta[:-1] < 0.0] = np.array([zenith[0], zenith[1], 0.0])
    return values.reshape(d.shape)


def luminance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float) -> NDArray[np.float64]:
    """Sky luminance Y in cd/m^2 in the directions ``dirs`` (..., 3) -> (...,); zero below the horizon."""
    return xyY(dirs, sun_zenith, sun_azimuth, turbidity)[..., 2]


def colourspace_names() -> tuple[str, ...]:
    """The names :func:`rgb_from_xyz_matrix` accepts (colour-science's ``RGB_COLOURSPACES`` keys), sorted."""
    return tuple(sorted(import_colour().RGB_COLOURSPACES.keys(), key=str.lower))


def rgb_from_xyz_matrix(colourspace: str = "sRGB") -> NDArray[np.float64]:
    """
    The XYZ -> linear RGB matrix of a colour-science colourspace (no chromatic adaptation).

    Parameters
    ----------
    colourspace
        Any key of ``colour.RGB_COLOURSPACES`` ("sRGB", "ITU-R BT.2020", "ACEScg", ...;
        :func:`colourspace_names`). Another name is refused with the list of valid ones.

    Returns
    -------
    ndarray
        (3, 3), read-only, cached.
    """
    if not isinstance(colourspace, str):
        raise ValueError(f"colourspace must be a colour-science RGB colourspace name (a str), got {short_repr(colourspace)}")
    return _rgb_from_xyz_matrix(colourspace)


@cache
def _rgb_from_xyz_matrix(colourspace: str) -> NDArray[np.float64]:
    colour = import_colour()
    if colourspace not in colour.RGB_COLOURSPACES:
        raise ValueError(f"colourspace must be a colour-science RGB colourspace name, got {colourspace!r}; valid names: "
                         + ", ".join(colourspace_names()))
    matrix = np.array(colour.RGB_COLOURSPACES[colourspace].matrix_XYZ_to_RGB, dtype=np.float64)
    matrix.flags.writeable = False
    return matrix


def radiance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float,
             colourspace: str = "sRGB") -> NDArray[np.float64]:
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
    matrix = rgb_from_xyz_matrix(colourspace)
    return import_colour().xyY_to_XYZ(xyY(dirs, sun_zenith, sun_azimuth, turbidity)) @ matrix.T


def sky_quadrature_rule(sun_zenith: float, n_theta: int = SKY_SH_THETA_NODES) -> tuple[NDArray, NDArray]:
    """
    Product Gauss rule over the upper hemisphere, adapted to a sky with its sun at azimuth 0.

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    n_theta
        Gauss-Legendre nodes per zenith panel, an integer in [1,
        :data:`MAX_THETA_NODES`]; the azimuth gets ``2 * n_theta``.

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
    ts = check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    return _sky_rule(ts, check_count(n_theta, "n_theta", 1, MAX_THETA_NODES), math.pi / 2.0)  # theta panels only


def _sky_rule(ts: float, n_theta: int, split: float) -> tuple[NDArray, NDArray]:
    """:func:`sky_quadrature_rule` of checked values, with zenith panels ending at 0, ``ts``, ``split`` and pi/2:
    Gauss-Legendre in theta above ``split``, in u = sqrt(cos theta) below it (``split`` < pi/2 is
    :func:`skysh.model.hosek.sky_quadrature_rule`)."""
    nodes, weights = sh.gauss_legendre(n_theta)
    half = 0.5 * (nodes + 1.0)
    thetas, theta_weights = [], []
    for low, high in itertools.pairwise(sorted({0.0, ts, split, 0.5 * math.pi})):
        if low >= split:  # u = sqrt(cos theta) from sqrt(cos high) to sqrt(cos low)
            u_low, u_high = math.sqrt(max(math.cos(high), 0.0)), math.sqrt(math.cos(low))
            u = u_low + (u_high - u_low) * half
            thetas.append(np.arccos(u * u))
            theta_weights.append(weights * (u_high - u_low) * u)  # 0.5 Jacobian x d(cos)/du = 2u
        else:
            theta = low + (high - low) * half
            thetas.append(theta)
            theta_weights.append(weights * (high - low) * 0.5 * np.sin(theta))
    theta, w_theta = np.concatenate(thetas), np.concatenate(theta_weights)
    phi_nodes, phi_weights = sh.gauss_legendre(2 * n_theta)
    phi = 0.5 * math.pi * (phi_nodes + 1.0)
    w_phi = math.pi * phi_weights  # (pi / 2) Jacobian, times 2 for the mirrored half
    st = np.sin(theta)[:, None]
    dirs = np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1)
    return dirs.reshape(-1, 3), (w_theta[:, None] * w_phi[None, :]).ravel()


def _project_half(dirs: NDArray, weights: NDArray, values: NDArray, bands: int) -> NDArray[np.float64]:
    """(N * N, C) SH of ``values`` (M, C) at the nodes of :func:`_sky_rule` (checked sizes); m < 0 set to 0,
    the coefficients of a sky symmetric about its sun's vertical plane (the rule covers azimuth [0, pi] only)."""
    coeffs = (sh.basis_unchecked(dirs, bands).T * weights) @ values  # .T is the contiguous (K, M) buffer
    coeffs[[i for i in range(bands * bands) if sh.lm(i)[1] < 0]] = 0.0
    return coeffs


def sky_sh(sun_zenith: float, turbidity: float, bands: int = 7, sun_azimuth: float = 0.0, colourspace: str = "sRGB",
           method: str = "quadrature", n: int | None = None, seed: int | None = None) -> NDArray[np.float64]:
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
        by :func:`skysh.sh.basis.rotate_z`, which is exact (Habel eq. 4).
    colourspace
        colour-science RGB colourspace name.
    method
        ``"quadrature"`` (default): the sun-adapted rule of
        :func:`sky_quadrature_rule`, about ``n`` directions (``n_theta =
        max(bands, round(sqrt(n / 4)))``, default :data:`SKY_SH_THETA_NODES`,
        at most :data:`MAX_THETA_NODES`). ``"mc"``, ``"stratified"``,
        ``"qmc"``: :func:`skysh.sh.basis.project` over the upper hemisphere with
        ``n`` samples and ``seed``.
    n
        Sample count, an integer >= 1 (see ``method``); the basis at the
        samples (``n * N * N`` values) must fit
        :data:`skysh.checks.MAX_ARRAY_ELEMENTS`.
    seed
        None or an integer >= 0, for the random methods.

    Returns
    -------
    ndarray
        (N * N, 3) linear RGB SH coefficients in cd/m^2.
    """
    bands = check_bands(bands)
    check_choice(method, "method", sh.PROJECTION_METHODS)
    ts = check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_scalar(turbidity, "turbidity", *TURBIDITY_RANGE)
    azimuth = math.fmod(check_scalar(sun_azimuth, "sun_azimuth", unit="rad"), 2.0 * math.pi)
    seed = check_seed(seed)
    if n is not None:
        n = check_count(n, "n", 1, 4 * MAX_THETA_NODES**2 if method == "quadrature" else MAX_ARRAY_ELEMENTS)
    rgb_from_xyz_matrix(colourspace)  # validate the name before the projection
    if method == "quadrature":
        n_theta = SKY_SH_THETA_NODES if n is None else max(bands, round(math.sqrt(n / 4.0)))
        check_size(4 * n_theta * n_theta * bands * bands, "n" if n is not None else "bands", "the basis at the nodes")
        dirs, weights = _sky_rule(ts, n_theta, math.pi / 2.0)
        coeffs = _project_half(dirs, weights, radiance(dirs, ts, 0.0, t, colourspace), bands)
    else:
        coeffs = sh.project(lambda dirs: radiance(dirs, ts, 0.0, t, colourspace), bands, method=method, n=n, seed=seed,
                            hemisphere=True)
    return sh.rotate_z(coeffs, azimuth) if azimuth else coeffs


MAX_THETA_NODES: int = sh.MAX_GAUSS_NODES // 2
"""Largest ``n_theta`` of :func:`sky_quadrature_rule` (its azimuth rule has ``2 * n_theta`` nodes,
at most :data:`skysh.sh.basis.MAX_GAUSS_NODES`): 4 * 512**2, about a million directions."""

_MIN_GRID_STEP: float = math.radians(2.0)
"""Spacing of the coarse grid that seeds :func:`hemisphere_minimum`, radians."""

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
    The search of :func:`hemisphere_minimum`. An RGB channel can be negative: near
    sunset at low turbidity the sky's chromaticity leaves the sRGB gamut (blue about
    -700 cd/m^2 at sun_zenith = pi/2, turbidity 2.5).
    """
    ts = check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_scalar(turbidity, "turbidity", *TURBIDITY_RANGE)
    rgb_from_xyz_matrix(colourspace)

    def values(d: NDArray) -> NDArray:
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        return np.concatenate([radiance(d, ts, 0.0, t, colourspace), luminance(d, ts, 0.0, t)[..., None]], axis=-1)

    return hemisphere_minimum(values)


def hemisphere_minimum(values: Callable[[NDArray], NDArray]) -> NDArray[np.float64]:
    """
    Minimum of each of Q quantities of a sky over the upper hemisphere, its sun at azimuth 0.

    Parameters
    ----------
    values
        Takes unit vectors (..., 3) with azimuth in [0, pi] and returns (..., Q): the
        quantities there (the sky is symmetric about its sun's vertical plane).

    Returns
    -------
    ndarray
        (Q,): each quantity's minimum, searched on its own.

    Notes
    -----
    A 2-degree grid over zenith [0, 90] x azimuth [0, 180] degrees, then two local grids
    of 41 x 41 nodes around each quantity's best node, each 20 times finer (final
    spacing 0.005 degrees; a smooth minimum then leaves an error second order in it).
    Deterministic and vectorised. Used by :func:`sky_minimum` and
    :func:`skysh.model.hosek.sky_minimum`.
    """

    def at(theta: NDArray, phi: NDArray) -> NDArray:
        st = np.sin(theta)
        return values(np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], axis=-1))

    step = _MIN_GRID_STEP
    theta = np.linspace(0.0, math.pi / 2.0, round(math.pi / 2.0 / step) + 1)
    phi = np.linspace(0.0, math.pi, round(math.pi / step) + 1)
    th, ph = (a.ravel() for a in np.meshgrid(theta, phi, indexing="ij"))
    grid = at(th, ph)  # (M, Q)
    q = np.arange(grid.shape[-1])
    best = np.argmin(grid, axis=0)
    centre = np.stack([th[best], ph[best]], axis=-1)  # (Q, 2)
    out = grid[best, q]
    for k in _MIN_REFINE:
        offsets = np.linspace(-step, step, 2 * k + 1)
        step = step / k
        oth, oph = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
        cth = np.clip(centre[:, 0, None] + oth, 0.0, math.pi / 2.0)  # (Q, M)
        cph = np.clip(centre[:, 1, None] + oph, 0.0, math.pi)
        local = at(cth, cph)[q, :, q]  # quantity k on its own grid
        best = np.argmin(local, axis=1)
        centre = np.stack([cth[q, best], cph[q, best]], axis=-1)
        out = np.minimum(out, local[q, best])
    return out
