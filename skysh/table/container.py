"""
The container of the coefficient file: stored ``.npy`` members in a zip
=======================================================================

The byte-level half of :mod:`skysh.table.coefficient_file`: the one writer of its
zip (fixed headers, so one content has one file) and a reader of untrusted
bytes whose every step is bounded and whose every refusal is a
:class:`CoefficientFileError`. What the members mean is
:mod:`skysh.table.coefficient_file`'s business, not this module's.

-   :func:`encode`: ``.npy`` members, stored, in a zip with fixed headers.
-   :func:`read_bytes`: a regular file of bounded size, opened non-blocking.
-   :func:`directory`, :func:`check_declared`: the zip directory, checked before any member is read.
-   :func:`payload`, :func:`inflate`, :func:`array`: one member's bytes (bounded), then its array (no pickles).
-   :func:`as_path`: a path argument (files are written by :func:`skysh.files.write_atomic`).

References: PKWARE APPNOTE 6.3 (sections 4.3.7, 4.3.12, 4.3.16); the ``.npy``
format 1.0 (numpy.lib.format).
"""

from __future__ import annotations

import io
import math
import os
import stat
import struct
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.lib import format as npy_format
from numpy.typing import NDArray

__all__ = ["CoefficientFileError", "array", "as_path"]


class CoefficientFileError(ValueError):
    """A coefficient file (or SkyTable) that cannot be used; the message says what is wrong."""

    __module__ = "skysh.table.coefficient_file"  # its public home (defined here so the container can raise it)


NPY_HEADER_MAX: int = 256
"""Largest .npy header accepted, bytes (magic, length and the padded dict: 128 for any member here)."""

NOT_NPZ: str = "not a readable coefficient file (truncated or not an npz)"

STORED, DEFLATED = 0, 8
_LOCAL = struct.Struct("<IHHHHHIIIHH")  # zip local file header (30 bytes)
_CENTRAL = struct.Struct("<IHHHHHHIIIHHHHHII")  # zip central directory entry (46 bytes)
_END = struct.Struct("<IHHHHIIH")  # zip end of central directory record (22 bytes)
_LOCAL_SIG, _CENTRAL_SIG, _END_SIG = 0x04034B50, 0x02014B50, 0x06054B50
_ZIP_VERSION: int = 20  # "version needed to extract" 2.0
_MADE_BY: int = (3 << 8) | _ZIP_VERSION  # made on Unix, zip 2.0
_DOS_DATE: int = (0 << 9) | (1 << 5) | 1  # 1980-01-01, time 00:00:00
_EXTERNAL_ATTR: int = 0o100644 << 16  # a regular file, rw-r--r--
_MAX_LISTED: int = 16  # directory entries parsed (and named in a refusal) at most


def zip_bytes(bounds: Mapping[str, int]) -> int:
    """Largest zip of the members named in ``bounds`` (name -> largest payload), stored, with their headers."""
    return sum(bounds.values()) + sum(_LOCAL.size + _CENTRAL.size + 2 * len(name) for name in bounds) + _END.size


# --------------------------------------------------------------------------- #
# Encoding (the one writer)
# --------------------------------------------------------------------------- #
def _npy(values: NDArray) -> bytes:
    """An .npy (version 1.0) of a little-endian C-order array, header laid out as numpy's own."""
    header = f"{{'descr': {values.dtype.str!r}, 'fortran_order': False, 'shape': {tuple(int(n) for n in values.shape)!r}, }}"
    header += " " * (63 - (10 + len(header)) % 64) + "\n"  # pad magic + length + header to a multiple of 64
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1") + values.tobytes()


def encode(members: Sequence[tuple[str, NDArray]]) -> bytes:
    """The bytes of a zip of (name, array) members, stored (uncompressed), with fixed headers, in the given order."""
    local, central = bytearray(), bytearray()
    for name, values in members:
        data, raw_name = _npy(values), name.encode("ascii")
        crc, size = zlib.crc32(data), len(data)
        central += _CENTRAL.pack(_CENTRAL_SIG, _MADE_BY, _ZIP_VERSION, 0, STORED, 0, _DOS_DATE, crc, size, size,
                                 len(raw_name), 0, 0, 0, 0, _EXTERNAL_ATTR, len(local)) + raw_name
        local += _LOCAL.pack(_LOCAL_SIG, _ZIP_VERSION, 0, STORED, 0, _DOS_DATE, crc, size, size, len(raw_name), 0)
        local += raw_name + data
    end = _END.pack(_END_SIG, 0, 0, len(members), len(members), len(central), len(local), 0)
    return bytes(local + central + end)


# --------------------------------------------------------------------------- #
# Decoding (every step bounded; every refusal a CoefficientFileError)
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class Member:
    """One entry of the zip's central directory."""

    name: str
    flags: int
    method: int
    crc: int
    compressed: int
    size: int
    offset: int


def _end_record(data: bytes) -> tuple[int, int, int]:
    """(member count, directory size, directory offset) of the zip end record, which must close the file
    and describe a one-disk directory just before it."""
    if len(data) < _END.size:
        raise CoefficientFileError(f"{NOT_NPZ}: {len(data)} bytes, shorter than a zip end record")
    sig, disk, start_disk, here, count, size, offset, comment = _END.unpack_from(data, len(data) - _END.size)
    if sig != _END_SIG or comment != 0:
        raise CoefficientFileError(f"{NOT_NPZ}: no zip end record at its end")
    if disk or start_disk or here != count or offset + size != len(data) - _END.size:
        raise CoefficientFileError(f"{NOT_NPZ}: its zip end record does not describe a directory just before it")
    return count, size, offset


def _entries(data: bytes, offset: int, size: int, most: int) -> tuple[list[Member], int]:
    """At most ``most`` central directory entries from ``offset``, and the position after the last one read."""
    entries: list[Member] = []
    position = offset
    while position < offset + size and len(entries) < most:
        if position + _CENTRAL.size > offset + size:
            raise CoefficientFileError(f"{NOT_NPZ}: its zip directory is cut short")
        fields = _CENTRAL.unpack_from(data, position)
        if fields[0] != _CENTRAL_SIG:
            raise CoefficientFileError(f"{NOT_NPZ}: damaged zip directory entry at byte {position}")
        name_end = position + _CENTRAL.size + fields[10]
        name = data[position + _CENTRAL.size : name_end].decode("ascii", errors="replace")
        entries.append(Member(name, fields[3], fields[4], fields[7], fields[8], fields[9], fields[16]))
        position = name_end + fields[11] + fields[12]
    return entries, position


def directory(data: bytes, known: tuple[str, ...]) -> tuple[dict[str, Member], int]:
    """The central directory's entries (by name, in file order) and its offset: only ``known`` names, none twice."""
    count, size, offset = _end_record(data)
    entries, position = _entries(data, offset, size, min(max(count, len(known)), _MAX_LISTED))
    names = [entry.name for entry in entries]
    unknown = sorted(set(names) - set(known))
    if count > len(known) or unknown:
        raise CoefficientFileError(
            f"holds {count} members including unexpected ones {unknown or names}; a coefficient file holds only {list(known)}")
    if position != offset + size or len(entries) != count:
        raise CoefficientFileError(f"{NOT_NPZ}: its zip directory disagrees with its end record")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise CoefficientFileError(f"repeats the members {repeated} (holds {names}); is it a skysh coefficient file?")
    return {entry.name: entry for entry in entries}, offset


def check_declared(members: Mapping[str, Member], bounds: Mapping[str, int], length: int) -> None:
    """Declared sizes, compression and flags, against ``bounds`` (name -> largest size): before any member is read."""
    for name, member in members.items():
        if member.size > bounds[name]:
            raise CoefficientFileError(f"member {name} declares {member.size} bytes, above the format's {bounds[name]}: refused "
                                       "unread")
        if member.compressed > length or member.offset >= length:
            raise CoefficientFileError(f"{NOT_NPZ}: member {name} declares data beyond the file's {length} bytes")
        if member.flags & 0x1:
            raise CoefficientFileError(f"member {name} is encrypted")
        if member.method not in (STORED, DEFLATED) or (member.method == STORED and member.compressed != member.size):
            raise CoefficientFileError(f"member {name} has compression method {member.method} or inconsistent sizes")


def inflate(raw: bytes, size: int) -> bytes:
    """Inflate a raw deflate stream to at most ``size`` + 1 bytes (a declared, already bounded size)."""
    inflater = zlib.decompressobj(-zlib.MAX_WBITS)
    out = inflater.decompress(raw, size + 1)
    if len(out) != size or not inflater.eof:
        raise CoefficientFileError(f"a member does not inflate to its declared {size} bytes")
    return out


def payload(data: bytes, member: Member, directory_offset: int) -> bytes:
    """A member's bytes, located through its local header, inflated if deflated (bounded), CRC-checked."""
    if member.offset + _LOCAL.size > directory_offset:
        raise CoefficientFileError(f"{NOT_NPZ}: member {member.name} starts past its data area")
    fields = _LOCAL.unpack_from(data, member.offset)
    start = member.offset + _LOCAL.size + fields[9] + fields[10]
    name = data[member.offset + _LOCAL.size : member.offset + _LOCAL.size + fields[9]]
    if fields[0] != _LOCAL_SIG or name != member.name.encode("ascii") or fields[3] != member.method:
        raise CoefficientFileError(f"{NOT_NPZ}: the local header of {member.name} disagrees with the zip directory")
    if start + member.compressed > directory_offset:
        raise CoefficientFileError(f"{NOT_NPZ}: member {member.name} runs past the end of its data area")
    raw = data[start : start + member.compressed]
    out = inflate(raw, member.size) if member.method == DEFLATED else raw
    if zlib.crc32(out) != member.crc:
        raise CoefficientFileError(f"member {member.name} fails its CRC-32 check: the file is corrupted")
    return out


def array(raw: bytes, name: str, dtype: str | None, kinds: str, ndim: int | None) -> NDArray:
    """Parse an .npy payload without pickles: dtype (exact ``dtype``, else of ``kinds``), order, ndim, length."""
    stream = io.BytesIO(raw)
    version = npy_format.read_magic(stream)
    if version != (1, 0):
        raise CoefficientFileError(f"member {name} is an .npy of version {version}; the format writes 1.0")
    shape, fortran_order, found = npy_format.read_array_header_1_0(stream, max_header_size=NPY_HEADER_MAX)
    if (dtype is not None and found.str != dtype) or found.kind not in kinds or found.hasobject:
        wanted = repr(dtype) if dtype is not None else f"kind {kinds!r}"
        raise CoefficientFileError(f"member {name} holds {found} values (dtype {found.str!r}); the format stores {wanted}")
    if fortran_order or (ndim is not None and len(shape) != ndim):
        raise CoefficientFileError(f"member {name} has shape {shape} (fortran order {fortran_order}); the format stores a "
                                   f"C-order {ndim}-D array")
    count = math.prod(shape)
    if len(raw) - stream.tell() != count * found.itemsize:
        raise CoefficientFileError(f"member {name} holds {len(raw) - stream.tell()} data bytes; shape {shape} needs "
                                   f"{count * found.itemsize}")
    return np.frombuffer(raw, dtype=found, count=count, offset=stream.tell()).reshape(shape)


# --------------------------------------------------------------------------- #
# Files
# --------------------------------------------------------------------------- #
def as_path(path: Any, name: str = "path") -> Path:
    """``path`` as a Path; a CoefficientFileError unless it is a str or os.PathLike naming a file as text."""
    if not isinstance(path, (str, os.PathLike)):
        raise CoefficientFileError(f"{name} must be a str or os.PathLike naming a file, got {type(path).__name__}")
    try:
        return Path(path)
    except TypeError as error:  # a PathLike returning bytes
        raise CoefficientFileError(f"{name} must name a file as text: {error}") from None


def _check_regular(path: Path, mode: int) -> None:
    """Refuse anything but a regular file, naming what it is, before a byte of it is read."""
    if stat.S_ISREG(mode):
        return
    kinds = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
             (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
    kind = next((label for test, label in kinds if test(mode)), "a special file")
    raise CoefficientFileError(f"{path} is {kind}, not a regular file: refused unread")


def read_bytes(path: Path, max_bytes: int) -> bytes:
    """The file's bytes: a regular file of at most ``max_bytes``, opened without blocking, read bounded."""
    try:
        info = os.stat(path)
        _check_regular(path, info.st_mode)
        if info.st_size > max_bytes:
            raise CoefficientFileError(f"{path} is {info.st_size} bytes; a coefficient file is at most {max_bytes}: refused "
                                       "unread")
        flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_BINARY", 0)
        descriptor = os.open(path, flags)
        try:
            _check_regular(path, os.fstat(descriptor).st_mode)  # what was opened, not what the name pointed at a moment ago
            with open(descriptor, "rb", closefd=False) as stream:  # a buffered read loops to the bound or the end
                data = stream.read(max_bytes + 1)
        finally:
            os.close(descriptor)
    except FileNotFoundError:
        raise CoefficientFileError(f"coefficient file not found: {path}") from None
    except (OSError, ValueError) as error:  # permissions, a NUL in the name, ...
        if isinstance(error, CoefficientFileError):
            raise
        raise CoefficientFileError(f"{path} cannot be read: {error}") from None
    if len(data) > max_bytes:
        raise CoefficientFileError(f"{path} grew beyond {max_bytes} bytes while being read: refused")
    return data
