"""
The normalised SH basis of Hazel (Geomerics) and the non-linear L1 irradiance
==============================================================================

Hazel's basis drops the constant factors of the orthonormal SH by using the
normalised inner product ``<R, S> = (1 / 4 pi) integral R S dw`` and the
unnormalised functions

    B0 = 1,   B1 = (x, y, z),   B2_ij = w_i w_j - delta_ij / 3,

so a radiance ``R`` has a mean ``R0 = <R, 1>``, a vector ``R1 = <R, w>`` (its
average direction, ``|R1| <= R0``) and a symmetric traceless 3x3 matrix
``R2_ij = <R, w_i w_j - delta_ij / 3>`` per colour channel.

-   :func:`to_normalised`, :func:`from_normalised`: our orthonormal (Condon-
    Shortley) coefficients <-> (R0, R1, R2).
-   :func:`radiance`: ``R0 + 3 R1.w + (15/2) w R2 w``.
-   :func:`irradiance`: ``I(n) = R0 + 2 R1.n + (15/8) n R2 n``, the seed's
    irradiance ``I = E / pi`` (E the cosine-weighted integral of docs/conventions.md;
    I is the radiance leaving a white Lambertian surface).
-   :func:`geomerics_parameters`, :func:`irradiance_l1_nonlinear`: the
    non-linear L1 irradiance of Geomerics (CEDEC 2015), which is never negative.
-   :func:`exact_irradiance`: the irradiance I of the true (not band-limited)
    Preetham sky.
-   :func:`irradiance_comparison`, :func:`irradiance_experiment`: accuracy
    against the sky's exact irradiance and cost of linear L1, non-linear L1,
    L2 and deringed L2.

Conversion at the boundary (Condon-Shortley signs)
--------------------------------------------------
With ``c_i = integral R Y_i dw`` and the table of docs/conventions.md
(``Y(1, -1) = -k1 y``, ``Y(1, 0) = k1 z``, ``Y(1, 1) = -k1 x``, ``k1 =
sqrt(3) / (2 sqrt(pi))``; ``Y(2, -2) = k2 x y``, ``Y(2, -1) = -k2 y z``,
``Y(2, 1) = -k2 x z``, ``Y(2, 2) = (k2 / 2)(x^2 - y^2)``, ``Y(2, 0) = (3
sqrt(5) / (4 sqrt(pi))) (z^2 - 1/3)``, ``k2 = sqrt(15) / (2 sqrt(pi))``):

    R0     =  c0 / (2 sqrt(pi))
    R1     =  (-c3, -c1, c2) / (2 sqrt(3 pi))                 (x, y, z)
    R2_xy  =  c4 / (2 sqrt(15 pi)),   R2_yz = -c5 / (2 sqrt(15 pi)),
    R2_xz  = -c7 / (2 sqrt(15 pi)),   R2_zz =  c6 / (3 sqrt(5 pi)),
    R2_xx - R2_yy = c8 / sqrt(15 pi),  R2_xx + R2_yy = -R2_zz.

The minus signs are the Condon-Shortley phase: Hazel's basis is in plain x, y,
z, ours carries (-1)^m on m = +-1.

Reconstruction constants
------------------------
``R(w) = R0 + 3 R1.w + (15/2) w R2 w`` because the sphere averages are
``<x, x> = 1/3`` (factor 3) and ``<x y, x y> = 1/15`` with ``x y`` appearing
twice in ``w R2 w`` (factor 15/2). Irradiance multiplies band l by ``A_l / pi``
(1, 2/3, 1/4): 1, 2, 15/8. Both routes are exactly the orthonormal ones
(``skysh.sh.evaluate`` and ``skysh.sh.irradiance``, divided by pi).

The Geomerics non-linear L1 irradiance, derived in this basis
--------------------------------------------------------------
Given only R0 and R1 (r = |R1| / R0 in [0, 1], d = R1 / |R1|), model the
irradiance as a function of ``q = (1 + n.d) / 2`` in [0, 1]:

    I(n) = R0 (a + b q^p).

1.  Energy: the sphere average of I must be R0 (``I_0 = R0``). As n.d is
    uniform on [-1, 1] over the sphere (Archimedes), q is uniform on [0, 1]
    and the average of q^p is 1 / (p + 1): ``a + b / (p + 1) = 1``, so
    ``b = (1 - a)(p + 1)``.
2.  Antipodal difference: Hazel's identity ``n.R1 = (I(n) - I(-n)) / 4``
    holds for the *exact* irradiance; impose it at n = d:
    ``I(d) - I(-d) = R0 b = 4 |R1|``, so ``(1 - a)(p + 1) = 4 r``.
3.  The exponent: r = 0 (uniform light) must give the constant R0, which with
    (2) means a = 1 and, to match the linear L1 at first order in r, p = 1.
    r = 1 is a single directional light, whose exact irradiance vanishes on
    the far side: I(-d) = R0 a = 0, so a = 0 and (2) gives p + 1 = 4, p = 3.
    Geomerics interpolate the exponent linearly between these two exact ends:
    **p = 1 + 2 r**.
4.  Then (2) gives **a = 1 - 4 r / (p + 1) = (1 - r) / (1 + r)** and
    ``b = (1 - a)(p + 1) = 4 r``.

So ``I(n) = R0 [a + (1 - a)(1 + p) q^p]``, which is the published shader (Enlighten
SDK, "Light probe evaluation"; the CEDEC 2015 talk). It is non-negative for
every r in [0, 1] (a >= 0, q^p >= 0), keeps the mean R0 exactly and the
antipodal difference along d exactly, and tends to the linear ``R0 + 2 R1.n``
as r -> 0. It does not keep the L1 moment exactly: its ``<I, n>`` is
``R0 (1 - a) p / (p + 2) d``, ``6 p / ((p + 1)(p + 2))`` times the exact
``(2/3) R1`` (1 at r = 0 and r = 1/2, 0.9 at r = 1). The linear L1 goes negative once
r > 1/2 (``R0 - 2 |R1| < 0``). In our coefficients ``r = |(c1, c2, c3)| /
(sqrt(3) c0)`` (the prior quantization bound sqrt(3) of ``skysh.quantize``
makes r <= 1 for non-negative radiance).

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
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import sh
from skysh._checks import as_float_array, check_bands, check_dirs

__all__ = [
    "L0_SCALE",
    "L1_SCALE",
    "L2_OFF_DIAGONAL_SCALE",
    "L2_ZZ_SCALE",
    "L2_XX_MINUS_YY_SCALE",
    "RADIANCE_FACTORS",
    "IRRADIANCE_FACTORS",
    "ANTIPODAL_FACTOR",
    "GEOMERICS_EXPONENT_ENDS",
    "SYMMETRY_TOLERANCE",
    "EXACT_BANDS",
    "COMPARISON_THETA_NODES",
    "METHODS",
    "COSTS",
    "to_normalised",
    "from_normalised",
    "radiance",
    "irradiance",
    "geomerics_parameters",
    "irradiance_l1_nonlinear",
    "exact_irradiance",
    "irradiance_comparison",
    "irradiance_experiment",
]

_SQRT_PI: float = math.sqrt(math.pi)

L0_SCALE: float = 1.0 / (2.0 * _SQRT_PI)
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

IRRADIANCE_FACTORS: tuple[float, float, float] = tuple(
    float(f * a / math.pi) for f, a in zip(RADIANCE_FACTORS, sh.cosine_lobe(3))
)
"""Irradiance (E / pi) factors (1, 2, 15/8): RADIANCE_FACTORS times A_l / pi (1, 2/3, 1/4)."""

ANTIPODAL_FACTOR: float = 2.0 * IRRADIANCE_FACTORS[1]
"""I(n) - I(-n) = 4 n.R1: the odd part of I is its L1 term 2 R1.n, exact for any radiance (seed 003)."""

GEOMERICS_EXPONENT_ENDS: tuple[float, float] = (1.0, ANTIPODAL_FACTOR - 1.0)
"""Exponent p of the non-linear L1 at r = 0 (1: the linear limit) and r = 1 (3: a = 0 with
(1 - a)(p + 1) = 4 r); p is linear in between: p = 1 + 2 r (module docstring, step 3)."""

SYMMETRY_TOLERANCE: float = 1e-9
"""Relative asymmetry or trace of R2 (to its largest entry) accepted by :func:`from_normalised`:
far above rounding (1e-16), far below any meaningful L2 term."""

EXACT_BANDS: int = 32
"""Bands of the sky projection behind :func:`exact_irradiance`. Against an independent adaptive
quadrature of the true sky over the lune {z >= 0, n.w >= 0} (tests/test_hazel.py) 32 bands agree to
2e-5 .. 3e-5 of the mean irradiance R0 (16 bands: 2.5e-4 .. 4e-4). Against 40 bands, over 1152 normals
and the sun from zenith to horizon, the worst normal is off by 2.4e-4 at 32 bands and 2.2e-3 at 16
(near-horizontal normals, low sun): the sky's horizon step makes its coefficients decay slowly, so
``A_l L_l`` falls only like about l^-2.6 although A_l ~ l^-2.5."""

COMPARISON_THETA_NODES: int = 24
"""Gauss nodes in cos(theta) of the normals of :func:`irradiance_comparison` (2 * 24^2 = 1152 normals,
area-weighted)."""

METHODS: tuple[str, ...] = ("L1 linear", "L1 non-linear (Geomerics)", "L2", "L2 deringed")
"""Rows of :func:`irradiance_comparison`."""

COSTS: dict[str, dict[str, Any]] = {
    "L1 linear": {
        "floats_per_channel": 4,
        "alu_per_normal": 3,
        "transcendental_per_normal": 0,
        "per_probe": "fold 2 R1 (3 mul)",
    },
    "L1 non-linear (Geomerics)": {
        "floats_per_channel": 4,
        "alu_per_normal": 6,
        "transcendental_per_normal": 2,
        "per_probe": "|R1|, d, r, p, a, R0 a, R0 (1-a)(1+p): 1 sqrt, 2 div, ~10 ALU",
    },
    "L2": {
        "floats_per_channel": 9,
        "alu_per_normal": 8,
        "transcendental_per_normal": 0,
        "per_probe": "fold the factors into the 9 coefficients (9 mul)",
    },
    "L2 deringed": {
        "floats_per_channel": 9,
        "alu_per_normal": 8,
        "transcendental_per_normal": 0,
        "per_probe": "dering window search (skysh.dering), then as L2",
    },
}
"""Hand-counted shader cost per normal and colour channel (multiply-adds; transcendental = sqrt, log2,
exp2), with per-probe work done once. L1 linear: ``R0 + (2 R1).n``, 3 FMA. Non-linear L1 with d, p,
A = R0 a, B = R0 (1 - a)(1 + p) per probe: ``t = d.n`` (3), ``q = 0.5 t + 0.5`` (1), ``q^p = exp2(p
log2 q)`` (1 mul, 2 transcendental), ``A + B q^p`` (1): 6 ALU, 2 transcendental (the Enlighten shader
recomputes the per-probe part per pixel: add 1 sqrt, 2 div, ~10 ALU). L2: 5 quadratic monomials
shared by the channels (xy, yz, xz, (x - y)(x + y), z^2: 6 ALU per normal), then 3 + 5 FMA per channel."""


# --------------------------------------------------------------------------- #
# Basis change
# --------------------------------------------------------------------------- #
def _check_coeffs(coeffs: ArrayLike, name: str = "coeffs") -> tuple[NDArray[np.float64], bool]:
    """(..., K, C) float array with K in {1, 4, 9}, and whether the input was a (K,) vector."""
    c = as_float_array(coeffs, name)
    vector = c.ndim == 1
    if vector:
        c = c[:, None]
    if c.ndim < 2 or c.shape[-2] not in (1, 4, 9):
        raise ValueError(
            f"{name} must have shape (K,), (K, C) or (..., K, C) with K in (1, 4, 9) (bands <= 3), got {c.shape}"
        )
    return c, vector


def to_normalised(coeffs: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """
    Orthonormal (Condon-Shortley) SH -> Hazel's normalised (R0, R1, R2).

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
    c, vector = _check_coeffs(coeffs)
    r0, r1, r2 = _to_normalised(c)
    if vector:
        return r0[..., 0], r1[..., 0, :], r2[..., 0, :, :]
    return r0, r1, r2


def _to_normalised(c: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    k = c.shape[-2]
    r0 = L0_SCALE * c[..., 0, :]
    r1 = np.zeros(r0.shape + (3,))
    r2 = np.zeros(r0.shape + (3, 3))
    if k >= 4:
        r1[..., 0] = -L1_SCALE * c[..., 3, :]
        r1[..., 1] = -L1_SCALE * c[..., 1, :]
        r1[..., 2] = L1_SCALE * c[..., 2, :]
    if k >= 9:
        xy = L2_OFF_DIAGONAL_SCALE * c[..., 4, :]
        yz = -L2_OFF_DIAGONAL_SCALE * c[..., 5, :]
        xz = -L2_OFF_DIAGONAL_SCALE * c[..., 7, :]
        zz = L2_ZZ_SCALE * c[..., 6, :]
        diff = L2_XX_MINUS_YY_SCALE * c[..., 8, :]
        r2[..., 0, 0] = 0.5 * (diff - zz)
        r2[..., 1, 1] = -0.5 * (diff + zz)
        r2[..., 2, 2] = zz
        r2[..., 0, 1] = r2[..., 1, 0] = xy
        r2[..., 1, 2] = r2[..., 2, 1] = yz
        r2[..., 0, 2] = r2[..., 2, 0] = xz
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
        (..., K, C) with K = 1, 4 or 9 as R1 and R2 are given (a () R0 gives (K,)).
    """
    r0 = as_float_array(R0, "R0")
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
                raise ValueError(
                    f"R2 must be symmetric and traceless (within {SYMMETRY_TOLERANCE:g} of its largest entry)"
                )
        rows[4] = r2[..., 0, 1] / L2_OFF_DIAGONAL_SCALE
        rows[5] = -r2[..., 1, 2] / L2_OFF_DIAGONAL_SCALE
        rows[6] = r2[..., 2, 2] / L2_ZZ_SCALE
        rows[7] = -r2[..., 0, 2] / L2_OFF_DIAGONAL_SCALE
        rows[8] = (r2[..., 0, 0] - r2[..., 1, 1]) / L2_XX_MINUS_YY_SCALE
    return out


# --------------------------------------------------------------------------- #
# Reconstruction
# --------------------------------------------------------------------------- #
def _reconstruct(coeffs: ArrayLike, dirs: ArrayLike, factors: tuple[float, float, float], name: str) -> NDArray:
    c, vector = _check_coeffs(coeffs)
    d = check_dirs(dirs, name)
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

    Returns
    -------
    ndarray
        (broadcast batch..., C), or without C for a (K,) input; the unit of the
        coefficients. Equal to ``skysh.sh.evaluate`` to rounding.
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
    Per-probe constants of the non-linear L1 irradiance (module docstring, steps 1-4).

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
    c, vector = _check_coeffs(coeffs)
    if c.shape[-2] < 4:
        raise ValueError(f"coeffs must have K = 4 or 9 coefficients for the L1 reconstruction, got {c.shape}")
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
        in the module docstring). Non-negative whenever R0 >= 0; equals R0
        where R1 = 0. Mean over the sphere R0, ``I(d) - I(-d) = 4 |R1|``.

    Notes
    -----
    The model is built for light that is directional but arrives from all
    around (r between 0 and 1 interpolating a uniform light and one delta).
    A sky is light from one hemisphere: a uniform upper hemisphere of radiance
    L has R0 = L / 2, R1 = (L / 4) z, r = 1/2, and its exact irradiance
    ``L (1 + n_z) / 2`` *is* the linear L1 ``R0 + 2 R1.n``, whereas this model
    (a = 1/3, p = 2) gives ``L (1/6 + q^2)``: 7L/6 at the zenith and L/6 facing
    straight down, where the sky gives nothing.
    """
    c, vector = _check_coeffs(coeffs)
    n = check_dirs(normals, "normals")
    g = geomerics_parameters(c)
    q = np.clip(0.5 + 0.5 * np.sum(g["direction"] * n[..., None, :], axis=-1), 0.0, 1.0)
    a, p = g["a"], g["p"]
    out = g["R0"] * (a + (1.0 - a) * (1.0 + p) * q**p)
    return out[..., 0] if vector else out


# --------------------------------------------------------------------------- #
# The sky's exact irradiance and the comparison
# --------------------------------------------------------------------------- #
def _sky_coefficients(ts: NDArray, t: NDArray, az: NDArray, bands: int) -> NDArray:
    """(P, bands^2, 3) reference projections; a loop because skysh.preetham.sky_sh takes scalars."""
    from skysh import preetham

    return np.stack(
        [preetham.sky_sh(float(a), float(b), bands=bands, sun_azimuth=float(g)) for a, b, g in zip(ts, t, az)]
    )


def exact_irradiance(
    sun_zenith: float,
    turbidity: float,
    normals: ArrayLike,
    sun_azimuth: float = 0.0,
    bands: int = EXACT_BANDS,
) -> NDArray[np.float64]:
    """
    Irradiance ``I = E / pi`` of the true Preetham sky (not band-limited).

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2].
    turbidity
        [1.7, 10] (the model's domain; the runtime covers [2.5, 6]).
    normals
        Unit vectors (..., 3).
    sun_azimuth
        Radians.
    bands
        Bands of the projection, [2, 64]; default :data:`EXACT_BANDS`.

    Returns
    -------
    ndarray
        (..., 3) linear sRGB, cd/m^2.

    Notes
    -----
    Computed as ``sum_lm (A_l / pi) L_lm Y_lm(n)`` with ``L_lm`` from
    :func:`skysh.preetham.sky_sh` at ``bands`` bands. The clamped-cosine factors
    fall like l^-2.5 but the sky's coefficients fall slowly (it jumps to zero
    at the horizon), so the series converges only like about l^-2.6: the error at
    32 bands is about 3e-5 of the mean irradiance (checked against a direct
    adaptive quadrature in the tests), at 16 bands up to 2e-3. A direct
    quadrature of ``L max(0, n.w)`` is the other route but needs a rule per
    normal to resolve the kink along n.w = 0.
    """
    check_bands(bands, high=sh.MAX_BANDS)
    if bands < 2:
        raise ValueError(f"bands must be an integer in [2, {sh.MAX_BANDS}], got {bands}")
    from skysh import preetham

    c = preetham.sky_sh(sun_zenith, turbidity, bands=bands, sun_azimuth=sun_azimuth)
    return sh.evaluate(sh.irradiance(c) / math.pi, normals)


def _dering(c9: NDArray) -> tuple[NDArray | None, str]:
    """Deringed radiance SH from skysh.dering if it exists, else (None, why)."""
    try:
        from skysh import dering
    except ImportError as error:
        return None, f"L2 deringed skipped: skysh.dering is not importable ({error})"
    try:
        out, _scales = dering.dering(c9, target="irradiance")
    except (TypeError, AttributeError) as error:  # an API other than dering(coeffs, target=...) -> (coeffs, scales)
        return None, f"L2 deringed skipped: skysh.dering.dering(coeffs, target='irradiance') failed ({error})"
    out = np.asarray(out, dtype=np.float64)
    if out.shape != c9.shape:
        return None, f"L2 deringed skipped: dering returned shape {out.shape} for {c9.shape}"
    return out, "L2 deringed: skysh.dering.dering(coeffs, target='irradiance') (windowed radiance SH), then as L2"


def irradiance_comparison(
    sun_zenith: ArrayLike,
    turbidity: ArrayLike,
    sun_azimuth: ArrayLike = 0.0,
    exact_bands: int = EXACT_BANDS,
    n_theta: int = COMPARISON_THETA_NODES,
) -> dict[str, Any]:
    """
    Accuracy of L1 linear, L1 non-linear, L2 and deringed L2 irradiance against the sky's exact irradiance.

    Parameters
    ----------
    sun_zenith, turbidity, sun_azimuth
        Sky points (radians, radians, turbidity in [1.7, 10]), broadcasting to
        (P,).
    exact_bands
        Bands of the "exact" irradiance (:func:`exact_irradiance`), [10, 64].
    n_theta
        Gauss nodes in cos(theta) of the sphere of normals, >= 2.

    Returns
    -------
    dict
        ``"rows"``: per method (:data:`METHODS`) a dict with ``method``,
        ``mean_abs``, ``rms``, ``max_abs`` (errors over the sphere of normals
        divided by the probe's mean irradiance R0, averaged or maximised over
        points and channels), ``min`` (the smallest I / R0: negative means
        negative irradiance), ``negative_area`` (fraction of the sphere of
        normals with I < 0) and the :data:`COSTS` entries. ``"notes"``: what was
        skipped or assumed. ``"truncation"``: max |I(exact_bands) -
        I(exact_bands - 8)| / R0, an upper estimate of the exact irradiance's
        own error. ``"points"``, ``"exact_bands"``, ``"normals"``.

    Notes
    -----
    All four methods start from the same projection (its first 4 or 9
    coefficients), so the differences are those of the reconstructions, not
    of a fit. Errors are relative to R0 rather than to I(n) because the sky
    gives zero irradiance to a normal pointing straight down. The errors of
    the linear L1 and L2 reconstructions are even, ``e(n) = e(-n)``: by Hazel's
    antipodal identity their odd part (the L1 term) is exact, so the upward
    normals alone would give the same averages. The sky
    projections are computed point by point (about 0.3 s each at 32 bands).
    """
    check_bands(exact_bands, name="exact_bands", high=sh.MAX_BANDS)
    if exact_bands < 10:
        raise ValueError(f"exact_bands must be an integer in [10, {sh.MAX_BANDS}], got {exact_bands}")
    if isinstance(n_theta, bool) or not isinstance(n_theta, (int, np.integer)) or n_theta < 2:
        raise ValueError(f"n_theta must be an integer >= 2, got {n_theta!r}")
    ts, t, az = (np.ravel(a) for a in np.broadcast_arrays(
        as_float_array(sun_zenith, "sun_zenith"), as_float_array(turbidity, "turbidity"),
        as_float_array(sun_azimuth, "sun_azimuth")))
    if ts.size == 0:
        raise ValueError("sun_zenith must hold at least one sky point")
    coeffs = _sky_coefficients(ts, t, az, exact_bands)  # (P, B^2, 3), validated by sky_sh
    normals, weights = sh.quadrature_rule(int(n_theta))
    area = weights / (4.0 * math.pi)
    y = sh.basis(normals, exact_bands)  # (M, B^2)
    irr = sh.irradiance(coeffs) / math.pi
    exact = np.einsum("mk,pkc->pmc", y, irr)
    k_low = (exact_bands - 8) ** 2
    truncated = np.einsum("mk,pkc->pmc", y[:, :k_low], irr[:, :k_low])
    r0 = L0_SCALE * coeffs[:, 0, :]  # (P, C) mean irradiance = mean radiance
    if not np.all(r0 > 0.0):
        raise ValueError("the sky must have a positive mean in every channel")
    scale = r0[:, None, :]
    notes = [f"exact irradiance: {exact_bands}-band projection of the true sky (skysh.preetham.sky_sh)"]
    estimates: dict[str, NDArray] = {
        "L1 linear": irradiance(coeffs[:, None, :4], normals),
        "L1 non-linear (Geomerics)": irradiance_l1_nonlinear(coeffs[:, None, :4], normals),
        "L2": irradiance(coeffs[:, None, :9], normals),
    }
    deringed, note = _dering(coeffs[:, :9])
    notes.append(note)
    if deringed is not None:
        estimates["L2 deringed"] = irradiance(deringed[:, None], normals)
    rows = []
    for method in METHODS:  # four fixed rows, not data
        if method not in estimates:
            continue
        value = estimates[method]
        error = (value - exact) / scale
        rows.append(
            {
                "method": method,
                "mean_abs": float(np.mean(np.einsum("m,pmc->pc", area, np.abs(error)))),
                "rms": float(np.sqrt(np.mean(np.einsum("m,pmc->pc", area, error * error)))),
                "max_abs": float(np.max(np.abs(error))),
                "min": float(np.min(value / scale)),
                "negative_area": float(np.mean(np.einsum("m,pmc->pc", area, (value < 0.0).astype(np.float64)))),
                **COSTS[method],
            }
        )
    return {
        "rows": rows,
        "notes": notes,
        "truncation": float(np.max(np.abs(exact - truncated) / scale)),
        "points": int(ts.size),
        "exact_bands": int(exact_bands),
        "normals": int(normals.shape[0]),
    }


def irradiance_experiment(
    n_points: int = 64,
    seed: int | None = 0,
    exact_bands: int = EXACT_BANDS,
    n_theta: int = COMPARISON_THETA_NODES,
) -> dict[str, Any]:
    """
    :func:`irradiance_comparison` over ``n_points`` sky points spread over the runtime's domain.

    The points are :func:`skysh.quantize.sample_sky_parameters` (sun zenith in
    [0, pi/2], azimuth in [0, 2 pi), turbidity in [2.5, 6]). Returns the
    comparison's dict plus ``"seed"``.
    """
    from skysh.quantize import sample_sky_parameters

    ts, az, t = sample_sky_parameters(n_points, seed)
    result = irradiance_comparison(ts, t, az, exact_bands=exact_bands, n_theta=n_theta)
    result["seed"] = seed
    return result
