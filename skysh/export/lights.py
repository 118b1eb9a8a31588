"""
The sun's and the ground's numbers in the exports
=================================================

The exported functions of :mod:`skysh.export.c_like` (C, GLSL, HLSL: the kernel
``skysh/export/templates/c_like_kernel.h``) and :mod:`skysh.export.js` (JavaScript) follow
the sky's rotation with the steps of :meth:`skysh.SkySH.coefficients` (the order of
:mod:`skysh.lighting.lights`): the deringing of the sky, the sun (``sun=True``) and the ground
(``ground_albedo=...``), then the per-band factor; they also give the sun as a directional
light, as :meth:`skysh.SkySH.sun_light`. This module holds the numbers of those steps that
every export shares (the code is in the templates):

-   :class:`LightTables`, :func:`light_tables`: the numbers (the file's sun
    table, its XYZ -> RGB matrix, the sun's windowed SH as a trigonometric
    polynomial, the ground's zonal factors, the unfiltered c_10 table) and the
    constants, read through public names only; :func:`light_flags`.
-   :func:`chebyshev_terms`: a file table's Chebyshev terms at an export's degrees
    (the sky's, the irradiance table's, the c_10's).
-   :data:`BY_INTENT`: the C and shader value of ``irradiance_table`` that means the runtime's default.

What the generated code computes (after the sky's rotation and its deringing)
------------------------------------------------------------------------------
1.  The sun's RGB direct normal illuminance (lux): Kasten's air mass
    ``m = 1 / (cos ts + a (b - ts[deg])^-c)``, ``x = clamp(2 (m - m0) / (m1 - m0)
    - 1)``, ``y = clamp(2 (T - 2.5) / 3.5 - 1)`` (:data:`skysh.table.sun_table.SUN_VARIABLES`),
    ``ln XYZ = sum T_i(x) T_j(y) SUN[i][j]``, ``RGB = rgb_from_xyz @ exp(ln XYZ)``.
2.  The ground (when its albedo is not black): ``L_g = albedo (E_sky + cos(ts) RGB_sun)
    / pi`` with ``E_sky = sqrt(4 pi / 3) c_10`` of the *unfiltered* sky
    (:func:`skysh.model.ground.horizontal_irradiance_from_sh`; the sun's term only with
    ``sun``); ``coefficient (l, 0) += GROUND[l] (sinc(pi l / N) with gibbs) L_g``.
3.  The sun (with ``sun``): its colour clamped at :data:`skysh.lighting.lights.SUN_SH_CLAMP`
    per channel; ``coefficient (l, m) += Ybar_l|m|(ts) rot_m(phi) RGB``, with
    ``Ybar_lm(ts) = window_l Y_lm(sin ts, 0, cos ts) = sum_k TRIG[r][k] cos(k ts) +
    TRIG[r][N + k] sin(k ts)`` (:func:`skysh.lighting.lights.sun_trig_matrix`, the window
    :func:`skysh.model.solar.sun_window`) and ``rot_m`` the sky's rotation factors (Habel eq. 4).

Then the per-band factor (``A_l`` for irradiance, an engine's) multiplies the sum.

The certified irradiance table
------------------------------
``irradiance_table`` follows :meth:`skysh.SkySH.coefficients` (by intent: :data:`BY_INTENT`
in C and the shaders, ``null`` in JavaScript; 0 never; 1 always): the 3-band sky's rows come
from the file's table (E_lm / A_l over the luminance scale, m >= 0), are summed, scaled and
rotated as the sky's (Habel eqs. 1, 4), never filtered or deringed (``docs/irradiance.md``).

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: the sun's light.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (4), (5).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000), section 3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_bands
from skysh.domain import KASTEN_COEFFICIENTS, SUN, term_index
from skysh.lighting import lights, sunlight
from skysh.model import ground, solar
from skysh.table import coefficient_file

__all__ = []

BY_INTENT: int = -1
"""The C and shader value of ``irradiance_table`` that means the runtime's default (None): by intent."""


def chebyshev_terms(table: ArrayLike, max_degrees: tuple[int, int], degrees: tuple[int, int]) -> NDArray[np.float64]:
    """
    A file table's Chebyshev terms at an export's degrees, zero where the table has none.

    Parameters
    ----------
    table
        (n_terms, rows, 3): a :class:`skysh.table.coefficient_file.SkyTable`'s or
        :class:`~skysh.table.coefficient_file.NamedTable`'s ``table``, terms in
        :func:`skysh.domain.term_index` order for ``max_degrees``.
    max_degrees, degrees
        (d_x, d_y) of the table's layout and of the export, each in [0, 31].

    Returns
    -------
    ndarray
        (DX + 1, DY + 1, rows, 3), float64: [i][j] the coefficient of T_i(x) T_j(y).
    """
    values = np.asarray(table, dtype=np.float64)
    out = np.zeros((degrees[0] + 1, degrees[1] + 1) + values.shape[1:])
    for i in range(min(degrees[0], max_degrees[0]) + 1):
        for j in range(min(degrees[1], max_degrees[1]) + 1):
            out[i, j] = values[term_index(i, j, max_degrees)]
    return out



@dataclass(frozen=True)
class LightTables:
    """
    The sun's and the ground's numbers of an export of ``bands`` bands.

    Attributes
    ----------
    bands
        N.
    has_sun, has_ground
        Whether the file has the sun table (every file since format 3), and the sky's c_10 (>= 2 bands).
        Without them the tables below are zeros and the generated code refuses the option.
    sun_degrees
        (SDX, SDY) of the sun table.
    sun_table
        (SDX + 1, SDY + 1, 3): Chebyshev coefficients of ln X, ln Y, ln Z (ln lux).
    rgb_from_xyz
        (3, 3): the file's XYZ -> linear RGB matrix.
    trig
        (N (N + 1) / 2, 2 N): the sun's SH at azimuth 0 per unit colour, *without* the
        window, as ``[cos(k ts)]_k ++ [sin(k ts)]_k`` (:func:`skysh.lighting.lights.sun_trig_matrix`).
    windows
        The window of every band count n = 1 .. N, concatenated (n entries each).
    ground_zonal
        (N,): :data:`skysh.model.ground.GROUND_ZONAL` (the Gibbs filter is applied in the code).
    c10
        (DX + 1, DY + 1, 3): the unfiltered (1, 0) sky coefficient over the luminance scale,
        at the sky table's degrees.
    constants
        Named scalars of the generated code (:func:`light_tables` lists them).
    """

    bands: int
    has_sun: bool
    has_ground: bool
    sun_degrees: tuple[int, int]
    sun_table: NDArray[np.float64]
    rgb_from_xyz: NDArray[np.float64]
    trig: NDArray[np.float64]
    windows: NDArray[np.float64]
    ground_zonal: NDArray[np.float64]
    c10: NDArray[np.float64]
    constants: dict[str, float]

    def windowed_trig(self) -> NDArray[np.float64]:
        """(N (N + 1) / 2, 2 N): :attr:`trig` with the window of N bands folded into its rows."""
        window = self.windows[-self.bands :]
        rows = [l for l, _ in coefficient_file.zonal_half_layout(self.bands)]
        return self.trig * window[rows][:, None]


def light_tables(sky: Any, bands: int, degrees: tuple[int, int]) -> LightTables:
    """
    The sun's and the ground's numbers for an export of ``bands`` bands.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`: its ``table`` (:class:`skysh.table.coefficient_file.SkyTable`)
        is read through public attributes only.
    bands
        N in [1, the file's bands].
    degrees
        (DX, DY) of the sky table the export embeds (the c_10 table takes the same terms,
        as the runtime's plan of N bands).
    """
    table = sky.table
    bands = check_bands(bands, high=table.bands)
    dx, dy = degrees
    named = table.tables.get("sun")
    has_sun, has_ground = named is not None, table.bands >= 2
    if has_sun:
        sun_table = np.array(named.table[:, 0, :], dtype=np.float64)
        sdx, sdy = named.max_degrees
        rgb = np.array(sunlight.SunLight(table).rgb_from_xyz, dtype=np.float64)
    else:
        sun_table, (sdx, sdy), rgb = np.zeros((1, 3)), (0, 0), np.zeros((3, 3))
    c10 = np.zeros((dx + 1, dy + 1, 3))
    if has_ground:  # the sky's unfiltered (1, 0), at the export's terms
        c10 = chebyshev_terms(table.table[:, 1:2], table.max_degrees, degrees)[:, :, 0]
    a, b, c = KASTEN_COEFFICIENTS  # the sun table's map (skysh.domain.SUN): x = (m - m0) sx_scale - 1, y likewise
    constants = {
        "am_a": a, "am_b": b, "am_neg_c": -c, "deg": 180.0 / math.pi, "m0": SUN.x.origin, "sx_scale": SUN.x.scale,
        "sun_tmin": SUN.y.origin, "sy_scale": SUN.y.scale, "hf": ground.HORIZONTAL_FACTOR, "inv_pi": 1.0 / math.pi,
        "clamp": lights.SUN_SH_CLAMP,
    }
    return LightTables(
        bands=bands, has_sun=has_sun, has_ground=has_ground, sun_degrees=(sdx, sdy),
        sun_table=sun_table.reshape(sdx + 1, sdy + 1, 3), rgb_from_xyz=rgb,
        trig=lights.sun_trig_matrix(bands, np.ones(bands)),
        windows=np.concatenate([solar.sun_window(n) for n in range(1, bands + 1)]),
        ground_zonal=np.array(ground.GROUND_ZONAL[:bands]), c10=c10, constants=constants,
    )


def light_flags(tables: LightTables) -> int:
    """SKYSH_LIGHTS of the generated code: 1 the sun is available, 2 the ground."""
    return int(tables.has_sun) + 2 * int(tables.has_ground)
