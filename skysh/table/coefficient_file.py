"""
The versioned coefficient file
==============================

The fitted polynomial tables of the sky's SH coefficients (Habel 2008, eq. 1),
of the sun's direct illuminance (Preetham et al. 1999, appendix) and of the
sky's certified non-negative 3-band irradiance (issue 18, ``docs/irradiance.md``),
their conventions and measured accuracy, in one ``.npz`` file that the runtime
loads and checks. Loading is the one place where untrusted bytes enter skysh,
so :func:`read` accepts exactly what :func:`write` produces and refuses
everything else with one :class:`CoefficientFileError`, at a bounded cost.

-   :class:`SkyTable`: the tables in memory (the sky's, and the named tables).
-   :class:`NamedTable`, :class:`TableSpec`, :data:`TABLES`: the tables besides
    the sky's, each declared once (members, bounds, metadata it must carry).
-   :func:`read`, :func:`write`, :func:`default_path`: the file.
-   :func:`content_sha256`: the content hash recorded in the file.
-   :class:`CoefficientFileError`: raised for a file that does not match.
-   :func:`zonal_half_layout`: the stored coefficient order (m >= 0 only).

File layout (:data:`FORMAT_VERSION` 4)
--------------------------------------
A zip archive (an ``.npz`` that :func:`numpy.load` reads) of stored
(uncompressed) ``.npy`` members in the order of :data:`MEMBERS`: all of
:data:`REQUIRED_MEMBERS`, an optional table's two members together or not at
all. Zip headers (date 1980-01-01, no extra fields or comments) and ``.npy``
headers (version 1.0) are written byte for byte (:mod:`skysh.table.container`), so one
content has exactly one file:

``format.npy``, ``format_version.npy``
    '<U18' scalar :data:`FORMAT`; '<i8' scalar :data:`FORMAT_VERSION`.
``table.npy``, ``degrees.npy`` (the sky)
    '<f8' (n_terms, bands (bands + 1) / 2, 3): Chebyshev coefficients of every
    m >= 0 SH coefficient of every RGB channel over the luminance scale
    (:data:`BASIS`), terms in :data:`skysh.domain.TERM_ORDER` for the largest degrees of any
    band; '<i8' (bands, 2): each band's (d_theta, d_tau), terms above them zero
    in its rows. The sky with its sun at azimuth 0 is even in azimuth: its
    m < 0 coefficients are zero, not stored; the runtime's rotation (eq. 4)
    creates them.
``<name>_table.npy``, ``<name>_degrees.npy`` (each table of :data:`TABLES`)
    The same layout, '<f8' (n_terms, rows, 3) and '<i8' (groups, 2), rows
    grouped as ``zonal_half_layout(groups)``; what the numbers mean is the
    table's metadata block. Both required: ``sun``, one group, one row, ln X,
    ln Y, ln Z of the sun's direct normal illuminance in lux
    (:mod:`skysh.table.sun_table`; :mod:`skysh.lighting.sunlight` evaluates it);
    ``irradiance``, three groups (bands), six rows, the sky's form of the
    constrained 3-band irradiance (:data:`IRRADIANCE_BASIS`), its block recording
    the objective and the non-negativity certificate (:attr:`TableSpec.recorded`).
``metadata.npy``
    '|u1' (n,): a JSON object as ASCII bytes in canonical form (sorted keys,
    no spaces, \\u escapes, no NaN): conventions, grid, versions, measured
    errors, the fields the runtime relies on (:data:`RUNTIME_FIELDS`),
    :data:`HASH_KEY`, and under ``tables`` one block per named table: its
    :attr:`TableSpec.fields` (variables, domain, basis, term order, units),
    ``degrees``, the file's ``colourspace``, its :attr:`TableSpec.matrices`
    (the sun's ``rgb_from_xyz``: the XYZ -> linear RGB matrix of the file's
    colourspace, so the runtime needs no colour library) and the fit's errors.
A further table is one more :class:`TableSpec`: members, bounds, hash, writer
and checks follow from it.

What :func:`read` checks, in this order
---------------------------------------
1.  A regular file (``os.stat``, then ``fstat`` of a descriptor opened non-blocking: a FIFO
    cannot hang) of at most :data:`MAX_FILE_BYTES`, read whole with a bounded read.
2.  The zip directory: only members of :data:`MEMBERS`, none twice, each declaring at most
    its :data:`MAX_MEMBER_BYTES`, before any is read.
3.  ``format`` and ``format_version`` (the only members ever inflated, bounded
    by their declared sizes, for the compressed version-1 files): versions 1
    to 3 (:data:`RETIRED_VERSIONS`) and unknown ones refused by name; then
    every required member present.
4.  Every member stored, its CRC-32, its ``.npy`` header (exact dtype, C order, a byte count
    equal to its shape's); ``allow_pickle`` is never used. 5. The metadata: ASCII, JSON, canonical.
6.  :meth:`SkyTable.validate`: shapes, degrees, bounds, the layout's zeros, fields and blocks.
7.  The content hash (any change to any number or metadata field is refused). 8. The file
    equals, byte for byte, what :func:`write` makes of its content.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import files
from skysh._version import __version__
from skysh.checks import check_count, read_only
from skysh.domain import SKY, SUN, TERM_ORDER
from skysh.table import container, poly
from skysh.table.container import CoefficientFileError
from skysh.table.sun_table import SUN_BASIS, SUN_MAX_LN, SUN_UNITS, SUN_VARIABLES

__all__ = ["DEFAULT_FILE_NAME", "MAX_FILE_DEGREE", "MAX_TABLE_MAGNITUDE", "FILE_COLOURSPACES", "BASIS", "TABLES",
    "CoefficientFileError", "NamedTable", "SkyTable", "zonal_half_layout", "default_path", "read", "write"]

FORMAT: str = "skysh-coefficients"
"""Value of the ``format`` member of every coefficient file."""

FORMAT_VERSION: int = 4
"""Version of the layout above; :func:`read` refuses any other."""

RETIRED_VERSIONS: dict[int, str] = {1: "skysh 0.1.0: compressed, no content hash", 2: "hashed, without the sun's table",
                                    3: "without the irradiance table"}
"""Versions once written and no longer read, with what they lacked (named in the refusal)."""

DEFAULT_FILE_NAME: str = "preetham_sh.npz"
"""Name of the shipped file in ``data/`` (installed as ``skysh/data/``)."""

MAX_FILE_BANDS: int = 7
"""Largest band count a coefficient file may hold (``tools/fit_sky.py --bands`` goes to 7)."""

MAX_FILE_DEGREE: int = 31
"""Largest polynomial degree of any table in either variable: at most 32 x 32 = 1024 terms."""

MAX_TABLE_MAGNITUDE: float = 1.0e4
"""Largest |value| of a sky (or irradiance) table entry (dimensionless: a coefficient over the luminance scale).

The table holds Chebyshev coefficients of c_lm / luminance_scale (:data:`BASIS`); a least-squares
fit of a function bounded by M has coefficients of order M, and the sky's SH coefficients are a few
times its luminance scale at most (``tools/fit_sky.py`` prints the largest |value| of each fit). An
entry near 1e4 is a broken file, not a sky; within the bound every runtime result stays finite:
1024 terms with |T_i T_j| <= 1 give at most about 1e7 times the luminance scale."""

MAX_METADATA_BYTES: int = 65536
"""Largest metadata JSON, bytes (a fit writes a few kilobytes)."""

MAX_MATRIX_ENTRY: float = 16.0
"""Largest |entry| of a matrix in a table block, so RGB = matrix @ XYZ stays finite; the XYZ -> RGB
matrices of every :data:`FILE_COLOURSPACES` lie within it (tests/table/test_coefficient_file.py checks)."""

FILE_COLOURSPACES: tuple[str, ...] = (
    "sRGB", "ITU-R BT.709", "ITU-R BT.2020", "Display P3", "DCI-P3", "P3-D65", "Adobe RGB (1998)", "ProPhoto RGB",
    "ACEScg", "ACES2065-1",
)
"""colour-science RGB colourspace names a file may be fitted in (each a key of
``colour.RGB_COLOURSPACES``, checked by tests/table/test_coefficient_file.py), listed
here so that reading a file never imports colour-science."""

BASIS: str = (
    "coefficient = luminance_scale(sun_zenith, T) * sum table[i (d_tau+1) + j] T_i(x) T_j(y); "
    "x = 4 sun_zenith / pi - 1, y = (2 ln T - ln 2.5 - ln 6) / (ln 6 - ln 2.5); "
    "luminance_scale = Y_z / F_Y(0, sun_zenith) (Preetham appendix, cd/m^2)"
)
"""The polynomial form the runtime evaluates (skysh.table.poly.scale, skysh.model.preetham.luminance_scale)."""

IRRADIANCE_BASIS: str = (
    "irradiance coefficient (l, m) = A_l * (the BASIS form of its row), A_l = pi, 2 pi / 3, pi / 4; "
    "3 bands, rows m >= 0, sun at azimuth 0 (rotated about Z as the sky, Habel eq. 4)"
)
"""The irradiance table's form: the sky table's (:data:`BASIS`) times the clamped-cosine factor A_l."""

DOMAIN: dict[str, list[float]] = SKY.metadata()
"""The fitted domain the runtime's variables assume (radians; turbidity), as the file records it
(:meth:`skysh.domain.Domain.metadata` of :data:`skysh.domain.SKY`; the sun table's is the same)."""

HASH_KEY: str = "content_sha256"
"""Metadata key of the content hash (:func:`content_sha256`)."""

RUNTIME_FIELDS: tuple[str, ...] = ("colourspace", "domain", "basis", "term_order", "degrees", "bands", "tables")
"""Metadata fields the runtime relies on: required in a file, checked wherever present."""

@dataclass(frozen=True)
class TableSpec:
    """
    What the format requires of one named table (an entry of :data:`TABLES`).

    ``name``: members ``<name>_table.npy``, ``<name>_degrees.npy``, metadata
    block ``tables[name]``. ``required``: in every file (else both members or
    neither). ``groups``: (low, high) count of degree pairs.
    ``fields``: fixed block fields the runtime relies on, filled in by
    :func:`write`, any other value refused. ``max_magnitude``, ``max_abs_sum``
    (or None): largest |entry| and largest sum of |entries| per (row, channel),
    named ``bound_name`` in refusals. ``matrices``: block fields holding a
    3 x 3 list of numbers within :data:`MAX_MATRIX_ENTRY` (required). ``recorded``:
    block fields required in a file, of any JSON value (what the fit measured).
    """

    name: str
    required: bool
    groups: tuple[int, int]
    fields: Mapping[str, Any]
    max_magnitude: float
    max_abs_sum: float | None = None
    bound_name: str = "MAX_TABLE_MAGNITUDE"
    matrices: tuple[str, ...] = ()
    recorded: tuple[str, ...] = ()

    @property
    def members(self) -> tuple[str, str]:
        """The table's two member names."""
        return f"{self.name}_table.npy", f"{self.name}_degrees.npy"


TABLES: tuple[TableSpec, ...] = (
    TableSpec(
        name="sun", required=True, groups=(1, 1),
        fields={"air_mass_range": list(SUN.x.fitted), "basis": SUN_BASIS, "domain": DOMAIN,
                "term_order": TERM_ORDER, "units": SUN_UNITS, "variables": SUN_VARIABLES},
        max_magnitude=SUN_MAX_LN, max_abs_sum=SUN_MAX_LN, bound_name="SUN_MAX_LN", matrices=("rgb_from_xyz",),
    ),
    TableSpec(
        name="irradiance", required=True, groups=(3, 3),
        fields={"basis": IRRADIANCE_BASIS, "domain": DOMAIN, "term_order": TERM_ORDER,
                "units": "cd/m^2 x sr (irradiance; lux for the luminance), linear RGB"},
        max_magnitude=MAX_TABLE_MAGNITUDE, recorded=("objective", "margin", "fit_error", "nonnegativity"),
    ),
)
"""The named tables of format version 4, in member order."""

_SKY: TableSpec = TableSpec(name="sky", required=True, groups=(1, MAX_FILE_BANDS), fields={}, max_magnitude=MAX_TABLE_MAGNITUDE)
"""The sky's own table in the terms of a :class:`TableSpec` (its groups are the bands), for the checks all tables share."""


def _layout(tables: tuple[TableSpec, ...]) -> tuple[tuple[str, ...], tuple[str, ...], dict[str, int], int]:
    """(MEMBERS, REQUIRED_MEMBERS, MAX_MEMBER_BYTES, MAX_FILE_BYTES) of a set of named tables."""
    header, terms = container.NPY_HEADER_MAX, (MAX_FILE_DEGREE + 1) ** 2
    bounds = {
        "format.npy": header + 4 * 64,  # a '<U' string of up to 64 characters
        "format_version.npy": header + 8,
        "table.npy": header + 8 * 3 * terms * (MAX_FILE_BANDS * (MAX_FILE_BANDS + 1) // 2),
        "degrees.npy": header + 8 * 2 * MAX_FILE_BANDS,
    }
    for spec in tables:
        rows = spec.groups[1] * (spec.groups[1] + 1) // 2
        bounds[spec.members[0]] = header + 8 * 3 * terms * rows
        bounds[spec.members[1]] = header + 8 * 2 * spec.groups[1]
    bounds["metadata.npy"] = header + MAX_METADATA_BYTES
    required = tuple(name for name in bounds if not any(name in s.members for s in tables if not s.required))
    return tuple(bounds), required, bounds, container.zip_bytes(bounds)


MEMBERS, REQUIRED_MEMBERS, MAX_MEMBER_BYTES, MAX_FILE_BYTES = _layout(TABLES)
"""MEMBERS: every member a file may hold, in the order :func:`write` stores them; REQUIRED_MEMBERS: those
every file holds; MAX_MEMBER_BYTES: the largest size of each member (bytes) from the bounds above;
MAX_FILE_BYTES: the largest file, every member at its bound, stored, with its zip headers."""

_SHA256_HEX = re.compile(r"[0-9a-f]{64}")


def zonal_half_layout(bands: int) -> list[tuple[int, int]]:
    """Order of the stored coefficients: ``[(l, m) for l in range(bands) for m in range(l + 1)]``."""
    bands = check_count(bands, "bands", 1, MAX_FILE_BANDS)
    return [(l, m) for l in range(bands) for m in range(l + 1)]


def _canonical(value: Any) -> bytes:
    """Canonical JSON bytes: sorted keys, no spaces, ASCII, no NaN or inf (ValueError/TypeError otherwise)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode("ascii")


def _canonical_or_none(value: Any) -> bytes | None:
    """:func:`_canonical`, or None for a value it refuses (not JSON, NaN or inf, a number too large for a float)."""
    try:
        return _canonical(value)
    except (TypeError, ValueError):
        return None


def _same(a: Any, b: Any) -> bool:
    canonical = _canonical_or_none(a)
    return canonical is not None and canonical == _canonical_or_none(b)


def _max_degrees(degrees: NDArray[np.int64]) -> tuple[int, int]:
    """Largest (d_x, d_y) of any group of ``degrees`` (groups, 2): the term layout of their table."""
    return int(degrees[:, 0].max()), int(degrees[:, 1].max())


def _term_mask(degrees: Any, within: tuple[int, int]) -> NDArray[np.bool_]:
    """Which terms of a table of degrees ``within`` (its layout) belong to a polynomial of ``degrees`` (d_x, d_y)."""
    i, j = np.meshgrid(np.arange(within[0] + 1), np.arange(within[1] + 1), indexing="ij")
    return ((i <= degrees[0]) & (j <= degrees[1])).ravel()


def _describe(value: Any) -> str:
    return f"an array of dtype {value.dtype}" if isinstance(value, np.ndarray) else type(value).__name__


def _spec(name: Any) -> TableSpec:
    spec = next((s for s in TABLES if s.name == name), None)
    if spec is None:
        raise CoefficientFileError(f"unknown table {name!r}; format version {FORMAT_VERSION} knows {[s.name for s in TABLES]}")
    return spec


# --------------------------------------------------------------------------- #
# Tables in memory and their checks
# --------------------------------------------------------------------------- #
def _check_arrays(table: Any, degrees: Any, names: tuple[str, str, str], spec: TableSpec) -> None:
    """Dtypes, shapes, degrees, finite values within ``spec``'s bounds and the layout's zeros of one (table, degrees) pair."""
    t_name, d_name, unit = names
    if not isinstance(table, np.ndarray) or table.dtype.kind != "f":
        raise CoefficientFileError(f"{t_name} must be a numpy array of floats, got {_describe(table)}")
    _check_degrees(degrees, d_name, unit, spec.groups)
    n = degrees.shape[0]
    expected = (poly.n_terms(_max_degrees(degrees)), n * (n + 1) // 2, 3)
    if table.shape != expected:
        raise CoefficientFileError(f"{t_name} must have shape {expected} for {d_name} {degrees.tolist()}, got {table.shape}")
    _check_values(table, t_name, spec)
    _check_layout_zeros(table, degrees, names)


def _check_degrees(degrees: Any, d_name: str, unit: str, groups: tuple[int, int]) -> None:
    """:func:`_check_arrays`' degrees: an integer array of shape (groups, 2), each in [0, :data:`MAX_FILE_DEGREE`]."""
    if not isinstance(degrees, np.ndarray) or degrees.dtype.kind not in "iu":
        raise CoefficientFileError(f"{d_name} must be a numpy array of integers, got {_describe(degrees)}")
    if degrees.ndim != 2 or degrees.shape[1] != 2 or not groups[0] <= degrees.shape[0] <= groups[1]:
        raise CoefficientFileError(
            f"{d_name} must have shape ({unit}, 2) with {groups[0]} <= {unit} <= {groups[1]}, got {degrees.shape}")
    if degrees.min() < 0 or degrees.max() > MAX_FILE_DEGREE:
        raise CoefficientFileError(f"{d_name} must lie in [0, {MAX_FILE_DEGREE}], got {degrees.tolist()}")


def _check_values(table: NDArray[np.float64], t_name: str, spec: TableSpec) -> None:
    """:func:`_check_arrays`' values: finite, within ``spec.max_magnitude`` and (if given) ``spec.max_abs_sum`` per channel."""
    if not np.all(np.isfinite(table)):
        raise CoefficientFileError(f"{t_name} holds NaN or inf")
    largest = float(np.abs(table).max())
    if largest > spec.max_magnitude:
        raise CoefficientFileError(
            f"{t_name} holds |value| {largest:.3g}, above {spec.max_magnitude:g} ({spec.bound_name}): not a fitted table")
    if spec.max_abs_sum is not None and float(np.abs(table).sum(axis=0).max()) > spec.max_abs_sum:
        raise CoefficientFileError(
            f"{t_name} sums |values| to {float(np.abs(table).sum(axis=0).max()):.3g} in a channel, above {spec.max_abs_sum:g} "
            f"({spec.bound_name}): its exponential could overflow")


def _check_layout_zeros(table: NDArray[np.float64], degrees: NDArray[np.int64], names: tuple[str, str, str]) -> None:
    """:func:`_check_arrays`' layout promise (shapes checked): terms above a group's own degrees are zero in its rows."""
    t_name, d_name, unit = names
    for row, (l, _) in enumerate(zonal_half_layout(degrees.shape[0])):
        if np.any(table[~_term_mask(degrees[l], _max_degrees(degrees)), row] != 0.0):
            raise CoefficientFileError(
                f"{t_name} has non-zero terms above the degrees {degrees[l].tolist()} of {unit[:-1]} {l}: "
                f"{d_name} and {t_name} disagree")


def _check_present_fields(where: str, block: dict[str, Any], keys: tuple[str, ...], why: str) -> None:
    """Refuse a metadata object (``where``) that lacks any of ``keys`` (``why`` they are needed)."""
    missing = [key for key in keys if key not in block]
    if missing:
        raise CoefficientFileError(f"{where} lacks the fields {missing} {why}")


def _check_same_fields(where: str, block: dict[str, Any], expected: Mapping[str, Any]) -> None:
    """Refuse a field of a metadata object (``where``) present with another value than ``expected`` holds."""
    for key, value in expected.items():
        if key in block and not _same(block[key], value):
            raise CoefficientFileError(f"{where} {key} {block[key]!r} differs from {value!r}, which this skysh's runtime assumes")


def _runtime_values(degrees: NDArray[np.int64]) -> dict[str, Any]:
    """The values this skysh's runtime assumes of the :data:`RUNTIME_FIELDS` but the colourspace and the tables,
    for the sky's per-band ``degrees`` (bands, 2)."""
    return {"domain": DOMAIN, "basis": BASIS, "term_order": TERM_ORDER, "degrees": degrees.tolist(),
            "bands": int(degrees.shape[0])}


def _check_block(spec: TableSpec, block: Any, named: NamedTable | None, colourspace: Any, required: bool) -> None:
    """One table's metadata block: its fixed fields, degrees, colourspace and matrices."""
    where = f"metadata tables[{spec.name!r}]"
    if not isinstance(block, dict):
        raise CoefficientFileError(f"{where} must be a JSON object, got {_describe(block)}")
    expected: dict[str, Any] = {**spec.fields, "colourspace": colourspace}
    if named is not None:
        expected["degrees"] = named.degrees.tolist()
    if required:
        _check_present_fields(where, block, (*expected, *spec.matrices, *spec.recorded), "the format requires")
    _check_same_fields(where, block, expected)
    for key in spec.matrices:
        if key in block:
            _check_matrix(where, key, block[key])


def _check_matrix(where: str, key: str, value: Any) -> None:
    """One matrix field of a metadata block: a 3 x 3 list of Python numbers within +-:data:`MAX_MATRIX_ENTRY`."""
    try:
        matrix = np.array(value, dtype=np.float64)
        ok = (matrix.shape == (3, 3) and all(type(v) in (int, float) for row in value for v in row)
              and bool(np.all(np.abs(matrix) <= MAX_MATRIX_ENTRY)))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise CoefficientFileError(f"{where} {key} must be a 3 x 3 list of numbers within +-{MAX_MATRIX_ENTRY:g}, got "
                                   f"{value!r}")


def _check_runtime_metadata(metadata: dict[str, Any], sky: SkyTable, required: bool) -> None:
    """The metadata fields the runtime relies on: all present if ``required``, each valid where present."""
    if required:
        _check_present_fields("metadata", metadata, RUNTIME_FIELDS + (HASH_KEY,), "the runtime relies on")
    if "colourspace" in metadata:
        name = metadata["colourspace"]
        if not isinstance(name, str) or name not in FILE_COLOURSPACES:
            raise CoefficientFileError(
                f"metadata colourspace {name!r} is not one a coefficient file may use ({', '.join(FILE_COLOURSPACES)})")
    _check_same_fields("metadata", metadata, _runtime_values(sky.degrees))
    _check_table_blocks(metadata, sky, required)


def _check_table_blocks(metadata: dict[str, Any], sky: SkyTable, required: bool) -> None:
    """The metadata's ``tables``: a JSON object with a block per table held (each :func:`_check_block`)."""
    blocks = metadata.get("tables", {})
    if not isinstance(blocks, dict):
        raise CoefficientFileError(f"metadata tables must be a JSON object, got {_describe(blocks)}")
    held = set(sky.tables)  # in memory a block may describe a known table not held (it is then unused)
    if set(blocks) != held if required else not set(blocks) <= held | {s.name for s in TABLES}:
        raise CoefficientFileError(f"metadata tables describes {sorted(blocks)}; the tables held are {sorted(sky.tables)}")
    for name, block in blocks.items():
        _check_block(_spec(name), block, sky.tables.get(name), metadata.get("colourspace", "sRGB"), required)


@dataclass(frozen=True)
class NamedTable:
    """One named table besides the sky's (:data:`TABLES` says what each means): ``table`` (n_terms, rows, 3)
    Chebyshev coefficients in :data:`skysh.domain.TERM_ORDER`; ``degrees`` (groups, 2) per-group (d_x, d_y) in [0, 31]."""

    table: NDArray[np.float64]
    degrees: NDArray[np.int64]

    @property
    def max_degrees(self) -> tuple[int, int]:
        """Largest (d_x, d_y) of any group: the term layout of :attr:`table`."""
        return _max_degrees(self.degrees)


@dataclass(frozen=True)
class SkyTable:
    """
    Fitted polynomial tables of the sky's SH coefficients, and the named tables.

    Attributes
    ----------
    table
        (n_terms, bands (bands + 1) / 2, 3) Chebyshev coefficients of the
        coefficients over the luminance scale (dimensionless; :data:`BASIS`).
    degrees
        (bands, 2) per-band (d_theta, d_tau), each in [0, :data:`MAX_FILE_DEGREE`].
    metadata
        Conventions, settings and measured errors (see the module docstring),
        with a block per named table under ``"tables"``; a table read from a
        file also holds :data:`HASH_KEY`.
    tables
        :class:`NamedTable` by name (:data:`TABLES`): ``"sun"`` and
        ``"irradiance"`` in every file; optional in memory (a SkyTable without
        them serves the sky but cannot be written).
    """

    table: NDArray[np.float64]
    degrees: NDArray[np.int64]
    metadata: dict[str, Any] = field(default_factory=dict)
    tables: Mapping[str, NamedTable] = field(default_factory=dict)

    @property
    def bands(self) -> int:
        """Number of SH bands in the file."""
        return int(self.degrees.shape[0])

    @property
    def max_degrees(self) -> tuple[int, int]:
        """Largest (d_theta, d_tau) of any band: the term layout of :attr:`table`."""
        return _max_degrees(self.degrees)

    @property
    def colourspace(self) -> str:
        """colour-science name of the RGB space the sky was fitted in (default sRGB)."""
        return str(self.metadata.get("colourspace", "sRGB"))

    def validate(self) -> None:
        """
        Raise :class:`CoefficientFileError` unless the tables can be used: for the sky and every
        named table (names of :data:`TABLES`), arrays of floats and integers, degrees within the
        allowed count and [0, :data:`MAX_FILE_DEGREE`], the shape for them, finite values within
        the table's bounds, zeros above each group's degrees; valid :data:`RUNTIME_FIELDS` and
        table blocks where present.
        """
        _check_arrays(self.table, self.degrees, ("table", "degrees", "bands"), _SKY)
        if not isinstance(self.tables, Mapping):
            raise CoefficientFileError(f"tables must be a mapping of names to NamedTable, got {_describe(self.tables)}")
        for name, named in self.tables.items():
            spec = _spec(name)
            if not isinstance(named, NamedTable):
                raise CoefficientFileError(f"tables[{name!r}] must be a NamedTable, got {_describe(named)}")
            _check_arrays(named.table, named.degrees, (f"{name}_table", f"{name}_degrees", "groups"), spec)
        if not isinstance(self.metadata, dict):
            raise CoefficientFileError(f"metadata must be a dict, got {_describe(self.metadata)}")
        _check_runtime_metadata(self.metadata, self, required=False)


def _arrays(sky: SkyTable) -> list[tuple[str, NDArray]]:
    """(member stem, array) of every table array, in member order, little-endian C order."""
    out = [("table", np.ascontiguousarray(sky.table, dtype="<f8")), ("degrees", np.ascontiguousarray(sky.degrees, dtype="<i8"))]
    for spec in TABLES:
        if spec.name in sky.tables:
            named = sky.tables[spec.name]
            out += [(f"{spec.name}_table", np.ascontiguousarray(named.table, dtype="<f8")),
                    (f"{spec.name}_degrees", np.ascontiguousarray(named.degrees, dtype="<i8"))]
    return out


def content_sha256(table: NDArray, degrees: NDArray, metadata: dict[str, Any],
                   tables: Mapping[str, NamedTable] | None = None) -> str:
    """
    The content hash recorded in a file's metadata under :data:`HASH_KEY`.

    SHA-256 (hex) of, in this order: ``"skysh-coefficients\\n4\\n"``; for every
    array in member order (``table`` and ``degrees``, then ``<name>_table`` and
    ``<name>_degrees`` of each named table present, in :data:`TABLES` order;
    floats '<f8', integers '<i8'), the line ``"<name> <dtype> <shape as a JSON
    list> <byte count>\\n"`` followed by the C-order bytes; then ``"metadata
    <byte count>\\n"`` and the canonical JSON (sorted keys, no spaces, ASCII) of
    ``metadata`` without :data:`HASH_KEY`. Every number and every metadata
    field (the colourspace and the table blocks included) is covered.
    """
    digest = hashlib.sha256(f"{FORMAT}\n{FORMAT_VERSION}\n".encode("ascii"))
    for name, values in _arrays(SkyTable(table, degrees, tables=dict(tables or {}))):
        digest.update(f"{name} {values.dtype.str} {list(values.shape)} {values.nbytes}\n".encode("ascii"))
        digest.update(values.tobytes())
    text = _canonical({key: value for key, value in metadata.items() if key != HASH_KEY})
    digest.update(f"metadata {len(text)}\n".encode("ascii"))
    digest.update(text)
    return digest.hexdigest()


def default_path() -> Path:
    """Path of the shipped coefficient file (installed package first, then a source checkout)."""
    here = Path(__file__).resolve().parents[1]  # the skysh package (skysh/table/coefficient_file.py)
    for candidate in (here / "data" / DEFAULT_FILE_NAME, here.parent / "data" / DEFAULT_FILE_NAME):
        if candidate.is_file():
            return candidate
    raise CoefficientFileError(
        f"the shipped coefficient file {DEFAULT_FILE_NAME} was not found next to the package "
        f"({here / 'data'}) or in the source tree ({here.parent / 'data'}); reinstall skysh, "
        "or run `skysh fit --out data/preetham_sh.npz --force` in a source checkout")


# --------------------------------------------------------------------------- #
# Encoding and decoding (the container is skysh.table.container)
# --------------------------------------------------------------------------- #
def _encode(sky: SkyTable, metadata_bytes: bytes) -> bytes:
    """The file's bytes: the members stored (uncompressed) in a zip with fixed headers."""
    arrays = [("format", np.array(FORMAT, dtype=f"<U{len(FORMAT)}")), ("format_version", np.array(FORMAT_VERSION, dtype="<i8"))]
    arrays += _arrays(sky) + [("metadata", np.frombuffer(metadata_bytes, dtype="|u1"))]
    return container.encode([(f"{name}.npy", array) for name, array in arrays])


def _check_version(data: bytes, members: dict[str, container.Member], directory: int) -> None:
    """The ``format`` string and ``format_version``: this format, version :data:`FORMAT_VERSION` only."""
    _check_present(members, ("format.npy", "format_version.npy"))
    text = str(container.array(container.payload(data, members["format.npy"], directory), "format.npy", None, "U", 0)[()])
    if text != FORMAT:
        raise CoefficientFileError(f"has format {text!r}, expected {FORMAT!r}")
    payload = container.payload(data, members["format_version.npy"], directory)
    raw = container.array(payload, "format_version.npy", None, "biufUS", 0)
    if raw.dtype.kind not in "iu" or raw.dtype.itemsize > 8:
        raise CoefficientFileError(f"has a malformed format version {raw.tolist()!r}; expected the integer {FORMAT_VERSION}")
    version = int(raw[()])
    regenerate = "regenerate the file with `skysh fit --out FILE` (tools/fit_sky.py)"
    if version in RETIRED_VERSIONS:
        raise CoefficientFileError(
            f"format version {version} ({RETIRED_VERSIONS[version]}) is no longer read: this skysh ({__version__}) "
            f"reads format version {FORMAT_VERSION} only (hashed, strictly checked, with the sun's and the irradiance "
            f"tables); {regenerate}")
    if version != FORMAT_VERSION:
        raise CoefficientFileError(
            f"has format version {version}; this skysh ({__version__}) reads format version {FORMAT_VERSION} only "
            f"({regenerate}, or use the skysh that wrote it)")
    compressed = [name for name in members if members[name].method != container.STORED]
    if compressed:
        raise CoefficientFileError(f"members {compressed} are compressed; format version {FORMAT_VERSION} stores every member "
                                   "uncompressed")


def _check_present(members: Mapping[str, Any], needed: tuple[str, ...]) -> None:
    """Refuse a directory lacking any of ``needed`` or holding half of an optional table."""
    missing = [name for name in needed if name not in members]
    for spec in TABLES:
        if not spec.required and (spec.members[0] in members) != (spec.members[1] in members):
            missing += [name for name in spec.members if name not in members]
    if missing:
        raise CoefficientFileError(f"lacks the members {missing} (holds {list(members)}); is it a skysh coefficient file?")


def _metadata(raw: bytes) -> dict[str, Any]:
    """The metadata object: ASCII canonical JSON, nothing else."""
    try:
        metadata = json.loads(raw.decode("ascii"))
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise CoefficientFileError(f"has unreadable metadata ({type(error).__name__}: {error})") from None
    if not isinstance(metadata, dict):
        raise CoefficientFileError(f"has metadata that is not a JSON object (a {type(metadata).__name__})")
    if _canonical_or_none(metadata) != raw:  # also NaN, inf or a number too large for a float
        raise CoefficientFileError("has metadata not in canonical form (sorted keys, no spaces, ASCII, no NaN): altered after "
                                   "writing")
    return metadata


def _decode(data: bytes) -> SkyTable:
    """Every check of the module docstring, in order, on a file's bytes."""
    members, directory = container.directory(data, MEMBERS)
    container.check_declared(members, MAX_MEMBER_BYTES, len(data))
    _check_version(data, members, directory)
    _check_present(members, REQUIRED_MEMBERS)

    def member(name: str, dtype: str, kinds: str, ndim: int | None = None) -> NDArray:
        return container.array(container.payload(data, members[name], directory), name, dtype, kinds, ndim).copy()

    tables = {spec.name: NamedTable(member(spec.members[0], "<f8", "f"), member(spec.members[1], "<i8", "i"))
              for spec in TABLES if spec.members[0] in members}
    raw = member("metadata.npy", "|u1", "u", 1).tobytes()
    if len(raw) > MAX_METADATA_BYTES:
        raise CoefficientFileError(f"metadata is {len(raw)} bytes, above MAX_METADATA_BYTES = {MAX_METADATA_BYTES}")
    metadata = _metadata(raw)
    sky = SkyTable(member("table.npy", "<f8", "f"), member("degrees.npy", "<i8", "i"), metadata, tables)
    sky.validate()
    _check_runtime_metadata(metadata, sky, required=True)
    recorded, computed = metadata[HASH_KEY], content_sha256(sky.table, sky.degrees, metadata, tables)
    if not isinstance(recorded, str) or not _SHA256_HEX.fullmatch(recorded):
        raise CoefficientFileError(f"metadata {HASH_KEY} {recorded!r} is not a SHA-256 hex digest")
    if recorded != computed:
        raise CoefficientFileError(
            f"content hash mismatch: the metadata records sha256 {recorded[:16]}..., the content hashes to "
            f"{computed[:16]}...: numbers or metadata were changed after writing")
    expected = _encode(sky, raw)
    if expected != data:
        n = min(len(expected), len(data))
        differ = np.flatnonzero(np.frombuffer(expected[:n], np.uint8) != np.frombuffer(data[:n], np.uint8))
        raise CoefficientFileError(
            f"differs from what skysh writes for its content (first at byte {int(differ[0]) if differ.size else n} "
            f"of {len(data)}): headers altered, or written by another program")
    read_only(sky.table, sky.degrees, *(a for t in tables.values() for a in (t.table, t.degrees)))
    return sky


# --------------------------------------------------------------------------- #
# Files
# --------------------------------------------------------------------------- #
def read(path: str | os.PathLike | None = None) -> SkyTable:
    """
    Read and check a coefficient file (every check of the module docstring).

    ``path``: the file; default :func:`default_path`. Returns a :class:`SkyTable` of read-only
    arrays (the sky's and every named table) and the metadata as written (with :data:`HASH_KEY`).

    Raises
    ------
    CoefficientFileError
        For every kind of failure (missing, special or too large file, truncated, corrupted,
        hostile members, other format or version, wrong dtypes, shapes or values, unusable
        metadata, hash mismatch, altered headers), with the path and what is wrong. Costs at
        most one read of :data:`MAX_FILE_BYTES` and a few copies of it.
    """
    path = default_path() if path is None else container.as_path(path)
    data = container.read_bytes(path, MAX_FILE_BYTES)
    try:
        return _decode(data)
    except CoefficientFileError as error:
        raise CoefficientFileError(f"{path}: {error}") from None
    except Exception as error:
        raise CoefficientFileError(f"{path}: {container.NOT_NPZ} ({type(error).__name__}: {error})") from None


def _stored_metadata(sky_table: SkyTable) -> dict[str, Any]:
    """The caller's metadata with the runtime fields and table blocks filled in where absent, as JSON types."""
    caller = {key: value for key, value in sky_table.metadata.items() if key != HASH_KEY}
    metadata = {"colourspace": "sRGB", **_runtime_values(sky_table.degrees), **caller}
    blocks = metadata.setdefault("tables", {})
    if isinstance(blocks, dict):  # else refused by the checks
        metadata["tables"] = blocks = dict(blocks)
        for spec in TABLES:
            if spec.name in sky_table.tables and isinstance(blocks.get(spec.name, {}), dict):
                filled = {**spec.fields, "colourspace": metadata["colourspace"],
                          "degrees": sky_table.tables[spec.name].degrees.tolist()}
                blocks[spec.name] = {**filled, **blocks.get(spec.name, {})}
    try:
        return json.loads(_canonical(metadata))  # JSON types only: tuples become lists
    except (TypeError, ValueError) as error:
        raise CoefficientFileError(f"metadata must be JSON with str keys and finite numbers: {error}") from None


def write(path: str | os.PathLike, sky_table: SkyTable) -> Path:
    """
    Write ``sky_table`` to ``path`` after validating it; return the path.

    The metadata is stored with the :data:`RUNTIME_FIELDS` this skysh assumes
    filled in where absent (colourspace sRGB, :data:`DOMAIN`, :data:`BASIS`,
    :data:`skysh.domain.TERM_ORDER`, the degrees and band count, and a block per named
    table with its :attr:`TableSpec.fields`, degrees and the colourspace) and
    refused where they disagree, then hashed (:func:`content_sha256`). The
    bytes are checked by :func:`read`'s own decoder, written to a temporary
    file beside ``path`` and renamed over it: never left half written.

    Raises
    ------
    CoefficientFileError
        If the tables fail :meth:`SkyTable.validate`; a required table (the sun's, the
        irradiance's), a block's matrix (``rgb_from_xyz``) or recorded field is missing; ``path``
        is not a str or path, ``sky_table`` not a SkyTable, or the metadata not JSON (str keys;
        finite numbers) or above :data:`MAX_METADATA_BYTES`.
    OSError
        If the file cannot be written.
    """
    path = container.as_path(path)
    if not isinstance(sky_table, SkyTable):
        raise CoefficientFileError(f"sky_table must be a skysh.table.coefficient_file.SkyTable, got {type(sky_table).__name__}")
    sky_table.validate()
    absent = [spec.name for spec in TABLES if spec.required and spec.name not in sky_table.tables]
    if absent:
        raise CoefficientFileError(
            f"a file of format version {FORMAT_VERSION} holds the tables {absent}; this SkyTable has none "
            "(tools/fit_sky.py fits them)")
    metadata = _stored_metadata(sky_table)  # the arrays are stored as _arrays makes them: '<f8' and '<i8', C order
    metadata[HASH_KEY] = content_sha256(sky_table.table, sky_table.degrees, metadata, sky_table.tables)
    raw = _canonical(metadata)
    if len(raw) > MAX_METADATA_BYTES:
        raise CoefficientFileError(f"metadata is {len(raw)} bytes as JSON, above MAX_METADATA_BYTES = {MAX_METADATA_BYTES}")
    data = _encode(sky_table, raw)
    _decode(data)  # what is written reads back (every check of read, the runtime fields included)
    return files.write_atomic(path, data, parents=True)
