"""
Tests of :mod:`skysh.post.dering` and :mod:`skysh.sh.minimum`
===================================================

References are independent of the modules: minima of SH functions come from
:func:`reference_min` (a Gauss-product grid, its discrete local minima, then a
damped Newton method on the sphere with finite-difference derivatives in a tangent
frame built here); windowed delta lights from a dense grid in t = cos(angle); the
clamped-cosine factors from ``sh.cosine_lobe``; the seed's bound from its own 1-D
function after a rotation made here with ``sh.rotate``. Lights used as inputs are
non-negative by construction (sums of positive deltas, deltas along arcs, ambient).

One class per public function (plus the window table). Every tolerance is a named
constant with its reason. No timing assertions (``benchmarks/bench_dering.py``).
The core run (``-m "not slow"``) checks smaller samples and property budgets; their
``slow`` twins run the full ones (the same seeds), and the 1e5-function run of the issue
is marked ``slow``.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from conftest import EPS, L_OF, channel_min, light, random_functions, reference_min, sky_samples, tangents, tools_on_path, unit
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

tools_on_path()
from studies.seed_bound import min_bound  # noqa: E402  (the seed's bound is a study: tools/studies)

EXACT_RTOL: float = 1e-12
"""The issue's bound: the 3-band minimum agrees with the reference to 1e-12 of max |c|
(measured within 2e-13: the module's rounding allowance 256 eps of |c| + |g| + |Q|)."""

ABOVE_RTOL: float = 8 * EPS
"""exact_min / min_bound may exceed the reference only by the reference's own rounding
(a 9..49-term sum evaluated at its point), relative to max |c|."""

CERTIFIED_RTOL: float = 2e-5
"""4..7 bands: the certified bound stays within 2e-5 of max |c| below the reference
(measured <= 5e-8 on random functions and skies, whose minima are isolated; <= 3e-6 on
lights' irradiance, whose ring-shaped minima hit the refinement's cell budget)."""

NONNEG_RTOL: float = 1e-12
"""A deringed target counts as negative below -1e-12 of its largest |coefficient|:
rounding of a 9..49-term sum with room; the reference itself errs by ~1e-16."""

SEED_RTOL: float = 1e-12
"""min_bound against the seed's 1-D function minimised by grid and ternary search: both
are exact to rounding of terms of size max |c| (the ternary search brackets to 1e-16 rad)."""

CONVERGED_RTOL: float = 1e-13
"""The shipped Newton steps reach the 64-step multiplier's value to rounding (measured
<= 4e-16 of max |c|); a step short would leave ~1e-10 on near-hard-case problems."""

PRINTED_4_DIGITS: float = 6e-5
"""The seed's Table 1 and eq. (6) figures are printed to 4 decimals: half a unit of the last
digit (5e-5) plus the printed w = 16.7's own rounding."""

PRINTED_5_DIGITS: float = 5e-6
"""Half a unit of the 5th decimal (0.93905, printed in the module's docstring)."""

PRINTED_3_DIGITS_PCT: float = 5e-4
"""Half a unit of the 3rd significant digit of -7.46 % (the punctual window's dip, printed)."""

ATTENUATION_BACKOFF_RTOL: float = 1e-8
"""The shipped attenuation is the closed form less 1e-12 relative (linear_attenuation's
back-off) plus root-finding rounding, far inside 1e-8."""

ROUNDING_RTOL: float = 1e-14
"""Relative rounding of a few float64 operations (a sinc^4, a product of three factors)."""

PRODUCT_RTOL: float = 1e-15
"""A basis value times two factors, computed in another order: a few eps."""

SUM_ATOL: float = 1e-14
"""Absolute rounding of a 9-term sum of O(1) terms (coefficients and basis values <= 1)."""

TRACE_ATOL: float = 1e-15
"""The trace of the 3x3 form cancels exactly in exact arithmetic: a few eps of its entries."""

PROFILE_ATOL: float = 1e-10
"""delta_minimum (exact roots) against a 200,001-point t grid: the grid's miss of the vertex,
(2 / 200000)^2 / 8 times the curvature (< 4), plus rounding: about 1e-10 at worst."""

QUADRATIC_RTOL: float = 1e-13
"""A quadratic's vertex in closed form against the module's root finding: rounding only."""

DELTA_T_GRID: int = 200_001
"""Points in t = cos(angle) for the dense check of a windowed delta's profile."""

HYPOTHESIS = settings(max_examples=30, deadline=None, derandomize=True, database=None,
                      suppress_health_check=[HealthCheck.too_slow])  # a deterministic property-test budget
"""The property tests' full budget (their ``slow`` twins)."""

HYPOTHESIS_CORE = settings(HYPOTHESIS, max_examples=10)
"""The core run's budget of the same properties: 10 seeds, each of several random lights (the twins run 30)."""

SEEDS = st.integers(0, 2**32 - 1)

RANDOM_3_BAND_FUNCTIONS: dict[str, int] = {"core": 2_500, "slow": 10_000}
"""Random 3-band functions of :meth:`TestExactMin.test_three_bands_random` (seed 2) in the core run and in its
``slow`` twin (the issue's 10^5 run is a third test)."""

CERTIFIED_FUNCTIONS: dict[str, tuple[int, int]] = {"core": (30, 10), "slow": (60, 20)}
"""(random functions, lights' irradiance) per band count 4..7 of :meth:`TestExactMin.test_four_to_seven_bands_certified`
(seed 10 + bands) in the core run and in its ``slow`` twin: the certified search is the module's costliest path."""

ADVERSARIAL_3_BAND_FUNCTIONS: dict[str, int] = {"core": 400, "slow": 800}
"""Adversarial quadratics of :meth:`TestExactMin.test_three_bands_adversarial` (seed 4) in the core run and in its
``slow`` twin: the four kinds (generic, repeated, near-repeated eigenvalues, zero g on the lowest eigenvector) take
turns, so each has 100 in the core."""



# --------------------------------------------------------------------------- #
# Independent references (reference_min, channel_min, light, ... : tests/conftest.py)
# --------------------------------------------------------------------------- #


def delta_profile_min(scales: np.ndarray, kernel: np.ndarray) -> float:
    """Minimum of a windowed delta's zonal profile, sum_l k_l s_l (2l+1)/(4 pi) P_l(t), on a dense t grid."""
    from numpy.polynomial import legendre as npleg

    n = len(scales)
    series = kernel[:n] * scales * (2 * np.arange(n) + 1) / (4.0 * math.pi)
    return float(npleg.legval(np.linspace(-1.0, 1.0, DELTA_T_GRID), series).min())


def target_min_rel(out: np.ndarray, target: str = "irradiance") -> np.ndarray:
    """Reference minimum of the target of radiance SH (..., K, C) over its largest |coefficient|."""
    t = sh.irradiance(out) if target == "irradiance" else out
    return channel_min(t) / (np.abs(t).max(axis=-2) + 1e-300)


# --------------------------------------------------------------------------- #
# Windows
# --------------------------------------------------------------------------- #
class TestWindowTable:
    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    @pytest.mark.parametrize("bands", range(1, 8))
    def test_structure(self, bands: int, target: str) -> None:
        table = dering.window_table(bands, target)
        assert table.shape[1] == bands
        assert np.all(table[:, 0] == 1.0) and np.all(table[0] == 1.0)
        assert np.all(np.diff(table, axis=0) <= 0.0)  # each band decreases down the rows
        assert np.all((table >= 0.0) & (table <= 1.0)) and not table.flags.writeable

    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    @pytest.mark.parametrize("bands", range(1, 8))
    def test_last_row_makes_any_delta_non_negative(self, bands: int, target: str) -> None:
        kernel = sh.cosine_lobe(7) if target == "irradiance" else np.ones(7)
        row = dering.window_table(bands, target)[-1]
        margin = dering.DELTA_MARGIN if bands <= 3 else dering.CERTIFIED_MARGIN
        mean = kernel[0] / (4 * math.pi)
        assert delta_profile_min(row, kernel) >= 0.5 * margin * mean
        assert dering.delta_minimum(row, target) >= margin * mean * (1 - 1e-6)

    def test_last_row_on_projected_deltas(self) -> None:
        """The claim through sh.basis: deltas in many directions, the reference minimum."""
        dirs = unit(np.random.default_rng(0).normal(size=(60, 3)))
        c = sh.basis(dirs, 3)[..., None] * dering.WINDOW_TABLE[-1][L_OF[:9], None]  # (60, 9, 1)
        assert np.all(target_min_rel(c) >= -NONNEG_RTOL)

    def test_finding_table1_and_eq6_fail(self) -> None:
        kernel = sh.cosine_lobe(7)
        assert delta_profile_min(dering.SEED_TABLE_1[-1, :3], kernel) < -0.02 * 0.25
        assert delta_profile_min(dering.sinc4_window(5.6, 3), kernel) < -0.05 * 0.25
        assert dering.SEED_TABLE_1[-1, 1] > math.sqrt(3) / 2  # no band-2 factor can save it

    def test_table1_is_sinc_power_one(self) -> None:
        """Table 1's first column (w = 16.7) is plain sinc, bands 1..3, to its 4 printed digits."""
        np.testing.assert_allclose(dering.SEED_TABLE_1[1, 1:], np.sinc(np.arange(1, 4) / 16.7), atol=PRINTED_4_DIGITS)

    def test_linear_attenuation_closed_form(self) -> None:
        s1, s2 = dering.sinc4_window(5.6, 3)[1:]
        closed = math.sqrt(15 / 8 * s2 * (1 - 5 * s2 / 8)) / s1
        assert closed == pytest.approx(0.93905, abs=PRINTED_5_DIGITS)
        assert dering.LINEAR_ATTENUATION == pytest.approx(closed, rel=ATTENUATION_BACKOFF_RTOL)
        assert dering.LINEAR_ATTENUATION < closed
        np.testing.assert_allclose(dering.WINDOW_TABLE[-1], [1.0, s1 * dering.LINEAR_ATTENUATION, s2])

    @pytest.mark.parametrize("bands", [2, 3, 5, 7])
    def test_linear_attenuation_is_the_largest(self, bands: int) -> None:
        """1e-6 more attenuation-free linear band breaks the margin (dense profile, not delta_minimum)."""
        kernel = sh.cosine_lobe(7)
        a = dering.linear_attenuation(5.6, bands)
        base = dering.sinc4_window(5.6, bands)
        margin = (dering.DELTA_MARGIN if bands <= 3 else dering.CERTIFIED_MARGIN) * 0.25
        s = base.copy()
        s[1] *= a * (1 + 1e-6)
        assert delta_profile_min(s, kernel) < margin

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="bands"):
            dering.window_table(8)
        with pytest.raises(ValueError, match="target"):
            dering.window_table(3, "luminance")


class TestSinc4:
    def test_values(self) -> None:
        w, ell = 7.0, np.arange(5)
        x = math.pi * ell[1:] / w
        np.testing.assert_allclose(dering.sinc4_window(w, 5)[1:], (np.sin(x) / x) ** 4, rtol=ROUNDING_RTOL)
        assert dering.sinc4_window(w, 5)[0] == 1.0
        assert np.all(dering.sinc4_window(3.5, 7)[4:] == 0.0)  # zero past the cutoff
        assert np.all(dering.sinc4_window(math.inf, 4) == 1.0)

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="cutoff"):
            dering.sinc4_window(0.0)


class TestDeltaMinimum:
    @pytest.mark.parametrize("scales", [[1.0, 1.0, 1.0], [1.0, 0.8, 0.5], [1.0, 0.9, 0.7, 0.4, 0.2],
                                        [1.0, 0.3], [1.0, 0.9, 0.8, 0.6, 0.4, 0.2, 0.1]])
    def test_against_dense_profile(self, scales: list[float]) -> None:
        s = np.array(scales)
        for target, kernel in (("irradiance", sh.cosine_lobe(7)), ("radiance", np.ones(7))):
            assert dering.delta_minimum(s, target) == pytest.approx(delta_profile_min(s, kernel), abs=PROFILE_ATOL)

    def test_unwindowed_reference(self) -> None:
        # (1/4)(3/8 + 2 t + 15/8 t^2): vertex t = -8/15, value (1/4)(3/8 - 8/15).
        assert dering.delta_minimum([1.0, 1.0, 1.0]) == pytest.approx(0.25 * (3 / 8 - 8 / 15), rel=QUADRATIC_RTOL)

    def test_punctual_window_finding(self) -> None:
        assert dering.delta_minimum(np.array(dering.PUNCTUAL_WINDOW)) / 0.25 == pytest.approx(-0.0746, abs=PRINTED_3_DIGITS_PCT)

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="scales"):
            dering.delta_minimum(np.ones(8))
        with pytest.raises(ValueError, match="scales"):
            dering.delta_minimum([1.0, np.nan])


# --------------------------------------------------------------------------- #
# Minima
# --------------------------------------------------------------------------- #
def adversarial_quadratics(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 9) 3-band functions at the trust-region problem's hard places: built as
    c + g.w + w^T Q w with Q = R diag(lam) R^T (repeated or near-repeated eigenvalues),
    g with a tiny (or zero) component on Q's lowest eigenvector, then fitted to SH."""
    dirs, w = sh.quadrature_rule(8)
    y = sh.basis(dirs, 3)
    out = np.empty((n, 9))
    for i in range(n):
        lam = rng.normal(size=3)
        lam -= lam.mean()
        kind = i % 4
        if kind == 1:
            lam[1] = lam[0]  # a repeated eigenvalue
        elif kind == 2:
            lam[1] = lam[0] + 10.0 ** rng.uniform(-15, -3)
        lam -= lam.mean()
        lam.sort()
        r, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        g = r @ (rng.normal(size=3) * [10.0 ** rng.uniform(-16, -1) * (kind != 3), 1.0, 1.0])
        q = r @ np.diag(lam) @ r.T
        vals = rng.normal() + dirs @ g + np.einsum("mi,ij,mj->m", dirs, q, dirs)
        out[i] = (y * w[:, None]).T @ vals  # exact: a 3-band polynomial, integrated exactly
    return out


class TestSphereQuadratic:
    def test_closed_forms_against_the_basis(self) -> None:
        """c + g.w + w^T Q w reproduces sh.basis evaluation (the Condon-Shortley signs)."""
        rng = np.random.default_rng(1)
        f = rng.normal(size=(5, 9))
        c, g, q = shmin.sphere_quadratic(f)
        w = unit(rng.normal(size=(50, 3)))
        direct = f @ sh.basis(w, 3).T
        quad = c[:, None] + g @ w.T + np.einsum("mi,nij,mj->nm", w, q, w)
        np.testing.assert_allclose(quad, direct, atol=SUM_ATOL)
        np.testing.assert_allclose(np.trace(q, axis1=-2, axis2=-1), 0.0, atol=TRACE_ATOL)
        np.testing.assert_array_equal(q, np.swapaxes(q, -1, -2))


class TestExactMin:
    @staticmethod
    def _check_three(f: np.ndarray, dense: int = 1) -> None:
        vals = shmin.exact_min(f[..., None])[:, 0]
        ref = reference_min(f, dense=dense)
        scale = np.abs(f).max(axis=1)
        assert np.all(vals <= ref + ABOVE_RTOL * scale)
        assert np.all(vals >= ref - EXACT_RTOL * scale)

    def test_three_bands_random(self) -> None:
        self._check_three(random_functions(np.random.default_rng(2), RANDOM_3_BAND_FUNCTIONS["core"], 3))

    @pytest.mark.slow
    def test_three_bands_random_1e4(self) -> None:
        self._check_three(random_functions(np.random.default_rng(2), RANDOM_3_BAND_FUNCTIONS["slow"], 3))

    @pytest.mark.slow
    def test_three_bands_random_1e5(self) -> None:
        """The issue's count: 10^5 random functions."""
        self._check_three(random_functions(np.random.default_rng(3), 100_000, 3))

    def test_three_bands_adversarial(self) -> None:
        self._check_three(adversarial_quadratics(np.random.default_rng(4), ADVERSARIAL_3_BAND_FUNCTIONS["core"]), dense=3)

    @pytest.mark.slow
    def test_three_bands_adversarial_800(self) -> None:
        self._check_three(adversarial_quadratics(np.random.default_rng(4), ADVERSARIAL_3_BAND_FUNCTIONS["slow"]), dense=3)

    @pytest.mark.parametrize("bands", [1, 2])
    def test_one_and_two_bands_closed_form(self, bands: int) -> None:
        f = random_functions(np.random.default_rng(bands), 500, bands)
        expected = f[:, 0] * 0.5 / math.sqrt(math.pi)
        if bands == 2:
            expected = expected - math.sqrt(3 / (4 * math.pi)) * np.linalg.norm(f[:, 1:4], axis=1)
        vals = shmin.exact_min(f[..., None])[:, 0]
        scale = np.abs(f).max(axis=1)
        assert np.all(vals <= expected + ABOVE_RTOL * scale) and np.all(vals >= expected - EXACT_RTOL * scale)

    def test_direction_attains_the_value(self) -> None:
        f = np.concatenate([random_functions(np.random.default_rng(5), 300, 3),
                            adversarial_quadratics(np.random.default_rng(6), 100)])
        vals, dirs = shmin.exact_min(f.T, return_dirs=True)  # channels: (9, F)
        at = np.einsum("nk,nk->n", sh.basis(dirs, 3), f)
        scale = np.abs(f).max(axis=1)
        assert np.all(at >= vals) and np.all(at - vals <= EXACT_RTOL * scale)

    @pytest.mark.parametrize("bands", [4, 5, 6, 7])
    def test_four_to_seven_bands_certified(self, bands: int) -> None:
        self._check_certified(bands, *CERTIFIED_FUNCTIONS["core"])

    @pytest.mark.slow
    @pytest.mark.parametrize("bands", [4, 5, 6, 7])
    def test_four_to_seven_bands_certified_80(self, bands: int) -> None:
        self._check_certified(bands, *CERTIFIED_FUNCTIONS["slow"])

    @staticmethod
    def _check_certified(bands: int, random: int, lights: int) -> None:
        rng = np.random.default_rng(10 + bands)
        f = np.concatenate([random_functions(rng, random, bands),
                            np.moveaxis(sh.irradiance(np.stack([light(rng, bands, 1) for _ in range(lights)])), -1, -2)[:, 0]])
        vals, dirs = shmin.exact_min(f[..., None], return_dirs=True)
        vals, dirs = vals[:, 0], dirs[:, 0]
        ref = reference_min(f, dense=3)
        scale = np.abs(f).max(axis=1)
        assert np.all(vals <= ref + ABOVE_RTOL * scale)  # the certificate: never above
        assert np.all(vals >= ref - CERTIFIED_RTOL * scale)  # and tight
        at = np.einsum("nk,nk->n", sh.basis(dirs, bands), f)
        assert np.all(at <= ref + CERTIFIED_RTOL * scale)  # the direction found is as low as the reference's

    def test_cover_radius(self) -> None:
        """The covering radius behind the certificate: the largest circumradius of the
        directions' spherical Delaunay triangles (convex-hull facets), by scipy."""
        from scipy.spatial import ConvexHull

        p = shmin.fibonacci(shmin.DIRECTIONS)
        tri = p[ConvexHull(p).simplices]
        normal = unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
        radius = np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", normal, tri[:, 0])), -1.0, 1.0)).max()
        assert radius <= shmin.COVER_RADIUS < radius * 1.01

    def test_newton_steps_converge(self) -> None:
        rng = np.random.default_rng(31)
        f = np.concatenate([adversarial_quadratics(rng, 2000), random_functions(rng, 2000, 3)])
        shipped = shmin.exact_min(f[..., None])[:, 0]
        t, e, _ = shmin.normalised(f)  # as exact_min does
        q = t @ shmin.FORM_MAP
        converged = np.ldexp(shmin.trust_region_min(q[:, 0], q[:, 1:4], q[:, 4:].reshape(-1, 3, 3), steps=64)[0], e)
        np.testing.assert_array_less(np.abs(converged - shipped), CONVERGED_RTOL * np.abs(f).max(axis=1))

    def test_shapes_and_scale(self) -> None:
        f = np.random.default_rng(0).normal(size=(2, 9, 3))
        v, d = dering.exact_min(f, return_dirs=True)
        assert v.shape == (2, 3) and d.shape == (2, 3, 3)
        np.testing.assert_array_equal(v[1], dering.exact_min(f[1]))
        assert isinstance(dering.exact_min(f[0, :, 0]), float)
        for k in (-1000, -300, 300, 1000):  # powers of two: exact, whatever the magnitude
            np.testing.assert_array_equal(dering.exact_min(np.ldexp(f, k)), np.ldexp(v, k))
        assert dering.exact_min(np.zeros(9)) == 0.0 and dering.exact_min(np.zeros(16)) == 0.0

    def test_bad_input(self) -> None:
        for bad in (np.ones(10), np.ones(64), [np.inf] * 9, np.ones((9, 3, 0)).T):
            with pytest.raises(ValueError, match="coeffs"):
                dering.exact_min(bad)
        with pytest.raises(TypeError, match="return_dirs"):
            dering.exact_min(np.ones(9), return_dirs=1)


SEED_GRID: int = 20_001
"""Points of :func:`seed_bound_reference`'s grid on each quarter circle of phi (spacing 7.9e-5 rad)."""

TERNARY_STEPS: int = 100
"""Ternary-search steps of :func:`seed_bound_reference` around the grid's least point: the bracket of two grid
spacings shrinks by (2/3)^100, far below 1e-16 rad."""


def seed_bound_reference(f: np.ndarray) -> np.ndarray:
    """The seed's 1-D function minimised densely, for functions f (F, 9): rotate the optimal linear direction to +Z
    (sh.rotate, frame from a cross product), then min over z = cos(phi) of the zonal part
    (eq. 3) - T (1 - z^2) - S |z| sqrt(1 - z^2), T and S the |m| = 2 and |m| = 1 amplitudes
    (eqs. 4, 5). Smooth in phi on each quarter circle: a dense grid there, then ternary
    search around its least point (all functions at once, each with its own bracket)."""
    k0, k1, kz = 0.5 / math.sqrt(math.pi), math.sqrt(3 / (4 * math.pi)), math.sqrt(5 / (16 * math.pi))
    kb, k2 = math.sqrt(15 / (4 * math.pi)), math.sqrt(15 / (16 * math.pi))
    rotated = []
    for x in f:
        n = np.array([-x[3], -x[1], x[2]])
        n = unit(n) if np.linalg.norm(n) > 0 else np.array([0.0, 0.0, 1.0])
        e1 = tangents(n[None])[0][0]
        rotated.append(sh.rotate(x, np.stack([e1, np.cross(n, e1), n], axis=1).T))  # coefficients of f(frame w)
    r = np.array(rotated).reshape(-1, 9)
    # per function: the weights of 1, z, 3 z^2 - 1, sin^2 and |z| sin
    c0, c1, cz = k0 * r[:, :1], k1 * r[:, 2:3], kz * r[:, 6:7]
    t, b = k2 * np.hypot(r[:, 4:5], r[:, 8:9]), kb * np.hypot(r[:, 5:6], r[:, 7:8])

    def h(phi: np.ndarray) -> np.ndarray:
        z, s = np.cos(phi), np.sin(phi)
        return c0 + c1 * z + cz * (3 * z * z - 1) - t * s * s - b * np.abs(z) * s

    out = np.full(len(r), math.inf)
    for lo in (0.0, math.pi / 2):
        phi = np.linspace(lo, lo + math.pi / 2, SEED_GRID)
        z, s = np.cos(phi), np.sin(phi)
        grid = np.concatenate([c0, c1, cz, -t, -b], axis=1) @ np.stack([np.ones_like(z), z, 3 * z * z - 1, s * s,
                                                                       np.abs(z) * s])
        j = np.argmin(grid, axis=1)
        a, b_ = phi[np.maximum(j - 1, 0)][:, None], phi[np.minimum(j + 1, SEED_GRID - 1)][:, None]
        for _ in range(TERNARY_STEPS):
            m1, m2 = a + (b_ - a) / 3, b_ - (b_ - a) / 3
            left = h(m1) < h(m2)
            a, b_ = np.where(left, a, m1), np.where(left, m2, b_)
        out = np.minimum(out, np.minimum(grid[np.arange(len(r)), j], h(0.5 * (a + b_))[:, 0]))
    return out


class TestMinBound:
    def test_is_the_seed_bound_and_never_above(self) -> None:
        """Random, adversarial and near-zonal functions (tiny |m| = 1, 2 parts, where invariants
        computed as differences once left the bound 3e-9 too high)."""
        rng = np.random.default_rng(7)
        zonal = np.zeros((60, 9))
        zonal[:, [0, 2, 6]] = rng.uniform([-1.0, 0.0, -1.0], [2.0, 1.0, 1.0], (60, 3))
        zonal[:, [4, 5, 7, 8]] = rng.normal(size=(60, 4)) * 10.0 ** rng.uniform(-12, 0, (60, 4))
        f = np.concatenate([random_functions(rng, 200, 3), adversarial_quadratics(rng, 100), zonal])
        bound = min_bound(f.T)
        scale = np.abs(f).max(axis=1)
        np.testing.assert_allclose(bound, seed_bound_reference(f), rtol=0, atol=SEED_RTOL * scale.max())
        assert np.all(bound <= reference_min(f) + ABOVE_RTOL * scale)

    @staticmethod
    def _never_above_for_lights(seed: int) -> None:
        rng = np.random.default_rng(seed)
        e = sh.irradiance(np.stack([light(rng, 3, 1) for _ in range(6)]))[..., 0]
        assert np.all(min_bound(e.T) <= reference_min(e) + ABOVE_RTOL * np.abs(e).max(axis=1))

    @HYPOTHESIS_CORE
    @given(seed=SEEDS)
    def test_never_above_for_lights(self, seed: int) -> None:
        self._never_above_for_lights(seed)

    @pytest.mark.slow
    @HYPOTHESIS
    @given(seed=SEEDS)
    def test_never_above_for_lights_full(self, seed: int) -> None:
        self._never_above_for_lights(seed)

    def test_exact_for_zonal_functions(self) -> None:
        """Zonal about the linear direction: c0 Y00 + c2 K z + c6 K0 (3 z^2 - 1), minimum in closed form."""
        k0, k1, kz = 0.5 / math.sqrt(math.pi), math.sqrt(3 / (4 * math.pi)), math.sqrt(5 / (16 * math.pi))
        for c0, c2, c6 in ((1.0, 0.5, 0.3), (1.0, 0.2, -0.4), (0.2, 1.0, 0.1), (1.0, 0.0, 0.5), (0.0, 0.0, -1.0)):
            f = np.zeros(9)
            f[0], f[2], f[6] = c0, c2, c6
            z = np.linspace(-1, 1, 2_000_001)
            exact = float(np.min(k0 * c0 + k1 * c2 * z + kz * c6 * (3 * z * z - 1)))
            assert min_bound(f) == pytest.approx(exact, abs=SEED_RTOL)

    def test_rotation_about_the_linear_direction_keeps_the_bound(self) -> None:
        rng = np.random.default_rng(3)
        f = rng.normal(size=(9, 2))
        f[1] = f[3] = 0.0
        turned = sh.rotate_z(f, np.array(0.7))
        np.testing.assert_allclose(min_bound(turned), min_bound(f), rtol=SEED_RTOL, atol=SUM_ATOL)

    def test_shapes_and_scale(self) -> None:
        f = np.random.default_rng(5).normal(size=(2, 3, 9, 4))
        b = min_bound(f)
        assert b.shape == (2, 3, 4)
        np.testing.assert_array_equal(min_bound(f[1, 2]), b[1, 2])
        assert isinstance(min_bound(f[0, 0, :, 1]), float)
        np.testing.assert_array_equal(min_bound(np.ldexp(f, 900)), np.ldexp(b, 900))
        assert min_bound(np.zeros(9)) == 0.0

    def test_bad_input(self) -> None:
        for bad in (np.ones(16), np.full(9, np.nan), np.ones(4)):
            with pytest.raises(ValueError, match="coeffs"):
                min_bound(bad)


# --------------------------------------------------------------------------- #
# Deringing
# --------------------------------------------------------------------------- #
def least_row_brute_force(c: np.ndarray, target: str = "irradiance") -> tuple[np.ndarray, np.ndarray]:
    """Per function (n, K, 3): the least table row whose windowed target has a reference
    minimum >= 0 in every channel (R if none), and the reference minima (n, R, 3) relative
    to each channel's largest |coefficient|."""
    bands = math.isqrt(c.shape[-2])
    table = dering.window_table(bands, target)
    w = c[:, None] * table[None, :, L_OF[: bands * bands], None]  # (n, R, K, 3)
    rel = target_min_rel(w, target)
    ok = (rel >= 0.0).all(-1)
    return np.where(ok.any(-1), np.argmax(ok, -1), len(table)), rel


SUBNORMAL_LIGHTS: int = 120
"""All-subnormal 3-band RGB lights of :meth:`TestDering.test_all_subnormal_lights` (seed 2023; the issue's 1 in 100)."""

SUBNORMAL_EXPONENTS: tuple[int, int] = (-1064, -1023)
"""Binary exponents (low, high) of a subnormal test light's largest |coefficient|: 1e-320 .. 1.1e-308, all
below 2^-1022 (channels of an HDR light lie up to 10^4 lower still)."""

MIXED_EXPONENTS: tuple[int, int] = (-1070, -1040)
"""Binary exponents of the subnormal channels next to a normal one (largest |coefficient| 1): lower than
:data:`SUBNORMAL_EXPONENTS`, since the normal channel mostly sets the window and only the least channels round."""


def subnormal_scaled(c: np.ndarray, exponent: np.ndarray | int) -> np.ndarray:
    """Lights (..., K, C) scaled by powers of two so that each function's largest |coefficient| lies in
    [2^(exponent - 1), 2^exponent); in the subnormal range the scaling rounds: that rounded input is the test's."""
    m = np.abs(c).max((-1, -2), keepdims=True)
    return np.ldexp(c / np.ldexp(1.0, np.frexp(m)[1]), exponent)


def exact_target_min(out: np.ndarray, target: str = "irradiance") -> np.ndarray:
    """The exact minimum (shmin.exact_min) of the target of radiance SH (..., K, C), per channel, in units of
    the target's largest |coefficient| rounded up to a power of two; each channel of ``out`` is first
    scaled by a power of two into the normal range (exact), so the target is of the very coefficients
    returned, not of a subnormal product that rounds."""
    e = np.frexp(np.abs(out).max(-2, keepdims=True))[1]
    t = np.ldexp(out, -e)
    t = sh.irradiance(t) if target == "irradiance" else t
    return shmin.exact_min(t) / np.ldexp(1.0, np.frexp(np.abs(t).max(-2))[1])


def row_of(scales: np.ndarray, table: np.ndarray) -> np.ndarray:
    """The table row of each scales vector (..., N)."""
    return np.argmin(np.abs(scales[..., None, :] - table).max(-1), axis=-1)


class TestDering:
    def test_positive_input_untouched(self) -> None:
        c = np.zeros((9, 3))
        c[0], c[2] = [3.0, 2.0, 1.0], [0.5, 0.2, 0.1]
        out, scales = dering.dering(c)
        np.testing.assert_array_equal(out, c)
        np.testing.assert_array_equal(scales, np.ones(3))
        assert out is not c

    def test_least_row_brute_force(self) -> None:
        """3 bands, ``method="table"``: the chosen row is the least that a brute-force scan of the rows with the
        reference minimum accepts, except where a row's reference minimum is within 1e-12 of
        zero (then either row is right to rounding)."""
        rng = np.random.default_rng(9)
        c = np.concatenate([np.stack([light(rng, 3) for _ in range(150)]), sky_samples(20, gibbs=False),
                            random_functions(rng, 60, 3).reshape(20, 3, 9).swapaxes(1, 2)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            _, scales, failed = dering.dering(c, method="table", return_failed=True)
        brute, rel = least_row_brute_force(c)
        chosen = np.where(failed, len(dering.WINDOW_TABLE), row_of(scales, dering.WINDOW_TABLE))
        tie = (np.abs(rel) <= NONNEG_RTOL).any(axis=(-1, -2))
        assert np.all((chosen == brute) | tie) and (chosen == brute).sum() > 0.95 * len(c)
        assert len(set(brute.tolist())) >= 4  # many rows exercised

    def test_least_row_negative_control(self) -> None:
        """The brute-force check fails on a search that stops one row early."""
        c = np.stack([light(np.random.default_rng(10), 3) for _ in range(40)])
        _, scales = dering.dering(c, method="table")
        chosen = row_of(scales, dering.WINDOW_TABLE)
        brute, _ = least_row_brute_force(c)
        assert np.any(np.maximum(chosen - 1, 0) != brute)

    @staticmethod
    def _random_lights_non_negative(seed: int, target: str) -> None:
        rng = np.random.default_rng(seed)
        c = np.stack([light(rng, 3) for _ in range(8)])
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales, failed = dering.dering(c, target=target, return_failed=True)
        assert not failed.any() and np.all(target_min_rel(out, target) >= -NONNEG_RTOL)
        assert np.all(np.isfinite(out)) and np.all(np.isfinite(scales))

    @HYPOTHESIS_CORE
    @given(seed=SEEDS, target=st.sampled_from(dering.DERING_TARGETS))
    def test_random_lights_non_negative(self, seed: int, target: str) -> None:
        self._random_lights_non_negative(seed, target)

    @pytest.mark.slow
    @HYPOTHESIS
    @given(seed=SEEDS, target=st.sampled_from(dering.DERING_TARGETS))
    def test_random_lights_non_negative_full(self, seed: int, target: str) -> None:
        self._random_lights_non_negative(seed, target)

    def test_single_deltas_many_directions(self) -> None:
        dirs = unit(np.random.default_rng(1).normal(size=(60, 3)))
        c = sh.basis(dirs, 3)[..., None] * np.array([1.0, 10.0, 1000.0])  # HDR colours
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert np.all(target_min_rel(out) >= -NONNEG_RTOL)
        assert np.all(scales[:, 1] < 1.0)  # a lone delta always needs windowing

    def test_one_window_for_all_channels(self) -> None:
        """The applied row is the strongest any channel needs alone (seed section 3)."""
        rng = np.random.default_rng(21)
        c = np.stack([light(rng, 3) for _ in range(20)])
        s = dering.dering(c)[1]
        per = np.stack([dering.dering(c[..., [k]])[1] for k in range(3)])
        np.testing.assert_array_equal(s, per.min(axis=0))

    def test_batched_equals_single(self) -> None:
        rng = np.random.default_rng(31)
        c = np.stack([light(rng, 3) for _ in range(8)]).reshape(2, 4, 9, 3)
        c[0, 0] = 0.0
        c[0, 0, 0] = 1.0  # one that needs nothing
        out, scales = dering.dering(c)
        assert out.shape == c.shape and scales.shape == (2, 4, 3)
        for i in range(2):
            for j in range(4):
                o, s = dering.dering(c[i, j])
                np.testing.assert_array_equal(s, scales[i, j])
                np.testing.assert_array_equal(o, out[i, j])
        o, s, failed = dering.dering(c[0, 1, :, 0], return_failed=True)  # (K,) input
        assert o.shape == (9,) and s.shape == (3,) and failed.shape == ()

    def test_failed_flag_and_warning(self) -> None:
        c = np.zeros((3, 9, 3))
        c[0, 0] = [-1.0, 1.0, 1.0]  # negative mean: no window can help
        c[1, 0], c[1, 2] = 1.0, 2.0  # a linear band too large for any non-negative light
        c[2, 0] = 1.0  # fine
        with pytest.warns(dering.DeringWarning):
            out, scales, failed = dering.dering(c, return_failed=True)
        np.testing.assert_array_equal(failed, [True, True, False])
        np.testing.assert_array_equal(scales[:2], np.broadcast_to(dering.WINDOW_TABLE[-1], (2, 3)))
        assert np.all(np.isfinite(out))
        assert np.all((channel_min(sh.irradiance(out[:2])) < 0).any(-1))  # truly negative at the last row

    @pytest.mark.parametrize("bands", [1, 2, 4, 5, 7])
    def test_other_band_counts(self, bands: int) -> None:
        rng = np.random.default_rng(100 + bands)
        c = np.stack([light(rng, bands) for _ in range(6)])
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert scales.shape == (6, bands) and np.all(target_min_rel(out) >= -NONNEG_RTOL)

    @pytest.mark.parametrize("bands", [3, 7])
    def test_skies(self, bands: int) -> None:
        for gibbs in (False, True):
            c = sky_samples(8, bands, gibbs)
            with warnings.catch_warnings():
                warnings.simplefilter("error", dering.DeringWarning)
                out, _ = dering.dering(c)
            assert np.all(target_min_rel(out) >= -NONNEG_RTOL)

    def test_never_nan(self) -> None:
        rng = np.random.default_rng(1)
        c = rng.normal(size=(50, 9, 3)) * 10.0 ** rng.uniform(-300, 300, (50, 1, 3))
        c[:5] = 0.0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert np.all(np.isfinite(out)) and np.all(np.isfinite(scales))

    def test_all_subnormal_lights(self) -> None:
        """Issue 23: deringing all-subnormal 3-band RGB lights (every coefficient below 2^-1022) leaves
        the returned irradiance's exact minimum >= 0 within the module's allowance, or flags the function
        (before: 1 in 100 was left at up to -1e-5 of its size, unflagged: its windowed coefficients
        round in the subnormal range after an exact decision)."""
        rng = np.random.default_rng(2023)
        c = np.stack([light(rng, 3) for _ in range(SUBNORMAL_LIGHTS)])
        c = subnormal_scaled(c, rng.integers(*SUBNORMAL_EXPONENTS, (len(c), 1, 1)))
        assert np.all(np.abs(c) < np.finfo(np.float64).tiny)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out, _, failed = dering.dering(c, return_failed=True)
        assert np.all(failed | (exact_target_min(out) >= -shmin.ALLOWANCE).all(-1))
        assert failed.sum() < 0.5 * len(c)  # most still pass

    @HYPOTHESIS_CORE
    @given(seed=SEEDS, exponent=st.integers(*SUBNORMAL_EXPONENTS), bands=st.integers(1, 3),
           target=st.sampled_from(dering.DERING_TARGETS))
    def test_subnormal_property(self, seed: int, exponent: int, bands: int, target: str) -> None:
        """Any magnitude below the normal range: failed, or the returned target's exact minimum >= 0
        within :data:`shmin.ALLOWANCE` (the allowance the module decides with for normal inputs)."""
        rng = np.random.default_rng(seed)
        c = subnormal_scaled(np.stack([light(rng, bands) for _ in range(16)]), exponent)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out, _, failed = dering.dering(c, target=target, return_failed=True)
        assert np.all(failed | (exact_target_min(out, target) >= -shmin.ALLOWANCE).all(-1))

    def test_normal_and_subnormal_channels(self) -> None:
        """The boundary: a normal channel next to subnormal ones, and channels whose largest |coefficient|
        is the least normal number 2^-1022 or the float just below it: every channel of the result passes."""
        rng = np.random.default_rng(2024)
        c = np.stack([light(rng, 3) for _ in range(120)])
        c = c / np.abs(c).max(-2, keepdims=True)  # each channel's largest |coefficient| is 1
        tiny = np.finfo(np.float64).tiny
        c[:80, :, 1:] = np.ldexp(c[:80, :, 1:], rng.integers(*MIXED_EXPONENTS, (80, 1, 2)))
        c[80:100] *= np.array([tiny, np.nextafter(tiny, 0.0), 1.0])  # the least normal, the largest subnormal
        c[100:] *= np.array([1.0, tiny, 2.0**-1060])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out, _, failed = dering.dering(c, return_failed=True)
        assert np.all(failed | (exact_target_min(out) >= -shmin.ALLOWANCE).all(-1))
        least_normal = c[80:100, :, [0]]  # a channel at the least normal size is decided as at any normal size
        np.testing.assert_array_equal(dering.dering(least_normal)[1], dering.dering(np.ldexp(least_normal, 1000))[1])

    def test_bad_input(self) -> None:
        c = np.ones((9, 3))
        with pytest.raises(ValueError, match="target"):
            dering.dering(c, target="luminance")
        with pytest.raises(ValueError, match="method"):
            dering.dering(c, method="exact")
        for bad in (np.ones((64, 3)), np.ones((10, 3)), np.full((9, 3), np.nan)):
            with pytest.raises(ValueError, match="coeffs"):
                dering.dering(bad)
        with pytest.raises(TypeError, match="return_failed"):
            dering.dering(c, return_failed=1)


class TestSinc4WindowIntegers:
    @pytest.mark.parametrize("cutoff", [10**400, -10**400, 10**5000], ids=["1e400", "-1e400", "1e5000"])
    def test_integers_beyond_float64(self, cutoff: int) -> None:
        """Issue 23: sinc4_window(10**400) (and linear_attenuation, built on it) raised OverflowError."""
        with pytest.raises(ValueError, match=r"^cutoff must be a real number > 0 within float64 .*an integer of \d+ digits$"):
            dering.sinc4_window(cutoff)
        with pytest.raises(ValueError, match="cutoff"):
            dering.linear_attenuation(cutoff)

    def test_integer_cutoffs_in_range(self) -> None:
        np.testing.assert_array_equal(dering.sinc4_window(10**300, 3), dering.sinc4_window(1e300, 3))
        np.testing.assert_array_equal(dering.sinc4_window(4), dering.sinc4_window(4.0))


class TestDirectionalLight:
    def test_reference(self) -> None:
        d = unit(np.array([0.3, -0.4, 0.8]))
        colour = np.array([1000.0, 900.0, 800.0])
        c = dering.directional_light_sh(d, colour)
        expected = sh.basis(d, 3)[:, None] * np.array(dering.PUNCTUAL_WINDOW)[L_OF[:9], None] * colour
        np.testing.assert_allclose(c, expected, rtol=PRODUCT_RTOL)

    def test_sun_plus_deringed_sky(self) -> None:
        """The seed's recipe: dering the sky, add the sun windowed by the last row: non-negative."""
        sky = sky_samples(4, gibbs=False)
        sun = unit(np.array([[0.2, 0.1, 0.97], [0.9, 0.0, 0.44], [0.0, -0.7, 0.71], [1.0, 0.0, 0.0]]))
        total = dering.dering(sky)[0] + dering.directional_light_sh(sun, np.full(3, 1e5), window=dering.WINDOW_TABLE[-1])
        assert np.all(target_min_rel(total) >= -NONNEG_RTOL)

    def test_batched_and_bad_input(self) -> None:
        d = unit(np.random.default_rng(2).normal(size=(5, 3)))
        assert dering.directional_light_sh(d, np.ones((5, 3)), bands=2).shape == (5, 4, 3)
        with pytest.raises(ValueError, match="window"):
            dering.directional_light_sh(d[0], np.ones(3), bands=4)
        with pytest.raises(ValueError, match="direction"):
            dering.directional_light_sh([0.0, 0.0, 2.0], np.ones(3))

    def test_bands_beyond_the_window_name_bands(self) -> None:
        """Issue 23: bands=8 with the default 3-factor window spoke of ``window`` only; the message names
        ``bands`` and its range [1, len(window)]."""
        for bands, window, high in ((8, dering.PUNCTUAL_WINDOW, 3), (4, dering.PUNCTUAL_WINDOW, 3), (3, [1.0, 0.9], 2)):
            with pytest.raises(ValueError, match=rf"^bands must lie in \[1, {high}\]: window .*, got {bands}$"):
                dering.directional_light_sh([0.0, 0.0, 1.0], np.ones(3), bands=bands, window=window)
        assert dering.directional_light_sh([0.0, 0.0, 1.0], np.ones(3), bands=8, window=np.ones(8)).shape == (64, 3)
        with pytest.raises(ValueError, match=r"bands must be an integer in \[1, 64\]"):
            dering.directional_light_sh([0.0, 0.0, 1.0], np.ones(3), bands=65, window=np.ones(65))
