"""
Deringing measurements (Sloan 2017, seed 000, and the exact minimum)
====================================================================

Prints markdown tables, then one JSON line per row:

1.  **Table 1 vs eq. (6)**: the least irradiance of a windowed delta (of its mean) for the
    seed's Table 1, plain eq. (6) and :data:`skysh.post.dering.WINDOW_TABLE`.
2.  **The seed's bound against the exact minimum**: ``exact_min - min_bound`` for random
    3-band functions (unit: largest |coefficient|), skies and lights (unit: mean); a
    violation is a bound above the minimum.
3.  **The 3-band minimum's rounding and Newton steps**: the shipped dual against the root
    found by 200 bisection steps (independent of Newton), and the shortfall of 1..5 steps
    against 64, on random and adversarial (hard-case, clustered eigenvalue) problems.
4.  **The 4..7-band certificate**: its covering radius (scipy's convex hull), the slack
    ``value at the direction - certified bound`` of :func:`skysh.post.dering.exact_min`, and the
    curvature bound of the last table row, on lights and for any non-negative light
    (``sum_l l^2 (2l+1) |A_l| / A_0 s_l`` means: the basis of ``CERTIFIED_MARGIN``).
5.  **Windowing excess**: the windows of :func:`skysh.post.dering.dering` (the least window,
    and whole rows) against the least continuous position along the table path (linear
    interpolation between rows, bisection to 2^-12 of a row on exact_min), and the relative
    L2 change of the irradiance.
6.  **Timings**: one (K, 3) call and per item of a batch, 3 and 7 bands, by method.

Skies come from ``skysh.SkySH`` (``gibbs=False``); lights are non-negative by construction
(HDR deltas, arcs of deltas, ambient). Run::

    PYTHONPATH=. python tools/dering_experiment.py --quick
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray
from studies.seed_bound import min_bound

from skysh import SkySH
from skysh.post import dering
from skysh.sh import basis as sh
from skysh.sh import minimum as shmin

QUICK: dict[str, int] = {"skies": 200, "lights": 120, "random": 2000}
"""Sample counts with --quick."""

FULL: dict[str, int] = {"skies": 2000, "lights": 600, "random": 20000}
"""Sample counts by default."""

EXCESS_BISECTION: int = 12
"""Bisection steps for the least continuous table position (2^-12 of a row)."""


def mean_value(coeffs: NDArray) -> NDArray:
    """Mean over the sphere of SH (..., K, C): c0 / (2 sqrt(pi)), (..., C)."""
    return coeffs[..., 0, :] * (0.5 / math.sqrt(math.pi))


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
    x = np.asarray(x, dtype=np.float64).ravel()
    return {"mean": float(x.mean()), "p95": float(np.quantile(x, 0.95)), "worst": float(x.max())}


def lights(n: int, rng: np.random.Generator, bands: int) -> NDArray:
    """(n, K, 3) non-negative lights: 1-3 HDR deltas, maybe an arc of 64 deltas and ambient."""
    out = np.zeros((n, bands * bands, 3))
    for i in range(n):
        d = rng.normal(size=(int(rng.integers(1, 4)), 3))
        out[i] = sh.basis(d / np.linalg.norm(d, axis=1, keepdims=True), bands).T @ (10.0 ** rng.uniform(-1, 3, (len(d), 3)))
        if rng.random() < 0.5:
            a, b = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 3)))
            b = (b - a * (a @ b)) / np.linalg.norm(b - a * (a @ b))
            t = np.linspace(0.0, rng.uniform(0.05, 1.5), 64)
            ring = sh.basis(np.cos(t)[:, None] * a + np.sin(t)[:, None] * b, bands).sum(0)[:, None]
            out[i] += ring * 10.0 ** rng.uniform(0, 2, 3) / 64
        if rng.random() < 0.4:
            out[i, 0] += 10.0 ** rng.uniform(-2, 1, 3) * 2.0 * math.sqrt(math.pi)
    return out


def skies(n: int, rng: np.random.Generator, bands: int) -> NDArray:
    """(n, K, 3) sky radiance SH over the fitted domain, without the Gibbs filter."""
    return np.asarray(SkySH.load().coefficients(rng.uniform(0, math.pi / 2, n), rng.uniform(2.5, 6.0, n),
                                                rng.uniform(0, 2 * math.pi, n), bands=bands, gibbs=False))


def table_finding() -> list[dict[str, Any]]:
    rows = []
    for i, w in enumerate(dering.SEED_WINDOW_SIZES):
        rows.append({"experiment": "table", "w": w, "seed Table 1": dering.delta_minimum(dering.SEED_TABLE_1[i, :3]) / 0.25,
                     "eq. (6)": dering.delta_minimum(dering.sinc4_window(w, 3)) / 0.25,
                     "WINDOW_TABLE": dering.delta_minimum(dering.WINDOW_TABLE[i]) / 0.25})
    return rows


def bound_conservativeness(sets: dict[str, NDArray], rng: np.random.Generator, n_random: int) -> list[dict[str, Any]]:
    """``exact_min - min_bound`` per set (irradiance of radiance SH (n, 9, C)) and for random functions."""
    rand = rng.normal(size=(n_random, 9, 1)) * rng.uniform(0.0, 2.0, (n_random, 9, 1)) ** 2
    gap = (dering.exact_min(rand) - min_bound(rand)) / np.abs(rand).max(axis=-2)
    rows = [{"experiment": "bound", "set": "random (unit = max |coeff|)", "n": int(gap.size),
             "violations": int((gap < -1e-12).sum()), **stats(gap)}]
    for name, c in sets.items():
        irr = sh.irradiance(c)
        gap = (dering.exact_min(irr) - min_bound(irr)) / np.abs(mean_value(irr))
        rows.append({"experiment": "bound", "set": f"{name} (unit = mean)", "n": int(gap.size),
                     "violations": int((gap < -1e-12).sum()), **stats(gap)})
    return rows


def secular_problems(rng: np.random.Generator, n: int) -> dict[str, tuple[NDArray, NDArray]]:
    """(lam ascending, a) of random and adversarial secular equations, n each."""
    q = rng.normal(size=(n, 3, 3))
    lam, v = np.linalg.eigh(q + np.swapaxes(q, 1, 2))
    a = 0.25 * np.einsum("nji,nj->ni", v, rng.normal(size=(n, 3))) ** 2
    near = a * np.stack([10.0 ** rng.uniform(-40, 0, n), np.ones(n), np.ones(n)], 1)
    cl_lam = lam.copy()
    cl_lam[:, 1] = lam[:, 0] + 10.0 ** rng.uniform(-16, -6, n) * (lam[:, 2] - lam[:, 0])
    cl_a = a * np.stack([10.0 ** rng.uniform(-20, -4, n), 10.0 ** rng.uniform(-12, -2, n), np.ones(n)], 1)
    return {"random": (lam, a), "near hard case": (lam, near), "hard case": (lam, a * [0.0, 1.0, 1.0]),
            "clustered eigenvalues": (cl_lam, cl_a), "Q = 0": (np.zeros_like(lam), a)}


def dual_after(lam: NDArray, a: NDArray, steps: int) -> NDArray:
    """The module's dual value for c = 0 after its steps: proven start, one step, estimates, ``steps``."""
    d = lam - lam[..., :1]
    x = shmin.prefix_bound(d, a)
    x = shmin.newton(d, a, shmin.cluster_bounds(d, a, shmin.newton(d, a, x, 1)), steps)
    return shmin.dual(np.zeros(len(lam)), lam, d, a, x)


def secular(rng: np.random.Generator, n: int) -> list[dict[str, Any]]:
    rows = []
    for name, (lam, a) in secular_problems(rng, n).items():
        d, size = lam - lam[:, :1], np.abs(lam).max(1) + 2.0 * np.sqrt(a.sum(1)) + 1e-300
        lo, hi = np.zeros(n), np.sqrt(a.sum(1)) + 1e-300
        for _ in range(200):  # bisection on sum a / (d + x)^2 = 1: independent of Newton
            mid = 0.5 * (lo + hi)
            with np.errstate(divide="ignore", invalid="ignore"):
                big = (a / (d + mid[:, None]) ** 2).sum(1) > 1.0
            lo, hi = np.where(big, mid, lo), np.where(big, hi, mid)
        with np.errstate(divide="ignore", invalid="ignore"):
            truth = np.where(hi > 0, lam[:, 0] - hi - np.nan_to_num((a / (d + hi[:, None])).sum(1)), lam[:, 0])
        row = {"experiment": "secular", "problems": name, "n": n}
        for steps in (1, 2, 3, 4, 5, 64):
            row[f"{steps} steps: worst below truth"] = float(((truth - dual_after(lam, a, steps)) / size).max())
        row["shipped: worst above truth"] = float(((dual_after(lam, a, shmin.NEWTON_STEPS) - truth) / size).max())
        rows.append(row)
    return rows


def certificate(rng: np.random.Generator, n: int) -> list[dict[str, Any]]:
    from scipy.spatial import ConvexHull

    p = shmin.fibonacci(shmin.DIRECTIONS)
    tri = p[ConvexHull(p).simplices]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    cover = float(np.arccos(np.abs(np.einsum("ij,ij->i", normal, tri[:, 0]))).max())
    rows = [{"experiment": "certificate", "covering radius (rad)": cover, "COVER_RADIUS": shmin.COVER_RADIUS}]
    for bands in (4, 5, 6, 7):
        sets = {"random": rng.normal(size=(n, bands * bands, 1)) * rng.uniform(0, 2, (n, bands * bands, 1)) ** 2,
                "lights' irradiance": sh.irradiance(lights(n // 4, rng, bands)),
                "skies' irradiance": sh.irradiance(skies(n // 4, rng, bands))}
        for name, c in sets.items():
            t0 = time.perf_counter()
            val, w = dering.exact_min(c, return_dirs=True)
            seconds = (time.perf_counter() - t0) / (c.shape[0] * c.shape[-1])
            at = np.einsum("...ck,...kc->...c", sh.basis(w, bands), c)
            slack = (at - val) / np.abs(c).max(axis=-2)
            rows.append({"experiment": "certificate", "bands": bands, "set": name, "n": int(slack.size),
                         "slack / max|c| mean": float(slack.mean()), "worst": float(slack.max()),
                         "negative slack (must be 0)": int((slack < 0).sum()), "ms per function": 1e3 * seconds})
        last = dering.window_table(bands)[-1][sh.band_of_index(bands), None]
        irr = sh.irradiance(lights(n // 4, rng, bands) * last)
        norms = [np.linalg.norm(irr[:, l * l:(l + 1) ** 2], axis=1) * math.sqrt((2 * l + 1) / (4 * math.pi))
                 for l in range(bands)]
        k2 = sum(l * l * x for l, x in enumerate(norms)) / np.abs(mean_value(irr))
        ell = np.arange(bands)
        analytic = max(float((ell**2 * (2 * ell + 1) * np.abs(dering.KERNELS[tg][:bands]) / dering.KERNELS[tg][0]
                              * dering.window_table(bands, tg)[-1]).sum()) for tg in dering.DERING_TARGETS)
        def slack(level: int, analytic: float = analytic) -> float:  # K r^2 / 2 at a level's half-diagonal
            return analytic * (math.sqrt(2) * shmin.COVER_RADIUS / 2**level) ** 2 / 2

        rows.append({"experiment": "certificate", "bands": bands, "set": "last row, lights",
                     "curvature bound / mean, worst": float(k2.max()), "any non-negative light (either target)": analytic,
                     "final-level slack / mean, any light": slack(shmin.LEVELS),
                     "levels until below the margin": next(k for k in range(64) if slack(k) < dering.CERTIFIED_MARGIN),
                     "LEVELS": shmin.LEVELS, "CERTIFIED_MARGIN": dering.CERTIFIED_MARGIN})
    return rows


def excess(sets: dict[str, NDArray]) -> list[dict[str, Any]]:
    """Each method's window against the least continuous position along the table path (3 bands): the
    position beyond it (rows) and the relative L2 change of the irradiance."""
    table, rows = dering.WINDOW_TABLE, []
    for name, c in sets.items():
        for method in dering.DERING_METHODS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", dering.DeringWarning)
                _, scales, failed = dering.dering(c, method=method, return_failed=True)
                position = dering.least_window(c, method=method)[0]
            row = np.ceil(position).astype(int)
            lo, hi = np.maximum(row - 1.0, 0.0), row.astype(float)
            for _ in range(EXCESS_BISECTION):  # the least tau in (row - 1, row] whose exact minimum is >= 0
                mid = 0.5 * (lo + hi)
                i = np.minimum(np.floor(mid).astype(int), len(table) - 2)
                s = table[i] + (mid - i)[:, None] * (table[i + 1] - table[i])
                ok = (dering.exact_min(sh.irradiance(c * s[:, sh.band_of_index(3), None])) >= 0).all(-1)
                lo, hi = np.where(ok, lo, mid), np.where(ok, mid, hi)
            keep = ~failed & (row > 0)
            base = sh.irradiance(c)
            windowed = sh.irradiance(c * scales[:, sh.band_of_index(3), None])
            change = np.sqrt(((windowed - base) ** 2).sum(1) / (base ** 2).sum(1)).max(-1)
            beyond = (position - hi)[keep]
            rows.append({"experiment": "excess", "set": name, "method": method, "windowed": int(keep.sum()),
                         "n": len(c), "rows beyond the least continuous position, mean":
                         float(beyond.mean()) if keep.any() else 0.0, "worst": float(beyond.max()) if keep.any() else 0.0,
                         "L2 change of the irradiance, mean": float(change[keep].mean()) if keep.any() else 0.0})
    return rows


def timings(rng: np.random.Generator) -> list[dict[str, Any]]:
    rows = []
    for bands in (3, 7):
        one, batch = lights(1, rng, bands)[0], lights(200 if bands == 3 else 20, rng, bands)
        exact = best_time(lambda batch=batch: dering.exact_min(batch), 3, 1) / (3 * len(batch))
        for method in dering.DERING_METHODS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", dering.DeringWarning)
                single = best_time(lambda one=one, m=method: dering.dering(one, method=m), 5, 20 if bands == 3 else 2)
                per = best_time(lambda batch=batch, m=method: dering.dering(batch, method=m), 3, 1) / len(batch)
            rows.append({"experiment": "timing", "bands": bands, "method": method,
                         "dering one (K, 3) light, us": 1e6 * single, f"dering per item of {len(batch)}, us": 1e6 * per,
                         "exact_min per function, us": 1e6 * exact})
    return rows


def markdown(rows: list[dict[str, Any]]) -> str:
    keys = [k for k in rows[0] if k != "experiment"]
    fmt = lambda v: f"{v:.3g}" if isinstance(v, float) else str(v)  # noqa: E731
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    return "\n".join(lines + ["| " + " | ".join(fmt(r.get(k, "")) for k in keys) + " |" for r in rows])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Deringing measurements")
    parser.add_argument("--quick", action="store_true", help="small samples (about a minute)")
    args = parser.parse_args(argv)
    n = QUICK if args.quick else FULL
    rng = np.random.default_rng(2017)
    sets = {"skies": skies(n["skies"], rng, 3), "lights": lights(n["lights"], rng, 3)}
    groups = {"1. Table 1 vs eq. (6) (delta's least irradiance / mean)": table_finding(),
              "2. min_bound against exact_min": bound_conservativeness(sets, rng, n["random"]),
              "3. The 3-band minimum: truth - value (unit: size)": secular(rng, n["random"]),
              "4. The 4..7-band certificate": certificate(rng, n["lights"]),
              "5. Windowing excess (3 bands)": excess(sets),
              "6. Timings": timings(rng)}
    for title, rows in groups.items():
        print(f"\n### {title}\n")
        for kind in dict.fromkeys(tuple(r) for r in rows):  # one table per row layout
            print(markdown([r for r in rows if tuple(r) == kind]) + "\n")
    for rows in groups.values():
        for r in rows:
            print(json.dumps(r))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
