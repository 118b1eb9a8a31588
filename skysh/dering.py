"""
Deringing: the least windowing that keeps SH lighting non-negative
==================================================================

Sloan (2017), "Deringing Spherical Harmonics" (seed 000), in the sign convention
of ``CONVENTIONS.md`` (orthonormal real SH **with** the Condon-Shortley phase,
which is also the seed's: its eqs. (4) and (5) carry the phase, so its optimal
linear direction ``(-f3, -f1, f2)`` is used as printed; no conversion is needed).

-   :func:`min_bound`: the seed's conservative lower bound of the minimum of a
    3-band (9-coefficient) function over the sphere (section 2.3), made
    conservative everywhere (see below).
-   :func:`exact_min`: the true minimum, numerically (dense seeding plus a
    trust-region Newton method on the sphere), any number of bands.
-   :func:`align_to_linear_direction`: the rotation of section 2.3 (optimal
    linear direction to +Z) with a frame that never fails.
-   :func:`dering`: the least windowing making the reconstructed irradiance (or
    radiance) non-negative (section 2.4), the same scales for every colour
    channel (section 3); methods ``"table"``, ``"exact"``, ``"sinc4"``.
-   :data:`WINDOW_TABLE`, :func:`window_table`: rows of per-band scale factors.
-   :func:`sinc4_window`: the seed's eq. (6) window.
-   :func:`delta_minimum`, :func:`linear_attenuation`: the windowed delta
    function's minimum, exactly, and the extra linear attenuation derived from it.
-   :data:`PUNCTUAL_WINDOW`, :func:`directional_light_sh`: the seed's hand-tuned
    window for direct lights (section 3) and the projection of a directional
    light (the sun) into windowed SH.
-   :class:`DeringWarning`: issued when no table row makes a function
    non-negative.

Table 1 against eq. (6): a finding
----------------------------------
The seed claims that its most aggressive window makes the irradiance of any
delta function non-negative. The irradiance of a delta light projected to 3
bands and windowed by (1, s1, s2) is, as a function of t = cos(angle to the
light), ``(1/4) [1 + 2 s1 t + (5/8) s2 (3 t^2 - 1)]``; it is non-negative iff
``s1^2 <= (15/8) s2 (1 - 5 s2 / 8)`` (vertex inside [-1, 1]), which needs
``s1 <= sqrt(3)/2 = 0.866`` whatever s2. Computed by :func:`delta_minimum`:

-   **Table 1 fails.** Its digits are plain ``sinc(pi l / w)`` (power 1, rows
    l1, l2, l3 = bands 1, 2, 3: w = 16.7 gives 0.9941, 0.9766, 0.9478 exactly),
    with the linear band of the last four columns attenuated further. Its last
    column (s1 = 0.8915 > 0.866) leaves the delta's irradiance at -3.0 % of its
    mean (minimum -0.0074 against mean 0.25), and no column is non-negative.
-   **Eq. (6) alone fails too**: sinc^4 at w = 5.6 gives (0.8089, 0.4158) and a
    minimum of -9.8 % of the mean. Plain sinc^4 needs w <= 3.31 (3 bands).
-   **Eq. (6) with the extra linear attenuation delivers the claim.** At
    w = 5.6 the largest linear factor allowed by the inequality above is
    ``sqrt((15/8) s2 (1 - 5 s2/8)) = 0.7596``, i.e. an extra attenuation of
    **0.93905** times sinc^4 (3 bands; 0.93595 once bands 4..6 are kept, because
    A_4 < 0). The seed's own last column divided by sinc(pi/5.6) is 0.940: the
    seed derived this factor for sinc^4 and printed it on a sinc^1 table.

So :data:`WINDOW_TABLE` is eq. (6) at the seed's window sizes w = (inf, 16.7,
11.3, 10, 9, 7, 5.6) with the linear band attenuated by a factor that rises
smoothly from 1 to the derived :data:`LINEAR_ATTENUATION` (in proportion to the
attenuation of band 2), with a safety margin :data:`DELTA_MARGIN`. Its last row
is proved to meet the claim by :func:`delta_minimum` (the exact minimum of a
Legendre series: endpoints and roots of its derivative). Since any non-negative
light is a non-negative sum of deltas, the last row makes the irradiance of any
non-negative light non-negative.

The bound (section 2.3), made conservative everywhere
-----------------------------------------------------
After rotating the optimal linear direction to +Z, the function is
``c + a z^2 + b z`` (the zonal part, exact, plus the |m| = 2 pair in its worst
phase ``-T (1 - z^2)``, exact for each z) plus the |m| = 1 pair, which the seed
bounds by ``S z sqrt(1 - z^2)`` (worst phase for z < 0 only). We use
``-S |z| sqrt(1 - z^2)``, the worst phase in **both** hemispheres (the seed's
"run twice with the sign negated"). Because the rotation makes ``b >= 0``, the
upper-hemisphere value at ``z`` is never below the lower one at ``-z``, so the
minimum is in the lower hemisphere. Where the seed minimises over the angle
``phi`` (``z = -cos(phi)``) by Newton's method from ``z = -1/sqrt(2)``, which can
stop at a local minimum and needs a certificate, we solve the problem's Lagrange
dual directly. It is a quadratic plus a linear form on the unit circle (a
trust-region subproblem), for which strong duality holds: every multiplier below
the smallest eigenvalue gives a valid lower bound, and the best one (the root of
the secular equation, found by a monotone Newton iteration without trigonometry,
see :func:`_bound`) gives the minimum itself. The result is the larger of this
and the seed's early-out ``min(c + a z^2 + b z) - S/2``: never above the true
minimum (up to rounding), equal to it for zonal functions. The rotation
invariants (S, T) and the dual's small eigenvalue are computed without
cancellation: computed as differences they left the bound up to about 3e-9 (of
the largest coefficient) too high for functions with tiny |m| = 1 or |m| = 2
parts, now found by ``tests/test_dering.py`` against :func:`exact_min`.

Deringing for more bands and the sinc^4 search (beyond the seed)
----------------------------------------------------------------
For 4..7 bands (16..49 coefficients) the bound does not exist and
:func:`exact_min` decides instead (cost: about 30 ms for one 5-band RGB function,
45 ms at 7 bands, against well under 1 ms for the bound at 3 bands). ``method="sinc4"``
searches the cutoff w of eq. (6) continuously (no table, no extra linear
attenuation) down to the largest w that meets the delta claim (3.31 for 3-band
irradiance). ``method="exact"`` follows the table but decides with
:func:`exact_min`, giving the least windowing the table allows; the default
method also falls back to it for the rare functions whose bound certifies no
candidate at all. ``tools/dering_experiment.py`` measures what each keeps:
on random HDR delta, linear-light and mixed lights the relative L2 change of
the irradiance is about 0.19 (table + bound), 0.18 (table + exact_min) and 0.40
(plain sinc^4 search, which must go down to w = 3.31): the derived linear
attenuation is worth more than the exact decision.

References
----------
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics. SIGGRAPH Asia Technical
    Briefs (seed 000): section 2.2 (optimal linear direction), 2.3 (eqs. 3-5,
    the bound), 2.4 (eq. 6, Table 1, binary search with linear interpolation),
    3 (colour channels, punctual window 0.92 / 0.73).
-   Ramamoorthi, R., Hanrahan, P. (2001). An Efficient Representation for
    Irradiance Environment Maps (the clamped-cosine factors A_l).
-   More, J. J., Sorensen, D. C. (1983). Computing a Trust Region Step. SIAM J.
    Sci. Stat. Comput. 4(3) (global optimality and duality of the circle problem).
-   Duff, T. et al. (2017). Building an Orthonormal Basis, Revisited. JCGT 6(1)
    (the frame that never fails).
"""

from __future__ import annotations

import math
import warnings
from functools import lru_cache
from typing import Callable

import numpy as np
from numpy.polynomial import legendre as _legendre
from numpy.typing import ArrayLike, NDArray

from skysh import sh
from skysh._checks import as_float_array, check_bands, check_choice, check_dirs

__all__ = [
    "DeringWarning",
    "DERING_TARGETS",
    "DERING_METHODS",
    "MAX_DERING_BANDS",
    "SEED_WINDOW_SIZES",
    "SEED_TABLE_1",
    "RADIANCE_WINDOW_SIZES",
    "DELTA_MARGIN",
    "LINEAR_ATTENUATION",
    "WINDOW_TABLE",
    "PUNCTUAL_WINDOW",
    "QUADRATIC_FORM",
    "IRRADIANCE_KERNEL",
    "RADIANCE_KERNEL",
    "sinc4_window",
    "delta_minimum",
    "linear_attenuation",
    "window_table",
    "sinc4_cutoff_floor",
    "align_to_linear_direction",
    "min_bound",
    "exact_min",
    "dering",
    "directional_light_sh",
]


class DeringWarning(UserWarning):
    """Even the most aggressive window leaves a negative value.

    Issued by :func:`dering` when the coefficients are not those of any
    non-negative light (for example a fit's error, or an RGB channel that is
    negative because the sky leaves the colourspace's gamut). The last table row
    (or the sinc^4 floor) is then returned: finite, but still negative somewhere.
    """


# --------------------------------------------------------------------------- #
# Constants
# --------------------------------------------------------------------------- #
DERING_TARGETS: tuple[str, ...] = ("irradiance", "radiance")
"""What :func:`dering` makes non-negative: the clamped-cosine convolution, or the radiance itself."""

DERING_METHODS: tuple[str, ...] = ("table", "exact", "sinc4")
"""Search methods of :func:`dering`: table + bound (exact_min above 3 bands), table + exact_min, sinc^4 cutoff."""

MAX_DERING_BANDS: int = 7
"""Largest band count :func:`dering` accepts (49 coefficients, l <= 6)."""

_Y00: float = 0.5 / math.sqrt(math.pi)
"""Y(0, 0) = 1 / (2 sqrt(pi))."""

_K_LIN: float = math.sqrt(3.0) / (2.0 * math.sqrt(math.pi))
"""|Y(1, m)| / |(x, y, z) component|: sqrt(3) / (2 sqrt(pi))."""

_K1: float = math.sqrt(15.0) / (2.0 * math.sqrt(math.pi))
"""Factor of xy, yz, xz in Y(2, +-2 / +-1): sqrt(15) / (2 sqrt(pi))."""

_K0: float = math.sqrt(5.0) / (4.0 * math.sqrt(math.pi))
"""Factor of (3 z^2 - 1) in Y(2, 0): sqrt(5) / (4 sqrt(pi))."""

_K2: float = math.sqrt(15.0) / (4.0 * math.sqrt(math.pi))
"""Factor of (x^2 - y^2) in Y(2, 2): sqrt(15) / (4 sqrt(pi))."""

_HALF_K1: float = 0.5 * _K1
"""Off-diagonal entries of the band-2 quadratic form per coefficient: K1 / 2."""


def _quadratic_form_map() -> NDArray[np.float64]:
    """(9, 3, 3): the band-2 part of a 3-band function is w^T Q w with Q = sum_i f_i MAP[i]."""
    m = np.zeros((9, 3, 3))
    m[4, 0, 1] = m[4, 1, 0] = _K1 / 2.0  # (2,-2):  K1 x y
    m[5, 1, 2] = m[5, 2, 1] = -_K1 / 2.0  # (2,-1): -K1 y z
    m[6] = np.diag([-_K0, -_K0, 2.0 * _K0])  # (2, 0): K0 (3 z^2 - 1) = K0 (2 z^2 - x^2 - y^2) on the sphere
    m[7, 0, 2] = m[7, 2, 0] = -_K1 / 2.0  # (2, 1): -K1 x z
    m[8] = np.diag([_K2, -_K2, 0.0])  # (2, 2):  K2 (x^2 - y^2)
    m.flags.writeable = False
    return m


QUADRATIC_FORM: NDArray[np.float64] = _quadratic_form_map()
"""(9, 3, 3) map from 3-band coefficients to the symmetric traceless 3x3 matrix of their band 2."""

_QUAD_NORM2: float = 15.0 / (8.0 * math.pi)
"""|Q|_F^2 = 15 / (8 pi) * sum of the squared band-2 coefficients (rotation invariant)."""

IRRADIANCE_KERNEL: NDArray[np.float64] = sh.cosine_lobe(MAX_DERING_BANDS)
"""Clamped-cosine factors A_0 .. A_6 (pi, 2 pi/3, pi/4, 0, -pi/24, 0, pi/64)."""
IRRADIANCE_KERNEL.flags.writeable = False

RADIANCE_KERNEL: NDArray[np.float64] = np.ones(MAX_DERING_BANDS)
"""The identity kernel: deringing the radiance itself."""
RADIANCE_KERNEL.flags.writeable = False

_KERNELS: dict[str, NDArray[np.float64]] = {"irradiance": IRRADIANCE_KERNEL, "radiance": RADIANCE_KERNEL}

_KERNEL_FLOATS: dict[str, tuple[float, float, float]] = {k: tuple(v[:3].tolist()) for k, v in _KERNELS.items()}
"""Bands 0..2 of each kernel as Python floats (the scalar path of :func:`dering`)."""

SEED_WINDOW_SIZES: tuple[float, ...] = (math.inf, 16.7, 11.3, 10.0, 9.0, 7.0, 5.6)
"""Window sizes w of the seed's Table 1 (band at which the window reaches zero), least to most aggressive."""

RADIANCE_WINDOW_SIZES: tuple[float, ...] = SEED_WINDOW_SIZES + (4.0,)
"""Sizes for ``target="radiance"``: the seed's plus w = 4, where sinc^4 with an extra
linear attenuation makes a delta's *radiance* non-negative (w = 5.6 cannot: band 2
keeps more than 0.4, and 1 - 2.5 s2 < 0 at the delta's equator)."""

SEED_TABLE_1: NDArray[np.float64] = np.array(
    [
        [1.0, 1.0, 1.0, 1.0],
        [1.0, 0.9941, 0.9766, 0.9478],
        [1.0, 0.9872, 0.9493, 0.8880],
        [1.0, 0.9634, 0.9355, 0.8584],
        [1.0, 0.9602, 0.9207, 0.8270],
        [1.0, 0.9184, 0.8710, 0.7241],
        [1.0, 0.8915, 0.8030, 0.5904],
    ]
)
"""The seed's Table 1 as printed (rows w = inf .. 5.6, columns bands 0..3; band 0 added
as 1). Kept for comparison only: its last row does *not* meet the seed's claim."""
SEED_TABLE_1.flags.writeable = False

DELTA_MARGIN: float = 1e-9
"""The last table row must keep a windowed delta's target function >= DELTA_MARGIN
times its mean: a positive margin, so that rounding in a bound (about 1e-15
relative) cannot turn an exactly-zero minimum of a single delta into a failure."""

PUNCTUAL_WINDOW: tuple[float, float, float] = (1.0, 0.92, 0.73)
"""The seed's hand-tuned per-band factors for direct (punctual) lights, bands 0..2 (section 3).

Not a non-negative window on its own: a windowed delta's irradiance still dips
to -7.5 % of its mean behind the light (0.92 > sqrt(3)/2); the seed adds it to
sky or indirect light whose own positive irradiance covers that ring."""

_BISECTION_STEPS: int = 64
"""Bisection steps of the import-time derivations (interval halves to 2^-64, below float64 rounding)."""

_SINC4_SCAN: tuple[float, float, float] = (1.0, 12.0, 0.01)
"""Scan (start, stop, step) of the sinc^4 cutoff w in :func:`sinc4_cutoff_floor` before bisection."""


# --------------------------------------------------------------------------- #
# Windows and the delta claim
# --------------------------------------------------------------------------- #
def sinc4_window(cutoff: float, bands: int = 3) -> NDArray[np.float64]:
    """
    Per-band factors of the seed's eq. (6): ``(sin(pi l / w) / (pi l / w))^4``.

    Parameters
    ----------
    cutoff
        w > 0, the band where the window reaches zero; ``inf`` for no windowing.
    bands
        Number of bands N (factors for l = 0 .. N - 1).

    Returns
    -------
    ndarray
        (N,), in [0, 1]; 1 at l = 0, 0 for l >= w (the window stays at zero
        past its cutoff instead of rebounding).
    """
    bands = check_bands(bands)
    w = float(cutoff)
    if not w > 0.0:
        raise ValueError(f"cutoff must be > 0 (a band index, or inf), got {cutoff!r}")
    x = np.arange(bands) / w
    return np.where(x < 1.0, np.sinc(x) ** 4, 0.0)


def delta_minimum(scales: ArrayLike, target: str = "irradiance") -> float:
    """
    Exact minimum of the windowed SH projection of a unit delta light.

    Parameters
    ----------
    scales
        Per-band factors s_0 .. s_{N-1}, shape (N,), N <= 7.
    target
        ``"irradiance"`` (after the clamped-cosine convolution) or ``"radiance"``.

    Returns
    -------
    float
        ``min over t in [-1, 1]`` of ``sum_l A_l s_l (2 l + 1) / (4 pi) P_l(t)``
        (A = clamped-cosine factors, or ones for radiance), in units of the
        delta's integral (sr^-1). The mean is ``A_0 s_0 / (4 pi)`` (1/4 for
        irradiance with s_0 = 1).

    Notes
    -----
    A delta's projection is zonal about its direction, so this is the minimum of
    a Legendre series: at an endpoint or at a real root of its derivative (found
    with :mod:`numpy.polynomial.legendre`), evaluated there. Exact to rounding.
    """
    check_choice(target, "target", DERING_TARGETS)
    s = as_float_array(scales, "scales")
    if s.ndim != 1 or not 1 <= s.shape[0] <= MAX_DERING_BANDS:
        raise ValueError(f"scales must have shape (N,) with 1 <= N <= {MAX_DERING_BANDS}, got {s.shape}")
    n = s.shape[0]
    ell = np.arange(n)
    series = _KERNELS[target][:n] * s * (2 * ell + 1) / (4.0 * math.pi)
    t = [-1.0, 1.0]
    if n > 2:
        roots = _legendre.legroots(_legendre.legder(series))
        t += [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-9 and -1.0 <= r.real <= 1.0]
    elif n == 2:
        pass  # linear: minimum at an endpoint
    return float(np.min(_legendre.legval(np.array(t), series)))


def _delta_ok(scales: NDArray, target: str) -> bool:
    """The delta claim with margin: minimum >= DELTA_MARGIN * mean."""
    mean = _KERNELS[target][0] * scales[0] / (4.0 * math.pi)
    return delta_minimum(scales, target) >= DELTA_MARGIN * mean


def linear_attenuation(cutoff: float, bands: int = 3, target: str = "irradiance") -> float:
    """
    The extra attenuation of the linear band that makes sinc^4 (eq. 6) meet the delta claim.

    Parameters
    ----------
    cutoff
        Window size w of eq. (6).
    bands
        Number of bands N in [1, 7].
    target
        ``"irradiance"`` or ``"radiance"``.

    Returns
    -------
    float
        The largest ``a`` in (0, 1] such that the window ``sinc4_window(w)`` with
        band 1 multiplied by ``a`` keeps a delta's target function >=
        :data:`DELTA_MARGIN` times its mean (1 when no attenuation is needed).

    Notes
    -----
    For 3-band irradiance the answer has a closed form: the delta's irradiance
    is ``(1/4)[(1 - 5 s2/8) + 2 s1 t + (15/8) s2 t^2]``, non-negative iff
    ``s1 <= sqrt((15/8) s2 (1 - 5 s2/8))`` while its vertex lies in [-1, 1], so
    ``a = sqrt((15/8) s2 (1 - 5 s2/8)) / sinc^4(pi/w)``: 0.93905 at w = 5.6.
    Here it is found by bisection on :func:`delta_minimum` for any N (the
    minimum over t is concave in ``a``, so the feasible set is an interval).
    """
    bands = check_bands(bands, high=MAX_DERING_BANDS)
    check_choice(target, "target", DERING_TARGETS)
    base = sinc4_window(cutoff, bands)
    if bands < 2:
        return 1.0

    def ok(a: float) -> bool:
        s = base.copy()
        s[1] *= a
        return _delta_ok(s, target)

    if ok(1.0):
        return 1.0
    lo, hi = 0.0, 1.0
    if not ok(lo):
        raise ValueError(f"no linear attenuation makes sinc^4 at cutoff={cutoff} non-negative for {target}")
    for _ in range(_BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


@lru_cache(maxsize=None)
def _window_table(bands: int, target: str) -> NDArray[np.float64]:
    sizes = SEED_WINDOW_SIZES if target == "irradiance" else RADIANCE_WINDOW_SIZES
    a_min = linear_attenuation(sizes[-1], bands, target)
    wide = max(bands, 3)  # band 2's attenuation drives the ramp even for N < 3
    rows = np.array([sinc4_window(w, wide) for w in sizes])
    ramp = (1.0 - rows[:, 2]) / (1.0 - rows[-1, 2])  # 0 at w = inf, 1 at the last row
    rows[:, 1] *= 1.0 - (1.0 - a_min) * ramp
    table = np.ascontiguousarray(rows[:, :bands])
    table.flags.writeable = False
    return table


def window_table(bands: int = 3, target: str = "irradiance") -> NDArray[np.float64]:
    """
    The table of per-band scale factors searched by :func:`dering`.

    Parameters
    ----------
    bands
        Number of bands N in [1, 7].
    target
        ``"irradiance"`` or ``"radiance"``.

    Returns
    -------
    ndarray
        (R, N), read-only, cached. Row 0 is all ones (no windowing); every row
        has ``row[0] == 1``; each band's factor decreases down the rows; the last
        row makes the target function of any delta light, hence of any
        non-negative light, non-negative (with margin :data:`DELTA_MARGIN`).

    Notes
    -----
    Row r is eq. (6) at ``w = SEED_WINDOW_SIZES[r]`` (``RADIANCE_WINDOW_SIZES``
    for radiance) with band 1 multiplied by ``1 - (1 - a) rho``, where ``a =
    linear_attenuation(w_last, N, target)`` and ``rho = (1 - s2(w)) / (1 -
    s2(w_last))`` rises from 0 to 1 with the attenuation of band 2. The extra
    linear attenuation is needed only by the last row; the ramp keeps the path
    between rows smooth and monotone.
    """
    return _window_table(check_bands(bands, high=MAX_DERING_BANDS), check_choice(target, "target", DERING_TARGETS))


LINEAR_ATTENUATION: float = linear_attenuation(SEED_WINDOW_SIZES[-1], 3, "irradiance")
"""Extra attenuation of the linear band derived for the last row of :data:`WINDOW_TABLE` (0.93905)."""

WINDOW_TABLE: NDArray[np.float64] = window_table(3, "irradiance")
"""(7, 3) per-band factors for 3-band irradiance, bands 0..2: row 0 no windowing, last row
eq. (6) at w = 5.6 with the linear band times :data:`LINEAR_ATTENUATION`."""


@lru_cache(maxsize=None)
def _sinc4_floor(bands: int, target: str) -> float:
    start, stop, step = _SINC4_SCAN
    grid = np.arange(start, stop, step)
    ok = [bool(_delta_ok(sinc4_window(w, bands), target)) for w in grid]
    if not any(ok):
        raise ValueError(f"no sinc^4 cutoff makes {target} of {bands} bands non-negative")
    k = max(i for i, v in enumerate(ok) if v)
    lo, hi = float(grid[k]), float(grid[k]) + step
    for _ in range(_BISECTION_STEPS // 2):  # 2^-32 of a 0.01 step
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _delta_ok(sinc4_window(mid, bands), target) else (lo, mid)
    return lo


def sinc4_cutoff_floor(bands: int = 3, target: str = "irradiance") -> float:
    """
    The largest cutoff w at which plain eq. (6) makes any delta light's target non-negative.

    The end of ``method="sinc4"``'s search (3.31 for 3-band irradiance, 2.53 for
    radiance). Found by a scan in steps of 0.01 and bisection; cached.
    """
    return _sinc4_floor(check_bands(bands, high=MAX_DERING_BANDS), check_choice(target, "target", DERING_TARGETS))


# --------------------------------------------------------------------------- #
# The bound (section 2.3)
# --------------------------------------------------------------------------- #
_NEWTON_STEPS: int = 4
"""Newton steps on the dual's secular equation (see :func:`_bound`), from a start proved
to lie left of its root, so the iterates rise monotonically to it. Measured on 200,000
random functions and 200,000 adversarial (near the trust-region "hard case") problems
against 300 steps: after 3 steps the certified bound is within 1.2e-9 of the converged
one (in units of the largest coefficient), after 4 within 2e-15 (rounding). A
non-converged multiplier only loosens the certificate, never invalidates it. (Read at
call time: ``tools/error_report.py`` sets it temporarily.)"""

_DUAL_FLOOR: float = 1e-12
"""Smallest distance of the dual multiplier below the smallest eigenvalue, in units
of the function's scale: keeps the certificate finite (it is valid for any positive
distance)."""

_FLOOR_ABS: float = 1e-150
"""Absolute part of that floor (normalised units): its square stays a normal number, so
the secular equation's A / x^2 is never 0 / 0 (the zero function)."""

_TINY: float = 1e-300
"""Guards divisions by a scale that is exactly zero (the zero function)."""

_SCALAR_CHANNELS: int = 8
"""Inputs of up to 8 channels in all (one RGB function, with room for a few more) take the
scalar :mod:`math` path of :func:`min_bound` and :func:`dering`: for so few channels
numpy's fixed cost per call (some 100 array operations per bound) exceeds the scalar
arithmetic, which grows with the channels (``benchmarks/bench_dering.py`` prints the
single-input costs of ``min_bound`` and ``dering`` and ``dering``'s per-item cost in a batch)."""


def _check_coeffs(coeffs: ArrayLike, name: str = "coeffs") -> tuple[NDArray[np.float64], bool, int]:
    """(..., K, C) float64 view, whether the input was (K,), and the band count."""
    c = as_float_array(coeffs, name)
    vector = c.ndim == 1
    if vector:
        c = c[:, None]
    if c.ndim < 2:
        raise ValueError(f"{name} must have shape (K,), (K, C) or (..., K, C), got {c.shape}")
    k = c.shape[-2]
    bands = math.isqrt(k)
    if k == 0 or bands * bands != k:
        raise ValueError(f"{name} must have a coefficient axis of length N**2 (1, 4, 9, ...), got shape {c.shape}")
    return c, vector, bands


def _quadratic_times_vector_map() -> NDArray[np.float64]:
    """(3, 15): (Q v)_i = sum over (k, j) of MAP[i, 3 k + j] f_{4+k} v_j, for band-2 coefficients f_4..f_8."""
    m = np.transpose(QUADRATIC_FORM[4:9], (1, 0, 2)).reshape(3, 15).copy()
    m.flags.writeable = False
    return m


_QV_MAP: NDArray[np.float64] = _quadratic_times_vector_map()
"""(3, 15) bilinear map (band-2 coefficients, unit vector) -> Q v, in function units."""

_LINEAR_DIRECTION_MAP: NDArray[np.float64] = np.array(
    [[0, 0, 0, -1, 0, 0, 0, 0, 0], [0, -1, 0, 0, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0, 0, 0, 0]], dtype=np.float64
)
"""(3, 9): coefficients -> the optimal linear direction (-f3, -f1, f2) (seed section 2.2, same sign convention)."""
_LINEAR_DIRECTION_MAP.flags.writeable = False


_SYM_I: NDArray[np.intp] = np.array([0, 1, 2, 0, 0, 1])
_SYM_J: NDArray[np.intp] = np.array([0, 1, 2, 1, 2, 2])
"""Row and column of the 6 distinct entries (00, 11, 22, 01, 02, 12) of a symmetric 3x3 matrix."""

_Q6_MAP: NDArray[np.float64] = np.ascontiguousarray(QUADRATIC_FORM[4:9][:, _SYM_I, _SYM_J].T)
"""(6, 5): band-2 coefficients f_4..f_8 -> the 6 distinct entries of Q, in function units."""
_Q6_MAP.flags.writeable = False

_DIAG6: NDArray[np.float64] = np.array([[1.0], [1.0], [1.0], [0.0], [0.0], [0.0]])
"""The identity in the 6-entry layout, (6, 1)."""
_DIAG6.flags.writeable = False

_FROBENIUS6: NDArray[np.float64] = np.array([2.0, 2.0, 2.0, 4.0, 4.0, 4.0])
"""2 x (the weights of |W|_F^2 in the 6-entry layout): gap^2 = 2 |W|_F^2."""
_FROBENIUS6.flags.writeable = False


def _parts(c: NDArray) -> tuple[NDArray, ...]:
    """Seed section 2.3 quantities of 3-band coefficients (..., 9, C), per channel.

    Returns D (DC value), B (linear slope along the optimal linear direction, >= 0),
    Z (zonal band-2 amplitude: Z (3 z^2 - 1) / 2), T (|m| = 2 amplitude: T (1 - z^2)
    at its worst phase) and S (|m| = 1 amplitude: S |z| sqrt(1 - z^2)), all in the
    function's units and shaped (..., C). These are invariant under rotations about
    the optimal linear direction, so no explicit frame is needed: with Q the band-2
    quadratic form and v the unit direction (+Z when the linear band is zero),
    Z = v.Q v, S = 2 |p| with p = Q v - Z v, and 2 T = the eigenvalue gap of Q
    restricted to the plane orthogonal to v, = sqrt(2) |W|_F with
    ``W = Q - v p^T - p v^T + (Z/2) (I - 3 v v^T)`` (the traceless part of that
    restriction). Both are computed from their components, not from invariants
    such as ``|Q v|^2 - Z^2`` or ``2 |Q|^2 - 3 Z^2 - 4 |p|^2``: those cancel, and
    their rounding error (eps |Q|^2) would make S or T wrong by sqrt(eps) |Q| ~ 1e-8
    when they are small, and the bound that much too high.
    :func:`align_to_linear_direction` computes the same numbers through a frame.
    Arranged as a few matrix products over a (9, n) layout: the per-call cost of
    numpy operations, not arithmetic, dominates for one RGB function.
    """
    shape = c.shape[:-2] + c.shape[-1:]
    f = c[0] if c.ndim == 3 and c.shape[0] == 1 else np.swapaxes(c.reshape((-1,) + c.shape[-2:]), 0, 1).reshape(9, -1)
    add = np.add.reduce  # over axis 0 of (3, n) arrays; skips np.sum's argument handling
    lin = _LINEAR_DIRECTION_MAP @ f  # (3, n)
    norm = np.sqrt(add(lin * lin))
    v = lin / np.where(norm > 0.0, norm, 1.0)
    v[2] += norm == 0.0
    v /= np.sqrt(add(v * v))  # exact unit length even when |lin|^2 was subnormal
    f2 = f[4:9]
    qv = _QV_MAP @ (f2[:, None, :] * v).reshape(15, -1)
    z = add(v * qv)
    perp = qv - z * v
    vi, vj, pi, pj = v[_SYM_I], v[_SYM_J], perp[_SYM_I], perp[_SYM_J]
    w6 = _Q6_MAP @ f2 - vi * pj - pi * vj + (0.5 * z) * (_DIAG6 - 3.0 * vi * vj)
    t = 0.5 * np.sqrt(np.dot(_FROBENIUS6, w6 * w6))
    out = (_Y00 * f[0], _K_LIN * norm, z, t, 2.0 * np.sqrt(add(perp * perp)))
    return tuple(x.reshape(shape) for x in out)


def _cheap_bound(b: NDArray, a: NDArray, c: NDArray, s: NDArray) -> NDArray:
    """The seed's early-out: min over z in [-1, 1] of c + a z^2 + b z (b >= 0), minus S/2.

    |z| sqrt(1 - z^2) <= 1/2 bounds the |m| = 1 pair. The quadratic's minimum is
    the vertex value when a > b/2 (vertex in [-1, 0]) and the endpoint z = -1
    otherwise; the smaller of the two formulas is always the right one.
    """
    vertex = c - b * b / (4.0 * np.maximum(a, 0.5 * b) + _TINY)
    return np.minimum(vertex, c + a - b) - 0.5 * s


def _bound(dc: NDArray, b: NDArray, zon: NDArray, t: NDArray, s: NDArray) -> NDArray:
    """Certified lower bound of c + a z^2 + b z - S |z| sqrt(1 - z^2) over z in [-1, 1].

    Arguments broadcast; b, t, s >= 0 and all of order <= 1 (normalised), with
    a = 1.5 zon + t and c = dc - 0.5 zon - t. No trigonometry: numpy's sin and cos
    cost ten times a division.

    With u = (-z, sqrt(1 - z^2)) and its mirror image, the function is
    ``c + u^T M u + g^T u`` on the whole unit circle, M = [[a, -S/2], [-S/2, 0]],
    g = (-b, 0): a trust-region subproblem with an equality constraint, for which
    strong duality holds (More and Sorensen 1983). Its eigenvalues are
    ``e1 = (a - delta) / 2 <= 0 <= e2 = e1 + delta``, delta = sqrt(a^2 + S^2); the
    squared components of g on the eigenvectors are g1sq = b^2 (-e1) / delta and
    g2sq = b^2 e2 / delta. The smaller of -e1 and e2 is computed as
    ``S^2 / (2 (delta + |a|))``, not as a difference: A below is of order S^2 when
    S << a, the bound depends on sqrt(A), and ``(a - delta) / 2`` would leave it
    wrong (too high) by about S / 2. For every multiplier at distance x > 0 below e1,

        min >= c + e1 - x - A / x - B / (x + delta),  A = g1sq / 4, B = g2sq / 4,

    a concave function of x, largest (and equal to the minimum) at the root of the
    secular equation ``A / x^2 + B / (x + delta)^2 = 1``. Newton's method on
    ``1 / sqrt(A / x^2 + B / (x + delta)^2) = 1``, which is concave and increasing in
    x (the trust-region theory's ``1 / |p|``), rises monotonically to the root from
    any start left of it. The start is the largest of three points proved to be
    left of it: sqrt(A), sqrt(A + B) - delta, and, near the hard case A -> 0 where
    the root is ~ (A delta / 2)^(1/3), ``min((A delta^3 / (4 B))^(1/3),
    sqrt(A delta^2 / (2 (delta^2 - B))))`` (from ``1 / (1 + y)^2 >= 1 - 2 y``). The
    result is the larger of this certificate and the seed's early-out: never above
    the minimum (up to rounding), equal to it once Newton has converged.
    :func:`_bound_scalar` is the same arithmetic on Python floats.
    """
    a = 1.5 * zon + t
    c = dc - 0.5 * zon - t
    cheap = _cheap_bound(b, a, c, s)
    ss = s * s
    delta = np.sqrt(a * a + ss)
    small = ss / (2.0 * (delta + np.abs(a)) + _TINY)  # min(-e1, e2), without cancellation
    bb = 0.25 * (b * b)
    share = bb * small / (delta + _TINY)
    pos = a > 0.0
    e1 = np.where(pos, -small, small - delta)
    big_a = np.where(pos, share, bb - share)
    big_b = np.where(pos, bb - share, share)
    floor = _DUAL_FLOOR * (2.0 * np.abs(a) + b + 2.0 * s) + _FLOOR_ABS
    dd = delta * delta
    hard = np.minimum(np.cbrt(big_a * dd * delta / (4.0 * big_b + _TINY)),
                      np.sqrt(big_a * dd / (2.0 * np.maximum(dd - big_b, 0.0) + _TINY)))
    x = np.maximum(np.maximum(np.sqrt(big_a), np.sqrt(big_a + big_b) - delta), np.maximum(hard, floor))
    for _ in range(_NEWTON_STEPS):
        w = x + delta
        u = big_a / (x * x)
        v = big_b / (w * w)
        n2 = u + v
        x = np.maximum(x + (np.sqrt(n2) - 1.0) * n2 / (u / x + v / w + _TINY), floor)
    return np.maximum(cheap, c + e1 - x - big_a / x - big_b / (x + delta))


def _bound_scalar(dc: float, b: float, zon: float, t: float, s: float, sqrt: Callable = math.sqrt) -> float:
    """:func:`_bound` for one channel on Python floats: the same operations in the same order
    (min / max written as conditional expressions, which CPython runs faster)."""
    a = 1.5 * zon + t
    c = dc - 0.5 * zon - t
    half_b = 0.5 * b
    vertex = c - b * b / (4.0 * (a if a > half_b else half_b) + _TINY)
    end = c + a - b
    cheap = (vertex if vertex < end else end) - 0.5 * s
    ss = s * s
    delta = sqrt(a * a + ss)
    abs_a = a if a >= 0.0 else -a
    small = ss / (2.0 * (delta + abs_a) + _TINY)
    bb = 0.25 * (b * b)
    share = bb * small / (delta + _TINY)
    if a > 0.0:
        e1, big_a, big_b = -small, share, bb - share
    else:
        e1, big_a, big_b = small - delta, bb - share, share
    floor = _DUAL_FLOOR * (2.0 * abs_a + b + 2.0 * s) + _FLOOR_ABS
    dd = delta * delta
    gap = dd - big_b
    r3 = big_a * dd * delta / (4.0 * big_b + _TINY)
    r3 = r3 ** (1.0 / 3.0) if r3 < math.inf else r3
    r2 = sqrt(big_a * dd / (2.0 * (gap if gap > 0.0 else 0.0) + _TINY))
    x = sqrt(big_a)
    x2 = sqrt(big_a + big_b) - delta
    x = x if x > x2 else x2
    x2 = r3 if r3 < r2 else r2
    x2 = x2 if x2 > floor else floor
    x = x if x > x2 else x2
    for _ in range(_NEWTON_STEPS):
        w = x + delta
        u = big_a / (x * x)
        v = big_b / (w * w)
        n2 = u + v
        x = x + (sqrt(n2) - 1.0) * n2 / (u / x + v / w + _TINY)
        x = x if x > floor else floor
    dual = c + e1 - x - big_a / x - big_b / (x + delta)
    return dual if dual > cheap else cheap


def _parts_scalar(
    f: list[float], sqrt: Callable = math.sqrt
) -> tuple[tuple[float, float, float, float, float], float]:
    """:func:`_normalised_parts` of one channel, 9 Python floats: ((D, B, Z, T, S), scale).

    The arithmetic of :func:`_parts` written out (Q by its six distinct entries);
    equal to it to rounding, not bitwise (numpy's matrix products sum in another order).
    """
    scale = max(map(abs, f)) + _TINY
    inv = 1.0 / scale
    f0, f1, f2, f3, f4, f5, f6, f7, f8 = [x * inv for x in f]
    lx, ly, lz = -f3, -f1, f2
    norm = sqrt(lx * lx + ly * ly + lz * lz)
    if norm > 0.0:
        vx, vy, vz = lx / norm, ly / norm, lz / norm
    else:
        vx, vy, vz = lx, ly, lz + 1.0
    length = sqrt(vx * vx + vy * vy + vz * vz)  # exact unit length even when |lin|^2 was subnormal
    vx, vy, vz = vx / length, vy / length, vz / length
    k0f6, k2f8 = _K0 * f6, _K2 * f8
    q00, q11, q22 = k2f8 - k0f6, -k0f6 - k2f8, 2.0 * k0f6
    q01, q02, q12 = _HALF_K1 * f4, -_HALF_K1 * f7, -_HALF_K1 * f5
    qx = q00 * vx + q01 * vy + q02 * vz
    qy = q01 * vx + q11 * vy + q12 * vz
    qz = q02 * vx + q12 * vy + q22 * vz
    z = vx * qx + vy * qy + vz * qz
    px, py, pz = qx - z * vx, qy - z * vy, qz - z * vz
    h = 0.5 * z
    h3 = 3.0 * h
    w00 = q00 - 2.0 * vx * px + h * (1.0 - 3.0 * vx * vx)
    w11 = q11 - 2.0 * vy * py + h * (1.0 - 3.0 * vy * vy)
    w22 = q22 - 2.0 * vz * pz + h * (1.0 - 3.0 * vz * vz)
    w01 = q01 - vx * py - px * vy - h3 * vx * vy
    w02 = q02 - vx * pz - px * vz - h3 * vx * vz
    w12 = q12 - vy * pz - py * vz - h3 * vy * vz
    t = 0.5 * sqrt(2.0 * (w00 * w00 + w11 * w11 + w22 * w22) + 4.0 * (w01 * w01 + w02 * w02 + w12 * w12))
    return (_Y00 * f0, _K_LIN * norm, z, t, 2.0 * sqrt(px * px + py * py + pz * pz)), scale


def _normalised_parts(c: NDArray) -> tuple[tuple[NDArray, ...], NDArray]:
    """:func:`_parts` of the coefficients divided by their largest magnitude per channel, and that scale.

    The division keeps every intermediate of order one (no overflow of squares of
    1e200, no subnormal direction from a linear band of 1e-160).
    """
    scale = np.maximum.reduce(np.abs(c), axis=-2) + _TINY
    return _parts(c * (1.0 / scale)[..., None, :]), scale


def min_bound(coeffs: ArrayLike) -> NDArray[np.float64] | float:
    """
    Conservative lower bound of a 3-band function's minimum over the sphere (seed section 2.3).

    Parameters
    ----------
    coeffs
        SH coefficients of 3 bands: shape (9,), (9, C) or batched (..., 9, C),
        any unit.

    Returns
    -------
    float or ndarray
        The bound per channel: a float for (9,), else shape (..., C), same unit.
        Never above the true minimum (up to rounding, about 1e-15 of the
        coefficients' size); equal to it when the function is zonal about its
        optimal linear direction.

    Notes
    -----
    Steps (module docstring): optimal linear direction ``(-f3, -f1, f2)`` to +Z
    (no frame is built: the quantities used are invariant under rotations about
    that axis; a zero linear band uses +Z), the zonal quadratic (eq. 3) exactly,
    the |m| = 2 pair by its amplitude (eq. 4), the |m| = 1 pair (eq. 5) in its
    worst phase in both hemispheres, minimised through its Lagrange dual (the
    secular equation by Newton's method), never below the seed's early-out.
    Vectorised; inputs of up to 8 channels in all (one RGB function) are done in
    scalar arithmetic (``math``), which numpy's per-call cost makes faster there
    (same result to rounding). No NaN for any finite input.

    Examples
    --------
    >>> round(min_bound(np.eye(9)[0]), 6)  # the constant Y00
    0.282095
    >>> round(min_bound(np.eye(9)[2]), 6)  # Y10 = sqrt(3) z / (2 sqrt(pi)): exact at z = -1
    -0.488603
    """
    c, vector, bands = _check_coeffs(coeffs)
    if bands != 3:
        raise ValueError(f"coeffs must have 9 coefficients (3 bands) on axis -2, got {c.shape[-2]}")
    if c.size <= 9 * _SCALAR_CHANNELS:  # one RGB function: scalar arithmetic beats numpy's per-call cost
        vals = []
        for f in np.swapaxes(c, -1, -2).reshape(-1, 9).tolist():
            parts, scale = _parts_scalar(f)
            vals.append(_bound_scalar(*parts) * scale)
        return vals[0] if vector else np.array(vals).reshape(c.shape[:-2] + c.shape[-1:])
    parts, scale = _normalised_parts(c)
    out = _bound(*parts) * scale
    return float(out[0]) if vector else out


def align_to_linear_direction(coeffs: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    Rotate a 3-band function so that its optimal linear direction is +Z.

    Parameters
    ----------
    coeffs
        Shape (9,), (9, C) or (..., 9, C).

    Returns
    -------
    rotated, frames
        ``rotated``: same shape; coefficients of ``f(R w)`` (so ``rotated[1] =
        rotated[3] = 0`` and ``rotated[2] = |(-f3, -f1, f2)| >= 0``). ``frames``:
        (..., C, 3, 3) (or (3, 3) for (9,)) rotation matrices R whose third
        column is the unit optimal linear direction (+Z when the linear band is
        zero). ``rotated == sh.rotate(coeffs, R.T)`` per channel.

    Notes
    -----
    The frame is Duff et al. (2017)'s branch-free orthonormal basis, exact for
    every unit vector including +-Z. Band 2 is rotated as the quadratic form
    ``Q -> R^T Q R`` (5 numbers from a 3x3 product), not by a generic SH rotation.
    """
    c, vector, bands = _check_coeffs(coeffs)
    if bands != 3:
        raise ValueError(f"coeffs must have 9 coefficients (3 bands) on axis -2, got {c.shape[-2]}")
    lin = np.stack([-c[..., 3, :], -c[..., 1, :], c[..., 2, :]], axis=-1)
    norm = np.linalg.norm(lin, axis=-1)
    has = norm > 0.0
    n = np.where(has[..., None], lin / np.where(has, norm, 1.0)[..., None], np.array([0.0, 0.0, 1.0]))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)  # exact unit length even when |lin|^2 was subnormal
    nx, ny, nz = n[..., 0], n[..., 1], n[..., 2]
    sign = np.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    b1 = np.stack([1.0 + sign * nx * nx * a, sign * b, -sign * nx], axis=-1)
    b2 = np.stack([b, sign + ny * ny * a, -ny], axis=-1)
    frames = np.stack([b1, b2, n], axis=-1)  # columns
    q = np.einsum("...kc,kij->...cij", c, QUADRATIC_FORM)
    qr = np.swapaxes(frames, -1, -2) @ q @ frames
    out = np.zeros_like(c)
    out[..., 0, :] = c[..., 0, :]
    out[..., 2, :] = norm
    out[..., 4, :] = 2.0 * qr[..., 0, 1] / _K1
    out[..., 5, :] = -2.0 * qr[..., 1, 2] / _K1
    out[..., 6, :] = qr[..., 2, 2] / (2.0 * _K0)
    out[..., 7, :] = -2.0 * qr[..., 0, 2] / _K1
    out[..., 8, :] = (qr[..., 0, 0] - qr[..., 1, 1]) / (2.0 * _K2)
    if vector:
        return out[:, 0], frames[0]
    return out, frames


# --------------------------------------------------------------------------- #
# The exact minimum
# --------------------------------------------------------------------------- #
_SEEDS_PER_BAND2: int = 64
"""Seed directions per squared band count (576 for 3 bands, 3136 for 7): spacing about
0.44 / N rad, a fifth of the distance between extrema of band N - 1."""

_MIN_SEEDS: int = 256
"""Fewest seed directions (for 1 and 2 bands)."""

_SEED_NEIGHBOURS: int = 6
"""A seed starts a Newton run only if it is no higher than its 6 nearest seeds (one run per basin)."""

_STARTS: int = 4
"""Newton runs per function, from the lowest local-minimum seeds. On 1,200 random
functions of 3, 5 and 7 bands, 3, 4 and 6 starts found the same minima (all at or
below a 4,608-node grid refined eight times)."""

_EXACT_ITERATIONS: tuple[int, int] = (14, 2)
"""Trust-region Newton iterations with the coarse difference step (at most; fewer once all
runs have converged) and then with the fine one."""

_FD_STEPS: tuple[float, float] = (1e-3, 1e-5)
"""Difference steps (rad) for gradient and Hessian: 1e-3 while converging (truncation
error 1e-6 N^4 of the scale), 1e-5 to polish (rounding 1e-6 of the curvature,
gradient error 1e-10 N^3: the value is then exact to about 1e-16)."""

_CONVERGED: float = 1e-6
"""Newton steps all below 1e-6 rad (value change below 1e-12 of the curvature): stop the
coarse phase early; the polishing steps follow."""

_TRUST_MAX: float = 0.5
"""Largest Newton step on the sphere, radians."""

_EXACT_CHUNK: int = 2048
"""Functions per block of :func:`exact_min` (bounds memory at about 2048 x 3136 floats)."""

_STENCIL: NDArray[np.float64] = np.array([[u, v] for u in (-1, 0, 1) for v in (-1, 0, 1)], dtype=np.float64)
"""3 x 3 difference stencil in tangent coordinates; index 4 is the centre."""


def _fibonacci_sphere(n: int) -> NDArray[np.float64]:
    """n nearly uniform unit vectors (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


@lru_cache(maxsize=None)
def _seeds(bands: int) -> tuple[NDArray, NDArray, NDArray]:
    """Seed directions (M, 3), their basis (K, M) and nearest-neighbour indices (M, 6)."""
    dirs = _fibonacci_sphere(max(_MIN_SEEDS, _SEEDS_PER_BAND2 * bands * bands))
    y = np.ascontiguousarray(sh.basis(dirs, bands).T)
    near = np.argsort(-(dirs @ dirs.T), axis=1)[:, 1 : _SEED_NEIGHBOURS + 1]
    for array in (dirs, y, near):
        array.flags.writeable = False
    return dirs, y, near


def _tangent_frame(p: NDArray) -> tuple[NDArray, NDArray]:
    """Duff et al. (2017) orthonormal tangents of unit vectors p (..., 3)."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return (
        np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=-1),
        np.stack([b, sign + y * y * a, -y], axis=-1),
    )


def _exp_map(p: NDArray, e1: NDArray, e2: NDArray, uv: NDArray) -> NDArray:
    """Points at geodesic offsets uv (..., 2) from p along tangents e1, e2; unit length."""
    r = np.sqrt(np.sum(uv * uv, axis=-1, keepdims=True))
    d = uv[..., :1] * e1 + uv[..., 1:] * e2
    q = np.cos(r) * p + np.sinc(r / math.pi) * d
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _exact_min_flat(f: NDArray, bands: int) -> tuple[NDArray, NDArray]:
    """Minimum and its direction of F functions (F, K): values (F,), dirs (F, 3)."""
    seeds, y, near = _seeds(bands)
    unit = np.max(np.abs(f), axis=1) + _TINY  # work in units of the largest coefficient: no overflow
    f = f / unit[:, None]
    vals = f @ y  # (F, M)
    lowest_nbr = vals[:, near[:, 0]]
    for j in range(1, near.shape[1]):
        np.minimum(lowest_nbr, vals[:, near[:, j]], out=lowest_nbr)
    local = np.where(vals <= lowest_nbr, vals, np.inf)
    k = min(_STARTS, seeds.shape[0])
    start = np.argpartition(local, k - 1, axis=1)[:, :k]  # (F, k)
    n_f = f.shape[0]
    p = seeds[start].reshape(-1, 3)
    val = np.take_along_axis(vals, start, axis=1).reshape(-1)
    fr = np.repeat(f, k, axis=0)  # (P, K)
    radius = np.full(p.shape[0], math.pi / (2.0 * bands))
    n_coarse, n_fine = _EXACT_ITERATIONS
    it = 0
    while it < n_coarse + n_fine:
        h = _FD_STEPS[0] if it < n_coarse else _FD_STEPS[1]
        e1, e2 = _tangent_frame(p)
        q = _exp_map(p[:, None], e1[:, None], e2[:, None], h * _STENCIL)  # (P, 9, 3)
        fq = np.einsum("pk,pjk->pj", fr, sh.basis(q, bands))
        g1 = (fq[:, 7] - fq[:, 1]) / (2.0 * h)
        g2 = (fq[:, 5] - fq[:, 3]) / (2.0 * h)
        huu = (fq[:, 7] - 2.0 * fq[:, 4] + fq[:, 1]) / (h * h)
        hvv = (fq[:, 5] - 2.0 * fq[:, 4] + fq[:, 3]) / (h * h)
        huv = (fq[:, 8] - fq[:, 6] - fq[:, 2] + fq[:, 0]) / (4.0 * h * h)
        # Shift the Hessian to be positive definite (Levenberg), solve, clip to the trust radius.
        scale = np.abs(huu) + np.abs(hvv) + np.abs(huv) + _TINY
        low = 0.5 * (huu + hvv) - np.sqrt(0.25 * (huu - hvv) ** 2 + huv * huv)
        mu = np.maximum(0.0, 1e-9 * scale - low)
        a11, a22 = huu + mu, hvv + mu
        det = a11 * a22 - huv * huv
        det = np.where(det > 0.0, det, _TINY)
        step = np.stack([-(a22 * g1 - huv * g2) / det, -(a11 * g2 - huv * g1) / det], axis=-1)
        length = np.sqrt(np.sum(step * step, axis=-1))
        step *= (np.minimum(1.0, radius / np.maximum(length, _TINY)))[:, None]
        cand = _exp_map(p, e1, e2, step)
        cval = np.einsum("pk,pk->p", fr, sh.basis(cand, bands))
        better = cval < val
        p = np.where(better[:, None], cand, p)
        val = np.where(better, cval, val)
        radius = np.where(better, np.minimum(2.0 * radius, _TRUST_MAX), 0.25 * radius)
        it += 1
        if it < n_coarse and float(np.max(np.where(better, length, 0.0))) < _CONVERGED:
            it = n_coarse  # every run has converged: go to the polishing steps
    val = val.reshape(n_f, k)
    best = np.argmin(val, axis=1)
    return val[np.arange(n_f), best] * unit, p.reshape(n_f, k, 3)[np.arange(n_f), best]


def exact_min(coeffs: ArrayLike, return_dirs: bool = False) -> NDArray[np.float64] | float | tuple:
    """
    The minimum of an SH function over the sphere, numerically.

    Parameters
    ----------
    coeffs
        Shape (K,), (K, C) or batched (..., K, C) with K = N^2, any N <= 64
        (seeding costs O(N^2) directions; practical up to about 16 bands).
    return_dirs
        Also return the unit direction of each minimum.

    Returns
    -------
    ndarray or float, optionally with directions
        Minimum per channel: float for (K,), else (..., C); directions (3,) or
        (..., C, 3).

    Notes
    -----
    Dense seeding: the function at 64 N^2 Fibonacci directions; each of the 4
    lowest seeds that are no higher than their 6 nearest neighbours starts a
    trust-region Newton method on the sphere (tangent frame of Duff et al.
    2017, exponential map, central differences on a 3 x 3 stencil, Levenberg
    shift when the Hessian is indefinite, steps accepted only if they descend):
    up to 14 iterations with a 1e-3 rad difference step (fewer once every run
    has converged), then 2 with 1e-5. About 0.3 ms per 3-band function,
    1.4 ms at 7 bands, in batches. The value
    returned is the function at an actual point, so it is never below the true
    minimum and is within rounding of it when the basin was seeded. Vectorised
    in blocks of 2048 functions.
    """
    c, vector, bands = _check_coeffs(coeffs)
    check_bands(bands)
    flat = np.moveaxis(c, -2, -1).reshape(-1, bands * bands)
    vals = np.empty(flat.shape[0])
    dirs = np.empty((flat.shape[0], 3))
    for i in range(0, flat.shape[0], _EXACT_CHUNK):  # blocks bound memory; not a per-item loop
        vals[i : i + _EXACT_CHUNK], dirs[i : i + _EXACT_CHUNK] = _exact_min_flat(flat[i : i + _EXACT_CHUNK], bands)
    shape = c.shape[:-2] + (c.shape[-1],)
    vals, dirs = vals.reshape(shape), dirs.reshape(shape + (3,))
    if vector:
        vals, dirs = float(vals[0]), dirs[0]
    return (vals, dirs) if return_dirs else vals


# --------------------------------------------------------------------------- #
# Deringing (section 2.4)
# --------------------------------------------------------------------------- #
_BOUND_STAGES_SMALL: tuple[int, ...] = (32,)
"""Search of the bound for a few functions: one batched evaluation of every row and 31
points between consecutive rows (193 candidates); numpy's per-call cost, not the
candidate count, dominates there."""

_BOUND_STAGES_LARGE: tuple[int, ...] = (2, 4, 4)
"""Search of the bound for many functions: 13 candidates, then 3 and 3 inside the
bracket found (the same 1/32-row resolution with 10x fewer evaluations)."""

_SMALL_BATCH: int = 16
"""Batches up to this many functions (items x channels) use the one-stage search."""

_SCREEN_PARTS: int = 32
"""The single-function search (:func:`_search_single`) screens every candidate of the
one-stage grid: the rows and 31 points between consecutive rows (the same 1/32 row)."""

_SCREEN_NODES: int = 49
"""Sample points of the bound's 1D function on z = -cos(phi), phi in [0, pi/2] (step
h = pi/96): sampling gives an upper bound of its minimum and, less L h^2 / 8 with
L >= |H''|, a lower one. The band between them (1.3e-4 L, in units of the largest
coefficient) is below the change of the minimum between neighbouring candidates
(about 1e-3), so at most about one candidate per channel is left for the exact bound
(none for the benchmark's lights and sky; 33 nodes left three bound evaluations there,
more nodes cost more in the matrix product than they save)."""

_SCREEN_SLACK: float = 1e-12
"""Added to the screen's Lipschitz margin (units of the largest coefficient): covers the
rounding of its sums (a few eps) with a wide margin, and is far below the margin itself."""

_SCREEN_EXACT_MAX: int = 6
"""Undecided candidates up to this many are resolved one by one with
:func:`_bound_scalar`; more (rare: a minimum that stays near zero along the path) in one
batched :func:`_bound`."""


def _screen_basis() -> NDArray[np.float64]:
    """(_SCREEN_NODES, 4): 1, z, z^2 and |z| sqrt(1 - z^2) at z = -cos(phi), phi evenly in [0, pi/2]."""
    z = -np.cos(np.linspace(0.0, 0.5 * math.pi, _SCREEN_NODES))
    basis = np.stack([np.ones_like(z), z, z * z, np.abs(z) * np.sqrt(np.maximum(1.0 - z * z, 0.0))], axis=-1)
    basis.flags.writeable = False
    return basis


_SCREEN_BASIS: NDArray[np.float64] = _screen_basis()
"""Sample points of the screen (see :data:`_SCREEN_NODES`)."""

_SCREEN_BASIS32: NDArray[np.float32] = _SCREEN_BASIS.astype(np.float32)
"""The screen's samples are summed in float32 (half the cost of its largest product and
reduction); :data:`_SCREEN_F32_ERROR` accounts for it."""

_SCREEN_MARGIN: float = (0.5 * math.pi / (_SCREEN_NODES - 1)) ** 2 / 8.0
"""h^2 / 8 of the screen: a function with |H''| <= L is at least its sampled minimum less L h^2 / 8."""

_SCREEN_F32_ERROR: float = 2.0**-17
"""Error allowance of a float32 sample, per unit of ``|D| + |c0| + B + |a0| + S`` (which
bounds the sum of its four terms' magnitudes, as s1, s2 <= 1 and |1|, |z|, z^2, w <= 1):
a 4-term float32 dot product with rounded inputs errs by at most about 6 u = 3.6e-7
(u = 2^-24) of that; 2^-17 = 7.6e-6 is 20 times that. It widens the band left
undecided by a few 1e-5 (units of the largest coefficient), against the Lipschitz
margin's 1.3e-4 L."""

_EXACT_STAGES: tuple[int, ...] = (1, 4, 8)
"""Search with :func:`exact_min`: the rows, then 3 and 7 points inside the bracket (1/32 row)."""

_SINC4_INTERVALS: int = 6
"""The sinc^4 path, x = 1/w from 0 to 1/w_floor, is cut into as many intervals as the table has."""

_FAIL_TOL: float = 1e-9
"""A function left at the last row without passing is reported (DeringWarning, failed)
only if its exact minimum there is below -1e-9 times the sum of its |coefficients|:
smaller negatives are rounding of a minimum that touches zero, not a real negative."""


class _Path:
    """Per-band scales along a one-parameter path tau in [0, intervals]: table rows with linear
    interpolation between them, or eq. (6) with x = 1/w linear in tau."""

    def __init__(self, bands: int, target: str, method: str) -> None:
        self.bands = bands
        self.method = method
        if method == "sinc4":
            self.intervals = _SINC4_INTERVALS
            self.x_max = 1.0 / sinc4_cutoff_floor(bands, target)
        else:
            self.table = window_table(bands, target)
            self.intervals = self.table.shape[0] - 1
        self._grids: dict[int, tuple[NDArray, NDArray]] = {}

    def __call__(self, tau: NDArray) -> NDArray:
        """Scales (..., bands) at path parameters tau (...)."""
        if self.method == "sinc4":
            x = (tau / self.intervals * self.x_max)[..., None] * np.arange(self.bands)
            return np.where(x < 1.0, np.sinc(x) ** 4, 0.0)
        i = np.minimum(np.floor(tau).astype(np.intp), self.intervals - 1)
        frac = (tau - i)[..., None]
        return self.table[i] * (1.0 - frac) + self.table[i + 1] * frac

    def screen(self) -> tuple[list[float], list[float], list[float], NDArray, NDArray]:
        """Cached for :func:`_search_single`: the grid's tau, s1 and s2 as lists, the features
        (3, J) = (1, s1, s2) of every candidate, and the candidates' scales (J, bands)."""
        if not hasattr(self, "_screen"):
            tau, scales = self.grid(_SCREEN_PARTS)
            features = np.ascontiguousarray(np.stack([np.ones_like(tau), scales[:, 1], scales[:, 2]]))
            features.flags.writeable = False
            self._screen = (tau.tolist(), scales[:, 1].tolist(), scales[:, 2].tolist(), features, scales)
        return self._screen

    def grid(self, parts: int) -> tuple[NDArray, NDArray]:
        """The first-stage candidates: tau (J,) = 0, 1/parts, ..., intervals and their scales (J, bands)."""
        if parts not in self._grids:
            tau = np.linspace(0.0, float(self.intervals), self.intervals * parts + 1)
            scales = self(tau)
            tau.flags.writeable = False
            scales.flags.writeable = False
            self._grids[parts] = (tau, scales)
        return self._grids[parts]


@lru_cache(maxsize=None)
def _path(bands: int, target: str, method: str) -> _Path:
    return _Path(bands, target, method)


def _search(
    check: Callable[[NDArray | None, NDArray], NDArray], n: int, path: _Path, stages: tuple[int, ...]
) -> tuple[NDArray, NDArray]:
    """Least tau of the candidate grid whose check passes, per item, vectorised over items.

    ``check(items, scales)`` gets item indices (m,) (None: all n items) and
    candidate scales (J, N) shared by all items or (m, J, N) per item, and returns
    passes (m, J). Stage 1 tests tau = 0, 1/s1, ..., intervals at once; each later
    stage splits the bracket (last failing, first passing) into s_k parts and tests
    the interior points at once. Returns tau (n,) and failed (n,) (nothing passed:
    tau = intervals, the last row).
    """
    grid, grid_scales = path.grid(stages[0])
    passes = check(None, grid_scales)
    any_pass = passes.any(axis=1)
    first = np.argmax(passes, axis=1)
    tau = np.where(any_pass, grid[first], grid[-1])
    failed = ~any_pass
    if len(stages) == 1:
        return tau, failed
    lo = np.where(any_pass & (first > 0), grid[np.maximum(first - 1, 0)], tau)
    for parts in stages[1:]:
        active = np.flatnonzero(lo < tau)
        if active.size == 0:
            break
        lo_a, tau_a = lo[active], tau[active]
        cand = lo_a[:, None] + (tau_a - lo_a)[:, None] * (np.arange(1, parts) / parts)  # interior points
        ok = check(active, path(cand))
        hit = ok.any(axis=1)
        k = np.argmax(ok, axis=1)
        rows = np.arange(active.size)
        tau[active] = np.where(hit, cand[rows, k], tau_a)
        lo[active] = np.where(hit, np.where(k > 0, cand[rows, np.maximum(k - 1, 0)], lo_a), cand[:, -1])
    return tau, failed


_SAFE_EXPONENTS: tuple[int, int] = (-960, 1000)
"""Binary exponents (``np.frexp``) of coefficients that :func:`dering` decides on as given:
|c| in about [1e-289, 1e301]. Beyond, the kernel's factor pi could overflow to inf and
sums of subnormal values lose their digits, so :func:`_exactly_rescaled` first scales
every (function, channel) by a power of two."""


_SAFE_SCALES: tuple[float, float] = (math.ldexp(1.0, _SAFE_EXPONENTS[0]), math.ldexp(1.0, _SAFE_EXPONENTS[1]))
""":data:`_SAFE_EXPONENTS` as magnitudes: the range for the largest |coefficient| of one
channel after the kernel, on the scalar path."""


def _exactly_rescaled(flat: NDArray) -> NDArray:
    """``flat`` (n, K, C), or a copy with every (function, channel) divided by a power of two
    near its largest |coefficient| when any coefficient lies outside :data:`_SAFE_EXPONENTS`.

    Exact (powers of two), and every decision of :func:`dering` is invariant under a
    positive scale per channel, so the windows are those of the unscaled input.
    """
    exponents = np.frexp(flat)[1]
    if flat.size == 0 or _SAFE_EXPONENTS[0] <= exponents.min() and exponents.max() <= _SAFE_EXPONENTS[1]:
        return flat
    largest = np.frexp(np.max(np.abs(flat), axis=-2))[1]  # (n, C); 0 for a zero channel
    return np.ldexp(flat, -largest[:, None, :])


def dering(
    coeffs: ArrayLike,
    target: str = "irradiance",
    method: str = "table",
    *,
    return_failed: bool = False,
) -> tuple[NDArray[np.float64], ...]:
    """
    Window SH lighting as little as possible so that it is non-negative (seed section 2.4).

    Parameters
    ----------
    coeffs
        Radiance SH, shape (K, C) or batched (..., K, C) (also (K,)), K = N^2
        with N in [1, 7] (9 for the usual 3 bands), any unit (cd/m^2).
    target
        ``"irradiance"`` (default): make ``E(n) = integral L(w) max(0, n.w) dw``
        of the windowed radiance non-negative everywhere; ``"radiance"``: make
        the windowed radiance itself non-negative.
    method
        ``"table"`` (default): search the rows of :func:`window_table` with
        linear interpolation between them; decided by :func:`min_bound` for
        3 bands, by :func:`exact_min` for other band counts. ``"exact"``: the
        same path decided by :func:`exact_min` (least windowing along the table,
        slower). ``"sinc4"``: eq. (6) with a continuous cutoff w, from inf down
        to :func:`sinc4_cutoff_floor` (same deciders as ``"table"``).
    return_failed
        Also return a boolean array (...,): True where even the last row
        leaves a negative value.

    Returns
    -------
    coeffs_out, scales
        ``coeffs_out``: same shape as ``coeffs``, every band l multiplied by
        ``scales[..., l]``. ``scales``: (..., N), the per-band factors actually
        applied, the same for all channels (the strongest window any channel
        needs, so colour does not shift; seed section 3). All ones when nothing
        is negative. Never NaN or inf.

    Warns
    -----
    DeringWarning
        When some function is negative even at the last row (coefficients that
        no non-negative light produces); the last row is returned for it.

    Notes
    -----
    The seed's binary search with linear interpolation is replaced by batched
    candidates (numpy's per-call cost makes a sequential search slow): every
    table row and 31 points between consecutive rows are candidates, and the
    least-windowed candidate that passes in every channel wins (resolution 1/32
    of a row). One function of up to 8 channels (one RGB result) is screened:
    its bound's 1D function is sampled for every candidate at once (two small
    matrix products), which decides every candidate but the one or two near the
    answer, decided by the bound in scalar arithmetic (same decisions as the
    batched bound; see ``_search_single``). A few functions (items x channels
    <= 16) evaluate the bound for every candidate in one batch. Large batches use
    13 candidates, then 3 and 3 inside the bracket found (the same resolution),
    and the fine grid for items where that finds nothing: the bound is not
    monotone along the path. A function that passes the seed's early-out
    unwindowed returns at once. No Python loop over items.

    Where the bound certifies no candidate, not even the last row (its |m| = 1
    term assumes the worst phase; measured on about 4 % of random HDR light
    mixtures, never on a sky), :func:`exact_min` decides those items along the
    same path: exact_min is needed anyway to tell a loose bound from a truly
    negative function (then the last row and a DeringWarning).

    Cost (``benchmarks/bench_dering.py``, ratios to ``SkySH.coefficients``,
    about 5.4 us, measured in the same run): one (9, 3) input about 2.5x (13 us)
    when nothing is negative (the early-out, which every Preetham sky of the
    fitted domain takes with the runtime's Gibbs filter: their 3-band irradiance
    is positive), about 7.2x (39 us) when windowing is needed (HDR lights, or a
    sky with ``gibbs=False``), where the parts in scalar arithmetic and the
    screen's two matrix products dominate; :func:`min_bound` alone 2.7x (15 us);
    12 us per item in batches of 1000. With :func:`exact_min` (more bands,
    ``method="exact"``, or the rare fallback) some 30-50 ms per RGB function.

    Guarantee: the output's target function is non-negative wherever the bound
    passed (conservative), or, on the exact_min route, to that method's
    accuracy (a dense-seeded local search; never wrong in the tests). The last
    row is non-negative for every non-negative light (the module's delta proof).

    Examples
    --------
    >>> light = sh.basis([0.0, 0.6, 0.8], 3)[:, None] * np.array([1.0, 2.0, 3.0])  # one delta
    >>> out, scales = dering(light)
    >>> scales.shape, bool(scales[1] < 1.0), bool(min_bound(sh.irradiance(out)).min() >= 0.0)
    ((3,), True, True)
    """
    check_choice(target, "target", DERING_TARGETS)
    check_choice(method, "method", DERING_METHODS)
    c, vector, bands = _check_coeffs(coeffs)
    if bands > MAX_DERING_BANDS:
        raise ValueError(f"coeffs must have N**2 coefficients with N in [1, {MAX_DERING_BANDS}], got {c.shape[-2]}")
    flat = c.reshape((-1,) + c.shape[-2:])  # (n, K, C)
    n, n_ch = flat.shape[0], flat.shape[-1]
    l_of = _L_OF_INDEX[: bands * bands]
    path = _path(bands, target, method)
    scales = None
    if bands == 3 and method != "exact" and n == 1 and n_ch <= _SCALAR_CHANNELS:
        tgt = None  # one function: the scalar path applies the kernel itself
        tau, failed, scales = _search_single(flat[0], target, path)
        if failed is not None and failed[0]:  # see below
            tgt = _exactly_rescaled(flat) * _KERNELS[target][l_of][:, None]  # decisions; output scales flat
            tau, failed = _search_exact(tgt, path, l_of)
            scales = None
    else:
        tgt = _exactly_rescaled(flat) * _KERNELS[target][l_of][:, None]  # decisions; output scales flat
        if bands == 3 and method != "exact":
            tau, failed = _search_bound(tgt, path)
            if failed is not None and failed.any():
                # The bound certified no candidate, not even the last row (about 4 % of random
                # HDR light mixtures, never a sky): the exact minimum decides those few, as it
                # would have to anyway to tell a loose bound from a truly negative function.
                idx = np.flatnonzero(failed)
                tau[idx], failed[idx] = _search_exact(tgt[idx], path, l_of)
        else:
            tau, failed = _search_exact(tgt, path, l_of)
    if tau is None:  # nothing to do: the unwindowed function passed the early-out
        scales = np.ones((n, bands))
        out = flat.copy()
    else:
        if scales is None:
            scales = path(tau)
        if failed.any():
            # Warn only beyond rounding: the exact search rejects any negative value.
            idx = np.flatnonzero(failed)
            size = np.abs(tgt[idx]).sum(axis=-2)  # no absolute floor: tgt is of order one or zero
            failed[idx] = (exact_min(tgt[idx] * scales[idx][:, l_of, None]) < -_FAIL_TOL * size).any(axis=-1)
            if failed.any():
                warnings.warn(
                    f"dering: {int(failed.sum())} of {n} functions stay negative ({target}) even at the most "
                    "aggressive window: they are not the projection of any non-negative light; the last "
                    "window was applied to them.",
                    DeringWarning,
                    stacklevel=2,
                )
        out = flat * scales[:, l_of, None]
    out = out.reshape(c.shape)
    scales = scales.reshape(c.shape[:-2] + (bands,))
    if vector:
        out = out[:, 0]
    if return_failed:
        return out, scales, (np.zeros(n, dtype=bool) if tau is None else failed).reshape(c.shape[:-2])
    return out, scales


_L_OF_INDEX: NDArray[np.intp] = np.repeat(np.arange(MAX_DERING_BANDS), 2 * np.arange(MAX_DERING_BANDS) + 1)
"""Band l of every flat index up to 7 bands."""


def _search_bound(tgt: NDArray, path: _Path) -> tuple[NDArray | None, NDArray | None]:
    """tau and failed per item of 3-band target coefficients (n, 9, C), decided by the bound.

    Returns (None, None) when every item passes the seed's early-out unwindowed.
    """
    n, n_ch = tgt.shape[0], tgt.shape[-1]
    parts, _ = _normalised_parts(tgt)  # each (n, C)
    dc, b0, zon0, t0, s0 = parts
    quick = _cheap_bound(b0, 1.5 * zon0 + t0, dc - 0.5 * zon0 - t0, s0) >= 0.0  # the seed's early-out
    if quick.all():
        return None, None
    todo = np.flatnonzero(~quick.all(axis=-1))
    sub = parts if todo.size == n else tuple(p[todo] for p in parts)
    small = todo.size * n_ch <= _SMALL_BATCH
    stages = _BOUND_STAGES_SMALL if small else _BOUND_STAGES_LARGE
    tau_sub, failed_sub = _search(_bound_check(sub), todo.size, path, stages)
    if not small and failed_sub.any():
        # The bound is not monotone along the path: a coarse first stage can miss a short
        # passing stretch. Items that found nothing get the fine one-stage search.
        again = np.flatnonzero(failed_sub)
        check = _bound_check(tuple(p[again] for p in sub))
        tau_sub[again], failed_sub[again] = _search(check, again.size, path, _BOUND_STAGES_SMALL)
    if todo.size == n:
        return tau_sub, failed_sub
    tau, failed = np.zeros(n), np.zeros(n, dtype=bool)
    tau[todo], failed[todo] = tau_sub, failed_sub
    return tau, failed


def _bound_check(parts: tuple[NDArray, ...]) -> Callable[[NDArray | None, NDArray], NDArray]:
    """The search's decider for normalised parts (m, C) of 3-band targets: bound >= 0 in every channel."""

    def check(items: NDArray | None, scales: NDArray) -> NDArray:
        s1, s2 = scales[..., 1, None], scales[..., 2, None]  # (J, 1) or (m, J, 1)
        d, b, z, t, s = (p[:, None, :] if items is None else p[items][:, None, :] for p in parts)
        return (_bound(d, b * s1, z * s2, t * s2, s * s2) >= 0.0).all(axis=-1)

    return check


def _search_single(
    coeffs: NDArray, target: str, path: _Path
) -> tuple[NDArray | None, NDArray | None, NDArray | None]:
    """tau (1,), failed (1,) and scales (1, 3) of one 3-band function (9, C), C <= _SCALAR_CHANNELS.

    ``coeffs`` are radiance SH; the target's kernel (A_l or ones) is applied here.

    The same decision as the one-stage search of :func:`_search_bound` (the least
    candidate of the 1/32-row grid whose :func:`_bound` is >= 0 in every channel) in
    about 20 numpy calls instead of some 130. Per channel, in normalised units, the
    bound's 1D function at candidate (s1, s2) is
    ``H(z) = D - s2 c0 + s1 B z + s2 (a0 z^2 - S w)``, w = |z| sqrt(1 - z^2),
    a0 = 1.5 Z + T, c0 = 0.5 Z + T, linear in (1, s1, s2): two small matrix
    products give it at the screen's sample points for every candidate and channel
    at once (the second in float32, with an error allowance e). Its sampled minimum
    is a value of the function, so at least the bound's value (the function's
    minimum): a candidate with a sample below -e in some channel fails. The sampled
    minimum less ``(2 s2 sqrt(a0^2 + S^2) + s1 B) h^2 / 8 + slack + e`` (|H''| along
    phi is at most ``2 sqrt(a^2 + S^2) + b``) is a lower bound of the minimum: a
    candidate where it is >= 0 in every channel passes. The undecided candidates
    before the first certain pass (typically none or one) are decided by
    :func:`_bound_scalar` in the channels not already certain (by one batched
    :func:`_bound` when there are many). Returns (None, None, None) when the seed's
    early-out passes unwindowed; scales None when nothing passed (failed).
    """
    k0, k1, k2 = _KERNEL_FLOATS[target]
    parts = []
    for f in coeffs.T.tolist():
        f0, f1, f2, f3, f4, f5, f6, f7, f8 = f
        part, scale = _parts_scalar([k0 * f0, k1 * f1, k1 * f2, k1 * f3, k2 * f4, k2 * f5, k2 * f6, k2 * f7, k2 * f8])
        if not _SAFE_SCALES[0] <= scale <= _SAFE_SCALES[1]:  # extreme (or zero) channel: as _exactly_rescaled
            shift = -math.frexp(max(map(abs, f)))[1]
            f0, f1, f2, f3, f4, f5, f6, f7, f8 = (math.ldexp(x, shift) for x in f)
            part = _parts_scalar([k0 * f0, k1 * f1, k1 * f2, k1 * f3, k2 * f4, k2 * f5, k2 * f6, k2 * f7, k2 * f8])[0]
        parts.append(part)
    quick = True
    for dc, b, zon, t, s in parts:  # the seed's early-out, as in _cheap_bound
        a, c = 1.5 * zon + t, dc - 0.5 * zon - t
        if not min(c - b * b / (4.0 * max(a, 0.5 * b) + _TINY), c + a - b) - 0.5 * s >= 0.0:  # NaN fails
            quick = False
            break
    if quick:
        return None, None, None
    taus, s1s, s2s, features, grid_scales = path.screen()
    n_ch, n_j = len(parts), len(taus)
    const, lin, quad, side, margin, single = [], [], [], [], [], []  # rows (k, channel) of a (6 C, 3) map
    for dc, b, zon, t, s in parts:
        a0, c0 = 1.5 * zon + t, 0.5 * zon + t
        const += (dc, 0.0, -c0)  # 1: D - s2 c0
        lin += (0.0, b, 0.0)  # z: s1 B
        quad += (0.0, 0.0, a0)  # z^2: s2 a0
        side += (0.0, 0.0, -s)  # w: -s2 S
        f32 = _SCREEN_F32_ERROR * (abs(dc) + abs(c0) + b + abs(a0) + s)  # >= float32 error of a sample
        margin += (_SCREEN_SLACK + f32, _SCREEN_MARGIN * b, 2.0 * _SCREEN_MARGIN * math.sqrt(a0 * a0 + s * s))
        single += (f32, 0.0, 0.0)
    terms = np.dot(np.array(const + lin + quad + side + margin + single).reshape(6 * n_ch, 3), features)  # (6 C, J)
    samples = np.dot(_SCREEN_BASIS32, terms[: 4 * n_ch].reshape(4, n_ch * n_j).astype(np.float32))
    upper = np.minimum.reduce(samples).reshape(n_ch, n_j)  # float32 sampled minimum
    sure = np.flatnonzero(np.logical_and.reduce(upper >= terms[4 * n_ch : 5 * n_ch]))  # lower bound >= 0
    first = int(sure[0]) if sure.size else n_j
    possible = upper[:, :first] >= -terms[5 * n_ch :, :first]  # no sample certainly negative
    undecided = np.flatnonzero(np.logical_and.reduce(possible))
    found = first
    if undecided.size > _SCREEN_EXACT_MAX:
        j = undecided
        d, b, z, t, s = (np.array(p)[:, None] for p in zip(*parts))  # (C, 1)
        s1, s2 = grid_scales[j, 1], grid_scales[j, 2]
        ok = np.logical_and.reduce(_bound(d, b * s1, z * s2, t * s2, s * s2) >= 0.0)
        if ok.any():
            found = int(j[np.argmax(ok)])
    elif undecided.size:
        low_all = upper[:, undecided] - terms[4 * n_ch : 5 * n_ch, undecided]
        for j, low in zip(undecided.tolist(), low_all.T.tolist()):
            s1, s2 = s1s[j], s2s[j]
            if all(lo >= 0.0 or _bound_scalar(dc, b * s1, zon * s2, t * s2, s * s2) >= 0.0
                   for lo, (dc, b, zon, t, s) in zip(low, parts)):
                found = j
                break
    if found == n_j:  # nothing passed: the last row, reported as failed
        return np.array([taus[-1]]), np.ones(1, dtype=bool), None
    return np.array([taus[found]]), np.zeros(1, dtype=bool), grid_scales[found : found + 1].copy()


def _search_exact(tgt: NDArray, path: _Path, l_of: NDArray) -> tuple[NDArray, NDArray]:
    """tau and failed per item of target coefficients (n, K, C), decided by :func:`exact_min`."""

    def check(items: NDArray | None, scales: NDArray) -> NDArray:
        sel = tgt if items is None else tgt[items]
        mins = exact_min(sel[:, None] * scales[..., l_of, None])  # (m, J, C)
        return (mins >= 0.0).all(axis=-1)

    return _search(check, tgt.shape[0], path, _EXACT_STAGES)


# --------------------------------------------------------------------------- #
# Punctual lights (section 3)
# --------------------------------------------------------------------------- #
def directional_light_sh(
    direction: ArrayLike,
    colour: ArrayLike,
    bands: int = 3,
    window: ArrayLike = PUNCTUAL_WINDOW,
) -> NDArray[np.float64]:
    """
    Windowed SH radiance of a directional light (a delta), to add to deringed sky SH.

    Parameters
    ----------
    direction
        Unit vector towards the light, shape (3,) or (..., 3), Z up.
    colour
        The light's integral over the sphere per channel: its illuminance at
        normal incidence, shape (C,) or broadcasting (..., C); for a source of
        radiance L (cd/m^2) and solid angle Omega, ``L * Omega`` (lux).
    bands
        Number of bands N; ``window`` must have at least N factors.
    window
        Per-band factors; default the seed's :data:`PUNCTUAL_WINDOW`
        (1, 0.92, 0.73). Pass ``window_table(bands)[-1]`` for a window under
        which the light alone has non-negative irradiance.

    Returns
    -------
    ndarray
        (..., N * N, C): ``window[l] * Y_i(direction) * colour``, in the unit of
        ``colour`` per sr (radiance SH, same convention as the sky's).

    Notes
    -----
    The seed windows direct lights by a fixed hand-tuned kernel and runs the
    search only on sky and indirect light (section 3). For the sun::

        sky, _ = dering(sky_coeffs)
        total = sky + directional_light_sh(sun_dir, sun_illuminance)

    With the seed's window a lone delta's irradiance dips to -7.5 % of its mean
    behind the light; the sky's irradiance must cover that dip.
    """
    bands = check_bands(bands, high=sh.MAX_BANDS)
    d = check_dirs(direction, "direction")
    col = as_float_array(colour, "colour")
    w = as_float_array(window, "window")
    if w.ndim != 1 or w.shape[0] < bands:
        raise ValueError(f"window must have shape (>= {bands},), got {w.shape}")
    if col.ndim == 0:
        raise ValueError(f"colour must have shape (C,) or (..., C), got {col.shape}")
    l_of = np.repeat(np.arange(bands), 2 * np.arange(bands) + 1)
    y = sh.basis(d, bands) * w[l_of]  # (..., K)
    return y[..., :, None] * col[..., None, :]
