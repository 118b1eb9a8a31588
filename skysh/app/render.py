"""
Pictures of the sky and its SH lighting, as PNG, without plotting libraries
==========================================================================

-   :func:`render_image`: three latitude-longitude panels side by side, the
    Preetham sky, its SH reconstruction and the SH irradiance, tone-mapped
    with one exposure and labelled; an (H, W, 3) uint8 array. With ``sun``
    and ``ground_albedo`` the scene gains the sun's disk and a Lambertian
    ground (:func:`true_scene`), in all three panels.
-   :func:`true_scene`: the radiance of sky + sun's disk + ground in given
    directions, from the models (not the fit); :func:`true_hosek_sky` the
    Hosek-Wilkie sky's (``render_image`` of ``SkySH.load(model="hosek-wilkie")``).
-   :func:`latlong_dirs`: the view directions of a latitude-longitude panel.
-   :func:`tone_map`: exposure, Reinhard's operator and the sRGB transfer
    function, linear RGB -> 8-bit sRGB.
-   :func:`draw_text`: a built-in 5 x 7 bitmap font (upper case, digits, a few signs).
-   :func:`write_png`: a minimal PNG writer (zlib and struct only).

matplotlib is not needed (nor imported). The true sky comes from
:func:`skysh.model.preetham.radiance`, so rendering imports colour-science.

Panel layout: column x covers azimuth phi from -180 degrees (left edge) to
+180 degrees (right edge), from +X towards +Y as in ``docs/conventions.md``; row y
covers the zenith angle theta from 0 (top) to 180 degrees (bottom), so the
horizon is the middle row. The irradiance panel shows E(n) / pi for the
surface normal n of each pixel: the radiance of a white Lambertian surface, in
cd/m^2 like the sky, so one exposure serves all three panels.

References
----------
-   Reinhard, E., Stark, M., Shirley, P., Ferwerda, J. (2002). Photographic
    Tone Reproduction for Digital Images. SIGGRAPH (key value 0.18, L / (1 + L)).
-   IEC 61966-2-1:1999, the sRGB transfer function.
-   PNG (Third Edition), W3C: signature, IHDR, IDAT (zlib), IEND, CRC-32.
"""

from __future__ import annotations

import math
import os
import struct
import zlib
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import files
from skysh.checks import as_float_array, check_count, check_flag, check_scalar, short_repr
from skysh.lighting.lights import check_albedo
from skysh.model import ground, hosek, preetham, solar
from skysh.runtime import SkySH
from skysh.sh import basis as sh

__all__ = ["latlong_dirs", "render_image"]

KEY_VALUE: float = 0.18
"""Reinhard's key: the sky's log-average maps to this linear value before L / (1 + L)."""

GLYPH_WIDTH: int = 5
"""Width of a glyph of the built-in font, pixels (before scaling)."""

GLYPH_HEIGHT: int = 7
"""Height of a glyph of the built-in font, pixels (before scaling)."""

_FONT: dict[str, str] = {
    # 7 rows of 5 bits (bit 4 = leftmost pixel), two hex digits per row.
    "0": "0e11131519110e", "1": "040c040404040e", "2": "0e11010204081f", "3": "1f02040201110e", "4": "02060a121f0202",
    "5": "1f101e0101110e", "6": "0608101e11110e", "7": "1f010204080808", "8": "0e11110e11110e", "9": "0e11110f01020c",
    "A": "0e1111111f1111", "B": "1e11111e11111e", "C": "0e11101010110e", "D": "1c12111111121c", "E": "1f10101e10101f",
    "F": "1f10101e101010", "G": "0e11101711110f", "H": "1111111f111111", "I": "0e04040404040e", "J": "0702020202120c",
    "K": "11121418141211", "L": "1010101010101f", "M": "111b1515111111", "N": "11111915131111", "O": "0e11111111110e",
    "P": "1e11111e101010", "Q": "0e11111115120d", "R": "1e11111e141211", "S": "0f10100e01011e", "T": "1f040404040404",
    "U": "1111111111110e", "V": "11111111110a04", "W": "1111111515150a", "X": "11110a040a1111", "Y": "1111110a040404",
    "Z": "1f01020408101f", " ": "00000000000000", ".": "00000000000c0c", ",": "00000000000c04", "-": "0000001f000000",
    "+": "0004041f040400", "/": "00010204081000", "(": "02040808080402", ")": "08040202020408", ":": "000c0c000c0c00",
    "=": "00001f001f0000", "^": "040a1100000000", "*": "0004150e150400",
}

PANEL_WIDTH_RANGE: tuple[int, int] = (16, 4096)
"""Valid width of each panel of :func:`render_image`, pixels."""

DEFAULT_PANEL_WIDTH: int = 448
"""Default panel width of :func:`render_image` and ``skysh render``: three panels with their
axes make an image 1,658 x 358 pixels (``skysh render`` prints the size), text at twice the
font's size."""

MAX_LATLONG_WIDTH: int = 8192
"""Largest width of :func:`latlong_dirs` (8192 x 4096 directions, 0.8 GB of float64)."""

MAX_TEXT_SCALE: int = 64
"""Largest pixel scale of the built-in font in :func:`draw_text`."""

_BACKGROUND: tuple[int, int, int] = (24, 24, 28)
_TEXT: tuple[int, int, int] = (235, 235, 235)
_MUTED: tuple[int, int, int] = (150, 150, 150)
_SUN_RING: tuple[int, int, int] = (255, 60, 0)
_SUN_OUTLINE: tuple[int, int, int] = (0, 0, 0)


def latlong_dirs(width: int) -> NDArray[np.float64]:
    """
    Unit view directions of a latitude-longitude panel ``width`` x ``width // 2``.

    Parameters
    ----------
    width
        Pixels, an integer in [2, :data:`MAX_LATLONG_WIDTH`].

    Returns
    -------
    ndarray
        (width // 2, width, 3): pixel centres, phi from -pi (left) to pi
        (right), theta from 0 (top) to pi (bottom); Z up.
    """
    width = check_count(width, "width", 2, MAX_LATLONG_WIDTH)
    height = width // 2
    theta = (np.arange(height) + 0.5) * (math.pi / height)
    phi = (np.arange(width) + 0.5) * (2.0 * math.pi / width) - math.pi
    st = np.sin(theta)[:, None]
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1)


def true_scene(dirs: NDArray[np.float64], sun_zenith: float, turbidity: float, sun_azimuth: float = 0.0,
               colourspace: str = "sRGB", sun: bool = False, ground_albedo: ArrayLike = 0.0,
               sun_pixels: NDArray[np.bool_] | None = None, pixel_solid_angle: ArrayLike = 0.0) -> NDArray[np.float64]:
    """
    Radiance (cd/m^2, linear RGB) of the true scene in the directions ``dirs`` (..., 3), from the models.

    The Preetham sky (:func:`skysh.model.preetham.radiance`) above the horizon; below
    it, a Lambertian ground of ``ground_albedo`` (a number or RGB in [0, 1])
    with the uniform radiance albedo x E_h / pi, E_h the horizontal irradiance
    from the converged projection's c_10 (:func:`skysh.model.preetham.sky_sh`, exact
    for light zero below the horizon) plus the sun's ``E cos(theta_s)`` when
    ``sun``; with ``sun``, the sun's disk (:func:`skysh.model.solar.illuminance_rgb`):
    its illuminance spread over the ``sun_pixels`` (a boolean mask over
    ``dirs[..., 0]``) of solid angles ``pixel_solid_angle`` (sr, broadcasting
    with ``dirs[..., 0]``), so the picture holds the sun's energy whatever its
    resolution (the disk, 0.53 deg across, is smaller than a pixel of most panels).
    """
    albedo, sun = check_albedo(ground_albedo), check_flag(sun, "sun")
    out = preetham.radiance(dirs, sun_zenith, sun_azimuth, turbidity, colourspace=colourspace)
    e_sun = solar.illuminance_rgb(sun_zenith, turbidity, colourspace) if sun else np.zeros(3)
    if albedo is not None:
        c10 = preetham.sky_sh(sun_zenith, turbidity, 2, colourspace=colourspace)[2]
        e_h = ground.HORIZONTAL_FACTOR * c10 + e_sun * math.cos(sun_zenith)
        out[dirs[..., 2] < 0.0] = ground.ground_radiance(albedo, e_h)
    if sun and sun_pixels is not None and sun_pixels.any():
        area = np.broadcast_to(pixel_solid_angle, sun_pixels.shape)[sun_pixels]
        out[sun_pixels] += e_sun / float(area.sum())
    return out


def true_hosek_sky(dirs: NDArray[np.float64], sun_zenith: float, turbidity: float, sun_azimuth: float,
                   albedo: ArrayLike = 0.0) -> NDArray[np.float64]:
    """
    Radiance (cd/m^2, linear sRGB) of the Hosek-Wilkie sky in the directions ``dirs`` (..., 3), from the model
    (:func:`skysh.model.hosek.radiance`, the RGB dataset), zero below the horizon; ``albedo`` a number or an RGB
    triple in [0, 1] (each channel at its own albedo, as :class:`skysh.hosek_runtime.HosekWilkieSH`).
    """
    a = np.broadcast_to(as_float_array(albedo, "albedo"), (3,))
    out = np.empty(dirs.shape)
    for value in sorted(set(a.tolist())):  # one model evaluation per distinct albedo
        channels = a == value
        out[..., channels] = hosek.radiance(dirs, sun_zenith, sun_azimuth, turbidity, value)[..., channels]
    return out


def _sun_pixels(dirs: NDArray[np.float64], sun_zenith: float, sun_azimuth: float) -> NDArray[np.bool_]:
    """The pixels of a latitude-longitude panel that show the sun's disk: within its angular radius, or the nearest."""
    st = math.sin(sun_zenith)
    cos_angle = dirs @ np.array([st * math.cos(sun_azimuth), st * math.sin(sun_azimuth), math.cos(sun_zenith)])
    mask = cos_angle >= math.cos(solar.SUN_ANGULAR_RADIUS)
    if not mask.any():
        mask = cos_angle == cos_angle.max()
    return mask


def tone_map(rgb: ArrayLike, exposure: float) -> NDArray[np.uint8]:
    """
    Linear RGB (any unit) -> 8-bit sRGB: times ``exposure``, Reinhard, sRGB transfer function.

    ``rgb`` is finite, shape (..., 3) (empty batches give empty results);
    ``exposure`` one finite number > 0. Reinhard's L / (1 + L) is applied to the
    mean of R, G and B and every channel is scaled by the same ratio
    (per-channel compression would wash the sky's blue out); a channel still
    above 1 clips. Negative values (SH ringing, out-of-gamut sky) show as 0.
    """
    exposure = check_scalar(exposure, "exposure")
    if not exposure > 0.0:
        raise ValueError(f"exposure must be > 0, got {exposure!r}")
    v = as_float_array(rgb, "rgb")
    if v.ndim == 0 or v.shape[-1] != 3:
        raise ValueError(f"rgb must have shape (..., 3), got {v.shape}")
    with np.errstate(over="ignore"):  # an overflow to inf maps to white, as any value far above 1
        v = np.maximum(v * exposure, 0.0)
        level = v.mean(axis=-1, keepdims=True)  # Reinhard on the RGB mean keeps the sky's saturation
        v = np.where(np.isfinite(level), v / (1.0 + level), 1.0)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)
    return np.clip(np.rint(v * 255.0), 0, 255).astype(np.uint8)


def draw_text(image: NDArray[np.uint8], text: str, x: int, y: int, scale: int = 1,
              colour: tuple[int, int, int] = _TEXT) -> int:
    """
    Draw ``text`` (upper-cased; unknown characters as blanks) with its top-left corner at (x, y), in place.

    Parameters
    ----------
    image
        (H, W, 3) uint8 array, drawn into.
    text
        A str.
    x, y
        Pixels, integers (may lie outside the image; such pixels are skipped).
    scale
        Pixels per font pixel, an integer in [1, :data:`MAX_TEXT_SCALE`].
    colour
        (R, G, B), integers in [0, 255].

    Returns
    -------
    int
        The x just after the text.
    """
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        shape = getattr(image, "shape", None)
        raise ValueError(f"image must be an (H, W, 3) numpy array of uint8, got {type(image).__name__} of shape {shape}")
    if not isinstance(text, str):
        raise ValueError(f"text must be a str, got {short_repr(text)}")
    x = check_count(x, "x", -(1 << 30), 1 << 30)
    y = check_count(y, "y", -(1 << 30), 1 << 30)
    scale = check_count(scale, "scale", 1, MAX_TEXT_SCALE)
    if not isinstance(colour, (tuple, list, np.ndarray)) or len(colour) != 3 or not all(
            isinstance(c, (int, np.integer)) and not isinstance(c, bool) and 0 <= c <= 255 for c in colour):
        raise ValueError(f"colour must be three integers (R, G, B) in [0, 255], got {short_repr(colour)}")
    return _draw_text(image, text, x, y, scale, tuple(int(c) for c in colour))


def _draw_text(image: NDArray[np.uint8], text: str, x: int, y: int, scale: int, colour: tuple[int, ...]) -> int:
    for ch in text.upper():
        for r, bits in enumerate(bytes.fromhex(_FONT.get(ch, _FONT[" "]))):  # the glyph's GLYPH_HEIGHT rows
            for c in range(GLYPH_WIDTH):
                if bits & (1 << (GLYPH_WIDTH - 1 - c)):
                    y0, x0 = y + r * scale, x + c * scale
                    image[max(y0, 0) : max(y0 + scale, 0), max(x0, 0) : max(x0 + scale, 0)] = colour
        x += (GLYPH_WIDTH + 1) * scale
    return x


def _text_width(text: str, scale: int) -> int:
    return len(text) * (GLYPH_WIDTH + 1) * scale - scale


def _draw_text_up(image: NDArray[np.uint8], text: str, x: int, y_centre: int, scale: int, colour: tuple[int, ...]) -> None:
    """``text`` rotated 90 degrees anticlockwise (read from bottom to top), centred on row ``y_centre``."""
    strip = np.zeros((GLYPH_HEIGHT * scale, _text_width(text, scale) + scale, 3), np.uint8)
    _draw_text(strip, text, 0, 0, scale, (255, 255, 255))
    up = np.rot90(strip)  # (width of the text, height of a glyph)
    y0 = max(0, y_centre - up.shape[0] // 2)
    region = image[y0 : y0 + up.shape[0], x : x + up.shape[1]]
    mask = up[: region.shape[0], : region.shape[1]].any(axis=-1)
    region[mask] = colour


def _ring(image: NDArray[np.uint8], cx: float, cy: float, radius: float, box: tuple[int, int, int, int], scale: int) -> None:
    """A ring around (cx, cy) (cx in panel columns, cy in image rows), wrapping in x.

    The ring is ``scale`` pixels thick with a one-pixel dark line on each side (visible on a
    bright sky); its inside is left alone, so the sky's glow around the sun stays visible.
    ``box`` = (x0, y0, x1, y1): the panel's columns and the rows the ring may use (beyond the
    panel's top and bottom edges, so a sun near the zenith keeps its whole ring).
    """
    x0, y0, x1, y1 = box
    width = x1 - x0
    steps = max(64, int(16 * radius))
    a = 2.0 * np.pi * np.arange(steps) / steps
    rings = [(radius - 1.0, _SUN_OUTLINE), (radius + scale, _SUN_OUTLINE)] + [(radius + t, _SUN_RING) for t in range(scale)]
    for r, colour in rings:
        px = x0 + np.floor(cx + r * np.cos(a)).astype(int) % width
        py = np.floor(cy + r * np.sin(a)).astype(int)
        keep = (py >= y0) & (py < y1)
        image[py[keep], px[keep]] = colour


def render_image(sky: SkySH, sun_zenith: float, turbidity: float, sun_azimuth: float = 0.0, bands: int = 3,
                 width: int = DEFAULT_PANEL_WIDTH, gibbs: bool = True, sun: bool = False,
                 ground_albedo: ArrayLike = 0.0, albedo: ArrayLike = 0.0) -> NDArray[np.uint8]:
    """
    The sky, its SH reconstruction and the SH irradiance, side by side, labelled.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`, or ``SkySH.load(model="hosek-wilkie")`` (the true sky
        is then :func:`true_hosek_sky`; no sun or ground).
    sun_zenith, turbidity, sun_azimuth
        Radians in [0, pi/2], turbidity in [2.5, 6] ([1, 10] for Hosek-Wilkie), radians (the
        runtime's domain); single numbers.
    bands
        SH bands of the reconstruction and the irradiance, [1, the file's bands].
    width
        Width of each panel in pixels, an integer in :data:`PANEL_WIDTH_RANGE`;
        panels are width // 2 high. Default :data:`DEFAULT_PANEL_WIDTH`.
    gibbs
        Apply the zonal Gibbs filter (Habel eq. 5) to the reconstruction (a
        bool). The irradiance panel always uses the runtime's irradiance
        defaults (no filter, deringing on: what an engine should light diffuse
        surfaces with).
    sun, ground_albedo
        As :meth:`skysh.SkySH.coefficients`: the sun's disk and a Lambertian
        ground, in the true scene (:func:`true_scene`), the reconstruction and
        the irradiance alike.
    albedo
        Hosek-Wilkie only: the ground albedo its sky sees (a number or RGB in [0, 1]).

    Returns
    -------
    ndarray
        (H, W, 3) uint8 sRGB image: a title line, then the three panels with a
        label above each, elevation ticks (degrees) on the left, azimuth ticks
        (degrees) below and the axis names; a ring marks the sun, drawn whole
        even when the sun is near the zenith (the ring may leave the panel).

    Notes
    -----
    One exposure for all panels: ``KEY_VALUE`` over the log-average (geometric
    mean over the upper-hemisphere pixels, weighted by solid angle) of the
    true sky's mean of R, G and B (the sun's pixels left out, so it does not
    change the exposure). The irradiance panel is E / pi.
    """
    if not hasattr(sky, "coefficients") or not hasattr(sky, "colourspace"):
        raise ValueError(f"sky must be a loaded skysh.SkySH, got {type(sky).__name__}")
    width = check_count(width, "width", *PANEL_WIDTH_RANGE)
    gibbs = check_flag(gibbs, "gibbs")
    sun_zenith = check_scalar(sun_zenith, "sun_zenith", unit="rad")
    turbidity = check_scalar(turbidity, "turbidity")
    sun_azimuth = check_scalar(sun_azimuth, "sun_azimuth", unit="rad")
    hosek_sky = getattr(sky, "model", "preetham") == "hosek-wilkie"
    lights = {"albedo": albedo} if hosek_sky else {"sun": check_flag(sun, "sun"), "ground_albedo": ground_albedo}
    panels, exposure = _panels(sky, sun_zenith, turbidity, sun_azimuth, bands, width, gibbs, lights)
    ground_text = np.atleast_1d(np.asarray(ground_albedo, dtype=np.float64))
    scene = (", SUN" if lights.get("sun") else "") + (
        f", GROUND ALBEDO {' '.join(f'{a:g}' for a in ground_text)}" if ground_text.any() else "")
    if hosek_sky:
        scene = ", ALBEDO " + " ".join(f"{a:g}" for a in np.atleast_1d(np.asarray(albedo, dtype=np.float64)))
    title = (("HOSEK-WILKIE, " if hosek_sky else "") + f"SUN ZENITH {math.degrees(sun_zenith):.1f} DEG, AZIMUTH "
             f"{math.degrees(sun_azimuth):.1f} DEG, TURBIDITY {turbidity:g}, {bands} BAND{'' if bands == 1 else 'S'}"
             f"{'' if gibbs else ', NO GIBBS'}{scene}")
    labels = _LABELS if scene == "" else (_LABELS[0], ("SKY, SUN, GROUND",) + _LABELS[1][1:])
    if hosek_sky:
        labels = (_LABELS[0], ("HOSEK-WILKIE SKY",) + _LABELS[1][1:])
    return _compose(panels, exposure, title, width, sun_zenith, sun_azimuth, labels)


def _panels(sky: SkySH, sun_zenith: float, turbidity: float, sun_azimuth: float, bands: int, width: int, gibbs: bool,
            lights: dict) -> tuple[tuple[NDArray, ...], float]:
    """The three panels' linear RGB (true scene, SH reconstruction, E / pi) and the exposure of :func:`render_image`."""
    coefficients = sky.coefficients(sun_zenith, turbidity, sun_azimuth, bands=bands, gibbs=gibbs, **lights)  # checks
    dirs = latlong_dirs(width)
    sin_theta = np.sin(np.arccos(np.clip(dirs[..., 2], -1.0, 1.0)))
    disk = _sun_pixels(dirs, sun_zenith, sun_azimuth)
    pixel = sin_theta * (math.pi / (width // 2)) * (2.0 * math.pi / width)  # solid angle of each pixel, sr
    if "albedo" in lights:  # Hosek-Wilkie: the sky alone
        truth = true_hosek_sky(dirs, sun_zenith, turbidity, sun_azimuth, lights["albedo"])
    else:
        truth = true_scene(dirs, sun_zenith, turbidity, sun_azimuth, sky.colourspace, sun_pixels=disk,
                           pixel_solid_angle=pixel, **lights)
    reconstruction = sh.evaluate(coefficients, dirs)
    irradiance = sh.evaluate(sky.coefficients(sun_zenith, turbidity, sun_azimuth, bands=bands, irradiance=True,
                                              **lights), dirs)
    upper = (dirs[..., 2] > 0.0) & ~disk
    weight = sin_theta[upper]
    grey = np.maximum(truth[upper].mean(axis=-1), 1e-6)
    exposure = KEY_VALUE / math.exp(float(np.sum(weight * np.log(grey)) / np.sum(weight)))
    return (truth, reconstruction, irradiance / math.pi), exposure


class _Layout(NamedTuple):
    """Where :func:`_compose` puts things (pixels)."""

    scale: int  # font pixel size
    detailed: bool  # tick numbers and axis names (panels at least COMPACT_BELOW wide)
    top: int  # first row of the panels
    lefts: tuple[int, int, int]  # first column of each panel
    height: int  # panel rows
    radius: float  # of the sun's ring
    size: tuple[int, int]  # (rows, columns) of the image


_DETAILED_WIDTH: int = 192
"""Panels narrower than this get short labels, ticks without numbers and no axis names (they would not fit)."""

_LABELS: tuple[tuple[str, ...], tuple[str, ...]] = (
    ("SKY", "SH", "E / PI"), ("PREETHAM SKY", "SH RECONSTRUCTION", "SH IRRADIANCE / PI"))
_AZIMUTH_NAME: str = "AZIMUTH (DEG), FROM +X TOWARDS +Y"
_ELEVATION_NAME: str = "ELEVATION (DEG)"


def _layout(width: int, title: str) -> _Layout:
    """The layout of three panels ``width`` wide under ``title``."""
    height = width // 2
    detailed = width >= _DETAILED_WIDTH
    scale = max(1, width // 192)  # font pixels: 2 at the default 512, 1 below 384
    line = (GLYPH_HEIGHT + 4) * scale
    radius = max(4.0, width / 40)
    tick = 3 * scale
    margin = 4 * scale
    axis = 2 * line + _text_width("-90", scale) + tick if detailed else margin + tick
    gap = _text_width("180  -180", scale) if detailed else 2 * tick  # azimuth numbers of neighbours stay apart
    top = margin + 2 * line + int(radius) + 2 * scale  # room above the panels for a ring at the zenith
    lefts = (axis, axis + width + gap, axis + 2 * (width + gap))
    columns = max(lefts[2] + width + margin + _text_width("0", scale), _text_width(title, scale) + 2 * margin)
    rows = top + height + int(radius) + 2 * scale + (2 * line if detailed else 0) + margin
    return _Layout(scale, detailed, top, lefts, height, radius, (rows, columns))


def _compose(panels: tuple[NDArray, ...], exposure: float, title: str, width: int, sun_zenith: float,
             sun_azimuth: float, labels: tuple[tuple[str, ...], tuple[str, ...]] = _LABELS) -> NDArray[np.uint8]:
    """Lay the tone-mapped panels out with their labels, axes and sun rings."""
    lay = _layout(width, title)
    scale, top, height, radius = lay.scale, lay.top, lay.height, lay.radius
    tick, line, margin = 3 * scale, (GLYPH_HEIGHT + 4) * scale, 4 * scale
    image = np.full(lay.size + (3,), _BACKGROUND, dtype=np.uint8)
    _draw_text(image, title, margin, margin, scale, _TEXT)
    sun_x = (math.remainder(sun_azimuth, 2.0 * math.pi) + math.pi) / (2.0 * math.pi) * width
    sun_y = sun_zenith / math.pi * height
    below = top + height + int(radius) + 2 * scale
    for k, (label, values, x0) in enumerate(zip(labels[lay.detailed], panels, lay.lefts)):
        _draw_text(image, label, x0, margin + line, scale, _TEXT)
        image[top : top + height, x0 : x0 + width] = tone_map(values, exposure)
        for elevation in (90, 45, 0, -45, -90):  # ticks on the panel's left edge, numbers left of the first
            row = top + min(height - 1, round((90 - elevation) / 180 * height))
            image[row : row + scale, x0 - tick : x0] = _MUTED
            if k == 0 and lay.detailed:
                text = str(elevation)
                _draw_text(image, text, x0 - tick - scale - _text_width(text, scale),
                           row - GLYPH_HEIGHT * scale // 2, scale, _MUTED)
        for azimuth in (-180, -90, 0, 90, 180):  # ticks below the panel, numbers under them
            col = x0 + min(width - 1, round((azimuth + 180) / 360 * width))
            image[top + height : top + height + tick, col : col + scale] = _MUTED
            if lay.detailed:
                text = str(azimuth)
                _draw_text(image, text, col - _text_width(text, scale) // 2, below, scale, _MUTED)
        _ring(image, sun_x, top + sun_y, radius, (x0, top - int(radius) - scale, x0 + width, top + height + int(radius)),
              scale)
    if lay.detailed:
        span = lay.lefts[2] + width - lay.lefts[0]
        _draw_text(image, _AZIMUTH_NAME, lay.lefts[0] + (span - _text_width(_AZIMUTH_NAME, scale)) // 2, below + line,
                   scale, _TEXT)
        _draw_text_up(image, _ELEVATION_NAME, margin, top + height // 2, scale, _TEXT)
    return image


def write_png(path: str | Path, image: ArrayLike) -> Path:
    """
    Write an (H, W, 3) uint8 RGB image as an 8-bit PNG (no filtering, zlib level 6).

    Parameters
    ----------
    path
        File to write (a str or path-like).
    image
        (H, W, 3) array of uint8 (other integer types are checked to lie in [0, 255]), H, W >= 1.

    Returns
    -------
    Path
        ``path``.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"path must be a str or path-like, got {short_repr(path)}")
    try:
        pixels = np.asarray(image)
    except (TypeError, ValueError):
        raise ValueError(f"image must be an (H, W, 3) array of integers in [0, 255], got {type(image).__name__}") from None
    if pixels.ndim != 3 or pixels.shape[2] != 3 or pixels.shape[0] < 1 or pixels.shape[1] < 1:
        raise ValueError(f"image must have shape (H, W, 3) with H, W >= 1, got {pixels.shape}")
    if pixels.shape[0] >= 1 << 31 or pixels.shape[1] >= 1 << 31:
        raise ValueError(f"image is too large for PNG (at most 2**31 - 1 pixels a side), got {pixels.shape}")
    if pixels.dtype != np.uint8:
        if not np.issubdtype(pixels.dtype, np.integer) or pixels.min() < 0 or pixels.max() > 255:
            raise ValueError("image must hold integers in [0, 255]")
        pixels = pixels.astype(np.uint8)
    height, width = pixels.shape[:2]
    raw = np.concatenate([np.zeros((height, 1), dtype=np.uint8), pixels.reshape(height, -1)], axis=1)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit truecolour, no interlace
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6)) + chunk(b"IEND", b"")
    return files.write_atomic(path, data)  # never half written; a link there is replaced, not followed
