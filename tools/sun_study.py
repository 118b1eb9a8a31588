#!/usr/bin/env python
"""
The sun and the ground: figures behind skysh.model.solar and skysh.model.ground (issue 15)
==============================================================================

Prints (plain text, no files) every figure quoted in the docstrings of
:mod:`skysh.model.solar` and :mod:`skysh.model.ground` and in the issue-15 report:

``--table``
    The sun's direct normal illuminance, luminance and sRGB chromaticity over
    (sun zenith, turbidity); the illuminance above the atmosphere against the
    solar illuminance constant; the share of the CIE functions the 380-750 nm
    range leaves out.
``--windows``
    The sun's per-band windows: exact minimum of a delta's irradiance and its
    relative L2 error for the derived non-negative windows, the seed's
    (1, 0.92, 0.73), no window, and the deringing table's last row.
    ``--derive`` re-derives :data:`skysh.model.solar.SUN_WINDOW_PARAMETERS` (about 30 s).
``--ground``
    The Gibbs-filter question for the ground: its N-band irradiance error with
    and without the zonal sinc filter (Habel eq. 5) against the exact
    irradiance, and the radiance ringing with and without.
``--fit``
    How smooth the sun's illuminance is over (sun zenith, turbidity): held-out
    errors of Chebyshev fits of ln XYZ (skysh.table.fit's fit_table / evaluate_table)
    in three zenith variables and two turbidity variables, by degrees.
``--cover``
    Whether the sky's irradiance covers the negative ring of the seed's
    punctual window: minimum over normals of the 3-band irradiance of sky
    (deringed) + sun, across the domain.

Run::

    PYTHONPATH=. python tools/sun_study.py              # all but --derive, about half a minute
    PYTHONPATH=. python tools/sun_study.py --fit
"""

from __future__ import annotations

import argparse
import math
import os
import time

# Small least-squares problems: threaded BLAS only adds contention on a shared machine (50x slower here).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402 (after the thread settings)

from skysh.model import ground, preetham, solar  # noqa: E402
from skysh.sh import basis as sh  # noqa: E402
from skysh.table import fit  # noqa: E402

DEG = math.pi / 180.0
TURBIDITIES = (2.5, 3.0, 4.0, 6.0)
ZENITHS_DEG = (0, 30, 45, 60, 70, 80, 85, 88, 89, 90)
FIT_GOAL = 1e-4  # issue 15: held-out error <= 1e-4 relative


# --------------------------------------------------------------------------- #
# --table
# --------------------------------------------------------------------------- #
def section_table() -> None:
    print("== The sun through the atmosphere (skysh.model.solar) ==")
    ts = np.array(ZENITHS_DEG) * DEG
    print(f"solid angle {solar.SUN_SOLID_ANGLE:.6e} sr, angular radius {solar.SUN_ANGULAR_RADIUS:.4e} rad "
          f"= {math.degrees(solar.SUN_ANGULAR_RADIUS):.5f} deg")
    m = solar.relative_optical_mass([0.0, math.pi / 2])
    print(f"relative optical mass (Kasten 1966): {m[0]:.5f} at the zenith, {m[1]:.4f} on the horizon")
    print("direct normal illuminance, lux (rows: zenith deg; columns: turbidity)")
    print("  zen " + "".join(f"{t:>13}" for t in TURBIDITIES))
    dni = solar.direct_normal_illuminance(ts[:, None], np.array(TURBIDITIES)[None, :])
    for z, row in zip(ZENITHS_DEG, dni):
        print(f"  {z:3d} " + "".join(f"{v:13.5g}" for v in row))
    print("luminance of the disk at the zenith, cd/m^2: "
          + ", ".join(f"T={t}: {solar.luminance(0.0, t):.4g}" for t in TURBIDITIES))
    print("sRGB illuminance / Y (R, G, B) at T = 2.5 and 6:")
    for t in (2.5, 6.0):
        rgb = solar.illuminance_rgb(ts, t)
        y = dni[:, TURBIDITIES.index(t)]
        for z, c, yy in zip(ZENITHS_DEG, rgb, y):
            print(f"  T={t} zen {z:2d}: ({c[0] / yy:7.4f}, {c[1] / yy:7.4f}, {c[2] / yy:7.4f})")
    xyz0 = solar.extraterrestrial_xyz()
    print(f"above the atmosphere: XYZ = ({xyz0[0]:.6g}, {xyz0[1]:.6g}, {xyz0[2]:.6g}) lux; "
          f"Y against E_sc = 128000 lux: {xyz0[1] / 128000.0 - 1:+.4%}")
    _truncation()


def _truncation() -> None:
    """Share of each CIE integral outside 380-750 nm, for the spectrum held constant beyond its ends."""
    import colour

    cmfs = colour.MSDS_CMFS[solar.CMFS_NAME]
    lam = np.arange(360.0, 831.0)
    table = np.array(cmfs[lam])
    for ts, t in ((0.0, 2.5), (85 * DEG, 6.0)):
        s = solar.spectral_radiance(ts, t)
        full = np.interp(lam, solar.WAVELENGTHS, s)  # constant extension beyond 380 and 750 nm
        inside = (lam >= 380) & (lam <= 750)
        total = np.trapezoid(full[:, None] * table, lam, axis=0)
        kept = np.trapezoid((full * inside)[:, None] * table, lam, axis=0)
        share = 1.0 - kept / total
        print(f"left out by 380-750 nm (spectrum held constant outside), zen {math.degrees(ts):.0f} T {t}: "
              f"X {share[0]:.2e}, Y {share[1]:.2e}, Z {share[2]:.2e}")


# --------------------------------------------------------------------------- #
# --windows
# --------------------------------------------------------------------------- #
def _min_ratio(window: np.ndarray) -> float:
    """Exact minimum of a unit delta's windowed irradiance over its mean (1/4)."""
    return solar.delta_irradiance_minimum(window) / 0.25


def section_windows(derive: bool) -> None:
    print("== The sun as a windowed delta (skysh.model.solar.sun_window) ==")
    print("min = exact minimum of the delta's irradiance / its mean; err = relative L2 error over normals")
    from skysh.post import dering

    for n in range(1, solar.MAX_WINDOW_BANDS + 1):
        w, a = solar.SUN_WINDOW_PARAMETERS[n - 1]
        ours = solar.SUN_WINDOWS[n - 1]
        last = dering.window_table(n)[-1]
        none = np.ones(n)
        print(f"  N={n}: w={w:<8g} a={a:<9g} window {np.array2string(ours, precision=4)}")
        print(f"        derived: min {_min_ratio(ours):+.3e} err {solar.delta_irradiance_error(ours):.4f} | "
              f"none: min {_min_ratio(none):+.4f} err {solar.delta_irradiance_error(none):.4f} | "
              f"dering last row: min {_min_ratio(last):+.2e} err {solar.delta_irradiance_error(last):.4f}")
    seed = np.array(solar.SEED_PUNCTUAL_WINDOW)
    print(f"  seed (1, 0.92, 0.73) at N=3: min {_min_ratio(seed):+.4f} err {solar.delta_irradiance_error(seed):.4f}")
    if derive:
        print("re-deriving SUN_WINDOW_PARAMETERS (scan 1.5..40 by 0.25, golden section):")
        for n in range(1, solar.MAX_WINDOW_BANDS + 1):
            t0 = time.perf_counter()
            w, a, err = solar.derive_sun_window(n)
            print(f"  N={n}: w={w!r} a={a!r} err={err:.6f} ({time.perf_counter() - t0:.1f} s)")


# --------------------------------------------------------------------------- #
# --ground
# --------------------------------------------------------------------------- #
def _gibbs(n: int) -> np.ndarray:
    """Habel eq. (5), as skysh.runtime.gibbs_factors: sinc(pi l / N)."""
    return np.sinc(np.arange(n) / n)


def section_ground() -> None:
    print("== The ground (uniform lower hemisphere, L = 1): Gibbs filter or not ==")
    normals = sh.quadrature_rule(96)[0]
    exact = ground.ground_irradiance([1.0], normals)[:, 0]
    z = np.linspace(-1.0, 1.0, 20001)
    zdirs = np.stack([np.sqrt(1 - z * z), np.zeros_like(z), z], axis=-1)
    step = (z < 0).astype(float)
    print("irradiance: max |E_N - E| / (pi L) over normals; radiance: overshoot max(L_N) - 1 below the horizon, "
          "undershoot min(L_N) above, RMS error over the sphere")
    print("   N | irr. no filter | irr. filter | overshoot no/filter | undershoot no/filter | RMS no/filter")
    for n in range(2, 8):
        c = ground.ground_sh([1.0], n)
        cf = sh.convolve(c, _gibbs(n))
        e0 = sh.evaluate(sh.irradiance(c), normals)[:, 0]
        e1 = sh.evaluate(sh.irradiance(cf), normals)[:, 0]
        l0 = sh.evaluate(c, zdirs)[:, 0]
        l1 = sh.evaluate(cf, zdirs)[:, 0]
        rms0 = math.sqrt(np.trapezoid((l0 - step) ** 2, z) / 2)
        rms1 = math.sqrt(np.trapezoid((l1 - step) ** 2, z) / 2)
        print(f"  {n:2d} | {np.max(np.abs(e0 - exact)) / math.pi:14.2e} | {np.max(np.abs(e1 - exact)) / math.pi:11.4f} | "
              f"{l0[z < 0].max() - 1:+8.4f} {l1[z < 0].max() - 1:+8.4f}  | "
              f"{l0[z > 0].min():+8.4f} {l1[z > 0].min():+8.4f}   | {rms0:.4f} {rms1:.4f}")
    print("  (irradiance without the filter is exact for N >= 2: only bands 0 and 1 reach it)")


# --------------------------------------------------------------------------- #
# --fit
# --------------------------------------------------------------------------- #
_M0 = float(solar.relative_optical_mass(0.0))
_M1 = float(solar.relative_optical_mass(math.pi / 2))


def _pseudo_zenith(ts: np.ndarray, variable: str) -> np.ndarray:
    """The zenith variable mapped onto [0, pi/2] so fit_table's affine Chebyshev map applies."""
    if variable == "theta":
        return ts
    m = solar.relative_optical_mass(ts)
    if variable == "log m":
        return (np.log(m) - math.log(_M0)) / (math.log(_M1) - math.log(_M0)) * (math.pi / 2)
    return (m - _M0) / (_M1 - _M0) * (math.pi / 2)


def _zenith_of(pseudo: np.ndarray, variable: str) -> np.ndarray:
    """Invert :func:`_pseudo_zenith` (monotone) by bisection to full precision."""
    lo, hi = np.zeros_like(pseudo), np.full_like(pseudo, math.pi / 2)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = _pseudo_zenith(mid, variable) < pseudo
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def _fit_errors(variable: str, log_t: bool, degrees: tuple[int, int], data: dict) -> tuple[float, float, float]:
    ts_fit, tu_fit, ln_fit = data["fit"]
    hs, hu, xyz_h, rgb_h, y_zenith = data["held"]
    deg = np.array([degrees])
    ones = np.ones((ts_fit.size, 3))
    table, _ = fit.fit_table(_pseudo_zenith(ts_fit, variable), tu_fit, ln_fit[:, None, :], ones, deg, (log_t, False))
    xyz = np.exp(fit.evaluate_table(table, deg, _pseudo_zenith(hs, variable), hu, (log_t, False))[:, 0, :])
    strict = float(np.max(np.abs(xyz / xyz_h - 1.0)))
    d_rgb = (xyz - xyz_h) @ data["matrix"].T
    floored = float(np.max(np.abs(d_rgb) / np.maximum(np.abs(rgb_h), xyz_h[:, 1:2])))
    zenith = float(np.max(np.abs(d_rgb) / y_zenith[:, None]))
    return strict, floored, zenith


def section_fit() -> None:
    print("== Smoothness of the sun's illuminance: Chebyshev fits of ln XYZ (skysh.table.fit.fit_table) ==")
    print("fit grid: 48 x 16 Chebyshev nodes in (zenith variable, turbidity variable); held out: 512 uniform "
          "random points + 4 corners + 4 x 64 edge points (skysh.table.fit.held_out_points / edge_points)")
    print("errors, worst over held-out points: xyz = max_c |dXYZ_c| / XYZ_c (strict, per channel); "
          "rgb = max_c |dRGB_c| / max(|RGB_c|, Y) (sRGB, floored at the point's own luminance, so out-of-gamut "
          "channels near 0 are measured against Y); zen = max_c |dRGB_c| / DNI(zenith, same T)")
    matrix = preetham.rgb_from_xyz_matrix("sRGB")
    hs, hu = fit.held_out_points(512, 2024)
    es, eu = fit.edge_points(64, 2025)
    hs, hu = np.concatenate([hs, es]), np.concatenate([hu, eu])
    xyz_h = solar.illuminance_xyz(hs, hu)
    held = (hs, hu, xyz_h, xyz_h @ matrix.T, solar.direct_normal_illuminance(0.0, hu))
    nodes, tu_fit = fit.chebyshev_grid((48, 16))
    smallest: dict[str, tuple[int, tuple[int, int], tuple[float, float, float]]] = {}
    for variable in ("theta", "log m", "m"):
        ts_fit = _zenith_of(nodes, variable)
        data = {"fit": (ts_fit, tu_fit, np.log(solar.illuminance_xyz(ts_fit, tu_fit))), "held": held, "matrix": matrix}
        for log_t in (False, True):
            name = f"{variable}, {'log T' if log_t else 'T'}"
            sweep = ((8, 12, 16, 24, 32), (3, 5, 7)) if variable == "theta" else ((8, 10, 12, 14, 16), (3, 4, 5, 6, 7))
            print(f"-- zenith variable: {variable}; turbidity variable: {'log T' if log_t else 'T'}")
            for d_theta in sweep[0]:
                cells = []
                for d_tau in sweep[1]:
                    errors = _fit_errors(variable, log_t, (d_theta, d_tau), data)
                    cells.append(f"({d_theta},{d_tau}) xyz {errors[0]:.1e} rgb {errors[1]:.1e} zen {errors[2]:.1e}")
                    terms = (d_theta + 1) * (d_tau + 1)
                    if max(errors) <= FIT_GOAL and terms < smallest.get(name, (10**9,))[0]:
                        smallest[name] = (terms, (d_theta, d_tau), errors)
                print("   " + " | ".join(cells))
    print(f"smallest fits with all three errors <= {FIT_GOAL:g}:")
    for name, (terms, degrees, errors) in smallest.items():
        print(f"  ({name}): degrees {degrees}, {terms} terms x 3 channels; "
              f"xyz {errors[0]:.1e}, rgb {errors[1]:.1e}, zen {errors[2]:.1e}")


# --------------------------------------------------------------------------- #
# --cover
# --------------------------------------------------------------------------- #
def section_cover() -> None:
    print("== Does the deringed sky cover the seed window's negative ring? (3 bands, ground albedo 0) ==")
    print("min over normals of the irradiance of sky (true 3-band SH, deringed) + sun, / DNI; "
          "'seed' = (1, 0.92, 0.73), 'nonneg' = SUN_WINDOWS[2]")
    try:
        from skysh.post import dering as dering_module
    except ImportError:  # pragma: no cover - dering is part of the package
        dering_module = None
    normals = sh.quadrature_rule(64)[0]
    worst = {"seed": math.inf, "nonneg": math.inf}
    for t in (2.5, 4.0, 6.0):
        cells = []
        for zen in (0, 30, 60, 75, 85, 89):
            ts = zen * DEG
            sky = preetham.sky_sh(ts, t, 3)
            if dering_module is not None:
                sky = dering_module.dering(sky)[0]
            rgb = solar.illuminance_rgb(ts, t)
            d = solar.sun_direction(ts, 0.0)
            dni = float(solar.direct_normal_illuminance(ts, t))
            out = []
            for kind, window in (("seed", "seed"), ("nonneg", "nonnegative")):
                total = sky + solar.sun_sh(d, rgb, 3, window=window)
                m = float(sh.evaluate(sh.irradiance(total), normals).min()) / dni
                worst[kind] = min(worst[kind], m)
                out.append(f"{m:+.2e}")
            cells.append(f"{zen:2d}: {'/'.join(out)}")
        print(f"  T={t}: " + "  ".join(cells))
    print(f"  worst: seed {worst['seed']:+.3e}, nonneg {worst['nonneg']:+.3e} (of the DNI)")


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1], formatter_class=argparse.RawTextHelpFormatter)
    for name in ("table", "windows", "ground", "fit", "cover"):
        parser.add_argument(f"--{name}", action="store_true", help=f"print the {name} section")
    parser.add_argument("--derive", action="store_true", help="with --windows: re-derive the window table")
    args = parser.parse_args(argv)
    chosen = [n for n in ("table", "windows", "ground", "fit", "cover") if getattr(args, n)]
    if not chosen:
        chosen = ["table", "windows", "ground", "fit", "cover"]
    for name in chosen:
        t0 = time.perf_counter()
        if name == "windows":
            section_windows(args.derive)
        else:
            globals()[f"section_{name}"]()
        print(f"[{name}: {time.perf_counter() - t0:.1f} s]\n")


if __name__ == "__main__":
    main()
