"""The wheel installs into a fresh virtual environment and runs there, data file included.

The wheel is conftest's session fixture ``wheel`` (built once, shared with
``tests/test_wheel.py``). The environment uses ``--system-site-packages`` so numpy,
scipy, colour-science and pip come from the test machine (no network needed, no
pip bootstrap); skysh itself is installed from the wheel only (``--no-deps --no-index``) and run from a directory outside the
repository, so nothing can be imported from the source tree.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import venv
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, environment_without_pythonpath

from skysh import SkySH

pytestmark = pytest.mark.integration  # builds a wheel with setuptools and installs it with pip into a venv


@pytest.fixture(scope="module")
def installed(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh venv (no pip of its own: the system's, seen through its site packages, installs into it)
    with conftest's wheel installed; return the venv's bin directory."""
    base = tmp_path_factory.mktemp("install")
    env_dir = base / "venv"
    venv.EnvBuilder(system_site_packages=True, with_pip=False).create(env_dir)
    bin_dir = env_dir / ("Scripts" if os.name == "nt" else "bin")
    subprocess.run(
        [str(bin_dir / "python"), "-m", "pip", "install", "--no-deps", "--no-index", "-q", str(wheel)],
        check=True, capture_output=True, text=True, env=_clean_env(), cwd=base,
    )
    return bin_dir


def _clean_env() -> dict[str, str]:
    return environment_without_pythonpath()


class TestInstalledWheel:
    def test_cli_runs_from_the_wheel(self, installed: Path, tmp_path: Path) -> None:
        result = subprocess.run(
            [str(installed / "skysh"), "coeffs", "--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "3",
             "--format", "json"],
            cwd=tmp_path, env=_clean_env(), capture_output=True, text=True, check=True,
        )
        payload = json.loads(result.stdout)
        coefficients = payload["coefficients"]
        assert len(coefficients) == 9 and all(len(row) == 3 for row in coefficients)
        assert coefficients[0][1] > 0.0  # the DC term of the sky is positive

    def test_hosek_wilkie_runs_from_the_wheel_without_mitsuba(self, installed: Path, tmp_path: Path) -> None:
        """Issue 27: the Hosek-Wilkie dataset ships in the wheel; mitsuba (a test-only extra) is made unimportable."""
        argv = ["coeffs", "--sun-zenith", "30", "--sun-azimuth", "45", "--turbidity", "7", "--model", "hosek-wilkie",
                "--albedo", "0.3", "--format", "json"]
        code = ("import sys; sys.modules['mitsuba'] = sys.modules['drjit'] = None; from skysh.app import cli; "
                "from skysh.model import hosek_data; print(hosek_data.DATA_PATH, file=sys.stderr); "
                f"raise SystemExit(cli.main({argv!r}))")
        result = subprocess.run([str(installed / "python"), "-c", code], cwd=tmp_path, env=_clean_env(),
                                capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        assert str(ROOT) not in result.stderr and "hosek_wilkie_sky.npz" in result.stderr, result.stderr
        payload = json.loads(result.stdout)
        expected = SkySH.load(model="hosek-wilkie").coefficients(math.radians(30), 7.0, math.radians(45), albedo=0.3)
        np.testing.assert_allclose(payload["coefficients"], expected, rtol=1e-12)  # JSON round-trips float64

    def test_package_and_data_come_from_the_wheel(self, installed: Path, tmp_path: Path) -> None:
        code = (
            "import skysh, skysh.table.coefficient_file as f; from skysh import SkySH; "
            "s = SkySH.load(); print(skysh.__file__); print(f.default_path())"
        )
        result = subprocess.run(
            [str(installed / "python"), "-c", code], cwd=tmp_path, env=_clean_env(), capture_output=True, text=True,
            check=True,
        )
        package_file, data_file = result.stdout.split()
        assert str(ROOT) not in package_file, "skysh was imported from the source tree, not the wheel"
        assert Path(data_file).name == "preetham_sh.npz" and str(ROOT) not in data_file

    def test_fit_runs_from_the_wheel(self, installed: Path, tmp_path: Path) -> None:
        """Issue 24: ``skysh fit`` is the package's own command (the tools extra brings its solver)."""
        result = subprocess.run([str(installed / "skysh"), "fit", "--help"], cwd=tmp_path, env=_clean_env(),
                                capture_output=True, text=True)
        assert result.returncode == 0 and "--out" in result.stdout, result.stderr
        report = subprocess.run([str(installed / "skysh"), "report", "--out", str(tmp_path / "r")], cwd=tmp_path,
                                env=_clean_env(), capture_output=True, text=True)
        assert report.returncode == 2 and "source checkout" in report.stderr, report.stderr  # the report stays a tool

    @pytest.mark.slow
    def test_a_quick_fit_from_the_wheel(self, installed: Path, tmp_path: Path) -> None:
        """A whole quick fit from the installed package, outside the checkout (cvxpy from the machine's packages)."""
        pytest.importorskip("cvxpy", reason="the fit's irradiance table needs the tools extra: pip install -e \".[tools]\"")
        out = tmp_path / "q.npz"
        result = subprocess.run([str(installed / "skysh"), "fit", "--quick", "--no-progress", "--out", str(out)],
                                cwd=tmp_path, env=_clean_env(), capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        check = subprocess.run([str(installed / "python"), "-c", f"from skysh import SkySH; SkySH.load({str(out)!r})"],
                               cwd=tmp_path, env=_clean_env(), capture_output=True, text=True)
        assert check.returncode == 0, check.stderr
