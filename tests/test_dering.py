"""
Tests of :mod:`skysh.dering`
============================

References are independent of the module: minima of SH functions come from a
dense product-quadrature sphere (``sh.quadrature_rule`` nodes, ``sh.basis``)
refined by shrinking local grids in a tangent plane built here (no Newton, no
duality); windowed delta lights are projected with ``sh.basis`` and checked on a
dense sphere, and their zonal profile on a dense grid in t = cos(angle); the
clamped-cosine factors come from ``sh.cosine_lobe``. Lights used as inputs are
non-negative by construction (sums of positive deltas, of deltas along arcs,
and an ambient term).

One class per public function (plus the window table), each with reference
values, batched shapes and NaN / bad-input cases. Every tolerance is a named
constant with its reason. No timing assertions (``benchmarks/bench_dering.py``).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.polynomial import legendre as npleg

from skysh import dering, sh

EPS: float = float(np.finfo(np.float64).eps)
"""Machine epsilon of float64."""

BOUND_RTOL: float = 1e-12
"""The bound may exceed the reference minimum only by rounding: a few hundred
flops on numbers of the size of the largest coefficient (relative to it)."""

NONNEG_RTOL: float = 1e-12
"""A deringed function counts as negative below -1e-12 of its mean (rounding of
a 9..49-term sum on values of the size of the mean)."""

REFINE_RTOL: float = 1e-8
"""The dense reference refines to ~1e-5 rad; near a minimum the value then errs
by ~curvature * 1e-10 <= 1e-8 of the largest coefficient (for <= 7 bands)."""

EXACT_VALUE_RTOL: float = 64 * EPS
"""exact_min returns f at its direction: re-evaluating agrees to rounding."""

SCALAR_PATH_RTOL: float = 1e-13
"""min_bound's scalar (math module) path and its numpy path do the same arithmetic
except the order of a few sums (numpy's matrix products); relative to the largest
coefficient they agree to a few eps (measured <= 7e-16 on 3,000 random functions):
1e-13 leaves room without hiding a real difference (the bound's terms are of order 1)."""

CONVERGED_RTOL: float = 1e-13
"""After the shipped Newton steps the bound equals the converged one (64 steps) to
rounding (measured <= 4e-16 of the largest coefficient on random and near-hard-case
functions); a step short would leave up to 1e-10."""

DELTA_T_GRID: int = 200_001
"""Points in t = cos(angle) for the dense check of a windowed delta's profile."""

HYPOTHESIS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
"""Property-test budget: keeps the file under a minute on two cores."""

L_OF: np.ndarray = np.repeat(np.arange(7), 2 * np.arange(7) + 1)
"""Band of every flat index up to 7 bands."""


# --------------------------------------------------------------------------- #
# Independent references
# --------------------------------------------------------------------------- #
def _tangents(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangents by a cross product with the least-aligned axis (not the module's frame)."""
    helper = np.where(np.abs(p[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(p, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(p, e1)


def dense_min(coeffs: np.ndarray) -> np.ndarray:
    """Minimum of SH functions (F, K) over the sphere: 4,608 quadrature nodes, then from the
    4 lowest nodes, 8 rounds of 7 x 7 tangent-plane grids shrinking 3x per round. (F,)."""
    f = np.asarray(coeffs, dtype=np.float64)
    bands = math.isqrt(f.shape[1])
    dirs, _ = sh.quadrature_rule(48)
    vals = f @ sh.basis(dirs, bands).T
    k = 4
    start = np.argpartition(vals, k - 1, axis=1)[:, :k]
    p = dirs[start].reshape(-1, 3)
    best = np.take_along_axis(vals, start, axis=1).reshape(-1)
    fr = np.repeat(f, k, axis=0)
    offs = np.arange(-3, 4, dtype=np.float64)
    uu, vv = (a.ravel() for a in np.meshgrid(offs, offs, indexing="ij"))
    h = 0.05
    for _ in range(8):
        e1, e2 = _tangents(p)
        q = p[:, None] + h * (uu[None, :, None] * e1[:, None] + vv[None, :, None] * e2[:, None])
        q /= np.linalg.norm(q, axis=-1, keepdims=True)
        qv = np.einsum("pk,pjk->pj", fr, sh.basis(q, bands))
        j = np.argmin(qv, axis=1)
        better = qv[np.arange(p.shape[0]), j] < best
        p = np.where(better[:, None], q[np.arange(p.shape[0]), j], p)
        best = np.where(better, qv[np.arange(p.shape[0]), j], best)
        h /= 3.0
    return np.minimum(best.reshape(-1, k).min(axis=1), vals.min(axis=1))


def dense_values(coeffs: np.ndarray, n_theta: int = 48) -> np.ndarray:
    """Values (..., M, C) of SH (..., K, C) on a dense product-quadrature sphere."""
    dirs, _ = sh.quadrature_rule(n_theta)
    y = sh.basis(dirs, math.isqrt(coeffs.shape[-2]))
    return np.einsum("mk,...kc->...mc", y, coeffs)


def delta_profile_min(scales: np.ndarray, kernel: np.ndarray) -> float:
    """Minimum of a windowed delta's zonal profile on a dense t grid, plus the derivative's roots."""
    n = len(scales)
    series = kernel[:n] * scales * (2 * np.arange(n) + 1) / (4.0 * math.pi)
    t = np.linspace(-1.0, 1.0, DELTA_T_GRID)
    vals = npleg.legval(t, series)
    if n > 2:
        r = np.roots(npleg.leg2poly(npleg.legder(series))[::-1])
        r = r[(np.abs(r.imag) < 1e-9) & (np.abs(r.real) <= 1.0)].real
        vals = np.concatenate([vals, npleg.legval(r, series)])
    return float(vals.min())


def unit(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_dirs(rng: np.random.Generator, n: int) -> np.ndarray:
    return unit(rng.normal(size=(n, 3)))


def light(rng: np.random.Generator, bands: int, channels: int = 3) -> np.ndarray:
    """A random non-negative light (K, C): HDR deltas, an arc (linear light) and maybe ambient."""
    c = np.zeros((bands * bands, channels))
    k = int(rng.integers(1, 4))
    c += sh.basis(random_dirs(rng, k), bands).T @ (10.0 ** rng.uniform(-1.0, 3.0, (k, channels)))
    if rng.random() < 0.6:
        a, b = random_dirs(rng, 2)
        b = unit(b - a * (a @ b))
        t = np.linspace(0.0, rng.uniform(0.1, 1.5), 48)
        arc = np.cos(t)[:, None] * a + np.sin(t)[:, None] * b
        c += sh.basis(arc, bands).sum(axis=0)[:, None] * (10.0 ** rng.uniform(0.0, 2.0, channels) / 48)
    if rng.random() < 0.4:
        c[0] += 10.0 ** rng.uniform(-2.0, 1.0, channels) * 2.0 * math.sqrt(math.pi)
    return c


def irradiance(c: np.ndarray) -> np.ndarray:
    return sh.irradiance(c)


def sky_samples(n: int) -> np.ndarray:
    """(n, 9, 3) 3-band sky radiance SH across the domain: SkySH if importable, else the
    reference projection with the zonal Gibbs filter, rotated by the sun azimuth."""
    rng = np.random.default_rng(44)
    zen = np.concatenate([[0.0, math.pi / 2, 0.0, math.pi / 2], rng.uniform(0, math.pi / 2, n - 4)])
    tur = np.concatenate([[2.5, 2.5, 6.0, 6.0], rng.uniform(2.5, 6.0, n - 4)])
    azi = rng.uniform(0.0, 2 * math.pi, n)
    try:
        from skysh import SkySH

        sky = SkySH.load()
        return np.stack(
            [np.asarray(sky.coefficients(z, t, sun_azimuth=a, bands=3, gibbs=True)) for z, t, a in zip(zen, tur, azi)]
        )
    except Exception:  # noqa: BLE001 - the runtime is optional here
        from skysh import preetham

        out = []
        for z, t, a in zip(zen, tur, azi):
            c = preetham.sky_sh(float(z), float(t), bands=3, n=4000)
            c[[0, 2, 6]] *= np.sinc(np.arange(3) / 3.0)[:, None]
            out.append(sh.rotate_z(c, float(a)))
        return np.stack(out)


# --------------------------------------------------------------------------- #
# Windows
# --------------------------------------------------------------------------- #
class TestWindowTable:
    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    @pytest.mark.parametrize("bands", range(1, 8))
    def test_structure(self, bands: int, target: str) -> None:
        table = dering.window_table(bands, target)
        assert table.shape[1] == bands
        assert np.all(table[:, 0] == 1.0)
        assert np.all(table[0] == 1.0)
        assert np.all(np.diff(table, axis=0) <= 0.0)  # each band decreases down the rows
        assert np.all((table >= 0.0) & (table <= 1.0))
        assert not table.flags.writeable

    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    @pytest.mark.parametrize("bands", range(1, 8))
    def test_last_row_makes_any_delta_non_negative(self, bands: int, target: str) -> None:
        kernel = sh.cosine_lobe(7) if target == "irradiance" else np.ones(7)
        row = dering.window_table(bands, target)[-1]
        mean = kernel[0] / (4 * math.pi)
        assert delta_profile_min(row, kernel) >= 0.5 * dering.DELTA_MARGIN * mean
        assert dering.delta_minimum(row, target) >= 0.5 * dering.DELTA_MARGIN * mean

    def test_last_row_on_projected_deltas(self) -> None:
        """The claim through sh.basis on a dense sphere, deltas in many directions."""
        dirs = dering._fibonacci_sphere(50)
        c = sh.basis(dirs, 3)[..., None] * dering.WINDOW_TABLE[-1][L_OF[:9], None]  # (50, 9, 1)
        vals = dense_values(irradiance(c))
        assert vals.min() >= -NONNEG_RTOL * 0.25

    def test_finding_table1_and_eq6_fail(self) -> None:
        kernel = sh.cosine_lobe(7)
        assert delta_profile_min(dering.SEED_TABLE_1[-1, :3], kernel) < -0.02 * 0.25
        assert delta_profile_min(dering.sinc4_window(5.6, 3), kernel) < -0.05 * 0.25
        assert dering.SEED_TABLE_1[-1, 1] > math.sqrt(3) / 2  # no band-2 factor can save it

    def test_table1_is_sinc_power_one(self) -> None:
        """Table 1's first column (w = 16.7) is plain sinc, bands 1..3, to its 4 printed digits."""
        np.testing.assert_allclose(dering.SEED_TABLE_1[1, 1:], np.sinc(np.arange(1, 4) / 16.7), atol=6e-5)

    def test_linear_attenuation_closed_form(self) -> None:
        s1, s2 = dering.sinc4_window(5.6, 3)[1:]
        closed = math.sqrt(15 / 8 * s2 * (1 - 5 * s2 / 8)) / s1
        assert closed == pytest.approx(0.93905, abs=5e-6)
        assert dering.LINEAR_ATTENUATION == pytest.approx(closed, rel=1e-8)  # less only by the margin
        assert dering.LINEAR_ATTENUATION < closed
        np.testing.assert_allclose(dering.WINDOW_TABLE[-1], [1.0, s1 * dering.LINEAR_ATTENUATION, s2])

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="bands"):
            dering.window_table(8)
        with pytest.raises(ValueError, match="target"):
            dering.window_table(3, "luminance")


class TestSinc4:
    def test_values(self) -> None:
        w = 7.0
        l = np.arange(5)  # noqa: E741
        x = math.pi * l[1:] / w
        np.testing.assert_allclose(dering.sinc4_window(w, 5)[1:], (np.sin(x) / x) ** 4, rtol=1e-14)
        assert dering.sinc4_window(w, 5)[0] == 1.0
        assert np.all(dering.sinc4_window(3.5, 7)[4:] == 0.0)  # zero past the cutoff
        assert np.all(dering.sinc4_window(math.inf, 4) == 1.0)

    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    def test_floor_meets_the_claim(self, target: str) -> None:
        kernel = sh.cosine_lobe(7) if target == "irradiance" else np.ones(7)
        w = dering.sinc4_cutoff_floor(3, target)
        assert delta_profile_min(dering.sinc4_window(w, 3), kernel) >= 0.0
        assert delta_profile_min(dering.sinc4_window(w + 0.05, 3), kernel) < 0.0

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="cutoff"):
            dering.sinc4_window(0.0)


class TestDeltaMinimum:
    @pytest.mark.parametrize("scales", [[1.0, 1.0, 1.0], [1.0, 0.8, 0.5], [1.0, 0.9, 0.7, 0.4, 0.2], [1.0, 0.3]])
    def test_against_dense_profile(self, scales: list[float]) -> None:
        s = np.array(scales)
        for target, kernel in (("irradiance", sh.cosine_lobe(7)), ("radiance", np.ones(7))):
            assert dering.delta_minimum(s, target) == pytest.approx(delta_profile_min(s, kernel), abs=1e-10)

    def test_unwindowed_reference(self) -> None:
        # (1/4)(3/8 + 2 t + 15/8 t^2): vertex t = -8/15, value (1/4)(3/8 - 8/15).
        assert dering.delta_minimum([1.0, 1.0, 1.0]) == pytest.approx(0.25 * (3 / 8 - 8 / 15), rel=1e-13)

    def test_punctual_window_finding(self) -> None:
        assert dering.delta_minimum(np.array(dering.PUNCTUAL_WINDOW)) / 0.25 == pytest.approx(-0.0746, abs=5e-4)

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="scales"):
            dering.delta_minimum(np.ones(8))
        with pytest.raises(ValueError, match="scales"):
            dering.delta_minimum([1.0, np.nan])


# --------------------------------------------------------------------------- #
# The bound
# --------------------------------------------------------------------------- #
def _adversarial_functions() -> np.ndarray:
    """(F, 9) adversarial 3-band functions."""
    rng = np.random.default_rng(7)
    out = []
    base = rng.normal(size=9)
    axes = ([0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1])
    for lin in axes + ([1e-300, 0, 0], [1e-160, 1e-160, 0]):  # zero, along every axis, subnormal
        c = base.copy()
        c[1:4] = lin
        out.append(c)
    for i in (4, 5, 7, 8):  # pure |m| = 2 and |m| = 1, with and without DC and a linear part
        for extra in ([0.0] * 9, [1.0] + [0.0] * 8, [1.0, 0, 0.7, 0] + [0.0] * 5, [0.5, 0.3, 0, -0.4] + [0.0] * 5):
            c = np.array(extra, dtype=float)
            c[i] += 1.0
            out.append(c)
    for pair in ((5, 7), (4, 8), (5, 8), (4, 7)):  # |m| = 1 with |m| = 2 and zonal parts
        c = np.zeros(9)
        c[0], c[2], c[6] = 1.2, -0.8, 0.5
        c[list(pair)] = [0.9, -0.6]
        out.append(c)
    for d in dering._fibonacci_sphere(24):  # single deltas and their irradiance
        out.append(sh.basis(d, 3))
        out.append(sh.irradiance(sh.basis(d, 3)))
    out.append(np.zeros(9))
    out.append(np.eye(9)[0])
    return np.array(out)


def _near_zonal_functions(n: int, seed: int) -> np.ndarray:
    """(n, 9) functions zonal about +Z up to tiny |m| = 1 and |m| = 2 parts (1e-12 .. 1),
    the quadratic's vertex mostly inside [-1, 0]: where invariants such as |Q v|^2 - Z^2
    cancel and the dual's smaller eigenvalue is of order S^2 (the trust region's hard case)."""
    rng = np.random.default_rng(seed)
    f = np.zeros((n, 9))
    f[:, 0] = rng.uniform(-1.0, 2.0, n)
    f[:, 2] = rng.uniform(0.0, 1.0, n)
    f[:, 6] = rng.uniform(-1.0, 1.0, n)
    f[:, 5] = rng.normal(size=n) * 10.0 ** rng.uniform(-12.0, 0.0, n)
    f[:, 8] = rng.normal(size=n) * 10.0 ** rng.uniform(-12.0, 0.0, n)
    f[:, 4] = rng.normal(size=n) * rng.uniform(0.0, 1.0, n)
    return f


class TestMinBound:
    def test_never_above_the_dense_minimum_adversarial(self) -> None:
        f = _adversarial_functions()
        bound = dering.min_bound(f[..., None])[:, 0]
        ref = dense_min(f)
        scale = np.abs(f).max(axis=1)
        assert np.all(np.isfinite(bound))
        assert np.all(bound <= ref + BOUND_RTOL * scale)

    @HYPOTHESIS
    @given(seed=st.integers(0, 2**32 - 1), spread=st.floats(0.0, 3.0))
    def test_never_above_the_dense_minimum_random(self, seed: int, spread: float) -> None:
        rng = np.random.default_rng(seed)
        f = rng.normal(size=(40, 9)) * rng.uniform(0.0, spread, size=(40, 9)) ** 2
        bound = dering.min_bound(f[..., None])[:, 0]
        assert np.all(bound <= dense_min(f) + BOUND_RTOL * (np.abs(f).max(axis=1) + 1e-300))

    @HYPOTHESIS
    @given(seed=st.integers(0, 2**32 - 1))
    def test_never_above_for_lights(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        c = np.stack([light(rng, 3, 1) for _ in range(6)])  # (6, 9, 1)
        e = irradiance(c)
        bound = dering.min_bound(e)[:, 0]
        assert np.all(bound <= dense_min(e[..., 0]) + BOUND_RTOL * np.abs(e).max(axis=(1, 2)))

    def test_never_above_exact_min_near_zonal(self) -> None:
        """Tiny |m| = 1 / |m| = 2 parts: exact_min (a value of the function, so never below
        the minimum) is the reference, since the dense one refines only to ~1e-10. A bound
        from cancelling invariants, or from e1 = (a - delta) / 2, was up to 3e-9 too high here."""
        f = _near_zonal_functions(3000, 17)
        bound = dering.min_bound(f[..., None])[:, 0]
        ref = dering.exact_min(f[..., None])[:, 0]
        assert np.all(bound <= ref + BOUND_RTOL * np.abs(f).max(axis=1))

    def test_scalar_path_equals_numpy_path(self) -> None:
        """A (9,) or (9, C <= 8) input takes the math-module path; a batch the numpy one."""
        rng = np.random.default_rng(23)
        f = np.concatenate(
            [
                _adversarial_functions(),
                _near_zonal_functions(200, 29),
                rng.normal(size=(300, 9)) * rng.uniform(0.0, 2.0, size=(300, 9)) ** 2,
                rng.normal(size=(20, 9)) * 10.0 ** rng.uniform(-200.0, 200.0, size=(20, 1)),
            ]
        )
        batch = dering.min_bound(f[..., None])[:, 0]  # (F, 9, 1): the numpy path
        single = np.array([dering.min_bound(row) for row in f])
        rgb = dering.min_bound(f[:6].T)  # (9, 6): the scalar path, several channels
        unit = np.abs(f).max(axis=1)
        assert np.all(np.isfinite(single))
        np.testing.assert_array_less(np.abs(single - batch), SCALAR_PATH_RTOL * unit + 1e-300)
        np.testing.assert_allclose(rgb, single[:6], rtol=0, atol=0)

    def test_scalar_path_never_above_the_dense_minimum(self) -> None:
        f = _adversarial_functions()
        bound = np.array([dering.min_bound(row) for row in f])
        assert np.all(bound <= dense_min(f) + BOUND_RTOL * np.abs(f).max(axis=1))

    def test_newton_steps_converge(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """The shipped steps reach the converged dual multiplier (64 steps) to rounding, also
        near the hard case where the secular equation's root is ~ (A delta / 2)^(1/3)."""
        rng = np.random.default_rng(31)
        random = rng.normal(size=(2000, 9)) * rng.uniform(0.0, 2.0, (2000, 9)) ** 2
        f = np.concatenate([_near_zonal_functions(2000, 37), random])
        shipped = dering.min_bound(f[..., None])[:, 0]
        monkeypatch.setattr(dering, "_NEWTON_STEPS", 64)
        converged = dering.min_bound(f[..., None])[:, 0]
        np.testing.assert_array_less(np.abs(converged - shipped), CONVERGED_RTOL * np.abs(f).max(axis=1))

    def test_exact_for_zonal_functions(self) -> None:
        """Zonal about the linear direction: c0 + c2 z + c6 (3 z^2 - 1), minimum in closed form."""
        for c0, c2, c6 in ((1.0, 0.5, 0.3), (1.0, 0.2, -0.4), (0.2, 1.0, 0.1), (1.0, 0.0, 0.5), (0.0, 0.0, -1.0)):
            f = np.zeros(9)
            f[0], f[2], f[6] = c0, c2, c6
            a, b = 3 * c6 * dering._K0, c2 * dering._K_LIN
            cc = c0 * dering._Y00 - c6 * dering._K0
            z = np.array([-1.0, 1.0] + ([-b / (2 * a)] if a > 0 and abs(b / (2 * a)) <= 1 else []))
            exact = float(np.min(a * z * z + b * z + cc))
            assert dering.min_bound(f) == pytest.approx(exact, abs=1e-14)

    def test_rotation_about_z_keeps_the_bound(self) -> None:
        """The bound uses rotation invariants about the linear direction (+Z here)."""
        rng = np.random.default_rng(3)
        f = rng.normal(size=(9, 2))
        f[1] = f[3] = 0.0
        f[2] = np.abs(f[2])
        turned = sh.rotate_z(f, np.array(0.7))
        np.testing.assert_allclose(dering.min_bound(turned), dering.min_bound(f), rtol=1e-12, atol=1e-14)

    def test_scale_and_shapes(self) -> None:
        rng = np.random.default_rng(5)
        f = rng.normal(size=(2, 3, 9, 4))
        b = dering.min_bound(f)
        assert b.shape == (2, 3, 4)
        unit = np.abs(f).max(axis=-2)
        # (9, 4) and (9,) take the scalar path, the batch the numpy path: equal to rounding
        tol = SCALAR_PATH_RTOL * unit
        np.testing.assert_allclose(dering.min_bound(f[1, 2]), b[1, 2], rtol=0, atol=tol[1, 2].max())
        assert dering.min_bound(f[0, 0, :, 1]) == pytest.approx(b[0, 0, 1], rel=0, abs=tol[0, 0, 1])
        np.testing.assert_allclose(dering.min_bound(f * 1e250), b * 1e250, rtol=1e-12)
        np.testing.assert_allclose(dering.min_bound(f * 1e-250), b * 1e-250, rtol=1e-12)
        assert dering.min_bound(np.zeros(9)) == 0.0

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="coeffs"):
            dering.min_bound(np.ones(16))
        with pytest.raises(ValueError, match="coeffs"):
            dering.min_bound(np.full(9, np.nan))
        with pytest.raises(ValueError, match="coeffs"):
            dering.min_bound(np.ones((9, 3))[..., None].squeeze() * np.inf)


class TestAlignToLinearDirection:
    def test_against_generic_rotation(self) -> None:
        f = _adversarial_functions()[:30].T  # (9, 30): each column a channel
        rotated, frames = dering.align_to_linear_direction(f)
        assert np.all(np.isfinite(rotated)) and np.all(np.isfinite(frames))
        for k in range(f.shape[1]):
            r = frames[k]
            np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
            assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
            expected = sh.rotate(f[:, k], r.T)
            np.testing.assert_allclose(rotated[:, k], expected, atol=1e-13 * (1 + np.abs(f[:, k]).max()))
        np.testing.assert_allclose(rotated[[1, 3]], 0.0, atol=0)
        assert np.all(rotated[2] >= 0.0)
        np.testing.assert_allclose(rotated[2], np.linalg.norm(f[1:4], axis=0), rtol=1e-14)

    def test_invariants_match_the_bound_parts(self) -> None:
        rng = np.random.default_rng(11)
        f = rng.normal(size=(9, 5))
        rotated, _ = dering.align_to_linear_direction(f)
        dc, b, z, t, s = dering._parts(f[None])
        np.testing.assert_allclose(z[0], rotated[6] * 2 * dering._K0, rtol=1e-12)
        np.testing.assert_allclose(t[0], np.hypot(rotated[4], rotated[8]) * dering._K2, rtol=1e-12)
        np.testing.assert_allclose(s[0], np.hypot(rotated[5], rotated[7]) * dering._K1, rtol=1e-12)
        np.testing.assert_allclose(b[0], rotated[2] * dering._K_LIN, rtol=1e-14)

    def test_vector_shape(self) -> None:
        rotated, frame = dering.align_to_linear_direction(np.eye(9)[2])
        np.testing.assert_allclose(frame[:, 2], [0, 0, 1])
        np.testing.assert_allclose(rotated, np.eye(9)[2], atol=1e-16)


# --------------------------------------------------------------------------- #
# The exact minimum
# --------------------------------------------------------------------------- #
class TestExactMin:
    @pytest.mark.parametrize("bands", [1, 2, 3, 5, 7])
    def test_against_dense_reference(self, bands: int) -> None:
        rng = np.random.default_rng(bands)
        f = rng.normal(size=(24, bands * bands)) / (1 + L_OF[: bands * bands])
        vals, dirs = dering.exact_min(f.T, return_dirs=True)  # channels: (K, 24)
        ref = dense_min(f)
        scale = np.abs(f).max(axis=1)
        assert np.all(vals <= ref + REFINE_RTOL * scale)  # finds at least the reference's minimum
        assert np.all(vals >= ref - REFINE_RTOL * scale)  # and it is a true value, not below
        direct = np.einsum("nk,nk->n", sh.basis(dirs, bands), f)
        np.testing.assert_allclose(vals, direct, rtol=0, atol=EXACT_VALUE_RTOL * bands * scale.max())

    def test_closed_form(self) -> None:
        assert dering.exact_min(np.eye(4)[2]) == pytest.approx(-math.sqrt(3) / (2 * math.sqrt(math.pi)), rel=1e-13)
        assert dering.exact_min(np.zeros(9)) == 0.0

    def test_shapes(self) -> None:
        rng = np.random.default_rng(0)
        f = rng.normal(size=(2, 9, 3))
        v = dering.exact_min(f)
        assert v.shape == (2, 3)
        np.testing.assert_allclose(v[1], dering.exact_min(f[1]), rtol=1e-14)
        v, d = dering.exact_min(f, return_dirs=True)
        assert d.shape == (2, 3, 3)

    def test_bad_input(self) -> None:
        with pytest.raises(ValueError, match="coeffs"):
            dering.exact_min(np.ones(10))
        with pytest.raises(ValueError, match="coeffs"):
            dering.exact_min([np.inf] * 9)


# --------------------------------------------------------------------------- #
# Deringing
# --------------------------------------------------------------------------- #
def _min_rel(coeffs: np.ndarray, target: str = "irradiance") -> np.ndarray:
    """Dense-sphere minimum over mean of the target function of radiance SH (..., K, C)."""
    t = irradiance(coeffs) if target == "irradiance" else coeffs
    return dense_values(t, 40).min(axis=-2) / (t[..., 0, :] * 0.5 / math.sqrt(math.pi))


class TestDering:
    def test_positive_input_untouched(self) -> None:
        c = np.zeros((9, 3))
        c[0] = [3.0, 2.0, 1.0]
        c[2] = [0.5, 0.2, 0.1]
        out, scales = dering.dering(c)
        np.testing.assert_array_equal(out, c)
        np.testing.assert_array_equal(scales, np.ones(3))

    def test_single_deltas_many_directions(self) -> None:
        dirs = dering._fibonacci_sphere(60)
        c = sh.basis(dirs, 3)[..., None] * np.array([1.0, 10.0, 1000.0])  # (60, 9, 3) HDR colours
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert scales.shape == (60, 3)
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)
        assert np.all(scales[:, 1] < 1.0)  # a lone delta always needs windowing

    @HYPOTHESIS
    @given(seed=st.integers(0, 2**32 - 1))
    def test_random_non_negative_lights(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        c = np.stack([light(rng, 3) for _ in range(8)])
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)
        assert np.all(np.isfinite(out)) and np.all(np.isfinite(scales))

    @HYPOTHESIS
    @given(seed=st.integers(0, 2**32 - 1))
    def test_radiance_target(self, seed: int) -> None:
        rng = np.random.default_rng(seed)
        c = np.stack([light(rng, 3) for _ in range(4)])
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, _ = dering.dering(c, target="radiance")
        assert np.all(_min_rel(out, "radiance") >= -NONNEG_RTOL)

    def test_least_windowing_on_the_candidate_grid(self) -> None:
        """The scales lie on the table path, and the candidate 1/32 row before them fails the bound."""
        rng = np.random.default_rng(9)
        c = np.stack([light(rng, 3) for _ in range(10)])
        _, scales = dering.dering(c)
        table = dering.WINDOW_TABLE

        def on_path(tau: np.ndarray) -> np.ndarray:
            i = np.minimum(np.floor(tau).astype(int), table.shape[0] - 2)
            return table[i] + (tau - i)[:, None] * (table[i + 1] - table[i])

        tau = np.interp(-scales[:, 2], -table[:, 2], np.arange(table.shape[0]))  # band 2 strictly decreases
        np.testing.assert_allclose(scales, on_path(tau), atol=1e-12)
        np.testing.assert_allclose(tau * 32, np.round(tau * 32), atol=1e-6)  # on the 1/32-row grid
        s_prev = on_path(np.maximum(tau - 1.0 / 32.0, 0.0))
        bound_prev = dering.min_bound(irradiance(c * s_prev[:, L_OF[:9], None]))
        assert np.all((bound_prev < 0).any(axis=-1)[tau > 0])

    def test_exact_method_never_windows_more(self) -> None:
        rng = np.random.default_rng(12)
        c = np.stack([light(rng, 3) for _ in range(6)])
        _, s_table = dering.dering(c)
        out, s_exact = dering.dering(c, method="exact")
        assert np.all(s_exact >= s_table - 1e-12)
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)

    def test_sinc4_method(self) -> None:
        rng = np.random.default_rng(13)
        c = np.stack([light(rng, 3) for _ in range(6)])
        out, scales = dering.dering(c, method="sinc4")
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)
        # every row is eq. (6) at one cutoff: band 2 determines it
        for s in scales:
            if s[1] < 1.0:
                lo, hi = dering.sinc4_cutoff_floor(3), 1e6
                for _ in range(80):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (lo, mid) if dering.sinc4_window(mid, 3)[2] > s[2] else (mid, hi)
                np.testing.assert_allclose(s, dering.sinc4_window(lo, 3), atol=1e-9)

    def test_one_window_for_all_channels(self) -> None:
        """The applied window is the strongest any channel needs alone (seed section 3)."""
        rng = np.random.default_rng(21)
        for _ in range(5):
            c = light(rng, 3)
            _, s = dering.dering(c)
            per = np.stack([dering.dering(c[:, [k]])[1] for k in range(3)])
            np.testing.assert_allclose(s, per.min(axis=0), atol=1e-12)

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
                np.testing.assert_allclose(s, scales[i, j], atol=1e-12)
                np.testing.assert_allclose(o, out[i, j], rtol=1e-12, atol=0)
        o, s = dering.dering(c[0, 1, :, 0])  # (K,) input
        assert o.shape == (9,) and s.shape == (3,)

    def test_impossible_input_warns_and_stays_finite(self) -> None:
        c = np.zeros((2, 9, 3))
        c[0, 0] = [-1.0, 1.0, 1.0]  # negative mean: no window can help
        c[1, 0] = 1.0
        c[1, 2] = 2.0  # a linear band too large for any non-negative light
        with pytest.warns(dering.DeringWarning):
            out, scales, failed = dering.dering(c, return_failed=True)
        np.testing.assert_array_equal(failed, [True, True])
        np.testing.assert_allclose(scales, np.broadcast_to(dering.WINDOW_TABLE[-1], (2, 3)))
        assert np.all(np.isfinite(out))

    @pytest.mark.parametrize("bands", [2, 4, 5])
    def test_more_bands(self, bands: int) -> None:
        rng = np.random.default_rng(100 + bands)
        c = np.stack([light(rng, bands) for _ in range(3)])
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert scales.shape == (3, bands)
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)

    def test_skies(self) -> None:
        c = sky_samples(12)
        with warnings.catch_warnings():
            warnings.simplefilter("error", dering.DeringWarning)
            out, _ = dering.dering(c)
        assert np.all(_min_rel(out) >= -NONNEG_RTOL)
        out, _ = dering.dering(c, target="radiance")
        assert np.all(np.isfinite(out))

    @staticmethod
    def _singles_and_pairs(c: np.ndarray, **kwargs: str) -> tuple[np.ndarray, np.ndarray]:
        """Scales of every function alone (the scalar screening path) and in pairs (2 items x
        3 channels <= 16: the numpy one-stage search over the same candidates)."""
        single = np.stack([dering.dering(x, **kwargs)[1] for x in c])
        pairs = np.concatenate([dering.dering(c[i : i + 2], **kwargs)[1] for i in range(0, len(c), 2)])
        return single, pairs

    @pytest.mark.parametrize(
        "target, method", [("irradiance", "table"), ("radiance", "table"), ("irradiance", "sinc4")]
    )
    def test_single_path_equals_the_batched_search(self, target: str, method: str) -> None:
        """The screen decides certain candidates, the scalar bound the rest: the same least
        candidate as the batched bound over every candidate (both decide by the same bound)."""
        rng = np.random.default_rng(41)
        c = np.stack([light(rng, 3) for _ in range(40)] + list(sky_samples(4)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            single, pairs = self._singles_and_pairs(c, target=target, method=method)
        np.testing.assert_allclose(single, pairs, rtol=0, atol=1e-12)  # the same grid point

    def test_single_path_screen_resolution_does_not_matter(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """A coarse screen (5 samples: a wide Lipschitz margin, many undecided candidates,
        resolved in one batch) gives the same scales: the screen only sorts out certain
        cases, so a margin that were not a true lower bound would show here."""
        rng = np.random.default_rng(43)
        c = np.stack([light(rng, 3) for _ in range(30)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            fine = np.stack([dering.dering(x)[1] for x in c])
            nodes = 5
            monkeypatch.setattr(dering, "_SCREEN_NODES", nodes)
            monkeypatch.setattr(dering, "_SCREEN_BASIS", dering._screen_basis())
            monkeypatch.setattr(dering, "_SCREEN_BASIS32", dering._SCREEN_BASIS.astype(np.float32))
            monkeypatch.setattr(dering, "_SCREEN_MARGIN", (0.5 * math.pi / (nodes - 1)) ** 2 / 8.0)
            coarse = np.stack([dering.dering(x)[1] for x in c])
            monkeypatch.setattr(dering, "_SCREEN_EXACT_MAX", 10**6)  # every undecided one by one
            scalar = np.stack([dering.dering(x)[1] for x in c])
        np.testing.assert_allclose(coarse, fine, rtol=0, atol=1e-12)
        np.testing.assert_allclose(scalar, fine, rtol=0, atol=1e-12)

    def test_single_path_input_forms(self) -> None:
        rng = np.random.default_rng(47)
        c = light(rng, 3)
        out, scales, failed = dering.dering(c, return_failed=True)
        assert out.shape == (9, 3) and scales.shape == (3,) and failed.shape == () and not failed
        o1, s1 = dering.dering(c[:, 0])  # (K,): one channel
        np.testing.assert_allclose(s1, dering.dering(c[:, :1])[1], atol=0)
        assert o1.shape == (9,)
        wide = np.concatenate([c, c], axis=1)  # 6 channels: still the scalar path
        np.testing.assert_allclose(dering.dering(wide)[1], scales, atol=0)
        sky = sky_samples(4)[2]
        o, s = dering.dering(sky)  # the early-out: untouched
        np.testing.assert_array_equal(o, sky)
        np.testing.assert_array_equal(s, np.ones(3))
        assert o is not sky

    def test_never_nan(self) -> None:
        rng = np.random.default_rng(1)
        c = rng.normal(size=(50, 9, 3)) * 10.0 ** rng.uniform(-200, 200, (50, 1, 1))
        c[:5] = 0.0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            out, scales = dering.dering(c)
        assert np.all(np.isfinite(out)) and np.all(np.isfinite(scales))

    def test_bad_input(self) -> None:
        c = np.ones((9, 3))
        with pytest.raises(ValueError, match="target"):
            dering.dering(c, target="luminance")
        with pytest.raises(ValueError, match="method"):
            dering.dering(c, method="binary")
        with pytest.raises(ValueError, match="coeffs"):
            dering.dering(np.ones((64, 3)))
        with pytest.raises(ValueError, match="coeffs"):
            dering.dering(np.ones((10, 3)))
        with pytest.raises(ValueError, match="coeffs"):
            dering.dering(np.full((9, 3), np.nan))


class TestDirectionalLight:
    def test_reference(self) -> None:
        d = unit(np.array([0.3, -0.4, 0.8]))
        colour = np.array([1000.0, 900.0, 800.0])
        c = dering.directional_light_sh(d, colour)
        expected = sh.basis(d, 3)[:, None] * np.array(dering.PUNCTUAL_WINDOW)[L_OF[:9], None] * colour
        np.testing.assert_allclose(c, expected, rtol=1e-15)
        assert c.shape == (9, 3)

    def test_sun_plus_deringed_sky(self) -> None:
        """The seed's recipe: dering the sky, add the windowed sun; with the last table row as
        window the sum is provably non-negative (each part is)."""
        sky = sky_samples(4)
        sun = unit(np.array([[0.2, 0.1, 0.97], [0.9, 0.0, 0.44], [0.0, -0.7, 0.71], [1.0, 0.0, 0.0]]))
        deringed, _ = dering.dering(sky)
        sun_sh = dering.directional_light_sh(sun, np.array([1e5, 1e5, 1e5]), window=dering.WINDOW_TABLE[-1])
        total = deringed + sun_sh
        assert np.all(_min_rel(total) >= -NONNEG_RTOL)

    def test_batched_and_bad_input(self) -> None:
        d = dering._fibonacci_sphere(5)
        assert dering.directional_light_sh(d, np.ones((5, 3)), bands=2).shape == (5, 4, 3)
        with pytest.raises(ValueError, match="window"):
            dering.directional_light_sh(d[0], np.ones(3), bands=4)
        with pytest.raises(ValueError, match="direction"):
            dering.directional_light_sh([0.0, 0.0, 2.0], np.ones(3))
