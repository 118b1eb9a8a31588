"""
The sun's light per frame, from the coefficient file's sun table
================================================================

The sun's direct normal illuminance of Preetham, Shirley and Smits (1999,
appendix), computed spectrally offline by :mod:`skysh.model.solar` and fitted by
``tools/fit_sky.py`` into the coefficient file (format version 3, member
``sun_table.npy``), evaluated here at the cost of a runtime call.

-   :class:`SunLight`: built once from a
    :class:`~skysh.table.coefficient_file.SkyTable`; :meth:`SunLight.rgb` (linear
    RGB of the file's colourspace, lux), :meth:`SunLight.xyz` (CIE 1931 XYZ,
    lux) and :meth:`SunLight.light` (the unit vector towards the sun and its
    RGB illuminance: a directional light), each for one frame (Python floats:
    the fast path) or a batch (arrays, broadcast).

The table's form (its variables, polynomial form, units and bound: what the
file stores for the sun) is :mod:`skysh.table.sun_table`, shared with the file format
(:mod:`skysh.table.coefficient_file`, which checks it in every file's metadata) and
the fit; :meth:`SunLight.load` reads the file with :func:`skysh.table.coefficient_file.read`.

Near the horizon the sun leaves the sRGB gamut: blue (at T = 6 green too)
turns slightly negative, as :func:`skysh.model.solar.illuminance_rgb` does. Values
are never NaN or inf, never 0 in XYZ (the file bounds the table by
:data:`skysh.table.sun_table.SUN_MAX_LN`).

Cost
----
A scalar call: checks on Python floats, m (one cos, one power), the Chebyshev
terms of both variables as ``cos(k acos v)`` in one vectorised cosine, two
``np.dot`` contractions (in x, then in y), one exp and one 3 x 3 product.
``python benchmarks/bench_sunlight.py`` prints it against a 1-band
:meth:`skysh.SkySH.coefficients` call. ``import skysh.lighting.sunlight`` imports numpy
and the coefficient file reader only (not colour-science or :mod:`skysh.model.solar`).

References
----------
The table's model and air mass: Preetham, Shirley, Smits (1999), appendix, and
Kasten (1966), as :mod:`skysh.table.sun_table` cites them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_size, read_only, real_scalar
from skysh.domain import KASTEN_COEFFICIENTS, SUN
from skysh.table import coefficient_file, poly
from skysh.table.container import CoefficientFileError
from skysh.table.sun_table import sun_variables

__all__ = ["SunLight"]

# The sun table's domain (skysh.domain.SUN) as floats for the scalar fast path:
# x = (m - _M0) _SXS - 1 of Kasten's m, y = (T - _TMIN) _SYS - 1.
_A, _B, _NEG_C = KASTEN_COEFFICIENTS[0], KASTEN_COEFFICIENTS[1], -KASTEN_COEFFICIENTS[2]
_DEG: float = 180.0 / math.pi
(_ZMIN, _ZMAX), (_TMIN, _TMAX) = SUN.x.interval, SUN.y.interval
_M0, _SXS, _SYS = SUN.x.origin, SUN.x.scale, SUN.y.scale


class SunLight:
    """
    The sun's direct illuminance per frame, from a coefficient file's sun table.

    Create from a :class:`~skysh.table.coefficient_file.SkyTable` holding
    ``tables["sun"]`` (every format-3 file does), or with :meth:`load`.
    Methods are read-only and thread-safe.

    Attributes
    ----------
    colourspace
        colour-science name of the file's RGB colourspace (:meth:`rgb`'s).
    degrees
        (d_x, d_y) of the sun table.
    rgb_from_xyz
        (3, 3) the file's XYZ -> linear RGB matrix (read-only).
    errors
        The fit's held-out errors as recorded in the file (a dict; empty if none).

    Examples
    --------
    >>> sun = SunLight.load()
    >>> sun.rgb(0.5, 3.0).shape, sun.rgb([0.1, 0.5], 3.0).shape
    ((3,), (2, 3))
    """

    __slots__ = ("colourspace", "degrees", "rgb_from_xyz", "errors", "_by_x", "_angle_map", "_split", "_rgb_t")

    def __init__(self, sky_table: Any) -> None:
        tables = getattr(sky_table, "tables", None)
        if not isinstance(tables, Mapping) or "sun" not in tables:
            raise CoefficientFileError(
                "the SkyTable has no sun table (tables['sun']): every coefficient file of format version 3 holds "
                "one; an in-memory SkyTable needs it for the sun's light")
        sky_table.validate()  # shapes, degrees, bounds (sun_table.SUN_MAX_LN) and the metadata block's fields where present
        block = sky_table.metadata.get("tables", {}).get("sun", {})
        if "rgb_from_xyz" not in block:
            raise CoefficientFileError("metadata tables['sun'] lacks rgb_from_xyz, the XYZ -> RGB matrix of the file's "
                                       "colourspace")
        named = tables["sun"]
        dx, dy = named.max_degrees
        self.colourspace: str = sky_table.colourspace
        self.degrees: tuple[int, int] = (dx, dy)
        self.errors: dict[str, Any] = dict(block.get("errors", {}))
        self.rgb_from_xyz: NDArray[np.float64] = np.array(block["rgb_from_xyz"], dtype=np.float64)
        self._rgb_t = np.ascontiguousarray(self.rgb_from_xyz.T)
        # ln XYZ = T(y) . (T(x) . by_x).reshape(d_y + 1, 3): contracted in x, then in y.
        self._by_x = np.ascontiguousarray(np.asarray(named.table, dtype=np.float64)[:, 0, :].reshape(dx + 1, (dy + 1) * 3))
        # cos(angle_map @ (acos x, acos y)) = T_0..T_dx(x), T_0..T_dy(y).
        self._angle_map = np.zeros((dx + dy + 2, 2))
        self._angle_map[: dx + 1, 0] = np.arange(dx + 1)
        self._angle_map[dx + 1 :, 1] = np.arange(dy + 1)
        self._split = dx + 1
        read_only(self.rgb_from_xyz, self._rgb_t, self._by_x, self._angle_map)

    @classmethod
    def load(cls, path: str | Path | None = None) -> SunLight:
        """The sun of the shipped coefficient file (or ``path``), checked (:func:`skysh.table.coefficient_file.read`)."""
        return cls(coefficient_file.read(path))

    def __repr__(self) -> str:
        return f"SunLight(degrees={self.degrees}, colourspace={self.colourspace!r})"

    # ------------------------------------------------------------------ #
    def _ln_one(self, ts: float, t: float) -> NDArray[np.float64]:
        """ln XYZ (3,) at one checked point: arithmetic on the prepared tables only."""
        x = (1.0 / (math.cos(ts) + _A * (_B - ts * _DEG) ** _NEG_C) - _M0) * _SXS - 1.0
        y = (t - _TMIN) * _SYS - 1.0
        # Clamp what rounding (and Kasten's dip near the zenith) pushes past +-1; T_k = cos(k acos v), error <= k^2 eps.
        angles = (math.acos(x if -1.0 < x < 1.0 else math.copysign(1.0, x)),
                  math.acos(y if -1.0 < y < 1.0 else math.copysign(1.0, y)))
        packed = np.cos(np.dot(self._angle_map, angles))
        i = self._split
        return np.dot(packed[i:], np.dot(packed[:i], self._by_x).reshape(-1, 3))

    def _ln_batch(self, sun_zenith: ArrayLike, turbidity: ArrayLike) -> tuple[NDArray[np.float64], tuple[int, ...]]:
        """ln XYZ (n, 3) at checked, broadcast points, and their broadcast shape."""
        ts, t = SUN.x.check_array(sun_zenith), SUN.y.check_array(turbidity)
        try:
            shape = np.broadcast_shapes(ts.shape, t.shape)
        except ValueError:
            raise ValueError(f"sun_zenith and turbidity must broadcast together, got shapes {ts.shape} and {t.shape}") from None
        size = math.prod(shape)
        check_size(size * self._by_x.shape[1], "sun_zenith" if ts.size >= t.size else "turbidity", f"{size:,} frames")
        x, y = sun_variables(np.broadcast_to(ts, shape).ravel(), np.broadcast_to(t, shape).ravel())
        tx = poly.chebyshev_rows(x, self.degrees[0]).T  # (n, dx + 1) views: by doubling, few numpy calls
        ty = poly.chebyshev_rows(y, self.degrees[1]).T
        partial = (tx @ self._by_x).reshape(size, self.degrees[1] + 1, 3)
        return np.einsum("nj,njc->nc", ty, partial), shape

    def xyz(self, sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
        """
        CIE 1931 XYZ of the sun's direct normal illuminance, lux.

        Parameters
        ----------
        sun_zenith
            Radians, [0, pi/2] (the fitted domain).
        turbidity
            [2.5, 6] (the fitted domain).

        Returns
        -------
        ndarray
            (3,) for two real scalars; else (..., 3) over the broadcast shape
            (empty inputs: an empty result). Positive and finite.

        Raises
        ------
        ValueError
            For a parameter outside its range (named, with the range), NaN or
            inf, text, booleans, or shapes that do not broadcast.
        """
        ts, t = real_scalar(sun_zenith), real_scalar(turbidity)
        if ts is not None and t is not None:
            if not (_ZMIN <= ts <= _ZMAX and _TMIN <= t <= _TMAX):  # NaN included
                SUN.check(ts, t)  # raises the domain's refusal of the first parameter outside it
            return np.exp(self._ln_one(ts, t))
        ln, shape = self._ln_batch(sun_zenith, turbidity)
        return np.exp(ln).reshape(shape + (3,))

    def rgb(self, sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
        """
        Linear RGB (the file's colourspace) of the sun's direct normal illuminance, lux per channel.

        ``rgb_from_xyz @ xyz(sun_zenith, turbidity)``: R = G = B = Y for a
        white of the colourspace's whitepoint; near the horizon a channel
        outside the gamut turns slightly negative. Arguments, shapes and
        refusals as :meth:`xyz`; two Python floats take the fast path.
        """
        ts, t = real_scalar(sun_zenith), real_scalar(turbidity)
        if ts is not None and t is not None:
            if not (_ZMIN <= ts <= _ZMAX and _TMIN <= t <= _TMAX):  # NaN included
                SUN.check(ts, t)  # raises the domain's refusal of the first parameter outside it
            return np.dot(self.rgb_from_xyz, np.exp(self._ln_one(ts, t)))
        ln, shape = self._ln_batch(sun_zenith, turbidity)
        return (np.exp(ln) @ self._rgb_t).reshape(shape + (3,))

    def light(
        self, sun_zenith: ArrayLike, turbidity: ArrayLike, sun_azimuth: ArrayLike = 0.0
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """
        The sun as a directional light: the unit vector towards it and its RGB illuminance.

        Parameters
        ----------
        sun_zenith, turbidity
            As :meth:`xyz`.
        sun_azimuth
            Radians, any finite value; from +X towards +Y (Z up).

        Returns
        -------
        direction, rgb
            ``(sin ts cos phi, sin ts sin phi, cos ts)`` and :meth:`rgb` (lux
            per channel at normal incidence: an engine's directional light of
            that colour and intensity), each (3,) for real scalars, else (..., 3)
            over the broadcast shape of the three parameters.

        Raises
        ------
        ValueError
            As :meth:`xyz`; ``sun_azimuth`` NaN, inf or not a number.
        """
        ts, t, phi = real_scalar(sun_zenith), real_scalar(turbidity), real_scalar(sun_azimuth)
        if ts is not None and t is not None and phi is not None:
            if not math.isfinite(phi):
                raise ValueError(f"sun_azimuth must be finite (radians), got {phi!r}")
            rgb = self.rgb(ts, t)  # checks the domain
            s = math.sin(ts)
            phi = math.fmod(phi, 2.0 * math.pi)
            return np.array((s * math.cos(phi), s * math.sin(phi), math.cos(ts))), rgb
        zen = SUN.x.check_array(sun_zenith)
        a = np.fmod(as_float_array(sun_azimuth, "sun_azimuth"), 2.0 * math.pi)
        tu = SUN.y.check_array(turbidity)
        try:
            zen, tu, a = np.broadcast_arrays(zen, tu, a)
        except ValueError:
            raise ValueError(
                f"sun_zenith, turbidity and sun_azimuth must broadcast together, got shapes {np.shape(sun_zenith)}, "
                f"{np.shape(turbidity)} and {np.shape(sun_azimuth)}") from None
        sine = np.sin(zen)
        return np.stack([sine * np.cos(a), sine * np.sin(a), np.cos(zen)], axis=-1), self.rgb(zen, tu)
