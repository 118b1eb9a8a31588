"""
Tests of skysh.engines.sun: the sun as each engine's directional light
=====================================================================

-   three.js and Babylon.js under node (``tests/js``, pinned): the JavaScript snippets run, and the
    engines' own code gives the light's colour x intensity and direction (three's ``WebGLLights``,
    the path into the ``directionalLights`` uniform; Babylon's ``Light.getScaledIntensity`` and
    ``DirectionalLight.direction``).
-   Every engine: the diffuse radiance of a white Lambertian surface, the engine's SH ambient term
    of the sky preset (``tests/engines/test_engines.py``'s formulas) plus its direct term of the sun preset
    (the BRDF lines cited in ``docs/engines.md``, written below), equals skysh's
    ``(E_sky(n) + E_sun max(0, n.s)) / pi`` on 2054 normals: the sun is in the sky's scale and frame.
    The sky preset is the engines' diffuse one by intent (3 bands: the certified irradiance table's
    radiance-equivalent, ``irradiance_table=True``) and the deringed old pipeline one option away.
-   Negative controls: the other scale (lux where the engine takes E/pi, E/pi where it takes lux)
    fails the same comparison.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from test_engines import CLAMPED, ENGINE_IRRADIANCE, engine_dirs, irradiance, make_dirs, rel_error, run_node
from test_engines import _node_available as node_available

from skysh.engines import presets as engines
from skysh.engines import sun as engine_sun
from skysh.runtime import SkySH

EXACT_TOL: float = 1e-12
"""Double arithmetic on both sides (measured below 1e-15 of the peak)."""
SIX_DIGIT_TOL: float = 1e-5
"""three.js's SH constants have 6 significant digits (``tests/engines/test_engines.py``); its sun term is exact."""
UNREAL_COLOUR_TOL: float = 5e-3
"""Unreal stores the light colour as 8-bit sRGB (``SetLightColor`` -> ``ToFColor(true)``): half a code step,
decoded, is at most 0.5 / 255 x d(linear)/d(sRGB) <= 0.5 / 255 x 2.4 = 4.7e-3 of the largest channel."""
CONTROL_MIN: float = 0.1
"""The wrong scale is off by pi - 1 times the sun's share of the peak: far more than 10 %."""
DIRECTION_TOL: float = 1e-15
"""The engines' own unit vectors (three.js normalises position - target, Babylon stores the direction, both in
JavaScript doubles) against the preset's float64 vector: a few roundings of components of size <= 1 (eps 2.2e-16)."""
SCALE_PRODUCT_TOL: float = 4.5e-16
"""colour x intensity against SUN_SCALES x max(rgb, 0), over the largest channel: one division and one product,
within 2 ulps of the largest channel (2 x eps = 4.4e-16); a subnormal channel loses its own digits."""
COLOUR_RATIO_TOL: float = 1e-16
"""A channel over the largest (2e4 / 1e5 = 0.2): one correctly rounded division, half an ulp of 0.2 (1.4e-17)."""
INTENSITY_RTOL: float = 1e-15
"""The intensity 1e5 / pi against this file's float64 1e5 / pi: the same quotient, possibly formed as a product
with 1 / pi, so a few ulps (eps 2.2e-16) apart."""

FRAMES_UNDER_TEST: tuple[tuple[float, float, float], ...] = ((0.3, 2.5, 0.7), (1.0, 4.0, -2.0), (1.5, 6.0, 2.9))
"""(sun zenith, turbidity, sun azimuth): a high sun, a mid one, one near the horizon (blue clamped)."""


def srgb_round_trip(c: np.ndarray) -> np.ndarray:
    """Unreal's colour storage: linear -> 8-bit sRGB (ToFColor(true)) -> linear (FLinearColor(FColor))."""
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    code = np.round(np.clip(encoded, 0.0, 1.0) * 255.0) / 255.0
    return np.where(code <= 0.04045, code / 12.92, np.power((code + 0.055) / 1.055, 2.4))


def direct(engine: str, preset: engine_sun.SunPreset, n: np.ndarray) -> np.ndarray:
    """The engine's diffuse radiance of a white Lambertian surface lit by the preset (engine-frame normals n).

    three.js RE_Direct_Physical: dotNL x color (x intensity, WebGLLights) x BRDF_Lambert = 1/pi; Filament
    surface_light_directional: Fd_Lambert = 1/pi x colorIntensity x NoL, l = -direction; Babylon
    computeDiffuseLighting: 1/PI x NdotL x diffuse x getScaledIntensity, L = -direction; Unreal Diffuse_Lambert
    = 1/PI x GetColoredLightBrightness x NoL, L = -X axis; Unity URP LightingPhysicallyBased: brdfData.diffuse
    (no 1/pi) x color x NdotL, L = -forward.
    """
    colour = srgb_round_trip(preset.colour) if engine == "unreal" else preset.colour
    lambert = 1.0 if engine.startswith("unity") else 1.0 / math.pi
    towards = -preset.travel
    return lambert * np.maximum(n @ towards, 0.0)[:, None] * (colour * preset.intensity)


def scene_error(sky: SkySH, engine: str, scales: dict[str, float] | None = None) -> float:
    """Worst error of the engine's sky + sun diffuse against skysh's, over the frames and 2054 normals."""
    d = make_dirs()
    n = engine_dirs(engine, d)
    worst = 0.0
    for (ts, t, phi), table in itertools.product(FRAMES_UNDER_TEST, (True, False)):
        c = sky.coefficients(ts, t, phi, bands=3, gibbs=False, dering=True, irradiance_table=table)
        direction, rgb = sky.sun_light(ts, t, phi)
        preset = engine_sun.sun_preset(direction, rgb, engine)
        if scales is not None:  # the negative control: the preset built with another scale
            factor = scales[engine] / engine_sun.SUN_SCALES[engine]
            preset = engine_sun.SunPreset(engine, preset.direction, preset.travel, preset.colour, preset.intensity * factor)
        ambient = ENGINE_IRRADIANCE[engine](engines.convert(c, engine), n)
        ambient = ambient / math.pi if engine == "threejs" else ambient  # three's probe shader returns E
        sky_part = irradiance(c, d) / math.pi
        if engine in CLAMPED:
            sky_part = np.maximum(sky_part, 0.0)
        reference = sky_part + np.maximum(d @ direction, 0.0)[:, None] * np.maximum(rgb, 0.0) / math.pi
        worst = max(worst, rel_error(ambient + direct(engine, preset, n), reference))
    return worst


TOLERANCE: dict[str, float] = {engine: EXACT_TOL for engine in engines.ENGINES} | {
    "threejs": SIX_DIGIT_TOL, "unreal": UNREAL_COLOUR_TOL}


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_sky_and_sun_light_a_surface_as_skysh_does(sky: SkySH, engine: str):
    assert scene_error(sky, engine) <= TOLERANCE[engine]


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_negative_control_the_other_scale_fails(sky: SkySH, engine: str):
    swapped = {e: (1.0 if s != 1.0 else 1.0 / math.pi) for e, s in engine_sun.SUN_SCALES.items()}
    assert scene_error(sky, engine, swapped) > CONTROL_MIN


@pytest.mark.integration
def test_js_snippets_build_the_lights_in_the_engines(sky: SkySH):
    """The three.js and Babylon.js snippets, run, hold colour x intensity = the sun's lux (clamped) and the
    preset's directions as the engines read them (WebGLLights' uniforms; Babylon's scaled intensity)."""
    node_available()
    direction, rgb = sky.sun_light(1.5, 6.0, 2.9)  # near the horizon: the blue channel is clamped
    three = engine_sun.sun_snippet(direction, rgb, "threejs")
    babylon = engine_sun.sun_snippet(direction, rgb, "babylon").replace(
        "import { Color3, DirectionalLight, Vector3 } from '@babylonjs/core';",
        "import { DirectionalLight as BabylonLight } from '@babylonjs/core/Lights/directionalLight.js';\n"
        "import { Vector3 } from '@babylonjs/core/Maths/math.vector.js';\n"
        "import { Color3 } from '@babylonjs/core/Maths/math.color.js';\n"
        "import { NullEngine } from '@babylonjs/core/Engines/nullEngine.js';\n"
        "import { Scene } from '@babylonjs/core/scene.js';\n"
        "const scene = new Scene(new NullEngine());\n").replace("const sunLight = new DirectionalLight(",
                                                             "const babylonSun = new BabylonLight(").replace(
        "sunLight.", "babylonSun.")
    tail = """
import { PerspectiveCamera } from 'three';
import { WebGLLights } from 'three/src/renderers/webgl/WebGLLights.js';
sunLight.updateMatrixWorld(); sunLight.target.updateMatrixWorld();
const lights = new WebGLLights({ has: () => false });
lights.setup([sunLight]);
const camera = new PerspectiveCamera(); camera.updateMatrixWorld();
lights.setupView([sunLight], camera);
const u = lights.state.directional[0];
const scaled = babylonSun.diffuse.scale(babylonSun.getScaledIntensity());
console.log(JSON.stringify({ threejs: [u.color.toArray(), u.direction.toArray()],
  babylon: [scaled.asArray(), babylonSun.direction.asArray()] }));
"""
    out = run_node({}, code=three + babylon + tail)
    got = json.loads(out.strip().splitlines()[-1])  # Babylon's engine prints a banner first
    lux = np.maximum(rgb, 0.0)
    for engine, (colour, towards_or_travel) in got.items():
        preset = engine_sun.sun_preset(direction, rgb, engine)
        assert np.abs(np.array(colour) - lux).max() <= EXACT_TOL * lux.max(), engine
        expected = preset.direction if engine == "threejs" else preset.travel
        np.testing.assert_allclose(towards_or_travel, expected, rtol=0, atol=DIRECTION_TOL, err_msg=engine)
    assert lux[2] == 0.0 and rgb[2] < 0.0  # the clamp was exercised


def test_compiled_snippets_hold_the_preset(sky: SkySH):
    direction, rgb = sky.sun_light(0.6, 3.0, 1.2)
    for engine in ("filament", "unity", "unreal"):
        text = engine_sun.sun_snippet(direction, rgb, engine)
        preset = engine_sun.sun_preset(direction, rgb, engine)
        for value in (*preset.colour, preset.intensity, *preset.travel):
            assert repr(float(value)) in text or repr(float(value)) + "f" in text, (engine, value)


def _literals(text: str) -> list[str]:
    """Every number literal of a sun snippet (JavaScript, C++ or C#; an ``f`` suffix kept)."""
    import re

    return re.findall(r"(?<![\w.])-?\d+\.?\d*(?:e[-+]?\d+)?f?(?![\w.])", text.split("\n", 3)[-1])


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_snippets_print_no_noise_or_negative_zero(engine: str):
    """Issue 23: a zenith sun's travel is (-0.0, -1, -0.0) in a Y-up frame, and cos(pi/2) leaves 6e-17 in a
    direction: both print as 0 (engines.SNIPPET_ZERO_BELOW of the unit length); a true component of 1e-10 prints."""
    for direction in ((0.0, 0.0, 1.0), (math.cos(math.pi / 2), math.sin(0.5), math.cos(0.5))):
        text = engine_sun.sun_snippet(direction, (1e5, 9e4, 8e4), engine)
        numbers = [float(x.rstrip("f")) for x in _literals(text)]
        assert not any(x.startswith("-") and float(x.rstrip("f")) == 0.0 for x in _literals(text)), text
        assert all(v == 0.0 or abs(v) >= engines.SNIPPET_ZERO_BELOW for v in numbers), text
    small = np.array([1e-10, math.sin(0.5), math.cos(0.5)])
    text = engine_sun.sun_snippet(small / np.linalg.norm(small), (1e5, 9e4, 8e4), engine)  # negative control
    assert any(0.0 < abs(float(x.rstrip("f"))) < 1e-9 for x in _literals(text)), text


@pytest.mark.parametrize(("args", "name"), [
    (((0.0, 0.0, 2.0), (1.0, 1.0, 1.0), "unity"), "direction"),
    (((0.0, 0.0, 1.0), (1.0, math.nan, 1.0), "unity"), "rgb"),
    (((0.0, 0.0, 1.0), (1.0, 1.0), "unity"), "rgb"),
    (((0.0, 0.0, 1.0), (1.0, 1.0, 1.0), "godot"), "engine"),
    ((np.zeros((2, 3)) + (0.0, 0.0, 1.0), (1.0, 1.0, 1.0), "unity"), "direction"),
])
def test_bad_input_is_refused_by_name(args: tuple, name: str):
    with pytest.raises(ValueError, match=name):
        engine_sun.sun_preset(*args)


@given(st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3), st.sampled_from(engines.ENGINES))
def test_colour_times_intensity_is_the_scaled_clamped_illuminance(rgb: list[float], engine: str):
    """colour x intensity = SUN_SCALES[engine] x max(rgb, 0) (to rounding), the colour in [0, 1] with max 1 (or 0)."""
    p = engine_sun.sun_preset((0.0, 0.0, 1.0), rgb, engine)
    expected = np.maximum(rgb, 0.0) * engine_sun.SUN_SCALES[engine]
    np.testing.assert_allclose(p.colour * p.intensity, expected, rtol=0.0, atol=SCALE_PRODUCT_TOL * expected.max())
    assert p.colour.min() >= 0.0 and p.colour.max() == (1.0 if expected.max() > 0.0 else 0.0)


def test_preset_scales_and_colour():
    preset = engine_sun.sun_preset((0.0, 0.0, 1.0), (2.0e4, 1.0e5, -3.0), "unity")
    np.testing.assert_allclose(preset.colour, [0.2, 1.0, 0.0], rtol=0, atol=COLOUR_RATIO_TOL)
    assert preset.intensity == pytest.approx(1.0e5 / math.pi, rel=INTENSITY_RTOL)
    np.testing.assert_array_equal(preset.direction, engines.sun_direction(0.0, 0.0, "unity"))
    black = engine_sun.sun_preset((0.0, 0.0, 1.0), (0.0, -1.0, 0.0), "threejs")
    assert black.intensity == 0.0 and np.all(black.colour == 0.0)


if __name__ == "__main__":  # the measured figures of docs/engines.md
    the_sky = SkySH.load()
    other = {e: (1.0 if s != 1.0 else 1.0 / math.pi) for e, s in engine_sun.SUN_SCALES.items()}
    for name in engines.ENGINES:
        print(json.dumps({"engine": name, "sky_plus_sun_over_peak": scene_error(the_sky, name),
                          "other_scale_control": scene_error(the_sky, name, other)}))
