"""
What a compiled per-call kernel would buy (evidence for a design decision)
==========================================================================

The runtime is pure numpy. ``benchmarks/bench_runtime.py`` shows it misses two
of the fit issue's speed targets: one call <= 3x one numpy matrix-vector
product, and a batch <= 1.5x the batched matrix product. The cause is numpy's
fixed cost per call and memory traffic, not arithmetic. This script measures
the alternative: the same arithmetic (the runtime's own precomputed tables) in
a numba-compiled kernel. It is **not** part of the package and numba is
**not** a dependency. The script skips, saying so, when numba is not
installed (``pip install numba``).

Timings interleave the candidate with the runtime and the baselines, as
``bench_runtime.py`` does, so the ratios compare like with like:

-   ``single``: a Python wrapper (the runtime's validation, its luminance scale
    and an output array) around one compiled call, against the numpy runtime
    and against ``np.dot(v, A)`` with A of shape (112, 3 N^2);
-   ``batch``: one compiled call over 10^5 parameter sets, parallel over the
    points (``numba.prange``), against the numpy runtime and the batched
    product ``(10^5, 112) @ (112, 3 N^2)``.

The script checks that the kernel agrees with the runtime to 1e-13 of the
largest coefficient (a different summation order) before timing.

Run: ``python benchmarks/bench_compiled.py [--repeats 7] [--batch 100000]``.
One JSON line per measurement.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_runtime import interleaved_best

from skysh import runtime
from skysh.domain import SKY
from skysh.model.preetham import luminance_scale_unchecked

AGREEMENT: float = 1e-13
"""Largest difference kernel vs runtime, in units of the largest coefficient: the two sum
the 112 terms in different orders (rounding ~ 112 eps), far above it only if wrong."""


def build_kernels():  # pragma: no cover - needs numba
    import numba

    @numba.njit(cache=False, nogil=True)
    def evaluate_into(table, gather, rot, nx, ny, bands, ax, ay, phi, scale, out, tx, ty, half, row, rf):
        """One parameter set into ``out`` with caller-owned scratch: Chebyshev terms, the two
        contractions (x outer, y inner, as the runtime), rotation (eq. 4)."""
        width = half.shape[0]
        # T_k = cos(k acos x) by the three-term recurrence (no transcendental call per term).
        x, y = math.cos(ax), math.cos(ay)
        tx[0], ty[0] = 1.0, scale
        if nx > 1:
            tx[1] = x
        if ny > 1:
            ty[1] = y * scale
        for k in range(2, nx):
            tx[k] = 2.0 * x * tx[k - 1] - tx[k - 2]
        for k in range(2, ny):
            ty[k] = 2.0 * y * ty[k - 1] - ty[k - 2]
        half[:] = 0.0
        for i in range(nx):
            row[:] = 0.0
            for j in range(ny):
                w = ty[j]
                base = j * width
                for c in range(width):
                    row[c] += w * table[i, base + c]
            w = tx[i]
            for c in range(width):
                half[c] += w * row[c]
        c1, s1 = math.cos(phi), math.sin(phi)  # cos(m phi), sin(m phi) by angle addition
        rf[0], rf[bands] = 1.0, 0.0
        for m in range(1, bands):
            rf[m] = rf[m - 1] * c1 - rf[bands + m - 1] * s1
            rf[bands + m] = rf[bands + m - 1] * c1 + rf[m - 1] * s1
        for o in range(gather.shape[0]):
            f = rf[rot[o]]
            for ch in range(3):
                out[o, ch] = half[gather[o, ch]] * f

    @numba.njit(cache=False)
    def evaluate(table, gather, rot, nx, ny, bands, ax, ay, phi, scale, out):
        width = table.shape[1] // ny
        evaluate_into(table, gather, rot, nx, ny, bands, ax, ay, phi, scale, out,
                      np.empty(nx), np.empty(ny), np.empty(width), np.empty(width), np.empty(2 * bands))

    @numba.njit(parallel=True, cache=False)
    def evaluate_many(table, gather, rot, nx, ny, bands, ax, ay, phi, scale, out):
        n = ax.shape[0]
        width = table.shape[1] // ny
        chunks = 64  # scratch allocated once per chunk, not per point
        for k in numba.prange(chunks):
            tx, ty, half, row, rf = np.empty(nx), np.empty(ny), np.empty(width), np.empty(width), np.empty(2 * bands)
            for p in range(k * n // chunks, (k + 1) * n // chunks):
                evaluate_into(table, gather, rot, nx, ny, bands, ax[p], ay[p], phi[p], scale[p], out[p],
                              tx, ty, half, row, rf)

    return evaluate, evaluate_many


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Compiled-kernel evidence for the runtime's speed targets")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--batch", type=int, default=100_000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    try:
        evaluate, evaluate_many = build_kernels()
        import numba
    except ImportError:
        print(json.dumps({"bench": "compiled", "skipped": "numba is not installed (pip install numba)"}))
        return 0
    sky = runtime.SkySH.load()
    print(json.dumps({"bench": "environment", "numba": numba.__version__, "numpy": np.__version__,
                      "threads": numba.get_num_threads(), "batch": args.batch}), flush=True)
    rng = np.random.default_rng(args.seed)
    ts = rng.uniform(0.0, math.pi / 2.0, args.batch)
    tu = rng.uniform(2.5, 6.0, args.batch)
    phi = rng.uniform(-math.pi, math.pi, args.batch)
    n_terms = 112
    vector = rng.standard_normal(n_terms)
    design = rng.standard_normal((args.batch, n_terms))

    for bands in (7, 3):
        plan = sky.plan(bands, True)
        nx, ny = plan.split[0], plan.split[1] - plan.split[0]
        table, gather, rot = plan.half_table, plan.gather, plan.rot_index
        (z0, z1), (t0, t1) = SKY.x.interval, SKY.y.interval

        def compiled_one(ts_: float, t_: float, phi_: float) -> np.ndarray:
            # The runtime's own validation and argument reduction, then one compiled call.
            if not (z0 <= ts_ <= z1 and t0 <= t_ <= t1 and math.isfinite(phi_)):
                raise ValueError("out of domain")
            x = ts_ * SKY.x.scale - SKY.x.shift
            y = math.log(t_) * SKY.y.scale - SKY.y.shift
            out = np.empty((bands * bands, 3))
            evaluate(table, gather, rot, nx, ny, bands, math.acos(min(x, 1.0)), math.acos(max(-1.0, min(y, 1.0))),
                     math.fmod(phi_, 2 * math.pi), luminance_scale_unchecked(ts_, t_), out)
            return out

        def compiled_many() -> np.ndarray:
            x = np.clip(ts * SKY.x.scale - SKY.x.shift, -1.0, 1.0)
            y = np.clip(np.log(tu) * SKY.y.scale - SKY.y.shift, -1.0, 1.0)
            out = np.empty((args.batch, bands * bands, 3))
            evaluate_many(table, gather, rot, nx, ny, bands, np.arccos(x), np.arccos(y), np.fmod(phi, 2 * math.pi),
                          luminance_scale_unchecked(ts, tu, np), out)
            return out

        reference = sky.coefficients(0.5, 3.0, 1.0, bands=bands)
        scale = np.abs(reference).max()
        assert np.abs(compiled_one(0.5, 3.0, 1.0) - reference).max() <= AGREEMENT * scale
        batch_ref = sky.coefficients(ts, tu, phi, bands=bands)
        assert np.abs(compiled_many() - batch_ref).max() <= AGREEMENT * np.abs(batch_ref).max()

        matrix = rng.standard_normal((n_terms, 3 * bands * bands))
        t = interleaved_best({
            "compiled": lambda: compiled_one(0.5, 3.0, 1.0),
            "numpy runtime": lambda: sky.coefficients(0.5, 3.0, 1.0, bands=bands),
            "dot": lambda: np.dot(vector, matrix),
        }, args.repeats)
        print(json.dumps({"bench": "single", "bands": bands, "compiled_s": t["compiled"],
                          "numpy_runtime_s": t["numpy runtime"], "baseline_s": t["dot"],
                          "compiled_ratio": t["compiled"] / t["dot"], "numpy_ratio": t["numpy runtime"] / t["dot"],
                          "target": "ratio <= 3"}), flush=True)
        t = interleaved_best({
            "compiled": compiled_many,
            "numpy runtime": lambda: sky.coefficients(ts, tu, phi, bands=bands),
            "matmul": lambda: design @ matrix,
        }, args.repeats, run_seconds=0.0)
        print(json.dumps({"bench": "batch", "bands": bands, "compiled_s": t["compiled"],
                          "numpy_runtime_s": t["numpy runtime"], "baseline_s": t["matmul"],
                          "compiled_ratio": t["compiled"] / t["matmul"],
                          "numpy_ratio": t["numpy runtime"] / t["matmul"], "target": "ratio <= 1.5"}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
