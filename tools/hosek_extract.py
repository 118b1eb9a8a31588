#!/usr/bin/env python
"""
Extract the Hosek-Wilkie sky dataset that skysh ships from the file mitsuba installs (issue 27)
================================================================================================

skysh ships the four sky tensors of Hosek and Wilkie's fitted dataset as
``skysh/model/data/hosek_wilkie_sky.npz`` (float64, bit for bit the values of Mitsuba's file),
beside ``hosek_wilkie_sky.LICENSE.txt`` (their 3-clause BSD notice, as Mitsuba ships it, with the
source file's provenance). This script regenerates both from mitsuba's installed
``mitsuba/data/sunsky/sunsky_datasets.bin`` (``pip install 'skysh[hosek]'``), refusing a file whose
SHA-256 is not :data:`skysh.model.hosek_data.PINNED_SHA256`::

    python tools/hosek_extract.py            # rewrite the two files
    python tools/hosek_extract.py --check    # compare the shipped files with mitsuba's (exit 1 if they differ)

-   :func:`dataset_path`: locate mitsuba's file without importing mitsuba.
-   :func:`read_tensor_file`: a reader of Mitsuba's tensor file format, every header field
    checked before any data is read.
-   :func:`extract`: the arrays and the notice the package ships.

File format (Mitsuba 3, ``mitsuba/python/tensor_io.py`` and ``core/tensor.h``), little-endian::

    "tensor_file\\0"  version u8 major = 1, u8 minor = 0   field count u32
    per field: name length u16, name (UTF-8), ndim u16, dtype u8 (Struct type
               code: 11 = float64), data offset u64, shape u64 x ndim
    then each field's data, C order, at its offset

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome Radiance.
    ACM Trans. Graph. 31(4), 95.
-   Mitsuba 3.9.1: ``include/mitsuba/render/sunsky.h`` (dataset layout), ``python/tensor_io.py``.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import importlib.metadata
import importlib.util
import io
import math
import struct
import sys
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from skysh.model import hosek_data  # noqa: E402

DATASET_RELATIVE_PATH: tuple[str, ...] = ("data", "sunsky", "sunsky_datasets.bin")
"""The dataset file inside the installed ``mitsuba`` package directory."""

EXTRA_HINT: str = (f"mitsuba's dataset comes with the optional extra: pip install 'skysh[hosek]' "
                   f"(mitsuba=={hosek_data.MITSUBA_VERSION})")
"""The sentence every refusal for want of mitsuba's file ends with."""

_MAGIC: bytes = b"tensor_file\x00"
_VERSION: tuple[int, int] = (1, 0)
_MAX_FIELDS: int = 64
"""More fields than any tensor file Mitsuba ships (the sunsky file has 7): a corrupt count is refused."""
_MAX_FILE_BYTES: int = 64 << 20
"""Largest tensor file read, bytes (the sunsky file is 552,955)."""
_DTYPES: dict[int, str] = {
    1: "<u1", 2: "<i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<u8", 8: "<i8", 9: "<f2", 10: "<f4", 11: "<f8",
}
"""Mitsuba's Struct type codes (``tensor_io.py``'s map) -> numpy little-endian dtypes."""


class ExtractError(RuntimeError):
    """Mitsuba's file is missing, corrupt or not the pinned one."""


def _candidates() -> list[Path]:
    """Where the installed mitsuba package directory may be, without importing it (importing it loads the renderer)."""
    found: list[Path] = []
    spec = None
    with contextlib.suppress(importlib.metadata.PackageNotFoundError):
        found.append(Path(str(importlib.metadata.distribution("mitsuba").locate_file("mitsuba"))))
    with contextlib.suppress(ImportError, ValueError):
        spec = importlib.util.find_spec("mitsuba")
    if spec is not None:
        found.extend(Path(p) for p in (spec.submodule_search_locations or []))
        if spec.origin:
            found.append(Path(spec.origin).parent)
    return found


def dataset_path() -> Path:
    """Mitsuba's installed ``sunsky_datasets.bin`` (its distribution record, then ``find_spec``); ExtractError if absent."""
    candidates = _candidates()
    for directory in candidates:
        path = directory.joinpath(*DATASET_RELATIVE_PATH)
        if path.is_file():
            return path
    if not candidates:
        raise ExtractError(f"mitsuba is not installed: {EXTRA_HINT}")
    raise ExtractError(f"mitsuba is installed but has no {'/'.join(DATASET_RELATIVE_PATH)}: {EXTRA_HINT}")


def _unpack(fmt: str, data: bytes, offset: int, what: str) -> tuple[tuple[Any, ...], int]:
    size = struct.calcsize(fmt)
    if offset + size > len(data):
        raise ExtractError(f"tensor file truncated in {what} (needs {offset + size} bytes, has {len(data)})")
    return struct.unpack_from(fmt, data, offset), offset + size


def _read_header(data: bytes) -> dict[str, tuple[str, int, tuple[int, ...]]]:
    """The field table: name -> (numpy dtype, offset, shape), every entry checked against the file."""
    if data[: len(_MAGIC)] != _MAGIC:
        raise ExtractError("not a Mitsuba tensor file (its first 12 bytes are not 'tensor_file\\0')")
    version, offset = _unpack("<BB", data, len(_MAGIC), "the version")
    if version != _VERSION:
        raise ExtractError(f"tensor file version {version[0]}.{version[1]} is not the supported 1.0")
    (count,), offset = _unpack("<I", data, offset, "the field count")
    if not 1 <= count <= _MAX_FIELDS:
        raise ExtractError(f"tensor file declares {count} fields (expected 1 to {_MAX_FIELDS})")
    fields: dict[str, tuple[str, int, tuple[int, ...]]] = {}
    for _ in range(count):
        (length,), offset = _unpack("<H", data, offset, "a field name length")
        if offset + length > len(data):
            raise ExtractError("tensor file truncated in a field name")
        name = data[offset : offset + length].decode("utf-8", errors="replace")
        (ndim, code, start), offset = _unpack("<HBQ", data, offset + length, f"field {name!r}")
        shape, offset = _unpack("<" + "Q" * ndim, data, offset, f"the shape of {name!r}")
        if code not in _DTYPES:
            raise ExtractError(f"field {name!r} has an unknown type code {code}")
        if name in fields:
            raise ExtractError(f"field {name!r} appears twice")
        fields[name] = (_DTYPES[code], int(start), tuple(int(s) for s in shape))
    for name, (dtype, start, shape) in fields.items():
        end = start + math.prod(shape) * np.dtype(dtype).itemsize
        if start < offset or end > len(data):
            raise ExtractError(f"field {name!r} lies outside the file's data (bytes {start} to {end} of {len(data)})")
    return fields


def read_tensor_file(path: str | Path) -> dict[str, NDArray]:
    """
    Every field of a Mitsuba tensor file, as read-only numpy arrays.

    Parameters
    ----------
    path
        A regular file of at most 64 MiB.

    Returns
    -------
    dict
        Field name -> array of its declared dtype (native byte order) and shape.

    Raises
    ------
    ExtractError
        Bad magic or version, an implausible field count, an unknown type code,
        a duplicate name, or a field whose data lies outside the file.
    """
    path = Path(path)
    if not path.is_file():
        raise ExtractError(f"{path} is not a regular file")
    if path.stat().st_size > _MAX_FILE_BYTES:
        raise ExtractError(f"{path} is larger than {_MAX_FILE_BYTES} bytes: not the sunsky tensor file")
    data = path.read_bytes()
    out: dict[str, NDArray] = {}
    for name, (dtype, start, shape) in _read_header(data).items():
        array = np.frombuffer(data, dtype=dtype, count=math.prod(shape), offset=start).reshape(shape)
        array = array.astype(array.dtype.newbyteorder("="), copy=True)  # aligned, owned, native order
        array.flags.writeable = False
        out[name] = array
    return out


def extract(path: Path) -> tuple[dict[str, NDArray], str]:
    """
    The arrays of the shipped ``.npz`` and the text of its notice, from mitsuba's file at ``path``.

    Returns
    -------
    arrays, notice
        The four sky tensors (float64, shapes :data:`skysh.model.hosek_data.SKY_TENSOR_SHAPES`)
        plus ``source_sha256`` and ``mitsuba_version`` (0-d unicode arrays); the provenance
        followed by Mitsuba's LICENSE beside the file, verbatim.

    Raises
    ------
    ExtractError
        The file's SHA-256 is not the pinned one, a tensor is missing or has another
        dtype or shape, or there is no LICENSE beside it.
    """
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != hosek_data.PINNED_SHA256:
        raise ExtractError(f"{path} has SHA-256 {digest}, not the pinned {hosek_data.PINNED_SHA256} "
                           f"(mitsuba {hosek_data.MITSUBA_VERSION}): {EXTRA_HINT}")
    tensors = read_tensor_file(path)
    arrays: dict[str, NDArray] = {}
    for name, shape in hosek_data.SKY_TENSOR_SHAPES.items():
        if name not in tensors or tensors[name].dtype != np.float64 or tensors[name].shape != shape:
            raise ExtractError(f"{path}: no float64 field {name!r} of shape {shape}")
        arrays[name] = tensors[name]
    arrays["source_sha256"] = np.array(digest)
    arrays["mitsuba_version"] = np.array(hosek_data.MITSUBA_VERSION)
    licence = path.parent / "LICENSE"
    if not licence.is_file():
        raise ExtractError(f"no LICENSE beside {path}: the notice must be shipped with the data")
    notice = (f"skysh/model/data/{hosek_data.DATA_FILE_NAME}: the sky tensors ({', '.join(hosek_data.SKY_TENSOR_SHAPES)})\n"
              f"of mitsuba {hosek_data.MITSUBA_VERSION}'s mitsuba/{'/'.join(DATASET_RELATIVE_PATH)},\n"
              f"SHA-256 {digest}, values unchanged (float64), written by tools/hosek_extract.py.\n"
              "Mitsuba's LICENSE beside that file follows, verbatim.\n\n" + licence.read_text(encoding="utf-8"))
    return arrays, notice


def _npz_bytes(arrays: dict[str, NDArray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _differences(arrays: dict[str, NDArray], notice: str) -> list[str]:
    """What the shipped files hold that ``extract`` would not write (empty when they agree)."""
    found = []
    if not hosek_data.LICENSE_PATH.is_file() or hosek_data.LICENSE_PATH.read_text(encoding="utf-8") != notice:
        found.append(f"{hosek_data.LICENSE_PATH} differs")
    if not hosek_data.DATA_PATH.is_file():
        return found + [f"{hosek_data.DATA_PATH} is missing"]
    with np.load(hosek_data.DATA_PATH, allow_pickle=False) as shipped:
        if sorted(shipped.files) != sorted(arrays):
            return found + [f"{hosek_data.DATA_PATH} holds {sorted(shipped.files)}"]
        found += [f"{name} differs" for name, array in arrays.items()
                  if shipped[name].dtype != array.dtype or not np.array_equal(shipped[name], array)]
    return found


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--check", action="store_true", help="compare the shipped files with mitsuba's; write nothing")
    args = parser.parse_args(argv)
    try:
        source = dataset_path()
        arrays, notice = extract(source)
    except ExtractError as error:
        parser.error(str(error))
    if args.check:
        found = _differences(arrays, notice)
        print("\n".join(found) if found else f"the shipped files match {source}")
        return 1 if found else 0
    hosek_data.DATA_PATH.parent.mkdir(exist_ok=True)
    hosek_data.DATA_PATH.write_bytes(_npz_bytes(arrays))
    hosek_data.LICENSE_PATH.write_text(notice, encoding="utf-8")
    print(f"wrote {hosek_data.DATA_PATH} ({hosek_data.DATA_PATH.stat().st_size} bytes) and {hosek_data.LICENSE_PATH}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
