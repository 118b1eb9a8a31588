"""
Deringing: the least windowing that keeps SH lighting non-negative
==================================================================

Sloan (2017), "Deringing Spherical Harmonics" (seed 000), in the sign convention of
``docs/conventions.md`` (orthonormal real SH with the Condon-Shortley phase, the seed's own).

-   :func:`dering`: the least row of :func:`window_table` that makes the reconstructed
    irradiance (or radiance) non-negative in every colour channel (one window for all,
    section 3), decided on the exact minimum (1..3 bands) or a certified lower bound of
    it (4..7 bands), :mod:`skysh.sh.minimum`; batched, one route.
-   :data:`WINDOW_TABLE`, :func:`window_table`, :func:`sinc4_window` (eq. 6),
    :func:`delta_minimum`, :func:`linear_attenuation`: the windows and their derivation.
-   :data:`PUNCTUAL_WINDOW`, :func:`directional_light_sh`: direct lights (section 3).
-   :func:`exact_min`: re-exported from :mod:`skysh.sh.minimum` (the seed's section 2.3 bound,
    which this module no longer decides on, is kept for comparison in ``tools/studies``).

Table 1 against eq. (6), a finding: no column of Table 1 (plain sinc) nor eq. (6) alone
keeps a 3-band delta's irradiance non-negative (s1 <= sqrt(3)/2 is needed); eq. (6) with
an extra linear attenuation of 0.93905 does. :data:`WINDOW_TABLE` is eq. (6) at the seed's
sizes with that attenuation ramped in (derivations: ``docs/dering.md``).

References: Sloan, P.-P. (2017), Deringing Spherical Harmonics, SIGGRAPH Asia Technical
Briefs: sections 2.3, 2.4 (eq. 6, Table 1), 3; Ramamoorthi, R., Hanrahan, P. (2001), An
Efficient Representation for Irradiance Environment Maps (the factors A_l).
"""

from __future__ import annotations

import math
import warnings
from functools import cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import (
    as_float_array,
    check_bands,
    check_choice,
    check_coeffs,
    check_cutoff,
    check_dirs,
    check_flag,
    read_only,
)
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin
from skysh.sh.minimum import exact_min

__all__ = ["DeringWarning", "DERING_TARGETS", "DELTA_MARGIN", "CERTIFIED_MARGIN", "PUNCTUAL_WINDOW", "delta_minimum",
    "linear_attenuation", "window_table", "exact_min", "dering"]


class DeringWarning(UserWarning):
    """No row makes a function non-negative (no non-negative light has it); the last is applied."""


DERING_TARGETS: tuple[str, ...] = ("irradiance", "radiance")
"""What :func:`dering` makes non-negative: the clamped-cosine convolution, or the radiance."""
DERING_METHODS: tuple[str, ...] = ("table",)
"""Search methods of :func:`dering`: the least non-negative row of :func:`window_table`."""
MAX_DERING_BANDS: int = 7
"""Largest band count :func:`dering` accepts (49 coefficients)."""

IRRADIANCE_KERNEL: NDArray[np.float64] = sh.cosine_lobe(MAX_DERING_BANDS)
"""Clamped-cosine factors A_0 .. A_6 (pi, 2 pi/3, pi/4, 0, -pi/24, 0, pi/64)."""
RADIANCE_KERNEL: NDArray[np.float64] = np.ones(MAX_DERING_BANDS)  # the identity: deringing the radiance
IRRADIANCE_KERNEL.flags.writeable = RADIANCE_KERNEL.flags.writeable = False
KERNELS: dict[str, NDArray[np.float64]] = {"irradiance": IRRADIANCE_KERNEL, "radiance": RADIANCE_KERNEL}
"""The factor of each band in the function made non-negative, per :data:`DERING_TARGETS` entry."""

SEED_WINDOW_SIZES: tuple[float, ...] = (math.inf, 16.7, 11.3, 10.0, 9.0, 7.0, 5.6)
"""Window sizes w of the seed's Table 1 (band where the window reaches zero)."""
RADIANCE_WINDOW_SIZES: tuple[float, ...] = SEED_WINDOW_SIZES + (4.0,)
"""Sizes for ``target="radiance"``: a delta's radiance needs w = 4 (``1 - 2.5 s2`` >= 0 at its equator)."""

SEED_TABLE_1: NDArray[np.float64] = np.array([
    [1.0, 1.0, 1.0, 1.0], [1.0, 0.9941, 0.9766, 0.9478], [1.0, 0.9872, 0.9493, 0.8880], [1.0, 0.9634, 0.9355, 0.8584],
    [1.0, 0.9602, 0.9207, 0.8270], [1.0, 0.9184, 0.8710, 0.7241], [1.0, 0.8915, 0.8030, 0.5904]])
"""The seed's Table 1 as printed (rows w = inf .. 5.6, bands 0..3, 0 added): for comparison only."""
SEED_TABLE_1.flags.writeable = False

DELTA_MARGIN: float = 1e-9
"""1..3 bands: the last row keeps a delta's target >= 1e-9 of its mean (far above the minimum's
rounding allowance, 2.3e-13 of the normalised size): a lone delta never fails."""

CERTIFIED_MARGIN: float = 1e-3
"""4..7 bands (a certified minimum, with slack): the last row keeps a delta's target >= 1e-3 of
its mean, more than the certificate's slack at :data:`shmin.LEVELS` for any non-negative light
(``tools/dering_experiment.py`` prints both), so none fails; the last row changes < 0.1 %."""

PUNCTUAL_WINDOW: tuple[float, float, float] = (1.0, 0.92, 0.73)
"""The seed's hand-tuned factors for direct lights (section 3); alone, a delta so windowed dips
to -7.5 % of its mean (0.92 > sqrt(3)/2): the sky it is added to must cover that."""


def sinc4_window(cutoff: float, bands: int = 3) -> NDArray[np.float64]:
    """Per-band factors (N,) of the seed's eq. (6), ``(sin(pi l / w) / (pi l / w))^4`` for
    l = 0 .. ``bands`` - 1, w = ``cutoff`` > 0 (``inf``: none); in [0, 1], 0 for l >= w."""
    x = np.arange(check_bands(bands)) / check_cutoff(cutoff)
    return np.where(x < 1.0, np.sinc(x) ** 4, 0.0)


def _delta_power(scales: NDArray, target: str) -> NDArray:
    """Power-basis coefficients in t of a delta's windowed target ``sum_l A_l s_l (2l+1)/(4 pi) P_l(t)``."""
    n = len(scales)
    power = np.polynomial.legendre.leg2poly(KERNELS[target][:n] * scales * (2 * np.arange(n) + 1) / (4.0 * math.pi))
    return np.pad(power, (0, n - len(power)))  # (leg2poly drops trailing zeros)


def _real_roots(power: NDArray, low: float, high: float) -> NDArray:  # of a power-basis polynomial
    r = np.roots(power[::-1])
    return r[(np.abs(r.imag) < 1e-9) & (r.real >= low) & (r.real <= high)].real


def delta_minimum(scales: ArrayLike, target: str = "irradiance") -> float:
    """Exact minimum of the windowed SH projection of a unit delta light: per-band ``scales``
    (N,), 1 <= N <= 7, ``target`` ``"irradiance"`` or ``"radiance"``. Returns ``min over t in
    [-1, 1] of sum_l A_l s_l (2l+1)/(4 pi) P_l(t)`` (per sr of the delta's integral; the mean is
    ``A_0 s_0 / (4 pi)``), at t = +-1 or a real root of the derivative (the projection is zonal)."""
    check_choice(target, "target", DERING_TARGETS)
    s = as_float_array(scales, "scales")
    if s.ndim != 1 or not 1 <= s.shape[0] <= MAX_DERING_BANDS:
        raise ValueError(f"scales must have shape (N,) with 1 <= N <= {MAX_DERING_BANDS}, got {s.shape}")
    power = _delta_power(s, target)
    t = np.concatenate([[-1.0, 1.0], _real_roots(power[1:] * np.arange(1, len(s)), -1.0, 1.0)])
    return float(np.min(np.polyval(power[::-1], t)))


def linear_attenuation(cutoff: float, bands: int = 3, target: str = "irradiance") -> float:
    """The extra attenuation ``a`` in (0, 1] of the linear band that makes eq. (6) at window
    size ``cutoff`` meet the delta claim for ``bands`` in [1, 7] and ``target``: the largest a
    keeping a delta's target >= the margin times its mean (:data:`DELTA_MARGIN` for N <= 3,
    :data:`CERTIFIED_MARGIN` above), less 1e-12 relative; 1 if none is needed. 3-band
    irradiance: ``sqrt((15/8) s2 (1 - 5 s2/8)) / s1``. Any N: with the target ``B(t) + a k t``
    only t < 0 limits a, so ``a = min over t in [-1, 0) of (B(t) - floor) / (-k t)``, at t = -1
    or a root of ``t B'(t) - B(t) + floor``."""
    bands = check_bands(bands, high=MAX_DERING_BANDS)
    check_choice(target, "target", DERING_TARGETS)
    base = sinc4_window(cutoff, bands)
    floor = (DELTA_MARGIN if bands <= 3 else CERTIFIED_MARGIN) * KERNELS[target][0] / (4.0 * math.pi)
    if bands < 2 or delta_minimum(base, target) >= floor:
        return 1.0
    k = KERNELS[target][1] * base[1] * 3.0 / (4.0 * math.pi)  # the linear band is k t
    rest = _delta_power(base, target)
    rest[1] -= k
    rest[0] -= floor
    t = np.concatenate([[-1.0], _real_roots(rest * (np.arange(bands) - 1.0), -1.0, -1e-300)])
    a = min(1.0, float(np.min(np.polyval(rest[::-1], t) / (-k * t)))) * (1.0 - 1e-12)
    if not (a > 0.0 and delta_minimum(np.concatenate([base[:1], base[1:2] * a, base[2:]]), target) >= floor):
        raise ValueError(f"no linear attenuation makes sinc^4 at cutoff={cutoff} non-negative for {target}")
    return a


class _Rows(NamedTuple):
    """One (bands, target) setting of the search, built once: the table (R, N), its factor of
    every coefficient (R, K, 1) and times the target's kernel (R, K), the maps of normalised
    coefficients to (c, g) (K, 4) and Q (K, 9) of the target, and the rows' s1, s1^2, s2 columns (R, 1) (zero past
    the bands)."""

    table: NDArray
    per_coeff: NDArray
    per_target: NDArray
    form_cg: NDArray
    form_q: NDArray
    s1: NDArray
    s1sq: NDArray
    s2: NDArray


@cache
def _rows(bands: int, target: str) -> _Rows:
    """The search's setting of ``bands`` and ``target``, built once (:func:`window_table` reads its table)."""
    sizes = SEED_WINDOW_SIZES if target == "irradiance" else RADIANCE_WINDOW_SIZES
    a_min = linear_attenuation(sizes[-1], bands, target)
    rows = np.array([sinc4_window(w, max(bands, 3)) for w in sizes])  # band 2 drives the ramp
    rows[:, 1] *= 1.0 - (1.0 - a_min) * (1.0 - rows[:, 2]) / (1.0 - rows[-1, 2])
    l_of = sh.band_of_index(bands)
    pad = np.where(np.arange(3) < bands, rows[:, :3], 0.0)
    kernel = KERNELS[target][l_of]
    quadratic = bands <= 3 or (bands == 4 and target == "irradiance")  # A_3 = 0: a 3-band target
    k = min(bands, 3) ** 2
    form = kernel[:k, None] * shmin.FORM_MAP[:k] if quadratic else np.zeros((0, 13))
    out = _Rows(np.ascontiguousarray(rows[:, :bands]), rows[:, l_of, None], rows[:, l_of] * kernel,
                np.ascontiguousarray(form[:, :4]), np.ascontiguousarray(form[:, 4:]), pad[:, 1:2], pad[:, 1:2] ** 2,
                pad[:, 2:3])
    read_only(*out)
    return out


def window_table(bands: int = 3, target: str = "irradiance") -> NDArray[np.float64]:
    """The (R, N) per-band scale factors searched by :func:`dering`, N = ``bands`` in [1, 7],
    read-only and cached. Row 0 is all ones, ``row[0] == 1``, every factor decreases down the
    rows, the last keeps any non-negative light's target at least the margin times its mean.
    Row r is eq. (6) at ``SEED_WINDOW_SIZES[r]`` (radiance: ``RADIANCE_WINDOW_SIZES``) with band
    1 times ``1 - (1 - a) rho``, ``a`` the last row's :func:`linear_attenuation`, ``rho = (1 -
    s2(w)) / (1 - s2(w_last))``."""
    return _rows(check_bands(bands, high=MAX_DERING_BANDS), check_choice(target, "target", DERING_TARGETS)).table


LINEAR_ATTENUATION: float = linear_attenuation(SEED_WINDOW_SIZES[-1], 3, "irradiance")
"""Extra attenuation of the linear band in the last row of :data:`WINDOW_TABLE` (0.93905)."""

WINDOW_TABLE: NDArray[np.float64] = window_table(3, "irradiance")
"""(7, 3) factors for 3-band irradiance: row 0 none, the last eq. (6) at w = 5.6 with band 1
times :data:`LINEAR_ATTENUATION`."""


def _first(values: NDArray, floor: float) -> NDArray:
    """The least row r with values[:, :, r] >= floor in every channel, per function; R if none."""
    ok = np.minimum.reduce(values, 1) >= floor
    return np.where(ok.any(-1), np.argmax(ok, -1), ok.shape[-1])


def _least_row3(t: NDArray, rows: _Rows) -> NDArray:
    """:func:`_least_row` for 1..3 bands, exact: every row's dual and a point of it from one
    eigendecomposition (a row scales g by s1 and Q by s2). Per function, what cannot change
    the answer is skipped: row 0 certified by its dual at x = |g|/2; after one Newton step, a
    certified row whose earlier rows all take a negative value at their dual's point. The
    rest take the remaining steps (the cluster bounds, then :data:`shmin.NEWTON_STEPS`)."""
    cg = t @ rows.form_cg
    lam, v = np.linalg.eigh((t @ rows.form_q).reshape(t.shape[:-1] + (3, 3)))
    gam = (cg[..., None, 1:] @ v)[..., 0, :]
    a, d, c0 = 0.25 * gam * gam, lam - lam[..., :1], cg[..., 0]
    x = np.maximum(np.sqrt(a @ shmin.ONES), shmin.FLOOR)
    ok = np.minimum.reduce(shmin.dual(c0, lam, d, a, x), 1) >= shmin.ALLOWANCE
    if ok.all():
        return np.zeros(len(t), dtype=np.intp)
    todo = np.flatnonzero(~ok) if ok.any() else slice(None)
    lam, d = lam[todo, :, None] * rows.s2, d[todo, :, None] * rows.s2
    a, gam = a[todo, :, None] * rows.s1sq, gam[todo, :, None] * rows.s1
    c0 = c0[todo, :, None]
    x = shmin.newton(d, a, shmin.prefix_bound(d, a), 1)
    w = 1.0 / (d + x[..., None])
    first = _first(c0 + lam[..., 0] - x - (a * w) @ shmin.ONES, shmin.ALLOWANCE)
    y = gam * w  # -2 times the dual's point: the value at y / |y|
    n2 = (y * y) @ shmin.ONES + shmin.TINY
    refuted = np.minimum.reduce(c0 - (gam * y) @ shmin.ONES / np.sqrt(n2) + (lam * y * y) @ shmin.ONES / n2, 1) < 0.0
    lead = np.where(refuted.all(-1), refuted.shape[-1], np.argmin(refuted, -1))  # rows refuted before the first not
    left = np.flatnonzero(lead < first)
    if left.size:
        d, a, lam, c0, x = d[left], a[left], lam[left], c0[left], x[left]
        x = shmin.newton(d, a, shmin.cluster_bounds(d, a, x), shmin.NEWTON_STEPS)
        first[left] = _first(shmin.dual(c0, lam, d, a, x), shmin.ALLOWANCE)
    if isinstance(todo, slice):
        return first
    out = np.zeros(len(t), dtype=np.intp)
    out[todo] = first
    return out


def _least_row(t: NDArray, rows: _Rows) -> NDArray:
    """Per function of t (n, C, K) (normalised SH), the least row certified non-negative in
    every channel, R if none. 4..7 bands, row by row for the functions still undecided:
    level 0 of the certificate, then, where no channel was refuted by a sampled negative
    value, the full certificate for the channels left undecided."""
    n, n_ch, k = t.shape
    if len(rows.form_cg):
        return _least_row3(t[..., : len(rows.form_cg)], rows)
    first = np.full(n, len(rows.table))
    todo = np.arange(n)
    for row, factors in enumerate(rows.per_target):
        flat = (t[todo] * factors).reshape(-1, k)
        vals = flat @ shmin.level0_basis(math.isqrt(k))
        best = vals.min(-1)
        k2, allow = shmin.curvature(flat)
        low = best - 0.5 * k2 * shmin.COVER_RADIUS**2 - allow
        refuted = np.logical_or.reduce((best < 0.0).reshape(-1, n_ch), 1)
        idx = np.flatnonzero((low < 0.0) & np.repeat(~refuted, n_ch))
        if idx.size:
            low[idx] = shmin.certified_min(flat[idx], 0.0, vals=vals[idx])[0]
        ok = np.logical_and.reduce((low >= 0.0).reshape(-1, n_ch), 1)
        first[todo[ok]] = row
        todo = todo[~ok]
        if todo.size == 0:
            break
    return first


SUBNORMAL_EXPONENT: int = int(np.finfo(np.float64).minexp)
"""-1022: a channel whose largest |coefficient| has a binary exponent ``e <= SUBNORMAL_EXPONENT``
(:func:`numpy.frexp`, ``max |c| < 2^-1022``) has subnormal windowed coefficients that round by
more than eps of its size: :func:`dering` decides such functions on the rounded output."""


def _least_row_rounded(flat: NDArray, rows: _Rows) -> NDArray:
    """:func:`_least_row` for functions (n, K, C) with a subnormal channel, decided on what
    :func:`dering` returns: row by row, the windowed coefficients ``flat * per_coeff[r]`` as
    rounded (a subnormal product keeps fewer digits: deciding on the exact product left
    returned irradiance at -1e-5 of its size), normalised (exact), on row 0's exact test."""
    row0 = _Rows(rows.table[:1], rows.per_coeff[:1], rows.per_target[:1], rows.form_cg, rows.form_q,
                 rows.s1[:1], rows.s1sq[:1], rows.s2[:1])
    first = np.full(len(flat), len(rows.table))
    todo = np.arange(len(flat))
    for row, factors in enumerate(rows.per_coeff):
        t, _, zero = shmin.normalised(np.swapaxes(flat[todo] * factors, -1, -2))
        t[..., 0] += zero
        ok = _least_row(t, row0) == 0
        first[todo[ok]] = row
        todo = todo[~ok]
        if todo.size == 0:
            break
    return first


def dering(
    coeffs: ArrayLike, target: str = "irradiance", method: str = "table", *, return_failed: bool = False
) -> tuple[NDArray[np.float64], ...]:
    """
    Window SH lighting as little as the table allows so that it is non-negative (section 2.4).

    Parameters
    ----------
    coeffs
        Radiance SH (K, C), (..., K, C) or (K,), K = N^2, N in [1, 7], any unit and magnitude.
    target
        ``"irradiance"``: ``E(n) = integral L(w) max(0, n.w) dw`` must be non-negative
        everywhere; ``"radiance"``: the radiance itself.
    method
        ``"table"``, the only search: the least row of :func:`window_table`.
    return_failed
        Also return a boolean array (...,): True where no row is non-negative.

    Returns
    -------
    coeffs_out, scales[, failed]
        ``coeffs_out``: same shape, band l times ``scales[..., l]``; ``scales``: (..., N), the
        row applied, the same for every channel; never NaN or inf.

    Warns
    -----
    DeringWarning
        When some function fails (no non-negative light does): the last row is applied.

    Notes
    -----
    The row is the least whose target's minimum is >= 0 in every channel: 1..3 bands on
    the exact minimum (:func:`exact_min`, less its 2.3e-13 rounding allowance), so exactly
    the row a brute-force scan finds; 4..7 bands on the certified bound, so never
    negative, and one row more than the least only when a minimum lies within the
    certificate's slack of zero. The last row certifies every non-negative light, so
    ``failed`` marks coefficients of none. Each channel is first divided by a power of two
    (exact: decisions are scale-invariant). A function with a channel below 2^-1022 in
    every coefficient (:data:`SUBNORMAL_EXPONENT`) is decided on its windowed coefficients
    as returned (subnormal products round by more than eps of the channel), so the
    returned target is non-negative at any magnitude; such a non-negative light may then
    fail (flagged). Vectorised; one input is a batch of one.
    Costs: ``benchmarks/bench_dering.py``.

    Examples
    --------
    >>> light = sh.basis([0.0, 0.6, 0.8], 3)[:, None] * np.array([1.0, 2.0, 3.0])  # one delta
    >>> out, scales = dering(light)
    >>> bool(scales[1] < 1.0), bool(exact_min(sh.irradiance(out)).min() >= 0.0)
    (True, True)
    """
    check_choice(target, "target", DERING_TARGETS)
    check_choice(method, "method", DERING_METHODS)
    return_failed = check_flag(return_failed, "return_failed")
    c, vector, bands = check_coeffs(coeffs, high=MAX_DERING_BANDS)
    flat = c.reshape((-1,) + c.shape[-2:])
    rows = _rows(bands, target)
    t, e, zero = shmin.normalised(np.swapaxes(flat, -1, -2))
    t[..., 0] += zero  # a zero channel's minimum is exactly 0: it passes, as the constant 1 does
    first = _least_row(t, rows)
    if e.min(initial=0) <= SUBNORMAL_EXPONENT:  # a channel of subnormal size (a zero channel has e = 0)
        tiny = np.flatnonzero(np.logical_or.reduce(e <= SUBNORMAL_EXPONENT, -1))
        first[tiny] = _least_row_rounded(flat[tiny], rows)
    failed = first == len(rows.table)
    if failed.any():
        warnings.warn(f"dering: {int(failed.sum())} of {len(flat)} functions stay negative ({target}) even at the "
                      "most aggressive window: they are not the projection of any non-negative light; the last "
                      "window was applied to them.", DeringWarning, stacklevel=2)
        first = np.minimum(first, len(rows.table) - 1)
    out = (flat * rows.per_coeff[first]).reshape(c.shape)
    scales = rows.table[first].reshape(c.shape[:-2] + (bands,))
    out = out[:, 0] if vector else out
    return (out, scales, failed.reshape(c.shape[:-2])) if return_failed else (out, scales)


def directional_light_sh(
    direction: ArrayLike, colour: ArrayLike, bands: int = 3, window: ArrayLike = PUNCTUAL_WINDOW
) -> NDArray[np.float64]:
    """Windowed SH radiance (..., N * N, C) of a directional light, ``window[l] Y_i(direction)
    colour``, to add to deringed sky SH (the seed's recipe: ``dering(sky)[0] +
    directional_light_sh(sun_dir, sun_illuminance)``). ``direction``: unit vector(s) (..., 3),
    Z up; ``colour`` (C,) or (..., C): the light's integral per channel (radiance times solid
    angle, lux at normal incidence); ``bands``: N in [1, min(64, len(window))] (1..3 with the
    default window); ``window``: at least N factors, default :data:`PUNCTUAL_WINDOW`
    (``window_table(bands)[-1]`` keeps the light's irradiance >= 0)."""
    bands = check_bands(bands, high=sh.MAX_BANDS)
    d = check_dirs(direction, "direction")
    col = as_float_array(colour, "colour")
    w = as_float_array(window, "window")
    if w.ndim != 1 or w.shape[0] == 0:
        raise ValueError(f"window must have shape (M,), M >= bands = {bands} (one factor per band), got {w.shape}")
    if w.shape[0] < bands:
        default = " (the default PUNCTUAL_WINDOW)" if window is PUNCTUAL_WINDOW else ""
        raise ValueError(f"bands must lie in [1, {w.shape[0]}]: window{default} has {w.shape[0]} factor"
                         f"{'s' if w.shape[0] > 1 else ''} (one per band; give a longer window for more bands), got {bands}")
    if col.ndim == 0:
        raise ValueError(f"colour must have shape (C,) or (..., C), got {col.shape}")
    y = sh.basis(d, bands) * w[sh.band_of_index(bands)]
    return y[..., :, None] * col[..., None, :]
