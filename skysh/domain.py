"""
The fitted domain: the parameters' intervals and their maps to [-1, 1]
======================================================================

Every table of the coefficient file is a 2D Chebyshev polynomial (Habel 2008,
eq. 1) of two variables x, y in [-1, 1], each an affine function of a fitted
variable, itself a function of a parameter as users type it. This module holds
those facts once; the runtime, the fit, the file, the sun, the command line and
the exports ask it.

-   :class:`Variable`: one parameter: its public name and unit, its closed
    interval, the transform to the fitted variable (identity, natural log, or
    Kasten's air mass) and the affine map of the fitted variable to [-1, 1]
    (``u = (f - origin) scale - shift``, computed once at construction).
-   :class:`Domain`: two variables ``x`` and ``y`` with :meth:`Domain.check`
    (one refusal form naming the parameter, its interval and unit),
    :meth:`Domain.unit` (the Chebyshev variables) and :meth:`Domain.metadata`.
-   :data:`SKY`: the sky tables' domain: sun zenith [0, pi/2] rad (x affine in
    the angle), turbidity [2.5, 6] (y affine in ln T).
-   :data:`SUN`: the sun table's domain: x affine in Kasten's air mass of the
    sun zenith over [m(0), m(pi/2)], y affine in the turbidity over [2.5, 6].
-   :data:`KASTEN_COEFFICIENTS`: (a, b, c) of Kasten's air mass.
-   :data:`MAX_DEGREE`, :data:`TERM_ORDER`, :func:`term_index`,
    :func:`check_degrees`: the order of the terms T_i(x) T_j(y) in every table.

``import skysh.domain`` imports numpy only.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008). Efficient Spherical Harmonics
    Lighting with the Preetham Skylight Model. Eurographics short papers,
    eq. (1): the 2D polynomial over (sun zenith, turbidity).
-   Kasten, F. (1966). A new table and approximation formula for the relative
    optical air mass. Arch. Meteorol. Geophys. Bioklimatol. B 14, 206-223
    (the coefficients (0.15, 93.885, 1.253); not Kasten and Young's 1989
    revision (0.50572, 96.07995, 1.6364), which the sun table was not fitted with).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_count, check_range, interval_text, number_text, short_repr

__all__ = ["KASTEN_COEFFICIENTS", "MAX_DEGREE", "TERM_ORDER", "Variable", "Domain", "SKY", "SUN", "term_index",
    "check_degrees"]

KASTEN_COEFFICIENTS: tuple[float, float, float] = (0.15, 93.885, 1.253)
"""(a, b, c) of Kasten's (1966) relative optical mass m = 1 / (cos theta + a (b - theta[deg])^-c), theta in rad."""

TRANSFORMS: tuple[str, ...] = ("identity", "log", "kasten")
"""Transforms from a parameter to its fitted variable: itself, its natural log, Kasten's air mass (of an angle, rad)."""

MAX_DEGREE: int = 64
"""Largest polynomial degree accepted in either variable (the shipped file uses (13, 7); the
coefficient file format allows 31)."""

TERM_ORDER: str = "i (d_tau + 1) + j for the largest degrees of any band"
"""Order of every table's terms T_i(x) T_j(y), as the coefficient file records it (:func:`term_index`)."""

_DEG: float = 180.0 / math.pi
_KASTEN_A, _KASTEN_B, _KASTEN_NEG_C = KASTEN_COEFFICIENTS[0], KASTEN_COEFFICIENTS[1], -KASTEN_COEFFICIENTS[2]


@dataclass(frozen=True)
class Variable:
    """
    One fitted parameter: its name, interval, transform and map to [-1, 1].

    Parameters
    ----------
    name
        The parameter as users type it (``"sun_zenith"``, ``"turbidity"``).
    unit
        Its unit as refusals write it (``"rad"``; ``""`` for none).
    interval
        (low, high), the closed interval accepted, in the parameter's unit.
    transform
        One of :data:`TRANSFORMS`: the fitted variable f is the parameter, its
        natural log, or Kasten's air mass of it.
    anchored
        The map to [-1, 1] written from the low end, ``u = (f - f0) scale - 1``
        (the sun table's form), instead of ``u = f scale - shift`` (the sky's).

    Attributes
    ----------
    fitted
        (f0, f1): the interval of the fitted variable (the transform of the ends).
    scale, shift, origin
        ``u = (f - origin) scale - shift``: scale = 2 / (f1 - f0); origin f0 and
        shift 1 when ``anchored``, else origin 0 and shift (f0 + f1) / (f1 - f0).
        ``f - 0`` is exact, so both forms are evaluated bit for bit as written.
    """

    name: str
    unit: str
    interval: tuple[float, float]
    transform: str = "identity"
    anchored: bool = False
    fitted: tuple[float, float] = field(init=False)
    scale: float = field(init=False)
    shift: float = field(init=False)
    origin: float = field(init=False)

    def __post_init__(self) -> None:
        if self.transform not in TRANSFORMS:
            raise ValueError(f"transform must be one of {', '.join(TRANSFORMS)}, got {short_repr(self.transform)}")
        if not self.interval[0] < self.interval[1]:
            raise ValueError(f"interval must be (low, high) with low < high, got {short_repr(self.interval)}")
        f0, f1 = (self.fitted_scalar(v) for v in self.interval)
        object.__setattr__(self, "fitted", (f0, f1))
        object.__setattr__(self, "scale", 2.0 / (f1 - f0))
        object.__setattr__(self, "origin", f0 if self.anchored else 0.0)
        object.__setattr__(self, "shift", 1.0 if self.anchored else (f0 + f1) / (f1 - f0))

    # ------------------------------------------------------------------ #
    @property
    def refusal_unit(self) -> str:
        """The unit and provenance refusals append to the interval: ``"rad (the fitted domain)"``."""
        return f"{self.unit} (the fitted domain)" if self.unit else "(the fitted domain)"

    def error(self, value: Any) -> ValueError:
        """The refusal of ``value`` outside :attr:`interval`: "sun_zenith must lie in [0, 1.5708] rad (the fitted
        domain), got 2" (ends with 6 significant digits, the value as it reads back)."""
        low, high = self.interval
        return ValueError(f"{self.name} must lie in [{low:g}, {high:g}] {self.refusal_unit}, got {number_text(value)}")

    def check(self, value: ArrayLike) -> Any:
        """``value`` checked to lie in :attr:`interval`: a Python float as is (fast path; NaN refused), anything else
        as a float64 array (any shape; NaN, inf, text and booleans refused, naming :attr:`name`)."""
        if type(value) is float:
            if not self.interval[0] <= value <= self.interval[1]:  # also False for NaN
                raise self.error(value)
            return value
        return self.check_array(value)

    def check_array(self, value: ArrayLike) -> NDArray[np.float64]:
        """``value`` as a float64 array (any shape, a Python float too) checked to lie in :attr:`interval` (NaN, inf,
        text and booleans refused, naming :attr:`name`)."""
        return check_range(value, self.name, self.interval[0], self.interval[1], unit=self.refusal_unit)

    def interval_text(self, degrees: bool = False, pi: bool = False) -> str:
        """:attr:`interval` as help text: "[2.5, 6]"; ``degrees``: an angle in degrees ("[0, 90]"); ``pi``: ends as
        multiples of pi where they are ("[0, pi/2]")."""
        low, high = self.interval
        if degrees:
            low, high = math.degrees(low), math.degrees(high)
        return interval_text(low, high, pi=pi)

    # ------------------------------------------------------------------ #
    def fitted_scalar(self, value: float) -> float:
        """The fitted variable of one checked float (no range check)."""
        if self.transform == "log":
            return math.log(value)
        if self.transform == "kasten":
            return 1.0 / (math.cos(value) + _KASTEN_A * (_KASTEN_B - value * _DEG) ** _KASTEN_NEG_C)
        return value

    def fitted_value(self, value: NDArray[np.float64]) -> NDArray[np.float64]:
        """The fitted variable of a checked float64 array (no range check), same shape."""
        if self.transform == "log":
            return np.log(value)
        if self.transform == "kasten":
            return 1.0 / (np.cos(value) + _KASTEN_A * (_KASTEN_B - value * _DEG) ** _KASTEN_NEG_C)
        return value

    def unit_unchecked(self, value: NDArray[np.float64]) -> NDArray[np.float64]:
        """The Chebyshev variable of a checked float64 array, clamped to [-1, 1] (where rounding, or Kasten's dip
        just below m(0) near the zenith, pushes it past an end)."""
        return np.clip((self.fitted_value(value) - self.origin) * self.scale - self.shift, -1.0, 1.0)


@dataclass(frozen=True)
class Domain:
    """
    The fitted domain of one table: two :class:`Variable` (``x`` of the first parameter, ``y`` of the second).

    ``source`` says where the table's form is defined.
    """

    name: str
    x: Variable
    y: Variable
    source: str

    @property
    def variables(self) -> tuple[Variable, Variable]:
        """(x, y)."""
        return self.x, self.y

    def check(self, x: ArrayLike, y: ArrayLike) -> tuple[Any, Any]:
        """Both parameters checked (:meth:`Variable.check`): Python floats as is, anything else as float64 arrays
        (not broadcast). A ValueError names the first parameter outside its interval, the interval and the unit."""
        return self.x.check(x), self.y.check(y)

    def unit(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """
        The Chebyshev variables of the parameters, each in [-1, 1].

        Parameters
        ----------
        x, y
            The parameters (e.g. radians in [0, pi/2] and turbidity in [2.5, 6]), any shapes, not broadcast;
            checked (:meth:`check`).

        Returns
        -------
        u, v
            Float64 arrays of the shapes of ``x`` and ``y``.
        """
        return self.x.unit_unchecked(self.x.check_array(x)), self.y.unit_unchecked(self.y.check_array(y))

    def metadata(self) -> dict[str, list[float]]:
        """The domain as the coefficient file records it: ``{"sun_zenith": [0.0, 1.5707963267948966], ...}``."""
        return {v.name: list(v.interval) for v in self.variables}


SKY: Domain = Domain(
    name="sky",
    x=Variable("sun_zenith", "rad", (0.0, math.pi / 2.0)),
    y=Variable("turbidity", "", (2.5, 6.0), transform="log"),
    source="skysh.table.coefficient_file.BASIS (Habel 2008 eq. 1)",
)
"""The sky tables' domain: sun zenith [0, pi/2] rad (zenith to horizon), x affine in it; turbidity [2.5, 6] (Habel
2008 after Zotti et al. 2007: the model is unusable below 2.5), y affine in ln T."""

SUN: Domain = Domain(
    name="sun",
    x=Variable("sun_zenith", "rad", SKY.x.interval, transform="kasten", anchored=True),
    y=Variable("turbidity", "", SKY.y.interval, anchored=True),
    source="skysh.table.sun_table.SUN_BASIS (Preetham 1999 appendix; Kasten 1966)",
)
"""The sun table's domain: the sky's intervals (the same objects); x affine in Kasten's air mass over
[m(0), m(pi/2)] = [0.99949, 36.510], y affine in the turbidity."""


def check_degrees(degrees: Any, name: str = "degrees") -> tuple[int, int]:
    """(d_theta, d_tau) as ints, each in [0, :data:`MAX_DEGREE`]; a ValueError naming ``name`` otherwise."""
    try:
        d_theta, d_tau = degrees
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair of integers (d_theta, d_tau) in [0, {MAX_DEGREE}], "
                         f"got {short_repr(degrees)}") from None
    return check_count(d_theta, f"{name}[0]", 0, MAX_DEGREE), check_count(d_tau, f"{name}[1]", 0, MAX_DEGREE)


def term_index(i: int, j: int, degrees: tuple[int, int]) -> int:
    """Flat index of the term T_i(x) T_j(y) in a table of degrees (d_theta, d_tau) (:data:`TERM_ORDER`);
    0 <= i <= d_theta, 0 <= j <= d_tau."""
    d_theta, d_tau = check_degrees(degrees)
    i, j = check_count(i, "i", 0, d_theta), check_count(j, "j", 0, d_tau)
    return i * (d_tau + 1) + j
