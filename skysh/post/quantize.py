"""
Low-precision storage of quadratic SH: divide by DC, quantize, pack
===================================================================

A 9-coefficient SH (bands l <= 2) of a **non-negative** function keeps its DC
term as a float and stores the other eight coefficients divided by DC and by a
bound on that ratio, so that they lie in [-1, 1] whatever the brightness, then
rounds them to ``bits``-bit integers packed into 32-bit words (Wiederien and
Sloan 2024, Listing 1). For 8 bits that is four coefficients per word and two
words per colour channel.

-   :func:`compress`, :func:`decompress`: the codec (seed 002, Listing 1).
-   :func:`ratios`: the coefficients divided by DC and by their bound, the
    values the codec quantizes (|value| <= 1 for non-negative functions).
-   :func:`bounds`: the per-coefficient bound used by ``bound`` and
    ``irradiance``.
-   :func:`words_per_channel`: the packed size for a bit depth.
-   :func:`table3_errors`: the seed's Table 3 (L1, L2 and RMSE of the
    reconstructed radiance and irradiance after compression, prior versus
    tight bound, with and without the square root) for any batch of SH.
-   :class:`QuantizationClampWarning`: issued when a coefficient lies outside
    its bound (then it is clamped; only SH that no non-negative function
    produces can do that).

The bound of ``|c_lm / c_00|`` is ``max |Y_lm / Y_00|`` over the sphere (the
seed's delta-function argument, section 2.2): the **prior** bound sqrt(2 l + 1)
for every coefficient of a band, or the **tight** bound sqrt(15) / 2 for the four
non-zonal quadratics (section 3.2, Table 2). Irradiance coefficients shrink it by
``A_l / A_0``. Field ``j = k - 1`` of coefficient ``k`` sits in word
``j // (32 // bits)``; a field holds ``round(bv (v + 1))``, ``bv = 2^(bits - 1) - 1``.
The derivation of the bounds, the table of words per bit depth, the rounding and
the square-root option are in docs/quantize.md; the measurement on sky data is a
study (``tools/studies/quantize_study.py``).

Conventions: orthonormal real SH with the Condon-Shortley phase (docs/conventions.md),
the same as the seed's Table 1, so no conversion is needed. Coefficient arrays
are (..., 9, C), computed in float64.

References
----------
-   Wiederien, T., Sloan, P.-P. (2024). A Tighter Quantization Bound for the
    Spherical Harmonic Projection of Non-Negative Functions. Technical Memo
    ATVI-TR-24-02 (seed 002): section 2.2 (prior bound), section 3.2 and Table
    2 (tight bound), Table 3 (the error experiment), Listing 1 (the codec).
-   Sloan, P.-P., Silvennoinen, A. (2020). Precomputed Lighting Advances in
    Call of Duty: Modern Warfare. SIGGRAPH course (the prior bound and the
    square-root option, as cited by seed 002).
"""

from __future__ import annotations

import math
import warnings
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_choice, check_coeffs, check_count, check_flag, read_only, short_repr
from skysh.sh import basis as sh

__all__ = ["PRIOR_BOUNDS", "TIGHT_BOUNDS", "IRRADIANCE_FACTORS", "bounds", "ratios", "decompress", "table3_errors"]

BOUND_NAMES: tuple[str, ...] = ("prior", "tight")
"""Names accepted by ``bound``: sqrt(2l + 1) for every coefficient, or sqrt(15)/2 for the non-zonal quadratics."""

BITS_RANGE: tuple[int, int] = (2, 32)
"""Accepted bit depths per coefficient (1 bit leaves no code for zero)."""

DEFAULT_BITS: int = 8
"""The seed's bit depth: four coefficients per 32-bit word."""

BANDS: int = 3
"""Bands handled by the codec (l = 0, 1, 2)."""

N_COEFFS: int = BANDS * BANDS
"""Coefficients per channel handled by the codec (9)."""

_L_OF_K: tuple[int, ...] = tuple(sh.lm(k)[0] for k in range(1, N_COEFFS))
_M_OF_K: tuple[int, ...] = tuple(sh.lm(k)[1] for k in range(1, N_COEFFS))

PRIOR_BOUNDS: NDArray[np.float64] = np.array([math.sqrt(2 * l + 1) for l in _L_OF_K])
"""Prior bound of |c_k / c_0| for k = 1..8: sqrt(2 l + 1) = Y_l0(+Z) / Y_00 (seed eq. in 2.2)."""

TIGHT_BOUNDS: NDArray[np.float64] = np.array([
    # Non-zonal l = 2: max |Y / Y_00| = sqrt(15) max|x y| = sqrt(15) max|x z| = (sqrt(15) / 2) max|x^2 - y^2|,
    # with |x y| <= (x^2 + y^2) / 2 <= 1/2 and |x^2 - y^2| <= 1 on the sphere: sqrt(15) / 2.
    math.sqrt(15.0) * 0.5 if (l == 2 and m != 0) else math.sqrt(2 * l + 1) for l, m in zip(_L_OF_K, _M_OF_K)
])
"""Tight bound of |c_k / c_0| for k = 1..8: sqrt(15)/2 for (2, +-1), (2, +-2), else the prior (seed 3.2)."""

IRRADIANCE_FACTORS: NDArray[np.float64] = np.array([sh.cosine_lobe(3)[l] / sh.cosine_lobe(3)[0] for l in _L_OF_K])
"""A_l / A_0 for k = 1..8 (2/3 for l = 1, 1/4 for l = 2): the seed's ``isIrrad`` factors."""

read_only(PRIOR_BOUNDS, TIGHT_BOUNDS, IRRADIANCE_FACTORS)

CLAMP_TOLERANCE: float = 1e-9
"""Relative overshoot of |c_k / (c_0 bound)| above 1 that is clamped silently: a delta light at a
maximising direction reaches the bound exactly, and float64 rounding of its projection can
exceed it by a few ulps; anything beyond this is reported with :class:`QuantizationClampWarning`."""

_FLOAT_MAX: float = float(np.finfo(np.float64).max)
"""Largest finite float64: decoded coefficients are clipped to +-this (see :func:`decompress`)."""

TABLE3_THETA_NODES: int = 32
"""Gauss nodes in cos(theta) of the sphere rule (2 * 32^2 = 2048 directions) on which
:func:`table3_errors` integrates |error|; the squared error is integrated exactly (it is a
polynomial of degree 4). |error| has kinks, so its rule is not exact: ``tools/quantize_experiment.py``
prints the change at twice the nodes and ``tests/post/test_quantize.py`` bounds it."""


class QuantizationClampWarning(UserWarning):
    """A coefficient exceeded its bound (by more than :data:`CLAMP_TOLERANCE`) and was clamped.

    Only SH that no non-negative function projects to can do that (e.g. a fit or a
    deringed/negative-lobed signal); the stored value is the nearest end of the range.
    """


# --------------------------------------------------------------------------- #
# Checks and helpers
# --------------------------------------------------------------------------- #
def _codec_coeffs(coeffs: ArrayLike) -> NDArray[np.float64]:
    """(..., 9, C) float64: the codec's 3 bands, the channel axis required (:func:`skysh.checks.check_coeffs`)."""
    return check_coeffs(coeffs, high=BANDS, low=BANDS, vector=False)[0]


def _check_bits(bits: int) -> int:
    return check_count(bits, "bits", *BITS_RANGE)


def _layout(bits: int) -> tuple[int, int]:
    """(fields per word, words per channel) of a bit depth."""
    per_word = 32 // bits
    return per_word, -(-(N_COEFFS - 1) // per_word)


@cache
def _used_bits(bits: int) -> NDArray[np.uint64]:
    """Per word, the mask of the bits that hold a field (the rest is zero padding)."""
    used = _pack(np.full(N_COEFFS - 1, (1 << bits) - 1, dtype=np.uint64), bits).astype(np.uint64)  # every field all ones
    read_only(used)
    return used


def words_per_channel(bits: int = DEFAULT_BITS) -> int:
    """
    Number of uint32 words per colour channel that :func:`compress` produces.

    Parameters
    ----------
    bits
        Bits per coefficient, in [2, 32].

    Returns
    -------
    int
        ``ceil(8 / (32 // bits))``: 2 for 8 bits (the seed's layout), 3 for 10,
        4 for 16. The full table is in docs/quantize.md.

    Examples
    --------
    >>> [words_per_channel(b) for b in (4, 8, 10, 16)]
    [1, 2, 3, 4]
    """
    return _layout(_check_bits(bits))[1]


def bounds(bound: str = "tight", irradiance: bool = False) -> NDArray[np.float64]:
    """
    The bound of ``|c_k / c_0|``, k = 1..8, that the codec divides by.

    Parameters
    ----------
    bound
        ``"prior"`` (sqrt(3) for l = 1, sqrt(5) for l = 2) or ``"tight"``
        (sqrt(15)/2 for the four non-zonal quadratic coefficients).
    irradiance
        Coefficients are irradiance (clamped-cosine convolved radiance): multiply
        by A_l / A_0 (2/3 for l = 1, 1/4 for l = 2).

    Returns
    -------
    ndarray
        Shape (8,), dimensionless, in the coefficient order k = 1..8.
    """
    irradiance = check_flag(irradiance, "irradiance")
    check_choice(bound, "bound", BOUND_NAMES)
    b = PRIOR_BOUNDS if bound == "prior" else TIGHT_BOUNDS
    return b * IRRADIANCE_FACTORS if irradiance else b.copy()


def ratios(coeffs: ArrayLike, bound: str = "tight", irradiance: bool = False) -> NDArray[np.float64]:
    """
    Coefficients 1..8 divided by DC and by their bound: the values the codec stores.

    Parameters
    ----------
    coeffs
        SH with bands l <= 2, shape (9, C) or (..., 9, C), any unit.
    bound, irradiance
        As in :func:`compress`.

    Returns
    -------
    ndarray
        Shape (..., 8, C), dimensionless. For the coefficients of any non-negative
        (or any non-positive) function every value is in [-1, 1]. Where DC is zero
        the value is 0 if the coefficient is zero too, else +-inf (not finite:
        such SH come from no non-negative function; :func:`compress` clamps them).
    """
    irradiance = check_flag(irradiance, "irradiance")
    return _ratios(_codec_coeffs(coeffs), bounds(bound, irradiance))


def _ratios(c: NDArray, scale: NDArray) -> NDArray:
    dc = c[..., :1, :]
    rest = c[..., 1:, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        v = (rest / dc) / scale[:, None]  # not rest / (dc * scale): dc * scale overflows for dc near 1e308
    # 0 / 0 (zero function): store exactly zero; x / 0 with x != 0 stays +-inf and is clamped.
    return np.where(dc == 0.0, np.where(rest == 0.0, 0.0, np.copysign(np.inf, rest)), v)


# --------------------------------------------------------------------------- #
# The codec
# --------------------------------------------------------------------------- #
def compress(
    coeffs: ArrayLike, bits: int = DEFAULT_BITS, bound: str = "tight", sqrt: bool = False, irradiance: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.uint32]]:
    """
    Compress 9-coefficient SH: DC as a float, the rest as ``bits``-bit codes (Listing 1).

    Parameters
    ----------
    coeffs
        Shape (9, C) or (..., 9, C): SH (l <= 2) of a non-negative function, any
        unit (cd/m^2 for sky radiance).
    bits
        Bits per coefficient, in [2, 32]; 8 is the seed's (two words per channel).
    bound
        ``"tight"`` (default; sqrt(15)/2 for the non-zonal quadratics) or
        ``"prior"`` (sqrt(2l + 1) throughout).
    sqrt
        Store ``sign(v) sqrt(|v|)`` (finer steps near zero, coarser near +-1).
    irradiance
        ``coeffs`` are irradiance coefficients (``sh.irradiance`` of a radiance):
        the bounds are multiplied by A_l / A_0 (2/3, 1/4).

    Returns
    -------
    dc : ndarray
        Shape (..., C), float64, the DC coefficients unchanged.
    words : ndarray
        Shape (..., C, W), uint32, ``W = words_per_channel(bits)`` (2 for 8
        bits); layout in docs/quantize.md (for 8 bits: word 0 holds
        coefficients 1, 2, 3, 4 in bits 0-7, 8-15, 16-23, 24-31, word 1 holds
        5, 6, 7, 8).

    Warns
    -----
    QuantizationClampWarning
        If any ``|c_k / (c_0 bound_k)|`` exceeds 1 by more than
        :data:`CLAMP_TOLERANCE` (only SH of no non-negative function do): the
        value is clamped to +-1 and the count and the worst ratio reported.

    Notes
    -----
    The maximum error of a decoded coefficient is half a step times its bound
    times |DC|: ``|c'_k - c_k| <= |c_0| bound_k / (2 bv)``, ``bv = 2^(bits-1) - 1``
    (without ``sqrt``). Listing 1 of the seed multiplies ``sh[4]`` by ``nz`` in
    a three-component ``vec4(lc, lc, nz)`` (a typo: its decoder uses ``(lc, lc,
    lc, nz)``); this follows the decoder.

    Examples
    --------
    >>> c = np.zeros((9, 1)); c[0] = 1.0; c[2] = 0.5   # DC and Y(1, 0)
    >>> dc, words = compress(c)
    >>> words.shape, bool(np.allclose(decompress(dc, words), c, atol=np.sqrt(3) / 254))
    ((1, 2), True)
    """
    sqrt, irradiance = check_flag(sqrt, "sqrt"), check_flag(irradiance, "irradiance")
    c = _codec_coeffs(coeffs)
    bits = _check_bits(bits)
    v = _clamped(_ratios(c, bounds(bound, irradiance)))
    if sqrt:
        v = np.sign(v) * np.sqrt(np.abs(v))
    bv = float((1 << (bits - 1)) - 1)
    codes = np.floor((bv + 0.5) + v * bv).astype(np.uint64)  # 0 .. 2 bv, round to nearest (Listing 1)
    return c[..., 0, :].copy(), _pack(np.moveaxis(codes, -2, -1), bits)  # words: (..., C, 8) -> (..., C, W)


def _clamped(v: NDArray) -> NDArray:
    """The ratios clipped to [-1, 1], with one :class:`QuantizationClampWarning` (to the caller of
    :func:`compress`) when any lies beyond :data:`CLAMP_TOLERANCE`."""
    over = ~(np.abs(v) <= 1.0 + CLAMP_TOLERANCE)
    if over.any():
        worst = float(np.max(np.abs(v[over])))
        warnings.warn(QuantizationClampWarning(f"{int(over.sum())} of {v.size} SH coefficients exceed their bound "
                                               f"(worst |c_k / (c_0 bound)| = {worst:.6g}); clamped to [-1, 1]. "
                                               "No non-negative function has such SH."), stacklevel=3)
    return np.clip(v, -1.0, 1.0)


def _pack(codes: NDArray[np.uint64], bits: int) -> NDArray[np.uint32]:
    per_word, n_words = _layout(bits)
    padded = np.zeros(codes.shape[:-1] + (n_words * per_word,), dtype=np.uint64)
    padded[..., : N_COEFFS - 1] = codes
    shifts = (np.arange(per_word, dtype=np.uint64) * np.uint64(bits))
    fields = padded.reshape(codes.shape[:-1] + (n_words, per_word)) << shifts
    return np.bitwise_or.reduce(fields, axis=-1).astype(np.uint32)


def _unpack(words: NDArray[np.uint64], bits: int) -> NDArray[np.uint64]:
    per_word, n_words = _layout(bits)
    shifts = np.arange(per_word, dtype=np.uint64) * np.uint64(bits)
    mask = np.uint64((1 << bits) - 1)
    fields = (words[..., None] >> shifts) & mask  # (..., W, F)
    return fields.reshape(words.shape[:-1] + (n_words * per_word,))


def decompress(
    dc: ArrayLike, words: ArrayLike, bits: int = DEFAULT_BITS, bound: str = "tight", sqrt: bool = False,
    irradiance: bool = False,
) -> NDArray[np.float64]:
    """
    Rebuild 9-coefficient SH from :func:`compress`'s output (Listing 1, ``UncompressSH``).

    Parameters
    ----------
    dc
        Shape (..., C): the DC coefficients.
    words
        Shape (..., C, W), unsigned or non-negative integers below 2^32, ``W =
        words_per_channel(bits)``.
    bits, bound, sqrt, irradiance
        The values given to :func:`compress` (they are not stored in the words).

    Returns
    -------
    ndarray
        Shape (..., 9, C), float64, same unit as ``dc``. Code ``q`` decodes to
        ``(q / bv - 1) * dc * bound_k`` (squared with its sign first when ``sqrt``),
        finite for every finite ``dc``: a value beyond the largest float (a DC near
        1e308 with a coefficient near its bound) is clipped to it, which moves it
        towards the compressed coefficient (itself finite).

    Raises
    ------
    ValueError
        If ``words`` is ragged or not integers, the shapes disagree, a word is
        outside [0, 2^32 - 1], a field holds the unused code 2^bits - 1 (valid
        codes are 0 .. 2^bits - 2), or the padding bits above the last field are
        not zero (words packed with another ``bits``).
    """
    sqrt, irradiance = check_flag(sqrt, "sqrt"), check_flag(irradiance, "irradiance")
    d = as_float_array(dc, "dc")
    bits = _check_bits(bits)
    scale = bounds(bound, irradiance)
    _per_word, n_words = _layout(bits)
    try:
        w = np.asarray(words)
    except (TypeError, ValueError) as error:  # ragged nested lists: numpy's "inhomogeneous shape"
        raise ValueError(f"words must be a rectangular array of integers in [0, 2^32 - 1] of shape dc.shape + "
                         f"({n_words},), got {short_repr(words)}") from error
    if w.dtype.kind not in "ui":
        raise ValueError(f"words must be integers in [0, 2^32 - 1], got dtype {w.dtype}")
    if d.ndim < 1 or w.shape != d.shape + (n_words,):
        raise ValueError(f"words must have shape dc.shape + ({n_words},) for bits={bits}, "
                         f"got dc {d.shape} and words {w.shape}")
    if w.size and (w.min() < 0 or w.max() > 0xFFFFFFFF):
        raise ValueError("words must be integers in [0, 2^32 - 1]")
    w = w.astype(np.uint64)
    if np.any(w & ~_used_bits(bits)):
        raise ValueError(f"words have non-zero padding bits: they were not packed with bits={bits}")
    codes = _unpack(w, bits)[..., : N_COEFFS - 1]
    top = (1 << bits) - 2
    if codes.size and codes.max() > top:
        raise ValueError(f"words hold the code {(1 << bits) - 1}, outside the valid codes [0, {top}] for bits={bits}")
    bv = float((1 << (bits - 1)) - 1)
    t = codes.astype(np.float64) / bv - 1.0
    if sqrt:
        t = np.sign(t) * (t * t)
    out = np.empty(d.shape[:-1] + (N_COEFFS, d.shape[-1]))
    out[..., 0, :] = d
    with np.errstate(over="ignore"):  # (t * bound) * dc, not t * (dc * bound): dc * bound overflows near 1e308
        rest = np.moveaxis(t * scale, -1, -2) * d[..., None, :]
    out[..., 1:, :] = np.clip(rest, -_FLOAT_MAX, _FLOAT_MAX)
    return out


# --------------------------------------------------------------------------- #
# Table 3 of the seed
# --------------------------------------------------------------------------- #
def _error_norms(delta: NDArray, mean: NDArray, weighted_basis: NDArray, basis_t: NDArray) -> dict[str, float]:
    """L1, L2, RMSE of ``sum_k delta_k Y_k`` over the sphere, per probe and channel divided by ``mean``.

    ``delta`` (P, 9, C) coefficient errors, ``mean`` (P, C) positive normalisers.
    L1 = sum over probes and channels of the sphere average of |e| / mean;
    L2 = sqrt(sum of the sphere average of (e / mean)^2) (exact: Parseval);
    RMSE = L2 / sqrt(P C).
    """
    rel = delta / mean[:, None, :]
    values = np.einsum("mk,pkc->pmc", basis_t, rel)  # (P, M, C) errors at the directions
    l1 = float(np.einsum("m,pmc->", weighted_basis, np.abs(values)))
    l2 = math.sqrt(float(np.sum(rel * rel)) / (4.0 * math.pi))
    return {"L1": l1, "L2": l2, "RMSE": l2 / math.sqrt(rel.shape[0] * rel.shape[2])}


def table3_errors(coeffs: ArrayLike, bits: int = DEFAULT_BITS, n_theta: int = TABLE3_THETA_NODES) -> dict[str, Any]:
    """
    The seed's Table 3 for a batch of SH: compression error, prior versus tight bound.

    Parameters
    ----------
    coeffs
        Radiance SH of non-negative functions (one per "probe"), shape (P, 9, C)
        or (..., 9, C) (batch axes are flattened), any unit. Probes whose DC is
        not positive in some channel are refused.
    bits
        Bits per coefficient, [2, 32].
    n_theta
        Gauss nodes in cos(theta) of the sphere rule used for the L1 error
        (:func:`skysh.sh.basis.quadrature_rule`), [3, :data:`skysh.sh.basis.MAX_GAUSS_NODES`].

    Returns
    -------
    dict
        ``"rows"``: one dict per (quantity, sqrt, bound) with keys ``quantity``
        ("radiance" or "irradiance"), ``sqrt``, ``bound``, ``L1``, ``L2``,
        ``RMSE`` and ``clamped`` (coefficients outside their bound).
        ``"changes"``: per (quantity, sqrt, metric) the relative change
        ``100 (prior - tight) / prior`` in percent (positive = the tight bound
        is better), as the seed's "Delta error" columns. ``"probes"``,
        ``"channels"``, ``"bits"``.

    Notes
    -----
    ``e`` is the decoded minus the original band-limited function (the compression
    error only), divided per probe and channel by the original's mean over the sphere
    (``c_0 Y_00``; ``A_0 c_0 Y_00`` for irradiance; why: docs/quantize.md). As in the
    seed, ``L1 = sum_{p,c} (1 / 4 pi) integral |e| dw`` (quadrature), ``L2 =
    sqrt(sum_{p,c} (1 / 4 pi) integral e^2 dw)`` (exact by orthonormality) and ``RMSE =
    L2 / sqrt(P C)``. The irradiance rows compress ``sh.irradiance(coeffs)`` with
    ``irradiance=True``.
    """
    checked = _codec_coeffs(coeffs)
    c: NDArray[np.float64] = checked.reshape((-1, N_COEFFS, checked.shape[-1]))
    if c.shape[0] == 0:
        raise ValueError("coeffs must hold at least one probe")
    if not np.all(c[:, 0, :] > 0.0):
        raise ValueError("coeffs must have a positive DC coefficient in every probe and channel (non-negative functions)")
    n_theta = check_count(n_theta, "n_theta", 3, sh.MAX_GAUSS_NODES)
    bits = _check_bits(bits)
    dirs, weights = sh.quadrature_rule(n_theta)
    basis_t = sh.basis(dirs, 3)  # (M, 9)
    weighted = weights / (4.0 * math.pi)
    rows: list[dict[str, Any]] = []
    for quantity in ("radiance", "irradiance"):
        is_irr = quantity == "irradiance"
        original = sh.irradiance(c) if is_irr else c
        mean = original[:, 0, :] * sh.Y00
        for use_sqrt in (False, True):
            for bound in BOUND_NAMES:
                clamped = int(np.sum(~(np.abs(ratios(original, bound, is_irr)) <= 1.0 + CLAMP_TOLERANCE)))
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", QuantizationClampWarning)  # counted in ``clamped``
                    dc, words = compress(original, bits, bound, use_sqrt, is_irr)
                decoded = decompress(dc, words, bits, bound, use_sqrt, is_irr)
                norms = _error_norms(decoded - original, mean, weighted, basis_t)
                rows.append({"quantity": quantity, "sqrt": use_sqrt, "bound": bound, **norms, "clamped": clamped})
    changes: list[dict[str, Any]] = []
    for prior_row, tight_row in zip(rows[::2], rows[1::2]):  # one quantity and sqrt, bounds in BOUND_NAMES order
        setting = {"quantity": prior_row["quantity"], "sqrt": prior_row["sqrt"]}
        for metric in ("L1", "L2", "RMSE"):
            prior, tight = prior_row[metric], tight_row[metric]
            change = 100.0 * (prior - tight) / prior if prior > 0.0 else 0.0
            changes.append({**setting, "metric": metric, "change_percent": change})
    return {"rows": rows, "changes": changes, "probes": int(c.shape[0]), "channels": int(c.shape[2]), "bits": bits}
