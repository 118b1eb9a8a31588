"""
Tests of :mod:`skysh.sh.basis`
========================

Every expected value comes from a route independent of skysh: scipy's complex
``sph_harm_y`` turned real, the closed forms of ``docs/conventions.md`` typed from its
table, exact polynomial integrals of :mod:`numpy.polynomial.legendre`, the
definition of a rotated function evaluated point by point, or identities
(orthonormality, composition, norm preservation, linearity).

scipy's route is :func:`conftest.scipy_real_sh`, shared with the other tests.
One class per public function; each has a reference-value test, an
n-dimensional (batched shapes) test and a NaN / inf test where the function
takes arrays. Every tolerance is a named constant with the reason for its size.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from conftest import EPS, random_unit_vectors, scipy_real_sh
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from numpy.polynomial import legendre as npleg

from skysh.model import preetham
from skysh.sh import basis as sh

BASIS_SCIPY_ATOL: float = 64 * 16 * EPS
"""|sh.basis - scipy| at l <= 15 (values up to 1.6): both routes lose about one
ulp per recurrence step over 16 bands; measured worst 2.6e-14 = 118 eps, allowed
64 * 16 eps = 2.3e-13."""

CLOSED_FORM_ATOL: float = 8 * EPS
"""Closed forms of l <= 2 are a handful of flops on values <= 1.1."""

GRAM_ATOL_PER_BAND: float = 8 * EPS
"""Orthonormality by the exact quadrature: one rounding per summed product, the
error grows with the number of coefficients; measured <= 19 eps at 16 bands,
allowed 8 eps per band (128 eps at 16 bands)."""

QUADRATURE_EXACT_RTOL: float = 1e-13
"""Quadrature projection of a band-limited function (or of z on the hemisphere)
is exact in exact arithmetic: only rounding of sums over ~10^3 nodes remains."""

ROTATION_RTOL_PER_BAND: float = 16 * EPS
"""Rotations are exact orthogonal maps per band; rounding grows with m * angle in
cos(m a) and with the ~bands-term sums; measured <= 20 eps at 12 bands, allowed
16 eps per band (relative to max |c|)."""

MC_SIGMAS: float = 5.0
"""Random projections must land within 5 standard errors of the exact
coefficient (computed exactly, per coefficient): a false alarm has probability
below 1e-6 per coefficient, and the seeds are fixed anyway."""

MC_RATE_BOUNDS: tuple[float, float] = (3.2, 5.0)
"""RMS error ratio of plain Monte Carlo between n and 16 n samples: sqrt(16) = 4
expected; RMS over 32 seeds x 16 coefficients scatters by about 3 %, so +-20 %
is more than 5 standard deviations."""

STRATIFIED_MIN_RATIO: float = 10.0
"""Jittered stratification converges as n^-1 for smooth integrands (ratio 16 at
16 n; measured 14.5), clearly faster than Monte Carlo's 4."""

QMC_MIN_RATIO: float = 30.0
"""Scrambled Sobol converges close to n^-1.5 for smooth integrands (ratio 64 at
16 n; measured 64), clearly faster than Monte Carlo's 4."""

SKY_QUADRATURE_MIN_RATIO: float = 4.0
"""The plain product rule on the sky (kink at the sun) converges as n_theta^-3:
measured error ratio 7.5 - 9 per doubling of n_theta; 4 still proves an order
above n_theta^-2."""

SKY_PROJECT_N_THETA: int = 64
"""Nodes in z of the product rule used for the moved-sun test (8,192 directions)."""

SKY_PROJECT_RTOL: float = 2e-4
"""Moved sun vs rotated projection at a generic azimuth: both projections carry
the product rule's discretisation error, measured <= 1.8e-5 of the DC term at
n_theta = 64 (against the converged sky, any sun, T 2.5 - 6); their difference
measured <= 3.1e-5 (worst: an azimuth half a node spacing off); allowed 2e-4."""

SKY_PROJECT_ALIGNED_RTOL: float = 1e-12
"""Moved sun by a multiple of the azimuth node spacing: the rule maps onto
itself, so only rounding (sums over 8,192 nodes, arccos near the sun) remains."""

IRRADIANCE_RTOL: float = 1e-12
"""Irradiance of constant / linear radiance is exact in SH (band-limited to
l <= 1) and the projection is exact quadrature: rounding only."""

UNIT_NORM_ATOL: float = 4 * EPS
"""|norm - 1| of a unit vector built from sines and cosines (three rounded squares, a sum
and a square root): a few half-ulps of 1; measured 0.5 eps."""

SMALL_EVAL_ATOL: float = 16 * EPS
"""A handful of products and sums on values <= 3 (ulp(3) = 2 eps): closed-form coefficients
of 1 + 2 z evaluated, a 3x3 rotation applied to a unit lobe; measured <= 2 eps."""

MATRIX_ATOL: float = 4 * EPS
"""Entries of a 3x3 rotation from one cosine and one sine (and R R^T, det R: three products
summed): one rounding of values <= 1 per step; measured 0.5 eps."""

LINEARITY_ATOL_PER_TERM: float = 64 * EPS
"""evaluate(a c1 + b c2) vs a evaluate(c1) + b evaluate(c2), per unit of the test's scale
(16 x the largest |a c|, |b c| plus 1): each side sums 16 basis products rounded at ~1 ulp of
that scale, and the basis values carry a few ulp of their recurrence."""

BATCH_ATOL: float = 4 * EPS
"""The same values through another array shape: a (M, K) @ (K, C) product may sum its K terms
in another order (BLAS blocking) than one column of it, about 1 ulp per partial sum; absolute on
evaluated values <= 2.8 (measured <= 1 eps), relative to max |c| for rotated coefficients
(measured <= 0.5 eps)."""

ROTATED_EVAL_ATOL_PER_BAND: float = 64 * EPS
"""f(R^T w) by evaluating at moved points vs evaluating the rotated coefficients, per band and per
unit of sum |c|: both sides carry the basis' recurrence rounding (~1 ulp per band) on every
term; measured 0.36 eps per band of sum |c|."""

PROJECT_LINEARITY_RTOL: float = 1e-12
"""project(a f + b g) vs a project(f) + b project(g), relative to (|a| + |b| + 1) 4 pi: the
same 1,024-sample weighted sums in another order, ~sqrt(1024) ulp of the terms (|f|, |g| <= e,
|Y| <= 1.1), far below 1e-12."""

PROJECT_CHANNELS_ATOL: float = 1e-14
"""One channel of a three-channel projection vs the single-channel projection of the same
function: a (n, 9) x (n, 3) product summed in another order than (n, 9) x (n,); 1,024 terms of
size <= e x 1.1 x 4 pi / n; measured 7.1e-15 (8 ulp of the largest coefficient, 4.2)."""

CONSTANT_DC_ATOL: float = 1e-14
"""The DC coefficient of f = 1 by any method: sum of n equal weights times Y_00 = sqrt(4 pi) = 3.5;
every rule's weights sum to the area exactly up to rounding of the sum; measured <= 2 eps (4.4e-16)."""

CLOSED_FORM_TABLE_ATOL: float = 4 * EPS
"""A_l and c(l, 0) typed as fractions of pi vs skysh's values: one division or multiplication each
on values <= pi (ulp(pi) = 2 eps); measured 0."""

ANALYTIC_LOBE_ATOL: float = 16 * EPS
"""A_l vs sqrt(4 pi / (2l + 1)) x the exact Legendre-series integral up to l = 15: a square root,
a product and the series' rounding (~l terms of size <= 1)."""

CLAMPED_COSINE_TAIL: float = 1e-3
"""2 pi / 3 - E(+z) of max(0, z) truncated to 16 bands: the even terms A_l c_l0 Y_l0(+z) fall
as l^-4, so the missing tail falls as l^-3: 1.6e-2, 1.6e-3, 1.8e-4, 2.1e-5 at 4, 8, 16, 32
bands (computed with this test's own clamped_cosine_coefficients); 1e-3 is below the 8-band
error and far below the band-2 term (0.25), so a wrong A_l or a missing band fails."""


# --------------------------------------------------------------------------- #
# Independent references
# --------------------------------------------------------------------------- #
def special_points() -> np.ndarray:
    """The poles, points on the equator and points next to the poles."""
    phi = np.linspace(0.0, 2.0 * np.pi, 13)
    equator = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=-1)
    tiny = 1e-9
    near = np.array([[tiny, 0.0, math.sqrt(1 - tiny**2)], [0.0, -tiny, -math.sqrt(1 - tiny**2)]])
    return np.concatenate([[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], equator, near])


def closed_form_sh(dirs: np.ndarray) -> np.ndarray:
    """The l <= 2 table of docs/conventions.md, typed from it, (M, 9)."""
    x, y, z = dirs[:, 0], dirs[:, 1], dirs[:, 2]
    sp = math.sqrt(math.pi)
    return np.stack(
        [
            np.full_like(x, 1.0 / (2.0 * sp)),
            -math.sqrt(3.0) / (2.0 * sp) * y,
            math.sqrt(3.0) / (2.0 * sp) * z,
            -math.sqrt(3.0) / (2.0 * sp) * x,
            math.sqrt(15.0) / (2.0 * sp) * x * y,
            -math.sqrt(15.0) / (2.0 * sp) * y * z,
            math.sqrt(5.0) / (4.0 * sp) * (3.0 * z * z - 1.0),
            -math.sqrt(15.0) / (2.0 * sp) * x * z,
            math.sqrt(15.0) / (4.0 * sp) * (x * x - y * y),
        ],
        axis=-1,
    )


COSINE_LOBE_TABLE: tuple[float, ...] = (
    math.pi,
    2.0 * math.pi / 3.0,
    math.pi / 4.0,
    0.0,
    -math.pi / 24.0,
    0.0,
    math.pi / 64.0,
)
"""A_0 .. A_6 typed from docs/conventions.md."""


def clamped_cosine_coefficients(bands: int) -> np.ndarray:
    """Exact SH coefficients of max(0, z), (bands**2,): zonal only.

    c(l, 0) = integral over z > 0 of z Y_l0 = 2 pi sqrt((2l+1)/(4 pi)) integral_0^1 z P_l(z) dz,
    the last integral done exactly on Legendre-series polynomials.
    """
    c = np.zeros(bands * bands)
    for l in range(bands):
        poly = npleg.legmul(npleg.Legendre.basis(l).coef, [0.0, 1.0])  # z P_l(z)
        antiderivative = npleg.legint(poly)
        integral = npleg.legval(1.0, antiderivative) - npleg.legval(0.0, antiderivative)
        c[l * l + l] = 2.0 * math.pi * math.sqrt((2 * l + 1) / (4.0 * math.pi)) * integral
    return c


def rotation_from_quaternion(q: np.ndarray) -> np.ndarray:
    """Proper rotation matrix of a (not necessarily normalised) quaternion (w, x, y, z)."""
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def band_norms(coeffs: np.ndarray, bands: int) -> np.ndarray:
    """Euclidean norm of every band (over its 2l+1 coefficients and the channels)."""
    return np.array([np.linalg.norm(coeffs[l * l : (l + 1) ** 2]) for l in range(bands)])


quaternions = hnp.arrays(np.float64, 4, elements=st.floats(-1.0, 1.0, allow_subnormal=False)).filter(
    lambda q: np.linalg.norm(q) > 0.1
)
unit_vectors = hnp.arrays(np.float64, 3, elements=st.floats(-1.0, 1.0, allow_subnormal=False)).filter(
    lambda v: np.linalg.norm(v) > 0.1
).map(lambda v: v / np.linalg.norm(v))


def coefficient_arrays(bands: int, channels: int = 3):
    return hnp.arrays(
        np.float64, (bands * bands, channels), elements=st.floats(-1e3, 1e3, allow_subnormal=False)
    )


# --------------------------------------------------------------------------- #
# Index layout
# --------------------------------------------------------------------------- #
class TestNCoeffs:
    def test_reference_values(self):
        assert [sh.n_coeffs(b) for b in (1, 2, 3, 7, 64)] == [1, 4, 9, 49, 4096]

    @pytest.mark.parametrize("bad", [0, 65, -1, 2.0, "3", True, None])
    def test_invalid(self, bad):
        with pytest.raises(ValueError, match="bands"):
            sh.n_coeffs(bad)

    def test_numpy_integer(self):
        assert sh.n_coeffs(np.int64(5)) == 25


class TestIndex:
    def test_reference_values(self):
        # docs/conventions.md table: i = l (l + 1) + m.
        expected = {(0, 0): 0, (1, -1): 1, (1, 0): 2, (1, 1): 3, (2, -2): 4, (2, 0): 6, (2, 2): 8, (15, 15): 255}
        for (l, m), i in expected.items():
            assert sh.index(l, m) == i

    def test_layout_comprehension(self):
        layout = [(l, m) for l in range(16) for m in range(-l, l + 1)]
        assert [sh.index(l, m) for l, m in layout] == list(range(256))

    @given(st.integers(0, 63).flatmap(lambda l: st.tuples(st.just(l), st.integers(-l, l))))
    def test_round_trip(self, lm_pair):
        assert sh.lm(sh.index(*lm_pair)) == lm_pair

    @pytest.mark.parametrize("l, m", [(-1, 0), (1, 2), (2, -3)])
    def test_invalid(self, l, m):
        with pytest.raises(ValueError):
            sh.index(l, m)


class TestLm:
    def test_reference_values(self):
        expected = [(0, 0), (1, -1), (1, 0), (1, 1), (2, -2), (2, -1), (2, 0), (2, 1), (2, 2)]
        assert [sh.lm(i) for i in range(9)] == expected

    @given(st.integers(0, 64 * 64 - 1))
    def test_round_trip(self, i):
        l, m = sh.lm(i)
        assert abs(m) <= l and sh.index(l, m) == i

    def test_invalid(self):
        with pytest.raises(ValueError, match=r"i must be an integer in \[0, 4095\]"):
            sh.lm(-1)


# --------------------------------------------------------------------------- #
# Quadrature rule
# --------------------------------------------------------------------------- #
class TestQuadratureRule:
    @pytest.mark.parametrize("hemisphere, area", [(False, 4 * math.pi), (True, 2 * math.pi)])
    def test_reference_values(self, hemisphere, area):
        dirs, weights = sh.quadrature_rule(12, hemisphere)
        assert dirs.shape == (2 * 12**2, 3) and weights.shape == (2 * 12**2,)
        np.testing.assert_allclose(weights.sum(), area, rtol=QUADRATURE_EXACT_RTOL)
        np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, rtol=0, atol=UNIT_NORM_ATOL)
        assert (weights > 0).all()
        if hemisphere:
            assert (dirs[:, 2] >= 0).all()

    @pytest.mark.parametrize("hemisphere", [False, True])
    def test_exact_for_polynomials(self, hemisphere):
        # integral of z^k over the sphere is 4 pi / (k + 1) for even k, 0 for odd;
        # over the upper hemisphere 2 pi / (k + 1). Exact up to degree 2 n - 1.
        n = 6
        dirs, weights = sh.quadrature_rule(n, hemisphere)
        for k in range(2 * n):
            exact = 2 * math.pi / (k + 1) if hemisphere else (4 * math.pi / (k + 1) if k % 2 == 0 else 0.0)
            assert abs(weights @ dirs[:, 2] ** k - exact) < QUADRATURE_EXACT_RTOL * 4 * math.pi
        # x^2 y^2 (a product of l = 2 harmonics): 4 pi / 15 over the sphere.
        if not hemisphere:
            assert abs(weights @ (dirs[:, 0] ** 2 * dirs[:, 1] ** 2) - 4 * math.pi / 15) < QUADRATURE_EXACT_RTOL

    def test_read_only(self):
        dirs, weights = sh.quadrature_rule(5)
        assert not dirs.flags.writeable and not weights.flags.writeable

    def test_invalid(self):
        with pytest.raises(ValueError, match="n_theta"):
            sh.quadrature_rule(0)


# --------------------------------------------------------------------------- #
# Basis
# --------------------------------------------------------------------------- #
class TestBasis:
    def test_against_scipy(self):
        dirs = np.concatenate([random_unit_vectors(500, seed=1), special_points()])
        got = sh.basis(dirs, 16)
        np.testing.assert_allclose(got, scipy_real_sh(dirs, 16), rtol=0, atol=BASIS_SCIPY_ATOL)

    def test_poles_and_equator(self):
        dirs = special_points()[:15]  # both poles and the equator
        np.testing.assert_allclose(sh.basis(dirs, 16), scipy_real_sh(dirs, 16), rtol=0, atol=BASIS_SCIPY_ATOL)
        poles = sh.basis(dirs[:2], 16)
        for i in range(256):
            l, m = sh.lm(i)
            if m != 0:  # every m != 0 harmonic vanishes on the axis
                assert poles[0, i] == 0.0 and poles[1, i] == 0.0
            else:  # Y_l0(+z) = sqrt((2l+1)/(4 pi)), Y_l0(-z) = (-1)^l of it
                expected = math.sqrt((2 * l + 1) / (4 * math.pi))
                assert abs(poles[0, i] - expected) < BASIS_SCIPY_ATOL
                assert abs(poles[1, i] - (-1) ** l * expected) < BASIS_SCIPY_ATOL

    def test_closed_forms(self):
        dirs = np.concatenate([random_unit_vectors(200, seed=2), special_points()])
        np.testing.assert_allclose(sh.basis(dirs, 3), closed_form_sh(dirs), rtol=0, atol=CLOSED_FORM_ATOL)

    def test_sign_convention(self):
        # Condon-Shortley: Y(1, 1) = -c x is negative at +x, Y(1, -1) negative at +y.
        assert sh.basis([1.0, 0.0, 0.0], 2)[3] < 0 and sh.basis([0.0, 1.0, 0.0], 2)[1] < 0

    @pytest.mark.parametrize("bands", [1, 2, 5, 9, 16])
    def test_orthonormal(self, bands):
        dirs, weights = sh.quadrature_rule(bands)  # the smallest exact rule for Y_i Y_j
        y = sh.basis(dirs, bands)
        gram = (y * weights[:, None]).T @ y
        np.testing.assert_allclose(gram, np.eye(bands * bands), rtol=0, atol=GRAM_ATOL_PER_BAND * bands)

    def test_prefix_consistency(self):
        dirs = random_unit_vectors(50, seed=3)
        np.testing.assert_array_equal(sh.basis(dirs, 16)[:, :49], sh.basis(dirs, 7))

    def test_n_dimensional(self):
        dirs = random_unit_vectors(24, seed=4)
        flat = sh.basis(dirs, 4)
        assert sh.basis(dirs[0], 4).shape == (16,)
        np.testing.assert_array_equal(sh.basis(dirs[0], 4), flat[0])
        np.testing.assert_array_equal(sh.basis(dirs.reshape(2, 3, 4, 3), 4), flat.reshape(2, 3, 4, 16))
        assert sh.basis(np.zeros((0, 3)), 4).shape == (0, 16)

    @pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
    def test_nan_inf(self, bad):
        with pytest.raises(ValueError, match="dirs"):
            sh.basis([[0.0, 0.0, 1.0], [bad, 0.0, 0.0]], 3)

    @pytest.mark.parametrize("dirs", [[0.0, 1.0], [[1.0, 0.0, 0.0, 0.0]], [0.0, 0.0, 2.0], [0.0, 0.0, 0.0], 1.0])
    def test_invalid_dirs(self, dirs):
        with pytest.raises(ValueError, match="dirs"):
            sh.basis(dirs, 3)

    @pytest.mark.parametrize("bands", [0, 65, 3.0, "3", None])
    def test_invalid_bands(self, bands):
        with pytest.raises(ValueError, match="bands"):
            sh.basis([0.0, 0.0, 1.0], bands)


# --------------------------------------------------------------------------- #
# Evaluate
# --------------------------------------------------------------------------- #
LINEARITY_ARGUMENTS = (coefficient_arrays(4), coefficient_arrays(4), st.floats(-10, 10, allow_subnormal=False),
                       st.floats(-10, 10, allow_subnormal=False), unit_vectors)

LINEARITY_EXAMPLES: dict[str, int] = {"core": 15, "slow": 50}
"""Hypothesis examples of TestEvaluate's linearity in the core run (``-m "not slow"``) and in its ``slow`` twin:
each example draws two arrays through hypothesis.extra.numpy, most of the test's time."""


class TestEvaluate:
    def test_reference_values(self):
        dirs = random_unit_vectors(40, seed=5)
        closed = closed_form_sh(dirs)
        for i in range(9):
            c = np.zeros(9)
            c[i] = 1.0
            np.testing.assert_allclose(sh.evaluate(c, dirs), closed[:, i], rtol=0, atol=CLOSED_FORM_ATOL)
        # A known function: f = 1 + 2 z has c0 = sqrt(4 pi), c(1,0) = 2 sqrt(4 pi / 3).
        c = np.zeros(4)
        c[0], c[2] = math.sqrt(4 * math.pi), 2 * math.sqrt(4 * math.pi / 3)
        np.testing.assert_allclose(sh.evaluate(c, dirs), 1 + 2 * dirs[:, 2], rtol=0, atol=SMALL_EVAL_ATOL)

    @staticmethod
    def _linearity(c1, c2, a, b, d):
        lhs = sh.evaluate(a * c1 + b * c2, d)
        rhs = a * sh.evaluate(c1, d) + b * sh.evaluate(c2, d)
        scale = (abs(a) * np.abs(c1).max() + abs(b) * np.abs(c2).max() + 1.0) * 16
        np.testing.assert_allclose(lhs, rhs, rtol=0, atol=LINEARITY_ATOL_PER_TERM * scale)

    @settings(max_examples=LINEARITY_EXAMPLES["core"], deadline=None)
    @given(*LINEARITY_ARGUMENTS)
    def test_linearity(self, c1, c2, a, b, d):
        self._linearity(c1, c2, a, b, d)

    @pytest.mark.slow
    @settings(max_examples=LINEARITY_EXAMPLES["slow"], deadline=None)
    @given(*LINEARITY_ARGUMENTS)
    def test_linearity_full(self, c1, c2, a, b, d):
        self._linearity(c1, c2, a, b, d)

    def test_n_dimensional(self):
        dirs = random_unit_vectors(12, seed=6)
        c = np.random.default_rng(6).normal(size=(16, 3))
        flat = sh.evaluate(c, dirs)
        assert flat.shape == (12, 3)
        np.testing.assert_allclose(sh.evaluate(c, dirs.reshape(3, 4, 3)), flat.reshape(3, 4, 3), rtol=0, atol=BATCH_ATOL)
        np.testing.assert_allclose(sh.evaluate(c[:, 1], dirs), flat[:, 1], rtol=0, atol=BATCH_ATOL)
        assert sh.evaluate(c, dirs[0]).shape == (3,)

    @pytest.mark.parametrize("bad", [np.nan, np.inf])
    def test_nan_inf(self, bad):
        c = np.zeros(4)
        c[1] = bad
        with pytest.raises(ValueError, match="coeffs"):
            sh.evaluate(c, [0.0, 0.0, 1.0])
        with pytest.raises(ValueError, match="dirs"):
            sh.evaluate(np.zeros(4), [0.0, bad, 1.0])

    @pytest.mark.parametrize("coeffs", [np.zeros(5), np.zeros((2, 4, 3)), 1.0])
    def test_invalid(self, coeffs):
        with pytest.raises(ValueError, match="coeffs"):
            sh.evaluate(coeffs, [0.0, 0.0, 1.0])


# --------------------------------------------------------------------------- #
# Project
# --------------------------------------------------------------------------- #
def _sky(sun_zenith: float, sun_azimuth: float, turbidity: float):
    return lambda d: preetham.radiance(d, sun_zenith, sun_azimuth, turbidity)


def _exact_standard_error(f, exact: np.ndarray, bands: int, hemisphere: bool, n: int) -> np.ndarray:
    """Standard error of the plain Monte Carlo estimate of every coefficient.

    The estimator is A f(w) Y_i(w), w uniform on the domain of area A: its
    variance is A integral f^2 Y_i^2 - c_i^2, integrated exactly by a product
    rule with enough nodes (f^2 Y_i^2 is a polynomial of degree <= 4 bands here).
    """
    dirs, weights = sh.quadrature_rule(2 * bands + 4, hemisphere)
    area = 2 * math.pi if hemisphere else 4 * math.pi
    second_moment = (sh.basis(dirs, bands) ** 2 * weights[:, None]).T @ (np.asarray(f(dirs)) ** 2)
    return np.sqrt(np.maximum(area * second_moment - exact**2, 0.0) / n)


def _single(bands: int, i: int) -> np.ndarray:
    c = np.zeros(bands * bands)
    c[i] = 1.0
    return c


KNOWN_FUNCTIONS = {
    # name: (f, exact coefficients of 4 bands, hemisphere)
    "constant": (lambda d: np.full(d.shape[0], 2.5), 2.5 * math.sqrt(4 * math.pi) * _single(4, 0), False),
    "Y(2,-1)": (lambda d: sh.basis(d, 3)[:, 5], _single(4, 5), False),
    "Y(3,2)": (lambda d: sh.basis(d, 4)[:, 14], _single(4, 14), False),
    "max(0,z) on the hemisphere": (lambda d: np.maximum(0.0, d[:, 2]), clamped_cosine_coefficients(4), True),
}


class TestProject:
    @pytest.mark.parametrize("name", KNOWN_FUNCTIONS)
    def test_quadrature_reference_values(self, name):
        f, exact, hemisphere = KNOWN_FUNCTIONS[name]
        got = sh.project(f, 4, hemisphere=hemisphere)
        np.testing.assert_allclose(got, exact, rtol=0, atol=QUADRATURE_EXACT_RTOL * max(1.0, np.abs(exact).max()))

    def test_clamped_cosine_analytic(self):
        # Independent check of the reference itself against docs/conventions.md's A_l:
        # c(l, 0) of max(0, z) = sqrt((2l + 1) / (4 pi)) A_l (Funk-Hecke).
        exact = clamped_cosine_coefficients(7)
        for l, a in enumerate(COSINE_LOBE_TABLE):
            assert abs(exact[l * l + l] - math.sqrt((2 * l + 1) / (4 * math.pi)) * a) < CLOSED_FORM_TABLE_ATOL
        got = sh.project(lambda d: np.maximum(0.0, d[:, 2]), 7, hemisphere=True)
        np.testing.assert_allclose(got, exact, rtol=0, atol=QUADRATURE_EXACT_RTOL)

    def test_clamped_cosine_full_sphere_converges(self):
        # max(0, z) has a kink at the equator: the full-sphere rule is not exact,
        # but its error must fall as n grows.
        exact = clamped_cosine_coefficients(5)
        f = lambda d: np.maximum(0.0, d[:, 2])  # noqa: E731
        errors = [np.abs(sh.project(f, 5, n=2 * k * k) - exact).max() for k in (9, 17, 33, 65)]
        assert all(later < earlier / 2 for earlier, later in itertools.pairwise(errors)), errors

    @pytest.mark.parametrize("method", ["mc", "stratified", "qmc"])
    @pytest.mark.parametrize("name", KNOWN_FUNCTIONS)
    def test_random_methods_known_coefficients(self, method, name):
        f, exact, hemisphere = KNOWN_FUNCTIONS[name]
        n = 4096
        got = sh.project(f, 4, method=method, n=n, seed=11, hemisphere=hemisphere)
        se = _exact_standard_error(f, exact, 4, hemisphere, n)
        assert np.all(np.abs(got - exact) <= MC_SIGMAS * se + QUADRATURE_EXACT_RTOL), (got - exact) / se

    def test_convergence_rates(self):
        exact = np.random.default_rng(12).normal(size=16)  # a smooth band-limited function
        f = lambda d: sh.basis(d, 4) @ exact  # noqa: E731

        def rms(method, n):
            errors = [sh.project(f, 4, method=method, n=n, seed=s) - exact for s in range(32)]
            return float(np.sqrt(np.mean(np.square(errors))))

        n = 1024  # a power of two and a square: no rounding of n by any method
        results = {m: (rms(m, n), rms(m, 16 * n)) for m in ("mc", "stratified", "qmc")}
        ratios = {m: a / b for m, (a, b) in results.items()}
        assert MC_RATE_BOUNDS[0] < ratios["mc"] < MC_RATE_BOUNDS[1], ratios
        assert ratios["stratified"] > STRATIFIED_MIN_RATIO, ratios
        assert ratios["qmc"] > QMC_MIN_RATIO, ratios
        for m in ("stratified", "qmc"):  # and smaller errors at both sizes
            assert results[m][0] < results["mc"][0] and results[m][1] < results["mc"][1], results

    @pytest.mark.parametrize("method", ["mc", "stratified", "qmc"])
    def test_reproducible(self, method):
        f = lambda d: np.exp(d[:, 0]) * (1 + d[:, 2] ** 2)  # noqa: E731
        a = sh.project(f, 5, method=method, n=2000, seed=3)
        b = sh.project(f, 5, method=method, n=2000, seed=3)
        c = sh.project(f, 5, method=method, n=2000, seed=4)
        np.testing.assert_array_equal(a, b)
        assert not np.array_equal(a, c)

    def test_sky_quadrature_converges(self):
        # The plain product rule on the Preetham sky, against the sun-adapted
        # reference (itself checked to 1e-7 in test_preetham.py).
        for sun_zenith, turbidity in ((0.0, 2.5), (1.0, 6.0), (math.pi / 2, 4.0)):
            reference = preetham.sky_sh(sun_zenith, turbidity, 7)
            sky = _sky(sun_zenith, 0.0, turbidity)
            errors = [
                (np.abs(sh.project(sky, 7, n=2 * k * k, hemisphere=True) - reference).max(0) / reference[0]).max()
                for k in (16, 32, 64, 128)
            ]
            assert all(later < earlier / SKY_QUADRATURE_MIN_RATIO for earlier, later in itertools.pairwise(errors)), errors

    @settings(max_examples=25, deadline=None)
    @given(
        st.sampled_from(sh.PROJECTION_METHODS),
        st.floats(-10, 10, allow_subnormal=False),
        st.floats(-10, 10, allow_subnormal=False),
        st.booleans(),
    )
    def test_linearity(self, method, a, b, hemisphere):
        f = lambda d: np.exp(d[:, 0])  # noqa: E731
        g = lambda d: np.stack([d[:, 2] ** 3, np.cos(3 * d[:, 1])], axis=-1)  # noqa: E731
        kw = dict(method=method, n=1024, seed=5, hemisphere=hemisphere)
        lhs = sh.project(lambda d: a * f(d)[:, None] + b * g(d), 3, **kw)
        rhs = a * sh.project(f, 3, **kw)[:, None] + b * sh.project(g, 3, **kw)
        np.testing.assert_allclose(lhs, rhs, rtol=0, atol=PROJECT_LINEARITY_RTOL * (abs(a) + abs(b) + 1) * 4 * math.pi)

    def test_n_dimensional(self):
        f1 = lambda d: np.exp(d[:, 1])  # noqa: E731
        f3 = lambda d: np.stack([np.exp(d[:, 1]), d[:, 0], 2 * np.exp(d[:, 1])], axis=-1)  # noqa: E731
        for method in sh.PROJECTION_METHODS:
            one = sh.project(f1, 3, method=method, n=1024, seed=1)
            three = sh.project(f3, 3, method=method, n=1024, seed=1)
            assert one.shape == (9,) and three.shape == (9, 3)
            np.testing.assert_allclose(three[:, 0], one, rtol=0, atol=PROJECT_CHANNELS_ATOL)
            np.testing.assert_allclose(three[:, 2], 2 * one, rtol=0, atol=PROJECT_CHANNELS_ATOL)

    def test_sample_counts(self):
        # Stratified rounds n down to a square, qmc up to a power of two: both
        # still integrate the constant exactly (c0 = sqrt(4 pi) for f = 1).
        for method, n in (("stratified", 10), ("qmc", 1000), ("mc", 1)):
            c = sh.project(lambda d: np.ones(d.shape[0]), 2, method=method, n=n, seed=0)
            assert abs(c[0] - math.sqrt(4 * math.pi)) < CONSTANT_DC_ATOL

    def test_invalid(self):
        f = lambda d: d[:, 2]  # noqa: E731
        with pytest.raises(ValueError, match="method"):
            sh.project(f, 3, method="simpson")
        for n in (0, -4, 2.5, True):
            with pytest.raises(ValueError, match="n must be"):
                sh.project(f, 3, method="mc", n=n)
        with pytest.raises(ValueError, match="bands"):
            sh.project(f, 0)
        with pytest.raises(ValueError, match="f must return"):
            sh.project(lambda d: np.ones((d.shape[0], 2, 2)), 3)
        with pytest.raises(ValueError, match="f must return"):
            sh.project(lambda d: np.ones(5), 3)


# --------------------------------------------------------------------------- #
# Rotation
# --------------------------------------------------------------------------- #
def habel_rotate_z(c: np.ndarray, angle: float) -> np.ndarray:
    """docs/conventions.md rotation about Z, typed from it: coefficient by coefficient."""
    out = c.copy()
    bands = math.isqrt(c.shape[0])
    for l in range(1, bands):
        for m in range(1, l + 1):
            p, q = l * (l + 1) + m, l * (l + 1) - m
            out[p] = c[p] * math.cos(m * angle) - c[q] * math.sin(m * angle)
            out[q] = c[q] * math.cos(m * angle) + c[p] * math.sin(m * angle)
    return out


class TestRotationZMatrix:
    def test_reference_values(self):
        np.testing.assert_allclose(sh.rotation_z_matrix(math.pi / 2) @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], rtol=0, atol=MATRIX_ATOL)
        r = sh.rotation_z_matrix(0.3)
        np.testing.assert_allclose(r @ r.T, np.eye(3), rtol=0, atol=MATRIX_ATOL)
        assert abs(np.linalg.det(r) - 1.0) < MATRIX_ATOL and r[2, 2] == 1.0


class TestRotateZ:
    def test_reference_values(self):
        c = np.random.default_rng(20).normal(size=(36, 3))
        for angle in (0.0, 0.4, -2.0, math.pi, 7.5):
            np.testing.assert_allclose(sh.rotate_z(c, angle), habel_rotate_z(c, angle), rtol=0,
                                       atol=ROTATION_RTOL_PER_BAND * math.isqrt(c.shape[0]) * np.abs(c).max())

    def test_definition(self):
        # The rotated coefficients describe f(Rz(a)^T w): a lobe at azimuth 0 moves to azimuth a.
        bands, angle = 6, 0.9
        c = np.random.default_rng(21).normal(size=bands * bands)
        dirs = random_unit_vectors(100, seed=21)
        moved = dirs @ sh.rotation_z_matrix(angle)  # rows R^T w
        np.testing.assert_allclose(sh.evaluate(sh.rotate_z(c, angle), dirs), sh.evaluate(c, moved), rtol=0,
                                   atol=ROTATED_EVAL_ATOL_PER_BAND * bands * np.abs(c).sum())
        y11 = _single(2, 3)  # -x lobe: turned by +90 deg it becomes the -y lobe Y(1,-1)
        np.testing.assert_allclose(sh.rotate_z(y11, math.pi / 2), _single(2, 1), rtol=0, atol=MATRIX_ATOL)

    def test_matches_rotate(self):
        c = np.random.default_rng(22).normal(size=(64, 3))
        for angle in (0.25, -1.3, 3.0):
            np.testing.assert_allclose(sh.rotate(c, sh.rotation_z_matrix(angle)), sh.rotate_z(c, angle), rtol=0,
                                       atol=ROTATION_RTOL_PER_BAND * math.isqrt(c.shape[0]) * np.abs(c).max())

    def test_composition_and_inverse(self):
        c = np.random.default_rng(23).normal(size=(49, 3))
        tol = ROTATION_RTOL_PER_BAND * math.isqrt(c.shape[0]) * np.abs(c).max()
        np.testing.assert_allclose(sh.rotate_z(sh.rotate_z(c, 0.7), 1.1), sh.rotate_z(c, 1.8), rtol=0, atol=tol)
        np.testing.assert_allclose(sh.rotate_z(sh.rotate_z(c, 0.7), -0.7), c, rtol=0, atol=tol)
        np.testing.assert_allclose(sh.rotate_z(c, 2 * math.pi), c, rtol=0, atol=tol)

    def test_n_dimensional(self):
        rng = np.random.default_rng(24)
        c = rng.normal(size=(16, 3))
        angles = rng.uniform(-4, 4, size=(2, 5))
        batched = sh.rotate_z(c, angles)
        assert batched.shape == (2, 5, 16, 3)
        for idx in np.ndindex(angles.shape):
            np.testing.assert_array_equal(batched[idx], sh.rotate_z(c, angles[idx]))
        # batched coefficients with matching angles, vector coefficients with an angle array
        cb = rng.normal(size=(5, 16, 3))
        out = sh.rotate_z(cb, angles[0])
        assert out.shape == (5, 16, 3)
        for k in range(5):
            np.testing.assert_array_equal(out[k], sh.rotate_z(cb[k], angles[0, k]))
        vec = sh.rotate_z(c[:, 0], angles[0])
        assert vec.shape == (5, 16)
        np.testing.assert_allclose(vec, batched[0, :, :, 0], rtol=0, atol=0)
        assert sh.rotate_z(c[:, 0], 0.3).shape == (16,)

    @pytest.mark.parametrize("bad", [np.nan, np.inf])
    def test_nan_inf(self, bad):
        with pytest.raises(ValueError, match="angle"):
            sh.rotate_z(np.zeros(9), bad)
        with pytest.raises(ValueError, match="coeffs"):
            sh.rotate_z(np.full(9, bad), 0.1)

    def test_invalid(self):
        with pytest.raises(ValueError, match="coeffs"):
            sh.rotate_z(np.zeros((8, 3)), 0.1)

    def test_moved_sun(self):
        # Projecting the sky with its sun at azimuth phi equals turning the
        # projection of the azimuth-0 sky: the Habel et al. use of eq. 4.
        n = 2 * SKY_PROJECT_N_THETA**2
        spacing = 2 * math.pi / (2 * SKY_PROJECT_N_THETA)  # azimuth step of the product rule
        for sun_zenith, turbidity in ((0.3, 2.5), (1.0, 6.0), (math.pi / 2, 4.0)):
            base = sh.project(_sky(sun_zenith, 0.0, turbidity), 7, hemisphere=True, n=n)
            cases = ((1.234, SKY_PROJECT_RTOL), (-2.0, SKY_PROJECT_RTOL), (5 * spacing, SKY_PROJECT_ALIGNED_RTOL))
            for phi, rtol in cases:
                moved = sh.project(_sky(sun_zenith, phi, turbidity), 7, hemisphere=True, n=n)
                error = (np.abs(sh.rotate_z(base, phi) - moved).max(0) / base[0]).max()
                assert error < rtol, (sun_zenith, turbidity, phi, error)


class TestRotate:
    def test_reference_values(self):
        # The definition: g(w) = f(R^T w).
        bands = 6
        rng = np.random.default_rng(30)
        c = rng.normal(size=(bands * bands, 2))
        r = rotation_from_quaternion(rng.normal(size=4))
        dirs = random_unit_vectors(200, seed=30)
        np.testing.assert_allclose(sh.evaluate(sh.rotate(c, r), dirs), sh.evaluate(c, dirs @ r), rtol=0,
                                   atol=ROTATED_EVAL_ATOL_PER_BAND * bands * np.abs(c).sum(0).max())
        # A z-lobe turned by the rotation taking +z to +x becomes Y(1,1) = -c x: coefficient -1.
        to_x = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
        np.testing.assert_allclose(sh.rotate(_single(2, 2), to_x), -_single(2, 3), rtol=0, atol=SMALL_EVAL_ATOL)

    @settings(max_examples=40, deadline=None)
    @given(quaternions, st.integers(1, 8).flatmap(lambda b: coefficient_arrays(b)))
    def test_band_norms_preserved(self, q, c):
        bands = math.isqrt(c.shape[0])
        rotated = sh.rotate(c, rotation_from_quaternion(q))
        tol = ROTATION_RTOL_PER_BAND * bands * max(1.0, np.abs(c).max()) * math.sqrt(c.size)
        np.testing.assert_allclose(band_norms(rotated, bands), band_norms(c, bands), rtol=0, atol=tol)

    @settings(max_examples=25, deadline=None)
    @given(quaternions, quaternions, st.integers(1, 7).flatmap(lambda b: coefficient_arrays(b)))
    def test_composition_and_inverse(self, q1, q2, c):
        bands = math.isqrt(c.shape[0])
        r1, r2 = rotation_from_quaternion(q1), rotation_from_quaternion(q2)
        tol = 4 * ROTATION_RTOL_PER_BAND * bands * max(1.0, np.abs(c).max()) * math.sqrt(2 * bands + 1)
        np.testing.assert_allclose(sh.rotate(sh.rotate(c, r1), r2), sh.rotate(c, r2 @ r1), rtol=0, atol=tol)
        np.testing.assert_allclose(sh.rotate(sh.rotate(c, r1), r1.T), c, rtol=0, atol=tol)

    @settings(max_examples=25, deadline=None)
    @given(st.floats(-10, 10, allow_subnormal=False), st.integers(1, 8).flatmap(lambda b: coefficient_arrays(b)))
    def test_matches_rotate_z(self, angle, c):
        bands = math.isqrt(c.shape[0])
        tol = ROTATION_RTOL_PER_BAND * bands * (1 + abs(angle)) * max(1.0, np.abs(c).max())
        np.testing.assert_allclose(sh.rotate(c, sh.rotation_z_matrix(angle)), sh.rotate_z(c, angle), rtol=0, atol=tol)

    def test_n_dimensional(self):
        rng = np.random.default_rng(31)
        c = rng.normal(size=(2, 3, 25, 3))
        r = rotation_from_quaternion(rng.normal(size=4))
        out = sh.rotate(c, r)
        assert out.shape == c.shape
        for idx in np.ndindex(2, 3):
            np.testing.assert_allclose(out[idx], sh.rotate(c[idx], r), rtol=0, atol=BATCH_ATOL * np.abs(c).max())
        np.testing.assert_allclose(sh.rotate(c[0, 0, :, 1], r), out[0, 0, :, 1], rtol=0, atol=BATCH_ATOL * np.abs(c).max())

    @pytest.mark.parametrize("bad", [np.nan, np.inf])
    def test_nan_inf(self, bad):
        r = np.eye(3)
        r[0, 1] = bad
        with pytest.raises(ValueError, match="R"):
            sh.rotate(np.zeros(9), r)
        with pytest.raises(ValueError, match="coeffs"):
            sh.rotate(np.full(9, bad), np.eye(3))

    @pytest.mark.parametrize("r", [np.diag([1.0, 1.0, -1.0]), 2 * np.eye(3), np.eye(2), np.eye(4)])
    def test_invalid(self, r):
        with pytest.raises(ValueError, match="R"):
            sh.rotate(np.zeros(9), r)


# --------------------------------------------------------------------------- #
# Convolution and irradiance
# --------------------------------------------------------------------------- #
class TestConvolve:
    def test_reference_values(self):
        c = np.arange(9.0)
        expected = np.array([0.0, 2 * 1, 2 * 2, 2 * 3, 3 * 4, 3 * 5, 3 * 6, 3 * 7, 3 * 8])
        np.testing.assert_array_equal(sh.convolve(c, [1.0, 2.0, 3.0, 99.0]), expected)

    def test_n_dimensional(self):
        c = np.random.default_rng(40).normal(size=(4, 2, 9, 3))
        k = [1.0, -0.5, 0.25]
        out = sh.convolve(c, k)
        assert out.shape == c.shape
        np.testing.assert_array_equal(out[1, 1, :, 2], sh.convolve(c[1, 1, :, 2], k))

    @pytest.mark.parametrize("bad", [np.nan, np.inf])
    def test_nan_inf(self, bad):
        with pytest.raises(ValueError, match="per_band"):
            sh.convolve(np.zeros(4), [1.0, bad])
        with pytest.raises(ValueError, match="coeffs"):
            sh.convolve(np.full(4, bad), [1.0, 1.0])

    def test_invalid(self):
        with pytest.raises(ValueError, match="per_band"):
            sh.convolve(np.zeros(9), [1.0, 2.0])
        with pytest.raises(ValueError, match="coeffs"):
            sh.convolve(np.zeros(7), [1.0, 2.0, 3.0])


class TestCosineLobe:
    def test_reference_values(self):
        np.testing.assert_allclose(sh.cosine_lobe(7), COSINE_LOBE_TABLE, rtol=0, atol=CLOSED_FORM_TABLE_ATOL)

    def test_against_projection(self):
        # A_l = sqrt(4 pi / (2l + 1)) c(l, 0)[max(0, z)], the clamped cosine projected
        # numerically (exact hemisphere quadrature) and analytically, up to l = 15.
        bands = 16
        numeric = sh.project(lambda d: np.maximum(0.0, d[:, 2]), bands, hemisphere=True)
        analytic = clamped_cosine_coefficients(bands)
        for l in range(bands):
            factor = math.sqrt(4 * math.pi / (2 * l + 1))
            assert abs(sh.cosine_lobe(bands)[l] - factor * numeric[l * l + l]) < QUADRATURE_EXACT_RTOL
            assert abs(sh.cosine_lobe(bands)[l] - factor * analytic[l * l + l]) < ANALYTIC_LOBE_ATOL

    def test_copy(self):
        a = sh.cosine_lobe(3)
        a[0] = 0.0
        assert sh.cosine_lobe(3)[0] == math.pi

    @pytest.mark.parametrize("bad", [0, 65, 2.0])
    def test_invalid(self, bad):
        with pytest.raises(ValueError, match="bands"):
            sh.cosine_lobe(bad)


class TestIrradiance:
    def test_constant_radiance(self):
        # E(n) = pi L for every normal.
        radiance = np.array([1.0, 2.5, 1000.0])
        c = sh.project(lambda d: np.broadcast_to(radiance, (d.shape[0], 3)), 5)
        normals = np.concatenate([random_unit_vectors(100, seed=50), special_points()])
        e = sh.evaluate(sh.irradiance(c), normals)
        np.testing.assert_allclose(e, np.broadcast_to(math.pi * radiance, e.shape), rtol=IRRADIANCE_RTOL, atol=0)

    def test_linear_radiance(self):
        # L(w) = a + b.w gives E(n) = pi a + (2 pi / 3) b.n.
        a, b = 3.0, np.array([0.5, -1.25, 2.0])
        c = sh.project(lambda d: a + d @ b, 4)
        normals = np.concatenate([random_unit_vectors(100, seed=51), special_points()])
        e = sh.evaluate(sh.irradiance(c), normals)
        np.testing.assert_allclose(e, math.pi * a + 2 * math.pi / 3 * normals @ b, rtol=0,
                                   atol=IRRADIANCE_RTOL * (a + np.abs(b).sum()) * 4 * math.pi)

    def test_clamped_cosine_radiance(self):
        # Zonal radiance max(0, z): E(+z) = integral max(0,z)^2 = 2 pi / 3 (bands -> inf);
        # with E(l, m) = A_l c(l, m) the band-limited sum must approach it.
        c = clamped_cosine_coefficients(16)
        e = sh.evaluate(sh.irradiance(c), [0.0, 0.0, 1.0])
        assert abs(e - 2 * math.pi / 3) < CLAMPED_COSINE_TAIL

    def test_n_dimensional(self):
        c = np.random.default_rng(52).normal(size=(3, 2, 16, 3))
        out = sh.irradiance(c)
        assert out.shape == c.shape
        np.testing.assert_array_equal(out[2, 1], sh.irradiance(c[2, 1]))
        np.testing.assert_array_equal(out[2, 1, :, 0], sh.irradiance(c[2, 1, :, 0]))

    @pytest.mark.parametrize("bad", [np.nan, np.inf])
    def test_nan_inf(self, bad):
        with pytest.raises(ValueError, match="coeffs"):
            sh.irradiance(np.full((4, 3), bad))

    def test_invalid(self):
        with pytest.raises(ValueError, match="coeffs"):
            sh.irradiance(np.zeros(6))


class TestBasisConstants:
    """The constants of the first three bands' polynomials, defined once in skysh.sh.basis (issue 24)."""

    def test_against_scipy(self) -> None:
        """Y_i = k_i p_i with p = (1, y, z, x, xy, yz, 3z^2 - 1, xz, x^2 - y^2), against scipy's real SH."""
        d = random_unit_vectors(64, 24)
        x, y, z = d.T
        p = np.stack([np.ones_like(x), y, z, x, x * y, y * z, 3 * z * z - 1, x * z, x * x - y * y], axis=-1)
        np.testing.assert_allclose(p * sh.BASIS_CONSTANTS, scipy_real_sh(d, 3), rtol=0, atol=BASIS_SCIPY_ATOL)
        assert sh.BASIS_CONSTANTS[0] == sh.Y00 == 1.0 / (2.0 * math.sqrt(math.pi))

    def test_used_by_identity(self) -> None:
        """Every module that writes the constants takes them from skysh.sh.basis: the same objects, not copies."""
        from skysh.engines import presets as engines
        from skysh.sh import minimum as shmin
        from skysh.table import irradiance_fit

        assert engines.BASIS_CONSTANTS is sh.BASIS_CONSTANTS and not sh.BASIS_CONSTANTS.flags.writeable
        for name in ("Y00", "K_LINEAR", "K_PRODUCT", "K_ZONAL", "K_SECTORAL"):
            assert getattr(shmin, name) is getattr(sh, name), name
        assert irradiance_fit.Y00 is sh.Y00
