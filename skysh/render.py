"""
Pictures of the sky and its SH lighting, as PNG, without plotting libraries
==========================================================================

-   :func:`render_image`: three latitude-longitude panels side by side, the
    Preetham sky, its SH reconstruction and the SH irradiance, tone-mapped
    with one exposure and labelled; an (H, W, 3) uint8 array.
-   :func:`latlong_dirs`: the view directions of a latitude-longitude panel.
-   :func:`tone_map`: exposure, Reinhard's operator and the sRGB transfer
    function, linear RGB -> 8-bit sRGB.
-   :func:`draw_text`: a built-in 5 x 7 bitmap font (upper case, digits, a few signs).
-   :func:`write_png`: a minimal PNG writer (zlib and struct only).

matplotlib is not needed (nor imported). The true sky comes from
:func:`skysh.preetham.radiance`, so rendering imports colour-science.

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
import struct
import zlib
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skysh import preetham, sh

if TYPE_CHECKING:  # pragma: no cover
    from skysh.runtime import SkySH

__all__ = ["KEY_VALUE", "GLYPH_WIDTH", "GLYPH_HEIGHT", "latlong_dirs", "tone_map", "draw_text", "render_image", "write_png"]

KEY_VALUE: float = 0.18
"""Reinhard's key: the sky's log-average maps to this linear value before L / (1 + L)."""

GLYPH_WIDTH: int = 5
"""Width of a glyph of the built-in font, pixels (before scaling)."""

GLYPH_HEIGHT: int = 7
"""Height of a glyph of the built-in font, pixels (before scaling)."""

_FONT: dict[str, str] = {
    # 7 rows of 5 bits (bit 4 = leftmost pixel), two hex digits per row.
    "0": "0e11131519110e", "1": "040c040404040e", "2": "0e11010204081f", "3": "1f02040201110e",
    "4": "02060a121f0202", "5": "1f101e0101110e", "6": "0608101e11110e", "7": "1f010204080808",
    "8": "0e11110e11110e", "9": "0e11110f01020c", "A": "0e1111111f1111", "B": "1e11111e11111e",
    "C": "0e11101010110e", "D": "1c12111111121c", "E": "1f10101e10101f", "F": "1f10101e101010",
    "G": "0e11101711110f", "H": "1111111f111111", "I": "0e04040404040e", "J": "0702020202120c",
    "K": "11121418141211", "L": "1010101010101f", "M": "111b1515111111", "N": "11111915131111",
    "O": "0e11111111110e", "P": "1e11111e101010", "Q": "0e11111115120d", "R": "1e11111e141211",
    "S": "0f10100e01011e", "T": "1f040404040404", "U": "1111111111110e", "V": "11111111110a04",
    "W": "1111111515150a", "X": "11110a040a1111", "Y": "1111110a040404", "Z": "1f01020408101f",
    " ": "00000000000000", ".": "00000000000c0c", ",": "00000000000c04", "-": "0000001f000000",
    "+": "0004041f040400", "/": "00010204081000", "(": "02040808080402", ")": "08040202020408",
    ":": "000c0c000c0c00", "=": "00001f001f0000", "^": "040a1100000000", "*": "0004150e150400",
}

_BACKGROUND: tuple[int, int, int] = (24, 24, 28)
_TEXT: tuple[int, int, int] = (235, 235, 235)
_MUTED: tuple[int, int, int] = (150, 150, 150)
_SUN_RING: tuple[int, int, int] = (255, 60, 0)


def latlong_dirs(width: int) -> NDArray[np.float64]:
    """
    Unit view directions of a latitude-longitude panel ``width`` x ``width // 2``.

    Returns
    -------
    ndarray
        (width // 2, width, 3): pixel centres, phi from -pi (left) to pi
        (right), theta from 0 (top) to pi (bottom); Z up.
    """
    height = width // 2
    theta = (np.arange(height) + 0.5) * (math.pi / height)
    phi = (np.arange(width) + 0.5) * (2.0 * math.pi / width) - math.pi
    st = np.sin(theta)[:, None]
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)[:, None]), axis=-1)


def tone_map(rgb: ArrayLike, exposure: float) -> NDArray[np.uint8]:
    """
    Linear RGB (any unit) -> 8-bit sRGB: times ``exposure``, Reinhard, sRGB transfer function.

    Reinhard's L / (1 + L) is applied to the mean of R, G and B and every
    channel is scaled by the same ratio (per-channel compression would wash
    the sky's blue out); a channel still above 1 clips. Negative values (SH
    ringing, out-of-gamut sky) show as 0.
    """
    v = np.maximum(np.asarray(rgb, dtype=np.float64) * exposure, 0.0)
    level = v.mean(axis=-1, keepdims=True)  # Reinhard on the RGB mean keeps the sky's saturation
    v = v / (1.0 + level)
    v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)
    return np.clip(np.rint(v * 255.0), 0, 255).astype(np.uint8)


def draw_text(image: NDArray[np.uint8], text: str, x: int, y: int, scale: int = 1, colour: tuple[int, int, int] = _TEXT) -> int:
    """
    Draw ``text`` (upper-cased; unknown characters as blanks) with its top-left corner at (x, y), in place.

    Returns
    -------
    int
        The x just after the text. Pixels outside the image are skipped.
    """
    for ch in text.upper():
        rows = _FONT.get(ch, _FONT[" "])
        for r in range(GLYPH_HEIGHT):
            bits = int(rows[2 * r : 2 * r + 2], 16)
            for c in range(GLYPH_WIDTH):
                if bits & (1 << (GLYPH_WIDTH - 1 - c)):
                    y0, x0 = y + r * scale, x + c * scale
                    image[max(y0, 0) : max(y0 + scale, 0), max(x0, 0) : max(x0 + scale, 0)] = colour
        x += (GLYPH_WIDTH + 1) * scale
    return x


def _ring(image: NDArray[np.uint8], cx: float, cy: float, radius: float, box: tuple[int, int, int, int]) -> None:
    """A one-pixel ring centred at (cx, cy), clipped to box (x0, y0, x1, y1), wrapping in x."""
    x0, y0, x1, y1 = box
    for k in range(64):
        a = 2.0 * math.pi * k / 64
        px = x0 + int(math.floor(cx + radius * math.cos(a))) % (x1 - x0)
        py = int(math.floor(cy + radius * math.sin(a)))
        if y0 <= y0 + py < y1:
            image[y0 + py, px] = _SUN_RING


def render_image(
    sky: SkySH,
    sun_zenith: float,
    turbidity: float,
    sun_azimuth: float = 0.0,
    bands: int = 3,
    width: int = 256,
    gibbs: bool = True,
) -> NDArray[np.uint8]:
    """
    The sky, its SH reconstruction and the SH irradiance, side by side, labelled.

    Parameters
    ----------
    sky
        A loaded :class:`skysh.SkySH`.
    sun_zenith, turbidity, sun_azimuth
        Radians, [2.5, 6], radians (the runtime's domain).
    bands
        SH bands of the reconstruction and the irradiance.
    width
        Width of each panel in pixels, [16, 4096]; panels are width // 2 high.
    gibbs
        Apply the zonal Gibbs filter (Habel eq. 5) to the reconstruction. The
        irradiance panel always uses the runtime's irradiance defaults (no
        filter, deringing on: what an engine should light diffuse surfaces with).

    Returns
    -------
    ndarray
        (H, W, 3) uint8 sRGB image: a title line, then the three panels with a
        label above each and azimuth ticks below.

    Notes
    -----
    One exposure for all panels: ``KEY_VALUE`` over the log-average (geometric
    mean over the upper-hemisphere pixels, weighted by solid angle) of the
    true sky's mean of R, G and B. The irradiance panel is E / pi.
    """
    if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or not 16 <= width <= 4096:
        raise ValueError(f"width must be an integer in [16, 4096], got {width!r}")
    coefficients = sky.coefficients(sun_zenith, turbidity, sun_azimuth, bands=bands, gibbs=gibbs)  # checks the domain
    width = int(width)
    height = width // 2
    dirs = latlong_dirs(width)
    truth = preetham.radiance(dirs, sun_zenith, sun_azimuth, turbidity, colourspace=sky.colourspace)
    reconstruction = sh.evaluate(coefficients, dirs)
    irradiance = sh.evaluate(sky.coefficients(sun_zenith, turbidity, sun_azimuth, bands=bands, irradiance=True), dirs) / math.pi

    upper = dirs[..., 2] > 0.0
    weight = np.broadcast_to(np.sin(np.arccos(np.clip(dirs[..., 2], -1.0, 1.0))), upper.shape)[upper]
    grey = np.maximum(truth[upper].mean(axis=-1), 1e-6)
    exposure = KEY_VALUE / math.exp(float(np.sum(weight * np.log(grey)) / np.sum(weight)))

    scale = max(1, width // 128)
    line = (GLYPH_HEIGHT + 3) * scale
    margin, gap = 4 * scale, 6 * scale
    top = margin + 2 * line
    total_w = 3 * width + 2 * gap + 2 * margin
    total_h = top + height + line + margin
    image = np.empty((total_h, total_w, 3), dtype=np.uint8)
    image[...] = _BACKGROUND

    title = (
        f"SUN ZENITH {math.degrees(sun_zenith):.1f}, AZIMUTH {math.degrees(sun_azimuth):.1f} DEG, "
        f"TURBIDITY {turbidity:g}, {bands} BANDS{'' if gibbs else ', NO GIBBS'}"
    )
    draw_text(image, title, margin, margin, scale)
    labels = ("PREETHAM SKY", "SH RECONSTRUCTION", "SH IRRADIANCE / PI")
    panels = (truth, reconstruction, irradiance)
    sun_x = (math.remainder(sun_azimuth, 2.0 * math.pi) + math.pi) / (2.0 * math.pi) * width
    sun_y = sun_zenith / math.pi * height
    for k, (label, values) in enumerate(zip(labels, panels)):
        x0 = margin + k * (width + gap)
        draw_text(image, label, x0, margin + line, scale)
        image[top : top + height, x0 : x0 + width] = tone_map(values, exposure)
        _ring(image, sun_x, sun_y, max(3.0, width / 64), (x0, top, x0 + width, top + height))
        # horizon ticks in the gaps, azimuth labels below
        tick = top + height // 2
        image[tick, max(x0 - 3 * scale, 0) : x0] = _MUTED
        image[tick, x0 + width : x0 + width + 3 * scale] = _MUTED
        below = top + height + 2 * scale
        draw_text(image, "-180", x0, below, scale, _MUTED)
        draw_text(image, "0", x0 + width // 2 - (GLYPH_WIDTH * scale) // 2, below, scale, _MUTED)
        draw_text(image, "180", x0 + width - 3 * (GLYPH_WIDTH + 1) * scale + scale, below, scale, _MUTED)
    return image


def write_png(path: str | Path, image: ArrayLike) -> Path:
    """
    Write an (H, W, 3) uint8 RGB image as an 8-bit PNG (no filtering, zlib level 6).

    Parameters
    ----------
    path
        File to write.
    image
        (H, W, 3) array of uint8 (other integer types are checked to lie in [0, 255]).

    Returns
    -------
    Path
        ``path``.
    """
    pixels = np.asarray(image)
    if pixels.ndim != 3 or pixels.shape[2] != 3 or pixels.shape[0] < 1 or pixels.shape[1] < 1:
        raise ValueError(f"image must have shape (H, W, 3) with H, W >= 1, got {pixels.shape}")
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
    path = Path(path)
    path.write_bytes(data)
    return path
