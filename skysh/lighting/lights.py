"""
The sun and the ground in the per-frame runtime (issue 15)
==========================================================

The arithmetic behind ``SkySH.coefficients(..., sun=True, ground_albedo=...)``
and ``SkySH.sun_light``; :mod:`skysh.runtime` owns the API and the checks of
the sky's parameters, this module the static tables and the per-frame sums.

-   :func:`check_albedo`: the ``ground_albedo`` parameter, checked (defined in :mod:`skysh.options`).
-   :func:`sun_trig_matrix`: the sun's windowed SH at azimuth 0 as a
    trigonometric polynomial in the sun zenith.
-   :func:`ground_zonal`: the ground's zonal SH per unit radiance, Gibbs-filtered or not.
-   :class:`LitPlan`: everything static of one (bands, gibbs) setting with the
    sun and the ground; its :meth:`LitPlan.fused` evaluates sky + sun + ground
    of one frame with one vectorised cosine, two small products, one gather and a (N^2, 5) x (5, 3) product.

Order of the parts (``SkySH.coefficients``)
-------------------------------------------
sky (Habel eq. 1) -> Gibbs filter of the sky (eq. 5) -> rotation (eq. 4) ->
deringing of the sky alone -> + the sun, a delta windowed by
:func:`skysh.model.solar.sun_window` (never Gibbs-filtered: the window is its
filter) -> colourspace conversion -> + the ground (after the conversion, so an
RGB albedo is in the output colourspace) -> clamped-cosine convolution. Each
added part has a non-negative irradiance by construction (the window keeps a
delta's irradiance >= 0; the ground's irradiance is ``pi L_g (1 - s_1 n_z) / 2``
with ``s_1 <= 1``), so the deringed sky plus them is non-negative too, for
non-negative RGB. The sun leaves the sRGB gamut near the horizon (a slightly
negative blue, :func:`skysh.model.solar.illuminance_rgb`); its delta then takes the
colour clamped to >= 0 (:data:`SUN_SH_CLAMP`), the directional light of
``sun_light`` keeps the exact value.

The ground
----------
A Lambertian ground of albedo rho reflects ``L_g = rho E_h / pi`` (cd/m^2) with
E_h the irradiance of the horizontal ground: ``sqrt(4 pi / 3) c_10`` of the
*unfiltered* sky fit (exact for light that is zero below the horizon,
:func:`skysh.model.ground.horizontal_irradiance_from_sh`; the fitted table holds c_10
whatever ``bands``, so 1 band gets it too) plus ``E_sun cos(theta_s)`` when the
sun is on. Its SH are zonal (:data:`skysh.model.ground.GROUND_ZONAL`), multiplied by
the zonal sinc filter when ``gibbs`` is on: ``python tools/sun_study.py --ground``
prints the trade. Without the filter the ground's irradiance is exact for every
N >= 2 (only bands 0 and 1 reach it) and its radiance overshoots by 0.25 at
N = 3; with it the radiance ring halves (0.12 at N = 3) but the irradiance is off
by up to 8.65 % of pi L_g. So the ground follows the sky's ``gibbs`` setting:
off by default for irradiance (exact), on by default for radiance (half the ring).

The sun's SH as a trigonometric polynomial
------------------------------------------
At azimuth 0 the sun's direction is ``(sin ts, 0, cos ts)``; each real SH
``Y_lm`` (m >= 0) is a homogeneous polynomial of degree l in (x, y, z), so
``Ybar_lm(ts) = Y_lm(sin ts, 0, cos ts) = sum_{k<N} a_k cos(k ts) + b_k sin(k ts)``
exactly. :func:`sun_trig_matrix` finds (a, b) from 4 N equally spaced samples
(an exact discrete Fourier fit, to rounding) with the window folded in; the
runtime's scalar path gets cos(k ts) and sin(k ts) from the same vectorised
cosine that already gives the Chebyshev terms and the rotation factors, and
rotates the sun with the sky's own rotation (eq. 4): ``c_{l,-m} = Ybar_lm sin(m
phi)``, ``c_{l,m} = Ybar_lm cos(m phi)``.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5);
    ground colour named as future work.
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000): section 3,
    windowed direct lights.
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: the sun's light.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_bands, check_flag, read_only
from skysh.domain import KASTEN_COEFFICIENTS, SUN
from skysh.model import ground
from skysh.model.preetham import luminance_scale_unchecked
from skysh.options import ALBEDO_RANGE, check_albedo
from skysh.sh import basis as sh
from skysh.table import coefficient_file

__all__ = ["SUN_SH_CLAMP", "ALBEDO_RANGE", "check_albedo", "sun_trig_matrix", "ground_zonal", "LitPlan"]

SUN_SH_CLAMP: float = 0.0
"""Lower bound of each channel of the sun's RGB illuminance in its SH delta (lux).

Near the horizon the sun's colour leaves the sRGB gamut: blue, at high turbidity
also green, turns slightly negative (``python tools/sun_study.py --table`` prints
RGB / Y: blue -0.03 Y at 88 deg for T = 2.5, green -0.49 Y on the horizon for
T = 6, where the sun is 2.5e-4 lux). A negative channel would make the
windowed delta's irradiance negative, so the delta takes the colour clamped to
this bound; :meth:`skysh.SkySH.sun_light` and the ground's irradiance keep the
exact value."""

_TWO_PI: float = 2.0 * math.pi
_INV_PI: float = 1.0 / math.pi
_HF: float = ground.HORIZONTAL_FACTOR
_A, _B, _NEG_C = KASTEN_COEFFICIENTS[0], KASTEN_COEFFICIENTS[1], -KASTEN_COEFFICIENTS[2]
# The sun table's map (skysh.domain.SUN) as floats: x_s = (m - _M0) _SX_SCALE - 1, y_s = (T - _TMIN) _SY_SCALE - 1.
_M0, _SX_SCALE, _TMIN, _SY_SCALE = SUN.x.origin, SUN.x.scale, SUN.y.origin, SUN.y.scale
_DEG: float = 180.0 / math.pi


def sun_trig_matrix(bands: int, window: ArrayLike) -> NDArray[np.float64]:
    """
    (K_half, 2 N): ``window[l] Y_lm(sin ts, 0, cos ts) = M @ [cos(k ts)]_k ++ [sin(k ts)]_k``, k = 0 .. N - 1.

    Rows follow :func:`skysh.table.coefficient_file.zonal_half_layout` (m >= 0);
    exact to rounding (a discrete Fourier fit on 4 N samples of a trigonometric
    polynomial of degree < N; ``tests/lighting/test_lights.py`` checks it against
    :func:`skysh.sh.basis.basis`).
    """
    bands = check_bands(bands, high=sh.MAX_BANDS)
    w = as_float_array(window, "window")
    if w.ndim != 1 or w.shape[0] < bands:
        raise ValueError(f"window must have shape (>= {bands},) (one factor per band), got {w.shape}")
    layout = coefficient_file.zonal_half_layout(bands)
    samples = 4 * bands
    theta = _TWO_PI * np.arange(samples) / samples
    dirs = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=-1)
    y = sh.basis(dirs, bands)[:, [l * (l + 1) + m for l, m in layout]] * w[[l for l, _ in layout]]
    k = np.arange(bands)
    design = np.concatenate([np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k))], axis=1)
    matrix = np.linalg.lstsq(design, y, rcond=None)[0].T
    matrix[:, bands] = 0.0  # sin(0 ts) = 0: no information, keep it exactly 0
    return np.ascontiguousarray(matrix)


def ground_zonal(bands: int, gibbs: bool) -> NDArray[np.float64]:
    """(N * N,): the ground's SH per unit radiance (:data:`skysh.model.ground.GROUND_ZONAL` on the m = 0 rows),
    times the zonal sinc filter sinc(pi l / N) when ``gibbs``."""
    bands, gibbs = check_bands(bands, high=sh.MAX_BANDS), check_flag(gibbs, "gibbs")
    out = np.zeros(bands * bands)
    factors = np.sinc(np.arange(bands) / bands) if gibbs else np.ones(bands)
    out[[l * (l + 1) for l in range(bands)]] = ground.GROUND_ZONAL[:bands] * factors
    return out


def _trig_q(bands: int, window: ArrayLike, zonal: NDArray[np.float64], lobe: bool) -> NDArray[np.float64]:
    """(K_half, 2, 2 N): Q per frame = q @ trig(ts): the sun's windowed Ybar; the ground's constant via
    cos(0 ts) = 1; times the clamped-cosine factors A_l when ``lobe`` (irradiance out)."""
    layout = coefficient_file.zonal_half_layout(bands)
    q = np.zeros((len(layout), 2, 2 * bands))
    q[:, 0, :] = sun_trig_matrix(bands, window)
    q[:, 1, 0] = [zonal[l * (l + 1)] if m == 0 else 0.0 for l, m in layout]
    if lobe:  # the sun and the ground convolved as the sky (its plan built with ``lobe``)
        q *= sh.cosine_lobe(bands)[[l for l, _ in layout]][:, None, None]
    return q


def _angle_map(sky_degrees: tuple[int, int], sun_degrees: tuple[int, int], bands: int,
               depth: int) -> NDArray[np.float64]:
    """:class:`LitPlan`'s angle map: rows (column, multiplier, phase) over the columns (acos x, acos y, phi,
    1, ts, acos x_s, acos y_s); see the class docstring for the order of its blocks."""
    (dx, dy), (sdx, sdy) = sky_degrees, sun_degrees
    zero = (3, 0, 0.5 * math.pi)  # cos(pi / 2) = 6e-17: the weight matrix's zeros
    rows = [(0, k, 0.0) for k in range(dx + 1)] + [(5, k, 0.0) for k in range(sdx + 1)]
    rows += [(4, k, 0.0) for k in range(bands)] + [(4, k, -0.5 * math.pi) for k in range(bands)]
    rows += [(1, j if j <= dy else 0, 0.0) for j in range(depth)] + [zero]  # padding rows meet zero columns
    rows += [(6, j if j <= sdy else 0, 0.0) for j in range(depth)] + [zero]
    rows += [zero] * depth + [(3, 0, 0.0)]
    rows += [(2, m, 0.0) for m in range(bands)] + [(2, m, -0.5 * math.pi) for m in range(bands)]
    angle_map = np.zeros((len(rows), 7))
    for r, (column, multiplier, phase) in enumerate(rows):
        angle_map[r, column] += multiplier
        angle_map[r, 3] += phase
    return angle_map


class LitPlan:
    """
    Static tables of one (bands, gibbs) setting with the sun and the ground.

    Built from the runtime's sky plan of the same setting whose half table
    carries one extra row, the *unfiltered* (1, 0) coefficient (for E_h), and
    from the file's sun table (or none: then only the ground is available).

    The scalar path packs every per-frame factor into one vectorised cosine,
    ``cos(angle_map @ (acos x, acos y, phi, 1, ts, acos x_s, acos y_s))``: the
    sky's Chebyshev terms T_i(x), T_j(y), the sun table's T_i(x_s), T_j(y_s)
    (x_s affine in Kasten's air mass, y_s in the turbidity:
    :data:`skysh.table.sun_table.SUN_VARIABLES`), the sun's cos(k ts), sin(k ts) and the
    rotation factors cos(m phi), sin(m phi). Then two products: ``a = u @
    table_x`` with u = (T(x), T(x_s), trig(ts)) and a block table, read as a
    (D + 1, C) matrix; ``b = Y @ a`` with the (3, D + 1) weights Y = [[T(y), 0],
    [T(y_s), 0], [0, 1]] (also from the cosine; its zeros are cos(pi/2) =
    6e-17, a perturbation at the rounding level): b[0] holds the sky's m >= 0
    coefficients over the luminance scale and its unfiltered c_10, b[1] the
    sun's ln XYZ, b[2] the (K_half, 2) matrix Q = [sun's windowed Ybar(ts),
    ground's zonal factor]. One gather of b gives, per output coefficient, the
    sky's three channels, the sun's Ybar and the ground's factor (m < 0 values
    from their m > 0 partners), one multiplication rotates all five (eq. 4), and
    one product with V = [lum I; sun RGB; ground RGB] (5, 3), built from Python
    floats, adds sun and ground and applies the sky's luminance scale.

    ``lobe``: irradiance out, the clamped-cosine factors A_l folded into the sky
    plan's rows (built with ``lobe``) and into Q, for :meth:`fused` only.
    """

    __slots__ = ("bands", "k_half", "width", "depth", "nx", "y_slice", "angle_map", "table_x", "gather", "rotation",
                 "zonal_rows", "ground_rows", "window_l", "rgb_from_xyz", "rgb_rows", "sky", "readback", "gather5",
                 "rotation5")

    def __init__(self, sky_plan: Any, sun_named: Any, rgb_from_xyz: ArrayLike | None, gibbs: bool,
                 lobe: bool = False) -> None:
        from skysh.model.solar import SUN_WINDOWS  # physics constants, only when the sun or the ground is first used

        self.sky = sky_plan  # the runtime's _Plan with the unfiltered c_10 row (its batch path uses it)
        bands = self.bands = int(sky_plan.bands)
        dx, dy = sky_plan.degrees
        self.k_half = k_half = bands * (bands + 1) // 2
        self.width = width = (k_half + 1) * 3  # sky m >= 0 rows and the unfiltered c_10, x 3 channels
        sun_table = np.zeros((1, 1, 3)) if sun_named is None else np.asarray(sun_named.table, dtype=np.float64)
        sdx, sdy = (0, 0) if sun_named is None else sun_named.max_degrees
        self.depth = depth = max(dy, sdy) + 1
        self.nx = nx = dx + sdx + 2 + 2 * bands
        # (K_half, 2) Q per frame = q @ trig: the sun's windowed Ybar; the ground's constant via cos(0 ts) = 1.
        window = SUN_WINDOWS[bands - 1]
        zonal = ground_zonal(bands, gibbs)
        q = _trig_q(bands, window, zonal, lobe)
        # Block table: u-rows (sky x, sun x, trig) -> (D + 1) rows of C = W + 3 columns.
        table = np.zeros((nx, depth + 1, width + 3))
        table[: dx + 1, : dy + 1, :width] = np.asarray(sky_plan.half_table).reshape(dx + 1, dy + 1, width)
        table[dx + 1 : dx + sdx + 2, : sdy + 1, width:] = sun_table.reshape(sdx + 1, sdy + 1, 3)
        table[dx + sdx + 2 :, depth, : 2 * k_half] = q.reshape(2 * k_half, 2 * bands).T
        self.table_x = np.ascontiguousarray(table.reshape(nx, -1))
        self.angle_map = _angle_map((dx, dy), (sdx, sdy), bands, depth)
        self.y_slice = slice(nx, nx + 3 * (depth + 1))
        self.gather = sky_plan.gather
        self.rotation = (self.y_slice.stop + np.asarray(sky_plan.rot_index))[:, None].repeat(3, axis=1)
        self.zonal_rows = np.array([l * (l + 1) for l in range(bands)], dtype=np.intp)
        self.ground_rows = zonal[self.zonal_rows][:, None]
        self.window_l = np.asarray(window)[sh.band_of_index(bands)][:, None]
        self.rgb_from_xyz = np.eye(3) if rgb_from_xyz is None else np.array(rgb_from_xyz, dtype=np.float64)
        self.rgb_rows: tuple[tuple[float, ...], ...] = tuple(tuple(row) for row in self.rgb_from_xyz.tolist())
        # fused: b's flat indices of the sky's c_10 (row 0) and the sun's ln XYZ (row 1), read back together;
        # X (N^2, 5) = b[gather5] * packed[rotation5] holds, per output value, the sky's three channels,
        # the sun's Ybar and the ground's factor, each rotated (eq. 4); the result is X @ V with V (5, 3) =
        # [lum I; sun RGB; ground RGB] (Python floats), so sun, ground and the luminance scale are one product.
        c = width + 3
        self.readback = np.array([*range(width - 3, width), *range(c + width, c + width + 3)], dtype=np.intp)
        source = np.asarray(sky_plan.gather)[:, 0] // 3  # m >= 0 row of every output value
        self.gather5 = np.concatenate([np.asarray(sky_plan.gather), (2 * c + 2 * source)[:, None],
                                       (2 * c + 2 * source + 1)[:, None]], axis=1).astype(np.intp)
        self.rotation5 = np.ascontiguousarray(self.rotation[:, :1].repeat(5, axis=1))
        read_only(self.table_x, self.angle_map, self.rotation, self.zonal_rows, self.ground_rows, self.window_l,
                  self.rgb_from_xyz, self.readback, self.gather5, self.rotation5)

    # ------------------------------------------------------------------ #
    def _evaluate(self, ts: float, t: float, phi: float, x: float, y: float,
                  sun: bool) -> tuple[NDArray[np.float64], NDArray[np.float64], float, tuple, tuple]:
        """Shared scalar step: packed factors, b (3 C,), the luminance scale, the sun's RGB and E_h (lux).

        b, read as (3, C): b[0] holds the sky's m >= 0 coefficients and its unfiltered c_10 over the luminance scale, b[1]
        the sun's ln XYZ, b[2] the (K_half, 2) matrix [sun's windowed Ybar(ts), ground's zonal factor]."""
        cos_ts = math.cos(ts)
        m = 1.0 / (cos_ts + _A * (_B - ts * _DEG) ** _NEG_C)  # Kasten's air mass (skysh.table.sun_table)
        xs = (m - _M0) * _SX_SCALE - 1.0
        ys = (t - _TMIN) * _SY_SCALE - 1.0
        # Clamp what rounding (and Kasten's dip near the zenith) pushes past +-1 (x >= -1 holds exactly).
        angles = (math.acos(x if x < 1.0 else 1.0), math.acos(y if -1.0 < y < 1.0 else math.copysign(1.0, y)), phi,
                  1.0, ts, math.acos(xs if -1.0 < xs < 1.0 else math.copysign(1.0, xs)),
                  math.acos(ys if -1.0 < ys < 1.0 else math.copysign(1.0, ys)))
        packed = np.cos(np.dot(self.angle_map, np.array(angles)))
        depth = self.depth
        a = np.dot(packed[: self.nx], self.table_x)
        b = np.dot(packed[self.y_slice].reshape(3, depth + 1), a.reshape(depth + 1, -1)).ravel()
        lum = luminance_scale_unchecked(ts, t)
        c0, c1, c2, lx, ly, lz = b[self.readback].tolist()  # the sky's c_10 (over lum); the sun's ln XYZ
        hf = _HF * lum
        if sun:  # Python floats: cheaper than numpy for three values
            ex, ey, ez = math.exp(lx), math.exp(ly), math.exp(lz)
            (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = self.rgb_rows
            rgb = (r00 * ex + r01 * ey + r02 * ez, r10 * ex + r11 * ey + r12 * ez, r20 * ex + r21 * ey + r22 * ez)
            e_h = (hf * c0 + cos_ts * rgb[0], hf * c1 + cos_ts * rgb[1], hf * c2 + cos_ts * rgb[2])
        else:
            rgb, e_h = (0.0, 0.0, 0.0), (hf * c0, hf * c1, hf * c2)
        return packed, b, lum, rgb, e_h

    def fused(self, ts: float, t: float, phi: float, x: float, y: float, sun: bool,
              albedo: tuple[float, float, float] | None) -> NDArray[np.float64]:
        """(N * N, 3) radiance SH of sky + sun + ground of one checked frame, file colourspace, no deringing.

        ``x``, ``y``: the sky's Chebyshev variables (the runtime computes them); ``phi`` reduced mod 2 pi.
        """
        packed, b, lum, (r, g, bl), e_h = self._evaluate(ts, t, phi, x, y, sun)
        if albedo is None:
            gr = gg = gb = 0.0
        else:
            gr, gg, gb = albedo[0] * e_h[0] * _INV_PI, albedo[1] * e_h[1] * _INV_PI, albedo[2] * e_h[2] * _INV_PI
        mix = np.array((lum, 0.0, 0.0, 0.0, lum, 0.0, 0.0, 0.0, lum, r if r > SUN_SH_CLAMP else SUN_SH_CLAMP,
                        g if g > SUN_SH_CLAMP else SUN_SH_CLAMP, bl if bl > SUN_SH_CLAMP else SUN_SH_CLAMP, gr, gg, gb))
        parts = b[self.gather5]  # (N^2, 5): sky RGB, sun's Ybar, ground's factor; m < 0 from m > 0
        parts *= packed[self.rotation5]  # eq. (4), the sky, the sun and the ground alike
        return np.dot(parts, mix.reshape(5, 3))

    def parts(self, ts: float, t: float, phi: float, x: float, y: float,
              sun: bool) -> tuple[NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.float64]]:
        """The sky (N * N, 3), the sun's windowed SH (or None) and E_h (3,), separately (for deringing
        or a colourspace conversion between them)."""
        packed, b, lum, rgb, e_h = self._evaluate(ts, t, phi, x, y, sun)
        rotation = packed[self.rotation]
        sky = b[self.gather] * (rotation * lum)  # row 0 of b
        sun_sh = None
        if sun:
            delta = np.maximum(np.array(rgb), SUN_SH_CLAMP)
            start = 2 * (self.width + 3)  # row 2 of b: the sun's Ybar, the ground's factor, per m >= 0 row
            sun_sh = np.outer(b[start : start + 2 * self.k_half : 2], delta).ravel()[self.gather] * rotation
        return sky, sun_sh, np.array(e_h)

    def sun_batch(self, ts: NDArray, phi: NDArray, rgb: NDArray) -> NDArray[np.float64]:
        """(n, N * N, 3): the windowed delta of ``rgb`` (n, 3) lux towards (ts, phi) (n,), clamped as :meth:`fused`."""
        s = np.sin(ts)
        dirs = np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(ts)], axis=-1)
        y = sh.basis_unchecked(dirs, self.bands) * self.window_l[:, 0]
        return y[:, :, None] * np.maximum(rgb, SUN_SH_CLAMP)[:, None, :]

    def add_ground(self, coeffs: NDArray[np.float64], e_h: NDArray[np.float64],
                   albedo: tuple[float, float, float]) -> NDArray[np.float64]:
        """``coeffs`` (..., N * N, 3) plus the ground lit by ``e_h`` (..., 3), in place; returns it."""
        radiance = e_h * (np.array(albedo) * _INV_PI)
        for row, factor in zip(self.zonal_rows.tolist(), self.ground_rows[:, 0].tolist()):  # N rows, not points
            if factor != 0.0:  # even l >= 2: the ground's coefficient is exactly 0
                coeffs[..., row, :] += factor * radiance
        return coeffs
