"""
Deringing: the least windowing that keeps SH lighting non-negative
==================================================================

Sloan (2017), "Deringing Spherical Harmonics" (seed 000), in the sign convention of
``docs/conventions.md`` (orthonormal real SH with the Condon-Shortley phase, the seed's own).

-   :func:`dering`: the least window that makes the reconstructed irradiance (or radiance)
    non-negative in every colour channel (one window for all, section 3): the seed's
    search, a position along :func:`window_table` with linear interpolation between its
    rows (:func:`least_window`), decided on the exact minimum (1..3 bands, 4-band irradiance:
    to :data:`WINDOW_TOLERANCE` of a row) or a certified lower bound of it (5..7 bands, and
    4-band radiance: to :data:`CERTIFIED_TOLERANCE`), :mod:`skysh.sh.minimum`; or, with
    ``method="table"``, the least whole row. Batched.
-   :func:`least_window`, :func:`window_at`, :func:`exact_target`, :func:`tolerance`: the position
    searched, its factors, and which minimum decides at what tolerance.
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

__all__ = ["DeringWarning", "DERING_TARGETS", "DERING_METHODS", "DELTA_MARGIN", "CERTIFIED_MARGIN", "PUNCTUAL_WINDOW",
    "WINDOW_TOLERANCE", "CERTIFIED_TOLERANCE", "exact_target", "tolerance", "delta_minimum", "linear_attenuation",
    "window_table", "window_at", "least_window", "exact_min", "dering"]


class DeringWarning(UserWarning):
    """No row makes a function non-negative (no non-negative light has it); the last is applied."""


DERING_TARGETS: tuple[str, ...] = ("irradiance", "radiance")
"""What :func:`dering` makes non-negative: the clamped-cosine convolution, or the radiance."""
DERING_METHODS: tuple[str, ...] = ("window", "table")
"""Search methods of :func:`dering`: ``"window"`` (the default) the least position along :func:`window_table`
with linear interpolation between rows (the seed's section 3), ``"table"`` the least whole row."""

CERTIFIED_TOLERANCE: float = 2.0**-5
"""The same for certified targets (4..7 bands but 4-band irradiance): 1/32 of a row step."""

WINDOW_TOLERANCE: float = 2.0**-10
"""Tolerance of :func:`least_window`'s position, in row steps (1/1024 < 1e-3, a dyadic number: the
bisection's points are exact): the position returned passes and one at most this much less does not."""
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


def exact_target(bands: int, target: str = "irradiance") -> bool:
    """Whether the target of ``bands`` is a 3-band function, decided on the exact minimum: 1..3 bands, and
    4-band irradiance (A_3 = 0); else the certificate decides."""
    return bands <= 3 or (bands == 4 and target == "irradiance")


def tolerance(bands: int, target: str = "irradiance") -> float:
    """The window position's tolerance for ``bands`` and ``target``: :data:`WINDOW_TOLERANCE` where the exact
    minimum decides (:func:`exact_target`), :data:`CERTIFIED_TOLERANCE` where the certificate does."""
    return WINDOW_TOLERANCE if exact_target(bands, target) else CERTIFIED_TOLERANCE


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
    quadratic = exact_target(bands, target)
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


class _Spectrum(NamedTuple):
    """A 1..3-band target per function and channel, row 0: c0 (n, C), the eigenvalues ``lam`` of Q
    (n, C, 3) ascending, their gaps ``d`` to the first, ``gam = V^T g`` and the weights ``a = gam^2 / 4``.
    A window (1, s1, s2) scales g by s1 and Q by s2: every window shares it."""

    c0: NDArray
    lam: NDArray
    d: NDArray
    a: NDArray
    gam: NDArray

    def take(self, i: NDArray) -> _Spectrum:
        """The functions i (an index array) of it."""
        return _Spectrum(*(x[i] for x in self))


def _spectrum(t: NDArray, rows: _Rows) -> _Spectrum:
    """The :class:`_Spectrum` of normalised SH t (n, C, K), K the target's first 1..9 coefficients."""
    cg = t @ rows.form_cg
    lam, v = np.linalg.eigh((t @ rows.form_q).reshape(t.shape[:-1] + (3, 3)))
    gam = (cg[..., None, 1:] @ v)[..., 0, :]
    return _Spectrum(cg[..., 0], lam, lam - lam[..., :1], 0.25 * gam * gam, gam)


def _minima3(sp: _Spectrum, s1: NDArray, s2: NDArray) -> tuple[NDArray, NDArray]:
    """Per function and channel (n, C), the certified minimum less the rounding allowance with the window
    (1, s1, s2) (n,): the dual after the proven start, one Newton step, the cluster bounds and the
    remaining steps; the window passes where every channel's is >= 0. Also the dual's multiplier x."""
    s1b, s2b = s1[:, None, None], s2[:, None, None]
    lam, d, a = sp.lam * s2b, sp.d * s2b, sp.a * (s1b * s1b)
    x = shmin.newton(d, a, shmin.cluster_bounds(d, a, shmin.newton(d, a, shmin.prefix_bound(d, a), 1)),
                     shmin.NEWTON_STEPS)
    return shmin.dual(sp.c0, lam, d, a, x) - shmin.ALLOWANCE, x


def _rates3(sp: _Spectrum, s1: NDArray, s2: NDArray, x: NDArray, ds1: NDArray, ds2: NDArray) -> NDArray:
    """Each minimum's rate (n, C) as the factors move by ``ds1``, ``ds2`` (n,), from :func:`_minima3`'s x: the
    envelope theorem, the rate of ``s1 g.w + s2 w^T Q w`` at the dual's minimiser w."""
    y = -0.5 * s1[:, None, None] * sp.gam / (sp.d * s2[:, None, None] + x[..., None])
    y[..., 0] += np.sqrt(np.maximum(1.0 - (y * y) @ shmin.ONES, 0.0))  # the hard case's free component
    return ds1[:, None] * ((sp.gam * y) @ shmin.ONES) + ds2[:, None] * ((sp.lam * y * y) @ shmin.ONES)


def _passes3(sp: _Spectrum, s1: NDArray, s2: NDArray) -> NDArray:
    """Per function (n,), whether the window (1, s1, s2) passes in every channel (:func:`_minima3`)."""
    return np.logical_and.reduce(_minima3(sp, s1, s2)[0] >= 0.0, 1)


def _least_row3(sp: _Spectrum, rows: _Rows) -> NDArray:
    """:func:`_least_row` for 3-band targets (1..3 bands, 4-band irradiance), exact: every row's dual and a point of it from one
    eigendecomposition. Per function, what cannot change the answer is skipped: row 0 certified
    by its dual at x = |g|/2; after one Newton step, a certified row whose earlier rows all take
    a negative value at their dual's point. The rest take the remaining steps (the cluster
    bounds, then :data:`shmin.NEWTON_STEPS`)."""
    x = np.maximum(np.sqrt(sp.a @ shmin.ONES), shmin.FLOOR)
    ok = np.minimum.reduce(shmin.dual(sp.c0, sp.lam, sp.d, sp.a, x), 1) >= shmin.ALLOWANCE
    n = len(ok)
    if ok.all():
        return np.zeros(n, dtype=np.intp)
    todo = np.flatnonzero(~ok) if ok.any() else slice(None)
    lam, d = sp.lam[todo, :, None] * rows.s2, sp.d[todo, :, None] * rows.s2
    a, gam = sp.a[todo, :, None] * rows.s1sq, sp.gam[todo, :, None] * rows.s1
    c0 = sp.c0[todo, :, None]
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
    out = np.zeros(n, dtype=np.intp)
    out[todo] = first
    return out


def _passes(flat: NDArray, vals: NDArray, n_ch: int) -> NDArray:
    """4..7 bands: per function, whether the certificate puts every channel of the windowed
    normalised target flat (n * C, K) (level-0 values ``vals`` (n * C, M)) at >= 0: level 0,
    then, where no channel was refuted by a sampled negative value, the full certificate for
    the channels left undecided."""
    best = vals.min(-1)
    k2, allow = shmin.curvature(flat)
    low = best - 0.5 * k2 * shmin.COVER_RADIUS**2 - allow
    refuted = np.logical_or.reduce((best < 0.0).reshape(-1, n_ch), 1)
    idx = np.flatnonzero((low < 0.0) & np.repeat(~refuted, n_ch))
    if idx.size:
        low[idx] = shmin.certified_min(flat[idx], 0.0, vals=vals[idx])[0]
    return np.logical_and.reduce((low >= 0.0).reshape(-1, n_ch), 1)


def _least_row(t: NDArray, rows: _Rows) -> NDArray:
    """Per function of t (n, C, K) (normalised SH), the least row certified non-negative in
    every channel, R if none: exact (1..3 bands, :func:`_least_row3`), or row by row for the
    functions still undecided (:func:`_passes`)."""
    n, n_ch, k = t.shape
    if len(rows.form_cg):
        return _least_row3(_spectrum(t[..., : len(rows.form_cg)], rows), rows)
    first = np.full(n, len(rows.table))
    todo = np.arange(n)
    for row, factors in enumerate(rows.per_target):
        flat = (t[todo] * factors).reshape(-1, k)
        ok = _passes(flat, flat @ shmin.level0_basis(math.isqrt(k)), n_ch)
        first[todo[ok]] = row
        todo = todo[~ok]
        if todo.size == 0:
            break
    return first


TANGENT_STEPS: int = 3
"""Tangent steps of the exact fraction search before it falls back to bisection: from the left the
tangents converge to each channel's crossing as Newton's method does (quadratically), so a few suffice;
more only delay the fallback (``tools/dering_experiment.py`` times the search against whole rows)."""


def _bisect(lo: NDArray, guess: NDArray, passes, gallop: bool, tolerance: float = WINDOW_TOLERANCE) -> NDArray:
    """The least passing multiple of ``tolerance`` in (lo, 1], per function: ``passes(i, f)`` decides
    functions i at fractions f; 1 passes, ``lo`` (n,) (a multiple) does not. The first candidate is
    ``guess`` (n,) rounded up to a multiple; then, with ``gallop``, steps of 1, 2, 4, .. multiples away
    from it (down from a passing guess, up from a failing one) until the answer is bracketed, and
    bisection on multiples. Where the passing fractions form an interval ending at 1 (exactly so for
    the exact minimum, concave in f), any bracketing order returns the same multiple (halvings of
    [0, 1] do); the certificate's cell budget can break that, so the order is part of the definition."""
    q = 1.0 / tolerance
    lo, hi = lo.copy(), np.ones_like(lo)
    step = np.ones_like(lo)  # in multiples
    cand = np.clip(np.ceil(guess * q), lo * q + 1.0, q) / q
    go, down = np.full(len(lo), gallop), np.zeros(len(lo), bool)
    fresh = np.ones(len(lo), bool)
    active = np.flatnonzero(hi - lo > tolerance)
    cand = cand[active]
    while active.size:
        ok = passes(active, cand)
        hi[active[ok]], lo[active[~ok]] = cand[ok], cand[~ok]
        down[active[fresh[active]]] = ok[fresh[active]]
        go[active] &= fresh[active] | (ok == down[active])  # galloping on while the side stays the same
        fresh[active] = False
        active = active[hi[active] - lo[active] > tolerance]
        g, st = go[active], step[active]
        nxt = np.where(down[active], hi[active] - st / q, lo[active] + st / q)
        g &= (nxt > lo[active]) & (nxt < hi[active])
        go[active], step[active] = g, np.where(g, 2.0 * st, st)
        cand = np.where(g, nxt, np.floor(0.5 * (lo[active] + hi[active]) * q) / q)
    return hi


def _fraction3(sp: _Spectrum, rows: _Rows, row: NDArray) -> NDArray:
    """:func:`_fraction` for exact targets. Each channel's minimum m_c(f) (less the allowance) is concave,
    and the answer is the largest of the channels' crossings. Per channel, the tangent at a failing point
    crosses zero at or below its crossing (the tangent lies above m_c), the chord to a passing point at
    or above it; the largest over channels of each bounds the answer. When both bounds fall in one step
    of :data:`WINDOW_TOLERANCE`, its upper end is the answer; when the tangents have converged (a step
    below it; a passing point's chord can be poor, where the minimum peaks near the row),
    the step above the lower bound is. Either is checked by one evaluation; elsewhere (a failed check, or
    neither after :data:`TANGENT_STEPS` tangents) :func:`_bisect`."""
    q, n, n_ch = 1.0 / WINDOW_TOLERANCE, len(row), sp.c0.shape[1]
    s1, s2 = rows.s1[row - 1, 0], rows.s2[row - 1, 0]
    ds1, ds2 = rows.s1[row, 0] - s1, rows.s2[row, 0] - s2
    both, s1s, s2s = sp.take(np.tile(np.arange(n), 2)), np.concatenate([s1, s1 + ds1]), np.concatenate([s2, s2 + ds2])
    m, x = _minima3(both, s1s, s2s)  # both rows at once
    m_lo, k_lo, m_hi = m[:n], _rates3(both, s1s, s2s, x, np.tile(ds1, 2), np.tile(ds2, 2))[:n], m[n:]
    lo, hi, answer = np.zeros((n, n_ch)), np.ones((n, n_ch)), np.ones(n)
    todo = np.arange(n)
    for step in range(TANGENT_STEPS + 1):
        fail = m_lo[todo] < 0.0  # a channel passing at its lo point has crossed before it
        tangent = lo[todo] - np.where(fail, m_lo[todo], 0.0) / np.maximum(k_lo[todo], shmin.TINY)
        chord = lo[todo] + (hi[todo] - lo[todo]) * np.where(fail, m_lo[todo], 0.0) / np.minimum(
            m_lo[todo] - m_hi[todo], -shmin.TINY)
        upper = np.maximum.reduce(chord, 1)
        lower = np.minimum(np.maximum.reduce(tangent, 1), upper)
        answer[todo] = np.minimum(answer[todo], np.ceil(upper * q) / q)
        closed = np.ceil(lower * q) >= np.ceil(upper * q)
        settled = ~closed & (lower - np.maximum.reduce(lo[todo], 1) < WINDOW_TOLERANCE)
        answer[todo[settled]] = np.ceil(lower[settled] * q) / q  # the tangent has converged: the step above it
        keep = ~closed & ~settled
        todo, f = todo[keep], lower[keep]
        if todo.size == 0 or step == TANGENT_STEPS:
            break
        sub, s1f, s2f = sp.take(todo), s1[todo] + f * ds1[todo], s2[todo] + f * ds2[todo]
        m, x = _minima3(sub, s1f, s2f)
        k = _rates3(sub, s1f, s2f, x, ds1[todo], ds2[todo])
        f2 = np.broadcast_to(f[:, None], m.shape)
        fail, tighter = m < 0.0, (m >= 0.0) & (f2 < hi[todo])
        lo[todo] = np.where(fail, f2, lo[todo])
        m_lo[todo], k_lo[todo] = np.where(fail, m, m_lo[todo]), np.where(fail, k, k_lo[todo])
        hi[todo], m_hi[todo] = np.where(tighter, f2, hi[todo]), np.where(tighter, m, m_hi[todo])
    ok = _passes3(sp, s1 + answer * ds1, s2 + answer * ds2)
    ok[todo] = False  # no bracket yet
    redo = np.flatnonzero(~ok)
    if redo.size:
        sub, start = sp.take(redo), np.maximum.reduce(lo[redo], 1)  # the latest point known to fail
        answer[redo] = _bisect(np.floor(start * q) / q, start, lambda i, f: _passes3(
            sub.take(i), s1[redo][i] + f * ds1[redo][i], s2[redo][i] + f * ds2[redo][i]), False)
    return answer


def _fraction(t: NDArray, rows: _Rows, row: NDArray) -> NDArray:
    """Per function of t (n, C, K) whose least passing row ``row`` (n,) is in [1, R - 1], the least
    passing fraction f of the step from row - 1 (the factors ``table[row - 1] + f (table[row] -
    table[row - 1])``, linear per band), by :func:`_bisect`. At every direction the target is linear
    in f, so its minimum m(f) is concave. Exact targets: :func:`_fraction3`. Certified ones, to
    :data:`CERTIFIED_TOLERANCE`, start from the least f at which every level-0 value reaches the
    certificate's final slack (each side linear in f; below it the certificate cannot pass) and step
    up from it."""
    n_ch, k = t.shape[1:]
    lo_rows, n = row - 1, len(t)
    basis = shmin.level0_basis(math.isqrt(k))
    p_lo = rows.per_target[lo_rows][:, None, :]
    dp = rows.per_target[row][:, None, :] - p_lo
    flat_lo, flat_hi = (t * p_lo).reshape(-1, k), (t * (p_lo + dp)).reshape(-1, k)
    v_lo, v_hi = flat_lo @ basis, flat_hi @ basis
    final = (shmin.COVER_RADIUS / shmin.SPLIT**shmin.LEVELS) ** 2
    (k_lo, a_lo), (k_hi, a_hi) = shmin.curvature(flat_lo), shmin.curvature(flat_hi)
    g_lo, g_hi = v_lo - (k_lo * final + a_lo)[:, None], v_hi - (k_hi * final + a_hi)[:, None]
    neg = g_lo < 0.0
    ratio = np.where(neg, g_lo / np.where(neg, np.minimum(g_lo - g_hi, -shmin.TINY), -1.0), 0.0)
    start = np.clip(np.maximum.reduce(ratio.reshape(n, -1), 1), 0.0, 1.0)
    dv = v_hi - v_lo

    def passes(i: NDArray, f: NDArray) -> NDArray:
        sel = (i[:, None] * n_ch + np.arange(n_ch)).ravel()
        flat = (t[i] * (p_lo[i] + f[:, None, None] * dp[i])).reshape(-1, k)
        return _passes(flat, v_lo[sel] + np.repeat(f, n_ch)[:, None] * dv[sel], n_ch)

    start = np.floor(start / CERTIFIED_TOLERANCE) * CERTIFIED_TOLERANCE  # a multiple at or below the bound
    return _bisect(start, start + CERTIFIED_TOLERANCE, passes, True, CERTIFIED_TOLERANCE)


SEARCH_CHUNK: tuple[int, int] = (16, 4096)
"""Functions decided at a time: (certified targets, exact targets). The certificate's refinement of a sky
near zero holds about 0.85 MB per function, the exact search about 4 kB: each chunk stays near 16 MB (a
batch of 10^5 7-band skies held 84 GB at once and was killed)."""

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


def _search(c: NDArray, target: str, method: str) -> tuple[NDArray, NDArray, NDArray, _Rows]:
    """Checked SH c (..., K, C): the flat functions (n, K, C), each one's window position (n,) (the
    least passing; R - 1 where none passes) and failure flag (n,), and the setting's rows; decided
    :data:`SEARCH_CHUNK` functions at a time (the certificate's refinement holds up to ~1 MB each)."""
    flat = c.reshape((-1,) + c.shape[-2:])
    rows = _rows(math.isqrt(c.shape[-2]), target)
    step = SEARCH_CHUNK[len(rows.form_cg) > 0]
    position, failed = np.empty(len(flat)), np.empty(len(flat), bool)
    for start in range(0, len(flat), step):
        part = slice(start, start + step)
        position[part], failed[part] = _search_chunk(flat[part], rows, method)
    return flat, position, failed, rows


def _search_chunk(flat: NDArray, rows: _Rows, method: str) -> tuple[NDArray, NDArray]:
    """:func:`_search` of functions (n, K, C): their positions (n,) and failure flags (n,)."""
    t, e, zero = shmin.normalised(np.swapaxes(flat, -1, -2))
    t[..., 0] += zero  # a zero channel's minimum is exactly 0: it passes, as the constant 1 does
    k = len(rows.form_cg)
    sp = _spectrum(t[..., :k], rows) if k else None  # quadratic targets: one eigendecomposition for every window
    first = _least_row3(sp, rows) if sp is not None else _least_row(t, rows)
    tiny = np.zeros(len(flat), bool)
    if e.min(initial=0) <= SUBNORMAL_EXPONENT:  # a channel of subnormal size (a zero channel has e = 0)
        tiny = np.logical_or.reduce(e <= SUBNORMAL_EXPONENT, -1)
        first[tiny] = _least_row_rounded(flat[tiny], rows)
    failed = first == len(rows.table)
    position = np.minimum(first, len(rows.table) - 1).astype(np.float64)
    if method == "window" and first.any():  # the fraction of the step below a passing row, not for subnormal ones
        idx = np.flatnonzero((first > 0) & ~failed & ~tiny)
        if idx.size:
            position[idx] += (_fraction3(sp.take(idx), rows, first[idx]) if sp is not None
                              else _fraction(t[idx], rows, first[idx])) - 1.0
    return position, failed


def _factors(rows: _Rows, position: NDArray) -> NDArray:
    """The per-band factors (n, N) at window positions (n,): ``table[i] + f (table[j] - table[i])``, i =
    floor(position), j = min(i + 1, R - 1), f = position - i (a whole position is its row exactly)."""
    last = len(rows.table) - 1
    i = np.minimum(position.astype(np.intp), last)
    lo = rows.table[i]
    return lo + (position - i)[:, None] * (rows.table[np.minimum(i + 1, last)] - lo)


def window_at(position: ArrayLike, bands: int = 3, target: str = "irradiance") -> NDArray[np.float64]:
    """The per-band factors (..., N) of :func:`window_table` at fractional ``position`` (...) in [0, R - 1]
    (R its rows): row i where the position is i, linear per band between neighbouring rows."""
    rows = _rows(check_bands(bands, high=MAX_DERING_BANDS), check_choice(target, "target", DERING_TARGETS))
    p = as_float_array(position, "position")
    high = len(rows.table) - 1
    if not np.all((p >= 0.0) & (p <= high)):
        raise ValueError(f"position must lie in [0, {high}] (the rows of window_table({bands}, {target!r})), got {p}")
    return _factors(rows, p.ravel()).reshape(p.shape + (rows.table.shape[1],))


def least_window(coeffs: ArrayLike, target: str = "irradiance", method: str = "window") -> tuple[NDArray, NDArray]:
    """The window :func:`dering` applies, as a position along :func:`window_table` (...) in [0, R - 1]
    (:func:`window_at` gives its factors), and whether none passes (...) (the position is then R - 1).
    ``coeffs``, ``target``, ``method``: as :func:`dering`'s."""
    check_choice(target, "target", DERING_TARGETS)
    check_choice(method, "method", DERING_METHODS)
    c, _, _ = check_coeffs(coeffs, high=MAX_DERING_BANDS)
    _, position, failed, _ = _search(c, target, method)
    return position.reshape(c.shape[:-2]), failed.reshape(c.shape[:-2])


def dering(
    coeffs: ArrayLike, target: str = "irradiance", method: str = "window", *, return_failed: bool = False
) -> tuple[NDArray[np.float64], ...]:
    """
    Window SH lighting as little as needed so that it is non-negative (sections 2.4, 3).

    Parameters
    ----------
    coeffs
        Radiance SH (K, C), (..., K, C) or (K,), K = N^2, N in [1, 7], any unit and magnitude.
    target
        ``"irradiance"``: ``E(n) = integral L(w) max(0, n.w) dw`` must be non-negative
        everywhere; ``"radiance"``: the radiance itself.
    method
        ``"window"`` (default): the seed's search, the least position along :func:`window_table`
        with the factors linear between rows, to :func:`tolerance` of a row step;
        ``"table"``: the least whole row (blurs more: the error report's section 5).
    return_failed
        Also return a boolean array (...,): True where no row is non-negative.

    Returns
    -------
    coeffs_out, scales[, failed]
        ``coeffs_out``: same shape, band l times ``scales[..., l]``; ``scales``: (..., N), the
        window applied, the same for every channel; never NaN or inf.

    Warns
    -----
    DeringWarning
        When some function fails (no non-negative light does): the last row is applied.

    Notes
    -----
    First the least row whose target's minimum is >= 0 in every channel: 1..3 bands (and
    4-band irradiance, whose band 3 the kernel zeroes) on the exact minimum
    (:func:`exact_min`, less its 2.3e-13 rounding allowance), exactly the row a brute-force
    scan finds; 4..7 bands on the certified bound, so never negative. Then, with
    ``"window"``, the fraction f of the step from the row before it (:func:`least_window`):
    at every direction the windowed target is linear in f, so its minimum is concave in f
    and the passing fractions form one interval ending at 1; exact targets bracket its
    crossing by tangents and chords (then bisection), certified ones gallop up from the
    least f at which the level-0 samples can pass and bisect. The window returned is
    always one that passed. The
    last row certifies every non-negative light, so ``failed`` marks coefficients of none.
    Each channel is first divided by a power of two (exact: decisions are scale-invariant).
    A function with a channel below 2^-1022 in every coefficient
    (:data:`SUBNORMAL_EXPONENT`) is decided, on whole rows, on its windowed coefficients as
    returned (subnormal products round by more than eps of the channel), so the returned
    target is non-negative at any magnitude; such a non-negative light may then fail
    (flagged). Vectorised; one input is a batch of one. Costs: ``benchmarks/bench_dering.py``.

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
    flat, position, failed, rows = _search(c, target, method)
    if failed.any():
        warnings.warn(f"dering: {int(failed.sum())} of {len(flat)} functions stay negative ({target}) even at the "
                      "most aggressive window: they are not the projection of any non-negative light; the last "
                      "window was applied to them.", DeringWarning, stacklevel=2)
    if position.any():
        factors = _factors(rows, position)
        out = (flat * factors[:, sh.band_of_index(bands), None]).reshape(c.shape)
    else:  # no function needs a window (row 0: every factor 1)
        factors, out = np.ones((len(flat), bands)), c.copy()
    scales = factors.reshape(c.shape[:-2] + (bands,))
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
