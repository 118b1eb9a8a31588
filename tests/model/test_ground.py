"""
Tests of :mod:`skysh.model.ground`
============================

References independent of skysh: a Gauss-Legendre quadrature of scipy's
spherical harmonics over the lower hemisphere (exact for these polynomial
integrands, so "converged" to rounding), brute-force integrals of the Preetham
sky's radiance, and the view-factor integral of a tilted plane by a product
rule split at the plane's horizon.

Every tolerance is a named constant with the reason for its size.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EPS, random_unit_vectors, scipy_real_sh
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh.model import ground, preetham, solar
from skysh.sh import basis as sh

ROUNDING_RTOL: float = EPS
"""One or two correctly rounded operations on exact inputs (a product or quotient by pi, a
channel scale): each within half an ulp, so within eps relative."""

CLOSED_FORM_RTOL: float = 2 * EPS
"""A square root of a rounded product, times an exact number, on both sides (sqrt(3 pi) / 2,
sqrt(4 pi / 3) x c_10): up to four half-ulp roundings."""

VIEW_FACTOR_ATOL: float = 1e-13
"""Absolute floor of the tilted-plane comparison: at tilt 0 the ground is out of view and both
sides are 0 up to the rounding of sums of values <= pi (~1e-15)."""

PROPERTY_RTOL: float = 1e-12
"""SH irradiance of the ground (exact for >= 2 bands) vs pi L (1 - n_z) / 2 at up to 12 bands:
rounding of a <= 144-term sum of terms <= L; relative, with the same absolute floor x max(L, 1)."""

SUN_DELTA_RTOL: float = 1e-14
"""sqrt(4 pi / 3) c_10 of an unwindowed delta of 1e5 lux vs 1e5 cos(theta): two square roots and
two products (a few ulp); for cos(1.5) = 0.07 the same bound taken absolute, x 1e5."""

ZONAL_ATOL: float = 1e-12
"""The brief's figure: closed form vs a converged quadrature of the uniform lower hemisphere
(coefficients <= sqrt(pi); the Gauss rule is exact, so only rounding, ~1e-14, remains)."""

IRRADIANCE_ATOL: float = 1e-12
"""SH irradiance of the ground vs the closed form pi L (1 - n_z) / 2 for L = 1 (values <= pi)."""

VIEW_FACTOR_NODES: int = 400
"""Gauss nodes per panel of the tilted-plane integral."""

VIEW_FACTOR_RTOL: float = 1e-8
"""That integral has a square-root endpoint singularity where the ground's horizon grazes the
normal's (t = |sin tilt|, a panel edge), so Gauss converges as n^-3: measured 6e-9 at 400 nodes."""

SKY_HORIZONTAL_RTOL: float = 2e-7
"""sqrt(4 pi / 3) c_10 of preetham.sky_sh (accurate to 1e-7 of the DC term, test_preetham) vs a
direct integral of L cos(theta) with a 4x denser sun-adapted rule."""

ZONAL_BANDS: int = 16
"""Bands checked against the quadrature (the closed form is tabulated to 64)."""

LINEAR_ARGUMENTS = {"bands": st.integers(2, 12), "lg": st.floats(0.0, 1e5), "theta": st.floats(0.0, math.pi),
                    "phi": st.floats(-3.2, 3.2)}
LINEAR_EXAMPLES: dict[str, int] = {"core": 15, "slow": 50}
"""Hypothesis examples of TestGroundIrradiance's linear-and-exact property in the core run (``-m "not slow"``) and
in its ``slow`` twin; the core also checks the SH irradiance's exactness at 503 normals for 2..7 bands
(test_sh_irradiance_is_exact_for_two_or_more_bands)."""


def lower_hemisphere_rule(n_z: int, n_phi: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre in z on [-1, 0] x uniform azimuth: exact for Y_lm (l < n_z, |m| < n_phi)."""
    x, wx = np.polynomial.legendre.leggauss(n_z)
    z, wz = 0.5 * (x - 1.0), 0.5 * wx
    phi = (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi
    s = np.sqrt(1 - z * z)
    dirs = np.stack(np.broadcast_arrays(s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), z[:, None]), -1)
    return dirs.reshape(-1, 3), np.repeat(wz * 2 * math.pi / n_phi, n_phi)


class TestGroundSH:
    def test_against_converged_quadrature(self) -> None:
        dirs, w = lower_hemisphere_rule(64, 64)
        expected = (scipy_real_sh(dirs, ZONAL_BANDS) * w[:, None]).sum(0)  # L_g = 1
        got = ground.ground_sh([1.0], ZONAL_BANDS)[:, 0]
        np.testing.assert_allclose(got, expected, rtol=0, atol=ZONAL_ATOL)

    def test_closed_form_values(self) -> None:
        assert ground.GROUND_ZONAL[0] == pytest.approx(math.sqrt(math.pi), rel=ROUNDING_RTOL)
        assert ground.GROUND_ZONAL[1] == pytest.approx(-math.sqrt(3 * math.pi) / 2, rel=CLOSED_FORM_RTOL)
        assert np.all(ground.GROUND_ZONAL[2::2] == 0.0)
        assert ground.GROUND_ZONAL.shape == (sh.MAX_BANDS,)

    def test_zonal_only_rgb_and_batch(self) -> None:
        lg = np.array([[1.0, 2.0, 3.0], [0.5, 0.0, 4.0]])
        got = ground.ground_sh(lg, 4)
        assert got.shape == (2, 16, 3)
        zonal = [0, 2, 6, 12]
        others = [i for i in range(16) if i not in zonal]
        assert np.all(got[:, others, :] == 0.0)
        np.testing.assert_array_equal(got[1], ground.ground_sh(lg[1], 4))
        np.testing.assert_allclose(got[0, zonal, 2], 3.0 * ground.GROUND_ZONAL[:4], rtol=ROUNDING_RTOL)

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="radiance"):
            ground.ground_sh(1.0, 3)
        with pytest.raises(ValueError, match="radiance"):
            ground.ground_sh([math.nan, 1.0, 1.0], 3)
        with pytest.raises(ValueError, match="bands"):
            ground.ground_sh([1.0], 0)


class TestGroundRadiance:
    def test_energy_albedo_one(self) -> None:
        e_h = np.array([30_000.0, 31_000.0, 35_000.0])
        lg = ground.ground_radiance(1.0, e_h)
        np.testing.assert_allclose(math.pi * lg, e_h, rtol=ROUNDING_RTOL)  # exitance = horizontal irradiance

    def test_rgb_albedo_and_default_black(self) -> None:
        e_h = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
        got = ground.ground_radiance([0.2, 0.5, 1.0], e_h)
        np.testing.assert_allclose(got, e_h * [0.2, 0.5, 1.0] / math.pi, rtol=ROUNDING_RTOL)
        assert np.all(ground.ground_radiance(0.0, e_h) == 0.0)

    @pytest.mark.parametrize("albedo", [-0.01, 1.01, math.nan, [0.5, 0.5], [[0.5, 0.5, 0.5]], "grey", math.inf])
    def test_bad_albedo(self, albedo: object) -> None:
        with pytest.raises(ValueError, match="ground_albedo"):
            ground.ground_radiance(albedo, [1.0, 1.0, 1.0])

    def test_bad_irradiance(self) -> None:
        with pytest.raises(ValueError, match="horizontal_irradiance"):
            ground.ground_radiance(0.5, 1.0)
        with pytest.raises(ValueError, match="horizontal_irradiance"):
            ground.ground_radiance(0.5, [1.0, math.nan, 1.0])


class TestGroundIrradiance:
    @pytest.mark.parametrize("bands", range(2, 8))
    def test_sh_irradiance_is_exact_for_two_or_more_bands(self, bands: int) -> None:
        normals = np.concatenate([random_unit_vectors(500, bands), [[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0]]])
        e_sh = sh.evaluate(sh.irradiance(ground.ground_sh([1.0], bands)), normals)[:, 0]
        np.testing.assert_allclose(e_sh, ground.ground_irradiance([1.0], normals)[:, 0], rtol=0, atol=IRRADIANCE_ATOL)
        assert abs(e_sh[-3]) <= IRRADIANCE_ATOL  # the upward normal sees no ground

    @pytest.mark.parametrize("tilt", [0.0, 0.4, math.pi / 2, 2.5, math.pi])
    def test_view_factor_against_quadrature(self, tilt: float) -> None:
        # Integrate L max(0, n.w) over z < 0 in a frame whose pole is n: t = n.w in [0, 1] (one
        # smooth panel), azimuth psi; w_z = t cos(tilt) + sqrt(1 - t^2) sin(tilt) cos(psi) must be
        # < 0. For each t the psi-interval where w_z < 0 is found in closed form.
        x, wx = np.polynomial.legendre.leggauss(VIEW_FACTOR_NODES)
        c, s = math.cos(tilt), math.sin(tilt)
        total = 0.0
        for lo, hi in ((0.0, abs(s)), (abs(s), 1.0)):  # split where the horizon circle grazes: t = |sin tilt|
            for ti, wi in zip(lo + (hi - lo) * 0.5 * (x + 1.0), (hi - lo) * 0.5 * wx):
                r = math.sqrt(1 - ti * ti) * s
                a = ti * c  # w_z = a + r cos(psi) < 0
                frac = (1.0 if a < 0 else 0.0) if abs(r) <= abs(a) else math.acos(a / abs(r)) / math.pi
                total += wi * ti * 2 * math.pi * frac
        n = np.array([s, 0.0, c])
        assert ground.ground_irradiance([1.0], n)[0] == pytest.approx(total, rel=VIEW_FACTOR_RTOL, abs=VIEW_FACTOR_ATOL)

    @staticmethod
    def _linear_and_exact(bands: int, lg: float, theta: float, phi: float) -> None:
        n = np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])
        e = sh.evaluate(sh.irradiance(ground.ground_sh([lg], bands)), n)[0]
        assert e == pytest.approx(math.pi * lg * (1 - n[2]) / 2, rel=PROPERTY_RTOL, abs=PROPERTY_RTOL * max(lg, 1.0))

    @settings(max_examples=LINEAR_EXAMPLES["core"], deadline=None)
    @given(**LINEAR_ARGUMENTS)
    def test_property_linear_and_exact(self, bands: int, lg: float, theta: float, phi: float) -> None:
        self._linear_and_exact(bands, lg, theta, phi)

    @pytest.mark.slow
    @settings(max_examples=LINEAR_EXAMPLES["slow"], deadline=None)
    @given(**LINEAR_ARGUMENTS)
    def test_property_linear_and_exact_full(self, bands: int, lg: float, theta: float, phi: float) -> None:
        self._linear_and_exact(bands, lg, theta, phi)


class TestHorizontalIrradiance:
    @pytest.mark.parametrize("ts,tu", [(0.0, 2.5), (0.7, 3.0), (1.45, 6.0)])
    def test_sky_against_brute_force(self, ts: float, tu: float) -> None:
        c = preetham.sky_sh(ts, tu, 3)
        dirs, w = preetham.sky_quadrature_rule(ts, 4 * preetham.SKY_SH_THETA_NODES)
        expected = (preetham.radiance(dirs, ts, 0.0, tu) * (dirs[:, 2] * w)[:, None]).sum(0)
        np.testing.assert_allclose(ground.horizontal_irradiance_from_sh(c), expected, rtol=SKY_HORIZONTAL_RTOL)

    def test_sun_delta_is_e_cos_theta(self) -> None:
        for ts in (0.0, 0.6, 1.5):
            d = solar.sun_direction(ts, 0.8)
            c = solar.sun_sh(d, [1e5], 4, window=np.ones(4))
            assert ground.horizontal_irradiance_from_sh(c)[0] == pytest.approx(1e5 * math.cos(ts), rel=SUN_DELTA_RTOL,
                                                                                  abs=SUN_DELTA_RTOL * 1e5)

    def test_shapes_and_bad_input(self) -> None:
        c = np.zeros((2, 9, 3))
        c[..., 2, :] = 1.0
        np.testing.assert_allclose(ground.horizontal_irradiance_from_sh(c), np.full((2, 3), math.sqrt(4 * math.pi / 3)),
                                   rtol=CLOSED_FORM_RTOL)
        expected = 2 * math.sqrt(4 * math.pi / 3)
        assert ground.horizontal_irradiance_from_sh(np.arange(4.0)) == pytest.approx(expected, rel=CLOSED_FORM_RTOL)
        for bad in (np.zeros(1), np.zeros((5, 3)), np.array([0.0, 0.0, math.nan, 0.0])):
            with pytest.raises(ValueError, match="coeffs"):
                ground.horizontal_irradiance_from_sh(bad)
