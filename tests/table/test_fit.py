"""
Tests of :mod:`skysh.table.fit`
=========================

The fit is checked on data it must reproduce exactly: coefficients that ARE
``luminance_scale(ts, T)`` times a 2D Chebyshev polynomial in the variables of
:func:`skysh.table.poly.scale`, evaluated here with
:func:`numpy.polynomial.chebyshev.chebval2d` (an independent route). Least
squares on such data has zero residual, so the fitted table must equal the
polynomial's coefficients to rounding, and the smallest degrees that meet any
small budget are the true ones. The whole pipeline (:func:`skysh.table.fit.build`)
runs once on synthetic projections (through its ``mapper`` hook) and once,
tiny, on the real sky. The sun's table is checked the same way (exact
recovery of ln XYZ that is a Chebyshev polynomial in variables typed here from
:func:`skysh.model.solar.relative_optical_mass`), its grid and held-out points by
their definitions, and its fit against :mod:`skysh.model.solar` on held-out points.
``tools/fit_sky.py`` (what ``skysh fit`` runs) is
checked for its output rules with ``fit.build`` replaced by the polynomial sky:
``--out`` required, the shipped file replaced only with ``--force``, every
refusal one line with exit status 2, without cvxpy (the tools extra) too, before
any projection (in process and in a fresh interpreter that cannot import it).

One class per public function; every tolerance is a named constant with the
reason for its size.
"""

from __future__ import annotations

import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import EPS, ROOT, chebyshev_variables, script_without_cvxpy
from numpy.polynomial import chebyshev as npcheb

from skysh.lighting.sunlight import SunLight
from skysh.model import preetham, solar
from skysh.runtime import SkySH
from skysh.sh import basis as sh
from skysh.table import coefficient_file, fit, irradiance_fit, poly

CONDITION_MAX: float = 1e3
"""Largest condition number of a weighted design accepted for the exact-recovery
tests: the tiny Chebyshev-node grids give about 3.5 (measured) with point
weights in [0.5, 2]; the bound keeps FIT_EXACT_RTOL meaningful."""

FIT_EXACT_RTOL: float = 1e-12
"""Recovered Chebyshev coefficients vs the true ones, relative to the largest
|coefficient|. For consistent data (zero residual) the least-squares solution's
relative error is about condition x eps (not condition^2), i.e. <= 1e3 x 2.2e-16
= 2.2e-13 with CONDITION_MAX; measured 1.1e-15 at condition 3.5."""

EVAL_RTOL: float = 1e-12
"""evaluate_table vs chebval2d at held-out points, relative to the largest
|value|: the table's rounding (FIT_EXACT_RTOL) times sum |T_i T_j| <= 12 terms
of size <= 1, plus Clenshaw vs recurrence rounding (~k^2 eps); measured 1.5e-15."""

EXACT_BUDGET: float = 1e-8
"""E_mean budget for choose_degrees on exact polynomial data: far above the
rounding of an exact fit (~1e-14 relative) and far below the error of any
degree that misses a true term (the top coefficient is >= 1 against an L_min
of the same size, so leaving it out costs E_mean of order 1)."""

ARITH_RTOL: float = 8 * EPS
"""error_measures on hand-made numbers: a few additions, one square root and
one division of small exact values."""

NODE_ATOL: float = 32 * EPS
"""Grid nodes vs the formula typed here: a cosine and an affine map in another
order; absolute on values <= 6 (ulp(6) = 8.9e-16 = 4 eps)."""

SUN_GOAL: float = 1e-4
"""Issue 15's goal for the sun table (held out, relative): the real fit must meet it."""

AIR_MASS_RTOL: float = 1e-13
"""zenith_of_air_mass then Kasten's m (skysh.model.solar's numpy route) vs the target m: bisection to
8.5e-20 rad moves m by at most dm/dtheta (about 270 per rad near the horizon) x that, far below
rounding; the two formulas' roundings (a few eps x m) dominate. Relative to m."""

EXP_RTOL: float = 1e-12
"""Sun values recovered from exact ln XYZ data: the fit's coefficients within condition (2) x eps,
times sum |T_i T_j| <= 91 terms, in ln; exp turns that into the same relative error."""

HALF_PI_ATOL: float = 1e-15
"""zenith_of_air_mass at the horizon's air mass: the bisection (to 8.5e-20 rad) ends on a float next to
pi/2; 1e-15 is about 4 ulp of pi/2."""

SUN_NODE_ATOL: float = 1e-12
"""The sun grid's air-mass variable recomputed from its zeniths vs the Chebyshev nodes: the inversion's
relative error AIR_MASS_RTOL on m <= 36.5, over (m1 - m0) / 2 = 17.8, is <= 2e-13 in x (the test groups
equal nodes by rounding x to 12 decimals first)."""

AIR_MASS_SHARE_ATOL: float = 0.04
"""Share of the air-mass-uniform block within 5 deg of the horizon vs the air mass's own share: 4
binomial standard deviations of 2000 draws (sd 0.01)."""

ZENITH_SHARE_MAX: float = 0.1
"""Share of the zenith-uniform block within 5 deg of the horizon: 5 / 90 = 0.056 expected, sd 0.005 for
2000 draws; 0.1 is 8 sd above, far below the air-mass block's share (> 0.7)."""

RECOMPUTED_RTOL: float = 1e-9
"""The worst held-out sun error recorded by build_sun vs the same quotient minus 1 recomputed here from
the same table and points: rounding of values ~1 cancelling to ~1e-5 leaves ~1e-11 relative."""

HALF_PI = math.pi / 2.0

# --------------------------------------------------------------------------- #
# Synthetic polynomial sky
# --------------------------------------------------------------------------- #
TRUE_DEGREES: np.ndarray = np.array([[1, 0], [3, 2], [2, 1]], dtype=np.int64)
"""True per-band (d_theta, d_tau) of the synthetic data: lower than MAX_DEGREES and different per band."""

MAX_DEGREES: tuple[int, int] = (5, 3)
"""The degrees choose_degrees may go up to."""

GRID: tuple[int, int] = (8, 5)
"""A tiny Chebyshev grid, larger than MAX_DEGREES + 1 in each variable (so every candidate fit is determined)."""


class PolynomialSky:
    """Coefficients (m >= 0 rows) that are exactly luminance_scale x a Chebyshev polynomial of TRUE_DEGREES."""

    def __init__(self, seed: int = 5) -> None:
        rng = np.random.default_rng(seed)
        self.bands = TRUE_DEGREES.shape[0]
        self.layout = coefficient_file.zonal_half_layout(self.bands)
        within = tuple(int(v) for v in TRUE_DEGREES.max(axis=0))
        self.within = within
        # p[row, channel, i, j]: coefficient of T_i(x) T_j(y)
        self.p = np.zeros((len(self.layout), 3, within[0] + 1, within[1] + 1))
        for row, (l, _) in enumerate(self.layout):
            d0, d1 = TRUE_DEGREES[l]
            self.p[row, :, : d0 + 1, : d1 + 1] = rng.normal(size=(3, d0 + 1, d1 + 1))
            self.p[row, :, d0, d1] = 1.0 + np.abs(self.p[row, :, d0, d1])  # the top term matters
            self.p[row, :, 0, 0] += 4.0

    def table(self) -> np.ndarray:
        """The true table in the file's layout: (n_terms, K_half, 3), term (i, j) at i (d_tau + 1) + j."""
        return self.p.transpose(2, 3, 0, 1).reshape(-1, len(self.layout), 3)

    def values(self, ts: np.ndarray, t: np.ndarray) -> np.ndarray:
        """(P, K_half, 3) coefficients in cd/m^2."""
        x, y = chebyshev_variables(ts, t)
        scale = preetham.luminance_scale(ts, t)
        out = np.empty((np.size(ts), len(self.layout), 3))
        for row in range(len(self.layout)):
            for c in range(3):
                out[:, row, c] = npcheb.chebval2d(x, y, self.p[row, c]) * scale
        return out

    def denominator(self, ts: np.ndarray, t: np.ndarray, rng: np.random.Generator | None = None) -> np.ndarray:
        """(P, 3) an L_min of the size of the coefficients; randomised weights if ``rng``."""
        base = preetham.luminance_scale(ts, t)[:, None] * np.ones((1, 3))
        return base if rng is None else base * rng.uniform(0.5, 2.0, base.shape)


@pytest.fixture(scope="module")
def psky() -> PolynomialSky:
    return PolynomialSky()


# --------------------------------------------------------------------------- #
# Grids and points
# --------------------------------------------------------------------------- #
class TestChebyshevGrid:
    def test_nodes(self) -> None:
        ts, t = fit.chebyshev_grid((6, 4))
        assert ts.shape == t.shape == (24,)
        # Chebyshev-Gauss nodes cos((2k + 1) pi / (2n)) mapped affinely, interior only.
        expected_ts = np.sort(HALF_PI * 0.5 * (np.cos((2 * np.arange(6) + 1) * math.pi / 12) + 1.0))
        expected_t = np.sort(2.5 + 3.5 * 0.5 * (np.cos((2 * np.arange(4) + 1) * math.pi / 8) + 1.0))
        np.testing.assert_allclose(np.unique(ts), expected_ts, rtol=0, atol=NODE_ATOL)
        np.testing.assert_allclose(np.unique(t), expected_t, rtol=0, atol=NODE_ATOL)
        assert ts.min() > 0.0 and ts.max() < HALF_PI and t.min() > 2.5 and t.max() < 6.0
        # The product grid: each zenith node with each turbidity node (ij order).
        assert np.all(ts.reshape(6, 4) == ts.reshape(6, 4)[:, :1])


class TestHeldOutPoints:
    def test_random_plus_corners(self) -> None:
        ts, t = fit.held_out_points(10, 3)
        assert ts.shape == t.shape == (14,)
        assert np.all((ts >= 0) & (ts <= HALF_PI) & (t >= 2.5) & (t <= 6.0))
        assert set(zip(ts[-4:], t[-4:])) == {(0.0, 2.5), (0.0, 6.0), (HALF_PI, 2.5), (HALF_PI, 6.0)}
        np.testing.assert_array_equal(fit.held_out_points(10, 3)[0], ts)  # seeded
        assert fit.held_out_points(10, 3, corners=False)[0].shape == (10,)

    def test_edge_points(self) -> None:
        ts, t = fit.edge_points(5, 1)
        assert ts.shape == t.shape == (20,)
        on_edge = np.isin(ts, [0.0, HALF_PI]) | np.isin(t, [2.5, 6.0])
        assert on_edge.all()


# --------------------------------------------------------------------------- #
# Fit and evaluation
# --------------------------------------------------------------------------- #
class TestFitTable:
    def test_recovers_polynomial_exactly(self, psky: PolynomialSky) -> None:
        ts, t = fit.chebyshev_grid(GRID)
        rng = np.random.default_rng(11)
        table, condition = fit.fit_table(ts, t, psky.values(ts, t), psky.denominator(ts, t, rng), TRUE_DEGREES)
        assert 1.0 <= condition < CONDITION_MAX, condition
        truth = psky.table()
        assert table.shape == truth.shape == (poly.n_terms(psky.within), 6, 3)
        np.testing.assert_allclose(table, truth, rtol=0, atol=FIT_EXACT_RTOL * np.abs(truth).max())
        # Terms above a band's degrees are exactly zero in its rows (the file's layout promise).
        for row, (l, _) in enumerate(psky.layout):
            i, j = np.divmod(np.arange(table.shape[0]), psky.within[1] + 1)
            above = (i > TRUE_DEGREES[l, 0]) | (j > TRUE_DEGREES[l, 1])
            assert np.all(table[above, row] == 0.0)

    def test_evaluate_table_reproduces(self, psky: PolynomialSky) -> None:
        ts, t = fit.chebyshev_grid(GRID)
        table, _ = fit.fit_table(ts, t, psky.values(ts, t), psky.denominator(ts, t), TRUE_DEGREES)
        hts, ht = fit.held_out_points(16, 2)
        got = fit.evaluate_table(table, TRUE_DEGREES, hts, ht)
        expected = psky.values(hts, ht)
        assert got.shape == (20, 6, 3)
        np.testing.assert_allclose(got, expected, rtol=0, atol=EVAL_RTOL * np.abs(expected).max())
        # And with the true table directly (no fit involved).
        direct = fit.evaluate_table(psky.table(), TRUE_DEGREES, hts, ht)
        np.testing.assert_allclose(direct, expected, rtol=0, atol=EVAL_RTOL * np.abs(expected).max())

    def test_weights_do_not_matter_for_exact_data(self, psky: PolynomialSky) -> None:
        ts, t = fit.chebyshev_grid(GRID)
        a, _ = fit.fit_table(ts, t, psky.values(ts, t), psky.denominator(ts, t), TRUE_DEGREES)
        b, _ = fit.fit_table(ts, t, psky.values(ts, t), psky.denominator(ts, t, np.random.default_rng(1)), TRUE_DEGREES)
        np.testing.assert_allclose(a, b, rtol=0, atol=2 * FIT_EXACT_RTOL * np.abs(a).max())  # two fits

    def test_plain_variant_recovers_plain_polynomial(self) -> None:
        # variant (False, False): the seed's plain polynomial (no scale, turbidity affine).
        ts, t = fit.chebyshev_grid(GRID)
        x = 4.0 * ts / math.pi - 1.0
        y = (2.0 * t - 8.5) / 3.5
        p = np.random.default_rng(4).normal(size=(3, 3))  # degrees (2, 2)
        values = np.repeat(npcheb.chebval2d(x, y, p)[:, None, None], 3, axis=2)  # bands 1, one row
        table, condition = fit.fit_table(ts, t, values, np.ones((ts.size, 3)), np.array([[2, 2]]), variant=(False, False))
        assert condition < CONDITION_MAX
        np.testing.assert_allclose(table[:, 0, 1], p.ravel(), rtol=0, atol=FIT_EXACT_RTOL * np.abs(p).max())


class TestErrorMeasures:
    def test_definitions(self) -> None:
        # Seed eqs. (2), (3): E_max = sum |diff| / L_min, E_mean = sqrt(sum diff^2) / L_min,
        # worst channel; over the first `bands` bands (K_half = bands (bands + 1) / 2 rows).
        truth = np.zeros((1, 6, 3))
        truth[0, 0] = [10.0, 20.0, 40.0]
        predicted = truth.copy()
        predicted[0, 0] += [1.0, 0.0, 0.0]  # band 0
        predicted[0, 1] += [0.0, 3.0, 0.0]  # band 1
        predicted[0, 2] += [0.0, -4.0, 0.0]  # band 1
        predicted[0, 5] += [0.0, 0.0, 100.0]  # band 2
        denominator = np.array([[2.0, 10.0, 50.0]])
        one = fit.error_measures(predicted, truth, denominator, 1)
        assert one["e_mean"][0] == pytest.approx(0.5, rel=ARITH_RTOL)
        assert one["e_max"][0] == pytest.approx(0.5, rel=ARITH_RTOL)
        assert one["dc"][0] == pytest.approx(0.1, rel=ARITH_RTOL)
        two = fit.error_measures(predicted, truth, denominator, 2)
        assert two["e_mean"][0] == pytest.approx(0.5, rel=ARITH_RTOL)  # channel 1: 5 / 10; channel 0: 1 / 2
        assert two["e_max"][0] == pytest.approx(0.7, rel=ARITH_RTOL)  # channel 1: 7 / 10
        three = fit.error_measures(predicted, truth, denominator, 3)
        assert three["e_mean"][0] == pytest.approx(2.0, rel=ARITH_RTOL)
        assert three["e_max"][0] == pytest.approx(2.0, rel=ARITH_RTOL)

    def test_error_denominator_floor(self) -> None:
        lmin = np.array([[100.0, 50.0, -700.0, 1000.0]])
        np.testing.assert_array_equal(fit.error_denominator(lmin), [[100.0, 50.0, fit.LMIN_FLOOR * 1000.0]])


class TestChooseDegrees:
    def test_picks_true_degrees(self, psky: PolynomialSky) -> None:
        gts, gt = fit.chebyshev_grid(GRID)
        vts, vt = fit.held_out_points(12, 9)
        grid = (gts, gt, psky.values(gts, gt), psky.denominator(gts, gt))
        validation = (vts, vt, psky.values(vts, vt), psky.denominator(vts, vt))
        chosen = fit.choose_degrees(EXACT_BUDGET, psky.bands, MAX_DEGREES, grid, validation)
        np.testing.assert_array_equal(chosen, TRUE_DEGREES)

    def test_unreachable_budget_gives_max(self, psky: PolynomialSky) -> None:
        # Data of higher degree than allowed: no candidate meets the budget.
        gts, gt = fit.chebyshev_grid(GRID)
        vts, vt = fit.held_out_points(12, 9)
        grid = (gts, gt, psky.values(gts, gt), psky.denominator(gts, gt))
        validation = (vts, vt, psky.values(vts, vt), psky.denominator(vts, vt))
        chosen = fit.choose_degrees(EXACT_BUDGET, psky.bands, (2, 1), grid, validation)
        np.testing.assert_array_equal(chosen, [[1, 0], [2, 1], [2, 1]])


# --------------------------------------------------------------------------- #
# The whole pipeline
# --------------------------------------------------------------------------- #
class TestBuild:
    def test_synthetic_pipeline(self, psky: PolynomialSky, tmp_path: Path) -> None:
        """build() with projections replaced by the polynomial sky (its mapper hook): exact results."""

        def mapper(function, jobs):
            jobs = list(jobs)
            ts = np.array([j[0] for j in jobs])
            t = np.array([j[1] for j in jobs])
            values = psky.values(ts, t)
            lmin = np.concatenate([psky.denominator(ts, t), preetham.luminance_scale(ts, t)[:, None]], axis=1)
            return [(values[k], lmin[k]) for k in range(len(jobs))]

        settings = fit.FitSettings(bands=3, degrees=MAX_DEGREES, grid=GRID, held_out=8, validation=8)
        table, report, samples = fit.build(settings, tolerance=EXACT_BUDGET, mapper=mapper, provenance={"test": True})
        np.testing.assert_array_equal(table.degrees, TRUE_DEGREES)
        truth = psky.table()
        np.testing.assert_allclose(table.table, truth, rtol=0, atol=FIT_EXACT_RTOL * np.abs(truth).max())
        assert report["held_out_points"] == 12
        for bands in ("1", "2", "3"):
            assert report["by_bands"][bands]["e_mean_worst"] < EXACT_BUDGET
        assert table.metadata["errors"] == report and table.metadata["test"] is True
        assert table.metadata["degrees"] == TRUE_DEGREES.tolist()
        assert samples["grid"][2].shape == (GRID[0] * GRID[1], 6, 3)
        assert table.tables["sun"].degrees.tolist() == [list(settings.sun_degrees)]
        assert table.metadata["tables"]["sun"]["errors"]["worst"] <= SUN_GOAL
        # The runtime built from this table evaluates the same polynomial.
        path = coefficient_file.write(tmp_path / "synthetic.npz", _with_shipped_irradiance(table))
        runtime = SkySH.load(path)
        got = runtime.coefficients(0.9, 3.3, 0.0, bands=3, gibbs=False)
        expected = psky.values(np.array([0.9]), np.array([3.3]))[0]
        rows = [sh.index(l, m) for l, m in psky.layout]
        np.testing.assert_allclose(got[rows], expected, rtol=0, atol=EVAL_RTOL * np.abs(expected).max())

    def test_tiny_real_build(self, tmp_path: Path) -> None:
        """The real sky on a tiny grid: self-consistent report, file and runtime (no accuracy claim)."""
        settings = fit.FitSettings(bands=2, degrees=(3, 2), grid=(6, 4), held_out=3)
        table, report, samples = fit.build(settings)
        assert table.table.shape == (12, 3, 3) and table.degrees.tolist() == [[3, 2], [3, 2]]
        hts, ht, hc, hd = samples["test"]
        assert hts.size == report["held_out_points"] == 7
        predicted = fit.evaluate_table(table.table, table.degrees, hts, ht)
        measures = fit.error_measures(predicted, hc, hd, 2)
        assert report["by_bands"]["2"]["e_mean_worst"] == float(measures["e_mean"].max())  # the same computation
        # The held-out truth is the reference projection.
        np.testing.assert_array_equal(hc[0], preetham.sky_sh(float(hts[0]), float(ht[0]), 2)[[0, 2, 3]])
        # Round trip through the file, then the runtime equals evaluate_table (phi = 0, no Gibbs).
        path = coefficient_file.write(tmp_path / "tiny.npz", _with_shipped_irradiance(table))
        runtime = SkySH.load(path)
        got = runtime.coefficients(hts, ht, 0.0, bands=2, gibbs=False)[:, [0, 2, 3]]
        np.testing.assert_allclose(got, predicted, rtol=0, atol=EVAL_RTOL * np.abs(predicted).max())
        # The sun: the runtime's SunLight from the file equals the fit's own evaluation.
        sun = table.tables["sun"]
        np.testing.assert_allclose(SunLight.load(path).xyz(hts, ht),
                                   fit.evaluate_sun_table(sun.table, sun.max_degrees, hts, ht), rtol=EXP_RTOL, atol=0)

    def test_compare_variants_rows(self, psky: PolynomialSky) -> None:
        gts, gt = fit.chebyshev_grid(GRID)
        hts, ht = fit.held_out_points(6, 1)
        samples = {"grid": (gts, gt, psky.values(gts, gt), psky.denominator(gts, gt)),
                   "test": (hts, ht, psky.values(hts, ht), psky.denominator(hts, ht))}
        rows = fit.compare_variants(samples, (3, 2), 3)
        assert [r["variant"] for r in rows] == list(fit.VARIANTS)
        shipped = rows[-1]
        assert shipped["variant"] == "both (shipped)"
        # The shipped form represents this data exactly; the others cannot.
        assert shipped["e_mean_worst_3"] < EXACT_BUDGET
        assert all(r["e_mean_worst_3"] > 1e3 * EXACT_BUDGET for r in rows[:-1])


# --------------------------------------------------------------------------- #
# The sun's table
# --------------------------------------------------------------------------- #
def _sun_x(ts: np.ndarray) -> np.ndarray:
    """The air-mass variable typed from the file's definition with skysh.model.solar's Kasten formula."""
    m0, m1 = solar.relative_optical_mass([0.0, HALF_PI])
    return np.clip(2.0 * (solar.relative_optical_mass(ts) - m0) / (m1 - m0) - 1.0, -1.0, 1.0)


class TestSunGrid:
    def test_zenith_of_air_mass(self) -> None:
        m0, m1 = solar.relative_optical_mass([0.0, HALF_PI])
        m = np.linspace(m0 + 1e-6, m1, 500)
        np.testing.assert_allclose(solar.relative_optical_mass(fit.zenith_of_air_mass(m)), m, rtol=AIR_MASS_RTOL, atol=0)
        assert fit.zenith_of_air_mass(np.array([m1]))[0] == pytest.approx(HALF_PI, abs=HALF_PI_ATOL)

    def test_nodes(self) -> None:
        ts, t = fit.sun_grid((6, 4))
        assert ts.shape == t.shape == (24,)
        nodes_x = np.sort(np.cos((2 * np.arange(6) + 1) * math.pi / 12))
        nodes_y = np.sort(np.cos((2 * np.arange(4) + 1) * math.pi / 8))
        np.testing.assert_allclose(np.unique(np.round(_sun_x(ts), 12)), nodes_x, rtol=0, atol=SUN_NODE_ATOL)
        np.testing.assert_allclose(np.unique(2.0 * (t - 2.5) / 3.5 - 1.0), nodes_y, rtol=0, atol=NODE_ATOL)

    def test_held_out_points(self) -> None:
        ts, t = fit.sun_held_out_points(2000, 5)
        assert ts.shape == t.shape == (2000 + 2000 + 4 * 250 + 4,)
        assert np.all((ts >= 0) & (ts <= HALF_PI) & (t >= 2.5) & (t <= 6.0))
        assert set(zip(ts[-4:], t[-4:])) == {(0.0, 2.5), (0.0, 6.0), (HALF_PI, 2.5), (HALF_PI, 6.0)}
        # The second block is uniform in the air mass: most of it within 5 degrees of the horizon, as m's range is.
        m0, m1 = solar.relative_optical_mass([0.0, HALF_PI])
        share = (m1 - solar.relative_optical_mass(math.radians(85.0))) / (m1 - m0)
        near = np.mean(ts[2000:4000] > math.radians(85.0))
        assert abs(near - share) < AIR_MASS_SHARE_ATOL and share > 0.7
        assert np.mean(ts[:2000] > math.radians(85.0)) < ZENITH_SHARE_MAX  # the first block is uniform in the zenith
        np.testing.assert_array_equal(fit.sun_held_out_points(2000, 5)[0], ts)  # seeded


class TestSunFit:
    def test_recovers_exact_log_polynomial(self) -> None:
        degrees = (5, 3)
        p = np.random.default_rng(2).normal(size=(3, degrees[0] + 1, degrees[1] + 1))
        p[:, 0, 0] += 8.0  # about ln(3000 lux)

        def xyz(ts: np.ndarray, t: np.ndarray) -> np.ndarray:
            y = 2.0 * (t - 2.5) / 3.5 - 1.0
            return np.exp(np.stack([npcheb.chebval2d(_sun_x(ts), y, p[c]) for c in range(3)], axis=-1))

        ts, t = fit.sun_grid((12, 8))
        table, condition = fit.fit_sun_table(ts, t, xyz(ts, t), degrees)
        assert table.shape == (24, 1, 3) and condition < CONDITION_MAX
        np.testing.assert_allclose(table[:, 0, :], p.reshape(3, -1).T, rtol=0, atol=FIT_EXACT_RTOL * np.abs(p).max())
        hs, ht = fit.sun_held_out_points(50, 3)
        np.testing.assert_allclose(fit.evaluate_sun_table(table, degrees, hs, ht), xyz(hs, ht), rtol=EXP_RTOL, atol=0)

    def test_sun_errors_definitions(self) -> None:
        truth = np.array([[1.0, 2.0, 4.0], [10.0, 10.0, 10.0]])
        fitted = truth * np.array([[1.0, 1.01, 1.0], [1.0, 1.0, 0.98]])
        identity = np.eye(3)
        swap = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # R = X - Y: crosses zero at row 1
        e = fit.sun_errors(fitted, truth, identity, (np.array([0.1, 0.2]), np.array([3.0, 4.0])))
        assert e["xyz_relative_worst"] == pytest.approx([0.0, 0.01, 0.02], rel=ARITH_RTOL)
        assert e["worst"] == pytest.approx(0.02, rel=ARITH_RTOL) and e["worst_at"] == [0.2, 4.0]
        assert e["rgb_relative_worst"] == pytest.approx([0.0, 0.01, 0.02], rel=ARITH_RTOL)
        # The floor: R = X - Y = 0 at row 1 and -1 at row 0; |dR| / max(|R|, Y) = 0.02 / 2 at row 0.
        f = fit.sun_errors(fitted, truth, swap, (np.zeros(2), np.zeros(2)))
        assert f["rgb_relative_worst"][0] == pytest.approx(0.01, rel=ARITH_RTOL)
        assert f["held_out_points"] == 2 and "floored" in f["definition"]

    def test_real_sun_meets_the_goal(self) -> None:
        """build_sun with the shipped settings: recorded errors recomputed here against skysh.model.solar directly."""
        settings = fit.FitSettings(sun_held_out=64)
        matrix = preetham.rgb_from_xyz_matrix("sRGB")
        sun, block = fit.build_sun(settings, matrix)
        assert sun.degrees.tolist() == [list(settings.sun_degrees)] and block["rgb_from_xyz"] == matrix.tolist()
        hs, ht = fit.sun_held_out_points(64, settings.seed)
        xyz = fit.evaluate_sun_table(sun.table, settings.sun_degrees, hs, ht)
        assert np.abs(xyz / solar.illuminance_xyz(hs, ht) - 1.0).max() == pytest.approx(
            max(block["errors"]["xyz_relative_worst"]), rel=RECOMPUTED_RTOL)
        assert block["errors"]["worst"] <= SUN_GOAL and block["largest_abs_sum"] < 50.0
        assert block["condition_number"] < CONDITION_MAX


# --------------------------------------------------------------------------- #
# tools/fit_sky.py: --out, --force and one-line refusals
# --------------------------------------------------------------------------- #
@pytest.fixture(scope="module")
def fit_sky():
    """skysh.app.fit_command (what `skysh fit` and tools/fit_sky.py run)."""
    from skysh.app import fit_command

    return fit_command


def _with_shipped_irradiance(table: coefficient_file.SkyTable) -> coefficient_file.SkyTable:
    """``table`` with the shipped file's irradiance table and block (format 4 requires one; fit.build fits the sky)."""
    shipped = coefficient_file.read()
    blocks = {**table.metadata["tables"], "irradiance": shipped.metadata["tables"]["irradiance"]}
    return coefficient_file.SkyTable(table.table, table.degrees, {**table.metadata, "tables": blocks},
                                     {**table.tables, "irradiance": shipped.tables["irradiance"]})


@pytest.fixture()
def fake_build(monkeypatch: pytest.MonkeyPatch, psky: PolynomialSky) -> list:
    """fit.build replaced by the synthetic table (no projections): records its calls."""
    calls: list = []

    def build(settings, tolerance=None, mapper=map, provenance=None):
        calls.append(settings)
        sun = coefficient_file.NamedTable(np.zeros((1, 1, 3)), np.zeros((1, 2), dtype=np.int64))
        metadata = {"condition_number": 1.0, "tables": {"sun": {"rgb_from_xyz": np.eye(3).tolist()}}, **(provenance or {})}
        table = coefficient_file.SkyTable(psky.table(), TRUE_DEGREES.copy(), metadata, {"sun": sun})
        report = {"held_out_points": 0, "by_bands": {}}
        return table, report, {}

    monkeypatch.setattr(fit, "build", build)
    shipped = coefficient_file.read()  # the irradiance's convex problems replaced by the shipped table
    irradiance = (shipped.tables["irradiance"].table, shipped.tables["irradiance"].degrees,
                  shipped.metadata["tables"]["irradiance"])
    monkeypatch.setattr(irradiance_fit, "build_table", lambda *args, **kwargs: irradiance)
    monkeypatch.setattr(irradiance_fit, "missing_solver_packages", lambda: ())  # build_table needs no solver now
    return calls


FRESH_TIMEOUT_S: float = 120.0
"""Hang guard of fit_sky.py's refusal in a fresh interpreter (imports only: about a second)."""


def _tool_refuses(fit_sky, argv: list[str], capsys: pytest.CaptureFixture, match: str) -> None:
    """main(argv) exits with status 2 after exactly one line '<prog>: error: ...' naming the problem."""
    with pytest.raises(SystemExit) as info:
        fit_sky.main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ": error: " in err and "usage:" not in err, err
    assert match in err, err


class TestFitToolOutput:
    def test_out_required(self, fit_sky, capsys: pytest.CaptureFixture, fake_build: list) -> None:
        before = coefficient_file.default_path().read_bytes()
        _tool_refuses(fit_sky, ["--quick"], capsys, "--out is required")
        _tool_refuses(fit_sky, [], capsys, "--out is required")
        assert fake_build == [] and coefficient_file.default_path().read_bytes() == before

    def test_shipped_file_needs_force(self, fit_sky, tmp_path: Path, capsys: pytest.CaptureFixture,
                                      monkeypatch: pytest.MonkeyPatch, fake_build: list) -> None:
        shipped = ROOT / "data" / coefficient_file.DEFAULT_FILE_NAME
        before = shipped.read_bytes()
        link = tmp_path / "link.npz"
        link.symlink_to(shipped)
        monkeypatch.chdir(ROOT)
        for out in (str(shipped), "data/preetham_sh.npz", "skysh/../data/preetham_sh.npz", str(link)):
            _tool_refuses(fit_sky, ["--quick", "--out", out], capsys, "is the shipped coefficient file; add --force")
        installed = Path(fit_sky.skysh.__file__).resolve().parent / "data" / coefficient_file.DEFAULT_FILE_NAME
        assert installed in fit_sky.shipped_files()
        _tool_refuses(fit_sky, ["--out", str(installed)], capsys, "add --force")
        assert fake_build == [] and shipped.read_bytes() == before

    def test_force_replaces_the_named_file(self, fit_sky, tmp_path: Path, capsys: pytest.CaptureFixture,
                                           monkeypatch: pytest.MonkeyPatch, fake_build: list, psky: PolynomialSky) -> None:
        protected = tmp_path / "shipped.npz"
        protected.write_bytes(b"the shipped bytes")
        monkeypatch.setattr(fit_sky, "shipped_files", lambda: [protected])
        _tool_refuses(fit_sky, ["--out", str(protected), "--no-progress"], capsys, "add --force")
        assert protected.read_bytes() == b"the shipped bytes"
        assert fit_sky.main(["--out", str(protected), "--force", "--no-progress", "--jobs", "1"]) == 0
        np.testing.assert_array_equal(coefficient_file.read(protected).table, psky.table())
        # Any other file is written without --force, existing or not.
        other = tmp_path / "other.npz"
        other.write_bytes(b"old")
        assert fit_sky.main(["--out", str(other), "--no-progress", "--jobs", "1"]) == 0
        assert coefficient_file.read(other).bands == 3 and len(fake_build) == 2

    @pytest.mark.parametrize(
        "argv, match",
        [
            (["--bogus"], "unrecognized arguments: --bogus"),
            (["--out", "/tmp/x.npz", "--bands", "9"], "--bands"),
            (["--out", "/tmp/x.npz", "--degrees", "3"], "--degrees"),
            (["--out", "/tmp/x.npz", "--degrees", "32,7"], "--degrees must be at most 31,31"),
            (["--out", "/tmp/x.npz", "--sun-degrees", "12,40"], "--sun-degrees must be at most 31,31"),
            (["--out", "/tmp/x.npz", "--grid", "0,8"], "--grid must be two integers in [1, 256]"),
            (["--out", "/tmp/x.npz", "--samples", "0"], "--samples must be an integer in [1, 1000000]"),
            (["--out", "/tmp/x.npz", "--tolerance", "nan"], "--tolerance must lie in (0, 1)"),
            (["--out", "/tmp/x.npz", "--jobs", "0"], "--jobs must be an integer in [1, 256]"),
            (["--out", "/tmp/x.npz", "--colourspace", "Bogus"], "--colourspace must be one of: sRGB, ITU-R BT.709"),
            (["--out", "/tmp"], "--out /tmp is a directory"),
            (["--out", str(ROOT / "skysh" / "runtime.py"), "--force"], "lies inside skysh's own files"),
            (["--out", str(ROOT / "data" / "other.npz"), "--force"], "lies inside skysh's own files"),
        ],
        ids=["unknown-flag", "bands", "degrees-form", "degrees-bound", "sun-degrees-bound", "grid", "samples", "tolerance",
             "jobs", "colourspace", "directory", "package-module", "package-data"],
    )
    def test_one_line_refusals(self, fit_sky, capsys: pytest.CaptureFixture, fake_build: list, argv: list, match: str) -> None:
        _tool_refuses(fit_sky, argv, capsys, match)
        assert fake_build == []

    @pytest.mark.parametrize("extra", [[], ["--compare-scalings"]], ids=["fit", "compare-scalings"])
    def test_refuses_without_cvxpy_before_any_work(self, fit_sky, tmp_path: Path, capsys: pytest.CaptureFixture,
                                                   monkeypatch: pytest.MonkeyPatch, fake_build: list,
                                                   extra: list) -> None:
        # Every file needs the irradiance table (a required table of the format); --compare-scalings writes one too.
        monkeypatch.setattr(irradiance_fit, "missing_solver_packages", lambda: ("cvxpy",))
        out = tmp_path / "sky.npz"
        _tool_refuses(fit_sky, ["--quick", "--out", str(out), *extra], capsys,
                      f"error: {fit_sky.IRRADIANCE_TASK} needs cvxpy (the tools extra), which is not installed: "
                      'pip install -e ".[tools]"')
        assert fake_build == [] and not out.exists()
        assert "irradiance" in {spec.name for spec in coefficient_file.TABLES if spec.required}

    def test_refuses_without_cvxpy_in_a_fresh_interpreter(self, tmp_path: Path) -> None:
        out = tmp_path / "sky.npz"
        proc = subprocess.run(script_without_cvxpy(ROOT / "tools" / "fit_sky.py", "--quick", "--out", str(out)),
                              cwd=ROOT, capture_output=True, text=True, timeout=FRESH_TIMEOUT_S, check=False)
        assert proc.returncode == 2 and proc.stdout == "", proc.stderr
        assert proc.stderr.startswith("fit_sky.py: error: ") and proc.stderr.count("\n") == 1, proc.stderr
        assert "needs cvxpy" in proc.stderr and 'pip install -e ".[tools]"' in proc.stderr and not out.exists()

    def test_through_the_cli(self, capsys: pytest.CaptureFixture) -> None:
        from skysh.app import cli

        assert cli.main(["fit", "--bogus"]) == 2
        err = capsys.readouterr().err
        assert err == "skysh fit: error: unrecognized arguments: --bogus\n"
        assert cli.main(["fit", "--quick"]) == 2
        assert capsys.readouterr().err.startswith("skysh fit: error: --out is required")
