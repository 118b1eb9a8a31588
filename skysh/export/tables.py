"""
The numbers every export is written from: the sky's tables and the engines' plans
=================================================================================

Every language of :mod:`skysh.export.c_like` (C, GLSL, HLSL) and of :mod:`skysh.export.js`
(JavaScript, JSON) is generated from the same numbers, prepared here once:

-   :class:`ExportTables`, :func:`export_tables`: the file's sky table as the
    runtime's plan reads it, the certified irradiance table, the variables' affine
    maps and the sun's and the ground's numbers (:func:`skysh.export.lights.light_tables`).
-   :class:`EnginePlan`, :func:`engine_plan`: an engine's linear conversion
    (:func:`skysh.engines.presets.engine_map`) split at the Z rotation (per-band factors
    folded before it, the rest after it), for every export that takes an engine (its
    nonzero terms, :meth:`EnginePlan.terms`, are the exports' index-and-factor tables);
    :data:`ENGINE_ZERO`, :data:`ENGINE_UNIT`: the rounding it snaps to 0 and +-1.
-   :func:`term_major`: a sky table as the compiled exports lay it out, one row of outputs per
    Chebyshev term (a vectorisable pass each).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from skysh import runtime
from skysh.checks import check_bands
from skysh.domain import SKY
from skysh.engines import presets as engines
from skysh.export.lights import LightTables, chebyshev_terms, light_tables
from skysh.sh import basis as sh
from skysh.table import coefficient_file

__all__ = []


@dataclass(frozen=True)
class ExportTables:
    """
    Everything an export is generated from, for one band count.

    Attributes: ``bands`` N (l = 0 .. N - 1); ``degrees`` (DX, DY), the Chebyshev degrees
    in x (sun zenith) and y (log turbidity); ``table`` (DX + 1, DY + 1, N (N + 1) / 2, 3),
    the Chebyshev coefficients (no Gibbs filter) of the stored (m >= 0) SH coefficients
    over the luminance scale (dimensionless), third axis ``half_layout`` (l, m); ``gibbs``
    (N,) sinc(pi l / N); ``lobe`` (N,) A_l; ``x_scale, x_shift, y_scale, y_shift`` the
    variables' affine maps (module docstring, step 2); the fitted domain (radians, turbidity);
    ``lights`` the sun's and the ground's numbers (:func:`skysh.export.lights.light_tables`);
    ``irradiance`` (DX + 1, DY + 1, 6, 3) the certified irradiance table's rows (E_lm / A_l over
    the luminance scale, 3 bands, m >= 0) or None (fewer than 3 bands, or a file without it).
    (DX, DY) are the largest of the N bands' and the irradiance table's, zeros above a table's own.
    """

    bands: int
    degrees: tuple[int, int]
    table: NDArray[np.float64]
    half_layout: list[tuple[int, int]]
    gibbs: NDArray[np.float64]
    lobe: NDArray[np.float64]
    x_scale: float
    x_shift: float
    y_scale: float
    y_shift: float
    sun_zenith_domain: tuple[float, float]
    turbidity_domain: tuple[float, float]
    lights: LightTables
    irradiance: NDArray[np.float64] | None


def export_tables(sky: runtime.SkySH, bands: int = 3) -> ExportTables:
    """
    The numbers of an export: the file's sky table as the runtime's plan for (``bands``, no Gibbs)
    reads it (the largest degrees of bands 0 .. N - 1, the m >= 0 rows), the irradiance table
    (3 bands or more) and the variables' maps.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH` (read through its public ``table``).
    bands
        N in [1, the file's bands].
    """
    if not isinstance(sky, runtime.SkySH):
        raise ValueError(f"sky must be a loaded skysh.SkySH (SkySH.load()), got {type(sky).__name__}")
    bands = check_bands(bands, high=sky.bands)
    named = sky.table.tables.get("irradiance") if sky.has_irradiance_table and bands >= 3 else None
    own = sky.table.degrees[:bands] if named is None else np.concatenate([sky.table.degrees[:bands], named.degrees])
    dx, dy = (int(d) for d in own.max(axis=0))
    layout = coefficient_file.zonal_half_layout(bands)
    table = chebyshev_terms(sky.table.table[:, : len(layout)], sky.table.max_degrees, (dx, dy))
    irradiance = None if named is None else chebyshev_terms(named.table, named.max_degrees, (dx, dy))
    return ExportTables(
        bands=bands, degrees=(dx, dy), table=table, half_layout=layout, gibbs=runtime.gibbs_factors(bands),
        lobe=sh.cosine_lobe(bands), x_scale=SKY.x.scale, x_shift=SKY.x.shift, y_scale=SKY.y.scale,
        y_shift=SKY.y.shift, sun_zenith_domain=SKY.x.interval, turbidity_domain=SKY.y.interval,
        lights=light_tables(sky, bands, (dx, dy)), irradiance=irradiance,
    )


ENGINE_ZERO: float = 1e-13
"""Entries of an engine map smaller than this times its largest entry are rounding
residue of the engine's rotation matrices (exact zeros in closed form) and are
dropped; the change to an output is below 1e-13 of the largest term."""

ENGINE_UNIT: float = 1e-14
"""Entries within this of +-1 once the per-band factor is divided out are +-1 in closed form
(the engines' maps are signs, axis permutations, exact 90-degree rotations and band
constants, built numerically): they are snapped to exact +-1 factors, changing an output by
at most this relative amount."""



def term_major(table: NDArray[np.float64]) -> NDArray[np.float64]:
    """
    A sky table laid out term-major, as C, GLSL and HLSL store ``SKYSH_TABLE`` and ``SKYSH_IRRADIANCE``.

    Parameters
    ----------
    table
        (DX + 1, DY + 1, rows, 3): the Chebyshev coefficient of T_i(x) T_j(y) for stored row r, channel c
        (:attr:`ExportTables.table`, :attr:`ExportTables.irradiance`).

    Returns
    -------
    numpy.ndarray
        (terms, 3 rows): entry [q, o] is term q = i (DY + 1) + j of output o = 3 r + c, so that a
        kernel forms every output as ``acc[o] += w[q] T[q, o]``, one contiguous pass per term.
    """
    return np.ascontiguousarray(table).reshape(table.shape[0] * table.shape[1], -1)


@dataclass(frozen=True)
class EnginePlan:
    """
    An engine's conversion (:func:`skysh.engines.presets.engine_map`) arranged for the exports.

    ``engine_flat = matrix @ (band_factor[l] * radiance_flat) + offset``, where
    ``radiance_flat`` is the skysh radiance coefficients (N * N, 3) flattened
    coefficient-major (index 3 i + channel) and l the band of each column.

    Attributes
    ----------
    engine, bands
        The engine's name and N.
    band_factor
        (N,) per-band factors folded before the Z rotation (they commute with it):
        for each band the most common magnitude of its entries in the engine's
        map (for example A_l / pi times a basis constant), so that the most
        entries of ``matrix`` are exactly +-1.
    matrix
        (P, N * N * 3): the rest of the map (frame change, signs, per-coefficient
        constants, packing), applied after the rotation; entries below
        :data:`ENGINE_ZERO` of the largest are exact zeros.
    offset
        (P,) constant terms of the engine's layout (for example a packed 1).
    shape, labels
        The engine's own array shape (row-major, product P) and the labels of its rows (first axis).
    """

    engine: str
    bands: int
    band_factor: NDArray[np.float64]
    matrix: NDArray[np.float64]
    offset: NDArray[np.float64]
    shape: tuple[int, ...]
    labels: tuple[str, ...]

    def terms(self, row: int) -> list[tuple[int, float]]:
        """The nonzero (column, value) pairs of ``matrix[row]``, columns ascending."""
        (columns,) = np.nonzero(self.matrix[row])
        return [(int(q), float(self.matrix[row, q])) for q in columns]


def _most_common_magnitude(values: NDArray[np.float64]) -> float:
    """The magnitude shared by the most entries (12 significant digits decide equality), or 1 for none."""
    magnitudes = np.abs(values[values != 0.0])
    if magnitudes.size == 0:
        return 1.0
    keys = [f"{v:.11e}" for v in magnitudes]
    best, _ = Counter(keys).most_common(1)[0]  # ties: the first met, column order (deterministic)
    return float(magnitudes[keys.index(best)])


def engine_plan(engine: str, bands: int) -> EnginePlan:
    """
    An engine's conversion for ``bands`` bands, split at the Z rotation (see :class:`EnginePlan`).

    Parameters
    ----------
    engine
        One of :data:`skysh.engines.presets.ENGINES`.
    bands
        N in [1, the engine's limit :data:`skysh.engines.presets.ENGINE_MAX_BANDS`].

    Raises
    ------
    ValueError
        From :func:`skysh.engines.presets.engine_map`: unknown engine (the valid names
        listed) or a band count the engine cannot take.
    """
    emap = engines.engine_map(engine, bands)
    matrix = np.array(emap.matrix, dtype=np.float64)
    offset = np.array(emap.offset, dtype=np.float64).reshape(-1)
    n = int(emap.bands)
    if matrix.shape != (offset.size, n * n * 3):
        raise ValueError(f"engine_map({engine!r}, {bands}) has matrix {matrix.shape} and offset {offset.shape}")
    largest = float(np.abs(matrix).max(initial=0.0))
    matrix[np.abs(matrix) <= ENGINE_ZERO * largest] = 0.0
    band_of_column = np.repeat([sh.lm(i)[0] for i in range(n * n)], 3)
    factors = np.ones(n)
    for l in range(n):
        columns = band_of_column == l
        factor = _most_common_magnitude(matrix[:, columns])
        factors[l] = 1.0 if abs(factor - 1.0) <= ENGINE_UNIT else factor
        matrix[:, columns] /= factors[l]
    unit = np.abs(np.abs(matrix) - 1.0) <= ENGINE_UNIT
    matrix[unit] = np.sign(matrix[unit])
    for array in (factors, matrix, offset):
        array.flags.writeable = False
    return EnginePlan(
        engine=str(emap.engine), bands=n, band_factor=factors, matrix=matrix, offset=offset,
        shape=tuple(int(s) for s in emap.shape), labels=tuple(str(s) for s in emap.labels),
    )
