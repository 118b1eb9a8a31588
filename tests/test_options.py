"""
Tests of skysh.options: the per-frame options, checked and resolved in one place
================================================================================

-   The rule table: :meth:`skysh.options.Options.resolve` for every combination of
    ``irradiance`` x ``engine`` x ``bands`` in {1, 3, 7} x ``gibbs`` / ``dering`` in
    {None, True, False} x a file with or without the irradiance table, against
    :func:`readme_rule`, the README's table "Defaults follow the intent" restated here.
-   The runtime and the command line resolve the same flags: :meth:`skysh.SkySH.coefficients`
    by intent equals the call with the resolved flags spelt out, bit for bit, and
    ``skysh coeffs --format json`` records the resolved ``gibbs`` and ``dering``.
-   Refusals name the parameter (TypeError for a flag not a bool, ValueError else), and the
    runtime's cache of resolved options refuses what the uncached check refuses.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
from typing import Any

import numpy as np
import pytest

from skysh import SkySH
from skysh.app import cli
from skysh.lighting import lights
from skysh.options import Options, check_albedo

BY_INTENT: dict[str, tuple[bool, bool]] = {
    "radiance": (True, False),  # backgrounds, reflections: the filter halves the ringing; no deringing
    "irradiance": (False, True),  # the filter blurs diffuse light; deringing on (3 bands: the table)
    "engine": (False, True),  # engines light diffuse surfaces with their SH: as irradiance
}
"""The README's table "Defaults follow the intent": intent -> (Gibbs filter, deringing) by default."""

TABLE_BANDS: int = 3
"""The certified irradiance table's band count (docs/irradiance.md)."""


def readme_rule(irradiance: bool, engine: str | None, bands: int, gibbs: bool | None, dering: bool | None,
                has_table: bool) -> tuple[bool, bool, bool]:
    """(gibbs, dering, irradiance_table) for ``irradiance_table=None``, as the README's table states them."""
    intent = "engine" if engine is not None else "irradiance" if irradiance else "radiance"
    default_gibbs, default_dering = BY_INTENT[intent]
    # Diffuse light at 3 bands takes the certified table, unless the caller asked for the filter or for no
    # deringing (either keeps the sky's own pipeline), and only where the file has the table.
    table = intent != "radiance" and bands == TABLE_BANDS and has_table and gibbs is not True and dering is not False
    return (default_gibbs if gibbs is None else gibbs), (default_dering if dering is None else dering), table


FLAGS: tuple[bool | None, ...] = (None, True, False)


@pytest.fixture(scope="module")
def sky() -> SkySH:
    return SkySH.load()


class TestRule:
    def test_the_readme_table(self) -> None:
        for irradiance, engine, bands, gibbs, dering, has_table in itertools.product(
                (False, True), (None, "threejs"), (1, 3, 7), FLAGS, FLAGS, (False, True)):
            o = Options.resolve(bands, gibbs, dering, irradiance, engine=engine, has_table=has_table, max_bands=7)
            case = dict(irradiance=irradiance, engine=engine, bands=bands, gibbs=gibbs, dering=dering, has_table=has_table)
            assert (o.gibbs, o.dering, o.irradiance_table) == readme_rule(irradiance, engine, bands, gibbs, dering,
                                                                          has_table), case
            assert (o.bands, o.irradiance, o.engine, o.diffuse) == (bands, irradiance, engine,
                                                                    irradiance or engine is not None), case
            assert all(type(v) is bool for v in (o.gibbs, o.dering, o.irradiance_table, o.sun)), case

    @pytest.mark.parametrize("irradiance", [False, True])
    def test_explicit_table(self, irradiance: bool) -> None:
        """``irradiance_table=True`` takes the table whatever the intent, the filter then off by default;
        False keeps the sky's pipeline."""
        o = Options.resolve(3, None, None, irradiance, True, has_table=True, max_bands=7)
        assert (o.irradiance_table, o.gibbs, o.dering) == (True, False, irradiance)
        o = Options.resolve(3, None, None, irradiance, False, has_table=True, max_bands=7)
        assert (o.irradiance_table, o.gibbs, o.dering) == (False, not irradiance, irradiance)

    def test_values(self) -> None:
        o = Options.resolve(bands=np.int64(2), sun=np.True_, ground_albedo=[0.25, 0.5, 1], colourspace="ACEScg",
                            has_table=True, max_bands=7)
        assert (type(o.bands), o.bands, o.sun, o.ground_albedo, o.colourspace) == (int, 2, True, (0.25, 0.5, 1.0), "ACEScg")
        assert Options.resolve(ground_albedo=0, has_table=True, max_bands=7).ground_albedo is None  # a black ground
        assert Options.resolve(has_table=True, max_bands=7) == Options()  # the defaults: radiance, 3 bands
        with pytest.raises(dataclasses.FrozenInstanceError):
            Options().gibbs = False  # type: ignore[misc]

    def test_one_albedo_check(self) -> None:
        assert lights.check_albedo is check_albedo


class TestShared:
    @pytest.mark.parametrize("bands", [1, 3, 7])
    def test_runtime(self, sky: SkySH, bands: int) -> None:
        """By intent equals the resolved flags spelt out (and irradiance_at equals irradiance=True)."""
        for irradiance, gibbs, dering, table in itertools.product((False, True), FLAGS, FLAGS, FLAGS):
            kwargs: dict[str, Any] = dict(bands=bands, gibbs=gibbs, dering=dering, irradiance=irradiance,
                                          irradiance_table=table)
            try:
                o = Options.resolve(**kwargs, has_table=sky.has_irradiance_table, max_bands=sky.bands)
            except ValueError as error:
                with pytest.raises(ValueError, match="irradiance_table") as refused:
                    sky.coefficients(0.5, 3.0, 1.0, **kwargs)
                assert str(refused.value) == str(error)
                continue
            got = sky.coefficients(0.5, 3.0, 1.0, **kwargs)
            spelt = sky.coefficients(0.5, 3.0, 1.0, bands=o.bands, gibbs=o.gibbs, dering=o.dering, irradiance=o.irradiance,
                                     irradiance_table=o.irradiance_table)
            assert got.tobytes() == spelt.tobytes(), kwargs

    @pytest.mark.parametrize("argv", [
        [], ["--irradiance"], ["--bands", "1"], ["--bands", "7", "--irradiance"], ["--gibbs", "--irradiance"],
        ["--no-dering", "--irradiance"], ["--no-gibbs", "--dering"], ["--engine", "threejs"],
        ["--engine", "unity", "--bands", "1"], ["--engine", "filament", "--gibbs"], ["--engine", "babylon", "--no-dering"],
    ])
    def test_cli(self, sky: SkySH, argv: list[str], capsys: pytest.CaptureFixture) -> None:
        assert cli.main(["coeffs", "--sun-zenith", "30", "--turbidity", "3", *argv, "--format", "json"]) == 0
        payload = json.loads(capsys.readouterr().out)
        flag = {"--gibbs": True, "--no-gibbs": False, "--dering": True, "--no-dering": False}
        o = Options.resolve(
            int(argv[argv.index("--bands") + 1]) if "--bands" in argv else 3,
            next((flag[a] for a in argv if "gibbs" in a), None), next((flag[a] for a in argv if "dering" in a), None),
            "--irradiance" in argv, engine=argv[argv.index("--engine") + 1] if "--engine" in argv else None,
            has_table=sky.has_irradiance_table, max_bands=sky.bands)
        assert (payload["gibbs"], payload["dering"], payload["bands"]) == (o.gibbs, o.dering, o.bands)


class TestRefusals:
    @pytest.mark.parametrize(("name", "value", "error"), [
        ("gibbs", 1, TypeError), ("dering", "False", TypeError), ("irradiance", np.float64(1.0), TypeError),
        ("irradiance_table", 0, TypeError), ("sun", None, TypeError), ("bands", 0, ValueError),
        ("bands", 3.0, ValueError), ("bands", True, ValueError), ("bands", 8, ValueError),
        ("ground_albedo", 1.5, ValueError), ("ground_albedo", (0.1, 0.2), ValueError), ("ground_albedo", True, ValueError),
        ("colourspace", 3, ValueError), ("engine", 3, ValueError),
    ])
    def test_names_the_parameter(self, sky: SkySH, name: str, value: Any, error: type[Exception]) -> None:
        with pytest.raises(error, match=name):
            Options.resolve(**{name: value}, has_table=True, max_bands=7)
        if name != "engine":  # the runtime's cached path refuses it too, after the valid value was cached
            sky.coefficients(0.5, 3.0, 1.0)
            sky.coefficients(0.5, 3.0, 1.0, sun=True, gibbs=True, dering=True, irradiance_table=False)
            with pytest.raises(error, match=name):
                sky.coefficients(0.5, 3.0, 1.0, **{name: value})

    @pytest.mark.parametrize(("kwargs", "match"), [
        (dict(irradiance_table=True), "needs the coefficient file's irradiance table"),
        (dict(irradiance_table=True, bands=1, has_table=True), "needs bands=3"),
        (dict(irradiance_table=True, gibbs=True, has_table=True), "does not go with gibbs=True"),
    ])
    def test_the_table(self, kwargs: dict[str, Any], match: str) -> None:
        with pytest.raises(ValueError, match=match):
            Options.resolve(**{"has_table": False, "max_bands": 7, **kwargs})

    def test_numpy_values_take_the_checked_path(self, sky: SkySH) -> None:
        """numpy bools and integers are accepted (not from the cache of plain values) and give the same result."""
        plain = sky.coefficients(0.5, 3.0, 1.0, bands=3, gibbs=True, irradiance=False)
        numpy = sky.coefficients(0.5, 3.0, 1.0, bands=np.int64(3), gibbs=np.True_, irradiance=np.False_)
        assert plain.tobytes() == numpy.tobytes()
