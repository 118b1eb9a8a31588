"""Tests of skysh.post.hazel against definitions by quadrature, the orthonormal route and analytic irradiance.

The study of the reconstructions on the sky (exact irradiance, comparison) is tested in tests/test_studies.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import random_unit_vectors, unit
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh.post import hazel
from skysh.sh import basis as sh

ROUTE_TOLERANCE: float = 1e-13
"""Hazel's formulas against the orthonormal route: a few float64 operations on values of size ~1
(relative to the largest coefficient)."""

QUADRATURE_TOLERANCE: float = 1e-13
"""(R0, R1, R2) by an exact Gauss rule (degree <= 7) against the closed-form mapping: float64 sums of
~30 terms."""

GEOMERICS_MEAN_TOLERANCE: float = 1e-6
"""Sphere average of the non-linear L1 by a 64-node Gauss rule in n.d: q^p with p in [1, 3] is a
polynomial for p = 1, 2, 3 and smooth otherwise except at q = 0, where q^p has a p-th power kink;
the rule's error there is far below 1e-6 (measured ~1e-9)."""

IDENTITY_TOLERANCE: float = 1e-9
"""Relative tolerance of exact algebraic identities evaluated through pow and sqrt in float64
(I(d) - I(-d) = 4 |R1|, r = 1 for one delta light): rounding is ~1e-15, cancellation near r = 0 costs
a few more digits."""


@st.composite
def delta_lights(draw) -> tuple[np.ndarray, np.ndarray]:
    """A few delta lights: unit directions (n, 3) and positive single-channel powers (n,)."""
    n = draw(st.integers(1, 5))
    raw = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=3 * n, max_size=3 * n))).reshape(n, 3)
    raw[np.linalg.norm(raw, axis=1) < 1e-3] = [0.0, 0.0, 1.0]
    powers = np.array(draw(st.lists(st.floats(1e-3, 1e3), min_size=n, max_size=n)))
    return unit(raw), powers


def exact_delta_irradiance(dirs: np.ndarray, powers: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """I(n) = (1 / pi) sum_j s_j max(0, n.d_j) for R = sum_j s_j delta(w - d_j): analytic, not SH."""
    return np.maximum(0.0, normals @ dirs.T) @ powers / math.pi


# --------------------------------------------------------------------------- #
class TestNormalised:
    def test_definition_by_quadrature(self):
        """R0 = <R, 1>, R1 = <R, w>, R2 = <R, w w^T - I/3> under (1 / 4 pi) integral: fixes the CS signs."""
        rng = np.random.default_rng(1)
        coeffs = rng.normal(size=(9, 2))
        dirs, weights = sh.quadrature_rule(4)
        values = sh.evaluate(coeffs, dirs)  # (M, 2)
        w = weights / (4 * math.pi)
        r0 = w @ values
        r1 = np.einsum("m,mi,mc->ci", w, dirs, values)
        b2 = dirs[:, :, None] * dirs[:, None, :] - np.eye(3) / 3
        r2 = np.einsum("m,mij,mc->cij", w, b2, values)
        got = hazel.to_normalised(coeffs)
        scale = np.abs(coeffs).max()
        np.testing.assert_allclose(got[0], r0, atol=QUADRATURE_TOLERANCE * scale)
        np.testing.assert_allclose(got[1], r1, atol=QUADRATURE_TOLERANCE * scale)
        np.testing.assert_allclose(got[2], r2, atol=QUADRATURE_TOLERANCE * scale)

    def test_a_light_from_plus_x_points_r1_to_plus_x(self):
        """The Condon-Shortley minus sign of Y(1, 1) must not flip the average direction."""
        for d in np.eye(3):
            c = sh.basis(d, 3)[:, None] * 4 * math.pi  # delta of power 4 pi: R0 = 1
            r0, r1, r2 = hazel.to_normalised(c)
            np.testing.assert_allclose(r0, [1.0], atol=ROUTE_TOLERANCE)
            np.testing.assert_allclose(r1[0], d, atol=ROUTE_TOLERANCE)
            np.testing.assert_allclose(r2[0], np.outer(d, d) - np.eye(3) / 3, atol=ROUTE_TOLERANCE)

    def test_round_trip_symmetric_traceless(self):
        coeffs = np.random.default_rng(2).normal(size=(4, 5, 9, 3))
        r0, r1, r2 = hazel.to_normalised(coeffs)
        assert r0.shape == (4, 5, 3) and r1.shape == (4, 5, 3, 3) and r2.shape == (4, 5, 3, 3, 3)
        np.testing.assert_array_equal(r2, np.swapaxes(r2, -1, -2))
        np.testing.assert_allclose(np.trace(r2, axis1=-2, axis2=-1), 0.0, atol=ROUTE_TOLERANCE)
        scale = np.abs(coeffs).max()
        np.testing.assert_allclose(hazel.from_normalised(r0, r1, r2), coeffs, rtol=0, atol=ROUTE_TOLERANCE * scale)

    def test_lower_bands_and_vectors(self):
        c4 = np.random.default_rng(3).normal(size=(4, 3))
        r0, r1, r2 = hazel.to_normalised(c4)
        assert np.all(r2 == 0.0)
        np.testing.assert_allclose(hazel.from_normalised(r0, r1), c4, atol=ROUTE_TOLERANCE)
        c1 = c4[:1]
        np.testing.assert_allclose(hazel.from_normalised(hazel.to_normalised(c1)[0]), c1, atol=ROUTE_TOLERANCE)
        v = c4[:, 0]
        r0, r1, r2 = hazel.to_normalised(v)
        assert r0.shape == () and r1.shape == (3,) and r2.shape == (3, 3)
        np.testing.assert_allclose(hazel.from_normalised(r0, r1), v, atol=ROUTE_TOLERANCE)

    def test_bad_inputs(self):
        with pytest.raises(ValueError, match="K in \\(1, 4, 9\\)"):
            hazel.to_normalised(np.ones((16, 3)))
        with pytest.raises(ValueError, match="finite"):
            hazel.to_normalised(np.full((9, 3), np.nan))
        with pytest.raises(ValueError, match="symmetric and traceless"):
            hazel.from_normalised(np.ones(1), np.zeros((1, 3)), np.eye(3)[None])
        with pytest.raises(ValueError, match="symmetric and traceless"):
            hazel.from_normalised(np.ones(1), np.zeros((1, 3)), np.triu(np.ones((3, 3)), 1)[None])
        with pytest.raises(ValueError, match="R2 needs R1"):
            hazel.from_normalised(np.ones(1), None, np.zeros((1, 3, 3)))
        with pytest.raises(ValueError, match="R1 must have shape"):
            hazel.from_normalised(np.ones(2), np.zeros((3, 3)))


# --------------------------------------------------------------------------- #
class TestReconstruction:
    @pytest.mark.parametrize("k", [1, 4, 9])
    def test_equal_to_the_orthonormal_route(self, k):
        coeffs = np.random.default_rng(4).normal(size=(k, 3))
        dirs = random_unit_vectors(200, 5)
        scale = np.abs(coeffs).max()
        orthonormal_radiance = sh.evaluate(coeffs, dirs)
        orthonormal_irradiance = sh.evaluate(sh.irradiance(coeffs), dirs) / math.pi
        np.testing.assert_allclose(hazel.radiance(coeffs, dirs), orthonormal_radiance, atol=ROUTE_TOLERANCE * scale)
        np.testing.assert_allclose(hazel.irradiance(coeffs, dirs), orthonormal_irradiance, atol=ROUTE_TOLERANCE * scale)

    def test_n_dimensional(self):
        coeffs = np.random.default_rng(6).normal(size=(7, 9, 3))
        dirs = random_unit_vectors(11, 7)
        batched = hazel.irradiance(coeffs[:, None], dirs)  # (7, 11, 3)
        assert batched.shape == (7, 11, 3)
        for p in (0, 6):
            np.testing.assert_allclose(batched[p], hazel.irradiance(coeffs[p], dirs), atol=ROUTE_TOLERANCE)
        assert hazel.radiance(coeffs[0, :, 0], dirs).shape == (11,)
        paired = hazel.radiance(coeffs, dirs[:7])  # batch axes (7,) and (7,) pair up
        np.testing.assert_allclose(paired[3], hazel.radiance(coeffs[3], dirs[3]), atol=ROUTE_TOLERANCE)

    def test_bad_dirs(self):
        with pytest.raises(ValueError, match="dirs must be unit vectors"):
            hazel.radiance(np.ones((9, 3)), [[1.0, 1.0, 0.0]])
        with pytest.raises(ValueError, match="normals must have shape"):
            hazel.irradiance(np.ones((9, 3)), [1.0, 0.0])
        with pytest.raises(ValueError, match="normals must be finite"):
            hazel.irradiance(np.ones((9, 3)), [np.nan, 0.0, 1.0])

    @settings(max_examples=40, deadline=None)
    @given(delta_lights())
    def test_antipodal_identity_with_the_exact_irradiance(self, lights):
        """n.R1 = (I(n) - I(-n)) / 4 with I the exact (not band-limited) irradiance of delta lights."""
        dirs, powers = lights
        coeffs = sh.basis(dirs, 3).T @ powers  # exact projection of the deltas
        _, r1, _ = hazel.to_normalised(coeffs)
        normals = random_unit_vectors(50, 8)
        difference = exact_delta_irradiance(dirs, powers, normals) - exact_delta_irradiance(dirs, powers, -normals)
        np.testing.assert_allclose(normals @ r1, difference / 4, atol=ROUTE_TOLERANCE * powers.sum())


# --------------------------------------------------------------------------- #
class TestGeomerics:
    def test_constants_match_the_published_shader(self):
        """p = 1 + 2 r, a = (1 - r) / (1 + r) (Enlighten's NonlinearL1ComputeChannel)."""
        r = np.linspace(0.0, 1.0, 11)
        d = np.array([0.0, 0.0, 1.0])
        coeffs = np.zeros((11, 4))
        coeffs[:, 0] = 2 * math.sqrt(math.pi)  # R0 = 1
        coeffs[:, 2] = r * 2 * math.sqrt(3 * math.pi)  # R1 = r z
        g = hazel.geomerics_parameters(coeffs[..., None])
        np.testing.assert_allclose(g["r"][:, 0], r, atol=ROUTE_TOLERANCE)
        np.testing.assert_allclose(g["p"][:, 0], 1 + 2 * r, atol=ROUTE_TOLERANCE)
        np.testing.assert_allclose(g["a"][:, 0], (1 - r) / (1 + r), atol=ROUTE_TOLERANCE)
        np.testing.assert_allclose(g["direction"][1:, 0], np.broadcast_to(d, (10, 3)), atol=ROUTE_TOLERANCE)

    def shader(self, normal: np.ndarray, l0: float, l1: np.ndarray) -> float:
        """Scalar transcription of the Enlighten SDK shader (Hazel coefficients L0 = R0, L1 = R1)."""
        mod = float(np.linalg.norm(l1))
        if mod == 0.0:
            return l0
        q = 0.5 + 0.5 * float(normal @ (l1 / mod))
        r = mod / l0
        p = 1.0 + 2.0 * r
        a = (1.0 - r) / (1.0 + r)
        return l0 * (a + (1.0 - a) * (p + 1.0) * q**p)

    def test_matches_the_shader(self):
        coeffs = sh.basis(random_unit_vectors(3, 9), 2).T @ np.array([[1.0, 0.2], [2.0, 0.0], [0.5, 0.1]])  # (4, 2)
        coeffs[0, 1] += 1.0
        normals = random_unit_vectors(20, 10)
        got = hazel.irradiance_l1_nonlinear(coeffs, normals)
        r0, r1, _ = hazel.to_normalised(coeffs)
        for i in range(0, 20, 5):  # the reference is scalar
            for c in range(2):
                assert got[i, c] == pytest.approx(self.shader(normals[i], r0[c], r1[c]), rel=ROUTE_TOLERANCE)

    @settings(max_examples=40, deadline=None)
    @given(delta_lights())
    def test_derivation_conditions(self, lights):
        """Never negative; mean R0; I(d) - I(-d) = 4 |R1| (docs/hazel.md, steps 1-2)."""
        dirs, powers = lights
        coeffs = sh.basis(dirs, 2).T @ powers
        r0, r1, _ = hazel.to_normalised(coeffs)
        length = np.linalg.norm(r1)
        normals = random_unit_vectors(200, 11)
        values = hazel.irradiance_l1_nonlinear(coeffs, normals)
        assert np.all(values >= 0.0)
        if length > IDENTITY_TOLERANCE * r0:  # else the direction d is undefined
            d = r1 / length
            ends = hazel.irradiance_l1_nonlinear(coeffs, np.stack([d, -d]))
            assert ends[0] - ends[1] == pytest.approx(4 * length, rel=IDENTITY_TOLERANCE)
            # Sphere mean: n.d = t is uniform on [-1, 1]; Gauss in t around d.
            t, w = np.polynomial.legendre.leggauss(64)
            side = unit(np.cross(d, [1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.cross(d, [0.0, 1.0, 0.0]))
            ring = t[:, None] * d + np.sqrt(1 - t * t)[:, None] * side
            mean = 0.5 * w @ hazel.irradiance_l1_nonlinear(coeffs, unit(ring))
            assert mean == pytest.approx(float(r0), rel=GEOMERICS_MEAN_TOLERANCE)

    def test_single_light_ends(self):
        """r = 1 (one delta): a = 0, p = 3, zero irradiance opposite the light; linear L1 goes to -R0 there."""
        d = unit([0.3, -0.4, 0.5])
        coeffs = sh.basis(d, 2)[:, None] * 4 * math.pi
        g = hazel.geomerics_parameters(coeffs)
        assert g["r"][0] == pytest.approx(1.0, rel=IDENTITY_TOLERANCE)
        assert g["p"][0] == pytest.approx(3.0, rel=IDENTITY_TOLERANCE)
        assert hazel.irradiance_l1_nonlinear(coeffs, -d)[0] == pytest.approx(0.0, abs=IDENTITY_TOLERANCE)
        assert hazel.irradiance(coeffs, -d)[0] == pytest.approx(-1.0, rel=IDENTITY_TOLERANCE)

    def test_uniform_upper_hemisphere(self):
        """Linear L1 is exact for a uniform hemisphere, I = L (1 + n_z) / 2; the model gives L (1/6 + q^2)."""
        c = sh.project(lambda d: np.ones(d.shape[0]), 2, hemisphere=True)  # L = 1
        normals = random_unit_vectors(30, 17)
        np.testing.assert_allclose(hazel.irradiance(c, normals), (1 + normals[:, 2]) / 2, atol=ROUTE_TOLERANCE)
        q = (1 + normals[:, 2]) / 2
        np.testing.assert_allclose(hazel.irradiance_l1_nonlinear(c, normals), 1 / 6 + q**2, rtol=IDENTITY_TOLERANCE)

    def test_uniform_light_and_zero(self):
        c = np.zeros((4, 2))
        c[0, 0] = 2 * math.sqrt(math.pi) * 5.0
        out = hazel.irradiance_l1_nonlinear(c, random_unit_vectors(10, 12))
        np.testing.assert_allclose(out[:, 0], 5.0, rtol=ROUTE_TOLERANCE)
        np.testing.assert_array_equal(out[:, 1], 0.0)

    def test_unphysical_input_stays_finite(self):
        c = np.array([[-1.0], [3.0], [0.0], [0.0]])
        out = hazel.irradiance_l1_nonlinear(c, random_unit_vectors(10, 13))
        assert np.all(np.isfinite(out))
        with pytest.raises(ValueError, match=r"coeffs must .* K = N\*\*2, N in \[2, 3\] \(K in \(4, 9\)\)"):
            hazel.irradiance_l1_nonlinear(np.ones((1, 3)), [0.0, 0.0, 1.0])

    def test_n_dimensional(self):
        coeffs = np.abs(np.random.default_rng(14).normal(size=(5, 9, 3)))
        coeffs[:, 0] += 5.0
        normals = random_unit_vectors(6, 15)
        batched = hazel.irradiance_l1_nonlinear(coeffs[:, None], normals)
        assert batched.shape == (5, 6, 3)
        np.testing.assert_allclose(batched[2], hazel.irradiance_l1_nonlinear(coeffs[2], normals), rtol=ROUTE_TOLERANCE)
        assert hazel.irradiance_l1_nonlinear(coeffs[0, :, 0], normals).shape == (6,)
