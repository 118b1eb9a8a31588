"""
Batches of every size give what single frames give (issue 26, item 3)
=====================================================================

:meth:`skysh.SkySH.coefficients` evaluates an array batch in chunks of
:data:`skysh.runtime.BATCH_CHUNK` output values, each by one of two routes (:data:`skysh.runtime.FEW_FRAMES`):
Chebyshev terms and rotation factors from ``cos`` for few frames, by doubling and angle addition for
more. These tests pin what a user sees: the same numbers as the scalar call at every batch size, across
the chunk and route boundaries; the doubling against an independent extended-precision recurrence; and
the temporaries of a large batch bounded (tracemalloc sees numpy's allocations).
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh import SkySH, runtime
from skysh.domain import MAX_DEGREE
from skysh.table import poly

EPS: float = float(np.finfo(np.float64).eps)

SCALAR_AGREEMENT: float = 256 * EPS
"""Batch vs scalar call, in units of the largest |coefficient|: the scalar path takes T_k = cos(k acos x)
(error up to k^2 eps, 169 eps at degree 13) and sums in another order; a wrong term or rotation is O(1)."""

DOUBLING_ERROR_PER_DEGREE_SQUARED: float = 1.0
"""chebyshev_rows' error against the exact T_k, in eps times degree^2: the bound the scalar path's
cos(k acos x) is documented with (measured: 24 eps at degree 13, as the three-term recurrence's 25)."""

TEMPORARY_LIMIT_BYTES: int = 32 << 20
"""Most memory a batch may hold beyond its result: "a few tens of MB" (issue 26). Chunks of BATCH_CHUNK
values keep it near 1 MB; the unchunked design matrix of 10^5 7-band frames alone was 90 MB."""


TEST_CHUNK: int = 4096
"""The chunk these tests evaluate with: small, so that batches a few chunks long are compared frame by frame
with the scalar call in a second (the shipped chunk's seams are the same code)."""


@pytest.fixture(scope="module")
def sky() -> SkySH:
    return SkySH.load()


def _frames(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, math.pi / 2.0, n), rng.uniform(2.5, 6.0, n), rng.uniform(-7.0, 7.0, n)


def _sizes(bands: int) -> list[int]:
    step = runtime.BATCH_CHUNK // (3 * bands * bands)  # frames per chunk of a plain plan
    few = runtime.FEW_FRAMES
    return [1, 2, few - 1, few, few + 1, step - 1, step, step + 1, 2 * step + few + 3]


@pytest.mark.parametrize("bands", [1, 3, 7])
@pytest.mark.parametrize("options", [{}, {"irradiance": True}, {"gibbs": False, "irradiance": True, "dering": False},
                                     {"sun": True, "ground_albedo": 0.3}])
def test_batch_equals_single_frames_at_every_size(sky: SkySH, bands: int, options: dict,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runtime, "BATCH_CHUNK", TEST_CHUNK)
    if bands == 1 and "sun" in options:
        options = {"sun": True}  # a 1-band sky has no c_10 for the ground
    if bands == 7 and options.get("irradiance") and options.get("dering") is None:
        pytest.skip("the 7-band deringing is per function (tests/post): the batch path here is the same as at 3")
    for n in _sizes(bands):
        ts, t, phi = _frames(n, seed=n)
        batch = sky.coefficients(ts, t, phi, bands=bands, **options)
        single = np.array([sky.coefficients(float(a), float(b), float(c), bands=bands, **options)
                           for a, b, c in zip(ts, t, phi)])  # every frame: a chunk's seam is anywhere
        scale = np.max(np.abs(single))
        assert batch.shape == (n, bands * bands, 3)
        np.testing.assert_allclose(batch, single, rtol=0.0, atol=SCALAR_AGREEMENT * scale, err_msg=f"n={n}")


def test_both_routes_agree(sky: SkySH, monkeypatch: pytest.MonkeyPatch) -> None:
    """The cos route and the doubling route on the same frames (the route is a cost choice, not a result)."""
    ts, t, phi = _frames(40)
    for bands in (2, 7):
        monkeypatch.setattr(runtime, "FEW_FRAMES", 10**6)
        by_cos = sky.coefficients(ts, t, phi, bands=bands)
        monkeypatch.setattr(runtime, "FEW_FRAMES", 0)
        by_doubling = sky.coefficients(ts, t, phi, bands=bands)
        np.testing.assert_allclose(by_cos, by_doubling, rtol=0.0, atol=SCALAR_AGREEMENT * np.max(np.abs(by_cos)))


def test_broadcast_and_shapes(sky: SkySH) -> None:
    ts, t, _ = _frames(runtime.FEW_FRAMES + 5)
    grid = sky.coefficients(ts[:, None], t[None, :6], 0.25)
    assert grid.shape == (ts.size, 6, 9, 3)
    column = sky.coefficients(ts, np.full(ts.size, t[2]), np.full(ts.size, 0.25))  # BLAS may block n differently
    np.testing.assert_allclose(grid[:, 2], column, rtol=0.0, atol=SCALAR_AGREEMENT * np.max(np.abs(column)))
    assert sky.coefficients(np.empty((0, 4)), 3.0).shape == (0, 4, 9, 3)


@settings(max_examples=60, deadline=None)
@given(x=st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=20), degree=st.integers(0, MAX_DEGREE))
def test_chebyshev_rows_against_extended_precision(x: list[float], degree: int) -> None:
    xs = np.array(x)
    exact = [np.ones(xs.size, np.longdouble), xs.astype(np.longdouble)]
    for _ in range(2, degree + 1):
        exact.append(2 * exact[1] * exact[-1] - exact[-2])
    got = poly.chebyshev_rows(xs, degree)
    assert got.shape == (degree + 1, xs.size)
    error = np.abs(got - np.array(exact[: degree + 1])).astype(np.float64)
    assert np.all(error <= DOUBLING_ERROR_PER_DEGREE_SQUARED * max(degree, 1) ** 2 * EPS), error.max() / EPS


def test_large_batch_temporaries_are_bounded(sky: SkySH) -> None:
    n, bands = 100_000, 7
    ts, t, phi = _frames(n)
    sky.coefficients(ts[:10], t[:10], phi[:10], bands=bands)  # plans built outside the measurement
    tracemalloc.start()
    try:
        out = sky.coefficients(ts, t, phi, bands=bands)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak - out.nbytes <= TEMPORARY_LIMIT_BYTES, (peak - out.nbytes) / 2**20


def test_deringed_batch_temporaries_are_bounded(sky: SkySH) -> None:
    """The 7-band irradiance default deringes each sky on the certificate: decided a chunk of functions at a
    time (skysh.post.dering.SEARCH_CHUNK), 200 skies hold what 16 do (unchunked: ~170 MB here, 84 GB at 10^5)."""
    ts, t, phi = _frames(200, seed=7)
    sky.coefficients(ts[:2], t[:2], phi[:2], bands=7, irradiance=True)
    tracemalloc.start()
    try:
        out = sky.coefficients(ts, t, phi, bands=7, irradiance=True)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak - out.nbytes <= TEMPORARY_LIMIT_BYTES, (peak - out.nbytes) / 2**20
