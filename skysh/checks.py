"""
Input checks shared by every public function of skysh
=====================================================

-   :func:`as_float_array`: convert to float64, refuse NaN / inf, text, booleans,
    complex numbers, objects and ragged lists.
-   :func:`check_range`: refuse values outside a closed interval, naming the parameter.
-   :func:`check_scalar`: one real number (optionally in a closed interval).
-   :func:`check_cutoff`: a window's cutoff band, a real number > 0 or inf.
-   :func:`check_dirs`: refuse direction arrays that are not (..., 3) unit vectors.
-   :func:`check_bands`: refuse a band count outside [1, max].
-   :func:`check_coeffs`: refuse SH coefficients that are not (K,), (K, C) or (..., K, C), K = N**2.
-   :func:`check_count`: refuse an integer count outside [low, high].
-   :func:`check_seed`: refuse a random seed that is not None or an integer >= 0.
-   :func:`check_size`: refuse work whose arrays would exceed :data:`MAX_ARRAY_ELEMENTS`.
-   :func:`check_choice`: refuse a name that is not one of the valid ones, listing them.
-   :func:`check_flag`: refuse anything but ``bool`` / ``numpy.bool_`` (a TypeError).
-   :func:`check_out`: refuse an output buffer that is not a writeable, C-contiguous float64 array of the result's
    shape, or that shares memory with an input.
-   :func:`number_text`: a float as text that reads back exactly (for messages).
-   :func:`integer_text`: an integer beyond float64 by its size (for messages).
-   :func:`interval_text`: a closed interval as the documentation writes it ("[2.5, 6]", "[0, pi/2]").
-   :func:`short_repr`: a one-line, bounded repr of any value (for messages).

Every failure is a :class:`ValueError` whose message names the parameter and the
valid range, so a user can fix the call without reading the source; the one
exception is a flag given as something other than a bool, a :class:`TypeError`.

Empty arrays: a batch axis of length 0 (no directions, no frames, no places) is a
batch of nothing and gives an empty result wherever a function takes batches, as
each docstring says; an empty coefficient axis, image or list of per-band factors
means nothing and is refused. Sizes: no function builds an array of more than
:data:`MAX_ARRAY_ELEMENTS` values; a call that would is refused before any work.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["MAX_ARRAY_ELEMENTS", "as_float_array", "check_range", "check_scalar", "check_cutoff", "check_dirs",
    "check_bands", "check_coeffs", "check_count", "check_seed", "check_size", "check_flag", "check_choice", "check_out",
    "number_text", "interval_text", "short_repr", "read_only"]

MAX_ARRAY_ELEMENTS: int = 1 << 28
"""Largest number of values (268,435,456; 2 GiB of float64) of any one array a skysh function
builds. A call whose inputs (a large batch, a broadcast view, a huge count) would need more is
refused at once with a ValueError naming the parameter, instead of a MemoryError after minutes."""

_NOT_A_NUMBER: str = "must be a real number or an array of real numbers"


def integer_text(value: int) -> str:
    """An integer beyond float64 described by its size ("an integer of 401 digits"): its repr may be
    thousands of digits, or refused by Python's limit on int-to-text conversion (4300 digits)."""
    digits = max(1, int(abs(value).bit_length() * math.log10(2.0)))  # the count, or one less
    digits += abs(value) >= 10**digits
    return f"an integer of {digits} digits"


def number_text(value: Any) -> str:
    """``value`` as text that reads back as the same float ("90", "90.0000001", "inf"), its size for an
    integer beyond float64 (:func:`integer_text`), or its repr."""
    try:
        x = float(value)
    except OverflowError:
        return integer_text(value) if isinstance(value, int) else short_repr(value)
    except (TypeError, ValueError):
        return repr(value)
    return str(int(x)) if x.is_integer() and abs(x) < 1e16 else repr(x)


def interval_text(low: float, high: float, pi: bool = False) -> str:
    """``[low, high]`` as the docs write a domain: each end by :func:`number_text`, or with ``pi``
    as a multiple k pi / n (n <= 12) where it is one to rounding ("0", "pi/2", "3 pi/4")."""

    def end(x: float) -> str:
        ratio = Fraction(x / math.pi).limit_denominator(12)
        if not pi or abs(float(ratio) * math.pi - x) > 4.0 * math.ulp(abs(x)):
            return number_text(x)
        k, n = abs(ratio.numerator), ratio.denominator
        sign, factor, divisor = "-" if ratio < 0 else "", "" if k == 1 else f"{k} ", "" if n == 1 else f"/{n}"
        return "0" if k == 0 else f"{sign}{factor}pi{divisor}"

    return f"[{end(low)}, {end(high)}]"


def short_repr(value: Any) -> str:
    """A repr of ``value`` short enough for one line of a message (an int beyond float64 by its size, a value
    whose repr fails, e.g. a list holding an int of more than 4300 digits, by its type)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 1024:
        return integer_text(value)
    try:
        text = repr(value) if not isinstance(value, np.ndarray) or value.size <= 6 else f"array of shape {value.shape}"
    except Exception as error:  # any repr may fail; the message must still name the parameter
        return f"a {type(value).__name__} (its repr fails: {type(error).__name__})"
    text = " ".join(text.split())
    return text if len(text) <= 80 else text[:77] + "..."


def as_float_array(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return ``value`` as a float64 array; refuse NaN, inf, text, booleans, complex, objects, ragged lists."""
    array = _float_array(value, name)
    if not np.all(np.isfinite(array)):  # also catches float128 / uint64 values beyond float64
        raise ValueError(f"{name} must be finite (no NaN or inf), got {short_repr(value)}")
    return array


def _float_array(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """:func:`as_float_array` before its finiteness check (the caller makes it)."""
    if type(value) is int:  # a Python int of any size: float() says whether it fits
        try:
            value = float(value)
        except OverflowError:
            raise ValueError(f"{name} must be finite (a float64, |x| <= 1.8e308), got {integer_text(value)}") from None
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as error:  # ragged nested lists: numpy's "inhomogeneous shape"
        raise ValueError(f"{name} {_NOT_A_NUMBER} (a rectangular array), got {short_repr(value)}") from error
    if raw.dtype.kind not in "iuf":  # no text, booleans, objects or complex numbers
        raise ValueError(f"{name} {_NOT_A_NUMBER}, got {short_repr(value)}")
    check_size(raw.size, name)  # before any copy: a broadcast view can be far larger than memory
    return np.asarray(raw, dtype=np.float64)


def check_range(value: ArrayLike, name: str, low: float, high: float, unit: str = "") -> NDArray[np.float64]:
    """Return ``value`` as float64 after checking it is finite and lies in the closed interval [low, high]."""
    array = _float_array(value, name)
    if not array.size:
        return array
    smallest, largest = array.min(), array.max()  # two reductions decide it all: NaN propagates into both
    if -math.inf < smallest and largest < math.inf and low <= smallest and largest <= high:
        return array
    if not np.all(np.isfinite(array)):  # the refusal's wording: as as_float_array's
        raise ValueError(f"{name} must be finite (no NaN or inf), got {short_repr(value)}")
    bad = array[(array < low) | (array > high)].ravel()[0]
    suffix = f" {unit}" if unit else ""
    raise ValueError(f"{name} must lie in [{low:g}, {high:g}]{suffix}, got {number_text(bad)}")


def check_scalar(value: Any, name: str, low: float = -math.inf, high: float = math.inf, unit: str = "") -> float:
    """Return one real number as a float after checking it is finite and in [low, high]."""
    array = check_range(value, name, low, high, unit)
    if array.ndim:
        raise ValueError(f"{name} must be a scalar (one number), got an array of shape {array.shape}")
    return float(array)


def check_cutoff(cutoff: Any, name: str = "cutoff") -> float:
    """Return a window's cutoff w (factors are 0 for bands l >= w) as a float: a real number > 0, or inf
    (no windowing); a ValueError naming ``name`` for anything else (a flag, text, NaN, an int beyond float64)."""
    if isinstance(cutoff, (bool, np.bool_)) or not isinstance(cutoff, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a real number > 0 (a band index, or inf), got {short_repr(cutoff)}")
    try:
        w = float(cutoff)
    except OverflowError:  # a Python int beyond float64
        raise ValueError(f"{name} must be a real number > 0 within float64 (a band index, or inf), got "
                         f"{number_text(cutoff)}") from None
    if not w > 0.0:
        raise ValueError(f"{name} must be > 0 (a band index, or inf), got {cutoff!r}")
    return w


def check_size(count: int, name: str, what: str = "") -> None:
    """Refuse work needing more than :data:`MAX_ARRAY_ELEMENTS` values in one array, naming ``name``."""
    if count > MAX_ARRAY_ELEMENTS:
        detail = f" ({what})" if what else ""
        raise ValueError(f"{name} is too large: the result would hold {count:,} values{detail}, more than the "
                         f"{MAX_ARRAY_ELEMENTS:,} (2 GiB of float64) skysh builds in one array; split the work")


def check_dirs(dirs: ArrayLike, name: str = "dirs", per_point: int = 3) -> NDArray[np.float64]:
    """Return directions as a float64 (..., 3) array; refuse other shapes, NaN, inf and non-unit vectors.

    An empty batch (shape (0, 3)) is accepted: zero directions give zero results. ``per_point``
    is the number of values the caller builds per direction, for :func:`check_size`.
    """
    array = as_float_array(dirs, name)
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) (unit vectors), got {array.shape}")
    check_size(array.size // 3 * max(per_point, 3), name, f"{array.size // 3:,} directions")
    flat = array.reshape(-1, 3)
    norm2 = np.einsum("ij,ij->i", flat, flat)  # |d|^2; |d| within 1e-6 of 1 <=> |d|^2 within ~2e-6
    if array.size and not np.all(np.abs(norm2 - 1.0) < 2e-6):
        raise ValueError(f"{name} must be unit vectors (|d| = 1 within 1e-6)")
    return array


def check_count(value: Any, name: str, low: int, high: int) -> int:
    """Return ``value`` as an int after checking it is an integer (not a bool) in [low, high]."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {short_repr(value)}")
    if not low <= int(value) <= high:
        shown = int(value) if int(value).bit_length() <= 1024 else integer_text(int(value))  # str() refuses > 4300 digits
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {shown}")
    return int(value)


def check_bands(bands: int, name: str = "bands", high: int = 64) -> int:
    """Return ``bands`` as an int after checking 1 <= bands <= high."""
    return check_count(bands, name, 1, high)


def check_coeffs(coeffs: ArrayLike, name: str = "coeffs", high: int = 64, *, low: int = 1,
                 vector: bool = True) -> tuple[NDArray[np.float64], bool, int]:
    """SH coefficients as a (..., K, C) float64 array, whether they came as one (K,) vector, and N.

    K = N**2 coefficients (docs/conventions.md order) of N bands in [low, high], C channels. A (K,)
    vector is accepted when ``vector`` (and returned as (K, 1)); otherwise the channel axis is
    required. The message names ``name``, the accepted shapes and the valid K.
    """
    c = as_float_array(coeffs, name)
    is_vector = vector and c.ndim == 1
    c = c[:, None] if is_vector else c
    bands = math.isqrt(c.shape[-2]) if c.ndim >= 2 else 0
    if c.ndim < 2 or not low <= bands <= high or bands * bands != c.shape[-2]:
        shapes = "(K,), (K, C) or (..., K, C)" if vector else "(K, C) or (..., K, C)"
        counts = ", ".join(str(n * n) for n in range(low, min(high, low + 7) + 1)) + (", ..." if high > low + 7 else "")
        valid = f"K = {low * low} ({low} bands)" if low == high else f"K = N**2, N in [{low}, {high}] (K in ({counts}))"
        raise ValueError(f"{name} must have shape {shapes} with {valid}, got {c.shape}")
    return c, is_vector, bands


def check_seed(seed: Any, name: str = "seed") -> int | None:
    """Return a random seed: None, or an integer in [0, 2**64 - 1] (not a bool)."""
    return None if seed is None else check_count(seed, name, 0, (1 << 64) - 1)


def check_choice(value: str, name: str, choices: tuple[str, ...]) -> str:
    """Return ``value`` after checking it is one of ``choices`` (a str; the message lists them)."""
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {short_repr(value)}")
    return value


def check_flag(value: object, name: str) -> bool:
    """Return ``value`` as a bool; refuse anything but ``bool`` and ``numpy.bool_`` with a TypeError naming it.

    Truthiness is not accepted: ``"False"`` and ``nan`` are true in Python, so a flag
    given as text or a number would silently mean the opposite of what was meant.
    """
    if type(value) is bool or type(value) is np.bool_:
        return bool(value)
    raise TypeError(f"{name} must be a bool (True or False), got {short_repr(value)} of type {type(value).__name__}")


def check_out(out: Any, shape: tuple[int, ...], inputs: tuple[Any, ...] = (), name: str = "out") -> NDArray[np.float64]:
    """Return ``out``, an output buffer a function writes its result into: a numpy array of float64, C-contiguous,
    writeable, of exactly ``shape``, sharing no memory with any array of ``inputs`` (the result would overwrite
    what is still to be read). Anything else is refused with a ValueError naming ``name`` and the buffer expected."""
    want = f"{name} must be a writeable, C-contiguous numpy array of float64 and shape {shape}, got"
    if not isinstance(out, np.ndarray):
        raise ValueError(f"{want} {short_repr(out)} of type {type(out).__name__}")
    flags = [f for f, ok in (("not C-contiguous", out.flags.c_contiguous), ("read-only", out.flags.writeable)) if not ok]
    if out.dtype != np.float64 or out.shape != shape or flags:
        raise ValueError(f"{want} dtype {out.dtype} and shape {out.shape}" + (f" ({', '.join(flags)})" if flags else ""))
    if any(isinstance(a, np.ndarray) and np.may_share_memory(out, a) for a in inputs):
        raise ValueError(f"{name} shares memory with an input: the result would overwrite parameters it still reads")
    return out


def read_only(*arrays: NDArray) -> None:
    """Mark arrays read-only: the cached tables a module hands out, so no caller can change them for the next."""
    for array in arrays:
        array.flags.writeable = False


REAL_SCALAR_TYPES: frozenset[type] = frozenset(
    {int, np.float64, np.float32, np.float16, np.int64, np.int32, np.int16, np.int8,
     np.uint64, np.uint32, np.uint16, np.uint8}
)
"""Scalar types (besides float) that take the per-frame scalar paths; ``bool`` is not a number here."""


def real_scalar(value: Any) -> float | None:
    """``value`` as a Python float when it is one real scalar (float, int, numpy real, 0-d array), else None.

    None sends the call to the array path, which validates and names the parameter
    (also for ints too large for a float, text and booleans). Cheap: a type lookup.
    """
    kind = type(value)
    if kind is float:
        return value
    if kind in REAL_SCALAR_TYPES or (kind is np.ndarray and value.ndim == 0 and value.dtype.kind in "iuf"):
        try:
            return float(value)
        except OverflowError:  # an int beyond float range: the array path refuses it by name
            return None
    return None
