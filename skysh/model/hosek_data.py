"""
The Hosek-Wilkie sky dataset, shipped with skysh
================================================

The Hosek-Wilkie (2012) sky model needs its fitted dataset: per turbidity (1..10),
ground albedo (0, 1), quintic Bezier control point (6) and channel, the nine
parameters A..I of the model's distribution and the channel's mean radiance.
skysh ships the four sky tensors as ``skysh/model/data/hosek_wilkie_sky.npz``
(float64, 135 KB), bit for bit the values of the file Mitsuba 3 installs
(``mitsuba/data/sunsky/sunsky_datasets.bin`` of mitsuba :data:`MITSUBA_VERSION`,
SHA-256 :data:`PINNED_SHA256`), beside ``hosek_wilkie_sky.LICENSE.txt``: Hosek and
Wilkie's 3-clause BSD notice as Mitsuba ships it, with that provenance.
``tools/hosek_extract.py`` regenerates both from an installed mitsuba (``pip install
'skysh[hosek]'``) and checks the hash; nothing here needs mitsuba.

-   :func:`sky_tensors`: the four sky tensors, shapes and values checked, read once.
-   :func:`dataset_info`: the shipped file, its source (mitsuba version, SHA-256) and its license.
-   :class:`HosekDataError`: the shipped file is missing or not what it should be.

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome
    Radiance. ACM Trans. Graph. 31(4), 95.
-   Mitsuba 3 (3.9.1): ``include/mitsuba/render/sunsky.h`` (dataset layout:
    turbidity, albedo, control point, channel, parameter).
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["HosekDataError", "dataset_info"]

MITSUBA_VERSION: str = "3.9.1"
"""The mitsuba release whose dataset file the shipped tensors come from (the ``hosek`` extra pins it)."""

PINNED_SHA256: str = "f110fa54ebcaf5f764da3a20bb4aafeeffd28111fcd0986f50a2489c12b294c7"
"""SHA-256 of ``sunsky_datasets.bin`` as installed by mitsuba 3.9.1 (``sha256sum`` of the file)."""

DATA_FILE_NAME: str = "hosek_wilkie_sky.npz"
"""The shipped tensors' file, in ``skysh/model/data/``."""

DATA_PATH: Path = Path(__file__).resolve().parent / "data" / DATA_FILE_NAME
"""The shipped tensors (package data, in the wheel)."""

LICENSE_PATH: Path = DATA_PATH.with_name("hosek_wilkie_sky.LICENSE.txt")
"""Hosek and Wilkie's BSD-3 notice and the tensors' provenance, beside :data:`DATA_PATH`."""

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

_LOCK = threading.Lock()
_CACHE: dict[str, Any] = {}


class HosekDataError(RuntimeError):
    """The shipped Hosek-Wilkie dataset is missing or not what it should be (a broken installation)."""


def _read(path: Path) -> dict[str, NDArray[np.float64]]:
    """The sky tensors of the shipped file, every shape, dtype and value checked, read-only."""
    if not path.is_file():
        raise HosekDataError(f"the Hosek-Wilkie dataset {path} is missing: reinstall skysh (or run tools/hosek_extract.py)")
    sky: dict[str, NDArray[np.float64]] = {}
    with np.load(path, allow_pickle=False) as data:
        if "source_sha256" not in data.files or str(data["source_sha256"]) != PINNED_SHA256:
            raise HosekDataError(f"{path} does not come from the pinned mitsuba {MITSUBA_VERSION} file")
        for name, shape in SKY_TENSOR_SHAPES.items():
            array = data[name] if name in data.files else np.empty(0)
            if array.dtype != np.float64 or array.shape != shape or not np.all(np.isfinite(array)):
                raise HosekDataError(f"{path}: {name} is {array.dtype} {array.shape}, expected finite float64 {shape}")
            array.flags.writeable = False
            sky[name] = array
    return sky


def sky_tensors() -> dict[str, NDArray[np.float64]]:
    """
    The sky's four tensors (:data:`SKY_TENSOR_SHAPES`), read once per process.

    Returns
    -------
    dict
        ``sky_params_rgb``, ``sky_rad_rgb``, ``sky_params_spec``, ``sky_rad_spec``:
        read-only float64 arrays of the documented shapes, all finite, identical to
        the fields of mitsuba 3.9.1's ``sunsky_datasets.bin``.

    Raises
    ------
    HosekDataError
        The shipped file is missing or does not hold these tensors with these shapes.
    """
    with _LOCK:
        if "sky" not in _CACHE:
            _CACHE["sky"] = _read(DATA_PATH)
        return _CACHE["sky"]


def dataset_info() -> dict[str, Any]:
    """
    Provenance of the dataset: for a fitted file's metadata.

    Returns
    -------
    dict
        ``path`` (str, the shipped file), ``source`` (the mitsuba file it was extracted
        from), ``mitsuba_version`` and ``sha256`` of that source (:data:`MITSUBA_VERSION`,
        :data:`PINNED_SHA256`, as recorded in the shipped file), ``license`` (the text of
        :data:`LICENSE_PATH`).
    """
    sky_tensors()  # refuses a missing or foreign file
    with np.load(DATA_PATH, allow_pickle=False) as data:
        version, digest = str(data["mitsuba_version"]), str(data["source_sha256"])
    return {"path": str(DATA_PATH), "source": "mitsuba/data/sunsky/sunsky_datasets.bin", "mitsuba_version": version,
            "sha256": digest, "license": LICENSE_PATH.read_text(encoding="utf-8")}
