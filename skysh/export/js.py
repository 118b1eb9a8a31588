"""
The JavaScript and JSON exports
===============================

-   :func:`module_source`: a self-contained ES module (no dependencies, double
    precision) with the fitted tables and ``coefficients(sunZenith, turbidity,
    sunAzimuth = 0, options = {})``, the per-frame runtime for browser day-night
    cycles (``export.export_source(sky, "js")`` calls it), and ``sunLight``, ``engineLayout``.
-   :func:`module_data`: the module's data object alone (JSON text), for code that reads the same numbers
    (``benchmarks/js_floor.mjs``, the hand-written floor the module is timed against).
-   :func:`declarations`, :func:`declarations_path`: the TypeScript declarations of that
    module and the file name TypeScript finds them under (``sky_sh.d.mts`` beside ``sky_sh.mjs``).
-   :func:`json_source`: the tables and the algorithm in words, for any other language.
-   :data:`MODULE_TEMPLATE`, :data:`DERING_TEMPLATE`, :data:`DECLARATIONS_TEMPLATE`, :data:`JSON_TEMPLATE`: their
    source files.

The module and its declarations are real source files, ``skysh/export/templates/js_module.mjs``
and ``js_module.d.mts`` (:mod:`skysh.export.template`): every statement is fixed text there,
checked as it stands by ``tests/export/test_js_template.py`` (node, tsc). Python fills in the
header's words and ONE data object, ``DATA``: the numbers of
:func:`skysh.export.tables.export_tables` (the sky's table, the certified irradiance table, the
sun's and the ground's tables), the deringing's window tables and constants (:mod:`skysh.post.dering`,
:mod:`skysh.sh.minimum`) and, for every engine and band count it takes, its
:func:`skysh.export.tables.engine_plan` as a sparse index-and-factor table that one loop reads.
Every number is written by :func:`skysh.literals.double_literal` (the shortest text that reads
back as the same double). The JSON export fills the fixed text of ``js_export.json`` with the
same numbers and writes it with :mod:`json`.

The module computes the runtime's algorithm (:meth:`skysh.SkySH.coefficients`: Habel 2008
eqs. 1, 4, 5, then the deringing, the sun and the ground, the per-band factor or the engine's
map), with everything static prepared at load: the table holds every band the export was asked for (``bands`` is a
run-time option), the Gibbs and clamped-cosine factors of every band count, and
for every engine and band count it takes, the folded per-band factors and the
rest of the map. A call validates, fills preallocated scratch arrays and allocates
its result only (or none, given ``out``); cos and sin of k phi (the rotation) and of k ts (the sun) come by angle
addition from one cos and one sin each, cos(ts) is taken once, and the certified irradiance table carries the sky's
c_10 row after its own, so that one pass sums both. ``benchmarks/bench_js_floor.py`` times a call against a
hand-written floor doing the same arithmetic (``benchmarks/js_floor.mjs``).

Options follow the Python runtime's defaults by intent: ``gibbs`` defaults to
``!irradiance`` and ``dering`` to ``irradiance``; ``irradianceTable`` (the runtime's
``irradiance_table``) takes the certified 3-band irradiance table for diffuse light unless
``gibbs: true`` or ``dering: false`` is asked for, ``false`` gives the filtered, deringed sky.
An engine implies the diffuse intent (engines light with SH diffusely), so it defaults like
irradiance (the table's radiance-equivalent at 3 bands) and refuses ``irradiance: true`` (its
map already applies the engine's scaling).

References
----------
-   Habel, R., Mustata, B., Wimmer, M. (2008), seed 004: eqs. (1), (4), (5).
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix.
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000).
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from skysh import runtime
from skysh._version import __version__
from skysh.checks import interval_text
from skysh.export import dering as export_dering
from skysh.export import template
from skysh.export.lights import light_flags
from skysh.export.tables import EnginePlan, ExportTables, engine_plan, export_tables
from skysh.literals import double_literal, number_rows
from skysh.model.preetham import PEREZ_Y, ZENITH_LUMINANCE
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

__all__ = ["module_source", "module_data", "declarations", "declarations_path", "json_source"]

MODULE_TEMPLATE: str = "js_module.mjs"
"""The ES module's source (:data:`skysh.export.template.TEMPLATE_DIR`): fixed code, header words and ``{{DATA}}``."""

DERING_TEMPLATE: str = "js_dering.mjs"
"""The deringing section of the ES module (fixed code reading ``MAX_BANDS`` and ``DATA.dering``), its ``{{DERING}}``;
the Hosek-Wilkie module (:mod:`skysh.export.hosek`) embeds the same file."""

DECLARATIONS_TEMPLATE: str = "js_module.d.mts"
"""The TypeScript declarations' source: its words (version, bands, engine names, turbidity domain) are holes."""

JSON_TEMPLATE: str = "js_export.json"
"""The JSON export's fixed text (layouts, the algorithm in words), its numbers ``null`` until filled."""


_PER_LINE: int = 6
"""Numbers per line of an array in the data object."""


def _number(value: Any) -> str:
    """An integer as written, any other real as :func:`double_literal`."""
    return str(int(value)) if isinstance(value, (int, np.integer)) else double_literal(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _data_text(value: Any, indent: str = "") -> str:
    """
    ``value`` as the text of a JSON value (also a JavaScript literal), objects one key a line.

    dict (str keys), list, tuple or ndarray (flattened), str, bool, None and reals; numbers by
    :func:`_number`, an array of more than :data:`_PER_LINE` of them :data:`_PER_LINE` a line.
    """
    inner = indent + "  "
    if isinstance(value, dict):
        items = [f"{json.dumps(key)}: {_data_text(item, inner)}" for key, item in value.items()]
        return "{\n" + inner + (",\n" + inner).join(items) + "\n" + indent + "}"
    if isinstance(value, np.ndarray):
        value = value.ravel().tolist()
    if isinstance(value, (list, tuple)):
        if not (value and all(_is_number(v) for v in value)):
            return "[" + ", ".join(_data_text(v, inner) for v in value) + "]"
        rows = number_rows([_number(v) for v in value], inner, _PER_LINE)
        return "[" + rows + "]" if len(value) <= _PER_LINE else "[\n" + inner + rows + "\n" + indent + "]"
    if value is None or isinstance(value, (bool, str)):
        return json.dumps(value)
    return _number(value)


def _engine_plans(bands: int) -> dict[str, list[EnginePlan | None]]:
    """For every engine, its plan for each band count 1 .. ``bands`` it takes (None where it refuses)."""
    from skysh.engines import presets as engines

    plans: dict[str, list[EnginePlan | None]] = {}
    for name in engines.ENGINES:
        row: list[EnginePlan | None] = [None]
        for n in range(1, bands + 1):
            try:
                row.append(engine_plan(name, n))
            except ValueError:
                row.append(None)
        while row[-1] is None and len(row) > 1:
            row.pop()
        if len(row) > 1:
            plans[name] = row
    return plans


def _plan_data(plan: EnginePlan | None) -> dict[str, Any] | None:
    """An engine plan as the module reads it: ``matrix`` row p's nonzero terms at ``start[p] .. start[p + 1]``."""
    if plan is None:
        return None
    start, index, factor = [0], [], []
    for row in range(plan.offset.size):
        for column, value in plan.terms(row):
            index.append(column)
            factor.append(value)
        start.append(len(index))
    return {"shape": list(plan.shape), "labels": list(plan.labels), "band": plan.band_factor, "start": start,
            "index": index, "factor": factor, "offset": plan.offset}


def _dering_data(bands: int) -> dict[str, Any]:
    """The constants of the module's deringing at 1 .. ``bands`` bands: :func:`skysh.post.dering.dering`'s (target
    irradiance, the least window), with the certificate's (:mod:`skysh.sh.minimum`) where a band count needs it
    (:func:`skysh.post.dering.exact_target`)."""
    windows = [dering.window_table(n, "irradiance") for n in range(1, bands + 1)]
    certificate = None
    if not dering.exact_target(bands):
        lists = export_dering.certificate_lists(bands)
        certificate = {"directions": shmin.DIRECTIONS, "cover": shmin.COVER_RADIUS, "split": shmin.SPLIT,
                       "levels": shmin.LEVELS, "rounding": shmin.SAMPLE_ROUNDING, "diag": lists["DIAG"],
                       "next": lists["NEXT"], "a": lists["RA"], "b": lists["RB"], "bandNorm": lists["BAND_NORM"],
                       "final": export_dering.FINAL_SLACK, "golden": export_dering.GOLDEN, "budget": shmin.CELL_BUDGET}
    counts = range(1, bands + 1)
    return {"rows": len(windows[0]), "windows": windows, "exact": [dering.exact_target(n) for n in counts],
            "lattice": [round(1.0 / dering.tolerance(n)) for n in counts], "subnormal": dering.SUBNORMAL_EXPONENT,
            "kernel": sh.cosine_lobe(bands), "basis": [sh.Y00, sh.K_LINEAR, sh.K_PRODUCT, sh.K_ZONAL, sh.K_SECTORAL],
            "guards": [shmin.TINY, shmin.FLOOR, shmin.POLE, shmin.ALLOWANCE], "steps": shmin.NEWTON_STEPS,
            "certificate": certificate}


def _rows(table: NDArray[np.float64]) -> NDArray[np.float64]:
    """A (DX + 1, DY + 1, rows, 3) table as the module lays it out: (rows, terms, 3), each row's terms contiguous."""
    return table.reshape(-1, table.shape[2], 3).transpose(1, 0, 2)


def _module_data(tables: ExportTables) -> dict[str, Any]:
    """
    The module's data object ``DATA`` for ``tables`` (:func:`skysh.export.tables.export_tables`), as Python values.

    The keys and layouts are those ``js_module.mjs`` documents above ``const DATA``; arrays are
    float64 (ndarray) or ints. :func:`module_source` writes it with every double's shortest text.
    """
    n, lights = tables.bands, tables.lights
    table = _rows(tables.table)
    if n == 1:  # the unfiltered c_10 as row 1, for the ground (stored row 1 from two bands on)
        table = np.concatenate([table, lights.c10.reshape(1, -1, 3)])
    plans = _engine_plans(n)
    return {
        "version": __version__, "maxBands": n, "defaultBands": min(3, n), "degrees": list(tables.degrees),
        "x": [tables.x_scale, tables.x_shift], "y": [tables.y_scale, tables.y_shift],
        "sunZenithDomain": list(tables.sun_zenith_domain), "turbidityDomain": list(tables.turbidity_domain),
        "table": table, "gibbs": np.concatenate([runtime.gibbs_factors(k) for k in range(1, n + 1)]),
        "lobe": tables.lobe, "perezY": PEREZ_Y, "zenithLuminance": list(ZENITH_LUMINANCE),
        "lights": {"flags": light_flags(lights), "sunDegrees": [int(d) for d in lights.sun_degrees],
                   "constants": dict(lights.constants), "sunTable": lights.sun_table, "rgbFromXyz": lights.rgb_from_xyz,
                   "trig": lights.trig, "windows": lights.windows, "ground": lights.ground_zonal},
        "irradiance": None if tables.irradiance is None else _rows(tables.irradiance),
        "dering": _dering_data(n),
        "engines": [[name, [_plan_data(plan) for plan in row]] for name, row in plans.items()],
    }


def _words(sky: runtime.SkySH, tables: ExportTables) -> dict[str, str]:
    """The holes the module and its declarations share: version, the command's options, bands, turbidity domain."""
    n = tables.bands
    return {"VERSION": __version__, "COMMAND_OPTIONS": "" if n == sky.bands else f" --bands {n}", "MAX_BANDS": str(n),
            "DEFAULT_BANDS": str(min(3, n)), "TURBIDITY_DOMAIN": interval_text(*tables.turbidity_domain)}


def module_source(sky: runtime.SkySH, bands: int | None = None) -> str:
    """
    The ES module (``sky_sh.mjs``): :data:`MODULE_TEMPLATE` with its header and data filled in.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`.
    bands
        The largest band count the module evaluates, in [1, the file's bands];
        None (default) for all of them (7 in the shipped file). The table
        grows with it (about 200 KB of text for 7 bands).

    Returns JavaScript source ending with a newline (its header documents the API); raises a
    ValueError for ``bands`` out of range (see :func:`skysh.export.tables.export_tables`).
    """
    tables = export_tables(sky, sky.bands if bands is None else bands)
    data = _module_data(tables)
    names = ", ".join(json.dumps(name) for name, _ in data["engines"]) or "none in this module"
    return template.fill(
        MODULE_TEMPLATE, **_words(sky, tables), DATA=_data_text(data), DERING=template.text(DERING_TEMPLATE),
        ENGINE_LIST=textwrap.fill(names, width=90, initial_indent=" " * 60, subsequent_indent=" *               ").strip(),
        SUN_ZENITH_DOMAIN=interval_text(*tables.sun_zenith_domain, pi=True),
    )


def module_data(sky: runtime.SkySH, bands: int | None = None) -> str:
    """
    The data object ``DATA`` that :func:`module_source` with the same arguments embeds, as JSON text (also a
    JavaScript literal): its keys and layouts are those ``js_module.mjs`` documents above ``const DATA``.

    Raises a ValueError for ``bands`` out of range.
    """
    return _data_text(_module_data(export_tables(sky, sky.bands if bands is None else bands)))


def declarations(sky: runtime.SkySH, bands: int | None = None) -> str:
    """
    TypeScript declarations of :func:`module_source` with the same arguments (:data:`DECLARATIONS_TEMPLATE`).

    Save them under :func:`declarations_path` of the module's path (``sky_sh.d.mts``
    beside ``sky_sh.mjs``): the name TypeScript looks for.

    Raises
    ------
    ValueError
        ``bands`` out of range.
    """
    tables = export_tables(sky, sky.bands if bands is None else bands)
    union = " | ".join(json.dumps(name) for name in _engine_plans(tables.bands)) or "never"
    return template.fill(DECLARATIONS_TEMPLATE, **_words(sky, tables), ENGINE_UNION=union)


def declarations_path(module_path: Path) -> Path:
    """Where TypeScript finds the declarations of a module at ``module_path``: ``sky.mjs`` -> ``sky.d.mts``
    (an ``.mjs`` import resolves to ``.d.mts`` only, whatever the module resolution), else ``sky.d.ts``."""
    path = Path(module_path)
    stem = path.name[: -len(path.suffix)] if path.suffix else path.name
    return path.with_name(stem + (".d.mts" if path.suffix == ".mjs" else ".d.ts"))


def json_source(tables: ExportTables, plan: EnginePlan | None = None) -> str:
    """
    The JSON export: :data:`JSON_TEMPLATE`'s fixed text with the float64 tables and constants (and ``plan``, if given).

    The irradiance table's block holds the table only for 3 bands (``available`` false otherwise).
    """
    payload = json.loads(template.text(JSON_TEMPLATE))
    lights, c = tables.lights, tables.lights.constants
    payload.update(skysh_version=__version__, bands=tables.bands, degrees=list(tables.degrees),
                   table=tables.table.tolist(), half_layout=[list(lm) for lm in tables.half_layout],
                   gibbs=tables.gibbs.tolist(), lobe=tables.lobe.tolist(), perez_Y=PEREZ_Y.tolist())
    payload["x"].update(scale=tables.x_scale, shift=tables.x_shift)
    payload["y"].update(scale=tables.y_scale, shift=tables.y_shift)
    payload["domain"].update(sun_zenith=list(tables.sun_zenith_domain), turbidity=list(tables.turbidity_domain))
    sun = payload["sun"]
    sun.update(available=lights.has_sun, degrees=list(lights.sun_degrees), table=lights.sun_table.tolist(),
               rgb_from_xyz=lights.rgb_from_xyz.tolist(), trig=lights.windowed_trig().tolist(), clamp=c["clamp"])
    sun["air_mass"].update(a=c["am_a"], b=c["am_b"], c=-c["am_neg_c"], m0=c["m0"], x_scale=c["sx_scale"])
    sun["turbidity"].update(min=c["sun_tmin"], y_scale=c["sy_scale"])
    payload["ground"].update(available=lights.has_ground, zonal=lights.ground_zonal.tolist(),
                             c10_table=lights.c10.tolist(), horizontal_factor=c["hf"])
    block, irradiance = payload["irradiance_table"], tables.irradiance if tables.bands == 3 else None
    block.update(available=irradiance is not None, table=None if irradiance is None else irradiance.tolist())
    if irradiance is None:
        for key in ("table", "table_layout", "algorithm"):
            del block[key]
    if plan is None:
        del payload["engine"]
    else:
        payload["engine"].update(name=plan.engine, shape=list(plan.shape), labels=list(plan.labels),
                                 band_factor=plan.band_factor.tolist(), matrix=plan.matrix.tolist(),
                                 offset=plan.offset.tolist())
    return json.dumps(payload, indent=1) + "\n"
