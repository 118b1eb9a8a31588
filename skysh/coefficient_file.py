"""
The versioned coefficient file
==============================

The fitted polynomial tables of the sky's SH coefficients (Habel 2008, eq. 1),
their conventions and their measured accuracy, in one ``.npz`` file that the
runtime loads and checks. Loading is the one place where untrusted bytes enter
skysh, so :func:`read` accepts exactly what :func:`write` produces and refuses
everything else with one :class:`CoefficientFileError`, at a bounded cost.

-   :class:`SkyTable`: the tables in memory.
-   :func:`read`, :func:`write`: the file.
-   :func:`content_sha256`: the content hash recorded in the file.
-   :func:`default_path`: the file shipped with the package.
-   :class:`CoefficientFileError`: raised for a file that does not match.
-   :func:`zonal_half_layout`: the stored coefficient order (m >= 0 only).

File layout (:data:`FORMAT_VERSION` 2)
--------------------------------------
A zip archive (an ``.npz`` that :func:`numpy.load` reads) of exactly the five
uncompressed ("stored") ``.npy`` members of :data:`MEMBERS`, in that order.
The zip headers (date 1980-01-01, no extra fields, no comments) and the ``.npy``
headers (version 1.0, numpy's layout) are written byte for byte by this module,
so one content has exactly one file:

``format.npy``
    '<U18' scalar, :data:`FORMAT`.
``format_version.npy``
    '<i8' scalar, :data:`FORMAT_VERSION`.
``table.npy``
    '<f8' (n_terms, bands (bands + 1) / 2, 3): Chebyshev coefficients of
    every m >= 0 SH coefficient of every RGB channel divided by the luminance
    scale (:data:`BASIS`), terms ordered as :func:`skysh.poly.design` for the
    largest degrees of any band (:data:`TERM_ORDER`). The sky with its sun at
    azimuth 0 is even in azimuth, so its m < 0 coefficients are zero and are
    not stored; the runtime's rotation (eq. 4) creates them.
``degrees.npy``
    '<i8' (bands, 2): the (d_theta, d_tau) of each band; terms above a band's
    degrees are zero in its rows.
``metadata.npy``
    '|u1' (n,): a JSON object as ASCII bytes in canonical form (sorted keys,
    no spaces, \\u escapes, no NaN): conventions, grid, quadrature,
    versions, measured errors, and the fields the runtime relies on
    (:data:`RUNTIME_FIELDS`: colourspace, domain, basis, term order, degrees,
    bands) plus :data:`HASH_KEY`, the :func:`content_sha256` of everything else.

What :func:`read` checks, in this order
---------------------------------------
1.  The path names a regular file (``os.stat``, then ``fstat`` of a
    descriptor opened non-blocking, so a FIFO cannot hang) of at most
    :data:`MAX_FILE_BYTES`; it is read whole with a bounded read.
2.  The zip end record and directory: exactly the members of :data:`MEMBERS`,
    each declaring at most :data:`MAX_MEMBER_BYTES`, before any member is read.
3.  ``format`` and ``format_version`` (the only members ever inflated, bounded
    by their declared sizes, for the compressed version-1 files): version 1
    and unknown versions are refused by name.
4.  Every member stored, its CRC-32, its ``.npy`` header (exact dtype, C
    order, a byte count equal to its shape's); ``allow_pickle`` is never used.
5.  The metadata: ASCII, a JSON object, canonical.
6.  :meth:`SkyTable.validate`: shapes, degrees, finite values within
    :data:`MAX_TABLE_MAGNITUDE`, the layout's zeros, the runtime fields.
7.  The content hash (any change to any number or metadata field is refused).
8.  The file equals, byte for byte, what :func:`write` makes of its content.

Format version 1 (skysh 0.1.0: compressed, no hash) is no longer read.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import re
import stat
import struct
import threading
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.lib import format as npy_format
from numpy.typing import NDArray

from skysh import poly
from skysh._version import __version__

__all__ = [
    "FORMAT", "FORMAT_VERSION", "DEFAULT_FILE_NAME", "MAX_FILE_BANDS", "MAX_FILE_DEGREE", "MAX_TABLE_MAGNITUDE",
    "MAX_METADATA_BYTES", "MAX_MEMBER_BYTES", "MAX_FILE_BYTES", "MEMBERS", "FILE_COLOURSPACES", "BASIS",
    "TERM_ORDER", "DOMAIN", "HASH_KEY", "RUNTIME_FIELDS", "CoefficientFileError", "SkyTable", "zonal_half_layout",
    "content_sha256", "default_path", "read", "write",
]

FORMAT: str = "skysh-coefficients"
"""Value of the ``format`` member of every coefficient file."""

FORMAT_VERSION: int = 2
"""Version of the layout above; :func:`read` refuses any other."""

DEFAULT_FILE_NAME: str = "preetham_sh.npz"
"""Name of the shipped file in ``data/`` (installed as ``skysh/data/``)."""

MAX_FILE_BANDS: int = 7
"""Largest band count a coefficient file may hold (``tools/fit_sky.py --bands`` goes to 7)."""

MAX_FILE_DEGREE: int = 31
"""Largest polynomial degree in either variable: at most 32 x 32 = 1024 terms per coefficient."""

MAX_TABLE_MAGNITUDE: float = 1.0e4
"""Largest |value| of a table entry (dimensionless: a coefficient over the luminance scale).

The table holds Chebyshev coefficients of c_lm / luminance_scale (:data:`BASIS`);
a least-squares fit of a function bounded by M has coefficients of order M, and
the sky's SH coefficients are a few times its luminance scale at most
(``tools/fit_sky.py`` prints the largest |value| of each fit it writes). An entry
near 1e4 is thus a broken file, not a sky; and within the bound every runtime
result stays finite: at most 1024 terms with |T_i T_j| <= 1 give at most about
1e7 times the luminance scale, far from float64's 1.8e308."""

MAX_METADATA_BYTES: int = 65536
"""Largest metadata JSON, bytes (a fit writes a few kilobytes)."""

FILE_COLOURSPACES: tuple[str, ...] = (
    "sRGB", "ITU-R BT.709", "ITU-R BT.2020", "Display P3", "DCI-P3", "P3-D65", "Adobe RGB (1998)", "ProPhoto RGB",
    "ACEScg", "ACES2065-1",
)
"""colour-science RGB colourspace names a file may be fitted in (each a key of
``colour.RGB_COLOURSPACES``, checked by tests/test_coefficient_file.py), listed
here so that reading a file never imports colour-science."""

BASIS: str = (
    "coefficient = luminance_scale(sun_zenith, T) * sum table[i (d_tau+1) + j] T_i(x) T_j(y); "
    "x = 4 sun_zenith / pi - 1, y = (2 ln T - ln 2.5 - ln 6) / (ln 6 - ln 2.5); "
    "luminance_scale = Y_z / F_Y(0, sun_zenith) (Preetham appendix, cd/m^2)"
)
"""The polynomial form the runtime evaluates (skysh.poly.scale, skysh.preetham.luminance_scale)."""

TERM_ORDER: str = "i (d_tau + 1) + j for the largest degrees of any band"
"""Order of the table's terms (skysh.poly.term_index)."""

DOMAIN: dict[str, list[float]] = {"sun_zenith": list(poly.SUN_ZENITH_DOMAIN), "turbidity": list(poly.TURBIDITY_DOMAIN)}
"""The fitted domain the runtime's variables assume (radians; turbidity)."""

HASH_KEY: str = "content_sha256"
"""Metadata key of the content hash (:func:`content_sha256`)."""

RUNTIME_FIELDS: tuple[str, ...] = ("colourspace", "domain", "basis", "term_order", "degrees", "bands")
"""Metadata fields the runtime relies on: required in a file, checked wherever present."""

MEMBERS: tuple[str, ...] = ("format.npy", "format_version.npy", "table.npy", "degrees.npy", "metadata.npy")
"""The members of a coefficient file, in the order :func:`write` stores them."""

_NPY_HEADER_MAX: int = 256
"""Largest .npy header accepted, bytes (magic, length and the padded dict: 128 for any member here)."""

_TABLE_MAX_BYTES: int = 8 * 3 * (MAX_FILE_DEGREE + 1) ** 2 * (MAX_FILE_BANDS * (MAX_FILE_BANDS + 1) // 2)

MAX_MEMBER_BYTES: dict[str, int] = {
    "format.npy": _NPY_HEADER_MAX + 4 * 64,  # a '<U' string of up to 64 characters
    "format_version.npy": _NPY_HEADER_MAX + 8,
    "table.npy": _NPY_HEADER_MAX + _TABLE_MAX_BYTES,  # float64 (1024 terms, 28 rows, 3)
    "degrees.npy": _NPY_HEADER_MAX + 8 * 2 * MAX_FILE_BANDS,
    "metadata.npy": _NPY_HEADER_MAX + MAX_METADATA_BYTES,
}
"""Largest uncompressed size of each member, bytes, from the bounds above."""

_LOCAL = struct.Struct("<IHHHHHIIIHH")  # zip local file header (30 bytes)
_CENTRAL = struct.Struct("<IHHHHHHIIIHHHHHII")  # zip central directory entry (46 bytes)
_END = struct.Struct("<IHHHHIIH")  # zip end of central directory record (22 bytes)
_LOCAL_SIG, _CENTRAL_SIG, _END_SIG = 0x04034B50, 0x02014B50, 0x06054B50
_STORED, _DEFLATED = 0, 8
_ZIP_VERSION: int = 20  # "version needed to extract" 2.0
_MADE_BY: int = (3 << 8) | _ZIP_VERSION  # made on Unix, zip 2.0
_DOS_DATE: int = (0 << 9) | (1 << 5) | 1  # 1980-01-01, time 00:00:00
_EXTERNAL_ATTR: int = 0o100644 << 16  # a regular file, rw-r--r--
_MAX_LISTED: int = 12  # members named in a refusal

MAX_FILE_BYTES: int = (
    sum(MAX_MEMBER_BYTES.values()) + sum(_LOCAL.size + _CENTRAL.size + 2 * len(name) for name in MEMBERS) + _END.size
)
"""Largest coefficient file, bytes: every member at its bound, stored, plus the zip headers."""

_SHA256_HEX = re.compile(r"[0-9a-f]{64}")
_NOT_NPZ: str = "not a readable coefficient file (truncated or not an npz)"


class CoefficientFileError(ValueError):
    """A coefficient file (or SkyTable) that cannot be used; the message says what is wrong."""


def zonal_half_layout(bands: int) -> list[tuple[int, int]]:
    """Order of the stored coefficients: ``[(l, m) for l in range(bands) for m in range(l + 1)]``."""
    return [(l, m) for l in range(bands) for m in range(l + 1)]  # noqa: E741


def _canonical(value: Any) -> bytes:
    """Canonical JSON bytes: sorted keys, no spaces, ASCII, no NaN or inf (ValueError/TypeError otherwise)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode("ascii")


def _check_runtime_metadata(metadata: dict[str, Any], degrees: NDArray, required: bool) -> None:
    """The metadata fields the runtime relies on: all present if ``required``, each valid where present."""
    if required:
        missing = [key for key in RUNTIME_FIELDS + (HASH_KEY,) if key not in metadata]
        if missing:
            raise CoefficientFileError(f"metadata lacks the fields {missing} the runtime relies on")
    if "colourspace" in metadata:
        name = metadata["colourspace"]
        if not isinstance(name, str) or name not in FILE_COLOURSPACES:
            raise CoefficientFileError(
                f"metadata colourspace {name!r} is not one a coefficient file may use ({', '.join(FILE_COLOURSPACES)})"
            )
    expected = {"domain": DOMAIN, "basis": BASIS, "term_order": TERM_ORDER, "degrees": degrees.tolist(),
                "bands": int(degrees.shape[0])}
    for key, value in expected.items():
        if key in metadata:
            try:
                same = _canonical(metadata[key]) == _canonical(value)
            except (TypeError, ValueError):
                same = False
            if not same:
                raise CoefficientFileError(
                    f"metadata {key} {metadata[key]!r} differs from {value!r}, which this skysh's runtime assumes"
                )


@dataclass(frozen=True)
class SkyTable:
    """
    Fitted polynomial tables of the sky's SH coefficients.

    Attributes
    ----------
    table
        (n_terms, bands (bands + 1) / 2, 3) Chebyshev coefficients of the
        coefficients over the luminance scale (dimensionless; :data:`BASIS`).
    degrees
        (bands, 2) per-band (d_theta, d_tau), each in [0, :data:`MAX_FILE_DEGREE`].
    metadata
        Conventions, settings and measured errors (see the module docstring);
        a table read from a file also holds :data:`HASH_KEY`.
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
        """colour-science name of the RGB space the sky was fitted in (default sRGB)."""
        return str(self.metadata.get("colourspace", "sRGB"))

    def validate(self) -> None:
        """
        Raise :class:`CoefficientFileError` unless the table can be used.

        Checks: numpy arrays of floats and integers; degrees (bands, 2) with
        1 <= bands <= :data:`MAX_FILE_BANDS` and each degree in [0,
        :data:`MAX_FILE_DEGREE`]; the table's shape for those degrees; finite
        values of |value| <= :data:`MAX_TABLE_MAGNITUDE`; zeros above each
        band's degrees; a dict of metadata whose :data:`RUNTIME_FIELDS`, where
        present, are valid.
        """
        table, degrees = self.table, self.degrees
        if not isinstance(table, np.ndarray) or table.dtype.kind != "f":
            raise CoefficientFileError(f"table must be a numpy array of floats, got {_describe(table)}")
        if not isinstance(degrees, np.ndarray) or degrees.dtype.kind not in "iu":
            raise CoefficientFileError(f"degrees must be a numpy array of integers, got {_describe(degrees)}")
        if degrees.ndim != 2 or degrees.shape[1] != 2 or not 1 <= degrees.shape[0] <= MAX_FILE_BANDS:
            raise CoefficientFileError(f"degrees must have shape (bands, 2) with 1 <= bands <= {MAX_FILE_BANDS}, got {degrees.shape}")
        if degrees.min() < 0 or degrees.max() > MAX_FILE_DEGREE:
            raise CoefficientFileError(f"degrees must lie in [0, {MAX_FILE_DEGREE}], got {degrees.tolist()}")
        expected = (poly.n_terms(self.max_degrees), self.bands * (self.bands + 1) // 2, 3)
        if table.shape != expected:
            raise CoefficientFileError(f"table must have shape {expected} for degrees {degrees.tolist()}, got {table.shape}")
        if not np.all(np.isfinite(table)):
            raise CoefficientFileError("table holds NaN or inf")
        largest = float(np.abs(table).max())
        if largest > MAX_TABLE_MAGNITUDE:
            raise CoefficientFileError(
                f"table holds |value| {largest:.3g}, above {MAX_TABLE_MAGNITUDE:g} (MAX_TABLE_MAGNITUDE): not a fitted sky"
            )
        # Layout promise: terms above a band's own degrees are zero in its rows.
        i, j = np.divmod(np.arange(expected[0]), self.max_degrees[1] + 1)
        for row, (l, _) in enumerate(zonal_half_layout(self.bands)):
            outside = (i > degrees[l, 0]) | (j > degrees[l, 1])
            if np.any(table[outside, row] != 0.0):
                raise CoefficientFileError(
                    f"table has non-zero terms above the degrees {degrees[l].tolist()} of band {l}: degrees and table disagree"
                )
        if not isinstance(self.metadata, dict):
            raise CoefficientFileError(f"metadata must be a dict, got {_describe(self.metadata)}")
        _check_runtime_metadata(self.metadata, degrees, required=False)


def _describe(value: Any) -> str:
    return f"an array of dtype {value.dtype}" if isinstance(value, np.ndarray) else type(value).__name__


def content_sha256(table: NDArray, degrees: NDArray, metadata: dict[str, Any]) -> str:
    """
    The content hash recorded in a file's metadata under :data:`HASH_KEY`.

    SHA-256 (hex) of, in this order: ``"skysh-coefficients\\n2\\n"``; for
    ``table`` ('<f8') then ``degrees`` ('<i8'), the line ``"<name> <dtype>
    <shape as a JSON list> <byte count>\\n"`` followed by the C-order bytes;
    then ``"metadata <byte count>\\n"`` and the canonical JSON (sorted keys, no
    spaces, ASCII) of ``metadata`` without :data:`HASH_KEY`. Every number and
    every metadata field (the colourspace included) is covered.
    """
    digest = hashlib.sha256(f"{FORMAT}\n{FORMAT_VERSION}\n".encode("ascii"))
    for name, array, dtype in (("table", table, "<f8"), ("degrees", degrees, "<i8")):
        values = np.ascontiguousarray(array, dtype=dtype)
        digest.update(f"{name} {dtype} {list(values.shape)} {values.nbytes}\n".encode("ascii"))
        digest.update(values.tobytes())
    text = _canonical({key: value for key, value in metadata.items() if key != HASH_KEY})
    digest.update(f"metadata {len(text)}\n".encode("ascii"))
    digest.update(text)
    return digest.hexdigest()


def default_path() -> Path:
    """Path of the shipped coefficient file (installed package first, then a source checkout)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / "data" / DEFAULT_FILE_NAME, here.parent / "data" / DEFAULT_FILE_NAME):
        if candidate.is_file():
            return candidate
    raise CoefficientFileError(
        f"the shipped coefficient file {DEFAULT_FILE_NAME} was not found next to the package "
        f"({here / 'data'}) or in the source tree ({here.parent / 'data'}); reinstall skysh, "
        "or run `skysh fit --out data/preetham_sh.npz --force` in a source checkout"
    )


# --------------------------------------------------------------------------- #
# Encoding (the one writer; read compares files against it)
# --------------------------------------------------------------------------- #
def _npy(array: NDArray) -> bytes:
    """An .npy (version 1.0) of a little-endian C-order array, header laid out as numpy's own."""
    header = f"{{'descr': {array.dtype.str!r}, 'fortran_order': False, 'shape': {tuple(int(n) for n in array.shape)!r}, }}"
    header += " " * (63 - (10 + len(header)) % 64) + "\n"  # pad magic + length + header to a multiple of 64
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1") + array.tobytes()


def _encode(table: NDArray, degrees: NDArray, metadata_bytes: bytes) -> bytes:
    """The file's bytes: the five members stored (uncompressed) in a zip with fixed headers."""
    arrays = (
        np.array(FORMAT, dtype=f"<U{len(FORMAT)}"),
        np.array(FORMAT_VERSION, dtype="<i8"),
        np.ascontiguousarray(table, dtype="<f8"),
        np.ascontiguousarray(degrees, dtype="<i8"),
        np.frombuffer(metadata_bytes, dtype="|u1"),
    )
    local, central = bytearray(), bytearray()
    for name, array in zip(MEMBERS, arrays):
        payload, raw_name = _npy(array), name.encode("ascii")
        crc, size = zlib.crc32(payload), len(payload)
        central += _CENTRAL.pack(_CENTRAL_SIG, _MADE_BY, _ZIP_VERSION, 0, _STORED, 0, _DOS_DATE, crc, size, size,
                                 len(raw_name), 0, 0, 0, 0, _EXTERNAL_ATTR, len(local)) + raw_name
        local += _LOCAL.pack(_LOCAL_SIG, _ZIP_VERSION, 0, _STORED, 0, _DOS_DATE, crc, size, size, len(raw_name), 0)
        local += raw_name + payload
    end = _END.pack(_END_SIG, 0, 0, len(MEMBERS), len(MEMBERS), len(central), len(local), 0)
    return bytes(local + central + end)


# --------------------------------------------------------------------------- #
# Decoding (every step bounded; every refusal a CoefficientFileError)
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class _Member:  # one entry of the zip's central directory
    name: str
    flags: int
    method: int
    crc: int
    compressed: int
    size: int
    offset: int


def _directory(data: bytes) -> tuple[dict[str, _Member], int]:
    """The central directory's entries (by name) and its offset; nothing is read beyond the headers."""
    if len(data) < _END.size:
        raise CoefficientFileError(f"{_NOT_NPZ}: {len(data)} bytes, shorter than a zip end record")
    sig, disk, start_disk, here, count, size, offset, comment = _END.unpack_from(data, len(data) - _END.size)
    if sig != _END_SIG or comment != 0:
        raise CoefficientFileError(f"{_NOT_NPZ}: no zip end record at its end")
    if disk or start_disk or here != count or offset + size != len(data) - _END.size:
        raise CoefficientFileError(f"{_NOT_NPZ}: its zip end record does not describe a directory just before it")
    entries: list[_Member] = []
    position = offset
    while position < offset + size and len(entries) < max(count, len(MEMBERS)) and len(entries) < _MAX_LISTED:
        if position + _CENTRAL.size > offset + size:
            raise CoefficientFileError(f"{_NOT_NPZ}: its zip directory is cut short")
        fields = _CENTRAL.unpack_from(data, position)
        if fields[0] != _CENTRAL_SIG:
            raise CoefficientFileError(f"{_NOT_NPZ}: damaged zip directory entry at byte {position}")
        name_end = position + _CENTRAL.size + fields[10]
        name = data[position + _CENTRAL.size : name_end].decode("ascii", errors="replace")
        entries.append(_Member(name, fields[3], fields[4], fields[7], fields[8], fields[9], fields[16]))
        position = name_end + fields[11] + fields[12]
    names = [entry.name for entry in entries]
    unknown = sorted(set(names) - set(MEMBERS))
    if count > len(MEMBERS) or unknown:
        raise CoefficientFileError(
            f"holds {count} members including unexpected ones {unknown or names}; a coefficient file holds exactly {list(MEMBERS)}"
        )
    if position != offset + size or len(entries) != count:
        raise CoefficientFileError(f"{_NOT_NPZ}: its zip directory disagrees with its end record")
    missing = [name for name in MEMBERS if name not in names]
    if missing or len(set(names)) != len(names):
        raise CoefficientFileError(f"lacks the members {missing} or repeats one (holds {names}); is it a skysh coefficient file?")
    return {entry.name: entry for entry in entries}, offset


def _check_declared(members: dict[str, _Member], length: int) -> None:
    """Declared sizes, compression and flags, against the format: before any member is read."""
    for name in MEMBERS:
        member = members[name]
        if member.size > MAX_MEMBER_BYTES[name]:
            raise CoefficientFileError(f"member {name} declares {member.size} bytes, above the format's {MAX_MEMBER_BYTES[name]}: refused unread")
        if member.compressed > length or member.offset >= length:
            raise CoefficientFileError(f"{_NOT_NPZ}: member {name} declares data beyond the file's {length} bytes")
        if member.flags & 0x1:
            raise CoefficientFileError(f"member {name} is encrypted")
        if member.method not in (_STORED, _DEFLATED) or (member.method == _STORED and member.compressed != member.size):
            raise CoefficientFileError(f"member {name} has compression method {member.method} or inconsistent sizes")


def _inflate(raw: bytes, size: int) -> bytes:
    """Inflate a raw deflate stream to at most ``size`` + 1 bytes (a declared, already bounded size)."""
    inflater = zlib.decompressobj(-zlib.MAX_WBITS)
    out = inflater.decompress(raw, size + 1)
    if len(out) != size or not inflater.eof:
        raise CoefficientFileError(f"a member does not inflate to its declared {size} bytes")
    return out


def _payload(data: bytes, member: _Member, directory: int) -> bytes:
    """A member's bytes, located through its local header, inflated if deflated (bounded), CRC-checked."""
    if member.offset + _LOCAL.size > directory:
        raise CoefficientFileError(f"{_NOT_NPZ}: member {member.name} starts past its data area")
    fields = _LOCAL.unpack_from(data, member.offset)
    start = member.offset + _LOCAL.size + fields[9] + fields[10]
    name = data[member.offset + _LOCAL.size : member.offset + _LOCAL.size + fields[9]]
    if fields[0] != _LOCAL_SIG or name != member.name.encode("ascii") or fields[3] != member.method:
        raise CoefficientFileError(f"{_NOT_NPZ}: the local header of {member.name} disagrees with the zip directory")
    if start + member.compressed > directory:
        raise CoefficientFileError(f"{_NOT_NPZ}: member {member.name} runs past the end of its data area")
    raw = data[start : start + member.compressed]
    payload = _inflate(raw, member.size) if member.method == _DEFLATED else raw
    if zlib.crc32(payload) != member.crc:
        raise CoefficientFileError(f"member {member.name} fails its CRC-32 check: the file is corrupted")
    return payload


def _array(payload: bytes, name: str, dtype: str | None, kinds: str, ndim: int | None) -> NDArray:
    """Parse an .npy payload without pickles: dtype (exact ``dtype``, else of ``kinds``), order, ndim, length."""
    stream = io.BytesIO(payload)
    version = npy_format.read_magic(stream)
    if version != (1, 0):
        raise CoefficientFileError(f"member {name} is an .npy of version {version}; the format writes 1.0")
    shape, fortran_order, found = npy_format.read_array_header_1_0(stream, max_header_size=_NPY_HEADER_MAX)
    if (dtype is not None and found.str != dtype) or found.kind not in kinds or found.hasobject:
        wanted = repr(dtype) if dtype is not None else f"kind {kinds!r}"
        raise CoefficientFileError(f"member {name} holds {found} values (dtype {found.str!r}); the format stores {wanted}")
    if fortran_order or (ndim is not None and len(shape) != ndim):
        raise CoefficientFileError(f"member {name} has shape {shape} (fortran order {fortran_order}); the format stores a C-order {ndim}-D array")
    count = math.prod(shape)
    if len(payload) - stream.tell() != count * found.itemsize:
        raise CoefficientFileError(f"member {name} holds {len(payload) - stream.tell()} data bytes; shape {shape} needs {count * found.itemsize}")
    return np.frombuffer(payload, dtype=found, count=count, offset=stream.tell()).reshape(shape)


def _check_version(data: bytes, members: dict[str, _Member], directory: int) -> None:
    """The ``format`` string and ``format_version``: this format, version :data:`FORMAT_VERSION` only."""
    text = str(_array(_payload(data, members["format.npy"], directory), "format.npy", None, "U", 0)[()])
    if text != FORMAT:
        raise CoefficientFileError(f"has format {text!r}, expected {FORMAT!r}")
    raw = _array(_payload(data, members["format_version.npy"], directory), "format_version.npy", None, "biufUS", 0)
    if raw.dtype.kind not in "iu" or raw.dtype.itemsize > 8:
        raise CoefficientFileError(f"has a malformed format version {raw.tolist()!r}; expected the integer {FORMAT_VERSION}")
    version = int(raw[()])
    if version == 1:
        raise CoefficientFileError(
            f"format version 1 is no longer read: this skysh ({__version__}) reads format version {FORMAT_VERSION} only "
            "(hashed, strictly checked); regenerate the file with `skysh fit --out FILE` (tools/fit_sky.py)"
        )
    if version != FORMAT_VERSION:
        raise CoefficientFileError(
            f"has format version {version}; this skysh ({__version__}) reads format version {FORMAT_VERSION} only "
            "(regenerate it with `skysh fit --out FILE`, or use the skysh that wrote it)"
        )
    compressed = [name for name in MEMBERS if members[name].method != _STORED]
    if compressed:
        raise CoefficientFileError(f"members {compressed} are compressed; format version {FORMAT_VERSION} stores every member uncompressed")


def _metadata(raw: bytes) -> dict[str, Any]:
    """The metadata object: ASCII canonical JSON, nothing else."""
    try:
        metadata = json.loads(raw.decode("ascii"))
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise CoefficientFileError(f"has unreadable metadata ({type(error).__name__}: {error})") from None
    if not isinstance(metadata, dict):
        raise CoefficientFileError(f"has metadata that is not a JSON object (a {type(metadata).__name__})")
    try:
        canonical = _canonical(metadata) == raw
    except ValueError:  # NaN, inf or a number too large for a float
        canonical = False
    if not canonical:
        raise CoefficientFileError("has metadata not in canonical form (sorted keys, no spaces, ASCII, no NaN): altered after writing")
    return metadata


def _decode(data: bytes) -> SkyTable:
    """Every check of the module docstring, in order, on a file's bytes."""
    members, directory = _directory(data)
    _check_declared(members, len(data))
    _check_version(data, members, directory)
    table = _array(_payload(data, members["table.npy"], directory), "table.npy", "<f8", "f", None)
    degrees = _array(_payload(data, members["degrees.npy"], directory), "degrees.npy", "<i8", "i", None)
    raw = _array(_payload(data, members["metadata.npy"], directory), "metadata.npy", "|u1", "u", 1).tobytes()
    if len(raw) > MAX_METADATA_BYTES:
        raise CoefficientFileError(f"metadata is {len(raw)} bytes, above MAX_METADATA_BYTES = {MAX_METADATA_BYTES}")
    metadata = _metadata(raw)
    sky_table = SkyTable(table=table.copy(), degrees=degrees.copy(), metadata=metadata)
    sky_table.validate()
    _check_runtime_metadata(metadata, sky_table.degrees, required=True)
    recorded, computed = metadata[HASH_KEY], content_sha256(table, degrees, metadata)
    if not isinstance(recorded, str) or not _SHA256_HEX.fullmatch(recorded):
        raise CoefficientFileError(f"metadata {HASH_KEY} {recorded!r} is not a SHA-256 hex digest")
    if recorded != computed:
        raise CoefficientFileError(
            f"content hash mismatch: the metadata records sha256 {recorded[:16]}..., the content hashes to "
            f"{computed[:16]}...: numbers or metadata were changed after writing"
        )
    expected = _encode(table, degrees, raw)
    if expected != data:
        n = min(len(expected), len(data))
        differ = np.flatnonzero(np.frombuffer(expected[:n], np.uint8) != np.frombuffer(data[:n], np.uint8))
        raise CoefficientFileError(
            f"differs from what skysh writes for its content (first at byte {int(differ[0]) if differ.size else n} "
            f"of {len(data)}): headers altered, or written by another program"
        )
    for array in (sky_table.table, sky_table.degrees):
        array.flags.writeable = False
    return sky_table


# --------------------------------------------------------------------------- #
# Files
# --------------------------------------------------------------------------- #
def _as_path(path: Any, name: str = "path") -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise CoefficientFileError(f"{name} must be a str or os.PathLike naming a file, got {type(path).__name__}")
    try:
        return Path(path)
    except TypeError as error:  # a PathLike returning bytes
        raise CoefficientFileError(f"{name} must name a file as text: {error}") from None


def _not_regular(path: Path, mode: int) -> CoefficientFileError:
    kinds = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
    kind = next((label for test, label in kinds if test(mode)), "a special file")
    return CoefficientFileError(f"{path} is {kind}, not a regular file: refused unread")


def _read_bytes(path: Path) -> bytes:
    """The file's bytes: a regular file of at most MAX_FILE_BYTES, opened without blocking, read bounded."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise _not_regular(path, info.st_mode)
        if info.st_size > MAX_FILE_BYTES:
            raise CoefficientFileError(f"{path} is {info.st_size} bytes; a coefficient file is at most {MAX_FILE_BYTES}: refused unread")
        flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
        descriptor = os.open(path, flags)
        try:
            info = os.fstat(descriptor)  # what was opened, not what the name pointed at a moment ago
            if not stat.S_ISREG(info.st_mode):
                raise _not_regular(path, info.st_mode)
            chunks, remaining = [], MAX_FILE_BYTES + 1
            while remaining > 0 and (chunk := os.read(descriptor, min(remaining, 1 << 20))):
                chunks.append(chunk)
                remaining -= len(chunk)
        finally:
            os.close(descriptor)
    except FileNotFoundError:
        raise CoefficientFileError(f"coefficient file not found: {path}") from None
    except (OSError, ValueError) as error:  # permissions, a NUL in the name, ...
        if isinstance(error, CoefficientFileError):
            raise
        raise CoefficientFileError(f"{path} cannot be read: {error}") from None
    data = b"".join(chunks)
    if len(data) > MAX_FILE_BYTES:
        raise CoefficientFileError(f"{path} grew beyond {MAX_FILE_BYTES} bytes while being read: refused")
    return data


def read(path: str | os.PathLike | None = None) -> SkyTable:
    """
    Read and check a coefficient file (every check of the module docstring).

    Parameters
    ----------
    path
        File to read; default :func:`default_path`.

    Returns
    -------
    SkyTable
        Read-only arrays; the metadata as written (with :data:`HASH_KEY`).

    Raises
    ------
    CoefficientFileError
        For every kind of failure (missing, special or too large file,
        truncated, corrupted, hostile members, other format or version, wrong
        dtypes, shapes or values, unusable metadata, hash mismatch, altered
        headers), with the path and what is wrong. Costs at most one read of
        :data:`MAX_FILE_BYTES` and a few copies of it.
    """
    path = default_path() if path is None else _as_path(path)
    data = _read_bytes(path)
    try:
        return _decode(data)
    except CoefficientFileError as error:
        raise CoefficientFileError(f"{path}: {error}") from None
    except Exception as error:  # noqa: BLE001 -- any other failure on untrusted bytes is the same refusal
        raise CoefficientFileError(f"{path}: {_NOT_NPZ} ({type(error).__name__}: {error})") from None


def write(path: str | os.PathLike, sky_table: SkyTable) -> Path:
    """
    Write ``sky_table`` to ``path`` after validating it; return the path.

    The metadata is stored with the :data:`RUNTIME_FIELDS` this skysh assumes
    filled in where absent (colourspace sRGB, :data:`DOMAIN`, :data:`BASIS`,
    :data:`TERM_ORDER`, the degrees and band count) and refused where they
    disagree, then hashed (:func:`content_sha256`). The bytes are checked by
    :func:`read`'s own decoder, written to a temporary file beside ``path``
    and renamed over it, so ``path`` is never left half written.

    Raises
    ------
    CoefficientFileError
        If the table fails :meth:`SkyTable.validate`, ``path`` is not a str or
        path, ``sky_table`` is not a SkyTable, or the metadata is not JSON
        (str keys; finite numbers) or exceeds :data:`MAX_METADATA_BYTES`.
    OSError
        If the file cannot be written.
    """
    path = _as_path(path)
    if not isinstance(sky_table, SkyTable):
        raise CoefficientFileError(f"sky_table must be a skysh.coefficient_file.SkyTable, got {type(sky_table).__name__}")
    sky_table.validate()
    table = np.ascontiguousarray(sky_table.table, dtype="<f8")
    degrees = np.ascontiguousarray(sky_table.degrees, dtype="<i8")
    defaults = {"colourspace": "sRGB", "domain": DOMAIN, "basis": BASIS, "term_order": TERM_ORDER,
                "degrees": degrees.tolist(), "bands": int(degrees.shape[0])}
    metadata = {**defaults, **{key: value for key, value in sky_table.metadata.items() if key != HASH_KEY}}
    try:
        metadata = json.loads(_canonical(metadata))  # JSON types only: tuples become lists
    except (TypeError, ValueError) as error:
        raise CoefficientFileError(f"metadata must be JSON with str keys and finite numbers: {error}") from None
    metadata[HASH_KEY] = content_sha256(table, degrees, metadata)
    raw = _canonical(metadata)
    if len(raw) > MAX_METADATA_BYTES:
        raise CoefficientFileError(f"metadata is {len(raw)} bytes as JSON, above MAX_METADATA_BYTES = {MAX_METADATA_BYTES}")
    data = _encode(table, degrees, raw)
    _decode(data)  # what is written reads back (every check of read, the runtime fields included)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        with open(temporary, "xb") as handle:  # exclusive; mode from the umask
            handle.write(data)
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()
    return path
