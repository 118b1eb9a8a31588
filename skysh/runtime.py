"""
The per-frame runtime (Habel 2008, sections 3.1-3.3)
====================================================

-   :class:`SkySH`: load the fitted tables once, then per frame
    :meth:`SkySH.coefficients` evaluates the polynomials for the sun and
    turbidity, applies the zonal sinc Gibbs filter (eq. 5), rotates about Z by
    the sun's azimuth (eq. 4), optionally deringes (Sloan 2017) and convolves
    with the clamped cosine (irradiance). ``sun=True`` adds the sun's disk as
    a windowed delta and ``ground_albedo`` a Lambertian ground lit by sky and
    sun (:mod:`skysh.lighting.lights`: the order of the parts and the fused scalar
    path); :meth:`SkySH.sun_light` gives the sun as a directional light
    (direction and RGB illuminance, lux) from the file's sun table
    (:class:`skysh.lighting.sunlight.SunLight`). Irradiance at 3 bands comes by default
    from the file's certified non-negative irradiance table instead
    (``docs/irradiance.md``): the same evaluation and rotation, no filter, no
    deringing search; ``irradiance_table=False`` gives the pipeline above.

Everything static is prepared in :meth:`SkySH.__init__`: for every band count
N and Gibbs setting, one table whose zonal rows are pre-scaled by
sinc(pi l / N) (the seed's own optimisation) and whose m < 0 columns repeat
their m > 0 partners, so that the rotation is one multiplication by
cos(|m| a) or sin(|m| a). A scalar call is then: validation on Python floats,
one small product and one vectorised cosine giving the Chebyshev terms
(T_k(x) = cos(k acos x)) and the rotation factors, two ``np.dot`` products over
the m >= 0 table (in x, then in turbidity), one gather and one multiplication
that rotate (eq. 4) and fill the m < 0 coefficients, and the luminance scale
(one tan, two exp). A batch is one design matrix, one matrix product over the
full table and one multiplication by the rotation factors (built by angle
addition), evaluated in chunks into the result: a new array, or the caller's
buffer (``out=``; a frame loop reusing one pays no fresh memory per call). The
composed paths (sun and ground, deringing, a colourspace conversion) run a
large batch as calls on chunks of frames into the result, their temporaries
bounded. ``python benchmarks/bench_runtime.py`` prints what each costs
against a bare numpy product; ``python benchmarks/bench_lights.py`` what the
sun and the ground add.

The per-frame flags are checked and their defaults resolved by intent once, by
:meth:`skysh.options.Options.resolve` (the rule the CLI shares), cached per
distinct setting of plain values so the scalar call pays a dictionary look-up.

``import skysh.runtime`` imports numpy and the coefficient file reader only:
not colour-science, matplotlib or the offline fit.

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import (
    check_bands,
    check_choice,
    check_dirs,
    check_flag,
    check_out,
    check_range,
    check_scalar,
    check_size,
    read_only,
    real_scalar,
    short_repr,
)
from skysh.domain import SKY
from skysh.lighting import lights
from skysh.lighting.sunlight import SunLight
from skysh.model import ground
from skysh.model.preetham import luminance_scale_unchecked as _luminance_scale
from skysh.options import MODELS, Options
from skysh.sh import basis as sh
from skysh.table import coefficient_file, poly

__all__ = ["SkySH", "gibbs_factors"]

gibbs_factors = sh.gibbs_factors  # the filter's factors, public here since the runtime first offered them

# The fitted domain (skysh.domain.SKY) as floats for the scalar fast path: x = zenith _XS - _XH, y = ln(T) _YS - _YH.
_XS, _XH, _YS, _YH = SKY.x.scale, SKY.x.shift, SKY.y.scale, SKY.y.shift
(_ZMIN, _ZMAX), (_TMIN, _TMAX) = SKY.x.interval, SKY.y.interval
_TWO_PI: float = 2.0 * math.pi
BATCH_CHUNK: int = 1 << 16
"""Output values a batch evaluates at a time (512 KiB of float64, its design matrix about as large at 7 bands):
per item, 10^6 frames cost what 10^3 do (``python benchmarks/bench_runtime.py --curve-only``)."""

COMPOSED_CHUNK: int = 1 << 19
"""Output values a batch through the composed paths (the sun and the ground, deringing, a colourspace conversion)
evaluates at a time, each chunk a call of its own written into the result: their temporaries (several arrays of
the chunk's size, 4 MiB each) stay bounded whatever the batch's size, and a chunk's fixed cost (about 0.3 ms at
7 bands lit) is under 2% of its arithmetic (``python benchmarks/bench_runtime.py --curve-only --million``)."""

FEW_FRAMES: int = 32
"""Frames up to which a batch's chunk takes its Chebyshev terms and rotation factors from one ``cos`` (as the
scalar path) rather than by doubling and angle addition: fewer numpy calls, more cosines per frame; the two
cross near here (``python benchmarks/bench_runtime.py --curve-only``)."""

_RESOLVED_CACHE: int = 256  # resolved Options kept per SkySH (cleared when full)


def _rotation_factors(phi: NDArray[np.float64], bands: int) -> NDArray[np.float64]:
    """
    (n, 2 N): cos(m phi) for m = 0 .. N - 1, then sin(m phi), by angle addition from cos(phi), sin(phi).

    Two transcendental calls per point instead of 2 (N - 1); the recurrence adds about one
    rounding per step (within 16 eps of direct cos and sin: tests/runtime/test_runtime.py).
    """
    a = np.fmod(phi, _TWO_PI)  # reduced, so the starting values are accurate
    rot = np.empty((2 * bands, a.shape[0]))  # rows: contiguous writes
    rot[0], rot[bands] = 1.0, 0.0
    if bands == 1:
        return rot.T
    c1, s1 = np.cos(a, out=rot[1]), np.sin(a, out=rot[bands + 1])
    for m in range(2, bands):
        np.multiply(rot[m - 1], c1, out=rot[m])
        rot[m] -= rot[bands + m - 1] * s1  # cos(m a) = cos((m-1) a) cos a - sin((m-1) a) sin a
        np.multiply(rot[bands + m - 1], c1, out=rot[bands + m])
        rot[bands + m] += rot[m - 1] * s1  # sin(m a) = sin((m-1) a) cos a + cos((m-1) a) sin a
    return rot.T


def _terms(table: NDArray[np.float64], top: tuple[int, int], degrees: tuple[int, int]) -> NDArray[np.float64]:
    """(T, rows, 3): the terms of ``degrees`` (:func:`skysh.domain.term_index` order) of a table laid out for ``top``,
    zero above its own degrees (a copy)."""
    i, j = np.divmod(np.arange(poly.n_terms(degrees)), degrees[1] + 1)  # inverse of skysh.domain.term_index
    inside = (i <= top[0]) & (j <= top[1])
    out = np.zeros((i.size,) + table.shape[1:])
    out[inside] = table[i[inside] * (top[1] + 1) + j[inside]]
    return out


class _Plan:
    """Precomputed arithmetic of one (bands, gibbs) setting (or of the irradiance table)."""

    __slots__ = ("bands", "degrees", "half_table", "table_flat", "rot_index", "batch_rot_index", "lobe", "split",
                 "angle_map", "gather", "rotation")

    def __init__(self, sky_table: coefficient_file.SkyTable, bands: int, gibbs: bool, c10: bool = False,
                 rows_from: coefficient_file.NamedTable | None = None, lobe: bool = False) -> None:
        """``c10``: append the sky's *unfiltered* (1, 0) row (for the ground's E_h; any ``bands``).
        ``rows_from``: the m >= 0 rows from this table (the file's irradiance table, 3 groups) instead of
        the sky's. ``lobe``: fold the clamped-cosine factors A_l into them (irradiance out)."""
        self.bands = bands
        self.degrees = _plan_degrees(sky_table, bands, c10, rows_from)
        lms = [sh.lm(i) for i in range(bands * bands)]
        half = _half_rows(sky_table, bands, gibbs, c10, rows_from, lobe, self.degrees)
        # Scalar path: the m >= 0 table, contracted in theta then in turbidity.
        self.half_table = np.ascontiguousarray(half.reshape(self.degrees[0] + 1, -1))
        # Source (m >= 0 row, channel) and rotation factor of every output value;
        # rotation factors are laid out [cos(0 a) .. cos((N-1) a), sin(0 a) .. sin((N-1) a)].
        source = np.array([l * (l + 1) // 2 + abs(m) for l, m in lms], dtype=np.intp)  # row of (l, |m|): zonal_half_layout
        self.rot_index = np.array([bands - m if m < 0 else m for _, m in lms], dtype=np.intp)
        # Batch path: the full table (m < 0 columns repeat their m > 0 partners; the c_10 row last, unrotated).
        columns = list(source) + ([bands * (bands + 1) // 2] if c10 else [])
        self.table_flat = np.ascontiguousarray(half[:, columns].reshape(half.shape[0], -1))
        self.batch_rot_index = np.concatenate([self.rot_index, np.zeros(len(columns) - len(source), np.intp)])
        self.lobe = sh.cosine_lobe(bands)[sh.band_of_index(bands)][:, None]
        # Scalar path: packed = cos(angle_map @ (acos x, acos y, phi, 1)), split into T(x), T(y), the rotation.
        dx, dy = self.degrees
        self.split = (dx + 1, dx + dy + 2)
        self.angle_map = _angle_map(self.degrees, bands)
        # Output value (i, channel) = half[gather[i, channel]] * packed[rotation[i]].
        self.gather = 3 * source[:, None] + np.arange(3)
        self.rotation = np.repeat((dx + dy + 2 + self.rot_index)[:, None], 3, axis=1)  # (N^2, 3): no broadcast
        read_only(self.half_table, self.table_flat, self.rot_index, self.batch_rot_index, self.lobe, self.angle_map,
                  self.gather, self.rotation)


def _plan_degrees(sky_table: coefficient_file.SkyTable, bands: int, c10: bool,
                  rows_from: coefficient_file.NamedTable | None) -> tuple[int, int]:
    """The (d_x, d_y) term layout of a :class:`_Plan`: its rows' largest degrees (and the sky's (1, 0) row's with ``c10``)."""
    own = sky_table.degrees[:bands] if rows_from is None else rows_from.degrees
    d = np.max(np.concatenate([own, sky_table.degrees[1:2]]) if c10 and rows_from is not None else own, axis=0)
    return (int(d[0]), int(d[1]))


def _half_rows(sky_table: coefficient_file.SkyTable, bands: int, gibbs: bool, c10: bool,
               rows_from: coefficient_file.NamedTable | None, lobe: bool, degrees: tuple[int, int]) -> NDArray[np.float64]:
    """(T, K_half (+ 1 with ``c10``), 3): a :class:`_Plan`'s m >= 0 rows in ``degrees``' layout, lobe and filter folded in."""
    l_of, m_of = np.array(coefficient_file.zonal_half_layout(bands)).T
    rows = sky_table if rows_from is None else rows_from
    half = _terms(rows.table, rows.max_degrees, degrees)[:, : len(l_of)]  # (T, K_half, 3), m >= 0 rows
    if lobe:
        half *= sh.cosine_lobe(bands)[l_of][:, None]
    if c10:  # (1, 0) is row 1 of the sky's layout (a 1-band file has none: zeros, the ground is refused)
        extra = _terms(sky_table.table, sky_table.max_degrees, degrees)[:, 1:2]
        half = np.concatenate([half, extra if sky_table.bands > 1 else np.zeros((half.shape[0], 1, 3))], axis=1)
    if gibbs:  # Habel eq. (5) folded into the zonal rows (the seed's own optimisation)
        zonal = np.flatnonzero(m_of == 0)
        half[:, zonal] *= sh.gibbs_factors(bands)[l_of[zonal]][:, None]
    return half


def _angle_map(degrees: tuple[int, int], bands: int) -> NDArray[np.float64]:
    """(dx + dy + 2 + 2 N, 4): the scalar path's packed = cos(angle_map @ (acos x, acos y, phi, 1)) holds
    T_0..T_dx(x), T_0..T_dy(y), cos(m phi) and sin(m phi) = cos(m phi - pi/2), m = 0 .. N - 1."""
    dx, dy = degrees
    multiplier = np.concatenate([np.arange(dx + 1), np.arange(dy + 1), np.arange(bands), np.arange(bands)])
    variable = np.concatenate([np.zeros(dx + 1), np.ones(dy + 1), np.full(2 * bands, 2)]).astype(np.intp)
    angle_map = np.zeros((multiplier.size, 4))
    angle_map[np.arange(multiplier.size), variable] = multiplier
    angle_map[dx + dy + 2 + bands :, 3] = -0.5 * math.pi
    return angle_map


class SkySH:
    """
    SH lighting of the Preetham sky, with its sun and ground, per frame, from the fitted tables.

    Create with :meth:`load`. Methods are read-only and thread-safe.

    Examples
    --------
    >>> sky = SkySH.load()
    >>> c = sky.coefficients(0.5, 3.0, sun_azimuth=1.0, bands=3)
    >>> c.shape
    (9, 3)
    >>> sky.coefficients(0.5, 3.0, 1.0, sun=True, ground_albedo=0.2).shape
    (9, 3)
    """

    model: str = "preetham"
    """The sky model (:data:`skysh.options.MODELS`)."""

    def __init__(self, sky_table: coefficient_file.SkyTable, path: Path | None = None) -> None:
        sky_table.validate()
        self.table: coefficient_file.SkyTable = sky_table
        self.path: Path | None = path
        self.bands: int = sky_table.bands
        self.colourspace: str = sky_table.colourspace
        self.metadata: dict[str, Any] = sky_table.metadata
        self._plans: dict[tuple[int, bool], _Plan] = {
            (n, g): _Plan(sky_table, n, g) for n in range(1, self.bands + 1) for g in (False, True)
        }
        self._colour_matrices: dict[str, NDArray[np.float64]] = {}
        self._mixing: dict[str, bool] = {}  # colourspace -> its conversion matrix has a negative entry
        self._sun: SunLight | None = SunLight(sky_table) if "sun" in sky_table.tables else None
        self._lit_plans: dict[tuple[int, bool, bool, bool], lights.LitPlan] = {}  # on first use of the sun or ground
        self._resolved: dict[tuple, Options] = {}  # SkySH._options per distinct plain setting
        irradiance = sky_table.tables.get("irradiance") if sky_table.bands >= 3 else None
        # The certified irradiance table (docs/irradiance.md): radiance-equivalent (False), irradiance (True).
        self._table_plans: dict[bool, _Plan] | None = None if irradiance is None else {
            lobe: _Plan(sky_table, 3, False, rows_from=irradiance, lobe=lobe) for lobe in (False, True)}

    @classmethod
    def load(cls, path: str | Path | None = None, model: str = "preetham") -> Any:
        """Load the shipped coefficient file (or ``path``, a str or os.PathLike naming a file), checked (see
        :func:`skysh.table.coefficient_file.read`, whose CoefficientFileError, a ValueError, names ``path`` when it is
        neither, e.g. bytes or a number).

        ``model`` (:data:`skysh.options.MODELS`): "preetham" (default) gives this class; "hosek-wilkie" a
        :class:`skysh.hosek_runtime.HosekWilkieSH`, the same per-frame interface over the exact model (no file:
        ``path`` must be None)."""
        if check_choice(model, "model", MODELS) == "hosek-wilkie":
            if path is not None:
                raise ValueError(f"path must be None for model='hosek-wilkie' (projected from its exact model, it "
                                 f"reads no coefficient file), got {short_repr(path)}")
            from skysh.hosek_runtime import HosekWilkieSH

            return HosekWilkieSH()
        sky_table = coefficient_file.read(path)  # checks path first, as skysh.table.container.as_path does
        return cls(sky_table, coefficient_file.default_path() if path is None else Path(path))

    @property
    def has_irradiance_table(self) -> bool:
        """Whether ``coefficients(..., irradiance_table=True)`` is available (the file's certified table, 3+ bands)."""
        return self._table_plans is not None

    def plan(self, bands: int, gibbs: bool = True) -> Any:
        """The precomputed arithmetic of one (``bands``, ``gibbs``) setting of the sky table (its
        half table, gather and rotation indices, degrees, lobe), read-only: for evaluators outside
        Python that must reproduce :meth:`coefficients` (``benchmarks/bench_compiled.py``)."""
        return self._plans[(check_bands(bands, high=self.bands), check_flag(gibbs, "gibbs"))]

    def __repr__(self) -> str:
        return f"SkySH(bands={self.bands}, degrees={self.table.max_degrees}, colourspace={self.colourspace!r})"

    # ------------------------------------------------------------------ #
    def coefficients(
        self, sun_zenith: ArrayLike, turbidity: ArrayLike, sun_azimuth: ArrayLike = 0.0, bands: int = 3,
        gibbs: bool | None = None, dering: bool | None = None, irradiance: bool = False, colourspace: str | None = None,
        sun: bool = False, ground_albedo: ArrayLike = 0.0, irradiance_table: bool | None = None,
        out: NDArray[np.float64] | None = None,
    ) -> NDArray[np.float64]:
        """
        SH coefficients of the sky (and its sun and ground) for one frame (or a batch).

        Parameters
        ----------
        sun_zenith, turbidity, sun_azimuth
            Radians in [0, pi/2] (zenith to horizon); turbidity in [2.5, 6]; radians, any finite
            value, from +X towards +Y. The fitted domain. ``bands``: N in [1, file bands] (7 shipped).
        gibbs
            The zonal sinc filter of Habel eq. (5), N = ``bands``, on the sky and the ground
            (never the sun). Default (None): on for radiance (it halves the ringing), off for
            irradiance (it blurs: ``python tools/error_report.py --sections 9``).
        dering
            Window the sky so its irradiance is non-negative (Sloan 2017, :func:`skysh.post.dering.dering`;
            one window for all channels), after the filter and the rotation, before the sun and
            the ground (each non-negative by construction). Default (None): on for irradiance only.
        irradiance
            Return irradiance E (clamped-cosine convolution, cd/m^2 x sr: lux for the luminance);
            engines wanting E / pi: :mod:`skysh.engines.presets`.
        colourspace
            colour-science RGB colourspace name; default the file's (linear sRGB).
        sun, ground_albedo
            Add the sun's disk (:meth:`sun_light`), a delta windowed by :func:`skysh.model.solar.sun_window`;
            a Lambertian ground below the horizon of albedo a number or an RGB triple (output
            colourspace) in [0, 1], radiance albedo x E_h / pi with E_h the exact irradiance of the
            horizontal ground by the sky (and the sun). Default 0: black. Order: :mod:`skysh.lighting.lights`.
        irradiance_table
            The sky from the file's certified 3-band irradiance table (``docs/irradiance.md``: the
            irradiance closest to the truth subject to being non-negative everywhere), evaluated
            as the sky (eqs. 1, 4), no filter, no deringing search. None: by intent, the table for
            ``irradiance=True``, ``bands=3``, ``gibbs`` not True, ``dering`` not False. False: the
            old pipeline. True: the table (with ``irradiance=False``, its radiance-equivalent
            E_lm / A_l, for engines). With it ``dering`` acts only after a conversion to a
            ``colourspace`` whose matrix has a negative entry (a no-op where non-negative).
        out
            Optional buffer for the result: a writeable, C-contiguous float64 array of the result's
            shape, sharing no memory with the parameters; the result is written into it and it is
            returned. A frame loop that reuses one buffer pays no fresh memory per call (for
            10^5 frames or more the system's price for it can exceed the arithmetic:
            ``python benchmarks/bench_runtime.py --curve-only``). The sky is evaluated straight into
            it for radiance and irradiance without deringing or a colourspace conversion; the
            other paths compute the result, then copy it in. Same values as without it, bit for bit.

        Returns (N * N, 3), or (..., N * N, 3) for array parameters (broadcast; empty: (0, N * N, 3);
        at most ``skysh.checks.MAX_ARRAY_ELEMENTS`` values in its largest array); radiance in
        cd/m^2 (R = G = B = Y for the colourspace's white), linear RGB.

        Raises ValueError for a parameter outside its range (named, with the range), not finite, not
        broadcasting, too large, or an unknown colourspace; an ``out`` that is not such a buffer; ``sun=True``
        without the file's sun table; ``irradiance_table=True`` without the table, with ``bands`` other than 3 or ``gibbs=True``.
        TypeError for ``gibbs``, ``dering``, ``irradiance``, ``sun`` or ``irradiance_table`` not a bool.
        The options are checked and resolved by :meth:`skysh.options.Options.resolve` (its docstring: the rules).
        """
        o = self._options(bands, gibbs, dering, irradiance, colourspace, sun, ground_albedo, irradiance_table)
        bands, gibbs, dering, irradiance, table, sun, albedo = (
            o.bands, o.gibbs, o.dering, o.irradiance, o.irradiance_table, o.sun, o.ground_albedo)
        ts, t, phi = real_scalar(sun_zenith), real_scalar(turbidity), real_scalar(sun_azimuth)
        scalar = ts is not None and t is not None and phi is not None
        frame: tuple = (ts, t, phi) if scalar else self._frames(sun_zenith, turbidity, sun_azimuth)
        into = False  # the per-frame call (a scalar, no out) skips the route: nothing to check or chunk
        if out is not None or not scalar:
            out, into, chunked = self._route(out, frame, scalar, o, colourspace, (sun_zenith, turbidity, sun_azimuth))
            if chunked:
                return self._composed_chunks(frame, out, o, colourspace, ground_albedo)
        if sun or albedo is not None:
            lit = self._lit(frame, scalar, bands, gibbs, dering, colourspace, sun, albedo, table, irradiance)
            return _into(out, lit)
        plan = self._table_plans[irradiance] if table else self._plans[(bands, gibbs)]  # type: ignore[index]
        if scalar:
            sky = self._one(ts, t, phi, plan)  # type: ignore[arg-type]
        else:  # the array path: one design matrix, one matrix product, vectorised rotation
            sky = self._batch_sky(frame[0], frame[1], frame[2], frame[3], plan, into=out if into else None)
        return _into(out, self._finish(sky, o, colourspace))

    def _finish(self, sky: NDArray, o: Options, colourspace: str | None) -> NDArray:
        """The sky's steps after the evaluation (``sky``: this call's own array, or ``out``): the table's conversion,
        or deringing, the lobe (in place) and the conversion."""
        if o.irradiance_table:  # never negative (the certificate); a conversion mixing signs is deringed after it
            return self._table_colour(sky, colourspace, o.dering, o.irradiance)
        if o.dering:
            sky = _dering(sky)
        if o.irradiance:
            sky *= self._plans[(o.bands, True)].lobe
        if colourspace is not None and colourspace != self.colourspace:
            sky = sky @ self._colour_matrix(colourspace).T
        return sky

    def _route(self, out: Any, frame: tuple, scalar: bool, o: Options, colourspace: str | None,
               params: tuple) -> tuple[NDArray | None, bool, bool]:
        """(``out`` checked against the result's shape, or None; whether the sky may be evaluated straight into it: no
        deringing or conversion after it but the table's; whether a batch runs as :meth:`_composed_chunks`: a step
        after the sky that makes new arrays, and more frames than a chunk)."""
        if out is not None:
            out = check_out(out, (() if scalar else frame[3]) + (o.bands * o.bands, 3), () if scalar else params)
        plain = not o.dering and (colourspace is None or colourspace == self.colourspace)
        composed = not plain or o.sun or o.ground_albedo is not None
        chunked = composed and not scalar and math.prod(frame[3]) > _composed_step(o.bands)
        return out, plain or o.irradiance_table, chunked

    def _composed_chunks(self, frame: tuple, out: NDArray | None, o: Options, colourspace: str | None,
                         ground_albedo: ArrayLike) -> NDArray:
        """A composed batch (checked ``frame`` of :meth:`_frames`) as calls of :func:`_composed_step` frames each into the result
        (``out`` or a new array), with the resolved options ``o`` (:meth:`skysh.options.Options.resolve` takes its
        own result back unchanged)."""
        result = np.empty(frame[3] + (o.bands * o.bands, 3)) if out is None else out
        flat, (ts, t, phi), step = result.reshape(-1, *result.shape[-2:]), _flat_frames(*frame), _composed_step(o.bands)
        for part in (slice(start, start + step) for start in range(0, flat.shape[0], step)):
            self.coefficients(ts[part], t[part], phi[part], o.bands, o.gibbs, o.dering, o.irradiance, colourspace,
                              o.sun, ground_albedo, o.irradiance_table, out=flat[part])
        return result

    def _options(
        self, bands: int = 3, gibbs: bool | None = None, dering: bool | None = None, irradiance: bool = False,
        colourspace: str | None = None, sun: bool = False, ground_albedo: ArrayLike = 0.0,
        irradiance_table: bool | None = None,
    ) -> Options:
        """The options of :meth:`coefficients` (same names, defaults and refusals) checked and resolved by
        intent for this file (:meth:`skysh.options.Options.resolve`, its table and irradiance table).

        Cached per distinct set of plain values (Python bools, None, an int, a float albedo or three, a str),
        so the per-frame call resolves each setting once; anything else (numpy values, arrays) is resolved
        on every call.
        """
        key = _plain_key(bands, gibbs, dering, irradiance, irradiance_table, sun, ground_albedo, colourspace)
        resolved = None if key is None else self._resolved.get(key)
        if resolved is None:
            resolved = Options.resolve(bands, gibbs, dering, irradiance, irradiance_table, sun, ground_albedo,
                                       colourspace, has_table=self._table_plans is not None, max_bands=self.bands)
            if key is not None:
                if len(self._resolved) >= _RESOLVED_CACHE:  # e.g. an albedo animated per frame
                    self._resolved.clear()
                self._resolved[key] = resolved
        return resolved

    def _table_colour(self, out: NDArray, colourspace: str | None, dering: bool, irradiance: bool) -> NDArray:
        """The table's result in ``colourspace``, deringed after a conversion whose matrix mixes signs (``dering``)."""
        if colourspace is None or colourspace == self.colourspace:
            return out
        out = out @ self._colour_matrix(colourspace).T
        return _dering(out, "radiance" if irradiance else "irradiance") if dering and self._mixing[colourspace] else out

    def _one(self, ts: float, t: float, phi: float, plan: _Plan) -> NDArray:
        """Scalar fast path: floats only, arithmetic on the precomputed tables of ``plan``."""
        phi = _check_frame(ts, t, phi)
        i1, i2 = plan.split
        # Every per-call factor in one vectorised cos: the Chebyshev terms T_k(x) =
        # cos(k acos x) of both variables and the rotation factors cos(m phi) and
        # sin(m phi) = cos(m phi - pi/2). Error <= k^2 eps, far below the fit's.
        x, y = ts * _XS - _XH, math.log(t) * _YS - _YH
        # Clamp what rounding may push past +-1 at the domain's edges (x >= -1 holds exactly).
        angles = (math.acos(x if x < 1.0 else 1.0), math.acos(y if -1.0 < y < 1.0 else math.copysign(1.0, y)), phi, 1.0)
        packed = np.cos(np.dot(plan.angle_map, np.array(angles)))
        # Habel eq. (1) contracted in x, then in y (np.dot: the cheapest numpy call for small operands).
        half = np.dot(packed[i1:i2], np.dot(packed[:i1], plan.half_table).reshape(i2 - i1, -1))
        out = half[plan.gather]  # (N^2, 3): m < 0 values from their m > 0 partners
        out *= packed[plan.rotation]  # eq. (4)
        out *= _luminance_scale(ts, t)
        return out

    def _frames(self, sun_zenith: ArrayLike, turbidity: ArrayLike,
                sun_azimuth: ArrayLike) -> tuple[NDArray, NDArray, NDArray, tuple[int, ...]]:
        """Checked parameter arrays of a batch and their broadcast shape (not yet broadcast)."""
        ts, t = SKY.x.check_array(sun_zenith), SKY.y.check_array(turbidity)
        phi = check_range(sun_azimuth, "sun_azimuth", -np.inf, np.inf, unit="rad")
        try:
            shape = np.broadcast_shapes(ts.shape, t.shape, phi.shape)
        except ValueError:
            raise ValueError(f"sun_zenith, turbidity and sun_azimuth must broadcast together, got shapes {ts.shape}, "
                             f"{t.shape} and {phi.shape}") from None
        return ts, t, phi, shape

    def _batch_sky(self, ts: NDArray, t: NDArray, phi: NDArray, shape: tuple[int, ...], plan: _Plan,
                   into: NDArray | None = None) -> NDArray:
        """(shape..., rows, 3) of checked arrays: rows N * N, plus the unfiltered c_10 for a ``c10`` plan.

        Evaluated in chunks of at most :data:`BATCH_CHUNK` output values into the preallocated result (``into``, a
        buffer checked by :func:`skysh.checks.check_out`, or a new array), so the temporaries (the design matrix,
        the rotation factors) stay in cache whatever the batch's size."""
        rows = plan.batch_rot_index.shape[0]
        size = math.prod(shape)
        largest = max((ts.size, "sun_zenith"), (t.size, "turbidity"), (phi.size, "sun_azimuth"))[1]
        check_size(size * max(len(plan.table_flat), rows * 3), largest, f"{size:,} frames")
        if into is not None:
            out = into
        else:
            out = np.zeros(shape + (rows, 3)) if 0 in shape else np.empty(shape + (rows, 3))
        flat = out.reshape(size, rows * 3)
        ts, t, phi = _flat_frames(ts, t, phi, shape)
        step = max(1, BATCH_CHUNK // (rows * 3))
        for start in range(0, size, step):
            part = slice(start, start + step)
            _sky_into(ts[part], t[part], phi[part], plan, flat[part])
        return out

    def _colour_matrix(self, colourspace: str) -> NDArray[np.float64]:
        matrix = self._colour_matrices.get(colourspace)
        if matrix is None:
            from skysh.model.preetham import rgb_from_xyz_matrix  # colour-science loads here, on first use

            matrix = rgb_from_xyz_matrix(colourspace) @ np.linalg.inv(rgb_from_xyz_matrix(self.colourspace))
            read_only(matrix)
            self._mixing[colourspace] = bool(np.any(matrix < 0.0))
            self._colour_matrices[colourspace] = matrix
        return matrix

    # ------------------------------------------------------------------ #
    # The sun and the ground (skysh.lighting.lights)
    # ------------------------------------------------------------------ #
    def _lit_plan(self, bands: int, gibbs: bool, table: bool = False, lobe: bool = False) -> lights.LitPlan:
        """The :class:`skysh.lighting.lights.LitPlan` of a checked setting, built on first use (``lobe``: irradiance out,
        its clamped-cosine factors folded into the tables: only for :meth:`skysh.lighting.lights.LitPlan.fused`)."""
        plan = self._lit_plans.get((bands, gibbs, table, lobe))
        if plan is None:  # once per setting; a concurrent first call at worst builds it twice
            sun = self.table.tables.get("sun")
            matrix = None if self._sun is None else self._sun.rgb_from_xyz
            rows_from = self.table.tables["irradiance"] if table else None
            sky_plan = _Plan(self.table, bands, gibbs, c10=True, rows_from=rows_from, lobe=lobe)
            plan = lights.LitPlan(sky_plan, sun, matrix, gibbs, lobe)
            self._lit_plans[(bands, gibbs, table, lobe)] = plan
        return plan

    def _lit(self, frame: tuple, scalar: bool, bands: int, gibbs: bool, dering: bool, colourspace: str | None,
             sun: bool, albedo: tuple[float, float, float] | None, table: bool = False,
             irradiance: bool = False) -> NDArray:
        """SH of sky + sun + ground, in the output colourspace (the order of :mod:`skysh.lighting.lights`); radiance,
        or irradiance (the clamped-cosine convolution last) when ``irradiance``.

        ``frame``: (sun_zenith, turbidity, sun_azimuth), Python floats when ``scalar``, else checked by
        :meth:`_frames` (with the broadcast shape). ``table``: the sky
        from the irradiance table (radiance-equivalent, never deringed), the sum deringed only after a
        conversion whose matrix mixes signs.
        """
        if sun and self._sun is None:
            raise ValueError("sun=True needs the coefficient file's sun table (format 3 on); this SkyTable has none")
        if albedo is not None and self.bands < 2:
            raise ValueError("ground_albedo needs the sky's band-1 coefficient c_10: this SkyTable has 1 band")
        convert = colourspace is not None and colourspace != self.colourspace
        dering_sky = dering and not table
        if scalar:
            ts, t, phi = frame
            phi = _check_frame(ts, t, phi)
            x, y = ts * _XS - _XH, math.log(t) * _YS - _YH
            if not dering_sky and not convert:  # the hot path: one fused evaluation, the lobe folded in
                plan = self._lit_plans.get((bands, gibbs, table, irradiance))
                plan = self._lit_plan(bands, gibbs, table, irradiance) if plan is None else plan
                return plan.fused(ts, t, phi, x, y, sun, albedo)
            plan = self._lit_plan(bands, gibbs, table)
            sky, sun_sh, e_h = plan.parts(ts, t, phi, x, y, sun)
        else:
            plan = self._lit_plan(bands, gibbs, table)
            sky, sun_sh, e_h = self._lit_batch(frame[0], frame[1], frame[2], frame[3], plan, sun)
        return self._lit_finish(plan, sky, sun_sh, e_h, dering_sky, colourspace if convert else None, albedo,
                                table and dering, irradiance)

    def _lit_finish(self, plan: lights.LitPlan, sky: NDArray, sun_sh: NDArray | None, e_h: NDArray, dering_sky: bool,
                    convert: str | None, albedo: tuple[float, float, float] | None, dering_table: bool,
                    irradiance: bool) -> NDArray:
        """The composed path of :meth:`_lit` after the evaluation: dering the sky, + sun, conversion to
        ``convert`` (None: none), + ground, the table's deringing after a mixing conversion, the lobe."""
        if dering_sky:
            sky = _dering(sky)
        if sun_sh is not None:
            sky = sky + sun_sh
        if convert is not None:
            matrix = self._colour_matrix(convert).T
            sky, e_h = sky @ matrix, e_h @ matrix
        if albedo is not None:
            sky = plan.add_ground(sky, e_h, albedo)
        if dering_table and convert is not None and self._mixing[convert]:
            sky = _dering(sky)
        return sky * self._plans[(plan.bands, True)].lobe if irradiance else sky

    def _lit_batch(self, ts: NDArray, t: NDArray, phi: NDArray, shape: tuple[int, ...], plan: lights.LitPlan,
                   sun: bool) -> tuple[NDArray, NDArray | None, NDArray]:
        """Batch: the sky (..., N * N, 3), the sun's windowed SH (or None) and E_h (..., 3), file colourspace."""
        k = plan.bands * plan.bands
        extended = self._batch_sky(ts, t, phi, shape, plan.sky)
        sky, e_h = extended[..., :k, :], ground.HORIZONTAL_FACTOR * extended[..., k, :]
        if not sun:
            return sky, None, e_h
        ts, t, phi = _flat_frames(ts, t, phi, shape)
        phi = np.fmod(phi, _TWO_PI)  # the sky's rotation reduces so (_rotation_factors): the sun sits where the sky turns
        rgb = self._sun.rgb(ts, t)  # type: ignore[union-attr]
        e_h = e_h + (np.cos(ts)[:, None] * rgb).reshape(shape + (3,))
        return sky, plan.sun_batch(ts, phi, rgb).reshape(shape + (k, 3)), e_h

    def sun_light(
        self, sun_zenith: ArrayLike, turbidity: ArrayLike, sun_azimuth: ArrayLike = 0.0, colourspace: str | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """
        The sun as a directional light: the unit vector towards it and its RGB illuminance.

        Parameters
        ----------
        sun_zenith, turbidity, sun_azimuth
            As :meth:`coefficients` (radians in [0, pi/2]; turbidity in [2.5, 6]; radians, any finite value).
        colourspace
            colour-science RGB colourspace name; default the file's (linear sRGB).

        Returns
        -------
        direction, rgb
            ``(sin ts cos phi, sin ts sin phi, cos ts)`` (Z up) and the sun's direct
            normal illuminance (Preetham 1999 appendix, fitted: :class:`skysh.lighting.sunlight.SunLight`),
            lux per channel: an engine's directional light of that colour and
            intensity. Each (3,) for real scalars, else (..., 3) over the broadcast
            shape. Near the horizon a channel outside the gamut is slightly
            negative, as the spectral model's RGB.

        Raises
        ------
        ValueError
            As :meth:`coefficients`; a coefficient table without a sun table.
        """
        if self._sun is None:
            raise ValueError("sun_light needs the coefficient file's sun table (format 3 on); this SkyTable has none")
        if colourspace is not None and not isinstance(colourspace, str):
            raise ValueError(f"colourspace must be None or a colour-science RGB colourspace name, got {short_repr(colourspace)}")
        ts, t, phi = real_scalar(sun_zenith), real_scalar(turbidity), real_scalar(sun_azimuth)
        if ts is not None and t is not None and phi is not None:
            direction, rgb = self._sun.light(ts, t, phi)  # Python floats: its fast path, the same refusals
        else:
            direction, rgb = self._sun.light(sun_zenith, turbidity, sun_azimuth)
        if colourspace is not None and colourspace != self.colourspace:
            rgb = rgb @ self._colour_matrix(colourspace).T
        return direction, rgb

    # ------------------------------------------------------------------ #
    def radiance(
        self, dirs: ArrayLike, sun_zenith: float, turbidity: float, sun_azimuth: float = 0.0, bands: int = 3,
        gibbs: bool | None = None, colourspace: str | None = None, sun: bool = False, ground_albedo: ArrayLike = 0.0,
    ) -> NDArray[np.float64]:
        """Reconstructed radiance (cd/m^2, linear RGB) in the directions ``dirs`` (..., 3) -> (..., 3).

        The sun's parameters are single numbers here (as :meth:`coefficients`, whose
        ``sun`` and ``ground_albedo`` these are); ``dirs`` is any batch of unit vectors,
        empty included (an empty result).
        """
        return self._reconstruct(dirs, "dirs", sun_zenith, turbidity, sun_azimuth, bands, gibbs=gibbs,
                                 colourspace=colourspace, sun=sun, ground_albedo=ground_albedo)

    def irradiance_at(
        self, normals: ArrayLike, sun_zenith: float, turbidity: float, sun_azimuth: float = 0.0, bands: int = 3,
        gibbs: bool | None = None, dering: bool | None = None, colourspace: str | None = None, sun: bool = False,
        ground_albedo: ArrayLike = 0.0, irradiance_table: bool | None = None,
    ) -> NDArray[np.float64]:
        """Reconstructed irradiance (cd/m^2 x sr = lux for luminance) on surfaces with ``normals`` (..., 3) -> (..., 3).

        The sun's parameters are single numbers here (as :meth:`coefficients`, whose
        ``sun``, ``ground_albedo`` and ``irradiance_table`` these are: the certified table
        by default at 3 bands); ``normals`` is any batch of unit vectors, empty included.
        """
        return self._reconstruct(normals, "normals", sun_zenith, turbidity, sun_azimuth, bands, gibbs=gibbs,
                                 dering=dering, irradiance=True, colourspace=colourspace, sun=sun,
                                 ground_albedo=ground_albedo, irradiance_table=irradiance_table)

    def _reconstruct(self, dirs: ArrayLike, name: str, sun_zenith: Any, turbidity: Any, sun_azimuth: Any, bands: Any,
                     **options: Any) -> NDArray[np.float64]:
        """:meth:`radiance` / :meth:`irradiance_at`: the directions ``dirs`` (named ``name``) checked, the sun's
        parameters refused unless scalars, then the basis there times :meth:`coefficients` with ``options``."""
        for key, value in (("sun_zenith", sun_zenith), ("turbidity", turbidity), ("sun_azimuth", sun_azimuth)):
            if real_scalar(value) is None:
                check_scalar(value, key)  # names the parameter: not a number, not finite, or an array
        d = check_dirs(dirs, name, per_point=check_bands(bands, high=self.bands) ** 2)
        c = self.coefficients(sun_zenith, turbidity, sun_azimuth, bands, **options)
        return sh.basis_unchecked(d, int(bands)) @ c


def _sky_into(ts: NDArray, t: NDArray, phi: NDArray, plan: _Plan, out: NDArray) -> None:
    """One chunk of :meth:`SkySH._batch_sky` into ``out`` (n, 3 rows): the Chebyshev rows, the design matrix
    (terms, n), the one matrix product (Habel eq. 1), the rotation (eq. 4)."""
    n = ts.shape[0]
    x, y = poly.scale_unchecked(ts, t)
    if n <= FEW_FRAMES:  # T_k = cos(k acos) as the scalar path (_angle_map), m phi in one cos, one sin
        i1, i2 = plan.split
        acos = np.arccos(np.clip(np.stack((x, y)), -1.0, 1.0))  # rounding may pass +-1 at the ends
        packed = np.cos(plan.angle_map[:i2, :2] @ acos)
        tx, ty = packed[:i1], packed[i1:]
        angles = np.multiply.outer(plan.angle_map[i2 : i2 + plan.bands, 2], np.fmod(phi, _TWO_PI))
        rot = np.concatenate((np.cos(angles), np.sin(angles))).T  # sin(0) = 0 exactly: no m < 0 at azimuth 0
    else:  # by doubling and angle addition: far fewer transcendental calls per frame
        tx = poly.chebyshev_rows(x, plan.degrees[0])
        ty = poly.chebyshev_rows(y, plan.degrees[1])
        rot = _rotation_factors(phi, plan.bands)
    ty *= _luminance_scale(ts, t, np)
    design = (tx[:, None, :] * ty[None, :, :]).reshape(-1, n)  # (T, n): term-major, rows contiguous
    np.matmul(design.T, plan.table_flat, out=out)
    out.reshape(n, -1, 3)[...] *= np.take(rot, plan.batch_rot_index, axis=1)[:, :, None]


def _composed_step(bands: int) -> int:
    """Frames per chunk of a composed batch: :data:`COMPOSED_CHUNK` output values."""
    return max(1, COMPOSED_CHUNK // (3 * bands * bands))


def _flat_frames(ts: NDArray, t: NDArray, phi: NDArray, shape: tuple[int, ...]) -> tuple[NDArray, NDArray, NDArray]:
    """Checked parameter arrays broadcast to ``shape`` and flattened (views where they already have it)."""
    flat = [a.reshape(-1) if a.shape == shape else np.broadcast_to(a, shape).ravel() for a in (ts, t, phi)]
    return flat[0], flat[1], flat[2]


def _into(out: NDArray | None, result: NDArray) -> NDArray:
    """``result``, or ``out`` (a checked buffer of its shape) holding it."""
    if out is None or result is out:
        return result
    out[...] = result
    return out


def _plain_key(bands: Any, gibbs: Any, dering: Any, irradiance: Any, irradiance_table: Any, sun: Any, ground_albedo: Any,
               colourspace: Any) -> tuple | None:
    """The cache key of :meth:`SkySH._options` for plain values (Python bools or None, an int, a float albedo or
    three, None or a str), else None: equal values of other types (1 for True, 3.0 for 3) must be checked."""
    albedo = ground_albedo if type(ground_albedo) is float else _albedo_key(ground_albedo)
    if albedo is not None and type(bands) is int and type(irradiance) is bool and type(sun) is bool \
            and (gibbs is None or type(gibbs) is bool) and (dering is None or type(dering) is bool) \
            and (irradiance_table is None or type(irradiance_table) is bool) \
            and (colourspace is None or type(colourspace) is str):
        return (bands, gibbs, dering, irradiance, irradiance_table, sun, albedo, colourspace)
    return None


def _albedo_key(albedo: Any) -> tuple[float, float, float] | None:
    """An RGB albedo of three Python floats (a tuple or a list) as a key, else None (a bool or an int is not one)."""
    kind = type(albedo)
    if (kind is tuple or kind is list) and len(albedo) == 3 and type(albedo[0]) is float and type(albedo[1]) is float \
            and type(albedo[2]) is float:
        return (albedo[0], albedo[1], albedo[2])
    return None


def _dering(coeffs: NDArray[np.float64], target: str = "irradiance") -> NDArray[np.float64]:
    """:func:`skysh.post.dering.dering`'s coefficients (imported on first use); ``target="radiance"`` for irradiance in."""
    from skysh.post.dering import dering

    return dering(coeffs, target)[0]


def _check_frame(ts: float, t: float, phi: float) -> float:
    """Refuse a scalar frame outside the fitted domain (NaN included), naming the parameter; phi mod 2 pi."""
    if not _ZMIN <= ts <= _ZMAX:  # also False for NaN
        raise SKY.x.error(ts)
    if not _TMIN <= t <= _TMAX:
        raise SKY.y.error(t)
    if not math.isfinite(phi):
        raise ValueError(f"sun_azimuth must be finite (radians), got {phi!r}")
    return math.fmod(phi, _TWO_PI)  # so m * phi cannot overflow
