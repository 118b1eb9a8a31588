"""
Tests of skysh.engines.presets against each engine's own code
=====================================================

-   three.js and Babylon.js run for real under node (``tests/js``, versions pinned in its
    package.json and lockfile; install with ``npm ci --prefix tests/js``): the converted sky is
    loaded through the engines' classes and evaluated by their shipped shader text.
-   Filament, Unity and Unreal: their shader formulas, written below from the cited sources,
    in double precision.
-   Every comparison has a negative control: the unconverted coefficients must fail it.

The node processes start in the background when the module begins (background.Prefetched); the
tests that read them are marked ``late``: the Python-only tests overlap them.

References are skysh's own evaluation (:func:`skysh.sh.basis.evaluate` of the radiance L, or of the
irradiance E = A_l L, or E / pi) at skysh directions d; the engines are evaluated at ``M d``
with M the engine frame written here from ``docs/engines.md`` (not taken from the module).
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from background import Prefetched, prefetched, start_early
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh.engines import presets as engines
from skysh.runtime import SkySH
from skysh.sh import basis as sh

JS_DIR: Path = Path(__file__).parents[1] / "js"

# Measured figures quoted below: ``python tests/engines/test_engines.py`` prints them.
SIX_DIGIT_TOL: float = 1e-5
"""three.js (SphericalHarmonics3, its shaders) and Unreal's SHBasisFunction3 use 6-significant-digit
constants (0.282095, 0.488603, 0.886227, ...), up to 1.6e-6 relative per term; summed over nine terms
whose sizes reach about twice the peak, below 1e-5 of the peak (measured 1.2e-6 at worst)."""
EXACT_TOL: float = 1e-12
"""Exact constants (Math.sqrt in Babylon, the sources' closed forms elsewhere): only double rounding
separates them from skysh (measured 1.1e-15 of the peak at worst)."""
BABYLON_SERIALIZED_TOL: float = 2e-4
"""Babylon's SphericalPolynomial.updateFromHarmonics writes pi * Y00 as 0.886277 (it is 0.886227): a
polynomial reloaded without its harmonics is 5.6e-5 high on the DC term (measured 3.2e-5 of the peak)."""
CUBEMAP_TOL: float = 5e-6
"""Babylon's cube-map projector integrates by texel centres, an error falling as 1/size^2 (measured over
the largest coefficient: 2.1e-5, 5.2e-6, 1.3e-6, 3.2e-7 at 16, 32, 64, 128 texels a side); 4x at 64."""
CONTROL_MIN: float = 1e-2
"""Unconverted coefficients must be off by more than 1% of the peak (1000x the six-digit tolerance);
measured 3.8% (Unreal's map only mirrors y, small for a sun near azimuth 0) to 280%."""
MAP_TOL: float = 1e-12
"""engines.convert against this file's own arithmetic of the same numbers (Unity's PackCoefficients: copies,
one subtraction, a factor 3), over max|c|: a few float64 roundings of terms of size max|c| (2.2e-16 each)."""
Y_UP_TOL: float = 1e-13
"""Filament's map against skysh.sh.basis.to_y_up, over max|c|: two routes to the same band rotations (each output at
most a 5-term sum of products of O(1) entries and coefficients), so a few ulps of max|c| apart."""
SUM_ORDER_TOL: float = 1e-14
"""The same map applied in another order, shape or dtype (zero padding, batches, float32 inputs promoted), over
max|c|: each engine number is a dot product with at most 3 non-zero entries whose absolute sum is below 4
(test_engine_map_layout), so a reordering moves it by at most 3 x 4 x eps = 2.7e-15 of max|c|."""
HUGE_RTOL: float = 1e-12
"""convert(c x 1e200) (the checked path) against convert(c) x 1e200, per entry: scaling by a constant commutes
with the at most 3-term sums up to a few roundings (eps 2.2e-16 each)."""
FINITE_MAX: float = 1e6
"""Largest |value| (coefficients and scale) the affine property test draws."""
AFFINE_TOL: float = 1e-9
"""convert(a x + y) against a (convert(x) - b) + convert(y), over (1 + |a|) x FINITE_MAX: both sides round terms
up to 4 (1 + |a|) FINITE_MAX in at most 3-term sums, about 3 x 4 x eps = 2.7e-15 of that scale; the allowance
keeps the original test's 1e-9 (never loosened), far above the rounding."""
SUN_DIRECTION_TOL: float = 1e-15
"""sun_direction against the documented frame matrix (entries 0 and +-1) times (sin z cos a, sin z sin a, cos z):
the matrix only permutes and negates, so the two agree up to the rounding of sin and cos, and the norm is 1
within a few ulps (eps 2.2e-16)."""
PEAK_PLANE_TOL: float = 1e-6
"""Distance of the located irradiance peak from the sun's vertical plane (unit vectors): Nelder-Mead stops at
fatol 1e-14 on a quadratic maximum of O(1) curvature, which pins the position to about sqrt(1e-14) = 1e-7."""

# Engine frames as docs/engines.md states them: engine direction = M @ skysh direction.
FRAMES: dict[str, np.ndarray] = {
    "rh-y-up": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),  # three.js, Filament: (x, z, -y)
    "lh-y-up": np.array([[1.0, 0, 0], [0, 0, 1], [0, 1, 0]]),  # Unity, Babylon: (x, z, y)
    "lh-z-up": np.array([[1.0, 0, 0], [0, -1, 0], [0, 0, 1]]),  # Unreal: (x, -y, z)
}
ENGINE_FRAME: dict[str, str] = {
    "threejs": "rh-y-up", "filament": "rh-y-up", "filament-irradiance": "rh-y-up",
    "unity": "lh-y-up", "unity-shader": "lh-y-up", "babylon": "lh-y-up", "unreal": "lh-z-up",
}
UP_AXIS: dict[str, int] = {"rh-y-up": 1, "lh-y-up": 1, "lh-z-up": 2}

SKIES: tuple[tuple[float, float, float, bool], ...] = (
    (0.2, 2.5, 0.3, True), (0.9, 4.0, 2.5, False), (1.45, 6.0, -2.2, True), (1.2, 3.0, 4.0, False),
)
"""(sun zenith, turbidity, sun azimuth, gibbs): high and low suns, every quadrant of azimuth."""


def make_sets(sky: SkySH) -> list[np.ndarray]:
    """Sky radiance sets, then random ones (9, 3), then a 2-band random set padded by the engines."""
    rng = np.random.default_rng(11)
    skies = [sky.coefficients(ts, t, phi, bands=3, gibbs=g) for ts, t, phi, g in SKIES]
    return skies + [rng.standard_normal((9, 3)) for _ in range(3)] + [rng.standard_normal((4, 3))]


def make_dirs() -> np.ndarray:
    """2048 random unit vectors (skysh frame) plus the six axes."""
    z = np.random.default_rng(5).standard_normal((2048, 3))
    axes = np.vstack([np.eye(3), -np.eye(3)])
    return np.vstack([z / np.linalg.norm(z, axis=1, keepdims=True), axes])


@pytest.fixture(scope="module")
def coefficient_sets(sky: SkySH) -> list[np.ndarray]:
    return make_sets(sky)


@pytest.fixture(scope="module")
def dirs() -> np.ndarray:
    return make_dirs()


def radiance(c: np.ndarray, d: np.ndarray) -> np.ndarray:
    return sh.evaluate(c, d)


def irradiance(c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """E (lux for the luminance) of radiance coefficients c at normals d (skysh frame)."""
    return sh.evaluate(sh.irradiance(c), d)


def rel_error(value: np.ndarray, reference: np.ndarray) -> float:
    """Largest difference over the peak |reference| (all directions and channels)."""
    return float(np.max(np.abs(value - reference)) / np.max(np.abs(reference)))


def engine_dirs(engine: str, d: np.ndarray) -> np.ndarray:
    return d @ FRAMES[ENGINE_FRAME[engine]].T


# --------------------------------------------------------------------------- #
# Engine formulas, written from the engines' sources
# --------------------------------------------------------------------------- #
def poly9(n: np.ndarray) -> np.ndarray:
    """(..., 9) polynomial terms (1, y, z, x, xy, yz, 3z^2 - 1, xz, x^2 - y^2) the engines share."""
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    return np.stack([np.ones_like(x), y, z, x, x * y, y * z, 3 * z * z - 1, x * z, x * x - y * y], axis=-1)


SQRT_PI = math.sqrt(math.pi)
K_SIGNED = np.array([  # Unity SphericalHarmonics.hlsl kSHBasisCoef / HDRP ks; Filament IndirectLight.cpp A[] / C_l
    0.5 / SQRT_PI, -math.sqrt(3) / (2 * SQRT_PI), math.sqrt(3) / (2 * SQRT_PI), -math.sqrt(3) / (2 * SQRT_PI),
    math.sqrt(15) / (2 * SQRT_PI), -math.sqrt(15) / (2 * SQRT_PI), math.sqrt(5) / (4 * SQRT_PI),
    -math.sqrt(15) / (2 * SQRT_PI), math.sqrt(15) / (4 * SQRT_PI),
])
COSINE_OVER_PI = np.array([1.0, 2 / 3, 2 / 3, 2 / 3, 0.25, 0.25, 0.25, 0.25, 0.25])  # Unity kClampedCosineCoefs


def pad9(rows: np.ndarray) -> np.ndarray:
    out = np.zeros((9, 3))
    out[: rows.shape[0]] = rows
    return out


def three_irradiance(coefficients93: np.ndarray, n: np.ndarray) -> np.ndarray:
    """three.js shGetIrradianceAt (lights_pars_begin.glsl.js), its 6-digit constants: E."""
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    terms = np.stack([
        np.full_like(x, 0.886227), 2 * 0.511664 * y, 2 * 0.511664 * z, 2 * 0.511664 * x, 2 * 0.429043 * x * y,
        2 * 0.429043 * y * z, 0.743125 * z * z - 0.247708, 2 * 0.429043 * x * z, 0.429043 * (x * x - y * y),
    ], axis=-1)
    return terms @ coefficients93


def filament_builder_radiance(sh_radiance: np.ndarray) -> np.ndarray:
    """IndirectLight::Builder::radiance (IndirectLight.cpp): sh[i] * A[i], A = k_i C_l / pi,
    C = (pi, 2pi/3, pi/4) (the source's float literals 2.0943951f, 0.785398f round these)."""
    c_l = np.array([math.pi] + [2 * math.pi / 3] * 3 + [math.pi / 4] * 5)
    a = K_SIGNED * c_l / math.pi
    return pad9(sh_radiance) * a[:, None]


def filament_shader(ibl_sh: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Irradiance_SphericalHarmonics (surface_light_indirect.fs): max(sum iblSH[i] p_i(n), 0) = max(E/pi, 0)."""
    return np.maximum(poly9(n) @ pad9(ibl_sh), 0.0)


def unity_pack(sh_rgb: np.ndarray) -> np.ndarray:
    """PackCoefficients (HDRP SphericalHarmonics.cs) / PackSH (core SphericalHarmonics.hlsl): (7, 4)."""
    packed = np.zeros((7, 4))
    for c in range(3):
        s = sh_rgb[c]
        packed[c] = (s[3], s[1], s[2], s[0] - s[6])
        packed[3 + c] = (s[4], s[5], 3.0 * s[6], s[7])
    packed[6] = (sh_rgb[0, 8], sh_rgb[1, 8], sh_rgb[2, 8], 1.0)
    return packed


def shade_sh9(packed: np.ndarray, n: np.ndarray) -> np.ndarray:
    """ShadeSH9 (UnityCG.cginc) = SHEvalLinearL0L1 + SHEvalLinearL2 (SphericalHarmonics.hlsl): E/pi."""
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    va = np.stack([x, y, z, np.ones_like(x)], axis=-1)
    vb = np.stack([x * y, y * z, z * z, z * x], axis=-1)  # normal.xyzz * normal.yzzx
    vc = x * x - y * y
    return va @ packed[0:3].T + vb @ packed[3:6].T + vc[..., None] * packed[6, :3]


def unity_undo_cosine_rescaling(sh_rgb: np.ndarray) -> np.ndarray:
    """HDRP SphericalHarmonicMath.UndoCosineRescaling: canonical radiance SH (9, 3) from the ambient probe."""
    c = np.array([0.28209479177387814347, 0.32573500793527994772, 0.27313710764801976764,
                  0.07884789131313000151, 0.13656855382400988382])
    inv = 1.0 / np.array([c[0], -c[1], c[1], -c[1], c[2], -c[2], c[3], -c[2], c[4]])
    return (sh_rgb * inv).T


def babylon_shader(harmonics: np.ndarray, n: np.ndarray) -> np.ndarray:
    """preScaleForRendering (sphericalPolynomial.ts, Math.sqrt constants) + harmonicsFunctions.fx: E/pi."""
    return poly9(n) @ (pad9(harmonics) * K_SIGNED[:, None])


def unreal_pack(v: np.ndarray) -> np.ndarray:
    """SetupSkyIrradianceEnvironmentMapConstantsFromSkyIrradiance (SceneRendering.cpp): (7, 4)."""
    c0, c1 = 1 / (2 * SQRT_PI), math.sqrt(3) / (3 * SQRT_PI)
    c2, c3 = math.sqrt(15) / (8 * SQRT_PI), math.sqrt(5) / (16 * SQRT_PI)
    c4 = 0.5 * c2
    packed = np.zeros((7, 4))
    for c in range(3):
        s = v[c]
        packed[c] = (-c1 * s[3], -c1 * s[1], c1 * s[2], c0 * s[0] - c3 * s[6])
        packed[3 + c] = (c2 * s[4], -c2 * s[5], 3 * c3 * s[6], -c2 * s[7])
    packed[6] = (c4 * v[0, 8], c4 * v[1, 8], c4 * v[2, 8], 1.0)
    return packed


def get_sky_sh_diffuse(packed: np.ndarray, n: np.ndarray) -> np.ndarray:
    """GetSkySHDiffuse (ReflectionEnvironmentShared.ush): max(0, E/pi)."""
    return np.maximum(shade_sh9(packed, n), 0.0)  # same dot products as ShadeSH9, then the clamp


def unreal_sh_basis3(n: np.ndarray) -> np.ndarray:
    """SHBasisFunction3 (SHCommon.ush), 6-digit constants."""
    k = np.array([0.282095, -0.488603, 0.488603, -0.488603, 1.092548, -1.092548, 0.315392, -1.092548, 0.546274])
    return poly9(n) * k


ENGINE_IRRADIANCE = {  # each engine's diffuse evaluation of convert()'s numbers: E (three.js) or E / pi
    "threejs": three_irradiance,
    "filament": lambda v, n: filament_shader(filament_builder_radiance(v), n),
    "filament-irradiance": filament_shader,
    "unity": lambda v, n: shade_sh9(unity_pack(v), n),
    "unity-shader": shade_sh9,
    "babylon": babylon_shader,
    "unreal": lambda v, n: get_sky_sh_diffuse(unreal_pack(v), n),
}
CLAMPED = {"filament", "filament-irradiance", "unreal"}


def raw_layout(engine: str, c: np.ndarray) -> np.ndarray:
    """The negative control: skysh's numbers pasted into the engine's layout with no conversion."""
    c9 = pad9(c)
    if engine in ("unity", "unreal"):
        return c9.T
    if engine == "unity-shader":
        return unity_pack(c9.T)
    return c9 if engine in ("threejs", "babylon") else c


# --------------------------------------------------------------------------- #
# three.js and Babylon.js under node
# --------------------------------------------------------------------------- #
def _node_available() -> None:
    if shutil.which("node") is None or shutil.which("npm") is None:
        pytest.skip("node and npm are needed to run three.js and Babylon.js (install Node.js >= 18)")
    for package in ("three", "@babylonjs/core"):
        if not (JS_DIR / "node_modules" / package / "package.json").exists():
            pytest.skip(f"tests/js/node_modules/{package} is missing: the engines' pinned JavaScript is installed by "
                        "`npm ci --prefix tests/js` (.ci/run does)")


def run_node(job: dict, script: str = "engines.mjs", code: str | None = None) -> object:
    """Run one node process in tests/js (so bare imports resolve to the pinned packages)."""
    args = ["node", "--input-type=module", "-e", code] if code is not None else ["node", script]
    done = subprocess.run(args, input=json.dumps(job), capture_output=True, text=True, cwd=JS_DIR, timeout=300,
                          check=False)
    if done.returncode != 0:
        raise AssertionError(f"node failed ({done.returncode}):\n{done.stderr[-4000:]}")
    return json.loads(done.stdout) if code is None else done.stdout


CUBE_SIZE: int = 64


def cube_sets(sets: list[np.ndarray]) -> list[np.ndarray]:
    """The random sets with a DC above sum |k_i p_i| max|c| / Y00: positive radiance, as Babylon clamps
    texels to [0, 4096]."""
    dc = np.zeros((9, 3))
    dc[0] = 20.0
    return [c + dc * np.abs(c).max() for c in sets[4:7]]


def engines_job(sets: list[np.ndarray], d: np.ndarray, cube_size: int = 64) -> tuple[dict, list[np.ndarray]]:
    """The input of one node run of engines.mjs (every set converted for three and babylon, then the same sets
    unconverted: the controls; the cube-map sets), and those cube-map sets (:func:`cube_sets`)."""
    converted = {e: [engines.convert(c, e).ravel().tolist() for c in sets] for e in ("threejs", "babylon")}
    raw = [pad9(c).ravel().tolist() for c in sets]
    cubes = cube_sets(sets)
    job = {
        "threejs": {"dirs": engine_dirs("threejs", d).tolist(), "sets": converted["threejs"] + raw},
        "babylon": {"dirs": engine_dirs("babylon", d).tolist(), "sets": converted["babylon"] + raw},
        "babylonCubemap": {"size": cube_size, "frame": FRAMES["lh-y-up"].tolist(),
                           "sets": [c.ravel().tolist() for c in cubes]},
    }
    return job, cubes


def run_engines(sets: list[np.ndarray], d: np.ndarray, cube_size: int = 64) -> dict:
    """One node run: every set converted (three, babylon), then the same sets unconverted (controls)."""
    job, cubes = engines_job(sets, d, cube_size)
    return {"out": run_node(job), "count": len(sets), "cube_sets": cubes}


def snippets_program(c: np.ndarray) -> tuple[str, str]:
    """Babylon's snippet of ``c`` as engines.snippet writes it, and one node module running both JavaScript snippets
    of ``c`` that prints the numbers the engine objects hold. (Babylon's import is pointed at the one module it
    needs: the package root takes 2 s to load.)"""
    three, babylon = engines.snippet(c, "threejs"), engines.snippet(c, "babylon")
    module = babylon.replace("from '@babylonjs/core';", "from '@babylonjs/core/Maths/sphericalPolynomial.js';")
    names = json.dumps(["l00", "l1_1", "l10", "l11", "l2_2", "l2_1", "l20", "l21", "l22"])
    tail = (f"\nconsole.log(JSON.stringify([skyProbe.sh.toArray(), "
            f"{names}.flatMap((n) => skyHarmonics[n].asArray())]));\n")
    return babylon, three + module + tail


@pytest.fixture(scope="module")
def node_runs(request: pytest.FixtureRequest, coefficient_sets: list[np.ndarray],
              dirs: np.ndarray) -> Iterator[Prefetched[Any]]:
    """The module's node processes, in the background from its start: ``engines`` (engines.mjs on the test sets)
    and ``snippets`` (the snippets of set 1). Their inputs are computed here; the jobs only run node."""
    job, cubes = engines_job(coefficient_sets, dirs, CUBE_SIZE)
    program = snippets_program(coefficient_sets[1])[1]
    yield from prefetched(request, {
        "engines": lambda: {"out": run_node(job), "count": len(coefficient_sets), "cube_sets": cubes},
        "snippets": lambda: run_node({}, code=program),
    })


@pytest.fixture(scope="module", autouse=True)
def _start_early(request: pytest.FixtureRequest) -> None:
    start_early(request, "node_runs")


@pytest.fixture(scope="module")
def node_results(node_runs: Prefetched[Any]) -> dict:
    _node_available()
    return node_runs.result("engines")


THREE_OUTPUTS = (("getAt", radiance), ("getIrradianceAt", irradiance), ("probeShader", irradiance))


@pytest.mark.integration
@pytest.mark.late
@pytest.mark.parametrize("output, reference", THREE_OUTPUTS, ids=[o for o, _ in THREE_OUTPUTS])
def test_threejs_matches_skysh(node_results: dict, coefficient_sets: list, dirs: np.ndarray, output, reference):
    """SphericalHarmonics3.fromArray + LightProbe: getAt is the radiance, getIrradianceAt and the
    renderer's path (WebGLLights -> `lightProbe` uniform -> shGetIrradianceAt) the irradiance E."""
    values = node_results["out"]["threejs"][output]
    for k, c in enumerate(coefficient_sets):
        assert rel_error(np.array(values[k]), reference(c, dirs)) <= SIX_DIGIT_TOL, (output, k)


@pytest.mark.integration
@pytest.mark.late
@pytest.mark.parametrize("output, reference", THREE_OUTPUTS, ids=[o for o, _ in THREE_OUTPUTS])
def test_threejs_negative_control(node_results: dict, coefficient_sets: list, dirs: np.ndarray, output, reference):
    values = node_results["out"]["threejs"][output]
    n = node_results["count"]
    for k, c in enumerate(coefficient_sets):
        assert rel_error(np.array(values[n + k]), reference(c, dirs)) > CONTROL_MIN, (output, k)


@pytest.mark.integration
@pytest.mark.late
def test_babylon_default_path_matches_skysh(node_results: dict, coefficient_sets: list, dirs: np.ndarray):
    """SphericalHarmonics.FromArray -> SphericalPolynomial.FromHarmonics -> BindIBLParameters (default
    SPHERICAL_HARMONICS define) -> computeEnvironmentIrradiance of harmonicsFunctions.fx: E / pi."""
    values = node_results["out"]["babylon"]["harmonicsShader"]
    n = node_results["count"]
    for k, c in enumerate(coefficient_sets):
        reference = irradiance(c, dirs) / math.pi
        assert rel_error(np.array(values[k]), reference) <= EXACT_TOL, k
        assert rel_error(np.array(values[n + k]), reference) > CONTROL_MIN, k  # negative control


@pytest.mark.integration
@pytest.mark.late
def test_babylon_serialized_polynomial(node_results: dict, coefficient_sets: list, dirs: np.ndarray):
    """A polynomial reloaded without its harmonics (SphericalPolynomial.FromArray) goes back through
    FromPolynomial: right up to Babylon's 0.886277 constant (BABYLON_SERIALIZED_TOL)."""
    values = node_results["out"]["babylon"]["serializedShader"]
    for k, c in enumerate(coefficient_sets):
        assert rel_error(np.array(values[k]), irradiance(c, dirs) / math.pi) <= BABYLON_SERIALIZED_TOL, k


@pytest.mark.integration
@pytest.mark.late
def test_babylon_polynomial_branch_convolves_again(node_results: dict, coefficient_sets: list, dirs: np.ndarray):
    """Babylon's non-default branch (brdf.useSphericalHarmonics = false) evaluates the polynomial of
    FromHarmonics, which applies A_l / pi once more: it gives sum (A_l / pi)^2 L_i Y_i, not E / pi,
    for harmonics in Babylon's own convention (its cube-map projector's). Documented, not fixed here."""
    values = node_results["out"]["babylon"]["polynomialShader"]
    lobe = sh.cosine_lobe(3) / math.pi
    for k, c in enumerate(coefficient_sets):
        twice = sh.convolve(sh.convolve(c, lobe), lobe)
        reference = irradiance(c, dirs) / math.pi
        assert rel_error(np.array(values[k]), radiance(twice, dirs)) <= BABYLON_SERIALIZED_TOL, k
        assert rel_error(np.array(values[k]), reference) > CONTROL_MIN, k


@pytest.mark.integration
@pytest.mark.late
def test_babylon_cube_map_projector_agrees(node_results: dict):
    """Babylon's ConvertCubeMapToSphericalPolynomial, fed cube faces showing the skysh radiance in
    Babylon's frame, keeps the harmonics convert(..., 'babylon') gives (A_l / pi, CS phase)."""
    for k, c in enumerate(node_results["cube_sets"]):
        harmonics = np.array(node_results["out"]["babylonCubemap"]["harmonics"][k])
        expected = engines.convert(c, "babylon")
        assert rel_error(harmonics, expected) <= CUBEMAP_TOL, k
        assert rel_error(harmonics, pad9(c)) > CONTROL_MIN, k


@pytest.mark.integration
@pytest.mark.late
@pytest.mark.parametrize("engine", ["threejs", "babylon"])
def test_python_formulas_match_node(node_results: dict, coefficient_sets: list, dirs: np.ndarray, engine: str):
    """The Python transcriptions used by the sun tests are the engines' code (same numbers as node)."""
    output = "probeShader" if engine == "threejs" else "harmonicsShader"
    evaluate = ENGINE_IRRADIANCE[engine]
    for k, c in enumerate(coefficient_sets):
        node = np.array(node_results["out"][engine][output][k])
        mine = evaluate(engines.convert(c, engine), engine_dirs(engine, dirs))
        assert rel_error(mine, node) <= EXACT_TOL, k


@pytest.mark.integration
@pytest.mark.late
def test_js_snippets_run_and_build_the_numbers(coefficient_sets: list, node_runs: Prefetched[Any]):
    """Both JavaScript snippets, run in one node module (:func:`snippets_program`), build engine objects holding
    exactly convert()'s numbers."""
    _node_available()
    c = coefficient_sets[1]
    babylon = snippets_program(c)[0]
    assert "from '@babylonjs/core';" in babylon
    got = json.loads(node_runs.result("snippets"))
    assert got == [engines.convert(c, "threejs").ravel().tolist(), engines.convert(c, "babylon").ravel().tolist()]


# --------------------------------------------------------------------------- #
# Filament, Unity, Unreal: their formulas in double precision
# --------------------------------------------------------------------------- #
SHADER_ENGINES = ("filament", "filament-irradiance", "unity", "unity-shader", "unreal", "babylon")


@pytest.mark.parametrize("engine", SHADER_ENGINES)
def test_engine_diffuse_matches_skysh(coefficient_sets: list, dirs: np.ndarray, engine: str):
    """Each engine's diffuse evaluation of convert()'s numbers is E / pi (clamped at 0 where the
    engine clamps: Filament, Unreal) to 1e-12 of the peak; the unconverted numbers are not."""
    evaluate = ENGINE_IRRADIANCE[engine]
    n = engine_dirs(engine, dirs)
    for k, c in enumerate(coefficient_sets):
        reference = irradiance(c, dirs) / math.pi
        if engine in CLAMPED:
            reference = np.maximum(reference, 0.0)
        assert rel_error(evaluate(engines.convert(c, engine), n), reference) <= EXACT_TOL, k
        assert rel_error(evaluate(raw_layout(engine, c), n), reference) > CONTROL_MIN, k


def test_unity_shader_is_unity_packed(coefficient_sets: list):
    """unity-shader is PackCoefficients of the unity numbers (exact arithmetic: copies, one subtraction, x3)."""
    for c in coefficient_sets:
        np.testing.assert_allclose(engines.convert(c, "unity-shader"), unity_pack(engines.convert(c, "unity")),
                                   rtol=0, atol=MAP_TOL * np.abs(c).max())


def test_unity_ambient_probe_undoes_to_radiance(coefficient_sets: list, dirs: np.ndarray):
    """HDRP's UndoCosineRescaling(RenderSettings.ambientProbe) is the canonical radiance SH in Unity's
    frame: evaluated there it is the skysh radiance, so the ambient probe holds "Unity format"."""
    n = engine_dirs("unity", dirs)
    for k, c in enumerate(coefficient_sets):
        canonical = unity_undo_cosine_rescaling(engines.convert(c, "unity"))
        assert rel_error(sh.evaluate(canonical, n), radiance(c, dirs)) <= EXACT_TOL, k
        assert rel_error(sh.evaluate(unity_undo_cosine_rescaling(raw_layout("unity", c)), n),
                         radiance(c, dirs)) > CONTROL_MIN, k


def test_unreal_vector_is_radiance(coefficient_sets: list, dirs: np.ndarray):
    """FSHVectorRGB3 dotted with SHBasisFunction3 (SHCommon.ush) at Unreal directions is the radiance."""
    n = engine_dirs("unreal", dirs)
    for k, c in enumerate(coefficient_sets):
        value = unreal_sh_basis3(n) @ engines.convert(c, "unreal").T
        assert rel_error(value, radiance(c, dirs)) <= SIX_DIGIT_TOL, k
        assert rel_error(unreal_sh_basis3(n) @ pad9(c), radiance(c, dirs)) > CONTROL_MIN, k


def test_filament_radiance_is_the_y_up_rotation(coefficient_sets: list):
    """Filament's radiance() takes skysh's coefficients rotated to Y up (sh.to_y_up): `--up y` output."""
    for c in coefficient_sets:
        np.testing.assert_allclose(engines.convert(c, "filament"), sh.to_y_up(c), rtol=0,
                                   atol=Y_UP_TOL * np.abs(c).max())


# --------------------------------------------------------------------------- #
# The sun
# --------------------------------------------------------------------------- #
def _fibonacci(n: int) -> np.ndarray:
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = math.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def _brightest(f, start: np.ndarray) -> np.ndarray:
    """Local maximum of f on the sphere near `start` (Nelder-Mead in the tangent plane)."""
    from scipy.optimize import minimize

    t1 = np.cross(start, [0.3, 0.5, 0.8])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(start, t1)

    def point(p):
        d = start + p[0] * t1 + p[1] * t2
        return d / np.linalg.norm(d)

    best = minimize(lambda p: -f(point(p)[None])[0], [0.0, 0.0], method="Nelder-Mead",
                    options={"xatol": 1e-11, "fatol": 1e-14, "maxiter": 4000})
    return point(best.x)


SUNS: tuple[tuple[float, float], ...] = ((1.0, 0.4), (1.3, 2.6), (0.8, -1.9), (1.2, 4.5))
"""(zenith, azimuth): off-zenith suns in all four quadrants, so a swapped or mirrored axis shows."""


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_sun_is_where_the_irradiance_peaks(sky: SkySH, engine: str):
    """The brightest irradiance in the engine's frame (the engine's own evaluation of convert()'s
    numbers) lies in the vertical plane of sun_direction(), on the sun's side and above the horizon."""
    evaluate = ENGINE_IRRADIANCE[engine]
    up = np.zeros(3)
    up[UP_AXIS[ENGINE_FRAME[engine]]] = 1.0
    grid = _fibonacci(20000)
    for zenith, azimuth in SUNS:
        v = engines.convert(sky.coefficients(zenith, 3.0, azimuth, gibbs=False), engine)

        def luminance(n: np.ndarray, v: np.ndarray = v) -> np.ndarray:
            return evaluate(v, n) @ np.array([0.2126, 0.7152, 0.0722])

        peak = _brightest(luminance, grid[np.argmax(luminance(grid))])
        sun = engines.sun_direction(zenith, azimuth, engine)
        normal = np.cross(up, sun)
        normal /= np.linalg.norm(normal)
        horizontal = sun - sun @ up * up
        assert abs(peak @ normal) < PEAK_PLANE_TOL, (zenith, azimuth)  # in the sun's vertical plane
        assert peak @ horizontal > 0 and peak @ up > 0, (zenith, azimuth)  # on the sun's side, above


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_sun_direction_in_documented_frame(engine: str):
    zenith, azimuth = 0.7, 2.1
    d = np.array([math.sin(zenith) * math.cos(azimuth), math.sin(zenith) * math.sin(azimuth), math.cos(zenith)])
    expected = FRAMES[ENGINE_FRAME[engine]] @ d
    np.testing.assert_allclose(engines.sun_direction(zenith, azimuth, engine), expected, rtol=0, atol=SUN_DIRECTION_TOL)
    np.testing.assert_array_equal(engines.ENGINE_FRAMES[engine], FRAMES[ENGINE_FRAME[engine]])
    batch = engines.sun_direction(np.array([0.1, 0.7]), np.array([[2.1], [-0.3]]), engine)
    assert batch.shape == (2, 2, 3)
    np.testing.assert_allclose(batch[0, 1], expected, rtol=0, atol=SUN_DIRECTION_TOL)
    np.testing.assert_allclose(np.linalg.norm(batch, axis=-1), 1.0, rtol=0, atol=SUN_DIRECTION_TOL)


def test_sun_direction_refuses_bad_input():
    with pytest.raises(ValueError, match="sun_zenith"):
        engines.sun_direction(1.7, 0.0, "unity")
    with pytest.raises(ValueError, match="sun_zenith"):
        engines.sun_direction(-0.1, 0.0, "unity")
    with pytest.raises(ValueError, match="sun_azimuth"):
        engines.sun_direction(0.5, math.nan, "unity")
    with pytest.raises(ValueError, match="threejs"):
        engines.sun_direction(0.5, 0.0, "three")


# --------------------------------------------------------------------------- #
# The map itself
# --------------------------------------------------------------------------- #
@pytest.mark.parametrize("engine", engines.ENGINES)
@pytest.mark.parametrize("bands", [1, 2, 3])
def test_engine_map_layout(engine: str, bands: int):
    emap = engines.engine_map(engine, bands)
    assert emap is engines.engine_map(engine, bands)  # cached
    assert (emap.engine, emap.bands) == (engine, bands)
    assert emap.matrix.shape == (math.prod(emap.shape), bands * bands * 3)
    assert emap.offset.shape == (math.prod(emap.shape),)
    assert len(emap.labels) == emap.shape[0]
    assert not emap.matrix.flags.writeable and not emap.offset.flags.writeable
    assert np.count_nonzero(emap.offset) == (1 if engine == "unity-shader" else 0)
    assert np.abs(emap.matrix).sum(axis=1).max() < 4  # what the fast path's screen (_FAST_LIMIT) assumes
    with pytest.raises(ValueError):
        emap.matrix[0, 0] = 1.0


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_fewer_bands_are_the_first_coefficients(coefficient_sets: list, engine: str):
    """Converting 1 or 2 bands equals converting 3 bands whose higher bands are zero."""
    c = coefficient_sets[5]
    for bands in (1, 2):
        k = bands * bands
        padded = np.zeros((9, 3))
        padded[:k] = c[:k]
        lower = engines.convert(c[:k], engine)
        full = engines.convert(padded, engine)
        if engine.startswith("filament"):
            full = full[:k]
        np.testing.assert_allclose(lower, full, rtol=0, atol=SUM_ORDER_TOL * np.abs(c).max())


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_fast_and_general_paths_agree(coefficient_sets: list, engine: str):
    c = coefficient_sets[0]
    fast = engines.convert(c, engine)
    assert fast.shape == engines.engine_map(engine).shape
    for variant in (c.tolist(), np.asfortranarray(c), c[None], c[::-1][::-1].copy()[None, None]):
        other = engines.convert(variant, engine)  # the checked path: same map, summed in another order
        np.testing.assert_allclose(other.reshape(fast.shape), fast, rtol=0, atol=SUM_ORDER_TOL * np.abs(c).max())
    single = c.astype(np.float32)  # other dtypes take the checked path on their float64 values
    np.testing.assert_allclose(engines.convert(single, engine), engines.convert(single.astype(np.float64), engine),
                               rtol=0, atol=SUM_ORDER_TOL * np.abs(c).max())
    huge = c * 1e200  # beyond the fast path's screen (sum x^2 overflows): the checked path, same product
    offset = engines.engine_map(engine).offset.reshape(fast.shape)
    np.testing.assert_allclose(engines.convert(huge, engine) - offset, (fast - offset) * 1e200, rtol=HUGE_RTOL)


finite = st.floats(min_value=-FINITE_MAX, max_value=FINITE_MAX, allow_nan=False)


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(engines.ENGINES), st.lists(finite, min_size=54, max_size=54), finite)
def test_convert_is_affine_and_batches(engine: str, values: list, scale: float):
    """convert(a x + y) = a (convert(x) - b) + convert(y); a batch equals its items."""
    x, y = np.array(values[:27]).reshape(9, 3), np.array(values[27:]).reshape(9, 3)
    b = engines.engine_map(engine).offset.reshape(engines.engine_map(engine).shape)
    lhs = engines.convert(scale * x + y, engine)
    rhs = scale * (engines.convert(x, engine) - b) + engines.convert(y, engine)
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=AFFINE_TOL * (1 + abs(scale)) * FINITE_MAX)
    batch = engines.convert(np.stack([x, y]).reshape(2, 1, 9, 3), engine)
    assert batch.shape == (2, 1) + b.shape
    np.testing.assert_allclose(batch[1, 0], engines.convert(y, engine), rtol=0, atol=SUM_ORDER_TOL * FINITE_MAX)


# --------------------------------------------------------------------------- #
# Snippets and bad input
# --------------------------------------------------------------------------- #
NUMBER_LINES = {
    "filament": r"^\s+\{(.*)\},?$", "filament-irradiance": r"^\s+\{(.*)\},?$",
    "unity": r"^skyProbe\[\d, \d\] = (.*);$", "unity-shader": r"new Vector4\((.*)\)\);$",
    "unreal": r"^SkySH\.[RGB]\.V\[\d\] = (.*);$",
}


@pytest.mark.parametrize("engine", sorted(NUMBER_LINES))
def test_compiled_language_snippets_hold_the_numbers(coefficient_sets: list, engine: str):
    """C++ / C# snippets: every float literal reads back as convert()'s double, in layout order."""
    import re

    c = coefficient_sets[2]
    text = engines.snippet(c, engine)
    numbers = [float(x.strip().rstrip("f")) for line in text.splitlines()
               for m in [re.search(NUMBER_LINES[engine], line)] if m for x in m.group(1).split(",")]
    assert numbers == engines.convert(c, engine).ravel().tolist()
    assert "nan" not in text and "inf" not in text


def test_unknown_engine_lists_the_valid_ones(coefficient_sets: list):
    c = coefficient_sets[0]
    for call in (lambda: engines.convert(c, "three.js"), lambda: engines.engine_map("Unity"),
                 lambda: engines.snippet(c, "godot"), lambda: engines.convert(c, None)):
        with pytest.raises(ValueError, match="engine must be one of") as info:
            call()
        assert all(name in str(info.value) for name in engines.ENGINES)


def test_too_many_bands_names_engine_and_limit():
    with pytest.raises(ValueError, match=r"'threejs' holds at most 3 bands"):
        engines.convert(np.ones((16, 3)), "threejs")
    with pytest.raises(ValueError, match=r"bands must be an integer in \[1, 3\] for engine 'unity'"):
        engines.engine_map("unity", 4)
    for bad in (0, True, 2.0, "3"):
        with pytest.raises(ValueError, match="bands"):
            engines.engine_map("unreal", bad)


@pytest.mark.parametrize("bad", [np.ones(9), np.ones((9, 4)), np.ones((8, 3)), np.ones((0, 3)), np.ones(()),
                                 [[1, 2, 3]] * 5, "coefficients", np.ones((9, 3), dtype=complex)])
def test_wrong_shapes_and_types_are_refused(bad):
    with pytest.raises(ValueError, match="coeffs"):
        engines.convert(bad, "filament")


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize("engine", engines.ENGINES)
def test_non_finite_coefficients_are_refused(engine: str, value: float):
    c = np.ones((9, 3))
    c[4, 1] = value
    with pytest.raises(ValueError, match="coeffs must be finite"):
        engines.convert(c, engine)
    with pytest.raises(ValueError, match="coeffs must be finite"):
        engines.convert(c[None], engine)
    with pytest.raises(ValueError, match="coeffs"):
        engines.snippet(c, engine)


def test_overflowing_coefficients_are_refused():
    """Finite coefficients whose engine numbers would overflow (a row of the three.js map sums to > 1)."""
    matrix = engines.engine_map("threejs").matrix
    row = matrix[np.argmax(np.abs(matrix).sum(axis=1))]
    with pytest.raises(ValueError, match="too large"):
        engines.convert((1.7e308 * np.sign(row)).reshape(9, 3), "threejs")


SNIPPET_NOISE: float = 1e-13
"""Rounding noise planted in a snippet's input, over its DC term: below engines.SNIPPET_ZERO_BELOW (1e-12), above
the rotation's own (the runtime leaves ~1e-17 of the DC in the m < 0 terms at sun azimuth 0)."""
SNIPPET_SIGNAL: float = 1e-10
"""A small true value, over the DC term: 100x the threshold, so the snippet must still print it."""


def _literals(text: str, engine: str) -> list[str]:
    """The number literals of a snippet, in layout order (as test_compiled_language_snippets_hold_the_numbers reads
    them; the JavaScript ones from the lines between the array's brackets)."""
    import re

    if engine in NUMBER_LINES:
        return [x.strip() for line in text.splitlines() for m in [re.search(NUMBER_LINES[engine], line)] if m
                for x in m.group(1).split(",")]
    body = text[text.index("([\n") + 3 : text.index("\n])")]
    return [x.strip() for x in re.sub(r"/\*.*?\*/|[\[\]]", "", body).split(",") if x.strip()]


def test_snippet_constant_is_the_table_rule():
    from skysh.app import cli_output

    assert engines.SNIPPET_ZERO_BELOW == cli_output.TABLE_ZERO_BELOW == 1e-12


@pytest.mark.parametrize("engine", engines.ENGINES)
def test_snippet_prints_rounding_noise_as_zero(coefficient_sets: list, engine: str):
    """Issue 23: values below SNIPPET_ZERO_BELOW x the DC term (max |row 0| over channels) print as 0, -0.0 as 0;
    a value of 1e-10 of the DC still prints (negative control); every other literal is convert()'s double."""
    c = coefficient_sets[0].copy()
    dc = np.abs(c[0]).max()
    c[1:4] = [SNIPPET_NOISE * dc, -SNIPPET_NOISE * dc, -0.0]  # m = -1, 0, 1 of band 1: noise, noise, -0.0
    c[4:6] = 0.0  # two zero rows whose maps keep a -0.0 only if the sign leaks
    text = engines.snippet(c, engine)
    printed = np.array([float(x.rstrip("f")) for x in _literals(text, engine)])
    values = engines.convert(c, engine).ravel()
    noise = (np.abs(values) < engines.SNIPPET_ZERO_BELOW * dc) & (engines.engine_map(engine).offset == 0.0)
    assert noise.sum() >= 9 and np.count_nonzero((values != 0.0) & noise) >= 6  # the planted noise reached the output
    assert np.all(printed[noise] == 0.0) and not any(v.startswith("-") and float(v.rstrip("f")) == 0.0
                                                     for v in _literals(text, engine))  # no -0.0 either
    np.testing.assert_array_equal(printed[~noise], values[~noise])

    c[1:4] = [SNIPPET_SIGNAL * dc, -SNIPPET_SIGNAL * dc, 0.0]  # negative control: true small values print
    kept = np.array([float(x.rstrip("f")) for x in _literals(engines.snippet(c, engine), engine)])
    np.testing.assert_array_equal(kept, engines.convert(c, engine).ravel())
    assert np.count_nonzero((kept != 0.0) & (np.abs(kept) < 1e-9 * dc)) >= 6


def test_snippet_refuses_a_batch():
    with pytest.raises(ValueError, match="one set"):
        engines.snippet(np.ones((2, 9, 3)), "unreal")


def report() -> None:
    """``python tests/engines/test_engines.py``: the measured agreements the tolerances above quote (worst over
    the test sets, relative to the peak) and the smallest error of the negative controls."""
    sets, d = make_sets(SkySH.load()), make_dirs()
    res = run_engines(sets, d)
    out, n = res["out"], res["count"]

    def worst(values: list, refs: list, offset: int = 0) -> float:
        return max(rel_error(np.array(values[offset + k]), r) for k, r in enumerate(refs))

    def least(values: list, refs: list, offset: int = 0) -> float:
        return min(rel_error(np.array(values[offset + k]), r) for k, r in enumerate(refs))

    e_pi = [irradiance(c, d) / math.pi for c in sets]
    rows = [(f"threejs {o}", worst(out["threejs"][o], [f(c, d) for c in sets]),
             least(out["threejs"][o], [f(c, d) for c in sets], n)) for o, f in THREE_OUTPUTS]
    rows.append(("babylon default path", worst(out["babylon"]["harmonicsShader"], e_pi),
                 least(out["babylon"]["harmonicsShader"], e_pi, n)))
    rows.append(("babylon serialized polynomial", worst(out["babylon"]["serializedShader"], e_pi), math.nan))
    rows.append(("babylon polynomial branch vs E/pi", worst(out["babylon"]["polynomialShader"], e_pi), math.nan))
    for engine in SHADER_ENGINES:
        evaluate = ENGINE_IRRADIANCE[engine]
        ne = engine_dirs(engine, d)
        refs = [np.maximum(r, 0.0) if engine in CLAMPED else r for r in e_pi]
        rows.append((f"{engine} formula", max(rel_error(evaluate(engines.convert(c, engine), ne), r)
                                              for c, r in zip(sets, refs)),
                     min(rel_error(evaluate(raw_layout(engine, c), ne), r) for c, r in zip(sets, refs))))
    for name, error, control in rows:
        print(f"{name:36s} worst {error:9.2e}   control >= {control:9.2e}")
    for size in (16, 32, 64, 128):
        cube = run_engines(sets, d[:6], size)
        errors = [rel_error(np.array(h), engines.convert(c, "babylon"))
                  for h, c in zip(cube["out"]["babylonCubemap"]["harmonics"], cube["cube_sets"])]
        print(f"babylon cube-map projector, {size:3d} texels: worst {max(errors):9.2e}")


if __name__ == "__main__":
    report()
