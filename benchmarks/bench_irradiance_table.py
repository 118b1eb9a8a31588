"""
Cost of the tabulated irradiance (issue 18)
===========================================

Issue 18's speed goal, measured side by side in one run (:func:`_timing.interleaved_best`:
the calls take turns within each round, so all see the same load, and each keeps its
best of ``--repeats`` short rounds):

1.  ``table``: ``sky.coefficients(0.5, 3.0, 1.0, bands=3, irradiance=True)`` (the
    certified irradiance table, the default for irradiance: one polynomial evaluation
    and the rotation, no deringing search) vs ``sky.coefficients(0.5, 3.0, 1.0,
    bands=3)`` (one 3-band radiance call). Target: ratio <= 1.3.
2.  ``table_batch``: the same on arrays of ``--batch`` frames vs the radiance call on
    the same arrays. Target: ratio <= 1.3.
3.  ``old_pipeline``: for comparison, ``irradiance_table=False`` (the Gibbs-free sky,
    deringed by :func:`skysh.post.dering.dering`, then convolved) vs the same radiance call.
4.  ``table_lit``: for context, case 1 with ``sun=True, ground_albedo=0.3`` vs the
    radiance call with the same sun and ground.

Timings are wall time: on a loaded machine run it a few times and compare. Targets are
reported, never enforced (exit status 0). A table, then one JSON object per line::

    {"bench": "table", "runtime_s": ..., "baseline": "...", "baseline_s": ..., "ratio": ...,
     "target": "ratio <= 1.3", "met": true}

Run: ``PYTHONPATH=. python benchmarks/bench_irradiance_table.py [--repeats 200] [--batch 10000]``.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import _timing
import numpy as np

from skysh.runtime import SkySH

TABLE_TARGET: float = 1.3
"""Issue 18: the tabulated irradiance call costs <= 1.3 x a 3-band ``coefficients`` call."""

RUN_SECONDS: float = 0.002
"""Approximate length of one timed round; the loop count is chosen to reach it."""


def row(bench: str, runtime_s: float, baseline: str, baseline_s: float, target: float | None) -> dict[str, Any]:
    """One result: the JSON line's fields."""
    line: dict[str, Any] = {"bench": bench, "runtime_s": runtime_s, "baseline": baseline, "baseline_s": baseline_s,
                            "ratio": runtime_s / baseline_s}
    if target is None:
        line["target"] = "context (no target)"
    else:
        line.update(target=f"ratio <= {target:g}", met=bool(line["ratio"] <= target))
    return line


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--repeats", type=int, default=200, help="timed rounds per measurement (best is kept)")
    parser.add_argument("--batch", type=int, default=10_000, help="frames in the batched calls")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    sky = SkySH.load()
    environment = _timing.environment(repeats=args.repeats, batch=args.batch)
    coefficients = sky.coefficients
    radiance = "sky.coefficients(0.5, 3.0, 1.0, bands=3)"
    t = _timing.interleaved_best({
        "radiance": lambda: coefficients(0.5, 3.0, 1.0, bands=3),
        "table": lambda: coefficients(0.5, 3.0, 1.0, bands=3, irradiance=True),
        "old": lambda: coefficients(0.5, 3.0, 1.0, bands=3, irradiance=True, irradiance_table=False),
        "radiance_lit": lambda: coefficients(0.5, 3.0, 1.0, bands=3, sun=True, ground_albedo=0.3),
        "table_lit": lambda: coefficients(0.5, 3.0, 1.0, bands=3, irradiance=True, sun=True, ground_albedo=0.3),
    }, args.repeats, RUN_SECONDS)
    rows = [
        row("table", t["table"], radiance, t["radiance"], TABLE_TARGET),
        row("old_pipeline", t["old"], radiance, t["radiance"], None),
        row("table_lit", t["table_lit"], f"{radiance[:-1]}, sun=True, ground_albedo=0.3)", t["radiance_lit"], None),
    ]
    rng = np.random.default_rng(args.seed)
    ts, tu = rng.uniform(0.0, math.pi / 2, args.batch), rng.uniform(2.5, 6.0, args.batch)
    phi = rng.uniform(-3.0, 3.0, args.batch)
    t = _timing.interleaved_best({
        "radiance": lambda: coefficients(ts, tu, phi, bands=3),
        "table": lambda: coefficients(ts, tu, phi, bands=3, irradiance=True),
    }, max(3, args.repeats // 4), 0.0)
    rows.insert(1, row("table_batch", t["table"], f"sky.coefficients on {args.batch} frames, bands=3", t["radiance"],
                       TABLE_TARGET))

    print("| case | call | baseline | ratio | target |")
    print("|---|---|---|---|---|")
    for r in rows:
        verdict = f"{r['target']}: {'met' if r['met'] else 'NOT met'}" if "met" in r else r["target"]
        print(f"| {r['bench']} | {r['runtime_s'] * 1e6:.2f} us | {r['baseline_s'] * 1e6:.2f} us ({r['baseline']}) | "
              f"{r['ratio']:.3f} | {verdict} |")
    print(json.dumps(environment), flush=True)
    for r in rows:
        print(json.dumps(r), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
