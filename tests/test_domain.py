"""
The fitted domain, in one place (issue 24, item 1)
==================================================

-   :class:`TestRegistry`: every module that needs the domain takes it from :mod:`skysh.domain`
    (the same objects, or values derived from them): the runtime, the sun, the file, the CLI, the exports.
-   :class:`TestDomain`: the maps send the intervals' ends to -1 and 1, the checks refuse NaN, inf and
    values outside with the parameter's name, the scalar and array paths agree, and Kasten's air mass
    matches its published form (Kasten 1966), written here independently.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skysh import domain, runtime
from skysh.app import cli
from skysh.domain import SKY, SUN
from skysh.lighting import lights, sunlight
from skysh.model import preetham, solar
from skysh.table import coefficient_file, poly, sun_table


class TestRegistry:
    def test_the_sun_shares_the_skys_intervals(self) -> None:
        assert SUN.x.interval is SKY.x.interval and SUN.y.interval is SKY.y.interval

    def test_the_runtime_reads_the_sky_domain(self) -> None:
        assert (runtime._ZMIN, runtime._ZMAX) == SKY.x.interval and (runtime._TMIN, runtime._TMAX) == SKY.y.interval
        assert (runtime._XS, runtime._XH, runtime._YS, runtime._YH) == (SKY.x.scale, SKY.x.shift, SKY.y.scale,
                                                                        SKY.y.shift)

    def test_the_physics_ranges_are_the_domain(self) -> None:
        assert preetham.SUN_ZENITH_RANGE is SKY.x.interval
        assert solar.SUN_ZENITH_RANGE is SKY.x.interval and solar.TURBIDITY_RANGE is SKY.y.interval
        assert solar.KASTEN_COEFFICIENTS is domain.KASTEN_COEFFICIENTS

    def test_the_sun_reads_the_sun_domain(self) -> None:
        assert (sunlight._M0, sunlight._SXS, sunlight._SYS) == (SUN.x.origin, SUN.x.scale, SUN.y.scale)
        assert (lights._M0, lights._SX_SCALE, lights._TMIN, lights._SY_SCALE) == (SUN.x.origin, SUN.x.scale,
                                                                                  SUN.y.origin, SUN.y.scale)

    def test_the_file_records_the_domain(self) -> None:
        assert coefficient_file.DOMAIN == SKY.metadata() == SUN.metadata()
        assert coefficient_file.DOMAIN == {"sun_zenith": [0.0, math.pi / 2], "turbidity": [2.5, 6.0]}
        sun_spec = next(spec for spec in coefficient_file.TABLES if spec.name == "sun")
        assert sun_spec.fields["air_mass_range"] == list(SUN.x.fitted)
        assert sun_spec.fields["term_order"] is domain.TERM_ORDER

    def test_the_shipped_file_still_verifies(self) -> None:
        table = coefficient_file.read()  # checks the metadata against the constants and the content hash
        assert table.metadata["domain"] == SKY.metadata()
        assert table.metadata["tables"]["sun"]["air_mass_range"] == list(SUN.x.fitted)

    def test_the_cli_help_and_checks(self) -> None:
        assert cli._turbidity_range() == SKY.y.interval_text() == "[2.5, 6]"
        assert cli._sun_zenith_range() == SKY.x.interval_text(degrees=True) == "[0, 90]"

    def test_the_exports_constants(self) -> None:
        from skysh.export.tables import export_tables

        tables = export_tables(runtime.SkySH.load(), 3)
        assert (tables.x_scale, tables.x_shift, tables.y_scale, tables.y_shift) == (
            SKY.x.scale, SKY.x.shift, SKY.y.scale, SKY.y.shift)
        assert tables.sun_zenith_domain is SKY.x.interval and tables.turbidity_domain is SKY.y.interval
        c = tables.lights.constants
        assert (c["am_a"], c["am_b"], -c["am_neg_c"]) == domain.KASTEN_COEFFICIENTS
        assert (c["m0"], c["sx_scale"], c["sun_tmin"], c["sy_scale"]) == (SUN.x.origin, SUN.x.scale, SUN.y.origin,
                                                                          SUN.y.scale)

    def test_poly_maps_over_the_sky_domain(self) -> None:
        x, y = poly.scale(np.array(SKY.x.interval), np.array(SKY.y.interval))
        np.testing.assert_allclose(x, [-1.0, 1.0], rtol=0, atol=4e-16)
        np.testing.assert_allclose(y, [-1.0, 1.0], rtol=0, atol=4e-16)

    def test_the_term_order(self) -> None:
        assert domain.term_index(2, 3, (13, 7)) == 2 * 8 + 3
        assert domain.check_degrees((13, 7)) == (13, 7)
        with pytest.raises(ValueError, match=r"degrees\[1\]"):
            domain.check_degrees((1, domain.MAX_DEGREE + 1))


def _kasten_1966(theta: float) -> float:
    """Kasten (1966) as published: m = 1 / (cos z + 0.15 (93.885 - z)^-1.253), z in degrees."""
    z = theta * 180.0 / math.pi
    return 1.0 / (math.cos(theta) + 0.15 * (93.885 - z) ** -1.253)


class TestDomain:
    @pytest.mark.parametrize("dom", [SKY, SUN], ids=["sky", "sun"])
    def test_the_ends_map_to_minus_one_and_one(self, dom: domain.Domain) -> None:
        for v in dom.variables:
            low, high = v.fitted
            assert (low - v.origin) * v.scale - v.shift == -1.0
            assert (high - v.origin) * v.scale - v.shift == pytest.approx(1.0, abs=4e-16)
            np.testing.assert_array_equal(v.unit_unchecked(np.array(v.interval)), [-1.0, 1.0])

    @pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, -1e-12, 1.6, 90.0])
    def test_check_refuses_the_zenith(self, bad: float) -> None:
        for path in (bad, np.array([0.1, bad])):
            with pytest.raises(ValueError, match="sun_zenith"):
                SKY.check(path, 3.0)

    @pytest.mark.parametrize("bad", [math.nan, math.inf, 2.4999, 6.0001, 0.0])
    def test_check_refuses_the_turbidity(self, bad: float) -> None:
        for dom in (SKY, SUN):
            for path in (bad, np.array([3.0, bad])):
                with pytest.raises(ValueError, match="turbidity"):
                    dom.check(0.5, path)

    def test_one_message_form(self) -> None:
        messages = []
        for path in (2.0, np.array([2.0])):
            with pytest.raises(ValueError) as info:
                SKY.check(path, 3.0)
            messages.append(str(info.value))
        assert messages[0] == messages[1] == "sun_zenith must lie in [0, 1.5708] rad (the fitted domain), got 2"
        with pytest.raises(ValueError, match=r"^turbidity must lie in \[2\.5, 6\] \(the fitted domain\), got 7$"):
            SKY.check(1.0, 7.0)

    def test_scalar_and_array_paths_agree(self) -> None:
        rng = np.random.default_rng(5)
        ts, tu = rng.uniform(*SKY.x.interval, 200), rng.uniform(*SKY.y.interval, 200)
        for dom in (SKY, SUN):
            ux, uy = dom.unit(ts, tu)
            for k in range(0, 200, 17):
                a, b = dom.check(float(ts[k]), float(tu[k]))
                assert type(a) is float and type(b) is float
                sx, sy = dom.unit(a, b)
                assert float(sx) == ux[k] and float(sy) == uy[k]
                assert dom.x.fitted_scalar(a) == pytest.approx(float(dom.x.fitted_value(np.array(a))), rel=1e-15)

    def test_kasten_against_its_published_form(self) -> None:
        for theta in np.linspace(0.0, math.pi / 2, 91):
            assert SUN.x.fitted_scalar(float(theta)) == pytest.approx(_kasten_1966(float(theta)), rel=1e-14)
        assert SUN.x.fitted == (_kasten_1966(0.0), _kasten_1966(math.pi / 2))
        assert SUN.x.fitted[0] == pytest.approx(0.99949, abs=1e-5) and SUN.x.fitted[1] == pytest.approx(36.510, abs=1e-3)
        np.testing.assert_array_equal(sun_table.air_mass(np.array([0.0, math.pi / 2])), SUN.x.fitted)

    def test_the_sky_map_is_log_in_turbidity(self) -> None:
        assert SKY.y.fitted == (math.log(2.5), math.log(6.0))
        assert SKY.y.scale == 2.0 / (math.log(6.0) - math.log(2.5))
        assert SKY.x.scale == 4.0 / math.pi and SKY.x.shift == 1.0

    def test_a_bad_variable_is_refused(self) -> None:
        with pytest.raises(ValueError, match="transform"):
            domain.Variable("v", "", (0.0, 1.0), transform="sqrt")
        with pytest.raises(ValueError, match="interval"):
            domain.Variable("v", "", (1.0, 1.0))
