"""
Cost of the sun's light per frame against a 1-band sky call
===========================================================

Issue 15's goal: the sun's light (direction and RGB illuminance) costs at most
1.5 times a 1-band :meth:`skysh.SkySH.coefficients` call. Measured side by
side in one run (the calls take turns within each round, so both see the same
load; the best of ``--repeats`` runs after a warm-up, each run about 0.2 s):

1.  ``rgb``: ``sun.rgb(0.5, 3.0)`` (Python floats: the fast path) vs
    ``sky.coefficients(0.5, 3.0, 1.0, bands=1)``. Target: ratio <= 1.5.
2.  ``light``: ``sun.light(0.5, 3.0, 1.0)`` (direction and RGB: what
    ``SkySH.sun_light`` returns) vs the same sky call. Target: ratio <= 1.5.
3.  ``batch``: ``sun.rgb`` on arrays of ``--batch`` points vs the 1-band sky
    call on the same arrays, per point. Target: ratio <= 1.5.
4.  ``reference``: one fast-path call vs :func:`skysh.model.solar.illuminance_rgb`
    (the spectral model the table was fitted to), for context: a speed-up.

Timings are wall time: on a loaded machine run it a few times and compare.
Targets are reported, never enforced (exit status 0). One JSON object per
line::

    {"bench": "rgb", "runtime_s": ..., "baseline": "...", "baseline_s": ..., "ratio": ..., "target": "ratio <= 1.5", "met": true}

Run: ``PYTHONPATH=. python benchmarks/bench_sunlight.py [--repeats 7] [--batch 100000]``.
"""

from __future__ import annotations

import argparse
import json
import math
import timeit
from collections.abc import Callable

import _timing
import numpy as np

from skysh.lighting.sunlight import SunLight
from skysh.runtime import SkySH

TARGET_RATIO: float = 1.5
"""Issue 15: ``sun_light`` <= 1.5 x a 1-band ``coefficients`` call."""

RUN_SECONDS: float = 0.2
"""Approximate length of one timed run; the loop count is chosen to reach it."""


def interleaved_best(cases: dict[str, Callable[[], object]], repeats: int,
                     run_seconds: float = RUN_SECONDS) -> dict[str, float]:
    """:func:`_timing.interleaved_best` with this script's run length."""
    return _timing.interleaved_best(cases, repeats, run_seconds)


def emit(bench: str, runtime_s: float, baseline: str, baseline_s: float, speedup: bool = False) -> None:
    value = baseline_s / runtime_s if speedup else runtime_s / baseline_s
    line: dict[str, object] = {"bench": bench, "runtime_s": runtime_s, "baseline": baseline, "baseline_s": baseline_s}
    if speedup:
        line.update(speedup=value, target="context (no target)")
    else:
        line.update(ratio=value, target=f"ratio <= {TARGET_RATIO:g}", met=bool(value <= TARGET_RATIO))
    print(json.dumps(line), flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--repeats", type=int, default=7, help="timed runs per measurement (best is kept)")
    parser.add_argument("--batch", type=int, default=100_000, help="points in the batched calls")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    sky, sun = SkySH.load(), SunLight.load()
    print(json.dumps(_timing.environment(sun_degrees=list(sun.degrees), repeats=args.repeats, batch=args.batch)), flush=True)

    t = interleaved_best({
        "sky": lambda: sky.coefficients(0.5, 3.0, 1.0, bands=1),
        "rgb": lambda: sun.rgb(0.5, 3.0),
        "light": lambda: sun.light(0.5, 3.0, 1.0),
    }, args.repeats)
    emit("rgb", t["rgb"], "sky.coefficients(0.5, 3.0, 1.0, bands=1)", t["sky"])
    emit("light", t["light"], "sky.coefficients(0.5, 3.0, 1.0, bands=1)", t["sky"])

    rng = np.random.default_rng(args.seed)
    ts, tu, phi = rng.uniform(0.0, math.pi / 2, args.batch), rng.uniform(2.5, 6.0, args.batch), rng.uniform(-3, 3, args.batch)
    t = interleaved_best({
        "sky": lambda: sky.coefficients(ts, tu, phi, bands=1),
        "rgb": lambda: sun.rgb(ts, tu),
    }, args.repeats, run_seconds=0.0)
    emit("batch", t["rgb"], f"sky.coefficients on {args.batch} points, bands=1", t["sky"])

    from skysh.model import solar

    solar.illuminance_rgb(0.5, 3.0)  # warm-up: colour-science import, caches
    reference = min(timeit.repeat(lambda: solar.illuminance_rgb(0.5, 3.0), repeat=args.repeats, number=20)) / 20
    fast = interleaved_best({"rgb": lambda: sun.rgb(0.5, 3.0)}, args.repeats)["rgb"]
    emit("reference", fast, "solar.illuminance_rgb(0.5, 3.0)", reference, speedup=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
