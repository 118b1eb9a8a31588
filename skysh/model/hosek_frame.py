"""
Hosek-Wilkie sky SH per frame: the exact model on a small sun-adapted rule
==========================================================================

-   :func:`coefficients`: the sky's radiance SH, (..., N*N, 3) cd/m^2, scalar or batched.
-   :data:`ACCURACIES`, :class:`Accuracy`: the rules offered ("fast", "default", "fine").
-   :func:`basis_rows`: the SH basis at azimuth 0 as Chebyshev sums in cos(k theta) (the exports' data).
-   :func:`rule`: the rule of one sun position (ring zenith angles and weights, azimuth
    nodes and weights), for inspection and studies.

Tabulating the sky's SH over (sun zenith, turbidity, albedo) cannot reach 1e-4 of L_min
(``docs/hosek.md``): the dataset interpolates the model's *parameters* (quintic Bezier in
elevation^(1/3), linear between integer turbidities and between albedo 0 and 1), and the
sky is not linear in them. So each call evaluates the model itself (Hosek and Wilkie 2012,
eq. 9, parameters as section 5, :func:`skysh.model.hosek.configuration`) on a product rule
fitted to the sun and contracts it with the SH basis:

-   zenith panels with edges {0, the sun's zenith, 45 deg, 85 deg, 90 deg}: Gauss-Legendre in
    theta for zenith angles below 45 deg, in u = sqrt(cos theta) above (the model's
    I sqrt(cos theta) term is then a polynomial); the horizon panel [85, 90] deg holds the
    steep exp(B / (cos theta + 0.01)) and the low sun's horizon glow; the sun's cone kink
    exp(E gamma) sits on a panel edge. The fixed panel holding the sun gets
    :attr:`Accuracy.sun` nodes more, shared by its two sides in proportion to their widths
    (at least :attr:`Accuracy.minimum` each), so that the number of rings never changes and
    a sun just past a fixed edge wastes no nodes on the thin side;
-   azimuth: Gauss-Legendre on [0, pi] only (the sky is mirror-symmetric about the sun's
    vertical plane: its m < 0 coefficients vanish), more nodes when the sun is within
    :data:`LOW_SUN` of the horizon (the glow around a low sun is narrow in azimuth);
-   per call: the parameters, the model on (rings x azimuth nodes), one Legendre row per ring
    (Chebyshev sums cos(k theta) of constants computed once per band count), two contractions,
    then the rotation about Z by the sun's azimuth (Habel 2008, eq. 4). Gauss nodes and weights
    are computed once per (accuracy, panel layout) and cached.

Accuracy (``python tools/hosek_study.py --rule --jobs 2``: worst E_mean of the Habel seed, eq. 3,
fraction of L_min, over 272 held-out random skies and 96 stress skies -- suns in [80, 90] degrees,
on and 1e-7 rad either side of every panel edge, the domain's corners -- against
:func:`skysh.model.hosek.sky_sh`, which doubling its nodes moves by less than 1e-8 of L_min)::

    accuracy  rings  azimuth  points     3 bands random/stress  7 bands random/stress
    fast        26    20/24   520/624     5.2e-5 / 1.1e-4        2.0e-4 / 3.8e-4
    default     34    24/28   816/952     9.1e-6 / 1.4e-5        2.1e-5 / 3.3e-5
    fine        42    28/36  1176/1512    3.7e-6 / 4.8e-6        8.5e-6 / 1.1e-5

(azimuth and points: the sun above / beyond :data:`LOW_SUN`). Sharing the sun panel's nodes in
halves instead of by width costs "default" 2.3x at 7 bands (stress 7.7e-5); a minimum of 2
instead of 5 nodes per side 36x (a thin side next to the sun starves); the extra azimuth
nodes for a low sun gain 10 %. One call at 7 bands takes about 0.17 ms (numpy, sRGB, 2-core
machine; 86 us a sky in a batch of 1,000): 26 to 29 times the Preetham table's
:meth:`skysh.SkySH.coefficients`. The ground is not part of the result (zero below the
horizon, skysh's convention); add :func:`skysh.model.ground.ground_sh` for it.

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome Radiance.
    ACM Trans. Graph. 31(4), 95: eq. (9), section 5.
-   Habel, R., Mustata, B., Wimmer, M. (2008). Efficient Spherical Harmonics Lighting with
    the Preetham Skylight Model: eq. (4) (rotation about Z), eqs. (2), (3) (error measures).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import cache
from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_bands, check_choice, check_range, check_size
from skysh.model import hosek, hosek_data, preetham
from skysh.sh import basis as sh

__all__ = ["ACCURACIES", "Accuracy", "basis_rows", "coefficients", "rule"]


@dataclass(frozen=True)
class Accuracy:
    """Node counts of the sun-adapted rule (see the module docstring)."""

    zenith: tuple[int, int, int]
    """Gauss-Legendre nodes of the fixed zenith panels [0, 45], [45, 85] and [85, 90] degrees."""
    sun: int
    """Nodes added to the fixed panel that holds the sun, shared by its two sides by width."""
    minimum: int
    """Least nodes of either side of the sun (when the sun is strictly inside its panel)."""
    azimuth: int
    """Gauss-Legendre azimuth nodes on [0, pi]."""
    low_sun_azimuth: int
    """Azimuth nodes when the sun's zenith angle exceeds :data:`LOW_SUN`."""
    by_width: bool = True
    """Share the sun panel's nodes by the widths of its sides (else half each): the study's comparison."""

    @property
    def rings(self) -> int:
        """Zenith nodes (rings) of the rule, the same for every sun position."""
        return sum(self.zenith) + self.sun


ACCURACIES: dict[str, Accuracy] = {
    "fast": Accuracy((6, 8, 6), 6, 4, 20, 24),
    "default": Accuracy((8, 10, 8), 8, 5, 24, 28),
    "fine": Accuracy((10, 12, 10), 10, 6, 28, 36),
}
"""The rules offered (node counts: :class:`Accuracy`'s fields in order); "default" is the cheapest of those
measured that meets issue 27's targets (worst E_mean 3e-5 at 3 bands, 1e-4 at 7, on both point sets) with
a margin of 2x or more; "fast" misses them by up to 3.8x, "fine" has 9x margin (table in the module docstring)."""

ZENITH_EDGES: tuple[float, ...] = (0.0, math.pi / 4.0, math.radians(85.0), math.pi / 2.0)
"""The fixed zenith panel edges, radians: 0, 45, 85 and 90 degrees."""

U_FROM: float = hosek.QUADRATURE_SPLIT
"""Zenith angle (45 degrees) from which the panels are Gauss-Legendre in u = sqrt(cos theta)."""

LOW_SUN: float = math.radians(80.0)
"""Sun zenith angle, radians, beyond which the rule takes :attr:`Accuracy.low_sun_azimuth` azimuth nodes."""

MAX_BANDS: int = 16
"""Most bands :func:`coefficients` takes (the rules are measured to 7; more bands need finer rules)."""

_FINITE: float = 1e300
"""Azimuths the checks-free path takes (any finite float beyond is still checked by numpy's path)."""

CHUNK: int = 256
"""Skies evaluated together: the model at the nodes of a chunk holds at most 256 x 42 x 11 x 36 values (33 MB)."""


@dataclass(frozen=True)
class _Layout:
    """The standard nodes of one panel layout: which fixed panel holds the sun, how its nodes are shared."""

    panel: int  # index of the fixed panel holding the sun
    nodes: NDArray[np.float64]  # (R,) Gauss nodes on [0, 1], panel by panel
    weights: NDArray[np.float64]  # (R,) their weights (sum 1 per panel)
    side: NDArray[np.intp]  # (R,) the sub-panel of each node: 0..3
    in_u: NDArray[np.bool_]  # (R,) nodes of panels integrated in u = sqrt(cos theta)
    phi: NDArray[np.float64]  # (J,) azimuth nodes on [0, pi]
    phi_weights: NDArray[np.float64]  # (J,) weights x 2 (the mirrored half)
    half_sin2: NDArray[np.float64]  # (J,) sin^2(phi / 2)


def _key(acc: Accuracy, ts: float) -> tuple[int, int, bool]:
    """The layout of a sun zenith: the fixed panel holding it (a sun on an inner edge: the panel above it), the
    nodes of that panel's upper side [edge, ts] (by width or half, at least ``minimum`` a side; a sun on the
    panel's edge splits nothing) and whether the sun is low (:data:`LOW_SUN`)."""
    panel = max(bisect.bisect_left(ZENITH_EDGES, ts) - 1, 0)
    low, high = ZENITH_EDGES[panel], ZENITH_EDGES[panel + 1]
    total = acc.zenith[panel] + acc.sun
    if ts <= low or ts >= high:
        return panel, 0 if ts <= low else total, ts > LOW_SUN
    fraction = (ts - low) / (high - low) if acc.by_width else 0.5
    return panel, min(max(round(total * fraction), acc.minimum), total - acc.minimum), ts > LOW_SUN


@cache
def _layout(acc: Accuracy, panel: int, upper: int, low_sun: bool) -> _Layout:
    """Gauss nodes of a layout, computed once: the sun panel's sides get ``upper`` and the rest of its nodes."""
    counts = list(acc.zenith)
    counts.insert(panel + 1, counts[panel] + acc.sun - upper)
    counts[panel] = upper
    nodes, weights, side = [], [], []
    for k, n in enumerate(counts):
        x, w = sh.gauss_legendre(n) if n else (np.empty(0), np.empty(0))
        nodes.append(0.5 * (x + 1.0))
        weights.append(0.5 * w)
        side.append(np.full(n, k, dtype=np.intp))
    phi_x, phi_w = sh.gauss_legendre(acc.low_sun_azimuth if low_sun else acc.azimuth)
    phi = 0.5 * math.pi * (phi_x + 1.0)
    side_all = np.concatenate(side)
    in_u = side_all >= (2 if panel == 0 else 1)  # the sub-panels below 45 degrees (U_FROM)
    out = _Layout(panel, np.concatenate(nodes), np.concatenate(weights), side_all, in_u, phi, math.pi * phi_w,
                  np.sin(0.5 * phi) ** 2)
    for array in (out.nodes, out.weights, out.side, out.in_u, out.phi, out.phi_weights, out.half_sin2):
        array.flags.writeable = False
    return out


def _rings(layout: _Layout, ts: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Ring zenith angle, cos, sqrt(cos) and weight (dcos theta, times the panel's width), (G, R), for suns ``ts`` (G,)."""
    edges = np.empty((ts.size, 5))
    edges[:, : layout.panel + 1] = ZENITH_EDGES[: layout.panel + 1]
    edges[:, layout.panel + 1] = ts
    edges[:, layout.panel + 2 :] = ZENITH_EDGES[layout.panel + 1 :]
    low, high = edges[:, layout.side], edges[:, layout.side + 1]  # (G, R)
    u_low, u_high = np.sqrt(np.cos(high)), np.sqrt(np.cos(low))
    u_low[high >= 0.5 * math.pi] = 0.0  # cos(pi/2) rounds to 6e-17: the horizon is u = 0
    theta = low + (high - low) * layout.nodes
    u = u_low + (u_high - u_low) * layout.nodes
    cos = np.where(layout.in_u, u * u, np.cos(theta))
    theta = np.where(layout.in_u, np.arccos(np.minimum(cos, 1.0)), theta)
    weight = layout.weights * np.where(layout.in_u, (u_high - u_low) * 2.0 * u, (high - low) * np.sin(theta))
    return theta, cos, np.sqrt(cos), weight


@cache
def basis_rows(bands: int) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.bool_]]:
    """(bands, N*N) Chebyshev coefficients c[k, i] with Y_(l,|m|)(theta, phi = 0) = sin^|m|(theta) sum_k c[k, i]
    cos(k theta) (the m < 0 columns repeat the m > 0 ones: the rotation picks cos or sin), the |m| of each
    index and whether m < 0; computed once from skysh's basis."""
    x = np.cos(math.pi * (np.arange(bands) + 0.5) / bands)  # Chebyshev nodes of the first kind in z
    s = np.sqrt(1.0 - x * x)
    values = sh.basis(np.stack([s, np.zeros(bands), x], axis=-1), bands)  # (bands, N*N) at phi = 0
    lms = [sh.lm(i) for i in range(bands * bands)]
    m = np.array([abs(mm) for _, mm in lms], dtype=np.intp)
    values = values[:, [sh.index(l, abs(mm)) for l, mm in lms]]
    rows = np.asarray(np.polynomial.chebyshev.chebfit(x, values / s[:, None] ** m, bands - 1), dtype=np.float64)
    negative = np.array([mm < 0 for _, mm in lms], dtype=np.bool_)
    for array in (rows, m, negative):
        array.flags.writeable = False
    return rows, m, negative


@cache
def _parameter_table(kind: str) -> NDArray[np.float64]:
    """(10, 2, 6, C, 10): the dataset's parameters A..I (stored order) and L_M side by side, read once."""
    params, mean = (hosek_data.sky_tensors()[key] for key in hosek._DATA_KEYS[kind])
    out = np.concatenate([params, mean[..., None]], axis=-1)
    out.flags.writeable = False
    return out


@cache
def _azimuth_matrix(nodes: int, bands: int) -> NDArray[np.float64]:
    """(J, bands): ``g @ matrix`` is the integral over the azimuth circle of g (..., J) times cos(m phi),
    m = 0..bands-1, for g symmetric about phi = 0 and given at the Gauss nodes on [0, pi]; computed once."""
    x, w = sh.gauss_legendre(nodes)
    out = math.pi * w[:, None] * np.cos(np.outer(0.5 * math.pi * (x + 1.0), np.arange(bands)))
    out.flags.writeable = False
    return out


def _project(layout: _Layout, ts: NDArray, t: NDArray, a: NDArray, phi: NDArray, bands: int,
             kind: str) -> NDArray[np.float64]:
    """(G, N*N, C) SH of the model's channels (dataset units), turned by the azimuths ``phi``, for suns of one
    layout: ts, t, phi (G,), a (G,) or (G, 3) per channel, checked."""
    theta, ct, sct, w = _rings(layout, ts)
    if a.ndim == 1:
        p = hosek._interpolate(_parameter_table(kind), ts, t, a)  # (G, C, 10)
    else:  # one albedo per channel, (G, C): the dataset is linear in albedo between its two tables
        ends = [hosek._interpolate(_parameter_table(kind), ts, t, np.full_like(ts, e)) for e in (0.0, 1.0)]
        p = (1.0 - a[..., None]) * ends[0] + a[..., None] * ends[1]
    pa, pb, pc, pd, pe, pf, pg, pi_, ph, lm = (v[:, None, :] for v in np.moveaxis(p, -1, 0))  # (G, 1, C)
    # 1 - cos gamma = 2 sin^2((theta - ts) / 2) + 2 sin theta sin ts sin^2(phi / 2): accurate near the sun
    hav = np.sin(0.5 * (theta - ts[:, None])) ** 2
    hav = np.minimum(hav[..., None] + (np.sin(theta) * np.sin(ts)[:, None])[..., None] * layout.half_sin2, 1.0)
    gamma, cg = (2.0 * np.arcsin(np.sqrt(hav)))[:, :, None, :], (1.0 - 2.0 * hav)[:, :, None, :]  # (G, R, 1, J)
    den = 1.0 + ph[..., None] * (ph[..., None] - 2.0 * cg)
    chi = (1.0 + cg * cg) / (den * np.sqrt(den))  # (G, R, C, J)
    sums = _azimuth_matrix(layout.phi.size, bands)
    by_m = pd[..., None] * (np.exp(pe[..., None] * gamma) @ sums)  # (G, R, C, bands)
    by_m += pg[..., None] * (chi @ sums) + pf[..., None] * ((cg * cg) @ sums)
    by_m[..., 0] += 2.0 * math.pi * (pc + pi_ * sct[..., None])  # the terms constant in the azimuth: m = 0 only
    radial = (1.0 + pa * np.exp(pb / (ct[..., None] + hosek.HORIZON_OFFSET))) * lm * w[..., None]  # (G, R, C)
    rows, m, negative = basis_rows(bands)
    y = (np.cos(theta[..., None] * np.arange(bands)) @ rows) * np.sin(theta)[..., None] ** m  # (G, R, N*N)
    turn = np.fmod(phi, 2.0 * math.pi)[:, None] * m  # Habel eq. 4 for coefficients whose m < 0 vanish
    factor = np.where(negative, np.sin(turn), np.cos(turn))  # (G, N*N)
    return np.einsum("gri,grci->gic", y, (radial[..., None] * by_m)[..., m]) * factor[..., None]


def _accuracy(accuracy: str | Accuracy) -> Accuracy:
    """The rule's node counts: a key of :data:`ACCURACIES`, or an :class:`Accuracy` (for studies)."""
    return accuracy if isinstance(accuracy, Accuracy) else ACCURACIES[check_choice(accuracy, "accuracy", tuple(ACCURACIES))]


def _check(sun_zenith: ArrayLike, turbidity: ArrayLike, albedo: ArrayLike, sun_azimuth: ArrayLike,
           per_channel: bool) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The four parameters checked and broadcast (the albedo's channel axis kept apart with ``per_channel``);
    Python numbers in range take a path without numpy's checks."""
    values = (sun_zenith, turbidity, albedo, sun_azimuth)
    ranges = (hosek.SUN_ZENITH_RANGE, hosek.TURBIDITY_RANGE, hosek.ALBEDO_RANGE, (-_FINITE, _FINITE))
    if not per_channel and all(type(v) in (float, int) and r[0] <= cast(float, v) <= r[1]
                               for v, r in zip(values, ranges)):  # not NaN
        return tuple(np.array(float(cast(float, v))) for v in values)  # type: ignore[return-value]
    ts = check_range(sun_zenith, "sun_zenith", *hosek.SUN_ZENITH_RANGE, unit="rad")
    t = check_range(turbidity, "turbidity", *hosek.TURBIDITY_RANGE)
    a = check_range(albedo, "albedo", *hosek.ALBEDO_RANGE)
    phi = check_range(sun_azimuth, "sun_azimuth", -math.inf, math.inf, unit="rad")
    if per_channel and (a.ndim == 0 or a.shape[-1] != 3):
        raise ValueError(f"albedo must end in an axis of 3 (R, G, B) with per_channel=True, got shape {a.shape}")
    a_shape = a.shape[:-1] if per_channel else a.shape
    shape = preetham._broadcast_shape("sun_zenith, turbidity, albedo and sun_azimuth", ts.shape, t.shape, a_shape,
                                      phi.shape)
    a = np.broadcast_to(a, shape + a.shape[len(a_shape):])
    return np.broadcast_to(ts, shape), np.broadcast_to(t, shape), a, np.broadcast_to(phi, shape)


def coefficients(sun_zenith: ArrayLike, turbidity: ArrayLike, albedo: ArrayLike, sun_azimuth: ArrayLike = 0.0,
                 bands: int = 3, colourspace: str = "sRGB", accuracy: str | Accuracy = "default",
                 per_channel: bool = False) -> NDArray[np.float64]:
    """
    SH of the Hosek-Wilkie sky's radiance, from the exact model on a sun-adapted rule.

    Parameters
    ----------
    sun_zenith
        Sun zenith angle, radians, [0, pi/2].
    turbidity
        [1, 10].
    albedo
        Ground albedo, [0, 1]: one grey value per sky, as :mod:`skysh.model.hosek` (whose
        dataset interpolation and reference take a scalar albedo); with ``per_channel``, one
        per RGB channel on a last axis of 3.
    sun_azimuth
        Radians, any finite value (from +X towards +Y).
    bands
        Number of bands N, [1, :data:`MAX_BANDS`]; the accuracies are measured at 3 and 7.
    colourspace
        colour-science RGB colourspace name. "sRGB" (default) projects the RGB dataset;
        any other projects the 11 spectral channels on the same rule and converts them
        linearly (the route of :func:`skysh.model.hosek.radiance`).
    accuracy
        A key of :data:`ACCURACIES` or an :class:`Accuracy`.
    per_channel
        ``albedo``'s last axis holds (R, G, B): each channel of the RGB dataset takes its
        parameters at its own albedo, ``(1 - a_c) P_c(0) + a_c P_c(1)`` (the dataset is linear in
        albedo between its two tables; the channels are independent). "sRGB" only: the spectral
        channels take one grey albedo.

    Returns
    -------
    ndarray
        (..., N*N, 3) linear RGB SH coefficients of the sky's radiance, cd/m^2 (real
        orthonormal, Condon-Shortley phase, index l(l+1)+m), the four parameters
        broadcast to (...,). The sky only: zero below the horizon.

    Raises
    ------
    ValueError
        A parameter outside its range, NaN or inf (naming it and the range), arrays that
        do not broadcast, an unknown colourspace or accuracy.

    Notes
    -----
    Per sky: the parameters A..I and L_M of the dataset at (sun zenith, turbidity, albedo)
    (Hosek and Wilkie 2012, section 5: quintic Bezier in (elevation / (pi/2))^(1/3), linear in
    turbidity and albedo), the model L = F(theta, gamma) L_M (eq. 9) at the rule's rings x
    azimuth nodes, ``c(l, m) = sum_r w_r Y_l|m|(theta_r, 0) sum_j w_j cos(|m| phi_j) L(theta_r, phi_j)``
    with the sun at azimuth 0, then the rotation about Z (Habel 2008, eq. 4), which for these
    mirror-symmetric coefficients is c(l, |m|) cos(m alpha) for m >= 0 and c(l, |m|)
    sin(|m| alpha) for m < 0. Accuracy: the module docstring's table (E_mean, Habel eqs. 2, 3).

    Examples
    --------
    >>> coefficients(0.5, 3.0, 0.2, sun_azimuth=1.0, bands=7).shape
    (49, 3)
    """
    acc = _accuracy(accuracy)
    bands = check_bands(bands, high=MAX_BANDS)
    kind = hosek._resolve("auto", colourspace)
    if per_channel and kind != "rgb":
        raise ValueError(f"per_channel=True needs colourspace 'sRGB' (the RGB dataset), got {colourspace!r}: the "
                         "spectral channels take one grey albedo")
    ts, t, a, phi = _check(sun_zenith, turbidity, albedo, sun_azimuth, per_channel)
    channels = 3 if kind == "rgb" else hosek.WAVELENGTHS.size
    check_size(ts.size * bands * bands * channels, "sun_zenith", "the coefficients")
    flat = [v.reshape(-1, *v.shape[ts.ndim:]) for v in (ts, t, a, phi)]
    out = np.empty((flat[0].size, bands * bands, channels))
    groups: dict[tuple[int, int, bool], list[int]] = {}
    for i, z in enumerate(flat[0].tolist()):
        groups.setdefault(_key(acc, z), []).append(i)
    for key, members in groups.items():
        layout = _layout(acc, *key)
        for start in range(0, len(members), CHUNK):
            chunk = np.array(members[start : start + CHUNK])
            out[chunk] = _project(layout, flat[0][chunk], flat[1][chunk], flat[2][chunk], flat[3][chunk], bands, kind)
    if kind == "rgb":
        out *= hosek.LUMINOUS_EFFICACY
    else:
        out = out @ (hosek.spectral_to_xyz_weights() @ preetham.rgb_from_xyz_matrix(colourspace).T)
    return out.reshape(ts.shape + (bands * bands, 3))


def rule(sun_zenith: float, accuracy: str | Accuracy = "default") -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """
    The sun-adapted rule of one sun position (its sun at azimuth 0).

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    accuracy
        A key of :data:`ACCURACIES` or an :class:`Accuracy`.

    Returns
    -------
    theta, theta_weights, phi, phi_weights
        (R,) ring zenith angles (radians) and weights (of d cos theta), (J,) azimuth nodes on
        [0, pi] and weights (doubled: the mirrored half). The product integrates a function
        f symmetric about the sun's vertical plane over the upper hemisphere:
        ``sum_rj theta_weights[r] phi_weights[j] f(theta[r], phi[j])``.
    """
    acc = _accuracy(accuracy)
    ts = check_range(sun_zenith, "sun_zenith", *hosek.SUN_ZENITH_RANGE, unit="rad").reshape(1)
    layout = _layout(acc, *_key(acc, float(ts[0])))
    theta, _, _, w = _rings(layout, ts)
    return theta[0], w[0], layout.phi.copy(), layout.phi_weights.copy()
