"""Tests of skysh.post.quantize: bounds derived on a dense sphere, the Listing 1 codec bit for bit, Table 3."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from conftest import fibonacci_sphere, unit
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh.post import quantize
from skysh.post.quantize import QuantizationClampWarning, compress, decompress
from skysh.sh import basis as sh

DENSE_POINTS: int = 400_001
"""Fibonacci-sphere points of the Table 2 search (the seed used 90,301)."""

DENSE_SPHERE_TOLERANCE: float = 1e-4
"""How far below the true maximum the best of the dense points may be: the nearest point lies within
about 0.7 sqrt(4 pi / N) = 0.0039 rad of the maximiser and |Y / Y_00| curves at most ~8 per rad^2
there (sqrt(15) * 2 for x z), so the shortfall is <= 0.5 * 8 * 0.0039^2 = 6e-5."""

MAXIMISER_TOLERANCE: float = 0.01
"""Coordinates of the best dense point against the analytic maximiser: the best point may sit up to
sqrt(2 * 1e-4 / 8) = 0.005 rad away on the flat top of the maximum (DENSE_SPHERE_TOLERANCE)."""

ROUNDING_TOLERANCE: float = 1e-12
"""Float64 rounding of a basis value of size ~2 (a few ulps, with room)."""

CODEC_RELATIVE_TOLERANCE: float = 1e-12
"""Slack on the half-step error bound for the float64 arithmetic of encode and decode (each ~1e-16
relative; the bound itself is ~1e-3 for 8 bits)."""

PARSEVAL_TOLERANCE: float = 1e-12
"""L2 from the coefficients versus L2 by an exact quadrature: both are float64 sums of ~1e4 terms."""

L1_RULE_TOLERANCE: float = 1e-3
"""Relative change of the L1 sums between 32 and 64 Gauss nodes (|e| has kinks; measured ~1e-5)."""

SCALED_ROUND_TRIP_RTOL: float = 1e-12
"""A function times a large or small DC vs the function itself: the codes depend on the ratios c / dc
only (the same codes), and decoding multiplies by dc, so out / dc differs by one or two roundings."""


def delta_lights(dirs: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """SH (9, C) of a sum of delta lights: c_k = sum_j w_j Y_k(d_j), a non-negative function."""
    return sh.basis(dirs, 3).T @ weights


@st.composite
def nonnegative_sh(draw, channels: int = 3) -> np.ndarray:
    n = draw(st.integers(1, 6))
    raw = draw(st.lists(st.floats(-1.0, 1.0), min_size=3 * n, max_size=3 * n))
    vectors = np.array(raw).reshape(n, 3)
    vectors[np.linalg.norm(vectors, axis=1) < 1e-3] = [0.0, 0.0, 1.0]
    weights = np.array(draw(st.lists(st.floats(1e-3, 1e3), min_size=n * channels, max_size=n * channels)))
    coeffs = delta_lights(unit(vectors), weights.reshape(n, channels))
    ambient = draw(st.floats(0.0, 10.0))
    coeffs[0] += ambient * 2.0 * math.sqrt(math.pi)  # a constant ambient term L has c0 = L / Y00
    return coeffs


# --------------------------------------------------------------------------- #
# A pure-Python transcription of the seed's Listing 1 (integer arithmetic)
# --------------------------------------------------------------------------- #
def listing1_compress(sh9: list[float], bits: int, non_zonal: float, sq: bool, irrad: bool) -> list[int]:
    bv = float((1 << (bits - 1)) - 1)
    lc = 1.0 / (sh9[0] * math.sqrt(3.0) * (2.0 / 3.0 if irrad else 1.0))
    qz = 1.0 / (sh9[0] * math.sqrt(5.0) * (0.25 if irrad else 1.0))
    nz = 1.0 / (sh9[0] * non_zonal * (0.25 if irrad else 1.0))
    scales = [lc, lc, lc, nz, nz, qz, nz, nz]  # the decoder's (lc, lc, lc, nz), (nz, qz, nz, nz)
    codes = []
    for value, scale in zip(sh9[1:], scales):
        v = value * scale
        if sq:
            v = math.copysign(math.sqrt(abs(v)), v)
        codes.append(math.floor(bv + 0.5 + v * bv))
    per_word = 32 // bits
    words = [0] * (-(-8 // per_word))
    for j, code in enumerate(codes):
        words[j // per_word] |= code << (bits * (j % per_word))
    return words


def listing1_decompress(words: list[int], dc: float, bits: int, nzb: float, sq: bool, irrad: bool) -> list[float]:
    bv = float((1 << (bits - 1)) - 1)
    lc = math.sqrt(3.0) * (2.0 / 3.0 if irrad else 1.0)
    qz = math.sqrt(5.0) * (0.25 if irrad else 1.0)
    nz = nzb * (0.25 if irrad else 1.0)
    scales = [lc, lc, lc, nz, nz, qz, nz, nz]
    per_word = 32 // bits
    out = [dc]
    for j in range(8):
        code = (words[j // per_word] >> (bits * (j % per_word))) & ((1 << bits) - 1)
        t = code / bv - 1.0
        if sq:
            t = math.copysign(t * t, t)
        out.append(t * dc * scales[j])
    return out


# --------------------------------------------------------------------------- #
class TestBounds:
    @pytest.fixture(scope="class")
    @classmethod
    def table2(cls):
        dirs = fibonacci_sphere(DENSE_POINTS)
        y = sh.basis(dirs, 3)
        return dirs, y[:, 1:] / y[:, :1]  # (N, 8): Y_k / Y_00

    def test_dense_sphere_maxima_are_the_tight_bounds(self, table2):
        """The seed's Table 2: max |Y_k / Y_00| over a dense sphere is sqrt(3), sqrt(15)/2 or sqrt(5)."""
        _, ratio = table2
        numeric = np.abs(ratio).max(axis=0)
        np.testing.assert_array_less(numeric, quantize.TIGHT_BOUNDS + ROUNDING_TOLERANCE)
        np.testing.assert_array_less(quantize.TIGHT_BOUNDS - DENSE_SPHERE_TOLERANCE, numeric)
        # Reference values written independently of the module: sqrt(2l + 1) and sqrt(15) / 2.
        expected = [math.sqrt(3)] * 3 + [math.sqrt(15) / 2] * 2 + [math.sqrt(5)] + [math.sqrt(15) / 2] * 2
        np.testing.assert_allclose(quantize.TIGHT_BOUNDS, expected, rtol=0, atol=ROUNDING_TOLERANCE)
        prior = [math.sqrt(3)] * 3 + [math.sqrt(5)] * 5
        np.testing.assert_allclose(quantize.PRIOR_BOUNDS, prior, rtol=0, atol=ROUNDING_TOLERANCE)

    def test_prior_bound_is_loose_for_non_zonal_quadratics_only(self, table2):
        _, ratio = table2
        numeric = np.abs(ratio).max(axis=0)
        loose = quantize.PRIOR_BOUNDS - numeric
        non_zonal = [3, 4, 6, 7]  # (2, -2), (2, -1), (2, 1), (2, 2) in k = 1..8 order
        assert np.all(loose[non_zonal] > math.sqrt(5) - math.sqrt(15) / 2 - DENSE_SPHERE_TOLERANCE)
        assert np.all(loose[[0, 1, 2, 5]] < DENSE_SPHERE_TOLERANCE)

    def test_maximisers_are_where_two_coordinates_are_one_over_sqrt2(self, table2):
        """Seed 3.2: Y(2, 1) peaks at (1/sqrt 2, 0, -1/sqrt 2); Y(2, -2) at phi = pi/4 on the equator."""
        dirs, ratio = table2
        loc = MAXIMISER_TOLERANCE
        best = dirs[np.argmax(ratio[:, 6])]  # Y(2, 1) = -sqrt(15) x z / ... is largest where x z = -1/2
        assert abs(abs(best[0]) - 1 / math.sqrt(2)) < loc and abs(best[1]) < loc and best[0] * best[2] < 0
        best = dirs[np.argmax(ratio[:, 3])]  # Y(2, -2) ~ x y
        assert abs(abs(best[0]) - abs(best[1])) < 2 * loc and abs(best[2]) < loc and best[0] * best[1] > 0

    def test_y20_range_is_asymmetric(self, table2):
        """Y(2, 0) / Y_00 = (sqrt 5 / 2)(3 z^2 - 1) spans [-sqrt(5) / 2, sqrt(5)] (seed Table 2: -1.1180)."""
        _, ratio = table2
        y20 = ratio[:, 5]
        assert abs(y20.max() - math.sqrt(5)) < DENSE_SPHERE_TOLERANCE
        assert abs(y20.min() + math.sqrt(5) / 2) < DENSE_SPHERE_TOLERANCE
        assert y20.max() + y20.min() > 1.0  # far from symmetric

    def test_irradiance_factors(self):
        """A_1 / A_0 = (2 pi / 3) / pi and A_2 / A_0 = (pi / 4) / pi (docs/conventions.md)."""
        expected = np.array([2 / 3] * 3 + [1 / 4] * 5) * quantize.TIGHT_BOUNDS
        np.testing.assert_allclose(quantize.bounds("tight", irradiance=True), expected, rtol=ROUNDING_TOLERANCE)

    def test_unknown_bound(self):
        with pytest.raises(ValueError, match="bound must be one of"):
            quantize.bounds("loose")

    @settings(max_examples=60, deadline=None)
    @given(nonnegative_sh())
    def test_ratios_of_nonnegative_functions_are_within_the_tight_bound(self, coeffs):
        assert np.all(np.abs(quantize.ratios(coeffs, "tight")) <= 1.0 + quantize.CLAMP_TOLERANCE)
        irr = quantize.ratios(sh.irradiance(coeffs), "tight", irradiance=True)
        assert np.all(np.abs(irr) <= 1.0 + quantize.CLAMP_TOLERANCE)


# --------------------------------------------------------------------------- #
class TestCodec:
    @pytest.fixture
    def probes(self):
        rng = np.random.default_rng(5)
        dirs = unit(rng.normal(size=(40, 3)))
        return np.stack([delta_lights(dirs[i : i + 4], rng.random((4, 3)) + 0.01) for i in range(0, 40, 4)])

    @pytest.mark.parametrize("bound", quantize.BOUND_NAMES)
    @pytest.mark.parametrize("sq", [False, True])
    @pytest.mark.parametrize("irrad", [False, True])
    def test_listing1_bit_for_bit(self, probes, bound, sq, irrad):
        non_zonal = math.sqrt(15) / 2 if bound == "tight" else math.sqrt(5)
        coeffs = sh.irradiance(probes) if irrad else probes
        dc, words = compress(coeffs, 8, bound, sq, irrad)
        assert words.dtype == np.uint32 and words.shape == (10, 3, 2) and dc.shape == (10, 3)
        for p in range(coeffs.shape[0]):  # the reference is scalar Python, one probe and channel at a time
            for c in range(3):
                ref = listing1_compress(list(coeffs[p, :, c]), 8, non_zonal, sq, irrad)
                assert [int(w) for w in words[p, c]] == ref
                back = listing1_decompress(ref, float(dc[p, c]), 8, non_zonal, sq, irrad)
                np.testing.assert_allclose(
                    decompress(dc, words, 8, bound, sq, irrad)[p, :, c], back, rtol=CODEC_RELATIVE_TOLERANCE, atol=0
                )

    @pytest.mark.parametrize("bits", [2, 4, 5, 6, 7, 10, 11, 16, 17, 32])
    def test_other_bit_depths_follow_the_documented_layout(self, probes, bits):
        _dc, words = compress(probes, bits)
        assert words.shape == probes.shape[:1] + (3, quantize.words_per_channel(bits))
        for p in (0, 7):
            for c in range(3):
                ref = listing1_compress(list(probes[p, :, c]), bits, math.sqrt(15) / 2, False, False)
                assert [int(w) for w in words[p, c]] == ref

    def test_words_per_channel_table(self):
        table = {2: 1, 4: 1, 5: 2, 6: 2, 7: 2, 8: 2, 9: 3, 10: 3, 11: 4, 16: 4, 17: 8, 32: 8}
        assert {b: quantize.words_per_channel(b) for b in table} == table

    @pytest.mark.parametrize("sq", [False, True])
    def test_recompressing_decoded_coefficients_is_bit_exact(self, probes, sq):
        dc, words = compress(probes, sqrt=sq)
        dc2, words2 = compress(decompress(dc, words, sqrt=sq), sqrt=sq)
        np.testing.assert_array_equal(words2, words)
        np.testing.assert_array_equal(dc2, dc)

    def test_zero_and_the_bound_are_exact(self):
        """A delta light at +Z: c(1, 0) / c0 = sqrt(3) exactly at the top code; c(1, +-1) = 0 at code bv."""
        c = delta_lights(np.array([[0.0, 0.0, 1.0]]), np.array([[2.0]]))
        dc, words = compress(c)
        out = decompress(dc, words)
        assert out[1, 0] == 0.0 and out[3, 0] == 0.0 and out[4, 0] == 0.0
        assert out[2, 0] == pytest.approx(c[2, 0], rel=CODEC_RELATIVE_TOLERANCE)
        assert (int(words[0, 0]) >> 8) & 0xFF == 254  # Y(1, 0) is field 1: code 2 bv

    def test_irradiance_flag_stores_the_same_codes_as_radiance(self, probes):
        """E_lm / (E_00 bound A_l / A_0) = L_lm / (L_00 bound): the codes coincide."""
        np.testing.assert_array_equal(compress(sh.irradiance(probes), irradiance=True)[1], compress(probes)[1])

    def test_n_dimensional(self, probes):
        batch = probes.reshape(2, 5, 9, 3)
        dc, words = compress(batch, 10, "prior", True)
        flat_dc, flat_words = compress(probes, 10, "prior", True)
        np.testing.assert_array_equal(words.reshape(flat_words.shape), flat_words)
        np.testing.assert_array_equal(dc.reshape(flat_dc.shape), flat_dc)
        out = decompress(dc, words, 10, "prior", True)
        np.testing.assert_array_equal(out.reshape(probes.shape), decompress(flat_dc, flat_words, 10, "prior", True))
        single_dc, single_words = compress(probes[3])
        np.testing.assert_array_equal(single_words, compress(probes)[1][3])
        assert decompress(single_dc, single_words).shape == (9, 3)

    def test_out_of_bound_is_clamped_and_reported(self):
        c = np.zeros((9, 2))
        c[0] = 1.0
        c[7] = [3.0, -0.5]  # 3 > sqrt(15) / 2: no non-negative function
        with pytest.warns(QuantizationClampWarning, match="1 of 16 SH coefficients exceed"):
            dc, words = compress(c)
        out = decompress(dc, words)
        assert np.all(np.isfinite(out))
        assert out[7, 0] == pytest.approx(math.sqrt(15) / 2, rel=CODEC_RELATIVE_TOLERANCE)
        assert abs(out[7, 1] + 0.5) <= math.sqrt(15) / 2 / 254 * (1 + CODEC_RELATIVE_TOLERANCE)

    def test_zero_function_and_zero_dc(self):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            dc, words = compress(np.zeros((9, 3)))
        np.testing.assert_array_equal(decompress(dc, words), np.zeros((9, 3)))
        c = np.zeros((9, 1))
        c[2] = 1.0
        with pytest.warns(QuantizationClampWarning):
            dc, words = compress(c)
        out = decompress(dc, words)
        assert np.all(np.isfinite(out)) and np.all(out == 0.0)

    @pytest.mark.parametrize("dc", [1e308, 1.7e308, -1e308, 1e-308, 5e-324])
    def test_extreme_dc_round_trips_finite(self, dc):
        """Issue 12: a finite DC of 1e308 decoded rows 4-8 as NaN (dc * bound overflowed). Every
        finite input gives finite output, within half a step of the input (ratios are scale-free)."""
        unit = np.zeros((9, 3))
        unit[0], unit[1], unit[5], unit[8] = 1.0, [0.5, -0.3, 0.1], [-0.9, 0.2, 0.0], [0.7, -0.99, 0.3]
        c = unit * dc
        for bound in quantize.BOUND_NAMES:
            with warnings.catch_warnings():
                warnings.simplefilter("error")  # no overflow warning, no clamp report
                out = decompress(*compress(c, bound=bound), bound=bound)
            assert np.all(np.isfinite(out))
            if dc > 1e-300:  # normal magnitudes: the same codes as the unit function, scaled
                np.testing.assert_allclose(out / dc, decompress(*compress(unit, bound=bound), bound=bound),
                                           rtol=SCALED_ROUND_TRIP_RTOL)

    def test_decoded_beyond_the_largest_float_is_clipped(self):
        """A coefficient near the largest float decodes (within half a step) beyond it: clipped, finite."""
        c = np.zeros((9, 1))
        c[0], c[4] = 1e308, 1.79e308  # ratio 1.79 <= sqrt(15)/2: valid; the nearest code may exceed it
        out = decompress(*compress(c))
        assert np.all(np.isfinite(out)) and abs(out[4, 0] - c[4, 0]) <= 1e308 * 1.9365 / 254

    def test_extreme_nonnegative_functions_are_not_reported(self):
        """Delta lights exactly at the maximisers reach the bound up to rounding: no warning."""
        s = 1 / math.sqrt(2)
        dirs = np.array([[s, 0.0, -s], [s, s, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -s, s]])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            for d in dirs:  # five fixed cases
                c = delta_lights(d[None], np.array([[1.0, 1e-30, 1e6]]))
                for bound in quantize.BOUND_NAMES:
                    for irr in (False, True):
                        compress(sh.irradiance(c) if irr else c, bound=bound, irradiance=irr)

    @settings(max_examples=80, deadline=None)
    @given(nonnegative_sh(), st.integers(2, 16), st.sampled_from(quantize.BOUND_NAMES), st.booleans())
    def test_error_is_at_most_half_a_step_times_bound_times_dc(self, coeffs, bits, bound, sq):
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # non-negative functions never clamp
            dc, words = compress(coeffs, bits, bound, sq)
        out = decompress(dc, words, bits, bound, sq)
        half = 0.5 / ((1 << (bits - 1)) - 1)  # half a step in units of bound * DC
        scale = quantize.bounds(bound)[:, None] * np.abs(coeffs[0])
        if sq:
            # |t^2 - s^2| = |t - s| |t + s| <= h (2 s + h) with s = sqrt|v| <= 1
            s = np.sqrt(np.abs(coeffs[1:] / scale))
            allowed = half * (2.0 * s + half) * scale
        else:
            allowed = half * scale
        assert np.all(np.abs(out[1:] - coeffs[1:]) <= allowed * (1 + CODEC_RELATIVE_TOLERANCE))
        np.testing.assert_array_equal(out[0], coeffs[0])

    @pytest.mark.parametrize(
        "kwargs, match",
        [
            ({"bits": 1}, "bits must be an integer in \\[2, 32\\]"),
            ({"bits": 33}, "bits must be an integer in \\[2, 32\\]"),
            ({"bits": 8.0}, "bits must be an integer"),
            ({"bits": True}, "bits must be an integer"),
            ({"bound": "loose"}, "bound must be one of"),
        ],
    )
    def test_bad_parameters(self, kwargs, match):
        with pytest.raises(ValueError, match=match):
            compress(np.ones((9, 3)), **kwargs)
        with pytest.raises(ValueError, match=match):
            decompress(np.ones(3), np.zeros((3, 2), dtype=np.uint32), **kwargs)

    @pytest.mark.parametrize("bad", [np.ones((4, 3)), np.ones(9), np.full((9, 3), np.nan), np.full((9, 3), np.inf)])
    def test_bad_coefficients(self, bad):
        with pytest.raises(ValueError, match="coeffs must"):
            compress(bad)

    def test_bad_words(self):
        dc, words = compress(np.ones((9, 3)))
        with pytest.raises(ValueError, match="words must have shape"):
            decompress(dc, words[:, :1])
        with pytest.raises(ValueError, match="words must be integers"):
            decompress(dc, words.astype(np.float64))
        with pytest.raises(ValueError, match="words must be integers"):
            decompress(dc, words.astype(np.int64) - 2**31 * 2)
        with pytest.raises(ValueError, match="outside the valid codes \\[0, 254\\]"):
            decompress(dc, words | np.uint32(0xFF))
        dc10, words10 = compress(np.ones((9, 3)), bits=10)
        with pytest.raises(ValueError, match="padding bits"):
            decompress(dc10, words10 | np.uint32(1 << 31), bits=10)
        with pytest.raises(ValueError, match="dc must be finite"):
            decompress(np.full(3, np.nan), words)

    def test_ragged_words_name_words(self):
        """Issue 23: a ragged ``words`` was numpy's "inhomogeneous shape" error, naming nothing."""
        dc, words = compress(np.ones((9, 3)))
        for ragged in ([[1, 2], [3], [4, 5]], [words[0].tolist(), words[1, :1].tolist(), words[2].tolist()]):
            with pytest.raises(ValueError, match=r"^words must be a rectangular array of integers in \[0, 2\^32 - 1\]"):
                decompress(dc, ragged)
        np.testing.assert_array_equal(decompress(dc, words.tolist()), decompress(dc, words))  # a rectangular list passes


# --------------------------------------------------------------------------- #
class TestTable3:
    @pytest.fixture(scope="class")
    @classmethod
    def probes(cls):
        rng = np.random.default_rng(11)
        dirs = unit(rng.normal(size=(64, 3, 3)))
        weights = rng.random((64, 3, 3))
        y = sh.basis(dirs, 3)  # (64, 3 lights, 9)
        coeffs = np.einsum("pjk,pjc->pkc", y, weights)
        coeffs[:, 0] += 2.0 * math.sqrt(math.pi) * 0.2  # some ambient light
        return coeffs

    def test_structure_and_parseval(self, probes):
        result = quantize.table3_errors(probes)
        assert len(result["rows"]) == 8 and len(result["changes"]) == 12
        assert result["probes"] == 64 and result["channels"] == 3 and result["bits"] == 8
        dirs, weights = sh.quadrature_rule(4)  # exact for the degree-4 squared error
        y = sh.basis(dirs, 3)
        for row in result["rows"]:
            irr = row["quantity"] == "irradiance"
            original = sh.irradiance(probes) if irr else probes
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                dc, words = compress(original, 8, row["bound"], row["sqrt"], irr)
            error = (decompress(dc, words, 8, row["bound"], row["sqrt"], irr) - original) / (
                original[:, :1] * 0.5 / math.sqrt(math.pi)
            )
            values = np.einsum("mk,pkc->pmc", y, error)
            l2 = math.sqrt(np.einsum("m,pmc->", weights, values**2) / (4 * math.pi))
            assert row["L2"] == pytest.approx(l2, rel=PARSEVAL_TOLERANCE)
            assert row["RMSE"] == pytest.approx(l2 / math.sqrt(64 * 3), rel=PARSEVAL_TOLERANCE)
            assert row["clamped"] == 0

    def test_tight_bound_reduces_the_error_without_sqrt(self, probes):
        """4 of 8 steps shrink by sqrt(15)/2 / sqrt(5) = 0.866: the squared error falls by about 15%."""
        result = quantize.table3_errors(probes)
        for change in result["changes"]:
            if not change["sqrt"] and change["metric"] in ("L2", "RMSE"):
                assert change["change_percent"] > 0.0

    def test_l1_rule_is_converged(self, probes):
        coarse = quantize.table3_errors(probes[:16])
        fine = quantize.table3_errors(probes[:16], n_theta=64)
        for a, b in zip(coarse["rows"], fine["rows"]):
            assert a["L1"] == pytest.approx(b["L1"], rel=L1_RULE_TOLERANCE)

    def test_refuses_non_positive_dc(self, probes):
        bad = probes.copy()
        bad[0, 0, 0] = 0.0
        with pytest.raises(ValueError, match="positive DC"):
            quantize.table3_errors(bad)
        with pytest.raises(ValueError, match="n_theta"):
            quantize.table3_errors(probes, n_theta=2)
