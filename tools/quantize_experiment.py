"""
The quantization and irradiance-reconstruction studies on sky data
==================================================================

Two studies over many (sun zenith, sun azimuth, turbidity) points of the fitted
domain (:mod:`studies.sky`):

1.  The Table 3 of Wiederien and Sloan (2024) on sky data
    (:func:`studies.quantize_study.table3_experiment`): L1, L2 and RMSE of the
    reconstructed radiance and irradiance after 8-bit compression with the
    prior bound sqrt(5) and the tight bound sqrt(15)/2, with and without the
    square root, and the relative change; then how much the L1 column moves at
    twice the quadrature nodes (:func:`studies.quantize_study.l1_rule_check`).
2.  Irradiance reconstructions against the sky's exact irradiance
    (:func:`studies.hazel_study.irradiance_experiment`): linear L1, Geomerics'
    non-linear L1, L2 and deringed L2, with the hand-counted shader cost, the
    exact irradiance's truncation estimate and a numpy throughput measured here
    (``time.perf_counter``, best of 5 after a warm-up; a CPU figure, not a GPU one).

Prints markdown tables, then one JSON line per table row.

Run::

    python tools/quantize_experiment.py --quick
    python tools/quantize_experiment.py            # 1024 + 64 points

Sky data for (1) come from the source named by ``--source`` (default: the shipped
runtime ``skysh.SkySH``; ``reference``: ``skysh.model.preetham.sky_sh``); (2) always uses
the reference projection at 32 bands.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from studies import hazel_study, quantize_study, sky

from skysh.post import hazel, quantize

RULE_CHECK_POINTS: int = 64
"""Sky points of the L1 quadrature check (the doubled rule costs four times the Table 3 rule)."""

QUICK_POINTS: tuple[int, int] = (64, 8)
"""Sky points of (Table 3, irradiance comparison) with --quick."""

FULL_POINTS: tuple[int, int] = (1024, 64)
"""Sky points of (Table 3, irradiance comparison) by default."""

SEED_TABLE3: dict[str, float] = {
    "L1": 4.593, "L2": 5.361, "RMSE": 1.493, "sqrt L1": 2.146, "sqrt L2": 2.151, "sqrt RMSE": 5.0,
}
"""The seed's Table 3 "Delta error" columns on PBR_White_Box, percent, for comparison."""

TIMING_NORMALS: int = 1 << 16
"""Normals per timing run of the reconstructions."""


def _fmt(value: float) -> str:
    return f"{value:.4g}" if abs(value) >= 1e-3 or value == 0.0 else f"{value:.3e}"


def table3_markdown(result: dict[str, Any]) -> str:
    """The seed's Table 3 layout, one table per quantity."""
    lines = []
    for quantity in ("radiance", "irradiance"):
        rows = {(r["sqrt"], r["bound"]): r for r in result["rows"] if r["quantity"] == quantity}
        change = {(c["sqrt"], c["metric"]): c["change_percent"] for c in result["changes"] if c["quantity"] == quantity}
        lines.append(f"\n**{quantity}** ({result['probes']} sky points x {result['channels']} channels, "
                     f"{result['bits']} bits, sky data: {result['source']})\n")
        lines.append("| Function | sqrt(5) | sqrt(15)/2 | Δ error | sqrt, sqrt(5) | sqrt, sqrt(15)/2 | Δ error |")
        lines.append("|---|---|---|---|---|---|---|")
        for metric in ("L1", "L2", "RMSE"):
            cells = []
            for use_sqrt in (False, True):
                cells += [_fmt(rows[(use_sqrt, "prior")][metric]), _fmt(rows[(use_sqrt, "tight")][metric]),
                          f"{change[(use_sqrt, metric)]:.3f}%"]
            lines.append(f"| {metric} error | " + " | ".join(cells) + " |")
        clamped = sum(r["clamped"] for r in rows.values())
        lines.append(f"\nCoefficients clamped (outside their bound): {clamped}")
    seed = ", ".join(f"{k} {v:g}%" for k, v in SEED_TABLE3.items())
    lines.append(f"\nSeed (PBR_White_Box, radiance): {seed}.")
    return "\n".join(lines)


def _best_time(function: Callable[[], Any], repeats: int = 5) -> float:
    function()  # warm-up
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def reconstruction_timings(seed: int = 0) -> dict[str, float]:
    """Numpy nanoseconds per normal and channel of each reconstruction (one probe, RGB)."""
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(TIMING_NORMALS, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    coeffs = np.abs(rng.normal(size=(9, 3)))
    coeffs[0] += 5.0
    functions: dict[str, Callable[[], Any]] = {
        "L1 linear": lambda: hazel.irradiance(coeffs[:4], normals),
        "L1 non-linear (Geomerics)": lambda: hazel.irradiance_l1_nonlinear(coeffs[:4], normals),
        "L2": lambda: hazel.irradiance(coeffs, normals),
        "L2 deringed": lambda: hazel.irradiance(coeffs, normals),  # same per-normal work as L2
    }
    return {name: 1e9 * _best_time(f) / (TIMING_NORMALS * 3) for name, f in functions.items()}


def hazel_markdown(result: dict[str, Any], timings: dict[str, float]) -> str:
    lines = [
        f"\n**Irradiance I = E / pi against the sky's exact irradiance** ({result['points']} sky points x 3 "
        f"channels x {result['normals']} normals; errors relative to the mean irradiance R0)\n",
        "| Method | mean abs | RMS | max abs | min I / R0 | negative area | floats/ch | ALU/normal/ch "
        "| transc./normal/ch | numpy ns/normal/ch |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in result["rows"]:
        lines.append(
            f"| {row['method']} | {_fmt(row['mean_abs'])} | {_fmt(row['rms'])} | {_fmt(row['max_abs'])} | "
            f"{_fmt(row['min'])} | {_fmt(row['negative_area'])} | {row['floats_per_channel']} | "
            f"{row['alu_per_normal']} | {row['transcendental_per_normal']} | {timings[row['method']]:.2f} |"
        )
    lines.append(f"\nExact-irradiance truncation estimate max |I({result['exact_bands']}) - "
                 f"I({result['exact_bands'] - 8})| / R0 = {result['truncation']:.2e}")
    lines += [f"- {note}" for note in result["notes"]]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help=f"{QUICK_POINTS[0]} + {QUICK_POINTS[1]} sky points")
    parser.add_argument("--points", type=int, help="sky points of the Table 3 experiment")
    parser.add_argument("--hazel-points", type=int, help="sky points of the irradiance comparison")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sky points (default 0)")
    parser.add_argument("--bits", type=int, default=quantize.DEFAULT_BITS, help="bits per coefficient (default 8)")
    parser.add_argument("--source", choices=sky.SKY_SOURCES, default="runtime",
                        help="sky data of Table 3 (default: runtime)")
    parser.add_argument("--exact-bands", type=int, default=hazel_study.EXACT_BANDS,
                        help="bands of the exact irradiance")
    parser.add_argument("--only", choices=("table3", "hazel"), help="run one experiment")
    args = parser.parse_args(argv)
    default = QUICK_POINTS if args.quick else FULL_POINTS
    points = args.points or default[0]
    hazel_points = args.hazel_points or default[1]

    records: list[dict[str, Any]] = []
    if args.only in (None, "table3"):
        start = time.perf_counter()
        result = quantize_study.table3_experiment(points, seed=args.seed, bits=args.bits, source=args.source)
        print(f"## Table 3 on sky data ({time.perf_counter() - start:.1f} s)")
        print(table3_markdown(result))
        rule = quantize_study.l1_rule_check(min(points, RULE_CHECK_POINTS), seed=args.seed, bits=args.bits,
                                            source=args.source)
        print(f"\nL1 quadrature check ({min(points, RULE_CHECK_POINTS)} points): max |L1({quantize.TABLE3_THETA_NODES}"
              f" nodes) - L1({2 * quantize.TABLE3_THETA_NODES} nodes)| / L1 = {rule:.2e}")
        common = {"source": result["source"], "points": points, "seed": args.seed, "bits": result["bits"]}
        records += [{"experiment": "table3", **common, **row} for row in result["rows"]]
        records += [{"experiment": "table3_change", **common, **change} for change in result["changes"]]
        records.append({"experiment": "table3_l1_rule", **common, "l1_rule_change": rule})
    if args.only in (None, "hazel"):
        start = time.perf_counter()
        result = hazel_study.irradiance_experiment(hazel_points, seed=args.seed, exact_bands=args.exact_bands)
        timings = reconstruction_timings(args.seed)
        print(f"\n## Irradiance reconstructions ({time.perf_counter() - start:.1f} s)")
        print(hazel_markdown(result, timings))
        common = {"points": hazel_points, "seed": args.seed, "exact_bands": result["exact_bands"],
                  "truncation": result["truncation"]}
        records += [{"experiment": "irradiance", **common, **row, "numpy_ns": timings[row["method"]]}
                    for row in result["rows"]]
        records += [{"experiment": "irradiance_note", "note": note} for note in result["notes"]]
    print()
    for record in records:
        print(json.dumps(record))
    return 0


if __name__ == "__main__":
    sys.exit(main())
