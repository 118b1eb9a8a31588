"""
The sun table's form: what the coefficient file stores for the sun
==================================================================

The coefficient file's member ``sun_table.npy`` (:mod:`skysh.table.coefficient_file`,
which checks every file's metadata block ``tables.sun`` against the constants
here) holds the sun's direct normal illuminance of Preetham, Shirley and Smits
(1999, appendix), fitted by :mod:`skysh.table.fit` and evaluated per frame by
:class:`skysh.lighting.sunlight.SunLight`. This module is that table's schema, shared by
the writer, the format and the reader:

-   :data:`SUN_VARIABLES`, :data:`SUN_BASIS`, :data:`SUN_UNITS`,
    :data:`SUN_MAX_LN`: the table's variables, polynomial form, units and bound,
    as the file records them (the domain itself, Kasten's coefficients and the
    air-mass interval, is :data:`skysh.domain.SUN`).
-   :func:`air_mass`, :func:`sun_variables`: the table's variables (Kasten's
    relative optical mass; the Chebyshev variables x, y) as arrays.

The table (:data:`SUN_BASIS`)
-----------------------------
The illuminance depends on the sun zenith only through the relative optical
mass m (every transmittance of the model is exp(-m x depth)), and its
logarithm is nearly linear in m; so the table holds ln X, ln Y, ln Z as 2D
Chebyshev polynomials of x affine in m over [m(0), m(pi/2)] = [0.99949, 36.510]
and y affine in the turbidity over [2.5, 6]. RGB is the recorded XYZ -> RGB
matrix of the file's colourspace (colour-science's, no chromatic adaptation:
the sky's colour route) times exp(ln XYZ). Its held-out error is in the file's
metadata (``tables.sun.errors``; ``tools/fit_sky.py`` prints it).

Values are never NaN or inf, never 0 in XYZ: the file bounds each channel's sum
of |coefficients| by :data:`SUN_MAX_LN` (at sun zenith pi/2 and T = 6 the
illuminance is about 2.5e-4 lux). ``import skysh.table.sun_table`` imports numpy only.

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999). A Practical Analytic Model
    for Daylight. SIGGRAPH 1999, appendix (the attenuated sun).
-   Kasten, F. (1966). A new table and approximation formula for the relative
    optical air mass. Arch. Meteorol. Geophys. Bioklimatol. B 14.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.domain import KASTEN_COEFFICIENTS, SUN

__all__ = ["SUN_VARIABLES", "SUN_BASIS", "SUN_MAX_LN", "air_mass", "sun_variables"]

_A, _B, _C = KASTEN_COEFFICIENTS
_T0, _T1 = SUN.y.interval

SUN_VARIABLES: dict[str, str] = {
    "m": f"1 / (cos sun_zenith + {_A:g} ({_B:g} - sun_zenith[deg])^-{_C:g}) (Kasten 1966 relative optical mass)",
    "x": "2 (m - m0) / (m1 - m0) - 1 clamped to [-1, 1], [m0, m1] = air_mass_range (m at sun zenith 0 and pi/2)",
    "y": f"2 (T - {_T0:g}) / ({_T1:g} - {_T0:g}) - 1 (turbidity T, affine)",
}
"""The sun table's Chebyshev variables, as recorded in the file's metadata (written from :data:`skysh.domain.SUN`)."""

SUN_BASIS: str = (
    "ln XYZ_c = sum_k table[k, 0, c] T_i(x) T_j(y), k = i (d_y + 1) + j, c = X, Y, Z: CIE 1931 XYZ of the "
    "sun's direct normal illuminance (Preetham 1999 appendix), lux; RGB = rgb_from_xyz @ exp(ln XYZ)"
)
"""The polynomial form of the sun table, as recorded in the file's metadata."""

SUN_UNITS: str = "ln lux (CIE 1931 XYZ of the direct normal illuminance)"
"""Units of the sun table's values."""

SUN_MAX_LN: float = 100.0
"""Largest sum of |coefficients| of a sun table channel (ln lux), hence largest |ln XYZ| (|T_i T_j| <= 1).

exp then lies in [e^-100, e^100] = [3.7e-44, 2.7e43] lux: never 0, inf or NaN, also on the
horizon. A fit's largest sum is far below (``tools/fit_sky.py`` prints it with the fit)."""


def air_mass(sun_zenith: ArrayLike) -> NDArray[np.float64]:
    """Kasten's relative optical mass at ``sun_zenith`` (radians in [0, pi/2], any shape): dimensionless, 0.9995 .. 36.51.

    Kasten's formula (:data:`skysh.domain.KASTEN_COEFFICIENTS`) dips slightly below m(0) for sun
    zeniths just above 0 (its derivative at 0 is slightly negative; by less than 1e-7, which
    ``tests/lighting/test_sunlight.py`` asserts); there :func:`sun_variables` clamps x to -1, which moves
    ln XYZ by less than 1e-7 (its slope in m is of order 1): far below the fit's error.
    """
    return SUN.x.fitted_value(SUN.x.check_array(sun_zenith))


def sun_variables(sun_zenith: ArrayLike, turbidity: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    The sun table's Chebyshev variables (:data:`SUN_VARIABLES`, :data:`skysh.domain.SUN`), each in [-1, 1].

    Parameters
    ----------
    sun_zenith, turbidity
        Radians in [0, pi/2] and turbidity in [2.5, 6], any shapes (not broadcast).

    Returns
    -------
    x, y
        x = 2 (m - m0) / (m1 - m0) - 1 (clamped), y = 2 (T - 2.5) / 3.5 - 1.
    """
    return SUN.unit(sun_zenith, turbidity)
