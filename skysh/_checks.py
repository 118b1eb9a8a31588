"""
Input checks shared by every public function of skysh
=====================================================

-   :func:`as_float_array`: convert to float64, refuse NaN / inf.
-   :func:`check_range`: refuse values outside a closed interval, naming the parameter.
-   :func:`check_dirs`: refuse direction arrays that are not (..., 3).
-   :func:`check_bands`: refuse a band count outside [1, max].
-   :func:`check_flag`: refuse anything but ``bool`` / ``numpy.bool_`` (a TypeError).

Every failure is a :class:`ValueError` whose message names the parameter and the
valid range, so a user can fix the call without reading the source.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["as_float_array", "check_range", "check_dirs", "check_bands", "check_flag", "check_choice"]


def as_float_array(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """Return ``value`` as a float64 array, refusing NaN and inf with a ValueError."""
    raw = np.asarray(value)
    if raw.dtype.kind not in "iuf":  # no text, booleans, objects or complex numbers
        raise ValueError(f"{name} must be a real number or array of them, got {value!r}")
    try:
        array = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{name} must be a real number or array of them, got {value!r}") from error
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite (no NaN or inf), got {value!r}")
    return array


def check_range(value: ArrayLike, name: str, low: float, high: float, unit: str = "") -> NDArray[np.float64]:
    """Return ``value`` as float64 after checking it lies in the closed interval [low, high]."""
    array = as_float_array(value, name)
    if array.size and (array.min() < low or array.max() > high):
        bad = array[(array < low) | (array > high)].ravel()[0]
        suffix = f" {unit}" if unit else ""
        raise ValueError(f"{name} must lie in [{low:g}, {high:g}]{suffix}, got {bad:g}")
    return array


def check_dirs(dirs: ArrayLike, name: str = "dirs") -> NDArray[np.float64]:
    """Return directions as a float64 (..., 3) array; refuse other shapes, NaN, inf and zero vectors."""
    array = as_float_array(dirs, name)
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {array.shape}")
    flat = array.reshape(-1, 3)
    norm2 = np.einsum("ij,ij->i", flat, flat)  # |d|^2; |d| within 1e-6 of 1 <=> |d|^2 within ~2e-6
    if array.size and not np.all(np.abs(norm2 - 1.0) < 2e-6):
        raise ValueError(f"{name} must be unit vectors (|d| = 1 within 1e-6)")
    return array


def check_bands(bands: int, name: str = "bands", high: int = 64) -> int:
    """Return ``bands`` as an int after checking 1 <= bands <= high."""
    if isinstance(bands, bool) or not isinstance(bands, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [1, {high}], got {bands!r}")
    if not 1 <= int(bands) <= high:
        raise ValueError(f"{name} must be an integer in [1, {high}], got {bands}")
    return int(bands)


def check_choice(value: str, name: str, choices: tuple[str, ...]) -> str:
    """Return ``value`` after checking it is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")
    return value


def check_flag(value: object, name: str) -> bool:
    """Return ``value`` as a bool; refuse anything but ``bool`` and ``numpy.bool_`` with a TypeError naming it.

    Truthiness is not accepted: ``"False"`` and ``nan`` are true in Python, so a flag
    given as text or a number would silently mean the opposite of what was meant.
    """
    if type(value) is bool:
        return value  # type: ignore[return-value]
    if type(value) is np.bool_:
        return bool(value)
    raise TypeError(f"{name} must be a bool (True or False), got {value!r} of type {type(value).__name__}")
