"""
The result written into a buffer the caller owns (``out=``, issue 26 item 3)
============================================================================

A frame loop over large batches reuses one result (``coefficients(..., out=buf)``) so that no call pays for
fresh memory. These tests pin what a user relies on: the values are those of the same call without ``out``, bit
for bit, on every path (radiance, the irradiance table, the pipeline with and without deringing, a colourspace
conversion, the sun and the ground, scalar and batch, across chunk seams); ``out`` itself is returned; the
evaluation writes straight into it (tracemalloc: no result-sized temporary, with the call without ``out`` as the
control that does allocate one); and a buffer of the wrong kind is refused before any work, naming ``out``.
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh import SkySH, runtime

TEST_CHUNK: int = 4096
"""A small chunk (of both kinds: the evaluation's and the composed paths'), so a batch of a few hundred frames
crosses several seams (the shipped chunks' code)."""

PATHS: list[dict] = [
    {}, {"bands": 7}, {"irradiance": True}, {"irradiance": True, "bands": 7, "dering": False},
    {"irradiance": True, "bands": 5}, {"sun": True, "ground_albedo": 0.3}, {"sun": True, "ground_albedo": 0.3,
    "irradiance": True}, {"colourspace": "ACEScg", "bands": 4}, {"irradiance": True, "colourspace": "ACEScg"},
    {"irradiance_table": True}, {"gibbs": False, "bands": 2},
]
"""Every route through :meth:`skysh.SkySH.coefficients` after the evaluation (each option that changes it)."""

CHUNK_AGREEMENT: float = 64 * float(np.finfo(np.float64).eps)
"""A composed batch in chunks vs in one call, in units of the largest |coefficient|: each frame's arithmetic is its
own, but the BLAS product sums its 112 terms in an order that depends on how many rows it is given (measured: 17 eps
at most); a frame misplaced at a seam is O(1)."""

COMPOSED_WHOLE: float = 2.0
"""Least traced memory of a lit batch evaluated in one chunk, in results: several arrays of its size (measured 3.5)."""

COMPOSED_SLACK: float = 12.0
"""Most traced memory of a lit batch in chunks beyond its result, in chunk values (8 bytes each): a chunk's sky,
sun, sum and E_h (measured 7.3 at 2^14 values a chunk)."""

OUT_PEAK_FRACTION: float = 0.25
"""Most traced memory a batch written into ``out`` may allocate, as a fraction of the result's size: its chunks
hold about 1 MB (here 11.8 MB of result); the same call without ``out`` allocates the whole result (the control)."""


def _frames(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(0.0, math.pi / 2.0, n), rng.uniform(2.5, 6.0, n), rng.uniform(-7.0, 7.0, n)


@pytest.mark.parametrize("options", PATHS, ids=lambda o: ",".join(f"{k}={v}" for k, v in o.items()) or "default")
def test_out_holds_the_same_values_bit_for_bit(sky: SkySH, options: dict, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runtime, "BATCH_CHUNK", TEST_CHUNK)
    monkeypatch.setattr(runtime, "COMPOSED_CHUNK", TEST_CHUNK)
    for frame in (_frames(37 if options.get("bands") == 5 else 300), (0.4, 3.1, -2.0)):
        expected = sky.coefficients(*frame, **options)
        buffer = np.full_like(expected, np.nan)  # a value never written stays NaN
        result = sky.coefficients(*frame, **options, out=buffer)
        assert result is buffer
        np.testing.assert_array_equal(buffer, expected)


@settings(max_examples=25, deadline=None)
@given(rows=st.integers(0, 5), columns=st.integers(1, 4), bands=st.integers(1, 7), irradiance=st.booleans(),
       seed=st.integers(0, 2**16))
def test_out_with_broadcast_parameters(sky: SkySH, rows: int, columns: int, bands: int, irradiance: bool,
                                       seed: int) -> None:  # sky: session-scoped, which hypothesis accepts
    rng = np.random.default_rng(seed)
    ts = rng.uniform(0.0, math.pi / 2.0, (rows, 1))
    t, phi = rng.uniform(2.5, 6.0, columns), float(rng.uniform(-4.0, 4.0))
    options = {"bands": bands, "irradiance": irradiance, "dering": False}
    expected = sky.coefficients(ts, t, phi, **options)
    buffer = np.full((rows, columns, bands * bands, 3), np.nan)
    assert sky.coefficients(ts, t, phi, **options, out=buffer) is buffer
    np.testing.assert_array_equal(buffer, expected)


def _traced_peak(call: object) -> int:
    tracemalloc.start()
    try:
        call()  # type: ignore[operator]
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_a_batch_is_evaluated_straight_into_out(sky: SkySH) -> None:
    frames = _frames(10_000)
    buffer = sky.coefficients(*frames, bands=7)
    size = buffer.nbytes
    peak_out = _traced_peak(lambda: sky.coefficients(*frames, bands=7, out=buffer))
    peak_new = _traced_peak(lambda: sky.coefficients(*frames, bands=7))
    assert peak_new >= size  # the control: without out the result itself is allocated (and traced)
    assert peak_out <= OUT_PEAK_FRACTION * size, f"{peak_out:,} bytes traced for a {size:,}-byte result"


def _bad_buffers(shape: tuple[int, ...]) -> list[tuple[str, object]]:
    read_only = np.empty(shape)
    read_only.flags.writeable = False
    return [
        ("a list", np.zeros(shape).tolist()),
        ("float32", np.empty(shape, np.float32)),
        ("a wrong shape", np.empty(shape[:-2] + (shape[-2] + 1, 3))),
        ("a missing batch axis", np.empty(shape[-2:])),
        ("not C-contiguous", np.empty(shape[::-1]).T),
        ("read-only", read_only),
    ]


@pytest.mark.parametrize("options", [{"sun": True, "ground_albedo": 0.3}, {"bands": 4, "irradiance": True},
                                     {"colourspace": "ACEScg"}], ids=["lit", "dering", "conversion"])
def test_composed_paths_in_chunks_as_in_one_call(sky: SkySH, options: dict, monkeypatch: pytest.MonkeyPatch) -> None:
    frames = (np.linspace(0.0, 1.5, 40)[:, None], np.array([2.5, 4.0, 6.0]), 0.7)  # broadcast: (40, 3) frames
    whole = sky.coefficients(*frames, **options)
    monkeypatch.setattr(runtime, "COMPOSED_CHUNK", 3 * 16 * 3 * 7)  # 7 frames a chunk at 4 bands: a ragged end
    chunked = sky.coefficients(*frames, **options)
    scale = np.abs(whole).max()
    np.testing.assert_allclose(chunked / scale, whole / scale, rtol=0.0, atol=CHUNK_AGREEMENT)


def test_composed_batches_hold_bounded_temporaries(sky: SkySH, monkeypatch: pytest.MonkeyPatch) -> None:
    frames = _frames(20_000)
    options = {"bands": 3, "sun": True, "ground_albedo": 0.3}
    size = 20_000 * 9 * 3 * 8
    sky.coefficients(*(a[:10] for a in frames), **options)  # plans built first, untraced
    monkeypatch.setattr(runtime, "COMPOSED_CHUNK", 1 << 30)  # the control: one chunk, the whole batch at once
    whole = _traced_peak(lambda: sky.coefficients(*frames, **options))
    monkeypatch.setattr(runtime, "COMPOSED_CHUNK", 1 << 14)
    chunked = _traced_peak(lambda: sky.coefficients(*frames, **options))
    assert whole >= COMPOSED_WHOLE * size  # measured 3.5x: the sky, the sun, their sum, E_h
    assert chunked <= size + COMPOSED_SLACK * 8 * (1 << 14), f"{chunked:,} bytes for a {size:,}-byte result"


@pytest.mark.parametrize("case", range(6))
def test_a_wrong_buffer_is_refused_naming_out(sky: SkySH, case: int) -> None:
    frames = _frames(5)
    buffer = _bad_buffers((5, 9, 3))[case][1]
    before = np.array(buffer, copy=True)
    with pytest.raises(ValueError, match=r"^out must be a writeable, C-contiguous numpy array of float64 and shape "
                                         r"\(5, 9, 3\)"):
        sky.coefficients(*frames, out=buffer)
    np.testing.assert_array_equal(np.asarray(buffer), before)  # refused before any work: untouched
    with pytest.raises(ValueError, match=r"shape \(9, 3\)"):  # the scalar call's shape
        sky.coefficients(0.5, 3.0, 1.0, out=np.empty((5, 9, 3)))


def test_a_buffer_sharing_memory_with_a_parameter_is_refused(sky: SkySH) -> None:
    buffer = np.zeros((4, 9, 3))
    buffer[..., 0, 0] = 0.5  # the zeniths live in the buffer itself
    zenith = buffer[:, 0, 0]
    with pytest.raises(ValueError, match="out shares memory with an input"):
        sky.coefficients(zenith, 3.0, 0.0, out=buffer)
    sky.coefficients(zenith.copy(), 3.0, 0.0, out=buffer)  # the same call on a copy is taken


def test_an_empty_batch_into_an_empty_buffer(sky: SkySH) -> None:
    buffer = np.empty((0, 49, 3))
    assert sky.coefficients(np.empty(0), 3.0, 0.0, bands=7, out=buffer) is buffer


class TestHosekWilkie:
    """The second model's runtime takes the same ``out`` (copied in after the projection)."""

    @pytest.fixture(scope="class")
    def hw(self) -> object:
        return SkySH.load(model="hosek-wilkie")

    def test_same_values(self, hw: object) -> None:
        ts, t, phi = _frames(3)
        t = t + 1.0
        for options in ({"bands": 7}, {"irradiance": True}, {"albedo": (0.1, 0.2, 0.3)}):
            expected = hw.coefficients(ts, t, phi, **options)  # type: ignore[attr-defined]
            buffer = np.full_like(expected, np.nan)
            assert hw.coefficients(ts, t, phi, **options, out=buffer) is buffer  # type: ignore[attr-defined]
            np.testing.assert_array_equal(buffer, expected)

    def test_refused_before_any_work(self, hw: object) -> None:
        buffer = np.zeros((3, 49, 3))  # shape of 7 bands, asked for 3
        with pytest.raises(ValueError, match=r"^out must be .* shape \(3, 9, 3\)"):
            hw.coefficients(*_frames(3), out=buffer)  # type: ignore[attr-defined]
        assert not buffer.any()
