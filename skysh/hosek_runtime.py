"""
The Hosek-Wilkie sky per frame, with the runtime's interface
============================================================

-   :class:`HosekWilkieSH`: ``skysh.SkySH.load(model="hosek-wilkie")``. Per frame,
    :meth:`HosekWilkieSH.coefficients` projects the exact model (Hosek and Wilkie 2012,
    eq. 9, its dataset shipped in the package) on a small sun-adapted rule
    (:func:`skysh.model.hosek_frame.coefficients`, rotated about Z by the sun's azimuth,
    Habel 2008 eq. 4), then applies the same steps as :class:`skysh.SkySH`: the zonal sinc
    Gibbs filter (Habel 2008, eq. 5), Sloan's deringing (on the exact minimum at 1..3
    bands, the certified bound above), the clamped-cosine convolution for irradiance.
-   :data:`BANDS`: the most bands it gives (the rules are measured to 7).

There is no fitted table: tabulating this sky's SH over (sun zenith, turbidity, albedo)
cannot reach 1e-4 of L_min in a reasonable size (``docs/hosek.md``). The defaults follow the
intent as :meth:`skysh.options.Options.resolve` states them (there is no certified
irradiance table: deringing is the search, on for irradiance). The ground albedo enters the
sky itself (the dataset's two albedo tables, per RGB channel); the ground below the horizon
is black, as skysh's convention (add :func:`skysh.model.ground.ground_sh` for it), and the
sun's disk is not part of the model's sky dataset.

Cost: ``python benchmarks/bench_hosek.py`` measures one call against the Preetham runtime's
side by side. ``import skysh.hosek_runtime`` imports numpy and the model's dataset reader,
not colour-science (imported only for a colourspace other than sRGB).

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome Radiance.
    ACM Trans. Graph. 31(4), 95: eq. (9), section 5.
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (4), (5).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import check_out, check_range, short_repr
from skysh.model import hosek, hosek_frame
from skysh.options import Options
from skysh.post import dering as post_dering
from skysh.sh import basis as sh

__all__ = ["BANDS", "HosekWilkieSH"]

BANDS: int = 7
"""Most bands :meth:`HosekWilkieSH.coefficients` gives: the rules' accuracy is measured at 3 and 7 bands
(:mod:`skysh.model.hosek_frame`), and 7 is the Preetham file's."""

RGB_DATASET: str = "sRGB"
"""The colourspace of the model's RGB dataset, the runtime's own (others go through its spectral channels)."""


class HosekWilkieSH:
    """
    SH lighting of the Hosek-Wilkie sky per frame, from the exact model (no fitted table).

    Create with ``skysh.SkySH.load(model="hosek-wilkie")`` (or directly). Methods are
    read-only and thread-safe; the rules' nodes are computed on first use and cached.

    Examples
    --------
    >>> sky = HosekWilkieSH()
    >>> sky.coefficients(0.5, 3.0, sun_azimuth=1.0, albedo=0.2).shape
    (9, 3)
    >>> sky.coefficients(0.5, 3.0, bands=7, irradiance=True, albedo=(0.1, 0.2, 0.3)).shape
    (49, 3)
    """

    model: str = "hosek-wilkie"
    bands: int = BANDS
    colourspace: str = RGB_DATASET

    def __init__(self) -> None:
        # Per band count, computed once: the zonal rows and their sinc factors (Habel eq. 5), A_l per row.
        self._zonal = {n: np.array([sh.index(l, 0) for l in range(n)]) for n in range(1, BANDS + 1)}
        self._gibbs = {n: sh.gibbs_factors(n)[:, None] for n in range(1, BANDS + 1)}
        self._lobe = {n: sh.cosine_lobe(n)[sh.band_of_index(n)][:, None] for n in range(1, BANDS + 1)}

    def __repr__(self) -> str:
        return f"HosekWilkieSH(bands={self.bands}, colourspace={self.colourspace!r})"

    def coefficients(
        self, sun_zenith: ArrayLike, turbidity: ArrayLike, sun_azimuth: ArrayLike = 0.0, bands: int = 3,
        gibbs: bool | None = None, dering: bool | None = None, irradiance: bool = False,
        colourspace: str | None = None, albedo: ArrayLike = 0.0, accuracy: str = "default",
        out: NDArray[np.float64] | None = None,
    ) -> NDArray[np.float64]:
        """
        SH coefficients of the Hosek-Wilkie sky for one frame (or a batch).

        Parameters
        ----------
        sun_zenith, turbidity, sun_azimuth
            Radians in [0, pi/2] (zenith to horizon); turbidity in [1, 10] (the dataset's);
            radians, any finite value, from +X towards +Y. Arrays broadcast together.
        bands
            N in [1, :data:`BANDS`].
        gibbs, dering, irradiance
            As :meth:`skysh.SkySH.coefficients`, the same defaults by intent
            (:meth:`skysh.options.Options.resolve`): the zonal sinc filter (Habel eq. 5) on for
            radiance, off for irradiance; Sloan's deringing (one window for all channels, after
            the filter and the rotation) on for irradiance only; ``irradiance=True`` returns
            E (cd/m^2 x sr).
        colourspace
            colour-science RGB colourspace name; default (None) linear sRGB, the RGB dataset.
            Any other projects the dataset's 11 spectral channels on the same rule and converts
            them (exact, linear).
        albedo
            Ground albedo, [0, 1]: a number, or an RGB triple (each channel of the RGB dataset
            at its own albedo; sRGB only, unless its three values are equal). One per call.
        accuracy
            The rule, a key of :data:`skysh.model.hosek_frame.ACCURACIES`: "fast", "default"
            (meets worst E_mean 3e-5 at 3 bands and 1e-4 at 7 with a margin of 2x or more) or
            "fine" (:mod:`skysh.model.hosek_frame`'s table).
        out
            Optional buffer for the result, as :meth:`skysh.SkySH.coefficients`' (a writeable,
            C-contiguous float64 array of the result's shape, sharing no memory with the
            parameters): the result is copied into it and it is returned.

        Returns
        -------
        ndarray
            (N * N, 3), or (..., N * N, 3) for array parameters; radiance in cd/m^2 (or
            irradiance, cd/m^2 x sr), linear RGB, real orthonormal SH (Condon-Shortley phase,
            index l (l + 1) + m). Zero below the horizon before the filter.

        Raises
        ------
        ValueError
            A parameter outside its range, NaN or inf (naming it and the range); arrays that do
            not broadcast; ``bands`` outside [1, 7]; an RGB albedo with another colourspace; an
            unknown colourspace or accuracy; an ``out`` that is not such a buffer (checked before any work).
        TypeError
            ``gibbs``, ``dering`` or ``irradiance`` not a bool.
        """
        o = Options.resolve(bands, gibbs, dering, irradiance, colourspace=colourspace, has_table=False,
                            max_bands=BANDS)
        space = RGB_DATASET if o.colourspace is None else o.colourspace
        grey, rgb = _albedo(albedo, space)
        params = (sun_zenith, turbidity, sun_azimuth)
        checked = False
        if out is not None:  # before any work, when the parameters broadcast (else hosek_frame names them)
            try:
                shape = np.broadcast_shapes(*(np.shape(p) for p in params))
            except ValueError:
                shape = None
            checked = shape is not None and check_out(out, shape + (o.bands * o.bands, 3), params) is out
        if rgb is None:
            sky = hosek_frame.coefficients(sun_zenith, turbidity, grey, sun_azimuth, o.bands, space, accuracy)
        else:
            sky = hosek_frame.coefficients(sun_zenith, turbidity, rgb, sun_azimuth, o.bands, space, accuracy,
                                           per_channel=True)
        if o.gibbs:  # Habel eq. (5): zonal rows only
            sky[..., self._zonal[o.bands], :] *= self._gibbs[o.bands]
        if o.dering:
            sky = post_dering.dering(sky, "irradiance")[0]
        if o.irradiance:
            sky *= self._lobe[o.bands]
        if out is None:
            return sky
        (out if checked else check_out(out, sky.shape, params))[...] = sky
        return out


def _albedo(albedo: Any, colourspace: str) -> tuple[float, NDArray[np.float64] | None]:
    """``albedo`` checked: (the grey value, None) for a number or three equal values, else (0, the RGB triple)."""
    a = check_range(albedo, "albedo", *hosek.ALBEDO_RANGE)
    if a.shape == ():
        return float(a), None
    if a.shape != (3,):
        raise ValueError(f"albedo must be a number or an RGB triple (3 values), got shape {a.shape}: "
                         f"{short_repr(albedo)}")
    if a[0] == a[1] == a[2]:
        return float(a[0]), None
    if colourspace != RGB_DATASET:
        raise ValueError(f"albedo as an RGB triple of different values needs colourspace None or {RGB_DATASET!r} (the "
                         f"RGB dataset), got colourspace={colourspace!r}: the spectral channels take one grey albedo")
    return 0.0, a
