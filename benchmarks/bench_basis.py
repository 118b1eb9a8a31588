"""
Throughput of :func:`skysh.sh.basis.basis` against a scipy route
==========================================================

Evaluates the real SH basis (Condon-Shortley phase, ``i = l (l + 1) + m``) on
10^5 random unit vectors for bands 3, 7 and 16, once with :func:`skysh.sh.basis.basis`
and once the way a user would with scipy: ``scipy.special.sph_harm_y`` in a loop
over (l, m >= 0), turned real as

    Y(l, 0) = Re Y_l^0,  Y(l, m > 0) = sqrt(2) Re Y_l^m,  Y(l, -m) = sqrt(2) Im Y_l^m

(scipy's complex Y_l^m already carries the Condon-Shortley phase), plus the
``arccos`` / ``arctan2`` to get (theta, phi) from the vectors.

Each timing is the best of ``--repeats`` runs after one warm-up run, measured
with :func:`time.perf_counter`. One JSON line per band count::

    {"bench": "basis", "bands": 7, "n": 100000, "skysh_s": ..., "scipy_s": ...,
     "speedup": ..., "max_abs_diff": ...}

``max_abs_diff`` checks that both routes computed the same thing.

Run: ``PYTHONPATH=. python benchmarks/bench_basis.py [--n 100000] [--repeats 5]``.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

import numpy as np
from scipy.special import sph_harm_y

from skysh.sh import basis as sh

BANDS: tuple[int, ...] = (3, 7, 16)
"""Band counts timed: low order (irradiance), the sky's default, the test maximum."""


def scipy_basis(dirs: np.ndarray, bands: int) -> np.ndarray:
    """Real CS-phase SH through scipy, (M, bands**2): what a user would write."""
    theta = np.arccos(np.clip(dirs[:, 2], -1.0, 1.0))
    phi = np.arctan2(dirs[:, 1], dirs[:, 0])
    out = np.empty((dirs.shape[0], bands * bands))
    for l in range(bands):
        for m in range(l + 1):
            y = sph_harm_y(l, m, theta, phi)
            if m == 0:
                out[:, l * l + l] = y.real
            else:
                out[:, l * l + l + m] = np.sqrt(2.0) * y.real
                out[:, l * l + l - m] = np.sqrt(2.0) * y.imag
    return out


def best_time(fn: Callable[[], object], repeats: int) -> float:
    """Best wall time of ``repeats`` calls after one warm-up call, seconds."""
    fn()
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--n", type=int, default=100_000, help="number of random unit vectors")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats (best is kept)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    rng = np.random.default_rng(args.seed)
    dirs = rng.normal(size=(args.n, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)

    for bands in BANDS:
        diff = float(np.max(np.abs(sh.basis(dirs, bands) - scipy_basis(dirs, bands))))
        skysh_s = best_time(lambda: sh.basis(dirs, bands), args.repeats)
        scipy_s = best_time(lambda: scipy_basis(dirs, bands), args.repeats)
        record = {
            "bench": "basis",
            "bands": bands,
            "n": args.n,
            "skysh_s": round(skysh_s, 6),
            "scipy_s": round(scipy_s, 6),
            "speedup": round(scipy_s / skysh_s, 2),
            "max_abs_diff": diff,
        }
        print(json.dumps(record), flush=True)


if __name__ == "__main__":
    main()
