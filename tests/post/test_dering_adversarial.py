"""
Never negative: :func:`skysh.post.dering.dering` on random and adversarial inputs, 1..7 bands
=======================================================================================

Families (radiance SH, 3 channels): HDR deltas per channel 1e-8 .. 1e8 apart; deltas
with one channel exactly zero; near-zonal functions with tiny |m| > 0 parts; an HDR
delta over a noisy ambient; lights at 1e-300 .. 1e300; exactly zonal functions; sums
of many deltas; linear (arc) lights; arbitrary random functions; and functions whose
windowed irradiance has its minimum within 1e-9 (either side) of zero at some row.

For every input: if ``failed`` is False, the target of the output has a reference
minimum (:func:`test_dering.reference_min`, independent of the module) >= -1e-12 of
its size; if True, the last row is not non-negative by the reference (beyond the
certificate's margin for 4..7 bands), and a DeringWarning was issued. Non-negative
lights never fail. The core run checks 1,000 inputs per band count at 1..3 bands and 100
at 4..7 (all 10 families); ``-m slow`` adds the same seeds at 5,000 and 300 per band count
and runs 10^5 per band count at 1..3 and 10^4 at 4..7.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from conftest import L_OF, channel_min, light, reference_min, unit

from skysh.post import dering
from skysh.sh import basis as sh

NONNEG_RTOL: float = 1e-12
"""A target counts as negative below -1e-12 of its largest |coefficient| (rounding of a
9..49-term sum; the module's own allowance is 6e-14 of the function's size)."""

NEAR_ZERO: float = 1e-9
"""The near-zero family puts a row's minimum at +-1e-9 of the target's largest |coefficient|."""

PHYSICAL: tuple[int, ...] = (0, 1, 4, 5, 6, 7)
"""Families that are non-negative lights by construction: they must never fail."""

FAMILIES: int = 10
"""Number of families in :func:`family`."""


def family(rng: np.random.Generator, kind: int, n: int, bands: int) -> np.ndarray:
    """(n, K, 3) inputs of one family (module docstring, in order)."""
    k = bands * bands
    basis = lambda d: sh.basis(unit(d), bands)  # noqa: E731
    if kind == 0:
        return np.einsum("njk,njc->nkc", basis(rng.normal(size=(n, 3, 3))), 10.0 ** rng.uniform(-8, 8, (n, 3, 3))
                         * (rng.random((n, 3, 1)) < 0.7))
    if kind == 1:
        c = np.einsum("njk,njc->nkc", basis(rng.normal(size=(n, 2, 3))), 10.0 ** rng.uniform(-3, 6, (n, 2, 3)))
        c[np.arange(n), :, rng.integers(3, size=n)] = 0.0
        return c
    if kind == 2:
        c = np.zeros((n, k, 3))
        zonal = [l * (l + 1) for l in range(bands)]
        c[:, zonal] = rng.uniform(-0.3, 1.0, (n, bands, 3)) / (1 + np.arange(bands))[:, None]
        c[:, 0] = rng.uniform(0.5, 2.0, (n, 3))
        other = np.setdiff1d(np.arange(k), zonal)
        c[:, other] = rng.normal(size=(n, len(other), 3)) * 10.0 ** rng.uniform(-15, 0, (n, 1, 3))
        return c
    if kind == 3:
        c = basis(rng.normal(size=(n, 3)))[..., None] * 10.0 ** rng.uniform(3, 7, (n, 1, 3))
        c[:, 0] += rng.uniform(0.1, 10, (n, 3))
        c[:, 1:] += rng.normal(size=(n, k - 1, 3)) * 0.1
        return c
    if kind == 4:
        return np.einsum("njk,njc->nkc", basis(rng.normal(size=(n, 2, 3))), rng.uniform(0.1, 1, (n, 2, 3))) \
            * 10.0 ** rng.uniform(-300, 300, (n, 1, 3))
    if kind == 5:
        v = np.zeros((n, 3))
        v[np.arange(n), rng.integers(3, size=n)] = rng.choice([-1.0, 1.0], n)
        c = basis(v)[..., None] * rng.uniform(0.5, 3, (n, 1, 3))
        c[:, 0] += rng.uniform(0, 0.3, (n, 3))
        return c
    if kind == 6:
        return np.einsum("njk,njc->nkc", basis(rng.normal(size=(n, 12, 3))), rng.uniform(0, 1, (n, 12, 3)) ** 4)
    if kind == 7:
        return np.stack([light(rng, bands) for _ in range(n)])
    if kind == 8:
        return rng.normal(size=(n, k, 3)) * rng.uniform(0, 2, (n, k, 3)) ** 2
    return near_zero(rng, n, bands)


def near_zero(rng: np.random.Generator, n: int, bands: int) -> np.ndarray:
    """Lights whose irradiance windowed by a random row has its minimum moved (through the DC
    term, using the reference minimum) to +-NEAR_ZERO of the target's largest |coefficient|."""
    c = np.stack([light(rng, bands) for _ in range(n)])
    table = dering.window_table(bands)
    row = table[rng.integers(len(table), size=n)][:, L_OF[: bands * bands], None]
    irr = sh.irradiance(c * row)
    size = np.abs(irr).max(axis=-2)
    shift = channel_min(irr, dense=3) - rng.choice([-1.0, 1.0], (n, 3)) * NEAR_ZERO * size
    c[:, 0] -= shift / (math.pi * 0.5 / math.sqrt(math.pi))  # the irradiance DC is pi c0 Y00
    return c


def check(c: np.ndarray, bands: int, physical: bool) -> None:
    """The invariants of the module docstring on inputs c (n, K, 3)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out, scales, failed = dering.dering(c, return_failed=True)
    assert np.all(np.isfinite(out)) and np.all(np.isfinite(scales))
    assert failed.any() == any(issubclass(w.category, dering.DeringWarning) for w in caught)
    if physical:
        assert not failed.any()
    irr = sh.irradiance(out[~failed])
    rel = channel_min(irr) / (np.abs(irr).max(axis=-2) + 1e-300)
    assert np.all(rel >= -NONNEG_RTOL), f"{int((rel < -NONNEG_RTOL).sum())} negative, worst {rel.min():.3g}"
    if failed.any():  # no row works: at the last row some channel is negative (or, 4..7, within the margin)
        last = sh.irradiance(c[failed] * dering.window_table(bands)[-1][L_OF[: bands * bands], None])
        margin = 0.0 if bands <= 3 else dering.CERTIFIED_MARGIN
        mean = np.abs(last[:, 0]) * 0.5 / math.sqrt(math.pi)
        low = channel_min(last, dense=3)  # the denser reference: the minima here are within 1e-9 of zero
        assert np.all((low < margin * mean + NONNEG_RTOL * np.abs(last).max(axis=-2)).any(-1))


def run_families(bands: int, per_family: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    for kind in range(FAMILIES):
        check(family(rng, kind, per_family, bands), bands, kind in PHYSICAL)


CORE_PER_FAMILY: dict[str, int] = {"1..3": 100, "4..7": 10}
"""Inputs per family and band count in the core run (``-m "not slow"``): every family at every band count.
The ``slow`` twins run the former 500 and 30 from the same seeds."""


class TestNeverNegative:
    @pytest.mark.parametrize("bands", [1, 2, 3])
    def test_one_to_three_bands(self, bands: int) -> None:
        run_families(bands, CORE_PER_FAMILY["1..3"], 1000 + bands)

    @pytest.mark.parametrize("bands", [4, 5, 6, 7])
    def test_four_to_seven_bands(self, bands: int) -> None:
        run_families(bands, CORE_PER_FAMILY["4..7"], 2000 + bands)

    @pytest.mark.slow
    @pytest.mark.parametrize("bands", [1, 2, 3])
    def test_one_to_three_bands_500(self, bands: int) -> None:
        """The core test's seed at 500 inputs per family (5,000 per band count)."""
        run_families(bands, 500, 1000 + bands)

    @pytest.mark.slow
    @pytest.mark.parametrize("bands", [4, 5, 6, 7])
    def test_four_to_seven_bands_30(self, bands: int) -> None:
        """The core test's seed at 30 inputs per family (300 per band count)."""
        run_families(bands, 30, 2000 + bands)

    @pytest.mark.slow
    @pytest.mark.parametrize("bands", [1, 2, 3])
    def test_one_to_three_bands_1e5(self, bands: int) -> None:
        run_families(bands, 10_000, 3000 + bands)

    @pytest.mark.slow
    @pytest.mark.parametrize("bands", [4, 5, 6, 7])
    def test_four_to_seven_bands_1e4(self, bands: int) -> None:
        run_families(bands, 1_000, 4000 + bands)

    def test_near_zero_needs_the_next_row(self) -> None:
        """3 bands, ``method="table"``: a row whose minimum is -1e-9 of the size is rejected, at +1e-9 accepted
        (every channel moved there through its DC term by exact_min, itself checked against
        the reference in test_dering.py; the reference's own 4e-9 would blur the +-1e-9)."""
        rng = np.random.default_rng(5)
        c = np.stack([light(rng, 3) for _ in range(200)])
        table = dering.WINDOW_TABLE
        row = rng.integers(1, len(table), size=200)
        irr = sh.irradiance(c * table[row][:, L_OF[:9], None])
        low, size = dering.exact_min(irr), np.abs(irr).max(axis=-2)
        for sign in (1.0, -1.0):
            d = c.copy()
            d[:, 0] -= (low - sign * NEAR_ZERO * size) / (math.pi * 0.5 / math.sqrt(math.pi))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", dering.DeringWarning)
                _, scales, failed = dering.dering(d, method="table", return_failed=True)
            chosen = np.argmin(np.abs(scales[:, None, :] - table).max(-1), -1)
            assert np.all(chosen <= row) if sign > 0 else np.all((chosen != row) | failed & (row == len(table) - 1))


class TestEdges:
    @pytest.mark.parametrize("bands", [3, 5])
    def test_scale_invariance_per_channel(self, bands: int) -> None:
        """A channel times 2^k (exact) cannot change the row, from 2^-1000 to 2^1000."""
        rng = np.random.default_rng(311)
        c = np.stack([light(rng, bands) for _ in range(20)])
        base = dering.dering(c)[1]
        for k in (-1000, -400, 400, 1000):
            d = c.copy()
            d[..., int(rng.integers(3))] *= 2.0**k
            np.testing.assert_array_equal(dering.dering(d)[1], base)

    @pytest.mark.parametrize("bands", [3, 4])
    def test_zero_channel_and_zero_function(self, bands: int) -> None:
        rng = np.random.default_rng(331)
        c = np.stack([light(rng, bands) for _ in range(10)])
        c[..., 1] = 0.0
        np.testing.assert_array_equal(dering.dering(c)[1], dering.dering(c[..., [0, 2]])[1])
        o, s, failed = dering.dering(np.zeros((bands * bands, 3)), return_failed=True)
        assert not failed and np.all(s == 1.0) and np.all(o == 0.0)

    @pytest.mark.parametrize("target", dering.DERING_TARGETS)
    def test_1e308_does_not_overflow(self, target: str) -> None:
        c = np.zeros((9, 3))
        c[0] = c[2] = 1.0
        np.testing.assert_array_equal(dering.dering(c * 1e308, target=target)[1], dering.dering(c, target=target)[1])

    def test_negative_dc_is_flagged_at_any_magnitude(self) -> None:
        c = np.zeros((9, 3))
        c[0] = [-1.0, 1.0, 1.0]
        for mag in (1e300, 1.0, 1e-300, 1e-310):
            with pytest.warns(dering.DeringWarning):
                assert dering.dering(c * mag, return_failed=True)[2]

    def test_deterministic(self) -> None:
        rng = np.random.default_rng(401)
        c = np.concatenate([family(rng, k, 3, 3) for k in range(FAMILIES)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", dering.DeringWarning)
            first = dering.dering(c)
            singles = [dering.dering(x) for x in c[::-1]][::-1]
            again = dering.dering(c)
        for a, b in zip(first, again):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(np.stack([s[1] for s in singles]), first[1])

    def test_reference_finds_negatives(self) -> None:
        """Negative control: the reference sees the negative irradiance of unwindowed deltas."""
        d = sh.basis(unit(np.random.default_rng(3).normal(size=(20, 3))), 3)[..., None] * np.ones(3)
        assert np.all(channel_min(sh.irradiance(d)) < -0.01 * reference_min(np.zeros((1, 9))).max() - 0.01)


def sweep(bands: list[int], per_family: int, seed: int) -> None:
    """Run :func:`run_families` at ``per_family`` inputs per family (10 families) per band count
    and print what was checked; an AssertionError stops it."""
    import time

    for b in bands:
        t0 = time.perf_counter()
        rng = np.random.default_rng(seed + b)
        failed = 0
        for kind in range(FAMILIES):
            for start in range(0, per_family, 2000):  # in chunks: the reference's memory stays small
                c = family(rng, kind, min(2000, per_family - start), b)
                check(c, b, kind in PHYSICAL)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", dering.DeringWarning)
                    failed += int(dering.dering(c, return_failed=True)[2].sum())
        print(f"bands {b}: {FAMILIES * per_family} inputs, 0 negative, {failed} flagged failed "
              f"(none in the physical families), {time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":  # the 10^5 sweep of the closing note: python tests/post/test_dering_adversarial.py 4 5 6 7
    import sys

    sweep([int(a) for a in sys.argv[1:]] or [4, 5, 6, 7], 10_000, 5000)
