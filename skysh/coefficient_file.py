"""
The versioned coefficient file
==============================

The fitted polynomial tables of the sky's SH coefficients (Habel 2008, eq. 1),
their conventions and their measured accuracy, in one ``.npz`` file that the
runtime loads and checks.

-   :class:`SkyTable`: the tables in memory.
-   :func:`read`, :func:`write`: the file, with format-version and shape checks.
-   :func:`default_path`: the file shipped with the package.
-   :class:`CoefficientFileError`: raised for a file that does not match.
-   :func:`zonal_half_layout`: the stored coefficient order (m >= 0 only).

File layout (``FORMAT_VERSION`` 1), all arrays, no pickles:

``format``
    The string ``"skysh-coefficients"``.
``format_version``
    Integer, :data:`FORMAT_VERSION`.
``table``
    float64 (n_terms, bands (bands + 1) / 2, 3): Chebyshev coefficients of
    every m >= 0 SH coefficient of every RGB channel, terms ordered as
    :func:`skysh.poly.design` for the largest degrees of any band. The sky with
    its sun at azimuth 0 is even in azimuth, so its m < 0 coefficients are zero
    and are not stored; the runtime's rotation (eq. 4) creates them.
``degrees``
    int (bands, 2): the (d_theta, d_tau) of each band; terms above a band's
    degrees are zero in its rows.
``metadata``
    A JSON string: conventions, domain, basis, grid, quadrature, versions,
    and the error figures measured on held-out points.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import poly

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "DEFAULT_FILE_NAME",
    "MAX_FILE_BANDS",
    "CoefficientFileError",
    "SkyTable",
    "zonal_half_layout",
    "default_path",
    "read",
    "write",
]

FORMAT: str = "skysh-coefficients"
"""Value of the ``format`` entry of every coefficient file."""

FORMAT_VERSION: int = 1
"""Version of the layout above; :func:`read` refuses any other."""

DEFAULT_FILE_NAME: str = "preetham_sh.npz"
"""Name of the shipped file in ``data/`` (installed as ``skysh/data/``)."""

MAX_FILE_BANDS: int = 16
"""Largest band count a coefficient file may hold."""


class CoefficientFileError(ValueError):
    """A coefficient file that cannot be used: missing, truncated, wrong version or shapes."""


def zonal_half_layout(bands: int) -> list[tuple[int, int]]:
    """Order of the stored coefficients: ``[(l, m) for l in range(bands) for m in range(l + 1)]``."""
    return [(l, m) for l in range(bands) for m in range(l + 1)]  # noqa: E741


@dataclass(frozen=True)
class SkyTable:
    """
    Fitted polynomial tables of the sky's SH coefficients.

    Attributes
    ----------
    table
        (n_terms, bands (bands + 1) / 2, 3) Chebyshev coefficients (cd/m^2).
    degrees
        (bands, 2) per-band (d_theta, d_tau).
    metadata
        Conventions, settings and measured errors (see the module docstring).
    """

    table: NDArray[np.float64]
    degrees: NDArray[np.int64]
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def bands(self) -> int:
        """Number of SH bands in the file."""
        return int(self.degrees.shape[0])

    @property
    def max_degrees(self) -> tuple[int, int]:
        """Largest (d_theta, d_tau) of any band: the term layout of :attr:`table`."""
        d = self.degrees.max(axis=0)
        return int(d[0]), int(d[1])

    @property
    def colourspace(self) -> str:
        """colour-science name of the RGB space the sky was fitted in."""
        return str(self.metadata.get("colourspace", "sRGB"))

    def validate(self) -> None:
        """Raise :class:`CoefficientFileError` unless the arrays are consistent and finite."""
        degrees = self.degrees
        if degrees.ndim != 2 or degrees.shape[1] != 2 or not 1 <= degrees.shape[0] <= MAX_FILE_BANDS:
            raise CoefficientFileError(f"degrees must have shape (bands, 2) with 1 <= bands <= {MAX_FILE_BANDS}, got {degrees.shape}")
        if degrees.min() < 0:
            raise CoefficientFileError("degrees must be non-negative")
        expected = (poly.n_terms(self.max_degrees), self.bands * (self.bands + 1) // 2, 3)
        if self.table.shape != expected:
            raise CoefficientFileError(f"table must have shape {expected} for degrees {degrees.tolist()}, got {self.table.shape}")
        if not np.all(np.isfinite(self.table)):
            raise CoefficientFileError("table holds NaN or inf")
        # Layout promise: terms above a band's own degrees are zero in its rows.
        within = self.max_degrees
        i, j = np.meshgrid(np.arange(within[0] + 1), np.arange(within[1] + 1), indexing="ij")
        i, j = i.ravel(), j.ravel()
        for row, (l, _) in enumerate(zonal_half_layout(self.bands)):
            outside = (i > degrees[l, 0]) | (j > degrees[l, 1])
            if np.any(self.table[outside, row] != 0.0):
                raise CoefficientFileError(
                    f"table has non-zero terms above the degrees {degrees[l].tolist()} of band {l}: degrees and table disagree"
                )


def default_path() -> Path:
    """Path of the shipped coefficient file (installed package first, then a source checkout)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "data" / DEFAULT_FILE_NAME, here.parent / "data" / DEFAULT_FILE_NAME):
        if candidate.is_file():
            return candidate
    raise CoefficientFileError(
        f"the shipped coefficient file {DEFAULT_FILE_NAME} was not found next to the package "
        f"({here / 'data'}) or in the source tree ({here.parent / 'data'}); reinstall skysh or run tools/fit_sky.py"
    )


def write(path: str | Path, sky_table: SkyTable) -> Path:
    """Write ``sky_table`` to ``path`` (compressed npz) after validating it; return the path."""
    sky_table.validate()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as handle:  # a file handle keeps numpy from appending ".npz"
        np.savez_compressed(
            handle,
            format=np.array(FORMAT),
            format_version=np.array(FORMAT_VERSION, dtype=np.int64),
            table=np.ascontiguousarray(sky_table.table, dtype=np.float64),
            degrees=np.asarray(sky_table.degrees, dtype=np.int64),
            metadata=np.array(json.dumps(sky_table.metadata, sort_keys=True)),
        )
    return path


def read(path: str | Path | None = None) -> SkyTable:
    """
    Read and check a coefficient file.

    Parameters
    ----------
    path
        File to read; default :func:`default_path`.

    Raises
    ------
    CoefficientFileError
        If the file is missing, truncated or not an npz, lacks an entry, has
        another format or format version, or inconsistent shapes or non-finite
        values.
    """
    path = default_path() if path is None else Path(path)
    try:
        with open(path, "rb") as handle:
            if not zipfile.is_zipfile(handle):
                raise CoefficientFileError(f"{path} is not a readable coefficient file (truncated or not an npz)")
            handle.seek(0)
            with np.load(handle, allow_pickle=False) as data:
                entries = {key: data[key] for key in data.files}
    except FileNotFoundError as error:
        raise CoefficientFileError(f"coefficient file not found: {path}") from error
    except (zipfile.BadZipFile, EOFError, OSError, ValueError) as error:
        if isinstance(error, CoefficientFileError):
            raise
        raise CoefficientFileError(f"{path} is not a readable coefficient file (truncated or not an npz): {error}") from error
    missing = {"format", "format_version", "table", "degrees", "metadata"} - set(entries)
    if missing:
        raise CoefficientFileError(f"{path} lacks the entries {sorted(missing)}; is it a skysh coefficient file?")
    if str(entries["format"]) != FORMAT:
        raise CoefficientFileError(f"{path} has format {str(entries['format'])!r}, expected {FORMAT!r}")
    raw_version = entries["format_version"]
    if raw_version.shape != () or raw_version.dtype.kind not in "iu":
        raise CoefficientFileError(f"{path} has a malformed format version {raw_version.tolist()!r}; expected the integer {FORMAT_VERSION}")
    version = int(raw_version)
    if version != FORMAT_VERSION:
        raise CoefficientFileError(
            f"{path} has format version {version}; this skysh reads version {FORMAT_VERSION} only "
            "(regenerate it with tools/fit_sky.py or install the matching skysh)"
        )
    try:
        metadata = json.loads(str(entries["metadata"]))
    except json.JSONDecodeError as error:
        raise CoefficientFileError(f"{path} has unreadable metadata: {error}") from error
    if not isinstance(metadata, dict):
        raise CoefficientFileError(f"{path} has metadata that is not a JSON object")
    table, degrees = entries["table"], entries["degrees"]
    if table.dtype.kind != "f" or degrees.dtype.kind not in "iu":
        raise CoefficientFileError(f"{path}: table must be floating point and degrees integers, got {table.dtype} and {degrees.dtype}")
    sky_table = SkyTable(
        table=np.asarray(table, dtype=np.float64), degrees=np.asarray(degrees, dtype=np.int64), metadata=metadata
    )
    try:
        sky_table.validate()
    except CoefficientFileError as error:
        raise CoefficientFileError(f"{path}: {error}") from None
    sky_table.table.flags.writeable = False
    return sky_table
