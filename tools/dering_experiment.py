"""
Deringing measurements (Sloan 2017, seed 000, and beyond)
=========================================================

Prints markdown tables, then one JSON line per table row:

1.  **Table 1 vs eq. (6)**: the minimum of a windowed delta light's irradiance
    (relative to its mean) for the seed's Table 1, plain sinc^4 (eq. 6) at the
    same window sizes, and :data:`skysh.dering.WINDOW_TABLE`.
2.  **How conservative the bound is**: ``exact_min - min_bound`` of 3-band
    irradiance for random functions, skies and adversarial lights (relative to
    the function's mean, or to its largest coefficient for random functions),
    and the count of bounds above the exact minimum (must be 0).
3.  **Non-negativity after deringing**: the irradiance of deringed skies and
    lights on a dense sphere (8,192 Gauss-product nodes), relative to its mean;
    count of negative values (must be 0) and of DeringWarnings.
4.  **Excess windowing**: the chosen scales (table + bound) against the least
    scales along the same table path that :func:`skysh.dering.exact_min`
    accepts (bisection to 2^-12 of a row), mean and worst over items.
5.  **Detail kept against cost**: relative L2 distance of the deringed
    irradiance to the unwindowed one (over the items that needed windowing),
    and the time of one (K, 3) call, for the table + bound, table + exact_min and
    sinc^4 search, at 3 and 7 bands.

Sky data come from ``skysh.SkySH`` (``bands=3, gibbs=True``) when it can be
imported and loaded, else from ``skysh.preetham.sky_sh`` (4,000 directions)
with the zonal Gibbs filter ``c(l, 0) *= sinc(l / N)`` applied here, rotated by
the sun azimuth; the output says which. Lights are non-negative by
construction: HDR delta lights, "linear" lights (64 deltas along a great-circle
arc) and mixtures with an ambient term, projected with ``skysh.sh.basis``.

Run::

    PYTHONPATH=. python tools/dering_experiment.py --quick
    PYTHONPATH=. python tools/dering_experiment.py            # 2000 skies, 600 lights
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from skysh import dering, sh

QUICK: dict[str, int] = {"skies": 200, "lights": 120, "random": 2000}
"""Sample counts with --quick."""

FULL: dict[str, int] = {"skies": 2000, "lights": 600, "random": 20000}
"""Sample counts by default."""

DENSE_THETA: int = 64
"""Gauss nodes in z of the dense check sphere (2 * 64^2 = 8192 directions)."""

NEGATIVE_TOL: float = 1e-12
"""A dense-sphere value counts as negative below -1e-12 of the function's mean (rounding)."""

EXCESS_BISECTION: int = 12
"""Bisection steps for the least table position accepted by exact_min (2^-12 of a row)."""

ARC_SAMPLES: int = 64
"""Deltas per linear (arc) light."""


# --------------------------------------------------------------------------- #
# Inputs
# --------------------------------------------------------------------------- #
def sky_coefficients(n: int, rng: np.random.Generator) -> tuple[NDArray, str]:
    """(n, 9, 3) sky radiance SH over the fitted domain, and where they came from."""
    zen = rng.uniform(0.0, math.pi / 2.0, n)
    zen[:4] = [0.0, math.pi / 2.0, 0.0, math.pi / 2.0]  # domain corners
    tur = rng.uniform(2.5, 6.0, n)
    tur[:4] = [2.5, 2.5, 6.0, 6.0]
    azi = rng.uniform(0.0, 2.0 * math.pi, n)
    try:
        from skysh import SkySH

        sky = SkySH.load()
        out = np.asarray(sky.coefficients(zen, tur, sun_azimuth=azi, bands=3, gibbs=True), dtype=np.float64)
        if out.shape != (n, 9, 3):
            raise ValueError(f"unexpected shape {out.shape}")
        return out, "skysh.SkySH (bands=3, gibbs=True)"
    except Exception as error:  # noqa: BLE001 - any failure means: use the reference
        from skysh import preetham

        gibbs = np.sinc(np.arange(3) / 3.0)
        zonal = [sh.index(l, 0) for l in range(3)]  # noqa: E741
        out = np.empty((n, 9, 3))
        for i in range(n):  # the reference projection takes scalars
            c = preetham.sky_sh(float(zen[i]), float(tur[i]), bands=3, n=4000)
            c[zonal] *= gibbs[:, None]
            out[i] = sh.rotate_z(c, float(azi[i]))
        return out, f"skysh.preetham.sky_sh (n=4000) + zonal Gibbs filter (SkySH unavailable: {type(error).__name__})"


def _random_dirs(rng: np.random.Generator, n: int) -> NDArray:
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _arc(rng: np.random.Generator) -> NDArray:
    """ARC_SAMPLES unit vectors along a random great-circle arc of length up to pi/2."""
    a = _random_dirs(rng, 1)[0]
    b = _random_dirs(rng, 1)[0]
    b -= a * (a @ b)
    b /= np.linalg.norm(b)
    t = np.linspace(0.0, rng.uniform(0.05, math.pi / 2.0), ARC_SAMPLES)
    return np.cos(t)[:, None] * a + np.sin(t)[:, None] * b


def lights(n: int, rng: np.random.Generator, bands: int) -> dict[str, NDArray]:
    """Non-negative adversarial lights, radiance SH (m, bands^2, 3) per family."""
    out: dict[str, list[NDArray]] = {"single delta": [], "HDR deltas": [], "linear lights": [], "mixed": []}
    m = max(n // 4, 8)
    i = np.arange(m) + 0.5
    z = 1.0 - 2.0 * i / m
    phi = i * math.pi * (3.0 - math.sqrt(5.0))  # Fibonacci lattice: deltas in evenly spread directions
    r = np.sqrt(1.0 - z * z)
    for d in np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1):
        out["single delta"].append(sh.basis(d, bands)[:, None] * np.ones(3))
    for _ in range(n // 4):
        k = rng.integers(1, 5)
        w = 10.0 ** rng.uniform(-2.0, 4.0, (k, 3))
        out["HDR deltas"].append(sh.basis(_random_dirs(rng, k), bands).T @ w)
    for _ in range(n // 4):
        c = np.zeros((bands * bands, 3))
        for _ in range(rng.integers(1, 4)):
            w = 10.0 ** rng.uniform(-1.0, 3.0, 3) / ARC_SAMPLES
            c += sh.basis(_arc(rng), bands).sum(axis=0)[:, None] * w
        out["linear lights"].append(c)
    for _ in range(n - 3 * (n // 4)):
        c = np.zeros((bands * bands, 3))
        c[0] = 10.0 ** rng.uniform(-2.0, 1.0, 3) * 2.0 * math.sqrt(math.pi)  # ambient 0.01..10 per sr
        k = rng.integers(1, 4)
        c += sh.basis(_random_dirs(rng, k), bands).T @ (10.0 ** rng.uniform(0.0, 3.0, (k, 3)))
        c += sh.basis(_arc(rng), bands).sum(axis=0)[:, None] * (10.0 ** rng.uniform(0.0, 2.0, 3) / ARC_SAMPLES)
        out["mixed"].append(c)
    return {k: np.array(v) for k, v in out.items()}


# --------------------------------------------------------------------------- #
# Measures
# --------------------------------------------------------------------------- #
def dense_min(coeffs: NDArray) -> NDArray:
    """Minimum over the dense check sphere, (..., C), of SH (..., K, C)."""
    dirs, _ = sh.quadrature_rule(DENSE_THETA)
    y = sh.basis(dirs, math.isqrt(coeffs.shape[-2]))  # (M, K)
    return np.min(np.einsum("mk,...kc->...mc", y, coeffs), axis=-2)


def mean_value(coeffs: NDArray) -> NDArray:
    """Mean over the sphere of SH (..., K, C): c0 / (2 sqrt(pi)), (..., C)."""
    return coeffs[..., 0, :] * (0.5 / math.sqrt(math.pi))


def path_scales(tau: NDArray, table: NDArray) -> NDArray:
    """Scales (..., N) at table positions tau (...), linear between rows."""
    i = np.minimum(np.floor(tau).astype(int), table.shape[0] - 2)
    f = (tau - i)[..., None]
    return table[i] * (1.0 - f) + table[i + 1] * f


def least_exact_tau(irr: NDArray, table: NDArray, tau_hi: NDArray) -> NDArray:
    """Least table position whose irradiance exact_min accepts, by bisection below tau_hi."""
    l_of = np.repeat(np.arange(table.shape[1]), 2 * np.arange(table.shape[1]) + 1)

    def ok(tau: NDArray) -> NDArray:
        return (dering.exact_min(irr * path_scales(tau, table)[:, l_of, None]) >= 0.0).all(axis=-1)

    lo = np.maximum(tau_hi - 1.0 / 32.0, 0.0)
    hi = tau_hi.copy()
    zero_ok = ok(np.zeros_like(hi))
    lo_ok = ok(lo)
    hi = np.where(lo_ok, lo, hi)  # the 1/32 bracket did not hold: search the whole row below
    lo = np.where(lo_ok, np.maximum(lo - 1.0, 0.0), lo)
    for _ in range(EXCESS_BISECTION):
        mid = 0.5 * (lo + hi)
        good = ok(mid)
        hi = np.where(good, mid, hi)
        lo = np.where(good, lo, mid)
    return np.where(zero_ok, 0.0, hi)


def best_time(fn: Callable[[], Any], repeats: int = 7, number: int = 20) -> float:
    """Best mean time of ``number`` calls over ``repeats`` runs after a warm-up, seconds."""
    fn()
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def stats(x: NDArray) -> dict[str, float]:
    """mean, 95th percentile and worst of a 1-D sample (0 for an empty one)."""
    x = np.asarray(x, dtype=np.float64).ravel()
    if x.size == 0:
        return {"mean": 0.0, "p95": 0.0, "worst": 0.0}
    return {"mean": float(x.mean()), "p95": float(np.quantile(x, 0.95)), "worst": float(x.max())}


# --------------------------------------------------------------------------- #
# Experiments
# --------------------------------------------------------------------------- #
def table_finding() -> list[dict[str, Any]]:
    rows = []
    for r, w in enumerate(dering.SEED_WINDOW_SIZES):
        rows.append(
            {
                "experiment": "table",
                "w": w,
                "table1": dering.SEED_TABLE_1[r, :3].tolist(),
                "table1_delta_min_rel": dering.delta_minimum(dering.SEED_TABLE_1[r, :3]) / 0.25,
                "sinc4": dering.sinc4_window(w, 3).tolist(),
                "sinc4_delta_min_rel": dering.delta_minimum(dering.sinc4_window(w, 3)) / 0.25,
                "window_table": dering.WINDOW_TABLE[r].tolist(),
                "window_table_delta_min_rel": dering.delta_minimum(dering.WINDOW_TABLE[r]) / 0.25,
            }
        )
    return rows


def bound_conservativeness(sets: dict[str, NDArray], rng: np.random.Generator, n_random: int) -> list[dict[str, Any]]:
    rows = []
    rand = rng.normal(size=(n_random, 9, 1)) * rng.uniform(0.0, 2.0, (n_random, 9, 1)) ** 2
    unit = np.abs(rand).max(axis=-2)
    gap = (dering.exact_min(rand) - dering.min_bound(rand)) / unit
    rows.append({"experiment": "bound", "set": "random (unit = max |coeff|)", "n": int(gap.size),
                 "violations": int((gap < -1e-12).sum()), **stats(gap)})
    for name, c in sets.items():
        irr = sh.irradiance(c)
        gap = (dering.exact_min(irr) - dering.min_bound(irr)) / np.abs(mean_value(irr))
        rows.append({"experiment": "bound", "set": f"{name} (unit = mean)", "n": int(gap.size),
                     "violations": int((gap < -1e-12).sum()), **stats(gap)})
    return rows


def nonnegativity(sets: dict[str, NDArray]) -> list[dict[str, Any]]:
    rows = []
    for name, c in sets.items():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", dering.DeringWarning)
            out, scales, failed = dering.dering(c, return_failed=True)
        irr = sh.irradiance(out)
        rel = dense_min(irr) / mean_value(irr)
        rows.append(
            {
                "experiment": "nonneg",
                "set": name,
                "n": int(c.shape[0]),
                "windowed": int((scales[:, 1] < 1.0).sum()),
                "negative": int((rel < -NEGATIVE_TOL).sum()),
                "min_rel": float(rel.min()),
                "failed": int(failed.sum()),
                "warnings": len(caught),
                "finite": bool(np.isfinite(out).all() and np.isfinite(scales).all()),
                "raw_negative": int((dense_min(sh.irradiance(c)) < 0).any(axis=-1).sum()),
            }
        )
    return rows


def excess(sets: dict[str, NDArray]) -> list[dict[str, Any]]:
    rows = []
    table = dering.WINDOW_TABLE
    for name, c in sets.items():
        out, scales = dering.dering(c)
        need = scales[:, 1] < 1.0
        if not need.any():
            rows.append({"experiment": "excess", "set": name, "n": 0, "tau_mean": 0.0, "tau_worst": 0.0,
                         "scale_mean": 0.0, "scale_worst": 0.0, "at_exact_grid": 1.0})
            continue
        irr = sh.irradiance(c[need])
        _, s_exact = dering.dering(c[need], method="exact")
        tau_chosen = _tau_of(scales[need], table)
        tau_grid = _tau_of(s_exact, table)
        tau_least = least_exact_tau(irr, table, tau_grid)
        ex = path_scales(tau_least, table) - scales[need]
        rows.append(
            {
                "experiment": "excess",
                "set": name,
                "n": int(need.sum()),
                "tau_mean": float((tau_chosen - tau_least).mean()),
                "tau_worst": float((tau_chosen - tau_least).max()),
                "scale_mean": float(ex.max(axis=-1).mean()),
                "scale_worst": float(ex.max()),
                "at_exact_grid": float(np.mean(np.abs(tau_chosen - tau_grid) < 1e-9)),
            }
        )
    return rows


def _tau_of(scales: NDArray, table: NDArray) -> NDArray:
    """Invert path_scales through band 2 (strictly decreasing along the table)."""
    col = table[:, 2]
    return np.interp(-scales[:, 2], -col, np.arange(col.size, dtype=float))


def detail_cost(sets3: dict[str, NDArray], sets7: dict[str, NDArray]) -> list[dict[str, Any]]:
    rows = []
    for bands, sets in ((3, sets3), (7, sets7)):
        c = np.concatenate([v for k, v in sets.items() if k != "sky"])
        e0 = sh.irradiance(c)
        _, s_ref = dering.dering(c)
        need = s_ref[:, 1] < 1.0
        one = c[np.flatnonzero(need)[0]]
        for method in dering.DERING_METHODS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", dering.DeringWarning)
                t0 = time.perf_counter()
                out, scales = dering.dering(c, method=method)
                batch = time.perf_counter() - t0
                number = 20 if (bands == 3 and method != "exact") else 2
                single = best_time(lambda: dering.dering(one, method=method), repeats=5, number=number)
            e = sh.irradiance(out)
            l2 = np.sqrt(((e - e0) ** 2).sum(axis=-2) / (e0**2).sum(axis=-2)).max(axis=-1)
            rows.append(
                {
                    "experiment": "detail",
                    "bands": bands,
                    "method": method,
                    "n_windowed": int(need.sum()),
                    "l2_rel_mean": float(l2[need].mean()),
                    "l2_rel_worst": float(l2[need].max()),
                    "single_call_us": single * 1e6,
                    "batch_s": batch,
                    "batch_n": int(c.shape[0]),
                }
            )
    return rows


# --------------------------------------------------------------------------- #
# Output
# --------------------------------------------------------------------------- #
def markdown(rows: list[dict[str, Any]], keys: list[str]) -> str:
    def fmt(v: Any) -> str:
        if isinstance(v, float):
            return f"{v:.4g}"
        if isinstance(v, list):
            return "(" + ", ".join(f"{x:.4f}" for x in v) + ")"
        return str(v)

    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(fmt(r.get(k)) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--quick", action="store_true", help="fewer skies, lights and random functions")
    parser.add_argument("--seed", type=int, default=2017, help="random seed")
    args = parser.parse_args(argv)
    counts = QUICK if args.quick else FULL
    rng = np.random.default_rng(args.seed)

    skies, source = sky_coefficients(counts["skies"], rng)
    light_seed = int(rng.integers(1 << 31))
    sets3 = {"sky": skies, **lights(counts["lights"], np.random.default_rng(light_seed), 3)}
    sets7 = lights(counts["lights"] // 4, np.random.default_rng(light_seed), 7)
    print(f"# Deringing experiment ({'quick' if args.quick else 'full'}); sky source: {source}\n")

    all_rows: list[dict[str, Any]] = []
    sections = [
        ("1. Windowed delta irradiance minimum / mean (Table 1 vs eq. 6 vs WINDOW_TABLE)", table_finding(),
         ["w", "table1", "table1_delta_min_rel", "sinc4", "sinc4_delta_min_rel", "window_table",
          "window_table_delta_min_rel"]),
        ("2. Bound conservativeness: (exact_min - min_bound) / unit of 3-band irradiance",
         bound_conservativeness(sets3, rng, counts["random"]), ["set", "n", "violations", "mean", "p95", "worst"]),
        ("3. Irradiance after deringing (table + bound) on a dense sphere", nonnegativity(sets3),
         ["set", "n", "raw_negative", "windowed", "negative", "min_rel", "failed", "warnings", "finite"]),
        ("4. Excess windowing over the least table position exact_min accepts", excess(sets3),
         ["set", "n", "tau_mean", "tau_worst", "scale_mean", "scale_worst", "at_exact_grid"]),
        ("5. Detail kept (relative L2 of irradiance to unwindowed) against cost", detail_cost(sets3, sets7),
         ["bands", "method", "n_windowed", "l2_rel_mean", "l2_rel_worst", "single_call_us", "batch_s", "batch_n"]),
    ]
    for title, rows, keys in sections:
        print(f"## {title}\n\n{markdown(rows, keys)}\n")
        all_rows += rows
    for row in all_rows:
        print(json.dumps(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
