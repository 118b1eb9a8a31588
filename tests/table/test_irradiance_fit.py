"""
Tests of :mod:`skysh.table.irradiance_fit`
====================================

References are independent of the module: the polynomial form is checked against
``sh.basis`` and against the closed forms of ``docs/conventions.md`` typed here;
minima come from a dense product-quadrature sphere refined by scipy's
Nelder-Mead in spherical angles; the S-lemma is checked by a bounded scalar
search over the multiplier (the smallest eigenvalue of M(mu) is concave in mu);
the convex optima are compared with scipy solving the same problems with the
non-negativity sampled on a dense set of normals (a relaxation: its optimum is
at most the exact one, and close to it); chromaticities come from colour-science.
Every tolerance is a named constant with its reason. cvxpy is the tools extra:
the solver tests are skipped without it (``conftest.needs_cvxpy``); without it the
functions that solve refuse at once with one message naming the extra
(:class:`TestWithoutTheSolver`, whether or not cvxpy is installed).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable

import numpy as np
import pytest
from conftest import EPS, needs_cvxpy
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize

from skysh.sh import basis as sh
from skysh.table import irradiance_fit as irf

FORM_RTOL: float = 1e-13
"""c + g.w + w^T A w against sh.basis: two sums of 9 products of O(1) terms."""

MIN_RTOL: float = 1e-12
"""sphere_minimum against a refined dense minimum, relative to the largest coefficient:
the reference converges to ~1e-14 (Nelder-Mead, xatol 1e-10 rad at a quadratic minimum),
its rounding allowance (2.3e-13 x 2^e, shmin.ALLOWANCE); rounding of 9-term sums of O(1) values."""

BATCH_RTOL: float = 8 * EPS
"""A batch against the same functions one by one, of max|e|: the batched matrix product (BLAS gemm)
may sum each function's 9 terms in another order than a single one (measured: 1 ulp); 8 eps."""

ATTAINED_RTOL = 1e-8
"""How closely f at the returned direction attains the minimum, of max|e|. Near the hard case
(the gradient almost orthogonal to the lowest eigenvector, e.g. g_z = 2e-6 against Q ~ 6) the
minimiser is fixed only to about sqrt(eps) in angle, so f there is off by eps^(1/2) x |g_small|
x curvature terms: ~1e-9 of max|e| measured (hypothesis found 8.8e-10); the value itself stays
a lower bound to MIN_RTOL (the first assertion)."""

SOLVER_ATOL: float = 1e-6
"""Optimal L2 distance or worst error of the SDP against scipy's cutting-plane solve of the
same problem, in units of the channel's mean (the problems' scale): Clarabel stops at a
1e-8 gap; the cutting planes leave the relaxation's gap at (distance to the true contact
point)^2 ~ 1e-10 after their Nelder-Mead refinement; 1e-6 leaves room for both. (Plain
sampling of 20,000 normals alone is 1% off in the squared distance: it lets the function
dip by curvature x spacing^2 ~ 4e-4 of the mean between samples.)"""

NEGATIVE_RTOL: float = 1e-12
"""A repaired optimum is non-negative to rounding of its exact minimum (relative to the mean)."""

CHROMA_TOL: float = 1e-6
"""u'v' distance above the bound at the constrained normals: the solver's 1e-8 feasibility
on the scaled cone, divided by D ~ 0.05 x mean at the dimmest constrained normal."""

CERTIFICATE_GAP: float = 1e-4
"""Offset of the trial minimum from the dense minimum, in units of max|e|, at which the lifted matrix's best
eigenvalue must change sign: well above the bounded scalar search's accuracy (xatol 1e-13, so ~1e-10 in the
eigenvalue) and the dense minimum's MIN_RTOL."""

FEASIBLE_FLOOR: float = -1e-13
"""The cutting-plane reference stops once its iterate's refined minimum (in units of the channel's mean) is above
this: rounding of 9-term sums of O(1) values, far below SOLVER_ATOL."""

BINDING_MARGIN: float = 1e-4
"""The minimax objective with the non-negativity constraint exceeds the unconstrained one by more than this
(units of the mean) when the constraint binds: 100 x SOLVER_ATOL, so solver tolerance cannot fake it."""

BLEND_L2_TOL: float = 1e-4
"""A blend with weight 1e6 against the L2 optimum, per coefficient in units of the channel's mean: the worst-error
term moves the L2 optimum by about its gradient / weight ~ 1e-6; 100x that for the solvers' own tolerances."""

POLY_FIT_RTOL: float = 1e-10
"""A least-squares table fitted to exact polynomial data of its own degrees, at held-out points: rounding of a
20-term fit with condition number ~10 (a few hundred eps), with room for the luminance scale's evaluation."""

SMALL = irf.OPTIMISATION_NORMALS // 16
"""Normal count for fast solver tests (about 130 normals)."""

UNCACHED: irf.Objective = irf.Objective("l2", margin=0.0125)
"""An objective no other test solves, so that no compiled problem of this process hides a missing solver."""


def unit(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def convention_value(e: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The 3-band function from the table of docs/conventions.md, typed independently."""
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    s = math.sqrt(math.pi)
    return (e[0] / (2 * s) - e[1] * math.sqrt(3) / (2 * s) * y + e[2] * math.sqrt(3) / (2 * s) * z
            - e[3] * math.sqrt(3) / (2 * s) * x + e[4] * math.sqrt(15) / (2 * s) * x * y
            - e[5] * math.sqrt(15) / (2 * s) * y * z + e[6] * math.sqrt(5) / (4 * s) * (3 * z * z - 1)
            - e[7] * math.sqrt(15) / (2 * s) * x * z + e[8] * math.sqrt(15) / (4 * s) * (x * x - y * y))


def dense_minimum(e: np.ndarray) -> float:
    """Reference minimum of one 3-band function: 20,000-node Gauss sphere, then Nelder-Mead."""
    dirs, _ = sh.quadrature_rule(100)
    values = sh.basis(dirs, 3) @ e
    best = dirs[np.argsort(values)[:4]]

    def f(angles: np.ndarray) -> float:
        t, p = angles
        return float(sh.basis(np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]), 3) @ e)

    starts = [(math.acos(np.clip(d[2], -1, 1)), math.atan2(d[1], d[0])) for d in best]
    results = [optimize.minimize(f, s, method="Nelder-Mead", options={"xatol": 1e-10, "fatol": 1e-16}) for s in starts]
    return min(min(r.fun for r in results), float(values.min()))


class TestQuadraticParts:
    def test_against_basis_and_table(self) -> None:
        rng = np.random.default_rng(1)
        e = rng.normal(size=(9, 4))
        w = unit(rng, 500)
        c, g, a = irf.quadratic_parts(e)
        form = c + w @ g.T + np.einsum("mi,cij,mj->mc", w, a, w)
        scale = np.abs(e).max()
        assert np.max(np.abs(form - sh.basis(w, 3) @ e)) < FORM_RTOL * scale * 10
        assert np.max(np.abs(form - convention_value(e, w[:, None, :].repeat(4, 1)).reshape(500, 4))) < FORM_RTOL * scale * 10

    def test_single_coefficients_carry_the_phase(self) -> None:
        # e3 alone: -sqrt(3)/(2 sqrt(pi)) x, so g = (-k1, 0, 0) (Condon-Shortley sign)
        e = np.zeros(9)
        e[3] = 1.0
        c, g, a = irf.quadratic_parts(e)
        assert c == 0.0 and np.allclose(g, [-math.sqrt(3) / (2 * math.sqrt(math.pi)), 0, 0], rtol=EPS, atol=0)
        assert not a.any()

    def test_bad_shape(self) -> None:
        with pytest.raises(ValueError, match="coeffs"):
            irf.quadratic_parts(np.zeros(8))
        with pytest.raises(ValueError, match="coeffs"):
            irf.quadratic_parts([np.nan] * 9)


class TestLiftedMatrix:
    @pytest.mark.parametrize("mu", [-3.0, 0.0, 2.5])
    @pytest.mark.parametrize("margin", [0.0, 0.01])
    def test_quadratic_form_on_the_sphere(self, mu: float, margin: float) -> None:
        rng = np.random.default_rng(2)
        e = rng.normal(size=9)
        w = unit(rng, 200)
        m = irf.lifted_matrix(e, mu, margin)
        lifted = np.concatenate([np.ones((200, 1)), w], axis=1)
        expected = sh.basis(w, 3) @ e - margin * e[0] / (2 * math.sqrt(math.pi))
        assert np.max(np.abs(np.einsum("mi,ij,mj->m", lifted, m, lifted) - expected)) < FORM_RTOL * 10 * (1 + abs(mu))


class TestSphereMinimum:
    @pytest.mark.parametrize("seed", range(6))
    def test_against_dense_refined(self, seed: int) -> None:
        e = np.random.default_rng(seed).normal(size=9)
        assert abs(irf.sphere_minimum(e) - dense_minimum(e)) < MIN_RTOL * np.abs(e).max() * 100

    @pytest.mark.parametrize("tiny", [1e-12, 1e-9, 1e-6, 1e-4])
    def test_near_hard_case_direction(self, tiny: float) -> None:
        """g almost orthogonal to the lowest eigenvector (hypothesis found e7 = 1e-12): the direction attains
        the minimum to rounding, its near-zero gap's component taken from |w| = 1."""
        e = np.zeros(9)
        e[[3, 5, 7]] = (1.0, 1.0, tiny)
        value, w = irf.sphere_minimum(e, return_dirs=True)
        assert abs(value - dense_minimum(e)) < MIN_RTOL * 100
        assert abs(float(sh.basis(w, 3) @ e) - value) < MIN_RTOL * 100

    @pytest.mark.parametrize("case", ["zonal", "no_linear", "hard", "constant", "zero"])
    def test_hard_and_degenerate_cases(self, case: str) -> None:
        e = np.zeros(9)
        if case == "zonal":
            e[[0, 2, 6]] = (1.0, 0.3, 1.0)
        elif case == "no_linear":
            e[[0, 4, 8]] = (0.2, 1.0, -0.5)
        elif case == "hard":  # g along z, smallest eigenvalue of A in the xy plane: the hard case
            e[[0, 2, 6]] = (1.0, 0.05, 1.0)
        elif case == "constant":
            e[0] = 2.0
        value, w = irf.sphere_minimum(e, return_dirs=True)
        reference = dense_minimum(e) if case != "zero" else 0.0
        assert abs(value - reference) < MIN_RTOL * max(np.abs(e).max(), 1.0) * 100
        assert abs(float(sh.basis(w, 3) @ e) - value) < MIN_RTOL * max(np.abs(e).max(), 1.0) * 100

    @settings(max_examples=60, deadline=None)
    @given(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=9, max_size=9))
    def test_lower_bound_attained(self, values: list[float]) -> None:
        e = np.array(values)
        value, w = irf.sphere_minimum(e, return_dirs=True)
        dirs, _ = sh.quadrature_rule(24)
        scale = max(np.abs(e).max(), 1e-300)
        assert np.all(sh.basis(dirs, 3) @ e >= value - MIN_RTOL * scale * 100)
        assert abs(float(sh.basis(w, 3) @ e) - value) <= ATTAINED_RTOL * scale

    def test_batched_shapes(self) -> None:
        e = np.random.default_rng(3).normal(size=(2, 5, 9, 3))
        out = irf.sphere_minimum(e)
        assert out.shape == (2, 5, 3)
        single = np.array([[[irf.sphere_minimum(e[i, j, :, ch]) for ch in range(3)] for j in range(5)] for i in range(2)])
        np.testing.assert_allclose(out, single, rtol=0, atol=BATCH_RTOL * np.abs(e).max())


class TestCertificate:
    """The S-lemma: some M(mu) - s e0 e0^T is PSD iff s <= min f (module docstring)."""

    @staticmethod
    def best_eigenvalue(e: np.ndarray, s: float) -> float:
        def neg_lambda_min(mu: float) -> float:
            m = irf.lifted_matrix(e, mu)
            m[0, 0] -= s
            return -float(np.linalg.eigvalsh(m)[0])

        bound = 10.0 * np.abs(e).sum()
        return -optimize.minimize_scalar(neg_lambda_min, bounds=(-bound, bound), method="bounded",
                                         options={"xatol": 1e-13}).fun

    @pytest.mark.parametrize("seed", range(4))
    def test_certificate_exists_exactly_below_the_minimum(self, seed: int) -> None:
        e = np.random.default_rng(10 + seed).normal(size=9)
        minimum = dense_minimum(e)
        gap = CERTIFICATE_GAP * np.abs(e).max()
        assert self.best_eigenvalue(e, minimum - gap) > 0.0
        assert self.best_eigenvalue(e, minimum + gap) < 0.0

    @needs_cvxpy
    def test_sdp_maximises_to_the_minimum(self) -> None:
        import cvxpy

        e = np.random.default_rng(20).normal(size=9)
        mu, s = cvxpy.Variable(), cvxpy.Variable()
        m = sum(e[i] * irf.LIFT_MAP[i] for i in range(9)) + mu * irf.MU_MATRIX - s * np.diag([1.0, 0, 0, 0])
        cvxpy.Problem(cvxpy.Maximize(s), [m >> 0]).solve(solver="CLARABEL")
        assert abs(s.value - dense_minimum(e)) < SOLVER_ATOL * np.abs(e).max()  # e is O(1) here


def sky_truth(zenith_deg: float, turbidity: float, bands: int = 3) -> np.ndarray:
    return irf.true_irradiance(math.radians(zenith_deg), turbidity, bands, 24 if bands > 3 else None)


def sampled_constraints(count: int = 2000) -> np.ndarray:
    """Basis rows (m >= 0 columns) at a dense independent set: a Gauss sphere (not Fibonacci)."""
    dirs, _ = sh.quadrature_rule(int(math.sqrt(count / 2)))
    return sh.basis(dirs, 3)[:, list(irf.HALF_ROWS)]


def refined_argmin(x: np.ndarray) -> tuple[float, np.ndarray]:
    """Minimum and basis row (m >= 0 columns) at the minimiser of the function with m >= 0 coefficients x.

    A 7,200-node Gauss sphere, then Nelder-Mead on the convention's closed form (typed in this file).
    """
    e = np.zeros(9)
    e[list(irf.HALF_ROWS)] = x
    dirs, _ = sh.quadrature_rule(60)
    d = dirs[np.argmin(sh.basis(dirs, 3) @ e)]

    def at(angles: np.ndarray) -> np.ndarray:
        t, p = angles
        return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])

    start = (math.acos(np.clip(d[2], -1, 1)), math.atan2(d[1], d[0]))
    res = optimize.minimize(lambda a: float(convention_value(e, at(a))), start, method="Nelder-Mead",
                            options={"xatol": 1e-10, "fatol": 1e-16})
    return float(res.fun), sh.basis(at(res.x), 3)[list(irf.HALF_ROWS)]


def cutting_plane(solve: Callable[[np.ndarray], tuple[float, np.ndarray]], rounds: int = 8) -> float:
    """Brute-force exact optimum: solve with sampled f >= 0, add each solution's own minimiser, repeat.

    Every round is a relaxation (optimum <= exact); adding the violated minimiser closes the
    gap (Kelley's cutting planes), to the solver's tolerance within a few rounds here.
    """
    rows = sampled_constraints()
    for _ in range(rounds):
        value, x = solve(rows)
        lowest, row = refined_argmin(x)
        if lowest >= FEASIBLE_FLOOR:  # feasible on the whole sphere: the relaxation is exact
            break
        rows = np.vstack([rows, row])
    return value


@needs_cvxpy
class TestConstrainedL2:
    @pytest.mark.parametrize("zenith, turbidity", [(89.0, 2.5), (90.0, 6.0)])
    def test_against_scipy_cutting_plane(self, zenith: float, turbidity: float) -> None:
        truth = sky_truth(zenith, turbidity)
        coeffs, _info = irf.constrained_coefficients(truth, irf.Objective("l2"))
        rows = list(irf.HALF_ROWS)
        for ch in range(3):
            mean = irf.Y00 * truth[0, ch]
            target = truth[rows, ch] / mean

            def solve(a: np.ndarray, target: np.ndarray = target) -> tuple[float, np.ndarray]:
                res = optimize.minimize(lambda x: float(np.sum((x - target) ** 2)), target, jac=lambda x: 2 * (x - target),
                                        constraints=[{"type": "ineq", "fun": lambda x: a @ x, "jac": lambda x: a}],
                                        method="SLSQP", options={"ftol": 1e-16, "maxiter": 500})
                assert res.success
                return float(res.fun), res.x

            reference = math.sqrt(cutting_plane(solve))  # a relaxation: at most the exact optimum
            ours = math.sqrt(float(np.sum((coeffs[rows, ch] / mean - target) ** 2)))  # feasible: at least it
            assert reference - SOLVER_ATOL <= ours <= reference + SOLVER_ATOL
        assert np.all(irf.sphere_minimum(coeffs) >= -NEGATIVE_RTOL * irf.Y00 * coeffs[0])

    def test_non_negative_projection_is_kept(self) -> None:
        truth = sky_truth(0.0, 2.5)
        if np.any(irf.sphere_minimum(truth[:9]) < 0.0):
            pytest.skip("this sky's projection is negative: not the case under test")
        coeffs, _ = irf.constrained_coefficients(truth, irf.Objective("l2"))
        assert np.allclose(coeffs, truth[:9], rtol=0, atol=SOLVER_ATOL * irf.Y00 * truth[0].max())

    def test_negative_projection_is_moved(self) -> None:  # negative control of the constraint
        truth = sky_truth(89.0, 2.5)
        assert np.any(irf.sphere_minimum(truth[:9]) < 0.0)
        _coeffs, info = irf.constrained_coefficients(truth, irf.Objective("l2"))
        assert np.all(info["minimum"] >= -NEGATIVE_RTOL)

    @pytest.mark.parametrize("margin", [1e-3, 0.02])
    def test_margin(self, margin: float) -> None:
        truth = sky_truth(89.0, 2.5)
        coeffs, info = irf.constrained_coefficients(truth, irf.Objective("l2", margin))
        plain = irf.sphere_minimum(truth[:9]) / (irf.Y00 * truth[0])
        assert np.all(info["minimum"] >= margin - NEGATIVE_RTOL)
        # where the projection misses the margin, the optimum sits on it (the constraint is active)
        assert np.all(np.abs(info["minimum"] - margin)[plain < margin] <= SOLVER_ATOL)
        assert np.allclose(coeffs[:, plain >= margin], truth[:9, plain >= margin], rtol=SOLVER_ATOL, atol=0)
        assert not coeffs[[1, 4, 5]].any()  # symmetric in y: m < 0 rows exactly zero

    def test_deterministic(self) -> None:
        truth = sky_truth(85.0, 3.0)
        assert np.array_equal(irf.constrained_coefficients(truth)[0], irf.constrained_coefficients(truth)[0])


@needs_cvxpy
class TestWorstCase:
    def test_unconstrained_minimax_is_linprog(self) -> None:
        truth = sky_truth(88.0, 2.5, bands=16)
        obj = irf.Objective("minimax_free", normals=SMALL)
        _coeffs, info = irf.constrained_coefficients(truth, obj)
        normals = irf.half_sphere_normals(SMALL)
        basis, values = sh.basis(normals, 3)[:, list(irf.HALF_ROWS)], sh.evaluate(truth, normals)
        total = 0.0
        for ch in range(3):
            v = values[:, ch] / (irf.Y00 * truth[0, ch])
            ones = np.ones((len(v), 1))
            a_ub = np.block([[basis, -ones], [-basis, -ones]])
            res = optimize.linprog(np.r_[np.zeros(6), 1.0], A_ub=a_ub, b_ub=np.r_[v, -v], bounds=[(None, None)] * 7,
                                   method="highs")
            total += res.fun
        assert abs(info["objective"] - total) <= SOLVER_ATOL

    def test_constrained_minimax_against_cutting_plane_lp(self) -> None:
        truth = sky_truth(88.0, 2.5, bands=16)
        _coeffs, info = irf.constrained_coefficients(truth, irf.Objective("minimax", normals=SMALL))
        normals = irf.half_sphere_normals(SMALL)
        basis, values = sh.basis(normals, 3)[:, list(irf.HALF_ROWS)], sh.evaluate(truth, normals)
        total = 0.0
        for ch in range(3):
            v = values[:, ch] / (irf.Y00 * truth[0, ch])
            ones = np.ones((len(v), 1))

            def solve(dense: np.ndarray, v: np.ndarray = v, ones: np.ndarray = ones) -> tuple[float, np.ndarray]:
                a_ub = np.block([[basis, -ones], [-basis, -ones], [-dense, np.zeros((len(dense), 1))]])
                res = optimize.linprog(np.r_[np.zeros(6), 1.0], A_ub=a_ub, b_ub=np.r_[v, -v, np.zeros(len(dense))],
                                       bounds=[(None, None)] * 7, method="highs")
                return float(res.fun), res.x[:6]

            total += cutting_plane(solve)
        free = irf.constrained_coefficients(truth, irf.Objective("minimax_free", normals=SMALL))[1]["objective"]
        assert abs(info["objective"] - total) <= SOLVER_ATOL
        assert info["objective"] > free + BINDING_MARGIN  # the constraint binds on this sky (negative control)
        assert np.all(info["minimum"] >= -NEGATIVE_RTOL)

    def test_blend_spans_minimax_and_l2(self) -> None:
        truth = sky_truth(88.0, 2.5, bands=16)
        minimax = irf.constrained_coefficients(truth, irf.Objective("minimax", normals=SMALL))[1]["objective"]
        at_zero = irf.constrained_coefficients(truth, irf.Objective("blend", weight=0.0, normals=SMALL))[1]["objective"]
        l2 = irf.constrained_coefficients(truth, irf.Objective("l2"))[0]
        heavy = irf.constrained_coefficients(truth, irf.Objective("blend", weight=1e6, normals=SMALL))[0]
        assert abs(at_zero - minimax) <= SOLVER_ATOL
        assert np.max(np.abs(heavy - l2) / (irf.Y00 * truth[0])) <= BLEND_L2_TOL

    def test_chroma_bound_holds_at_lit_normals(self) -> None:
        import colour

        truth = sky_truth(88.0, 2.5, bands=16)
        normals = irf.half_sphere_normals(SMALL)
        true_rgb = sh.evaluate(truth, normals)
        space = colour.RGB_COLOURSPACES["sRGB"]
        lum = true_rgb @ np.asarray(space.matrix_RGB_to_XYZ)[1]
        lit = lum >= irf.CHROMA_FLOOR * float(irf.Y00 * truth[0] @ np.asarray(space.matrix_RGB_to_XYZ)[1])

        def uv(rgb: np.ndarray) -> np.ndarray:
            xyz = colour.RGB_to_XYZ(rgb, space, illuminant=None, chromatic_adaptation_transform=None)
            return colour.xy_to_Luv_uv(colour.XYZ_to_xy(xyz))

        bound = 0.005
        distance = {}
        for chroma in (None, bound):
            coeffs, _ = irf.constrained_coefficients(truth, irf.Objective("minimax", chroma=chroma, normals=SMALL))
            distance[chroma] = np.linalg.norm(uv(sh.evaluate(coeffs, normals)[lit]) - uv(true_rgb[lit]), axis=1)
        assert distance[None].max() > 2 * bound  # negative control: unconstrained colour exceeds the bound
        assert distance[bound].max() <= bound + CHROMA_TOL


@needs_cvxpy
class TestGridAndTable:
    def test_grid_matches_points(self) -> None:
        ts, tu = np.radians([80.0, 89.0]), np.array([2.5, 5.0])
        coeffs, minimum = irf.constrained_irradiance_grid(ts, tu, irf.Objective("l2"))
        assert coeffs.shape == (2, 2, 9, 3) and minimum.shape == (2, 2, 3)
        point = irf.constrained_point((float(ts[1]), float(tu[0]), irf.Objective("l2")))[0]
        assert np.array_equal(coeffs[1, 0], point)
        assert np.all(minimum >= -NEGATIVE_RTOL)

    def test_table_reproduces_polynomial_data(self) -> None:
        """Coefficients = luminance scale x a polynomial of degrees (2, 1) in the table's variables: fitted exactly."""
        from skysh.model import preetham
        from skysh.table import fit, poly

        params = np.random.default_rng(4).normal(size=(9, 2, 3))

        def data(ts: np.ndarray, tu: np.ndarray) -> np.ndarray:
            x, y = poly.scale(ts, tu)
            out = np.zeros((ts.size, 9, 3))
            for row in irf.HALF_ROWS:
                value = 1.0 + 0.1 * row + params[row, 0] * x[:, None] + params[row, 1] * (x * y)[:, None]
                out[:, row] = value * preetham.luminance_scale(ts, tu)[:, None] * irf.LOBE[row]
            out[:, 0] += 10.0 * irf.LOBE[0] * preetham.luminance_scale(ts, tu)[:, None]  # positive means
            return out

        ts, tu = fit.chebyshev_grid((8, 5))
        table, degrees, _ = irf.fit_irradiance_table(ts, tu, data(ts, tu), (2, 1))
        hts, htu = fit.held_out_points(20, 5)
        back = irf.evaluate_irradiance_table(table, degrees, hts, htu)
        assert np.allclose(back, data(hts, htu), rtol=POLY_FIT_RTOL, atol=0)
        assert not back[:, [1, 4, 5]].any()


class TestBadInput:
    def test_objective(self) -> None:
        with pytest.raises(ValueError, match="method"):
            irf.Objective("l1")
        with pytest.raises(ValueError, match="margin"):
            irf.Objective("l2", margin=0.9)
        with pytest.raises(ValueError, match="chroma"):
            irf.Objective("l2", chroma=2.0)
        with pytest.raises(ValueError, match="count"):
            irf.Objective("l2", normals=3)

    def test_truth(self) -> None:
        with pytest.raises(ValueError, match="truth"):
            irf.constrained_coefficients(np.ones((8, 3)))
        bad = np.zeros((9, 3))
        bad[0] = (1.0, -1.0, 1.0)
        with pytest.raises(ValueError, match="positive mean"):
            irf.constrained_coefficients(bad)

    def test_grid_ranges(self) -> None:
        with pytest.raises(ValueError, match="sun_zenith"):
            irf.constrained_irradiance_grid([2.0], [3.0])
        with pytest.raises(ValueError, match="turbidity"):
            irf.constrained_irradiance_grid([0.5], [12.0])


# --------------------------------------------------------------------------- #
# Without the solver (the tools extra)
# --------------------------------------------------------------------------- #
@pytest.fixture()
def no_solver(monkeypatch: pytest.MonkeyPatch) -> None:
    """The solver's packages unimportable and unfound in this test, whether or not they are installed."""
    for name in irf.SOLVER_PACKAGES:
        monkeypatch.setitem(sys.modules, name, None)


@pytest.mark.usefixtures("no_solver")
class TestWithoutTheSolver:
    def test_reported_missing_by_name(self) -> None:
        assert not irf.solver_available()
        assert irf.missing_solver_packages() == irf.SOLVER_PACKAGES
        message = irf.solver_missing_message("this task")
        assert message.startswith("this task needs cvxpy and clarabel (the tools extra)")
        assert message.endswith('pip install -e ".[tools]"') and "\n" not in message

    def test_a_solve_refuses_with_the_install_command(self) -> None:
        with pytest.raises(ModuleNotFoundError, match=r"needs cvxpy .*the tools extra.*pip install -e") as info:
            irf.constrained_coefficients(sky_truth(30.0, 3.0), UNCACHED)
        assert info.value.name == "cvxpy"

    def test_build_table_refuses_before_any_work(self) -> None:
        calls: list = []

        def mapper(function: Callable, jobs: object) -> list:
            calls.append(function)
            return []

        with pytest.raises(ModuleNotFoundError, match=r"the irradiance table needs cvxpy"):
            irf.build_table((6, 4), (2, 1), mapper=mapper, held_out=(4, 1))
        assert calls == []


def test_available_exactly_when_every_package_is_found() -> None:
    import importlib.util

    found = all(importlib.util.find_spec(name) is not None for name in irf.SOLVER_PACKAGES)
    assert irf.solver_available() is found and (irf.missing_solver_packages() == ()) is found
