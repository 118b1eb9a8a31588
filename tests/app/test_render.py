"""
Tests of skysh.app.render: the PNG writer (read back by an independent decoder
written here, and by matplotlib when it is installed), the tone mapping, the
bitmap font and the three-panel picture.
"""

from __future__ import annotations

import math
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from skysh import SkySH
from skysh.app import cli
from skysh.app.render import (
    _FONT,
    _MUTED,
    _SUN_RING,
    DEFAULT_PANEL_WIDTH,
    GLYPH_HEIGHT,
    GLYPH_WIDTH,
    _layout,
    draw_text,
    latlong_dirs,
    render_image,
    tone_map,
    write_png,
)


def read_png(path: Path) -> np.ndarray:
    """Decode an 8-bit RGB, non-interlaced PNG (filter types 0 only), checking every CRC."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, []
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        chunks.append((kind, body))
        pos += 12 + length
    assert chunks[0][0] == b"IHDR" and chunks[-1][0] == b"IEND"
    width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", chunks[0][1])
    assert (depth, colour, interlace) == (8, 2, 0)
    raw = zlib.decompress(b"".join(body for kind, body in chunks if kind == b"IDAT"))
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + 3 * width)
    assert np.all(rows[:, 0] == 0)
    return rows[:, 1:].reshape(height, width, 3)


UNIT_NORM_ATOL: float = 1e-12
"""|norm - 1| of latlong_dirs' directions (products of sines and cosines): rounding is a few eps; the
bound only has to catch a direction that is not normalised at all."""


class TestWritePng:
    def test_round_trip(self, tmp_path: Path) -> None:
        image = np.random.default_rng(1).integers(0, 256, size=(7, 11, 3), dtype=np.uint8)
        np.testing.assert_array_equal(read_png(write_png(tmp_path / "a.png", image)), image)

    def test_matplotlib_reads_it(self, tmp_path: Path) -> None:
        mpimg = pytest.importorskip("matplotlib.image")
        image = np.random.default_rng(2).integers(0, 256, size=(5, 9, 3), dtype=np.uint8)
        back = mpimg.imread(write_png(tmp_path / "b.png", image))
        np.testing.assert_array_equal(np.rint(back * 255).astype(np.uint8), image)

    @pytest.mark.parametrize(
        "bad", [np.zeros((4, 4)), np.zeros((4, 4, 4), np.uint8), np.full((2, 2, 3), 300), np.zeros((0, 3, 3), np.uint8)]
    )
    def test_refuses_bad_images(self, bad: np.ndarray, tmp_path: Path) -> None:
        with pytest.raises(ValueError):
            write_png(tmp_path / "c.png", bad)


class TestToneMap:
    def test_range_and_order(self) -> None:
        grey = np.linspace(-1.0, 100.0, 50)[:, None] * np.ones(3)
        out = tone_map(grey, 1.0)
        assert out.dtype == np.uint8 and out[0, 0] == 0 and out[-1, 0] >= 250
        assert np.all(np.diff(out[:, 0].astype(int)) >= 0)

    def test_srgb_transfer(self) -> None:
        # linear 0.18 * exposure 1 -> Reinhard 0.18 / 1.18 -> sRGB OETF
        v = 0.18 / 1.18
        expected = round(255 * (1.055 * v ** (1 / 2.4) - 0.055))
        assert tone_map([[0.18, 0.18, 0.18]], 1.0)[0, 0] == expected


class TestFont:
    def test_glyphs_are_7_rows_of_5_bits(self) -> None:
        for ch, rows in _FONT.items():
            assert len(rows) == 2 * GLYPH_HEIGHT, ch
            assert all(int(rows[k : k + 2], 16) < 32 for k in range(0, len(rows), 2)), ch

    def test_draws_and_advances(self) -> None:
        image = np.zeros((10, 40, 3), np.uint8)
        end = draw_text(image, "Hi 1", 1, 1)
        assert end == 1 + 4 * (GLYPH_WIDTH + 1)
        assert image.any() and not image[:, end:].any()
        blank = np.zeros_like(image)
        draw_text(blank, "~~", 0, 0)  # unknown characters are blanks
        assert not blank.any()


def inked_width(text: str, scale: int) -> int:
    """Columns from the first to the last drawn pixel of ``text`` drawn alone by draw_text."""
    canvas = np.zeros((GLYPH_HEIGHT * scale, len(text) * (GLYPH_WIDTH + 1) * scale, 3), np.uint8)
    draw_text(canvas, text, 0, 0, scale)
    columns = np.flatnonzero(canvas.any(axis=(0, 2)))
    return int(columns.max() - columns.min() + 1)


class TestRenderImage:
    def test_layout_and_content(self, sky: SkySH) -> None:
        width = 64
        image = render_image(sky, math.radians(50), 3.0, math.radians(30), bands=3, width=width)
        assert image.dtype == np.uint8 and image.ndim == 3
        dirs = latlong_dirs(width)
        assert dirs.shape == (width // 2, width, 3)
        np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, rtol=0, atol=UNIT_NORM_ATOL)
        title = "SUN ZENITH 50.0 DEG, AZIMUTH 30.0 DEG, TURBIDITY 3, 3 BANDS"
        layout = _layout(width, title)
        assert image.shape[:2] == layout.size
        top, height = layout.top, layout.height
        # the true sky (first panel) is black below the horizon, not above it (the sun's ring aside)
        panel = image[top : top + height, layout.lefts[0] : layout.lefts[0] + width]
        upper, lower = panel[: width // 4 - 1], panel[width // 4 + 1 :]
        assert upper.mean() > 40 and lower.max() == 0
        # the SH reconstruction is not zero below the horizon (ringing: the sky's jump at the horizon)
        sh_panel = image[top : top + height, layout.lefts[1] : layout.lefts[1] + width]
        assert sh_panel[width // 4 + 1 :].max() > 0

    def test_default_is_large_enough_to_read(self, sky: SkySH) -> None:
        image = render_image(sky, 0.5, 3.0)
        assert image.shape[1] >= 1600 and image.shape[0] >= 300
        assert _layout(DEFAULT_PANEL_WIDTH, "").detailed and _layout(DEFAULT_PANEL_WIDTH, "").scale >= 2

    @pytest.mark.parametrize("zenith_deg", [0.0, 2.0, 5.0])
    def test_a_high_sun_keeps_its_whole_ring(self, sky: SkySH, zenith_deg: float) -> None:
        """The ring leaves the panel above the zenith row instead of being clipped (issue 13)."""
        width = 256
        image = render_image(sky, math.radians(zenith_deg), 3.0, 0.0, width=width)
        layout = _layout(width, "")
        x0 = layout.lefts[0]
        ring = np.all(image == _SUN_RING, axis=-1)
        rows = np.flatnonzero(ring[:, x0 : x0 + width].any(axis=1))
        sun_row = layout.top + math.radians(zenith_deg) / math.pi * layout.height
        assert rows.min() < layout.top  # drawn above the panel's first row
        assert rows.min() <= sun_row - layout.radius + 1 and rows.max() >= sun_row + layout.radius - 1
        # the inside of the ring is the sky, untouched: the glow around the sun shows
        centre = image[round(sun_row), x0 + width // 2]
        assert not np.array_equal(centre, _SUN_RING) and centre.mean() > 60

    def test_axes_are_labelled(self, sky: SkySH) -> None:
        """Both axis names are drawn at full length, tick numbers for both axes in grey."""
        width = 256
        image = render_image(sky, 0.5, 3.0, 0.0, width=width)
        layout = _layout(width, "")
        k = layout.scale
        text = np.all(image == (235, 235, 235), axis=-1)
        below = layout.top + layout.height + int(layout.radius) + 2 * k
        line = (GLYPH_HEIGHT + 4) * k
        columns = np.flatnonzero(text[below + line : below + line + GLYPH_HEIGHT * k].any(axis=0))
        assert columns.max() - columns.min() + 1 == inked_width("AZIMUTH (DEG), FROM +X TOWARDS +Y", k)
        rows = np.flatnonzero(text[layout.top : layout.top + layout.height, : layout.lefts[0]].any(axis=1))
        assert rows.max() - rows.min() + 1 == inked_width("ELEVATION (DEG)", k)  # drawn upwards: down the rows
        grey = np.all(image == _MUTED, axis=-1)
        assert grey[below : below + GLYPH_HEIGHT * k].any()  # azimuth numbers
        assert grey[layout.top : layout.top + layout.height, : layout.lefts[0] - 3 * k].any()  # elevation numbers

    def test_checks(self, sky: SkySH) -> None:
        with pytest.raises(ValueError):
            render_image(sky, 0.5, 3.0, width=8)
        with pytest.raises(ValueError):
            render_image(sky, 0.5, 7.0, width=32)


class TestRenderCommand:
    def test_writes_a_png(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        out = tmp_path / "sky.png"
        code = cli.main(["render", "--sun-zenith", "70", "--sun-azimuth", "-30", "--turbidity", "4", "--width", "32",
                         "--bands", "2", "--out", str(out)])
        assert code == 0, capsys.readouterr().err
        image = read_png(out)
        assert image.shape[1] > 3 * 32 and image.shape[0] > 16
        assert "wrote" in capsys.readouterr().out


def test_command_line_default_is_the_library_default() -> None:
    from skysh.app.render import DEFAULT_PANEL_WIDTH as library

    assert cli.DEFAULT_RENDER_WIDTH == library  # the CLI repeats it so that its parser imports nothing


class TestSunAndGround:
    """The true scene with the sun's disk and a Lambertian ground (issue 15), and its panels."""

    GROUND_RTOL: float = 1e-12
    """true_scene's ground vs albedo x E_h / pi typed here from the same converged projection: one
    product and a division, a few eps."""

    ENERGY_RTOL: float = 1e-12
    """The sun's pixels hold its illuminance: sum of radiance x pixel solid angle over the disk's
    pixels vs solar.illuminance_rgb; a sum of a few values, rounding only (the sky under the disk is
    added too and is ~1e-5 of the sun's radiance there, so it is subtracted first)."""

    def test_true_scene_ground_and_sun(self, sky: SkySH) -> None:
        from skysh.app.render import _sun_pixels, true_scene
        from skysh.model import preetham, solar

        ts, t, phi, albedo = math.radians(50), 3.0, 0.4, np.array([0.3, 0.2, 0.1])
        dirs = latlong_dirs(64)
        sin_theta = np.sin(np.arccos(np.clip(dirs[..., 2], -1, 1)))
        pixel = sin_theta * (math.pi / 32) * (2 * math.pi / 64)
        disk = _sun_pixels(dirs, ts, phi)
        scene = true_scene(dirs, ts, t, phi, sun=True, ground_albedo=albedo, sun_pixels=disk, pixel_solid_angle=pixel)
        e_sun = solar.illuminance_rgb(ts, t)
        e_h = math.sqrt(4 * math.pi / 3) * preetham.sky_sh(ts, t, 2)[2] + e_sun * math.cos(ts)
        below = dirs[..., 2] < 0
        np.testing.assert_allclose(scene[below], np.broadcast_to(albedo * e_h / math.pi, scene[below].shape),
                                   rtol=self.GROUND_RTOL)
        sky_only = preetham.radiance(dirs, ts, phi, t)
        energy = ((scene - sky_only)[disk] * pixel[disk][:, None]).sum(axis=0)
        np.testing.assert_allclose(energy, e_sun, rtol=self.ENERGY_RTOL)
        assert disk.sum() >= 1
        np.testing.assert_array_equal(scene[~disk & ~below], sky_only[~disk & ~below])

    def test_panels(self, sky: SkySH) -> None:
        width = 64
        image = render_image(sky, math.radians(50), 3.0, math.radians(30), width=width, sun=True, ground_albedo=0.3)
        plain = render_image(sky, math.radians(50), 3.0, math.radians(30), width=width)
        layout = _layout(width, "SUN ZENITH 50.0 DEG, AZIMUTH 30.0 DEG, TURBIDITY 3, 3 BANDS, SUN, GROUND ALBEDO 0.3")
        assert image.shape[:2] == layout.size
        top, height, x0 = layout.top, layout.height, layout.lefts[0]
        truth = image[top : top + height, x0 : x0 + width]
        lower = truth[width // 4 + 1 :]
        assert lower.min() > 0 and np.all(lower == lower[0, 0])  # a uniform, lit ground
        old = _layout(width, "SUN ZENITH 50.0 DEG, AZIMUTH 30.0 DEG, TURBIDITY 3, 3 BANDS")
        assert plain[old.top + width // 4 + 1 : old.top + height, x0 : x0 + width].max() == 0  # black without it
        from skysh.app.render import _sun_pixels

        disk = _sun_pixels(latlong_dirs(width), math.radians(50), math.radians(30))
        assert truth[disk].max(axis=-1).min() == 255 and truth[disk].min() > 150  # the sun, saturated
        assert plain[old.top : old.top + height, x0 : x0 + width][disk].max() < 255  # the sky alone there

    def test_checks(self, sky: SkySH) -> None:
        with pytest.raises(TypeError, match="sun"):
            render_image(sky, 0.5, 3.0, width=32, sun=1)
        with pytest.raises(ValueError, match="ground_albedo"):
            render_image(sky, 0.5, 3.0, width=32, ground_albedo=2.0)
