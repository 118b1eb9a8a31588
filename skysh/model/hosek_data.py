"""
The Hosek-Wilkie datasets, read from the file Mitsuba 3 installs
================================================================

The Hosek-Wilkie (2012) sky model needs its fitted dataset: per turbidity (1..10),
ground albedo (0, 1), quintic Bezier control point (6) and channel, the nine
parameters A..I of the model's distribution and the channel's mean radiance.
skysh does not copy it: the optional extra ``pip install skysh[hosek]`` installs
``mitsuba`` (pinned, :data:`MITSUBA_VERSION`), whose wheel carries it as
``mitsuba/data/sunsky/sunsky_datasets.bin`` beside a LICENSE reproducing Hosek
and Wilkie's 3-clause BSD notice (``docs/hosek.md``).

-   :func:`dataset_path`: locate the file without importing mitsuba.
-   :func:`read_tensor_file`: a reader of Mitsuba's tensor file format, every
    header field checked before any data is read.
-   :func:`sky_tensors`: the four sky tensors, shapes and values checked, read once.
-   :func:`dataset_info`: path, mitsuba version, SHA-256 and whether it is the pinned file.
-   :class:`HosekDataError`: the file is missing or not what it should be.

File format (Mitsuba 3, ``mitsuba/python/tensor_io.py`` and ``core/tensor.h``),
little-endian::

    "tensor_file\\0"  version u8 major = 1, u8 minor = 0   field count u32
    per field: name length u16, name (UTF-8), ndim u16, dtype u8 (Struct type
               code: 11 = float64), data offset u64, shape u64 x ndim
    then each field's data, C order, at its offset

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome
    Radiance. ACM Trans. Graph. 31(4), 95.
-   Mitsuba 3 (3.9.1): ``include/mitsuba/render/sunsky.h`` (dataset layout:
    turbidity, albedo, control point, channel, parameter).
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.metadata
import importlib.util
import math
import struct
import threading
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["HosekDataError", "dataset_info"]

MITSUBA_VERSION: str = "3.9.1"
"""The mitsuba release whose dataset file skysh reads (the ``hosek`` extra pins it)."""

DRJIT_VERSION: str = "1.5.0"
"""The drjit release mitsuba 3.9.1 is built against (pinned beside it)."""

EXTRA_HINT: str = (
    f"the Hosek-Wilkie dataset comes with the optional extra: pip install 'skysh[hosek]' "
    f"(mitsuba=={MITSUBA_VERSION}, drjit=={DRJIT_VERSION})"
)
"""The sentence every refusal for want of the dataset ends with."""

DATASET_RELATIVE_PATH: tuple[str, ...] = ("data", "sunsky", "sunsky_datasets.bin")
"""The dataset file inside the installed ``mitsuba`` package directory."""

PINNED_SHA256: str = "f110fa54ebcaf5f764da3a20bb4aafeeffd28111fcd0986f50a2489c12b294c7"
"""SHA-256 of ``sunsky_datasets.bin`` as installed by mitsuba 3.9.1 (``sha256sum`` of the file)."""

SKY_TENSOR_SHAPES: dict[str, tuple[int, ...]] = {
    "sky_params_rgb": (10, 2, 6, 3, 9),
    "sky_rad_rgb": (10, 2, 6, 3),
    "sky_params_spec": (10, 2, 6, 11, 9),
    "sky_rad_spec": (10, 2, 6, 11),
}
"""The sky tensors and their shapes: (turbidity 1..10, albedo 0 and 1, Bezier control point,
channel (R, G, B or the 11 wavelengths), parameter A..I in the stored order of Hosek and
Wilkie's code: A, B, C, D, E, F, G, I, H)."""

WAVELENGTHS: tuple[float, ...] = tuple(320.0 + 40.0 * k for k in range(11))
"""The spectral dataset's wavelengths, nm: 320, 360, ..., 720 (Mitsuba's ``WAVELENGTHS``)."""

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

_LOCK = threading.Lock()
_CACHE: dict[str, Any] = {}


class HosekDataError(RuntimeError):
    """The Hosek-Wilkie dataset is missing (the ``hosek`` extra is not installed) or not what it should be."""


def _candidates() -> list[Path]:
    """Where the installed mitsuba package directory may be, without importing it."""
    found: list[Path] = []
    spec = None
    # The distribution's own record (unaffected by mitsuba replacing its module object on import), then the
    # top-level package's spec (found without running its __init__).
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
    """
    The installed ``sunsky_datasets.bin``, found without importing mitsuba.

    The installed distribution's metadata (``importlib.metadata``) gives the
    package directory; ``importlib.util.find_spec("mitsuba")`` is the fallback
    (it locates a top-level package without running its ``__init__``, which
    would load the renderer's shared libraries).

    Raises
    ------
    HosekDataError
        mitsuba is not installed, or has no dataset file; the message says how
        to install it (:data:`EXTRA_HINT`).
    """
    candidates = _candidates()
    for directory in candidates:
        path = directory.joinpath(*DATASET_RELATIVE_PATH)
        if path.is_file():
            return path
    if not candidates:
        raise HosekDataError(f"mitsuba is not installed: {EXTRA_HINT}")
    raise HosekDataError(f"mitsuba is installed but has no {'/'.join(DATASET_RELATIVE_PATH)}: {EXTRA_HINT}")


def _unpack(fmt: str, data: bytes, offset: int, what: str) -> tuple[tuple[Any, ...], int]:
    size = struct.calcsize(fmt)
    if offset + size > len(data):
        raise HosekDataError(f"tensor file truncated in {what} (needs {offset + size} bytes, has {len(data)})")
    return struct.unpack_from(fmt, data, offset), offset + size


def _read_header(data: bytes) -> dict[str, tuple[str, int, tuple[int, ...]]]:
    """The field table: name -> (numpy dtype, offset, shape), every entry checked against the file."""
    if data[: len(_MAGIC)] != _MAGIC:
        raise HosekDataError("not a Mitsuba tensor file (its first 12 bytes are not 'tensor_file\\0')")
    version, offset = _unpack("<BB", data, len(_MAGIC), "the version")
    if version != _VERSION:
        raise HosekDataError(f"tensor file version {version[0]}.{version[1]} is not the supported 1.0")
    (count,), offset = _unpack("<I", data, offset, "the field count")
    if not 1 <= count <= _MAX_FIELDS:
        raise HosekDataError(f"tensor file declares {count} fields (expected 1 to {_MAX_FIELDS})")
    fields: dict[str, tuple[str, int, tuple[int, ...]]] = {}
    for _ in range(count):
        (length,), offset = _unpack("<H", data, offset, "a field name length")
        if offset + length > len(data):
            raise HosekDataError("tensor file truncated in a field name")
        name = data[offset : offset + length].decode("utf-8", errors="replace")
        (ndim, code, start), offset = _unpack("<HBQ", data, offset + length, f"field {name!r}")
        shape, offset = _unpack("<" + "Q" * ndim, data, offset, f"the shape of {name!r}")
        if code not in _DTYPES:
            raise HosekDataError(f"field {name!r} has an unknown type code {code}")
        if name in fields:
            raise HosekDataError(f"field {name!r} appears twice")
        fields[name] = (_DTYPES[code], int(start), tuple(int(s) for s in shape))
    for name, (dtype, start, shape) in fields.items():
        end = start + math.prod(shape) * np.dtype(dtype).itemsize
        if start < offset or end > len(data):
            raise HosekDataError(f"field {name!r} lies outside the file's data (bytes {start} to {end} of {len(data)})")
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
    HosekDataError
        Bad magic or version, an implausible field count, an unknown type code,
        a duplicate name, or a field whose data lies outside the file.
    """
    path = Path(path)
    if not path.is_file():
        raise HosekDataError(f"{path} is not a regular file")
    if path.stat().st_size > _MAX_FILE_BYTES:
        raise HosekDataError(f"{path} is larger than {_MAX_FILE_BYTES} bytes: not the sunsky tensor file")
    data = path.read_bytes()
    out: dict[str, NDArray] = {}
    for name, (dtype, start, shape) in _read_header(data).items():
        array = np.frombuffer(data, dtype=dtype, count=math.prod(shape), offset=start).reshape(shape)
        array = array.astype(array.dtype.newbyteorder("="), copy=True)  # aligned, owned, native order
        array.flags.writeable = False
        out[name] = array
    return out


def _check_sky(tensors: dict[str, NDArray], path: Path) -> dict[str, NDArray[np.float64]]:
    sky: dict[str, NDArray[np.float64]] = {}
    for name, shape in SKY_TENSOR_SHAPES.items():
        if name not in tensors:
            raise HosekDataError(f"{path} has no field {name!r} (fields: {', '.join(sorted(tensors))})")
        array = tensors[name]
        if array.dtype != np.float64 or array.shape != shape:
            raise HosekDataError(f"{path}: {name} is {array.dtype} {array.shape}, expected float64 {shape}")
        if not np.all(np.isfinite(array)):
            raise HosekDataError(f"{path}: {name} holds NaN or inf")
        sky[name] = array
    return sky


def sky_tensors() -> dict[str, NDArray[np.float64]]:
    """
    The sky's four tensors (:data:`SKY_TENSOR_SHAPES`), read once per process.

    Returns
    -------
    dict
        ``sky_params_rgb``, ``sky_rad_rgb``, ``sky_params_spec``, ``sky_rad_spec``:
        read-only float64 arrays of the documented shapes, all finite.

    Raises
    ------
    HosekDataError
        The extra is not installed (the message says how to install it) or the
        file does not hold these tensors with these shapes.
    """
    with _LOCK:
        if "sky" not in _CACHE:
            path = dataset_path()
            _CACHE["sky"] = _check_sky(read_tensor_file(path), path)
        return _CACHE["sky"]


def dataset_info() -> dict[str, Any]:
    """
    Provenance of the dataset: for a fitted file's metadata.

    Returns
    -------
    dict
        ``path`` (str), ``mitsuba_version`` (from the installed distribution's
        metadata, or None), ``sha256`` of the file, ``pinned`` (True when it is
        the file of :data:`MITSUBA_VERSION`, :data:`PINNED_SHA256`), ``license``
        (the LICENSE file beside it, its text, or None).
    """
    path = dataset_path()
    version: str | None = None
    with contextlib.suppress(importlib.metadata.PackageNotFoundError):
        version = importlib.metadata.version("mitsuba")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    licence = path.parent / "LICENSE"
    return {
        "path": str(path),
        "mitsuba_version": version,
        "sha256": digest,
        "pinned": digest == PINNED_SHA256,
        "license": licence.read_text(encoding="utf-8") if licence.is_file() else None,
    }
