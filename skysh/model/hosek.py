"""
The Hosek-Wilkie (2012) sky and its reference SH projection
===========================================================

-   :func:`radiance`: linear RGB of the sky, cd/m^2, zero below the horizon
    unless the ground is asked for.
-   :func:`luminance`: CIE Y of the sky, cd/m^2.
-   :func:`tristimulus`: CIE 1931 XYZ of the sky from the spectral dataset, cd/m^2.
-   :func:`spectral_radiance`: the spectral model, W m^-2 sr^-1 nm^-1.
-   :func:`channel_radiance`: the model's own channels (RGB or the 11 wavelengths)
    in its own units.
-   :func:`configuration`: the model's parameters A..I and mean radiance of each
    channel at a sun position, turbidity and ground albedo (paper, section 5).
-   :func:`distribution`: the extended Perez function F(theta, gamma) (paper, eq. 9).
-   :func:`bezier_weights`: the quintic Bezier weights in the solar elevation.
-   :func:`sky_quadrature_rule`, :func:`sky_sh`: the reference ("truth") SH projection.
-   :func:`horizontal_irradiance`, :func:`sky_minimum`: E_h of the sky and its minimum.

The per-frame projection (the exact model on a small sun-adapted rule) is
:func:`skysh.model.hosek_frame.coefficients`; the dataset ships with skysh
(:mod:`skysh.model.hosek_data`).

The model (paper, eq. 9 and section 5), per channel c (an RGB primary or one of 11
wavelengths, 320..720 nm)::

    L_c = F(theta, gamma) x L_M,c
    F = (1 + A exp(B / (cos theta + 0.01)))
        x (C + D exp(E gamma) + F cos^2 gamma + G chi(H, gamma) + I sqrt(cos theta))
    chi(g, a) = (1 + cos^2 a) / (1 + g^2 - 2 g cos a)^(3/2)

theta the view's zenith angle, gamma its angle to the sun. A..I and L_M are a
quintic Bezier curve in x = (elevation / (pi/2))^(1/3) over six control points
stored per integer turbidity 1..10 and albedo 0 and 1, linear in turbidity and
albedo between them (as the published code and Mitsuba's ``sunsky``). The sky
is *not* linear in the albedo: the parameters are, F is not linear in them.

Units: every function returns cd/m^2 (skysh's unit). The RGB dataset is linear
sRGB tristimulus of the spectral radiance (W m^-2 sr^-1 nm^-1) integrated
against CMFs, so x 683 lm/W it is cd/m^2; Mitsuba's ``sunsky`` returns the
dataset's value x 1/106.75 (``MI_CIE_Y_NORMALIZATION``), hence cd/m^2 = 683 x
106.75 x Mitsuba's RGB. Other colourspaces go through the spectral dataset
(linear between its wavelengths, zero outside [320, 720] nm, as Mitsuba's
spectral mode), colour-science's CIE 1931 CMFs and
:func:`skysh.model.preetham.rgb_from_xyz_matrix` (the Preetham sky's colour route).
The two datasets are separate fits: their sRGB differ by a few percent. The
radiance can be negative at the horizon for a low sun (the fit undershoots);
it is returned as is, as Mitsuba does. Frame: Z up, azimuth from +X towards
+Y, radians; Mitsuba's emitter frame is the same. ``docs/hosek.md`` has the
reconciliation and the dataset's license.

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome
    Radiance. ACM Trans. Graph. 31(4), 95: eq. (9), section 5.
-   Mitsuba 3.9.1, ``include/mitsuba/render/sunsky.h``: ``eval_sky``,
    ``bezier_interp``, the RGB scale ``MI_CIE_Y_NORMALIZATION``.
-   Habel et al. (2008), seed 004: as for the Preetham sky, zero below the
    horizon, and its SH projection is the ground truth.
"""

from __future__ import annotations

import math
from functools import cache, lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import options
from skysh.checks import (
    as_float_array,
    check_bands,
    check_choice,
    check_count,
    check_dirs,
    check_flag,
    check_range,
    check_scalar,
    check_size,
)
from skysh.model import hosek_data, preetham, solar
from skysh.model.ground import ground_sh
from skysh.sh import basis as sh

__all__ = ["PARAMETER_NAMES", "HosekDataError", "configuration", "distribution", "channel_radiance",
    "spectral_radiance", "tristimulus", "radiance", "luminance", "sky_sh"]

HosekDataError = hosek_data.HosekDataError

SUN_ZENITH_RANGE: tuple[float, float] = preetham.SUN_ZENITH_RANGE
"""Sun zenith angles of the model, radians (solar elevation 0 to 90 degrees; Preetham's interval)."""

TURBIDITY_RANGE: tuple[float, float] = (1.0, 10.0)
"""Turbidities of the dataset (control points at 1, 2, ..., 10)."""

ALBEDO_RANGE: tuple[float, float] = options.ALBEDO_RANGE
"""The dataset's ground albedo, per channel: the runtime's ground albedo range (:data:`skysh.options.ALBEDO_RANGE`)."""

DATASETS: tuple[str, ...] = ("auto", "rgb", "spectral")
"""``dataset`` choices: "rgb" (linear sRGB only), "spectral" (any colourspace), "auto" (rgb for sRGB)."""

RGB_DATASET_COLOURSPACE: str = "sRGB"
"""The colourspace of the RGB dataset (linear Rec. 709 primaries, D65 white)."""

PARAMETER_NAMES: tuple[str, ...] = ("A", "B", "C", "D", "E", "F", "G", "I", "H")
"""The dataset's parameter order (the published code's ``configuration[0..8]``)."""

BEZIER_BINOMIALS: tuple[float, ...] = (1.0, 5.0, 10.0, 10.0, 5.0, 1.0)
"""Binomial coefficients of the quintic Bernstein basis."""

WAVELENGTHS: NDArray[np.float64] = np.array(hosek_data.WAVELENGTHS)
"""The spectral dataset's wavelengths, nm (320 to 720 by 40)."""
WAVELENGTHS.flags.writeable = False

LUMINOUS_EFFICACY: float = solar.LUMINOUS_EFFICACY
"""K_m = 683 lm/W: dataset units (W m^-2 sr^-1, CMF-weighted) -> cd/m^2."""

HORIZON_OFFSET: float = 0.01
"""The ``+ 0.01`` in exp(B / (cos theta + 0.01)) (published code and Mitsuba)."""

SKY_SH_THETA_NODES: int = 48
"""Gauss-Legendre nodes per zenith panel of :func:`sky_quadrature_rule` used by :func:`sky_sh`
(at most three panels, 96 azimuth nodes: up to 13,824 directions). ``tests/model/test_hosek.py``
checks the result against twice the nodes and against scipy's adaptive quadrature."""

QUADRATURE_SPLIT: float = math.pi / 4.0
"""Zenith angle, radians, from which :func:`sky_quadrature_rule` integrates in u = sqrt(cos theta)."""

MAX_THETA_NODES: int = sh.MAX_GAUSS_NODES // 2
"""Largest ``n_theta`` of :func:`sky_quadrature_rule` (its azimuth rule has ``2 n_theta`` nodes)."""

_DATA_KEYS: dict[str, tuple[str, str]] = {"rgb": ("sky_params_rgb", "sky_rad_rgb"),
                                          "spectral": ("sky_params_spec", "sky_rad_spec")}


def _check_sun(sun_zenith: ArrayLike, turbidity: ArrayLike, albedo: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    ts = check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    t = check_range(turbidity, "turbidity", *TURBIDITY_RANGE)
    a = check_range(albedo, "albedo", *ALBEDO_RANGE)
    shape = preetham._broadcast_shape("sun_zenith, turbidity and albedo", ts.shape, t.shape, a.shape)
    check_size(11 * 9 * 12 * math.prod(shape), "sun_zenith", "the broadcast sky parameters")
    return ts, t, a


def _check_scalars(sun_zenith: float, turbidity: float, albedo: float) -> tuple[float, float, float]:
    return (
        check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad"),
        check_scalar(turbidity, "turbidity", *TURBIDITY_RANGE),
        check_scalar(albedo, "albedo", *ALBEDO_RANGE),
    )


def bezier_weights(sun_zenith: ArrayLike) -> NDArray[np.float64]:
    """
    Quintic Bernstein weights of the solar elevation: shape (..., 6).

    Parameters
    ----------
    sun_zenith
        Radians in [0, pi/2], any shape.

    Returns
    -------
    ndarray
        ``C(5, k) x^k (1 - x)^(5 - k)``, k = 0..5, with ``x = (eta / (pi/2))^(1/3)``
        and eta = pi/2 - sun_zenith the solar elevation (paper, section 5): control
        point 0 is the sun on the horizon, 5 the sun at the zenith. The weights sum to 1.
    """
    return _bezier_weights(check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad"))


def _bezier_weights(ts: NDArray) -> NDArray[np.float64]:
    x = np.cbrt(np.clip(1.0 - ts / (0.5 * math.pi), 0.0, 1.0))[..., None]
    k = np.arange(6)
    return np.asarray(BEZIER_BINOMIALS) * x**k * (1.0 - x) ** (5 - k)


def configuration(sun_zenith: ArrayLike, turbidity: ArrayLike, albedo: ArrayLike,
                  dataset: str = "rgb") -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    The model's parameters and mean radiance per channel (paper, section 5).

    Parameters
    ----------
    sun_zenith, turbidity, albedo
        Radians in [0, pi/2], turbidity in [1, 10], ground albedo in [0, 1];
        broadcasting to (...,).
    dataset
        "rgb" (3 channels: linear sRGB) or "spectral" (11 wavelengths, :data:`WAVELENGTHS`).

    Returns
    -------
    params, mean_radiance
        (..., C, 9) parameters in the order of :data:`PARAMETER_NAMES`, and
        (..., C) L_M: W m^-2 sr^-1 CMF-weighted (rgb) or W m^-2 sr^-1 nm^-1 (spectral).
        Linear in turbidity between integers, linear in albedo, quintic Bezier in
        x = (elevation / (pi/2))^(1/3).

    Raises
    ------
    HosekDataError
        The dataset shipped with skysh (:mod:`skysh.model.hosek_data`) is missing or damaged.
    """
    check_choice(dataset, "dataset", tuple(_DATA_KEYS))
    return _configuration(*_check_sun(sun_zenith, turbidity, albedo), dataset)


def _configuration(ts: NDArray, t: NDArray, a: NDArray, dataset: str) -> tuple[NDArray, NDArray]:
    """:func:`configuration` of checked inputs; the dataset's tensors are read once per process
    (HosekDataError if the shipped file is missing)."""
    params, mean = (hosek_data.sky_tensors()[key] for key in _DATA_KEYS[dataset])
    return _interpolate(params, ts, t, a), _interpolate(mean, ts, t, a)


def _interpolate(data: NDArray, ts: NDArray, t: NDArray, a: NDArray) -> NDArray[np.float64]:
    """Tensor (10, 2, 6, *rest) at (sun zenith, turbidity, albedo) -> (..., *rest); checked inputs.

    Linear in turbidity between the integers 1..10, linear in albedo between 0 and 1,
    then the quintic Bezier sum over the six control points (the interpolations are
    linear, so their order does not matter beyond rounding).
    """
    ts, t, a = np.broadcast_arrays(ts, t, a)
    batch = ts.ndim
    u = t - 1.0
    low = np.minimum(np.floor(u), 8.0).astype(np.intp)
    frac = (u - low).reshape(u.shape + (1,) * (data.ndim - 1))
    by_turbidity = (1.0 - frac) * data[low] + frac * data[low + 1]  # (..., 2, 6, *rest)
    weight = a.reshape(a.shape + (1,) * (data.ndim - 2))
    by_albedo = (1.0 - weight) * np.take(by_turbidity, 0, axis=batch) + weight * np.take(by_turbidity, 1, axis=batch)
    bezier = _bezier_weights(ts).reshape(ts.shape + (6,) + (1,) * (data.ndim - 3))
    return np.sum(bezier * by_albedo, axis=batch)


def distribution(cos_theta: ArrayLike, gamma: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
    """
    The extended Perez function F(theta, gamma) of Hosek and Wilkie (eq. 9).

    Parameters
    ----------
    cos_theta
        Cosine of the view's zenith angle, [0, 1].
    gamma
        Angle between the view and the sun, radians in [0, pi].
    params
        (..., 9): A..I in the order of :data:`PARAMETER_NAMES` (A, B, C, D, E, F, G, I, H).
        The three broadcast together.

    Returns
    -------
    ndarray
        ``(1 + A exp(B / (cos theta + 0.01))) (C + D exp(E gamma) + F cos^2 gamma
        + G chi(H, gamma) + I sqrt(cos theta))``, unitless. A result that is not
        finite (parameters far outside the model's) is refused.
    """
    p = as_float_array(params, "params")
    if p.ndim == 0 or p.shape[-1] != 9:
        raise ValueError(f"params must have shape (..., 9) (A..I in the dataset's order), got {p.shape}")
    ct = check_range(cos_theta, "cos_theta", 0.0, 1.0)
    g = check_range(gamma, "gamma", 0.0, math.pi, unit="rad")
    shape = preetham._broadcast_shape("cos_theta, gamma and params[..., 0]", ct.shape, g.shape, p.shape[:-1])
    check_size(math.prod(shape), "cos_theta")
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        out = _distribution(ct, g, p)
    if not np.all(np.isfinite(out)):
        raise ValueError("params give a value of F that is not finite: use the model's parameters (configuration())")
    return out


def _distribution(ct: NDArray, gamma: NDArray, params: NDArray) -> NDArray[np.float64]:
    """:func:`distribution` of checked arrays (cos theta >= 0)."""
    a, b, c, d, e, f, g, i, h = np.moveaxis(params, -1, 0)
    cg = np.cos(gamma)
    chi = (1.0 + cg * cg) / (1.0 + h * h - 2.0 * h * cg) ** 1.5
    return (1.0 + a * np.exp(b / (ct + HORIZON_OFFSET))) * (c + d * np.exp(e * gamma) + f * cg * cg + g * chi + i * np.sqrt(ct))


def _channels(flat: NDArray, ts: float, phi_s: float, t: float, a: float, dataset: str) -> NDArray[np.float64]:
    """The model's channels (M, C) at unit directions (M, 3), zero below the horizon; checked inputs."""
    p, lm = _configuration(np.asarray(ts), np.asarray(t), np.asarray(a), dataset)  # (C, 9) and (C,)
    gamma = preetham._sun_angle(flat, ts, phi_s)
    above = flat[:, 2] >= 0.0
    ct = np.where(above, flat[:, 2], 0.0)
    values = _distribution(ct[:, None], gamma[:, None], p) * lm
    values[~above] = 0.0
    return values


def _check_view(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float,
                albedo: float) -> tuple[NDArray, float, float, float, float]:
    d = check_dirs(dirs, per_point=40)
    ts, t, a = _check_scalars(sun_zenith, turbidity, albedo)
    phi_s = math.fmod(check_scalar(sun_azimuth, "sun_azimuth", unit="rad"), 2.0 * math.pi)
    return d, ts, phi_s, t, a


def channel_radiance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, albedo: float,
                     dataset: str = "rgb") -> NDArray[np.float64]:
    """
    The model's own channels in the dataset's units, zero below the horizon.

    Parameters
    ----------
    dirs
        Unit view vectors (..., 3), Z up.
    sun_zenith, sun_azimuth
        Radians: zenith in [0, pi/2], azimuth (from +X towards +Y) any finite value.
    turbidity, albedo
        [1, 10] and [0, 1].
    dataset
        "rgb" or "spectral".

    Returns
    -------
    ndarray
        (..., 3) linear sRGB in W m^-2 sr^-1 (CMF-weighted; x 683 = cd/m^2), or
        (..., 11) spectral radiance in W m^-2 sr^-1 nm^-1 at :data:`WAVELENGTHS`.
        At the horizon (z = 0) the model's value; below it 0.
    """
    check_choice(dataset, "dataset", tuple(_DATA_KEYS))
    d, ts, phi_s, t, a = _check_view(dirs, sun_zenith, sun_azimuth, turbidity, albedo)
    channels = 3 if dataset == "rgb" else WAVELENGTHS.size
    return _channels(d.reshape(-1, 3), ts, phi_s, t, a, dataset).reshape(d.shape[:-1] + (channels,))


def spectral_radiance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, albedo: float,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
    """
    Spectral sky radiance, W m^-2 sr^-1 nm^-1, zero below the horizon.

    Parameters
    ----------
    dirs, sun_zenith, sun_azimuth, turbidity, albedo
        As :func:`channel_radiance`.
    wavelengths
        None (the 11 :data:`WAVELENGTHS`) or a 1-D array of wavelengths in nm:
        linear between the dataset's wavelengths, zero outside [320, 720] nm
        (Mitsuba's spectral mode).

    Returns
    -------
    ndarray
        (..., W).
    """
    values = channel_radiance(dirs, sun_zenith, sun_azimuth, turbidity, albedo, "spectral")
    if wavelengths is None:
        return values
    lam = check_range(wavelengths, "wavelengths", 0.0, 1.0e4, unit="nm")
    if lam.ndim != 1:
        raise ValueError(f"wavelengths must be a 1-D array (nm), got shape {lam.shape}")
    check_size(values.size // WAVELENGTHS.size * max(lam.size, 1), "wavelengths", "radiance at every wavelength")
    return values @ _hats(lam)


def _hats(lam: NDArray) -> NDArray[np.float64]:
    """(11, W): the linear interpolation weights of the dataset's wavelengths at ``lam``, 0 outside [320, 720]."""
    step = WAVELENGTHS[1] - WAVELENGTHS[0]
    hats = np.clip(1.0 - np.abs(lam[None, :] - WAVELENGTHS[:, None]) / step, 0.0, 1.0)
    hats[:, (lam < WAVELENGTHS[0]) | (lam > WAVELENGTHS[-1])] = 0.0
    return hats


@lru_cache(maxsize=1)
def spectral_to_xyz_weights() -> NDArray[np.float64]:
    """
    (11, 3) weights: CIE 1931 XYZ in cd/m^2 = spectral radiance at :data:`WAVELENGTHS` @ weights.

    ``K_m int hat_k(lambda) cmf(lambda) d lambda`` with hat_k the linear
    interpolation weight of wavelength k (zero outside [320, 720] nm) and
    colour-science's CIE 1931 2-degree CMFs (1 nm, 360-830 nm, linear between
    entries): the integral of the product of two piecewise-linear functions,
    exact. Read-only, computed once.
    """
    cmfs = preetham.import_colour().MSDS_CMFS[solar.CMFS_NAME]
    lam = np.asarray(cmfs.wavelengths, dtype=np.float64)
    table = np.asarray(cmfs.values, dtype=np.float64)  # (L, 3)
    hats = _hats(lam)  # (11, L), linear on every 1 nm interval (the kinks lie on integers)
    inside = (lam[:-1] >= WAVELENGTHS[0]) & (lam[1:] <= WAVELENGTHS[-1])  # zero past 720 nm: a step, not a ramp
    h = np.diff(lam) * inside
    fa, fb, ga, gb = hats[:, :-1, None], hats[:, 1:, None], table[None, :-1], table[None, 1:]
    # int_a^b f g = h / 6 (2 f_a g_a + f_a g_b + f_b g_a + 2 f_b g_b) for f, g linear on [a, b]
    weights = LUMINOUS_EFFICACY * np.sum(h[None, :, None] / 6.0 * (2 * fa * ga + fa * gb + fb * ga + 2 * fb * gb), axis=1)
    weights.flags.writeable = False
    return weights


def tristimulus(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, albedo: float) -> NDArray[np.float64]:
    """CIE 1931 XYZ of the sky (spectral dataset), (..., 3) in cd/m^2; arguments as :func:`channel_radiance`."""
    return spectral_radiance(dirs, sun_zenith, sun_azimuth, turbidity, albedo) @ spectral_to_xyz_weights()


def _resolve(dataset: str, colourspace: str) -> str:
    """"rgb" or "spectral" for a (dataset, colourspace) pair; refuses "rgb" with another colourspace."""
    check_choice(dataset, "dataset", DATASETS)
    preetham.rgb_from_xyz_matrix(colourspace)  # validates the name (the message lists the valid ones)
    if dataset == "auto":
        return "rgb" if colourspace == RGB_DATASET_COLOURSPACE else "spectral"
    if dataset == "rgb" and colourspace != RGB_DATASET_COLOURSPACE:
        raise ValueError(f"dataset 'rgb' holds linear {RGB_DATASET_COLOURSPACE} only, got colourspace {colourspace!r}: "
                         "use dataset='spectral' (or 'auto')")
    return dataset


def _rgb(flat: NDArray, ts: float, phi_s: float, t: float, a: float, colourspace: str, kind: str) -> NDArray:
    """Sky RGB (M, 3) in cd/m^2 at unit directions (M, 3), zero below the horizon; checked inputs."""
    if kind == "rgb":
        return LUMINOUS_EFFICACY * _channels(flat, ts, phi_s, t, a, "rgb")
    matrix = preetham.rgb_from_xyz_matrix(colourspace)
    return _channels(flat, ts, phi_s, t, a, "spectral") @ (spectral_to_xyz_weights() @ matrix.T)


def radiance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, albedo: float,
             colourspace: str = "sRGB", dataset: str = "auto", ground: bool = False) -> NDArray[np.float64]:
    """
    Linear RGB sky radiance in cd/m^2.

    Parameters
    ----------
    dirs, sun_zenith, sun_azimuth
        As :func:`skysh.model.preetham.xyY`.
    turbidity
        [1, 10].
    albedo
        Ground albedo, [0, 1] (grey).
    colourspace
        colour-science RGB colourspace name; default linear sRGB.
    dataset
        "auto" (default: the RGB dataset for "sRGB", else the spectral one),
        "rgb" (sRGB only) or "spectral".
    ground
        False (default): zero below the horizon (z < 0). True: below the horizon
        the uniform radiance ``albedo x E_h / pi`` of a Lambertian ground lit by
        this sky (:func:`horizontal_irradiance`; the sun's direct light is not
        included, add ``albedo x E_sun cos(sun_zenith) / pi`` for it).

    Returns
    -------
    ndarray
        (..., 3) linear RGB, cd/m^2 per channel (R = G = B = Y for the
        colourspace's white). The model's value, negative where the model is
        (near the horizon for a low sun).
    """
    ground = check_flag(ground, "ground")
    kind = _resolve(dataset, colourspace)
    d, ts, phi_s, t, a = _check_view(dirs, sun_zenith, sun_azimuth, turbidity, albedo)
    flat = d.reshape(-1, 3)
    values = _rgb(flat, ts, phi_s, t, a, colourspace, kind)
    if ground:
        values[flat[:, 2] < 0.0] = a * _horizontal_irradiance(ts, t, a, colourspace, kind) / math.pi
    return values.reshape(d.shape)


def luminance(dirs: ArrayLike, sun_zenith: float, sun_azimuth: float, turbidity: float, albedo: float,
              colourspace: str = "sRGB", dataset: str = "auto", ground: bool = False) -> NDArray[np.float64]:
    """Luminance Y in cd/m^2 of :func:`radiance` (same arguments): (..., 3) -> (...,), the colourspace's RGB -> Y row."""
    rgb = radiance(dirs, sun_zenith, sun_azimuth, turbidity, albedo, colourspace, dataset, ground)
    return rgb @ luminance_row(colourspace)


@cache
def luminance_row(colourspace: str) -> NDArray[np.float64]:
    """The row of the colourspace's RGB -> XYZ matrix that gives Y (luminance), (3,), read-only, cached."""
    row = np.linalg.inv(preetham.rgb_from_xyz_matrix(colourspace))[1].copy()
    row.flags.writeable = False
    return row


def sky_quadrature_rule(sun_zenith: float, n_theta: int = SKY_SH_THETA_NODES) -> tuple[NDArray, NDArray]:
    """
    Product Gauss rule over the upper hemisphere for a sky with its sun at azimuth 0.

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    n_theta
        Gauss-Legendre nodes per zenith panel, an integer in [1, :data:`MAX_THETA_NODES`];
        the azimuth gets ``2 n_theta`` over [0, pi].

    Returns
    -------
    dirs, weights
        (M, 3) and (M,), M = P x 2 n_theta^2 with P (2 or 3) panels. Azimuth
        [0, pi] only with doubled weights: exact for the m >= 0 coefficients of a
        sky symmetric about its sun's vertical plane.

    Notes
    -----
    The zenith panels end at the sun (its conical kink exp(E gamma) then sits
    on a panel corner), at :data:`QUADRATURE_SPLIT` and at the horizon. Panels
    above the split are Gauss-Legendre in theta (weight sin theta), as
    :func:`skysh.model.preetham.sky_quadrature_rule`; panels below it in u =
    sqrt(cos theta) (weight 2u), which turns the model's I sqrt(cos theta)
    term, a square-root singularity at the horizon that limits a rule in theta
    to O(n^-3), into a polynomial. With the default nodes the result agrees
    with twice the nodes to 1e-8 of the DC term (``tests/model/test_hosek.py``).
    """
    ts = check_scalar(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    return preetham._sky_rule(ts, check_count(n_theta, "n_theta", 1, MAX_THETA_NODES), QUADRATURE_SPLIT)


def sky_sh(sun_zenith: float, turbidity: float, albedo: float, bands: int = 7, sun_azimuth: float = 0.0,
           colourspace: str = "sRGB", dataset: str = "auto", ground: bool = False,
           n_theta: int = SKY_SH_THETA_NODES) -> NDArray[np.float64]:
    """
    Reference SH projection of the Hosek-Wilkie sky ("truth").

    Parameters
    ----------
    sun_zenith, turbidity, albedo
        Radians in [0, pi/2], [1, 10], [0, 1].
    bands
        Number of bands N, [1, 64].
    sun_azimuth
        Radians: projected with the sun at azimuth 0, then turned by
        :func:`skysh.sh.basis.rotate_z` (exact, Habel eq. 4).
    colourspace, dataset, ground
        As :func:`radiance`; with ``ground`` the ground's closed form
        (:func:`skysh.model.ground.ground_sh`) is added.
    n_theta
        Nodes per zenith panel of :func:`sky_quadrature_rule`, in [bands, :data:`MAX_THETA_NODES`].

    Returns
    -------
    ndarray
        (N * N, 3) linear RGB SH coefficients in cd/m^2 (real orthonormal, Condon-Shortley
        phase, index l(l+1)+m).
    """
    bands = check_bands(bands)
    ground = check_flag(ground, "ground")
    ts, t, a = _check_scalars(sun_zenith, turbidity, albedo)
    azimuth = math.fmod(check_scalar(sun_azimuth, "sun_azimuth", unit="rad"), 2.0 * math.pi)
    n_theta = check_count(n_theta, "n_theta", bands, MAX_THETA_NODES)
    check_size(6 * n_theta * n_theta * bands * bands, "n_theta", "the basis at the nodes")
    kind = _resolve(dataset, colourspace)
    dirs, weights = preetham._sky_rule(ts, n_theta, QUADRATURE_SPLIT)
    coeffs = preetham._project_half(dirs, weights, _rgb(dirs, ts, 0.0, t, a, colourspace, kind), bands)
    if ground:
        coeffs += ground_sh(a * _horizontal_irradiance(ts, t, a, colourspace, kind) / math.pi, bands)
    return sh.rotate_z(coeffs, azimuth) if azimuth else coeffs


def horizontal_irradiance(sun_zenith: float, turbidity: float, albedo: float, colourspace: str = "sRGB",
                          dataset: str = "auto") -> NDArray[np.float64]:
    """
    The sky's irradiance on a horizontal surface, ``int L(w) cos theta dw``: (3,) lux per channel.

    Sky only (no sun); arguments as :func:`sky_sh`. By :func:`sky_quadrature_rule`
    with the default nodes (converged as :func:`sky_sh`). Cached per argument set.
    """
    ts, t, a = _check_scalars(sun_zenith, turbidity, albedo)
    return _horizontal_irradiance(ts, t, a, colourspace, _resolve(dataset, colourspace)).copy()


@lru_cache(maxsize=256)
def _horizontal_irradiance(ts: float, t: float, a: float, colourspace: str, kind: str) -> NDArray[np.float64]:
    dirs, weights = preetham._sky_rule(ts, SKY_SH_THETA_NODES, QUADRATURE_SPLIT)
    out = (weights * dirs[:, 2]) @ _rgb(dirs, ts, 0.0, t, a, colourspace, kind)
    out.flags.writeable = False
    return out


def sky_minimum(sun_zenith: float, turbidity: float, albedo: float, colourspace: str = "sRGB",
                dataset: str = "auto") -> NDArray[np.float64]:
    """
    Minimum of the sky over the closed upper hemisphere, per RGB channel and of luminance.

    Parameters
    ----------
    sun_zenith, turbidity, albedo, colourspace, dataset
        As :func:`sky_sh`.

    Returns
    -------
    ndarray
        (4,): the minimum R, G, B and Y in cd/m^2, each minimised on its own (the
        L_min of the Habel seed's eqs. 2, 3). Can be negative: the model's
        radiance undershoots at the horizon for a low sun.

    Notes
    -----
    The search of :func:`skysh.model.preetham.hemisphere_minimum`.
    """
    ts, t, a = _check_scalars(sun_zenith, turbidity, albedo)
    kind = _resolve(dataset, colourspace)
    row = luminance_row(colourspace)

    def values(d: NDArray) -> NDArray:
        rgb = _rgb(d.reshape(-1, 3), ts, 0.0, t, a, colourspace, kind).reshape(d.shape)
        return np.concatenate([rgb, (rgb @ row)[..., None]], axis=-1)

    return preetham.hemisphere_minimum(values)
