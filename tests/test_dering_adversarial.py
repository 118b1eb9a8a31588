"""
Adversarial and property tests of the fast paths of :mod:`skysh.dering`
=======================================================================

Targets the trig-free bound (:func:`dering._bound`), its scalar twin
(:func:`dering._bound_scalar` / :func:`dering._parts_scalar`) and the single-input
screened search (:func:`dering._search_single`: float32 samples with an error
allowance, a sampled upper estimate and a curvature-based lower estimate).

Invariants checked (references: :func:`dering.exact_min`, a value of the function
at a point, so never below the true minimum; and a dense Fibonacci sphere of
131,072 points with local refinement):

1. ``min_bound(c)`` is never above the true minimum (any input: zero and tiny
   bands, tiny |m| = 1 / |m| = 2 parts, 1e6 HDR lights, 1e+-300 and subnormal
   magnitudes, negative DC, exactly zonal functions, linear band along an axis).
2. ``dering`` leaves a non-negative target (or flags and warns), never NaN/inf;
   the single-input path makes the batched path's choice; the chosen window
   passes the bound.
3. Results are deterministic.

Two violations this file found are fixed and tested here (inputs beyond 1e301 overflowed
the irradiance kernel; a negative function of subnormal size was not flagged); the one
left, exact rounding ties between the single and batched paths, is kept as an
``xfail(strict=True)`` test beside the test that shows it is benign.
Every test is deterministic (fixed seeds; hypothesis with ``derandomize``).
"""

from __future__ import annotations

import math
import warnings
from functools import lru_cache

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from skysh import dering, sh

# --------------------------------------------------------------------------- #
# Tolerances (each says why it is that size)
# --------------------------------------------------------------------------- #
BOUND_RTOL: float = 1e-12
"""min_bound may exceed a value of the function only by rounding: a few hundred
flops on numbers normalised to the largest coefficient (measured <= 6e-16 of
max|c| on 6,000 rotated adversarial functions); 1e-12 leaves room without hiding
the 3e-9 error of a cancelling invariant that the module once had."""

TIGHT_RTOL: float = 1e-10
"""min_bound equals the minimum of its own 1D function (linear band along +Z, so the
bound's reduction is exact up to the |m| = 1 phase) to within the dual floor
(_DUAL_FLOOR = 1e-12 times 2|a| + b + 2S <= 1e-11) plus rounding. 1e-10 is still
five orders of magnitude below the screen's float32 allowance (~1e-6), which is
the size a Newton shortfall would need to split the single and batched paths."""

NONNEG_RTOL: float = 1e-12
"""A deringed target counts as negative below -1e-12 of the largest |coefficient|
of the target: rounding of a 9-term sum of values of that size (~1e-15) with room."""

TIE_RTOL: float = 1e-15
"""At a constructed exact tie the numpy and scalar bounds differ by rounding of
their parts (measured <= 5e-17 of the largest target coefficient); a real
disagreement would be of the size of the bound's change between candidates (1e-3)."""

F32_HEADROOM: float = 16.0
"""The module's float32 allowance (2^-17 = 128 u per unit of the sum of term
magnitudes, u = 2^-24) must exceed the measured float32 error by at least this
factor. Analysis gives at most ~6 u (rounded inputs plus a 4-term sum), i.e. a
headroom of ~21; measured here <= 1.6 u (headroom ~80). 16 flags an allowance
that has become thin without depending on the BLAS's summation order."""

H_GRID: int = 4097
"""Points in phi on [0, pi/2] for the reference minimum of the bound's 1D function,
then refined by ternary search (80 steps): the minimum to ~1e-16 of the scale."""

DENSE_POINTS: int = 131_072
"""Fibonacci points of the dense sphere reference (spacing ~0.006 rad); followed by
8 rounds of tangent-plane refinement from the 4 lowest points of each function."""

HYPOTHESIS = settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
"""Deterministic property-test budget (derandomize: the same examples on every run)."""

L_OF: np.ndarray = np.repeat(np.arange(3), 2 * np.arange(3) + 1)
"""Band of each of the 9 flat indices."""

KERNEL9: np.ndarray = dering.IRRADIANCE_KERNEL[L_OF]
"""Clamped-cosine factor of each of the 9 coefficients."""


# --------------------------------------------------------------------------- #
# References and generators
# --------------------------------------------------------------------------- #
def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@lru_cache(maxsize=None)
def _dense_sphere() -> tuple[np.ndarray, np.ndarray]:
    """Fibonacci points (M, 3) and their basis (M, 9); computed once."""
    i = np.arange(DENSE_POINTS) + 0.5
    z = 1.0 - 2.0 * i / DENSE_POINTS
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    dirs = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
    return dirs, sh.basis(dirs, 3)


def dense_sphere_min(f: np.ndarray) -> np.ndarray:
    """Minimum over the sphere of 3-band functions (F, 9): 131,072 Fibonacci points, then
    8 rounds of 7 x 7 tangent grids (step 0.01 rad shrinking 3x) from the 4 lowest. (F,)."""
    f = np.asarray(f, dtype=np.float64)
    dirs, y = _dense_sphere()
    unit = np.abs(f).max(axis=1) + 1e-300
    g = f / unit[:, None]
    out = np.empty(len(g))
    offs = np.arange(-3, 4, dtype=np.float64)
    uu, vv = (a.ravel() for a in np.meshgrid(offs, offs, indexing="ij"))
    for lo in range(0, len(g), 32):
        gc = g[lo : lo + 32]
        vals = y @ gc.T  # (M, F)
        k = 4
        start = np.argpartition(vals, k - 1, axis=0)[:k].T  # (F, k)
        p = dirs[start].reshape(-1, 3)
        best = vals[start.T, np.arange(gc.shape[0])].T.reshape(-1)
        fr = np.repeat(gc, k, axis=0)
        h = 0.01
        for _ in range(8):
            helper = np.where(np.abs(p[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
            e1 = _unit(np.cross(p, helper))
            e2 = np.cross(p, e1)
            q = _unit(p[:, None] + h * (uu[None, :, None] * e1[:, None] + vv[None, :, None] * e2[:, None]))
            qv = np.einsum("pk,pjk->pj", fr, sh.basis(q, 3))
            j = np.argmin(qv, axis=1)
            rows = np.arange(p.shape[0])
            better = qv[rows, j] < best
            p = np.where(better[:, None], q[rows, j], p)
            best = np.where(better, qv[rows, j], best)
            h /= 3.0
        out[lo : lo + 32] = np.minimum(best.reshape(-1, k).min(axis=1), vals.min(axis=0))
    return out * unit


def h_min(dc, b, zon, t, s) -> np.ndarray:
    """Reference minimum of the bound's 1D function c + a z^2 + b z - S |z| sqrt(1 - z^2) over
    z in [-1, 0] (z = -cos phi), a = 1.5 zon + t, c = dc - 0.5 zon - t: dense phi + ternary search."""
    dc, b, zon, t, s = (np.asarray(x, dtype=np.float64)[None] for x in (dc, b, zon, t, s))
    a, c = 1.5 * zon + t, dc - 0.5 * zon - t

    def f(p):
        cp, sp = np.cos(p), np.sin(p)
        return c + a * cp * cp - b * cp - s * cp * sp

    phi = np.linspace(0.0, 0.5 * math.pi, H_GRID).reshape((-1,) + (1,) * (dc.ndim - 1))
    vals = f(phi)
    k = np.argmin(vals, axis=0)
    step = 0.5 * math.pi / (H_GRID - 1)
    lo = np.maximum(k - 1, 0) * step
    hi = np.minimum(k + 1, H_GRID - 1) * step
    for _ in range(80):
        m1, m2 = lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0
        left = f(m1[None])[0] < f(m2[None])[0]
        hi, lo = np.where(left, m2, hi), np.where(left, lo, m1)
    return np.minimum(vals.min(axis=0), f((0.5 * (lo + hi))[None])[0])


def _rotation(rng: np.random.Generator) -> np.ndarray:
    """A random proper rotation; 30 % of the time a signed axis permutation (linear band along an axis)."""
    if rng.random() < 0.3:
        p = np.eye(3)[rng.permutation(3)] * rng.choice([-1.0, 1.0], 3)[:, None]
        if np.linalg.det(p) < 0:
            p[0] *= -1.0
        return p
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1.0
    return q


def framed_functions(rng: np.random.Generator, n: int, rotate: bool = True) -> np.ndarray:
    """(n, 9) functions built in the bound's own frame (linear band along +Z) with each of
    the parts B, Z, |m| = 1 and |m| = 2 of magnitude 10^U(-16, 0) or exactly zero, random
    phases and DC in [-1, 3] (negative-DC included), then (optionally) rotated."""

    def mag() -> np.ndarray:
        m = 10.0 ** rng.uniform(-16.0, 0.0, n)
        m[rng.random(n) < 0.15] = 0.0
        return m

    f = np.zeros((n, 9))
    f[:, 0] = rng.uniform(-1.0, 3.0, n)
    f[:, 2] = mag() * rng.choice([-1.0, 1.0], n)
    f[:, 6] = mag() * rng.choice([-1.0, 1.0], n)
    p1, p2 = rng.uniform(0.0, 2.0 * math.pi, (2, n))
    m1, m2 = mag(), mag()
    f[:, 5], f[:, 7] = m1 * np.cos(p1), m1 * np.sin(p1)
    f[:, 4], f[:, 8] = m2 * np.cos(p2), m2 * np.sin(p2)
    if rotate:
        f = np.stack([sh.rotate(x, _rotation(rng)) for x in f])
    return f


def adversarial_rgb(rng: np.random.Generator, kind: int) -> np.ndarray:
    """One (9, 3) radiance function of an adversarial family (kind 0..6)."""
    c = np.zeros((9, 3))
    if kind == 0:  # every channel its own HDR deltas, scales 1e-8 .. 1e8 apart
        for ch in range(3):
            k = int(rng.integers(1, 4))
            c[:, ch] = (sh.basis(_unit(rng.normal(size=(k, 3))), 3) * 10.0 ** rng.uniform(-8, 8, (k, 1))).sum(0)
    elif kind == 1:  # two deltas, one channel exactly zero
        d = _unit(rng.normal(size=(2, 3)))
        c = (sh.basis(d, 3)[..., None] * 10.0 ** rng.uniform(-3, 6, (2, 1, 3))).sum(0)
        c[:, rng.integers(3)] = 0.0
    elif kind == 2:  # near zonal about +Z, tiny |m| = 1 / 2 parts, maybe a subnormal linear x/y part
        c[0], c[2], c[6] = rng.uniform(0.2, 2, 3), rng.uniform(0, 1, 3), rng.uniform(-1, 1, 3)
        for i in (4, 5, 7, 8):
            c[i] = rng.normal(size=3) * 10.0 ** rng.uniform(-15, 0, 3)
        if rng.random() < 0.5:
            c[[1, 3]] = rng.normal(size=(2, 3)) * 10.0 ** rng.uniform(-300, -150)
    elif kind == 3:  # a 1e3 .. 1e7 HDR delta over a dim, slightly noisy ambient
        c = sh.basis(_unit(rng.normal(size=3)), 3)[:, None] * 10.0 ** rng.uniform(3, 7, 3)
        c[0] += rng.uniform(0.1, 10, 3)
        c[1:] += rng.normal(size=(8, 3)) * 0.1
    elif kind == 4:  # a light at 1e-300 .. 1e300, per channel
        d = _unit(rng.normal(size=(2, 3)))
        c = (sh.basis(d, 3)[..., None] * rng.uniform(0.1, 1, (2, 1, 3))).sum(0) * 10.0 ** rng.uniform(-300, 300, 3)
    elif kind == 5:  # exactly zonal, linear band along a signed axis, plus ambient
        v = np.zeros(3)
        v[rng.integers(3)] = rng.choice([-1.0, 1.0])
        c = sh.basis(v, 3)[:, None] * rng.uniform(0.5, 3, 3)
        c[0] += rng.uniform(0, 0.3, 3)
    else:  # a light whose |m| = 1 part dominates band 2 in one channel
        c = sh.basis(_unit(rng.normal(size=(1, 3))), 3)[0][:, None] * np.ones(3)
        c[[5, 7], rng.integers(3)] += rng.normal(size=2) * 0.3
    return c


def _target(c: np.ndarray, target: str = "irradiance") -> np.ndarray:
    return c * dering._KERNELS[target][L_OF][:, None]


def _numpy_bound_at(tgt: np.ndarray, s1: float, s2: float) -> np.ndarray:
    """The batched path's bound (normalised units) of target coefficients (9, C) at (1, s1, s2)."""
    (d, b, z, t, s), _ = dering._normalised_parts(np.stack([tgt, tgt]))  # the layout of _pair_scales
    return dering._bound(d[0], b[0] * s1, z[0] * s2, t[0] * s2, s[0] * s2)


def _pair_scales(c: np.ndarray, **kw: str) -> np.ndarray:
    """Scales chosen by the batched one-stage search: the function twice (2 items, n > 1)."""
    return dering.dering(np.stack([c, c]), **kw)[1][0]


# --------------------------------------------------------------------------- #
# Invariant 1: the bound
# --------------------------------------------------------------------------- #
class TestBoundAdversarial:
    @HYPOTHESIS
    @given(seed=st.integers(0, 2**32 - 1), log_scale=st.sampled_from([0.0, -300.0, -150.0, 150.0, 300.0]))
    def test_framed_functions_never_above_exact_min(self, seed: int, log_scale: float) -> None:
        """Parts of wildly different sizes (1e-16 .. 1, exact zeros), every rotation incl.
        axis-aligned ones, magnitudes 1e+-300: numpy and scalar paths never above exact_min."""
        rng = np.random.default_rng(seed)
        f = framed_functions(rng, 24) * 10.0**log_scale
        ref = dering.exact_min(f[..., None])[:, 0]
        batch = dering.min_bound(f[..., None])[:, 0]
        single = np.array([dering.min_bound(x) for x in f])
        size = np.abs(f).max(axis=1)
        assert np.all(np.isfinite(batch)) and np.all(np.isfinite(single))
        assert np.all(batch <= ref + BOUND_RTOL * size)
        assert np.all(single <= ref + BOUND_RTOL * size)

    def test_tight_in_its_own_frame(self) -> None:
        """Linear band along +Z: the bound must equal the minimum of its 1D function (dual
        converged, including the hard case b -> 0 with tiny S) and be <= the sphere's minimum."""
        rng = np.random.default_rng(101)
        f = framed_functions(rng, 3000, rotate=False)
        f[:, 2] = np.abs(f[:, 2])  # b >= 0 along +Z: the frame needs no rotation
        (d, b, z, t, s), scale = dering._normalised_parts(f[..., None])
        ref = h_min(d[:, 0], b[:, 0], z[:, 0], t[:, 0], s[:, 0])
        bound = dering._bound(d[:, 0], b[:, 0], z[:, 0], t[:, 0], s[:, 0])
        size = np.abs(d[:, 0]) + b[:, 0] + np.abs(z[:, 0]) + t[:, 0] + s[:, 0]
        assert np.all(bound <= ref + BOUND_RTOL * size)
        assert np.all(bound >= ref - TIGHT_RTOL * size)
        exact = dering.exact_min(f[:200, :, None])[:, 0]
        assert np.all(bound[:200] * scale[:200, 0] <= exact + BOUND_RTOL * np.abs(f[:200]).max(axis=1))

    def test_dense_sphere_reference(self) -> None:
        """Against a 131,072-point Fibonacci sphere with refinement (independent of exact_min)."""
        rng = np.random.default_rng(103)
        f = np.concatenate([framed_functions(rng, 96), sh.irradiance(framed_functions(rng, 32)[..., None])[..., 0]])
        ref = dense_sphere_min(f)
        size = np.abs(f).max(axis=1)
        assert np.all(dering.min_bound(f[..., None])[:, 0] <= ref + BOUND_RTOL * size)
        assert np.all(np.array([dering.min_bound(x) for x in f]) <= ref + BOUND_RTOL * size)

    def test_power_of_two_scaling_is_exact(self) -> None:
        """The bound is computed in units of the largest coefficient: scaling by 2^k (exact) must
        scale it exactly wherever that unit is far above _TINY (no absolute constant leaks)."""
        rng = np.random.default_rng(107)
        f = framed_functions(rng, 40)
        f /= np.abs(f).max(axis=1, keepdims=True)
        base = np.array([dering.min_bound(x) for x in f])
        for k in (-900, -300, 300, 1000):
            scaled = np.array([dering.min_bound(x * 2.0**k) for x in f])
            np.testing.assert_array_equal(scaled, base * 2.0**k)

    def test_subnormal_and_tiny_inputs(self) -> None:
        """Magnitudes down to the smallest subnormal: finite, never above exact_min."""
        rng = np.random.default_rng(109)
        f = framed_functions(rng, 40)
        for mag in (1e-305, 1e-310, 1e-318, 5e-324):
            g = f / np.abs(f).max(axis=1, keepdims=True) * mag
            bound = np.array([dering.min_bound(x) for x in g])
            ref = dering.exact_min(g[..., None])[:, 0]
            assert np.all(np.isfinite(bound))
            # subnormal inputs carry only a few bits: allow rounding of the input itself
            assert np.all(bound <= ref + max(BOUND_RTOL * mag, 4.0 * 5e-324))


# --------------------------------------------------------------------------- #
# The screen's two certificates, directly
# --------------------------------------------------------------------------- #
def _adversarial_parts(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    """Normalised parts (n,) with large curvature against small values: S and |a| up to 1,
    b often tiny (1e-12 .. 1, or exactly 0); DC 0 here, tuned by the test so that the 1D
    minimum is zero at a random candidate."""

    def mag() -> np.ndarray:
        m = 10.0 ** rng.uniform(-12.0, 0.0, n)
        m[rng.random(n) < 0.1] = 0.0
        return m

    b, t, s = mag(), mag(), mag()
    zon = mag() * rng.choice([-1.0, 1.0], n)
    dc = np.zeros(n)
    return dc, b, zon, t, s


class TestScreenCertificates:
    def test_float32_allowance_and_curvature_lower_estimate(self) -> None:
        """For every candidate of the grid: (i) the float32 samples err by at most the module's
        allowance (with headroom F32_HEADROOM); (ii) the screen's lower estimate is <= the true
        minimum of the 1D function; (iii) its upper estimate is >= it less the allowance.
        The parts are chosen so that the minimum is ~0 at a random candidate (the screen's
        decisions matter there)."""
        rng = np.random.default_rng(211)
        path = dering._path(3, "irradiance", "table")
        _, s1s, s2s, features, _ = path.screen()
        s1s, s2s = np.array(s1s), np.array(s2s)
        n = 32
        dc, b, zon, t, s = _adversarial_parts(rng, n)
        j = rng.integers(0, len(s1s), n)
        a0, c0 = 1.5 * zon + t, 0.5 * zon + t
        dc = dc - h_min(dc, b * s1s[j], zon * s2s[j], t * s2s[j], s * s2s[j])  # minimum 0 at candidate j
        # (n, J) terms as the module forms them: 1, z, z^2, w coefficients at each candidate
        const = dc[:, None] - c0[:, None] * s2s
        lin = b[:, None] * s1s
        quad = a0[:, None] * s2s
        side = -s[:, None] * s2s
        terms = np.stack([const, lin, quad, side])  # (4, n, J)
        exact = np.einsum("kq,qnj->knj", dering._SCREEN_BASIS, terms)
        f32 = np.dot(dering._SCREEN_BASIS32, terms.reshape(4, -1).astype(np.float32)).reshape(exact.shape)
        allowance = dering._SCREEN_F32_ERROR * (np.abs(dc) + np.abs(c0) + b + np.abs(a0) + s)[:, None]
        err = np.abs(f32.astype(np.float64) - exact).max(axis=0)
        assert np.all(err * F32_HEADROOM <= allowance)
        upper = f32.min(axis=0).astype(np.float64)
        margin = (
            dering._SCREEN_SLACK
            + allowance
            + dering._SCREEN_MARGIN * (b[:, None] * s1s + 2.0 * s2s * np.sqrt(a0 * a0 + s * s)[:, None])
        )
        true = h_min(
            np.broadcast_to(dc[:, None], upper.shape),
            b[:, None] * s1s,
            zon[:, None] * s2s,
            t[:, None] * s2s,
            s[:, None] * s2s,
        )
        unit = (np.abs(dc) + np.abs(c0) + b + np.abs(a0) + s)[:, None]
        assert np.all(upper - margin <= true + 1e-15 * unit)  # lower estimate (rounding of true)
        assert np.all(upper + allowance >= true - 1e-15 * unit)  # upper estimate

    def test_curvature_bound_holds(self) -> None:
        """|H''(phi)| <= 2 sqrt(a^2 + S^2) + b, checked by second differences on extreme parts."""
        rng = np.random.default_rng(213)
        n = 2000
        a = rng.uniform(-1.5, 2.5, n)
        b = rng.uniform(0, 1, n) * (rng.random(n) < 0.5)
        s = rng.uniform(0, 1.5, n)
        phi = np.linspace(0.0, 0.5 * math.pi, 2001)[:, None]
        h = phi[1, 0] - phi[0, 0]
        hv = a * np.cos(phi) ** 2 - b * np.cos(phi) - s * np.cos(phi) * np.sin(phi)
        second = np.abs(hv[2:] - 2 * hv[1:-1] + hv[:-2]) / (h * h)
        bound = 2.0 * np.sqrt(a * a + s * s) + b
        assert np.all(second.max(axis=0) <= bound * (1 + 1e-6))  # 1e-6: O(h^2) of the difference


# --------------------------------------------------------------------------- #
# Invariant 2: dering
# --------------------------------------------------------------------------- #
class TestDeringAdversarial:
    KINDS: int = 7
    PER_KIND: int = 24

    @pytest.fixture(scope="class")
    def inputs(self) -> np.ndarray:
        rng = np.random.default_rng(307)
        return np.stack([adversarial_rgb(rng, k) for k in range(self.KINDS) for _ in range(self.PER_KIND)])

    @pytest.mark.parametrize(
        "target, method", [("irradiance", "table"), ("radiance", "table"), ("irradiance", "sinc4")]
    )
    def test_single_equals_batched(self, inputs: np.ndarray, target: str, method: str) -> None:
        """Single (9, 3) input (screened scalar path) == the same function in a batch of 2 (numpy
        one-stage search) == the whole family as one large batch (staged search), bitwise."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            single = np.stack([dering.dering(c, target=target, method=method)[1] for c in inputs])
            pairs = np.stack([_pair_scales(c, target=target, method=method) for c in inputs])
            large = dering.dering(inputs, target=target, method=method)[1]
        np.testing.assert_array_equal(single, pairs)
        np.testing.assert_array_equal(single, large)

    def test_output_non_negative_on_dense_sphere(self, inputs: np.ndarray) -> None:
        """The chosen window leaves the irradiance >= 0 on the dense sphere (or the item is
        flagged), passes the exact bound in every channel, and nothing is NaN or inf."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            res = [dering.dering(c, return_failed=True) for c in inputs]
        out = np.stack([r[0] for r in res])
        failed = np.array([bool(r[2]) for r in res])
        assert np.all(np.isfinite(out)) and np.all(np.isfinite(np.stack([r[1] for r in res])))
        tgt = sh.irradiance(out[~failed])  # (F, 9, 3)
        flat = np.moveaxis(tgt, -1, 1).reshape(-1, 9)
        size = np.abs(flat).max(axis=1)
        assert np.all(dense_sphere_min(flat) >= -NONNEG_RTOL * size)
        # Where the bound certifies the last row, the bound decided: the window must pass it.
        # (Elsewhere exact_min decided, by design, and the bound may stay negative.)
        last = sh.irradiance(inputs[~failed] * dering.WINDOW_TABLE[-1][L_OF][:, None])
        by_bound = np.all(dering.min_bound(last) >= 0.0, axis=-1)
        assert by_bound.sum() > len(by_bound) // 2
        bound = dering.min_bound(tgt[by_bound])
        assert np.all(bound >= -NONNEG_RTOL * np.abs(tgt[by_bound]).max(axis=-2))

    def test_scale_invariance_per_channel(self) -> None:
        """Multiplying one channel by 2^k (exact) cannot change the window: decisions are made
        in units of each channel's largest coefficient; the screen's absolute slack (1e-12) and
        the kernel must not leak, from 2^-900 to 2^900 in one RGB input."""
        rng = np.random.default_rng(311)
        for _ in range(20):
            c = adversarial_rgb(rng, 3)
            c /= np.abs(c).max(axis=0)
            base = dering.dering(c)[1]
            for k in (-900, -400, 400, 900):
                d = c.copy()
                d[:, int(rng.integers(3))] *= 2.0**k
                np.testing.assert_array_equal(dering.dering(d)[1], base)
                np.testing.assert_array_equal(_pair_scales(d), base)

    def test_near_ties_beyond_rounding(self) -> None:
        """The bound at the decisive candidate set to +-delta (1e-13 .. 1e-4 of the target's
        largest coefficient: inside and around the screen's float32 allowance and curvature
        band): single path == batched path, with a second channel 1e6 larger and a zero third."""
        rng = np.random.default_rng(313)
        _, grid = dering._path(3, "irradiance", "table").grid(32)
        checked = 0
        for c, j, f0 in _tied_functions(rng, 12, grid):
            scale = np.abs(c * KERNEL9).max()
            for delta in (-1e-4, -1e-5, -7.6e-6, -1e-6, -1e-9, -1e-13, 1e-13, 1e-9, 1e-6, 7.6e-6, 1e-5, 1e-4):
                cc = np.r_[f0 + delta * scale / (dering._Y00 * KERNEL9[0]), c[1:]]
                for rgb in (cc[:, None], np.stack([cc, 1e6 * cc, np.zeros(9)], axis=1)):
                    np.testing.assert_array_equal(dering.dering(rgb)[1], _pair_scales(rgb))
                    checked += 1
        assert checked > 200

    @pytest.mark.xfail(
        strict=True,
        reason="Exact rounding ties: _parts_scalar and numpy's _parts differ by ~1e-17 (summation "
        "order), so where the bound is 0 to rounding at the decisive candidate the single and "
        "batched paths split: neighbouring candidates, or at the last row one path falls back to "
        "exact_min (13 candidates apart). Benign: see test_rounding_ties_are_benign.",
    )
    def test_exact_rounding_ties(self) -> None:
        """DC tuned by bisection to the last float where the batched bound at the decisive
        candidate is < 0 and the first where it is >= 0: the single path should agree."""
        rng = np.random.default_rng(317)
        _, grid = dering._path(3, "irradiance", "table").grid(32)
        for c, j, f0 in _tied_functions(rng, 40, grid, both_sides=True):
            cc = np.r_[f0, c[1:]][:, None]
            np.testing.assert_array_equal(dering.dering(cc)[1], _pair_scales(cc))

    def test_rounding_ties_are_benign(self) -> None:
        """Where the paths split at an exact tie, both windows are safe: either they are
        neighbouring candidates and both pass the numpy bound to rounding (TIE_RTOL), or the
        tie was at the last row and one path fell back to exact_min (which then chose less
        windowing, up to 13 candidates here), and exact_min is >= 0 under both windows."""
        rng = np.random.default_rng(317)
        _, grid = dering._path(3, "irradiance", "table").grid(32)
        splits = 0
        for c, j, f0 in _tied_functions(rng, 40, grid, both_sides=True):
            cc = np.r_[f0, c[1:]][:, None]
            a, b = dering.dering(cc)[1], _pair_scales(cc)
            if np.array_equal(a, b):
                continue
            splits += 1
            ja, jb = (int(np.argmin(np.abs(grid[:, 2] - x[2]))) for x in (a, b))
            tgt = cc * KERNEL9[:, None]
            if abs(ja - jb) == 1:
                for x in (a, b):
                    assert _numpy_bound_at(tgt, x[1], x[2]).min() >= -TIE_RTOL
            else:
                assert max(ja, jb) == len(grid) - 1  # the last row: the exact_min route
            for x in (a, b):
                windowed = tgt * x[L_OF][:, None]
                assert dering.exact_min(windowed).min() >= -NONNEG_RTOL * np.abs(windowed).max()
        assert splits > 0

    def test_zero_channel_and_zero_function(self) -> None:
        """An exactly zero channel is never 'sure' for the screen (slack 1e-12 > 0): it must still
        pass, giving the window of the other channels alone; an all-zero input is untouched."""
        rng = np.random.default_rng(331)
        for _ in range(10):
            c = adversarial_rgb(rng, 3)
            c[:, 1] = 0.0
            s = dering.dering(c)[1]
            np.testing.assert_array_equal(s, dering.dering(c[:, [0, 2]])[1])
            np.testing.assert_array_equal(s, _pair_scales(c))
        o, s, failed = dering.dering(np.zeros((9, 3)), return_failed=True)
        assert not failed and np.all(s == 1.0) and np.all(o == 0.0)

    def test_radiance_1e308_does_not_overflow(self) -> None:
        """Radiance target (kernel 1): a delta at 1e308 is windowed like one at 1."""
        c = np.zeros((9, 3))
        c[0] = c[2] = 1.0
        big = c * 1e308
        np.testing.assert_array_equal(dering.dering(big, target="radiance")[1], dering.dering(c, target="radiance")[1])

    def test_huge_irradiance_single_path(self) -> None:
        # Was a bug: pi * 1e308 overflowed to inf, normalised to NaN, and passed the early-out.
        c = np.zeros((9, 3))
        c[0] = c[2] = 1e308  # finite input; its irradiance coefficient pi * 1e308 is not
        out, scales, failed = dering.dering(c, return_failed=True)
        assert failed or dering.exact_min(sh.irradiance(out / 1e308)).min() >= -NONNEG_RTOL
        np.testing.assert_array_equal(scales, dering.dering(c / 1e300)[1])

    def test_huge_irradiance_batched_path(self) -> None:
        # Was a bug: the batched target held inf and exact_min refused it. Inputs are now
        # rescaled by powers of two (dering._exactly_rescaled) before any decision.
        c = np.zeros((9, 3))
        c[0] = c[2] = 1e308
        scales = dering.dering(np.stack([c, c]))[1]
        np.testing.assert_array_equal(scales[0], dering.dering(c / 1e300)[1])

    def test_negative_dc_is_flagged_down_to_1e_308(self) -> None:
        c = np.zeros((9, 3))
        c[0] = [-1.0, 1.0, 1.0]
        for mag in (1e300, 1.0, 1e-300, 1e-308):
            with pytest.warns(dering.DeringWarning):
                _, _, failed = dering.dering(c * mag, return_failed=True)
            assert failed

    def test_negative_dc_flagged_at_subnormal_magnitude(self) -> None:
        # Was a bug: an absolute floor (1e-300) under the failure tolerance hid it.
        c = np.zeros((9, 3))
        c[0] = [-1e-310, 1e-310, 1e-310]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out, _, failed = dering.dering(c, return_failed=True)
        assert dering.exact_min(sh.irradiance(out))[0] < 0.0  # truly negative: flag it
        assert failed and any(issubclass(w.category, dering.DeringWarning) for w in caught)


def _tied_functions(rng: np.random.Generator, count: int, grid: np.ndarray, both_sides: bool = False):
    """Yield (c, j, f0): one-channel lights (9,) whose DC f0 puts the batched bound at the
    candidate j they choose at an exact tie (smallest f0 with bound >= 0, by bisection to the
    last float). With both_sides, also the largest f0 with bound < 0."""
    made = 0
    while made < count:
        k = int(rng.integers(1, 4))
        c = (sh.basis(_unit(rng.normal(size=(k, 3))), 3) * 10.0 ** rng.uniform(-1, 2, (k, 1))).sum(0)
        c[1:] += rng.normal(size=8) * 0.05 * np.abs(c).max()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            s = dering.dering(c[:, None])[1]
        j = int(np.argmin(np.abs(grid[:, 2] - s[2])))
        if j == 0:
            continue

        def bound(f0: float) -> float:
            return float(_numpy_bound_at(np.r_[f0, c[1:]][:, None] * KERNEL9[:, None], grid[j, 1], grid[j, 2])[0])

        lo, hi = -3.0 * abs(c[0]), 3.0 * abs(c[0])
        if bound(lo) >= 0.0 or bound(hi) < 0.0:
            continue
        while True:
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            lo, hi = (lo, mid) if bound(mid) >= 0.0 else (mid, hi)
        made += 1
        yield c, j, hi
        if both_sides:
            yield c, j, lo


# --------------------------------------------------------------------------- #
# Invariant 3: determinism
# --------------------------------------------------------------------------- #
class TestDeterminism:
    def test_repeatable_and_independent_of_cache_state(self) -> None:
        rng = np.random.default_rng(401)
        c = np.stack([adversarial_rgb(rng, k % 7) for k in range(21)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            first = [dering.dering(x) for x in c] + [dering.dering(c)]
            dering._path.cache_clear()  # the screen's cached grid is rebuilt
            second = [dering.dering(x) for x in c] + [dering.dering(c)]
            third = [dering.dering(x) for x in c[::-1]][::-1] + [dering.dering(c)]
        for a, b, d in zip(first, second, third):
            for x, y, z in zip(a, b, d):
                np.testing.assert_array_equal(x, y)
                np.testing.assert_array_equal(x, z)
        bounds = [dering.min_bound(x) for x in c]
        np.testing.assert_array_equal(np.stack(bounds), np.stack([dering.min_bound(x) for x in c]))
