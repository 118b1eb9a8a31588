"""
Tests of skysh.render: the PNG writer (read back by an independent decoder
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

from skysh import SkySH, cli
from skysh.render import GLYPH_HEIGHT, GLYPH_WIDTH, _FONT, draw_text, latlong_dirs, render_image, tone_map, write_png


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


@pytest.fixture(scope="module")
def sky() -> SkySH:
    return SkySH.load()


class TestWritePng:
    def test_round_trip(self, tmp_path: Path) -> None:
        image = np.random.default_rng(1).integers(0, 256, size=(7, 11, 3), dtype=np.uint8)
        np.testing.assert_array_equal(read_png(write_png(tmp_path / "a.png", image)), image)

    def test_matplotlib_reads_it(self, tmp_path: Path) -> None:
        mpimg = pytest.importorskip("matplotlib.image")
        image = np.random.default_rng(2).integers(0, 256, size=(5, 9, 3), dtype=np.uint8)
        back = mpimg.imread(write_png(tmp_path / "b.png", image))
        np.testing.assert_array_equal(np.rint(back * 255).astype(np.uint8), image)

    @pytest.mark.parametrize("bad", [np.zeros((4, 4)), np.zeros((4, 4, 4), np.uint8), np.full((2, 2, 3), 300), np.zeros((0, 3, 3), np.uint8)])
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


class TestRenderImage:
    def test_layout_and_content(self, sky: SkySH) -> None:
        width = 64
        image = render_image(sky, math.radians(50), 3.0, math.radians(30), bands=3, width=width)
        assert image.dtype == np.uint8 and image.ndim == 3
        dirs = latlong_dirs(width)
        assert dirs.shape == (width // 2, width, 3)
        np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-12)
        # find the first panel: the block of rows where the left panel's pixels are not background
        background = image[0, 0]
        differs = np.any(image != background, axis=-1)
        assert differs.any()
        # the true sky (first panel) is black below the horizon, not above it
        margin, gap = 4, 6  # scale 1 for width 64
        top = margin + 2 * (GLYPH_HEIGHT + 3)
        panel = image[top : top + width // 2, margin : margin + width]
        upper, lower = panel[: width // 4 - 1], panel[width // 4 + 1 :]
        assert upper.mean() > 40 and lower.max() == 0
        # the SH reconstruction is not zero below the horizon (ringing: the sky's jump at the horizon)
        sh_panel = image[top : top + width // 2, margin + width + gap : margin + 2 * width + gap]
        assert sh_panel[width // 4 + 1 :].max() > 0

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
