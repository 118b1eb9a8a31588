"""
``--model hosek-wilkie`` and ``--albedo`` on ``skysh coeffs``, ``render`` and ``export`` (issue 27)
=================================================================================================

The command line's numbers against the library's (:class:`skysh.hosek_runtime.HosekWilkieSH`, radians
from the degrees typed), its refusals (one line naming the flag, status 2), and the render's true-sky
panel against :func:`skysh.model.hosek.radiance` through the same tone map.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from skysh import SkySH
from skysh.app import cli, render
from skysh.model import hosek

HOSEK = SkySH.load(model="hosek-wilkie")
SUN = ["--sun-zenith", "50", "--sun-azimuth", "-30", "--turbidity", "5"]
"""A sun and turbidity inside both models' domains."""

JSON_RTOL: float = 0.0
"""JSON writes float64 by repr: the printed numbers are the library's exactly."""


def run(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = cli.main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize("extra, kwargs", [
    ([], dict()),
    (["--albedo", "0.4", "--bands", "7"], dict(albedo=0.4, bands=7)),
    (["--albedo", "0.1,0.5,0.9", "--irradiance"], dict(albedo=(0.1, 0.5, 0.9), irradiance=True)),
    (["--no-gibbs", "--dering"], dict(gibbs=False, dering=True)),
])
def test_coeffs_are_the_runtime_s(extra, kwargs, capsys):
    code, out, err = run(["coeffs", *SUN, "--model", "hosek-wilkie", "--format", "json", *extra], capsys)
    assert code == 0, err
    payload = json.loads(out)
    expected = HOSEK.coefficients(math.radians(50), 5.0, math.radians(-30), **kwargs)
    np.testing.assert_allclose(payload["coefficients"], expected, rtol=JSON_RTOL, atol=0)
    assert payload["model"] == "hosek-wilkie"


def test_table_header_names_the_model(capsys):
    code, out, _ = run(["coeffs", *SUN, "--model", "hosek-wilkie", "--albedo", "0.2"], capsys)
    assert code == 0 and "of the Hosek-Wilkie sky (albedo 0.2)" in out.splitlines()[0]
    code, out, _ = run(["coeffs", *SUN], capsys)
    assert code == 0 and "of the Preetham sky" in out.splitlines()[0]


@pytest.mark.parametrize("argv, flag", [
    (["coeffs", "--sun-zenith", "50", "--turbidity", "10.5", "--model", "hosek-wilkie"], "--turbidity"),
    (["coeffs", "--sun-zenith", "50", "--turbidity", "1.5"], "--turbidity"),  # Preetham's domain is [2.5, 6]
    (["coeffs", *SUN, "--albedo", "0.3"], "--albedo"),  # the Preetham sky has none
    (["coeffs", *SUN, "--model", "hosek-wilkie", "--albedo", "1.2"], "--albedo"),
    (["coeffs", *SUN, "--model", "hosek-wilkie", "--sun"], "--sun"),
    (["coeffs", *SUN, "--model", "hosek-wilkie", "--sun-light"], "--sun-light"),
    (["coeffs", *SUN, "--model", "hosek-wilkie", "--ground-albedo", "0.2"], "--ground-albedo"),
    (["coeffs", *SUN, "--model", "hosek-wilkie", "--bands", "8"], "--bands"),
    (["coeffs", *SUN, "--model", "hosek"], "--model"),
    (["export", "--model", "hosek-wilkie", "--format", "c", "--out", "-", "--engine", "unity"], "--engine"),
])
def test_refusals_name_the_flag(argv, flag, capsys):
    code, out, err = run(argv, capsys)
    assert code == 2 and out == "" and err.startswith("skysh: error: ") and flag in err, err
    assert len(err.strip().splitlines()) == 1


def test_turbidity_beyond_preetham_is_hosek_s(capsys):
    """Turbidity 8 is outside the Preetham table's domain and inside the dataset's."""
    code, _, err = run(["coeffs", "--sun-zenith", "50", "--turbidity", "8"], capsys)
    assert code == 2 and "[2.5, 6]" in err
    code, _, err = run(["coeffs", "--sun-zenith", "50", "--turbidity", "8", "--model", "hosek-wilkie"], capsys)
    assert code == 0, err


def test_render_shows_the_hosek_sky(tmp_path: Path, capsys):
    out = tmp_path / "hw.png"
    code, _, err = run(["render", *SUN, "--model", "hosek-wilkie", "--albedo", "0.3", "--width", "64", "--out",
                        str(out)], capsys)
    assert code == 0 and out.stat().st_size > 0, err
    image = render.render_image(HOSEK, math.radians(50), 5.0, math.radians(-30), width=64, albedo=0.3)
    dirs = render.latlong_dirs(64)
    truth = hosek.radiance(dirs, math.radians(50), math.radians(-30), 5.0, 0.3)
    panel = render.true_hosek_sky(dirs, math.radians(50), 5.0, math.radians(-30), 0.3)
    np.testing.assert_array_equal(panel, truth)  # one albedo: the model itself
    assert image.ndim == 3 and image.shape[2] == 3


def test_true_hosek_sky_per_channel_albedo():
    dirs = render.latlong_dirs(32)
    got = render.true_hosek_sky(dirs, 0.8, 4.0, 1.0, (0.1, 0.5, 0.1))
    for channel, value in enumerate((0.1, 0.5, 0.1)):
        np.testing.assert_array_equal(got[..., channel], hosek.radiance(dirs, 0.8, 1.0, 4.0, value)[..., channel])


def test_export_writes_the_hosek_module_and_its_declarations(tmp_path: Path, capsys):
    from skysh.export import hosek as export_hosek

    out = tmp_path / "hw.mjs"
    code, printed, err = run(["export", "--model", "hosek-wilkie", "--format", "js", "--bands", "3", "--out", str(out)],
                             capsys)
    assert code == 0, err
    assert out.read_text(encoding="utf-8") == export_hosek.export_source("js", bands=3)
    assert (tmp_path / "hw.d.mts").read_text(encoding="utf-8") == export_hosek.declarations(3)
    code, printed, err = run(["export", "--model", "hosek-wilkie", "--format", "c", "--out", "-"], capsys)
    assert code == 0 and printed == export_hosek.export_source("c"), err


@pytest.mark.parametrize("language", ["glsl", "hlsl", "json"])
def test_export_refuses_what_the_hosek_export_does_not_write(language, tmp_path: Path, capsys):
    out = tmp_path / "hw.txt"
    code, _, err = run(["export", "--model", "hosek-wilkie", "--format", language, "--out", str(out)], capsys)
    assert code == 2 and language in err and "Use language 'c' or 'js'" in err and not out.exists(), err
