"""
Tests of the ``skysh`` command line (skysh.app.cli): every number it prints is the
runtime's, degrees are converted, refusals are one line with status 2.

Most tests call :func:`skysh.app.cli.main` in-process (fast); a few run the real
``python -m skysh`` in a subprocess to see the exit status and that no
traceback escapes. Those subprocesses (:data:`COMMANDS`, the quiet-without-matplotlib
programs and the ``skysh view`` server) all start in the background when the module
begins (background.Prefetched); the tests that wait for them are marked ``late``, so the
in-process tests overlap them.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from background import Prefetched, prefetched, server_session, start_early

from skysh import SkySH
from skysh.app import cli
from skysh.lighting import sun
from skysh.sh import basis as sh

ROOT = Path(__file__).resolve().parents[2]

EXACT: float = 1e-12
"""Relative tolerance for numbers printed at full precision (repr round-trips:
the only differences are the radians conversion, done the same way)."""

SUN = ["--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3"]
"""A sun in the middle of the domain (degrees)."""

VIENNA = ["--lat", "48.21", "--lon", "16.37", "--time", "2024-06-21T13:00:00+02:00"]

SUBPROCESS_TIMEOUT_S: float = 180.0
"""Hang guard of each subprocess (imports, loading the coefficient file and colour-science on a shared machine)."""

TIMES_BEYOND: list[str] = ["0001-01-01T00:00:00+05:00", "9999-12-31T23:59:59-14:00"]
"""Times whose UTC lies outside datetime's range (years 1 to 9999)."""

COMMANDS: dict[str, list[str]] = {
    "turbidity 9": ["coeffs", "--sun-zenith", "30", "--turbidity", "9"],
    "version": ["--version"],
    **{f"time {when}": ["coeffs", "--lat", "0", "--lon", "0", "--time", when, "--turbidity", "3"] for when in TIMES_BEYOND},
}
"""``python -m skysh`` command lines run as real commands, by name."""

NO_MATPLOTLIB = "import sys; sys.modules['matplotlib'] = None  # a plain install: colour-science without matplotlib\n"
"""Prefix of a subprocess script that makes ``import matplotlib`` fail, as on a fresh machine."""

QUIET_COMMANDS: dict[str, list[str]] = {
    "coeffs --colourspace": ["coeffs", *SUN, "--colourspace", "ACEScg"],
    "render": ["render", *SUN, "--width", "16", "--out", "OUT"],
}
"""Commands that import colour-science, run by TestQuietWithoutMatplotlib (OUT: a PNG in a temporary folder)."""


def run_without_matplotlib(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", NO_MATPLOTLIB + code], capture_output=True, text=True, cwd=ROOT,
                          timeout=SUBPROCESS_TIMEOUT_S, check=False)


def run_skysh(argv: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "skysh", *argv], capture_output=True, text=True, cwd=ROOT,
                          timeout=SUBPROCESS_TIMEOUT_S, check=False)


@pytest.fixture(scope="module")
def commands(request: pytest.FixtureRequest) -> Iterator[Prefetched[subprocess.CompletedProcess]]:
    """Every command of :data:`COMMANDS`, as a real ``python -m skysh``, in the background from the module's start."""
    yield from prefetched(request, {name: functools.partial(run_skysh, argv) for name, argv in COMMANDS.items()})


@pytest.fixture(scope="module")
def quiet_runs(request: pytest.FixtureRequest,
               tmp_path_factory: pytest.TempPathFactory) -> Iterator[Prefetched[subprocess.CompletedProcess]]:
    """The programs of TestQuietWithoutMatplotlib (``shim``: colour-science alone; each of :data:`QUIET_COMMANDS`,
    its PNG in a temporary folder), in the background from the module's start (each mostly imports colour-science)."""
    png = str(tmp_path_factory.mktemp("quiet") / "sky.png")
    jobs = {"shim": functools.partial(run_without_matplotlib, "import colour")}
    for name, argv in QUIET_COMMANDS.items():
        argv = [png if a == "OUT" else a for a in argv]
        jobs[name] = functools.partial(run_without_matplotlib, f"from skysh.app import cli; raise SystemExit(cli.main({argv!r}))")
    yield from prefetched(request, jobs)


@pytest.fixture(scope="module")
def view_run(request: pytest.FixtureRequest) -> Iterator[Prefetched[dict[str, Any]]]:
    """``python -m skysh view --port 0`` (background.server_session), in the background from the module's start."""
    argv = [sys.executable, "-m", "skysh", "view", "--port", "0"]
    yield from prefetched(request, {"view": functools.partial(server_session, argv, ROOT)})


@pytest.fixture(scope="module", autouse=True)
def _start_early(request: pytest.FixtureRequest) -> None:
    start_early(request, "commands", "quiet_runs", "view_run")


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
        argv = ["coeffs", "--lat", "48.21", "--lon", "16.37", "--time", "2024-06-21T01:00:00+02:00", "--turbidity", "3"]
        code, out, err = run(argv, capsys)
        assert code == 2 and out == ""
        assert err.count("\n") == 1 and "below the horizon" in err

    def test_unwritable_output(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["export", "--format", "c", "--out", str(tmp_path / "missing" / "sky.h")], capsys)
        assert code == 2 and err.startswith("skysh: error: ") and err.count("\n") == 1

    @pytest.mark.late
    def test_no_traceback_from_the_real_command(self, commands: Prefetched[subprocess.CompletedProcess]) -> None:
        result = commands.result("turbidity 9")
        assert result.returncode == 2 and result.stdout == ""
        assert result.stderr == "skysh: error: --turbidity must lie in [2.5, 6] (the fitted domain), got 9\n"


class TestHelp:
    @pytest.mark.parametrize(
        "command, needles",
        [
            ([], ["coeffs", "export", "render", "fit", "report", "degrees", "cd/m^2", "status 2"]),
            (["coeffs"], ["degrees, [0, 90]", "[2.5, 6]", "[1, 7]", "cd/m^2*sr", "--normalise", "R, G and B", "[-90, 90]",
                          "ISO8601"]),
            (["export"], ["radians", "[2.5, 6]", "float32", "double", "[1, 7]", "skysh_sun_light", "ground_albedo",
                          "groundAlbedo"]),
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

    @pytest.mark.late
    def test_python_m_skysh(self, commands: Prefetched[subprocess.CompletedProcess]) -> None:
        result = commands.result("version")
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

    def test_installed_package_says_tools_need_a_checkout(
        self, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
    ) -> None:
        monkeypatch.setattr(cli, "_tools_dir", lambda: None)
        assert cli.main(["report", "--quick"]) == 2
        err = capsys.readouterr().err
        assert "source checkout" in err and err.count("\n") == 1
        assert cli.main(["fit", "--help"]) == 0  # the fit is the package's: it runs without a checkout
        assert "--out" in capsys.readouterr().out


# --------------------------------------------------------------------------- #
# What a new user meets (issue 13): labels that say one true thing, no noise
# --------------------------------------------------------------------------- #
class TestLabels:
    def test_y_up_header_describes_the_y_up_frame(self, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--up", "y"], capsys)
        header = "\n".join(line for line in out.splitlines() if line.startswith("#"))
        assert "Y up (zenith +Y)" in header and "Z up" not in header and "to_y_up" in header
        _, out, _ = run(["coeffs", *SUN], capsys)
        assert "Z up (zenith)" in out and "Y up" not in out

    def test_one_band_is_singular(self, capsys: pytest.CaptureFixture) -> None:
        _, out, _ = run(["coeffs", *SUN, "--bands", "1"], capsys)
        assert ", 1 band;" in out and "1 bands" not in out
        _, out, _ = run(["coeffs", *SUN, "--bands", "2"], capsys)
        assert ", 2 bands;" in out

    @pytest.mark.parametrize(("zenith", "azimuth"), [("30", "45"), ("12.3456789012345", "-0.1"), ("0", "720")])
    def test_degrees_are_echoed_as_given(self, zenith: str, azimuth: str, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json(["--sun-zenith", zenith, "--sun-azimuth", azimuth, "--turbidity", "3"], capsys)
        assert payload["sun_zenith_deg"] == float(zenith) and payload["sun_azimuth_deg"] == float(azimuth)
        assert payload["sun_zenith_rad"] == math.radians(float(zenith))  # computed from the degrees given
        _, out, _ = run(["coeffs", "--sun-zenith", zenith, "--sun-azimuth", azimuth, "--turbidity", "3"], capsys)
        assert f"sun zenith {zenith} deg, azimuth {azimuth} deg" in out

    def test_refusal_prints_the_value_given(self, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["coeffs", "--sun-zenith", "90.0000001", "--turbidity", "3"], capsys)
        assert code == 2 and "got 90.0000001" in err
        code, _, err = run(["coeffs", "--sun-zenith", "30", "--turbidity", "6.0000000001"], capsys)
        assert code == 2 and "got 6.0000000001" in err

    def test_table_prints_rounding_noise_as_zero(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        """--up y at azimuth 0: (1,0), (2,-1), (2,1) are zero up to the rotation's rounding."""
        argv = ["--sun-zenith", "30", "--sun-azimuth", "0", "--turbidity", "3", "--up", "y"]
        exact = sh.to_y_up(sky.coefficients(math.radians(30), 3.0, 0.0))
        noise = np.abs(exact[[2, 5, 7]]).max() / np.abs(exact[0]).max()
        assert noise < cli.TABLE_ZERO_BELOW  # rounding noise: far below the threshold
        payload = coeffs_json(argv, capsys)
        np.testing.assert_array_equal(payload["coefficients"], exact)  # JSON keeps every digit
        _, out, _ = run(["coeffs", *argv], capsys)
        rows = [line.split() for line in out.splitlines() if line and not line.startswith("#")][1:]
        assert all(value == "0" for i in (2, 5, 7) for value in rows[i][3:])
        assert all(value != "0" for i in (0, 1, 3, 4, 6, 8) for value in rows[i][3:])
        assert f"below {cli.TABLE_ZERO_BELOW:g} x |DC|" in out

    @pytest.mark.parametrize(("factor", "fmt", "needle"), [("1e308", "json", "overflow float64"),
                                                           ("1e36", "glsl", "overflow float32"),
                                                           ("1e-320", "json", "underflows"),  # refused as read: argtypes.real
                                                           ("1e-50", "hlsl", "underflow float32")])
    def test_exposure_that_overflows_is_refused(self, factor: str, fmt: str, needle: str,
                                                capsys: pytest.CaptureFixture) -> None:
        code, out, err = run(["coeffs", *SUN, "--exposure", factor, "--format", fmt], capsys)
        assert code == 2 and out == "" and "--exposure" in err and needle in err, err

    def test_largest_exposure_that_fits_is_accepted(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        """Negative control of the refusal above: a factor just within float64 passes, finite."""
        largest = np.abs(reference(sky)).max()
        factor = repr(float(np.finfo(np.float64).max / largest / 2))
        payload = coeffs_json([*SUN, "--exposure", factor], capsys)
        assert np.all(np.isfinite(payload["coefficients"]))

    @pytest.mark.late
    @pytest.mark.parametrize("when", TIMES_BEYOND)
    def test_time_beyond_the_datetime_range_is_one_line(self, when: str,
                                                        commands: Prefetched[subprocess.CompletedProcess]) -> None:
        result = commands.result(f"time {when}")
        assert result.returncode == 2 and result.stdout == "" and "Traceback" not in result.stderr
        assert result.stderr.startswith("skysh: error: --time must lie in") and result.stderr.count("\n") == 1

    def test_an_unexpected_failure_is_one_line(self, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture) -> None:
        def broken(args: object) -> int:
            raise RuntimeError("something\nunforeseen")

        parser = cli.build_parser()
        monkeypatch.setattr(cli, "build_parser", lambda: parser)
        parser._subparsers._group_actions[0].choices["coeffs"].set_defaults(handler=broken)  # type: ignore[union-attr]
        code, out, err = run(["coeffs", *SUN], capsys)
        assert code == cli.EXIT_INTERNAL and out == ""
        assert err == "skysh: internal error: RuntimeError: something unforeseen (please report it with the command line)\n"

    def test_render_names_its_output_flag(self, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["render", *SUN, "--width", "16", "--out", "/nonexistent-dir/sky.png"], capsys)
        assert code == 2 and err.startswith("skysh: error: --out /nonexistent-dir/sky.png: ") and err.count("\n") == 1


@pytest.mark.late
class TestQuietWithoutMatplotlib:
    """colour-science warns on import when matplotlib is missing; skysh's commands stay quiet."""

    def test_the_shim_makes_colour_science_warn(self, quiet_runs: Prefetched[subprocess.CompletedProcess]) -> None:
        """Negative control: without skysh's filter the warning is there, so the tests below can see it."""
        result = quiet_runs.result("shim")
        assert "Matplotlib" in result.stderr and "not available" in result.stderr

    @pytest.mark.parametrize("name", list(QUIET_COMMANDS))
    def test_commands(self, name: str, quiet_runs: Prefetched[subprocess.CompletedProcess]) -> None:
        result = quiet_runs.result(name)
        assert result.returncode == 0 and result.stderr == "", result.stderr


# --------------------------------------------------------------------------- #
# The sun and the ground (issue 15)
# --------------------------------------------------------------------------- #
class TestSunAndGround:
    @pytest.mark.parametrize("albedo, value", [("0.3", 0.3), ("0.2,0.3,0.4", (0.2, 0.3, 0.4))])
    def test_coeffs_with_the_sun_and_the_ground(self, sky: SkySH, albedo: str, value: object,
                                                capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--sun", "--ground-albedo", albedo], capsys)
        expected = reference(sky, sun=True, ground_albedo=value)
        np.testing.assert_allclose(payload["coefficients"], expected, rtol=0, atol=EXACT * np.abs(expected).max())
        assert payload["sun"] is True and np.allclose(payload["ground_albedo"], value)
        code, out, _ = run(["coeffs", *SUN, "--sun", "--ground-albedo", albedo], capsys)
        assert code == 0 and "the sun's disk" in out.splitlines()[0] and "ground albedo" in out.splitlines()[0]

    def test_engine_takes_the_lit_radiance(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        from skysh.engines import presets as engines

        payload = coeffs_json([*SUN, "--sun", "--ground-albedo", "0.25", "--engine", "threejs"], capsys)
        radiance = reference(sky, sun=True, ground_albedo=0.25, gibbs=False, dering=True, irradiance_table=True)
        expected = engines.convert(radiance, "threejs")  # 3-band presets: the certified irradiance table
        np.testing.assert_allclose(payload["values"], expected, rtol=0, atol=EXACT * np.abs(expected).max())

    def test_sun_light(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        payload = coeffs_json([*SUN, "--sun-light"], capsys)
        direction, rgb = sky.sun_light(math.radians(30), 3.0, math.radians(45))
        np.testing.assert_allclose(payload["sun_direction"], direction, rtol=0, atol=1e-15)
        np.testing.assert_allclose(payload["sun_illuminance"], rgb, rtol=EXACT)
        assert payload["units"] == "lux" and "directional light" in payload["quantity"]

    def test_sun_light_frames(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        from skysh.engines import presets as engines

        direction = sky.sun_light(math.radians(30), 3.0, math.radians(45))[0]
        y_up = coeffs_json([*SUN, "--sun-light", "--up", "y"], capsys)["sun_direction"]
        np.testing.assert_allclose(y_up, sh.Y_UP_MATRIX @ direction, rtol=0, atol=1e-15)
        assert y_up[1] == pytest.approx(math.cos(math.radians(30)))  # the zenith is +Y
        for engine in ("threejs", "unity", "unreal"):
            got = coeffs_json([*SUN, "--sun-light", "--engine", engine], capsys)["sun_direction"]
            expected = engines.sun_direction(math.radians(30), math.radians(45), engine)
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)

    def test_sun_light_scales_as_the_coefficients(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        rgb = sky.sun_light(math.radians(30), 3.0, math.radians(45))[1]
        exposed = coeffs_json([*SUN, "--sun-light", "--exposure", "0.001"], capsys)["sun_illuminance"]
        np.testing.assert_allclose(exposed, 0.001 * rgb, rtol=EXACT)
        normalised = coeffs_json([*SUN, "--sun-light", "--normalise", "--irradiance"], capsys)["sun_illuminance"]
        factor = cli.normalise_factor(reference(sky, irradiance=True), True)
        np.testing.assert_allclose(normalised, factor * rgb, rtol=EXACT)

    @pytest.mark.parametrize("fmt", ["table", "csv", "glsl", "hlsl", "c"])
    def test_sun_light_formats(self, sky: SkySH, fmt: str, capsys: pytest.CaptureFixture) -> None:
        code, out, err = run(["coeffs", *SUN, "--sun-light", "--format", fmt], capsys)
        assert code == 0, err
        rgb = sky.sun_light(math.radians(30), 3.0, math.radians(45))[1]
        numbers = [float(v) for v in re.findall(r"-?\d+\.\d*(?:e[+-]?\d+)?", out.split("illuminance")[-1]
                                                      if fmt == "table" else out.split("ILLUMINANCE")[-1]
                                                      if fmt != "csv" else out.splitlines()[-1])]
        rtol = 1e-6 if fmt in ("table", "glsl", "hlsl") else EXACT  # 7 digits or float32
        np.testing.assert_allclose(numbers[-3:], rgb, rtol=rtol)

    @pytest.mark.parametrize("argv, needle", [
        (["--ground-albedo", "1.5"], "--ground-albedo"), (["--ground-albedo", "0.1,0.2"], "--ground-albedo"),
        (["--ground-albedo", "nan"], "--ground-albedo"), (["--ground-albedo", "red"], "--ground-albedo"),
        (["--ground-albedo", "0.1,0.2,-0.3"], "--ground-albedo"), (["--sun-light", "--sun"], "--sun-light"),
        (["--sun-light", "--format", "snippet"], "--engine"),
    ])
    def test_refusals(self, argv: list[str], needle: str, capsys: pytest.CaptureFixture) -> None:
        code, out, err = run(["coeffs", *SUN, *argv], capsys)
        assert code == 2 and out == "" and err.startswith("skysh: error: ") and err.count("\n") == 1
        assert needle in err

    def test_sun_light_for_an_engine(self, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        """--engine adds the engine's light colour and intensity (skysh.engines.sun); --format snippet sets its light."""
        from skysh.engines import sun as engine_sun

        direction, rgb = sky.sun_light(math.radians(30), 3.0, math.radians(45))
        payload = coeffs_json([*SUN, "--sun-light", "--engine", "unity"], capsys)
        preset = engine_sun.sun_preset(direction, rgb, "unity")
        np.testing.assert_allclose(payload["engine_light_colour"], preset.colour, rtol=EXACT)
        assert payload["engine_light_intensity"] == pytest.approx(preset.intensity, rel=EXACT)
        assert payload["engine_light_intensity_unit"].startswith("cd/m^2")
        code, out, err = run(["coeffs", *SUN, "--sun-light", "--engine", "babylon", "--format", "snippet"], capsys)
        assert code == 0, err
        assert out == engine_sun.sun_snippet(direction, rgb, "babylon") + "\n"

    def test_export_carries_the_sun_and_the_ground(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        for fmt, needles in (("c", ("skysh_sun_light(", "const skysh_real *ground_albedo")),
                             ("glsl", ("bool skysh_sun_light(", "vec3 groundAlbedo")),
                             ("js", ("export function sunLight(", '"groundAlbedo"'))):
            out = tmp_path / f"sky.{fmt}"
            code, _, err = run(["export", "--format", fmt, "--bands", "2", "--out", str(out)], capsys)
            assert code == 0, err
            assert all(needle in out.read_text() for needle in needles), fmt

    def test_render_with_the_sun_and_the_ground(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        out = tmp_path / "scene.png"
        code, stdout, err = run(["render", *SUN, "--sun", "--ground-albedo", "0.3,0.2,0.1", "--width", "32",
                                 "--out", str(out)], capsys)
        assert code == 0, err
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and "wrote" in stdout


class TestView:
    def test_out_writes_the_page(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        status, out, _ = run(["view", "--out", str(tmp_path / "page")], capsys)
        assert status == 0 and (tmp_path / "page" / "index.html").is_file()
        assert (tmp_path / "page" / "index.html").resolve().as_uri() in out

    def test_port_with_out_is_refused(self, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
        status, _, err = run(["view", "--out", str(tmp_path), "--port", "8000"], capsys)
        assert status == cli.EXIT_USAGE and "--port" in err and err.count("\n") == 1

    @pytest.mark.late
    def test_serves_on_loopback_and_stops_on_ctrl_c(self, view_run: Prefetched[dict[str, Any]]) -> None:
        session = view_run.result("view")
        assert re.search(r"http://127\.0\.0\.1:\d+/", session["line"]), session["line"]
        assert session["status"] == 200 and b"<html" in session["body"].lower()
        assert session["code"] == 0, session["err"]


# --------------------------------------------------------------------------- #
# Numbers on the command line (skysh.app.argtypes)
# --------------------------------------------------------------------------- #
NOT_ASCII_DECIMAL: list[str] = ["\uff13\uff10", "\u0663", "1_0", " 30", "30 ", "0x1e", "inf", "-inf", "nan", "1e", "--3",
                                 "3,0", ""]
"""Texts Python's float() or int() would take (fullwidth and Arabic-Indic digits, underscores, spaces,
inf, nan) or that are no number at all: each is refused by flag."""


class TestNumbers:
    @pytest.mark.parametrize("text", NOT_ASCII_DECIMAL)
    @pytest.mark.parametrize("flag", ["--sun-zenith", "--turbidity", "--exposure"])
    def test_only_ascii_decimal(self, flag: str, text: str, capsys: pytest.CaptureFixture) -> None:
        argv = {"--sun-zenith": ["--sun-zenith", text, "--turbidity", "3"],
                "--turbidity": ["--sun-zenith", "30", "--turbidity", text],
                "--exposure": [*SUN, "--exposure", text]}[flag]
        code, out, err = run(["coeffs", *argv], capsys)
        assert code == 2 and out == "" and f"argument {flag}: expected" in err and err.count("\n") == 1, err

    @pytest.mark.parametrize(("text", "needle"), [("1e-400", "underflows"), ("-1e-320", "underflows"),
                                                  ("1e400", "overflows"), ("-1e309", "overflows")])
    def test_underflow_and_overflow_are_refused(self, text: str, needle: str, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["coeffs", "--sun-zenith", "30", f"--sun-azimuth={text}", "--turbidity", "3"], capsys)
        assert code == 2 and "argument --sun-azimuth" in err and needle in err, err

    @pytest.mark.parametrize("text", ["30", "+30", "30.", "30.0", "3e1", "3E+1", ".3e2", "300e-1"])
    def test_every_ascii_form_reads_the_same(self, text: str, sky: SkySH, capsys: pytest.CaptureFixture) -> None:
        """Negative control of the refusals: the forms float() shares with a C strtod read exactly."""
        payload = coeffs_json(["--sun-zenith", text, "--turbidity", "3"], capsys)
        assert payload["sun_zenith_deg"] == 30.0

    def test_zero_written_small_is_zero(self, capsys: pytest.CaptureFixture) -> None:
        """'0e-999' is zero as written, not an underflow."""
        payload = coeffs_json(["--sun-zenith", "30", "--sun-azimuth", "0e-999", "--turbidity", "3"], capsys)
        assert payload["sun_azimuth_deg"] == 0.0

    @pytest.mark.parametrize("text", ["-5", "65536", "\u0663", "1_0", "80.0"])  # Arabic-Indic 3
    def test_port_is_named(self, text: str, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["view", "--port", text], capsys)
        assert code == 2 and "argument --port: expected an integer in [0, 65535]" in err, err

    @pytest.mark.parametrize("text", ["\uff13", "1_0", "+", "3.0"])  # fullwidth 3
    def test_integers_are_ascii(self, text: str, capsys: pytest.CaptureFixture) -> None:
        code, _, err = run(["coeffs", *SUN, "--bands", text], capsys)
        assert code == 2 and "argument --bands: expected a positive integer" in err, err


class TestToolsWithoutTheirExtra:
    def test_a_missing_tool_dependency_is_one_line(self, tmp_path: Path) -> None:
        """`skysh fit`/`skysh report` need the tools extra for some work: a missing package is named with the
        command that installs it, exit 2, no traceback (here: matplotlib made unimportable)."""
        code = ("import sys; sys.modules['matplotlib'] = None; sys.modules['matplotlib.pyplot'] = None\n"
                "from skysh.app.cli import main; sys.exit(main(['report', '--quick', '--out', sys.argv[1]]))")
        done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "r")], capture_output=True, text=True, cwd=ROOT,
                              timeout=SUBPROCESS_TIMEOUT_S, check=False)
        assert "Traceback" not in done.stderr, done.stderr
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert "'matplotlib'" in done.stderr and 'pip install -e ".[tools]"' in done.stderr, done.stderr
