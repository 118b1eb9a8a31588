"""
The sun as each engine's directional light
==========================================

:meth:`skysh.SkySH.sun_light` gives the sun as a unit vector towards it (skysh's
Z-up frame) and its RGB direct normal illuminance in lux. Engines take a
directional light as a direction in their own frame, a colour and an intensity
whose product scales their diffuse BRDF; this module turns the sun into those
numbers, consistent with the SH presets of :mod:`skysh.engines.presets` (the same frame,
:func:`skysh.engines.presets.sun_direction`, and the same radiometric scale as the sky's
ambient term), so sky + sun light a scene as the Python runtime's irradiance does.

-   :data:`SUN_SCALES`: per engine, colour x intensity = scale x illuminance (lux).
-   :class:`SunPreset`, :func:`sun_preset`: the engine's direction, colour and intensity.
-   :func:`sun_snippet`: paste-ready code that sets the engine's light to them.

The scale (``docs/engines.md`` cites the lines)
-----------------------------------------------
A Lambertian surface of albedo rho under a sun of illuminance E (normal incidence)
reflects ``rho E max(0, n.s) / pi``. Engines whose diffuse BRDF divides by pi
(three.js ``BRDF_Lambert``, Filament ``Fd_Lambert``, Babylon.js PBR
``computeDiffuseLighting``, Unreal ``Diffuse_Lambert``, Unity HDRP) take the
light's colour x intensity in lux: scale 1. Unity's built-in and URP lighting
(``LightingPhysicallyBased``: ``brdfData.diffuse`` times the light's colour and
N.L, no 1/pi; ``ShadeSH9`` and ``SampleSH`` return E/pi for the sky) take it in
E/pi units: scale 1/pi. The colour is linear RGB of the file's colourspace with
its largest channel 1 and every channel clamped at 0 (near the horizon the sun's
blue is slightly negative, :data:`skysh.lighting.lights.SUN_SH_CLAMP`); the intensity
carries the magnitude.

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999), appendix: the sun's light.
-   The engines' sources named in ``docs/engines.md`` (section "The sun").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_dirs, short_repr
from skysh.engines import presets as engines
from skysh.literals import double_literal, suffixed_literal

__all__ = ["SUN_UNITS", "sun_preset", "sun_snippet"]

SUN_SCALES: dict[str, float] = {
    "threejs": 1.0, "filament": 1.0, "filament-irradiance": 1.0, "babylon": 1.0, "unreal": 1.0,
    "unity": 1.0 / math.pi, "unity-shader": 1.0 / math.pi,
}
"""Engine's light colour x intensity per lux of the sun's illuminance (see the module docstring)."""

SUN_UNITS: dict[str, str] = {
    engine: "lux" if scale == 1.0 else "cd/m^2 (E/pi: Unity built-in and URP; HDRP takes lux, x pi)"
    for engine, scale in SUN_SCALES.items()
}
"""The unit of :attr:`SunPreset.intensity` per engine."""


@dataclass(frozen=True)
class SunPreset:
    """
    The sun as one engine's directional light.

    Attributes
    ----------
    engine
        One of :data:`skysh.engines.presets.ENGINES`.
    direction
        (3,) unit vector towards the sun in the engine's frame (:func:`skysh.engines.presets.sun_direction`).
    travel
        (3,) ``-direction``: where the light travels (Filament ``direction``, Babylon ``direction``,
        Unity's and Unreal's forward axis).
    colour
        (3,) linear RGB, largest channel 1, each in [0, 1] (all 0 for a black sun).
    intensity
        Largest channel of ``SUN_SCALES[engine] x max(rgb, 0)``, in :data:`SUN_UNITS` of the engine.
    """

    engine: str
    direction: NDArray[np.float64]
    travel: NDArray[np.float64]
    colour: NDArray[np.float64]
    intensity: float


def sun_preset(direction: ArrayLike, rgb: ArrayLike, engine: str) -> SunPreset:
    """
    The sun of :meth:`skysh.SkySH.sun_light` as ``engine``'s directional light.

    Parameters
    ----------
    direction
        (3,) unit vector towards the sun, skysh's frame (Z up).
    rgb
        (3,) its direct normal illuminance, lux per channel (linear RGB, finite; a negative
        channel is clamped to 0, as the sun's SH delta does).
    engine
        One of :data:`skysh.engines.presets.ENGINES`.

    Returns
    -------
    SunPreset
        ``colour x intensity = SUN_SCALES[engine] x max(rgb, 0)`` and the engine-frame directions.

    Raises
    ------
    ValueError
        An unknown engine (the valid ones listed), a direction that is not one unit vector,
        or ``rgb`` not three finite numbers.
    """
    if not isinstance(engine, str) or engine not in SUN_SCALES:
        raise ValueError(f"engine must be one of {', '.join(map(repr, engines.ENGINES))}, got {short_repr(engine)}")
    d = check_dirs(direction, "direction")
    if d.shape != (3,):
        raise ValueError(f"direction must be one unit vector of shape (3,), got shape {d.shape}")
    e = as_float_array(rgb, "rgb")
    if e.shape != (3,):
        raise ValueError(f"rgb must be three numbers (R, G, B lux), got shape {e.shape}")
    scaled = np.maximum(e, 0.0) * SUN_SCALES[engine]
    intensity = float(scaled.max())
    colour = scaled / intensity if intensity > 0.0 else np.zeros(3)
    towards = engines.ENGINE_FRAMES[engine] @ d
    return SunPreset(engine, towards, -towards, colour, intensity)


def _printed(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """A unit vector or a colour (largest |entry| 1 or 0) as :func:`sun_snippet` prints it: entries below
    :data:`skysh.engines.presets.SNIPPET_ZERO_BELOW` (1e-12, of that largest entry) are rounding noise (``cos(pi/2)``
    is 6e-17) printed as 0, and -0.0 (the travel of a zenith sun) as 0, as :func:`skysh.engines.presets.snippet` does."""
    return np.where(np.abs(values) < engines.SNIPPET_ZERO_BELOW, 0.0, values) + 0.0


def sun_snippet(direction: ArrayLike, rgb: ArrayLike, engine: str) -> str:
    """
    Paste-ready code that sets ``engine``'s directional light to the sun (:func:`sun_preset`).

    JavaScript for three.js and Babylon.js, C++ for Filament and Unreal, C# for Unity; numbers as
    :func:`skysh.engines.presets.snippet` writes them (a direction or colour component below
    :data:`skysh.engines.presets.SNIPPET_ZERO_BELOW` of 1, rounding noise, and -0.0 as 0). Arguments and
    refusals as :func:`sun_preset`.
    """
    p = sun_preset(direction, rgb, engine)
    js, f32 = double_literal, suffixed_literal  # JavaScript numbers; C++ and C# floats
    r, g, b = _printed(p.colour)
    (x, y, z), (tx, ty, tz) = _printed(p.direction), _printed(p.travel)
    unit = SUN_UNITS[engine]
    if engine == "threejs":
        return (
            f"// The sun (skysh): colour x intensity = its illuminance, {unit} (BRDF_Lambert divides by pi, as for\n"
            "// the probe); linear sRGB; position = towards the sun, target at the origin.\n"
            "import { Color, DirectionalLight } from 'three';\n\n"
            f"const sunLight = new DirectionalLight(new Color({js(r)}, {js(g)}, {js(b)}), {js(p.intensity)});\n"
            f"sunLight.position.set({js(x)}, {js(y)}, {js(z)}); // then scene.add(sunLight, sunLight.target);\n"
        )
    if engine == "babylon":
        return (
            f"// The sun (skysh): diffuse x intensity = its illuminance, {unit} (a directional light's automatic\n"
            "// intensity mode; the PBR diffuse divides by pi); linear sRGB; direction = where the light travels.\n"
            "import { Color3, DirectionalLight, Vector3 } from '@babylonjs/core';\n\n"
            f"const sunLight = new DirectionalLight('sun', new Vector3({js(tx)}, {js(ty)}, {js(tz)}), scene);\n"
            f"sunLight.diffuse = new Color3({js(r)}, {js(g)}, {js(b)});\nsunLight.intensity = {js(p.intensity)};\n"
        )
    if engine.startswith("filament"):
        return (
            f"// The sun (skysh): intensity in {unit} (Fd_Lambert divides by pi), linear sRGB colour, direction =\n"
            "// where the light travels. engine: your filament::Engine*; add sunEntity to the scene.\n"
            "utils::Entity sunEntity = utils::EntityManager::get().create();\n"
            "filament::LightManager::Builder(filament::LightManager::Type::SUN)\n"
            f"        .color({{{f32(r)}, {f32(g)}, {f32(b)}}})\n        .intensity({f32(p.intensity)})\n"
            f"        .direction({{{f32(tx)}, {f32(ty)}, {f32(tz)}}})\n        .build(*engine, sunEntity);\n"
        )
    if engine.startswith("unity"):
        return (
            f"// The sun (skysh), built-in and URP: color.linear x intensity = E/pi ({unit}), as ShadeSH9's sky;\n"
            "// HDRP: intensity in lux, x Mathf.PI. sunLight: your directional Light.\n"
            "UnityEngine.Rendering.GraphicsSettings.lightsUseLinearIntensity = true; // URP sets it in linear space\n"
            f"sunLight.color = new Color({f32(r)}, {f32(g)}, {f32(b)}).gamma; // Unity uses color.linear\n"
            f"sunLight.intensity = {f32(p.intensity)};\n"
            f"sunLight.transform.rotation = Quaternion.LookRotation(new Vector3({f32(tx)}, {f32(ty)}, {f32(tz)}));\n"
        )
    return (
        f"// The sun (skysh): Intensity in {unit} (Diffuse_Lambert divides by pi); the colour is stored as 8-bit\n"
        "// sRGB (SetLightColor); the light travels along its X axis. SunComponent: your UDirectionalLightComponent*;\n"
        "// with a SkyAtmosphere, SunComponent->SetAtmosphereSunLight(false): this illuminance is already attenuated.\n"
        f"SunComponent->SetLightColor(FLinearColor({f32(r)}, {f32(g)}, {f32(b)}));\n"
        f"SunComponent->SetIntensity({f32(p.intensity)});\n"
        f"SunComponent->SetWorldRotation(FVector({f32(tx)}, {f32(ty)}, {f32(tz)}).Rotation());\n"
    )
