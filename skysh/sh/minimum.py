"""
The minimum of an SH function over the sphere, never above the true one
=======================================================================

-   :func:`exact_min`: exact (to rounding) for 1..3 bands, certified for 4..7 bands.
-   :func:`sphere_quadratic`: a 3-band function as ``c + g.w + w^T Q w`` on |w| = 1.

1..3 bands: ``c + g.w + w^T Q w`` (closed forms of ``docs/conventions.md``) is a trust-region
subproblem (More and Sorensen 1983): with Q = V diag(lam) V^T, a_i = (V^T g)_i^2 / 4, d_i =
lam_i - lam_1, every x > 0 gives the dual bound ``D(x) = c + lam_1 - x - sum a_i / (d_i +
x)``, largest (strong duality: the minimum) at the root of ``sum a_i / (d_i + x)^2 = 1``,
found by Newton's method from its left. 4..7 bands: sampled values less a Bernstein bound of
the curvature between samples, refined where the minimum can be. Derivations:
``docs/dering.md``; tightness and timings: ``tools/dering_experiment.py``.

References: Sloan (2017), Deringing Spherical Harmonics (seed 000); More, J. J., Sorensen,
D. C. (1983), Computing a Trust Region Step, SIAM J. Sci. Stat. Comput. 4(3); Duff, T. et
al. (2017), Building an Orthonormal Basis, Revisited, JCGT 6(1).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_coeffs, check_flag, read_only
from skysh.sh import basis as sh
from skysh.sh.basis import K_LINEAR, K_PRODUCT, K_SECTORAL, K_ZONAL, Y00  # the basis constants, once

__all__ = ["FORM_MAP", "COVER_RADIUS", "LEVELS", "CELL_BUDGET", "sphere_quadratic", "exact_min"]

MAX_MIN_BANDS: int = 7
"""Largest band count of :func:`exact_min` (49 coefficients)."""



def _form_map() -> NDArray[np.float64]:
    m = np.zeros((9, 13))
    m[0, 0] = Y00
    m[3, 1], m[1, 2], m[2, 3] = -K_LINEAR, -K_LINEAR, K_LINEAR  # g = K (-f3, -f1, f2): the seed's optimal linear direction
    q = m[:, 4:].reshape(9, 3, 3)  # a view: Q row-major
    q[4, 0, 1] = q[4, 1, 0] = K_PRODUCT / 2  # (2,-2):  KB x y
    q[5, 1, 2] = q[5, 2, 1] = -K_PRODUCT / 2  # (2,-1): -KB y z
    q[6] = np.diag([-K_ZONAL, -K_ZONAL, 2 * K_ZONAL])  # (2, 0):  K0 (3 z^2 - 1) = K0 (2 z^2 - x^2 - y^2)
    q[7, 0, 2] = q[7, 2, 0] = -K_PRODUCT / 2  # (2, 1): -KB x z
    q[8] = np.diag([K_SECTORAL, -K_SECTORAL, 0.0])  # (2, 2):  K2 (x^2 - y^2)
    read_only(m)
    return m


FORM_MAP: NDArray[np.float64] = _form_map()
"""(9, 13): 3-band coefficients -> (c, g (3), Q (3 x 3, row-major)) of ``c + g.w + w^T Q w``."""

NEWTON_STEPS: int = 4
"""Newton steps after the cluster bounds (one precedes them): rounding at 4 on random and
adversarial problems (``tools/dering_experiment.py``); fewer only loosen the bound."""

ALLOWANCE: float = 256.0 * np.finfo(np.float64).eps * 4.1
"""Rounding allowance of the 3-band minimum in normalised units (largest |coefficient| in
[1/2, 1)): 256 eps of 4.1 >= |c| + |g| + |Q|_F (0.886 + 1.772 + 1.356 with the irradiance
kernel), against eigh's backward error and the dual's dozen operations (measured <= 4e-16)."""

SAMPLE_ROUNDING: float = 2.0**-40
"""Allowance of a sampled value per unit of ``sum_l |f_l| sqrt((2l+1)/(4 pi)) >= max |f|``."""

TINY, FLOOR, POLE = 1e-300, 1e-140, 1e-90
ONES: NDArray[np.float64] = np.ones(3)  # sums over a last axis of 2 or 3 as one product (cheaper than a reduce)
"""Guards (normalised units): denominator offset, least x (x^2 normal), least gap (a / d^3 finite)."""

DIRECTIONS: int = 4096
"""Level-0 sample directions of the 4..7-band certificate (a Fibonacci lattice)."""

COVER_RADIUS: float = 0.0427
"""Their covering radius (rad), rounded up: the largest circumradius of their spherical
Delaunay triangles (printed by the experiment, checked by ``tests/post/test_dering.py``)."""

SPLIT: int = 2
"""A refined cell splits into SPLIT x SPLIT sub-squares (slack / 4 per level): an isolated
minimum keeps about as many cells per level, so small splits cost least."""

LEVELS, VALUE_LEVELS = 6, 12
"""Refinement levels when deciding "minimum >= 0" (final half-diagonal 1.9e-3 rad) and in
:func:`exact_min` (2.9e-5 rad)."""

CELL_BUDGET: int = 2_000
"""Cells kept per function beyond which the deciding certificate stops refining (the bound stays
valid, looser): caps the cost of ring-shaped or flat minima (a lone light's irradiance); the
exports' certificates read it."""
_VALUE_BUDGET: int = 20_000  # the same for exact_min's values
_POINT_BLOCK: int = 1 << 16


def normalised(f: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """f (..., K) times 2^-e (exact; e from frexp of max |f|, so the largest is in [1/2, 1)),
    e, and where f is zero."""
    m = np.maximum.reduce(np.abs(f), -1)
    e = np.frexp(m)[1]
    return np.ldexp(f, -e[..., None]), e, m == 0.0


def sphere_quadratic(coeffs: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    """A 3-band function (..., 9) (docs/conventions.md) as ``f(w) = c + g.w + w^T Q w`` on the unit
    sphere: c (...), g (..., 3) and Q (..., 3, 3) (symmetric, traceless), in its unit."""
    c = as_float_array(coeffs, "coeffs")
    if c.ndim == 0 or c.shape[-1] != 9:
        raise ValueError(f"coeffs must have shape (..., 9) (3 bands, docs/conventions.md order), got {c.shape}")
    m = c @ FORM_MAP
    return m[..., 0], m[..., 1:4], m[..., 4:].reshape(m.shape[:-1] + (3, 3))


def prefix_bound(d: NDArray, a: NDArray) -> NDArray:
    """A proven lower bound of the secular root from the gaps d (..., n) (ascending, d_1 = 0) and
    the weights a: ``max(FLOOR, max_k sqrt(a_1 + .. + a_k) - d_k)``."""
    return np.maximum(np.maximum.reduce(np.sqrt(np.cumsum(a, -1)) - d, -1), FLOOR)


def cluster_bounds(d: NDArray, a: NDArray, x: NDArray) -> NDArray:
    """x raised to proven lower bounds of the root, one pair per split into a pole cluster 1..k
    (merged at its largest gap d_k, which lowers S; A its a) and the rest (gaps d_i - d_k, sums
    C0, T0 of a_i / gap^2, a_i / gap^3): ``(sqrt(C0) - 1) C0 / T0`` and ``min(sqrt(A / (2 (1 -
    C0))), cbrt(A / (4 T0)))``, each less d_k (docs/dering.md). They matter for clusters."""
    shift = d[..., :-1]
    far = np.maximum(d[..., None, :] - shift[..., None], POLE)  # (..., split k, i)
    u = a[..., None, :] * _REST[d.shape[-1]] / (far * far)
    c0, t0 = np.add.reduce(u, -1), np.add.reduce(u / far, -1) + TINY
    big = np.cumsum(a[..., :-1], -1)
    near = np.minimum(np.sqrt(big / (2.0 * np.maximum(1.0 - c0, 0.0) + TINY)), np.cbrt(big / (4.0 * t0)))
    return np.maximum(np.maximum.reduce(np.maximum((np.sqrt(c0) - 1.0) * c0 / t0, near) - shift, -1), x)


_REST: dict[int, NDArray] = {n: np.triu(np.ones((n - 1, n)), 1) for n in (2, 3)}
"""(n - 1, n) masks: row k marks the rest i > k of the split after pole k + 1."""


def newton(d: NDArray, a: NDArray, x: NDArray, steps: int) -> NDArray:
    """Newton's steps on 1 / sqrt(S(x)) = 1 from a start left of the root, never below it."""
    low, ones = x, ONES[: d.shape[-1]]
    for _ in range(steps):
        w = 1.0 / (d + x[..., None])
        aw2 = a * w * w
        s = aw2 @ ones
        x = np.maximum(x + (np.sqrt(s) - 1.0) * s / ((aw2 * w) @ ones + TINY), low)
    return x


def dual(c: NDArray, lam: NDArray, d: NDArray, a: NDArray, x: NDArray) -> NDArray:
    """``c + lam_1 - x - sum a_i / (d_i + x)``: never above the minimum, for any x > 0."""
    return c + lam[..., 0] - x - np.add.reduce(a / (d + x[..., None]), -1)


def trust_region_min(c: NDArray, g: NDArray, q: NDArray, steps: int = NEWTON_STEPS) -> tuple[NDArray, NDArray]:
    """Certified minimum of ``c + g.w + w^T Q w`` on |w| = 1 (2 or 3 dimensions) and a minimiser
    (with its hard-case component along the first eigenvector), batched: one Newton step
    from the proven bound, the cluster bounds, then ``steps`` more."""
    lam, v = np.linalg.eigh(q)
    gam = np.einsum("...ji,...j->...i", v, g)
    a = 0.25 * gam * gam
    d = lam - lam[..., :1]
    x = prefix_bound(d, a)
    x = newton(d, a, cluster_bounds(d, a, newton(d, a, x, 1)), steps)
    zero = (c == 0.0) & np.logical_and.reduce(g == 0.0, -1) & np.logical_and.reduce(q == 0.0, (-2, -1))
    y = -0.5 * gam / (d + x[..., None])
    y[..., 0] += np.sqrt(np.maximum(1.0 - np.einsum("...i,...i->...", y, y), 0.0))
    w = np.einsum("...ij,...j->...i", v, y)
    return np.where(zero, 0.0, dual(c, lam, d, a, x) - ALLOWANCE), w / np.linalg.norm(w, axis=-1, keepdims=True)


def fibonacci(n: int) -> NDArray[np.float64]:
    """n nearly uniform unit vectors (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    return sh._unit_vectors(1.0 - 2.0 * i / n, i * math.pi * (3.0 - math.sqrt(5.0)))


def tangent_frame(p: NDArray) -> tuple[NDArray, NDArray]:
    """Orthonormal tangents of unit vectors p (..., 3) (Duff et al. 2017, exact at +-Z)."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    sign = np.copysign(1.0, z)
    a = -1.0 / (sign + z)
    b = x * y * a
    return np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], -1), np.stack([b, sign + y * y * a, -y], -1)


@cache
def _grid(bands: int) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Level-0 directions (M, 3), their basis (K, M) and tangent frames, cached."""
    dirs = fibonacci(DIRECTIONS)
    out = (dirs, np.ascontiguousarray(sh.basis(dirs, bands).T), *tangent_frame(dirs))
    read_only(*out)
    return out


def level0_basis(bands: int) -> NDArray[np.float64]:
    """The basis (K, :data:`DIRECTIONS`) at the certificate's level-0 directions, read-only, cached."""
    return _grid(bands)[1]


def curvature(f: NDArray) -> tuple[NDArray, NDArray]:
    """Per function of f (..., K): the bound K2 of |f''| along great circles, ``sum_l l^2
    |f_l|_2 sqrt((2l+1)/(4 pi))`` (Bernstein per band), and the rounding allowance of a
    sampled value, :data:`SAMPLE_ROUNDING` times ``sum_l |f_l|_2 sqrt((2l+1)/(4 pi)) >= max |f|``."""
    bands = math.isqrt(f.shape[-1])
    norms = np.sqrt(np.add.reduceat(f * f, np.arange(bands) ** 2, axis=-1)) * np.sqrt((2 * np.arange(bands) + 1) / (4 * math.pi))
    return norms @ (np.arange(bands) ** 2.0), SAMPLE_ROUNDING * np.add.reduce(norms, -1)


def _values(f: NDArray, item: NDArray, p: NDArray) -> NDArray:
    """Values ``f[item[i]]`` at the unit vectors p[i], in blocks of :data:`_POINT_BLOCK` points:
    for a few functions all of them at every point (one matrix product, then a pick)."""
    bands, out = math.isqrt(f.shape[-1]), np.empty(len(p))
    for s in range(0, len(p), _POINT_BLOCK):
        y, it = sh.basis(p[s : s + _POINT_BLOCK], bands), item[s : s + _POINT_BLOCK]
        out[s : s + _POINT_BLOCK] = (np.take_along_axis(y @ f.T, it[:, None], 1)[:, 0] if len(f) <= 8
                                     else np.einsum("ik,ik->i", f[it], y))
    return out


def certified_min(f: NDArray, thr: NDArray | float, levels: int = LEVELS, vals: NDArray | None = None,
                 budget: int = CELL_BUDGET) -> tuple[NDArray, NDArray, NDArray]:
    """Certified lower bound (P,), best sampled value (P,) and its direction (P, 3) of f (P, K)
    (level-0 values ``vals`` (P, M) if known).

    Along great circles |f''| <= K = sum_l l^2 |f_l|_2 sqrt((2l+1)/(4 pi)) (Bernstein per band),
    and the gradient vanishes at the minimiser w*, so a point at angle r from w* is at most
    f* + K r^2 / 2. Every point lies within COVER_RADIUS of a direction; a direction's cell
    is the square [-h, h]^2 of its tangent plane under the exponential map (which never
    lengthens distances). Cells whose estimate ``f(centre) - K r^2 / 2`` (r: half-diagonal) is
    below min(best value, thr) are split; the cell of w* is never dropped, so min(best, thr,
    kept estimates) is never above the minimum, except that where a value below thr was
    sampled (refinement then stops: "minimum >= thr" is refuted) it is that value.
    """
    bands = math.isqrt(f.shape[-1])
    dirs, y0, e1, e2 = _grid(bands)
    k2, allow = curvature(f)
    vals = f @ y0 if vals is None else vals
    j = np.argmin(vals, -1)
    best, point = vals[np.arange(len(f)), j], dirs[j]
    low0 = vals - (0.5 * k2 * COVER_RADIUS**2 + allow)[:, None]
    item, root = np.nonzero(low0 < np.minimum(best, thr)[:, None])
    centre, half, lower = np.zeros((len(item), 2)), COVER_RADIUS, low0[item, root]
    frozen_item, frozen_lower = [item[:0]], [lower[:0]]
    hopeless = np.where(np.isfinite(thr), thr + k2 * (COVER_RADIUS / SPLIT**levels) ** 2 + allow, -np.inf)
    for _level in range(levels):
        big = (np.bincount(item, minlength=len(f))[item] > budget) | (best < hopeless)[item]  # stop refining these
        frozen_item.append(item[big])
        frozen_lower.append(lower[big])
        item, root, centre, lower = item[~big], root[~big], centre[~big], lower[~big]
        if len(item) == 0:
            break
        u = (2.0 * np.arange(SPLIT) + 1.0) / SPLIT - 1.0
        offs = np.stack(np.meshgrid(u, u, indexing="ij"), -1).reshape(-1, 2)  # sub-square centres
        centre = (centre[:, None, :] + half * offs).reshape(-1, 2)
        item, root, half = np.repeat(item, len(offs)), np.repeat(root, len(offs)), half / SPLIT
        r = np.hypot(centre[:, 0], centre[:, 1])[:, None]
        p = np.cos(r) * dirs[root] + np.sinc(r / math.pi) * (centre[:, :1] * e1[root] + centre[:, 1:] * e2[root])
        p /= np.linalg.norm(p, axis=-1, keepdims=True)
        v = _values(f, item, p)
        np.minimum.at(best, item, v)
        hit = v <= best[item]
        point[item[hit]] = p[hit]
        lower = v - k2[item] * half * half - allow[item]  # K r^2 / 2 with r^2 = 2 half^2
        keep = (lower < np.minimum(best, thr)[item]) & ((best >= thr) | np.isinf(thr))[item]
        item, root, centre, lower = item[keep], root[keep], centre[keep], lower[keep]
    bound = np.minimum(best, thr)
    np.minimum.at(bound, np.concatenate([item, *frozen_item]), np.concatenate([lower, *frozen_lower]))
    return bound, best, point


def exact_min(coeffs: ArrayLike, return_dirs: bool = False) -> NDArray[np.float64] | float | tuple:
    """
    The minimum over the sphere of SH functions of 1..7 bands, never above the true one.

    Parameters
    ----------
    coeffs
        (K,), (K, C) or (..., K, C), K = N^2, N in [1, 7], any unit and finite magnitude.
    return_dirs
        Also return a unit direction where the value is (nearly) attained.

    Returns
    -------
    float or ndarray[, directions]
        Per channel ((K,): a float); directions (3,) or (..., C, 3).

    Notes
    -----
    1..3 bands: the dual at its root less 2.3e-13 times 2^e (2^e normalises the largest
    |coefficient| to [1/2, 1)): exact to rounding. 4..7 bands: the sampling certificate
    (:data:`VALUE_LEVELS` levels); its gap to the value at the direction is its slack.
    """
    c, vector, bands = check_coeffs(coeffs, high=MAX_MIN_BANDS)
    return_dirs = check_flag(return_dirs, "return_dirs")
    t, e, _ = normalised(np.moveaxis(c, -2, -1))  # (..., C, K)
    if bands <= 3:
        q = t @ FORM_MAP[: bands * bands]
        val, w = trust_region_min(q[..., 0], q[..., 1:4], q[..., 4:].reshape(q.shape[:-1] + (3, 3)))
    else:
        val, _, w = certified_min(t.reshape(-1, bands * bands), np.inf, VALUE_LEVELS, budget=_VALUE_BUDGET)
        val, w = val.reshape(t.shape[:-1]), w.reshape(t.shape[:-1] + (3,))
    val = np.ldexp(val, e)
    result: float | NDArray = float(val[0]) if vector else val
    if vector:
        w = w[0]
    return (result, w) if return_dirs else result
