"""
The text of the ``skysh`` command line's output
===============================================

-   :func:`format_coefficients`: ``skysh coeffs`` in one of its formats.
-   :func:`format_engine`: ``skysh coeffs --engine``: an engine's numbers in its
    own layout, or a paste-ready snippet (:mod:`skysh.engines.presets`).
-   :func:`normalise_factor`: the factor of ``--normalise``.
-   :func:`format_sun_light`: ``skysh coeffs --sun-light``: the sun as a directional light.
-   :func:`number_text`, :func:`plural`, :func:`settings_text`, :func:`lm_rows`:
    the pieces of a header.
-   :data:`TABLE_ZERO_BELOW`, :data:`ONE_LINE_LISTS`: how tables and JSON are laid out.

Imports numpy only when a function runs (the command line's start-up stays
cheap: ``benchmarks/bench_startup.py``).
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

__all__ = ["TABLE_ZERO_BELOW"]

TABLE_ZERO_BELOW: float = 1e-12
"""``--format table`` prints |value| < TABLE_ZERO_BELOW x max|DC| as 0. The rotation of ``--up y``
leaves float64 rounding noise where the exact value is zero (tests/app/test_cli.py checks that it lies
below this threshold); the fit's own error (``skysh report``) is many orders of magnitude larger,
so nothing below the threshold carries information."""

ONE_LINE_LISTS = re.compile(r"\[\s*(-?[0-9.eE+-]+(?:,\s*-?[0-9.eE+-]+)*)\s*\]")
"""An innermost JSON list of numbers, to print on one line."""

_COMMENTS: dict[str, str] = {"table": "# {}", "c": "/* {} */", "glsl": "// {}", "hlsl": "// {}"}
"""A header line as a comment of each commented ``--format``."""

_VECTORS: dict[str, str] = {"c": "static const double {}[3] = {{{}}};", "glsl": "const vec3 {} = vec3({});",
                            "hlsl": "static const float3 {} = float3({});"}
"""A named constant 3-vector of ``--sun-light`` in each source ``--format`` (name, then the numbers)."""


def number_text(value: float) -> str:
    """A float as text that reads back as the same float ("90", "90.0000001")."""
    return str(int(value)) if value.is_integer() and abs(value) < 1e16 else repr(value)


def plural(count: int, noun: str) -> str:
    """``"1 band"``, ``"3 bands"``."""
    return f"{count} {noun}{'' if count == 1 else 's'}"


def normalise_factor(coefficients: NDArray[np.float64], irradiance: bool) -> float:
    """
    The factor of ``--normalise``: 1 / (irradiance DC coefficient averaged over R, G, B).

    Parameters
    ----------
    coefficients
        (N * N, 3) radiance (``irradiance=False``) or irradiance coefficients.
    irradiance
        Whether ``coefficients`` already are irradiance.

    Returns
    -------
    float
        k such that ``k * mean_c E(0, 0)_c = 1`` with ``E(0, 0) = A_0 L(0, 0) = pi L(0, 0)``.

    Raises
    ------
    ValueError
        If that average is not positive (never for the Preetham sky).
    """
    from skysh.sh import basis as sh

    dc = float(coefficients[0].mean())
    if not irradiance:
        dc *= float(sh.cosine_lobe(1)[0])
    if not dc > 0.0:
        raise ValueError(f"--normalise needs a positive irradiance DC (R+G+B average), got {dc:g}")
    return 1.0 / dc


def settings_text(info: dict[str, Any]) -> str:
    """The options of a header: filters, and the sun and the ground when present."""
    albedo = info.get("ground_albedo", 0.0)
    albedo = ",".join(number_text(float(v)) for v in (albedo if isinstance(albedo, (tuple, list)) else (albedo,)))
    return (f"gibbs {'on' if info['gibbs'] else 'off'}, dering {'on' if info['dering'] else 'off'}"
            + ("; the sun's disk" if info.get("sun") else "") + (f"; ground albedo {albedo}" if albedo != "0" else ""))


def _json_rows(record: dict[str, Any]) -> str:
    """``record`` as JSON indented by one, each innermost list of numbers on one line (:data:`ONE_LINE_LISTS`)."""
    import json

    return ONE_LINE_LISTS.sub(lambda match: "[" + " ".join(match.group(1).split()) + "]", json.dumps(record, indent=1))


def lm_rows(bands: int) -> list[tuple[int, int]]:
    from skysh.sh import basis as sh

    return [sh.lm(i) for i in range(bands * bands)]


def format_coefficients(coefficients: NDArray[np.float64], fmt: str, info: dict[str, Any]) -> str:
    """
    The text of ``skysh coeffs`` in the format ``fmt`` (one of :data:`COEFF_FORMATS`).

    Parameters
    ----------
    coefficients
        (N * N, 3) RGB coefficients.
    fmt
        ``"table"``: a header (parameters, units, convention) and one row per
        coefficient labelled i, l, m with R, G, B (7 significant digits;
        |values| below :data:`TABLE_ZERO_BELOW` x max|DC| printed as 0, as
        the header says).
        ``"json"``: an object with ``"coefficients"`` (the (N*N, 3) list, full
        precision) and the parameters, units, colourspace and convention.
        ``"csv"``: ``i,l,m,R,G,B`` rows (full precision). ``"glsl"``,
        ``"hlsl"``: a float32 constant array ``SKY_SH``; ``"c"``: a double
        array ``SKY_SH[N*N][3]``.
    info
        The parameters to record (keys as in the JSON output).
    """
    rows = lm_rows(math.isqrt(len(coefficients)))
    values = [[float(v) for v in row] for row in coefficients]
    if fmt == "json":
        return _json_rows({"coefficients": values, "lm": [list(lm) for lm in rows], **info})  # a row per line
    if fmt == "csv":
        lines = ["i,l,m,R,G,B"] + [f"{i},{l},{m}," + ",".join(map(repr, v)) for i, ((l, m), v) in enumerate(zip(rows, values))]
        return "\n".join(lines)
    context = _coefficients_context(info)
    if fmt == "table":
        return _coefficients_table(rows, values, context)
    body = _coefficients_c(rows, values) if fmt == "c" else _coefficients_shader(rows, values, fmt)
    return "\n".join([_COMMENTS[fmt].format(line) for line in context] + body)


def _coefficients_context(info: dict[str, Any]) -> list[str]:
    """The header lines of the commented formats: what was computed, the units and colourspace, the convention."""
    degrees = number_text if "place" not in info else (lambda value: f"{value:.6g}")  # echo what the user typed
    hosek = info.get("model") == "hosek-wilkie"
    albedo = info.get("albedo", 0.0)
    albedo_text = ", ".join(map(number_text, albedo)) if isinstance(albedo, (tuple, list)) else number_text(albedo)
    sky = f"the Hosek-Wilkie sky (albedo {albedo_text})" if hosek else "the Preetham sky"
    summary = (f"skysh {info['skysh_version']}: {info['quantity']} SH of {sky}, {plural(info['bands'], 'band')}; "
               f"sun zenith {degrees(info['sun_zenith_deg'])} deg, azimuth {degrees(info['sun_azimuth_deg'])} deg, "
               f"turbidity {number_text(info['turbidity'])}; {settings_text(info)}")
    return [summary, f"units: {info['units']}; colourspace: {info['colourspace']} (linear)", info["convention"]]


def _coefficients_table(rows: list[tuple[int, int]], values: list[list[float]], context: list[str]) -> str:
    """``--format table``: the commented header and one labelled row per coefficient, noise below the threshold as 0."""
    zero = TABLE_ZERO_BELOW * max(abs(x) for x in values[0])
    context = context + [f"values below {TABLE_ZERO_BELOW:g} x |DC| ({zero:.3g}) are printed as 0 (rounding noise); "
                         "--format json or csv: full precision"]
    header = f"{'i':>3} {'l':>2} {'m':>3} {'R':>15} {'G':>15} {'B':>15}"
    body = [f"{i:>3} {l:>2} {m:>3} " + " ".join(f"{(x if abs(x) >= zero else 0.0):>15.7g}" for x in v)
            for i, ((l, m), v) in enumerate(zip(rows, values))]
    return "\n".join(["# " + line for line in context] + [header] + body)


def _coefficients_c(rows: list[tuple[int, int]], values: list[list[float]]) -> list[str]:
    """``--format c``'s lines below the header: a double array ``SKY_SH[N*N][3]``, full precision."""
    body = [f"    {{{', '.join(map(repr, v))}}}, /* {i}: l={l}, m={m} */" for i, ((l, m), v) in enumerate(zip(rows, values))]
    return [f"static const double SKY_SH[{len(values)}][3] = {{"] + body + ["};"]


def _coefficients_shader(rows: list[tuple[int, int]], values: list[list[float]], fmt: str) -> list[str]:
    """``--format glsl`` or ``hlsl``'s lines below the header: a float32 constant array ``SKY_SH``, shortest round-trip
    text."""
    from skysh.literals import float32_literal

    n = len(values)
    vec3 = "vec3" if fmt == "glsl" else "float3"
    body = [f"    {vec3}({', '.join(map(float32_literal, v))}){',' if i < n - 1 else ''} // {i}: l={l}, m={m}"
            for i, ((l, m), v) in enumerate(zip(rows, values))]
    if fmt == "glsl":
        return [f"const vec3 SKY_SH[{n}] = vec3[{n}]("] + body + [");"]
    return [f"static const float3 SKY_SH[{n}] = {{"] + body + ["};"]


def format_engine(c: NDArray[np.float64], engine: str, fmt: str, info: dict[str, Any]) -> str:
    """The text of ``skysh coeffs --engine``: the engine's numbers in its own layout, or a snippet."""
    from skysh.engines import presets as engines

    if fmt == "snippet":
        return engines.snippet(c, engine)
    mapping = engines.engine_map(engine, int(info["bands"]))
    values = engines.convert(c, engine)
    rows = values.reshape(mapping.shape[0], -1)
    labels = list(mapping.labels)
    info = {**info, "engine": engine, "shape": list(mapping.shape), "labels": labels}
    if fmt == "json":
        return _json_rows({"values": values.tolist(), **info})
    row_labels = labels if len(labels) == rows.shape[0] else [str(i) for i in range(rows.shape[0])]
    if fmt == "csv":
        return "\n".join(f"{label}," + ",".join(map(repr, map(float, row))) for label, row in zip(row_labels, rows))
    header = (f"# skysh {info['skysh_version']}: {engine} preset, {info['bands']} bands; sun zenith "
              f"{info['sun_zenith_deg']:.6g} deg, azimuth {info['sun_azimuth_deg']:.6g} deg, turbidity {info['turbidity']:g}; "
              f"{settings_text(info)}; docs/engines.md")
    width = max(len(label) for label in row_labels)
    body = [f"{label:>{width}} " + " ".join(f"{float(x):>15.7g}" for x in row) for label, row in zip(row_labels, rows)]
    return "\n".join([header] + body)


def format_sun_light(direction: ArrayLike, rgb: ArrayLike, fmt: str, info: dict[str, Any], engine: str | None = None,
                     up: str = "z") -> str:
    """
    The text of ``skysh coeffs --sun-light``: the sun as a directional light.

    Parameters
    ----------
    direction
        (3,) unit vector towards the sun, skysh's frame (Z up).
    rgb
        (3,) its RGB illuminance at normal incidence (lux per channel, times any scale).
    fmt
        ``"table"`` (commented header and two labelled rows), ``"json"``, ``"csv"``
        (``quantity,x_or_R,y_or_G,z_or_B``), ``"glsl"``/``"hlsl"`` (two float32
        constants), ``"c"`` (two double arrays), or with an engine ``"snippet"``
        (:func:`skysh.engines.sun.sun_snippet`); with an engine, table, json and csv
        add the engine's light colour and intensity (:func:`skysh.engines.sun.sun_preset`).
    info
        Parameters to record (units, colourspace, ...); the quantity and the frame are added.
    engine, up
        The output frame: an engine's (:func:`skysh.engines.presets.sun_direction`), else
        ``"z"`` (skysh's) or ``"y"`` (:data:`skysh.sh.basis.Y_UP_MATRIX`, as ``--up y``).
    """
    import json

    import numpy as np

    d = np.asarray(direction, dtype=np.float64)  # checked by skysh.SkySH.sun_light, the format by the command line
    if engine is not None and fmt == "snippet":
        from skysh.engines.sun import sun_snippet

        return sun_snippet(d, rgb, engine)
    d, frame, light = _sun_light_frame(d, rgb, engine, up)
    info = {"quantity": "the sun as a directional light (Preetham 1999 appendix): the unit vector towards it and its "
            "RGB illuminance at normal incidence; the light shines along minus the vector", "frame": frame, **info}
    dl, el = [float(v) for v in d], [float(v) for v in np.asarray(rgb)]
    if fmt == "json":
        return json.dumps({"sun_direction": dl, "sun_illuminance": el, **light, **info}, indent=1)
    if fmt == "csv":
        lines = [("sun_direction", dl), ("sun_illuminance", el)]
        if light:
            lines += [("engine_light_colour", light["engine_light_colour"]),
                      ("engine_light_intensity", [light["engine_light_intensity"]])]
        return "quantity,x_or_R,y_or_G,z_or_B\n" + "\n".join(f"{name}," + ",".join(map(repr, v)) for name, v in lines)
    return _sun_light_commented(dl, el, light, info, fmt)


def _sun_light_frame(d: NDArray[np.float64], rgb: ArrayLike, engine: str | None,
                     up: str) -> tuple[NDArray[np.float64], str, dict[str, Any]]:
    """
    The direction ``d`` (skysh's frame) in the output frame, that frame's description, and with an engine
    its light colour and intensity (:func:`skysh.engines.sun.sun_preset`; else an empty dict).
    """
    from skysh.sh import basis as sh

    if engine is not None:
        from skysh.engines.sun import SUN_UNITS, sun_preset

        preset = sun_preset(d, rgb, engine)
        light = {"engine_light_colour": [float(v) for v in preset.colour], "engine_light_intensity": preset.intensity,
                 "engine_light_intensity_unit": SUN_UNITS[engine] + " (skysh.engines.sun)"}
        return preset.direction, f"the {engine} frame (skysh.engines.presets.sun_direction; docs/engines.md)", light
    if up == "y":
        return sh.Y_UP_MATRIX @ d, "Y up (zenith +Y), right-handed as glTF: skysh's +X stays, +Y becomes -Z", {}
    return d, "Z up (zenith), azimuth from +X towards +Y", {}


def _sun_light_commented(dl: list[float], el: list[float], light: dict[str, Any], info: dict[str, Any], fmt: str) -> str:
    """The sun light as ``--format`` table, c, glsl or hlsl: every parameter as a comment line, then the numbers."""
    info = {**info, **{key: value for key, value in light.items() if key != "engine_light_colour"}}
    if light:
        info["engine_light_colour"] = " ".join(f"{v:.9g}" for v in light["engine_light_colour"])
    context = [_COMMENTS[fmt].format(f"{key}: {value}") for key, value in info.items()]
    if fmt == "table":
        return "\n".join(context + [f"{'':>12} {'x | R':>15} {'y | G':>15} {'z | B':>15}",
                                    f"{'direction':>12} " + " ".join(f"{v:>15.9g}" for v in dl),
                                    f"{'illuminance':>12} " + " ".join(f"{v:>15.7g}" for v in el)])
    from skysh.literals import float32_literal

    number = repr if fmt == "c" else float32_literal
    vectors = (("SUN_DIRECTION", dl), ("SUN_ILLUMINANCE", el))
    return "\n".join(context + [_VECTORS[fmt].format(name, ", ".join(map(number, v))) for name, v in vectors])
