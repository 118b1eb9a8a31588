"""
skysh: spherical-harmonic lighting of physically based skies for real-time renderers
===================================================================================

-   :class:`skysh.SkySH`: the per-frame runtime (load once, then
    ``sky.coefficients(sun_zenith, turbidity, sun_azimuth)``); ``SkySH.load(model="hosek-wilkie")``
    gives the Hosek-Wilkie (2012) sky with the same interface (:mod:`skysh.hosek_runtime`).
-   :mod:`skysh.sh.basis`: real SH mathematics (basis, projection, rotation, irradiance).
-   :mod:`skysh.model.preetham`: the Preetham (1999) sky and its reference SH projection.

``import skysh`` is light: it imports numpy only. colour-science is imported the
first time the sky model or a colourspace conversion is used.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008). Efficient Spherical Harmonics
    Lighting with the Preetham Skylight Model. Eurographics 2008 short papers.
-   Preetham, A. J., Shirley, P., Smits, B. (1999). A Practical Analytic Model
    for Daylight. SIGGRAPH 1999.
"""

import typing as _typing

from skysh._version import __version__

if _typing.TYPE_CHECKING:  # pragma: no cover
    from skysh.runtime import SkySH

__all__ = ["__version__", "SkySH"]


def __getattr__(name: str) -> "type[SkySH]":
    # The runtime is imported on first use so that ``import skysh`` stays cheap.
    if name == "SkySH":
        from skysh.runtime import SkySH as runtime_sky

        return runtime_sky
    raise AttributeError(f"module 'skysh' has no attribute {name!r}")


def __dir__() -> list[str]:
    # The public names (the lazy ``SkySH`` included), the dunders and any submodule already imported.
    return sorted(set(globals()) | set(__all__))
