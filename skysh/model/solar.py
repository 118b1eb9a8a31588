"""
The sun's light: Preetham's attenuated solar disk, and the sun as windowed SH
=============================================================================

The direct sun that goes with the Preetham sky (Preetham, Shirley and Smits
1999, appendix): the extraterrestrial spectral radiance of the solar disk,
attenuated along the relative optical air mass by Rayleigh scattering, aerosols
(Angstrom's law with the turbidity), ozone, uniformly mixed gases and water
vapour, then integrated against the CIE 1931 observer of colour-science.

-   :func:`relative_optical_mass`: Kasten's (1966) air mass m(theta_s).
-   :func:`angstrom_beta`: the aerosol coefficient beta(T) of the model.
-   :func:`transmittance`: spectral transmittance of the direct beam.
-   :func:`spectral_radiance`: spectral radiance of the disk, W m^-2 sr^-1 nm^-1.
-   :func:`tristimulus`, :func:`luminance`: CIE XYZ (cd/m^2) and Y of the disk.
-   :func:`direct_normal_illuminance`: the sun's illuminance at normal incidence, lux.
-   :func:`illuminance_xyz`, :func:`illuminance_rgb`: the same as XYZ and as linear
    RGB of any colour-science colourspace (the sky's colour path, so sky and sun
    share one colour space by construction).
-   :func:`extraterrestrial_xyz`: the illuminance above the atmosphere (no attenuation).
-   :func:`sun_direction`: the unit vector towards the sun.
-   :func:`sun_window`, :data:`SUN_WINDOWS`, :data:`SEED_PUNCTUAL_WINDOW`,
    :func:`derive_sun_window`, :func:`delta_irradiance_error`: per-band windows
    for the sun as a delta light in SH.
-   :func:`sun_sh`: a directional light (the sun) as windowed SH radiance.

Model (Preetham et al. 1999, appendix; Iqbal 1983 for each factor)
-------------------------------------------------------------------
With lambda in micrometres in the power laws, m the relative optical mass and
beta = 0.04608365822050 T - 0.04586025928522 (T the turbidity)::

    L(lambda) = S0(lambda) tau_R tau_a tau_o tau_g tau_wa
    tau_R  = exp(-m 0.008735 lambda^-4.08)                            Rayleigh
    tau_a  = exp(-m beta lambda^-alpha),  alpha = 1.3                  aerosols
    tau_o  = exp(-m k_o l),               l = 0.35 cm                  ozone
    tau_g  = exp(-1.41 k_g m / (1 + 118.93 k_g m)^0.45)                mixed gases
    tau_wa = exp(-0.2385 k_wa w m / (1 + 20.07 k_wa w m)^0.45), w = 2 cm  water vapour
    m      = 1 / (cos theta_s + 0.15 (93.885 - theta_s[deg])^-1.253)  (Kasten 1966)

The paper prints the Rayleigh and aerosol terms with m inside the exponent of
lambda; the authors' program (Smits' ``RiSunConstants.C``), every renderer
listed below and Beer-Lambert's law multiply by m, as here (A. Jaffer's SLIB
``daylight.scm`` records the same disagreement). The beta line is printed with
14 digits by all copies; 0.04608 T - 0.04586 is its rounding.

Tables and their sources
------------------------
Transcribed as numbers (not code) and checked digit for digit against two
public copies each:

-   :data:`SOLAR_RADIANCE` (380-750 nm, 10 nm): mitsuba-renderer/mitsuba
    ``src/emitters/sunsky/sunmodel.h`` (``solAmplitudes``, "watts / (m^2 * nm *
    sr)") and LuxCoreRender/LuxCore ``include/luxrays/utils/sdl/data/sun_spect.h``
    (``sun_solAmplitudes``, "W.m-2.sr-1.nm-1"); the same digits are in SLIB's
    ``daylight.scm``. The authors' own program carries a 4-digit rounding of it
    in units 100 times smaller (LuxRender/Lux ``lights/data/sun_spect.h``),
    checked by ``tests/model/test_solar.py`` too, as is its origin (see Solid angle).
-   :data:`OZONE_ABSORPTION` (Iqbal 1983, p. 127), :data:`MIXED_GAS_ABSORPTION`
    and :data:`WATER_VAPOUR_ABSORPTION` (p. 130): the same three copies above,
    identical to the last digit.
-   Kasten's air mass: also pvlib/pvlib-python ``pvlib/atmosphere.py``
    (``kasten1966``).

Every table is linearly interpolated in wavelength and zero outside its
wavelengths (as in the renderers); the disk's spectrum is defined on
380-750 nm only (the radiance table's range). Colour integrals use the 1 nm
grid :data:`WAVELENGTHS` with trapezoid weights against colour-science's CIE
1931 2 degree observer and K_m = 683 lm/W; the part of the CIE functions beyond
the range is left out (``tools/sun_study.py`` prints its size).

Solid angle
-----------
The disk is uniform (no limb darkening) with angular radius
:data:`SUN_ANGULAR_RADIUS` = 4.64e-3 rad (0.26585 deg) and solid angle
``2 pi (1 - cos r)`` = 6.7637e-5 sr: the solid angle that turns Thekaekara's
irradiance into the radiance table (``tests/model/test_solar.py`` checks the table
against his irradiance over this solid angle to the rounding of both). With
it the direct normal illuminance is the extraterrestrial irradiance times the
transmittance, whatever disk size a renderer draws (the true mean radius is
close to it). Illuminances are radiance x solid angle.

References
----------
-   Preetham, A. J., Shirley, P., Smits, B. (1999). A Practical Analytic Model
    for Daylight. SIGGRAPH 1999, appendix.
-   Iqbal, M. (1983). An Introduction to Solar Radiation. Academic Press
    (tables of k_o, k_g, k_wa; transmittance formulas after Leckner 1978).
-   Kasten, F. (1966). A new table and approximation formula for the relative
    optical air mass. Arch. Meteorol. Geophys. Bioklimatol. B 14.
-   Thekaekara, M. P. (1973). Solar energy outside the earth's atmosphere.
    Solar Energy 14, 109.
-   Sloan, P.-P. (2017). Deringing Spherical Harmonics (seed 000): section 3
    (the punctual-light window 0.92 / 0.73) and eq. (6) (the sinc^4 window).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import domain
from skysh.checks import as_float_array, check_bands, check_choice, check_cutoff, check_dirs, check_range, read_only
from skysh.domain import SKY
from skysh.model.preetham import import_colour, rgb_from_xyz_matrix
from skysh.sh import basis as sh

__all__ = ["KASTEN_COEFFICIENTS", "SUN_ANGULAR_RADIUS", "SUN_WINDOWS", "luminance", "illuminance_xyz",
    "illuminance_rgb", "sun_direction", "sun_window", "sun_sh"]

# --------------------------------------------------------------------------- #
# Domain
# --------------------------------------------------------------------------- #
SUN_ZENITH_RANGE: tuple[float, float] = SKY.x.interval
"""Sun zenith angles accepted, radians: [0, pi/2] (the sky's fitted domain)."""

TURBIDITY_RANGE: tuple[float, float] = SKY.y.interval
"""Turbidities accepted: [2.5, 6] (the sky's fitted domain, ``skysh.domain.SKY``)."""

# --------------------------------------------------------------------------- #
# Tables (Preetham et al. 1999 appendix, after Iqbal 1983; sources in the module docstring)
# --------------------------------------------------------------------------- #
SOLAR_WAVELENGTHS: NDArray[np.float64] = np.arange(380.0, 751.0, 10.0)
"""Wavelengths of :data:`SOLAR_RADIANCE`, nm: 380, 390, ..., 750 (38 values)."""

SOLAR_RADIANCE: NDArray[np.float64] = np.array(
    [
        16559.0, 16233.7, 21127.5, 25888.2, 25829.1, 24232.3, 26760.5, 29658.3, 30545.4, 30057.5,
        30663.7, 28830.4, 28712.1, 27825.0, 27100.6, 27233.6, 26361.3, 25503.8, 25060.2, 25311.6,
        25355.9, 25134.2, 24631.5, 24173.2, 23685.3, 23212.1, 22827.7, 22339.8, 21970.2, 21526.7,
        21097.9, 20728.3, 20240.4, 19870.8, 19427.2, 19072.4, 18628.9, 18259.2,
    ]
)
"""Extraterrestrial spectral radiance of the solar disk at :data:`SOLAR_WAVELENGTHS`, W m^-2 sr^-1 nm^-1."""

OZONE_WAVELENGTHS: NDArray[np.float64] = np.array(
    [
        300, 305, 310, 315, 320, 325, 330, 335, 340, 345, 350, 355,
        445, 450, 455, 460, 465, 470, 475, 480, 485, 490, 495,
        500, 505, 510, 515, 520, 525, 530, 535, 540, 545, 550, 555, 560, 565, 570, 575, 580, 585, 590, 595,
        600, 605, 610, 620, 630, 640, 650, 660, 670, 680, 690,
        700, 710, 720, 730, 740, 750, 760, 770, 780, 790,
    ],
    dtype=np.float64,
)
"""Wavelengths of :data:`OZONE_ABSORPTION`, nm (64 values, irregular; Iqbal 1983, p. 127)."""

OZONE_ABSORPTION: NDArray[np.float64] = np.array(
    [
        10.0, 4.8, 2.7, 1.35, 0.8, 0.380, 0.160, 0.075, 0.04, 0.019, 0.007, 0.0,
        0.003, 0.003, 0.004, 0.006, 0.008, 0.009, 0.012, 0.014, 0.017, 0.021, 0.025,
        0.03, 0.035, 0.04, 0.045, 0.048, 0.057, 0.063, 0.07, 0.075, 0.08, 0.085, 0.095, 0.103, 0.110, 0.12,
        0.122, 0.12, 0.118, 0.115, 0.12,
        0.125, 0.130, 0.12, 0.105, 0.09, 0.079, 0.067, 0.057, 0.048, 0.036, 0.028,
        0.023, 0.018, 0.014, 0.011, 0.010, 0.009, 0.007, 0.004, 0.0, 0.0,
    ]
)
"""Ozone absorption coefficient k_o at :data:`OZONE_WAVELENGTHS`, cm^-1 (per cm of ozone at NTP)."""

MIXED_GAS_WAVELENGTHS: NDArray[np.float64] = np.array([759.0, 760.0, 770.0, 771.0])
"""Wavelengths of :data:`MIXED_GAS_ABSORPTION`, nm (Iqbal 1983, p. 130): the oxygen A band only."""

MIXED_GAS_ABSORPTION: NDArray[np.float64] = np.array([0.0, 3.0, 0.210, 0.0])
"""Absorption coefficient k_g of the uniformly mixed gases (cm^-1 as labelled by the sources).

Non-zero only at 759-771 nm, outside the disk's 380-750 nm: kept for fidelity
to the model; it has no effect on any output of this module."""

WATER_VAPOUR_WAVELENGTHS: NDArray[np.float64] = np.array(
    [689.0, 690.0, 700.0, 710.0, 720.0, 730.0, 740.0, 750.0, 760.0, 770.0, 780.0, 790.0, 800.0]
)
"""Wavelengths of :data:`WATER_VAPOUR_ABSORPTION`, nm (Iqbal 1983, p. 130)."""

WATER_VAPOUR_ABSORPTION: NDArray[np.float64] = np.array(
    [0.0, 0.160e-1, 0.240e-1, 0.125e-1, 0.100e1, 0.870, 0.610e-1, 0.100e-2, 0.100e-4, 0.100e-4, 0.600e-3,
     0.175e-1, 0.360e-1]
)
"""Water vapour absorption coefficient k_wa at :data:`WATER_VAPOUR_WAVELENGTHS`, cm^-1."""

RAYLEIGH_COEFFICIENT: float = 0.008735
"""Rayleigh optical depth per unit air mass at 1 um: tau_R = exp(-m 0.008735 lambda[um]^-4.08)."""

RAYLEIGH_EXPONENT: float = 4.08
"""Wavelength exponent of the Rayleigh optical depth."""

ANGSTROM_ALPHA: float = 1.3
"""Angstrom's wavelength exponent alpha of the aerosol optical depth (ratio of small to large particles)."""

ANGSTROM_BETA_SLOPE: float = 0.04608365822050
"""d beta / d T: beta = 0.04608365822050 T - 0.04586025928522 (Preetham 1999 appendix; all copies)."""

ANGSTROM_BETA_INTERCEPT: float = -0.04586025928522
"""beta at T = 0 (see :data:`ANGSTROM_BETA_SLOPE`)."""

OZONE_THICKNESS: float = 0.35
"""Amount of ozone l, cm at NTP."""

PRECIPITABLE_WATER: float = 2.0
"""Precipitable water vapour w, cm (Iqbal's standard)."""

KASTEN_COEFFICIENTS: tuple[float, float, float] = domain.KASTEN_COEFFICIENTS
"""(a, b, c) of Kasten's air mass m = 1 / (cos theta + a (b - theta[deg])^-c) (:data:`skysh.domain.KASTEN_COEFFICIENTS`)."""

_MIXED_GAS: tuple[float, float, float] = (1.41, 118.93, 0.45)
"""(a, b, c) of tau_g = exp(-a k_g m / (1 + b k_g m)^c)."""

_WATER_VAPOUR: tuple[float, float, float] = (0.2385, 20.07, 0.45)
"""(a, b, c) of tau_wa = exp(-a k_wa w m / (1 + b k_wa w m)^c)."""

SUN_ANGULAR_RADIUS: float = 4.64e-3
"""Angular radius of the solar disk, radians (0.26585 deg): the one implied by :data:`SOLAR_RADIANCE`."""

SUN_SOLID_ANGLE: float = 2.0 * math.pi * (1.0 - math.cos(SUN_ANGULAR_RADIUS))
"""Solid angle of the disk, sr: 2 pi (1 - cos r) = 6.7637e-5. Illuminance = radiance x this."""

WAVELENGTHS: NDArray[np.float64] = np.arange(380.0, 751.0, 1.0)
"""The 1 nm grid of the colour integrals, nm: 380, 381, ..., 750 (371 values)."""

LUMINOUS_EFFICACY: float = 683.0
"""K_m, lm/W: the maximum luminous efficacy (SI definition of the candela; colour's CONSTANT_K_M)."""

CMFS_NAME: str = "CIE 1931 2 Degree Standard Observer"
"""The colour-science colour matching functions used (its ybar is the CIE 1924 V(lambda))."""

read_only(SOLAR_WAVELENGTHS, SOLAR_RADIANCE, OZONE_WAVELENGTHS, OZONE_ABSORPTION, MIXED_GAS_WAVELENGTHS,
          MIXED_GAS_ABSORPTION, WATER_VAPOUR_WAVELENGTHS, WATER_VAPOUR_ABSORPTION, WAVELENGTHS)


def _depths(wavelengths: NDArray[np.float64]) -> NDArray[np.float64]:
    """(6, W) per-wavelength factors: Rayleigh, aerosol shape, ozone, k_g, k_wa w, solar radiance."""
    um = wavelengths / 1000.0
    out = np.stack(
        [
            RAYLEIGH_COEFFICIENT * um**-RAYLEIGH_EXPONENT,
            um**-ANGSTROM_ALPHA,
            OZONE_THICKNESS * np.interp(wavelengths, OZONE_WAVELENGTHS, OZONE_ABSORPTION, left=0.0, right=0.0),
            np.interp(wavelengths, MIXED_GAS_WAVELENGTHS, MIXED_GAS_ABSORPTION, left=0.0, right=0.0),
            PRECIPITABLE_WATER
            * np.interp(wavelengths, WATER_VAPOUR_WAVELENGTHS, WATER_VAPOUR_ABSORPTION, left=0.0, right=0.0),
            np.interp(wavelengths, SOLAR_WAVELENGTHS, SOLAR_RADIANCE),
        ]
    )
    out.flags.writeable = False
    return out


_GRID: NDArray[np.float64] = _depths(WAVELENGTHS)
"""The per-wavelength factors on :data:`WAVELENGTHS`, computed once."""


# --------------------------------------------------------------------------- #
# The attenuated sun
# --------------------------------------------------------------------------- #
def _check_sun(sun_zenith: ArrayLike, turbidity: ArrayLike) -> tuple[NDArray, NDArray]:
    ts = check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    return ts, check_range(turbidity, "turbidity", *TURBIDITY_RANGE)


def relative_optical_mass(sun_zenith: ArrayLike) -> NDArray[np.float64]:
    """
    Kasten's (1966) relative optical air mass ``1 / (cos theta + 0.15 (93.885 - theta[deg])^-1.253)``.

    ``sun_zenith`` in radians, [0, pi/2], any shape. Dimensionless: 0.9995 at the
    zenith, 36.51 on the horizon (``tools/sun_study.py --table``).
    """
    return _air_mass(check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad"))


def _air_mass(ts: NDArray) -> NDArray:
    a, b, c = KASTEN_COEFFICIENTS
    return 1.0 / (np.cos(ts) + a * (b - np.degrees(ts)) ** -c)


def angstrom_beta(turbidity: ArrayLike) -> NDArray[np.float64]:
    """Angstrom's aerosol coefficient beta = 0.04608365822050 T - 0.04586025928522, turbidity T in [2.5, 6]."""
    t = check_range(turbidity, "turbidity", *TURBIDITY_RANGE)
    return ANGSTROM_BETA_SLOPE * t + ANGSTROM_BETA_INTERCEPT


def _transmittance(ts: NDArray, t: NDArray, grid: NDArray) -> NDArray:
    """(..., W) transmittance for checked, broadcast-ready ts, t and a factor grid (6, W)."""
    m = _air_mass(ts)[..., None]
    beta = (ANGSTROM_BETA_SLOPE * t + ANGSTROM_BETA_INTERCEPT)[..., None]
    rayleigh, aerosol, ozone, k_g, k_ww = grid[:5]
    depth = m * (rayleigh + beta * aerosol + ozone)
    for k, (a, b, c) in ((k_g, _MIXED_GAS), (k_ww, _WATER_VAPOUR)):  # mixed gases, water vapour
        depth = depth + a * k * m / (1.0 + b * k * m) ** c
    return np.exp(-depth)


def _grid_for(wavelengths: ArrayLike | None) -> NDArray:
    if wavelengths is None:
        return _GRID
    w = check_range(wavelengths, "wavelengths", float(WAVELENGTHS[0]), float(WAVELENGTHS[-1]), unit="nm")
    if w.ndim != 1:
        raise ValueError(f"wavelengths must be a 1-D array of nm in [380, 750], got shape {w.shape}")
    return _depths(w)


def transmittance(sun_zenith: ArrayLike, turbidity: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
    """Spectral transmittance tau_R tau_a tau_o tau_g tau_wa of the direct beam, (..., W) in (0, 1].

    Arguments as in :func:`spectral_radiance`.
    """
    ts, t = _check_sun(sun_zenith, turbidity)
    return _transmittance(ts, t, _grid_for(wavelengths))


def spectral_radiance(sun_zenith: ArrayLike, turbidity: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
    """
    Spectral radiance of the solar disk seen through the atmosphere.

    Parameters
    ----------
    sun_zenith, turbidity
        Radians in [0, pi/2] and turbidity in [2.5, 6], broadcasting to (...,).
    wavelengths
        1-D wavelengths in nm within [380, 750]; default :data:`WAVELENGTHS` (1 nm).

    Returns
    -------
    ndarray
        (..., W), W m^-2 sr^-1 nm^-1, uniform over the disk.
    """
    ts, t = _check_sun(sun_zenith, turbidity)
    grid = _grid_for(wavelengths)
    return grid[5] * _transmittance(ts, t, grid)


@lru_cache(maxsize=1)
def _cmf_weights() -> NDArray[np.float64]:
    """(W, 3): K_m x trapezoid weight (1 nm) x the CIE 1931 xbar, ybar, zbar at :data:`WAVELENGTHS`."""
    cmfs = import_colour().MSDS_CMFS[CMFS_NAME]  # colour-science is heavy: imported on the first colour integral
    weights = LUMINOUS_EFFICACY * np.array(cmfs[WAVELENGTHS], dtype=np.float64)  # tabulated at 1 nm: no interpolation
    weights[[0, -1]] *= 0.5  # the trapezoid rule's end weights
    weights.flags.writeable = False
    return weights


def tristimulus(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """
    CIE 1931 XYZ of the disk's radiance, (..., 3) in cd/m^2 (Y is the luminance), all positive.

    ``X = K_m sum_lambda w_lambda L(lambda) xbar(lambda)`` over :data:`WAVELENGTHS`
    (trapezoid weights, 1 nm), likewise Y and Z; arguments as in :func:`spectral_radiance`.
    """
    return spectral_radiance(sun_zenith, turbidity) @ _cmf_weights()


def luminance(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """Luminance of the solar disk, cd/m^2 (about 1.4e9 at the zenith, T = 2.5); shape of the broadcast inputs."""
    return tristimulus(sun_zenith, turbidity)[..., 1]


def illuminance_xyz(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """CIE XYZ of the sun's illuminance at normal incidence, lux: :func:`tristimulus` x :data:`SUN_SOLID_ANGLE`."""
    return tristimulus(sun_zenith, turbidity) * SUN_SOLID_ANGLE


def direct_normal_illuminance(sun_zenith: ArrayLike, turbidity: ArrayLike) -> NDArray[np.float64]:
    """
    The sun's illuminance on a surface facing it, lux (luminance x solid angle).

    About 9.6e4 lux at the zenith for T = 2.5, falling to about 11 lux (T = 2.5)
    and 2.5e-4 lux (T = 6) on the horizon (``tools/sun_study.py --table``).
    """
    return illuminance_xyz(sun_zenith, turbidity)[..., 1]


def illuminance_rgb(sun_zenith: ArrayLike, turbidity: ArrayLike, colourspace: str = "sRGB") -> NDArray[np.float64]:
    """
    Linear RGB of the sun's illuminance at normal incidence, (..., 3) in lux per channel.

    XYZ -> RGB by the colour-science colourspace's own matrix, no chromatic
    adaptation (:func:`skysh.model.preetham.rgb_from_xyz_matrix`, the sky's route), so
    R = G = B = Y for a white of its whitepoint. Near the horizon the sun leaves
    the sRGB gamut: blue (at T = 6 also green) turns slightly negative.
    """
    matrix = rgb_from_xyz_matrix(colourspace)
    return illuminance_xyz(sun_zenith, turbidity) @ matrix.T


def extraterrestrial_xyz() -> NDArray[np.float64]:
    """CIE XYZ of the unattenuated sun's illuminance (above the atmosphere), lux: about (1.24, 1.27, 1.39) x 1e5."""
    return (_GRID[5] @ _cmf_weights()) * SUN_SOLID_ANGLE


def sun_direction(sun_zenith: ArrayLike, sun_azimuth: ArrayLike) -> NDArray[np.float64]:
    """Unit vector towards the sun, (..., 3): ``(sin ts cos phi, sin ts sin phi, cos ts)``.

    ``sun_zenith`` in radians in [0, pi/2], ``sun_azimuth`` any finite radians (from +X towards +Y).
    """
    ts = check_range(sun_zenith, "sun_zenith", *SUN_ZENITH_RANGE, unit="rad")
    ts, phi = np.broadcast_arrays(ts, as_float_array(sun_azimuth, "sun_azimuth"))
    s = np.sin(ts)
    return np.stack([s * np.cos(phi), s * np.sin(phi), np.cos(ts)], axis=-1)


# --------------------------------------------------------------------------- #
# The sun in SH: a windowed delta light
# --------------------------------------------------------------------------- #
MAX_WINDOW_BANDS: int = 7
"""Largest band count with a tabulated sun window (l <= 6, as the deringing)."""

SEED_PUNCTUAL_WINDOW: tuple[float, float, float] = (1.0, 0.92, 0.73)
"""The seed's hand-tuned factors for direct lights, bands 0..2 (Sloan 2017, section 3).

Not non-negative on its own: a delta windowed by it has an irradiance dipping
to -7.46 % of its mean behind the light (0.92 > sqrt(3)/2 forbids any band-2
factor from fixing it); the seed adds it to sky light whose irradiance should
cover the dip. The Preetham sky does not always: with the 3-band sky deringed
and a black ground, sky + sun dips to -1.6 % of the sun's illuminance for sun
zeniths of 30-75 deg (``tools/sun_study.py --cover``). Equal to
``skysh.post.dering.PUNCTUAL_WINDOW``."""

SUN_WINDOW_MARGIN: float = 1e-5
"""The derived windows keep a delta's irradiance >= this fraction of its mean (E/4):
a margin far above rounding (1e-15) and above the effect of rounding the
tabulated (cutoff, attenuation) to the digits of :data:`SUN_WINDOW_PARAMETERS`."""

SUN_WINDOW_PARAMETERS: tuple[tuple[float, float], ...] = (
    (math.inf, 1.0),
    (math.inf, 0.499994),
    (16.6856, 0.878422),
    (16.6856, 0.878422),
    (17.8964, 0.932128),
    (17.8964, 0.932128),
    (20.8528, 0.953729),
)
"""(cutoff w, linear attenuation a) of the sun's window for 1..7 bands, from :func:`derive_sun_window`.

The window is the seed's eq. (6), sinc^4(pi l / w), with band 1 further
multiplied by a (the seed's "extra attenuation of the linear band"); (w, a)
minimise the L2 error of the delta's irradiance over all normals
(:func:`delta_irradiance_error`) subject to that irradiance staying >=
:data:`SUN_WINDOW_MARGIN` times its mean, proved by its exact minimum (a
Legendre series in cos(angle): endpoints and real roots of its derivative).
For a given w the best a is the largest feasible one (the error falls as
a s1 -> 1), found by bisection; w is scanned (1.5 .. 40 by 0.25, and inf) and
refined by golden section within one scan step. ``a`` is rounded down and w to
4 decimals; the margin covers the rounding. Two bands allow s1 <= 1/2 whatever
w (ties go to w = inf). Band counts N and N + 1 share bands 0..N-1 when
A_N = 0 (N = 3, 5). ``tools/sun_study.py --windows --derive`` re-derives it."""

SUN_WINDOW_KINDS: tuple[str, ...] = ("nonnegative", "seed")
"""Window kinds of :func:`sun_window`."""


def sun_window_family(cutoff: float, attenuation: float, bands: int) -> NDArray[np.float64]:
    """
    The seed's eq. (6) window with an extra linear attenuation: ``s_l = sinc^4(pi l / w)``, ``s_1 *= a``.

    Parameters
    ----------
    cutoff
        w > 0 (``inf`` for no sinc^4 windowing); factors are 0 for l >= w.
    attenuation
        a in [0, 1], the extra factor of band 1.
    bands
        Number of bands N in [1, 64].

    Returns
    -------
    ndarray
        (N,) per-band factors, ``s_0 = 1``.
    """
    bands = check_bands(bands, high=sh.MAX_BANDS)
    w = check_cutoff(cutoff)
    a = float(check_range(attenuation, "attenuation", 0.0, 1.0))
    x = np.arange(bands) / w
    s = np.where(x < 1.0, np.sinc(x) ** 4, 0.0)
    s[1:2] *= a  # band 1, if there is one
    return s


SUN_WINDOWS: tuple[NDArray[np.float64], ...] = tuple(
    sun_window_family(w, a, n) for n, (w, a) in enumerate(SUN_WINDOW_PARAMETERS, start=1)
)
"""Per-band factors of the non-negative sun window for 1..7 bands: ``SUN_WINDOWS[N - 1]`` has N entries."""

_WINDOW_KERNEL: NDArray[np.float64] = sh.cosine_lobe(MAX_WINDOW_BANDS)
"""Clamped-cosine factors A_0 .. A_6."""
read_only(*SUN_WINDOWS, _WINDOW_KERNEL)


def sun_window(bands: int = 3, kind: str = "nonnegative") -> NDArray[np.float64]:
    """
    Per-band factors applied to the sun's SH (a delta light).

    Parameters
    ----------
    bands
        Number of bands N in [1, 7].
    kind
        ``"nonnegative"``: :data:`SUN_WINDOWS` (the delta's irradiance is
        non-negative at every band count, with the least L2 error in the seed's
        eq. (6) family; at 3 bands also a smaller L2 error than the seed's
        window, 0.1374 against 0.1398). ``"seed"``: the seed's hand-tuned
        (1, 0.92, 0.73) for 3 bands (the light's irradiance alone dips to
        -7.46 % of its mean, and the Preetham sky does not always cover it, see
        :data:`SEED_PUNCTUAL_WINDOW`), and the non-negative window at other
        band counts, for which the seed gives none.

    Returns
    -------
    ndarray
        (N,), a new array.
    """
    bands = check_bands(bands, high=MAX_WINDOW_BANDS)
    check_choice(kind, "kind", SUN_WINDOW_KINDS)
    if kind == "seed" and bands == 3:
        return np.array(SEED_PUNCTUAL_WINDOW)
    return SUN_WINDOWS[bands - 1].copy()


def _irradiance_series(window: ArrayLike) -> NDArray[np.float64]:
    """Legendre coefficients (in t = cos angle) of a unit delta's windowed irradiance, sr^-1."""
    s = as_float_array(window, "window")
    if s.ndim != 1 or not 1 <= s.shape[0] <= MAX_WINDOW_BANDS:
        raise ValueError(f"window must have shape (N,) with 1 <= N <= {MAX_WINDOW_BANDS}, got {s.shape}")
    ell = np.arange(s.shape[0])
    return _WINDOW_KERNEL[: s.shape[0]] * s * (2 * ell + 1) / (4.0 * math.pi)


def delta_irradiance_minimum(window: ArrayLike) -> float:
    """Exact minimum over all normals of a unit delta light's irradiance windowed by ``window``
    (per-band factors, shape (N,), 1 <= N <= 7), sr^-1; the unwindowed mean is 1/4.

    The irradiance is a Legendre series in t = cos(angle): its exact minimum over [-1, 1] is at an
    endpoint or a real root of its derivative."""
    from numpy.polynomial import legendre

    series = _irradiance_series(window)
    t = [-1.0, 1.0]
    if series.shape[0] > 2:
        roots = np.atleast_1d(legendre.legroots(legendre.legder(series)))
        t += [float(r.real) for r in roots if abs(r.imag) < 1e-9 and -1.0 <= r.real <= 1.0]
    return float(np.min(legendre.legval(np.array(t), series)))


def delta_irradiance_error(window: ArrayLike) -> float:
    """
    Relative L2 error of a windowed delta light's irradiance over all normals.

    Parameters
    ----------
    window
        Per-band factors s_0 .. s_{N-1}, N in [1, 7].

    Returns
    -------
    float
        ``||E_w - E|| / ||E||`` over the sphere of normals, E(n) = max(0, n.s) the
        exact irradiance of a unit delta and E_w its N-band windowed SH. With
        ``a_l = A_l (2 l + 1) / (4 pi)`` (Legendre coefficients of E):
        ``||E_w - E||^2 = sum_{l<N} (1 - s_l)^2 A_l^2 (2l+1) / (4 pi) + tail``,
        ``tail = ||E||^2 - sum_{l<N} A_l^2 (2l+1) / (4 pi)``, ``||E||^2 = 2 pi / 3``.
    """
    n = _irradiance_series(window).shape[0]  # validates the window
    s = np.asarray(window, dtype=np.float64)
    weight = _WINDOW_KERNEL[:n] ** 2 * (2 * np.arange(n) + 1) / (4.0 * math.pi)
    norm2 = 2.0 * math.pi / 3.0
    err2 = float(np.sum((1.0 - s) ** 2 * weight)) + norm2 - float(np.sum(weight))
    return math.sqrt(max(err2, 0.0) / norm2)


def _largest_attenuation(cutoff: float, bands: int) -> float | None:
    """Largest a in [0, 1] keeping the delta's irradiance >= margin x mean; None if even a = 0 fails."""
    mean = 0.25  # A_0 s_0 / (4 pi) = pi / (4 pi): the irradiance's mean for a unit delta

    def ok(a: float) -> bool:
        return delta_irradiance_minimum(sun_window_family(cutoff, a, bands)) >= SUN_WINDOW_MARGIN * mean

    if ok(1.0):
        return 1.0
    if not ok(0.0):
        return None
    lo, hi = 0.0, 1.0
    for _ in range(60):  # the feasible set in a is an interval (the minimum is concave in a)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def derive_sun_window(bands: int, scan: tuple[float, float, float] = (1.5, 40.0, 0.25)) -> tuple[float, float, float]:
    """
    Derive the non-negative sun window of :data:`SUN_WINDOW_PARAMETERS` (offline; seconds).

    Parameters
    ----------
    bands
        Number of bands N in [1, 7].
    scan
        (start, stop, step) of the cutoff scan before the golden-section refinement.

    Returns
    -------
    cutoff, attenuation, error
        The family's (w, a) of least :func:`delta_irradiance_error` under the
        non-negativity constraint, and that error.
    """
    bands = check_bands(bands, high=MAX_WINDOW_BANDS)
    if bands == 1:
        return math.inf, 1.0, delta_irradiance_error([1.0])

    def cost(w: float) -> tuple[float, float]:
        a = _largest_attenuation(w, bands)
        if a is None:
            return math.inf, 0.0
        return delta_irradiance_error(sun_window_family(w, a, bands)), a

    grid = [math.inf] + list(np.arange(*scan)[::-1])
    costs = [cost(float(w))[0] for w in grid]
    best = min(costs)
    k = next(i for i, c in enumerate(costs) if c <= best * (1.0 + 1e-12))  # ties: the largest w
    w_best = float(grid[k])
    if math.isfinite(w_best):
        lo, hi = w_best - scan[2], w_best + scan[2]
        golden = (math.sqrt(5.0) - 1.0) / 2.0
        for _ in range(48):
            x1, x2 = hi - golden * (hi - lo), lo + golden * (hi - lo)
            lo, hi = (lo, x2) if cost(x1)[0] <= cost(x2)[0] else (x1, hi)
        w_best = 0.5 * (lo + hi)
    err, a = cost(w_best)
    return w_best, a, err


def sun_sh(direction: ArrayLike, illuminance: ArrayLike, bands: int = 3,
           window: str | ArrayLike = "nonnegative") -> NDArray[np.float64]:
    """
    The sun (a directional light) as windowed SH radiance, to add to sky SH.

    Parameters
    ----------
    direction
        Unit vector towards the sun, (3,) or (..., 3), Z up.
    illuminance
        The light's illuminance at normal incidence per channel (the delta's
        integral over the sphere), (C,) or broadcasting (..., C); lux for
        :func:`illuminance_rgb`.
    bands
        Number of bands N in [1, 7] (any N up to 64 with an explicit window).
    window
        A kind of :func:`sun_window` (``"nonnegative"`` or ``"seed"``), or
        explicit per-band factors (>= N of them).

    Returns
    -------
    ndarray
        (..., N * N, C): ``c_lm = window[l] * Y_lm(direction) * illuminance``,
        radiance SH in the sky's units (cd/m^2 x sr for lux): the projection of
        ``illuminance x delta(w - direction)``, windowed.
    """
    d = check_dirs(direction, "direction")
    e = as_float_array(illuminance, "illuminance")
    if e.ndim == 0:
        raise ValueError(f"illuminance must have shape (C,) or (..., C), got {e.shape}")
    if isinstance(window, str):
        factors = sun_window(bands, window)
    else:
        bands = check_bands(bands, high=sh.MAX_BANDS)
        factors = as_float_array(window, "window")
        if factors.ndim != 1 or factors.shape[0] < bands:
            raise ValueError(f"window must have shape (>= {bands},), got {factors.shape}")
    y = sh.basis(d, bands) * factors[sh.band_of_index(bands)]
    return y[..., :, None] * e[..., None, :]
