"""
Tests of :class:`skysh.hosek_runtime.HosekWilkieSH` (``SkySH.load(model="hosek-wilkie")``, issue 27)
==================================================================================================

References are independent of the runtime's own steps: the converged projection
:func:`skysh.model.hosek.sky_sh` (a different rule), the Gibbs factors and the clamped-cosine
factors typed here in closed form, the irradiance evaluated at many directions from the basis
(:func:`skysh.sh.basis.basis`), and the RGB dataset's channel independence (a channel at its own
albedo is that channel of a grey sky at that albedo). The rule's accuracy over the issue's point
sets is ``tests/model/test_hosek_frame.py``'s.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skysh import SkySH
from skysh.hosek_runtime import BANDS, HosekWilkieSH
from skysh.model import hosek
from skysh.sh import basis as sh

SKY = SkySH.load(model="hosek-wilkie")

ACCURACY_OF_DC: float = 1e-4
"""The default rule against the converged reference, per coefficient, as a fraction of the DC term's largest
channel: the rule's worst E_mean at 7 bands is 3.3e-5 of L_min (``tests/model/test_hosek_frame.py``), and L_min is
below the mean radiance the DC holds; 1e-4 leaves room for either without hiding a wrong step (a missing Gibbs
filter moves a zonal coefficient by 17 % or more, a wrong lobe by a factor)."""

ROUNDING: float = 1e-13
"""The same arithmetic grouped differently (a batch against scalar calls, a per-channel albedo against three grey
calls, the parameters mixed before or after the Bezier sum): relative to the DC term, a few hundred roundings."""

NEGATIVE_FLOOR: float = -1e-9
"""Deringed irradiance at sampled directions, relative to its DC term: the window is searched to the exact minimum
less its 2.3e-13 rounding allowance (skysh.post.dering); sampled directions only see values above that minimum."""

SUNS = [(0.2, 2.0, 0.1, 0.0), (0.9, 5.0, 0.5, 2.0), (1.45, 9.0, 0.9, -4.0)]
"""(sun zenith, turbidity, albedo, azimuth): a high, a mid and a low sun across the dataset."""


def _sinc_filter(bands: int) -> np.ndarray:
    """sin(pi l / N) / (pi l / N), l = 0 is 1 (Habel eq. 5), typed here."""
    return np.array([1.0] + [math.sin(math.pi * l / bands) / (math.pi * l / bands) for l in range(1, bands)])


def _lobe(bands: int) -> np.ndarray:
    """Clamped-cosine factors A_l in closed form (Ramamoorthi and Hanrahan 2001), l < 7."""
    closed = [math.pi, 2 * math.pi / 3, math.pi / 4, 0.0, -math.pi / 24, 0.0, math.pi / 64]
    return np.array(closed[:bands])


def _per_index(values: np.ndarray, bands: int) -> np.ndarray:
    return np.array([values[l] for l in range(bands) for _ in range(2 * l + 1)])


def _zonal(bands: int) -> np.ndarray:
    return np.array([l * (l + 1) for l in range(bands)])


def _directions(n: int = 4000) -> np.ndarray:
    """Fibonacci sphere: near-uniform unit vectors."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    r = np.sqrt(1.0 - z * z)
    phi = math.pi * (1.0 + 5.0**0.5) * k
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def test_load_gives_the_hosek_runtime():
    assert isinstance(SKY, HosekWilkieSH) and SKY.model == "hosek-wilkie" and SKY.bands == BANDS == 7


@pytest.mark.parametrize("ts, t, a, phi", SUNS)
def test_radiance_against_the_converged_reference(ts, t, a, phi):
    truth = hosek.sky_sh(ts, t, a, 7, sun_azimuth=phi)
    got = SKY.coefficients(ts, t, phi, bands=7, gibbs=False, albedo=a)
    scale = np.abs(truth[0]).max()
    np.testing.assert_allclose(got, truth, rtol=0, atol=ACCURACY_OF_DC * scale)
    filtered = SKY.coefficients(ts, t, phi, bands=7, albedo=a)  # radiance: the filter by default
    expected = truth.copy()
    expected[_zonal(7)] *= _sinc_filter(7)[:, None]
    np.testing.assert_allclose(filtered, expected, rtol=0, atol=ACCURACY_OF_DC * scale)


@pytest.mark.parametrize("bands", [1, 2, 3, 5, 7])
def test_irradiance_by_intent(bands):
    ts, t, a, phi = SUNS[1]
    radiance = SKY.coefficients(ts, t, phi, bands=bands, gibbs=False, albedo=a)
    plain = SKY.coefficients(ts, t, phi, bands=bands, irradiance=True, dering=False, albedo=a)
    np.testing.assert_allclose(plain, radiance * _per_index(_lobe(bands), bands)[:, None], rtol=0,
                               atol=ROUNDING * np.abs(plain[0]).max())
    default = SKY.coefficients(ts, t, phi, bands=bands, irradiance=True, albedo=a)  # gibbs off, dering on
    explicit = SKY.coefficients(ts, t, phi, bands=bands, irradiance=True, gibbs=False, dering=True, albedo=a)
    np.testing.assert_array_equal(default, explicit)
    values = sh.basis(_directions(), bands) @ default
    assert values.min() >= NEGATIVE_FLOOR * abs(default[0]).max()


def test_low_sun_irradiance_is_deringed():
    """A sun on the horizon rings most: without deringing the 7-band irradiance dips below zero, with it not."""
    raw = SKY.coefficients(math.pi / 2, 10.0, 0.0, bands=7, irradiance=True, dering=False)
    fixed = SKY.coefficients(math.pi / 2, 10.0, 0.0, bands=7, irradiance=True)
    basis = sh.basis(_directions(), 7)
    assert (basis @ raw).min() < 0.0  # the control: the case is a real one
    assert (basis @ fixed).min() >= NEGATIVE_FLOOR * abs(fixed[0]).max()


def test_rgb_albedo_per_channel():
    ts, t, phi = 0.7, 4.0, 1.0
    albedo = (0.1, 0.5, 0.9)
    got = SKY.coefficients(ts, t, phi, bands=7, albedo=albedo)
    for channel, value in enumerate(albedo):
        grey = SKY.coefficients(ts, t, phi, bands=7, albedo=value)[:, channel]
        np.testing.assert_allclose(got[:, channel], grey, rtol=0, atol=ROUNDING * abs(grey[0]))
    same = SKY.coefficients(ts, t, phi, bands=3, albedo=[0.4, 0.4, 0.4])
    np.testing.assert_array_equal(same, SKY.coefficients(ts, t, phi, bands=3, albedo=0.4))


def test_batch_equals_scalar_calls():
    ts = np.array([0.0, 0.5, 1.2, math.pi / 2])
    t = np.array([1.0, 3.0, 7.5, 10.0])
    phi = np.array([0.0, -1.0, 3.0, 100.0])
    batch = SKY.coefficients(ts, t, phi, bands=5, irradiance=True, albedo=0.3)
    for i in range(ts.size):
        one = SKY.coefficients(float(ts[i]), float(t[i]), float(phi[i]), bands=5, irradiance=True, albedo=0.3)
        np.testing.assert_allclose(batch[i], one, rtol=0, atol=ROUNDING * abs(one[0]).max())
    assert SKY.coefficients(np.zeros((2, 3)), 3.0, 0.0).shape == (2, 3, 9, 3)


def test_other_colourspace_is_the_spectral_route():
    got = SKY.coefficients(0.6, 3.0, 0.5, bands=3, colourspace="ACEScg", albedo=0.2)
    truth = hosek.sky_sh(0.6, 3.0, 0.2, 3, sun_azimuth=0.5, colourspace="ACEScg")
    truth[_zonal(3)] *= _sinc_filter(3)[:, None]
    np.testing.assert_allclose(got, truth, rtol=0, atol=ACCURACY_OF_DC * np.abs(truth[0]).max())


@pytest.mark.parametrize("kwargs, name", [
    (dict(sun_zenith=-0.1), "sun_zenith"), (dict(sun_zenith=1.6), "sun_zenith"), (dict(sun_zenith=math.nan), "sun_zenith"),
    (dict(turbidity=0.99), "turbidity"), (dict(turbidity=10.01), "turbidity"), (dict(sun_azimuth=math.inf), "sun_azimuth"),
    (dict(albedo=1.01), "albedo"), (dict(albedo=-0.01), "albedo"), (dict(albedo=(0.1, 0.2)), "albedo"),
    (dict(albedo=(0.1, 0.2, 0.3), colourspace="ACEScg"), "albedo"), (dict(bands=0), "bands"), (dict(bands=8), "bands"),
    (dict(accuracy="best"), "accuracy"),
])
def test_refusals_name_the_parameter(kwargs, name):
    call = dict(sun_zenith=0.5, turbidity=3.0) | kwargs
    with pytest.raises(ValueError, match=name):
        SKY.coefficients(**call)


def test_flags_must_be_bools():
    with pytest.raises(TypeError, match="gibbs"):
        SKY.coefficients(0.5, 3.0, gibbs=1)


def test_load_refuses_a_path_and_an_unknown_model():
    with pytest.raises(ValueError, match="path"):
        SkySH.load("data/preetham_sh.npz", model="hosek-wilkie")
    with pytest.raises(ValueError, match="model"):
        SkySH.load(model="hosek")


@settings(max_examples=25, deadline=None)
@given(st.floats(0.0, math.pi / 2), st.floats(1.0, 10.0), st.floats(-50.0, 50.0), st.floats(0.0, 1.0),
       st.sampled_from([1, 3, 7]), st.booleans())
def test_finite_and_deterministic_over_the_domain(ts, t, phi, a, bands, irradiance):
    first = SKY.coefficients(ts, t, phi, bands=bands, irradiance=irradiance, albedo=a)
    assert np.all(np.isfinite(first))
    np.testing.assert_array_equal(first, SKY.coefficients(ts, t, phi, bands=bands, irradiance=irradiance, albedo=a))
