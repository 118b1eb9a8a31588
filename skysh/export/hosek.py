"""
Export the Hosek-Wilkie per-frame runtime to C and to JavaScript
================================================================

Source that reproduces :func:`skysh.model.hosek_frame.coefficients` (linear sRGB, the RGB dataset)
and the runtime's post steps without Python: the dataset's RGB tensors, the constants and the
accuracy's node counts as numbers, and the algorithm as fixed source in
``skysh/export/templates/hosek_wilkie.h`` (C99) and ``hosek_wilkie.mjs`` (an ES module, with
its TypeScript declarations ``hosek_wilkie.d.mts``). This module writes numbers and a few
switches only (:func:`skysh.export.template.fill`, the literals of :mod:`skysh.literals`):

-   :func:`export_source`: the text for ``"c"`` or ``"js"``;
-   :func:`declarations`: the TypeScript declarations of the ES module;
-   :data:`LANGUAGES`, :data:`REFUSED`, :data:`DEFAULT_FILE_NAMES`, :data:`MAX_EXPORT_BANDS`.

What the exported code computes per frame, in the order of the Python runtime
(``skysh.SkySH.load(model="hosek-wilkie").coefficients``):

1.  Refuse a sun zenith outside [0, pi/2], a turbidity outside [1, 10], an albedo outside
    [0, 1] in any channel or a non-finite azimuth (C: a negative code and zeroed output; JS: a
    RangeError naming the parameter).
2.  The parameters A..I and L_M of each channel (Hosek and Wilkie 2012, section 5, as
    :func:`skysh.model.hosek.configuration`): linear in turbidity between the integers, linear
    in the channel's own albedo between 0 and 1, quintic Bezier in (elevation / (pi/2))^(1/3).
3.  The sun-adapted product rule of :mod:`skysh.model.hosek_frame` (the same layout: zenith
    panels {0, the sun, 45, 85, 90} degrees, Gauss-Legendre in theta below 45 degrees and in
    u = sqrt(cos theta) above, the sun panel's extra nodes shared by width; azimuth
    Gauss-Legendre on [0, pi], more nodes past 80 degrees). The Gauss-Legendre nodes and
    weights of every count the accuracy can ask for are computed **at load** in the target
    language (Newton on the Legendre recurrence to full double precision, numpy's
    symmetrisation), as are the azimuth sums cos(m phi_j) w_j pi.
4.  The model L = F(theta, gamma) L_M (eq. 9) at every ring x azimuth node, its azimuth
    moments and the Legendre rows sin^|m| theta sum_k c_k cos(k theta) (the Chebyshev rows of
    :func:`skysh.model.hosek_frame.basis_rows`, written as data for every band count: bit for bit Python's
    constants, 784 numbers or 17 KB of text at 7 bands, against a closed form or a fit at load
    that would differ from them by rounding), contracted over the rings; times
    cos(m alpha) or sin(|m| alpha), alpha = fmod(sun azimuth, 2 pi) (Habel 2008, eq. 4);
    times 683 lm/W (cd/m^2).
5.  The post steps of the runtime, as asked: the zonal Gibbs filter sinc(pi l / N) (Habel
    eq. 5), the deringing (:func:`skysh.post.dering.dering`, target irradiance: C embeds
    :func:`skysh.export.dering.dering_source` at the export's band count, JavaScript the
    Preetham module's own deringing file, :data:`skysh.export.js.DERING_TEMPLATE`, at every band
    count), the clamped-cosine lobe
    A_l for irradiance. The defaults by intent: ``gibbs = !irradiance``, ``dering = irradiance``.

Why not GLSL, HLSL or JSON (:data:`REFUSED`)
--------------------------------------------
The per-frame projection is a CPU (or compute) job, not a shader function: at "default"
accuracy it evaluates the model at 34 rings x 24 or 28 azimuth nodes (816 to 952 points) in
3 channels, each point an ``exp`` of E gamma, a chi(H, gamma) with its square root, an
``asin`` and about 40 multiply-adds, so 2,500 to 2,900 ``exp`` and some 1e5 flops, then the
contraction with N^2 basis rows (another 34 x 49 x 3 at 7 bands), from a dataset of 2,160
numbers (1,800 parameters and 360 radiances) interpolated first. A fragment or vertex shader
would repeat all of it for every pixel for the same 3 N^2 numbers; a shader that wants the
true sky takes the 30 numbers of the ES module's ``configuration()`` (C:
``skysh_hw_configuration``) per frame and evaluates eq. 9 per pixel. JSON would be the dataset
without the algorithm, which is this module's point.

Cost per call on the project's 2-core machine (gcc -O2; node 20), "default" accuracy: C 35 us at
3 bands and 64 us at 7 (370 us with the 7-band deringing's certificate), JavaScript 90 us and
225 us (770 us), against 150 us and 170 us for :func:`skysh.model.hosek_frame.coefficients`;
the rule's nodes at load: 0.1 ms in C.

Precision: double only (``real="float"`` is refused: the rule's 900-term sums and the
exp(B / (cos theta + 0.01)) at the horizon were measured in double only).
``tests/export/test_export_hosek.py`` compares both languages with the Python pipeline to 1e-12
of the DC term's largest magnitude.

References
----------
-   Hosek, L., Wilkie, A. (2012). An Analytic Model for Full Spectral Sky-Dome Radiance.
    ACM Trans. Graph. 31(4), 95: eq. (9), section 5.
-   Habel, R., Mustata, B., Wimmer, M. (2008). Efficient Spherical Harmonics Lighting with
    the Preetham Skylight Model: eq. (4) (rotation about Z), eq. (5) (Gibbs filter).
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skysh._version import __version__
from skysh.checks import check_bands, check_choice
from skysh.export import dering as export_dering
from skysh.export import js as export_js
from skysh.export import template
from skysh.literals import double_literal, number_rows
from skysh.model import hosek, hosek_data, hosek_frame
from skysh.sh import basis as sh

__all__ = ["LANGUAGES", "REFUSED", "DEFAULT_FILE_NAMES", "MAX_EXPORT_BANDS", "export_source", "declarations"]

LANGUAGES: tuple[str, ...] = ("c", "js")
"""Languages :func:`export_source` writes."""

REFUSED: dict[str, str] = {
    language: (f"the Hosek-Wilkie per-frame export does not write {language}: the projection evaluates the model at "
               "816 to 952 points x 3 channels (about 2,900 exp and 1e5 flops) from a 2,160-number dataset for the "
               "same 3 N^2 numbers every pixel would recompute, a CPU or compute job, not a shader function. Use "
               "language 'c' or 'js' (whose configuration() gives a shader the 30 numbers of eq. 9)")
    for language in ("glsl", "hlsl")
} | {"json": ("the Hosek-Wilkie per-frame export does not write json: its point is the algorithm (the per-frame "
              "rule and projection), which JSON cannot hold. Use language 'c' or 'js'")}
"""Why each language the Preetham export writes is refused here (:func:`export_source`'s ValueError)."""

DEFAULT_FILE_NAMES: dict[str, str] = {"c": "hosek_wilkie.h", "js": "hosek_wilkie.mjs"}
"""The file name each export is meant to be saved as."""

MAX_EXPORT_BANDS: int = 7
"""Most bands an export takes: the rules are measured to 7 (:mod:`skysh.model.hosek_frame`) and the deringing
takes 7 (:data:`skysh.post.dering.MAX_DERING_BANDS`)."""

DEFAULT_BANDS: dict[str, int] = {"c": 3, "js": MAX_EXPORT_BANDS}
"""``bands=None``: C is compiled for 3 bands (the deringing is per band count); the ES module holds 7 (a run-time option)."""

C_TEMPLATE: str = "hosek_wilkie.h"
"""The C header's source (:data:`skysh.export.template.TEMPLATE_DIR`)."""

JS_TEMPLATE: str = "hosek_wilkie.mjs"
"""The ES module's source."""

DECLARATIONS_TEMPLATE: str = "hosek_wilkie.d.mts"
"""The ES module's TypeScript declarations."""



def _literals(values: Any, per_line: int = 6, indent: str = "  ") -> str:
    """``values`` flattened row-major as shortest round-trip doubles, a few a line."""
    flat = np.ravel(np.asarray(values, dtype=np.float64))
    return number_rows([double_literal(v) for v in flat], indent, per_line)


def _chebyshev(bands: int) -> tuple[np.ndarray, np.ndarray]:
    """The Chebyshev rows of every band count 1..``bands``, each (n, n^2) row-major, concatenated (offset of n: sum
    of k^3 for k < n), and the |m| of each index of ``bands`` bands (the same prefix for fewer)."""
    rows = [hosek_frame.basis_rows(n)[0].ravel() for n in range(1, bands + 1)]
    return np.concatenate(rows), hosek_frame.basis_rows(bands)[1]


def _gibbs(bands: int) -> np.ndarray:
    """The Gibbs factors sinc(l / n) (numpy's sinc) of every band count n = 1..``bands``, concatenated (offset n (n - 1) / 2)."""
    return np.concatenate([sh.gibbs_factors(n) for n in range(1, bands + 1)])


def _accuracy_numbers(accuracy: str) -> dict[str, int]:
    """The node counts of ``accuracy`` (:data:`skysh.model.hosek_frame.ACCURACIES`) and the sizes they imply."""
    acc = hosek_frame.ACCURACIES[check_choice(accuracy, "accuracy", tuple(hosek_frame.ACCURACIES))]
    if not acc.by_width:  # pragma: no cover - every named accuracy shares by width
        raise ValueError("the export shares the sun panel's nodes by width only")
    return {"ZENITH0": acc.zenith[0], "ZENITH1": acc.zenith[1], "ZENITH2": acc.zenith[2], "SUN": acc.sun,
            "MINIMUM": acc.minimum, "AZIMUTH": acc.azimuth, "LOW_SUN_AZIMUTH": acc.low_sun_azimuth, "RINGS": acc.rings,
            "MAX_AZIMUTH": max(acc.azimuth, acc.low_sun_azimuth),
            "MAX_NODES": max(max(acc.zenith) + acc.sun, acc.azimuth, acc.low_sun_azimuth)}


def _constants() -> dict[str, float]:
    """The model's and the rule's real constants, by the names the templates use."""
    edges = hosek_frame.ZENITH_EDGES
    assert len(edges) == 4 and edges[0] == 0.0 and hosek_frame.U_FROM == edges[1]  # the layout the templates assume
    return {"PI": math.pi, "HALF_PI": 0.5 * math.pi, "TWO_PI": 2.0 * math.pi, "EDGE1": edges[1], "EDGE2": edges[2],
            "EDGE3": edges[3], "LOW_SUN": hosek_frame.LOW_SUN, "HORIZON_OFFSET": hosek.HORIZON_OFFSET,
            "EFFICACY": hosek.LUMINOUS_EFFICACY, "ZMIN": hosek.SUN_ZENITH_RANGE[0], "ZMAX": hosek.SUN_ZENITH_RANGE[1],
            "TMIN": hosek.TURBIDITY_RANGE[0], "TMAX": hosek.TURBIDITY_RANGE[1], "AMIN": hosek.ALBEDO_RANGE[0],
            "AMAX": hosek.ALBEDO_RANGE[1]}


def _dataset() -> tuple[np.ndarray, np.ndarray]:
    """The RGB dataset's parameters (10, 2, 6, 3, 9) and radiances (10, 2, 6, 3), as shipped."""
    tensors = hosek_data.sky_tensors()
    params, radiances = tensors["sky_params_rgb"], tensors["sky_rad_rgb"]
    assert params.shape == (10, 2, 6, 3, 9) and radiances.shape == (10, 2, 6, 3)
    return params, radiances


def _license() -> str:
    """Hosek and Wilkie's BSD-3 notice (with the tensors' provenance), as the shipped dataset carries it, as the lines
    of a block comment (each after " * ")."""
    text = hosek_data.LICENSE_PATH.read_text(encoding="utf-8").rstrip().replace("*/", "* /")
    return "\n".join((" * " + line).rstrip() for line in text.splitlines())


def _check(language: str, bands: int | None, real: str) -> int:
    """The export's band count for ``language`` (checked), after refusing the languages and precisions it does not write."""
    if language in REFUSED:
        raise ValueError(REFUSED[language])
    check_choice(language, "language", LANGUAGES)
    check_choice(real, "real", ("double", "float"))
    if real != "double":
        raise ValueError("real must be 'double': the Hosek-Wilkie export is written and measured in double only "
                         "(900-term sums, exp(B / (cos theta + 0.01)) at the horizon)")
    return DEFAULT_BANDS[language] if bands is None else check_bands(bands, high=MAX_EXPORT_BANDS)


def _c_source(bands: int, accuracy: str) -> str:
    """The C header: the numbers of ``bands`` bands and ``accuracy``, the deringing of ``bands`` bands, the fixed code."""
    params, radiances = _dataset()
    chebyshev, m = _chebyshev(bands)
    sizes = {"BANDS": bands, "COUNT": bands * bands, "CHEBYSHEV_SIZE": chebyshev.size, "GIBBS_SIZE": bands * (bands + 1) // 2,
             **_accuracy_numbers(accuracy)}
    values: dict[str, object] = {f"SKYSH_HW_{k}": v for k, v in sizes.items()}
    values |= {f"SKYSH_HW_{k}": double_literal(v) for k, v in _constants().items()}
    values |= {"SKYSH_HW_BEZIER": ", ".join(map(double_literal, hosek.BEZIER_BINOMIALS)),
               "SKYSH_HW_M": ", ".join(str(int(v)) for v in m)}
    defines = template.defines(values)
    return template.fill(
        C_TEMPLATE, VERSION=__version__, ACCURACY=accuracy, LICENSE=_license(), DEFINES=defines,
        PARAMS=_literals(params, indent="    "), RADIANCES=_literals(radiances, indent="    "),
        CHEBYSHEV=_literals(chebyshev, indent="    "), GIBBS=_literals(_gibbs(bands), indent="    "),
        LOBE=_literals(sh.cosine_lobe(bands), indent="    "),
        DERING=export_dering.dering_source("c", "irradiance", "skysh_hw_dering", bands),
    )


def _js_data(bands: int, accuracy: str) -> dict[str, Any]:
    """The ES module's ``DATA`` (its keys documented above ``const DATA`` in ``hosek_wilkie.mjs``)."""
    params, radiances = _dataset()
    chebyshev, m = _chebyshev(bands)
    return {"version": __version__, "maxBands": bands, "accuracy": accuracy,
            "nodes": {k.lower(): v for k, v in _accuracy_numbers(accuracy).items()},
            "constants": {k.lower(): v for k, v in _constants().items()},
            "bezier": list(hosek.BEZIER_BINOMIALS), "params": params, "radiances": radiances, "chebyshev": chebyshev,
            "m": [int(v) for v in m], "gibbs": _gibbs(bands), "lobe": sh.cosine_lobe(bands),
            "dering": export_js._dering_data(bands)}


def export_source(language: str, bands: int | None = None, accuracy: str = "default", real: str = "double") -> str:
    """
    Source text of the Hosek-Wilkie per-frame runtime in ``language``.

    Parameters
    ----------
    language
        ``"c"``: a C99 header (``hosek_wilkie.h``: include guard, ``static inline`` functions,
        ``static const`` tables, clean under ``-std=c99 -Wall -Wextra -pedantic``, link with
        ``-lm``) for ``bands`` bands; ``"js"``: an ES module (``hosek_wilkie.mjs``) holding
        1..``bands`` bands, the band count a run-time argument. ``"glsl"``, ``"hlsl"`` and
        ``"json"`` are refused (:data:`REFUSED`, the module docstring: a per-frame projection
        over ~900 points x 3 channels is not a shader function).
    bands
        N in [1, :data:`MAX_EXPORT_BANDS`]; None: 3 for C, 7 for JavaScript. The C header's
        state may take fewer bands, without deringing (its tables are per band count).
    accuracy
        A key of :data:`skysh.model.hosek_frame.ACCURACIES` ("fast", "default", "fine"): the
        rule's node counts, fixed in the source.
    real
        ``"double"`` (the only precision offered; ``"float"`` is refused, saying why).

    Returns
    -------
    str
        The source, ending with a newline; its header documents the API and carries Hosek and
        Wilkie's BSD-3 notice (the dataset's).

    Raises
    ------
    ValueError
        A refused or unknown language, ``real`` not "double", an unknown accuracy, ``bands``
        out of range.

    Notes
    -----
    The numbers: the RGB dataset's parameters (10, 2, 6, 3, 9) and radiances (10, 2, 6, 3) as
    shipped (Hosek and Wilkie 2012, section 5), the rule's constants and node counts, the
    Chebyshev rows and Gibbs factors of every band count up to N, the lobe A_l and the
    deringing's numbers; every real as its shortest round-trip double
    (:func:`skysh.literals.double_literal`).

    Examples
    --------
    >>> export_source("c").startswith("/*")
    True
    """
    bands = _check(language, bands, real)
    if language == "c":
        return _c_source(bands, accuracy)
    data = _js_data(bands, accuracy)
    return template.fill(JS_TEMPLATE, VERSION=__version__, ACCURACY=accuracy, MAX_BANDS=str(bands),
                         LICENSE=_license(), DATA=export_js._data_text(data), DERING=template.text(export_js.DERING_TEMPLATE))


def declarations(bands: int | None = None, accuracy: str = "default") -> str:
    """The TypeScript declarations (``hosek_wilkie.d.mts``) of :func:`export_source` ``("js", bands, accuracy)``."""
    bands = _check("js", bands, "double")
    check_choice(accuracy, "accuracy", tuple(hosek_frame.ACCURACIES))
    return template.fill(DECLARATIONS_TEMPLATE, VERSION=__version__, MAX_BANDS=str(bands), ACCURACY=accuracy)
