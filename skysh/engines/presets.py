"""
Engine presets: skysh radiance SH in each engine's own dialect
===============================================================

skysh coefficients are real orthonormal SH **with** the Condon-Shortley (CS)
phase, index ``l (l + 1) + m``, in a right-handed **Z-up** frame, radiance in
cd/m^2 (``docs/conventions.md``). Engines differ in frame, handedness, sign
convention and pre-scaling; :func:`convert` produces exactly what an engine's
API takes, in its order and shape.

-   :data:`ENGINES`, :data:`ENGINE_MAX_BANDS`, :data:`ENGINE_FRAMES`.
-   :func:`engine_map`: the fixed affine map of one (engine, bands) as a
    matrix and an offset (:class:`EngineMap`), cached.
-   :func:`convert`: skysh radiance coefficients (..., N*N, 3) -> the engine's
    numbers (..., *EngineMap.shape).
-   :func:`snippet`: paste-ready code building the engine object.
-   :func:`sun_direction`: the unit vector towards the sun in an engine's frame; the sun's
    light in each engine's units (colour, intensity, code): :mod:`skysh.engines.sun`.

Every engine frame here keeps the physical sky: skysh's +X (sun azimuth 0)
stays the engine's +X, the zenith becomes the engine's up axis, and the third
axis follows from the engine's handedness (:data:`ENGINE_FRAMES`). To align the
sky with a level's north, add the angle to ``sun_azimuth``: the sky depends on
the azimuth only through a rotation about the vertical.

Irradiance naming: ``E`` is irradiance (lux for the luminance, cd/m^2 x sr),
``E/pi`` the irradiance over pi (the radiance a white Lambertian surface
reflects; cd/m^2). An engine "wants E/pi" when its shader returns E/pi and
multiplies it by the albedo.

Engines (``python -m pytest tests/engines/test_engines.py`` checks each against the
engine's own code; ``docs/engines.md`` has the table and the formulas)
--------------------------------------------------------------------------
``threejs``
    Feeds ``SphericalHarmonics3.fromArray`` / ``LightProbe`` (shape (9, 3),
    coefficient-major RGB). Radiance L without the CS phase: ``(-1)^|m|`` times
    the coefficients re-expressed in three's right-handed Y-up frame ``(x, z,
    -y)``. three's shader (``shGetIrradianceAt``) returns E and multiplies by
    albedo / pi. Sun azimuth phi: from +X towards -Z. Sources: mrdoob/three.js
    ``src/math/SphericalHarmonics3.js``, ``src/lights/LightProbe.js``,
    ``src/renderers/webgl/WebGLLights.js``,
    ``src/renderers/shaders/ShaderChunk/lights_pars_begin.glsl.js``.
``filament``
    Feeds ``IndirectLight::Builder::radiance(bands, sh)`` (shape (N*N, 3)).
    Radiance L with the CS phase in Filament's right-handed Y-up frame ``(x, z,
    -y)`` (what ``skysh coeffs --up y`` prints). Filament pre-scales by
    ``k_i A_l / pi`` itself; its shader returns ``max(E/pi, 0)``. Sun azimuth:
    from +X towards -Z. Sources: google/filament
    ``filament/src/details/IndirectLight.cpp``,
    ``filament/include/filament/IndirectLight.h``,
    ``shaders/src/surface_light_indirect.fs``, ``libs/ibl/src/CubemapSH.cpp``.
``filament-irradiance``
    Feeds ``IndirectLight::Builder::irradiance(bands, sh)`` and matches
    ``cmgen --sh-shader`` output (shape (N*N, 3)): E/pi pre-multiplied by the
    signed basis constants, ``k_i A_l / pi`` times the ``filament`` numbers
    (``sh[0]`` is the mean E/pi). Same frame and shader as ``filament``.
``unity``
    Feeds ``UnityEngine.Rendering.SphericalHarmonicsL2`` as
    ``RenderSettings.ambientProbe`` holds it, ``sh[rgb, i]`` (shape (3, 9)):
    E/pi pre-multiplied by ``k_i`` ("Unity format", what HDRP's
    ``UndoCosineRescaling`` undoes), in Unity's left-handed Y-up frame ``(x, z,
    y)``. Sun azimuth: from +X towards +Z. Sources: Unity-Technologies/Graphics
    ``com.unity.render-pipelines.high-definition/Runtime/Sky/AmbientProbeConvolution.compute``,
    ``.../Runtime/Lighting/SphericalHarmonics.cs`` (``UndoCosineRescaling``,
    ``PackCoefficients``), ``com.unity.render-pipelines.core/ShaderLibrary/SphericalHarmonics.hlsl``.
``unity-shader``
    The seven float4 ``unity_SHAr, unity_SHAg, unity_SHAb, unity_SHBr,
    unity_SHBg, unity_SHBb, unity_SHC`` (shape (7, 4)) that ``ShadeSH9``
    evaluates to E/pi (no clamp), packed from the ``unity`` numbers as
    ``PackCoefficients`` does; ``unity_SHC.w = 1`` is the map's one constant.
    Same frame as ``unity``. Sources: as ``unity``, plus ``CGIncludes/UnityCG.cginc``
    (``ShadeSH9``; Unity's built-in shaders, public mirror
    TwoTailsGames/Unity-Built-in-Shaders).
``babylon``
    Feeds ``SphericalHarmonics.FromArray`` -> ``SphericalPolynomial.FromHarmonics``
    (shape (9, 3), rows l00, l1_1, l10, l11, l2_2, l2_1, l20, l21, l22): the
    harmonics of E/pi, ``A_l / pi`` times the coefficients in Babylon's
    left-handed Y-up frame ``(x, z, y)`` (what Babylon's own
    ``ConvertCubeMapToSphericalPolynomial`` produces). Babylon's default PBR
    path evaluates them (``preScaledHarmonics``, ``harmonicsFunctions.fx``) to
    E/pi. Sun azimuth: from +X towards +Z (a right-handed scene,
    ``useRightHandedSystem``, flips z for the lookup: negate the sun's z).
    Sources: BabylonJS/Babylon.js ``packages/dev/core/src/Maths/sphericalPolynomial.ts``,
    ``.../Misc/HighDynamicRange/cubemapToSphericalPolynomial.ts``,
    ``.../Shaders/ShadersInclude/harmonicsFunctions.fx``,
    ``.../Materials/materialHelper.functions.ts``.
``unreal``
    Feeds ``FSHVectorRGB3`` for ``USkyLightComponent::SetIrradianceEnvironmentMap``
    (shape (3, 9), ``R.V[i]``, ``G.V[i]``, ``B.V[i]``): radiance L with the CS
    phase (despite the name) in Unreal's left-handed Z-up frame ``(x, -y, z)``.
    Unreal packs it with ``k_i A_l / pi`` and ``GetSkySHDiffuse`` returns
    ``max(E/pi, 0)``. Sun azimuth: from +X towards -Y (yaw ``-phi``). Epic's
    repository is access-restricted; read from public mirrors of
    ``Engine/Shaders/Private/SHCommon.ush``, ``.../ReflectionEnvironmentShared.ush``
    and ``Engine/Source/Runtime/Renderer/Private/SceneRendering.cpp``
    (``SetupSkyIrradianceEnvironmentMapConstantsFromSkyIrradiance``), e.g.
    chenyong2github/UnrealEngine.

References
----------
-   Ramamoorthi, R., Hanrahan, P. (2001). An Efficient Representation for
    Irradiance Environment Maps (clamped-cosine factors A_l).
-   Sloan, P.-P. (2008). Stupid Spherical Harmonics (SH) Tricks, appendix A10
    (the packed form Unity and Unreal evaluate).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh.checks import as_float_array, check_range, short_repr
from skysh.literals import double_literal, suffixed_literal
from skysh.sh import basis as sh

__all__ = ["ENGINES", "ENGINE_MAX_BANDS", "ENGINE_FRAMES", "EngineMap", "engine_map", "convert", "snippet",
    "SNIPPET_ZERO_BELOW", "sun_direction"]

ENGINES: tuple[str, ...] = (
    "threejs", "filament", "filament-irradiance", "unity", "unity-shader", "babylon", "unreal",
)
"""Names accepted by :func:`convert`, :func:`engine_map`, :func:`snippet` and :func:`sun_direction`."""

ENGINE_MAX_BANDS: dict[str, int] = {engine: 3 for engine in ENGINES}
"""Most bands each engine's API holds: three.js ``SphericalHarmonics3``, Filament's builder (clamps to 3),
Unity ``SphericalHarmonicsL2``, Babylon ``SphericalHarmonics`` and Unreal ``FSHVectorRGB3`` all hold l <= 2."""

_RH_Y_UP: NDArray[np.float64] = np.array(sh.Y_UP_MATRIX)
_LH_Y_UP: NDArray[np.float64] = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
_LH_Z_UP: NDArray[np.float64] = np.diag([1.0, -1.0, 1.0])

ENGINE_FRAMES: dict[str, NDArray[np.float64]] = {
    "threejs": _RH_Y_UP, "filament": _RH_Y_UP, "filament-irradiance": _RH_Y_UP,
    "unity": _LH_Y_UP, "unity-shader": _LH_Y_UP, "babylon": _LH_Y_UP, "unreal": _LH_Z_UP,
}
"""3x3 matrix M per engine: a skysh direction d (Z up) is ``M @ d`` in the engine's frame. Right-handed
Y up ``(x, z, -y)``; left-handed Y up ``(x, z, y)``; left-handed Z up ``(x, -y, z)`` (det -1 for the left-handed)."""
for _m in ENGINE_FRAMES.values():
    _m.flags.writeable = False

BASIS_CONSTANTS: NDArray[np.float64] = sh.BASIS_CONSTANTS
"""Signed k_i of ``Y_i = k_i p_i`` (:data:`skysh.sh.basis.BASIS_CONSTANTS`, read-only): the factors engines pre-scale by."""

_BABYLON_ROWS: tuple[str, ...] = ("l00", "l1_1", "l10", "l11", "l2_2", "l2_1", "l20", "l21", "l22")
_UNITY_ROWS: tuple[str, ...] = (
    "unity_SHAr", "unity_SHAg", "unity_SHAb", "unity_SHBr", "unity_SHBg", "unity_SHBb", "unity_SHC",
)

SNIPPET_ZERO_BELOW: float = 1e-12
""":func:`snippet` prints a number whose magnitude is below SNIPPET_ZERO_BELOW x the DC term (the largest
|row 0| coefficient over channels of its input) as 0, and -0.0 as 0: the rule of ``skysh coeffs --format
table`` (:data:`skysh.app.cli_output.TABLE_ZERO_BELOW`, the same 1e-12). Below it lies float64 rounding noise where
the exact value is zero (the sky's rotation by its azimuth leaves ~1e-17 of the DC in m < 0 terms at
azimuth 0); the fit's own error is many orders of magnitude larger. :func:`convert` keeps every bit."""

_FAST_LIMIT: float = 1e300
"""The fast path runs when ``sum x_j^2`` of the (9, 3) input is below this (False for NaN and inf):
every |x_j| < 1e150, so no product can overflow (the maps' row sums are < 4). Other inputs take the
checked path."""


@dataclass(frozen=True, eq=False)
class EngineMap:
    """
    The affine map of one (engine, bands): ``engine_flat = matrix @ skysh_flat + offset``.

    Attributes
    ----------
    engine, bands
        The engine name and the skysh band count N it takes (1 <= N <= the engine's limit).
    matrix
        (P, N*N*3), read-only; ``skysh_flat = coeffs.reshape(N*N*3)`` (coefficient-major, RGB).
    offset
        (P,), read-only; nonzero only for constants (``unity_SHC.w = 1``).
    shape
        The engine's own layout of the P numbers (row-major), e.g. (9, 3), (3, 9), (7, 4).
    labels
        One name per row of ``shape`` in the engine's vocabulary (its columns are R, G, B, or the
        coefficient index, or x, y, z, w).
    """

    engine: str
    bands: int
    matrix: NDArray[np.float64]
    offset: NDArray[np.float64]
    shape: tuple[int, ...]
    labels: tuple[str, ...]


@dataclass(frozen=True)
class _Spec:
    """How one engine reads SH: frame, per-coefficient scale kind, layout, row labels."""

    frame: str  # key of ENGINE_FRAMES (the engine itself)
    scale: str  # "radiance", "radiance-no-cs", "e-over-pi", "e-over-pi-prescaled"
    layout: str  # "rows", "rows9", "channels9", "unity-packed"
    labels: Callable[[int], tuple[str, ...]]


_SPECS: dict[str, _Spec] = {
    "threejs": _Spec("threejs", "radiance-no-cs", "rows9", lambda n: tuple(f"coefficients[{i}]" for i in range(9))),
    "filament": _Spec("filament", "radiance", "rows", lambda n: tuple(f"sh[{i}]" for i in range(n * n))),
    "filament-irradiance": _Spec(
        "filament-irradiance", "e-over-pi-prescaled", "rows", lambda n: tuple(f"sh[{i}]" for i in range(n * n))
    ),
    "unity": _Spec("unity", "e-over-pi-prescaled", "channels9", lambda n: ("sh[0, i]", "sh[1, i]", "sh[2, i]")),
    "unity-shader": _Spec("unity-shader", "e-over-pi-prescaled", "unity-packed", lambda n: _UNITY_ROWS),
    "babylon": _Spec("babylon", "e-over-pi", "rows9", lambda n: _BABYLON_ROWS),
    "unreal": _Spec("unreal", "radiance", "channels9", lambda n: ("R.V", "G.V", "B.V")),
}


# --------------------------------------------------------------------------- #
# Building the maps
# --------------------------------------------------------------------------- #
def _check_engine(engine: object) -> str:
    if not isinstance(engine, str) or engine not in _SPECS:
        raise ValueError(f"engine must be one of {', '.join(map(repr, ENGINES))}, got {short_repr(engine)}")
    return engine


def _check_engine_bands(engine: str, bands: object, name: str = "bands") -> int:
    limit = ENGINE_MAX_BANDS[engine]
    if isinstance(bands, bool) or not isinstance(bands, (int, np.integer)) or not 1 <= int(bands) <= limit:
        raise ValueError(
            f"{name} must be an integer in [1, {limit}] for engine {engine!r} (it holds at most {limit} bands, "
            f"{limit * limit} coefficients), got {short_repr(bands)}"
        )
    return int(bands)


def _frame_change(frame: NDArray[np.float64], bands: int) -> NDArray[np.float64]:
    """(K, K) coefficients of ``f(M^T d)`` from those of f: ``D_ij = integral Y_i(d) Y_j(M^T d) dd``.

    M may be a reflection (det -1). The integrand is a product of two functions of bands <= N, so
    the product Gauss rule with N nodes in z is exact (to rounding); the true entries are 0, +-1,
    +-1/2 or +-sqrt(3)/2, so values below 1e-12 are set to exact zeros.
    """
    dirs, weights = sh.quadrature_rule(bands)
    y = sh.basis(dirs, bands)
    y_moved = sh.basis(dirs @ frame, bands)  # rows: (M^T d)^T
    d = (y * weights[:, None]).T @ y_moved
    d[np.abs(d) < 1e-12] = 0.0
    return d


def _scale(kind: str, bands: int) -> NDArray[np.float64]:
    """Per-coefficient factor applied after the frame change."""
    k = bands * bands
    l_of = np.array([sh.lm(i)[0] for i in range(k)])
    m_of = np.array([sh.lm(i)[1] for i in range(k)])
    if kind == "radiance":
        return np.ones(k)
    if kind == "radiance-no-cs":
        return (-1.0) ** np.abs(m_of)  # three.js's basis is |k_i| p_i: drop the CS sign (-1)^|m|
    lobe = sh.cosine_lobe(bands)[l_of] / math.pi  # A_l / pi
    if kind == "e-over-pi":
        return lobe
    return lobe * BASIS_CONSTANTS[:k]  # "e-over-pi-prescaled": k_i A_l / pi


def _layout(layout: str, bands: int) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[int, ...]]:
    """(P, 3K) placement of the per-coefficient values u (coefficient-major RGB), offset (P,), shape."""
    k = bands * bands

    def col(i: int, c: int) -> int:  # column of u[i, channel c]
        return 3 * i + c

    if layout in ("rows", "rows9"):
        rows = k if layout == "rows" else 9
        place = np.zeros((rows * 3, 3 * k))
        for i in range(k):
            for c in range(3):
                place[3 * i + c, col(i, c)] = 1.0
        return place, np.zeros(rows * 3), (rows, 3)
    if layout == "channels9":
        place = np.zeros((27, 3 * k))
        for i in range(k):
            for c in range(3):
                place[9 * c + i, col(i, c)] = 1.0
        return place, np.zeros(27), (3, 9)
    # "unity-packed": PackCoefficients / SetSHEMapConstants (Sloan 2008, A10)
    place = np.zeros((28, 3 * k))
    terms = {  # (row, component) -> [(coefficient index, factor)], per channel c for rows 0..5
        0: [(3, 1.0)], 1: [(1, 1.0)], 2: [(2, 1.0)], 3: [(0, 1.0), (6, -1.0)],  # SHA = (u3, u1, u2, u0 - u6)
    }
    terms_b = {0: [(4, 1.0)], 1: [(5, 1.0)], 2: [(6, 3.0)], 3: [(7, 1.0)]}  # SHB = (u4, u5, 3 u6, u7)
    for c in range(3):
        for block, table in ((c, terms), (3 + c, terms_b)):
            for comp, items in table.items():
                for i, factor in items:
                    if i < k:
                        place[4 * block + comp, col(i, c)] = factor
        if 8 < k:
            place[24 + c, col(8, c)] = 1.0  # SHC = (u8_r, u8_g, u8_b, 1)
    offset = np.zeros(28)
    offset[27] = 1.0
    return place, offset, (7, 4)


@cache
def _engine_map(engine: str, bands: int) -> EngineMap:
    spec = _SPECS[engine]
    per_coefficient = _scale(spec.scale, bands)[:, None] * _frame_change(ENGINE_FRAMES[spec.frame], bands)
    place, offset, shape = _layout(spec.layout, bands)
    matrix = place @ np.kron(per_coefficient, np.eye(3))  # u = kron(S D, I3) @ flat
    matrix[np.abs(matrix) < 1e-15] = 0.0
    for array in (matrix, offset):
        array.flags.writeable = False
    return EngineMap(engine, bands, matrix, offset, shape, spec.labels(bands))


def engine_map(engine: str, bands: int = 3) -> EngineMap:
    """
    The fixed affine map from skysh radiance coefficients to an engine's numbers.

    Parameters
    ----------
    engine
        One of :data:`ENGINES`.
    bands
        skysh band count N, in [1, ``ENGINE_MAX_BANDS[engine]``] (3 for every engine). Engines
        with a fixed layout (three.js, Unity, Babylon, Unreal) get zeros for the missing bands.

    Returns
    -------
    EngineMap
        Cached: the same object (read-only arrays) for the same arguments.

    Raises
    ------
    ValueError
        Unknown engine (the message lists the valid names); bands outside the engine's range.
    """
    engine = _check_engine(engine)
    return _engine_map(engine, _check_engine_bands(engine, bands))


# --------------------------------------------------------------------------- #
# Converting
# --------------------------------------------------------------------------- #
@dataclass(frozen=True)
class _Fast:
    """One engine's 3-band single-input path: ``kind`` 0: ``a @ x`` (9, 3); 1: ``x.T @ a`` (3, 9);
    2: ``x.ravel() @ a`` with ``unity_SHC.w = 1``, reshaped (7, 4). ``a`` is read-only."""

    kind: int
    a: NDArray[np.float64]


def _fast(engine: str) -> _Fast:
    emap = _engine_map(engine, 3)
    layout = _SPECS[engine].layout
    if layout == "unity-packed":
        transposed = np.ascontiguousarray(emap.matrix.T)  # x @ M^T: measured faster than M @ x here
        transposed.flags.writeable = False
        return _Fast(2, transposed)
    if layout == "channels9":  # matrix[9 c + i, 3 j + c] = A[i, j]
        a = np.ascontiguousarray(emap.matrix[0:9, 0::3].T)
        kind = 1
    else:  # rows: matrix[3 i + c, 3 j + c] = A[i, j]
        a = np.ascontiguousarray(emap.matrix[0::3, 0::3])
        kind = 0
    expected = np.kron(a.T if kind else a, np.eye(3))
    if kind:
        expected = expected[np.array([3 * i + c for c in range(3) for i in range(9)])]
    assert np.array_equal(expected, emap.matrix)  # the map is one 9 x 9 matrix per channel
    a.flags.writeable = False
    return _Fast(kind, a)


_FAST: dict[str, _Fast] = {engine: _fast(engine) for engine in ENGINES}
_SHAPE_9_3: tuple[int, int] = (9, 3)
_FLOAT64: np.dtype = np.dtype(np.float64)
"""numpy's float64 dtype singleton (compared with ``is``; a byte-swapped float64 takes the checked path)."""


def convert(coeffs: ArrayLike, engine: str) -> NDArray[np.float64]:
    """
    Convert skysh radiance SH into the numbers an engine's API takes.

    Parameters
    ----------
    coeffs
        skysh **radiance** coefficients, shape (..., N*N, 3): Z up, real SH with the Condon-Shortley
        phase, cd/m^2, linear RGB (:meth:`skysh.SkySH.coefficients` with ``irradiance=False``; any
        Gibbs filter or deringing is applied before; for diffuse light at 3 bands pass
        ``irradiance_table=True``: the certified table's radiance-equivalent). N in [1, ``ENGINE_MAX_BANDS[engine]``].
    engine
        One of :data:`ENGINES` (see the module docstring for what each one feeds).

    Returns
    -------
    ndarray
        (..., *engine_map(engine, N).shape): ``matrix @ flat + offset`` for every leading index.

    Raises
    ------
    ValueError
        Unknown engine (the valid names are listed); ``coeffs`` not (..., N*N, 3), with more bands
        than the engine holds (engine and limit named), not real, or not finite.

    Notes
    -----
    A single (9, 3) float64 array takes a fast path: a screen ``sum x^2 < 1e300`` (:data:`_FAST_LIMIT`)
    and one 9 x 9 matrix product applied to all channels (one (27, 28) product for ``unity-shader``);
    ``python benchmarks/bench_engines.py`` prints its cost next to a runtime call.
    """
    fast = _FAST.get(engine) if type(engine) is str else None
    if (fast is not None and type(coeffs) is np.ndarray and coeffs.shape == _SHAPE_9_3
            and coeffs.dtype is _FLOAT64 and np.vdot(coeffs, coeffs) < _FAST_LIMIT):
        if fast.kind == 0:
            return np.dot(fast.a, coeffs)
        if fast.kind == 1:
            return np.dot(coeffs.T, fast.a)
        out = np.dot(coeffs.ravel(), fast.a)
        out[27] = 1.0  # unity_SHC.w, the map's one constant (its matrix row is zero)
        out.shape = (7, 4)  # a fresh contiguous array: reshaped in place
        return out
    return _convert_checked(coeffs, engine)


def _convert_checked(coeffs: ArrayLike, engine: str) -> NDArray[np.float64]:
    """The general path: any batch shape and band count, every check."""
    engine = _check_engine(engine)
    c = as_float_array(coeffs, "coeffs")
    if c.ndim < 2 or c.shape[-1] != 3:
        raise ValueError(f"coeffs must have shape (..., N*N, 3) (RGB radiance coefficients), got {c.shape}")
    k = c.shape[-2]
    bands = math.isqrt(k)
    if k == 0 or bands * bands != k:
        raise ValueError(f"coeffs must have N*N rows (1, 4, 9, ...) before the RGB axis, got shape {c.shape}")
    limit = ENGINE_MAX_BANDS[engine]
    if bands > limit:
        raise ValueError(
            f"coeffs has {bands} bands ({k} coefficients) but engine {engine!r} holds at most {limit} bands "
            f"({limit * limit} coefficients): pass coeffs[..., :{limit * limit}, :] or bands={limit}"
        )
    emap = _engine_map(engine, bands)
    flat = c.reshape(-1, k * 3)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is reported below, as a ValueError
        out = flat @ emap.matrix.T + emap.offset
    if not np.all(np.isfinite(out)):
        raise ValueError(f"coeffs are too large: the {engine} numbers overflow (|coeffs| must stay below ~1e307)")
    return out.reshape(c.shape[:-2] + emap.shape)


# --------------------------------------------------------------------------- #
# Snippets
# --------------------------------------------------------------------------- #
def _without_noise(values: NDArray[np.float64], coeffs: NDArray[np.float64], engine: str) -> NDArray[np.float64]:
    """``values`` (:func:`convert` of ``coeffs``) with every |value| below :data:`SNIPPET_ZERO_BELOW` x
    max |coeffs[0]| (the DC term) set to 0, except the map's constants (``unity_SHC.w = 1``), and -0.0
    to 0 (adding +0.0 clears the sign of a zero only)."""
    zero = SNIPPET_ZERO_BELOW * float(np.max(np.abs(coeffs[0])))
    constant = _engine_map(engine, math.isqrt(coeffs.shape[0])).offset.reshape(values.shape) != 0.0
    return np.where((np.abs(values) < zero) & ~constant, 0.0, values) + 0.0


_FRAME_NOTES: dict[str, str] = {
    "threejs": "three.js's right-handed Y-up frame: +X = skysh +X (sun azimuth 0), +Y = zenith, -Z = skysh +Y",
    "filament": "Filament's right-handed Y-up frame: +X = skysh +X (sun azimuth 0), +Y = zenith, -Z = skysh +Y",
    "unity": "Unity's left-handed Y-up frame: +X = skysh +X (sun azimuth 0), +Y = zenith, +Z = skysh +Y",
    "babylon": "Babylon's left-handed Y-up frame: +X = skysh +X (sun azimuth 0), +Y = zenith, +Z = skysh +Y",
    "unreal": "Unreal's left-handed Z-up frame: +X = skysh +X (sun azimuth 0), +Y = skysh -Y, +Z = zenith",
}
"""Each engine's frame in skysh's words, for the snippets' comments (variants such as ``unity-shader`` share it)."""


def _snippet_threejs(v: NDArray, bands: int) -> str:
    rows = ",\n".join("  " + ", ".join(double_literal(x) for x in row) for row in v)
    return (
        f"// skysh sky lighting ({bands} bands) for three.js: SphericalHarmonics3 / LightProbe.\n"
        f"// Radiance SH (cd/m^2) without the Condon-Shortley phase, in {_FRAME_NOTES['threejs']}.\n"
        "// three's shader turns it into irradiance E (lux) and multiplies by albedo / pi.\n"
        "import { LightProbe, SphericalHarmonics3 } from 'three';\n\n"
        f"const skySH = new SphericalHarmonics3().fromArray([\n{rows}\n]);\n"
        "const skyProbe = new LightProbe(skySH, 1.0); // then scene.add(skyProbe);\n"
    )


def _snippet_babylon(v: NDArray, bands: int) -> str:
    rows = ",\n".join(f"  [{', '.join(double_literal(x) for x in row)}] /* {name} */" for name, row in zip(_BABYLON_ROWS, v))
    return (
        f"// skysh sky lighting ({bands} bands) for Babylon.js: SphericalHarmonics -> SphericalPolynomial.\n"
        f"// Harmonics of E/pi (A_l / pi times the radiance SH, cd/m^2), in {_FRAME_NOTES['babylon']}.\n"
        "// Keep the default PBR path (brdf.useSphericalHarmonics = true): it evaluates these harmonics.\n"
        "import { SphericalHarmonics, SphericalPolynomial } from '@babylonjs/core';\n\n"
        f"const skyHarmonics = SphericalHarmonics.FromArray([\n{rows}\n]);\n"
        "const skyPolynomial = SphericalPolynomial.FromHarmonics(skyHarmonics);\n"
        "// environmentTexture.sphericalPolynomial = skyPolynomial;\n"
    )


def _snippet_filament(v: NDArray, bands: int, irradiance: bool) -> str:
    name = "kSkyIrradianceSH" if irradiance else "kSkyRadianceSH"
    rows = ",\n".join(f"    {{{', '.join(suffixed_literal(x) for x in row)}}}" for row in v)
    what = (
        "E/pi pre-multiplied by the basis constants (k_i A_l / pi, cd/m^2), as cmgen --sh-shader writes it"
        if irradiance else "radiance SH (cd/m^2) with the Condon-Shortley phase; Filament pre-scales it"
    )
    call = "irradiance" if irradiance else "radiance"
    return (
        f"// skysh sky lighting ({bands} bands) for Filament: IndirectLight::Builder::{call}.\n"
        f"// {what},\n// in {_FRAME_NOTES['filament']}.\n"
        "#include <filament/IndirectLight.h>\n#include <math/vec3.h>\n\n"
        f"static const filament::math::float3 {name}[{v.shape[0]}] = {{\n{rows}\n}};\n\n"
        "// engine: your filament::Engine*. The numbers are absolute (cd/m^2): intensity 1, not the default 30000.\n"
        "filament::IndirectLight* skyLight = filament::IndirectLight::Builder()\n"
        f"        .{call}({bands}, {name})\n        .intensity(1.0f)\n        .build(*engine);\n"
    )


def _snippet_unity(v: NDArray, bands: int) -> str:
    lines = [f"skyProbe[{c}, {i}] = {suffixed_literal(v[c, i])};" for c in range(3) for i in range(9)]
    return (
        f"// skysh sky lighting ({bands} bands) for Unity: RenderSettings.ambientProbe (SphericalHarmonicsL2).\n"
        "// \"Unity format\": E/pi pre-multiplied by the basis constants (k_i A_l / pi, cd/m^2), sh[rgb, i],\n"
        f"// in {_FRAME_NOTES['unity']}.\n"
        "var skyProbe = new UnityEngine.Rendering.SphericalHarmonicsL2();\n"
        + "\n".join(lines)
        + "\nUnityEngine.RenderSettings.ambientProbe = skyProbe;\n"
    )


def _snippet_unity_shader(v: NDArray, bands: int) -> str:
    lines = [
        f'skyBlock.SetVector("{name}", new Vector4({", ".join(suffixed_literal(x) for x in row)}));'
        for name, row in zip(_UNITY_ROWS, v)
    ]
    return (
        f"// skysh sky lighting ({bands} bands) for Unity shaders: unity_SHAr..unity_SHC, which ShadeSH9 evaluates\n"
        f"// to E/pi (cd/m^2), in {_FRAME_NOTES['unity']}.\n"
        "var skyBlock = new MaterialPropertyBlock();\n"
        + "\n".join(lines)
        + "\n// renderer: your Renderer. CustomProvided makes it use these instead of the light probes.\n"
        "renderer.lightProbeUsage = UnityEngine.Rendering.LightProbeUsage.CustomProvided;\n"
        "renderer.SetPropertyBlock(skyBlock);\n"
    )


def _snippet_unreal(v: NDArray, bands: int) -> str:
    lines = [f"SkySH.{ch}.V[{i}] = {suffixed_literal(v[c, i])};" for c, ch in enumerate("RGB") for i in range(9)]
    return (
        f"// skysh sky lighting ({bands} bands) for Unreal Engine: FSHVectorRGB3 of the sky light.\n"
        f"// Radiance SH (cd/m^2) with the Condon-Shortley phase, in {_FRAME_NOTES['unreal']}.\n"
        "// Unreal convolves it (GetSkySHDiffuse returns max(E/pi, 0)) and scales it by the light's color.\n"
        "FSHVectorRGB3 SkySH;\n"
        + "\n".join(lines)
        + "\n// SkyLightComponent: your USkyLightComponent*.\n"
        "SkyLightComponent->SetIrradianceEnvironmentMap(SkySH);\nSkyLightComponent->MarkRenderStateDirty();\n"
    )


def snippet(coeffs: ArrayLike, engine: str) -> str:
    """
    Paste-ready code that builds the engine's object from :func:`convert`'s numbers.

    JavaScript for ``threejs`` and ``babylon``, C# for ``unity`` and ``unity-shader``, C++ for
    ``filament``, ``filament-irradiance`` and ``unreal``. Numbers are the shortest text that reads
    back as the same double (JavaScript), or that text with the ``f`` suffix (C++, C#: the
    compiler rounds it to float once); a number below :data:`SNIPPET_ZERO_BELOW` (1e-12) times
    the input's DC term (max over channels of ``|coeffs[0]|``) is rounding noise and printed as
    0, as is -0.0. Comments name the quantity, the frame and the units.

    Parameters
    ----------
    coeffs
        One set of skysh radiance coefficients, shape (N*N, 3) (see :func:`convert`).
    engine
        One of :data:`ENGINES`.

    Raises
    ------
    ValueError
        As :func:`convert`, and for a batch of sets.
    """
    engine = _check_engine(engine)
    c = as_float_array(coeffs, "coeffs")
    if c.ndim != 2:
        raise ValueError(f"coeffs must be one set of shape (N*N, 3) for a snippet, got shape {c.shape}")
    values = _without_noise(convert(c, engine), c, engine)  # convert()'s numbers to the last bit, noise as exact zeros
    bands = math.isqrt(c.shape[0])
    if engine == "threejs":
        return _snippet_threejs(values, bands)
    if engine == "babylon":
        return _snippet_babylon(values, bands)
    if engine in ("filament", "filament-irradiance"):
        return _snippet_filament(values, bands, engine == "filament-irradiance")
    if engine == "unity":
        return _snippet_unity(values, bands)
    if engine == "unity-shader":
        return _snippet_unity_shader(values, bands)
    return _snippet_unreal(values, bands)


# --------------------------------------------------------------------------- #
# The sun
# --------------------------------------------------------------------------- #
def sun_direction(sun_zenith: ArrayLike, sun_azimuth: ArrayLike, engine: str) -> NDArray[np.float64]:
    """
    Unit vector towards the sun in an engine's frame, matching :func:`convert`'s frame.

    Parameters
    ----------
    sun_zenith
        Radians, [0, pi/2] (docs/conventions.md).
    sun_azimuth
        Radians, any finite value; skysh's azimuth (from +X towards +Y in the Z-up frame).
    engine
        One of :data:`ENGINES`.

    Returns
    -------
    ndarray
        (3,), or (..., 3) for array arguments (broadcast together): ``ENGINE_FRAMES[engine] @ (sin
        zenith cos azimuth, sin zenith sin azimuth, cos zenith)``. A directional light shines along
        the opposite vector: three.js ``light.position`` = this (target at the origin); Filament
        ``LightManager::Builder::direction`` = minus this; Unity ``Quaternion.LookRotation(-this)``;
        Babylon ``new DirectionalLight(name, -this)``; Unreal the light's forward (X) = minus this.
    """
    engine = _check_engine(engine)
    zenith = check_range(sun_zenith, "sun_zenith", 0.0, math.pi / 2.0, unit="rad")
    azimuth = check_range(sun_azimuth, "sun_azimuth", -np.inf, np.inf, unit="rad")
    azimuth = np.fmod(azimuth, 2.0 * math.pi)
    s = np.sin(zenith)
    d = np.stack(np.broadcast_arrays(s * np.cos(azimuth), s * np.sin(azimuth), np.cos(zenith)), axis=-1)
    return d @ ENGINE_FRAMES[engine].T
