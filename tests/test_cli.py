"""
Tests of the ``skysh`` command line (skysh.cli): every number it prints is the
runtime's, degrees are converted, refusals are one line with status 2.

Most tests call :func:`skysh.cli.main` in-process (fast); a few run the real
``python -m skysh`` in a subprocess to see the exit status and that no
traceback escapes.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from skysh import SkySH, cli, sh, sun

ROOT = Path(__file__).resolve().parent.parent

EXACT: float = 1e-12
"""Relative tolerance for numbers printed at full precision (repr round-trips:
the only differences are the radians conversion, done the same way)."""

SUN = ["--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3"]
"""A sun in the middle of the domain (degrees)."""

VIENNA = ["--lat", "48.21", "--lon", "16.37", "--time", "2024-06-21T13:00:00+02:00"]


@pytest.fixture(scope="module")
def sky() -> SkySH:
    return SkySH.load()


def run(argv: list[str], capsys: pytest.CaptureFixture) -> tuple[int, str, str]:
    code = cli.main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def coeffs_json(argv: list[str], capsys: pytest.CaptureFixture) -> dict:
    code, out, err = run(["coeffs", *argv, "--format", "json"], capsys)
    assert code == 0, err
    return json.loads(out)


def reference(sky: SkySH, zenith_deg: float = 30.0, azimuth_deg: float = 45.0, turbidity: float = 3.0, **kwargs) -> np.ndarray:
    return sky.coefficients(math.radians(zenith_deg), turbidity, math.radians(azimuth_deg), **kwargs)


class TestCoeffsValues:
    def test_json_is_the_runtime(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json(SUN, capsys)
        np.testing.assert_allclose(payload["coefficients"], reference(sky), rtol=EXACT, atol=0)
        assert payload["lm"] == [list(sh.lm(i)) for i in range(9)]
        assert payload["units"] == "cd/m^2" and payload["colourspace"] == "sRGB"
        assert payload["sun_zenith_deg"] == pytest.approx(30.0) and payload["sun_azimuth_rad"] == pytest.approx(math.pi / 4)
        assert "Condon-Shortley" in payload["convention"] and payload["quantity"] == "radiance"

    @pytest.mark.parametrize("bands", [1, 2, 5, 7])
    def test_bands(self, sky: SkySH, bands: int, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--bands", str(bands)], capsys)
        np.testing.assert_allclose(payload["coefficients"], reference(sky, bands=bands), rtol=EXACT, atol=0)

    def test_irradiance_no_gibbs_dering(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--irradiance", "--no-gibbs", "--dering"], capsys)
        expected = reference(sky, irradiance=True, gibbs=False, dering=True)
        np.testing.assert_allclose(payload["coefficients"], expected, rtol=EXACT, atol=0)
        assert payload["units"] == "cd/m^2*sr" and payload["quantity"] == "irradiance"
        assert payload["gibbs"] is False and payload["dering"] is True

    def test_y_up(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--up", "y"], capsys)
        expected = sh.to_y_up(reference(sky))
        scale = np.abs(expected[0]).max()
        np.testing.assert_allclose(payload["coefficients"], expected, rtol=0, atol=EXACT * scale)
        # the zenith (+Z in skysh) is +Y for the engine: same radiance there
        y_up = np.array(payload["coefficients"])
        np.testing.assert_allclose(sh.evaluate(y_up, [0.0, 1.0, 0.0]), sh.evaluate(reference(sky), [0.0, 0.0, 1.0]), rtol=1e-10)

    def test_exposure_multiplies(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--exposure", "0.25"], capsys)
        np.testing.assert_allclose(payload["coefficients"], 0.25 * reference(sky), rtol=EXACT, atol=0)
        assert payload["scale"] == 0.25 and "x 0.25" in payload["units"]

    @pytest.mark.parametrize("irradiance", [False, True])
    def test_normalise_makes_the_irradiance_dc_one(self, sky: SkySH, irradiance: bool, capsys: pytest.CaptureFixture) -> None:
        extra = ["--irradiance"] if irradiance else []
        c = np.array(coeffs_json([*SUN, "--normalise", *extra], capsys)["coefficients"])
        irradiance_dc = c[0] if irradiance else math.pi * c[0]  # E(0,0) = A_0 L(0,0)
        assert irradiance_dc.mean() == pytest.approx(1.0, rel=1e-14)
        # only a scale: proportional to the runtime's result
        expected = reference(sky, irradiance=irradiance)
        np.testing.assert_allclose(c / c[0, 0], expected / expected[0, 0], rtol=1e-12)

    def test_colourspace(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--colourspace", "ITU-R BT.2020"], capsys)
        expected = reference(sky, colourspace="ITU-R BT.2020")
        np.testing.assert_allclose(payload["coefficients"], expected, rtol=EXACT, atol=EXACT * np.abs(expected).max())
        assert payload["colourspace"] == "ITU-R BT.2020"

    def test_place_and_time(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*VIENNA, "--turbidity", "3"], capsys)
        zenith, azimuth = sun.position(48.21, 16.37, "2024-06-21T13:00:00+02:00")
        np.testing.assert_allclose(
            payload["coefficients"], sky.coefficients(float(zenith), 3.0, float(azimuth)), rtol=EXACT, atol=0
        )
        assert payload["place"] == {"lat": 48.21, "lon": 16.37, "time": "2024-06-21T13:00:00+02:00"}
        assert payload["sun_zenith_rad"] == pytest.approx(float(zenith), rel=1e-15)

    def test_default_azimuth_is_zero(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json(["--sun-zenith", "90", "--turbidity", "6"], capsys)  # the domain's corner
        np.testing.assert_allclose(payload["coefficients"], reference(sky, 90.0, 0.0, 6.0), rtol=EXACT, atol=0)


class TestCoeffsFormats:
    def test_table(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        code, out, _ = run(["coeffs", *SUN], capsys)
        assert code == 0
        lines = out.splitlines()
        comments = [line for line in lines if line.startswith("#")]
        assert any("units: cd/m^2" in line for line in comments) and any("sRGB" in line for line in comments)
        header = next(line for line in lines if not line.startswith("#"))
        assert header.split() == ["i", "l", "m", "R", "G", "B"]
        rows = [line.split() for line in lines[lines.index(header) + 1 :]]
        assert [(int(r[1]), int(r[2])) for r in rows] == [sh.lm(i) for i in range(9)]
        np.testing.assert_allclose(np.array([r[3:] for r in rows], float), reference(sky), rtol=1e-6, atol=1e-9)

    def test_table_irradiance_units(self, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--irradiance"], capsys)
        assert "units: cd/m^2*sr" in out and "irradiance SH" in out

    def test_csv(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--format", "csv"], capsys)
        rows = list(csv.DictReader(io.StringIO(out)))
        assert [(int(r["l"]), int(r["m"])) for r in rows] == [sh.lm(i) for i in range(9)]
        np.testing.assert_allclose([[float(r[c]) for c in "RGB"] for r in rows], reference(sky), rtol=EXACT, atol=0)

    @pytest.mark.parametrize("fmt", ["glsl", "hlsl"])
    def test_shader_arrays_are_float32(self, sky: SkySH, fmt: str, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--format", fmt], capsys)
        vec3 = "vec3" if fmt == "glsl" else "float3"
        assert f"{vec3} SKY_SH[9]" in out
        triples = re.findall(rf"{vec3}\(([^()]*)\)", out)
        values = np.array([[np.float32(v) for v in t.split(",")] for t in triples])
        np.testing.assert_array_equal(values, reference(sky).astype(np.float32))

    def test_c_array_is_double(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--format", "c"], capsys)
        assert "static const double SKY_SH[9][3]" in out
        triples = re.findall(r"\{([^{}]*)\},", out)
        np.testing.assert_array_equal(np.array([[float(v) for v in t.split(",")] for t in triples]), reference(sky))


class TestRefusals:
    @pytest.mark.parametrize(
        "argv",
        [
            ["coeffs", "--sun-zenith", "95", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "-1", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "2"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "6.5"],
            ["coeffs", "--sun-zenith", "nan", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "30", "--sun-azimuth", "inf", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "abc", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--bands", "8"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--bands", "0"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--colourspace", "no such space"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--exposure", "0"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--exposure", "2", "--normalise"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--format", "xml"],
            ["coeffs", "--sun-zenith", "30", "--turbidity", "3", "--up", "x"],
            ["coeffs", "--turbidity", "3"],
            ["coeffs", "--sun-zenith", "30"],
            ["coeffs", "--sun-zenith", "30", *VIENNA, "--turbidity", "3"],
            ["coeffs", "--lat", "48", "--lon", "16", "--turbidity", "3"],
            ["coeffs", "--lat", "91", "--lon", "16", "--time", "2024-06-21T12:00:00Z", "--turbidity", "3"],
            ["coeffs", "--lat", "48", "--lon", "16", "--time", "2024-06-21T12:00:00", "--turbidity", "3"],
            ["coeffs", "--lat", "48", "--lon", "16", "--time", "yesterday", "--turbidity", "3"],
            ["render", "--sun-zenith", "30", "--turbidity", "3", "--out", "x.png", "--width", "8"],
            ["nonsense"],
            [],
        ],
    )
    def test_one_line_and_status_2(self, argv: list[str], capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(argv, capsys)
        assert code == 2
        assert err.startswith("skysh: error: ") and err.count("\n") == 1, err

    def test_sun_below_the_horizon(self, capsys: pytest.CaptureFixture) -> None:
        code, out, err = run(["coeffs", "--lat", "48.21", "--lon", "16.37", "--time", "2024-06-21T01:00:00+02:00", "--turbidity", "3"], capsys)
        assert code == 2 and out == ""
        assert err.count("\n") == 1 and "below the horizon" in err

    def test_unwritable_output(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["export", "--format", "c", "--out", str(tmp_path / "missing" / "sky.h")], capsys)
        assert code == 2 and err.startswith("skysh: error: ") and err.count("\n") == 1

    def test_no_traceback_from_the_real_command(self) -> None:
        result = subprocess.run(
            [sys.executable, "-m", "skysh", "coeffs", "--sun-zenith", "30", "--turbidity", "9"],
            capture_output=True, text=True, cwd=ROOT,
        )
        assert result.returncode == 2 and result.stdout == ""
        assert result.stderr == "skysh: error: --turbidity must lie in [2.5, 6] (the fitted domain), got 9\n"


class TestHelp:
    @pytest.mark.parametrize(
        "command, needles",
        [
            ([], ["coeffs", "export", "render", "fit", "report", "degrees", "cd/m^2", "status 2"]),
            (["coeffs"], ["degrees, [0, 90]", "[2.5, 6]", "[1, 7]", "cd/m^2*sr", "--normalise", "R, G and B", "[-90, 90]", "ISO8601"]),
            (["export"], ["radians", "[2.5, 6]", "float32", "double", "[1, 7]"]),
            (["render"], ["degrees, [0, 90]", "[2.5, 6]", "[16, 4096]", "azimuth -180"]),
        ],
    )
    def test_help_states_units_and_ranges(self, command: list[str], needles: list[str], capsys: pytest.CaptureFixture) -> None:
        with pytest.raises(SystemExit) as exit_:
            cli.main([*command, "--help"])
        assert exit_.value.code == 0
        text = " ".join(capsys.readouterr().out.split())  # argparse wraps lines
        for needle in needles:
            assert needle in text, needle

    def test_python_m_skysh(self) -> None:
        result = subprocess.run([sys.executable, "-m", "skysh", "--version"], capture_output=True, text=True, cwd=ROOT)
        assert result.returncode == 0 and result.stdout.startswith("skysh 0.")


class TestTools:
    def test_fit_runs_the_tool(self, capsys: pytest.CaptureFixture) -> None:
        assert cli.main(["fit", "--help"]) == 0
        out = capsys.readouterr().out
        assert "skysh fit" in out and "--tolerance" in out  # tools/fit_sky.py's own help

    def test_fit_tool_refusal_keeps_its_status(self, capsys: pytest.CaptureFixture) -> None:
        assert cli.main(["fit", "--samples", "0", "--out", "/tmp/never.npz"]) == 2
        assert "--samples" in capsys.readouterr().err

    def test_report(self, capsys: pytest.CaptureFixture) -> None:
        if (ROOT / "tools" / "error_report.py").is_file():
            assert cli.main(["report", "--help"]) == 0
            assert "skysh report" in capsys.readouterr().out
        else:
            assert cli.main(["report"]) == 2
            err = capsys.readouterr().err
            assert "tools/error_report.py" in err and err.count("\n") == 1

    def test_installed_package_says_tools_need_a_checkout(self, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
        monkeypatch.setattr(cli, "_tools_dir", lambda: None)
        assert cli.main(["fit", "--quick"]) == 2
        err = capsys.readouterr().err
        assert "source checkout" in err and err.count("\n") == 1
