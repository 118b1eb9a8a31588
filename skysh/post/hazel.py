"""
The normalised SH basis of Hazel (Geomerics) and the non-linear L1 irradiance
==============================================================================

Hazel's basis (seed 003) drops the constant factors of the orthonormal SH: with
the normalised inner product ``<R, S> = (1 / 4 pi) integral R S dw`` and the
functions ``B0 = 1``, ``B1 = (x, y, z)``, ``B2_ij = w_i w_j - delta_ij / 3``, a
radiance has a mean ``R0``, a vector ``R1`` (its average direction) and a
symmetric traceless 3x3 matrix ``R2`` per colour channel.

-   :func:`to_normalised`, :func:`from_normalised`: our orthonormal (Condon-
    Shortley) coefficients <-> (R0, R1, R2).
-   :func:`radiance`: ``R0 + 3 R1.w + (15/2) w R2 w``.
-   :func:`irradiance`: ``I(n) = R0 + 2 R1.n + (15/8) n R2 n``, the seed's
    irradiance ``I = E / pi`` (E the cosine-weighted integral of docs/conventions.md;
    I is the radiance leaving a white Lambertian surface). Its odd part is exact
    for any radiance: ``n.R1 = (I(n) - I(-n)) / 4`` (the antipodal identity).
-   :func:`geomerics_parameters`, :func:`irradiance_l1_nonlinear`: the
    non-linear L1 irradiance of Geomerics (CEDEC 2015),
    ``R0 [a + (1 - a)(1 + p) q^p]`` with ``q = (1 + n.d) / 2``, ``r = |R1| / R0``,
    ``p = 1 + 2 r``, ``a = (1 - r) / (1 + r)``: never negative, mean R0, exact
    antipodal difference along ``d = R1 / |R1|``.

The conversion table with its Condon-Shortley signs, the reconstruction factors and
the derivation of the non-linear L1 (steps 1-4) are in docs/hazel.md. The accuracy
of these reconstructions on the sky is a study: ``tools/studies/hazel_study.py``.

References
----------
-   Hazel, G. Spherical Harmonics for Lighting. Geomerics (seed 003): the
    normalised inner product, B0, B1, B2, the radiance and irradiance
    reconstructions and the antipodal identity ``n.R1 = (I(n) - I(-n)) / 4``.
-   Geomerics (2015). Reconstructing Diffuse Lighting from Spherical Harmonic
    Data. CEDEC 2015 (cited by seed 003); the shader is in the Enlighten SDK
    documentation, "Light probe evaluation".
-   Ramamoorthi, R., Hanrahan, P. (2001). An Efficient Representation for
    Irradiance Environment Maps. SIGGRAPH (A_l).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_coeffs, check_dirs, check_size
from skysh.sh import basis as sh

__all__ = ["L0_SCALE", "L1_SCALE", "L2_OFF_DIAGONAL_SCALE", "L2_ZZ_SCALE", "L2_XX_MINUS_YY_SCALE",
    "ANTIPODAL_FACTOR", "GEOMERICS_EXPONENT_ENDS", "radiance", "irradiance"]

L0_SCALE: float = sh.Y00
"""R0 = L0_SCALE c0: (1 / 4 pi) integral R = c0 / (4 pi Y00), Y00 = 1 / (2 sqrt(pi))."""

L1_SCALE: float = 1.0 / (2.0 * math.sqrt(3.0 * math.pi))
"""R1 = L1_SCALE (-c3, -c1, c2): 1 / (4 pi k1), k1 = sqrt(3) / (2 sqrt(pi))."""

L2_OFF_DIAGONAL_SCALE: float = 1.0 / (2.0 * math.sqrt(15.0 * math.pi))
"""R2_xy = s c4, R2_yz = -s c5, R2_xz = -s c7 with s = 1 / (4 pi k2), k2 = sqrt(15) / (2 sqrt(pi))."""

L2_ZZ_SCALE: float = 1.0 / (3.0 * math.sqrt(5.0 * math.pi))
"""R2_zz = L2_ZZ_SCALE c6: Y(2, 0) = (3 sqrt(5) / (4 sqrt(pi))) (z^2 - 1/3), 1 / (4 pi) of its inverse factor."""

L2_XX_MINUS_YY_SCALE: float = 1.0 / math.sqrt(15.0 * math.pi)
"""R2_xx - R2_yy = L2_XX_MINUS_YY_SCALE c8: Y(2, 2) = (k2 / 2)(x^2 - y^2), so 2 / (4 pi k2)."""

RADIANCE_FACTORS: tuple[float, float, float] = (1.0, 1.0 / (1.0 / 3.0), 1.0 / (2.0 * (1.0 / 15.0)))
"""Reconstruction factors (1, 3, 15/2) of bands 0, 1, 2: 1 / <x, x> = 3, 1 / (2 <xy, xy>) = 15/2."""

_A: tuple[float, ...] = tuple(float(a) / math.pi for a in sh.cosine_lobe(3))  # A_l / pi, l = 0, 1, 2
IRRADIANCE_FACTORS: tuple[float, float, float] = (
    RADIANCE_FACTORS[0] * _A[0], RADIANCE_FACTORS[1] * _A[1], RADIANCE_FACTORS[2] * _A[2]
)
"""Irradiance (E / pi) factors (1, 2, 15/8): RADIANCE_FACTORS times A_l / pi (1, 2/3, 1/4)."""

ANTIPODAL_FACTOR: float = 2.0 * IRRADIANCE_FACTORS[1]
"""I(n) - I(-n) = 4 n.R1: the odd part of I is its L1 term 2 R1.n, exact for any radiance (seed 003)."""

GEOMERICS_EXPONENT_ENDS: tuple[float, float] = (1.0, ANTIPODAL_FACTOR - 1.0)
"""Exponent p of the non-linear L1 at r = 0 (1: the linear limit) and r = 1 (3: a = 0 with
(1 - a)(p + 1) = 4 r); p is linear in between: p = 1 + 2 r (docs/hazel.md, step 3)."""

MAX_BANDS: int = 3
"""Bands of Hazel's basis (B0, B1, B2): K = 1, 4 or 9 orthonormal coefficients."""

SYMMETRY_TOLERANCE: float = 1e-9
"""Relative asymmetry or trace of R2 (to its largest entry) accepted by :func:`from_normalised`:
far above rounding (1e-16), far below any meaningful L2 term."""


# --------------------------------------------------------------------------- #
# Basis change
# --------------------------------------------------------------------------- #
def to_normalised(coeffs: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """
    Orthonormal (Condon-Shortley) SH -> Hazel's normalised (R0, R1, R2) (table in docs/hazel.md).

    Parameters
    ----------
    coeffs
        Shape (K,), (K, C) or (..., K, C), K = 1, 4 or 9 (bands <= 3), any unit
        (cd/m^2 for radiance).

    Returns
    -------
    R0 : ndarray
        (..., C): the mean over the sphere, same unit.
    R1 : ndarray
        (..., C, 3): the (x, y, z) vector ``<R, w>``; zero when K = 1.
    R2 : ndarray
        (..., C, 3, 3): symmetric traceless ``<R, w w^T - I / 3>``; zero when
        K < 9.

    For a (K,) input the C axis is dropped: R0 (), R1 (3,), R2 (3, 3).

    Examples
    --------
    >>> c = np.zeros(4); c[0] = 2.0 * math.sqrt(math.pi); c[2] = math.sqrt(3.0 * math.pi)
    >>> r0, r1, r2 = to_normalised(c)   # the radiance 1 + 1.5 z: mean 1, L1 vector z / 2
    >>> round(float(r0), 12), [round(float(v), 12) + 0.0 for v in r1]
    (1.0, [0.0, 0.0, 0.5])
    """
    c, vector, _ = check_coeffs(coeffs, high=MAX_BANDS)
    r0, r1, r2 = _to_normalised(c)
    if vector:
        return r0[..., 0], r1[..., 0, :], r2[..., 0, :, :]
    return r0, r1, r2


def _to_normalised(c: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    k = c.shape[-2]
    r0 = L0_SCALE * c[..., 0, :]
    r1 = np.zeros(r0.shape + (3,))
    r2 = np.zeros(r0.shape + (3, 3))
    if k >= 4:  # R1 = L1_SCALE (-c3, -c1, c2)
        r1[...] = L1_SCALE * np.stack([-c[..., 3, :], -c[..., 1, :], c[..., 2, :]], axis=-1)
    if k >= 9:
        zz = L2_ZZ_SCALE * c[..., 6, :]
        diff = L2_XX_MINUS_YY_SCALE * c[..., 8, :]
        r2[..., 0, 0] = 0.5 * (diff - zz)
        r2[..., 1, 1] = -0.5 * (diff + zz)
        r2[..., 2, 2] = zz
        r2[..., 0, 1] = r2[..., 1, 0] = L2_OFF_DIAGONAL_SCALE * c[..., 4, :]
        r2[..., 1, 2] = r2[..., 2, 1] = -L2_OFF_DIAGONAL_SCALE * c[..., 5, :]
        r2[..., 0, 2] = r2[..., 2, 0] = -L2_OFF_DIAGONAL_SCALE * c[..., 7, :]
    return r0, r1, r2


def from_normalised(R0: ArrayLike, R1: ArrayLike | None = None, R2: ArrayLike | None = None) -> NDArray[np.float64]:
    """
    Hazel's normalised (R0, R1, R2) -> orthonormal (Condon-Shortley) SH.

    Parameters
    ----------
    R0
        Shape (..., C) (or () for one channel): the mean.
    R1
        Shape (..., C, 3) or None: the (x, y, z) L1 vector.
    R2
        Shape (..., C, 3, 3) or None: symmetric and traceless (within
        :data:`SYMMETRY_TOLERANCE` of its largest entry). Needs R1.

    Returns
    -------
    ndarray
        (..., K, C) with K = 1, 4 or 9 as R1 and R2 are given (a () R0 gives (K,));
        empty batches give empty results.
    """
    r0 = as_float_array(R0, "R0")
    check_size(9 * r0.size, "R0")
    if R1 is None and R2 is not None:
        raise ValueError("R2 needs R1 (pass zeros for R1 if the L1 band is zero)")
    k = 1 if R1 is None else (4 if R2 is None else 9)
    out = np.zeros(r0.shape[:-1] + (k,) + r0.shape[-1:]) if r0.ndim else np.zeros(k)
    rows = out if r0.ndim == 0 else np.moveaxis(out, -2, 0)  # coefficient-first view of ``out``
    rows[0] = r0 / L0_SCALE
    if R1 is not None:
        r1 = as_float_array(R1, "R1")
        if r1.shape != r0.shape + (3,):
            raise ValueError(f"R1 must have shape R0.shape + (3,) = {r0.shape + (3,)}, got {r1.shape}")
        rows[1] = -r1[..., 1] / L1_SCALE
        rows[2] = r1[..., 2] / L1_SCALE
        rows[3] = -r1[..., 0] / L1_SCALE
    if R2 is not None:
        r2 = as_float_array(R2, "R2")
        if r2.shape != r0.shape + (3, 3):
            raise ValueError(f"R2 must have shape R0.shape + (3, 3) = {r0.shape + (3, 3)}, got {r2.shape}")
        if r2.size:
            scale = np.abs(r2).max(axis=(-1, -2))
            asym = np.abs(r2 - np.swapaxes(r2, -1, -2)).max(axis=(-1, -2))
            trace = np.abs(np.trace(r2, axis1=-2, axis2=-1))
            if np.any(asym > SYMMETRY_TOLERANCE * scale) or np.any(trace > SYMMETRY_TOLERANCE * scale):
                raise ValueError(f"R2 must be symmetric and traceless (within {SYMMETRY_TOLERANCE:g} of its largest entry)")
        rows[4] = r2[..., 0, 1] / L2_OFF_DIAGONAL_SCALE
        rows[5] = -r2[..., 1, 2] / L2_OFF_DIAGONAL_SCALE
        rows[6] = r2[..., 2, 2] / L2_ZZ_SCALE
        rows[7] = -r2[..., 0, 2] / L2_OFF_DIAGONAL_SCALE
        rows[8] = (r2[..., 0, 0] - r2[..., 1, 1]) / L2_XX_MINUS_YY_SCALE
    return out


# --------------------------------------------------------------------------- #
# Reconstruction
# --------------------------------------------------------------------------- #
def _checked(coeffs: ArrayLike, dirs: ArrayLike, name: str) -> tuple[NDArray, bool, NDArray]:
    """Checked coefficients (..., K, C), whether they came as one (K,) vector, and directions (..., 3) named
    ``name``, whose batch axes broadcast together (the broadcast result size-checked)."""
    c, vector, _ = check_coeffs(coeffs, high=MAX_BANDS)
    d = check_dirs(dirs, name)
    try:
        shape = np.broadcast_shapes(c.shape[:-2], d.shape[:-1])
    except ValueError:
        raise ValueError(f"the batch axes of coeffs {c.shape[:-2]} and of {name} {d.shape[:-1]} "
                         "must broadcast together") from None
    check_size(int(np.prod(shape, dtype=np.float64)) * c.shape[-1] * 9, name, "the broadcast result")
    return c, vector, d


def _reconstruct(coeffs: ArrayLike, dirs: ArrayLike, factors: tuple[float, float, float], name: str) -> NDArray:
    c, vector, d = _checked(coeffs, dirs, name)
    r0, r1, r2 = _to_normalised(c)
    w = d[..., None, :]  # (..., 1, 3) against the channel axis
    out = r0 + factors[1] * np.sum(r1 * w, axis=-1)
    if c.shape[-2] == 9:
        out = out + factors[2] * np.einsum("...i,...ij,...j->...", w, r2, w)
    return out[..., 0] if vector else out


def radiance(coeffs: ArrayLike, dirs: ArrayLike) -> NDArray[np.float64]:
    """
    Radiance in Hazel's form, ``R0 + 3 R1.w + (15/2) w R2 w``.

    Parameters
    ----------
    coeffs
        Orthonormal SH, shape (K,), (K, C) or (..., K, C), K = 1, 4 or 9.
    dirs
        Unit vectors (..., 3). The batch axes of ``coeffs`` (all but the last
        two) and of ``dirs`` (all but the last) broadcast: coefficients (9, C)
        with dirs (M, 3) give (M, C); (P, 1, 9, C) with (M, 3) give (P, M, C).
        An empty batch gives an empty result.

    Returns
    -------
    ndarray
        (broadcast batch..., C), or without C for a (K,) input; the unit of the
        coefficients. Equal to ``skysh.sh.basis.evaluate`` to rounding.
    """
    return _reconstruct(coeffs, dirs, RADIANCE_FACTORS, "dirs")


def irradiance(coeffs: ArrayLike, normals: ArrayLike) -> NDArray[np.float64]:
    """
    Irradiance ``I(n) = R0 + 2 R1.n + (15/8) n R2 n`` of radiance SH (seed 003).

    Parameters
    ----------
    coeffs
        Orthonormal **radiance** SH, shape (K,), (K, C) or (..., K, C), K = 1,
        4 or 9. K = 4 is the linear L1 irradiance.
    normals
        Unit vectors (..., 3); batch axes broadcast as in :func:`radiance`.

    Returns
    -------
    ndarray
        ``I = E / pi`` (E the clamped-cosine integral of docs/conventions.md): the
        radiance of a white Lambertian surface, in the coefficients' unit
        (cd/m^2 for sky radiance). Equal to ``sh.evaluate(sh.irradiance(c)) /
        pi`` to rounding. Negative where the band-limited irradiance rings.
    """
    return _reconstruct(coeffs, normals, IRRADIANCE_FACTORS, "normals")


def geomerics_parameters(coeffs: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """
    Per-probe constants of the non-linear L1 irradiance (docs/hazel.md, steps 1-4).

    Parameters
    ----------
    coeffs
        Orthonormal radiance SH, (K,), (K, C) or (..., K, C), K = 4 or 9 (only
        the first four are used).

    Returns
    -------
    dict
        ``"R0"`` (..., C); ``"direction"`` (..., C, 3) = R1 / |R1| (zero where
        R1 = 0); ``"r"`` = |R1| / R0 clamped to [0, 1] (0 where R0 <= 0);
        ``"p"`` = 1 + 2 r; ``"a"`` = (1 - r) / (1 + r). Values above 1 of
        |R1| / R0 come from no non-negative radiance; clamping keeps the
        result non-negative when R0 >= 0.
    """
    c, vector, _ = check_coeffs(coeffs, high=MAX_BANDS, low=2)  # the L1 reconstruction needs R1
    r0, r1, _ = _to_normalised(c[..., :4, :])
    length = np.linalg.norm(r1, axis=-1)
    direction = r1 / np.where(length > 0.0, length, 1.0)[..., None]
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(r0 > 0.0, np.clip(length / np.where(r0 > 0.0, r0, 1.0), 0.0, 1.0), 0.0)
    p0, p1 = GEOMERICS_EXPONENT_ENDS
    p = p0 + (p1 - p0) * r
    a = 1.0 - ANTIPODAL_FACTOR * r / (p + 1.0)
    result = {"R0": r0, "direction": direction, "r": r, "p": p, "a": a}
    if vector:
        result = {key: value[..., 0, :] if key == "direction" else value[..., 0] for key, value in result.items()}
    return result


def irradiance_l1_nonlinear(coeffs: ArrayLike, normals: ArrayLike) -> NDArray[np.float64]:
    """
    Non-linear L1 irradiance of Geomerics: ``R0 [a + (1 - a)(1 + p) q^p]``, never negative.

    Parameters
    ----------
    coeffs
        Orthonormal radiance SH, (K,), (K, C) or (..., K, C), K = 4 or 9 (the L2
        band is ignored).
    normals
        Unit vectors (..., 3); batch axes broadcast as in :func:`radiance`.

    Returns
    -------
    ndarray
        ``I = E / pi`` in the coefficients' unit, with ``q = (1 + n.d) / 2``,
        ``r = |R1| / R0``, ``p = 1 + 2 r``, ``a = (1 - r) / (1 + r)`` (derivation
        in docs/hazel.md). Non-negative whenever R0 >= 0; equals R0
        where R1 = 0. Mean over the sphere R0, ``I(d) - I(-d) = 4 |R1|``.

    Notes
    -----
    The model is built for light that is directional but arrives from all
    around (r interpolates a uniform light, r = 0, and one delta, r = 1). On
    light from one hemisphere, as a sky, it lights normals facing away from it:
    docs/hazel.md works the uniform upper hemisphere, where the linear L1 is exact.
    """
    c, vector, n = _checked(coeffs, normals, "normals")
    g = geomerics_parameters(c)
    q = np.clip(0.5 + 0.5 * np.sum(g["direction"] * n[..., None, :], axis=-1), 0.0, 1.0)
    a, p = g["a"], g["p"]
    out = g["R0"] * (a + (1.0 - a) * (1.0 + p) * q**p)
    return out[..., 0] if vector else out
