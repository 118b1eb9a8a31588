"""
Tests of the sun and the ground in the runtime (skysh.lighting.lights, SkySH.sun_light,
``coefficients(..., sun=True, ground_albedo=...)``)
==============================================================================

Against routes independent of the runtime's fused arithmetic:

-   the ground's SH against a Gauss-Legendre quadrature of the uniform lower
    hemisphere written here (not ground.py's closed form), Gibbs filter by
    sin(pi l / N) / (pi l / N) typed here;
-   energy: with albedo 1 and the sun off, the ground's exitance pi L_g equals the
    true horizontal irradiance of the sky, from the converged projection
    (preetham.sky_sh's c_10) and from a direct quadrature of the model;
-   the sun's SH against skysh.model.solar.sun_sh (sh.basis of the direction) with the
    sun's colour from skysh.model.solar (the spectral model);
-   sun_light against skysh.model.solar.illuminance_rgb and sun_direction;
-   the order of the parts: deringing sees the sky alone (a recording stand-in),
    the ground is added after the colourspace conversion;
-   non-negativity of the irradiance with the sun and deringing over the domain.

Every tolerance is a named constant with the reason for its size. No test asserts wall time.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import EPS, L_OF, ROOT
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh.lighting import lights
from skysh.model import preetham, solar
from skysh.runtime import SkySH
from skysh.sh import basis as sh
from skysh.table import coefficient_file, fit

HALF_PI: float = math.pi / 2.0

PATH_RTOL: float = 1e-12
"""Fused scalar path vs parts, batch, or an independent composition (sky + solar.sun_sh + ground),
relative to the largest |coefficient|: the routes differ only in rounding (T_k as cos(k acos x) or
by recurrence, Y_lm as a trigonometric polynomial or by sh.basis, the weight matrix's zeros
cos(pi/2) = 6e-17): at most a few hundred eps of the sums; measured worst 8e-15."""

QUADRATURE_RTOL: float = 1e-12
"""Runtime ground SH vs the Gauss-Legendre projection of the uniform lower hemisphere: the
integrand is a polynomial in z (degree < 64) times cos/sin(m phi), so 64 nodes in z on [-1, 0] and
128 in phi are exact up to rounding (sums of ~8000 terms of size <= 1: ~1e-14)."""

SUN_RTOL: float = 1e-4
"""Issue 15's goal for the sun's fitted light: held-out error <= 1e-4 relative (RGB against
max(|RGB_c|, Y), as tests/lighting/test_sunlight.py: a channel outside the gamut crosses zero near the horizon)."""

TRIG_ATOL: float = 1e-14
"""sun_trig_matrix @ (cos k ts, sin k ts) vs sh.basis at the same direction: an exact discrete
Fourier fit of a trigonometric polynomial of degree < N on 4 N nodes (least squares, condition 1),
values of size <= 1.3: rounding of a few eps."""

FIT_SAFETY: float = 2.0
"""As tests/runtime/test_runtime.py: the recorded e_mean_worst is the worst of 260 held-out points; a
factor 2 leaves room for points outside that sample without hiding a broken E_h (a Gibbs-filtered
c_10 would be off by 1 - sinc(pi/3) = 17 % at N = 3, a missing sqrt(4 pi / 3) by 100 %)."""

QUADRATURE_AGREEMENT: float = 1e-6
"""E_h from sky_sh's sun-adapted rule vs a plain product Gauss rule in cos(theta) (400 x 800 nodes,
written here): the sky's kink at the sun limits the plain rule to O(n^-3), ~1e-7 at 400 nodes;
both are far closer than the fit's error bound (about 1e-4 of the sky's minimum)."""

DIRECTION_ATOL: float = 1e-14
"""sun_light's direction (azimuth reduced mod 2 pi first) vs solar.sun_direction (cos and sin of
the raw azimuth): the reduction is off by k x (2 pi - fl(2 pi)) = k x 2.4e-16 for k turns; k <= 7
for the |phi| <= 40 tested, so <= 2e-15, plus an ulp of each trigonometric function."""

NONNEGATIVE_ATOL: float = 1e-12
"""Irradiance with sun and deringing: >= -NONNEGATIVE_ATOL x its largest value over the normals
(rounding of the sum over N^2 <= 49 coefficients); the deringed sky, the windowed sun and the ground
are each >= 0 by construction."""

UNIT_ATOL: float = 4 * EPS
"""A direction from sines and cosines of the same angles by two routes (its norm, its z = cos(ts),
batch vs scalar): a few half-ulp roundings of values <= 1."""

AZIMUTH_ATOL: float = 1e-12
"""atan2 of the direction vs the requested azimuth (mod 2 pi): the azimuth reduction errs by
<= 2e-15 (DIRECTION_ATOL) and atan2 of components of size sin(ts) >= 0.3 adds ~eps / 0.3."""

CONTROL_FACTOR: float = 100.0
"""A negative control must miss by this many times the bound it is checked against: far outside the
bound, so the check could not pass by chance."""


def _close(got: np.ndarray, expected: np.ndarray, rtol: float) -> None:
    np.testing.assert_allclose(got, expected, rtol=0, atol=rtol * float(np.max(np.abs(expected))))


def _lower_hemisphere_sh(bands: int) -> np.ndarray:
    """(N*N,) projection of the indicator of z < 0: Gauss-Legendre in z on [-1, 0] x uniform phi."""
    z, wz = np.polynomial.legendre.leggauss(64)
    z, wz = 0.5 * (z - 1.0), 0.5 * wz  # [-1, 1] -> [-1, 0]
    phi = (np.arange(128) + 0.5) * (2.0 * math.pi / 128)
    s = np.sqrt(1.0 - z * z)
    dirs = np.stack(np.broadcast_arrays(s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), z[:, None]), axis=-1)
    weights = wz[:, None] * np.full(phi.shape, 2.0 * math.pi / 128)
    return np.einsum("ij,ijk->k", weights, sh.basis(dirs, bands))


def _sinc_filter(bands: int) -> np.ndarray:
    return np.array([1.0] + [math.sin(math.pi * l / bands) / (math.pi * l / bands) for l in range(1, bands)])


def _horizontal_irradiance(sky: SkySH, ts: float, t: float) -> np.ndarray:
    """E_h of the fitted sky: sqrt(4 pi / 3) x its unfiltered c_10 (2 bands, no window)."""
    return math.sqrt(4.0 * math.pi / 3.0) * sky.coefficients(ts, t, 0.3, bands=2, gibbs=False)[2]


def _composed(sky: SkySH, ts: float, t: float, phi: float, bands: int, gibbs: bool, dering: bool, albedo,
              colourspace: str | None = None) -> np.ndarray:
    """Radiance SH of sky + sun + ground built here from public pieces (sky, solar.sun_sh, ground, colour)."""
    sky_part = sky.coefficients(ts, t, phi, bands=bands, gibbs=gibbs, dering=dering)
    rgb = sky._sun.rgb(ts, t)  # the fitted sun (checked against the spectral model in TestSunLight)
    total = sky_part + solar.sun_sh(solar.sun_direction(ts, phi), np.maximum(rgb, 0.0), bands)
    e_h = _horizontal_irradiance(sky, ts, t) + rgb * math.cos(ts)
    if colourspace is not None:
        matrix = sky._colour_matrix(colourspace)
        total, e_h = total @ matrix.T, e_h @ matrix.T
    radiance = np.asarray(albedo, dtype=float) * e_h / math.pi
    ground = np.outer(_lower_hemisphere_sh(bands), radiance)
    if gibbs:
        ground *= _sinc_filter(bands)[L_OF[: bands * bands]][:, None]
    return total + ground


FUSED_ARGUMENTS = {"ts": st.floats(0.0, HALF_PI), "t": st.floats(2.5, 6.0), "phi": st.floats(-10.0, 10.0),
                   "albedo": st.floats(0.0, 1.0), "bands": st.integers(1, 7), "sun": st.booleans()}
FUSED_EXAMPLES: dict[str, int] = {"core": 15, "slow": 40}
"""Hypothesis examples of the fused-equals-composition property in the core run (``-m "not slow"``) and in its
``slow`` twin; the fixed grid of test_fused_equals_the_composition (every band count 1, 2, 3, 5, 7, both filters,
the domain's corners) stays in the core."""

ENERGY_SKIES: list[tuple[float, float]] = [(0.0, 2.5), (0.6, 3.4), (1.2, 6.0), (HALF_PI, 2.5), (HALF_PI, 6.0)]
"""(sun zenith, turbidity) of the energy tests: the zenith, mid-sky, the horizon, both turbidity ends."""


# --------------------------------------------------------------------------- #
class TestGround:
    @pytest.mark.parametrize("bands", [1, 2, 3, 4, 7])
    @pytest.mark.parametrize("gibbs", [False, True])
    def test_ground_sh_is_the_lower_hemisphere(self, sky: SkySH, bands: int, gibbs: bool) -> None:
        ts, t, phi, albedo = 0.9, 3.7, 1.3, (0.2, 0.5, 0.9)
        ground = (sky.coefficients(ts, t, phi, bands=bands, gibbs=gibbs, ground_albedo=albedo)
                  - sky.coefficients(ts, t, phi, bands=bands, gibbs=gibbs))
        radiance = np.array(albedo) * _horizontal_irradiance(sky, ts, t) / math.pi
        expected = np.outer(_lower_hemisphere_sh(bands), radiance)
        if gibbs:
            expected *= _sinc_filter(bands)[L_OF[: bands * bands]][:, None]
        _close(ground, expected, QUADRATURE_RTOL)

    def test_ground_is_zonal_and_independent_of_the_azimuth(self, sky: SkySH) -> None:
        a = sky.coefficients(0.5, 3.0, 0.0, bands=5, ground_albedo=0.7) - sky.coefficients(0.5, 3.0, 0.0, bands=5)
        b = sky.coefficients(0.5, 3.0, 2.1, bands=5, ground_albedo=0.7) - sky.coefficients(0.5, 3.0, 2.1, bands=5)
        _close(a, b, QUADRATURE_RTOL)
        zonal = np.array([m == 0 for l in range(5) for m in range(-l, l + 1)])
        assert np.all(np.abs(a[~zonal]) <= QUADRATURE_RTOL * np.abs(a).max())

    @pytest.mark.slow  # sky_sh's c_10 against a plain product rule: also tests/model/test_preetham.py's test_converged
    @pytest.mark.parametrize("ts, t", ENERGY_SKIES)
    def test_the_true_horizontal_irradiance_by_direct_quadrature(self, ts: float, t: float) -> None:
        """E_h = sqrt(4 pi / 3) c_10 of preetham.sky_sh (the truth of the energy test) against a direct
        quadrature of the model: E_h = int L cos(theta) over the upper hemisphere (a plain product rule)."""
        truth = math.sqrt(4.0 * math.pi / 3.0) * preetham.sky_sh(ts, t, 2)[2]
        mu, wmu = np.polynomial.legendre.leggauss(400)
        mu, wmu = 0.5 * (mu + 1.0), 0.5 * wmu
        phi = (np.arange(800) + 0.5) * (2.0 * math.pi / 800)
        s = np.sqrt(1.0 - mu * mu)
        dirs = np.stack(np.broadcast_arrays(s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), mu[:, None]), axis=-1)
        radiance = preetham.radiance(dirs, ts, 0.0, t)
        direct = np.einsum("i,ijc->c", wmu * mu, radiance) * (2.0 * math.pi / 800)
        np.testing.assert_allclose(direct, truth, rtol=QUADRATURE_AGREEMENT)

    @pytest.mark.parametrize("ts, t", ENERGY_SKIES)
    def test_energy_albedo_one_equals_the_true_horizontal_irradiance(self, sky: SkySH, ts: float, t: float) -> None:
        ground = sky.coefficients(ts, t, 0.4, bands=3, ground_albedo=1.0) - sky.coefficients(ts, t, 0.4, bands=3)
        exitance = math.pi * ground[0] / math.sqrt(math.pi)  # c_00 = sqrt(pi) L_g (the quadrature above)
        truth = math.sqrt(4.0 * math.pi / 3.0) * preetham.sky_sh(ts, t, 2)[2]  # see the direct quadrature above
        lmin = fit.error_denominator(preetham.sky_minimum(ts, t))
        bound = math.sqrt(4.0 * math.pi / 3.0) * FIT_SAFETY * sky.metadata["errors"]["by_bands"]["2"]["e_mean_worst"]
        assert np.all(np.abs(exitance - truth) <= bound * lmin), (exitance / truth - 1.0, bound * lmin / truth)
        # negative control: the Gibbs-filtered c_10 (the ground must not use it) is far off
        filtered = math.sqrt(4.0 * math.pi / 3.0) * sky.coefficients(ts, t, 0.4, bands=3, gibbs=True)[2]
        assert np.all(np.abs(filtered - truth) > CONTROL_FACTOR * bound * lmin)

    def test_energy_with_the_sun(self, sky: SkySH) -> None:
        ts, t = 0.8, 3.0
        ground = (sky.coefficients(ts, t, 0.0, bands=2, gibbs=False, sun=True, ground_albedo=1.0)
                  - sky.coefficients(ts, t, 0.0, bands=2, gibbs=False, sun=True))
        exitance = math.sqrt(math.pi) * ground[0]
        sky_part = math.sqrt(4.0 * math.pi / 3.0) * preetham.sky_sh(ts, t, 2)[2]
        sun_part = solar.illuminance_rgb(ts, t) * math.cos(ts)
        lmin = fit.error_denominator(preetham.sky_minimum(ts, t))
        bound = math.sqrt(4.0 * math.pi / 3.0) * FIT_SAFETY * sky.metadata["errors"]["by_bands"]["2"]["e_mean_worst"]
        assert np.all(np.abs(exitance - sky_part - sun_part) <= bound * lmin + SUN_RTOL * np.abs(sun_part).max())

    def test_one_band_gets_c10_from_the_table(self, sky: SkySH) -> None:
        ground = sky.coefficients(0.7, 4.0, 0.0, bands=1, ground_albedo=0.5) - sky.coefficients(0.7, 4.0, 0.0, bands=1)
        radiance = 0.5 * _horizontal_irradiance(sky, 0.7, 4.0) / math.pi
        _close(ground[0], math.sqrt(math.pi) * radiance, QUADRATURE_RTOL)

    def test_ground_irradiance_is_exact_without_the_filter(self, sky: SkySH) -> None:
        """Irradiance of the ground (N >= 2, no Gibbs filter) = pi L_g (1 - n_z) / 2, the view factor."""
        normals = sh.quadrature_rule(16)[0]
        ground = (sky.irradiance_at(normals, 0.7, 4.0, bands=3, dering=False, ground_albedo=0.5)
                  - sky.irradiance_at(normals, 0.7, 4.0, bands=3, dering=False))
        radiance = 0.5 * _horizontal_irradiance(sky, 0.7, 4.0) / math.pi
        _close(ground, (math.pi * radiance / 2.0) * (1.0 - normals[:, 2:3]), QUADRATURE_RTOL)


# --------------------------------------------------------------------------- #
class TestSunSH:
    @pytest.mark.parametrize("bands", [1, 2, 3, 5, 7])
    def test_trig_matrix_is_the_basis(self, bands: int) -> None:
        ts = np.linspace(0.0, HALF_PI, 37)
        window = solar.sun_window(bands)
        matrix = lights.sun_trig_matrix(bands, window)
        k = np.arange(bands)
        trig = np.concatenate([np.cos(np.outer(ts, k)), np.sin(np.outer(ts, k))], axis=1)
        dirs = np.stack([np.sin(ts), np.zeros_like(ts), np.cos(ts)], axis=-1)
        rows = [l * (l + 1) + m for l, m in coefficient_file.zonal_half_layout(bands)]
        expected = sh.basis(dirs, bands)[:, rows] * window[[l for l, _ in coefficient_file.zonal_half_layout(bands)]]
        np.testing.assert_allclose(trig @ matrix.T, expected, rtol=0, atol=TRIG_ATOL)

    @pytest.mark.parametrize("bands", [1, 3, 7])
    @pytest.mark.parametrize("gibbs", [False, True])
    def test_sun_is_the_windowed_delta_never_filtered(self, sky: SkySH, bands: int, gibbs: bool) -> None:
        ts, t, phi = 0.6, 2.8, -2.2
        sun = sky.coefficients(ts, t, phi, bands=bands, gibbs=gibbs, sun=True) - sky.coefficients(
            ts, t, phi, bands=bands, gibbs=gibbs)
        expected = solar.sun_sh(solar.sun_direction(ts, phi), solar.illuminance_rgb(ts, t), bands)
        scale = float(np.abs(expected).max())
        assert np.abs(sun - expected).max() <= SUN_RTOL * scale

    def test_fused_equals_the_composition(self, sky: SkySH) -> None:
        for bands in (1, 2, 3, 5, 7):
            for gibbs in (False, True):
                for ts, t, phi in [(0.7, 3.3, 1.2), (0.0, 2.5, 0.0), (HALF_PI, 6.0, -2.0), (1.5, 4.4, 30.0)]:
                    got = sky.coefficients(ts, t, phi, bands=bands, gibbs=gibbs, sun=True, ground_albedo=(0.2, 0.3, 0.5))
                    _close(got, _composed(sky, ts, t, phi, bands, gibbs, False, (0.2, 0.3, 0.5)), PATH_RTOL)

    @staticmethod
    def _fused_equals_the_composition(sky: SkySH, ts: float, t: float, phi: float, albedo: float, bands: int,
                                      sun: bool) -> None:
        got = sky.coefficients(ts, t, phi, bands=bands, sun=sun, ground_albedo=albedo)
        expected = _composed(sky, ts, t, phi, bands, True, False, albedo)
        if not sun:  # the composition without the sun: remove its delta and its light on the ground
            expected = sky.coefficients(ts, t, phi, bands=bands) + np.outer(
                _lower_hemisphere_sh(bands), albedo * _horizontal_irradiance(sky, ts, t) / math.pi
            ) * _sinc_filter(bands)[L_OF[: bands * bands]][:, None]
        _close(got, expected, PATH_RTOL)

    @settings(max_examples=FUSED_EXAMPLES["core"], deadline=None)
    @given(**FUSED_ARGUMENTS)
    def test_property_fused_equals_the_composition(self, sky: SkySH, ts: float, t: float, phi: float, albedo: float,
                                                   bands: int, sun: bool) -> None:
        self._fused_equals_the_composition(sky, ts, t, phi, albedo, bands, sun)

    @pytest.mark.slow
    @settings(max_examples=FUSED_EXAMPLES["slow"], deadline=None)
    @given(**FUSED_ARGUMENTS)
    def test_property_fused_equals_the_composition_full(self, sky: SkySH, ts: float, t: float, phi: float,
                                                        albedo: float, bands: int, sun: bool) -> None:
        self._fused_equals_the_composition(sky, ts, t, phi, albedo, bands, sun)

    def test_without_a_sun_table(self) -> None:
        table = coefficient_file.read(coefficient_file.default_path())
        metadata = {key: value for key, value in table.metadata.items() if key != "tables"}
        bare = SkySH(coefficient_file.SkyTable(table=table.table, degrees=table.degrees, metadata=metadata))
        with pytest.raises(ValueError, match="sun table"):
            bare.coefficients(0.5, 3.0, sun=True)
        with pytest.raises(ValueError, match="sun table"):
            bare.sun_light(0.5, 3.0)
        np.testing.assert_array_equal(bare.coefficients(0.5, 3.0, 1.0, ground_albedo=0.3),
                                      SkySH.load().coefficients(0.5, 3.0, 1.0, ground_albedo=0.3))


# --------------------------------------------------------------------------- #
class TestOrder:
    def test_dering_sees_the_sky_alone(self, sky: SkySH, monkeypatch: pytest.MonkeyPatch) -> None:
        import skysh.post.dering

        seen: list[np.ndarray] = []

        def recording(coeffs: np.ndarray, *args: object, **kwargs: object) -> tuple:
            seen.append(np.array(coeffs))
            return 0.5 * np.asarray(coeffs), None  # a stand-in window: halves everything

        monkeypatch.setattr(skysh.post.dering, "dering", recording)
        for args in [(0.6, 3.1, 0.7), (np.array([0.6, 0.9]), 3.1, 0.7)]:
            seen.clear()
            got = sky.coefficients(*args, irradiance=True, sun=True, ground_albedo=0.4, irradiance_table=False)
            alone = sky.coefficients(*args, gibbs=False, dering=False)
            assert len(seen) == 1
            _close(seen[0], alone, PATH_RTOL)
            # the result is the halved sky plus the un-halved sun and ground, convolved
            lit = sky.coefficients(*args, gibbs=False, dering=False, sun=True, ground_albedo=0.4)
            expected = (lit - 0.5 * alone) * sh.cosine_lobe(3)[L_OF[:9]][:, None]
            _close(got, expected, PATH_RTOL)

    @pytest.mark.parametrize("dering", [False, True])
    def test_ground_is_added_after_the_colourspace_conversion(self, sky: SkySH, dering: bool) -> None:
        for bands in (1, 3, 5):
            got = sky.coefficients(0.9, 3.5, 2.0, bands=bands, gibbs=True, dering=dering, colourspace="ACEScg",
                                   sun=True, ground_albedo=(0.1, 0.4, 0.8))
            expected = _composed(sky, 0.9, 3.5, 2.0, bands, True, dering, (0.1, 0.4, 0.8), colourspace="ACEScg")
            _close(got, expected, PATH_RTOL)


# --------------------------------------------------------------------------- #
class TestNonNegative:
    @pytest.mark.parametrize("bands", [1, 2, 3, 5, 7])
    def test_irradiance_with_the_sun_and_deringing(self, sky: SkySH, bands: int) -> None:
        normals = sh.quadrature_rule(48)[0]  # 4608 normals
        basis = sh.basis(normals, bands)
        for ts in np.radians([0.0, 30.0, 60.0, 80.0, 88.0, 89.5, 90.0]):
            for t in (2.5, 3.5, 6.0):
                for phi, albedo in ((0.0, 0.0), (1.1, 1.0), (-2.5, (0.05, 0.3, 0.9))):
                    with warnings.catch_warnings():
                        warnings.simplefilter("error")  # no DeringWarning: the sky is deringable
                        c = sky.coefficients(ts, t, phi, bands=bands, irradiance=True, sun=True, ground_albedo=albedo)
                    e = basis @ c
                    assert e.min() >= -NONNEGATIVE_ATOL * e.max(), (bands, ts, t, phi, albedo, e.min(axis=0))

    def test_the_sun_colour_is_clamped_in_the_delta_only(self, sky: SkySH) -> None:
        ts, t = math.radians(89.0), 6.0  # green and blue below 0 (outside the sRGB gamut)
        rgb = sky.sun_light(ts, t)[1]
        assert rgb.min() < 0.0
        got = sky.coefficients(ts, t, 0.0, bands=3, gibbs=False, sun=True)
        sky_part = sky.coefficients(ts, t, 0.0, bands=3, gibbs=False)
        direction = solar.sun_direction(ts, 0.0)
        _close(got, sky_part + solar.sun_sh(direction, np.maximum(rgb, 0.0), 3), PATH_RTOL)
        # negative control: the unclamped colour differs by far more than the tolerance
        unclamped = sky_part + solar.sun_sh(direction, rgb, 3)
        assert np.abs(got - unclamped).max() > 1e3 * PATH_RTOL * np.abs(sky_part).max()


# --------------------------------------------------------------------------- #
class TestSunLight:
    def test_against_the_spectral_model(self, sky: SkySH) -> None:
        rng = np.random.default_rng(15)
        ts = np.concatenate([rng.uniform(0.0, HALF_PI, 60), [0.0, HALF_PI, HALF_PI - 1e-3]])
        t = np.concatenate([rng.uniform(2.5, 6.0, 60), [2.5, 6.0, 4.0]])
        truth = solar.illuminance_rgb(ts, t)
        y = solar.direct_normal_illuminance(ts, t)[:, None]
        _, batch = sky.sun_light(ts, t, 0.0)
        assert (np.abs(batch - truth) / np.maximum(np.abs(truth), y)).max() <= SUN_RTOL
        for a, b, expected, floor in zip(ts[:10], t[:10], truth, y):
            _, one = sky.sun_light(float(a), float(b), 1.0)
            assert (np.abs(one - expected) / np.maximum(np.abs(expected), floor)).max() <= SUN_RTOL

    def test_colourspace(self, sky: SkySH) -> None:
        truth = solar.illuminance_rgb(0.4, 3.0, "ACEScg")
        got = sky.sun_light(0.4, 3.0, colourspace="ACEScg")[1]
        assert (np.abs(got - truth) / np.abs(truth)).max() <= SUN_RTOL

    @pytest.mark.parametrize("phi", [0.0, 0.7, -2.9, 40.0])
    def test_direction(self, sky: SkySH, phi: float) -> None:
        for ts in (0.0, 0.3, HALF_PI):
            d, _ = sky.sun_light(ts, 3.0, phi)
            assert abs(np.linalg.norm(d) - 1.0) <= UNIT_ATOL and abs(d[2] - math.cos(ts)) <= UNIT_ATOL
            np.testing.assert_allclose(d, solar.sun_direction(ts, phi), rtol=0, atol=DIRECTION_ATOL)
            if ts > 0.0:
                assert abs(math.remainder(math.atan2(d[1], d[0]) - phi, 2 * math.pi)) <= AZIMUTH_ATOL

    def test_batch_equals_scalar(self, sky: SkySH) -> None:
        ts, t, phi = np.array([[0.1, 0.9], [1.2, HALF_PI]]), np.array([2.5, 5.0]), 0.4
        d, rgb = sky.sun_light(ts, t, phi)
        assert d.shape == rgb.shape == (2, 2, 3)
        for i in range(2):
            for j in range(2):
                d1, rgb1 = sky.sun_light(float(ts[i, j]), float(t[j]), phi)
                np.testing.assert_allclose(d[i, j], d1, rtol=0, atol=UNIT_ATOL)
                np.testing.assert_allclose(rgb[i, j], rgb1, rtol=PATH_RTOL, atol=PATH_RTOL * abs(rgb1).max())

    def test_any_real_scalar(self, sky: SkySH) -> None:
        expected = sky.sun_light(0.5, 3.0, 1.0)
        for args in [(0.5, 3, 1), (np.float32(0.5), np.int64(3), np.array(1.0))]:
            got = sky.sun_light(*args)
            assert got[0].shape == got[1].shape == (3,)
            np.testing.assert_allclose(got[1], expected[1], rtol=PATH_RTOL)  # every value here is exact in float64

    @pytest.mark.parametrize("kwargs, name", [
        ({"sun_zenith": 1.6}, "sun_zenith"), ({"sun_zenith": float("nan")}, "sun_zenith"),
        ({"turbidity": 7.0}, "turbidity"), ({"sun_azimuth": float("inf")}, "sun_azimuth"),
        ({"sun_zenith": "0.5"}, "sun_zenith"), ({"turbidity": True}, "turbidity"),
        ({"colourspace": 3}, "colourspace"),
    ])
    def test_refusals_name_the_parameter(self, sky: SkySH, kwargs: dict, name: str) -> None:
        args = {"sun_zenith": 0.5, "turbidity": 3.0, **kwargs}
        with pytest.raises(ValueError, match=name):
            sky.sun_light(**args)


# --------------------------------------------------------------------------- #
class TestBatchAndPaths:
    @pytest.mark.parametrize("kwargs", [{}, {"irradiance": True}, {"colourspace": "ACEScg"}, {"gibbs": False},
                                        {"dering": True, "bands": 5}])
    def test_batch_equals_scalar(self, sky: SkySH, kwargs: dict) -> None:
        ts, t, phi = np.array([0.0, 0.7, HALF_PI]), np.array([[2.5], [6.0]]), 1.3
        batch = sky.coefficients(ts, t, phi, sun=True, ground_albedo=(0.3, 0.2, 0.1), **kwargs)
        assert batch.shape[:2] == (2, 3)
        for i in range(2):
            for j in range(3):
                one = sky.coefficients(float(ts[j]), float(t[i, 0]), phi, sun=True, ground_albedo=(0.3, 0.2, 0.1), **kwargs)
                _close(batch[i, j], one, PATH_RTOL)

    def test_empty_batch(self, sky: SkySH) -> None:
        out = sky.coefficients(np.zeros(0), 3.0, 0.0, sun=True, ground_albedo=0.5)
        assert out.shape == (0, 9, 3)

    def test_radiance_and_irradiance_at_pass_the_lights(self, sky: SkySH) -> None:
        dirs = sh.quadrature_rule(8)[0]
        c = sky.coefficients(0.5, 3.0, 1.0, bands=4, sun=True, ground_albedo=0.2)
        _close(sky.radiance(dirs, 0.5, 3.0, 1.0, bands=4, sun=True, ground_albedo=0.2), sh.evaluate(c, dirs), PATH_RTOL)
        e = sky.coefficients(0.5, 3.0, 1.0, bands=4, irradiance=True, sun=True, ground_albedo=0.2)
        _close(sky.irradiance_at(dirs, 0.5, 3.0, 1.0, bands=4, sun=True, ground_albedo=0.2), sh.evaluate(e, dirs),
               PATH_RTOL)

    def test_black_ground_and_no_sun_is_the_sky(self, sky: SkySH) -> None:
        for albedo in (0.0, 0, (0.0, 0.0, 0.0), np.zeros(3)):
            np.testing.assert_array_equal(sky.coefficients(0.5, 3.0, 1.0, ground_albedo=albedo),
                                          sky.coefficients(0.5, 3.0, 1.0))

    def test_tables_are_built_once(self, sky: SkySH) -> None:
        sky.coefficients(0.5, 3.0, sun=True)
        assert sky._lit_plan(3, True) is sky._lit_plan(3, True)


# --------------------------------------------------------------------------- #
class TestRefusals:
    @pytest.mark.parametrize("bad", [True, np.bool_(False), float("nan"), float("inf"), -0.1, 1.5, (0.1, 0.2),
                                     (0.1, 0.2, 0.3, 0.4), [[0.1, 0.2, 0.3]], (0.1, float("nan"), 0.2), (0.1, 0.2, 1.01),
                                     "0.5", (True, 0.0, 0.0), np.array([0.2, -1e-9, 0.3]), None])
    def test_ground_albedo(self, sky: SkySH, bad: object) -> None:
        with pytest.raises(ValueError, match="ground_albedo"):
            sky.coefficients(0.5, 3.0, ground_albedo=bad)
        with pytest.raises(ValueError, match="ground_albedo"):
            sky.irradiance_at([0.0, 0.0, 1.0], 0.5, 3.0, ground_albedo=bad)

    @pytest.mark.parametrize("bad", [10**400, -10**400, 10**5000, 2, -1, (10**400, 0.1, 0.1)],
                             ids=["1e400", "-1e400", "1e5000", "two", "minus-one", "triple-1e400"])
    def test_ground_albedo_integers_beyond_range(self, sky: SkySH, bad: object) -> None:
        """Issue 23: a Python int beyond float64 (10**400) was an OverflowError; now a ValueError naming
        ground_albedo and [0, 1], by an exact comparison of the int (no float() on the per-frame path)."""
        for kwargs in ({}, {"sun": True}):
            with pytest.raises(ValueError, match=r"ground_albedo must (lie in \[0, 1\]|be a real number)"):
                sky.coefficients(0.5, 3.0, ground_albedo=bad, **kwargs)
        with pytest.raises(ValueError, match=r"ground_albedo must (lie in \[0, 1\]|be a real number)"):
            sky.coefficients(np.array([0.5, 0.6]), 3.0, ground_albedo=bad)
        if isinstance(bad, int):
            with pytest.raises(ValueError, match=r"ground_albedo must lie in \[0, 1\], got (an integer of \d+ digits|-?\d)$"):
                lights.check_albedo(bad)

    def test_ground_albedo_integers_in_range(self, sky: SkySH) -> None:
        assert lights.check_albedo(1) == (1.0, 1.0, 1.0) and lights.check_albedo(0) is None
        np.testing.assert_array_equal(sky.coefficients(0.5, 3.0, ground_albedo=1), sky.coefficients(0.5, 3.0, ground_albedo=1.0))

    @pytest.mark.parametrize("bad", ["True", 1, 0.0, None, [True], np.array([True])])
    def test_sun_must_be_a_bool(self, sky: SkySH, bad: object) -> None:
        with pytest.raises(TypeError, match="sun"):
            sky.coefficients(0.5, 3.0, sun=bad)

    def test_domain_refusals_are_the_same_with_the_lights(self, sky: SkySH) -> None:
        for kwargs in ({}, {"sun": True, "ground_albedo": 0.5}):
            for args, name in [((1.6, 3.0), "sun_zenith"), ((0.5, 2.0), "turbidity"), ((0.5, 3.0, float("nan")), "sun_azimuth"),
                               ((np.array([0.5, 1.7]), 3.0), "sun_zenith")]:
                with pytest.raises(ValueError, match=name):
                    sky.coefficients(*args, **kwargs)
            with pytest.raises(ValueError, match="bands"):
                sky.coefficients(0.5, 3.0, bands=8, **kwargs)


# --------------------------------------------------------------------------- #
def test_the_lights_do_not_import_heavy_modules(tmp_path: Path) -> None:
    code = (
        "import sys, json, skysh\n"
        "sky = skysh.SkySH.load()\n"
        "sky.coefficients(0.5, 3.0, 1.0, bands=3, sun=True, ground_albedo=(0.1, 0.2, 0.3))\n"
        "sky.coefficients([0.5, 0.6], 3.0, 1.0, bands=3, irradiance=True, sun=True, ground_albedo=0.5)\n"
        "sky.sun_light(0.5, 3.0, 1.0)\n"
        "print(json.dumps(sorted(sys.modules)))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    result = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True, check=True)
    modules = set(json.loads(result.stdout))
    assert "skysh.lighting.lights" in modules
    heavy = sorted(m for m in modules if m.split(".")[0] in ("colour", "matplotlib") or m == "skysh.table.fit")
    assert heavy == [], heavy
