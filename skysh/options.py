"""
The per-frame options, checked and resolved once
================================================

-   :class:`Options`: the flags of one frame's coefficients (``bands``, ``gibbs``,
    ``dering``, ``irradiance``, ``irradiance_table``, ``sun``, ``ground_albedo``,
    ``colourspace``, ``engine``), every value checked and every "by intent"
    default (None) resolved to a concrete value.
-   :meth:`Options.resolve`: the one place the rules of the README's table
    "Defaults follow the intent" are written: :meth:`skysh.SkySH.coefficients`,
    ``skysh coeffs`` (:mod:`skysh.app.cli`) and everything built on them take their
    flags from it.
-   :data:`MODELS`: the sky models a runtime loads.
-   :func:`check_albedo` (and :data:`ALBEDO_RANGE`): the ``ground_albedo``
    parameter, checked (also :mod:`skysh.lighting.lights`' names).

The generated C, GLSL, HLSL and JavaScript runtimes restate the same rules in their
own languages (``skysh_use_table`` in ``skysh/export/templates/c_like_kernel.h``, ``useTable``
in ``js_module.mjs``); ``tests/test_options.py`` checks :meth:`Options.resolve`
against an independent restatement of the table, ``tests/export/test_export_js.py`` and
``tests/export/test_export.py`` the exports against the runtime.

A value is checked once, where it enters the public API: inner calls take the
resolved :class:`Options` (or its fields) as checked values. ``import skysh.options``
imports numpy and :mod:`skysh.checks` only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from skysh.checks import as_float_array, check_bands, check_flag, number_text, short_repr

__all__ = ["ALBEDO_RANGE", "MODELS", "check_albedo", "Options"]

MODELS: tuple[str, ...] = ("preetham", "hosek-wilkie")
"""The sky models a runtime loads (:meth:`skysh.SkySH.load`'s ``model``, the CLI's ``--model``): the fitted
Preetham table, or Hosek-Wilkie projected per frame from its exact model (:mod:`skysh.hosek_runtime`)."""

ALBEDO_RANGE: tuple[float, float] = (0.0, 1.0)
"""Valid ground albedo per channel (a Lambertian reflectance)."""

def check_albedo(ground_albedo: Any) -> tuple[float, float, float] | None:
    """
    The ``ground_albedo`` parameter as three Python floats, or None for a black ground.

    Parameters
    ----------
    ground_albedo
        A real number or an RGB triple, each in [0, 1] (dimensionless
        reflectance; per channel of the output colourspace).

    Returns
    -------
    tuple or None
        (R, G, B) albedo; None when every channel is 0 (the ground adds nothing).

    Raises
    ------
    ValueError
        Naming ``ground_albedo``: a bool, text, NaN or inf, not one number or
        three, or a value outside [0, 1].
    """
    low, high = ALBEDO_RANGE
    kind = type(ground_albedo)
    if kind is float or kind is int:  # the per-frame paths: Python numbers, no numpy
        if not low <= ground_albedo <= high:  # also False for NaN; exact for an int of any size (no float())
            raise ValueError(f"ground_albedo must lie in [{low:g}, {high:g}], got {number_text(ground_albedo)}")
        value = float(ground_albedo)
        return None if value == 0.0 else (value, value, value)
    if (kind is tuple or kind is list) and len(ground_albedo) == 3:  # three Python floats in range: no numpy
        r, g, b = ground_albedo
        if _plain_in_range(r, g, b, low, high):
            return None if r == 0.0 and g == 0.0 and b == 0.0 else (r, g, b)
    return _array_albedo(ground_albedo)


def _plain_in_range(r: Any, g: Any, b: Any, low: float, high: float) -> bool:
    """Whether ``r``, ``g`` and ``b`` are Python floats in [``low``, ``high``] (:func:`check_albedo`'s no-numpy path)."""
    return type(r) is float and type(g) is float and type(b) is float and low <= r <= high and low <= g <= high \
        and low <= b <= high


def _array_albedo(ground_albedo: Any) -> tuple[float, float, float] | None:
    """:func:`check_albedo` of anything but a Python number or three floats in range: through numpy."""
    low, high = ALBEDO_RANGE
    if type(ground_albedo) in (tuple, list) and any(isinstance(v, (bool, np.bool_)) for v in ground_albedo):
        raise ValueError(f"ground_albedo must be a real number or an RGB triple of numbers, got {short_repr(ground_albedo)}")
    albedo = as_float_array(ground_albedo, "ground_albedo")  # refuses bools, text, NaN, inf
    if albedo.shape not in ((), (3,)):
        raise ValueError(f"ground_albedo must be a number or an RGB triple (3 values), got shape {albedo.shape}")
    if albedo.min() < low or albedo.max() > high:
        bad = albedo[(albedo < low) | (albedo > high)].ravel()[0]
        raise ValueError(f"ground_albedo must lie in [{low:g}, {high:g}] per channel, got {number_text(bad)}")
    rgb = np.broadcast_to(albedo, (3,)).tolist()
    return None if not any(rgb) else (rgb[0], rgb[1], rgb[2])


@dataclass(frozen=True, slots=True)
class Options:
    """
    The per-frame flags of :meth:`skysh.SkySH.coefficients`, checked and resolved (:meth:`resolve`).

    Attributes
    ----------
    bands
        N, SH bands, in [1, the file's bands].
    gibbs, dering
        The zonal sinc filter (Habel eq. 5) and Sloan's deringing, resolved (never None).
    irradiance
        Irradiance out (the clamped-cosine convolution) instead of radiance.
    irradiance_table
        The sky from the file's certified 3-band irradiance table (resolved, never None).
    sun
        Add the sun's disk.
    ground_albedo
        The ground's (R, G, B) albedo, Python floats in [0, 1]; None for a black ground
        (no ground at all).
    colourspace
        A colour-science RGB colourspace name, or None for the file's (its name is
        checked where it is first converted to, by colour-science).
    engine
        An engine preset's name (:data:`skysh.engines.presets.ENGINES`, checked there), or None for
        skysh's own convention. Only its intent enters the rules: engines light diffusely.
    """

    bands: int = 3
    gibbs: bool = True
    dering: bool = False
    irradiance: bool = False
    irradiance_table: bool = False
    sun: bool = False
    ground_albedo: tuple[float, float, float] | None = None
    colourspace: str | None = None
    engine: str | None = None

    @property
    def diffuse(self) -> bool:
        """The intent: diffuse lighting (irradiance out, or an engine preset, which lights with SH diffusely)."""
        return self.irradiance or self.engine is not None

    @classmethod
    def resolve(
        cls, bands: Any = 3, gibbs: Any = None, dering: Any = None, irradiance: Any = False,
        irradiance_table: Any = None, sun: Any = False, ground_albedo: Any = 0.0, colourspace: Any = None,
        engine: Any = None, *, has_table: bool, max_bands: int,
    ) -> Options:
        """
        Check every option once and resolve the defaults (None: "by intent") to concrete values.

        The rules, as the README's table "Defaults follow the intent" states them; the intent is
        diffuse for ``irradiance=True`` or an ``engine`` preset (engines light with SH diffusely),
        radiance otherwise:

        ==============  ================  ===============================================
        intent          ``gibbs`` (None)  ``dering`` (None), ``irradiance_table`` (None)
        ==============  ================  ===============================================
        radiance        on                off; no table
        irradiance      off               on; 3 bands: the certified irradiance table
                                          (non-negative by construction: no deringing
                                          search, ``dering`` acts only after a colour
                                          conversion mixing signs)
        engine preset   off               on; 3 bands: the table (its radiance-equivalent)
        ==============  ================  ===============================================

        ``irradiance_table=None`` takes the table only for diffuse intent, ``bands=3``, a file
        with the table (``has_table``), ``gibbs`` not True and ``dering`` not False (an
        explicit choice of either keeps the sky's pipeline). ``irradiance_table=True`` takes it
        whatever the intent (radiance-equivalent without ``irradiance``), then ``gibbs`` defaults
        to off. An explicit ``gibbs`` or ``dering`` is kept as given.

        Parameters
        ----------
        bands, gibbs, dering, irradiance, irradiance_table, sun, ground_albedo, colourspace
            As :meth:`skysh.SkySH.coefficients`.
        engine
            None (skysh's convention) or an engine preset's name (a str; the name itself is
            checked by :mod:`skysh.engines.presets`).
        has_table
            Whether the coefficient file has the certified irradiance table
            (:attr:`skysh.SkySH.has_irradiance_table`).
        max_bands
            The file's band count (the largest ``bands``).

        Returns
        -------
        Options
            Every field concrete: ``gibbs``, ``dering`` and ``irradiance_table`` bools,
            ``bands`` an int, ``ground_albedo`` three floats or None.

        Raises
        ------
        TypeError
            ``gibbs``, ``dering``, ``irradiance``, ``irradiance_table`` or ``sun`` not a bool
            (``numpy.bool_`` is one).
        ValueError
            Naming the parameter: ``irradiance_table=True`` without the table, with ``bands``
            other than 3 or with ``gibbs=True``; ``ground_albedo`` not a number or an RGB triple
            in [0, 1]; ``colourspace`` or ``engine`` neither None nor a str; ``bands`` not an
            integer in [1, ``max_bands``].
        """
        irradiance = check_flag(irradiance, "irradiance")
        gibbs = gibbs if gibbs is None else check_flag(gibbs, "gibbs")
        dering = dering if dering is None else check_flag(dering, "dering")
        if engine is not None and not isinstance(engine, str):
            raise ValueError(f"engine must be None or an engine preset's name (skysh.engines.presets.ENGINES), got "
                             f"{short_repr(engine)}")
        diffuse = irradiance or engine is not None  # the intent
        table = _resolve_table(irradiance_table, diffuse, bands, gibbs, dering, has_table, max_bands)
        gibbs = not (diffuse or table) if gibbs is None else gibbs  # by intent: on for radiance only
        dering = diffuse if dering is None else dering  # by intent: on for diffuse light (the table: no search needed)
        sun = sun if sun is False else check_flag(sun, "sun")
        albedo = None if type(ground_albedo) is float and ground_albedo == 0.0 else check_albedo(ground_albedo)
        if colourspace is not None and not isinstance(colourspace, str):  # before any work, naming it
            raise ValueError(f"colourspace must be None or a colour-science RGB colourspace name, got {short_repr(colourspace)}")
        return cls(check_bands(bands, high=max_bands), gibbs, dering, irradiance, table, sun, albedo, colourspace, engine)


def _resolve_table(irradiance_table: Any, diffuse: bool, bands: Any, gibbs: bool | None, dering: bool | None,
                   has_table: bool, max_bands: int) -> bool:
    """:meth:`Options.resolve`'s ``irradiance_table``: by intent for None, else as asked (checked)."""
    if irradiance_table is None:  # by intent: the table for diffuse light at 3 bands
        return diffuse and has_table and gibbs is not True and dering is not False \
            and check_bands(bands, high=max_bands) == 3
    # as asked (True: checked that the file, the bands and the filter allow it)
    return check_flag(irradiance_table, "irradiance_table") and _table_allowed(bands, gibbs, has_table, max_bands)


def _table_allowed(bands: Any, gibbs: bool | None, has_table: bool, max_bands: int) -> bool:
    """True for ``irradiance_table=True`` where the file has the table, at 3 bands, without ``gibbs=True``; else the
    ValueError saying why."""
    if not has_table:
        raise ValueError("irradiance_table=True needs the coefficient file's irradiance table (format 4, 3 bands or "
                         "more); this SkyTable has none")
    if check_bands(bands, high=max_bands) != 3:
        raise ValueError(f"irradiance_table=True needs bands=3 (the table's), got bands={bands!r}")
    if gibbs is True:
        raise ValueError("irradiance_table=True does not go with gibbs=True: the table is the irradiance's own "
                         "optimum, not a filtered sky (pass gibbs=None or False, or irradiance_table=False)")
    return True
