"""
Tests of the tabulated irradiance (issue 18)
============================================

The coefficient file's certified 3-band irradiance table as the runtime serves it
(``SkySH.coefficients(..., irradiance=True)``), checked against independent references:

-   never negative: the exact minimum (:func:`skysh.sh.minimum.exact_min`, the minimiser the
    fit certified its own points with, itself checked against dense sampling and brute
    force in ``tests/post/test_dering.py``; not the file's recorded certificate) at 12,004
    held-out (sun zenith, turbidity) points of this file's own seed, other than the fit's,
    corners and edges included; negative control: the plain projection goes negative there;
-   the runtime equals :func:`skysh.table.irradiance_fit.evaluate_irradiance_table` rotated by
    :func:`skysh.sh.basis.rotate_z`, scalar and batch; rotation equivariance on normals;
-   closer to the true irradiance (:func:`skysh.table.irradiance_fit.true_irradiance`) than the
    old deringed pipeline, under the study's worst figure; negative control: the Gibbs
    filter's pipeline is far above it;
-   sun and ground: the sum stays non-negative, and is the table plus the same sun and
    ground parts as the old pipeline's; colourspaces: non-negative matrices keep it, a
    sign-mixing one is deringed after the conversion (negative control: without it the
    converted light goes negative);
-   defaults by intent, the old pipeline one option away, bad input;
-   :func:`skysh.table.irradiance_fit.build_table` on synthetic optima (fast): its block, and its
    refusal of a table that goes negative; a slow check against fresh convex solves (these three skipped
    without cvxpy, the tools extra).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import needs_cvxpy

from skysh.post import dering
from skysh.runtime import SkySH
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin
from skysh.table import coefficient_file as cf
from skysh.table import fit
from skysh.table import irradiance_fit as irf

HALF_PI = 0.5 * math.pi

AGREE_RTOL: float = 1e-12
"""Runtime vs evaluate_irradiance_table + rotate_z, relative to the largest |coefficient|: two
orders of the same float64 polynomial (cos-based Chebyshev terms vs the recurrence, rotation by
angle addition vs direct), each within ~100 eps of its exact value."""

STUDY_WORST: float = 0.0641
"""Worst error of the tabulated irradiance over the study's 42 skies (build/irradiance_study/report.md,
section 3, the tabulated row of the shipped objective: 6.41 % of each channel's mean)."""

TRUTH_TAIL: float = 5e-4
"""The 32-band truth here against the study's 64 bands: at most about 5e-4 of the mean
(skysh.table.irradiance_fit.TRUTH_BANDS: the convergence table of tools/irradiance_study.py)."""

ISSUE_GOAL: float = 0.07
"""Issue 18: the worst error over the domain <= 7 % of the mean."""

EXACT_MIN_SLACK: float = 0.0
"""exact_min never exceeds the true minimum (its rounding allowance is subtracted), so a
non-negative function passes with no slack; the table's margin is 1e-3 of the mean."""

FIT_RTOL: float = 5e-3
"""The table against fresh exact optima, max over the sphere / mean: the study measured a worst of
0.24 % on 164 held-out points (report.md, section 3); 0.5 % leaves room for other points."""

EXACT_FIT_TOL: float = 1e-12
"""build_table's recorded worst fit error (max over the sphere / mean) on data of the table's own form (the
luminance scale times an affine function of x): a least-squares fit that reproduces its data up to rounding
of the Chebyshev sums and the exact minimum search, a few hundred eps."""

POINTS: int = 10_000
EDGE: int = 500
SEED: int = 1818
"""Held-out points of these tests: their own seed (the file's certificate used 2025, its fit 2018)."""


@pytest.fixture(scope="module")
def points() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """12,004 (sun zenith, turbidity) points: uniform random, the 4 corners, 500 per edge; random azimuths."""
    ts, tu = fit.held_out_points(POINTS, SEED)  # corners included
    ets, etu = fit.edge_points(EDGE, SEED + 1)
    ts, tu = np.concatenate([ts, ets]), np.concatenate([tu, etu])
    return ts, tu, np.random.default_rng(SEED + 2).uniform(-math.pi, math.pi, ts.size)


def _relative_minimum(coeffs: np.ndarray) -> np.ndarray:
    """Exact minimum over the sphere / the mean (Y00 e0), lowest channel: (..., 9, 3) -> (...)."""
    return np.min(shmin.exact_min(coeffs) / (irf.Y00 * coeffs[..., 0, :]), axis=-1)


# --------------------------------------------------------------------------- #
# Never negative
# --------------------------------------------------------------------------- #
class TestNonNegative:
    def test_held_out_points(self, sky: SkySH, points: tuple) -> None:
        ts, tu, phi = points
        assert ts.size >= 10_000 and {(0.0, 2.5), (0.0, 6.0), (HALF_PI, 2.5), (HALF_PI, 6.0)} <= set(zip(ts, tu))
        lowest = _relative_minimum(sky.coefficients(ts, tu, phi, irradiance=True))
        assert np.all(lowest >= EXACT_MIN_SLACK), (lowest.min(), ts[np.argmin(lowest)], tu[np.argmin(lowest)])

    def test_negative_control_plain_projection(self, sky: SkySH, points: tuple) -> None:
        """The unconstrained L2 projection (no filter, no deringing) goes negative: the check can fail."""
        ts, tu, phi = points
        plain = sky.coefficients(ts, tu, phi, irradiance=True, irradiance_table=False, gibbs=False, dering=False)
        assert np.sum(_relative_minimum(plain) < 0.0) > ts.size // 2

    def test_scalar_path(self, sky: SkySH, points: tuple) -> None:
        ts, tu, phi = points
        for k in range(0, ts.size, 601):  # the corners come first
            c = sky.coefficients(float(ts[k]), float(tu[k]), float(phi[k]), irradiance=True)
            assert _relative_minimum(c) >= EXACT_MIN_SLACK

    def test_file_records_the_certificate(self, sky: SkySH) -> None:
        """The block the format requires (not used as evidence above: the tests recompute it)."""
        block = sky.metadata["tables"]["irradiance"]
        assert block["margin"] == irf.RECOMMENDED.margin and block["objective"]["method"] == irf.RECOMMENDED.method
        proof = block["nonnegativity"]
        assert proof["negative"] == 0 and proof["points"] >= 10_000 and proof["lowest"] > 0.0
        assert block["fit_error"]["points"] >= 100 and block["degrees"] == [[13, 7]] * 3


# --------------------------------------------------------------------------- #
# The runtime evaluates the table
# --------------------------------------------------------------------------- #
class TestEvaluation:
    def test_matches_the_fit_evaluation_and_rotation(self, sky: SkySH, points: tuple) -> None:
        named = sky.table.tables["irradiance"]
        ts, tu, phi = (a[:500] for a in points)
        reference = sh.rotate_z(irf.evaluate_irradiance_table(named.table, named.degrees, ts, tu), phi)
        scale = np.abs(reference).max()
        np.testing.assert_allclose(sky.coefficients(ts, tu, phi, irradiance=True), reference, rtol=0,
                                   atol=AGREE_RTOL * scale)
        for k in (0, 3, 77, 499):
            got = sky.coefficients(float(ts[k]), float(tu[k]), float(phi[k]), irradiance=True)
            np.testing.assert_allclose(got, reference[k], rtol=0, atol=AGREE_RTOL * scale)
        radiance = sky.coefficients(ts, tu, phi, irradiance_table=True)  # the radiance-equivalent
        np.testing.assert_allclose(radiance * irf.LOBE[:, None], reference, rtol=0, atol=AGREE_RTOL * scale)

    def test_rotation_equivariance(self, sky: SkySH) -> None:
        normals = irf.half_sphere_normals(256)
        for ts, tu, phi in ((0.3, 2.7, 0.9), (1.5, 5.5, -2.4), (HALF_PI, 4.0, 3.0)):
            turned = normals @ sh.rotation_z_matrix(phi).T
            at_phi = sh.basis(turned, 3) @ sky.coefficients(ts, tu, phi, irradiance=True)
            at_zero = sh.basis(normals, 3) @ sky.coefficients(ts, tu, 0.0, irradiance=True)
            np.testing.assert_allclose(at_phi, at_zero, rtol=0, atol=AGREE_RTOL * np.abs(at_zero).max())

    def test_irradiance_at_follows(self, sky: SkySH) -> None:
        normals = irf.half_sphere_normals(64)
        for option in (None, False):
            got = sky.irradiance_at(normals, 0.8, 3.1, 0.4, irradiance_table=option)
            c = sky.coefficients(0.8, 3.1, 0.4, irradiance=True, irradiance_table=option)
            np.testing.assert_array_equal(got, sh.basis(normals, 3) @ c)
        assert not np.array_equal(sky.irradiance_at(normals, 0.8, 3.1, 0.4),
                                  sky.irradiance_at(normals, 0.8, 3.1, 0.4, irradiance_table=False))


# --------------------------------------------------------------------------- #
# Closer to the truth
# --------------------------------------------------------------------------- #
SKIES: tuple[tuple[float, float], ...] = ((0.0, 2.5), (60.0, 4.0), (85.0, 2.5), (90.0, 2.5), (90.0, 6.0))
"""(sun zenith in degrees, turbidity): the study's worst sky (90, 2.5) and others across the domain."""


@pytest.fixture(scope="module")
def truths() -> list[np.ndarray]:
    return [irf.true_irradiance(math.radians(zd), t) for zd, t in SKIES]


def _worst_error(coeffs: np.ndarray, truth: np.ndarray, basis: np.ndarray) -> float:
    """max over normals and channels of |E - E_true| / the true mean, per channel."""
    return float(np.max(np.abs(basis[:, :9] @ coeffs - basis @ truth) / (irf.Y00 * truth[0])))


class TestAccuracy:
    def test_error_against_the_truth(self, sky: SkySH, truths: list[np.ndarray]) -> None:
        dirs, _ = sh.quadrature_rule(48)
        basis = sh.basis(dirs, irf.TRUTH_BANDS)
        for (zd, t), truth in zip(SKIES, truths):
            table = _worst_error(sky.coefficients(math.radians(zd), t, 0.0, irradiance=True), truth, basis)
            old = _worst_error(sky.coefficients(math.radians(zd), t, 0.0, irradiance=True, irradiance_table=False),
                               truth, basis)
            gibbs = _worst_error(sky.coefficients(math.radians(zd), t, 0.0, irradiance=True, gibbs=True), truth, basis)
            assert table <= STUDY_WORST + TRUTH_TAIL and table < old, (zd, t, table, old)
            assert gibbs > ISSUE_GOAL, (zd, t, gibbs)  # negative control: the check can fail


# --------------------------------------------------------------------------- #
# With the sun, the ground and colourspaces
# --------------------------------------------------------------------------- #
class TestComposition:
    def test_sun_and_ground_stay_non_negative(self, sky: SkySH, points: tuple) -> None:
        ts, tu, phi = (a[:2000] for a in points)
        albedo = np.random.default_rng(SEED + 3).uniform(0.0, 1.0, 3).tolist()
        for kwargs in ({"sun": True}, {"ground_albedo": 1.0}, {"sun": True, "ground_albedo": albedo}):
            lit = sky.coefficients(ts, tu, phi, irradiance=True, **kwargs)
            assert np.all(_relative_minimum(lit) >= EXACT_MIN_SLACK), kwargs
            one = sky.coefficients(float(ts[5]), float(tu[5]), float(phi[5]), irradiance=True, **kwargs)
            np.testing.assert_allclose(one, lit[5], rtol=0, atol=AGREE_RTOL * np.abs(lit[5]).max())

    def test_table_plus_the_old_pipelines_sun_and_ground(self, sky: SkySH, points: tuple) -> None:
        ts, tu, phi = (a[:50] for a in points)
        old = {"irradiance": True, "irradiance_table": False, "dering": False}  # Gibbs off as the table's
        parts = sky.coefficients(ts, tu, phi, sun=True, ground_albedo=0.4, **old) - sky.coefficients(ts, tu, phi, **old)
        got = sky.coefficients(ts, tu, phi, irradiance=True, sun=True, ground_albedo=0.4)
        expected = sky.coefficients(ts, tu, phi, irradiance=True) + parts
        np.testing.assert_allclose(got, expected, rtol=0, atol=AGREE_RTOL * np.abs(expected).max())

    def test_non_negative_matrix_keeps_it(self, sky: SkySH, points: tuple) -> None:
        ts, tu, phi = (a[:2000] for a in points)
        for wider in ("Display P3", "ACEScg", "ITU-R BT.2020"):  # docs/irradiance.md names these
            assert np.all(sky._colour_matrix(wider) >= 0.0) and not sky._mixing[wider], wider
        matrix = sky._colour_matrix("ITU-R BT.2020")  # sRGB inside BT.2020: a non-negative combination, nothing to dering
        got = sky.coefficients(ts, tu, phi, irradiance=True, colourspace="ITU-R BT.2020")
        np.testing.assert_array_equal(got, sky.coefficients(ts, tu, phi, irradiance=True) @ matrix.T)
        assert np.all(_relative_minimum(got) >= EXACT_MIN_SLACK)

    def test_sign_mixing_matrix_is_deringed_after(self, sky: SkySH, points: tuple,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
        ts, tu, phi = (a[:2000] for a in points)
        mixing = np.array([[1.0, -0.6, 0.0], [0.0, 1.0, 0.0], [-0.3, 0.0, 1.0]])  # a strongly shifted gamut
        monkeypatch.setitem(sky._colour_matrices, "mixing", mixing)
        monkeypatch.setitem(sky._mixing, "mixing", True)
        converted = sky.coefficients(ts, tu, phi, irradiance=True) @ mixing.T
        negative = _relative_minimum(converted) < 0.0
        assert negative.any() and not negative.all()  # negative control: the conversion alone goes negative
        got = sky.coefficients(ts, tu, phi, irradiance=True, colourspace="mixing")
        assert np.all(shmin.exact_min(got) >= 0.0)
        np.testing.assert_array_equal(got[~negative], converted[~negative])  # a no-op where non-negative
        np.testing.assert_array_equal(got[negative], dering.dering(converted[negative], "radiance")[0])
        lit = sky.coefficients(ts, tu, phi, irradiance=True, colourspace="mixing", sun=True, ground_albedo=0.5)
        assert np.all(shmin.exact_min(lit) >= 0.0)
        kept = sky.coefficients(ts, tu, phi, irradiance=True, colourspace="mixing", dering=False, irradiance_table=True)
        np.testing.assert_array_equal(kept, converted)  # dering=False: not deringed


# --------------------------------------------------------------------------- #
# Defaults by intent, the old pipeline, bad input
# --------------------------------------------------------------------------- #
class TestOptions:
    FRAME = (0.9, 3.4, 1.3)

    def test_defaults_by_intent(self, sky: SkySH) -> None:
        table = sky.coefficients(*self.FRAME, irradiance=True, irradiance_table=True)
        for kwargs in ({}, {"gibbs": False}, {"dering": True}, {"bands": np.int64(3)}):
            np.testing.assert_array_equal(sky.coefficients(*self.FRAME, irradiance=True, **kwargs), table)
        old = {"irradiance": True, "irradiance_table": False}
        for kwargs in ({"gibbs": True}, {"dering": False}):
            np.testing.assert_array_equal(sky.coefficients(*self.FRAME, **kwargs, irradiance=True),
                                          sky.coefficients(*self.FRAME, **kwargs, **old))
        for bands in (2, 4):
            np.testing.assert_array_equal(sky.coefficients(*self.FRAME, bands=bands, irradiance=True),
                                          sky.coefficients(*self.FRAME, bands=bands, **old))
        np.testing.assert_array_equal(sky.coefficients(*self.FRAME), sky.coefficients(*self.FRAME, irradiance_table=False))

    def test_old_pipeline_one_option_away(self, sky: SkySH) -> None:
        """irradiance_table=False: the Gibbs-free sky, deringed (skysh.post.dering), times A_l."""
        sky_only = sky.coefficients(*self.FRAME, gibbs=False, dering=False)
        expected = dering.dering(sky_only)[0] * irf.LOBE[:, None]
        np.testing.assert_allclose(sky.coefficients(*self.FRAME, irradiance=True, irradiance_table=False), expected,
                                   rtol=0, atol=AGREE_RTOL * np.abs(expected).max())

    def test_without_the_table(self, sky: SkySH) -> None:
        bare = SkySH(cf.SkyTable(sky.table.table, sky.table.degrees, {}))
        assert sky.has_irradiance_table and not bare.has_irradiance_table
        np.testing.assert_array_equal(bare.coefficients(*self.FRAME, irradiance=True),
                                      sky.coefficients(*self.FRAME, irradiance=True, irradiance_table=False))
        with pytest.raises(ValueError, match=r"^irradiance_table"):
            bare.coefficients(*self.FRAME, irradiance=True, irradiance_table=True)

    @pytest.mark.parametrize("kwargs, match", [
        ({"bands": 2}, "irradiance_table=True needs bands=3"),
        ({"bands": 7}, "irradiance_table=True needs bands=3"),
        ({"gibbs": True}, "irradiance_table=True does not go with gibbs=True"),
        ({"bands": 9}, "bands must be"),
    ], ids=["bands-2", "bands-7", "gibbs", "bands-out-of-range"])
    def test_true_where_it_does_not_apply(self, sky: SkySH, kwargs: dict, match: str) -> None:
        with pytest.raises(ValueError, match=match):
            sky.coefficients(*self.FRAME, irradiance=True, irradiance_table=True, **kwargs)

    @pytest.mark.parametrize("value", ["yes", 1, 0.0, [True]], ids=["text", "int", "float", "list"])
    def test_not_a_bool(self, sky: SkySH, value: object) -> None:
        with pytest.raises(TypeError, match="irradiance_table must be a bool"):
            sky.coefficients(*self.FRAME, irradiance=True, irradiance_table=value)

    def test_domain_still_checked(self, sky: SkySH) -> None:
        with pytest.raises(ValueError, match="sun_zenith"):
            sky.coefficients(2.0, 3.0, irradiance=True)
        with pytest.raises(ValueError, match="turbidity"):
            sky.coefficients(np.array([0.5]), 7.0, irradiance=True)
        assert np.all(np.isfinite(sky.coefficients(np.array([0.0, HALF_PI]), np.array([2.5, 6.0]), irradiance=True)))


# --------------------------------------------------------------------------- #
# build_table
# --------------------------------------------------------------------------- #
def _synthetic(offset: float) -> object:
    """A mapper serving exact 'optima' of the table's own form: lum x A_l x (affine in x, y), any point."""
    from skysh.model.preetham import luminance_scale

    rows = np.zeros((9, 3))
    rows[0], rows[2], rows[3], rows[6] = offset, 0.5, 0.3, 0.2

    def mapper(function, jobs):
        jobs = list(jobs)
        ts, tu = np.array([j[0] for j in jobs]), np.array([j[1] for j in jobs])
        x = 4.0 * ts / math.pi - 1.0
        e = rows * (1.0 + 0.1 * x)[:, None, None] * luminance_scale(ts, tu)[:, None, None] * irf.LOBE[:, None]
        return [(e[k], {"minimum": irf.sphere_minimum(e[k]) / (irf.Y00 * e[k, 0])}) for k in range(len(jobs))]

    return mapper


@needs_cvxpy  # build_table refuses without the solver (its block records the solver's versions)
class TestBuildTable:
    def test_block_and_exact_fit(self) -> None:
        table, degrees, block = irf.build_table((6, 4), (2, 1), mapper=_synthetic(3.0), held_out=(4, 1))
        assert table.shape == (6, 6, 3) and degrees.tolist() == [[2, 1]] * 3
        assert {"objective", "margin", "fit_error", "nonnegativity"} <= set(block)
        assert block["fit_error"]["worst"] < EXACT_FIT_TOL and block["fit_error"]["points"] == 4 + 4 + 4
        assert block["nonnegativity"]["negative"] == 0 and block["nonnegativity"]["points"] == 12_004
        again = irf.build_table((6, 4), (2, 1), mapper=_synthetic(3.0), held_out=(4, 1))
        np.testing.assert_array_equal(again[0], table)
        assert again[2] == block  # deterministic

    def test_refuses_a_negative_table(self) -> None:
        with pytest.raises(RuntimeError, match=r"negative at .* held-out points"):
            irf.build_table((6, 4), (2, 1), mapper=_synthetic(0.5), held_out=(4, 1))


@pytest.mark.slow
@needs_cvxpy
def test_table_against_fresh_solves(sky: SkySH) -> None:
    """Two held-out points solved afresh (in two orders: the solver is deterministic) vs the table."""
    jobs = [(0.6, 3.3, irf.RECOMMENDED), (1.45, 5.2, irf.RECOMMENDED)]
    first = [irf.constrained_point(job)[0] for job in jobs]
    second = [irf.constrained_point(job)[0] for job in reversed(jobs)][::-1]
    named = sky.table.tables["irradiance"]
    for (ts, tu, _), a, b in zip(jobs, first, second):
        np.testing.assert_array_equal(a, b)
        d = irf.evaluate_irradiance_table(named.table, named.degrees, [ts], [tu])[0] - a
        gap = np.maximum(-shmin.exact_min(d), -shmin.exact_min(-d)) / (irf.Y00 * a[0])
        assert np.all(gap <= FIT_RTOL), (ts, tu, gap)
