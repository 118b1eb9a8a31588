"""
Real spherical harmonics
========================

The SH mathematics every other module of skysh builds on, in the convention of
``docs/conventions.md``: real, orthonormal, **with the Condon-Shortley phase**, index
``i = l (l + 1) + m``, "bands" ``N`` meaning ``l = 0 .. N - 1``, coefficient arrays
shaped ``(..., N * N, C)``, right-handed Z-up frame.

-   :func:`n_coeffs`, :func:`index`, :func:`lm`, :func:`band_of_index`: the index layout.
-   :data:`Y00`, :data:`K_LINEAR`, :data:`K_PRODUCT`, :data:`K_ZONAL`, :data:`K_SECTORAL`,
    :data:`BASIS_CONSTANTS`: the constants of the first three bands' polynomials, once for
    every module that writes them out (the exact minimum, the engines, the irradiance fit,
    the normalised basis, the generated code).
-   :func:`basis`: the basis at unit vectors, by a Cartesian recurrence
    (:func:`basis_unchecked` for checked input; :func:`basis_recurrence`, its constants).
-   :func:`evaluate`: reconstruct a function from its coefficients.
-   :func:`project`: project a callable by quadrature, Monte Carlo, jittered
    stratified or Sobol quasi-Monte Carlo sampling.
-   :func:`rotate_z`, :func:`rotate`, :func:`rotation_z_matrix`: rotation about Z (Habel 2008,
    eq. 4), by any rotation matrix, and the 3x3 matrix of a rotation about +Z.
-   :func:`gibbs_factors`: the zonal sinc filter of Habel 2008, eq. (5).
-   :func:`convolve`, :func:`cosine_lobe`, :func:`irradiance`: zonal
    convolution and the clamped-cosine (irradiance) kernel.

Layout (as a comprehension)::

    [(l, m) for l in range(bands) for m in range(-l, l + 1)]

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008). Efficient Spherical Harmonics
    Lighting with the Preetham Skylight Model. Eurographics short papers.
    (seed 004: eq. 4, rotation about Z)
-   "Spherical Harmonics", Wakapon wiki (seed 001): Legendre recurrence, jittered
    stratified projection, decoding.
-   Ramamoorthi, R., Hanrahan, P. (2001). An Efficient Representation for
    Irradiance Environment Maps. SIGGRAPH. (clamped-cosine factors A_l)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache, lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import checks

__all__ = ["Y00", "K_LINEAR", "K_PRODUCT", "K_ZONAL", "K_SECTORAL", "BASIS_CONSTANTS", "MAX_BANDS",
    "MAX_GAUSS_NODES", "PROJECTION_METHODS", "index", "lm", "band_of_index", "basis", "basis_unchecked",
    "basis_recurrence", "evaluate", "project", "quadrature_rule", "gauss_legendre", "rotate_z", "rotate",
    "gibbs_factors", "cosine_lobe", "irradiance", "Y_UP_MATRIX", "to_y_up"]

_SQRT_PI: float = math.sqrt(math.pi)

Y00: float = 0.5 / _SQRT_PI
"""Y_0^0 = 1 / (2 sqrt(pi)), the constant basis function: the mean over the sphere of SH c is ``c_0 Y00``."""

K_LINEAR: float = math.sqrt(3.0) / (2.0 * _SQRT_PI)
"""|Y_1^m| / |(y, z, x)|: Y_1 = K_LINEAR (-y, z, -x) with the Condon-Shortley phase (docs/conventions.md)."""

K_PRODUCT: float = math.sqrt(15.0) / (2.0 * _SQRT_PI)
"""The factor of xy, yz and xz in Y_2^-2, Y_2^-1, Y_2^1."""

K_ZONAL: float = math.sqrt(5.0) / (4.0 * _SQRT_PI)
"""The factor of 3 z^2 - 1 in Y_2^0."""

K_SECTORAL: float = math.sqrt(15.0) / (4.0 * _SQRT_PI)
"""The factor of x^2 - y^2 in Y_2^2."""

BASIS_CONSTANTS: NDArray[np.float64] = np.array([
    Y00, -K_LINEAR, K_LINEAR, -K_LINEAR, K_PRODUCT, -K_PRODUCT, K_ZONAL, -K_PRODUCT, K_SECTORAL,
])
"""Signed k_i of ``Y_i = k_i p_i``, p = (1, y, z, x, xy, yz, 3z^2 - 1, xz, x^2 - y^2), i = 0 .. 8
(docs/conventions.md, Condon-Shortley phase); read-only."""
BASIS_CONSTANTS.flags.writeable = False

MAX_BANDS: int = 64
"""Largest band count accepted (l <= 63); the recurrence is stable far beyond it."""

MAX_GAUSS_NODES: int = 1024
"""Largest Gauss-Legendre node count of :func:`gauss_legendre` and :func:`quadrature_rule`:
numpy's eigenvalue method costs O(n^2) memory and O(n^3) time, and skysh's densest rule (the
error report's truth, ``sky_quadrature_rule`` with 2 x ``truth_nodes`` azimuth nodes) stays well
below it."""

PROJECTION_METHODS: tuple[str, ...] = ("quadrature", "mc", "stratified", "qmc")
"""Names accepted by :func:`project`'s ``method``."""

DEFAULT_SAMPLES: int = 1 << 16
"""Sample count of the random projection methods when ``n`` is not given."""


# --------------------------------------------------------------------------- #
# Index layout
# --------------------------------------------------------------------------- #
def n_coeffs(bands: int) -> int:
    """Number of coefficients of ``bands`` bands: ``bands ** 2``."""
    return checks.check_bands(bands, high=MAX_BANDS) ** 2


def index(l: int, m: int) -> int:
    """Flat index ``l (l + 1) + m`` of the coefficient (l, m): integers, ``0 <= l < MAX_BANDS``, ``|m| <= l``."""
    l = checks.check_count(l, "l", 0, MAX_BANDS - 1)
    m = checks.check_count(m, "m", -l, l)
    return l * (l + 1) + m


def lm(i: int) -> tuple[int, int]:
    """Inverse of :func:`index`: the (l, m) of the flat index ``i``, an integer in [0, MAX_BANDS**2 - 1]."""
    i = checks.check_count(i, "i", 0, MAX_BANDS * MAX_BANDS - 1)
    l = math.isqrt(i)
    return l, i - l * (l + 1)


@cache
def band_of_index(bands: int) -> NDArray[np.int64]:
    """Band l of every flat index i < ``bands``**2 (docs/conventions.md order), read-only, cached."""
    out = np.repeat(np.arange(bands), 2 * np.arange(bands) + 1)
    checks.read_only(out)
    return out


# --------------------------------------------------------------------------- #
# Basis by recurrence
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class BasisRecurrence:
    """Constants of the normalised associated-Legendre recurrence for ``bands`` bands.

    With ``Q[l, m](z) = N_lm P_l^m(z) / sin(theta)^m`` (Condon-Shortley phase in
    P, ``N_lm`` the orthonormal factor, times sqrt(2) for m > 0), the real SH are
    ``Q[l, |m|](z) * Re((x + i y)^m)`` for m > 0, ``Q[l, 0]`` for m = 0 and
    ``Q[l, |m|] * Im((x + i y)^|m|)`` for m < 0. Q is a polynomial in z:

        Q[m, m]     = DIAG[m]                                (constant)
        Q[m + 1, m] = sqrt(2m + 3) z Q[m, m]
        Q[l, m]     = A[l, m] z Q[l-1, m] - B[l, m] Q[l-2, m]
    """

    bands: int
    diag: NDArray[np.float64]  # (bands,)
    a: NDArray[np.float64]  # (bands, bands) indexed [l, m]
    b: NDArray[np.float64]  # (bands, bands)


def basis_recurrence(bands: int) -> BasisRecurrence:
    """The recurrence's constants for ``bands`` in [1, 64] (cached, read-only): for code that evaluates the basis elsewhere."""
    return _recurrence(checks.check_bands(bands, high=MAX_BANDS))


@cache
def _recurrence(bands: int) -> BasisRecurrence:
    diag = np.empty(bands)
    diag[0] = Y00
    for m in range(1, bands):
        # Q[m,m] / Q[m-1,m-1] = -(2m - 1) * sqrt((2m+1)/(2m) / (2m-1)^2 ...) in closed form:
        # N_mm (2m-1)!! / (N_{m-1,m-1} (2m-3)!!) = -sqrt((2m + 1) / (2m)), and sqrt(2) once at m = 1.
        diag[m] = -diag[m - 1] * math.sqrt((2 * m + 1) / (2 * m)) * (math.sqrt(2.0) if m == 1 else 1.0)
    a, b = np.zeros((bands, bands)), np.zeros((bands, bands))
    for l in range(2, bands):
        for m in range(0, l - 1):
            a[l, m] = math.sqrt((4 * l * l - 1) / (l * l - m * m))
            b[l, m] = math.sqrt(((l - 1) ** 2 - m * m) * (2 * l + 1) / ((2 * l - 3) * (l * l - m * m)))
    checks.read_only(diag, a, b)
    return BasisRecurrence(bands, diag, a, b)


_BLOCK: int = 4096
"""Points per block of the basis recurrence: its working set (about 4 rows per band
of this many doubles) then stays in cache, which makes it several times faster."""


def _basis_kn(x: NDArray, y: NDArray, z: NDArray, bands: int) -> NDArray[np.float64]:
    """Basis at flat coordinate arrays (N,), returned in the (bands**2, N) layout."""
    n = x.shape[0]
    out = np.empty((bands * bands, n))
    size = min(_BLOCK, max(n, 1))
    work = [np.empty((bands, size)) for _ in range(6)]  # cm, sm, three Q rows, scratch
    for start in range(0, n, _BLOCK):
        stop = min(n, start + _BLOCK)
        _basis_block(x[start:stop], y[start:stop], z[start:stop], bands, out[:, start:stop], work)
    return out


def _basis_block(x: NDArray, y: NDArray, z: NDArray, bands: int, out: NDArray, work: list[NDArray]) -> None:
    """One block of :func:`_basis_kn`, in place, reusing the ``work`` buffers."""
    rec = _recurrence(bands)
    b = x.shape[0]
    cm, sm, q2, q1, q, scratch = (w[:, :b] for w in work)
    # cos / sin of m phi times sin(theta)^m, i.e. Re / Im of (x + i y)^m.
    cm[0], sm[0] = 1.0, 0.0
    tmp = scratch[0]
    for m in range(1, bands):
        np.multiply(x, cm[m - 1], out=cm[m])
        np.multiply(y, sm[m - 1], out=tmp)
        cm[m] -= tmp
        np.multiply(x, sm[m - 1], out=sm[m])
        np.multiply(y, cm[m - 1], out=tmp)
        sm[m] += tmp
    # Rolling rows: q2 = Q[l-2, :], q1 = Q[l-1, :], q = Q[l, :], each indexed [m, point].
    for l in range(bands):
        if l >= 2:
            k = l - 1
            np.multiply(q1[:k], z, out=q[:k])
            q[:k] *= rec.a[l, :k, None]
            np.multiply(q2[:k], rec.b[l, :k, None], out=scratch[:k])
            q[:k] -= scratch[:k]
        if l >= 1:
            np.multiply(z, math.sqrt(2 * l + 1) * rec.diag[l - 1], out=q[l - 1])
        q[l] = rec.diag[l]
        centre = l * l + l
        out[centre] = q[0]
        if l:
            np.multiply(q[1 : l + 1], cm[1 : l + 1], out=out[centre + 1 : centre + l + 1])
            np.multiply(q[1 : l + 1], sm[1 : l + 1], out=out[l * l : centre][::-1])
        q2, q1, q = q1, q, q2


def basis(dirs: ArrayLike, bands: int) -> NDArray[np.float64]:
    """
    Real orthonormal SH (Condon-Shortley phase) at unit vectors.

    Parameters
    ----------
    dirs
        Unit vectors, shape (..., 3), in the Z-up frame of docs/conventions.md.
        An empty batch (0, 3) gives an empty result (0, N * N). At most
        ``MAX_ARRAY_ELEMENTS / (N * N)`` directions (``skysh.checks``).
    bands
        Number of bands N in [1, 64] (l = 0 .. N - 1).

    Returns
    -------
    ndarray
        Shape (..., N * N), ordered by ``i = l (l + 1) + m``. The result may be a
        non-contiguous view of a (N * N, ...) buffer.

    Notes
    -----
    Computed in Cartesian form: ``Re / Im (x + i y)^m`` by the complex-power
    recurrence and the normalised associated Legendre functions divided by
    ``sin(theta)^m`` (polynomials in z) by the three-term recurrence in l, all m
    of a band in one vectorised step. No trigonometric or special function is
    called, so the poles need no care. Cost O(N^2) per point.

    Examples
    --------
    >>> float(basis([0.0, 0.0, 1.0], 1)[0]) == 0.5 / math.sqrt(math.pi)
    True
    """
    bands = checks.check_bands(bands, high=MAX_BANDS)
    return basis_unchecked(checks.check_dirs(dirs, per_point=bands * bands), bands)


def basis_unchecked(d: NDArray[np.float64], bands: int) -> NDArray[np.float64]:
    """:func:`basis` without its checks, for a per-frame path that checked once: ``d`` a float64 array
    (..., 3) of unit vectors, ``bands`` an int in [1, 64]. Bad input gives wrong numbers, not an error."""
    x, y, z = np.ascontiguousarray(d.reshape(-1, 3).T)  # contiguous coordinate rows: the recurrence runs on them
    out = _basis_kn(x, y, z, bands)
    return np.moveaxis(out.reshape((bands * bands,) + d.shape[:-1]), 0, -1)




def _coeff_bands(coeffs: NDArray, name: str = "coeffs", axis: int = 0) -> int:
    """Band count of a coefficient array whose ``axis`` has length N**2."""
    k = coeffs.shape[axis] if coeffs.ndim else 0
    bands = math.isqrt(k)
    if k == 0 or bands * bands != k or bands > MAX_BANDS:
        raise ValueError(f"{name} must have a coefficient axis of length N**2 (1, 4, 9, ..., {MAX_BANDS}**2), "
                         f"got shape {coeffs.shape}")
    return bands


def _batched_bands(c: NDArray) -> int:
    """Band count of coefficients shaped (N * N,) or (..., N * N, C)."""
    if c.ndim == 0:
        raise ValueError("coeffs must have shape (N*N,) or (..., N*N, C)")
    return _coeff_bands(c, axis=0 if c.ndim == 1 else -2)


def evaluate(coeffs: ArrayLike, dirs: ArrayLike) -> NDArray[np.float64]:
    """
    Reconstruct the function with SH coefficients ``coeffs`` at ``dirs``.

    Parameters
    ----------
    coeffs
        Shape (N * N,) or (N * N, C); N <= 64, C >= 1.
    dirs
        Unit vectors, shape (..., 3); an empty batch gives an empty result.

    Returns
    -------
    ndarray
        Shape (...,) for coefficients (N * N,), else (..., C); same units as the
        coefficients.
    """
    c = checks.as_float_array(coeffs, "coeffs")
    if c.ndim not in (1, 2) or (c.ndim == 2 and c.shape[1] == 0):
        raise ValueError(f"coeffs must have shape (N*N,) or (N*N, C) with C >= 1, got {c.shape}")
    bands = _coeff_bands(c)
    d = checks.check_dirs(dirs, per_point=max(bands * bands, c.size // c.shape[0]))
    return basis_unchecked(d, bands) @ c


# --------------------------------------------------------------------------- #
# Projection
# --------------------------------------------------------------------------- #
def gauss_legendre(n: int) -> tuple[NDArray, NDArray]:
    """Gauss-Legendre nodes and weights on [-1, 1] (cached, read-only): exact for degree <= 2n - 1.

    ``n`` is an integer in [1, :data:`MAX_GAUSS_NODES`].
    """
    return _gauss_legendre(checks.check_count(n, "n", 1, MAX_GAUSS_NODES))


@lru_cache(maxsize=256)
def _gauss_legendre(n: int) -> tuple[NDArray, NDArray]:
    nodes, weights = np.polynomial.legendre.leggauss(n)
    checks.read_only(nodes, weights)
    return nodes, weights


def _unit_vectors(z: NDArray, phi: NDArray) -> NDArray:
    """The unit vectors (..., 3) of heights ``z`` in [-1, 1] and azimuths ``phi`` (radians), broadcast together."""
    s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack(np.broadcast_arrays(s * np.cos(phi), s * np.sin(phi), z), axis=-1)


def quadrature_rule(n_theta: int, hemisphere: bool = False) -> tuple[NDArray, NDArray]:
    """
    Product Gauss-Legendre (in cos theta) x uniform azimuth rule on the sphere.

    Parameters
    ----------
    n_theta
        Gauss-Legendre nodes in z = cos(theta) (over [-1, 1], or [0, 1] when
        ``hemisphere``), an integer in [1, :data:`MAX_GAUSS_NODES`]. The
        azimuth gets ``2 * n_theta`` uniform nodes.
    hemisphere
        Integrate only the upper hemisphere z >= 0 (a bool).

    Returns
    -------
    dirs, weights
        Shapes (M, 3) and (M,), ``M = 2 * n_theta ** 2``; the weights sum to
        4 pi (2 pi for the hemisphere). Exact for polynomials of degree
        ``<= 2 n_theta - 1`` in z times trigonometric polynomials of degree
        ``< 2 n_theta`` in phi, hence for products of two SH of bands
        ``<= n_theta``. Read-only arrays, cached.
    """
    n_theta = checks.check_count(n_theta, "n_theta", 1, MAX_GAUSS_NODES)
    return _quadrature_rule(n_theta, checks.check_flag(hemisphere, "hemisphere"))


@lru_cache(maxsize=64)
def _quadrature_rule(n_theta: int, hemisphere: bool) -> tuple[NDArray, NDArray]:
    z, wz = _gauss_legendre(n_theta)
    if hemisphere:
        z, wz = 0.5 * (z + 1.0), 0.5 * wz
    n_phi = 2 * n_theta
    phi = (np.arange(n_phi) + 0.5) * (2.0 * np.pi / n_phi)
    dirs = _unit_vectors(z[:, None], phi).reshape(-1, 3)
    weights = np.repeat(wz * (2.0 * np.pi / n_phi), n_phi)
    checks.read_only(dirs, weights)
    return dirs, weights


@lru_cache(maxsize=16)
def _quadrature_basis(n_theta: int, hemisphere: bool, bands: int) -> tuple[NDArray, NDArray]:
    """Nodes and the weighted basis (bands**2, M) of a cached quadrature rule."""
    dirs, weights = _quadrature_rule(n_theta, hemisphere)
    wy = _basis_kn(dirs[:, 0], dirs[:, 1], dirs[:, 2], bands) * weights
    checks.read_only(wy)
    return dirs, wy


def _uniform_dirs(u: NDArray, v: NDArray, hemisphere: bool) -> NDArray:
    """Area-preserving map of the unit square to the sphere (or upper hemisphere)."""
    return _unit_vectors(1.0 - u if hemisphere else 1.0 - 2.0 * u, 2.0 * np.pi * v)


def _sample_square(method: str, n: int, seed: int | None) -> NDArray:
    """(n, 2) points in the unit square for the random methods."""
    rng = np.random.default_rng(seed)
    if method == "mc":
        return rng.random((n, 2))
    if method == "stratified":
        k = max(1, math.isqrt(n))
        cells = np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="ij"), axis=-1).reshape(-1, 2)
        return (cells + rng.random((k * k, 2))) / k
    from scipy.stats import qmc  # scipy is a runtime dependency; imported here to keep import skysh light

    m = max(0, math.ceil(math.log2(n)))
    return qmc.Sobol(d=2, scramble=True, rng=rng).random_base2(m)


def project(
    f: Callable[[NDArray], ArrayLike], bands: int, method: str = "quadrature", n: int | None = None,
    seed: int | None = None, hemisphere: bool = False,
) -> NDArray[np.float64]:
    """
    Project a function on the sphere into SH: ``c_i = integral f(w) Y_i(w) dw``.

    Parameters
    ----------
    f
        Callable taking unit vectors (M, 3) and returning (M,) or (M, C).
    bands
        Number of bands N in [1, 64].
    method
        ``"quadrature"``: product Gauss-Legendre in cos(theta) x uniform azimuth
        (deterministic; exact for band-limited ``f`` once ``n_theta >= N + band
        of f``). ``"mc"``: uniform random directions. ``"stratified"``: jittered
        stratified sqrt(n) x sqrt(n) grid in the area-preserving square (seed
        001). ``"qmc"``: scrambled Sobol points (scipy.stats.qmc).
    n
        Sample count, an integer >= 1. Quadrature: about ``n`` nodes, as
        ``n_theta = max(bands, round(sqrt(n / 2)))`` (default ``n_theta = 2 *
        bands + 8``), at most :data:`MAX_GAUSS_NODES`. Stratified: rounded down
        to a square. QMC: rounded up to a power of two. Default for the random
        methods: 65536. The basis at the samples, ``n * N * N`` values, must
        fit :data:`skysh.checks.MAX_ARRAY_ELEMENTS`.
    seed
        Seed of the random methods, None or an integer >= 0 (ignored by
        quadrature); same seed, same result.
    hemisphere
        Integrate the upper hemisphere z >= 0 only (a bool): exact for
        functions that vanish below the horizon, and twice the sample density
        there.

    Returns
    -------
    ndarray
        (N * N, C), or (N * N,) when ``f`` returns (M,).

    Raises
    ------
    ValueError
        For a bad parameter (named), or when ``f`` returns another shape or a
        value that is not a finite real number.
    """
    if not callable(f):
        raise ValueError(f"f must be a callable taking unit vectors (M, 3), got {checks.short_repr(f)}")
    bands = checks.check_bands(bands, high=MAX_BANDS)
    checks.check_choice(method, "method", PROJECTION_METHODS)
    seed = checks.check_seed(seed)
    hemisphere = checks.check_flag(hemisphere, "hemisphere")
    if n is not None:
        n = checks.check_count(n, "n", 1, 2 * MAX_GAUSS_NODES**2 if method == "quadrature" else checks.MAX_ARRAY_ELEMENTS)
    if method == "quadrature":
        n_theta = 2 * bands + 8 if n is None else max(bands, round(math.sqrt(n / 2)))
        checks.check_size(2 * n_theta * n_theta * bands * bands, "n" if n is not None else "bands", "the basis at the nodes")
        dirs, wy = _quadrature_basis(n_theta, hemisphere, bands)
        return wy @ _call(f, dirs)
    count = DEFAULT_SAMPLES if n is None else n
    points = 1 << max(0, math.ceil(math.log2(count))) if method == "qmc" else count
    checks.check_size(points * bands * bands, "n", "the basis at the samples")
    square = _sample_square(method, count, seed)
    dirs = _uniform_dirs(square[:, 0], square[:, 1], hemisphere)
    values = _call(f, dirs)
    area = 2.0 * np.pi if hemisphere else 4.0 * np.pi
    y = _basis_kn(dirs[:, 0], dirs[:, 1], dirs[:, 2], bands)
    return (y @ values) * (area / dirs.shape[0])


def _call(f: Callable[[NDArray], ArrayLike], dirs: NDArray) -> NDArray:
    values = checks.as_float_array(f(dirs), "the values returned by f")
    if values.shape[:1] != dirs.shape[:1] or values.ndim > 2:
        raise ValueError(f"f must return shape (M,) or (M, C) for dirs (M, 3), got {values.shape}")
    return values


# --------------------------------------------------------------------------- #
# Rotation
# --------------------------------------------------------------------------- #
@cache
def _z_pairs(bands: int) -> tuple[NDArray, NDArray, NDArray]:
    """For every (l, m > 0): flat indices of (l, m), (l, -m), and m."""
    l, m = np.array([(l, m) for l in range(1, bands) for m in range(1, l + 1)], dtype=np.intp).reshape(-1, 2).T
    return l * (l + 1) + m, l * (l + 1) - m, m.astype(np.float64)


def rotate_z(coeffs: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    """
    Rotate SH coefficients about +Z by ``angle`` (Habel 2008, eq. 4).

    Parameters
    ----------
    coeffs
        Shape (N * N,), (N * N, C) or batched (..., N * N, C).
    angle
        Radians, finite, scalar or broadcasting with the batch axes (...,).
        Positive angles turn +X towards +Y. An empty array of angles gives an
        empty batch of results.

    Returns
    -------
    ndarray
        Coefficients of ``f(Rz(angle)^T w)``, same shape as ``coeffs`` (broadcast
        with ``angle``). For m > 0::

            c'(l, m)  = c(l, m) cos(m a) - c(l, -m) sin(m a)
            c'(l, -m) = c(l, -m) cos(m a) + c(l, m) sin(m a)
    """
    c = checks.as_float_array(coeffs, "coeffs")
    a = checks.as_float_array(angle, "angle")
    vector = c.ndim == 1
    c = c[:, None] if vector else c
    if c.ndim < 2:
        raise ValueError(f"coeffs must have shape (N*N,) or (..., N*N, C), got {c.shape}")
    bands = _coeff_bands(c, axis=-2)
    try:
        shape = np.broadcast_shapes(c.shape, a.shape + (1, 1))
    except ValueError:
        raise ValueError(f"angle must broadcast with the batch axes of coeffs: shapes {a.shape} and {c.shape[:-2]}") from None
    checks.check_size(math.prod(shape), "angle" if a.size > 1 else "coeffs", "rotated coefficients")
    pos, neg, ms = _z_pairs(bands)
    a = np.fmod(a, 2.0 * math.pi)  # m * angle stays small, so cos and sin keep their digits
    ma = a[..., None] * ms  # (..., P)
    cos, sin = np.cos(ma)[..., None], np.sin(ma)[..., None]
    out = np.array(np.broadcast_to(c, shape))
    cp, cn = c[..., pos, :], c[..., neg, :]
    out[..., pos, :] = cp * cos - cn * sin
    out[..., neg, :] = cn * cos + cp * sin
    return out[..., 0] if vector else out


def rotation_z_matrix(angle: float) -> NDArray[np.float64]:
    """3x3 matrix of the rotation about +Z by ``angle`` radians (one finite number; +X towards +Y)."""
    angle = math.fmod(checks.check_scalar(angle, "angle", unit="rad"), 2.0 * math.pi)
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotate(coeffs: ArrayLike, R: ArrayLike) -> NDArray[np.float64]:
    """
    Rotate SH coefficients by a 3x3 rotation matrix.

    Parameters
    ----------
    coeffs
        Shape (N * N,), (N * N, C) or batched (..., N * N, C); any N <= 64.
    R
        Proper rotation matrix (orthonormal, det +1 within 1e-9).

    Returns
    -------
    ndarray
        Coefficients of ``g(w) = f(R^T w)`` (the function turned by R), same
        shape as ``coeffs``. ``rotate(c, rotation_z_matrix(a)) == rotate_z(c, a)``.

    Notes
    -----
    Each band block ``D_l[i, j] = integral Y_i(w) Y_j(R^T w) dw`` is computed by
    the product quadrature with N nodes in z, which is exact for this
    band-limited integrand; this replaces the Ivanic-Ruedenberg recurrence with
    something that shares all of its code with :func:`basis`.
    """
    c = checks.as_float_array(coeffs, "coeffs")
    r = checks.as_float_array(R, "R")
    if r.shape != (3, 3):
        raise ValueError(f"R must have shape (3, 3), got {r.shape}")
    if not (np.allclose(r @ r.T, np.eye(3), atol=1e-9) and abs(np.linalg.det(r) - 1.0) < 1e-9):
        raise ValueError("R must be a rotation matrix (R R^T = I and det R = +1, within 1e-9)")
    bands = _batched_bands(c)
    # The block-diagonal (N*N, N*N) D[i, j] = integral Y_i(w) Y_j(R^T w) dw: the integrand is a product of two
    # band-limited functions of bands <= N, so the product rule with n_theta = N nodes is exact (to rounding).
    dirs, wy = _quadrature_basis(bands, False, bands)
    moved = dirs @ r  # rows are R^T w
    d = wy @ _basis_kn(moved[:, 0], moved[:, 1], moved[:, 2], bands).T
    l_of = band_of_index(bands)
    d[l_of[:, None] != l_of[None, :]] = 0.0  # exact zeros off the band blocks
    return d @ c


# --------------------------------------------------------------------------- #
# Convolution and irradiance
# --------------------------------------------------------------------------- #
def convolve(coeffs: ArrayLike, per_band: ArrayLike) -> NDArray[np.float64]:
    """
    Convolve with a zonal kernel: multiply every coefficient of band l by ``per_band[l]``.

    Parameters
    ----------
    coeffs
        Shape (N * N,) or (..., N * N, C).
    per_band
        At least N factors, shape (>= N,); the first N are used.
    """
    c = checks.as_float_array(coeffs, "coeffs")
    k = checks.as_float_array(per_band, "per_band")
    bands = _batched_bands(c)
    if k.ndim != 1 or k.shape[0] < bands:
        raise ValueError(f"per_band must have shape (>= {bands},), got {k.shape}")
    factors = k[band_of_index(bands)]
    return c * (factors if c.ndim == 1 else factors[:, None])


@cache
def _cosine_lobe(bands: int) -> NDArray[np.float64]:
    # Ramamoorthi & Hanrahan 2001, eq. 8: A_1 = 2 pi / 3, zero for odd l > 1, and for even l
    # A_l = 2 pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2)
    a = np.array([2.0 * math.pi / 3.0 if l == 1 else 0.0 if l % 2 else
                  2.0 * math.pi * (-1.0) ** (l // 2 - 1) / ((l + 2) * (l - 1)) * math.comb(l, l // 2) / 2.0**l
                  for l in range(bands)], dtype=np.float64)
    checks.read_only(a)
    return a


def gibbs_factors(bands: int) -> NDArray[np.float64]:
    """
    Zonal Gibbs filter of Habel eq. (5): sinc(pi l / N) for l = 0 .. N - 1, N = ``bands``.

    Only the zonal (m = 0) coefficients are multiplied by these factors; the
    factor of l = 0 is 1. Both runtimes fold them in (:class:`skysh.SkySH`,
    :class:`skysh.hosek_runtime.HosekWilkieSH`).
    """
    bands = checks.check_bands(bands)
    return np.sinc(np.arange(bands) / bands)  # numpy's sinc(x) = sin(pi x) / (pi x)


def cosine_lobe(bands: int) -> NDArray[np.float64]:
    """
    Clamped-cosine convolution factors A_l, l = 0 .. N - 1.

    ``E(l, m) = A_l L(l, m)`` turns radiance into irradiance ``E(n) = integral
    L(w) max(0, n.w) dw``: A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4, odd l > 1 zero,
    even l by the closed form of Ramamoorthi and Hanrahan (2001).
    """
    return _cosine_lobe(checks.check_bands(bands, high=MAX_BANDS)).copy()


def irradiance(coeffs: ArrayLike) -> NDArray[np.float64]:
    """
    Irradiance coefficients from radiance coefficients (clamped-cosine convolution).

    Parameters
    ----------
    coeffs
        Radiance SH, shape (N * N,) or (..., N * N, C), in cd/m^2 (or any unit L).

    Returns
    -------
    ndarray
        Irradiance SH in L * sr (cd/m^2 * sr = lux for luminance), same shape.
    """
    c = checks.as_float_array(coeffs, "coeffs")
    return convolve(c, _cosine_lobe(_batched_bands(c)))


# --------------------------------------------------------------------------- #
# Axis conventions of engines
# --------------------------------------------------------------------------- #
Y_UP_MATRIX: NDArray[np.float64] = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
"""Rotation taking this package's Z-up frame to a right-handed Y-up frame (glTF):
+X stays +X, +Z (zenith) goes to +Y, +Y goes to -Z (a rotation of -90 degrees
about X; det = +1, so handedness is kept)."""
checks.read_only(Y_UP_MATRIX)


def to_y_up(coeffs: ArrayLike) -> NDArray[np.float64]:
    """
    Re-express SH coefficients for a right-handed Y-up engine frame (glTF).

    The engine evaluates the standard real SH formulas (docs/conventions.md) with its
    own (x, y, z); the returned coefficients make that reproduce the same
    lighting. Zenith (+Z here) becomes +Y, +X stays +X, +Y here becomes -Z.

    For Unity's left-handed Y-up frame (x right, y up, z forward), first apply
    this, then flip the sign of z, i.e. multiply the coefficients odd in z by -1:
    those with l + m odd (for example (1, 0), (2, -1), (2, 1)).

    Parameters
    ----------
    coeffs
        Shape (N * N,), (N * N, C) or (..., N * N, C).
    """
    return rotate(coeffs, Y_UP_MATRIX)


def from_y_up(coeffs: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`to_y_up`: coefficients in a right-handed Y-up frame back to Z up."""
    return rotate(coeffs, Y_UP_MATRIX.T)
